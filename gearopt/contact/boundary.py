"""The pinion's interpolant near its generated boundary, on finer cells of the exact surface.

Toward the root the pinion's flank ends ``fold_trim_mm`` (0.3 mm) above the envelope's fold
(:func:`gearopt.envelope.solve_envelope`). Near a fold Theta(s, t) is not polynomial: its
second derivative across the fold grows as the inverse square root of the distance to it, so
the flank's bicubic cells (:attr:`gearopt.flank.FlankMap.cells`) are wrong by tenths of a
micrometre in the cell through the boundary (whose lower corners are not generated) and by
hundredths in the two above it (seed 001 Table 3's pinion, default grid). That is the size of a
line contact's whole clearance budget and enough to move a tangency point along a long contact
ellipse by tenths of a millimetre.

:func:`boundary_cells` replaces, in each face row of cells, the cells from the one through the
generated boundary up to :data:`REACH_MM` above it (and at least two cells above the lowest
generated nodes) by ``k`` cells each along the profile (``k`` = the cell's height over
:data:`STEP_MM`, at least one), bicubic Hermite cells through the exact surface's points and
normals at their corners (:meth:`gearopt.envelope.EnvelopeSurface.geometry_at`; the cross
derivative by differences along the profile): the error of a cubic falls as the fourth power of
the step, and the corners lie at least 0.05 mm clear of the fold (a corner more than
:data:`BELOW_MM` below its column's boundary takes the quadratic extension of the exact points
above it). The fine cells meet the flank's own cells above them on nodes whose data they share
(C1 across that line). Below the lowest fine cell its polynomial goes on (the smooth extension
the tangency point is solved on beyond the flank). On the conjugate face-milled pinion
(``studies/face_milling_conjugate.toml``) they are within 0.001 um of the exact surface, its own
cells 4 um off in the cell through the boundary and 0.03 um in the one above.

The contact engine evaluates the pinion through this table (:mod:`gearopt.contact.kernels`'s
point evaluations), so its refined minimum, tangency points and zones reach the generated
boundary on the same accurate interpolant (:func:`gearopt.contact.engine.node_tables`). A flank
without an exact surface or a solved boundary has none: the engine then keeps its refinement two
cells above the lowest generated nodes.
"""

from __future__ import annotations

import math
import weakref

import numpy as np

from gearopt.errors import GearoptError
from gearopt.flank import hermite_cells, hermite_coefficients, polar_gradient

__all__ = ["BELOW_MM", "STEP_MM", "boundary_cells", "band_theta"]

#: the fine cells' height along the profile at most (mm)
STEP_MM = 0.1
#: corners more than this below their column's generated boundary take an extension (mm; the
#: envelope keeps its flank 0.3 mm clear of the fold)
BELOW_MM = 0.25
#: the fine cells reach this far above the generated boundary at least (mm): the flank's own
#: cells err by 0.008 um 0.8 mm above a fold, 0.002 um 1.5 mm above (0.37 mm cells)
REACH_MM = 1.5
#: and this many cells above the lowest generated nodes
ROWS_ABOVE = 2

_CACHE: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def boundary_cells(pinion):
    """The pinion's fine cells at its generated boundary: ``(band, coefficients)`` or None.

    ``band`` ``(n_cells, 4)`` per cell of the flank's table: the index of its face row's first
    fine cell (-1: the flank's own cell), the cell's row above the face row's lowest fine row,
    the fine cells per cell ``k`` and the face row's fine cells ``m``; ``coefficients``
    ``(cells, 16)`` as :class:`gearopt.flank.HermiteCells`'s, in the fine cell's unit
    coordinates. A point at unit coordinates ``(u, v)`` of a cell with ``band = (b, o, k, m)``
    lies in fine cell ``b + clip(floor((o + v) k), 0, m - 1)`` (:func:`band_theta`). None
    without an exact surface or a solved boundary, or where the surface cannot be solved at a
    corner (the flank's own cells then). Kept per FlankMap (the same flank's fields share it).
    """
    if pinion.surface is None or pinion.lowest_profile_mm is None:
        return None
    if pinion not in _CACHE:
        try:
            _CACHE[pinion] = _made(pinion)
        except GearoptError:
            _CACHE[pinion] = None
    return _CACHE[pinion]


