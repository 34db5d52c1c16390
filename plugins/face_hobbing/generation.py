"""Face-hobbing flank generation: seed 001's envelope (eqs 15-31) on a FlankMap grid, from
settings.

Each flank is the envelope of one blade system (:class:`~gearopt_plugins.face_hobbing.family.
BladeSystem`) solved by :func:`gearopt.envelope.solve_envelope`. This module is what the
Klingelnberg models (cyclo-palloid, epicycloid) share past their heads: the generating family
(:class:`FaceHobbingFamily`), a blade system from the member's settings
(:func:`blade_system`: the work's settings, a disk, a blade edge), the turn that puts a flank
on tooth 0 (:func:`tooth_turn_rad`, :func:`outer_phase_rad`) and the batch generation
(:func:`generate_flanks`). None of it reads a design: a blank, a number of teeth and settings.

Phase of the outer blades, derived from the machine's kinematics (seed 001 states none of it).
Seed 001 writes each blade system with its own cutter rotation theta_k (eqs 15-19) and the work's
rotation psi_g = m_gc psi_cr - m_gb theta_k (eq 23), theta_k = 0 where the system's reference
point P_k passes the pitch point M (Figs 3-4: P_i = P'_o at M); it does not say where the outer
blades are while an inner blade is at M. On the machine both disks turn together (one spindle;
eq 37 gives both systems one m'_gb), so theta_o = theta_i + lambda with a constant lead lambda of
the outer blade. A tooth space is cut between the passages of one group's outer and inner blades
through it, so by eq 23 its width at M is the work's rotation m'_gb lambda between them: the
concave flank of tooth 0 is the outer system's envelope turned by 2 pi / N - m'_gb lambda
(:func:`tooth_turn_rad`). A single-radius head (the epicycloid's) is the case r_ci = r_co: the
two disks coincide and lambda = pi / N_b.

lambda is fixed by the tool and by how each disk is set on the cradle. Eq 19 (with eqs 13-14,
or 34-35 under dnu) sets disk k in the cradle frame S_d in two steps: its centre O_ck at the
machine distance M_dk and cradle angle q_2k, and its frame turned so that at theta_k = 0 the
blade points from O_ck to M, at psi_m - nu_k - pi/2 from x_d. Measured about the disk's axis from
its own radial line O_ck O_m, the blade through M therefore stands at

    eps_k = (psi_m - nu_k - pi/2) - (q_2k + pi) = pi/2 + psi_m - nu_k - q_2k   (mod 2 pi),

the angle at O_ck of the triangle O_m O_ck M that eqs 13-14 solve (its angle at O_m is q_2k, at
M pi/2 - psi_m + nu_k). The line O_m O_ck is the disk's datum on the machine: the cradle-angle
setting q_2k turns the disk's carrier, and with it the disk, about the cradle axis, and the
disk's roll circle (rho', the same for both systems, eq 37) rolls on its base circle about O_m
at the instantaneous centre C_k on that line (eqs 28-29, Fig. 4), so the angle from it is the
blade's phase on its extended epicycloid. Reading adopted: the tool spaces its blade groups by
half a group pitch, pi / N_b, from each disk's datum: when the inner blade is at M (at eps_i
from O_ci O_m) the outer blade is at eps_i + pi / N_b from O_co O_m; it passed M (at eps_o) a
rotation

    lambda = pi / N_b + eps_i - eps_o = pi / N_b + (q'_2o - q'_2i) - (nu'_i - nu'_o)

earlier (:func:`outer_phase_rad`; primes: the settings under dnu, eqs 33-38). With equal radii
the two disks coincide (e = 0, gamma = 0: nu_o = nu_i, q_2o = q_2i) and lambda = pi / N_b: with
dnu = 0 and m_b = m_mn tooth and space are exactly half a pitch (pi / N); the additional slope
angle widens the space through m'_gb (eq 37); unequal radii change it through the correction
(q'_2o - q'_2i) - (nu'_i - nu'_o).

Which datum is the paper's, seed 001 section 5.2 decides: r_co = 76.8 mm on the pinion, "instead
of" Table 3's additional slope angles, provides "backlash similar" to Table 3's. Measured on the
generated flanks (normal chordal thickness at the mean point, against the conjugate pair), Table
3's two slope angles thin the pair by 0.1472 mm; with r_co = 76.8 mm (correction 1.158 - 0.153 =
1.005 deg) this reading thins the pinion by 0.1468 mm (a test holds the two within 1 %). The
other datums one might read into Fig. 3, each giving lambda = pi / N_b + (datum_o - datum_i):

- each disk's own blade axis x_b (no datum: lambda = pi / N_b): unequal radii would hardly
  change the thickness, 0.0005 mm;
- one datum fixed in the head for both disks (the eccentricity's direction, parallel to the
  slope line: lambda = pi / N_b - gamma'): 0.153 deg less, the pinion 0.022 mm thicker than
  conjugate, and the pair interferes (backlash -32 um);
- the inner blade pi / N_b behind the outer one as seen from O_co (this module's earlier
  reading, 0.779 deg): 0.114 mm, 0.77 of Table 3's; as seen from O_ci: 0.12 mm thicker.

Indexing. With dnu = 0 the work turns by m_gb 2 pi / N_b = 2 pi / N per blade group, so the
next group cuts the next tooth. With dnu != 0 the paper's kinematics (eq 37) does not index
exactly (m'_gb != N_b / N); as seed 001 does, the generated tooth space is the one cut by one
blade group and the other teeth are copies turned by whole pitches 2 pi / N (what a machine that
re-indexes per tooth space would cut).

Tooth numbering: tooth 0 is the tooth whose convex flank passes through the pitch point M
(polar angle 0 in the member frame of a right-hand member at the machine's zero); its concave
flank is the outer blade's envelope on the other side of the same tooth.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np
from numpy.typing import NDArray

from gearopt.blank import Blank
from gearopt.design import MEMBERS
from gearopt.envelope import extended_geometry, flank_map, require_flank, solve_envelope
from gearopt.errors import SettingsError
from gearopt.flank import FlankGrid, FlankMap
from gearopt_plugins.face_hobbing import kernels
from gearopt_plugins.face_hobbing.family import (
    BladeSystem,
    components,
    edge,
    meshing_jacobian,
    pitch_line_starts,
)
from gearopt_plugins.face_hobbing.settings import CutterDisk, WorkSettings

__all__ = [
    "BLADE_OF_FLANK",
    "BladeEdge",
    "FaceHobbingFamily",
    "blade_system",
    "generate_flanks",
    "hobbing_family",
    "outer_phase_rad",
    "tooth_turn_rad",
]

#: in face cutting the inner blades cut the convex flank and the outer blades the concave flank
#: of every member
BLADE_OF_FLANK = {"convex": "inner", "concave": "outer"}
#: the side of a blade system (:class:`BladeSystem`): +1 inner, -1 outer
SIDE_OF_BLADE = {"inner": 1, "outer": -1}


@dataclass(frozen=True, kw_only=True)
class FaceHobbingFamily:
    """Blade systems as a :class:`gearopt.envelope.GeneratingFamily`, q = (u, theta, psi_cr).

    One flank per blade system in ``blades`` (flank index = position in the tuple).
    ``tip_depth_mm`` is the depth of the blades' tips below the cradle (pitch) plane, the
    member's dedendum: a blade ends there, so it generates nothing lower.
    """

    blades: tuple[BladeSystem, ...]
    scale_mm: float
    tip_depth_mm: float
    max_step: tuple[float, float, float] = (1.0, 0.05, 0.05)

    @property
    def n_flanks(self) -> int:
        return len(self.blades)

    @cached_property
    def _stacked(self) -> BladeSystem:
        return BladeSystem.stack(self.blades)

    @cached_property
    def _table(self) -> NDArray:
        return kernels.system_table(self.blades)

    @cached_property
    def _limit(self) -> NDArray:
        return np.asarray(self.max_step, dtype=float)

    def _compiled(self, q) -> bool:
        """Whether the compiled kernels evaluate ``q`` (real parameters; the numpy functions of
        :mod:`~gearopt_plugins.face_hobbing.family` take complex steps and run without numba)."""
        return kernels.ENABLED and not np.iscomplexobj(q)

    def axial_radial_meshing(self, q, flank):
        if self._compiled(q):
            qq, ff, shape = _flat(q, flank)
            out = np.empty((len(qq), 3))
            kernels.meshing(self._table, ff, qq, float(self.scale_mm), out)
            return out[:, 0].reshape(shape), out[:, 1].reshape(shape), out[:, 2].reshape(shape)
        fam = components(self._stacked.take(flank), q[..., 0], q[..., 1], q[..., 2])
        n = fam["normal"]
        norm = np.sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2])
        return fam["axial_mm"], fam["radius_mm"], fam["meshing"] / (norm * self.scale_mm)

    def axial_radial_meshing_jacobian(self, q, flank):
        if self._compiled(q):
            qq, ff, shape = _flat(q, flank)
            out, jac = np.empty((len(qq), 3)), np.empty((len(qq), 3, 3))
            kernels.meshing_jacobians(self._table, ff, qq, float(self.scale_mm), out, jac)
            return (
                out[:, 0].reshape(shape),
                out[:, 1].reshape(shape),
                out[:, 2].reshape(shape),
                jac.reshape(*shape, 3, 3),
            )
        return meshing_jacobian(
            self._stacked.take(flank), q[..., 0], q[..., 1], q[..., 2], self.scale_mm
        )

    def newton(self, q, flank, big_l, big_r, *, tol, max_iter, give_up, chords):
        """gearopt.envelope's Newton iteration compiled (:func:`kernels.newton`), or None
        without the kernels (the solver then runs its own)."""
        if not self._compiled(q):
            return None
        q, flank, _ = _flat(q, flank)
        n = len(q)
        f, jac, converged = np.empty((n, 3)), np.empty((n, 3, 3)), np.empty(n, bool)
        iterations = kernels.newton(
            self._table,
            flank,
            q,
            np.ascontiguousarray(big_l, dtype=float),
            np.ascontiguousarray(big_r, dtype=float),
            float(self.scale_mm),
            self._limit,
            float(tol),
            int(max_iter),
            int(give_up[0]),
            float(give_up[1]),
            bool(chords),
            f,
            jac,
            converged,
        )
        return q, f, jac, converged, int(iterations)

    def bisect(self, q_up, flank, face_mm, lower, upper, *, cos_sin, tol, bisections, sheet):
        """gearopt.envelope's bisection of a column's generated end on uniform depth compiled
        (:func:`kernels.bisected`): on the envelope's sheet of the signs ``sheet``, or with
        ``sheet`` None within the tool; None without the kernels."""
        if not self._compiled(q_up):
            return None
        q, flank, _ = _flat(q_up, flank)
        n = len(q)
        out = np.empty(n)
        kernels.bisected(
            self._table,
            flank,
            q,
            np.ascontiguousarray(face_mm, dtype=float),
            np.ascontiguousarray(lower, dtype=float),
            np.ascontiguousarray(upper, dtype=float),
            np.asarray(cos_sin, dtype=float),
            float(self.scale_mm),
            self._limit,
            float(tol),
            int(bisections),
            sheet is not None,
            np.ones(n) if sheet is None else np.ascontiguousarray(sheet, dtype=float),
            -self.tip_depth_mm - 1e-9,
            out,
        )
        return out

    def pitch_row(self, cone_distance_mm):
        return pitch_line_starts(self.blades, cone_distance_mm)

    def geometry(self, q, flank) -> dict[str, NDArray]:
        if self._compiled(q):
            qq, ff, shape = _flat(q, flank)
            point, normal = np.empty((len(qq), 3)), np.empty((len(qq), 3))
            kernels.geometries(self._table, ff, qq, point, normal)
            return {"point": point.reshape(*shape, 3), "normal": normal.reshape(*shape, 3)}
        b = self._stacked.take(flank)
        fam = components(b, q[..., 0], q[..., 1], q[..., 2])
        g = b.machine_root_angle_rad
        sg, cg = np.sin(g), np.cos(g)
        psi_g = b.gear_to_cradle_roll * q[..., 2] - b.gear_to_blade_roll * q[..., 1]  # eq 23
        cp, sp = np.cos(psi_g), np.sin(psi_g)

        def to_work(x, y, z):
            # eq 22 (M_qm) then eq 21 (M_gq = rot_z(-psi_g))
            xq, zq = sg * x - cg * z, cg * x + sg * z
            return np.stack([cp * xq + sp * y, -sp * xq + cp * y, zq], axis=-1)

        offset = np.asarray(b.work_offset_mm)
        dxd, dem, dxb = offset[..., 0], offset[..., 1], offset[..., 2]
        px, py, pz = fam["point"]
        point = to_work(px - dxd * cg, py - dem, pz - dxd * sg - dxb)
        normal = to_work(*fam["normal"])
        normal /= np.linalg.norm(normal, axis=-1, keepdims=True)
        # the inner blade's body lies radially outside its edge, the outer blade's inside, and
        # r_u x r_theta points away from the inner cutter axis (tests check it on the tooth)
        return {"point": point, "normal": b.side[..., None] * normal}

    def blade_height_mm(self, u, flank):
        """Height y_c of the edge point (eqs 2-8) above the cradle plane, toward the tip."""
        if self._compiled(u):
            u = np.asarray(u, float)
            ff = _flank_indices(flank, u.shape)
            out = np.empty(u.size)
            kernels.blade_heights(self._table, ff, np.ascontiguousarray(u).ravel(), out)
            return out.reshape(u.shape)
        return edge(self._stacked.take(flank), u)[1]

    def within_tool(self, q, flank):
        return self.blade_height_mm(q[..., 0], flank) >= -self.tip_depth_mm - 1e-9


def _flat(q, flank):
    """``(q (n, 3), flank (n,), shape)`` of parameters ``q`` ``(..., 3)`` and the flank indices
    broadcast to ``shape = q.shape[:-1]``, contiguous for the kernels."""
    q = np.asarray(q, float)
    shape = q.shape[:-1]
    flat = np.ascontiguousarray(q.reshape(-1, 3))
    return flat, _flank_indices(flank, shape), shape


def _flank_indices(flank, shape) -> NDArray:
    """``(n,)`` the flank indices ``flank`` broadcast to ``shape``, flattened: a writable copy
    (a read-only one is another type to numba, another compilation), made without
    ``np.broadcast_to``'s cost."""
    out = np.empty(shape, dtype=np.intp)
    out[...] = flank
    return out.reshape(-1)


