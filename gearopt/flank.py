"""FlankMap: one tooth flank sampled on a regular grid of the member's axial plane.

Every machine model hands its generated flanks to the rest of gearopt in this one form, so the
contact engine, the thickness measurement and the plots never see a machine.

Member frame: origin at the pitch-cone apex, ``z`` along the member axis from the apex toward the
back (heel), ``x`` and ``y`` across; the polar angle Theta = atan2(y, x). Axial-plane coordinates:
L = z and R = sqrt(x^2 + y^2). The grid is regular along the pitch-cone generatrix (``face_mm``,
the cone distance s from the apex, toe to heel) and normal to it (``profile_mm``, the height h
above the pitch cone, root to top), so that

    L = s cos(gamma) - h sin(gamma),    R = s sin(gamma) + h cos(gamma)

with gamma the pitch angle: a rotation of the L x R grid that makes the uniform-depth tooth a
rectangle. Node ``[i, j]`` is (face_mm[i], profile_mm[j]).

Tapered depth (face and root cones not parallel to the pitch cone): the tooth is a trapezoid in
(s, h), so the profile coordinate of the grid is then ``t``, the height scaled column by column
so that the root cone and the face cone are the grid's first and last rows
(:class:`DepthTaper`): h = t + (s - A_m)(alpha + beta t), bilinear, t = h at the mean cone
distance A_m. Every method that goes between the grid and space (:attr:`FlankMap.axial_mm`,
:meth:`FlankMap.to_grid`, :meth:`FlankMap.point_at`, the interpolants' derivatives) applies it;
``profile_mm`` and every "grid coordinate" are t. Uniform depth has no taper (t = h).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from functools import cached_property
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from gearopt.errors import GearoptError
from gearopt.jit import ENABLED, compiled

if TYPE_CHECKING:
    from scipy.interpolate import RectBivariateSpline

__all__ = [
    "axial_plane",
    "cone_coordinates",
    "DepthTaper",
    "FlankGrid",
    "FlankMap",
    "HermiteCells",
    "hermite_cells",
    "hermite_coefficients",
    "polar_gradient",
    "MEMBERS",
    "FLANKS",
    "HANDS",
    "check_member_and_flank",
    "extended_below",
    "mirror_image",
    "turned",
    "unwrapped_along_face",
    "warm_kernels",
]

MEMBERS = ("pinion", "gear")
FLANKS = ("convex", "concave")
HANDS = ("left", "right")


def turned(polar_rad: NDArray, points_mm: NDArray, normals: NDArray, angle_rad: float):
    """``(polar, points, normals)`` of a flank turned by ``angle_rad`` about the member axis
    (:meth:`FlankMap.rotated`)."""
    c, s = math.cos(angle_rad), math.sin(angle_rad)
    rot = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    return polar_rad + angle_rad, points_mm @ rot.T, normals @ rot.T


def mirror_image(polar_rad: NDArray, points_mm: NDArray, normals: NDArray):
    """``(polar, points, normals)`` of a flank mirrored in the member's x-z plane
    (:meth:`FlankMap.mirrored`)."""
    flip = np.array([1.0, -1.0, 1.0])
    return -polar_rad, points_mm * flip, normals * flip


def extended_below(values: NDArray, mask: NDArray) -> NDArray:
    """``values`` ``(..., n_f, n_p)`` with each column's values (along the last axis) below
    its lowest ``mask`` node replaced by the quadratic through that node and the two above it,
    so that a spline through all nodes stays smooth at the edge of the generated region (the
    envelope's values past the fold are a different sheet)."""
    n_p = mask.shape[-1]
    low = np.where(mask.any(axis=-1), np.argmax(mask, axis=-1), n_p - 3)
    low = np.minimum(low, n_p - 3).reshape(-1)
    out = np.array(values, float)
    flat = out.reshape(-1)  # (a view: out is a new contiguous array)
    # the nodes below (column c, node j): the quadratic's arithmetic there alone
    c, j = np.nonzero(np.arange(n_p) < low[:, None])
    at = c * n_p + low[c]
    p0, p1, p2 = flat[at], flat[at + 1], flat[at + 2]
    t = (j - low[c]).astype(float)
    flat[c * n_p + j] = 0.5 * (t - 1) * (t - 2) * p0 - t * (t - 2) * p1 + 0.5 * t * (t - 1) * p2
    return out


def unwrapped_along_face(p: NDArray) -> NDArray:
    """``np.unwrap(p, axis=-2)`` of ``(..., n_f, n_p)``: numpy's operations without its set-up,
    the correction's sum only where a step reaches pi."""
    dd = p[..., 1:, :] - p[..., :-1, :]
    up = p.copy()
    if (np.abs(dd) < math.pi).all():
        up[..., 1:, :] += 0.0  # (p + a sum of zeros: -0.0 made 0.0 as there)
        return up
    ddmod = np.mod(dd - (-math.pi), 2 * math.pi) + (-math.pi)
    np.copyto(ddmod, math.pi, where=(ddmod == -math.pi) & (dd > 0))
    correction = ddmod - dd
    np.copyto(correction, 0, where=np.abs(dd) < math.pi)
    up[..., 1:, :] = p[..., 1:, :] + correction.cumsum(axis=-2)
    return up


def check_member_and_flank(member: str, flank: str) -> None:
    """Raise a GearoptError unless ``member`` and ``flank`` name a member and a flank."""
    if member not in MEMBERS:
        raise GearoptError("member", member, f"must be one of {MEMBERS}")
    if flank not in FLANKS:
        raise GearoptError("flank", flank, f"must be one of {FLANKS}")


def axial_plane(cone_distance_mm, height_mm, pitch_angle_rad: float):
    """``(L, R)``: the axial position and radius of the point at cone distance ``s`` along the
    pitch generatrix and height ``h`` above it (the member's axial plane, pitch angle gamma):
    L = s cos(gamma) - h sin(gamma), R = s sin(gamma) + h cos(gamma)."""
    cg, sg = math.cos(pitch_angle_rad), math.sin(pitch_angle_rad)
    return cone_distance_mm * cg - height_mm * sg, cone_distance_mm * sg + height_mm * cg


def cone_coordinates(axial_mm, radius_mm, pitch_angle_rad: float):
    """``(s, h)`` of the axial-plane point ``(L, R)``: the inverse of :func:`axial_plane`."""
    cg, sg = math.cos(pitch_angle_rad), math.sin(pitch_angle_rad)
    return axial_mm * cg + radius_mm * sg, -axial_mm * sg + radius_mm * cg


@dataclass(frozen=True, kw_only=True)
class FlankGrid:
    """Grid size of a FlankMap: ``n_face`` nodes toe to heel, ``n_profile`` root to top."""

    n_face: int = 25
    n_profile: int = 13

    def __post_init__(self):
        for name in ("n_face", "n_profile"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or not 4 <= value <= 401:
                raise GearoptError(f"grid.{name}", value, "must be an integer from 4 to 401")

    @property
    def shape(self) -> tuple[int, int]:
        """``(n_face, n_profile)``."""
        return (self.n_face, self.n_profile)


@dataclass(frozen=True, kw_only=True)
class DepthTaper:
    """The profile coordinate t of a tapered-depth grid: the height above the pitch cone

        h(s, t) = t + (s - pivot_mm) (alpha + beta t),

    with ``beta = (top_slope - root_slope) / (top_mm - root_mm)`` and
    ``alpha = root_slope - beta root_mm``, so that the line t = ``root_mm`` is the root cone
    (h = root_mm + (s - pivot_mm) root_slope), t = ``top_mm`` the face cone, and t = h at the
    pivot (the mean cone distance). The slopes are dh/ds of the cones' generatrices in the
    axial plane: ``top_slope`` = tan(face angle - pitch angle) (the addendum angle),
    ``root_slope`` = -tan(pitch angle - root angle) (minus the dedendum angle's tangent).

    Parameters
    ----------
    pivot_mm
        Cone distance where t = h (the mean cone distance A_m).
    root_mm, top_mm
        t of the root and face cones (-b_m and a_m, the mean dedendum and addendum).
    root_slope, top_slope
        dh/ds of the root and face cones' generatrices.
    """

    pivot_mm: float
    root_mm: float
    top_mm: float
    root_slope: float
    top_slope: float

    def __post_init__(self):
        for name in ("pivot_mm", "root_mm", "top_mm", "root_slope", "top_slope"):
            value = getattr(self, name)
            if not math.isfinite(value):
                raise GearoptError(f"DepthTaper.{name}", value, "must be finite")
            object.__setattr__(self, name, float(value))
        if not self.top_mm > self.root_mm:
            raise GearoptError("DepthTaper.top_mm", self.top_mm, "must exceed root_mm")

    @property
    def beta(self) -> float:
        """d^2 h / (ds dt)."""
        return (self.top_slope - self.root_slope) / (self.top_mm - self.root_mm)

    @property
    def alpha(self) -> float:
        """dh/ds at t = 0."""
        return self.root_slope - self.beta * self.root_mm

    def height_mm(self, face_mm, profile_mm):
        """h(s, t)."""
        d = np.asarray(face_mm) - self.pivot_mm
        t = np.asarray(profile_mm)
        return t + d * (self.alpha + self.beta * t)

    def profile_of(self, face_mm, height_mm):
        """t(s, h), the inverse of :meth:`height_mm` at fixed s."""
        d = np.asarray(face_mm) - self.pivot_mm
        return (np.asarray(height_mm) - d * self.alpha) / (1.0 + d * self.beta)

    def dheight_dprofile(self, face_mm):
        """dh/dt at fixed s: 1 + (s - pivot) beta."""
        return 1.0 + (np.asarray(face_mm) - self.pivot_mm) * self.beta

    def dheight_dface(self, profile_mm):
        """dh/ds at fixed t: alpha + beta t."""
        return self.alpha + self.beta * np.asarray(profile_mm)


@dataclass(frozen=True, kw_only=True, eq=False)
class HermiteCells:
    """A FlankMap's local bicubic Hermite interpolant of Theta(s, t), one polynomial per cell.

    The grid is uniform: the cell of grid coordinates ``(s, t)`` is found by arithmetic, its
    unit coordinates are ``x = (s - face0_mm) * face_scale - i`` and
    ``y = (t - profile0_mm) * profile_scale - j``. Beyond the grid the edge cell's polynomial
    goes on (unit coordinates outside [0, 1]).

    Attributes
    ----------
    face0_mm, face_scale
        The grid's first face coordinate and its cells per mm along the face.
    last_row
        ``n_f - 2``, the last cell row (as a float, for clamping).
    profile0_mm, profile_scale
        The same along the profile.
    last_column
        ``n_p - 2``, the last cell column.
    columns
        ``n_p - 1`` cells per row: cell ``(i, j)`` is number ``i * columns + j``.
    coefficients
        ``(n_cells, 16)``: column ``4 a + b`` holds c_ab of Theta = sum c_ab x^a y^b.
    generated
        ``(n_cells,)`` True where the cell's four corners are generated nodes.
    """

    face0_mm: float
    face_scale: float
    last_row: float
    profile0_mm: float
    profile_scale: float
    last_column: float
    columns: int
    coefficients: NDArray
    generated: NDArray

    def locate(self, face_mm: NDArray, profile_mm: NDArray):
        """``(cell, x, y, within)`` of grid points: the cell number (clamped to the grid), the
        unit coordinates in it and whether the point lies on the grid."""
        x = (face_mm - self.face0_mm) * self.face_scale
        y = (profile_mm - self.profile0_mm) * self.profile_scale
        if not (np.all(np.isfinite(x)) and np.all(np.isfinite(y))):  # never index with NaN
            x = np.where(np.isfinite(x), x, -1.0)
            y = np.where(np.isfinite(y), y, -1.0)
        fi = np.minimum(np.maximum(x, 0.0), self.last_row).astype(np.intp)
        fj = np.minimum(np.maximum(y, 0.0), self.last_column).astype(np.intp)
        within = (x >= 0.0) & (x <= self.last_row + 1.0)
        within &= (y >= 0.0) & (y <= self.last_column + 1.0)
        return fi * self.columns + fj, x - fi, y - fj, within

    def polynomial(self, cell: int) -> NDArray:
        """``(4, 4)`` coefficients c_ab of one cell."""
        return self.coefficients[cell].reshape(4, 4)


@dataclass(frozen=True, kw_only=True, eq=False)
class FlankMap:
    """A generated tooth flank on a regular axial-plane grid (see the module docstring).

    Attributes
    ----------
    member, flank, hand
        ``"pinion"``/``"gear"``, ``"convex"``/``"concave"``, ``"left"``/``"right"``.
    teeth
        Number of teeth of the member (the angular pitch is 2 pi / teeth).
    tooth
        Index of the tooth: tooth k is tooth 0 turned by k pitches (positive Theta).
    pitch_angle_deg
        Pitch angle gamma of the grid's axes.
    face_mm, profile_mm
        ``(n_f,)`` cone distances and ``(n_p,)`` heights above the pitch cone of the nodes
        (with ``taper``: the profile coordinates t, :attr:`heights_mm` the heights).
    polar_angle_rad
        ``(n_f, n_p)`` Theta of the flank at each node.
    points_mm, normals
        ``(n_f, n_p, 3)`` flank points and unit normals in the member frame; the normal points out
        of the tooth material into the tooth space.
    residual
        ``(n_f, n_p)`` meshing residual of the generation, normalised by |N| A_m.
    mask
        ``(n_f, n_p)`` True where the node lies on the generated flank (converged, before the
        envelope's fold, within the tool). Values at other nodes are finite but meaningless.
    parameters
        ``(n_f, n_p, 3)`` the model's generation parameters at each node (model-specific).
    notes
        What generated the flank (free text).
    surface
        The generated surface beyond the grid (:class:`gearopt.envelope.EnvelopeSurface` or
        anything with the same ``points_at``, ``tool_points`` and ``transformed``), or None:
        exact points at any grid coordinates and the tool that cut the flank, for checks and
        refinements. It follows the map's turns and mirror.
    taper
        :class:`DepthTaper` of a tapered-depth member (the profile coordinate is then t, see
        the module docstring), or None for uniform depth.
    lowest_profile_mm
        ``(n_f,)`` each face column's lowest generated profile coordinate, continuous across
        the nodes (the envelope's fold solved and trimmed,
        :func:`gearopt.envelope.solve_envelope`; +inf without generated nodes), or None
        (known to the nodes only: :attr:`mask`).
    """

    member: str
    flank: str
    hand: str
    teeth: int
    tooth: int = 0
    pitch_angle_deg: float
    face_mm: NDArray
    profile_mm: NDArray
    polar_angle_rad: NDArray
    points_mm: NDArray
    normals: NDArray
    residual: NDArray
    mask: NDArray
    parameters: NDArray = field(repr=False)
    notes: tuple[str, ...] = ()
    surface: Any = field(default=None, repr=False)
    taper: DepthTaper | None = None
    lowest_profile_mm: NDArray | None = field(default=None, repr=False)

    def __post_init__(self):
        n_f, n_p = len(self.face_mm), len(self.profile_mm)
        for name, shape in (
            ("polar_angle_rad", (n_f, n_p)),
            ("points_mm", (n_f, n_p, 3)),
            ("normals", (n_f, n_p, 3)),
            ("residual", (n_f, n_p)),
            ("mask", (n_f, n_p)),
        ):
            value = np.asarray(getattr(self, name))
            if value.shape != shape:
                raise GearoptError(f"FlankMap.{name}", value.shape, f"must have shape {shape}")
            if value.dtype != bool and not np.isfinite(value).all():
                raise GearoptError(f"FlankMap.{name}", rule="must be finite at every node")
        for name in ("face_mm", "profile_mm"):
            step = np.diff(np.asarray(getattr(self, name), float))
            if (
                step.size < 1
                or (low := step.min()) <= 0.0
                or step.max() - low > 1e-9 * abs(step.sum() / step.size)  # (np.ptp, np.mean)
            ):
                raise GearoptError(
                    f"FlankMap.{name}", rule="must be increasing with a uniform step"
                )
        if self.member not in MEMBERS or self.flank not in FLANKS or self.hand not in HANDS:
            raise GearoptError(
                "FlankMap", (self.member, self.flank, self.hand), "unknown member/flank/hand"
            )

    # --- grid -------------------------------------------------------------------------------

    @property
    def shape(self) -> tuple[int, int]:
        """``(n_face, n_profile)``."""
        return (len(self.face_mm), len(self.profile_mm))

    @property
    def pitch_rad(self) -> float:
        """Angular pitch 2 pi / teeth."""
        return 2.0 * math.pi / self.teeth

    @cached_property
    def heights_mm(self) -> NDArray:
        """``(n_f, n_p)`` heights h above the pitch cone of the nodes (``profile_mm`` in every
        column for uniform depth)."""
        if self.taper is None:
            return np.broadcast_to(self.profile_mm[None, :], self.shape)
        return self.taper.height_mm(self.face_mm[:, None], self.profile_mm[None, :])

    def height_at(self, face_mm, profile_mm) -> NDArray:
        """Height h above the pitch cone at grid coordinates ``(s, t)``."""
        if self.taper is None:
            return np.asarray(profile_mm)
        return self.taper.height_mm(face_mm, profile_mm)

    @cached_property
    def axial_mm(self) -> NDArray:
        """``(n_f, n_p)`` L of the nodes."""
        g = math.radians(self.pitch_angle_deg)
        if self.taper is not None:
            return self.face_mm[:, None] * math.cos(g) - self.heights_mm * math.sin(g)
        return self.face_mm[:, None] * math.cos(g) - self.profile_mm[None, :] * math.sin(g)

    @cached_property
    def radius_mm(self) -> NDArray:
        """``(n_f, n_p)`` R of the nodes."""
        g = math.radians(self.pitch_angle_deg)
        if self.taper is not None:
            return self.face_mm[:, None] * math.sin(g) + self.heights_mm * math.cos(g)
        return self.face_mm[:, None] * math.sin(g) + self.profile_mm[None, :] * math.cos(g)

    def to_grid(self, axial_mm, radius_mm) -> tuple[NDArray, NDArray]:
        """Face and profile (grid) coordinates ``(s, t)`` of axial-plane points ``(L, R)``
        (t = h, the height above the pitch cone, for uniform depth)."""
        g = math.radians(self.pitch_angle_deg)
        s, h = cone_coordinates(np.asarray(axial_mm), np.asarray(radius_mm), g)
        if self.taper is not None:
            h = self.taper.profile_of(s, h)
        return s, h

    @property
    def generated_depth_mm(self) -> NDArray:
        """``(n_f,)`` lowest height h of a generated node in each face column (NaN-free: a
        column with no generated node reports the top of the grid)."""
        heights = self.heights_mm
        h = np.where(self.mask, heights, np.inf)
        low = h.min(axis=1)
        return np.where(np.isfinite(low), low, heights[:, -1])

    # --- interpolation ----------------------------------------------------------------------

    @cached_property
    def polar_spline(self) -> RectBivariateSpline:
        """Bicubic spline Theta(s, h) through all nodes (evaluate it on generated nodes only)."""
        # (imported here: about 0.5 s that a process which fits no spline, such as a study's
        # coordinator or the CLI's start, does not pay)
        from scipy.interpolate import RectBivariateSpline

        return RectBivariateSpline(self.face_mm, self.profile_mm, self.polar_angle_rad)

    def polar_angle_at(self, face_mm, profile_mm, *, dface: int = 0, dprofile: int = 0) -> NDArray:
        """Theta (or its derivatives) at grid coordinates ``(s, h)`` by the bicubic spline."""
        return self.polar_spline(
            np.asarray(face_mm), np.asarray(profile_mm), dx=dface, dy=dprofile, grid=False
        )

    @cached_property
    def node_derivatives(self) -> tuple[NDArray, NDArray, NDArray]:
        """Node derivatives of Theta for the local interpolant, ``(Theta_s, Theta_h,
        Theta_sh)`` in grid coordinates: Theta_s and Theta_h from the normals (n . r_s =
        n . r_h = 0, exact where the node is generated), Theta_sh by central differences of
        those."""
        d_s, d_h = polar_gradient(
            self.polar_angle_rad, self.normals, self.radius_mm, self.pitch_angle_deg
        )
        if self.taper is not None:  # to grid coordinates (s, t): the chain rule
            d_s = d_s + d_h * self.taper.dheight_dface(self.profile_mm)[None, :]
            d_h = d_h * self.taper.dheight_dprofile(self.face_mm)[:, None]
        d_sh = 0.5 * (
            _masked_gradient(d_h, self.mask, float(self.face_mm[1] - self.face_mm[0]), 0)
            + _masked_gradient(d_s, self.mask, float(self.profile_mm[1] - self.profile_mm[0]), 1)
        )
        return d_s, d_h, d_sh

    @cached_property
    def cells(self) -> HermiteCells:
        """The local bicubic Hermite interpolant of Theta, cell by cell (:class:`HermiteCells`):
        in each cell the polynomial through the values and first derivatives at its four
        corners (:attr:`node_derivatives`), in the cell's unit coordinates."""
        coef = hermite_coefficients(
            self.polar_angle_rad,
            *self.node_derivatives,
            np.diff(self.face_mm),
            np.diff(self.profile_mm),
        )
        k = self.mask
        ok = k[:-1, :-1] & k[1:, :-1] & k[:-1, 1:] & k[1:, 1:]
        fs, fp = self.face_mm, self.profile_mm
        return HermiteCells(
            face0_mm=float(fs[0]),
            face_scale=(len(fs) - 1) / float(fs[-1] - fs[0]),
            last_row=float(len(fs) - 2),
            profile0_mm=float(fp[0]),
            profile_scale=(len(fp) - 1) / float(fp[-1] - fp[0]),
            last_column=float(len(fp) - 2),
            columns=len(fp) - 1,
            coefficients=coef,
            generated=ok.ravel(),
        )

    def polar_angle_local(self, face_mm, profile_mm, *, with_inside=False):
        """Theta at grid coordinates ``(s, h)`` by the bicubic Hermite interpolant of the cell
        around each point: values and first derivatives at its four corners (the derivatives
        from the exact normals, the cross derivative by differences), so an error at one node
        stays in its cells. More accurate than the global spline near the envelope's fold,
        where Theta is not smooth. With ``with_inside``, also :meth:`inside` of the points (or,
        given a flat boolean array over the cells, whether each point's cell is one of them)."""
        s = np.asarray(face_mm, float)
        h = np.asarray(profile_mm, float)
        if s.shape != h.shape:
            s, h = np.broadcast_arrays(s, h)
        k, u, v, within = self.cells.locate(s, h)
        out = hermite_cells(self.cells.coefficients, k, u, v)
        if with_inside is False:
            return out
        cells = self.cells.generated if with_inside is True else with_inside
        return out, cells[k] & within

    def point_at(self, face_mm, profile_mm) -> NDArray:
        """``(..., 3)`` points of the flank at grid coordinates ``(s, h)`` (spline)."""
        s, h = np.broadcast_arrays(np.asarray(face_mm, float), np.asarray(profile_mm, float))
        g = math.radians(self.pitch_angle_deg)
        big_l, big_r = axial_plane(s, self.height_at(s, h), g)
        theta = self.polar_angle_at(s, h)
        return np.stack([big_r * np.cos(theta), big_r * np.sin(theta), big_l], axis=-1)

    def polar_angle_exact(self, face_mm, profile_mm) -> NDArray:
        """Theta at grid coordinates from the generated surface itself (not the spline);
        needs ``surface``."""
        if self.surface is None:
            raise GearoptError("FlankMap.surface", rule="this FlankMap carries no surface")
        p = self.surface.points_at(face_mm, profile_mm)
        near = self.polar_angle_at(face_mm, profile_mm)
        turn = np.arctan2(p[..., 1], p[..., 0]) - near
        return near + (turn + math.pi) % (2.0 * math.pi) - math.pi

    def tool_penetration_mm(self, count: int = 9) -> float:
        """Deepest penetration (mm, along the normal) of the tool into the tooth material at
        sampled tool positions near the flank (``surface.tool_points(count)``) whose points fall
        on the generated flank; zero or less when the tool only touches the flank, as an
        envelope must. Needs ``surface``."""
        if self.surface is None:
            raise GearoptError("FlankMap.surface", rule="this FlankMap carries no surface")
        p = self.surface.tool_points(count).reshape(-1, 3)
        radius = np.hypot(p[:, 0], p[:, 1])
        s, h = self.to_grid(p[:, 2], radius)
        on = self.inside(s, h)
        if not on.any():
            return 0.0
        p, radius, s, h = p[on], radius[on], s[on], h[on]
        theta = np.arctan2(p[:, 1], p[:, 0])
        flank = self.polar_angle_exact(s, h)
        gap = (theta - flank + math.pi) % (2.0 * math.pi) - math.pi
        # the normal's circumferential component at the nearest node says where the material is
        i = np.clip(np.searchsorted(self.face_mm, s), 0, len(self.face_mm) - 1)
        j = np.clip(np.searchsorted(self.profile_mm, h), 0, len(self.profile_mm) - 1)
        n = self.normals[i, j]
        around = -np.sin(flank) * n[:, 0] + np.cos(flank) * n[:, 1]
        return float(np.max(-radius * gap * around))

    def inside(self, face_mm, profile_mm) -> NDArray:
        """True where ``(s, h)`` lies within a cell whose four corners are generated nodes."""
        s, h = np.asarray(face_mm, float), np.asarray(profile_mm, float)
        i = np.clip(np.searchsorted(self.face_mm, s) - 1, 0, len(self.face_mm) - 2)
        j = np.clip(np.searchsorted(self.profile_mm, h) - 1, 0, len(self.profile_mm) - 2)
        m = self.mask
        cell = m[i, j] & m[i + 1, j] & m[i, j + 1] & m[i + 1, j + 1]
        within = (s >= self.face_mm[0]) & (s <= self.face_mm[-1])
        within &= (h >= self.profile_mm[0]) & (h <= self.profile_mm[-1])
        return cell & within

    # --- symmetry ---------------------------------------------------------------------------

    def rotated(self, angle_rad: float, *, teeth: int = 0) -> FlankMap:
        """The flank turned by ``angle_rad`` about the member axis (``teeth`` adds to ``tooth``)."""
        polar, points, normals = turned(
            self.polar_angle_rad, self.points_mm, self.normals, angle_rad
        )
        return replace(
            self,
            tooth=self.tooth + teeth,
            polar_angle_rad=polar,
            points_mm=points,
            normals=normals,
            surface=None
            if self.surface is None
            else self.surface.transformed(offset_rad=angle_rad),
        )

    def tooth_turned(self, k: int) -> FlankMap:
        """The same flank on tooth ``tooth + k`` (turned by k pitches)."""
        return self.rotated(k * self.pitch_rad, teeth=k)

    def mirrored(self) -> FlankMap:
        """The mirror image in the member's x-z plane: the flank of the opposite hand."""
        polar, points, normals = mirror_image(self.polar_angle_rad, self.points_mm, self.normals)
        return replace(
            self,
            hand="left" if self.hand == "right" else "right",
            polar_angle_rad=polar,
            points_mm=points,
            normals=normals,
            surface=self.surface and self.surface.transformed(sign=-1.0),
        )

    def summary(self) -> dict:
        """JSON-ready summary: grid, generated nodes, residual, how deep the flank is generated
        (the lowest generated height h at the toe, middle and heel columns; the whole depth
        below the top is ``profile_mm[-1] - h``)."""
        depth = self.generated_depth_mm
        return {
            "member": self.member,
            "flank": self.flank,
            "hand": self.hand,
            "tooth": self.tooth,
            "grid": list(self.shape),
            "generated_nodes": int(self.mask.sum()),
            "max_residual": float(self.residual[self.mask].max(initial=0.0)),
            "lowest_generated_height_mm": {
                "toe": float(depth[0]),
                "middle": float(depth[len(depth) // 2]),
                "heel": float(depth[-1]),
            },
            "generated_depth_mm": float(self.profile_mm[-1] - depth.max())
            if self.taper is None
            else float((self.heights_mm[:, -1] - depth).min()),
        }


#: the cubic Hermite basis: the coefficients of x^a in the polynomial with value v0, v1 and
#: derivatives d0, d1 at x = 0, 1 are ``HERMITE @ (v0, v1, d0, d1)``
HERMITE = np.array([[1, 0, 0, 0], [0, 0, 1, 0], [-3, 3, -2, -1], [2, -2, 1, 1]], float)


def polar_gradient(theta, normals, radius_mm, pitch_angle_deg: float):
    """``(Theta_s, Theta_h)`` of a flank at points with polar angles ``theta``, unit normals
    ``normals`` (``(..., 3)``) and radii ``radius_mm``, in the axial plane's cone coordinates
    (s, h): from n . r_s = n . r_h = 0 (:attr:`FlankMap.node_derivatives`)."""
    g = math.radians(pitch_angle_deg)
    sg, cg = math.sin(g), math.cos(g)
    th, n = theta, normals
    cos, sin = np.cos(th), np.sin(th)
    n_r = n[..., 0] * cos + n[..., 1] * sin
    n_t = -n[..., 0] * sin + n[..., 1] * cos
    scale = radius_mm * np.where(np.abs(n_t) > 1e-12, n_t, 1e-12)
    d_s = -(sg * n_r + cg * n[..., 2]) / scale
    d_h = -(cg * n_r - sg * n[..., 2]) / scale
    return d_s, d_h


def hermite_coefficients(theta, d_s, d_h, d_sh, face_steps_mm, profile_steps_mm) -> NDArray:
    """``(n_cells, 16)`` coefficients of the cells' bicubic Hermite polynomials
    (:class:`HermiteCells`): in cell ``(i, j)`` the polynomial through the values ``theta``
    and the derivatives ``d_s``, ``d_h``, ``d_sh`` (``(n_f, n_p)``, grid units) at its four
    corners, in unit coordinates (the cell steps ``(n_f - 1,)`` and ``(n_p - 1,)`` scale the
    derivatives). Compiled when the kernels are (the numpy path gives the same bits)."""
    theta, d_s, d_h, d_sh, a, b = (
        np.ascontiguousarray(v, float)
        for v in (theta, d_s, d_h, d_sh, face_steps_mm, profile_steps_mm)
    )
    if ENABLED:
        out = np.empty(((theta.shape[0] - 1) * (theta.shape[1] - 1), 16))
        _hermite_kernel(theta, d_s, d_h, d_sh, a, b, out)
        return out
    f = np.empty(theta[:-1, :-1].shape + (4, 4))
    for di in (0, 1):
        for dj in (0, 1):
            sl = (slice(di, theta.shape[0] - 1 + di), slice(dj, theta.shape[1] - 1 + dj))
            f[..., di, dj] = theta[sl]
            f[..., di, 2 + dj] = d_h[sl] * b[None, :]
            f[..., 2 + di, dj] = d_s[sl] * a[:, None]
            f[..., 2 + di, 2 + dj] = d_sh[sl] * a[:, None] * b[None, :]
    coef = np.einsum("ai,...ij,bj->...ab", HERMITE, f, HERMITE)
    return np.ascontiguousarray(coef.reshape(-1, 16))


@compiled
def _hermite_kernel(theta, d_s, d_h, d_sh, a, b, out):
    """:func:`hermite_coefficients` cell by cell into ``out``: the corners' values and scaled
    derivatives f, then ``HERMITE f HERMITE^T`` summed term by term in the order numpy's einsum
    sums. Where f is finite (below 1e300: no product overflows) the terms with a zero factor
    (a compile-time constant) are left out: each adds a signed zero to a sum that starts at +0
    and is never -0 (a rounded sum is -0 only of two -0), so the sum is the same to the bit
    with 100 of the 256 terms."""
    m = HERMITE
    n_f, n_p = theta.shape
    f = np.empty((4, 4))
    for ci in range(n_f - 1):
        for cj in range(n_p - 1):
            for di in range(2):
                for dj in range(2):
                    i, j = ci + di, cj + dj
                    f[di, dj] = theta[i, j]
                    f[di, 2 + dj] = d_h[i, j] * b[cj]
                    f[2 + di, dj] = d_s[i, j] * a[ci]
                    f[2 + di, 2 + dj] = d_sh[i, j] * a[ci] * b[cj]
            finite = True
            for i in range(4):
                for j in range(4):
                    finite = finite and abs(f[i, j]) < 1e300
            k = ci * (n_p - 1) + cj
            for p in range(4):
                for q in range(4):
                    total = 0.0
                    for i in range(4):
                        for j in range(4):
                            if not finite or (m[p, i] != 0.0 and m[q, j] != 0.0):
                                total += (m[p, i] * f[i, j]) * m[q, j]
                    out[k, 4 * p + q] = total


def warm_kernels() -> None:
    """Compile the kernels of the cells (:func:`hermite_coefficients`, the node derivatives),
    or load them from numba's disk cache, in this process
    (:func:`gearopt.warmup.warm_kernels`). Nothing without kernels."""
    if ENABLED:
        zeros = np.zeros((2, 2))
        hermite_coefficients(zeros, zeros, zeros, zeros, np.ones(1), np.ones(1))
        _masked_gradient(zeros, np.ones((2, 2), np.bool_), 1.0, 1)


def hermite_cells(coef: NDArray, k: NDArray | None, u: NDArray, v: NDArray) -> NDArray:
    """Bicubic polynomials sum_ab c_ab u^a v^b of cells ``k`` at unit coordinates ``(u, v)``:
    ``coef`` is ``(n_cells, 16)``, column ``4 a + b`` holding c_ab (:class:`HermiteCells`);
    with ``k`` None, ``coef`` holds the cells' rows already, ``(..., 16)``. One gather, then
    Horner on whole arrays."""
    c = np.take(coef, k, axis=0) if k is not None else np.array(coef)
    c = np.moveaxis(c, -1, 0)
    w = c[3::4]
    w *= v
    w += c[2::4]
    w *= v
    w += c[1::4]
    w *= v
    w += c[0::4]
    out = w[3] * u
    out += w[2]
    out *= u
    out += w[1]
    out *= u
    out += w[0]
    return out


def _masked_gradient(values: NDArray, mask: NDArray, step: float, axis: int) -> NDArray:
    """Derivative along ``axis`` of a uniformly spaced field: central differences where both
    neighbours are in ``mask``, second-order one-sided differences into the mask where one is
    not (values off the mask are not used when the mask allows). Compiled for 2-D fields when
    the kernels are (the same bits as the numpy path)."""
    if ENABLED and np.ndim(values) == 2:
        v = np.ascontiguousarray(np.moveaxis(values, axis, 0), float)
        m = np.ascontiguousarray(np.moveaxis(mask, axis, 0), np.bool_)
        out = np.empty_like(v)
        _masked_gradient_kernel(v, m, float(step), out)
        return np.moveaxis(out, 0, axis)
    v = np.moveaxis(values, axis, 0)
    m = np.moveaxis(mask, axis, 0)
    n = v.shape[0]
    out = np.gradient(v, step, axis=0)
    lo = np.zeros_like(m)
    lo[1:] = m[:-1]
    hi = np.zeros_like(m)
    hi[:-1] = m[1:]
    hi2 = np.zeros_like(m)
    hi2[:-2] = m[2:]
    lo2 = np.zeros_like(m)
    lo2[2:] = m[:-2]
    fwd = np.zeros_like(v)
    fwd[:-2] = (-3.0 * v[:-2] + 4.0 * v[1:-1] - v[2:]) / (2.0 * step)
    bwd = np.zeros_like(v)
    bwd[2:] = (3.0 * v[2:] - 4.0 * v[1:-1] + v[:-2]) / (2.0 * step)
    idx = np.arange(n).reshape((-1,) + (1,) * (v.ndim - 1))
    use_fwd = m & ~lo & hi & hi2 & (idx < n - 2)
    use_bwd = m & ~hi & lo & lo2 & (idx >= 2)
    out = np.where(use_fwd, fwd, np.where(use_bwd, bwd, out))
    return np.moveaxis(out, 0, axis)


@compiled
def _masked_gradient_kernel(v, m, step, out):
    """:func:`_masked_gradient` along the first axis of ``(n, k)`` fields, node by node in
    numpy's arithmetic (np.gradient's differences, then the one-sided ones into the mask)."""
    n, k = v.shape
    for c in range(k):
        for r in range(n):
            if r == 0:
                g = (v[1, c] - v[0, c]) / step
            elif r == n - 1:
                g = (v[n - 1, c] - v[n - 2, c]) / step
            else:
                g = (v[r + 1, c] - v[r - 1, c]) / (2.0 * step)
            if m[r, c]:
                lo = r >= 1 and m[r - 1, c]
                hi = r + 1 < n and m[r + 1, c]
                if not lo and hi and r < n - 2 and m[r + 2, c]:
                    g = (-3.0 * v[r, c] + 4.0 * v[r + 1, c] - v[r + 2, c]) / (2.0 * step)
                elif not hi and lo and r >= 2 and m[r - 2, c]:
                    g = (3.0 * v[r, c] - 4.0 * v[r - 1, c] + v[r - 2, c]) / (2.0 * step)
            out[r, c] = g
