"""Compiled kernels of loaded contact (numba): the half-space compliance columns, the flank's
points and tangents at the contact patches.

:func:`halfspace_columns` fills columns of the symmetric half-space compliance of rectangular
patches (:func:`gearopt.loaded.halfspace.halfspace_columns_mm_per_n` checks the input and
documents the formulas), Love's exact rectangle near a patch and its multipole expansion far
from it, entry by entry in a compiled loop. As :mod:`gearopt.contact.kernels`: where numba
cannot be imported, or with the environment variable ``GEAROPT_JIT=0``, :data:`ENABLED` is
False and the same functions run as plain Python (slow: for checks, not for studies).
"""

from __future__ import annotations

import math

import numpy as np

from gearopt.jit import ENABLED, compiled

__all__ = [
    "ENABLED",
    "flank_inside",
    "flank_jets",
    "halfspace_columns",
    "influence_columns",
    "patch_columns",
    "table_stencil",
    "warm",
]


@compiled(inline=True)
def _love(dx, dy, a, b):
    """Love's integral of 1 / distance over the rectangle of half-widths ``a, b`` whose centre
    lies at ``(dx, dy)`` from the field point (mm).

    The corners' primitives ``u asinh(v / |u|) + v asinh(u / |v|)`` with ``asinh(w) =
    sgn(w) ln(|w| + sqrt(w^2 + 1))``: ``sgn(u) sgn(v) (|u| ln(|v| + r) + |v| ln(|u| + r))``
    minus ``sgn(u) sgn(v) (|u| ln|u| + |v| ln|v|)``, ``r`` the corner's distance; the second
    part cancels between corners of the same ``u`` (``v``) unless the two ``v`` (``u``) differ
    in sign. Half the cost of eight ``asinh``, the same integral to round-off.
    """
    u1 = dx - a
    u2 = dx + a
    v1 = dy - b
    v2 = dy + b
    au1, au2, av1, av2 = abs(u1), abs(u2), abs(v1), abs(v2)
    su1, su2 = math.copysign(1.0, u1), math.copysign(1.0, u2)
    sv1, sv2 = math.copysign(1.0, v1), math.copysign(1.0, v2)
    total = 0.0
    r = math.sqrt(u2 * u2 + v2 * v2)
    if r > 0.0:
        total += su2 * sv2 * (au2 * math.log(av2 + r) + av2 * math.log(au2 + r))
    r = math.sqrt(u1 * u1 + v2 * v2)
    if r > 0.0:
        total -= su1 * sv2 * (au1 * math.log(av2 + r) + av2 * math.log(au1 + r))
    r = math.sqrt(u2 * u2 + v1 * v1)
    if r > 0.0:
        total -= su2 * sv1 * (au2 * math.log(av1 + r) + av1 * math.log(au2 + r))
    r = math.sqrt(u1 * u1 + v1 * v1)
    if r > 0.0:
        total += su1 * sv1 * (au1 * math.log(av1 + r) + av1 * math.log(au1 + r))
    across_v = sv2 - sv1
    if across_v != 0.0:
        if au2 > 0.0:
            total -= across_v * su2 * au2 * math.log(au2)
        if au1 > 0.0:
            total += across_v * su1 * au1 * math.log(au1)
    across_u = su2 - su1
    if across_u != 0.0:
        if av2 > 0.0:
            total -= across_u * sv2 * av2 * math.log(av2)
        if av1 > 0.0:
            total += across_u * sv1 * av1 * math.log(av1)
    return total