@dataclass(frozen=True, kw_only=True)
class BladeEdge:
    """The cutting edge of a blade system: pressure angle alpha_k on the front plane, rake
    alpha_r (eq 4), parabola a_p about u_o (eq 2) and the curvature 1 / R_b of a circular-arc
    edge (0 for the straight edge)."""

    pressure_angle_deg: float
    rake_angle_deg: float = 0.0
    parabola_per_mm: float = 0.0
    parabola_apex_mm: float = 0.0
    profile_curvature_per_mm: float = 0.0


def blade_system(
    work: WorkSettings,
    disk: CutterDisk,
    blade: BladeEdge,
    *,
    side: int,
    gear_to_blade_roll: float | None = None,
    tool_pass: int = 0,
) -> BladeSystem:
    """The blade system of ``disk`` with the edge ``blade`` (``side`` +1 inner, -1 outer) on
    the machine of ``work``, that of blade group ``tool_pass`` (counted against the cutter's
    rotation) when it is not 0. ``gear_to_blade_roll`` is the work's unless given."""
    roll = work.gear_to_blade_roll if gear_to_blade_roll is None else gear_to_blade_roll
    return BladeSystem(
        side=side,
        cutter_radius_mm=disk.cutter_radius_mm,
        assembly_angle_rad=math.radians(disk.assembly_angle_deg),
        machine_distance_mm=disk.machine_distance_mm,
        cradle_angle_rad=math.radians(disk.cradle_angle_deg),
        spiral_angle_rad=math.radians(work.spiral_angle_deg),
        pressure_angle_rad=math.radians(blade.pressure_angle_deg),
        rake_angle_rad=math.radians(blade.rake_angle_deg),
        parabola_per_mm=blade.parabola_per_mm,
        parabola_apex_mm=blade.parabola_apex_mm,
        machine_root_angle_rad=math.radians(work.machine_root_angle_deg),
        gear_to_cradle_roll=work.gear_to_cradle_roll,
        gear_to_blade_roll=roll,
        work_offset_mm=work.work_offset_mm,
        phase_rad=2.0 * math.pi * tool_pass / work.blade_groups,
        profile_curvature_per_mm=blade.profile_curvature_per_mm,
    )


