"""Klingelnberg epicycloid (single-radius face hobbing) machine model, seed 003.

Seed 003's generation chain (its eq 3, figures missing) is the face hobbing of seed 001 with one
cutter head radius R_h per flank, so this model states only its heads and runs the chain every
Klingelnberg model shares (:mod:`gearopt_plugins.face_hobbing`): each flank is cut by the blade
system of a single-radius head R_h (the dual head's r_ci = r_co with no additional slope angle:
no eccentricity, both disks one), its edge a circular arc of radius R_b.

Eq 3 from first principles, frame by frame (seed 003 -> seed 001):

* S_b, r_b(t): the cutter edge, a straight line at the pressure angle or an arc of radius R_b
  tangent to it at the pitch-line point (t = 0), the arc's centre on the tooth material side
  (profile crowning): seed 001 eq 2 with the arc for the straight line (``edge``).
* M_tb = rot(nu) about z_t: the edge plane turned by the slope angle nu toward the instantaneous
  axis I, sin nu = N_b m_b / (2 R_h) (seed 001 eqs 5-9, there the assembly angle delta = nu).
* M_ht: the edge at the head radius R_h = O_t O_h; M_uh(phi): the head turned by phi about its
  axis z_u (seed 001 eqs 8, 15-16).
* M_vu: the head axis at the machine distance M_d = O_u O_v from the cradle axis, at the cradle
  angle q_2; M_d^2 = R_m^2 + R_h^2 - 2 R_m R_h sin(beta_m - nu), the point where the edge meets
  the pitch line at R_m with the spiral angle beta_m (seed 001 eqs 13-14).
* M_cv(phi_a): the crown gear (cradle) turned by phi_a. Eq 1, phi / phi_a = rho / p: the rolling
  circle p (on the head) rolls on the base circle rho (on the crown gear), M_d = rho + p,
  p / rho = N_b / N_c with N_c = N / sin(delta) the crown gear's teeth (seed 001 eqs 25-30).
  In seed 001's parametrisation the cradle angle psi_cr carries both the crown gear and the head
  and theta is the head's turn relative to the work's blade roll m_gb = N_b / N (the same motion).
* M_mc(psi), M_wm, M_iw(psi_a): the crown gear turned by psi about z_m, the work at its pitch
  angle delta_1 (machine root angle = pitch angle for uniform depth), turned by psi_a with
  psi / psi_a = sin(delta_1) (eq 2; seed 001 eqs 20-25, m_gc = 1 / sin delta).

The meshing equation (the normal passes through the instantaneous axis) is seed 001 eq 31.

Design keys (``[machine]``; member keys in ``[machine.pinion]`` / ``[machine.gear]`` or in
``[machine]`` as a default for both members; flank keys in ``[machine.pinion.convex]`` etc.
override the member's for one flank)::

    [machine]
    model = "epicycloid"
    blade_groups = 5                        # N_b ("number of cutter groups")
    blade_module_mm = 6.1                   # m_b; default the mean normal module m_mn

    [machine.pinion]
    cutter_head_radius_mm = 137.4           # R_h
    blade_profile_radius_mm = "inf"         # R_b: a number in mm or "inf" (straight edge)
    rake_angle_deg = 0.0                    # as cyclo-palloid (seed 001 eq 4)
    profile_pressure_angle_deg = 20.0       # default the pair's (drive or coast) pressure angle

    [machine.pinion.convex]
    cutter_head_radius_mm = 135.0
    blade_profile_radius_mm = 509.634

Flanks and sides: the inner blades cut the convex flank and the outer blades the concave flank
of every member (as cyclo-palloid). Seed 003 studies the drive side, pinion convex against gear
concave (Tables 2-3); the unprefixed settings are those of the member's drive flank, the
``coast_`` settings those of its coast flank (pinion concave, gear convex).

Tooth thickness: each flank passes through the pitch point M at its nominal angle (the blade
systems' reference points meet M; the concave flank is turned by one pitch less m_gb pi / N_b,
i.e. half a pitch when the work indexes exactly): the tooth and the space are each half the mean
circular pitch on the pitch cone at M, without backlash. Uniform tooth depth.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from gearopt import hookimpl
from gearopt.design import MEMBERS, Design, PairData
from gearopt.errors import DesignError
from gearopt.flank import FLANKS, FlankGrid, FlankMap, check_member_and_flank
from gearopt.machine import BaseMachineModel, MachineSettings, SearchDimension
from gearopt.rexs.attributes import RexsMachine
from gearopt.validate import check_keys, read_integer, read_number, read_table
from gearopt_plugins.cutters.blades import MIN_PROFILE_RADIUS_DEPTHS, read_profile_radius
from gearopt_plugins.cutters.catalogue import EPICYCLOID, face_hobbing_dimensions
from gearopt_plugins.epicycloid import rexs as ep_rexs
from gearopt_plugins.face_hobbing import kernels as hobbing_kernels
from gearopt_plugins.face_hobbing.family import BladeSystem
from gearopt_plugins.face_hobbing.generation import (
    BLADE_OF_FLANK,
    SIDE_OF_BLADE,
    BladeEdge,
    blade_system,
    generate_flanks,
    tooth_turn_rad,
)
from gearopt_plugins.face_hobbing.settings import (
    CutterDisk,
    WorkSettings,
    cutter_disk,
    slope_angle_rad,
    work_settings,
)

__all__ = [
    "DRIVE_FLANK",
    "Epicycloid",
    "EpicycloidFlank",
    "EpicycloidMachine",
    "EpicycloidMember",
    "EpicycloidSettings",
    "flank_system",
]

FLANK_KEYS = (
    "cutter_head_radius_mm",
    "blade_profile_radius_mm",
    "rake_angle_deg",
    "profile_pressure_angle_deg",
)
MEMBER_KEYS = (*FLANK_KEYS, *FLANKS)
MACHINE_KEYS = ("blade_groups", "blade_module_mm", *MEMBERS, *FLANK_KEYS)
#: seed 003's drive side, pinion convex driving gear concave
#: (docs/architecture.md, Drive and coast)
DRIVE_FLANK = {"pinion": "convex", "gear": "concave"}
COAST_FLANK = {"pinion": "concave", "gear": "convex"}


# --- data ----------------------------------------------------------------------------------------


@dataclass(frozen=True, kw_only=True)
class EpicycloidFlank:
    """Cutter and blade of one flank: head radius R_h and blade profile radius R_b (inf =
    straight)."""

    cutter_head_radius_mm: float
    blade_profile_radius_mm: float = math.inf
    rake_angle_deg: float = 0.0
    profile_pressure_angle_deg: float = 20.0

    @property
    def profile_curvature_per_mm(self) -> float:
        """1 / R_b (0 for a straight blade)."""
        rb = self.blade_profile_radius_mm
        return 0.0 if math.isinf(rb) else 1.0 / rb


@dataclass(frozen=True, kw_only=True)
class EpicycloidMember:
    """The two flanks' cutters of one member."""

    convex: EpicycloidFlank
    concave: EpicycloidFlank

    def flank(self, name: str) -> EpicycloidFlank:
        return getattr(self, name)


