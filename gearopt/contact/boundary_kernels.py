"""Compiled steps of the pinion's fine boundary cells (:mod:`gearopt.contact.boundary`).

:func:`fine_layout` places the fine rows (which face rows of cells have them, their levels,
the exact surface's corners and the cell table's band), :func:`local_theta` evaluates the
flank's own interpolant at the corners (the polar angle the exact ones are unwrapped to),
:func:`exact_values` the exact corners' polar angle and its gradient and :func:`fine_corners`
fills the corners' values and derivatives: the exact ones, the extension
below them, the cross derivative by differences along the profile and the flank's own node
data on each face row's top line. Each does numpy's operations of the module's first version
in numpy's order (the same bits; checked by ``tests/test_boundary_cells.py``), without the
per-call cost of some sixty small array operations. Plain Python without the kernels
(:mod:`gearopt.jit`).
"""

from __future__ import annotations

import math

import numpy as np

from gearopt.jit import ENABLED, compiled

__all__ = ["ENABLED", "exact_values", "fine_corners", "fine_layout", "local_theta", "warm"]


@compiled
def fine_layout(face, profile, low, mask, dp, step_mm, reach_mm, below_mm, rows_above):
    """The fine rows of a flank's grid ``(face, profile)`` (``mask`` its generated nodes,
    ``low`` each face column's lowest generated profile coordinate, ``dp`` the profile step):
    ``(k, level0, bottom, top, rows, cols, exact, s_pts, t_pts, band)``. ``k`` fine cells per
    cell (0: no face row has fine cells, the rest empty), ``level0`` the lowest fine level,
    each face row's fine rows from cell ``bottom`` to ``top`` where ``rows``, the columns
    ``cols`` whose corners ``exact`` ``(cols, levels)`` lie on the exact surface, at grid
    coordinates ``(s_pts, t_pts)`` (row-major), and the band ``(cells, 4)`` of
    :func:`gearopt.contact.boundary.boundary_cells`."""
    n_f, n_p = mask.shape
    lowest = np.full(n_f, n_p, np.intp)
    for i in range(n_f):
        for j in range(n_p):
            if mask[i, j]:
                lowest[i] = j
                break
    bottom = np.zeros(n_f - 1, np.intp)
    top = np.zeros(n_f - 1, np.intp)
    rows = np.zeros(n_f - 1, np.bool_)
    first, last = n_p, 0
    for i in range(n_f - 1):
        a, b = low[i], low[i + 1]
        both = math.isfinite(a) and math.isfinite(b) and lowest[i] < n_p and lowest[i + 1] < n_p
        lo, reach = 0.0, 0.0
        if both:
            lo = float(math.floor((min(a, b) - profile[0]) / dp))
            reach = float(math.ceil((max(a, b) + reach_mm - profile[0]) / dp))
        bottom[i] = int(min(max(lo, 0.0), n_p - 2.0))
        top[i] = int(min(max(float(max(lowest[i], lowest[i + 1]) + rows_above), reach), n_p - 1.0))
        rows[i] = both and top[i] > bottom[i]
        if rows[i]:
            first, last = min(first, bottom[i]), max(last, top[i])
    k, step, level0, n_levels = 0, 0.0, 0, 0
    if first < n_p:  # some face row has fine cells
        k = max(1, math.ceil(dp / step_mm - 1e-9))
        step = dp / k
        level0, n_levels = first * k, last * k - first * k + 1
    in_cols = np.zeros(n_f, np.bool_)
    for i in range(n_f - 1):
        if rows[i]:
            in_cols[i] = True
            in_cols[i + 1] = True
    cols = np.flatnonzero(in_cols)
    exact = np.zeros((len(cols), n_levels), np.bool_)
    count = 0
    for c in range(len(cols)):
        edge = low[cols[c]]
        if math.isfinite(edge):
            for m in range(n_levels):
                if profile[0] + (level0 + m) * step >= edge - below_mm:
                    exact[c, m] = True
                    count += 1
    s_pts, t_pts = np.empty(count), np.empty(count)
    n = 0
    for c in range(len(cols)):
        for m in range(n_levels):
            if exact[c, m]:
                s_pts[n], t_pts[n] = face[cols[c]], profile[0] + (level0 + m) * step
                n += 1
    band = np.empty((n_f - 1, n_p - 1, 4))
    for i in range(n_f - 1):
        base = i * (n_levels - 1) + (bottom[i] * k - level0)
        for j in range(n_p - 1):
            inside = rows[i] and j < top[i]
            band[i, j, 0] = base if inside else -1.0
            band[i, j, 1] = j - bottom[i] if inside else 0.0
            band[i, j, 2] = k
            band[i, j, 3] = (top[i] - bottom[i]) * k if inside else 1.0
    return k, level0, bottom, top, rows, cols, exact, s_pts, t_pts, band.reshape(-1, 4)


@compiled
def local_theta(cells, coef, s, t):
    """``(n,)`` :meth:`gearopt.flank.FlankMap.polar_angle_local` at finite grid coordinates
    ``(s, t)``: the cell's Hermite polynomial (``coef``) at the point's unit coordinates, the
    same operations in the same order. ``cells``: ``(face0, face_scale, last_row, profile0,
    profile_scale, last_column, columns)`` of :class:`gearopt.flank.HermiteCells`."""
    face0, face_scale, last_row, profile0, profile_scale, last_column, columns = cells
    out = np.empty(len(s))
    for p in range(len(s)):
        x = (s[p] - face0) * face_scale
        y = (t[p] - profile0) * profile_scale
        fi = int(min(max(x, 0.0), last_row))
        fj = int(min(max(y, 0.0), last_column))
        u, v = x - fi, y - fj
        c = coef[fi * columns + fj]
        # Horner in v per power of u, then in u (scalars: no array per point)
        value = 0.0
        for a in range(3, -1, -1):
            acc = c[4 * a + 3] * v
            acc += c[4 * a + 2]
            acc *= v
            acc += c[4 * a + 1]
            acc *= v
            acc += c[4 * a]
            if a == 3:
                value = acc
            else:
                value *= u
                value += acc
        out[p] = value
    return out