def _made(pinion):
    face, profile = np.asarray(pinion.face_mm, float), np.asarray(pinion.profile_mm, float)
    n_f, n_p = len(face), len(profile)
    dp = float(np.mean(np.diff(profile)))
    mask = pinion.mask
    low = np.asarray(pinion.lowest_profile_mm, float)
    lowest_node = np.where(mask.any(axis=1), np.argmax(mask, axis=1), n_p)
    # each face row's fine rows: from the cell through its lower boundary point to two cells
    # above its higher lowest node
    both = np.isfinite(low[:-1]) & np.isfinite(low[1:]) & (lowest_node[:-1] < n_p)
    both &= lowest_node[1:] < n_p
    with np.errstate(invalid="ignore"):
        bottom = np.floor((np.minimum(low[:-1], low[1:]) - profile[0]) / dp)
    bottom = np.clip(np.where(both, bottom, 0), 0, n_p - 2).astype(np.intp)
    with np.errstate(invalid="ignore"):
        reach = np.ceil((np.maximum(low[:-1], low[1:]) + REACH_MM - profile[0]) / dp)
    top = np.maximum(
        np.maximum(lowest_node[:-1], lowest_node[1:]) + ROWS_ABOVE, np.where(both, reach, 0)
    )
    top = np.minimum(top, n_p - 1).astype(np.intp)
    rows = np.flatnonzero(both & (top > bottom))
    if not rows.size:
        return None
    k = max(1, math.ceil(dp / STEP_MM - 1e-9))
    step = dp / k
    # the corners: every column's levels (fine rows) from the lowest fine row to the highest
    level0, level1 = int(bottom[rows].min()) * k, int(top[rows].max()) * k
    levels = np.arange(level0, level1 + 1)
    t = profile[0] + levels * step
    cols = np.unique(np.concatenate([rows, rows + 1]))
    theta, d_s, d_h, d_sh = (np.zeros((n_f, len(levels))) for _ in range(4))
    exact = (t[None, :] >= low[cols, None] - BELOW_MM) & np.isfinite(low[cols, None])
    s_pts = np.broadcast_to(face[cols, None], exact.shape)[exact]
    t_pts = np.broadcast_to(t[None, :], exact.shape)[exact]
    geo = pinion.surface.geometry_at(s_pts, t_pts)
    point, normal = geo["point"], geo["normal"]
    near = pinion.polar_angle_local(s_pts, t_pts)
    th = np.arctan2(point[:, 1], point[:, 0]) - near
    th = near + (th + math.pi) % (2.0 * math.pi) - math.pi
    g_s, g_h = polar_gradient(
        th, normal, np.hypot(point[:, 0], point[:, 1]), pinion.pitch_angle_deg
    )
    if pinion.taper is not None:  # to grid coordinates (s, t): the chain rule
        g_s = g_s + g_h * pinion.taper.dheight_dface(t_pts)
        g_h = g_h * pinion.taper.dheight_dprofile(s_pts)
    block = [a[cols] for a in (theta, d_s, d_h)]
    for a, value in zip(block, (th, g_s, g_h), strict=True):
        a[exact] = value
    _extend_down(*block, exact, step)
    for a, b in zip((theta, d_s, d_h), block, strict=True):
        a[cols] = b
    d_sh[cols] = np.gradient(d_s[cols], step, axis=1, edge_order=2)
    # the flank's own node data where the fine cells' top meets its cells
    node_s, node_h, node_sh = pinion.node_derivatives
    on_node = (levels % k == 0) & (levels // k < n_p)
    j = levels[on_node] // k
    # (on the face rows' top lines only: below them the exact data)
    row_top = np.full(n_f - 1, -1)
    row_top[rows] = top[rows]
    on_top = np.zeros((n_f, len(j)), bool)
    on_top[:-1] |= j[None, :] == row_top[:, None]
    on_top[1:] |= j[None, :] == row_top[:, None]
    own = mask[:, j] & on_top
    for a, b in zip(
        (theta, d_s, d_h, d_sh), (pinion.polar_angle_rad, node_s, node_h, node_sh), strict=True
    ):
        part = a[:, on_node]
        part[own] = b[:, j][own]
        a[:, on_node] = part
    coef = hermite_coefficients(
        theta, d_s, d_h, d_sh, np.diff(face), np.full(len(levels) - 1, step)
    )
    per_row = len(levels) - 1
    band = np.zeros((n_f - 1, n_p - 1, 4))
    band[..., 0] = -1.0
    jj = np.arange(n_p - 1)[None, :]
    inside = np.zeros((n_f - 1, 1), bool)
    inside[rows] = True
    inside = inside & (jj < top[:, None])
    base = np.arange(n_f - 1) * per_row + (bottom * k - level0)
    band[..., 0] = np.where(inside, base[:, None], -1.0)
    band[..., 1] = np.where(inside, jj - bottom[:, None], 0.0)
    band[..., 2] = k
    band[..., 3] = np.where(inside, (top - bottom)[:, None] * k, 1.0)
    return np.ascontiguousarray(band.reshape(-1, 4)), coef


def _extend_down(theta, d_s, d_h, exact, step) -> None:
    """Each column's corners below its lowest exact one (``exact`` ``(n, levels)``, increasing
    levels ``step`` apart) from the two lowest exact ones: Theta quadratic, its derivatives
    linear (in place)."""
    n, m = exact.shape
    first = np.argmax(exact, axis=1)
    ok = exact.any(axis=1) & (first + 1 < m)
    r = np.arange(n)
    e = np.minimum(first, m - 2)
    t_hh = (d_h[r, e + 1] - d_h[r, e]) / step
    t_sh = (d_s[r, e + 1] - d_s[r, e]) / step
    gap = (np.arange(m)[None, :] - e[:, None]) * step
    below = ok[:, None] & (np.arange(m)[None, :] < first[:, None])
    theta[below] = (
        theta[r, e][:, None] + d_h[r, e][:, None] * gap + 0.5 * t_hh[:, None] * gap * gap
    )[below]
    d_h[below] = (d_h[r, e][:, None] + t_hh[:, None] * gap)[below]
    d_s[below] = (d_s[r, e][:, None] + t_sh[:, None] * gap)[below]


def band_theta(coef, band, band_coef, cell, u, v):
    """Theta of the pinion at unit coordinates ``(u, v)`` of cells ``cell`` (arrays) through the
    fine cells where ``band`` has them (:func:`boundary_cells`), else the cell's own
    polynomial ``coef``: numpy's path of :func:`gearopt.contact.kernels`'s evaluation."""
    out = hermite_cells(coef, cell, u, v)
    if band is None:
        return out
    entry = band[cell]
    fine = entry[..., 0] >= 0.0
    if not np.any(fine):
        return out
    y = (entry[..., 1] + v) * entry[..., 2]
    m = np.clip(np.floor(y), 0.0, entry[..., 3] - 1.0)
    index = np.where(fine, entry[..., 0] + m, 0).astype(np.intp)
    return np.where(fine, hermite_cells(band_coef, index, u, y - m), out)
