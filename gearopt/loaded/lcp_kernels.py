"""Compiled load distribution (numba): the active-set method of :mod:`gearopt.loaded.lcp` on
compliance columns held in a cache.

The method is :func:`gearopt.loaded.lcp.solve_load_columns`'s, step for step, for a positive
definite ``C``, on the columns held in ``rows`` (row ``slot[j]`` holds column ``j``; ``slot[j] <
0``: not held). Where it needs columns the cache does not hold it stops with status 3, the
columns in ``need`` and its feasible forces (``>= 0``, ``r^T F = t``) as the start of the next
call once the caller has computed them (the columns are the caller's: no kernel is linked
into this one, which keeps its compilation short). Status 1: a block ``C_PP`` is singular (a
Cholesky pivot below ``singular_rtol`` of its largest diagonal entry), the caller solves with
the Python method (its null-space branch); status 2: no convergence within ``cap`` outer
iterations; status 0: solved.

As every kernel: plain Python where numba is missing or ``GEAROPT_JIT=0``
(:mod:`gearopt.jit`).
"""

from __future__ import annotations

import numpy as np

from gearopt.jit import compiled

__all__ = ["solve_patches", "warm"]


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
def _support(mask):
    """The indices where ``mask`` holds, ascending."""
    count = 0
    for i in range(mask.size):
        if mask[i]:
            count += 1
    out = np.empty(count, dtype=np.intp)
    count = 0
    for i in range(mask.size):
        if mask[i]:
            out[count] = i
            count += 1
    return out


@compiled
def _missing(idx, slot):
    """The indices of ``idx`` whose columns are not held."""
    mask = np.zeros(slot.size, dtype=np.bool_)
    for j in idx:
        if slot[j] < 0:
            mask[j] = True
    return _support(mask)


@compiled
def _most_negative(new, gaps, limit):
    """The ``limit`` patches of ``new`` with the least gaps (ties: the lower index), in
    ascending order of index."""
    if new.size <= limit:
        return new
    taken = np.zeros(new.size, dtype=np.bool_)
    for _ in range(limit):
        best = -1
        for k in range(new.size):
            if not taken[k] and (best < 0 or gaps[new[k]] < gaps[new[best]]):
                best = k
        taken[best] = True
    out = np.empty(limit, dtype=np.intp)
    count = 0
    for k in range(new.size):
        if taken[k]:
            out[count] = new[k]
            count += 1
    return out


@compiled
def solve_patches(s, r, t, start, tol, cap, done, singular_rtol, block, rows, slot):
    """The load distribution (module docstring) from ``start`` (feasible forces, ``r^T F =
    t``; all zero: the patch that closes first), ``done`` outer iterations made before; the
    block addition takes at most ``max(block[0], block[1] |P|)`` patches at a time.
    Returns ``(status, forces, theta, gaps, active, iterations, need)``."""
    n = s.size
    forces = start.copy()
    in_p = forces > 0.0
    gaps = np.zeros(n)
    theta = 0.0
    iterations = done
    none = np.zeros(0, dtype=np.intp)
    support = _support(in_p)
    if support.size == 0:  # cold: the patch that closes first
        first = 0
        for i in range(1, n):
            if s[i] / r[i] < s[first] / r[first]:
                first = i
        forces[first] = t / r[first]
        in_p[first] = True
        return 3, forces, theta, gaps, in_p, iterations, np.array([first])
    while True:  # a warm start: its tensile forces dropped at once while there are some
        need = _missing(support, slot)
        if need.size:
            return 3, forces, theta, gaps, in_p, iterations, need
        ok, z, z_theta = _on_support(support, s, r, t, rows, slot, singular_rtol)
        if not ok:
            return 1, forces, theta, gaps, in_p, iterations, none
        tensile = False
        for j in support:
            tensile = tensile or z[j] <= 0.0
        if not tensile:
            break
        moment = 0.0
        for j in support:
            forces[j] = z[j] if z[j] > 0.0 else 0.0
            moment += r[j] * forces[j]
        for j in support:
            forces[j] *= t / moment
            in_p[j] = forces[j] > 0.0
        support = _support(in_p)
    stuck = np.zeros(n, dtype=np.bool_)
    while True:
        # Lawson-Hanson's inner loop: step towards z as far as the forces stay >= 0
        while True:
            alpha = np.inf
            for j in support:
                if z[j] <= 0.0:
                    alpha = min(alpha, forces[j] / (forces[j] - z[j]))
            if alpha == np.inf:
                forces, theta = z, z_theta
                break
            for j in support:
                if z[j] <= 0.0 and forces[j] / (forces[j] - z[j]) <= alpha:
                    forces[j] = 0.0  # (those reaching 0 exactly)
                    in_p[j] = False
                else:
                    forces[j] += alpha * (z[j] - forces[j])
                    if not forces[j] > 0.0:
                        forces[j] = 0.0
                        in_p[j] = False
            support = _support(in_p)
            ok, z, z_theta = _on_support(support, s, r, t, rows, slot, singular_rtol)
            if not ok:
                return 1, forces, theta, gaps, in_p, iterations, none
        for i in range(n):
            gaps[i] = s[i] - r[i] * theta
        for j in support:
            column = rows[slot[j]]
            f = forces[j]
            for i in range(n):
                gaps[i] += f * column[i]
        candidates = np.zeros(n, dtype=np.bool_)
        for i in range(n):
            candidates[i] = not in_p[i] and not stuck[i] and gaps[i] < -tol
        new = _support(candidates)
        if new.size == 0:
            return 0, forces, theta, gaps, in_p, iterations, none
        if iterations >= cap:
            return 2, forces, theta, gaps, in_p, iterations, none
        best = 0
        for k in range(1, new.size):
            if gaps[new[k]] < gaps[new[best]]:
                best = k
        single = new[best : best + 1]
        new = _most_negative(new, gaps, max(int(block[0]), int(block[1] * support.size)))
        need = _missing(new, slot)
        if need.size:  # the columns first: this state is the next call's start
            return 3, forces, theta, gaps, in_p, iterations, need
        iterations += 1
        while True:  # block addition: the new patches that would carry tension out again
            joined = in_p.copy()
            for j in new:
                joined[j] = True
            ok, z, z_theta = _on_support(_support(joined), s, r, t, rows, slot, singular_rtol)
            if not ok:
                return 1, forces, theta, gaps, in_p, iterations, none
            kept = 0
            for j in new:
                if z[j] > 0.0:
                    kept += 1
            if kept == new.size or (new.size == 1 and kept == 0):
                break
            if kept == 0:
                new = single
            else:
                keep = np.empty(kept, dtype=np.intp)
                kept = 0
                for j in new:
                    if z[j] > 0.0:
                        keep[kept] = j
                        kept += 1
                new = keep
        if z[new[0]] <= 0.0:  # a single patch, unloaded: round-off at the tolerance
            stuck[new[0]] = True
            z, z_theta = forces.copy(), theta  # the inner loop keeps the solution
            continue
        for j in new:
            in_p[j] = True
        support = _support(in_p)


def warm() -> None:
    """Compile the kernel, or load it from the disk cache, in this process (on two patches),
    before worker processes start (as :func:`gearopt.loaded.kernels.warm`)."""
    n = 2
    rows = np.array([[2.0, 1.0], [1.0, 2.0]])
    solve_patches(
        np.zeros(n), np.ones(n), 1.0, np.array([0.5, 0.5]), 1e-11, 10, 0, 1e-10, (32.0, 0.5),
        rows,
        np.arange(n),
    )  # fmt: skip