def outer_phase_rad(*, blade_groups: int, inner: BladeSystem, outer: BladeSystem) -> float:
    """The lead lambda of a group's outer blade over its inner blade through M (module
    docstring), in the disks' common rotation: pi / N_b + eps_i - eps_o.

    eps_k = pi/2 + psi_m - nu_k - q_2k is the angle about O_ck from the disk's radial line
    O_ck O_m to its blade through M (eq 19 with eqs 13-14 / 34-35; nu_k is the system's assembly
    angle, eqs 11, 38).

    Raises
    ------
    SettingsError
        When lambda leaves (0, 2 pi / N_b): the outer blade would pass M after the inner blade
        of its group, or before the inner blade of the group ahead, so no tooth space (or no
        tooth) would lie between them.
    """

    def eps(b: BladeSystem) -> float:
        return 0.5 * math.pi + b.spiral_angle_rad - b.assembly_angle_rad - b.cradle_angle_rad

    pitch = 2.0 * math.pi / blade_groups
    lead = 0.5 * pitch + eps(inner) - eps(outer)
    if not 0.0 < lead < pitch:
        raise SettingsError(
            "machine.inner_cutter_radius_mm, outer_cutter_radius_mm",
            (inner.cutter_radius_mm, outer.cutter_radius_mm),
            f"the outer blades must pass the pitch point between two inner blades (a lead of "
            f"0 to 360/{blade_groups} deg); these radii give {math.degrees(lead):.3f} deg "
            f"(180/{blade_groups} deg plus the difference of the two disks' cradle angles less "
            "that of their slope angles): bring the radii closer together",
        )
    return float(lead)


