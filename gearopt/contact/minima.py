"""The compiled tail of a clearance-field sample (numba; plain Python without it, as
:mod:`gearopt.contact.kernels`): from the node fields to the refined minima in three calls.

:meth:`gearopt.contact.engine.ContactEngine.sample` once did these steps array by array (the node
minimum of each row, its lowest refinable nodes, the refinement of each from there, the least
of them, the edge test against the node minimum), paying numpy's fixed cost per call on batches
of a few dozen rows, three times per TCA. :func:`minima_starts` gathers the refinement's starts,
:func:`gearopt.contact.kernels.refine` refines them and :func:`minima_pick` keeps each row's
least: the same steps on the same inputs, so the results are the same to the bit. (The
refinement stays a call of its own, and these two call no other kernel: a kernel called from
another is compiled again into it, which would lengthen the first use's compile.)
"""

from __future__ import annotations

import math

import numpy as np

from gearopt.jit import ENABLED, compiled

__all__ = ["ENABLED", "minima_pick", "minima_starts"]


@compiled
def minima_starts(
    field, side, refined, keep, candidates, near_sh, with_near, tolerances, grid, out
):
    """The node minima of a sample's rows and the starts of their refinement.

    Parameters
    ----------
    field
        ``(n, nodes)`` the rows' node clearances.
    side
        ``(n + m,)`` each row's field, the n sampled rows' then the m near rows' (as the
        rows of the refinement's constants).
    refined
        ``(n,)`` True where a row's minimum is refined.
    keep
        ``(sides, nodes)`` the refinable nodes.
    candidates
        How many of its lowest refinable nodes a row is refined from.
    near_sh
        ``(2, m)`` the pinion grid coordinates the near rows (rows refined from given points)
        start from; used only ``with_near``.
    with_near
        Whether there are near rows (else ``near_sh`` is a placeholder).
    tolerances
        ``(2, sides)`` each field's refinement tolerance (rad) and edge tolerance (um).
    grid
        ``(face_mm, profile_mm)`` the pinion grid.
    out
        ``(3, n)`` out: the rows' node minima and their grid coordinates (face, profile).

    Returns
    -------
    tuple
        ``(at, which, s, t, best, caps, group, tol)``: each row's least node (flat index),
        then :func:`gearopt.contact.kernels.refine`'s arguments: each start's row among the
        n + m (the refined rows' starts in their order, the near rows' last), the starts'
        points, values (NaN: none yet), the groups' step caps, each start's group and
        tolerance (none to refine where ``s`` is empty).
    """
    face, profile = grid
    n, size = field.shape
    n_p = profile.shape[0]
    at = np.empty(n, np.intp)
    chosen = 0
    for r in range(n):
        if refined[r]:
            chosen += 1
    m = near_sh.shape[1] if with_near else 0
    take = np.empty(chosen, np.intp)
    width = min(candidates, size)
    pick = np.empty((chosen, width), np.intp)
    values = np.empty((chosen, width))
    q = 0
    for r in range(n):
        # numpy's argmin (the first least, or the first NaN): the first least of the
        # numbers, the NaNs looked for after; with, on a refined row, its ``width`` least
        # refinable nodes, none twice (an insertion into the sorted list: the first of equal
        # values first, as ``width`` passes each taking the first least of the nodes not yet
        # picked)
        row = field[r]
        least, a, nan = row[0], 0, False
        if refined[r]:
            take[q] = r
            for c in range(width):
                pick[q, c] = 0
                values[q, c] = math.inf
            mine, cut = keep[side[r]], math.inf
            for g in range(size):
                v = row[g]
                if v < least:
                    least, a = v, g
                nan |= v != v
                if not (v < cut and mine[g]):
                    continue
                c = width - 1
                while c > 0 and v < values[q, c - 1]:
                    pick[q, c] = pick[q, c - 1]
                    values[q, c] = values[q, c - 1]
                    c -= 1
                pick[q, c] = g
                values[q, c] = v
                cut = values[q, width - 1]
            q += 1
        else:
            for g in range(1, size):
                v = row[g]
                if v < least:
                    least, a = v, g
                nan |= v != v
        if nan or least != least:
            a = 0
            while field[r, a] == field[r, a]:
                a += 1
        at[r] = a
        out[0, r] = field[r, a]
        out[1, r] = face[a // n_p]
        out[2, r] = profile[a % n_p]
    starts = 0
    for q in range(chosen):
        for c in range(width):
            if math.isfinite(values[q, c]):
                starts += 1
    k = starts + m
    which = np.empty(k, np.intp)
    s, t, best = np.empty(k), np.empty(k), np.empty(k)
    tol = np.empty(k)
    group = np.zeros(k, np.intp)
    p = 0
    for q in range(chosen):
        r = take[q]
        for c in range(width):
            if math.isfinite(values[q, c]):
                which[p] = r
                s[p] = face[pick[q, c] // n_p]
                t[p] = profile[pick[q, c] % n_p]
                best[p] = values[q, c]
                tol[p] = tolerances[0, side[r]]
                p += 1
    # the near rows: a second group (alone, ContactEngine.near: one group of 3 steps)
    for j in range(m):
        s[starts + j], t[starts + j] = near_sh[0, j], near_sh[1, j]
        best[starts + j] = np.nan
        tol[starts + j] = tolerances[0, side[n + j]]
        group[starts + j] = 1 if chosen else 0
        which[starts + j] = n + j
    if not chosen:
        caps = np.array([3], np.intp)
    elif with_near:
        caps = np.array([4, 3], np.intp)
    else:
        caps = np.array([4], np.intp)
    return at, which, s, t, best, caps, group, tol


@compiled
def minima_pick(factor, side, refined, at, which, s, t, best, flags, tolerances, out, edge):
    """Each refined row's least start (the first of equals; NaN after any number), then the
    edge test against its node minimum: a node minimum lower than that by more than the edge
    tolerance stands, flagged as edge contact (as the engine's refinement did).

    Parameters
    ----------
    factor
        ``(n, nodes)`` the rows' node normal factors.
    side
        ``(n,)`` each row's field.
    refined
        ``(n,)`` True where a row's minimum is refined (as :func:`minima_starts` took it).
    at, which
        As :func:`minima_starts` returned them.
    s, t, best, flags
        The starts refined (:func:`gearopt.contact.kernels.refine`): points, values, edge
        flags.
    tolerances
        As :func:`minima_starts`'s.
    out
        ``(3, n)`` in: the node minima and their points; out: the rows' minima and contact
        points (face, profile).
    edge
        ``(n,)`` out: the rows' edge flags.
    """
    edge[:] = False
    starts = which.shape[0]  # (the near rows' starts, last, belong to no sampled row)
    p = 0
    for r in range(refined.shape[0]):
        if not refined[r]:
            continue
        value, ss, tt, flag = math.inf, out[1, r], out[2, r], False
        first = True
        while p < starts and which[p] == r:
            v = best[p]
            if first or v < value or (value != value and v == v):
                value, ss, tt, flag = v, s[p], t[p], flags[p]
                first = False
            p += 1
        f0 = out[0, r]
        fac = factor[r, at[r]]
        scale = fac if (fac > 1e-9 or fac != fac) else 1e-9
        limit = tolerances[1, side[r]] * 1e-3 / scale
        low = math.isfinite(f0) and not (value - f0 <= limit)
        if not low:
            out[0, r], out[1, r], out[2, r] = value, ss, tt
        edge[r] = low or flag
