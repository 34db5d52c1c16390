"""Compiled kernels of the contact engine (numba), its one implementation of each hot loop.

Written point by point in compiled loops, so that a small batch costs its points rather than
numpy's fixed overhead per call (the engine's refinement evaluates a few hundred points at a
time, many times over); :class:`gearopt.contact.engine.ContactEngine` prepares their tables:

- :func:`node_fields`: the clearance, the normal factor and R2 at every generated node of the
  pinion flank for each row (side, pinion angle, gear angle), off-mask nodes +inf / 0 / 0;
- :func:`point_fields`: the clearance, the normal factor, R2 and the gear's grid coordinates of
  pinion points given in the member frame (the loaded contact's patches);
- :func:`clearance_at`: the clearance at pinion grid coordinates by the pinion's local
  interpolant, and whether the point is on both flanks and in a refinable pinion cell;
- :func:`refine`: the refinement's constrained Newton steps (its candidate nodes:
  :mod:`gearopt.contact.minima`);
- :func:`tangency`, :func:`interval_end`: the tangency point (the least clearance over the
  smooth extension of the flanks) and where it leaves the flanks (the contact interval's ends);
- :func:`pinion_at`, :func:`gap_of`: a pinion point's row-independent part and its clearance
  on a row, inlined into the kernels here and into the marking-compound zone's
  (:mod:`gearopt.contact.zone_kernels`).

The point helpers (:func:`pinion_at`, :func:`gap_of` and what they inline) take the tables
as tuples and read each entry where no branch lies between a table's first and last use:
numba takes a reference on every array of a tuple bound to a variable (an inlined helper's
parameter) and releases it after its last use, atomically, and prunes the pair only within
one block. Across a branch (or through a call that takes the tables) that cost 28 atomic
operations per point, as much as the evaluation itself; the loops over points are therefore
written in the kernels that own them, the tables unpacked once outside.

A numpy reference of the node fields, the point clearance and the refinement (the engine's
whole-array paths before these kernels) lives with the tests (``tests/numpy_engine.py``); the
kernels' parity test holds the two to the same results. Where numba cannot be imported, or
with the environment variable ``GEAROPT_JIT=0``, :data:`ENABLED` is False and the same
functions run as plain Python (slow: for checks, not for studies).
"""

from __future__ import annotations

import math

import numpy as np

from gearopt.jit import ENABLED, compiled

__all__ = [
    "ENABLED",
    "clearance_at",
    "interval_end",
    "node_fields",
    "point_fields",
    "refine",
    "gap_of",
    "pinion_at",
    "tangency",
]


_TO_TURNS = 0.5 / math.pi
_TURN = 2.0 * math.pi
# the refinement's stencil (centre, the four neighbours, the four corners) in steps of a
# fraction of a cell
_STENCIL_S = np.array([0.0, 1.0, -1.0, 0.0, 0.0, 1.0, 1.0, -1.0, -1.0])
_STENCIL_T = np.array([0.0, 0.0, 0.0, 1.0, -1.0, 1.0, -1.0, 1.0, -1.0])


@compiled(inline=True)
def _hermite(coef, k, u, v):
    """The bicubic of cell ``k`` (``coef`` is ``(cells, 16)``, c_ab at ``4 a + b``) at
    ``(u, v)``: Horner as :func:`gearopt.flank.hermite_cells`."""
    w0 = ((coef[k, 3] * v + coef[k, 2]) * v + coef[k, 1]) * v + coef[k, 0]
    w1 = ((coef[k, 7] * v + coef[k, 6]) * v + coef[k, 5]) * v + coef[k, 4]
    w2 = ((coef[k, 11] * v + coef[k, 10]) * v + coef[k, 9]) * v + coef[k, 8]
    w3 = ((coef[k, 15] * v + coef[k, 14]) * v + coef[k, 13]) * v + coef[k, 12]
    return ((w3 * u + w2) * u + w1) * u + w0


@compiled(inline=True)
def _corner(x, limit):
    """The cell's corner along one unit grid coordinate: ``trunc(fmin(fmax(x, 0), limit))``
    (a NaN coordinate takes 0; ``np.trunc`` of the finite ``a``, one instruction, is the
    ``float(int(a))`` it replaces)."""
    a = x if x > 0.0 else 0.0
    if not a < limit:
        a = limit
    return np.trunc(a)