@dataclass(frozen=True, kw_only=True)
class EpicycloidMachine:
    """The ``[machine]`` table of an epicycloid design."""

    blade_groups: int
    blade_module_mm: float
    pinion: EpicycloidMember
    gear: EpicycloidMember

    def member(self, name: str) -> EpicycloidMember:
        return getattr(self, name)


@dataclass(frozen=True, kw_only=True)
class EpicycloidSettings:
    """Basic settings of one member (seed 003 Tables 2-3).

    Unprefixed: the member's drive flank (pinion convex, gear concave); ``coast_``: the other.
    ``cutter_edge_radius_mm`` is R_b, reported as 0 for a straight edge (R_b = inf; a setting is
    a finite number), ``cutter_edge_curvature_per_mm`` = 1 / R_b. ``slope_angle_deg`` is nu
    (sin nu = N_b m_b / (2 R_h)); M_d = rho + p with p / rho = N_b / N_c.
    """

    cutter_head_radius_mm: float
    cutter_edge_radius_mm: float
    cutter_edge_curvature_per_mm: float
    slope_angle_deg: float
    machine_distance_mm: float
    cradle_angle_deg: float
    base_circle_radius_mm: float
    rolling_circle_radius_mm: float
    coast_cutter_head_radius_mm: float
    coast_cutter_edge_radius_mm: float
    coast_cutter_edge_curvature_per_mm: float
    coast_slope_angle_deg: float
    coast_machine_distance_mm: float
    coast_cradle_angle_deg: float
    coast_base_circle_radius_mm: float
    coast_rolling_circle_radius_mm: float
    blade_groups: int
    blade_module_mm: float
    machine_root_angle_deg: float
    machine_center_to_back_mm: float
    blank_offset_mm: float
    sliding_base_mm: float
    gear_to_cradle_roll: float
    gear_to_blade_roll: float


