"""The compiled tail of a clearance-field sample (numba; plain Python without it, as
:mod:`gearopt.contact.kernels`): from the node fields to the refined minima in one call.

:meth:`gearopt.contact.engine.ContactEngine.sample` once did these steps array by array (the node
minimum of each row, its lowest refinable nodes, the refinement of each from there, the least
of them, the edge test against the node minimum), paying numpy's fixed cost per call on batches
of a few dozen rows, three times per TCA. :func:`sample_minima` runs the same steps, with the
same kernels (:func:`gearopt.contact.kernels.lowest_nodes`, :func:`gearopt.contact.kernels.refine`)
on the same inputs, so the results are the same to the bit.
"""

from __future__ import annotations

import math

import numpy as np

from gearopt.contact import kernels as _kernels
from gearopt.jit import ENABLED, compiled

__all__ = ["ENABLED", "sample_minima"]


@compiled
def _gather(rows, take, near, k):
    """Row constants of ``k`` refinement starts: the rows ``take`` of ``rows`` then every row
    of ``near`` (both as :func:`gearopt.contact.kernels.clearance_at` takes them)."""
    kx, ky, turn, sense, offset, pinion_offset = rows
    n_kx, n_ky, n_turn, n_sense, n_offset, n_pinion_offset = near
    out_kx, out_ky = np.empty((4, k)), np.empty((4, k))
    out_turn, out_sense = np.empty(k), np.empty(k)
    out_offset, out_pinion_offset = np.empty(k, np.intp), np.empty(k, np.intp)
    first = take.shape[0]
    for q in range(k):
        if q < first:
            r = take[q]
            for i in range(4):
                out_kx[i, q], out_ky[i, q] = kx[i, r], ky[i, r]
            out_turn[q], out_sense[q] = turn[r], sense[r]
            out_offset[q], out_pinion_offset[q] = offset[r], pinion_offset[r]
        else:
            r = q - first
            for i in range(4):
                out_kx[i, q], out_ky[i, q] = n_kx[i, r], n_ky[i, r]
            out_turn[q], out_sense[q] = n_turn[r], n_sense[r]
            out_offset[q], out_pinion_offset[q] = n_offset[r], n_pinion_offset[r]
    return out_kx, out_ky, out_turn, out_sense, out_offset, out_pinion_offset


@compiled
def _node_minimum(field, r):
    """The flat index of row ``r``'s least node (numpy's argmin: the first, a NaN first)."""
    at = 0
    least = field[r, 0]
    if least != least:
        return 0
    for g in range(1, field.shape[1]):
        v = field[r, g]
        if v != v:
            return g
        if v < least:
            least, at = v, g
    return at


