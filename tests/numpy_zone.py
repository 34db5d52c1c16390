"""The zones' scans in whole-array numpy (:meth:`gearopt.mesh.zone.Zones.exits`,
:meth:`~gearopt.mesh.zone.Zones.pattern_exits`,
:meth:`~gearopt.mesh.zone.Zones.point_separations` and :meth:`~gearopt.mesh.zone.Zones.quadratic`
before their compiled kernels, :func:`gearopt.contact.zone_kernels.union_exits`,
:func:`~gearopt.contact.zone_kernels.swept_exits`,
:func:`~gearopt.contact.zone_kernels.separations` and
:func:`~gearopt.contact.zone_kernels.ring_clearances`):
every sample of every ray evaluated through :meth:`gearopt.mesh.zone.Zones.along` (the
engine's point clearance, itself the numpy reference under :func:`tests.numpy_engine.install`).
Kept for the kernels' parity test; production code never imports this module.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from gearopt.mesh.zone import NEAR, RING, RING_FIT, SCAN, SPREAD, ZOOM, Zones

#: the methods of :class:`gearopt.mesh.zone.Zones` this module replaces
METHODS = {
    "exits": "zone_exits",
    "pattern_exits": "zone_pattern_exits",
    "point_separations": "zone_point_separations",
    "quadratic": "zone_quadratic",
}


def install(monkeypatch) -> None:
    """Put the numpy scans in place of the zones' compiled ones."""
    for name, ours in METHODS.items():
        monkeypatch.setattr(Zones, name, globals()[ours])


def zone_point_separations(self, r, points) -> NDArray:
    """:meth:`gearopt.mesh.zone.Zones.point_separations` by :meth:`~gearopt.mesh.zone.Zones.
    separation` (the engine's point clearance)."""
    points = np.asarray(points, float).reshape(-1, 2)
    return self.separation(np.asarray(r, np.intp), points[:, :1], points[:, 1:])[:, 0]


def zone_quadratic(self, r, face_mm, profile_mm) -> NDArray:
    """:meth:`gearopt.mesh.zone.Zones.quadratic` by :meth:`~gearopt.mesh.zone.Zones.clearance`
    (the engine's point clearance) on the ring about each point."""
    face_mm, profile_mm = np.asarray(face_mm, float), np.asarray(profile_mm, float)
    s = np.concatenate([face_mm[:, None], face_mm[:, None] + RING[:, 0]], 1)
    h = np.concatenate([profile_mm[:, None], profile_mm[:, None] + RING[:, 1]], 1)
    delta, _ = self.clearance(np.asarray(r, np.intp), s, h)
    return (delta[:, 1:] - delta[:, :1]) @ RING_FIT.T