def tooth_turn_rad(flank: str, *, teeth: int, gear_to_blade_roll: float, lead_rad: float) -> float:
    """Turn of the flank's envelope about the work axis that places it on tooth 0.

    The convex flank is not turned. The concave flank of tooth 0 is the outer blade's envelope
    turned by one pitch less the work's rotation m_gb lambda while the group's outer blade leads
    its inner blade by ``lead_rad`` lambda (the tooth space is cut between their passages).
    """
    if flank == "convex":
        return 0.0
    return 2.0 * math.pi / teeth - gear_to_blade_roll * lead_rad


def hobbing_family(blank: Blank, member: str, blades) -> FaceHobbingFamily:
    """The generating family of ``blades`` (one flank each) on ``member``'s blank."""
    return FaceHobbingFamily(
        blades=tuple(blades),
        scale_mm=blank.mean_cone_distance_mm,
        tip_depth_mm=blank.mean_dedendum_mm[MEMBERS.index(member)],
    )


#: the most recent generations (the last most recent) by everything :func:`generate_flanks`
#: reads: a study that changes one member's settings generates the other member once per
#: worker, and its FlankMaps keep their interpolants (FlankMaps are never changed in place)
_RECENT: dict[tuple, dict[str, FlankMap]] = {}
#: how many generations :func:`generate_flanks` remembers (0: none)
RECENT_GENERATIONS = 8


