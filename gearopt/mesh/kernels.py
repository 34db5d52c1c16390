"""Compiled kernels of the mesh cycle's pattern at the nodes (numba; plain Python without it, as
:mod:`gearopt.contact.kernels`): the separations of every position's pairs, the pattern field,
the carrying zones' centroids, the TE and the pairs whose zones the pattern measures in one
pass over the node fields (:func:`pattern_fields`), where numpy makes a temporary of every
position's nodes at each step (:func:`gearopt.mesh.pattern.separation_mm`,
:func:`gearopt.mesh.pattern.centroids`: the same arithmetic, array by array); and the steps of
a side's mesh cycle on its few dozen samples, where numpy's per-call overhead outweighs the
work: its window's distinct rotations (:func:`window_rows`), its start on the window's sample
(:func:`side_start`), the checks of its window (the rows beyond it, its mesh centre, a lower
pair beyond it: :func:`beyond_rows`, :func:`window_check`), the contact interval's run of
interior samples (:func:`interior_run`) and the crossing of two pairs' interpolated lags, the
hand-over's first guess (:func:`crossing_root`), and its iteration's interpolants on the
samples so far (:func:`nearest_parabola`, :func:`inverse_roots`); and the zones' node factors
continued below the generated boundary (:func:`extend_factors`) and the neighbours over the
motion of the pairs a zone's rays cross (:func:`swept_pairs`). Each does numpy's arithmetic in
numpy's order: the results are the same to the bit.
"""

from __future__ import annotations

import math

import numpy as np

from gearopt.jit import ENABLED, compiled
from gearopt.mesh import path_kernels
from gearopt.units import ARCSEC

__all__ = [
    "ENABLED",
    "crossing_root",
    "extend_factors",
    "interior_run",
    "inverse_roots",
    "nearest_parabola",
    "pattern_fields",
    "side_start",
    "beyond_rows",
    "swept_pairs",
    "window_check",
    "window_rows",
    "warm",
]


