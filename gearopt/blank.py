"""Bevel gear blank geometry, uniform or tapered tooth depth.

Pitch cones from the tooth numbers and the shaft angle, cone distances, modules, pitch radii and
the crown gear of the pair (seed 001 section 3, Table 2; seed 003 Table 1). With uniform depth
(cyclo-palloid, epicycloid) the face and root cones are parallel to the pitch cone, so face, root
and pitch angles coincide and the mean addendum equals the outer addendum.

Tapered depth (``face_angle_deg``/``root_angle_deg`` in ``[pair]``): the addendum angle
theta_a = face - pitch and the dedendum angle theta_d = pitch - root; the given outer addendum
a_o and dedendum b_o are those at the heel (outer cone distance A_o, measured along the back
cone, normal to the pitch generatrix), and at a cone distance A

    a(A) = a_o - (A_o - A) tan(theta_a),    b(A) = b_o - (A_o - A) tan(theta_d),

so the mean values are a_m = a_o - (F/2) tan(theta_a), b_m = b_o - (F/2) tan(theta_d) (Gleason's
formulas). The outside diameter is 2 (R_o + a_o cos gamma) (at the heel); the whole depth and
the clearance reported are the mean ones (at A_m).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import TYPE_CHECKING

from gearopt.flank import DepthTaper

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
        radius (docs/architecture.md, Backlash and ease-off).
    crown_gear_teeth
        N_c = N / sin g (the same for both members).
    mean_addendum_mm, mean_dedendum_mm, whole_depth_mm, clearance_mm
        At the mean cone distance (uniform depth: mean = outer); whole depth a_m + b_m;
        clearance b1 - a2 and b2 - a1 (mean).
    outer_addendum_mm, outer_dedendum_mm
        At the heel (A_o), as given.
    addendum_angle_deg, dedendum_angle_deg
        face - pitch and pitch - root (0 for uniform depth).
    outside_diameter_mm
        2 (R_o + a_o cos g) at the heel.
    hand
        ``("left", "right")`` or the reverse.
    pressure_angle_deg, pressure_angles_deg
        The drive side's pressure angle, and ``(drive, coast)`` (``()``: both the first).
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
    outer_addendum_mm: tuple[float, float] = (0.0, 0.0)
    outer_dedendum_mm: tuple[float, float] = (0.0, 0.0)
    addendum_angle_deg: tuple[float, float] = (0.0, 0.0)
    dedendum_angle_deg: tuple[float, float] = (0.0, 0.0)
    pressure_angles_deg: tuple[float, ...] = ()

    def __post_init__(self) -> None:
        if not self.pressure_angles_deg:
            object.__setattr__(self, "pressure_angles_deg", (self.pressure_angle_deg,) * 2)

    @property
    def tapered(self) -> tuple[bool, bool]:
        """Per member: True when its face or root cone is not parallel to its pitch cone."""
        return tuple(  # type: ignore[return-value]
            a != 0.0 or d != 0.0
            for a, d in zip(self.addendum_angle_deg, self.dedendum_angle_deg, strict=True)
        )

    def addendum_at_mm(self, index: int, cone_distance_mm):
        """Addendum of member ``index`` (0 pinion, 1 gear) at a cone distance (normal to the
        pitch generatrix): a_o - (A_o - A) tan(theta_a)."""
        return self.outer_addendum_mm[index] - (
            self.outer_cone_distance_mm - cone_distance_mm
        ) * math.tan(math.radians(self.addendum_angle_deg[index]))

    def dedendum_at_mm(self, index: int, cone_distance_mm):
        """Dedendum of member ``index`` at a cone distance: b_o - (A_o - A) tan(theta_d)."""
        return self.outer_dedendum_mm[index] - (
            self.outer_cone_distance_mm - cone_distance_mm
        ) * math.tan(math.radians(self.dedendum_angle_deg[index]))

    def depth_taper(self, index: int) -> DepthTaper | None:
        """The FlankMap grid's :class:`gearopt.flank.DepthTaper` of member ``index``: the root
        cone at t = -b_m, the face cone at t = a_m; None for uniform depth."""
        if not self.tapered[index]:
            return None
        return DepthTaper(
            pivot_mm=self.mean_cone_distance_mm,
            root_mm=-self.mean_dedendum_mm[index],
            top_mm=self.mean_addendum_mm[index],
            root_slope=-math.tan(math.radians(self.dedendum_angle_deg[index])),
            top_slope=math.tan(math.radians(self.addendum_angle_deg[index])),
        )

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
    add_o, ded_o = pair.outer_addendum_mm, pair.outer_dedendum_mm
    pitch = (math.degrees(g1), math.degrees(g2))
    face_angle = pair.face_angle_deg if pair.face_angle_deg is not None else pitch
    root_angle = pair.root_angle_deg if pair.root_angle_deg is not None else pitch
    theta_a = tuple(f - p for f, p in zip(face_angle, pitch, strict=True))
    theta_d = tuple(p - r for p, r in zip(pitch, root_angle, strict=True))
    half = 0.5 * pair.face_width_mm
    add = tuple(
        a - half * math.tan(math.radians(t)) if t else a
        for a, t in zip(add_o, theta_a, strict=True)
    )
    ded = tuple(
        b - half * math.tan(math.radians(t)) if t else b
        for b, t in zip(ded_o, theta_d, strict=True)
    )
    outer_r = (ao * math.sin(g1), ao * math.sin(g2))
    return Blank(
        pinion_teeth=n1,
        gear_teeth=n2,
        gear_ratio=n2 / n1,
        shaft_angle_deg=pair.shaft_angle_deg,
        mean_spiral_angle_deg=pair.mean_spiral_angle_deg,
        pressure_angle_deg=pair.pressure_angle_deg,
        pressure_angles_deg=pair.pressure_angles_deg,
        face_width_mm=pair.face_width_mm,
        pitch_angle_deg=pitch,
        face_angle_deg=tuple(face_angle),
        root_angle_deg=tuple(root_angle),
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
            2.0 * (outer_r[0] + add_o[0] * math.cos(g1)),
            2.0 * (outer_r[1] + add_o[1] * math.cos(g2)),
        ),
        hand=(pair.pinion_hand, pair.gear_hand),
        outer_addendum_mm=tuple(add_o),
        outer_dedendum_mm=tuple(ded_o),
        addendum_angle_deg=theta_a,
        dedendum_angle_deg=theta_d,
    )