def zone_exits(self, ray, r, origins, directions, reach) -> NDArray:
    """How far rays leave the union of zones.

    Parameters
    ----------
    ray, r
        ``(P,)``: pair p puts the zone of row ``r[p]`` on ray ``ray[p]``.
    origins, directions
        ``(K, 2)`` the rays' origins and unit directions in grid coordinates.
    reach
        ``(K,)`` how far each ray is scanned at most (the grid's edge comes first).

    Returns
    -------
    NDArray
        ``(K,)`` the distance from each origin to its first exit from the union of its
        zones (0 where the origin is out of them; the reach where no exit is found).
    """
    ray, r = np.asarray(ray, np.intp), np.asarray(r, np.intp)
    origins, directions = np.asarray(origins, float), np.asarray(directions, float)
    k_rays, c = len(origins), self.compound_mm
    tau = np.minimum(reach, self.to_edge(origins, directions))[:, None] * SCAN[None, :]
    f = self.along(ray, r, origins, directions, tau[ray]) - c
    inside = f < 0.0
    held = np.zeros((k_rays, len(SCAN)), bool)
    np.logical_or.at(held, ray, inside)
    first = np.argmax(~held, axis=1)  # the first sample out of every zone (0: none)
    through = held.all(axis=1)
    result = np.where(through, tau[:, -1], 0.0)
    j = first[ray]
    p_on = np.flatnonzero((j > 0) & inside[np.arange(len(ray)), np.maximum(j - 1, 0)])
    if not p_on.size:
        return result
    jj = j[p_on]
    t1, t2 = tau[ray[p_on], jj - 1], tau[ray[p_on], jj]
    f1, f2 = f[p_on, jj - 1], f[p_on, jj]
    t0 = tau[ray[p_on], np.maximum(jj - 2, 0)]
    f0 = np.where(jj >= 2, f[p_on, np.maximum(jj - 2, 0)], np.nan)
    crossing = _crossing(t0, f0, t1, f1, t2, f2)
    # an exit through a flank's boundary: the finer scan of its bracket
    edge = ~np.isfinite(f2)
    if edge.any():
        pe = p_on[edge]
        w = np.linspace(0.0, 1.0, ZOOM)
        tz = t1[edge, None] + (t2[edge] - t1[edge])[:, None] * w[None, :]
        fz = self.along(ray[pe], r[pe], origins, directions, tz) - c
        out = ~(fz < 0.0)
        out[:, -1] = True
        m = np.maximum(np.argmax(out, axis=1), 1)
        at = np.arange(len(pe))
        za, zb, fa, fb = tz[at, m - 1], tz[at, m], fz[at, m - 1], fz[at, m]
        crossing[edge] = np.where(
            np.isfinite(fb), _crossing(za, np.nan, za, fa, zb, fb), 0.5 * (za + zb)
        )
    np.maximum.at(result, ray[p_on], crossing)
    return np.where(through, tau[:, -1], result)


def zone_pattern_exits(self, ray, r, key, position, origins, directions, spread) -> NDArray:
    """How far rays run from their origins inside the pattern the zones of rows sweep.

    The pattern at a point is its least separation over the motion: over the rows of one
    tooth pair (``key``) at consecutive positions (``position``), the least of their
    separations refined by the parabola through it and its neighbours' (as the TE peak:
    the zones of discrete positions leave gaps that the motion fills), then the least over
    the pairs. Each ray is scanned at :data:`SPREAD` (``spread``) or :data:`NEAR` fractions
    of the way to the grid's edge; its first exit, by inverse quadratic interpolation of
    that field, or through a flank's boundary by a finer scan (:data:`ZOOM`).

    Parameters
    ----------
    ray, r, key, position
        ``(P,)``: row ``r[p]`` of tooth pair ``key[p]`` at ``position[p]`` on ray
        ``ray[p]``.
    origins, directions
        ``(K, 2)`` the rays' origins and unit directions in grid coordinates.
    spread
        ``(K,)`` True to scan a ray evenly, False at geometric steps from its origin.

    Returns
    -------
    NDArray
        ``(K,)`` the distance to each ray's first exit (0 where its origin is out).
    """
    ray, r = np.asarray(ray, np.intp), np.asarray(r, np.intp)
    origins, directions = np.asarray(origins, float), np.asarray(directions, float)
    k_rays, c = len(origins), self.compound_mm
    prev, nxt = neighbours(ray, np.asarray(key), np.asarray(position))
    starts = np.flatnonzero(np.r_[True, np.diff(ray) != 0])
    if np.any(np.diff(ray) < 0) or len(starts) != k_rays:
        raise ValueError("pattern_exits: every ray's pairs, in order of the rays")
    fractions = np.where(np.asarray(spread, bool)[:, None], SPREAD[None, :], NEAR[None, :])
    tau = self.to_edge(origins, directions)[:, None] * fractions

    def field(t, pick=None):  # the pattern's least separation minus the compound at t
        if pick is None:  # (K, M): every ray
            f = self.along(ray, r, origins, directions, t[ray])
            g = _swept(f, prev, nxt)
        else:  # the pairs ``pick`` (whole rays) only
            f = np.full((len(ray), t.shape[1]), np.inf)
            f[pick] = self.along(ray[pick], r[pick], origins, directions, t[ray[pick]])
            g = _swept(f, prev, nxt)
        return np.minimum.reduceat(g, starts, axis=0) - c

    g = field(tau)
    inside = g < 0.0
    first = np.argmax(~inside, axis=1)
    result = np.where(inside.all(axis=1), tau[:, -1], 0.0)
    k = np.flatnonzero(inside[:, 0] & ~inside.all(axis=1))
    if not k.size:
        return result
    j = first[k]
    t1, t2, f1, f2 = tau[k, j - 1], tau[k, j], g[k, j - 1], g[k, j]
    t0 = tau[k, np.maximum(j - 2, 0)]
    f0 = np.where(j >= 2, g[k, np.maximum(j - 2, 0)], np.nan)
    result[k] = _crossing(t0, f0, t1, f1, t2, f2)
    edge = k[~np.isfinite(f2)]
    if edge.size:
        lo, hi = tau[edge, first[edge] - 1], tau[edge, first[edge]]
        w = np.linspace(0.0, 1.0, ZOOM)
        for _ in range(1):
            tz = np.zeros((k_rays, ZOOM))
            tz[edge] = lo[:, None] + (hi - lo)[:, None] * w[None, :]
            gz = field(tz, np.flatnonzero(np.isin(ray, edge)))[edge]
            out = ~(gz < 0.0)
            out[:, -1] = True
            m = np.maximum(np.argmax(out, axis=1), 1)
            at = np.arange(len(edge))
            lo, hi = tz[edge, m - 1], tz[edge, m]
            fa, fb = gz[at, m - 1], gz[at, m]
        result[edge] = np.where(
            np.isfinite(fb), _crossing(lo, np.nan, lo, fa, hi, fb), 0.5 * (lo + hi)
        )
    return result