@compiled(inline=True)
def _gear_unit(o2, o3, radius, gear):
    """The gear's unit grid coordinates ``(x, y)`` (y of the profile coordinate t on tapered
    depth) of a point with the qz parts ``o2``, ``o3`` and the radius R2.

    (The point helpers here read their tables' entries where no branch lies between a
    table's first and last use: numba then prunes the references it takes on them; across
    a branch each point evaluation would take and release one on every array of the tables,
    atomically, which cost as much as the evaluation.)"""
    rho0, rho1, tapered, d0, inv_ia = gear[0], gear[1], gear[5], gear[6], gear[7]
    ib, h0, alpha, beta = gear[8], gear[9], gear[10], gear[11]
    x = o2 + rho0 * radius
    y = o3 + rho1 * radius
    if tapered:
        d = x * inv_ia + d0
        y = (y + ib * (h0 - d * alpha)) / (1.0 + d * beta) - ib * h0
    return x, y


@compiled(inline=True)
def _gear_gap(o0, o1, o2, o3, theta, turn, sense, offset, gear):
    """Angular clearance of a pinion point with linear outputs ``o0..o3`` (``ContactEngine``'s
    qx, qy and the qz parts of the gear's unit coordinates; ``theta`` = atan2(o1, o0)) on a
    row: ``(delta, valid, R2)``. ``gear``: rho coefficients, limits, columns, taper (flag and
    constants), coefficients, valid cells."""
    radius = math.sqrt(o0 * o0 + o1 * o1)
    x, y = _gear_unit(o2, o3, radius, gear)
    a = _corner(x, gear[2])
    b = _corner(y, gear[3])
    cell = int(a * gear[4] + b) + offset
    u = x - a
    v = y - b
    valid = gear[13][cell] & (u >= 0.0) & (u <= 1.0) & (v >= 0.0) & (v <= 1.0)
    gap = _hermite(gear[12], cell, u, v) - theta
    gap += turn
    gap -= np.rint(gap * _TO_TURNS) * _TURN
    return gap * sense, valid, radius


# Cephes' atan (S. L. Moshier): the rational approximation on [0, 0.66] after reduction by
# tan(3 pi / 8) and tan(pi / 8); measured within 1 ulp of numpy's arctan2, at two thirds of
# libm's cost
_ATAN_P = (-8.750608600031904122785e-1, -1.615753718733365076637e1, -7.500855792314704667340e1)
_ATAN_P += (-1.228866684490136173410e2, -6.485021904942025371773e1)
_ATAN_Q = (2.485846490142306297962e1, 1.650270098316988542046e2, 4.328810604912902668951e2)
_ATAN_Q += (4.853903996359136964868e2, 1.945506571482613964425e2)
_MOREBITS = 6.123233995736765886130e-17  # pi / 2 - its double


@compiled(inline=True)
def _atan2_lanes(y, x):
    """atan2(y, x) for the node fields where x != 0 and both are finite (elsewhere libm's
    ``math.atan2``): Cephes' atan of y / x, then the quadrant, without a branch (the three
    reductions selected, -(1 / a) as (-1) / a and a as a / 1: the same values), so that the
    nodes' first pass vectorises."""
    a = y / x
    neg = a < 0.0
    a = -a if neg else a
    big = a > 2.41421356237309504880
    small = a <= 0.66
    a = (-1.0 if big else (a if small else a - 1.0)) / (a if big else (1.0 if small else a + 1.0))
    base = 0.5 * math.pi if big else (0.0 if small else 0.25 * math.pi)
    more = _MOREBITS if big else (0.0 if small else 0.5 * _MOREBITS)
    z = a * a
    p = (((_ATAN_P[0] * z + _ATAN_P[1]) * z + _ATAN_P[2]) * z + _ATAN_P[3]) * z + _ATAN_P[4]
    q = ((((z + _ATAN_Q[0]) * z + _ATAN_Q[1]) * z + _ATAN_Q[2]) * z + _ATAN_Q[3]) * z + _ATAN_Q[4]
    t = base + (a * (z * p / q) + a + more)
    t = -t if neg else t
    turned = t + math.pi if y >= 0.0 else t - math.pi
    return t if x > 0.0 else turned