@compiled
def halfspace_columns(x, y, a, b, columns, factor, far_ratio, out):
    """``out[k, i]``: the symmetric half-space compliance between patches ``i`` and
    ``columns[k]`` (mm/N), ``out`` of shape ``(len(columns), n)``.

    ``factor`` is ``composite / pi``. First the multipole expansion to fourth order for every
    pair (a loop without branches), then Love's exact integrals (the symmetric part of the two
    collocations) over it where the centres lie within ``far_ratio`` times the largest
    half-width of the two.
    """
    n = x.size
    a2 = a * a
    b2 = b * b
    a4 = a2 * a2
    b4 = b2 * b2
    ab = a2 * b2
    reach = np.maximum(a, b) * far_ratio
    for k in range(columns.size):
        j = columns[k]
        xj, yj = x[j], y[j]
        a2j, b2j, a4j, b4j, abj = a2[j], b2[j], a4[j], b4[j], ab[j]
        row = out[k]
        for i in range(n):
            dx = xj - x[i]
            dy = yj - y[i]
            d2 = dx * dx + dy * dy
            inv2 = 1.0 / d2 if d2 > 0.0 else 0.0
            p2 = dx * dx * inv2
            q2 = dy * dy * inv2
            # the two rectangles' moments summed, hence 12 and 16 for 6 and 8
            second = (2.0 * p2 - q2) * (a2[i] + a2j) + (2.0 * q2 - p2) * (b2[i] + b2j)
            fourth = (a4[i] + a4j) * ((7.0 * p2 - 6.0) * p2 + 0.6)
            fourth += (b4[i] + b4j) * ((7.0 * q2 - 6.0) * q2 + 0.6)
            fourth += (ab[i] + abj) * ((70.0 / 3.0) * p2 * q2 - 8.0 / 3.0)
            series = 1.0 + second * (inv2 / 12.0) + fourth * (inv2 * inv2 / 16.0)
            row[i] = factor * math.sqrt(inv2) * series
        aj, bj, reach_j = a[j], b[j], reach[j]
        for i in range(n):
            # Love's integral is even in dx and dy: |dx|, |dy| make the entries exactly
            # symmetric
            dx = abs(xj - x[i])
            dy = abs(yj - y[i])
            near = max(reach_j, reach[i])
            if dx * dx + dy * dy <= near * near:
                ai, bi = a[i], b[i]
                near_j = _love(dx, dy, aj, bj) / (4.0 * aj * bj)
                if ai == aj and bi == bj:
                    near_i = near_j
                else:
                    near_i = _love(dx, dy, ai, bi) / (4.0 * ai * bi)
                row[i] = 0.5 * factor * (near_j + near_i)


@compiled
def flank_jets(s, t, grid, coef, out):
    """Points of a flank's local interpolant and their tangents at grid coordinates ``(s, t)``
    (``(n,)`` each; :func:`gearopt.loaded.separations.flank_point` and its derivatives):
    writes ``out`` (``(n, 3, 3)``: the point, d/ds, d/dt, member frame). ``grid``: the cells'
    origin, scale and last index along the face and the profile, cells per row, sin and cos
    of the pitch angle, the taper (flag, pivot, alpha, beta); ``coef`` the cells' bicubics
    (:class:`gearopt.flank.HermiteCells`)."""
    s0, fscale, last_row, t0, pscale, last_col, columns, sg, cg, tapered, pivot, al, be = grid
    for k in range(s.shape[0]):
        x = (s[k] - s0) * fscale
        y = (t[k] - t0) * pscale
        if not math.isfinite(x):
            x = -1.0
        if not math.isfinite(y):
            y = -1.0
        i = int(min(max(x, 0.0), last_row))
        j = int(min(max(y, 0.0), last_col))
        u = x - i
        v = y - j
        c = int(i * columns + j)
        theta = 0.0
        theta_u = 0.0
        theta_v = 0.0
        for a in range(3, -1, -1):  # Horner in u over the rows c_a(v) = sum_b c_ab v^b
            c3, c2, c1, c0 = (
                coef[c, 4 * a + 3],
                coef[c, 4 * a + 2],
                coef[c, 4 * a + 1],
                coef[c, 4 * a],
            )
            w = ((c3 * v + c2) * v + c1) * v + c0
            dw = (3.0 * c3 * v + 2.0 * c2) * v + c1
            theta_u = theta_u * u + theta
            theta = theta * u + w
            theta_v = theta_v * u + dw
        theta_s = theta_u * fscale
        theta_t = theta_v * pscale
        if tapered:
            h = t[k] + (s[k] - pivot) * (al + be * t[k])
            h_s = al + be * t[k]
            h_t = 1.0 + (s[k] - pivot) * be
        else:
            h = t[k]
            h_s = 0.0
            h_t = 1.0
        big_r = s[k] * sg + h * cg
        ct, st = math.cos(theta), math.sin(theta)
        r_s, r_t = sg + h_s * cg, h_t * cg
        out[k, 0, 0] = big_r * ct
        out[k, 0, 1] = big_r * st
        out[k, 0, 2] = s[k] * cg - h * sg
        out[k, 1, 0] = r_s * ct - big_r * st * theta_s
        out[k, 1, 1] = r_s * st + big_r * ct * theta_s
        out[k, 1, 2] = cg - h_s * sg
        out[k, 2, 0] = r_t * ct - big_r * st * theta_t
        out[k, 2, 1] = r_t * st + big_r * ct * theta_t
        out[k, 2, 2] = -h_t * sg