def generate_flanks(
    blank: Blank,
    member: str,
    teeth: int,
    systems: dict[str, BladeSystem],
    turns_rad: dict[str, float],
    *,
    grid: FlankGrid,
    tool_pass: int = 0,
    notes: dict[str, tuple[str, ...]] | None = None,
) -> dict[str, FlankMap]:
    """FlankMaps of ``member``'s flanks, one per entry of ``systems`` (flank name -> the blade
    system that cuts it), solved in one batch; each is turned by ``turns_rad[flank]`` about the
    work axis onto tooth 0, or onto the tooth cut by blade group ``tool_pass`` (tooth
    ``tool_pass`` of a right-hand member, ``-tool_pass`` of a left-hand one, when the work
    indexes exactly: m_gb = N_b / N).

    A pure function of its arguments: the last :data:`RECENT_GENERATIONS` results are
    remembered by their arguments' values and returned again (the same FlankMaps, in a new
    dict)."""
    notes = notes or {}
    key = (
        blank,
        member,
        teeth,
        tuple(systems.items()),
        tuple((f, float(turns_rad[f])) for f in systems),
        grid,
        tool_pass,
        tuple((f, tuple(notes.get(f, ()))) for f in systems),
    )
    found = _RECENT.pop(key, None) if RECENT_GENERATIONS > 0 else None
    if found is None:
        found = _generated(blank, member, teeth, systems, turns_rad, grid, tool_pass, notes)
    _RECENT[key] = found
    while len(_RECENT) > RECENT_GENERATIONS:
        del _RECENT[next(iter(_RECENT))]
    return dict(found)


def _generated(blank, member, teeth, systems, turns_rad, grid, tool_pass, notes):
    """:func:`generate_flanks` itself (not remembered)."""
    index = MEMBERS.index(member)
    flanks = tuple(systems)
    family_ = hobbing_family(blank, member, [systems[f] for f in flanks])
    solution = solve_envelope(
        family_,
        cone_distances_mm=(blank.inner_cone_distance_mm, blank.outer_cone_distance_mm),
        heights_mm=(-blank.mean_dedendum_mm[index], blank.mean_addendum_mm[index]),
        pitch_angle_rad=math.radians(blank.pitch_angle_deg[index]),
        grid=grid,
        where=f"{member} flanks {', '.join(flanks)}",
    )
    for k, flank in enumerate(flanks):
        require_flank(solution, k, member=member, flank=flank)
    geometry = extended_geometry(family_, solution)  # both flanks at once
    out = {}
    for k, flank in enumerate(flanks):
        out[flank] = flank_map(
            family_,
            solution,
            index=k,
            member=member,
            flank=flank,
            hand=blank.hand[index],
            teeth=teeth,
            turn_rad=turns_rad[flank],
            notes=notes.get(flank, ()),
            tooth=tool_pass if blank.hand[index] == "right" else -tool_pass,
            geometry=geometry,
        )
    return out