@compiled
def node_fields(rows, side, count, index, xy, z, nxy, nz, gear, out):
    """Node fields of the first n rows r (``rows`` as :func:`clearance_at`'s, ``side``: each
    row's field; n = ``out.shape[1]``) on the generated nodes of each row's side:
    ``count[k]`` nodes, grid indices ``index[k]``, coordinates ``xy`` (``(2, K, m)``), z
    terms ``z`` (``(4, K, m)``), normals' terms ``nxy``, ``nz`` (``(2, K, m)``); the nodes'
    polar angles in the gear frame by :func:`_atan2_lanes`.
    Writes the clearance (+inf off the mask or off the gear flank), the normal factor and R2
    (0 off the mask) into ``out`` (``(3, n, nodes)``).

    Row by row in passes over the nodes, each its own compiled loop: :func:`_node_lanes`
    (no table look-up, no scattered store: vectorised), :func:`_node_cells` (the gear cells,
    the nodes facing the gear flank gathered), :func:`_node_angles` (their polar angles,
    vectorised) and :func:`_node_gaps` (their clearance)."""
    kx, ky, turn, sense, offset, _ = rows
    lim0, lim1, n_cols, coef, ok = gear[2], gear[3], gear[4], gear[12], gear[13]
    n = out.shape[1]
    size = xy.shape[2]
    # per node: the linear outputs o0, o1, the gear's unit coordinates, the normal factor and
    # R2; then per node facing the gear flank: (u, v), o0, o1, the polar angle, the gear cell
    # and the grid index
    lanes = np.empty((6, size))
    faced = np.empty((5, size))
    cells = np.empty((2, size), np.intp)
    for r in range(n):
        k = side[r]
        c = count[k]
        clearance, factor, radii = out[0, r], out[1, r], out[2, r]
        clearance[:] = math.inf
        factor[:] = 0.0
        radii[:] = 0.0
        _node_lanes(c, r, k, kx, ky, xy, z, nxy, nz, gear, lanes)
        m = _node_cells(
            c, index[k], lanes, lim0, lim1, n_cols, offset[r], ok, factor, radii, faced, cells
        )
        _node_angles(m, faced)
        _node_gaps(m, coef, faced, cells, turn[r], sense[r], clearance)


@compiled
def _node_lanes(c, r, k, kx, ky, xy, z, nxy, nz, gear, lanes):
    """:func:`node_fields`' first pass on row ``r`` over the ``c`` nodes of side ``k``:
    ``lanes`` = o0, o1, the gear's unit coordinates (x, y), the normal factor and R2 (as
    :func:`_gear_unit`; the taper applied in a loop of its own)."""
    rho0, rho1, tapered, d0, inv_ia = gear[0], gear[1], gear[5], gear[6], gear[7]
    ib, h0, alpha, beta = gear[8], gear[9], gear[10], gear[11]
    x, y, nx, ny = xy[0, k], xy[1, k], nxy[0, k], nxy[1, k]
    z0, z1, z2, z3, nz0, nz1 = z[0, k], z[1, k], z[2, k], z[3, k], nz[0, k], nz[1, k]
    kx0, kx1, kx2, kx3 = kx[0, r], kx[1, r], kx[2, r], kx[3, r]
    ky0, ky1, ky2, ky3 = ky[0, r], ky[1, r], ky[2, r], ky[3, r]
    o0s, o1s, gxs, gys = lanes[0], lanes[1], lanes[2], lanes[3]
    factors, radii = lanes[4], lanes[5]
    for j in range(c):
        o0 = kx0 * x[j] + ky0 * y[j] + z0[j]
        o1 = kx1 * x[j] + ky1 * y[j] + z1[j]
        o2 = kx2 * x[j] + ky2 * y[j] + z2[j]
        o3 = kx3 * x[j] + ky3 * y[j] + z3[j]
        radius = math.sqrt(o0 * o0 + o1 * o1)
        gxs[j] = o2 + rho0 * radius
        gys[j] = o3 + rho1 * radius
        m0 = kx0 * nx[j] + ky0 * ny[j] + nz0[j]
        m1 = kx1 * nx[j] + ky1 * ny[j] + nz1[j]
        factors[j] = abs(m1 * o0 - m0 * o1)
        radii[j] = radius
        o0s[j], o1s[j] = o0, o1
    if tapered:
        for j in range(c):
            d = gxs[j] * inv_ia + d0
            gys[j] = (gys[j] + ib * (h0 - d * alpha)) / (1.0 + d * beta) - ib * h0


