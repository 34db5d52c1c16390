"""Mean normal chordal tooth thickness, measured on generated flanks (seed 001 eqs 39-48).

The frame S_n (docs/architecture.md, Frames and signs): origin at the tooth's pitch point M (on the
pitch cone at the mean cone distance, in the tooth's middle), ``x_n`` along the tooth depth toward
the tip (the pitch cone's outward normal in the axial plane), ``z_n`` along the tooth's lengthwise
tangent at M (it makes the mean spiral angle with the cone generatrix; it is the normal of the
normal section), ``y_n = z_n x x_n`` across the tooth. The chordal points lie in the plane z_n = 0
at x_n = a_m - a_c (the mean addendum minus the chordal addendum), one on each flank, symmetric
about the tooth's middle: y_n = -t/2 and +t/2.

The measurement works on any pair of FlankMaps (convex and concave flank of the same tooth) and
so on any machine model; the tooth's angular position is an unknown of the solve, as phi_g is
in eqs 39-48.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import root

from gearopt.errors import GearoptError, SettingsError
from gearopt.flank import FlankMap

__all__ = ["NormalSection", "ChordalThickness", "chordal_thickness", "design_chordal_thickness"]


@dataclass(frozen=True, kw_only=True)
class NormalSection:
    """The frame S_n of a tooth whose middle lies at polar angle ``polar_rad``.

    ``spiral_sign`` is +1 when the tooth trace turns toward +Theta going from toe to heel (a
    right-hand member in the member frame of :mod:`gearopt.flank`), -1 for the left hand.
    """

    cone_distance_mm: float
    pitch_angle_rad: float
    spiral_angle_rad: float
    spiral_sign: int

    def axes(self, polar_rad) -> tuple[NDArray, NDArray]:
        """Origin ``(..., 3)`` and rows ``(..., 3, 3)`` = (x_n, y_n, z_n) in the member frame."""
        polar_rad = np.asarray(polar_rad)
        c, s = np.cos(polar_rad), np.sin(polar_rad)
        sg, cg = math.sin(self.pitch_angle_rad), math.cos(self.pitch_angle_rad)
        sp, cp = math.sin(self.spiral_angle_rad), math.cos(self.spiral_angle_rad)
        zero = np.zeros_like(c)
        generatrix = np.stack([sg * c, sg * s, cg + zero], axis=-1)
        depth = np.stack([cg * c, cg * s, -sg + zero], axis=-1)
        around = np.stack([-s, c, zero], axis=-1)
        along = cp * generatrix + self.spiral_sign * sp * around
        across = np.cross(along, depth)
        origin = self.cone_distance_mm * generatrix
        return origin, np.stack([depth, across, along], axis=-2)

    def coordinates(self, points, polar_rad) -> NDArray:
        """``(..., 3)`` coordinates (x_n, y_n, z_n) of member-frame points."""
        origin, rows = self.axes(polar_rad)
        return np.einsum("...ij,...j->...i", rows, np.asarray(points) - origin)


@dataclass(frozen=True, kw_only=True)
class ChordalThickness:
    """Result of :func:`chordal_thickness` (lengths in mm, angles in degrees)."""

    thickness_mm: float
    depth_mm: float
    tooth_middle_deg: float
    convex_point_mm: tuple[float, float]
    concave_point_mm: tuple[float, float]


def chordal_thickness(
    convex: FlankMap,
    concave: FlankMap,
    *,
    mean_cone_distance_mm: float,
    spiral_angle_deg: float,
    chordal_addendum_mm: float,
    mean_addendum_mm: float,
    tol_mm: float = 1e-10,
) -> ChordalThickness:
    """Mean normal chordal thickness of the tooth bounded by ``convex`` and ``concave``.

    Parameters
    ----------
    convex, concave
        The two flanks of one tooth (same member, hand and tooth).
    mean_cone_distance_mm, spiral_angle_deg
        Where S_n sits and how it is turned (the blank's A_m and psi_m).
    chordal_addendum_mm, mean_addendum_mm
        a_c and a_m: the chord lies at x_n = a_m - a_c.

    Returns
    -------
    ChordalThickness
        ``thickness_mm`` t; the (face, profile) grid coordinates of the two chordal points.

    Raises
    ------
    GearoptError
        When the flanks are not two flanks of one tooth.
    SettingsError
        When a chordal point falls outside the generated part of its flank.
    """
    if (convex.member, convex.hand, convex.tooth) != (concave.member, concave.hand, concave.tooth):
        raise GearoptError(
            "chordal_thickness",
            (convex.member, convex.hand, concave.member, concave.hand),
            "needs the convex and concave flank of one tooth",
        )
    if (convex.flank, concave.flank) != ("convex", "concave"):
        raise GearoptError(
            "chordal_thickness", (convex.flank, concave.flank), "order: convex, concave"
        )
    section = NormalSection(
        cone_distance_mm=mean_cone_distance_mm,
        pitch_angle_rad=math.radians(convex.pitch_angle_deg),
        spiral_angle_rad=math.radians(spiral_angle_deg),
        spiral_sign=1 if convex.hand == "right" else -1,
    )
    depth = mean_addendum_mm - chordal_addendum_mm
    s0, h0 = mean_cone_distance_mm, depth
    middle0 = 0.5 * float(convex.polar_angle_at(s0, h0) + concave.polar_angle_at(s0, h0))

    def residual(x):
        s1, h1, s2, h2, mid = x
        p1 = section.coordinates(convex.point_at(s1, h1), mid)
        p2 = section.coordinates(concave.point_at(s2, h2), mid)
        return [p1[0] - depth, p1[2], p2[0] - depth, p2[2], p1[1] + p2[1]]

    sol = root(residual, [s0, h0, s0, h0, middle0], method="hybr", options={"xtol": 1e-13})
    s1, h1, s2, h2, mid = sol.x
    if not sol.success or max(abs(v) for v in residual(sol.x)) > tol_mm:
        raise SettingsError("chordal_thickness", rule=f"did not converge ({sol.message})")
    for name, fm, s, h in (("convex", convex, s1, h1), ("concave", concave, s2, h2)):
        if not fm.inside(s, h):
            raise SettingsError(
                f"chordal_thickness.{name}",
                (round(float(s), 3), round(float(h), 3)),
                "the chordal point lies outside the generated flank",
            )
    p1 = section.coordinates(convex.point_at(s1, h1), mid)
    p2 = section.coordinates(concave.point_at(s2, h2), mid)
    return ChordalThickness(
        thickness_mm=float(abs(p2[1] - p1[1])),
        depth_mm=depth,
        tooth_middle_deg=math.degrees(mid),
        convex_point_mm=(float(s1), float(h1)),
        concave_point_mm=(float(s2), float(h2)),
    )


def design_chordal_thickness(design, member: str, flanks: dict) -> ChordalThickness:
    """:func:`chordal_thickness` of a design's ``member`` at the pair's chordal addendum.

    ``flanks`` holds the member's ``"convex"`` and ``"concave"`` FlankMaps of one tooth.
    Raises :class:`GearoptError` when the pair gives no chordal addendum.
    """
    index = ("pinion", "gear").index(member)
    pair = design.pair
    if pair.mean_normal_chordal_addendum_mm is None:
        raise GearoptError(
            "pair.mean_normal_chordal_addendum_mm", rule="is needed to measure the thickness"
        )
    return chordal_thickness(
        flanks["convex"],
        flanks["concave"],
        mean_cone_distance_mm=design.blank.mean_cone_distance_mm,
        spiral_angle_deg=pair.mean_spiral_angle_deg,
        chordal_addendum_mm=pair.mean_normal_chordal_addendum_mm[index],
        mean_addendum_mm=design.blank.mean_addendum_mm[index],
    )