@compiled
def pattern_fields(
    clearance, factor, minimum, inv, lag, carrying, g_min, compound, face, profile, sep, out, held
):
    """The pattern's node fields of a side's positions, their TE and the pairs whose zones the
    pattern measures (:meth:`gearopt.mesh.side.SideCycle.assemble`).

    Parameters
    ----------
    clearance, factor
        ``(R, N)`` the window sample's node clearances and node factors (normal or
        circumferential; N = n_f * n_p nodes, profile fastest).
    minimum
        ``(R,)`` the window sample's lags (least clearances; +inf off the flanks).
    inv
        ``(n * pairs,)`` the sample's row of each position's pair (position-major).
    lag
        ``(n,)`` the carrying pair's lag at each position.
    carrying
        ``(n,)`` the carrying pair's column.
    g_min
        The least lag (the TE's zero).
    compound
        The marking compound (mm).
    face, profile
        ``(n_f,)``, ``(n_p,)`` the nodes' pattern coordinates.
    sep
        ``(n * pairs, N)`` out: separations (um) at the carrying lag, +inf off the flanks
        (:func:`gearopt.mesh.pattern.separation_mm` times 1e3).
    out
        ``(N + (3 + pairs) n,)`` out: the pattern field (the least separation over the
        positions and pairs, um); the carrying zones' centroids (mm), face then profile
        (:func:`gearopt.mesh.pattern.centroids`); the TE (arcsec, ``(g_min - lag)``); the
        pairs' TE, pair-major (``(pairs, n)``).
    held
        ``(n * pairs,)`` out: first the entries whose zones reach within five compounds (their
        lag above the carrying one times the row's largest node factor; held or about to be).

    Returns
    -------
    int
        How many entries ``held`` lists.
    """
    n = lag.shape[0]
    pairs = inv.shape[0] // n
    n_p = profile.shape[0]
    size = clearance.shape[1]
    limit = 5.0 * compound
    count = 0
    for g in range(size):
        out[g] = math.inf
    for k in range(inv.shape[0]):
        row = inv[k]
        ref = lag[k // pairs]
        largest = -math.inf  # (numpy's max: a NaN wins)
        for g in range(size):
            f = factor[row, g]
            if largest == largest and (f > largest or f != f):
                largest = f
            v = (clearance[row, g] - ref) * f
            if v != v:  # (inf - inf: nothing on the flanks; inf * 0: off them)
                v = math.inf
            sep[k, g] = v
            if v < out[g]:
                out[g] = v
        above = minimum[row] - ref
        if not math.isfinite(above):
            above = math.inf
        if above * largest < limit:
            held[count] = k
            count += 1
    for i in range(n):
        k = i * pairs + carrying[i]
        total = ws = wh = 0.0
        least = math.inf
        at = 0
        for g in range(size):
            v = sep[k, g]
            if v < least:
                least, at = v, g
            w = compound - v
            if w > 0.0:
                total += w
                ws += w * face[g // n_p]
                wh += w * profile[g % n_p]
        if total > 0.0:
            out[size + i] = ws / total
            out[size + n + i] = wh / total
        else:  # no zone: its least-separated node
            out[size + i] = face[at // n_p]
            out[size + n + i] = profile[at % n_p]
        out[size + 2 * n + i] = (g_min - lag[i]) * ARCSEC
        for p in range(pairs):
            out[size + (3 + p) * n + i] = (g_min - minimum[inv[i * pairs + p]]) * ARCSEC
    for k in range(inv.shape[0]):  # mm to um (after the centroids, which take mm)
        for g in range(size):
            sep[k, g] *= 1e3
    for g in range(size):
        out[g] *= 1e3
    return count


@compiled
def side_start(minimum, edge, face, profile, inv, ids, t, pitch, step, tiny, g, edge_all, cs, ch):
    """A side's start on the window's sample (:class:`gearopt.mesh.side.SideCycle`): its
    pairs' lags, edge flags and contact points at each position, the carrying pair (the least
    lag), the TE maximum's guess (its relative rotation: the parabola through the least lag of
    the carrying pair and its neighbours on the same pair) and the hand-over's bracket
    (:meth:`~gearopt.mesh.side.SideCycle.start_handover`).

    Parameters
    ----------
    minimum, edge, face, profile
        ``(R,)`` the sample's lags (+inf off the flanks), edge flags and contact points.
    inv
        ``(n * pairs,)`` the sample's row of each position's pair (position-major).
    ids
        ``(n, pairs)`` the pairs' ids.
    t
        ``(n,)`` the positions.
    pitch, step
        The angular pitch and the position step.
    tiny
        The least rise of the lag difference over a bracket (rad).
    g, edge_all, cs, ch
        ``(n, pairs)`` out: the pairs' lags, edge flags and contact points.

    Returns
    -------
    tuple
        ``(carrying, lag, pair_id, touching, v_peak, spread, spread_finite, bracket, d_lo,
        d_hi)``: the carrying pair's column, lag and id at each position; False where a
        position has no pair touching inside the flanks; the peak's guess; the carrying lag's
        range (numpy's, a NaN wins) and its finite values' range (0 without); ``(k, leaving
        column at k, at k + 1, incoming column at k, at k + 1)``, ``k`` -1 without a bracket;
        the lag differences (leaving minus incoming) at its ends.
    """
    n, pairs = ids.shape
    carrying = np.empty(n, np.intp)
    lag = np.empty(n)
    pair_id = np.empty(n, ids.dtype)
    touching = True
    for i in range(n):
        best = 0
        finite = False
        for p in range(pairs):
            row = inv[i * pairs + p]
            v = minimum[row]
            g[i, p] = v
            edge_all[i, p] = edge[row]
            cs[i, p] = face[row]
            ch[i, p] = profile[row]
            finite = finite or math.isfinite(v)
            # (numpy's argmin: the first least, or the first NaN)
            if g[i, best] == g[i, best] and (v < g[i, best] or v != v):
                best = p
        touching = touching and finite
        carrying[i] = best
        lag[i] = g[i, best]
        pair_id[i] = ids[i, best]
    # the peak: the least lag on the carrying pair of the least lag, and the parabola through
    # its neighbours on the same pair
    least = 0  # (numpy's argmin, as above)
    for i in range(n):
        if lag[least] == lag[least] and (lag[i] < lag[least] or lag[i] != lag[i]):
            least = i
    kk = -1
    for i in range(n):
        if pair_id[i] == pair_id[least] and (
            kk < 0 or (lag[kk] == lag[kk] and (lag[i] < lag[kk] or lag[i] != lag[i]))
        ):
            kk = i
    v_peak = t[kk] + pair_id[kk] * pitch
    if 0 < kk < n - 1 and pair_id[kk - 1] == pair_id[kk] and pair_id[kk] == pair_id[kk + 1]:
        gm, g0, gp = lag[kk - 1], lag[kk], lag[kk + 1]
        curv = gm - 2.0 * g0 + gp
        if curv > 0.0:
            z = 0.5 * (gm - gp) / curv
            if z < -1.0:
                z = -1.0
            elif z > 1.0:
                z = 1.0
            v_peak += z * step
    high, low = -math.inf, math.inf
    high_f, low_f = -math.inf, math.inf
    nan = False
    for i in range(n):
        v = lag[i]
        nan = nan or v != v
        high, low = max(high, v), min(low, v)
        if math.isfinite(v):
            high_f, low_f = max(high_f, v), min(low_f, v)
    spread = math.nan if nan else high - low
    spread_finite = high_f - low_f if low_f <= high_f else 0.0
    # the hand-over: the first forward switch of the carrying pair (the next, one id lower,
    # takes over) whose two pairs' lag difference changes sign
    bracket = (-1, 0, 0, 0, 0)
    d_lo = d_hi = 0.0
    for k in range(n - 1):
        if pair_id[k + 1] - pair_id[k] != -1:
            continue
        leave = pair_id[k]
        cols = [-1, -1, -1, -1]  # leaving at k, k + 1; incoming at k, k + 1
        for j in range(2):
            for p in range(pairs):
                if ids[k + j, p] == leave and cols[j] < 0:
                    cols[j] = p
                if ids[k + j, p] == leave - 1 and cols[2 + j] < 0:
                    cols[2 + j] = p
        if min(cols[0], cols[1], cols[2], cols[3]) < 0:
            continue
        lo = g[k, cols[0]] - g[k, cols[2]]
        hi = g[k + 1, cols[1]] - g[k + 1, cols[3]]
        if math.isfinite(lo) and math.isfinite(hi) and lo <= 0.0 <= hi and hi - lo > tiny:
            bracket = (k, cols[0], cols[1], cols[2], cols[3])
            d_lo, d_hi = lo, hi
            break
    return carrying, lag, pair_id, touching, v_peak, spread, spread_finite, bracket, d_lo, d_hi


@compiled
def _rint(x):
    """``x`` rounded to the nearest integer, halves to even (numpy's ``round``)."""
    r = math.floor(x)
    rest = x - r  # (exact)
    if rest > 0.5 or (rest == 0.5 and r % 2.0 != 0.0):
        r += 1.0
    return r


@compiled
def _stable_order(key):
    """The stable ascending order of ``key`` (numpy's ``argsort(kind="stable")``: a stable
    sort's order is unique): by :func:`_insert`, for the few dozen to few thousand nearly
    ordered keys here, which compiles in a fraction of numba's merge sort's time."""
    keys, order = np.empty_like(key), np.empty(key.shape[0], np.intp)
    m = 0
    for i in range(key.shape[0]):
        m = _insert(key[i], i, keys, order, m)
    return order


@compiled
def swept_pairs(ray, key, position, prev, nxt, start):
    """The pairs of :func:`gearopt.contact.zone_kernels.swept_exits` from the rays' lists
    ``(P,)`` (ray, tooth pair, position; each ray's pairs together, the rays in order): each
    pair's neighbours over the motion, the rows of the same ray and tooth pair at the previous
    and next positions (-1 without), into ``prev`` and ``nxt``; the first pair of each ray
    into ``start`` ``(P + 2,)``, then ``P`` (without pairs, one ray of none: ``0, 0``).

    Returns
    -------
    tuple
        ``(rays, ordered)``: how many rays ``start`` lists (``start[rays]`` is ``P``), and
        False where a ray's pairs are not together in the order of the rays.
    """
    n = ray.shape[0]
    if n == 0:
        start[0] = start[1] = 0
        return 1, True
    # one stable sort of one code in the order (ray, key, position): lexsort's
    k0, p0 = key.min(), position.min()
    span_k, span_p = key.max() - k0 + 1, position.max() - p0 + 1
    order = _stable_order((ray * span_k + (key - k0)) * span_p + (position - p0))
    for i in range(n):
        prev[i] = nxt[i] = -1
    for i in range(1, n):
        a, b = order[i - 1], order[i]
        if ray[a] == ray[b] and key[a] == key[b] and position[b] - position[a] == 1:
            prev[b], nxt[a] = a, b
    count, ordered = 0, True
    for i in range(n):
        if i == 0 or ray[i] != ray[i - 1]:
            start[count] = i
            count += 1
        if i > 0 and ray[i] < ray[i - 1]:
            ordered = False
    start[count] = n
    return count, ordered


@compiled
def window_rows(t, centre, window, pitch, ids, u, first, inv):
    """A side's window of pairs about its mesh centre and its distinct relative rotations
    (:meth:`gearopt.mesh.cycle.MeshCycle.main_sample`).

    Parameters
    ----------
    t
        ``(n,)`` the positions.
    centre
        The mesh centre (a relative rotation).
    window
        ``(pairs,)`` the window's pair offsets.
    pitch
        The angular pitch.
    ids, u
        ``(n, pairs)`` out: the pairs' ids (the nearest whole pitches from the centre plus the
        offsets) and their relative rotations ``t + ids * pitch``.
    first, inv
        ``(n * pairs,)`` out: the first entry of ``u`` (flat) of each distinct rotation (to a
        billionth of a pitch), in increasing order; the distinct rotation of each entry
        (numpy's ``unique`` with ``return_index`` and ``return_inverse``).

    Returns
    -------
    int
        How many distinct rotations ``first`` lists.
    """
    n, pairs = ids.shape
    key = np.empty(n * pairs, np.int64)
    for i in range(n):
        base = _rint((centre - t[i]) / pitch)
        for j in range(pairs):
            ids[i, j] = base + window[j]
            u[i, j] = t[i] + ids[i, j] * pitch
            key[i * pairs + j] = np.int64(_rint(u[i, j] / pitch * 1e9))
    order = _stable_order(key)
    count = 0
    for m in range(key.shape[0]):
        k = order[m]
        if m == 0 or key[k] != key[order[m - 1]]:
            first[count] = k
            count += 1
        inv[k] = count - 1
    return count


@compiled
def _beyond_ends(u, carrying, pitch, at, beyond):
    """At the window's first end, then its last, at each position where that end's pair
    carries: the position (``at``) and the relative rotation of the pair beyond it
    (``beyond``), each ``(2 n,)`` out. Returns how many they list."""
    count = 0
    for e in range(2):
        slot, off = (0, -1.0 * pitch) if e == 0 else (u.shape[1] - 1, 1.0 * pitch)
        for i in range(u.shape[0]):
            if carrying[i] == slot:
                at[count], beyond[count] = i, u[i, slot] + off
                count += 1
    return count


@compiled
def _pitch_keys(v, pitch):
    """Relative rotations ``v`` as keys that match to a billionth of a pitch."""
    keys = np.empty(v.shape[0])
    for j in range(v.shape[0]):
        keys[j] = _rint(v[j] / pitch * 1e9)
    return keys


@compiled
def beyond_rows(v, u, carrying, pitch, out):
    """The pairs beyond a side's window where its end pair carries and that its sample does
    not hold (:meth:`gearopt.mesh.cycle.MeshCycle.beyond_requests`): at the first end, then
    the last, at each position where that end's pair carries, the relative rotation of the
    pair beyond it, where no sampled one (``v``) matches it to a billionth of a pitch.

    Parameters
    ----------
    v
        ``(m,)`` the relative rotations the window's sample holds.
    u
        ``(n, pairs)`` the pairs' relative rotations at each position.
    carrying
        ``(n,)`` the column of the carrying pair.
    pitch
        The angular pitch.
    out
        ``(2 n,)`` out: the rotations beyond, in that order.

    Returns
    -------
    int
        How many ``out`` lists.
    """
    known = _pitch_keys(v, pitch)
    at = np.empty(2 * u.shape[0], np.intp)
    beyond = np.empty(2 * u.shape[0])
    count = 0
    for q in range(_beyond_ends(u, carrying, pitch, at, beyond)):
        key = _rint(beyond[q] / pitch * 1e9)
        held = False
        for j in range(known.shape[0]):
            if known[j] == key:
                held = True
                break
        if not held:
            out[count] = beyond[q]
            count += 1
    return count


@compiled
def window_check(v, g, u, carrying, lag, pitch, flat):
    """A side's window checked on everything sampled for it: its mesh centre and whether a
    pair beyond it carries (:meth:`gearopt.mesh.cycle.MeshCycle.window_checks`).

    Parameters
    ----------
    v, g
        ``(m,)`` the relative rotations sampled (the window's sample, then the rows beyond it)
        and their lags.
    u, carrying, lag
        ``(n, pairs)`` the pairs' relative rotations at each position; ``(n,)`` the carrying
        pair's column and lag.
    pitch
        The angular pitch.
    flat
        Lags closer than this are equal (a flat TE).

    Returns
    -------
    tuple
        ``(centre, lower)``: the rotation of least lag (the first; non-finite lags as +inf)
        where it lies more than half a pitch from the window's centre and is lower than the
        least lag within by more than ``flat``, else 0.0; True where, at a position where an
        end pair of the window carries, the pair beyond it has a lower lag (the last sampled
        one matching its rotation to a billionth of a pitch; +inf without).
    """
    m = v.shape[0]
    best, least, within = 0, np.inf, np.inf
    half = 0.5 * pitch + 1e-9
    for j in range(m):
        gj = g[j] if math.isfinite(g[j]) else np.inf
        if j == 0 or gj < least:
            best, least = j, gj
        if abs(v[j]) <= half and gj < within:
            within = gj
    centre = 0.0
    if m and not abs(v[best]) <= half and least < within - flat:
        centre = v[best]
    keys = _pitch_keys(v, pitch)
    at = np.empty(2 * u.shape[0], np.intp)
    beyond = np.empty(2 * u.shape[0])
    lower = False
    for q in range(_beyond_ends(u, carrying, pitch, at, beyond)):
        key = _rint(beyond[q] / pitch * 1e9)
        lag_beyond = np.inf
        for j in range(m - 1, -1, -1):
            if keys[j] == key:
                lag_beyond = g[j]
                break
        if lag_beyond < lag[at[q]]:
            lower = True
    return centre, lower


@compiled
def interior_run(order, inner, lag):
    """The contact interval's run of samples (:meth:`gearopt.mesh.side.SideCycle.start_interval`).

    Parameters
    ----------
    order
        ``(m,)`` the samples' order by relative rotation.
    inner
        ``(m,)`` True where a sample is an interior contact (finite, not at an edge).
    lag
        ``(m,)`` their lags (+inf off the flanks).

    Returns
    -------
    tuple
        ``(lo, hi, spread)``: the first and last places (in that order) of the unbroken run of
        interior samples holding the least lag, else of the first longest run (-1, -1 without
        one); the lags' spread (max - min) over that run.
    """
    m = order.shape[0]
    centre = 0
    least = math.inf
    for k in range(m):
        x = lag[order[k]]
        if x < least:
            least, centre = x, k
    lo = hi = -1
    best = -1
    k = 0
    while k < m:
        end = k
        while end + 1 < m and inner[order[end + 1]] == inner[order[k]]:
            end += 1
        if inner[order[k]]:
            if k <= centre <= end:
                lo, hi = k, end
                break
            if end - k > best:
                best, lo, hi = end - k, k, end
        k = end + 1
    spread = 0.0
    if lo >= 0:
        top = bottom = lag[order[lo]]
        for k in range(lo + 1, hi + 1):
            x = lag[order[k]]
            top = max(top, x)
            bottom = min(bottom, x)
        spread = top - bottom
    return lo, hi, spread


@compiled
def _newton_value(z, c, x):
    value = c[3]
    for i in range(2, -1, -1):
        value = value * (x - z[i]) + c[i]
    return value


@compiled
def crossing_root(v, lag, edge, near, centres, step, half):
    """The crossing of two pairs' lags interpolated (cubic, divided differences) through their
    four nearest samples (Newton's form: divided differences, nested multiplication), by the
    Illinois method (regula falsi halving the retained end's value) to 1e-12: the hand-over's
    first guess (:func:`gearopt.mesh.handover.lag_crossing`).

    Parameters
    ----------
    v, lag, edge
        ``(m,)`` the samples: relative rotations, lags and edge flags.
    near
        ``(2, 4)`` the rows of the four samples nearest each pair's centre.
    centres
        ``(2,)`` the centres (the leaving pair's, the incoming pair's).
    step
        The position step (the unit of the cubics' abscissae).
    half
        The half-width of the bracket around the centres, in steps.

    Returns
    -------
    float
        The crossing in steps from the centres; NaN where a sample is missing, at an edge or
        more than two steps off, or without a sign change.
    """
    za, zb = np.empty(4), np.empty(4)
    ga, gb = np.empty(4), np.empty(4)
    for i in range(4):
        za[i] = (v[near[0, i]] - centres[0]) / step
        zb[i] = (v[near[1, i]] - centres[1]) / step
        ga[i] = lag[near[0, i]]
        gb[i] = lag[near[1, i]]
    for i in range(4):
        for k in range(2):
            row = near[k, i]
            z = za[i] if k == 0 else zb[i]
            if abs(z) > 2.0 or not math.isfinite(lag[row]) or edge[row]:
                return math.nan
    ca, cb = ga, gb
    for j in range(1, 4):
        for i in range(3, j - 1, -1):
            ca[i] = (ca[i] - ca[i - 1]) / (za[i] - za[i - j])
            cb[i] = (cb[i] - cb[i - 1]) / (zb[i] - zb[i - j])
    a, b = -half, half
    fa = _newton_value(za, ca, a) - _newton_value(zb, cb, a)
    fb = _newton_value(za, ca, b) - _newton_value(zb, cb, b)
    if fa == 0.0:
        return a
    if fb == 0.0:
        return b
    if fa * fb > 0.0:
        return math.nan
    for _ in range(100):
        c = b - fb * (b - a) / (fb - fa)
        fc = _newton_value(za, ca, c) - _newton_value(zb, cb, c)
        if fc == 0.0 or abs(c - b) <= 1e-12:
            return c
        if fc * fb < 0.0:
            a, fa = b, fb
        else:
            fa *= 0.5
        b, fb = c, fc
    return b


@compiled
def extend_factors(f):
    """Node factors ``f`` ``(R, n_f, n_p)`` (0 off the generated nodes; in place): in each face
    column whose lowest generated node (the first factor above 0) has a node below it and one
    above it, the node below continued linearly from that node and the one above, where the one
    above is generated, else given that node's factor
    (:func:`gearopt.mesh.zone.extended_factors`)."""
    rows, n_f, n_p = f.shape
    for r in range(rows):
        for i in range(n_f):
            low = -1
            for j in range(n_p):
                if f[r, i, j] > 0.0:
                    low = j
                    break
            if low >= 1 and low + 1 < n_p:
                above = f[r, i, low + 1]
                f[r, i, low - 1] = 2.0 * f[r, i, low] - above if above > 0.0 else f[r, i, low]


@compiled
def _newton_at(z, c, m, x):
    """The polynomial through the points ``(z[:m], c[:m])`` at ``x``: divided differences (in
    ``c``) and nested multiplication, as :func:`gearopt.mesh.handover.newton_form` and
    :func:`~gearopt.mesh.handover.newton_value` on Python floats."""
    for j in range(1, m):
        for i in range(m - 1, j - 1, -1):
            c[i] = (c[i] - c[i - 1]) / (z[i] - z[i - j])
    value = c[m - 1]
    for i in range(m - 2, -1, -1):
        value = value * (x - z[i]) + c[i]
    return value


@compiled
def _insert(key, i, keys, rows, m):
    """Insert row ``i`` with ``key`` into the ``m`` least ``keys`` so far (ascending, the first
    of equals first: a stable sort's order), keeping at most ``len(keys)``; the new count."""
    size = keys.shape[0]
    if m == size and not key < keys[size - 1]:
        return m
    c = m if m < size else size - 1
    while c > 0 and key < keys[c - 1]:
        keys[c], rows[c] = keys[c - 1], rows[c - 1]
        c -= 1
    keys[c], rows[c] = key, i
    return m + 1 if m < size else m


@compiled
def nearest_parabola(samples, x):
    """The lag of a hand-over's pair at ``x``: the parabola through the three of its samples
    ``(x, lag)`` (rows of ``samples``) nearest ``x`` (the first of equals first)
    (:meth:`gearopt.mesh.handover.HandOver.interpolated`)."""
    keys, rows = np.empty(3), np.empty(3, np.intp)
    m = 0
    for i in range(samples.shape[0]):
        m = _insert(abs(samples[i, 0] - x), i, keys, rows, m)
    z, c = np.empty(m), np.empty(m)
    for k in range(m):
        z[k], c[k] = samples[rows[k], 0], samples[rows[k], 1]
    return _newton_at(z, c, m, x)


@compiled
def inverse_roots(a, b, d_a, d_b, trail):
    """The roots of the inverse interpolants (x as a polynomial of D) through a bracket's ends
    ``(a, d_a)``, ``(b, d_b)`` and the one, then the two points of ``trail`` (rows ``(x, D)``)
    nearest the bracket (by the lesser distance to its ends; the first of equals first; none
    at an end): ``(root, root)``, NaN where too few points or D's values not distinct
    (:func:`gearopt.mesh.handover.inverse_root`)."""
    keys, rows = np.empty(2), np.empty(2, np.intp)
    m = 0
    for i in range(trail.shape[0]):
        x = trail[i, 0]
        if x != a and x != b:
            m = _insert(min(abs(x - a), abs(x - b)), i, keys, rows, m)
    roots = np.full(2, math.nan)
    for count in range(1, m + 1):
        z, c = np.empty(2 + count), np.empty(2 + count)
        z[0], z[1], c[0], c[1] = d_a, d_b, a, b
        for k in range(count):
            z[2 + k], c[2 + k] = trail[rows[k], 1], trail[rows[k], 0]
        distinct = True
        for p in range(2 + count):
            for q in range(p):
                distinct = distinct and z[p] != z[q]
        if distinct:
            roots[count - 1] = _newton_at(z, c, 2 + count, 0.0)
    return roots[0], roots[1]


def warm() -> None:
    """Compile the kernels, or load them from the disk cache (as
    :func:`gearopt.contact.kernel_warmup.warm`), with the path's
    (:func:`gearopt.mesh.path_kernels.warm`); nothing without them."""
    if not ENABLED:
        return
    path_kernels.warm()
    one, index = np.zeros((1, 1)), np.zeros(1, np.intp)
    pattern_fields(
        one,
        one,
        np.zeros(1),
        index,
        np.zeros(1),
        index,
        0.0,
        1.0,
        np.zeros(1),
        np.zeros(1),
        one.copy(),
        np.empty(5),
        index.copy(),
    )
    interior_run(np.arange(2), np.ones(2, np.bool_), np.zeros(2))
    side, none = np.zeros(1, np.intp), np.full(1, -1, np.intp)
    swept_pairs(side, side, side, none.copy(), none.copy(), np.zeros(3, np.intp))
    window_rows(
        np.zeros(2),
        0.0,
        np.arange(1),
        1.0,
        np.empty((2, 1)),
        np.empty((2, 1)),
        *np.empty((2, 2), np.intp),
    )
    two, ids = np.zeros(2), np.zeros((2, 1))
    side_start(
        two,
        two > 1.0,
        two,
        two,
        np.arange(2),
        ids,
        two,
        1.0,
        1.0,
        1e-9,
        two.reshape(2, 1).copy(),
        ids > 1.0,
        two.reshape(2, 1).copy(),
        two.reshape(2, 1).copy(),
    )
    extend_factors(np.zeros((1, 1, 3)))
    nearest_parabola(np.arange(6.0).reshape(3, 2), 0.5)
    inverse_roots(0.0, 1.0, -1.0, 1.0, np.arange(6.0).reshape(3, 2))
    u, carrying = np.zeros((2, 1)), np.zeros(2, np.intp)
    beyond_rows(two, u, carrying, 1.0, np.empty(4))
    window_check(two, two, u, carrying, two, 1.0, 0.0)
    four = np.arange(4.0)
    crossing_root(four, four, four > 9.0, np.zeros((2, 4), np.intp), np.zeros(2), 1.0, 1.0)