@compiled
def _node_cells(c, g, lanes, lim0, lim1, n_cols, shift, ok, factor, radius, faced, cells):
    """:func:`node_fields`' second pass: the normal factor and R2 at the grid nodes ``g``
    (``factor``, ``radius``), the gear cells and of the nodes facing the gear flank (as
    :func:`_gear_gap`, whose clearance is kept only there) their ``(u, v)``, o0, o1, cell
    and grid index gathered into ``faced`` and ``cells``; returns how many."""
    o0s, o1s, gxs, gys = lanes[0], lanes[1], lanes[2], lanes[3]
    factors, radii = lanes[4], lanes[5]
    m = 0
    for j in range(c):
        factor[g[j]], radius[g[j]] = factors[j], radii[j]
        a = _corner(gxs[j], lim0)
        b = _corner(gys[j], lim1)
        cell = int(a * n_cols + b) + shift
        u = gxs[j] - a
        v = gys[j] - b
        if ok[cell] & (u >= 0.0) & (u <= 1.0) & (v >= 0.0) & (v <= 1.0):  # (one branch)
            faced[0, m], faced[1, m], faced[2, m], faced[3, m] = u, v, o0s[j], o1s[j]
            cells[0, m], cells[1, m] = cell, g[j]
            m += 1
    return m


@compiled
def _node_angles(m, faced):
    """:func:`node_fields`' third pass: the polar angles of the ``m`` nodes gathered by
    :func:`_node_cells` (:func:`_atan2_lanes`; libm's where it does not hold)."""
    o0, o1, theta = faced[2], faced[3], faced[4]
    for i in range(m):
        theta[i] = _atan2_lanes(o1[i], o0[i])
    for i in range(m):
        if o0[i] == 0.0 or not (math.isfinite(o0[i]) and math.isfinite(o1[i])):
            theta[i] = math.atan2(o1[i], o0[i])


@compiled
def _node_gaps(m, coef, faced, cells, turn, sense, clearance):
    """:func:`node_fields`' last pass: the clearance of the ``m`` nodes gathered by
    :func:`_node_cells` (as :func:`_gear_gap`)."""
    u, v, theta = faced[0], faced[1], faced[4]
    cell, at = cells[0], cells[1]
    for i in range(m):
        gap = _hermite(coef, cell[i], u[i], v[i]) - theta[i]
        gap += turn
        gap -= np.rint(gap * _TO_TURNS) * _TURN
        clearance[at[i]] = gap * sense


@compiled
def point_fields(rows, points, normals, lin_z, const, gear, out, valid):
    """The clearance of pinion points given in the member frame, one row per leading index:
    ``points`` and ``normals`` ``(n, m, 3)`` (unturned pinion; row r's m points), ``rows`` as
    :func:`clearance_at`'s, ``lin_z`` and ``const`` the z coefficients and constants of the
    four linear outputs. Writes the clearance (the smooth extension beyond the flanks), the
    normal factor, R2 and the gear's unit grid coordinates ``(x, y)`` into ``out``
    (``(5, n, m)``) and whether the point faces the gear's generated cells into ``valid``: as
    :meth:`gearopt.contact.engine.ContactEngine.gap`, point by point."""
    kx, ky, turn, sense, offset, _ = rows
    n, m = valid.shape
    for r in range(n):
        for p in range(m):
            x, y, z = points[r, p, 0], points[r, p, 1], points[r, p, 2]
            o0 = kx[0, r] * x + ky[0, r] * y + (lin_z[0] * z + const[0])
            o1 = kx[1, r] * x + ky[1, r] * y + (lin_z[1] * z + const[1])
            o2 = kx[2, r] * x + ky[2, r] * y + (lin_z[2] * z + const[2])
            o3 = kx[3, r] * x + ky[3, r] * y + (lin_z[3] * z + const[3])
            theta = math.atan2(o1, o0)
            gap, on, radius = _gear_gap(o0, o1, o2, o3, theta, turn[r], sense[r], offset[r], gear)
            nx, ny, nz = normals[r, p, 0], normals[r, p, 1], normals[r, p, 2]
            m0 = kx[0, r] * nx + ky[0, r] * ny + lin_z[0] * nz
            m1 = kx[1, r] * nx + ky[1, r] * ny + lin_z[1] * nz
            gx, gy = _gear_unit(o2, o3, radius, gear)
            out[0, r, p] = gap
            out[1, r, p] = abs(m1 * o0 - m0 * o1)
            out[2, r, p] = radius
            out[3, r, p] = gx
            out[4, r, p] = gy
            valid[r, p] = on


@compiled
def _evaluate(rows, r, s, t, pinion, gear, cells):
    """:func:`_point_in` compiled once, called: the tangency's few evaluations outside its
    stencil (a copy inlined at each call site would multiply the compile time)."""
    return _point_in(rows, r, s, t, pinion, gear, cells)


