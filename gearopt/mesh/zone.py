"""The marking-compound zones measured on the refined field: chords of the region where the
separation from the mating flank is below the marking compound (seed 003 section 5), found by
root-finding along rays on the flanks' local Hermite interpolants
(:meth:`gearopt.contact.JointField.clearance_at_grid`), the field the TE is refined on, so
that they converge with the grid instead of moving with its nodes.

- The instantaneous zone's axes come from the separation's local quadratic form at the
  contact point (the tangency point, the clearance minimum; a least-squares fit on a ring of
  radius :data:`RING_MM`): the major axis along its least curvature (along the line of a line
  contact), the minor across it.
- A chord along an axis runs between the first exits from the zone on either side of its
  origin: the rays are scanned at :data:`SCAN` fractions of their reach, each crossing of the
  separation through the compound then solved by inverse quadratic interpolation through the
  last samples, and an exit through a flank's boundary located on a finer scan of its bracket
  (:data:`ZOOM` samples).
- Seed 003 section 6 simplifies the contact ellipse to its major axis, "the middle of the
  segment is situated on the contact line": a zone's centre is the middle of its major chord
  through the contact point, and the minor axis is the chord across it through that centre.
- The pattern the motion sweeps (:meth:`Zones.pattern_exits`): at a point, the least
  separation over the motion (over a tooth pair's positions, the parabola through the least
  and its neighbours: the zones of discrete positions leave gaps that the motion fills); its
  extent along a ray, found as a chord's.

- The pattern's outline (:meth:`Zones.outline`): rays across the path from the contact points
  of the positions inside the contact interval (at most :data:`STATIONS`), and along it from
  the first and the last, run to the pattern's edge as the width's.
- A point contact's outline stations are its tangency points (:meth:`Zones.tangency_points`):
  the sampled minima stop at the engine's refinement margin above the generated boundary.
- Point contact or line contact (:meth:`Zones.closed`): whether the zone closes on the flanks
  along its valley (:meth:`Zones.valley`), for a flat lag, which either can have.
- The zones end at the pinion's generated boundary, continuous across the grid (the
  evaluations' ``generated`` tables, :func:`gearopt.contact.engine.node_tables`: the
  envelope's fold solved per face column), not at the nodes or the refinement's margin.

The separation at a point is the angular clearance above the row's lag times the node factor
(normal or circumferential, :func:`gearopt.mesh.pattern.separation_mm`) interpolated
bilinearly (the node below each column's lowest generated node continued from the two above
it, :func:`extended_factors`): a smooth geometric factor, exact at the nodes, whose
interpolation error is of second order in the cell size on a quantity that varies by a few per
cent over a zone.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import NDArray

from gearopt.contact import JointField, zone_kernels
from gearopt.mesh import kernels

__all__ = [
    "NEAR",
    "RING",
    "RING_ANGLES",
    "RING_FIT",
    "RING_MM",
    "SCAN",
    "SPREAD",
    "STATIONS",
    "VALLEY",
    "ZOOM",
    "ZoneRows",
    "Zones",
    "extended_factors",
]

#: radius of the ring on which the separation's quadratic form is fitted (mm): well inside
#: the thinnest zone's half-width at the marking compounds in use, and over a patch on which
#: the separation is quadratic to rounding
RING_MM = 0.1
#: the rays' samples as fractions of their reach: the origin, then geometric steps of 7.7 %
#: from a thousandth of the reach
SCAN = np.concatenate([[0.0], np.geomspace(1e-3, 1.0, 92)])
#: samples of the finer scan of a bracket through a flank's boundary (0.24 % of its reach)
ZOOM = 33
#: the scans of :meth:`Zones.pattern_exits` (fractions of the way to the grid's edge):
#: geometric steps of 16 % from a thousandth of it, for a zone around the ray's origin; even
#: steps of 2 %, for the zones the motion sweeps over the ray
NEAR = np.concatenate([[0.0], np.geomspace(1e-3, 1.0, 31)])
SPREAD = np.linspace(0.0, 1.0, 32)
#: the most stations of :meth:`Zones.outline` along the path
STATIONS = 12
#: samples across a zone's major axis at each station of :meth:`Zones.closed` (over the grid)
VALLEY = 49

_ZOOM_FRACTIONS = np.linspace(0.0, 1.0, ZOOM)
#: the ring of :meth:`Zones.quadratic`: 8 points RING_MM around a point
RING_ANGLES = np.linspace(0.0, 2.0 * np.pi, 8, endpoint=False)
RING = RING_MM * np.stack([np.cos(RING_ANGLES), np.sin(RING_ANGLES)], axis=1)
#: least-squares map from the ring's clearance rises to (g_s, g_h, H_ss, H_sh, H_hh)
RING_FIT = np.linalg.pinv(
    np.stack(
        [
            RING[:, 0],
            RING[:, 1],
            0.5 * RING[:, 0] ** 2,
            RING[:, 0] * RING[:, 1],
            0.5 * RING[:, 1] ** 2,
        ],
        axis=1,
    )
)


@dataclass(frozen=True, kw_only=True)
class ZoneRows:
    """The field's rows the zones are measured on.

    Attributes
    ----------
    side
        ``(R,)`` each row's field in the joint field.
    phi_rad
        ``(R,)`` the pinion angle (the field's, as sampled).
    lag_rad
        ``(R,)`` the gear's lag: the clearance of the contact, separation zero.
    factor_mm
        ``(R, n_f, n_p)`` mm of separation per rad of clearance at the nodes.
    """

    side: NDArray
    phi_rad: NDArray
    lag_rad: NDArray
    factor_mm: NDArray


class Zones:
    """Chords of the marking-compound zones of several rows on the refined field.

    Parameters
    ----------
    joint
        The joint field of the rows' sides.
    face_mm, profile_mm
        The pinion grid's node coordinates (uniform, shared by the sides).
    rows
        The rows.
    compound_mm
        The marking compound.
    owned
        True where ``rows.factor_mm`` is a C-contiguous copy made for these zones: it is
        extended in place (:func:`extended_factors`) rather than copied.
    """

    def __init__(
        self, joint: JointField, face_mm, profile_mm, rows: ZoneRows, compound_mm, *, owned=False
    ):
        if owned:  # the caller's copy, extended in place
            kernels.extend_factors(rows.factor_mm)
        else:
            rows = replace(rows, factor_mm=extended_factors(rows.factor_mm))
        self.joint, self.rows, self.compound_mm = joint, rows, float(compound_mm)
        self.face0, self.dface = float(face_mm[0]), float(face_mm[1] - face_mm[0])
        self.profile0, self.dprofile = float(profile_mm[0]), float(profile_mm[1] - profile_mm[0])
        self.last = (len(face_mm) - 2, len(profile_mm) - 2)
        face_end = self.face0 + self.dface * (self.last[0] + 1)
        profile_end = self.profile0 + self.dprofile * (self.last[1] + 1)
        # the grid's edges (:meth:`to_edge`): low face, low profile, high face, high profile
        self.box = np.array([self.face0, self.profile0, face_end, profile_end])
        self._tables: tuple | None = None

    def clearance(self, r, s, h) -> tuple[NDArray, NDArray]:
        """``(clearance_rad, valid)`` of rows ``r`` ``(K,)`` at grid points ``(K, M)`` (valid up
        to the pinion's generated boundary)."""
        rows = self.rows
        return self.joint.clearance_at_grid(
            rows.side[r][:, None], s, h, rows.phi_rad[r][:, None], generated=True
        )

    def factor(self, r, s, h) -> NDArray:
        """The node factor of rows ``r`` ``(K,)`` interpolated bilinearly at ``(K, M)``."""
        x = np.clip((s - self.face0) / self.dface, 0.0, self.last[0] + 1.0)
        y = np.clip((h - self.profile0) / self.dprofile, 0.0, self.last[1] + 1.0)
        i = np.minimum(x.astype(np.intp), self.last[0])
        j = np.minimum(y.astype(np.intp), self.last[1])
        u, v = x - i, y - j
        f = self.rows.factor_mm
        n_p = f.shape[2]
        at = (np.asarray(r, np.intp) * (f.shape[1] * n_p))[:, None] + i * n_p + j
        flat = f.reshape(-1)
        return (1.0 - u) * ((1.0 - v) * flat[at] + v * flat[at + 1]) + u * (
            (1.0 - v) * flat[at + n_p] + v * flat[at + n_p + 1]
        )

    def separation(self, r, s, h) -> NDArray:
        """Separation (mm) of rows ``r`` ``(K,)`` at grid points ``(K, M)``; +inf off the
        flanks."""
        delta, valid = self.clearance(r, s, h)
        sep = (delta - self.rows.lag_rad[r][:, None]) * self.factor(r, s, h)
        return np.where(valid, sep, np.inf)

    def point_separations(self, r, points) -> NDArray:
        """:meth:`separation` of rows ``r`` ``(K,)`` at one point each, ``points`` ``(K, 2)``
        (:func:`gearopt.contact.zone_kernels.separations`, on the zones' tables)."""
        out = np.empty(len(points))
        zone_kernels.separations(
            *self.tables(), np.asarray(r, np.intp), np.ascontiguousarray(points, float), out
        )
        return out

    def quadratic(self, r, face_mm, profile_mm) -> NDArray:
        """``(K, 5)`` the clearance's local quadratic form about points ``(face_mm,
        profile_mm)`` of rows ``r``: ``(g_s, g_h, H_ss, H_sh, H_hh)`` (rad per mm, per mm^2),
        fitted on a ring of radius :data:`RING_MM` (least squares)."""
        face_mm = np.ascontiguousarray(face_mm, float)
        delta = np.empty((len(face_mm), 1 + len(RING)))
        zone_kernels.ring_clearances(
            *self.tables()[:3],
            np.asarray(r, np.intp),
            face_mm,
            np.ascontiguousarray(profile_mm, float),
            RING,
            delta,
        )
        return (delta[:, 1:] - delta[:, :1]) @ RING_FIT.T

    def axes(self, r, face_mm, profile_mm) -> NDArray:
        """``(K, 2)`` unit vectors (face, profile) of the major axes of the zones of rows
        ``r`` at their contact points: the direction of least curvature of the clearance's
        quadratic form (:meth:`quadratic`)."""
        c = self.quadratic(r, face_mm, profile_mm)
        # the largest curvature's direction, 0.5 atan2(2 H_sh, H_ss - H_hh); the major axis
        # across it
        across = 0.5 * np.arctan2(2.0 * c[:, 3], c[:, 2] - c[:, 4])
        major = np.empty((len(across), 2))  # (np.stack's columns, without its overhead)
        major[:, 0], major[:, 1] = -np.sin(across), np.cos(across)
        return major

    def tangency_points(self, r, contact_mm, steps: int = 4) -> NDArray:
        """``(K, 2)`` the tangency points of rows ``r`` (the clearance's minimum on the
        flanks' smooth extension, Litvin's: :func:`gearopt.contact.kernels.tangency`) from the
        contact points ``contact_mm`` ``(K, 2)``: Newton's steps on the quadratic form
        (:meth:`quadratic`), where it is positive definite (a point contact's unique minimum),
        up to two mm each. A point that ends off the flanks keeps its contact point. The
        sampled minima stop at the engine's refinement margin above the generated boundary
        (two cells: grid-dependent); the tangency point does not."""
        r = np.asarray(r, np.intp)
        x = np.array(contact_mm, float)
        for _ in range(steps):
            g_s, g_h, h_ss, h_sh, h_hh = self.quadratic(r, x[:, 0], x[:, 1]).T
            det = h_ss * h_hh - h_sh * h_sh
            ok = (h_ss > 0.0) & (det > 0.0)
            det = np.where(ok, det, 1.0)
            step = -np.stack([h_hh * g_s - h_sh * g_h, h_ss * g_h - h_sh * g_s], 1) / det[:, None]
            length = np.hypot(step[:, 0], step[:, 1])
            step *= np.minimum(1.0, 2.0 / np.maximum(length, 1e-300))[:, None]
            x = np.where(ok[:, None], x + step, x)
        _, valid = self.clearance(r, x[:, :1], x[:, 1:])
        return np.where(valid, x, contact_mm)

    def closed(self, r, face_mm, profile_mm) -> NDArray:
        """``(K,)`` True where the zone of row ``r`` around its contact point closes on the
        flanks along its valley both ways (:meth:`valley`): a point contact, not a line
        contact.

        The separation's valley runs from the contact point along the major axis (:meth:`axes`,
        the quadratic form's least curvature kappa): the least separation across it rises as
        kappa t^2 / 2 at a distance t. A point contact's zone (seed 003 section 5's contact
        ellipse) ends where that rise reaches the compound; a line contact's kappa is zero, its
        valley the contact line, on which the separation is the interpolants' error (some
        0.01 um, far below any compound) up to the flanks' edges, however the line curves. A
        way closes where a station's least separation exceeds the compound before the valley
        leaves the flanks. Measured on the zone's scale, not the grid's.
        """
        k = len(np.atleast_1d(r))
        _, least, inside = self.valley(r, face_mm, profile_mm)
        n = least.shape[1]
        above = inside & (least > self.compound_mm)
        first_out = np.where((~inside).any(axis=1), np.argmax(~inside, axis=1), n)
        first_above = np.where(above.any(axis=1), np.argmax(above, axis=1), n)
        closes = first_above < first_out
        return closes[:k] & closes[k:]

    def valley(self, r, face_mm, profile_mm) -> tuple[NDArray, NDArray, NDArray]:
        """The valley of the separation of rows ``r`` from their contact points along the
        major axes (:meth:`axes`) either way.

        Stations at :data:`SPREAD` fractions of the way to the grid's edge along the axis; at
        each, the least separation across it: :data:`VALLEY` samples over the grid, the
        parabola through the least and its neighbours.

        Returns
        -------
        tuple of NDArray
            ``(distance_mm, least_mm, inside)``, each ``(2K, n)``: rows ``0..K-1`` along the
            major axes, ``K..2K-1`` the other way; ``inside`` False where the least is not
            between samples on the flanks (the valley is off them there).
        """
        r = np.atleast_1d(np.asarray(r, np.intp))
        face_mm, profile_mm = np.atleast_1d(face_mm), np.atleast_1d(profile_mm)
        major = self.axes(r, face_mm, profile_mm)
        origins = np.tile(np.stack([face_mm, profile_mm], axis=1).astype(float), (2, 1))
        directions = np.concatenate([major, -major])
        tau = self.to_edge(origins, directions)[:, None] * SPREAD[None, 1:]  # (2K, n)
        n = tau.shape[1]
        stations = (origins[:, None, :] + tau[..., None] * directions[:, None, :]).reshape(-1, 2)
        across = np.repeat(np.stack([-directions[:, 1], directions[:, 0]], axis=1), n, axis=0)
        low = -self.to_edge(stations, -across)
        high = self.to_edge(stations, across)
        offsets = low[:, None] + (high - low)[:, None] * np.linspace(0.0, 1.0, VALLEY)[None, :]
        s = stations[:, :1] + offsets * across[:, :1]
        h = stations[:, 1:] + offsets * across[:, 1:]
        sep = self.separation(np.repeat(np.tile(r, 2), n), s, h)  # (2K n, VALLEY)
        on = np.isfinite(sep)
        j = np.argmin(np.where(on, sep, np.inf), axis=1)
        rows = np.arange(len(j))
        jm, jp = np.maximum(j - 1, 0), np.minimum(j + 1, VALLEY - 1)
        inside = on[rows, j] & (j > 0) & (j < VALLEY - 1) & on[rows, jm] & on[rows, jp]
        y0, ym, yp = sep[rows, j], sep[rows, jm], sep[rows, jp]
        with np.errstate(invalid="ignore", divide="ignore"):
            curvature = ym - 2.0 * y0 + yp
            least = np.where(curvature > 0.0, y0 - (yp - ym) ** 2 / (8.0 * curvature), y0)
        return tau, np.where(inside, least, np.nan).reshape(-1, n), inside.reshape(-1, n)

    def exits(self, ray, r, origins, directions, reach) -> NDArray:
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

        Notes
        -----
        Each ray is scanned at :data:`SCAN` fractions of its reach up to its first sample out
        of every zone; each zone that held it up to there gives its separation's crossing
        through the compound (inverse quadratic interpolation through the last samples, or
        through a flank's boundary on a finer scan of the bracket, :data:`ZOOM` samples); the
        farthest is the exit (:func:`gearopt.contact.zone_kernels.union_exits`).
        """
        ray, r = np.asarray(ray, np.intp), np.asarray(r, np.intp)
        order = np.argsort(ray, kind="stable")
        start = np.searchsorted(ray[order], np.arange(len(origins) + 1))
        return self._union_exits(start, r[order], origins, directions, reach)

    def _union_exits(self, start, r, origins, directions, reach) -> NDArray:
        """:meth:`exits` on the pairs in order of their rays, ray k's
        ``r[start[k]:start[k + 1]]``."""
        origins, directions = np.asarray(origins, float), np.asarray(directions, float)
        k_rays = len(origins)
        rays = self.rays(origins, directions)
        reach_mm, reach = reach, np.empty(k_rays)  # (writable)
        reach[:] = reach_mm
        tau = np.empty((k_rays, len(SCAN)))  # (to the grid's edge or the reach: to_edge's)
        zone_kernels.ray_samples(rays, self.box, reach, np.ones(k_rays, bool), SCAN, SCAN, tau)
        out = np.empty(k_rays)
        zone_kernels.union_exits(*self.tables(), start, r, rays, tau, _ZOOM_FRACTIONS, out)
        return out

    def pattern_exits(self, ray, r, key, position, origins, directions, spread) -> NDArray:
        """How far rays run from their origins inside the pattern the zones of rows sweep.

        The pattern at a point is its least separation over the motion: over the rows of one
        tooth pair (``key``) at consecutive positions (``position``), the least of their
        separations refined by the parabola through it and its neighbours' (as the TE peak:
        the zones of discrete positions leave gaps that the motion fills), then the least over
        the pairs. Each ray is scanned at :data:`SPREAD` (``spread``) or :data:`NEAR` fractions
        of the way to the grid's edge up to its first exit, located by inverse quadratic
        interpolation of that field, or through a flank's boundary by a finer scan
        (:data:`ZOOM`; :func:`gearopt.contact.zone_kernels.swept_exits`).

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
        k_rays = len(origins)
        prev, nxt, start = np.empty_like(ray), np.empty_like(ray), np.empty(len(ray) + 2, np.intp)
        found, ordered = kernels.swept_pairs(
            ray, np.asarray(key, np.int64), np.asarray(position, np.int64), prev, nxt, start
        )
        if not ordered or found != k_rays:
            raise ValueError("pattern_exits: every ray's pairs, in order of the rays")
        rays = self.rays(origins, directions)
        tau = np.empty((k_rays, len(SPREAD)))  # (to the grid's edge: to_edge's)
        zone_kernels.ray_samples(
            rays,
            self.box,
            np.full(k_rays, np.inf),
            np.ascontiguousarray(spread, bool),
            SPREAD,
            NEAR,
            tau,
        )
        out = np.empty(k_rays)
        zone_kernels.swept_exits(
            *self.tables(),
            start[: found + 1],
            r,
            prev,
            nxt,
            rays,
            tau,
            _ZOOM_FRACTIONS,
            out,
        )
        return out

    def outline(
        self, rows, contact_mm, u_rad, pair, position, reach_mm, interval, *, tangency=False
    ) -> NDArray:
        """The outline of the pattern one side's zones sweep, on the refined field.

        Stations: the contact points of the rows inside their own zones within the contact
        interval (the path; beyond it the contact point stops at an edge), in order of their
        relative rotation (one per rotation: a pair's row repeats another's a pitch on; at most
        :data:`STATIONS`, evenly). From
        each, rays across the path (its direction: the neighbouring stations') to either side,
        and from the first and the last along it outward, run to the pattern's edge as the
        width's (:meth:`pattern_exits`, over the rows whose contact points lie within
        ``reach_mm`` of the station along the path). The stations are fixed by the positions,
        not the grid, and each vertex is found by root-finding: the outline converges with the
        grid.

        Parameters
        ----------
        rows
            ``(n,)`` the rows (of :attr:`rows`).
        contact_mm
            ``(n, 2)`` their contact points (grid coordinates).
        u_rad, pair, position
            ``(n,)`` their relative rotations, tooth pairs and positions.
        reach_mm
            How far along the path a row's zone may reach a station.
        interval
            ``(start, end)`` the contact interval (relative rotations).
        tangency
            True to put the stations on the rows' tangency points (:meth:`tangency_points`;
            a point contact's): the sampled contact point of a position whose tangency point
            lies in the lowest generated cells stops at the engine's refinement margin.

        Returns
        -------
        NDArray
            ``(k, 2)`` a closed polygon (grid coordinates): the first end, one side of the path,
            the last end, the other side back; ``(0, 2)`` with fewer than two stations.
        """
        side = (rows, contact_mm, u_rad, pair, position, reach_mm, interval, tangency)
        return self.outlines([side])[0]

    def outlines(self, sides) -> list[NDArray]:
        """:meth:`outline` of several sides (each the tuple of its arguments, ``tangency``
        last) at once: the separations at every side's contact points in one evaluation, every
        side's rays in one scan (the same results as one call per side, at the cost of one)."""
        rows = [np.asarray(side[0], np.intp) for side in sides]
        contact = [np.asarray(side[1], float).reshape(-1, 2) for side in sides]
        sep = self.point_separations(np.concatenate(rows), np.concatenate(contact))
        at = list(itertools.accumulate([0] + [len(r) for r in rows]))
        sep = [sep[a:b] for a, b in zip(at[:-1], at[1:], strict=True)]
        found = [
            self._outline_rays(r, c, g, *side[2:])
            for r, c, g, side in zip(rows, contact, sep, sides, strict=True)
        ]
        rays = [f for f in found if f is not None]
        if rays:
            first = list(itertools.accumulate([0] + [len(f[0]) for f in rays]))
            ends = self.pattern_exits(
                np.concatenate([f[2] + k for f, k in zip(rays, first, strict=False)]),
                *(np.concatenate([f[i] for f in rays]) for i in (3, 4, 5)),
                np.concatenate([f[0] for f in rays]),
                np.concatenate([f[1] for f in rays]),
                np.ones(first[-1], bool),
            )
        out = []
        for f in found:
            if f is None:
                out.append(np.zeros((0, 2)))
                continue
            origins, directions = f[0], f[1]
            n = (len(origins) - 2) // 2
            points = origins + ends[: len(origins), None] * directions
            ends = ends[len(origins) :]
            out.append(
                np.concatenate(
                    [points[2 * n : 2 * n + 1], points[:n], points[-1:], points[n : 2 * n][::-1]]
                )
            )
        return out

    def _outline_rays(
        self, rows, contact, sep, u_rad, pair, position, reach_mm, interval, tangency
    ):
        """One side's rays of :meth:`outline` (``sep`` the separations at its contact points):
        ``(origins, directions, ray, rows, pairs, positions)`` as :meth:`pattern_exits` takes
        them, or None with fewer than two stations."""
        u = np.ascontiguousarray(u_rad, float)
        station = np.empty(len(u), np.intp)  # (one compiled pass: on, inside, one per rotation)
        count = zone_kernels.outline_stations(
            u,
            sep,
            self.compound_mm,
            float(interval[0]) - 1e-9,
            float(interval[1]) + 1e-9,
            STATIONS,
            station,
        )
        if count < 2:
            return None
        c = contact[station[:count]]
        if tangency:
            c = self.tangency_points(rows[station[:count]], c)
        k = 2 * count + 2  # rays: each station across either way, the two ends along the path
        origins, directions = np.empty((k, 2)), np.empty((k, 2))
        ray, near = np.empty(k * len(u), np.intp), np.empty(k * len(u), np.intp)
        found = zone_kernels.outline_rays(
            np.ascontiguousarray(c, float),
            np.ascontiguousarray(contact),
            float(reach_mm),
            origins,
            directions,
            ray,
            near,
        )
        near = near[:found]
        return (
            origins,
            directions,
            ray[:found],
            rows[near],
            np.asarray(pair)[near],
            np.asarray(position)[near],
        )

    def tables(self) -> tuple:
        """The compiled evaluations' tables of the rows (made once): the rows' constants, the
        pinion's and the gear's tables (:meth:`gearopt.contact.JointField.point_tables`) and
        the separation's (lags, node factors, the grid, the compound)."""
        if self._tables is None:
            rows = self.rows
            f = rows.factor_mm
            zone = (
                np.ascontiguousarray(rows.lag_rad, float),
                np.ascontiguousarray(f, float),
                self.face0,
                self.dface,
                self.profile0,
                self.dprofile,
                float(self.last[0]),
                float(self.last[1]),
                self.compound_mm,
            )
            tables = self.joint.point_tables(rows.side, rows.phi_rad, generated=True)
            self._tables = (*tables, zone)
        return self._tables

    @staticmethod
    def rays(origins, directions) -> NDArray:
        """``(K, 4)`` rays as the kernels take them: origin, direction."""
        return np.ascontiguousarray(np.concatenate([origins, directions], axis=1))

    def to_edge(self, origins, directions) -> NDArray:
        """``(K,)`` how far rays run from their origins to the grid's edge (off it nothing is
        on the flanks)."""
        low, high = self.box[:2], self.box[2:]
        with np.errstate(divide="ignore", invalid="ignore"):
            ends = np.where(directions > 0.0, (high - origins) / directions, np.inf)
            ends = np.where(directions < 0.0, (low - origins) / directions, ends)
        return np.maximum(ends.min(axis=1), 0.0)

    def along(self, ray, r, origins, directions, tau) -> NDArray:
        """Separations of rows ``r`` at distances ``tau`` ``(P, M)`` along rays ``ray``."""
        s = origins[ray, 0][:, None] + tau * directions[ray, 0][:, None]
        h = origins[ray, 1][:, None] + tau * directions[ray, 1][:, None]
        return self.separation(r, s, h)

    def chords(self, r, origins, axes, reach) -> tuple[NDArray, NDArray]:
        """Chords of the zones of rows ``r`` through ``origins`` along ``axes`` (``(K, 2)``):
        ``(length, middle)``, the middle ``(K, 2)``."""
        k = len(origins)
        both = np.concatenate([axes, -axes])
        ends = self._union_exits(  # (ray j: row r[j % k], one a ray: already in order)
            np.arange(2 * k + 1),
            np.concatenate([r, r]).astype(np.intp, copy=False),
            np.concatenate([origins, origins]),
            both,
            np.concatenate([reach, reach]),
        )
        forward, back = ends[:k], ends[k:]
        middle = origins + 0.5 * (forward - back)[:, None] * axes
        return forward + back, middle


def extended_factors(factor_mm: NDArray) -> NDArray:
    """Node factors ``(R, n_f, n_p)`` (0 off the generated nodes) with the node below each
    face column's lowest generated node continued linearly from the two above it (a copy).
    The bilinear interpolation of the factor in a cell through which the generated boundary
    runs then mixes no zero in (which shrank the separation toward the boundary by up to a
    cell's share: a pattern reaching the boundary on a coarse grid that ends above it on a
    fine one)."""
    f = np.array(factor_mm, float, order="C")
    kernels.extend_factors(f)  # (one compiled pass: :func:`gearopt.mesh.kernels.extend_factors`)
    return f
