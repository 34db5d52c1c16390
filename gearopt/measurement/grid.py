"""The nominal measuring grid of a member's flanks and normal deviations on it.

A coordinate measuring machine probes a cut flank at the points of a nominal grid and reports
the deviation along the nominal normal. The grid's positions come from the blank alone: ``n_face``
cone distances s uniformly from the toe to the heel, each ``margin_mm`` inside the blank's inner
and outer cone distances, and at each of them ``n_profile`` heights h above the pitch cone
uniformly from the root line to the face line of the blank (tapered or uniform depth), each
``margin_mm`` inside. Two designs of the same blank are therefore measured at the same
(s, h), whatever their machine; a grid point the tool does not generate (in the fillet, beyond
the envelope's fold) is marked ``generated = False``, not moved.

Normal deviation. At the nominal point P (axial plane (L, R), polar angle Theta_0, unit normal n
out of the tooth) a flank whose polar angle at the same (L, R) is Theta_1 lies, to first order
in the deviation, a distance

    delta = R (Theta_1 - Theta_0) (n . e_Theta)

along n from P (the flank is locally the plane n . (X - P) = delta, and X = P + R dTheta
e_Theta): positive when the measured flank stands out of the nominal one into the tooth space,
i.e. material above nominal (the measuring convention). The neglected term is of the order of
delta^2 times the flank's curvature, below 1e-6 um for deviations of some ten micrometres.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from gearopt.errors import GearoptError
from gearopt.flank import FLANKS, MEMBERS, FlankMap, axial_plane

__all__ = [
    "FlankPoints",
    "MeasuringGrid",
    "flank_points",
    "measuring_grid",
    "normal_deviation_um",
    "parse_points",
]

#: the usual CMM grid: 9 points toe to heel, 5 root to top
DEFAULT_POINTS = (9, 5)
#: finite-difference step (mm) of the grid coordinates for the normals
_STEP_MM = 1e-4


@dataclass(frozen=True, kw_only=True)
class MeasuringGrid:
    """Nominal grid positions of one member's flanks, from the blank alone.

    Attributes
    ----------
    member
        ``"pinion"`` or ``"gear"``.
    pitch_angle_deg
        The member's pitch angle (the axial plane's rotation, :func:`gearopt.flank.axial_plane`).
    face_mm
        ``(n_face,)`` cone distances s of the grid columns, toe to heel.
    profile_mm
        ``(n_face, n_profile)`` heights h above the pitch cone, root to top in each column.
    margin_mm
        The margin kept inside the blank's toe, heel, root and face lines.
    """

    member: str
    pitch_angle_deg: float
    face_mm: NDArray
    profile_mm: NDArray
    margin_mm: float

    @property
    def shape(self) -> tuple[int, int]:
        """``(n_face, n_profile)``."""
        return self.profile_mm.shape

    @property
    def axial_mm(self) -> NDArray:
        """``(n_face, n_profile)`` L of the grid points."""
        return self._axial_plane()[0]

    @property
    def radius_mm(self) -> NDArray:
        """``(n_face, n_profile)`` R of the grid points."""
        return self._axial_plane()[1]

    def _axial_plane(self) -> tuple[NDArray, NDArray]:
        s = np.broadcast_to(self.face_mm[:, None], self.shape)
        return axial_plane(s, self.profile_mm, math.radians(self.pitch_angle_deg))


def parse_points(text: str) -> tuple[int, int]:
    """``"9x5"`` -> ``(9, 5)``: points toe to heel by points root to top (each 2 to 101)."""
    parts = str(text).lower().split("x")
    try:
        n_face, n_profile = (int(p) for p in parts)
    except ValueError:
        raise GearoptError("--points", text, "must be NFxNP, e.g. 9x5") from None
    for name, n in (("face", n_face), ("profile", n_profile)):
        if not 2 <= n <= 101:
            raise GearoptError("--points", text, f"needs 2 to 101 {name} points")
    return n_face, n_profile


def measuring_grid(
    blank, member: str, *, points: tuple[int, int] = DEFAULT_POINTS, margin_mm: float | None = None
) -> MeasuringGrid:
    """The nominal measuring grid of ``member`` of ``blank`` (a :class:`gearopt.blank.Blank`).

    Parameters
    ----------
    blank
        The pair's blank.
    member
        ``"pinion"`` or ``"gear"``.
    points
        ``(n_face, n_profile)``.
    margin_mm
        Distance kept inside the toe and heel (along the pitch generatrix) and inside the root
        and face lines (normal to it); default a tenth of the member's mean whole depth.

    Raises
    ------
    GearoptError
        An unknown member, or a margin that leaves no face width or no depth to measure.
    """
    if member not in MEMBERS:
        raise GearoptError("--member", member, f"must be one of {MEMBERS}")
    index = MEMBERS.index(member)
    if margin_mm is None:
        margin_mm = 0.1 * blank.whole_depth_mm[index]
    margin_mm = float(margin_mm)
    if not (math.isfinite(margin_mm) and margin_mm >= 0.0):
        raise GearoptError("--margin-mm", margin_mm, "must be a finite length >= 0")
    toe = blank.inner_cone_distance_mm + margin_mm
    heel = blank.outer_cone_distance_mm - margin_mm
    if heel <= toe:
        raise GearoptError(
            "--margin-mm", margin_mm, f"leaves no face width (face width {blank.face_width_mm} mm)"
        )
    n_face, n_profile = points
    s = np.linspace(toe, heel, n_face)
    root = -blank.dedendum_at_mm(index, s) + margin_mm
    top = blank.addendum_at_mm(index, s) - margin_mm
    if np.any(top <= root):
        raise GearoptError(
            "--margin-mm",
            margin_mm,
            f"leaves no tooth depth (whole depth {blank.whole_depth_mm[index]:.3f} mm at the mean)",
        )
    u = np.linspace(0.0, 1.0, n_profile)
    return MeasuringGrid(
        member=member,
        pitch_angle_deg=blank.pitch_angle_deg[index],
        face_mm=s,
        profile_mm=root[:, None] + (top - root)[:, None] * u[None, :],
        margin_mm=margin_mm,
    )


@dataclass(frozen=True, kw_only=True)
class FlankPoints:
    """One flank at the grid's positions.

    Attributes
    ----------
    flank
        ``"convex"`` or ``"concave"``.
    points_mm, normals
        ``(n_face, n_profile, 3)`` points and unit normals (out of the tooth) in the member frame.
    polar_angle_rad
        ``(n_face, n_profile)`` Theta of the points.
    generated
        ``(n_face, n_profile)`` False where the tool does not generate the point (the values
        there are the flank's interpolant extended, not a cut surface).
    """

    flank: str
    points_mm: NDArray
    normals: NDArray
    polar_angle_rad: NDArray
    generated: NDArray = field(repr=False)

    @property
    def circumferential(self) -> NDArray:
        """``(n_face, n_profile)`` n . e_Theta: the normal's component around the axis."""
        return _around(self.polar_angle_rad, self.normals)


def _around(theta_rad: NDArray, normals: NDArray) -> NDArray:
    """n . e_Theta of unit normals at polar angles Theta (their component around the axis)."""
    return -np.sin(theta_rad) * normals[..., 0] + np.cos(theta_rad) * normals[..., 1]


def _polar(flank: FlankMap, axial_mm, radius_mm) -> tuple[NDArray, NDArray]:
    """Theta of ``flank`` at axial-plane points and whether they are generated: the exact
    surface's where the flank carries one and the point is generated, else the local
    interpolant's."""
    s, t = flank.to_grid(axial_mm, radius_mm)
    theta, inside = flank.polar_angle_local(s, t, with_inside=True)
    if flank.surface is not None and inside.any():
        theta = np.array(theta, float)
        theta[inside] = flank.polar_angle_exact(s[inside], t[inside])
    return theta, inside


def flank_points(grid: MeasuringGrid, flank: FlankMap) -> FlankPoints:
    """The points, normals and generated flags of ``flank`` at the grid's positions (exact on
    the generated surface where the flank carries one)."""
    g = math.radians(grid.pitch_angle_deg)
    s0 = np.broadcast_to(grid.face_mm[:, None], grid.shape)
    h0 = grid.profile_mm

    def point(ds: float, dh: float) -> NDArray:
        big_l, big_r = axial_plane(s0 + ds, h0 + dh, g)
        s, t = flank.to_grid(big_l, big_r)
        theta = flank.polar_angle_local(s, t)
        return np.stack([big_r * np.cos(theta), big_r * np.sin(theta), big_l], axis=-1)

    big_l, big_r = grid.axial_mm, grid.radius_mm
    theta, generated = _polar(flank, big_l, big_r)
    p = np.stack([big_r * np.cos(theta), big_r * np.sin(theta), big_l], axis=-1)
    r_s = (point(_STEP_MM, 0.0) - point(-_STEP_MM, 0.0)) / (2.0 * _STEP_MM)
    r_h = (point(0.0, _STEP_MM) - point(0.0, -_STEP_MM)) / (2.0 * _STEP_MM)
    n = np.cross(r_s, r_h)
    n /= np.linalg.norm(n, axis=-1, keepdims=True)
    # out of the tooth: the side of the flank's own normals (its nodes' circumferential sense)
    around = _around(flank.polar_angle_rad, flank.normals)
    sense = np.sign(np.median(around[flank.mask])) if flank.mask.any() else 1.0
    n *= np.where(np.sign(_around(theta, n)) == sense, 1.0, -1.0)[..., None]
    if flank.surface is not None and generated.any():
        s, t = flank.to_grid(big_l[generated], big_r[generated])
        n[generated] = flank.surface.geometry_at(s, t)["normal"]
    return FlankPoints(
        flank=flank.flank, points_mm=p, normals=n, polar_angle_rad=theta, generated=generated
    )


def normal_deviation_um(
    grid: MeasuringGrid, nominal: FlankPoints, flank: FlankMap
) -> tuple[NDArray, NDArray]:
    """Deviation (um, along the nominal normal, + = material above nominal) of ``flank`` from
    the nominal flank at the grid's points, and where both are generated.

    Returns
    -------
    deviation_um, valid
        ``(n_face, n_profile)`` each; the deviation is 0 where ``valid`` is False.
    """
    if flank.flank not in FLANKS or flank.flank != nominal.flank:
        raise GearoptError("flank", flank.flank, f"must be the nominal's {nominal.flank!r}")
    theta, inside = _polar(flank, grid.axial_mm, grid.radius_mm)
    turn = (theta - nominal.polar_angle_rad + math.pi) % (2.0 * math.pi) - math.pi
    valid = inside & nominal.generated
    dev = 1000.0 * grid.radius_mm * turn * nominal.circumferential
    return np.where(valid, dev, 0.0), valid