@compiled
def sample_minima(
    field,
    factor,
    side,
    rows,
    refined,
    keep,
    candidates,
    near_rows,
    near_side,
    near_sh,
    with_near,
    tolerances,
    cell,
    pinion,
    gear,
    grid,
    minimum,
    contact,
    edge,
    near_minimum,
    near_contact,
    near_edge,
):
    """The refined minima of a sample's rows from their node fields.

    Parameters
    ----------
    field, factor
        ``(n, nodes)`` the rows' node clearances and normal factors.
    side
        ``(n,)`` each row's field.
    rows
        The rows' constants (as :func:`gearopt.contact.kernels.clearance_at` takes them).
    refined
        ``(n,)`` True where a row's minimum is refined.
    keep
        ``(sides, nodes)`` the refinable nodes.
    candidates
        How many of its lowest refinable nodes a row is refined from.
    near_rows, near_side, near_sh
        Rows refined from given points (gear angle 0): their constants, fields and pinion grid
        coordinates ``(2, m)``; used only ``with_near``.
    with_near
        Whether there are near rows (else ``near_*`` are placeholders).
    tolerances
        ``(2, sides)`` each field's refinement tolerance (rad) and edge tolerance (um).
    cell
        The pinion grid's cell size ``(ds, dh)``.
    pinion, gear
        The kernel tables.
    grid
        ``(face_mm, profile_mm)`` the pinion grid.
    minimum, contact, edge
        Out: ``(n,)``, ``(2, n)``, ``(n,)`` the rows' minima, contact points (face, profile)
        and edge flags (as :meth:`gearopt.contact.engine.ContactEngine.sample`).
    near_minimum, near_contact, near_edge
        Out: the near rows' (as :meth:`gearopt.contact.engine.ContactEngine.near`).
    """
    face, profile = grid
    n, size = field.shape
    n_p = profile.shape[0]
    at = np.empty(n, np.intp)
    chosen = 0
    for r in range(n):
        at[r] = _node_minimum(field, r)
        minimum[r] = field[r, at[r]]
        contact[0, r] = face[at[r] // n_p]
        contact[1, r] = profile[at[r] % n_p]
        edge[r] = False
        if refined[r]:
            chosen += 1
    m = near_side.shape[0] if with_near else 0
    if chosen == 0 and m == 0:
        return
    take = np.empty(chosen, np.intp)
    q = 0
    for r in range(n):
        if refined[r]:
            take[q] = r
            q += 1
    if chosen == 0:  # the near rows alone (ContactEngine.near)
        s, t = near_sh[0].copy(), near_sh[1].copy()
        best = np.full(m, np.nan)
        tol = np.empty(m)
        for p in range(m):
            tol[p] = tolerances[0, near_side[p]]
        _kernels.refine(
            near_rows,
            s,
            t,
            best,
            np.array([3], np.intp),
            np.zeros(m, np.intp),
            tol,
            cell,
            pinion,
            gear,
            near_edge,
        )
        for p in range(m):
            near_minimum[p] = best[p]
            near_contact[0, p], near_contact[1, p] = s[p], t[p]
        return
    sub = np.empty((chosen, size))
    sub_side = np.empty(chosen, np.intp)
    for q in range(chosen):
        sub[q] = field[take[q]]
        sub_side[q] = side[take[q]]
    width = min(candidates, size)
    pick = np.empty((chosen, width), np.intp)
    values = np.empty((chosen, width))
    _kernels.lowest_nodes(sub, keep, sub_side, pick, values)
    starts = 0
    for q in range(chosen):
        for c in range(width):
            if math.isfinite(values[q, c]):
                starts += 1
    k = starts + m
    origin = np.empty(starts, np.intp)  # each start's row (of the sample)
    s, t, best = np.empty(k), np.empty(k), np.empty(k)
    tol = np.empty(k)
    group = np.zeros(k, np.intp)
    p = 0
    for q in range(chosen):
        r = take[q]
        for c in range(width):
            if math.isfinite(values[q, c]):
                origin[p] = r
                s[p] = face[pick[q, c] // n_p]
                t[p] = profile[pick[q, c] % n_p]
                best[p] = values[q, c]
                tol[p] = tolerances[0, side[r]]
                p += 1
    for j in range(m):
        s[starts + j], t[starts + j] = near_sh[0, j], near_sh[1, j]
        best[starts + j] = np.nan
        tol[starts + j] = tolerances[0, near_side[j]]
        group[starts + j] = 1
    flags = np.zeros(k, np.bool_)
    if k > 0:
        constants = _gather(rows, origin, near_rows, k)
        caps = np.array([4, 3], np.intp) if m > 0 or with_near else np.array([4], np.intp)
        _kernels.refine(constants, s, t, best, caps, group, tol, cell, pinion, gear, flags)
    for j in range(m):
        p = starts + j
        near_minimum[j] = best[p]
        near_contact[0, j], near_contact[1, j] = s[p], t[p]
        near_edge[j] = flags[p]
    # each row's least refined start (the first of equals; NaN after any number), then the
    # edge test against its node minimum
    p = 0
    for q in range(chosen):
        r = take[q]
        value, ss, tt, flag = math.inf, contact[0, r], contact[1, r], False
        first = True
        while p < starts and origin[p] == r:
            v = best[p]
            if first or v < value or (value != value and v == v):
                value, ss, tt, flag = v, s[p], t[p], flags[p]
                first = False
            p += 1
        f0 = minimum[r]
        fac = factor[r, at[r]]
        scale = fac if (fac > 1e-9 or fac != fac) else 1e-9
        limit = tolerances[1, side[r]] * 1e-3 / scale
        low = math.isfinite(f0) and not (value - f0 <= limit)
        if not low:
            minimum[r] = value
            contact[0, r], contact[1, r] = ss, tt
        edge[r] = low or flag
