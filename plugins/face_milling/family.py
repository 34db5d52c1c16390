"""The generating family of Gleason face milling (Litvin's model), for the shared envelope solver.

Frames and conventions are those of :mod:`gearopt_plugins.face_milling` (read its docstring
first). Parameters ``q = (u, theta, phi_p)``: ``u`` the arc length along the blade's edge from
its tip (0, on the tip plane) toward the cutter body (along the tip fillet first when the blade
has an edge radius, :func:`edge`), ``theta`` the angle of the edge point about the cutter axis
in the cradle frame (the head cutter's own rotation does not change the cone its blades sweep),
``phi_p`` the work rotation from centre roll (rad); the cradle turns by
``phi_c = c1 phi_p + c2 phi_p^2 + ... + c6 phi_p^6``.

Every flank of a family is described by the same arrays (one entry per flank), so that the
batched solver can take the entries of each point with ``take(flank)``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from functools import cached_property

import numpy as np
from numpy.typing import NDArray

__all__ = ["CutterFlank", "FaceMillingFamily", "design_family", "edge", "flank_family"]


@dataclass(frozen=True, kw_only=True)
class CutterFlank:
    """Blade and machine settings of one flank (angles in rad, lengths in mm); any field may be
    an array (stacked flanks).

    ``side`` = +1 for the outside blade (concave flank: the tooth material lies radially outside
    the edge), -1 for the inside blade (convex flank). ``curvature_per_mm`` = 1 / profile radius
    (0: straight edge), the arc tangent to the straight edge at arc length ``tangent_mm`` from
    the sharp corner (the pitch-line point). ``roll`` = (c1, ..., c6). ``index_rad`` turns the
    generated flank about the work axis (the work indexed by whole pitches before the pass).
    ``tip_radius_mm`` = the blade's edge radius rho_t (0: a sharp corner; :func:`edge`).
    """

    side: float
    point_radius_mm: float
    pressure_angle_rad: float
    curvature_per_mm: float
    radial_setting_mm: float
    cradle_angle_rad: float
    machine_root_angle_rad: float
    center_to_back_mm: float
    blank_offset_mm: float
    sliding_base_mm: float
    roll: tuple[float, ...]
    index_rad: float = 0.0
    tangent_mm: float = 0.0
    tip_radius_mm: float = 0.0

    @staticmethod
    def stack(flanks: tuple[CutterFlank, ...]) -> CutterFlank:
        values = {
            f.name: np.array([getattr(c, f.name) for c in flanks], float)
            for f in fields(CutterFlank)
        }
        return CutterFlank(**values)


def _profile(c: CutterFlank, u):
    """Radius, height and their u-derivatives of the blade's edge without its tip fillet, at arc
    length ``u`` from the sharp corner (the straight line at the pressure angle, or the profile
    arc tangent to it at ``tangent_mm``; complex-safe in ``u``)."""
    sa, ca = np.sin(c.pressure_angle_rad), np.cos(c.pressure_angle_rad)
    side = c.side
    t_r, t_h = side * sa, -ca  # unit tangent, from the tip toward the cutter body
    m_r, m_h = side * ca, sa  # unit normal toward the tooth material
    k = np.asarray(c.curvature_per_mm)
    straight = k == 0.0
    ks = np.where(straight, 1.0, k)
    u0 = np.asarray(c.tangent_mm)
    w = u - u0  # from the tangency point
    ang = ks * w
    sin_over = np.where(straight, w, np.sin(ang) / ks)
    vers_over = np.where(straight, 0.0 * w, (1.0 - np.cos(ang)) / ks)
    cos_k = np.where(straight, 1.0 + 0.0 * w, np.cos(ang))
    sin_k = np.where(straight, 0.0 * w, np.sin(ang))
    radius = c.point_radius_mm + (u0 + sin_over) * t_r + vers_over * m_r
    height = (u0 + sin_over) * t_h + vers_over * m_h
    d_radius = cos_k * t_r + sin_k * m_r
    d_height = cos_k * t_h + sin_k * m_h
    return radius, height, d_radius, d_height


def _fillet(c: CutterFlank):
    """The tip fillet of radius rho_t = ``tip_radius_mm``, tangent to the tip plane (z_m = 0)
    and to the edge (:func:`_profile`): ``(length, u_edge, centre_radius)`` with ``length`` =
    rho_t (pi/2 - alpha_c) its arc length (alpha_c the edge's pressure angle where the fillet
    touches it), ``u_edge`` the arc length of that point along the edge from the sharp corner,
    ``centre_radius`` the radius of its centre (its height is -rho_t). All 0 for rho_t = 0 (the
    sharp corner: the edge unchanged). Real arithmetic on the settings only (not on ``u``)."""
    rho = np.asarray(c.tip_radius_mm, float)
    alpha = np.asarray(c.pressure_angle_rad, float)
    sa, ca = np.sin(alpha), np.cos(alpha)
    k = np.asarray(c.curvature_per_mm, float)
    u0 = np.asarray(c.tangent_mm, float)
    straight = k == 0.0
    ks = np.where(straight, 1.0, k)
    # profile arc: its centre Q at height sa / k - u0 ca, the fillet's centre at distance
    # 1/k + rho_t from Q and at height -rho_t: sin(alpha_c) = (Q_h + rho_t) / (1/k + rho_t)
    sin_c = np.where(straight, sa, (sa - u0 * ca * ks + rho * ks) / (1.0 + rho * ks))
    alpha_c = np.where(straight, alpha, np.arcsin(sin_c))
    u_edge = np.where(straight, rho * (1.0 - sa) / ca, u0 + (alpha_c - alpha) / ks)
    rounded = rho > 0.0
    u_edge = np.where(rounded, u_edge, 0.0)
    length = np.where(rounded, rho * (0.5 * math.pi - alpha_c), 0.0)
    r_e, _, _, dh_e = _profile(c, u_edge)
    centre_radius = r_e + rho * c.side * dh_e  # the edge point less rho_t along its normal
    return length, u_edge, centre_radius


def edge(c: CutterFlank, u):
    """Radius, height (along the cradle axis z_m, toward the work; the tip plane at 0) and their
    derivatives in u of the edge point at arc length ``u`` from the tip (complex-safe in ``u``).

    From the tip plane: the tip fillet of radius rho_t (``tip_radius_mm``, Gleason's edge
    radius), tangent to the tip plane at u = 0 (its centre rho_t above the tip plane, toward
    the cutter body) and to the edge at u = rho_t (pi/2 - alpha_c); then the edge (the straight
    line at the blade pressure angle, or the circular arc of curvature kappa tangent to it at
    arc length ``tangent_mm`` from the sharp corner (the pitch-line point), its centre on the
    material side). With rho_t = 0 the edge starts at the sharp corner. For u < 0 (past the
    tip: not part of the blade, :meth:`FaceMillingFamily.within_tool`) the fillet's circle, or
    the edge when rho_t = 0, continues smoothly for the solver.
    """
    length, u_edge, centre_radius = _fillet(c)
    radius, height, d_radius, d_height = _profile(c, u - length + u_edge)
    rho = np.asarray(c.tip_radius_mm, float)
    on_fillet = (rho > 0.0) & (np.real(u) < length)
    psi = u / np.where(rho > 0.0, rho, 1.0)  # the fillet's turn from the tip plane
    s_half = np.sin(0.5 * psi)
    side = c.side
    return (
        np.where(on_fillet, centre_radius + rho * side * np.sin(psi), radius),
        np.where(on_fillet, -2.0 * rho * s_half * s_half, height),
        np.where(on_fillet, side * np.cos(psi), d_radius),
        np.where(on_fillet, -np.sin(psi), d_height),
    )


def _roll(c: CutterFlank, phi):
    """Cradle angle phi_c(phi_p) and its derivative (Horner)."""
    coef = c.roll
    value = 0.0 * phi
    slope = 0.0 * phi
    for k in range(5, -1, -1):  # c6 ... c1
        value = (value + coef[k]) * phi
        slope = slope * phi + (k + 1) * coef[k]
    return value, slope


def _machine(c: CutterFlank, u, theta, phi, cradle=None):
    """Tool point, unit normal (the edge's, not oriented to the material) and relative velocity
    per unit phi_p, in the machine frame; the work's apex and axis. ``cradle``: ``(phi_c,
    dphi_c/dphi_p)`` instead of the roll law's (inverse TCA)."""
    radius, height, dr, dh = edge(c, u)
    ct, st = np.cos(theta), np.sin(theta)
    sr, q = c.radial_setting_mm, c.cradle_angle_rad
    xc = sr * np.cos(q) + radius * ct
    yc = sr * np.sin(q) + radius * st
    zc = height
    # normal of the cone r = (rho cos t, rho sin t, h): (r_u x r_t) / rho, unit for arc length u
    nx, ny, nz = -dh * ct, -dh * st, dr
    phi_c, dphi_c = _roll(c, phi) if cradle is None else cradle
    cc, sc = np.cos(phi_c), np.sin(phi_c)
    x, y = cc * xc - sc * yc, sc * xc + cc * yc
    n = (cc * nx - sc * ny, sc * nx + cc * ny, nz)
    g = c.machine_root_angle_rad
    cg, sg = np.cos(g), np.sin(g)
    # the work's pitch apex: dX_D along the work axis, dE_m along y_m, dX_B toward the cradle
    ax = c.center_to_back_mm * cg
    ay = c.blank_offset_mm
    az = c.center_to_back_mm * sg - c.sliding_base_mm
    dx, dy, dz = x - ax, y - ay, zc - az
    # relative velocity: cradle about z_m (rate phi_c'), minus work about a_w through the apex
    v = (
        -dphi_c * y + sg * dy,
        dphi_c * x - (sg * dx - cg * dz),
        -cg * dy,
    )
    return (dx, dy, dz), n, v, (cg, sg)


