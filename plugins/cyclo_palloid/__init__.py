"""Klingelnberg cyclo-palloid (dual-head face hobbing) machine model, seed 001.

Analytic part: the slope angle and eccentricity of the dual-head cutter (eqs 5-12), machine
distances and cradle angles (13-14), roll ratios (25, 30), the settings under an additional slope
angle (32-38, what Table 3 uses) and the compensation of alignment errors (49-59).

Design keys (``[machine]``; member keys in ``[machine.pinion]`` / ``[machine.gear]``, or in
``[machine]`` itself as a default for both members)::

    [machine]
    model = "cyclo-palloid"
    blade_groups = 5                        # N_b
    blade_module_mm = 3.3973                # m_b; default 2 A_m cos(psi_m) sin(g1) / N1 (= m_mn)

    [machine.pinion]
    inner_cutter_radius_mm = 75.0           # r_ci (inner blades cut the convex flank)
    outer_cutter_radius_mm = 75.0           # r_co (outer blades: concave flank); default r_ci
    additional_slope_angle_deg = 0.103669   # dnu (eqs 33-38); "auto" = solved from the thickness
    blade_parabola_coefficient_per_mm = 0.0 # a_p (eq 2)
    parabola_apex_mm = 0.0                  # u_o (eq 2)
    rake_angle_deg = 0.0                    # alpha_ir (eq 1)
    profile_pressure_angle_deg = 20.0       # alpha_i on the front plane; default the pair's

Conventions: the settings are those of seed 001 Fig. 5 (a right-hand member); a left-hand member
uses the same magnitudes in the mirrored machine, so they do not depend on the hand. In face
cutting the inner blades cut the convex flank and the outer blades the concave flank of every
member (stated here; the flank generator tests it on the generated geometry).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

from gearopt import hookimpl
from gearopt.design import MEMBERS, Design, PairData
from gearopt.errors import DesignError
from gearopt.flank import FlankGrid, FlankMap, check_member_and_flank
from gearopt.machine import BaseMachineModel, MachineSettings, SearchDimension
from gearopt.rexs.attributes import RexsMachine
from gearopt.validate import check_keys, read_integer, read_number, read_table
from gearopt_plugins.cutters.catalogue import CYCLO_PALLOID, face_hobbing_dimensions
from gearopt_plugins.cyclo_palloid import rexs as cp_rexs
from gearopt_plugins.cyclo_palloid.settings import (
    AUTO,
    CycloPalloidMachine,
    CycloPalloidMember,
    CycloPalloidSettings,
    blade_systems,
    flank_turn_rad,
    member_settings,
)
from gearopt_plugins.cyclo_palloid.thickness import solve_additional_slope_angle
from gearopt_plugins.face_hobbing import kernels as hobbing_kernels
from gearopt_plugins.face_hobbing.generation import BLADE_OF_FLANK, generate_flanks
from gearopt_plugins.face_hobbing.settings import (
    eccentricity,
    machine_distance_and_cradle_angle,
    slope_angle_rad,
)

__all__ = [
    "CycloPalloid",
    "CycloPalloidMachine",
    "CycloPalloidMember",
    "CycloPalloidSettings",
    "slope_angle_rad",
    "eccentricity",
    "machine_distance_and_cradle_angle",
]

MEMBER_KEYS = (
    "inner_cutter_radius_mm",
    "outer_cutter_radius_mm",
    "additional_slope_angle_deg",
    "blade_parabola_coefficient_per_mm",
    "parabola_apex_mm",
    "rake_angle_deg",
    "profile_pressure_angle_deg",
)
MACHINE_KEYS = ("blade_groups", "blade_module_mm", *MEMBERS, *MEMBER_KEYS)


# --- data ----------------------------------------------------------------------------------------


#: the last member settings whose additional slope angle was solved from the thickness, keyed by
#: everything the solve reads (a study changing only the pinion solves the gear once per worker)
_SOLVED: dict[tuple, Any] = {}


def _solved_settings(design: Design, member: str):
    """The member's settings with the additional slope angle solved from its tooth thickness
    (seed 001 eqs 39-48), remembered for the same inputs."""
    machine = design.machine
    key = (
        member,
        design.pair,
        machine.blade_groups,
        machine.blade_module_mm,
        machine.member(member),
        design.compensation,
    )
    found = _SOLVED.pop(key, None)
    if found is None:
        found = solve_additional_slope_angle(
            design, member, lambda dnu_deg: member_settings(design, member, dnu_deg)
        ).settings
    _SOLVED[key] = found  # the most recent last
    while len(_SOLVED) > 16:
        del _SOLVED[next(iter(_SOLVED))]
    return found


def _settings_of(design: Design, member: str):
    """One member's basic settings (its additional slope angle solved from the thickness where
    it is ``"auto"``)."""
    spec = design.machine.member(member)
    if spec.is_auto:
        return _solved_settings(design, member)
    return member_settings(design, member, spec.additional_slope_angle_deg)


# --- parsing -------------------------------------------------------------------------------------


def _parse_member(
    table: Mapping[str, Any], defaults: Mapping[str, Any], where: str, pair: PairData, rho_mm: float
) -> CycloPalloidMember:
    check_keys(table, MEMBER_KEYS, where)
    merged = {**defaults, **table}
    rci = read_number(merged, "inner_cutter_radius_mm", where, gt=0.0)
    if rci <= rho_mm:
        raise DesignError(
            f"{where}.inner_cutter_radius_mm",
            rci,
            f"must exceed blade_module_mm * blade_groups / 2 = {rho_mm:.4f} mm "
            "(eq 9 of seed 001, sin nu = m_b N_b / (2 r_ci), has no solution)",
        )
    rco = read_number(merged, "outer_cutter_radius_mm", where, rci, gt=0.0)
    dnu = merged.get("additional_slope_angle_deg", 0.0)
    if isinstance(dnu, str):
        if dnu.lower() != AUTO:
            raise DesignError(
                f"{where}.additional_slope_angle_deg", dnu, 'must be a number in degrees or "auto"'
            )
        dnu = AUTO
        for key in ("mean_normal_chordal_addendum_mm", "mean_normal_chordal_thickness_mm"):
            if getattr(pair, key) is None:
                raise DesignError(
                    f"{where}.additional_slope_angle_deg",
                    dnu,
                    f'"auto" solves the thickness, so pair.{key} is required',
                )
    else:
        dnu = read_number(merged, "additional_slope_angle_deg", where, 0.0, gt=-5.0, lt=5.0)
        nu = math.asin(rho_mm / rci)
        nu_prime = nu + math.radians(dnu)
        if not 0.0 < nu_prime < math.pi / 2:
            raise DesignError(
                f"{where}.additional_slope_angle_deg",
                dnu,
                f"nu + dnu must lie in (0, 90) deg; nu = {math.degrees(nu):.6f} deg",
            )
        if rco < rci * math.sin(nu_prime):
            raise DesignError(
                f"{where}.outer_cutter_radius_mm",
                rco,
                f"must be >= inner_cutter_radius_mm sin(nu + dnu) = {rci * math.sin(nu_prime):.4f} "
                "mm (eq 33 of seed 001: the eccentricity has no solution)",
            )
    depth = max(pair.blank.whole_depth_mm)
    return CycloPalloidMember(
        inner_cutter_radius_mm=rci,
        outer_cutter_radius_mm=rco,
        additional_slope_angle_deg=dnu,
        blade_parabola_coefficient_per_mm=read_number(
            merged, "blade_parabola_coefficient_per_mm", where, 0.0, gt=-0.1, lt=0.1
        ),
        parabola_apex_mm=read_number(merged, "parabola_apex_mm", where, 0.0, gt=-depth, lt=depth),
        rake_angle_deg=read_number(merged, "rake_angle_deg", where, 0.0, gt=-30.0, lt=30.0),
        profile_pressure_angle_deg=read_number(
            merged, "profile_pressure_angle_deg", where, pair.pressure_angle_deg, gt=0.0, lt=45.0
        ),
    )


# --- the model -----------------------------------------------------------------------------------


class CycloPalloid(BaseMachineModel):
    """Klingelnberg cyclo-palloid dual-head face hobbing (seed 001)."""

    name = "cyclo-palloid"
    description = "Klingelnberg cyclo-palloid dual-head face hobbing, uniform depth (seed 001)"

    def warm_kernels(self) -> None:
        """The face-hobbing kernels of flank generation (compiled, or loaded from the cache)."""
        hobbing_kernels.warm()

    def parse_machine(self, table: Mapping[str, Any], pair: PairData) -> CycloPalloidMachine:
        pair.require_uniform_depth(self.name)
        if pair.unequal_pressure_angles:
            raise DesignError(
                "pair.pressure_angle_deg",
                list(pair.pressure_angles_deg),
                "the cyclo-palloid model grinds one profile_pressure_angle_deg per member into "
                "both blade systems (inner: convex flanks, outer: concave flanks), so it cannot "
                "cut unequal drive and coast pressure angles: give one angle",
            )
        check_keys(table, MACHINE_KEYS, "machine")
        nb = read_integer(table, "blade_groups", "machine", ge=1, le=30)
        default_mb = pair.mean_normal_module_mm
        mb = read_number(table, "blade_module_mm", "machine", default_mb, gt=0.0)
        rho = mb * nb / 2.0
        defaults = {k: v for k, v in table.items() if k in MEMBER_KEYS}
        members = {}
        for member in MEMBERS:
            if member not in table:
                if "inner_cutter_radius_mm" not in defaults:
                    raise DesignError(
                        f"machine.{member}",
                        rule=f"table [machine.{member}] is required (or give "
                        "inner_cutter_radius_mm in [machine] for both members)",
                    )
            sub = read_table(table, member, "machine")
            members[member] = _parse_member(sub, defaults, f"machine.{member}", pair, rho)
        return CycloPalloidMachine(blade_groups=nb, blade_module_mm=mb, **members)

    def basic_settings(self, design: Design) -> MachineSettings:
        settings = {member: _settings_of(design, member) for member in MEMBERS}
        notes = []
        if not design.compensation.is_zero:
            notes.append(
                "settings compensate [compensation] (seed 001 section 4): machine root angles and "
                "roll ratios for Sigma + dGamma (eqs 49-56), dXD1 = dA1, dEm1 = dE, dXD2 = dA2 "
                "(eqs 57-59); cutter settings unchanged"
            )
        auto = [m for m in MEMBERS if design.machine.member(m).is_auto]
        if auto:
            notes.append(
                f"additional slope angle of the {' and '.join(auto)} solved from the mean normal "
                "chordal thickness (seed 001 eqs 39-48)"
            )
        return MachineSettings(model=self.name, notes=tuple(notes), **settings)

    def rexs_export(self, design: Design) -> RexsMachine:
        """Each flank's blades and settings (:mod:`gearopt_plugins.cyclo_palloid.rexs`), an
        ``"auto"`` additional slope angle written as the value solved from the thickness."""
        settings = self.basic_settings(design)
        return cp_rexs.to_rexs(design.machine, {m: settings.member(m) for m in MEMBERS})

    def rexs_import(self, machine: RexsMachine, pair: PairData) -> dict[str, Any]:
        return cp_rexs.from_rexs(machine)

    def generate_flanks(
        self,
        design: Design,
        *,
        member: str,
        grid: FlankGrid | None = None,
        flanks: tuple[str, ...] = ("convex", "concave"),
        tool_pass: int = 0,
    ) -> dict[str, FlankMap]:
        """Both flanks (or ``flanks``) of the member's tooth 0, solved in one batch; with
        ``tool_pass`` k, those cut by the k-th blade group. Convex: inner blades; concave: outer
        blades (see :mod:`gearopt_plugins.face_hobbing.generation` for the phase of the outer
        blades, the masks and the tooth numbering): those of tooth ``tool_pass`` of a right-hand
        member, ``-tool_pass`` of a left-hand one, when the work indexes exactly (dnu = 0 and
        m_b the mean normal module, so that m_gb = N_b / N)."""
        for flank in flanks:
            check_member_and_flank(member, flank)
        settings = _settings_of(design, member)  # (the other member's not needed)
        systems = blade_systems(design, member, settings, tool_pass=tool_pass)
        return generate_flanks(
            design.blank,
            member,
            design.pair.pinion_teeth if member == "pinion" else design.pair.gear_teeth,
            {f: systems[BLADE_OF_FLANK[f]] for f in flanks},
            {f: flank_turn_rad(design, member, f, systems) for f in flanks},
            grid=grid or FlankGrid(),
            tool_pass=tool_pass,
            notes={f: (f"{BLADE_OF_FLANK[f]} blades (cyclo-palloid)",) for f in flanks},
        )

    def cutter_catalogue(self, design: Design) -> tuple[SearchDimension, ...]:
        """Each member's head radius (``inner_cutter_radius_mm``; the outer head follows it
        unless given) over the catalogue's cyclo-palloid heads with the design's blade groups
        that the slope angle allows (:mod:`gearopt_plugins.cutters.catalogue`)."""
        machine = design.machine
        return face_hobbing_dimensions(
            CYCLO_PALLOID,
            tuple(f"machine.{m}.inner_cutter_radius_mm" for m in MEMBERS),
            blade_groups=machine.blade_groups,
            module_mm=machine.blade_module_mm,
        )

    def search_space(self, design: Design) -> tuple[SearchDimension, ...]:
        machine = design.machine
        rho = machine.blade_module_mm * machine.blade_groups / 2.0
        dims = []
        for member in MEMBERS:
            spec = machine.member(member)
            prefix = f"machine.{member}."
            for key in ("inner_cutter_radius_mm", "outer_cutter_radius_mm"):
                radius = getattr(spec, key)
                dims.append(
                    SearchDimension(
                        key=prefix + key, low=max(0.9 * radius, 1.1 * rho), high=1.1 * radius
                    )
                )
            if not spec.is_auto:
                # keep nu + dnu > 0 over the whole radius range (nu is smallest at the largest r_ci)
                nu_min_deg = math.degrees(math.asin(rho / (1.1 * spec.inner_cutter_radius_mm)))
                dims.append(
                    SearchDimension(
                        key=prefix + "additional_slope_angle_deg",
                        low=max(-0.5, -0.5 * nu_min_deg),
                        high=0.5,
                    )
                )
            dims.append(
                SearchDimension(
                    key=prefix + "blade_parabola_coefficient_per_mm", low=0.0, high=0.005
                )
            )
        return tuple(dims)


@hookimpl
def gearopt_machine_models() -> list[BaseMachineModel]:
    """The cyclo-palloid machine model."""
    return [CycloPalloid()]