@compiled(inline=True)
def _point_in(rows, r, s, t, pinion, gear, cells):
    """Clearance of the pinion point at grid coordinates ``(s, t)`` on row ``r`` (as
    :func:`clearance_at`): ``(delta, valid)``, valid on the gear flank and in the pinion's
    ``cells`` (``(c0, c1)`` per cell of the pinion tables, ``pinion[14]``: the point is in
    where ``v >= c0 + c1 u``, :func:`gearopt.contact.engine.node_tables`)."""
    return gap_of(rows, r, pinion_at(s, t, pinion, rows[5][r]), gear, cells)


@compiled(inline=True)
def pinion_at(s, t, pinion, offset):
    """The row-independent part of :func:`_point_in` at grid coordinates ``(s, t)`` of the
    pinion tables ``offset`` cells in: ``(cell, u, v, px, py, l1, l2, l3, l4)``, the cell and
    the unit coordinates in it, the point's x and y in the pinion frame and the z terms of the
    four linear outputs.

    Theta is the cell's own polynomial, or where the band ``pinion[15]`` says so its fine
    cells at the generated boundary (:func:`gearopt.contact.boundary.boundary_cells`, whose
    ``band_theta`` is this in numpy), both in one table ``pinion[13]`` (the fine cells after
    the flank's, the band's first column pointing there). Straight-line, as
    :func:`_gear_unit`."""
    x = (s - pinion[0]) * pinion[2]
    y = (t - pinion[1]) * pinion[3]
    a = _corner(x, pinion[4])
    b = _corner(y, pinion[5])
    cell = int(a * pinion[6] + b) + offset
    u = x - a
    v = y - b
    band = pinion[15]
    first = band[cell, 0]
    level = (band[cell, 1] + v) * band[cell, 2]
    row = np.floor(level)  # (as float(math.floor(level)), without the two conversions)
    row = min(row if row > 0.0 else 0.0, band[cell, 3] - 1.0)
    fine = first >= 0.0
    theta = _hermite(pinion[13], int(first + row) if fine else cell, u, level - row if fine else v)
    tapered = t + (s - pinion[8]) * (pinion[9] + pinion[10] * t)
    h = tapered if pinion[7] else t
    lin, const = pinion[11], pinion[12]
    big_r = lin[0, 0] * s + lin[0, 1] * h + const[0]
    px = big_r * math.cos(theta)
    py = big_r * math.sin(theta)
    return (
        cell,
        u,
        v,
        px,
        py,
        lin[1, 0] * s + lin[1, 1] * h + const[1],
        lin[2, 0] * s + lin[2, 1] * h + const[2],
        lin[3, 0] * s + lin[3, 1] * h + const[3],
        lin[4, 0] * s + lin[4, 1] * h + const[4],
    )


@compiled(inline=True)
def gap_of(rows, r, point, gear, cells):
    """:func:`_point_in` on row ``r`` of the pinion point ``point`` (:func:`pinion_at`)."""
    cell, u, v, px, py, l1, l2, l3, l4 = point
    kx, ky = rows[0], rows[1]
    o0 = kx[0, r] * px + ky[0, r] * py + l1
    o1 = kx[1, r] * px + ky[1, r] * py + l2
    o2 = kx[2, r] * px + ky[2, r] * py + l3
    o3 = kx[3, r] * px + ky[3, r] * py + l4
    theta = math.atan2(o1, o0)
    gap, on, _ = _gear_gap(o0, o1, o2, o3, theta, rows[2][r], rows[3][r], rows[4][r], gear)
    inside = v >= cells[cell, 0] + cells[cell, 1] * u  # the generated boundary (node_tables)
    return gap, on & inside & (0.0 <= u) & (u <= 1.0) & (0.0 <= v) & (v <= 1.0)


@compiled
def clearance_at(rows, sh, pinion, gear, delta, valid):
    """Clearance at pinion grid coordinates ``sh`` (``(2, n, m)``: m points on each of n rows)
    by the pinion's local interpolant; writes ``delta`` (the smooth extension beyond the
    flanks) and ``valid`` (on both flanks, in a refinable pinion cell), each ``(n, m)``.
    ``rows``: ``kx``, ``ky`` (``(4, n)``), ``turn``, ``sense``, the gear's and the pinion's
    cell offsets (``(n,)``). ``pinion``: unit-coordinate origin and scale, limits, columns,
    taper (flag, pivot, alpha, beta), the map to R1 and the z terms (``(5, 2)``) with its
    constants, the coefficients of its cells followed by those of the fine cells at the
    generated boundary (:func:`gearopt.contact.boundary.boundary_cells`), the refinable
    cells and the fine cells' table per cell (its first column indexing the coefficients)."""
    n, m = delta.shape
    for r in range(n):
        for p in range(m):
            delta[r, p], valid[r, p] = _point_in(
                rows, r, sh[0, r, p], sh[1, r, p], pinion, gear, pinion[14]
            )