@compiled
def influence_columns(points, weights, columns, table, out):
    """``out[k, i] += sum_pq w_ip T_pq w_jq`` with ``j = columns[k]``: columns of a tooth's
    influence numbers interpolated from its table ``T`` (symmetric, ``(N, N)``) at flank
    points given by their stencils (``points``, ``weights``: ``(n, s)`` table points and
    weights, :meth:`gearopt.loaded.compliance.ToothCompliance.stencil`), ``out`` of shape
    ``(len(columns), n)``. In chunks of columns: the table's row combinations ``v_k = sum_q
    w_jq T_q`` side by side (``(N, chunk)``), then per point its stencil's sum over them, the
    innermost loop along the chunk."""
    n = points.shape[0]
    size = table.shape[0]
    chunk = 32
    v = np.empty((size, chunk))
    row_v = np.empty(size)
    acc = np.empty(chunk)
    for k0 in range(0, columns.size, chunk):
        kc = min(chunk, columns.size - k0)
        for c in range(kc):
            row_v[:] = 0.0
            _gather(row_v, weights[columns[k0 + c]], points[columns[k0 + c]], table, size)
            for m in range(size):
                v[m, c] = row_v[m]
        for i in range(n):
            acc[:kc] = 0.0
            _gather(acc, weights[i], points[i], v, kc)
            for c in range(kc):
                out[k0 + c, i] += acc[c]


@compiled
def patch_columns(starts, x, y, a, b, missing, factor, far_ratio, members, block):
    """Columns ``missing`` (ascending) of the compliance of contact patches into the rows of
    ``block`` (``(len(missing), n)``): within each column's group ``starts[g]:starts[g + 1]``
    (a tooth pair: separate bodies) the half-space part (:func:`halfspace_columns`) plus each
    member's influence numbers (:func:`influence_columns`; ``members``: ``(table, points,
    weights)`` of each), zero outside it. One call for any number of groups."""
    block[:, :] = 0.0
    c0 = 0
    while c0 < missing.size:  # ``missing`` ascending: each group's columns side by side
        g = np.searchsorted(starts, missing[c0], side="right") - 1
        lo, hi = starts[g], starts[g + 1]
        c1 = c0 + 1
        while c1 < missing.size and missing[c1] < hi:
            c1 += 1
        local = missing[c0:c1] - lo
        part = block[c0:c1, lo:hi]
        halfspace_columns(x[lo:hi], y[lo:hi], a[lo:hi], b[lo:hi], local, factor, far_ratio, part)
        for table, points, weights in members:
            influence_columns(points[lo:hi], weights[lo:hi], local, table, part)
        c0 = c1


