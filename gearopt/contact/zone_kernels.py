"""Compiled kernels of the marking-compound zone (numba): the exits of rays from the pattern
a side's zones sweep (:func:`swept_exits`) and from their union (:func:`union_exits`), and
the outline's stations and rays (:func:`outline_stations`, :func:`outline_rays`: numpy's steps
in numpy's order, the same bits), for :class:`gearopt.mesh.zone.Zones`. The clearance at a
pinion point is the contact engine's (:func:`gearopt.contact.kernels.pinion_at`,
:func:`gearopt.contact.kernels.gap_of`), scaled by the zone's node factors into the separation
(normal or circumferential) the compound measures.

Each kernel evaluates its points in its own loops, the tables unpacked once and read by the
inlined :func:`_separation_of` before its one branch: a call taking the tables, or an inlined
helper holding them across branches, would take and release a reference on each of their
arrays at every point, atomically (as in :mod:`gearopt.contact.kernels`), more than the
kernels' own work.
"""

from __future__ import annotations

import math

import numpy as np

from gearopt.contact.kernels import gap_of, pinion_at
from gearopt.jit import compiled

__all__ = [
    "outline_rays",
    "outline_stations",
    "ray_samples",
    "ring_clearances",
    "separations",
    "swept_exits",
    "union_exits",
]


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


@compiled(inline=True)
def _swept(f, p, prev, nxt):
    """Pair ``p``'s swept separation: its own ``f[p]``, less the dip of the parabola through
    it and its neighbours' (``prev[p]``, ``nxt[p]``) where it is their finite minimum and
    the parabola opens upward (:func:`swept_exits`)."""
    swept = f[p]
    if prev[p] >= 0 and nxt[p] >= 0:
        fa, fd = f[prev[p]], f[nxt[p]]
        curv = fa - 2.0 * swept + fd
        finite = math.isfinite(fa) and math.isfinite(swept) and math.isfinite(fd)
        if finite and swept <= fa and swept <= fd and curv > 0.0:
            swept = swept - 0.125 * (fd - fa) ** 2 / curv
    return swept


# a pinion point (pinion_at's) before the first row's: each loop evaluates it at one call site
# (every inlined copy of it costs compile time), where a row's cell offset (none is -1) differs
_NO_POINT = (0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)

# the stages of a ray in swept_exits: the scan (pair by pair until one is inside); the whole
# field at the first sample out, at the one before and the one before that; the finer scan of
# the bracket (through a flank's boundary); the whole field at its sample out and its last in
_SCAN, _OUT, _BEFORE, _TWO_BEFORE, _ZOOM, _ZOOM_OUT, _ZOOM_IN = range(7)