@dataclass(frozen=True, kw_only=True)
class FaceMillingFamily:
    """Face-milling cutters as a :class:`gearopt.envelope.GeneratingFamily`, q = (u, theta,
    phi_p), one flank per entry of ``cutters``. ``pitch_angle_rad`` is the member's pitch angle
    (for the start on the pitch line)."""

    cutters: tuple[CutterFlank, ...]
    scale_mm: float
    pitch_angle_rad: float
    max_step: tuple[float, float, float] = (1.0, 0.05, 0.05)

    @property
    def n_flanks(self) -> int:
        return len(self.cutters)

    @cached_property
    def _stacked(self) -> CutterFlank:
        return CutterFlank.stack(self.cutters)

    def _take(self, flank) -> CutterFlank:
        s = self._stacked
        idx = np.asarray(flank)
        values = {f.name: np.asarray(getattr(s, f.name))[idx] for f in fields(CutterFlank)}
        values["roll"] = tuple(np.asarray(s.roll)[idx][..., k] for k in range(6))
        return CutterFlank(**values)

    def axial_radial_meshing(self, q, flank):
        c = self._take(flank)
        (dx, dy, dz), n, v, (cg, sg) = _machine(c, q[..., 0], q[..., 1], q[..., 2])
        xw = sg * dx - cg * dz
        axial = cg * dx + sg * dz
        radius = np.sqrt(xw * xw + dy * dy)
        meshing = n[0] * v[0] + n[1] * v[1] + n[2] * v[2]  # |n| = 1
        return axial, radius, meshing / self.scale_mm

    def geometry(self, q, flank, *, cradle=None) -> dict[str, NDArray]:
        """Point and unit normal (out of the material) in the work frame; ``cradle`` as in
        :func:`_machine`, with ``meshing`` (per unit phi_p, scaled) added to the result."""
        c = self._take(flank)
        (dx, dy, dz), n, v, (cg, sg) = _machine(c, q[..., 0], q[..., 1], q[..., 2], cradle)
        turn = c.index_rad - q[..., 2]  # the work turned by phi_p: material seen at -phi_p
        ct, st = np.cos(turn), np.sin(turn)

        def to_work(x, y, z):
            xw, zw = sg * x - cg * z, cg * x + sg * z
            return np.stack([ct * xw - st * y, st * xw + ct * y, zw], axis=-1)

        normal = to_work(*n) * (-c.side)[..., None]  # out of the tooth material
        out = {
            "point": to_work(dx, dy, dz),
            "normal": normal / np.sqrt((normal * normal).sum(-1))[..., None],
        }
        if cradle is not None:
            out["meshing"] = (n[0] * v[0] + n[1] * v[1] + n[2] * v[2]) / self.scale_mm
        return out

    def within_tool(self, q, flank):
        return np.real(q[..., 0]) >= -1e-9  # the blade ends on the tip plane (u = 0)

    def pitch_row(self, cone_distance_mm):
        """Start on the pitch line: the point P(s) of the work's pitch generatrix nearest the
        cradle at centre roll (the rolling's instantaneous axis when the roll is pure); the
        cradle angle at which the cutter's cone at P's height passes through P; the work
        rotation from the roll law."""
        s = np.asarray(cone_distance_mm, float)
        rows = []
        for c in self.cutters:
            g, gp = c.machine_root_angle_rad, self.pitch_angle_rad
            apex = np.array(
                [
                    c.center_to_back_mm * math.cos(g),
                    c.blank_offset_mm,
                    c.center_to_back_mm * math.sin(g) - c.sliding_base_mm,
                ]
            )
            px = apex[0] + s * math.cos(g - gp)
            py = apex[1] + 0.0 * s
            pz = apex[2] + s * math.sin(g - gp)
            # blade point at P's height (Newton on the edge; exact at once for a straight edge)
            u = -pz / math.cos(c.pressure_angle_rad)
            for _ in range(4):
                _, h, _, dh = edge(c, u)
                u = u - (h - pz) / dh
            rho = edge(c, u)[0]
            sr, q = c.radial_setting_mm, c.cradle_angle_rad
            dist = np.hypot(px, py)
            k = np.clip((dist**2 + sr**2 - rho**2) / (2.0 * sr * dist), -1.0, 1.0)
            base = np.arctan2(py, px) - q
            cands = np.stack([base + np.arccos(k), base - np.arccos(k)])
            cands = (cands + math.pi) % (2.0 * math.pi) - math.pi
            phi_c = np.where(np.abs(cands[0]) <= np.abs(cands[1]), cands[0], cands[1])
            cc, sc = np.cos(phi_c), np.sin(phi_c)
            xr, yr = cc * px + sc * py, -sc * px + cc * py  # P in the cradle frame
            theta = np.arctan2(yr - sr * math.sin(q), xr - sr * math.cos(q))
            phi = phi_c / c.roll[0]
            for _ in range(6):
                value, slope = _roll(c, phi)
                phi = phi - (value - phi_c) / slope
            rows.append(np.stack([np.broadcast_to(u, s.shape), theta, phi], axis=-1))
        return np.stack(rows)