@compiled(inline=True)
def _pseudo_newton(g0, g1, hss, hsh, hhh, free):
    """One row of :func:`gearopt.contact._pseudo_newton`: ``(step_s, step_h, curved_s,
    curved_h)``."""
    mean = (hss + hhh) * 0.5
    half = (hss - hhh) * 0.5
    root = math.sqrt(half * half + hsh * hsh)
    scale = max(abs(hss) + abs(hhh), 1e-300)
    lam0 = mean + root
    lam1 = mean - root
    tiny = 1e-6 * scale
    if lam1 > tiny:
        det = hss * hhh - hsh * hsh
        a = (hsh * g1 - hhh * g0) / det
        b = (hsh * g0 - hss * g1) / det
        if a * a + b * b <= free * free:
            return a, b, a, b
    v0, v1 = hsh, lam0 - hss
    if abs(hsh) <= 1e-12 * scale:
        v0, v1 = (1.0, 0.0) if hss >= hhh else (0.0, 1.0)
    norm = math.hypot(v0, v1)
    if not norm > 0.0:
        norm = 1.0
    v0 /= norm
    v1 /= norm
    gnorm = max(math.hypot(g0, g1), 1e-300)
    step0 = step1 = curved0 = curved1 = 0.0
    for i in range(2):
        e0, e1, lam = (v0, v1, lam0) if i == 0 else (-v1, v0, lam1)
        slope = e0 * g0 + e1 * g1
        if lam > tiny:
            along = min(max(-slope / lam, -free), free)
            curved0 += along * e0
            curved1 += along * e1
        elif abs(slope) > 1e-9 * gnorm:
            along = -free if slope > 0.0 else free
        else:
            along = 0.0
        step0 += along * e0
        step1 += along * e1
    return (
        min(max(step0, -2.0), 2.0),
        min(max(step1, -2.0), 2.0),
        min(max(curved0, -2.0), 2.0),
        min(max(curved1, -2.0), 2.0),
    )


@compiled(inline=True)
def _around(i, s, t, qs, qt):
    """Point ``i`` of the refinement's stencil around ``(s, t)``, steps ``(qs, qt)``: centre,
    +s, -s, +t, -t, then the diagonals (++ +- -+ --). (The callers evaluate the stencil in
    their own loops: a call taking the tables would take and release a reference on each of
    their arrays, a fifth of the nine evaluations' cost.)"""
    return s + _STENCIL_S[i] * qs, t + _STENCIL_T[i] * qt