@compiled
def swept_exits(rows, pinion, gear, zone, start, pair_row, prev, nxt, rays, tau, zoom, out):
    """:meth:`gearopt.mesh.zone.Zones.pattern_exits` into ``out``: ray k (``rays[k]``: origin,
    direction) of pairs ``start[k]:start[k + 1]`` (rows ``pair_row``, neighbours over the
    motion ``prev``, ``nxt``, -1 without) scanned at ``tau[k]`` up to its first exit, a sample
    inside once a pair is; the field whole only where it brackets the exit (the same result;
    at a sample found out, every pair's separation is known already); an exit through a
    flank's boundary on the finer scan ``zoom``.

    The pattern at a sample ``x``: while scanning, -1.0 inside, +1.0 out, trying the pair
    last found inside (``hint``) first and the others until one is inside; else the least
    swept separation minus the compound. Pair p's swept separation is its separation at its
    least over the motion, as ``gearopt.mesh.zone``'s ``_swept``: the parabola through it and
    its neighbours' where it is the least of the three; each separation evaluated once at a
    sample (``f``, ``have``; ``kept``: known from the last sample, there). A ray's samples
    are taken in one loop, stage by stage, each separation evaluated in it (a call taking
    the tables would reference and release each of their arrays, and an inlined helper
    taking them, across its branches: :mod:`gearopt.contact.kernels`): while scanning, the
    pairs tried until one is inside (its own separation first: its swept one is no more, so
    inside where it is); at the other stages every pair's separation in a loop of its own
    (none evaluated where the sample found out holds them all), then the least swept one."""
    lag, factor, s0, ds, t0, dt, last0, last1, c = zone
    grid = (s0, ds, t0, dt, last0, last1)
    cells, offsets = pinion[14], rows[5]
    f = np.empty(pair_row.shape[0])
    have = np.zeros(pair_row.shape[0], np.bool_)
    m, n_zoom = tau.shape[1], zoom.shape[0]
    for k in range(rays.shape[0]):
        a, b = start[k], start[k + 1]
        out[k] = 0.0
        if not b > a:
            continue
        hint = a
        stage, j, i = _SCAN, 0, 0
        t1 = t2 = g = gm1 = za = zb = fb = 0.0
        inside = out_first = False
        while True:
            searching, kept = False, False
            if stage == _SCAN:
                x, searching = tau[k, j], True
            elif stage == _OUT:
                x, kept = t2, True  # (every pair known: found out there)
            elif stage == _BEFORE:
                x = t1
            elif stage == _TWO_BEFORE:
                x = tau[k, j - 2]
            elif stage == _ZOOM:
                zb = t1 + (t2 - t1) * zoom[i]
                x, searching = zb, True
            elif stage == _ZOOM_OUT:
                x, kept = zb, not inside
            else:
                x = za
            # the pattern at x (the point's pinion terms at the first row's offset): while
            # scanning, the pairs tried until one is inside
            s = rays[k, 0] + x * rays[k, 2]
            t = rays[k, 1] + x * rays[k, 3]
            offset, point = -1, _NO_POINT
            at = _zone_at(s, t, grid)
            if searching:
                have[a:b] = False
                value = 1.0
                for n in range(-1, b - a):
                    p = hint if n < 0 else a + n
                    for q in (p, prev[p], nxt[p]):
                        if q >= 0 and not have[q]:
                            r = pair_row[q]
                            if offsets[r] != offset:
                                offset = offsets[r]
                                point = pinion_at(s, t, pinion, offset)
                            f[q] = _separation_of(rows, r, point, at, gear, cells, lag, factor)
                            have[q] = True
                        if f[p] < c:  # (inside: its swept separation is no more)
                            break
                    if f[p] < c or _swept(f, p, prev, nxt) < c:
                        hint = p
                        value = -1.0
                        break
            else:  # every pair's separation (known where kept: the sample found out), then
                if not kept:  # the least swept one
                    for q in range(a, b):
                        r = pair_row[q]
                        if offsets[r] != offset:
                            offset = offsets[r]
                            point = pinion_at(s, t, pinion, offset)
                        f[q] = _separation_of(rows, r, point, at, gear, cells, lag, factor)
                value = math.inf
                for p in range(a, b):
                    value = min(value, _swept(f, p, prev, nxt))
                value -= c
            # the next stage
            if stage == _SCAN:
                if value > 0.0:
                    if j == 0:
                        break
                    t1, t2, stage = tau[k, j - 1], tau[k, j], _OUT
                    continue
                j += 1
                if j == m:
                    out[k] = tau[k, m - 1]
                    break
            elif stage == _OUT:
                g = value
                stage = _BEFORE if math.isfinite(g) else (_ZOOM if n_zoom > 0 else _ZOOM_OUT)
            elif stage == _BEFORE:
                gm1 = value
                if j < 2:
                    out[k] = _crossing(tau[k, 0], math.nan, t1, gm1, t2, g)
                    break
                stage = _TWO_BEFORE
            elif stage == _TWO_BEFORE:
                out[k] = _crossing(tau[k, j - 2], value, t1, gm1, t2, g)
                break
            elif stage == _ZOOM:
                inside = value < 0.0
                if i >= 1 and (out_first or not inside or i == n_zoom - 1):
                    stage = _ZOOM_OUT
                    continue
                out_first = not inside
                za = zb
                i += 1
                if i == n_zoom:
                    stage = _ZOOM_OUT
            elif stage == _ZOOM_OUT:
                fb, stage = value, _ZOOM_IN
            else:
                out[k] = (
                    _crossing(za, math.nan, za, value, zb, fb)
                    if math.isfinite(fb)
                    else 0.5 * (za + zb)
                )
                break


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


