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
from dataclasses import dataclass
from typing import Any

from gearopt import hookimpl
from gearopt.blank import pitch_angles_rad
from gearopt.design import MEMBERS, Design, PairData
from gearopt.errors import DesignError, SettingsError
from gearopt.flank import FlankGrid, FlankMap, check_member_and_flank
from gearopt.machine import BaseMachineModel, MachineSettings, SearchDimension
from gearopt.validate import (
    check_keys,
    read_integer,
    read_number,
    read_table,
)
from gearopt_plugins.face_hobbing.generation import generate_flanks, solve_additional_slope_angle

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
AUTO = "auto"


# --- kernels: pure functions of floats, radians inside -------------------------------------------


def slope_angle_rad(
    *, blade_module_mm: float, blade_groups: int, inner_cutter_radius_mm: float
) -> float:
    """Slope angle nu = asin(m_b N_b / (2 r_ci)) (seed 001 eqs 5, 9)."""
    return math.asin(blade_module_mm * blade_groups / (2.0 * inner_cutter_radius_mm))


def eccentricity(
    *, inner_cutter_radius_mm: float, outer_cutter_radius_mm: float, slope_angle_rad: float
) -> tuple[float, float]:
    """Eccentricity e and auxiliary angle gamma of the dual head (eqs 10, 12; 33, 36 with nu').

    Returns ``(e_mm, gamma_rad)``. With gamma, r_co sin(nu - gamma) = r_ci sin(nu): both blade
    systems have the same roll circle (rho_i = rho_o).
    """
    rci, rco, nu = inner_cutter_radius_mm, outer_cutter_radius_mm, slope_angle_rad
    e = math.sqrt(rco**2 - (rci * math.sin(nu)) ** 2) - rci * math.cos(nu)
    gamma = math.asin(e * math.sin(nu) / rco)
    return e, gamma


def machine_distance_and_cradle_angle(
    *, mean_cone_distance_mm: float, spiral_angle_rad: float, cutter_radius_mm: float, nu_rad: float
) -> tuple[float, float]:
    """Machine distance M_d and cradle angle q_2 of one blade system (eqs 13-14; 34-35).

    M_d^2 = A_m^2 + r_c^2 - 2 A_m r_c sin(psi_m - nu); q_2 from sin q_2 = r_c cos(psi_m - nu) / M_d,
    evaluated as atan2(r_c cos(psi_m - nu), A_m - r_c sin(psi_m - nu)) so that the branch is the
    one of Fig. 5 (the pitch point M at distance A_m on x_m) without an arcsin's loss of precision.
    Returns ``(M_d_mm, q_2_rad)``.
    """
    am, rc, arg = mean_cone_distance_mm, cutter_radius_mm, spiral_angle_rad - nu_rad
    md = math.sqrt(am**2 + rc**2 - 2.0 * am * rc * math.sin(arg))
    q2 = math.atan2(rc * math.cos(arg), am - rc * math.sin(arg))
    return md, q2


# --- data ----------------------------------------------------------------------------------------


@dataclass(frozen=True, kw_only=True)
class CycloPalloidMember:
    """Cutter and blade data of one member (``[machine.pinion]`` or ``[machine.gear]``)."""

    inner_cutter_radius_mm: float
    outer_cutter_radius_mm: float
    additional_slope_angle_deg: float | str = 0.0
    blade_parabola_coefficient_per_mm: float = 0.0
    parabola_apex_mm: float = 0.0
    rake_angle_deg: float = 0.0
    profile_pressure_angle_deg: float = 20.0

    @property
    def is_auto(self) -> bool:
        """True when the additional slope angle is to be solved from the tooth thickness."""
        return self.additional_slope_angle_deg == AUTO


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


@dataclass(frozen=True, kw_only=True)
class CycloPalloidMachine:
    """The ``[machine]`` table of a cyclo-palloid design."""

    blade_groups: int
    blade_module_mm: float
    pinion: CycloPalloidMember
    gear: CycloPalloidMember

    def member(self, name: str) -> CycloPalloidMember:
        """Data of ``"pinion"`` or ``"gear"``."""
        return getattr(self, name)


@dataclass(frozen=True, kw_only=True)
class CycloPalloidSettings:
    """Basic machine-tool settings of one member (seed 001 Table 3 and eqs 5-59).

    ``slope_angle_deg`` is nu of eq 9; the blade systems run at nu' = nu + dnu (inner) and
    nu' - gamma' (outer). Base and rolling circles: M_d = rho_b + rho_r with
    rho_r / rho_b = rho' / rho_cr (eq 29), rho' = r_ci sin nu' and rho_cr = A_m cos psi_m.
    """

    slope_angle_deg: float
    additional_slope_angle_deg: float
    inner_cutter_radius_mm: float
    outer_cutter_radius_mm: float
    blade_module_mm: float
    blade_groups: int
    eccentricity_mm: float
    eccentricity_angle_deg: float
    inner_assembly_angle_deg: float
    outer_assembly_angle_deg: float
    inner_machine_distance_mm: float
    inner_cradle_angle_deg: float
    outer_machine_distance_mm: float
    outer_cradle_angle_deg: float
    machine_root_angle_deg: float
    machine_center_to_back_mm: float
    blank_offset_mm: float
    sliding_base_mm: float
    gear_to_cradle_roll: float
    gear_to_blade_roll: float
    roll_circle_radius_mm: float
    crown_gear_radius_mm: float
    inner_base_circle_radius_mm: float
    inner_rolling_circle_radius_mm: float
    outer_base_circle_radius_mm: float
    outer_rolling_circle_radius_mm: float


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


