"""The fine boundary cells' numpy reference: ``gearopt/contact/boundary.py``'s tables as it made
them before its compiled kernels (:mod:`gearopt.contact.boundary_kernels`), operation for
operation; ``tests/test_boundary_cells.py`` holds the kernels to the same bits."""

from __future__ import annotations

import math

import numpy as np

from gearopt.contact.boundary import BELOW_MM, REACH_MM, ROWS_ABOVE, STEP_MM
from gearopt.flank import hermite_coefficients, polar_gradient

__all__ = ["boundary_cells", "exact_polar", "extend_down"]


def boundary_cells(pinion):
    """:func:`gearopt.contact.boundary.boundary_cells`'s tables (None for none) by numpy."""
    if pinion.surface is None or pinion.lowest_profile_mm is None:
        return None
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
    th, g_s, g_h = exact_polar(pinion, point, normal, near, s_pts, t_pts)
    block = [a[cols] for a in (theta, d_s, d_h)]
    for a, value in zip(block, (th, g_s, g_h), strict=True):
        a[exact] = value
    extend_down(*block, exact, step)
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


def extend_down(theta, d_s, d_h, exact, step) -> None:
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


def exact_polar(pinion, point, normal, near, s_pts, t_pts):
    """The polar angle and its grid gradient ``(theta, d_s, d_h)`` of exact surface points
    ``point`` (normals ``normal``) at grid coordinates ``(s_pts, t_pts)``, by numpy: the angle
    on the branch nearest ``near`` (the flank's own interpolant there), the gradient to grid
    coordinates by the chain rule where the depth tapers (the boundary cells take these from
    :func:`gearopt.contact.boundary_kernels.exact_values` and the same chain rule)."""
    th = np.arctan2(point[:, 1], point[:, 0]) - near
    th = near + (th + math.pi) % (2.0 * math.pi) - math.pi
    g_s, g_h = polar_gradient(
        th, normal, np.hypot(point[:, 0], point[:, 1]), pinion.pitch_angle_deg
    )
    if pinion.taper is not None:  # to grid coordinates (s, t): the chain rule
        g_s = g_s + g_h * pinion.taper.dheight_dface(t_pts)
        g_h = g_h * pinion.taper.dheight_dprofile(s_pts)
    return th, g_s, g_h