@compiled
def separations(rows, pinion, gear, zone, r, points, out):
    """:meth:`gearopt.mesh.zone.Zones.separation` of rows ``r`` ``(K,)`` at one point each,
    ``points`` ``(K, 2)`` (face, profile), into ``out`` ``(K,)`` (+inf off the flanks): on the
    tables the zones' other kernels take, without the rows' set-up of a clearance
    evaluation."""
    lag, factor, s0, ds, t0, dt, last0, last1, c = zone
    grid = (s0, ds, t0, dt, last0, last1)
    cells, offsets = pinion[14], rows[5]
    for k in range(r.shape[0]):
        row = r[k]
        s, t = points[k, 0], points[k, 1]
        point = pinion_at(s, t, pinion, offsets[row])
        at = _zone_at(s, t, grid)
        out[k] = _separation_of(rows, row, point, at, gear, cells, lag, factor)


@compiled
def ring_clearances(rows, pinion, gear, r, face, profile, ring, delta):
    """The clearance of rows ``r`` ``(K,)`` at points ``(face[k], profile[k])`` and on the
    ring about each, ``ring`` ``(M, 2)`` offsets, into ``delta`` ``(K, 1 + M)`` (the point
    first; the smooth extension beyond the flanks, as
    :meth:`gearopt.contact.JointField.clearance_at_grid`'s): the samples of
    :meth:`gearopt.mesh.zone.Zones.quadratic`, on the tables the zones' other kernels take."""
    cells, offsets = pinion[14], rows[5]
    for k in range(r.shape[0]):
        row = r[k]
        for j in range(delta.shape[1]):
            s, t = face[k], profile[k]
            if j > 0:
                s, t = s + ring[j - 1, 0], t + ring[j - 1, 1]
            point = pinion_at(s, t, pinion, offsets[row])
            delta[k, j] = gap_of(rows, row, point, gear, cells)[0]


@compiled
def ray_samples(rays, box, reach, spread, even, geometric, tau):
    """The samples of rays ``rays`` ``(K, 4)`` (origin, direction) into ``tau`` ``(K, m)``:
    ray k scanned to the grid's edge (the box ``(low face, low profile, high face, high
    profile)``; :meth:`gearopt.mesh.zone.Zones.to_edge`) or ``reach[k]`` if nearer, at the
    fractions ``even`` where ``spread[k]``, else ``geometric`` (each ``(m,)``). NaN
    propagates as numpy's minimum and maximum."""
    for k in range(rays.shape[0]):
        e0 = e1 = math.inf
        if rays[k, 2] > 0.0:
            e0 = (box[2] - rays[k, 0]) / rays[k, 2]
        elif rays[k, 2] < 0.0:
            e0 = (box[0] - rays[k, 0]) / rays[k, 2]
        if rays[k, 3] > 0.0:
            e1 = (box[3] - rays[k, 1]) / rays[k, 3]
        elif rays[k, 3] < 0.0:
            e1 = (box[1] - rays[k, 1]) / rays[k, 3]
        if e0 != e0 or e1 != e1:
            edge = math.nan
        else:  # (numpy's maximum with 0: a zero of either sign is +0)
            edge = min(e0, e1)
            edge = edge if edge > 0.0 else 0.0
        far = reach[k]
        if far != far or edge != edge:
            far = math.nan
        else:
            far = min(far, edge)
        fractions = even if spread[k] else geometric
        for j in range(tau.shape[1]):
            tau[k, j] = far * fractions[j]