def member_settings(design: Design, member: str, additional_slope_angle_deg: float):
    """Basic settings of one member for a given additional slope angle (eqs 5-14, 25, 30-38,
    and the compensation of section 4, eqs 49-59)."""
    pair, machine, comp = design.pair, design.machine, design.compensation
    am = pair.blank.mean_cone_distance_mm
    psi = math.radians(pair.mean_spiral_angle_deg)
    # eqs 49-52: the auxiliary pitch angles of the pair redesigned for Sigma + dGamma
    sigma = math.radians(pair.shaft_angle_deg + comp.shaft_angle_deg)
    gamma_m = pitch_angles_rad(pair.pinion_teeth, pair.gear_teeth, sigma)[MEMBERS.index(member)]
    offsets = {
        "pinion": (comp.pinion_axial_mm, comp.offset_mm),  # eqs 58-59
        "gear": (comp.gear_axial_mm, 0.0),  # eq 57
    }
    spec = machine.member(member)
    rci, rco = spec.inner_cutter_radius_mm, spec.outer_cutter_radius_mm
    nu = slope_angle_rad(
        blade_module_mm=machine.blade_module_mm,
        blade_groups=machine.blade_groups,
        inner_cutter_radius_mm=rci,
    )
    nu_prime = nu + math.radians(additional_slope_angle_deg)
    if not 0.0 < nu_prime < math.pi / 2 or rco < rci * math.sin(nu_prime):
        raise SettingsError(
            f"machine.{member}.additional_slope_angle_deg",
            additional_slope_angle_deg,
            f"nu + dnu must lie in (0, 90) deg with r_co >= r_ci sin(nu + dnu) (eq 33); "
            f"nu = {math.degrees(nu):.6f} deg",
        )
    e, gamma = eccentricity(
        inner_cutter_radius_mm=rci, outer_cutter_radius_mm=rco, slope_angle_rad=nu_prime
    )
    nu_k = {"inner": nu_prime, "outer": nu_prime - gamma}  # eqs 11, 38
    radii = {"inner": rci, "outer": rco}
    rho_prime = rci * math.sin(nu_prime)
    rho_cr = am * math.cos(psi)
    values: dict[str, Any] = {}
    for k in ("inner", "outer"):
        md, q2 = machine_distance_and_cradle_angle(
            mean_cone_distance_mm=am,
            spiral_angle_rad=psi,
            cutter_radius_mm=radii[k],
            nu_rad=nu_k[k],
        )
        values[f"{k}_machine_distance_mm"] = md
        values[f"{k}_cradle_angle_deg"] = math.degrees(q2)
        values[f"{k}_assembly_angle_deg"] = math.degrees(nu_k[k])
        values[f"{k}_rolling_circle_radius_mm"] = md * rho_prime / (rho_prime + rho_cr)
        values[f"{k}_base_circle_radius_mm"] = md * rho_cr / (rho_prime + rho_cr)
    center_to_back, blank_offset = offsets[member]
    return CycloPalloidSettings(
        slope_angle_deg=math.degrees(nu),
        additional_slope_angle_deg=float(additional_slope_angle_deg),
        inner_cutter_radius_mm=rci,
        outer_cutter_radius_mm=rco,
        blade_module_mm=machine.blade_module_mm,
        blade_groups=machine.blade_groups,
        eccentricity_mm=e,
        eccentricity_angle_deg=math.degrees(gamma),
        machine_root_angle_deg=math.degrees(gamma_m),
        machine_center_to_back_mm=center_to_back,
        blank_offset_mm=blank_offset,
        sliding_base_mm=0.0,
        gear_to_cradle_roll=1.0 / math.sin(gamma_m),  # eqs 25, 53-54
        gear_to_blade_roll=rho_prime / (math.sin(gamma_m) * rho_cr),  # eqs 37, 55-56
        roll_circle_radius_mm=rho_prime,
        crown_gear_radius_mm=rho_cr,
        **values,
    )


# --- the model -----------------------------------------------------------------------------------


class CycloPalloid(BaseMachineModel):
    """Klingelnberg cyclo-palloid dual-head face hobbing (seed 001)."""

    name = "cyclo-palloid"
    description = "Klingelnberg cyclo-palloid dual-head face hobbing, uniform depth (seed 001)"

    def parse_machine(self, table: Mapping[str, Any], pair: PairData) -> CycloPalloidMachine:
        pair.require_uniform_depth(self.name)
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
        settings = {}
        for member in MEMBERS:
            spec = design.machine.member(member)
            if spec.is_auto:
                settings[member] = _solved_settings(design, member)
            else:
                settings[member] = member_settings(design, member, spec.additional_slope_angle_deg)
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
        blades, the masks and the tooth numbering)."""
        for flank in flanks:
            check_member_and_flank(member, flank)
        settings = self.basic_settings(design).member(member)
        return generate_flanks(
            design, member, settings, grid=grid or FlankGrid(), flanks=flanks, tool_pass=tool_pass
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
