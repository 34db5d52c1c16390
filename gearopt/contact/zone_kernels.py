"""Compiled kernels of the marking-compound zone (numba): the exits of rays from the pattern
a side's zones sweep (:func:`swept_exits`) and from their union (:func:`union_exits`), for
:class:`gearopt.mesh.zone.Zones`. The clearance at a pinion point is the contact engine's
(:func:`gearopt.contact.kernels.pinion_at`, :func:`gearopt.contact.kernels.gap_of`), scaled by
the zone's node factors into the separation (normal or circumferential) the compound measures.
"""

from __future__ import annotations

import math

import numpy as np

from gearopt.contact.kernels import gap_of, pinion_at
from gearopt.jit import compiled

__all__ = ["swept_exits", "union_exits"]


@compiled(inline=True)
def _zone_at(s, t, grid):
    """The node factors' bilinear cell ``(i, j)`` and weights ``(u, v)`` at ``(s, t)``.
    ``grid``: the factors' origin, spacing and last cells, ``(s0, ds, t0, dt, last0, last1)``."""
    s0, ds, t0, dt, last0, last1 = grid
    x = min(max((s - s0) / ds, 0.0), last0 + 1.0)
    y = min(max((t - t0) / dt, 0.0), last1 + 1.0)
    i = min(int(x), int(last0))
    j = min(int(y), int(last1))
    return i, j, x - i, y - j


@compiled(inline=True)
def _separation_of(rows, r, point, at, gear, cells, lag, factor):
    """:meth:`gearopt.mesh.zone.Zones.separation` of row ``r`` at the pinion point ``point``
    (:func:`pinion_at`, its cell offset the row's) in the factors' cell ``at``
    (:func:`_zone_at`); ``cells``: the pinion's refinable cells (``pinion[14]``), ``lag`` and
    ``factor`` the rows' lags and node factors. (Every table read before the one branch: see
    :mod:`gearopt.contact.kernels` on the references numba takes.)"""
    i, j, u, v = at
    f = (1.0 - u) * ((1.0 - v) * factor[r, i, j] + v * factor[r, i, j + 1]) + u * (
        (1.0 - v) * factor[r, i + 1, j] + v * factor[r, i + 1, j + 1]
    )
    shift = lag[r]
    delta, valid = gap_of(rows, r, point, gear, cells)
    return (delta - shift) * f if valid else math.inf


@compiled(inline=True)
def _crossing(t0, f0, t1, f1, t2, f2):
    """:func:`gearopt.mesh.zone._crossing` of one bracket."""
    if not math.isfinite(f2):
        return t2
    linear = t1 + (t2 - t1) * f1 / (f1 - f2)
    quad = (
        t0 * f1 * f2 / ((f0 - f1) * (f0 - f2))
        + t1 * f0 * f2 / ((f1 - f0) * (f1 - f2))
        + t2 * f0 * f1 / ((f2 - f0) * (f2 - f1))
    )
    if math.isfinite(quad) and f0 < f1 and quad >= t1 and quad <= t2:
        return quad
    return linear


@compiled
def _swept_min(rows, pinion, gear, zone, a, b, pair_row, prev, nxt, ray, tau, f, have, hint, kept):
    """With ``hint[0]`` < 0 the pattern at ``tau`` along a ray of pairs ``a:b``, the least swept
    separation minus the compound; else -1.0 inside, +1.0 out, trying pair ``hint[0]`` (the
    last found inside) first and the others until one is inside. ``kept``: ``f`` and ``have``
    hold the separations at this ``tau`` already (the last call's, there).

    Pair p's swept separation is its separation at ``tau`` at its least over the motion, as
    ``gearopt.mesh.zone``'s ``_swept``: the parabola through it and its neighbours' (``prev``,
    ``nxt``) where it is the least of the three; each separation evaluated once (``f``,
    ``have``), in this loop (a call taking the tables would reference and release each of
    their arrays, :mod:`gearopt.contact.kernels`)."""
    lag, factor, s0, ds, t0, dt, last0, last1, c = zone
    cells, offsets = pinion[14], rows[5]
    if not kept:
        have[a:b] = False
    s = ray[0] + tau * ray[2]
    t = ray[1] + tau * ray[3]
    searching = hint[0] >= 0
    offset = offsets[pair_row[hint[0] if searching else a]]
    point = pinion_at(s, t, pinion, offset)  # (the rows of one pinion cell offset)
    at = _zone_at(s, t, (s0, ds, t0, dt, last0, last1))
    least = math.inf
    for i in range(-1 if searching else 0, b - a):
        p = hint[0] if i < 0 else a + i
        for q in (prev[p], p, nxt[p]):
            if q >= 0 and not have[q]:
                r = pair_row[q]
                if offsets[r] != offset:
                    offset = offsets[r]
                    point = pinion_at(s, t, pinion, offset)
                f[q] = _separation_of(rows, r, point, at, gear, cells, lag, factor)
                have[q] = True
        g = f[p]
        if prev[p] >= 0 and nxt[p] >= 0:
            fa, fd = f[prev[p]], f[nxt[p]]
            curv = fa - 2.0 * g + fd
            finite = math.isfinite(fa) and math.isfinite(g) and math.isfinite(fd)
            if finite and g <= fa and g <= fd and curv > 0.0:
                g = g - 0.125 * (fd - fa) ** 2 / curv
        if not searching:
            least = min(least, g)
        elif g < c:
            if i >= 0:
                hint[0] = p
            return -1.0
    return 1.0 if searching else least - c