@compiled
def influence_times(points, weights, starts, table, forces, out):
    """``out += W T W^T f`` within each group ``starts[g]:starts[g + 1]`` (separate bodies): a
    tooth's displacements at flank points under forces at the same points (their stencils
    ``points``, ``weights`` on the table ``T``, symmetric; as :func:`influence_columns`)."""
    size = table.shape[0]
    nodal = np.empty(size)
    moved = np.empty(size)
    for g in range(starts.size - 1):
        lo, hi = starts[g], starts[g + 1]
        nodal[:] = 0.0
        loaded = False
        for j in range(lo, hi):
            if forces[j] != 0.0:
                loaded = True
                for q in range(points.shape[1]):
                    nodal[points[j, q]] += weights[j, q] * forces[j]
        if not loaded:
            continue
        for m in range(size):
            acc = 0.0
            row = table[m]
            for k in range(size):
                acc += row[k] * nodal[k]
            moved[m] = acc
        for i in range(lo, hi):
            acc = 0.0
            for q in range(points.shape[1]):
                acc += weights[i, q] * moved[points[i, q]]
            out[i] += acc


@compiled(inline=True)
def _gather(acc, weights, points, source, count):
    """``acc[:count] += sum_p weights[p] source[points[p], :count]``: a stencil's sum of rows."""
    for p in range(weights.size):
        w = weights[p]
        if w != 0.0:
            row = source[points[p]]
            for c in range(count):
                acc[c] += w * row[c]


@compiled(inline=True)
def _catmull_rom(x, n, nodes, weights):
    """The four nodes and weights of local cubic (Catmull-Rom) interpolation on nodes 0..n-1
    at index coordinate ``x`` (clamped), a linear ghost node beyond either end folded into
    the nodes it stands for."""
    x = min(max(x, 0.0), n - 1.0)
    i = min(int(x), n - 2)
    f = x - i
    f2, f3 = f * f, f * f * f
    weights[0] = 0.5 * (-f3 + 2.0 * f2 - f)
    weights[1] = 0.5 * (3.0 * f3 - 5.0 * f2 + 2.0)
    weights[2] = 0.5 * (-3.0 * f3 + 4.0 * f2 + f)
    weights[3] = 0.5 * (f3 - f2)
    for k in range(4):
        nodes[k] = min(max(i - 1 + k, 0), n - 1)
    if i == 0:  # node -1 = 2 node 0 - node 1
        weights[1] += 2.0 * weights[0]
        weights[2] -= weights[0]
        weights[0] = 0.0
    if i == n - 2:  # node n = 2 node n-1 - node n-2
        weights[2] += 2.0 * weights[3]
        weights[1] -= weights[3]
        weights[3] = 0.0


@compiled
def table_stencil(u, v, n_f, n_p, points, weights):
    """``points[k], weights[k]`` (16 each): the tensor-product Catmull-Rom stencil on an
    ``n_f x n_p`` table (flat index ``a n_p + b``) at index coordinates ``(u[k], v[k])``."""
    nf = np.empty(4, np.intp)
    np_ = np.empty(4, np.intp)
    wf = np.empty(4)
    wp = np.empty(4)
    for k in range(u.size):
        _catmull_rom(u[k], n_f, nf, wf)
        _catmull_rom(v[k], n_p, np_, wp)
        for a in range(4):
            for b in range(4):
                points[k, 4 * a + b] = nf[a] * n_p + np_[b]
                weights[k, 4 * a + b] = wf[a] * wp[b]