@compiled
def exact_values(point, normal, near, sin_cos_pitch):
    """``(3, n)``: the polar angle and its gradient ``(theta, d_s, d_h)`` of exact surface
    points ``point`` (unit normals ``normal``, each ``(n, 3)``) in cone coordinates (s, h), the
    angle on the branch nearest ``near``: the numpy reference's (``tests/numpy_boundary.py``) on
    uniform depth (:func:`gearopt.flank.polar_gradient`), its operations in its order point by
    point. ``sin_cos_pitch``: the pitch angle's sine and cosine (Python's)."""
    sg, cg = sin_cos_pitch
    out = np.empty((3, len(near)))
    for p in range(len(near)):
        x, y = point[p, 0], point[p, 1]
        th = math.atan2(y, x) - near[p]
        th = near[p] + (th + math.pi) % (2.0 * math.pi) - math.pi
        cos, sin = math.cos(th), math.sin(th)
        n0, n1, n2 = normal[p, 0], normal[p, 1], normal[p, 2]
        n_r = n0 * cos + n1 * sin
        n_t = -n0 * sin + n1 * cos
        scale = np.hypot(x, y) * (n_t if abs(n_t) > 1e-12 else 1e-12)  # (libm's, not Python's)
        out[0, p] = th
        out[1, p] = -(sg * n_r + cg * n2) / scale
        out[2, p] = -(cg * n_r - sg * n2) / scale
    return out


@compiled
def fine_corners(n_f, cols, exact, values, step, layout, mask, node):
    """The fine cells' corner data ``(theta, d_s, d_h, d_sh)``, each ``(n_f, levels)``: the
    exact surface's ``values`` ``(3, points)`` (Theta, Theta_s, Theta_h at the ``exact``
    corners of columns ``cols``, row-major), each column's corners below them extended from
    the two lowest (Theta quadratic, its derivatives linear), Theta_sh by differences of
    Theta_s along the profile (second order, one-sided at the ends: :func:`numpy.gradient`'s),
    and on each face row's top line the flank's own data ``node`` ``(4, n_f, n_p)`` at its
    generated nodes (``mask``). ``layout``: ``(k, level0, top, rows)`` of
    :func:`fine_layout`."""
    k, level0, top, rows = layout
    n_c, m = exact.shape
    out = np.zeros((4, n_f, m))
    theta, d_s, d_h, d_sh = out[0], out[1], out[2], out[3]
    n = 0
    for c in range(n_c):
        i = cols[c]
        for j in range(m):
            if exact[c, j]:
                theta[i, j], d_s[i, j], d_h[i, j] = values[0, n], values[1, n], values[2, n]
                n += 1
        first = m
        for j in range(m):
            if exact[c, j]:
                first = j
                break
        if first < m and first + 1 < m:
            e = min(first, m - 2)
            t_hh = (d_h[i, e + 1] - d_h[i, e]) / step
            t_sh = (d_s[i, e + 1] - d_s[i, e]) / step
            for j in range(first):
                gap = (j - e) * step
                theta[i, j] = theta[i, e] + d_h[i, e] * gap + 0.5 * t_hh * gap * gap
                d_h[i, j] = d_h[i, e] + t_hh * gap
                d_s[i, j] = d_s[i, e] + t_sh * gap
        f, g = d_s[i], d_sh[i]
        for j in range(1, m - 1):
            g[j] = (f[j + 1] - f[j - 1]) / (2.0 * step)
        g[0] = -1.5 / step * f[0] + 2.0 / step * f[1] + -0.5 / step * f[2]
        g[m - 1] = 0.5 / step * f[m - 3] + -2.0 / step * f[m - 2] + 1.5 / step * f[m - 1]
    n_p = mask.shape[1]
    for j in range(m):
        level = level0 + j
        if level % k != 0 or level // k >= n_p:
            continue
        node_j = level // k
        for i in range(n_f):
            on_top = (i < n_f - 1 and rows[i] and top[i] == node_j) or (
                i > 0 and rows[i - 1] and top[i - 1] == node_j
            )
            if on_top and mask[i, node_j]:
                for a in range(4):
                    out[a, i, j] = node[a, i, node_j]
    return out


def warm() -> None:
    """Compile the kernels, or load them from numba's disk cache, in this process (one face
    row of two cells). Nothing without the kernels."""
    if not ENABLED:
        return
    face, profile = np.array([0.0, 1.0]), np.array([0.0, 0.1, 0.2])
    mask = np.ones((2, 3), np.bool_)
    low = np.zeros(2)
    k, level0, bottom, top, rows, cols, exact, s, t, _ = fine_layout(
        face, profile, low, mask, 0.1, 0.1, 0.1, 0.25, 1
    )
    cells = (0.0, 1.0, 0.0, 0.0, 10.0, 1.0, 2)
    theta = local_theta(cells, np.zeros((2, 16)), s, t)
    values = exact_values(np.ones((len(s), 3)), np.ones((len(s), 3)), theta, (0.5, 0.5))
    node = np.zeros((4, 2, 3))
    fine_corners(2, cols, exact, values, 0.1, (k, level0, top, rows), mask, node)
