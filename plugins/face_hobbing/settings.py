"""Basic settings of the face-hobbing chain, from the cutter head to the machine (seed 001).

What a cutter head of either Klingelnberg system turns into on the machine. The head is the
model's own (the cyclo-palloid's dual head of seed 001 eqs 5-12, 33-38; the epicycloid's single
radius per flank, seed 003); from there on the chain is one:

* the work on the machine (:class:`WorkSettings`, :func:`work_settings`): its machine root angle
  (the pitch angle, of the pair redesigned for Sigma + dGamma under compensation, eqs 49-52),
  its offsets (eqs 57-59), and the roll ratios m_gc = 1 / sin(gamma_m) (eqs 25, 53-54) and
  m_gb = rho' / (sin(gamma_m) rho_cr) (eqs 37, 55-56) of a head whose roll circle has the
  radius rho', rolling on the crown gear's base circle rho_cr = A_m cos(psi_m);
* each blade system's disk on the cradle (:class:`CutterDisk`, :func:`cutter_disk`): a disk of
  cutter radius r_c whose blade meets the pitch point M at the assembly angle nu_k stands at the
  machine distance M_d and cradle angle q_2 of eqs 13-14 (34-35 under dnu); its roll circle
  and base circle split M_d as rho' : rho_cr (eq 29).

A head's roll circle is the same for all its blade systems: rho' = r_ci sin(nu') for the dual
head (the eccentricity makes r_co sin(nu' - gamma') equal to it, eq 33), N_b m_b / 2 for a
single radius (seed 001 eq 9 with dnu = 0). Settings are reported in degrees and millimetres;
the flanks are generated from them as reported (:mod:`gearopt_plugins.face_hobbing.generation`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from gearopt.blank import pitch_angles_rad
from gearopt.design import MEMBERS, Misalignment, PairData

__all__ = [
    "CutterDisk",
    "WorkSettings",
    "cutter_disk",
    "eccentricity",
    "machine_distance_and_cradle_angle",
    "slope_angle_rad",
    "work_settings",
]


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


# --- settings ------------------------------------------------------------------------------------


@dataclass(frozen=True, kw_only=True)
class WorkSettings:
    """The work's settings of one member, common to the head's blade systems.

    ``mean_cone_distance_mm`` A_m and ``spiral_angle_deg`` psi_m place the pitch point M;
    ``roll_circle_radius_mm`` is the head's rho', ``crown_gear_radius_mm`` rho_cr.
    """

    blade_groups: int
    blade_module_mm: float
    mean_cone_distance_mm: float
    spiral_angle_deg: float
    machine_root_angle_deg: float
    machine_center_to_back_mm: float
    blank_offset_mm: float
    sliding_base_mm: float
    gear_to_cradle_roll: float
    gear_to_blade_roll: float
    roll_circle_radius_mm: float
    crown_gear_radius_mm: float

    @property
    def work_offset_mm(self) -> tuple[float, float, float]:
        """(dX_D, dE_m, dX_B): machine centre to back, blank offset, sliding base."""
        return (self.machine_center_to_back_mm, self.blank_offset_mm, self.sliding_base_mm)


def work_settings(
    pair: PairData,
    compensation: Misalignment,
    member: str,
    *,
    blade_groups: int,
    blade_module_mm: float,
    roll_circle_radius_mm: float,
) -> WorkSettings:
    """The work's settings of ``member`` cut by a head of roll circle rho' =
    ``roll_circle_radius_mm`` (eqs 25, 37; with the compensation of section 4, eqs 49-59: the
    pitch angles of the pair redesigned for Sigma + dGamma, dXD1 = dA1, dEm1 = dE, dXD2 = dA2)."""
    am = pair.blank.mean_cone_distance_mm
    psi = math.radians(pair.mean_spiral_angle_deg)
    sigma = math.radians(pair.shaft_angle_deg + compensation.shaft_angle_deg)
    gamma_m = pitch_angles_rad(pair.pinion_teeth, pair.gear_teeth, sigma)[MEMBERS.index(member)]
    offsets = {
        "pinion": (compensation.pinion_axial_mm, compensation.offset_mm),  # eqs 58-59
        "gear": (compensation.gear_axial_mm, 0.0),  # eq 57
    }
    center_to_back, blank_offset = offsets[member]
    rho_cr = am * math.cos(psi)
    return WorkSettings(
        blade_groups=blade_groups,
        blade_module_mm=blade_module_mm,
        mean_cone_distance_mm=am,
        spiral_angle_deg=pair.mean_spiral_angle_deg,
        machine_root_angle_deg=math.degrees(gamma_m),
        machine_center_to_back_mm=center_to_back,
        blank_offset_mm=blank_offset,
        sliding_base_mm=0.0,
        gear_to_cradle_roll=1.0 / math.sin(gamma_m),  # eqs 25, 53-54
        gear_to_blade_roll=roll_circle_radius_mm / (math.sin(gamma_m) * rho_cr),  # eqs 37, 55-56
        roll_circle_radius_mm=roll_circle_radius_mm,
        crown_gear_radius_mm=rho_cr,
    )


@dataclass(frozen=True, kw_only=True)
class CutterDisk:
    """One blade system's disk on the cradle: its cutter radius r_c, assembly angle nu_k
    (eqs 11, 38), machine distance M_d and cradle angle q_2 (eqs 13-14, 34-35), and the base and
    rolling circles that split M_d (eq 29)."""

    cutter_radius_mm: float
    assembly_angle_deg: float
    machine_distance_mm: float
    cradle_angle_deg: float
    base_circle_radius_mm: float
    rolling_circle_radius_mm: float


def cutter_disk(
    work: WorkSettings, *, cutter_radius_mm: float, assembly_angle_rad: float
) -> CutterDisk:
    """The disk of cutter radius ``cutter_radius_mm`` whose blade meets M at
    ``assembly_angle_rad`` on the machine of ``work``."""
    md, q2 = machine_distance_and_cradle_angle(
        mean_cone_distance_mm=work.mean_cone_distance_mm,
        spiral_angle_rad=math.radians(work.spiral_angle_deg),
        cutter_radius_mm=cutter_radius_mm,
        nu_rad=assembly_angle_rad,
    )
    rho_prime, rho_cr = work.roll_circle_radius_mm, work.crown_gear_radius_mm
    return CutterDisk(
        cutter_radius_mm=cutter_radius_mm,
        assembly_angle_deg=math.degrees(assembly_angle_rad),
        machine_distance_mm=md,
        cradle_angle_deg=math.degrees(q2),
        base_circle_radius_mm=md * rho_cr / (rho_prime + rho_cr),
        rolling_circle_radius_mm=md * rho_prime / (rho_prime + rho_cr),
    )