# --- parsing -------------------------------------------------------------------------------------


def _parse_flank(
    merged: Mapping[str, Any], where: str, pair: PairData, rho_mm: float, side: int
) -> EpicycloidFlank:
    """One flank's cutter; ``side`` 0 (drive) or 1 (coast) picks the pair's pressure angle
    that ``profile_pressure_angle_deg`` defaults to."""
    if "cutter_head_radius_mm" not in merged:
        raise DesignError(
            f"{where}.cutter_head_radius_mm",
            rule="required (in this flank's table, its member's, or [machine])",
        )
    rh = read_number(merged, "cutter_head_radius_mm", where, gt=0.0)
    if rh <= rho_mm:
        raise DesignError(
            f"{where}.cutter_head_radius_mm",
            rh,
            f"must exceed blade_module_mm * blade_groups / 2 = {rho_mm:.4f} mm (the slope "
            "angle, sin nu = N_b m_b / (2 R_h), is undefined)",
        )
    depth = max(pair.blank.whole_depth_mm)
    return EpicycloidFlank(
        cutter_head_radius_mm=rh,
        blade_profile_radius_mm=read_profile_radius(
            merged, where, MIN_PROFILE_RADIUS_DEPTHS * depth
        ),
        rake_angle_deg=read_number(merged, "rake_angle_deg", where, 0.0, gt=-30.0, lt=30.0),
        profile_pressure_angle_deg=read_number(
            merged,
            "profile_pressure_angle_deg",
            where,
            pair.pressure_angles_deg[side],
            gt=0.0,
            lt=45.0,
        ),
    )


def member_work(design: Design, member: str) -> WorkSettings:
    """The work's settings of ``member``: every head of the machine rolls on the roll circle
    rho = N_b m_b / 2 (seed 001 eq 9 with dnu = 0: r sin(nu) for any head radius r), so the
    roll ratios are one for both flanks."""
    machine: EpicycloidMachine = design.machine
    return work_settings(
        design.pair,
        design.compensation,
        member,
        blade_groups=machine.blade_groups,
        blade_module_mm=machine.blade_module_mm,
        roll_circle_radius_mm=machine.blade_module_mm * machine.blade_groups / 2.0,
    )


def flank_system(
    design: Design, member: str, flank: str, *, tool_pass: int = 0
) -> tuple[BladeSystem, float, CutterDisk]:
    """The blade system that cuts ``flank``, its turn onto tooth 0 and its head's disk.

    The head of radius R_h sets its blades at the slope angle nu, sin nu = N_b m_b / (2 R_h),
    on the disk of eqs 13-14; its blade groups are half a group pitch apart, the lead pi / N_b
    of :func:`~gearopt_plugins.face_hobbing.generation.outer_phase_rad` for coinciding disks.
    """
    machine: EpicycloidMachine = design.machine
    spec = machine.member(member).flank(flank)
    work_ = member_work(design, member)
    nu = slope_angle_rad(
        blade_module_mm=machine.blade_module_mm,
        blade_groups=machine.blade_groups,
        inner_cutter_radius_mm=spec.cutter_head_radius_mm,
    )
    disk = cutter_disk(work_, cutter_radius_mm=spec.cutter_head_radius_mm, assembly_angle_rad=nu)
    blade = BladeEdge(
        pressure_angle_deg=spec.profile_pressure_angle_deg,
        rake_angle_deg=spec.rake_angle_deg,
        profile_curvature_per_mm=spec.profile_curvature_per_mm,
    )
    side = SIDE_OF_BLADE[BLADE_OF_FLANK[flank]]
    system = blade_system(work_, disk, blade, side=side, tool_pass=tool_pass)
    teeth = design.pair.pinion_teeth if member == "pinion" else design.pair.gear_teeth
    turn = tooth_turn_rad(
        flank,
        teeth=teeth,
        gear_to_blade_roll=work_.gear_to_blade_roll,
        lead_rad=math.pi / machine.blade_groups,
    )
    return system, turn, disk


