"""Compiled load distribution (numba): the active-set method of :mod:`gearopt.loaded.lcp` on
contact patches whose compliance columns the kernel computes itself.

The compliance ``C`` of the patches is block-diagonal over the tooth pairs (``starts``: the
first patch of each pair, and the end): within a pair, the half-spaces' local compliance
(Love's rectangles, :func:`gearopt.loaded.kernels.halfspace_columns`) plus both teeth's
influence numbers (:func:`gearopt.loaded.kernels.influence_columns`, each member's table and
its stencils at the patches). Columns are computed when the method first needs them and kept
in ``rows`` (row ``slot[j]`` holds column ``j``), which the caller keeps across the torques of a
sweep. The method is :func:`gearopt.loaded.lcp.solve_load_columns`'s, step for step, for a
positive definite ``C``; where a block ``C_PP`` is singular (a Cholesky pivot below
``singular_rtol`` of its largest diagonal entry) the kernel stops with status 1 and the caller
solves with the Python method (its null-space branch); status 2: no convergence within ``cap``
outer iterations.

As every kernel: plain Python where numba is missing or ``GEAROPT_JIT=0``
(:mod:`gearopt.jit`).
"""

from __future__ import annotations

import numpy as np

from gearopt.jit import compiled
from gearopt.loaded.kernels import halfspace_columns, influence_columns

__all__ = ["fetch", "solve_patches"]

#: the block addition takes at most ``max(_BLOCK_LEAST, |P| / 2)`` patches at a time
_BLOCK_LEAST = 32


@compiled
def fetch(idx, starts, x, y, a, b, factor, far, members, rows, slot, count):
    """Columns ``idx`` into ``rows`` where not held; returns ``(rows, count)`` (``rows``
    reallocated twice as large when full)."""
    n = slot.size
    missing = idx[slot[idx] < 0]
    m = missing.size
    if m == 0:
        return rows, count
    if count + m > rows.shape[0]:
        grown = np.empty((min(n, max(2 * rows.shape[0], count + m)), n))
        grown[:count] = rows[:count]
        rows = grown
    block = np.searchsorted(starts, missing, side="right") - 1
    for blk in np.unique(block):
        lo, hi = starts[blk], starts[blk + 1]
        mine = missing[block == blk]
        local = mine - lo
        part = np.empty((mine.size, hi - lo))
        halfspace_columns(x[lo:hi], y[lo:hi], a[lo:hi], b[lo:hi], local, factor, far, part)
        for table, points, weights in members:
            influence_columns(points[lo:hi], weights[lo:hi], local, table, part)
        for k in range(mine.size):
            row = rows[count]
            row[:] = 0.0
            row[lo:hi] = part[k]
            slot[mine[k]] = count
            count += 1
    return rows, count


@compiled
def _on_support(support, s, r, t, rows, slot, singular_rtol):
    """``(ok, z, theta)``: the subproblem on the support (``C_PP z - r theta = -s``, ``r^T z =
    t``) by Cholesky and the Schur complement; ``ok`` False where ``C_PP`` is singular."""
    k = support.size
    c = np.empty((k, k))
    for j in range(k):
        column = rows[slot[support[j]]]
        for i in range(k):
            c[i, j] = column[support[i]]
    c = 0.5 * (c + c.T)
    top = 0.0
    for i in range(k):
        top = max(top, c[i, i])
    z = np.zeros(s.size)
    try:
        low = np.linalg.cholesky(c)
    except Exception:  # noqa: BLE001 - numba raises LinAlgError as a plain exception
        return False, z, 0.0
    pivot = np.inf
    for i in range(k):
        pivot = min(pivot, low[i, i])
    if not pivot * pivot > singular_rtol * top:
        return False, z, 0.0
    rhs = np.empty((k, 2))
    for i in range(k):
        rhs[i, 0] = r[support[i]]
        rhs[i, 1] = s[support[i]]
    for i in range(k):  # forward: L y = rhs
        for col in range(2):
            acc = rhs[i, col]
            for j in range(i):
                acc -= low[i, j] * rhs[j, col]
            rhs[i, col] = acc / low[i, i]
    for i in range(k - 1, -1, -1):  # back: L^T x = y
        for col in range(2):
            acc = rhs[i, col]
            for j in range(i + 1, k):
                acc -= low[j, i] * rhs[j, col]
            rhs[i, col] = acc / low[i, i]
    rr = 0.0
    rs = 0.0
    for i in range(k):
        rr += r[support[i]] * rhs[i, 0]
        rs += r[support[i]] * rhs[i, 1]
    theta = (t + rs) / rr
    for i in range(k):
        z[support[i]] = theta * rhs[i, 0] - rhs[i, 1]
    return True, z, theta