@compiled
def patch_frames(jets, major, minor, reference, normal, area, along, across):
    """At every point of a patch grid from the flank's jets (``(r, a, w, 3, 3)``: point and
    its derivatives d/ds, d/dt) and each row's directions along and across the contact line
    in grid coordinates (``major``, ``minor``: ``(r, 2)``): the tangents along and across,
    ``p_major = p_s major_s + p_t major_t`` and ``p_minor`` likewise, their lengths (``along``,
    ``across``: mm per unit of the direction), the unit normal ``p_major x p_minor`` turned as
    ``reference`` (out of the tooth) and the area element ``|p_major x p_minor|``."""
    rows, a_n, w_n = area.shape
    for r in range(rows):
        ms, mt, ns, nt = major[r, 0], major[r, 1], minor[r, 0], minor[r, 1]
        for i in range(a_n):
            for k in range(w_n):
                j = jets[r, i, k]
                ux = j[1, 0] * ms + j[2, 0] * mt
                uy = j[1, 1] * ms + j[2, 1] * mt
                uz = j[1, 2] * ms + j[2, 2] * mt
                vx = j[1, 0] * ns + j[2, 0] * nt
                vy = j[1, 1] * ns + j[2, 1] * nt
                vz = j[1, 2] * ns + j[2, 2] * nt
                cx = uy * vz - uz * vy
                cy = uz * vx - ux * vz
                cz = ux * vy - uy * vx
                size = math.sqrt(cx * cx + cy * cy + cz * cz)
                sign = cx * reference[0] + cy * reference[1] + cz * reference[2]
                scale = (-1.0 if sign < 0.0 else 1.0) / size if size > 0.0 else 0.0
                normal[r, i, k, 0] = cx * scale
                normal[r, i, k, 1] = cy * scale
                normal[r, i, k, 2] = cz * scale
                area[r, i, k] = size
                along[r, i, k] = math.sqrt(ux * ux + uy * uy + uz * uz)
                across[r, i, k] = math.sqrt(vx * vx + vy * vy + vz * vz)


@compiled
def flank_inside(face, profile, mask, s, h, out):
    """Whether grid coordinates ``(s, h)`` (flat, ``(n,)``) lie within a cell of the grid
    ``face`` x ``profile`` whose four corners are in ``mask``: point by point as
    :meth:`gearopt.flank.FlankMap.inside` (the same cells at the nodes: numpy's
    ``searchsorted``)."""
    nf, nh = face.size, profile.size
    for k in range(s.size):
        a, b = s[k], h[k]
        i = min(max(np.searchsorted(face, a) - 1, 0), nf - 2)
        j = min(max(np.searchsorted(profile, b) - 1, 0), nh - 2)
        out[k] = (
            mask[i, j]
            and mask[i + 1, j]
            and mask[i, j + 1]
            and mask[i + 1, j + 1]
            and a >= face[0]
            and a <= face[nf - 1]
            and b >= profile[0]
            and b <= profile[nh - 1]
        )


def warm() -> None:
    """Compile every kernel, or load it from the disk cache, in this process (on one patch),
    before worker processes start: they then load the cache rather than compile it side by
    side. Nothing without the kernels."""
    if not ENABLED:
        return
    one = np.ones(1)
    halfspace_columns(one, one, one, one, np.zeros(1, np.intp), 1.0, 4.0, np.empty((1, 1)))
    grid = (0.0, 1.0, 0.0, 0.0, 1.0, 0.0, 1, 0.0, 1.0, False, 0.0, 0.0, 0.0)
    flank_jets(one, one, grid, np.zeros((1, 16)), np.empty((1, 3, 3)))
    table_stencil(one, one, 2, 2, np.empty((1, 16), np.intp), np.empty((1, 16)))
    two = np.array([0.0, 1.0])
    flank_inside(two, two, np.ones((2, 2), np.bool_), one, one, np.empty(1, np.bool_))
    influence_times(
        np.zeros((1, 1), np.intp), np.ones((1, 1)), np.array([0, 1], np.intp), np.ones((1, 1)),
        np.ones(1), np.zeros(1),
    )  # fmt: skip
    frames = np.empty((1, 1, 1))
    patch_frames(
        np.zeros((1, 1, 1, 3, 3)), np.ones((1, 2)), np.ones((1, 2)), np.ones(3),
        np.empty((1, 1, 1, 3)), frames, frames.copy(), frames.copy(),
    )  # fmt: skip
    influence_columns(
        np.zeros((1, 1), np.intp),
        np.ones((1, 1)),
        np.zeros(1, np.intp),
        np.ones((1, 1)),
        np.zeros((1, 1)),
    )
    member = (np.ones((1, 1)), np.zeros((1, 16), np.intp), np.ones((1, 16)))
    patch_columns(
        np.array([0, 1], np.intp), one, one, one, one, np.zeros(1, np.intp), 1.0, 4.0,
        (member, member), np.empty((1, 1)),
    )  # fmt: skip
