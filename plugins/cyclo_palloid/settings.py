"""Cyclo-palloid settings: the dual head of seed 001 on the face-hobbing chain.

The model's own part of the settings is its head (eqs 5-12; 33-38 under an additional slope
angle dnu): the slope angle nu of eq 9 from the blade module and groups, the inner blade system
at the assembly angle nu' = nu + dnu, the outer at nu' - gamma' with the eccentricity e' and
auxiliary angle gamma' of eq 33, both on the roll circle rho' = r_ci sin(nu'). The rest is the
face-hobbing chain every Klingelnberg model shares (:mod:`gearopt_plugins.face_hobbing`): the
work's settings and roll ratios (eqs 25, 37, 49-59), each disk's machine distance and cradle
angle (eqs 13-14, 34-35), the blade systems and their flanks.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from gearopt.design import Design
from gearopt.errors import SettingsError
from gearopt_plugins.face_hobbing.family import BladeSystem
from gearopt_plugins.face_hobbing.generation import (
    SIDE_OF_BLADE,
    BladeEdge,
    blade_system,
    outer_phase_rad,
    tooth_turn_rad,
)
from gearopt_plugins.face_hobbing.settings import (
    CutterDisk,
    WorkSettings,
    cutter_disk,
    eccentricity,
    slope_angle_rad,
    work_settings,
)

__all__ = [
    "AUTO",
    "CycloPalloidMachine",
    "CycloPalloidMember",
    "CycloPalloidSettings",
    "blade_systems",
    "flank_turn_rad",
    "member_settings",
]

AUTO = "auto"
BLADES = ("inner", "outer")


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

    def work(self, spiral_angle_deg: float, mean_cone_distance_mm: float) -> WorkSettings:
        """The work's settings these settings hold (the pair's mean spiral angle and cone
        distance place the pitch point)."""
        return WorkSettings(
            blade_groups=self.blade_groups,
            blade_module_mm=self.blade_module_mm,
            mean_cone_distance_mm=mean_cone_distance_mm,
            spiral_angle_deg=spiral_angle_deg,
            machine_root_angle_deg=self.machine_root_angle_deg,
            machine_center_to_back_mm=self.machine_center_to_back_mm,
            blank_offset_mm=self.blank_offset_mm,
            sliding_base_mm=self.sliding_base_mm,
            gear_to_cradle_roll=self.gear_to_cradle_roll,
            gear_to_blade_roll=self.gear_to_blade_roll,
            roll_circle_radius_mm=self.roll_circle_radius_mm,
            crown_gear_radius_mm=self.crown_gear_radius_mm,
        )

    def disk(self, blades: str) -> CutterDisk:
        """The disk of the ``"inner"`` or ``"outer"`` blade system."""
        return CutterDisk(
            cutter_radius_mm=getattr(self, f"{blades}_cutter_radius_mm"),
            assembly_angle_deg=getattr(self, f"{blades}_assembly_angle_deg"),
            machine_distance_mm=getattr(self, f"{blades}_machine_distance_mm"),
            cradle_angle_deg=getattr(self, f"{blades}_cradle_angle_deg"),
            base_circle_radius_mm=getattr(self, f"{blades}_base_circle_radius_mm"),
            rolling_circle_radius_mm=getattr(self, f"{blades}_rolling_circle_radius_mm"),
        )


def member_settings(
    design: Design, member: str, additional_slope_angle_deg: float
) -> CycloPalloidSettings:
    """Basic settings of one member for a given additional slope angle (eqs 5-14, 25, 30-38,
    and the compensation of section 4, eqs 49-59)."""
    machine = design.machine
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
    work = work_settings(
        design.pair,
        design.compensation,
        member,
        blade_groups=machine.blade_groups,
        blade_module_mm=machine.blade_module_mm,
        roll_circle_radius_mm=rci * math.sin(nu_prime),
    )
    disks = {
        "inner": cutter_disk(work, cutter_radius_mm=rci, assembly_angle_rad=nu_prime),  # eq 11
        "outer": cutter_disk(work, cutter_radius_mm=rco, assembly_angle_rad=nu_prime - gamma),
    }
    values: dict[str, Any] = {}
    for k, disk in disks.items():
        values[f"{k}_machine_distance_mm"] = disk.machine_distance_mm
        values[f"{k}_cradle_angle_deg"] = disk.cradle_angle_deg
        values[f"{k}_assembly_angle_deg"] = disk.assembly_angle_deg
        values[f"{k}_rolling_circle_radius_mm"] = disk.rolling_circle_radius_mm
        values[f"{k}_base_circle_radius_mm"] = disk.base_circle_radius_mm
    return CycloPalloidSettings(
        slope_angle_deg=math.degrees(nu),
        additional_slope_angle_deg=float(additional_slope_angle_deg),
        inner_cutter_radius_mm=rci,
        outer_cutter_radius_mm=rco,
        blade_module_mm=machine.blade_module_mm,
        blade_groups=machine.blade_groups,
        eccentricity_mm=e,
        eccentricity_angle_deg=math.degrees(gamma),
        machine_root_angle_deg=work.machine_root_angle_deg,
        machine_center_to_back_mm=work.machine_center_to_back_mm,
        blank_offset_mm=work.blank_offset_mm,
        sliding_base_mm=work.sliding_base_mm,
        gear_to_cradle_roll=work.gear_to_cradle_roll,
        gear_to_blade_roll=work.gear_to_blade_roll,
        roll_circle_radius_mm=work.roll_circle_radius_mm,
        crown_gear_radius_mm=work.crown_gear_radius_mm,
        **values,
    )


def blade_systems(
    design: Design, member: str, settings: CycloPalloidSettings, *, tool_pass: int = 0
) -> dict[str, BladeSystem]:
    """The inner and outer blade systems of ``member`` from its basic ``settings``; those of
    blade group ``tool_pass`` (counted against the cutter's rotation) when it is not 0."""
    spec = design.machine.member(member)
    work = settings.work(design.pair.mean_spiral_angle_deg, design.blank.mean_cone_distance_mm)
    blade = BladeEdge(
        pressure_angle_deg=spec.profile_pressure_angle_deg,
        rake_angle_deg=spec.rake_angle_deg,
        parabola_per_mm=spec.blade_parabola_coefficient_per_mm,
        parabola_apex_mm=spec.parabola_apex_mm,
    )
    return {
        name: blade_system(
            work, settings.disk(name), blade, side=SIDE_OF_BLADE[name], tool_pass=tool_pass
        )
        for name in BLADES
    }


def flank_turn_rad(
    design: Design, member: str, flank: str, systems: dict[str, BladeSystem]
) -> float:
    """Turn of ``flank``'s envelope onto tooth 0 (:func:`~gearopt_plugins.face_hobbing.
    generation.tooth_turn_rad`): the concave flank's by the lead of the dual head's outer blades
    (:func:`~gearopt_plugins.face_hobbing.generation.outer_phase_rad`)."""
    lead = 0.0
    if flank != "convex":
        lead = outer_phase_rad(
            blade_groups=design.machine.blade_groups, inner=systems["inner"], outer=systems["outer"]
        )
    return tooth_turn_rad(
        flank,
        teeth=design.pair.pinion_teeth if member == "pinion" else design.pair.gear_teeth,
        gear_to_blade_roll=systems["outer"].gear_to_blade_roll,
        lead_rad=lead,
    )
