"""Initial separations for loaded contact: a fine grid of contact patches around each tooth
pair's unloaded contact, on the flanks' local interpolants.

A light-load contact is a millimetre or two wide, far below the FlankMap's node spacing, so the
potential contact zone of every tooth pair at a mesh position is sampled afresh: strips along the
instantaneous contact line (the long axis of the contact ellipse, the direction of least
curvature of the separation at the unloaded contact point), each strip centred on the valley of
the separation across it and divided into patches across. At every patch centre the clearance
field (:meth:`gearopt.contact.ClearanceField.clearance_of_points`, the same interpolants as the
unloaded TCA) gives the angular clearance delta (how far the gear must turn back from its ideal
position before its flank reaches the point) and the normal factor f = |n . (z_g x q)|, which is
both the normal separation per radian of gear rotation and the moment of a unit normal force
about the gear axis. With the gear turned back by theta, the normal gap at the patch is
(delta - theta) f: the load distribution (:mod:`gearopt.loaded.lcp`) solves for theta and the
patch forces.

One patch lies at the pair's refined unloaded contact point itself, so that at zero load the
least gap over the patches is the unloaded TCA's clearance minimum.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from gearopt.contact import ClearanceField
from gearopt.flank import FlankMap
from gearopt.load_options import PatchOptions
from gearopt.loaded import kernels

__all__ = [
    "PatchOptions",
    "PairPatches",
    "contact_patches",
    "flank_inside",
    "flank_jets",
    "flank_points",
    "outward",
    "position_patches",
]

#: finite-difference step of the separation's curvature (mm)
_STEP_MM = 0.05


def flank_jets(flank: FlankMap, face_mm, profile_mm) -> NDArray:
    """``(..., 3, 3)``: points of a flank's local interpolant at grid coordinates ``(s, t)``
    (the clearance field's) and their derivatives d/ds and d/dt, member frame, unturned
    (one compiled pass, :func:`gearopt.loaded.kernels.flank_jets`)."""
    s, t = np.broadcast_arrays(np.asarray(face_mm, float), np.asarray(profile_mm, float))
    cells, taper = flank.cells, flank.taper
    g = math.radians(flank.pitch_angle_deg)
    grid = (
        float(cells.face0_mm),
        float(cells.face_scale),
        float(cells.last_row),
        float(cells.profile0_mm),
        float(cells.profile_scale),
        float(cells.last_column),
        int(cells.columns),
        math.sin(g),
        math.cos(g),
        taper is not None,
        float(taper.pivot_mm) if taper is not None else 0.0,
        float(taper.alpha) if taper is not None else 0.0,
        float(taper.beta) if taper is not None else 0.0,
    )
    out = np.empty((s.size, 3, 3))
    kernels.flank_jets(
        np.ascontiguousarray(s).ravel(),
        np.ascontiguousarray(t).ravel(),
        grid,
        np.ascontiguousarray(cells.coefficients, dtype=float),
        out,
    )
    return out.reshape(s.shape + (3, 3))


def flank_points(flank: FlankMap, face_mm: NDArray, profile_mm: NDArray):
    """Points, unit normals (out of the tooth) and tangents of a flank's local interpolant at
    grid coordinates ``(s, t)`` (member frame, unturned): ``(p, n, p_s, p_t)``, each
    ``(..., 3)``, from :func:`flank_jets`."""
    jets = flank_jets(flank, face_mm, profile_mm)
    p, p_s, p_t = jets[..., 0, :], jets[..., 1, :], jets[..., 2, :]
    return p, outward(flank, np.cross(p_s, p_t)), p_s, p_t


def flank_inside(flank: FlankMap, face_mm: NDArray, profile_mm: NDArray) -> NDArray:
    """:meth:`gearopt.flank.FlankMap.inside` in one compiled pass
    (:func:`gearopt.loaded.kernels.flank_inside`)."""
    s, h = np.broadcast_arrays(np.asarray(face_mm, float), np.asarray(profile_mm, float))
    out = np.empty(s.shape, bool)
    kernels.flank_inside(
        np.ascontiguousarray(flank.face_mm, dtype=float),
        np.ascontiguousarray(flank.profile_mm, dtype=float),
        np.ascontiguousarray(flank.mask, dtype=np.bool_),
        np.ascontiguousarray(s).ravel(),
        np.ascontiguousarray(h).ravel(),
        out.reshape(-1),
    )
    return out


def outward(flank: FlankMap, normals: NDArray) -> NDArray:
    """``(..., 3)`` normals of a flank made unit and turned out of the tooth, each as the
    FlankMap's own normal at its middle node points."""
    n = normals / np.linalg.norm(normals, axis=-1, keepdims=True)
    reference = flank.normals[tuple(np.array(flank.shape) // 2)]
    sign = np.sign(n @ reference)
    return n * np.where(sign == 0.0, 1.0, sign)[..., None]


@dataclass(frozen=True, kw_only=True)
class PairPatches:
    """The contact patches of one tooth pair at one mesh position.

    Attributes
    ----------
    pair
        The pair's offset in pitches from the base pair.
    phi_rad
        The pair's relative pinion angle (the field's angle, base pair turned by whole pitches).
    face_mm, profile_mm
        ``(along, across)`` pinion grid coordinates of the patch centres.
    gear_face_mm, gear_profile_mm
        ``(along, across)`` the gear grid coordinates of the same points.
    clearance_rad, factor_mm
        ``(along, across)`` the angular clearance delta and the normal factor f (mm of normal
        separation per rad of gear rotation; the moment arm of a normal force about the gear
        axis, mm).
    area_mm2
        ``(along, across)`` the patches' areas on the pinion flank.
    length_mm, width_mm
        ``(along, across)`` the patches' sides along and across the contact line (mm, on the
        flank).
    x_mm, y_mm
        ``(along, across)`` the patch centres' coordinates along and across the contact line
        (mm on the flank, from the unloaded contact point): where the local contact
        compliance of the half-spaces is evaluated.
    valid
        ``(along, across)`` True where the patch lies on both flanks.
    boundary
        ``(along, across)`` True on a valid patch next to a point off the flanks (along or
        across the contact line, one patch further, also beyond the patch grid): the flanks'
        boundary (edge loading where loaded).
    open_end
        ``(along, across)`` True on a valid patch at the patch grid's end whose neighbour beyond
        the grid is on the flanks: the potential contact zone is cut short there (loaded, it
        asks for a longer reach).
    contact_rad
        The pair's refined unloaded clearance minimum (+inf where it does not touch).
    """

    pair: int
    phi_rad: float
    face_mm: NDArray
    profile_mm: NDArray
    gear_face_mm: NDArray
    gear_profile_mm: NDArray
    clearance_rad: NDArray
    factor_mm: NDArray
    area_mm2: NDArray
    length_mm: NDArray
    width_mm: NDArray
    x_mm: NDArray
    y_mm: NDArray
    valid: NDArray
    boundary: NDArray
    open_end: NDArray
    contact_rad: float


def _curvature(field: ClearanceField, phi, s0, h0, factor):
    """``(k, 2, 2)`` the separation's second derivatives (mm per mm^2) at ``(s0, h0)`` (each
    ``(k,)``) by differences."""
    e = _STEP_MM
    ds = np.array([0.0, e, -e, 0.0, 0.0, e, e, -e, -e])
    dh = np.array([0.0, 0.0, 0.0, e, -e, e, -e, e, -e])
    d, _ = field.clearance_at_grid(s0[:, None] + ds, h0[:, None] + dh, phi[:, None])
    hss = (d[:, 1] - 2.0 * d[:, 0] + d[:, 2]) / (e * e)
    hhh = (d[:, 3] - 2.0 * d[:, 0] + d[:, 4]) / (e * e)
    hsh = (d[:, 5] - d[:, 6] - d[:, 7] + d[:, 8]) / (4.0 * e * e)
    return factor[:, None, None] * np.stack(
        [np.stack([hss, hsh], -1), np.stack([hsh, hhh], -1)], -2
    )


def contact_patches(
    field: ClearanceField, u_rad: float, pairs, grid: PatchOptions | None = None
) -> list[PairPatches]:
    """The contact patches of the tooth pairs ``pairs`` (offsets in pitches from the base pair)
    at relative pinion rotation ``u_rad`` (direction of motion), each around its refined
    unloaded contact point (module docstring). Pairs that do not touch are left out, and those
    whose unloaded contact lies more than twice the reach (``grid.reach_um``, in normal
    separation at the contact) above the position's closest pair's: the normal factor would
    have to halve within the zone for a patch of theirs to come within reach."""
    return position_patches(field, [u_rad], pairs, grid)[0]


def position_patches(
    field: ClearanceField,
    u_rad,
    pairs,
    grid: PatchOptions | None = None,
    max_half_width_mm=None,
) -> list[list[PairPatches]]:
    """:func:`contact_patches` at several positions ``u_rad`` at once (one array operation for
    all positions and pairs): one list per position. ``pairs``: the same offsets at every
    position, or one row of offsets per position. ``max_half_width_mm``: the grid's largest
    half-width across the contact line, one per position (default the grid's)."""
    grid = grid or PatchOptions()
    pinion = field.pinion
    u = np.atleast_1d(np.asarray(u_rad, float))
    offsets = np.broadcast_to(np.asarray(pairs, np.intp), (len(u), np.shape(pairs)[-1]))
    phis = (field.sense * (u[:, None] + offsets * pinion.pitch_rad)).ravel()
    sample = field.sample(phis)
    rows = np.flatnonzero(np.isfinite(sample.minimum_rad))
    out: list[list[PairPatches]] = [[] for _ in u]
    if rows.size == 0:
        return out
    phi = phis[rows]
    m0 = sample.minimum_rad[rows]
    s0, h0 = sample.contact_face_mm[rows], sample.contact_profile_mm[rows]
    p0, n0, _, _ = flank_points(pinion, s0, h0)
    f0 = field.clearance_of_rows(p0, n0, phi).normal_factor_mm
    # a pair whose contact lies far above its position's closest one (twice the reach, in
    # normal separation) has no patch within reach: left out
    least = np.full(len(u), np.inf)
    np.minimum.at(least, rows // offsets.shape[1], m0)
    near = (m0 - least[rows // offsets.shape[1]]) * f0 <= 2e-3 * grid.reach_um
    rows, phi, m0, s0, h0, f0 = (a[near] for a in (rows, phi, m0, s0, h0, f0))
    lam, vec = np.linalg.eigh(_curvature(field, phi, s0, h0, f0))
    major, minor = vec[:, :, 0], vec[:, :, 1]  # least curvature: along the contact line
    reach_mm = grid.reach_um * 1e-3
    longest = math.hypot(
        float(pinion.face_mm[-1] - pinion.face_mm[0]),
        float(pinion.profile_mm[-1] - pinion.profile_mm[0]),
    )
    with np.errstate(divide="ignore", invalid="ignore"):
        half_l = np.where(lam[:, 0] > 0.0, np.sqrt(2.0 * reach_mm / lam[:, 0]), longest)
        half_w = np.where(lam[:, 1] > 0.0, np.sqrt(2.0 * reach_mm / lam[:, 1]), np.inf)
    half_l = np.minimum(half_l, longest)
    cap = np.broadcast_to(
        grid.max_half_width_mm if max_half_width_mm is None else max_half_width_mm, u.shape
    )
    half_w = np.minimum(half_w, cap[rows // offsets.shape[1]])
    along, across = grid.along, grid.across
    t = half_l[:, None] * np.linspace(-1.0, 1.0, along)
    w = half_w[:, None] * np.linspace(-1.0, 1.0, across)
    dt, dw = t[:, 1] - t[:, 0], w[:, 1] - w[:, 0]
    # each strip centred on the valley across it (a parabola through three points)
    probe = half_w[:, None] * np.array([-0.5, 0.0, 0.5])
    ps = s0[:, None, None] + t[:, :, None] * major[:, None, None, 0]
    ph = h0[:, None, None] + t[:, :, None] * major[:, None, None, 1]
    d, _ = field.clearance_at_grid(
        ps + probe[:, None, :] * minor[:, None, None, 0],
        ph + probe[:, None, :] * minor[:, None, None, 1],
        phi[:, None, None],
    )
    curve = d[..., 0] - 2.0 * d[..., 1] + d[..., 2]
    with np.errstate(divide="ignore", invalid="ignore"):
        shift = np.where(curve > 0.0, 0.25 * half_w[:, None] * (d[..., 0] - d[..., 2]) / curve, 0.0)
    shift = np.clip(shift, -0.5 * half_w[:, None], 0.5 * half_w[:, None])
    shift[:, along // 2] = 0.0  # the strip through the contact point itself
    # the patch centres and one patch further on every side (beyond the grid too)
    ext_t = np.concatenate([t[:, :1] - dt[:, None], t, t[:, -1:] + dt[:, None]], axis=1)
    ext_shift = np.concatenate([shift[:, :1], shift, shift[:, -1:]], axis=1)
    ext_w = np.concatenate([w[:, :1] - dw[:, None], w, w[:, -1:] + dw[:, None]], axis=1)
    off = ext_shift[:, :, None] + ext_w[:, None, :]
    es = (
        s0[:, None, None]
        + ext_t[:, :, None] * major[:, None, None, 0]
        + off * minor[:, None, None, 0]
    )
    eh = (
        h0[:, None, None]
        + ext_t[:, :, None] * major[:, None, None, 1]
        + off * minor[:, None, None, 1]
    )
    jets = flank_jets(pinion, es, eh)
    points = jets[..., 0, :]
    s, h = es[:, 1:-1, 1:-1], eh[:, 1:-1, 1:-1]
    # every point's tangents along and across the contact line, normal and area element
    normal, area, along_mm, across_mm = (np.empty(es.shape + (3,)), *np.empty((3,) + es.shape))
    reference = pinion.normals[tuple(np.array(pinion.shape) // 2)]
    kernels.patch_frames(jets, major, minor, reference, normal, area, along_mm, across_mm)
    area, along_mm, across_mm = (v[:, 1:-1, 1:-1] for v in (area, along_mm, across_mm))
    # the points beyond the grid (a ring) for the boundary, in the same call
    every = field.clearance_of_rows(points, normal, phi)
    inner = (slice(None), slice(1, -1), slice(1, -1))
    clearance, factor = every.clearance_rad[inner], every.normal_factor_mm[inner]
    ext_valid = flank_inside(pinion, es, eh)
    ext_valid &= every.valid
    valid = ext_valid[inner] & np.isfinite(clearance)
    ext_valid[inner] = valid
    beside = (
        ~ext_valid[:, :-2, 1:-1]
        | ~ext_valid[:, 2:, 1:-1]
        | ~ext_valid[:, 1:-1, :-2]
        | ~ext_valid[:, 1:-1, 2:]
    )
    at_end = np.zeros(valid.shape[1:], bool)
    at_end[0, :] = at_end[-1, :] = at_end[:, 0] = at_end[:, -1] = True
    # the gear's grid coordinates of the points (for the gear's compliance)
    gs, gh = every.gear_face_mm[inner], every.gear_profile_mm[inner]
    length = along_mm * dt[:, None, None]
    width = across_mm * dw[:, None, None]
    scale_a = along_mm[:, along // 2, across // 2]
    scale_w = across_mm[:, along // 2, across // 2]
    x = np.broadcast_to((t * scale_a[:, None])[:, :, None], s.shape)
    y = (shift[:, :, None] + w[:, None, :]) * scale_w[:, None, None]
    for j, row in enumerate(rows):
        out[row // offsets.shape[1]].append(
            PairPatches(
                pair=int(offsets.flat[row]),
                phi_rad=float(phi[j]),
                face_mm=s[j],
                profile_mm=h[j],
                gear_face_mm=gs[j],
                gear_profile_mm=gh[j],
                clearance_rad=np.where(valid[j], clearance[j], np.inf),
                factor_mm=factor[j],
                area_mm2=area[j] * dt[j] * dw[j],
                length_mm=length[j],
                width_mm=width[j],
                x_mm=np.array(x[j]),
                y_mm=y[j],
                valid=valid[j],
                boundary=valid[j] & beside[j],
                open_end=valid[j] & at_end & ~beside[j],
                contact_rad=float(m0[j]),
            )
        )
    return out
