"""Bevel gear blank geometry for uniform tooth depth.

Pitch cones from the tooth numbers and the shaft angle, cone distances, modules, pitch radii and
the crown gear of the pair (seed 001 section 3, Table 2; seed 003 Table 1). With uniform depth
(cyclo-palloid, epicycloid) the face and root cones are parallel to the pitch cone, so face, root
and pitch angles coincide and the mean addendum equals the outer addendum.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from gearopt.design import PairData

__all__ = ["Blank", "compute_blank", "pitch_angles_rad", "cone_distance_from_module_mm"]


def pitch_angles_rad(
    pinion_teeth: int, gear_teeth: int, shaft_angle_rad: float
) -> tuple[float, float]:
    """Pitch angles (rad) of pinion and gear: tan g1 = sin S / (N2/N1 + cos S), g2 = S - g1.

    The same relation with S + dS gives seed 001's auxiliary pitch angles (eqs 49-50).
    """
    g1 = math.atan2(
        math.sin(shaft_angle_rad), gear_teeth / pinion_teeth + math.cos(shaft_angle_rad)
    )
    return g1, shaft_angle_rad - g1


def cone_distance_from_module_mm(
    *, pinion_teeth: int, pinion_pitch_angle_rad: float, spiral_angle_rad: float, module_mm: float
) -> float:
    """Mean cone distance from the mean normal module: A_m = m_mn N1 / (2 sin g1 cos psi_m)."""
    return (
        module_mm
        * pinion_teeth
        / (2.0 * math.sin(pinion_pitch_angle_rad) * math.cos(spiral_angle_rad))
    )


@dataclass(frozen=True, kw_only=True)
class Blank:
    """Derived blank data of a pair (lengths in mm, angles in degrees; ``(pinion, gear)`` pairs).

    Attributes
    ----------
    pitch_angle_deg, face_angle_deg, root_angle_deg
        Cone angles; equal for uniform depth.
    mean_cone_distance_mm, outer_cone_distance_mm, inner_cone_distance_mm
        A_m, A_m + F/2, A_m - F/2.
    mean_normal_module_mm, mean_transverse_module_mm, outer_transverse_module_mm
        m_mn, m_mn / cos psi_m, m_mt A_o / A_m.
    mean_pitch_radius_mm, outer_pitch_radius_mm
        A_m sin g and A_o sin g; the gear's outer pitch radius (m_ot N2 / 2) is the backlash
        radius of DESIGN.md.
    crown_gear_teeth
        N_c = N / sin g (the same for both members).
    mean_addendum_mm, mean_dedendum_mm, whole_depth_mm, clearance_mm
        Uniform depth: mean = outer; whole depth a + b; clearance b1 - a2 and b2 - a1.
    outside_diameter_mm
        2 (R_o + a_o cos g) at the heel.
    hand
        ``("left", "right")`` or the reverse.
    """

    pinion_teeth: int
    gear_teeth: int
    gear_ratio: float
    shaft_angle_deg: float
    mean_spiral_angle_deg: float
    pressure_angle_deg: float
    face_width_mm: float
    pitch_angle_deg: tuple[float, float]
    face_angle_deg: tuple[float, float]
    root_angle_deg: tuple[float, float]
    mean_cone_distance_mm: float
    outer_cone_distance_mm: float
    inner_cone_distance_mm: float
    mean_normal_module_mm: float
    mean_transverse_module_mm: float
    outer_transverse_module_mm: float
    mean_pitch_radius_mm: tuple[float, float]
    outer_pitch_radius_mm: tuple[float, float]
    crown_gear_teeth: float
    mean_addendum_mm: tuple[float, float]
    mean_dedendum_mm: tuple[float, float]
    whole_depth_mm: tuple[float, float]
    clearance_mm: tuple[float, float]
    outside_diameter_mm: tuple[float, float]
    hand: tuple[str, str]

    def as_dict(self) -> dict:
        """JSON-ready dictionary (tuples become lists)."""
        return {k: list(v) if isinstance(v, tuple) else v for k, v in asdict(self).items()}


def compute_blank(pair: PairData) -> Blank:
    """Blank geometry of a validated pair (uniform tooth depth)."""
    n1, n2 = pair.pinion_teeth, pair.gear_teeth
    g1, g2 = pitch_angles_rad(n1, n2, math.radians(pair.shaft_angle_deg))
    psi = math.radians(pair.mean_spiral_angle_deg)
    am = pair.mean_cone_distance_mm
    ao = am + 0.5 * pair.face_width_mm
    ai = am - 0.5 * pair.face_width_mm
    mmn = 2.0 * am * math.sin(g1) * math.cos(psi) / n1
    mmt = mmn / math.cos(psi)
    add, ded = pair.outer_addendum_mm, pair.outer_dedendum_mm
    pitch = (math.degrees(g1), math.degrees(g2))
    outer_r = (ao * math.sin(g1), ao * math.sin(g2))
    return Blank(
        pinion_teeth=n1,
        gear_teeth=n2,
        gear_ratio=n2 / n1,
        shaft_angle_deg=pair.shaft_angle_deg,
        mean_spiral_angle_deg=pair.mean_spiral_angle_deg,
        pressure_angle_deg=pair.pressure_angle_deg,
        face_width_mm=pair.face_width_mm,
        pitch_angle_deg=pitch,
        face_angle_deg=pitch,
        root_angle_deg=pitch,
        mean_cone_distance_mm=am,
        outer_cone_distance_mm=ao,
        inner_cone_distance_mm=ai,
        mean_normal_module_mm=mmn,
        mean_transverse_module_mm=mmt,
        outer_transverse_module_mm=mmt * ao / am,
        mean_pitch_radius_mm=(am * math.sin(g1), am * math.sin(g2)),
        outer_pitch_radius_mm=outer_r,
        crown_gear_teeth=n1 / math.sin(g1),
        mean_addendum_mm=add,
        mean_dedendum_mm=ded,
        whole_depth_mm=(add[0] + ded[0], add[1] + ded[1]),
        clearance_mm=(ded[0] - add[1], ded[1] - add[0]),
        outside_diameter_mm=(
            2.0 * (outer_r[0] + add[0] * math.cos(g1)),
            2.0 * (outer_r[1] + add[1] * math.cos(g2)),
        ),
        hand=(pair.pinion_hand, pair.gear_hand),
    )