@compiled
def swept_exits(rows, pinion, gear, zone, start, pair_row, prev, nxt, rays, tau, zoom, out):
    """:meth:`gearopt.mesh.zone.Zones.pattern_exits` into ``out``: ray k (``rays[k]``: origin,
    direction) of pairs ``start[k]:start[k + 1]`` (rows ``pair_row``, neighbours over the
    motion ``prev``, ``nxt``, -1 without) scanned at ``tau[k]`` up to its first exit, a sample
    inside once a pair is; the field whole only where it brackets the exit (the same result;
    at a sample found out, every pair's separation is known already); an exit through a
    flank's boundary on the finer scan ``zoom``."""
    f = np.empty(pair_row.shape[0])
    have = np.zeros(pair_row.shape[0], np.bool_)
    m = tau.shape[1]
    full = np.full(1, -1, np.intp)
    for k in range(rays.shape[0]):
        a, b, ray = start[k], start[k + 1], rays[k]
        hint = np.full(1, a, np.intp)
        out[k] = 0.0
        zoned = (rows, pinion, gear, zone, a, b, pair_row, prev, nxt, ray)
        if not b > a or _swept_min(*zoned, tau[k, 0], f, have, hint, False) > 0.0:
            continue
        j = 1
        while j < m:
            if _swept_min(*zoned, tau[k, j], f, have, hint, False) > 0.0:
                break
            j += 1
        if j == m:
            out[k] = tau[k, m - 1]
            continue
        t1, t2 = tau[k, j - 1], tau[k, j]
        g = _swept_min(*zoned, t2, f, have, full, True)  # (every pair known: out at t2)
        if math.isfinite(g):
            gm1 = _swept_min(*zoned, t1, f, have, full, False)
            gm2 = math.nan
            if j >= 2:
                gm2 = _swept_min(*zoned, tau[k, j - 2], f, have, full, False)
            out[k] = _crossing(tau[k, max(j - 2, 0)], gm2, t1, gm1, t2, g)
            continue
        za = zb = 0.0
        inside = False
        out_first = False  # (the bracket: the first sample out, but never before the second)
        for i in range(zoom.shape[0]):
            zb = t1 + (t2 - t1) * zoom[i]
            inside = _swept_min(*zoned, zb, f, have, hint, False) < 0.0
            if i >= 1 and (out_first or not inside or i == zoom.shape[0] - 1):
                break
            out_first = not inside
            za = zb
        fb = _swept_min(*zoned, zb, f, have, full, not inside)
        fa = _swept_min(*zoned, za, f, have, full, False)
        out[k] = _crossing(za, math.nan, za, fa, zb, fb) if math.isfinite(fb) else 0.5 * (za + zb)


@compiled
def union_exits(rows, pinion, gear, zone, start, pair_row, rays, tau, zoom, out):
    """:meth:`gearopt.mesh.zone.Zones.exits` ray by ray, each scanned only up to its first
    sample out of every zone: ray k (``rays[k]`` = origin, unit direction) holds the zones of
    pairs ``start[k]:start[k + 1]`` (rows ``pair_row``) and is scanned at ``tau[k]``; each
    zone that held the ray up to that sample gives a crossing of its separation through the
    compound (``zone[8]``; through a flank's boundary, on the finer scan ``zoom``); the
    farthest is the exit. Writes ``out`` ``(K,)``."""
    lag, factor, s0, ds, t0, dt, last0, last1, c = zone
    grid = (s0, ds, t0, dt, last0, last1)
    cells, offsets = pinion[14], rows[5]
    m = tau.shape[1]
    f = np.empty((pair_row.shape[0], m))
    for k in range(rays.shape[0]):
        a, b = start[k], start[k + 1]
        ox, oy, dx, dy = rays[k, 0], rays[k, 1], rays[k, 2], rays[k, 3]
        j = 0
        offset = offsets[pair_row[a]] if b > a else 0
        while j < m:
            held = False
            s, t = ox + tau[k, j] * dx, oy + tau[k, j] * dy
            point = pinion_at(s, t, pinion, offset)  # (the rows of one pinion cell offset)
            at = _zone_at(s, t, grid)
            for p in range(a, b):
                r = pair_row[p]
                if offsets[r] != offset:
                    offset = offsets[r]
                    point = pinion_at(s, t, pinion, offset)
                f[p, j] = _separation_of(rows, r, point, at, gear, cells, lag, factor) - c
                held = held or f[p, j] < 0.0
            if not held:
                break
            j += 1
        if j == m:
            out[k] = tau[k, m - 1]
            continue
        result = 0.0
        for p in range(a, b):
            if j == 0 or not f[p, j - 1] < 0.0:
                continue
            t1, t2, f1, f2 = tau[k, j - 1], tau[k, j], f[p, j - 1], f[p, j]
            if math.isfinite(f2):
                t0 = tau[k, max(j - 2, 0)]
                x = _crossing(t0, f[p, j - 2] if j >= 2 else math.nan, t1, f1, t2, f2)
            else:
                r = pair_row[p]
                za = fa = zb = fb = 0.0
                out_first = False
                for i in range(zoom.shape[0]):
                    zb = t1 + (t2 - t1) * zoom[i]
                    s, t = ox + zb * dx, oy + zb * dy
                    point = pinion_at(s, t, pinion, offsets[r])
                    at = _zone_at(s, t, grid)
                    fb = _separation_of(rows, r, point, at, gear, cells, lag, factor) - c
                    if i >= 1 and (out_first or not fb < 0.0 or i == zoom.shape[0] - 1):
                        break
                    out_first = not fb < 0.0
                    za, fa = zb, fb
                if math.isfinite(fb):
                    x = _crossing(za, math.nan, za, fa, zb, fb)
                else:
                    x = 0.5 * (za + zb)
            result = math.nan if (x != x or result != result) else max(result, x)
        out[k] = result