def flank_family(blank, index: int, specs, *, index_rad: float = 0.0) -> FaceMillingFamily:
    """The family cutting the flanks ``specs`` (``{flank: settings}``, each with a
    ``cutter(flank, index_rad=, pitch_depth_mm=)``, e.g. a ``FaceMillingFlank``) of member
    ``index`` (0 pinion, 1 gear) of ``blank``, the work indexed by ``index_rad``."""
    return FaceMillingFamily(
        cutters=tuple(
            spec.cutter(flank, index_rad=index_rad, pitch_depth_mm=blank.mean_dedendum_mm[index])
            for flank, spec in specs.items()
        ),
        scale_mm=blank.mean_cone_distance_mm,
        pitch_angle_rad=math.radians(blank.pitch_angle_deg[index]),
    )


def design_family(design, member: str, flanks, *, tool_pass: int = 0) -> FaceMillingFamily:
    """The family of ``flanks`` of a design's ``member`` (its machine settings), the tool
    turned by ``tool_pass`` pitches."""
    index = ("pinion", "gear").index(member)
    teeth = (design.pair.pinion_teeth, design.pair.gear_teeth)[index]
    spec = design.machine.member(member)
    return flank_family(
        design.blank,
        index,
        {f: spec.flank(f) for f in flanks},
        index_rad=2.0 * math.pi * tool_pass / teeth,
    )