def _crossing(t0, f0, t1, f1, t2, f2) -> NDArray:
    """Where f crosses zero between ``(t1, f1 < 0)`` and ``(t2, f2 >= 0)``: inverse quadratic
    interpolation through the three samples where f rises through them, else linear;
    ``t2`` where ``f2`` is not finite (the bracket's far end is off the flanks)."""
    with np.errstate(invalid="ignore", divide="ignore"):
        linear = t1 + (t2 - t1) * f1 / (f1 - f2)
        quad = (
            t0 * f1 * f2 / ((f0 - f1) * (f0 - f2))
            + t1 * f0 * f2 / ((f1 - f0) * (f1 - f2))
            + t2 * f0 * f1 / ((f2 - f0) * (f2 - f1))
        )
    good = np.isfinite(quad) & (f0 < f1) & (quad >= t1) & (quad <= t2)
    out = np.where(good, quad, linear)
    return np.where(np.isfinite(f2), out, t2)


def _swept(f, prev, nxt) -> NDArray:
    """The separations ``f`` ``(P, M)`` of rows at their least over the motion: where a row's
    is the least of its pair's neighbouring positions' (``prev``, ``nxt``: their rows, -1
    without), the vertex of the parabola through the three; else its own."""
    both = (prev >= 0) & (nxt >= 0)
    out = f.copy()
    if not both.any():
        return out
    i = np.flatnonzero(both)
    a, b, d = f[prev[i]], f[i], f[nxt[i]]
    with np.errstate(invalid="ignore"):
        curv = a - 2.0 * b + d
        low = np.isfinite(a) & np.isfinite(b) & np.isfinite(d) & (b <= a) & (b <= d) & (curv > 0)
        vertex = b - 0.125 * (d - a) ** 2 / np.where(low, curv, 1.0)
    out[i] = np.where(low, vertex, b)
    return out


def neighbours(ray, key, position) -> tuple[NDArray, NDArray]:
    """The rows of the same ray and tooth pair at the previous and next positions (-1
    without)."""
    order = np.lexsort((position, key, ray))
    same = (np.diff(ray[order]) == 0) & (np.diff(key[order]) == 0)
    step = same & (np.diff(position[order]) == 1)
    prev, nxt = np.full(len(ray), -1, np.intp), np.full(len(ray), -1, np.intp)
    prev[order[1:][step]] = order[:-1][step]
    nxt[order[:-1][step]] = order[1:][step]
    return prev, nxt