@compiled
def outline_stations(u, sep, compound, low, high, most, out):
    """The stations of :meth:`gearopt.mesh.zone.Zones.outline` into ``out`` ``(n,)``, their
    count returned: the rows inside their own zones (``sep <= compound``) with relative
    rotations ``u`` in ``[low, high]``, one per rotation rounded to 1e-9 (the first; numpy's
    ``unique(rint(u * 1e9), return_index=True)``, by a stable insertion sort), in order of it,
    at most ``most`` evenly (``linspace(0, n - 1, most)`` rounded, as numpy's)."""
    n = u.shape[0]
    index, key = np.empty(n, np.intp), np.empty(n)
    m = 0
    for i in range(n):
        if sep[i] <= compound and u[i] >= low and u[i] <= high:
            x, j = np.rint(u[i] * 1e9), m
            while j > 0 and key[j - 1] > x:  # (stable: an equal key stays behind)
                key[j], index[j] = key[j - 1], index[j - 1]
                j -= 1
            key[j], index[j] = x, i
            m += 1
    count = 0
    for j in range(m):
        if j == 0 or key[j] != key[j - 1]:
            out[count] = index[j]
            count += 1
    if count > most:  # (the rounded steps exceed one: distinct and increasing, so in place)
        step = (count - 1.0) / (most - 1)
        for i in range(most):
            at = float(count - 1) if i == most - 1 else i * step
            out[i] = out[int(np.rint(at))]
        count = most
    return count


@compiled
def outline_rays(c, contact, reach, origins, directions, ray, near):
    """The rays of :meth:`gearopt.mesh.zone.Zones.outline` from its stations ``c`` ``(n, 2)``
    (``n >= 2``): the path's tangent at each (central differences, one-sided at the ends, as
    numpy's ``gradient``; unit), rays across it either way from every station, then along
    it outward from the first and the last, into ``origins`` and ``directions`` ``(2n + 2,
    2)``; each ray's rows, those of ``contact`` ``(P, 2)`` within ``reach`` of its station
    along the path, as ``(ray, near)`` pairs in numpy's ``nonzero`` order, their count
    returned."""
    n, p = c.shape[0], contact.shape[0]
    tangent = np.empty((n, 2))
    for i in range(n):
        a, b = max(i - 1, 0), min(i + 1, n - 1)
        for d in range(2):
            if 0 < i < n - 1:
                tangent[i, d] = (c[b, d] - c[a, d]) / 2.0
            else:
                tangent[i, d] = c[b, d] - c[a, d]
        norm = np.hypot(tangent[i, 0], tangent[i, 1])
        norm = norm if not norm < 1e-300 else 1e-300  # (numpy's maximum: NaN propagates)
        tangent[i, 0], tangent[i, 1] = tangent[i, 0] / norm, tangent[i, 1] / norm
    for i in range(2 * n + 2):
        at = i % n if i < 2 * n else (0 if i == 2 * n else n - 1)
        origins[i, 0], origins[i, 1] = c[at, 0], c[at, 1]
        if i < n:
            directions[i, 0], directions[i, 1] = -tangent[at, 1], tangent[at, 0]
        elif i < 2 * n:
            directions[i, 0], directions[i, 1] = tangent[at, 1], -tangent[at, 0]
        elif i == 2 * n:
            directions[i, 0], directions[i, 1] = -tangent[at, 0], -tangent[at, 1]
        else:
            directions[i, 0], directions[i, 1] = tangent[at, 0], tangent[at, 1]
    count = 0
    for i in range(2 * n + 2):
        at = i % n if i < 2 * n else (0 if i == 2 * n else n - 1)
        for j in range(p):
            offset = abs(
                (contact[j, 0] - c[at, 0]) * tangent[at, 0]
                + (contact[j, 1] - c[at, 1]) * tangent[at, 1]
            )
            if offset <= reach:
                ray[count], near[count] = i, j
                count += 1
    return count