@compiled
def refine(
    rows,
    which,
    s,
    t,
    best,
    caps,
    group,
    tol,
    cell,
    pinion,
    gear,
    edge,
):
    """:meth:`gearopt.contact.engine.ContactEngine.refine` start by start: constrained Newton
    steps from ``(s, t)`` (updated in place with ``best``, the start values, NaN: the
    interpolated value there; and ``edge``) on row ``which[p]`` of ``rows``, at most ``caps[g]``
    steps for the starts of group g, a group stopping when none of its starts moved more than a
    thousandth of a cell."""
    n = s.shape[0]
    fractions = np.array([1.0, 0.5, 0.25, 0.125, 0.0625])
    f = np.empty((n, 9))
    active = np.ones(n, np.bool_)
    moving = np.zeros(n, np.bool_)
    taken = np.zeros(n, np.bool_)
    # a start whose step was refused has the same step refused at every later iteration (its
    # point, stencil and best stay as they were): it is not evaluated again
    held = np.zeros(n, np.bool_)
    qs, qt = 0.25 * cell[0], 0.25 * cell[1]
    for r in range(n):
        ok = False
        for i in range(9):
            ps, pt = _around(i, s[r], t[r], qs, qt)
            f[r, i], on = _point_in(rows, which[r], ps, pt, pinion, gear, pinion[14])
            ok = on if i == 0 else ok
        if np.isnan(best[r]):
            best[r] = f[r, 0] if ok else math.inf
    small = 1e-3 * min(cell[0], cell[1])
    groups = caps.shape[0]
    for it in range(caps.max()):
        for r in range(n):
            moving[r] = taken[r] = False
            if not active[r] or held[r]:
                continue
            fr = f[r]
            g0 = 2.0 * (fr[1] - fr[2])
            g1 = 2.0 * (fr[3] - fr[4])
            hss = 16.0 * (fr[1] + fr[2]) - 32.0 * fr[0]
            hsh = 4.0 * (fr[5] + fr[8]) - 4.0 * (fr[6] + fr[7])
            hhh = 16.0 * (fr[3] + fr[4]) - 32.0 * fr[0]
            st0, st1, c0, c1 = _pseudo_newton(g0, g1, hss, hsh, hhh, 2.0)
            # the Newton part's predicted fall (a valley's slope along itself is not edge)
            fall = -(
                g0 * c0
                + g1 * c1
                + 0.5 * (hss * c0 * c0 + 2.0 * hsh * c0 * c1)
                + 0.5 * hhh * c1 * c1
            )
            # (the Newton part is the whole step unless a valley or a cap is in it: then the
            # full step's point tells whether its end is on the flanks)
            newton = st0 == c0 and st1 == c1
            # the step cut back by halvings to the first valid point not above the best
            # (i = -1: the Newton part's end, where it is not the whole step); one
            # evaluation site, inlined
            limit = best[r] + 1e-13 * abs(best[r])
            for i in range(0 if newton else -1, fractions.size):
                if i < 0:
                    ns, nt = s[r] + c0 * cell[0], t[r] + c1 * cell[1]
                else:
                    ns = s[r] + fractions[i] * (st0 * cell[0])
                    nt = t[r] + fractions[i] * (st1 * cell[1])
                value, on = _point_in(rows, which[r], ns, nt, pinion, gear, pinion[14])
                if i < 0 or (i == 0 and newton):
                    edge[r] = (not on) and fall > tol[r]
                    if i < 0:
                        continue
                if on and value <= limit:
                    moving[r] = abs(ns - s[r]) + abs(nt - t[r]) > small
                    taken[r] = True
                    s[r], t[r], best[r] = ns, nt, value
                    break
            held[r] = not taken[r]
        still = False
        for g in range(groups):
            stop = it == caps[g] - 1
            if not stop:
                stop = True
                for r in range(n):
                    if group[r] == g and moving[r]:
                        stop = False
                        break
            if stop:
                for r in range(n):
                    if group[r] == g:
                        active[r] = False
        for r in range(n):
            still = still or active[r]
        if not still:
            break
        for r in range(n):
            if active[r] and taken[r]:  # (its centre is the point just taken)
                f[r, 0] = best[r]
                for i in range(1, 9):
                    ps, pt = _around(i, s[r], t[r], qs, qt)
                    f[r, i], _ = _point_in(rows, which[r], ps, pt, pinion, gear, pinion[14])


@compiled(inline=True)
def _row_at(maker, phi, rows):
    """The one-row constants ``rows`` (as :func:`clearance_at`'s, filled in place) at pinion
    angle ``phi``, gear angle 0: ``maker`` = (the rotation table ``(8, 2)``, the side's gear
    turn at phi = 0, the ratio, the gear's sense, the gear's and the pinion's cell offsets)."""
    rotation, turn0, ratio, sense, offset, pinion_offset = maker
    kx, ky, turn, row_sense, row_offset, row_pinion_offset = rows
    c, s = math.cos(phi), math.sin(phi)
    for i in range(4):
        kx[i, 0] = rotation[i, 0] * c + rotation[i, 1] * s
        ky[i, 0] = rotation[i + 4, 0] * c + rotation[i + 4, 1] * s
    turn[0] = turn0 - ratio * phi
    row_sense[0] = sense
    row_offset[0] = offset
    row_pinion_offset[0] = pinion_offset