# --- the model -----------------------------------------------------------------------------------


class Epicycloid(BaseMachineModel):
    """Klingelnberg epicycloid face hobbing with one head radius per flank (seed 003)."""

    name = "epicycloid"
    description = (
        "Klingelnberg epicycloid face hobbing: head radius and arc blade per flank, uniform "
        "depth (seed 003)"
    )

    def warm_kernels(self) -> None:
        """The face-hobbing kernels of flank generation (compiled, or loaded from the cache)."""
        hobbing_kernels.warm()

    def parse_machine(self, table: Mapping[str, Any], pair: PairData) -> EpicycloidMachine:
        pair.require_uniform_depth(self.name)
        check_keys(table, MACHINE_KEYS, "machine")
        nb = read_integer(table, "blade_groups", "machine", ge=1, le=30)
        mb = read_number(table, "blade_module_mm", "machine", pair.mean_normal_module_mm, gt=0.0)
        rho = mb * nb / 2.0
        defaults = {k: v for k, v in table.items() if k in FLANK_KEYS}
        members = {}
        for member in MEMBERS:
            sub = read_table(table, member, "machine")
            check_keys(sub, MEMBER_KEYS, f"machine.{member}")
            member_defaults = {**defaults, **{k: v for k, v in sub.items() if k in FLANK_KEYS}}
            flanks = {}
            for flank in FLANKS:
                where = f"machine.{member}.{flank}"
                own = read_table(sub, flank, f"machine.{member}")
                check_keys(own, FLANK_KEYS, where)
                # errors name the table where the value came from
                source = where if own else f"machine.{member}"
                # drive: pinion convex, gear concave; coast: the other flanks
                side = int((flank == "convex") != (member == "pinion"))
                flanks[flank] = _parse_flank({**member_defaults, **own}, source, pair, rho, side)
            members[member] = EpicycloidMember(**flanks)
        return EpicycloidMachine(blade_groups=nb, blade_module_mm=mb, **members)

    def basic_settings(self, design: Design) -> MachineSettings:
        out = {}
        for member in MEMBERS:
            values: dict[str, Any] = {}
            for prefix, flank in (("", DRIVE_FLANK[member]), ("coast_", COAST_FLANK[member])):
                spec = design.machine.member(member).flank(flank)
                _, _, disk = flank_system(design, member, flank)
                rb = spec.blade_profile_radius_mm
                values.update(
                    {
                        f"{prefix}cutter_head_radius_mm": spec.cutter_head_radius_mm,
                        f"{prefix}cutter_edge_radius_mm": 0.0 if math.isinf(rb) else rb,
                        f"{prefix}cutter_edge_curvature_per_mm": spec.profile_curvature_per_mm,
                        f"{prefix}slope_angle_deg": disk.assembly_angle_deg,
                        f"{prefix}machine_distance_mm": disk.machine_distance_mm,
                        f"{prefix}cradle_angle_deg": disk.cradle_angle_deg,
                        f"{prefix}base_circle_radius_mm": disk.base_circle_radius_mm,
                        f"{prefix}rolling_circle_radius_mm": disk.rolling_circle_radius_mm,
                    }
                )
            common = member_work(design, member)
            out[member] = EpicycloidSettings(
                **values,
                blade_groups=common.blade_groups,
                blade_module_mm=common.blade_module_mm,
                machine_root_angle_deg=common.machine_root_angle_deg,
                machine_center_to_back_mm=common.machine_center_to_back_mm,
                blank_offset_mm=common.blank_offset_mm,
                sliding_base_mm=common.sliding_base_mm,
                gear_to_cradle_roll=common.gear_to_cradle_roll,
                gear_to_blade_roll=common.gear_to_blade_roll,
            )
        notes = [
            "unprefixed settings: the drive flank (pinion convex, gear concave, seed 003 Tables "
            "2-3); coast_*: pinion concave, gear convex",
            "cutter_edge_radius_mm = 0 means a straight blade (R_b = inf)",
        ]
        if not design.compensation.is_zero:
            notes.append(
                "settings compensate [compensation] as the cyclo-palloid model (seed 001 "
                "section 4): machine root angles and roll ratios for Sigma + dGamma, dXD, dEm"
            )
        return MachineSettings(model=self.name, notes=tuple(notes), **out)

    def generate_flanks(
        self,
        design: Design,
        *,
        member: str,
        grid: FlankGrid | None = None,
        flanks: tuple[str, ...] = ("convex", "concave"),
        tool_pass: int = 0,
    ) -> dict[str, FlankMap]:
        """Both flanks (or ``flanks``) of the member's tooth 0 in one batch; with ``tool_pass``
        k, those cut by the k-th blade group."""
        for flank in flanks:
            check_member_and_flank(member, flank)
        systems, turns, notes = {}, {}, {}
        for flank in flanks:
            systems[flank], turns[flank], _ = flank_system(
                design, member, flank, tool_pass=tool_pass
            )
            spec = design.machine.member(member).flank(flank)
            notes[flank] = (
                f"{BLADE_OF_FLANK[flank]} blades (epicycloid): R_h = "
                f"{spec.cutter_head_radius_mm:g} mm, R_b = {spec.blade_profile_radius_mm:g} mm",
            )
        return generate_flanks(
            design.blank,
            member,
            design.pair.pinion_teeth if member == "pinion" else design.pair.gear_teeth,
            systems,
            turns,
            grid=grid or FlankGrid(),
            tool_pass=tool_pass,
            notes=notes,
        )

    def rexs_export(self, design: Design) -> RexsMachine:
        """Each flank's head and derived settings (:mod:`gearopt_plugins.epicycloid.rexs`)."""
        settings = self.basic_settings(design)
        return ep_rexs.to_rexs(
            design.machine, {m: settings.member(m) for m in MEMBERS}, DRIVE_FLANK
        )

    def rexs_import(self, machine: RexsMachine, pair: PairData) -> dict[str, Any]:
        return ep_rexs.from_rexs(machine)

    def cutter_catalogue(self, design: Design) -> tuple[SearchDimension, ...]:
        """The head radius (``cutter_head_radius_mm`` of the whole machine or of a member,
        where a flank's table does not override it) over the catalogue's epicycloid heads with
        the design's blade groups that the slope angle allows."""
        machine = design.machine
        return face_hobbing_dimensions(
            EPICYCLOID,
            (
                "machine.cutter_head_radius_mm",
                *(f"machine.{m}.cutter_head_radius_mm" for m in MEMBERS),
            ),
            blade_groups=machine.blade_groups,
            module_mm=machine.blade_module_mm,
        )

    def search_space(self, design: Design) -> tuple[SearchDimension, ...]:
        machine: EpicycloidMachine = design.machine
        rho = machine.blade_module_mm * machine.blade_groups / 2.0
        min_rb = MIN_PROFILE_RADIUS_DEPTHS * max(design.blank.whole_depth_mm)
        dims = []
        for member in MEMBERS:
            for flank in FLANKS:
                spec = machine.member(member).flank(flank)
                prefix = f"machine.{member}.{flank}."
                rh = spec.cutter_head_radius_mm
                dims.append(
                    SearchDimension(
                        key=prefix + "cutter_head_radius_mm",
                        low=max(0.97 * rh, 1.1 * rho),
                        high=1.03 * rh,
                    )
                )
                dims.append(
                    SearchDimension(
                        key=prefix + "blade_profile_radius_mm",
                        low=max(250.0, 1.01 * min_rb),
                        high=20000.0,
                        log=True,
                    )
                )
        return tuple(dims)


@hookimpl
def gearopt_machine_models() -> list[BaseMachineModel]:
    """The epicycloid machine model."""
    return [Epicycloid()]