@compiled
def solve_patches(
    s, r, t, start, tol, cap, singular_rtol, starts, x, y, a, b, factor, far, members,
    rows, slot, count,
):  # fmt: skip
    """The load distribution (module docstring) from ``start`` (feasible forces, ``r^T F =
    t``; all zero: the patch that closes first). Returns ``(status, forces, theta, gaps,
    active, iterations, rows, count)``."""
    n = s.size
    forces = np.zeros(n)
    in_p = np.zeros(n, dtype=np.bool_)
    gaps = np.zeros(n)
    theta = 0.0
    iterations = 0
    if start.any():
        forces[:] = start
        in_p[:] = start > 0.0
        while True:
            support = np.flatnonzero(in_p)
            rows, count = fetch(
                support, starts, x, y, a, b, factor, far, members, rows, slot, count
            )
            ok, z, z_theta = _on_support(support, s, r, t, rows, slot, singular_rtol)
            if not ok:
                return 1, forces, theta, gaps, in_p, iterations, rows, count
            if (z[support] > 0.0).all():
                break
            forces = np.where(in_p & (z > 0.0), z, 0.0)
            forces *= t / np.sum(r * forces)
            in_p = forces > 0.0
    else:
        first = np.argmin(s / r)
        in_p[first] = True
        forces[first] = t / r[first]
        support = np.flatnonzero(in_p)
        rows, count = fetch(support, starts, x, y, a, b, factor, far, members, rows, slot, count)
        ok, z, z_theta = _on_support(support, s, r, t, rows, slot, singular_rtol)
        if not ok:
            return 1, forces, theta, gaps, in_p, iterations, rows, count
    stuck = np.zeros(n, dtype=np.bool_)
    while True:
        # Lawson-Hanson's inner loop: step towards z as far as the forces stay >= 0
        while True:
            support = np.flatnonzero(in_p)
            neg = support[z[support] <= 0.0]
            if neg.size == 0:
                forces, theta = z, z_theta
                break
            step = z - forces
            ratio = forces[neg] / -step[neg]
            alpha = ratio.min()
            forces = forces + alpha * step
            forces[neg[ratio <= alpha]] = 0.0
            in_p = in_p & (forces > 0.0)
            forces[~in_p] = 0.0
            support = np.flatnonzero(in_p)
            ok, z, z_theta = _on_support(support, s, r, t, rows, slot, singular_rtol)
            if not ok:
                return 1, forces, theta, gaps, in_p, iterations, rows, count
        support = np.flatnonzero(in_p)
        gaps = s - r * theta
        for j in support:
            gaps += forces[j] * rows[slot[j]]
        candidates = ~in_p & ~stuck & (gaps < -tol)
        if not candidates.any():
            return 0, forces, theta, gaps, in_p, iterations, rows, count
        if iterations >= cap:
            return 2, forces, theta, gaps, in_p, iterations, rows, count
        iterations += 1
        new = np.flatnonzero(candidates)
        single = new[np.argmin(gaps[new]) : np.argmin(gaps[new]) + 1]
        limit = max(_BLOCK_LEAST, int(0.5 * support.size))
        if new.size > limit:
            new = np.sort(new[np.argsort(gaps[new], kind="mergesort")[:limit]])
        while True:  # block addition: the new patches that would carry tension out again
            joined = in_p.copy()
            joined[new] = True
            union = np.flatnonzero(joined)
            rows, count = fetch(union, starts, x, y, a, b, factor, far, members, rows, slot, count)
            ok, z, z_theta = _on_support(union, s, r, t, rows, slot, singular_rtol)
            if not ok:
                return 1, forces, theta, gaps, in_p, iterations, rows, count
            keep = z[new] > 0.0
            if keep.all() or (new.size == 1 and not keep.any()):
                break
            new = new[keep] if keep.any() else single
        if z[new[0]] <= 0.0:  # a single patch, unloaded: round-off at the tolerance
            stuck[new[0]] = True
            z, z_theta = forces.copy(), theta  # the inner loop keeps the solution
            continue
        in_p[new] = True