@compiled
def tangency(rows, s, t, cell, pinion, gear, generated, f):
    """The tangency point of the flanks on a one-row ``rows``: the unconstrained minimum of
    the clearance over the pinion flank's smooth extension (where the gradient of the
    clearance vanishes, the gear flank turned by it touches the pinion flank with a common
    normal: Litvin's tangency), from ``(s, t)`` by the refinement's steps (Newton's on the
    positive curvatures, a descent along the others, at most two cells, cut back until the
    clearance does not rise) on its stencil, the differences a sixteenth of a cell wide (their
    error, a sixteenth of the refinement's, puts the point within about 1e-3 mm of the
    tangency equations' solution on the same interpolants). Returns ``(converged, s, t,
    inside)``, inside on the gear flank and in the pinion's ``generated`` cells; not converged
    after 32 steps or where the point found is not a minimum with both curvatures positive (a
    line contact: the point is not unique)."""
    q = 1.0 / 16.0
    for _ in range(32):
        for i in range(9):
            ps, pt = _around(i, s, t, q * cell[0], q * cell[1])
            f[i], _ = _point_in(rows, 0, ps, pt, pinion, gear, pinion[14])
        g0 = (f[1] - f[2]) / (2.0 * q)
        g1 = (f[3] - f[4]) / (2.0 * q)
        hss = (f[1] + f[2] - 2.0 * f[0]) / (q * q)
        hsh = (f[5] + f[8] - f[6] - f[7]) / (4.0 * q * q)
        hhh = (f[3] + f[4] - 2.0 * f[0]) / (q * q)
        d0, d1, c0, c1 = _pseudo_newton(g0, g1, hss, hsh, hhh, 2.0)
        norm = math.sqrt(d0 * d0 + d1 * d1)
        done = norm <= 1e-6
        if not done and norm <= 0.1 and d0 == c0 and d1 == c1:
            # a short Newton step on both positive curvatures is taken whole: so near the
            # minimum the differences' error, not the step, decides whether the clearance falls
            s, t = s + d0 * cell[0], t + d1 * cell[1]
        elif not done:
            done = True  # unless a (cut-back) step does not raise the clearance (beyond the
            # rounding of the differences, which near the minimum is the clearance's change)
            limit = f[0] + 1e-10 * abs(f[0])
            fraction = 1.0
            for _ in range(6):
                ns, nt = s + fraction * (d0 * cell[0]), t + fraction * (d1 * cell[1])
                value, _ = _evaluate(rows, 0, ns, nt, pinion, gear, pinion[14])
                if value <= limit:
                    s, t, done = ns, nt, fraction * math.sqrt(d0 * d0 + d1 * d1) <= 1e-6
                    break
                fraction *= 0.5
        if done:
            half = 0.5 * (hss - hhh)
            least = 0.5 * (hss + hhh) - math.sqrt(half * half + hsh * hsh)
            if not least > 1e-5 * (abs(hss) + abs(hhh)):
                return False, s, t, False
            _, inside = _evaluate(rows, 0, s, t, pinion, gear, generated)
            return True, s, t, inside
    return False, s, t, False


@compiled
def interval_end(maker, phi, s, t, step, steps, tol, cell, pinion, gear, generated):
    """Where the tangency point (:func:`tangency`) leaves the flanks, near pinion angle
    ``phi`` where the contact point is near ``(s, t)``: stepping by ``step`` (signed, toward
    the outside) while the point stays inside (or back while it does not), up to ``steps``
    steps, each solve started from the last point found (a step whose solve fails is halved,
    down to a sixteenth), then bisection to ``tol`` (rad). Returns ``(found, phi_inside,
    phi_outside, s, t)`` with the tangency point at ``phi_inside``; not found where a solve
    fails (a line contact) or no bracket is found within the steps."""
    rows = (
        np.empty((4, 1)),
        np.empty((4, 1)),
        np.empty(1),
        np.empty(1),
        np.empty(1, np.intp),
        np.empty(1, np.intp),
    )
    f = np.empty(9)
    _row_at(maker, phi, rows)
    ok, s, t, inside = tangency(rows, s, t, cell, pinion, gear, generated, f)
    if not ok:
        return False, phi, phi, s, t
    # march from the start to the first angle on the other side (inside -> outside, or back)
    direction = 1.0 if inside else -1.0
    start_inside = inside
    last = phi
    h = step
    found = False
    k = 0
    while k < steps:
        u = last + direction * h
        _row_at(maker, u, rows)
        ok, s1, t1, inside = tangency(rows, s, t, cell, pinion, gear, generated, f)
        if not ok:
            if abs(h) > abs(step) / 16.0:
                h *= 0.5  # a nearer seed
                continue
            return False, phi, phi, s, t
        if inside != start_inside:
            found = True
            break
        last, s, t = u, s1, t1
        h = step
        k += 1
    if not found:
        return False, phi, phi, s, t
    if start_inside:
        a, b = last, u
    else:
        a, b, s, t = u, last, s1, t1
    while abs(b - a) > tol:
        m = 0.5 * (a + b)
        _row_at(maker, m, rows)
        ok, s1, t1, inside = tangency(rows, s, t, cell, pinion, gear, generated, f)
        if not ok:
            return False, phi, phi, s, t
        if inside:
            a, s, t = m, s1, t1
        else:
            b = m
    return True, a, b, s, t
