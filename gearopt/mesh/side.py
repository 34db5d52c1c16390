"""One side's mesh cycle: its samples, contact interval, hand-over and extra positions, between
the joint evaluations that :class:`gearopt.mesh.cycle.MeshCycle` runs for every side at once.

Definitions: :mod:`gearopt.mesh`.
"""

from __future__ import annotations

import math
from itertools import repeat

import numpy as np
from numpy.typing import NDArray

from gearopt.contact import ClearanceField, ContactError, FieldSample
from gearopt.mesh import kernels, side_kernels
from gearopt.mesh.frame import ARCSEC, ToothFrame, gear_path_angle
from gearopt.mesh.handover import FIT_TAGS, ITERATION_TAGS, HandOver, Request, lag_crossing
from gearopt.mesh.pattern import centroids, columns, separation_mm

__all__ = ["BISECTIONS", "FLAT_ARCSEC", "SideCycle"]

#: lags that vary by less than this (arcsec) are flat: a line contact, or noise on one
FLAT_ARCSEC = 0.1
BISECTIONS = 3  # contact-interval ends to an eighth of a position step
#: the tags of each contact-interval end's bisection requests (:meth:`SideCycle.start_interval`)
CI_TAGS = tuple(tuple(("ci", e, j) for j in range(1, 2**BISECTIONS)) for e in (0, 1))
#: the tags of the extra positions' requests (:meth:`SideCycle.extra_rows`)
EX_TAGS = tuple(("ex", j) for j in range(6))
#: the node fields (clearance, normal factor, radius) of an extra position without them
_NO_FIELDS = np.array([np.inf, 1.0, 1.0]).reshape(3, 1, 1, 1)


class SideCycle:
    """The state machine of one side's mesh cycle.

    Every evaluation it needs is asked for as a :class:`~gearopt.mesh.handover.Request`
    (``requests``) or as extra positions (:meth:`extra_rows`); the driver evaluates every
    side's at once, files the answers (``answers``, by tag) and the extra positions
    (:meth:`take_extras`), and steps the sides (:meth:`interval_finish`,
    :meth:`handover_step`) until none asks for more; then :meth:`assemble` builds the result.

    Parameters
    ----------
    index
        The side's index in the joint field.
    field
        Its clearance field.
    sample
        The window's sample: each distinct relative rotation of ``u`` once.
    interval_sample
        ``sample`` followed by the rows beyond both ends of the window (the contact interval's
        search).
    u
        ``(n, pairs)`` each pair's relative rotation (direction of motion, the base pair's) at
        each position.
    ids
        ``(n, pairs)`` the pairs' ids: ``u = t + ids * pitch``.
    inv
        ``(n * pairs,)`` the row of ``sample`` of each entry of ``u``.
    t
        ``(n,)`` the positions (relative rotations from the mean position).
    pitch
        The pinion's angular pitch.
    step
        The position step.

    Attributes
    ----------
    index, field, sample, interval_sample, u, ids, inv, t, pitch, step
        As given.
    interval_v
        The relative rotations of ``interval_sample``'s rows.
    g
        ``(n, pairs)`` the pairs' lags (least clearance; +inf without contact on the flanks).
    edge_all
        ``(n, pairs)`` True where a pair touches at an edge of a flank.
    carrying
        ``(n,)`` column of the carrying pair (the least lag).
    lag
        ``(n,)`` the carrying pair's lag.
    pair_id
        ``(n,)`` the carrying pair's id.
    cs, ch
        ``(n, pairs)`` the pairs' contact points (pinion grid face and profile coordinates).
    requests
        The refinements to evaluate at the next joint evaluation.
    probes
        ``(relative rotation, tag)`` rows to sample (refined) at the next joint evaluation,
        their minima filed under ``answers`` like the requests'.
    answers
        The answers ``(minimum_rad, face, profile, edge)`` of evaluated requests, by tag, until
        taken.
    interval
        ``(start, end)``: the contact interval's ends (relative rotations), once bracketed.
    interval_done
        True once ``interval`` is final.
    interval_flat
        True where the pair's lag is flat over its interior samples (:data:`FLAT_ARCSEC`).
    centre_row
        The row of ``interval_sample`` in the middle of the interior run (None without one).
    point_contact
        True where a flat lag is a point contact's (no TE, as seed 003's case A), not a line
        contact's: set by the driver before the first extra positions
        (:meth:`gearopt.mesh.cycle.MeshCycle.classify`).
    end_inside, end_outside
        ``[start, end]`` the ends' brackets (floats): the last point in interior contact and
        the first beyond; None without interior contact.
    end_open
        ``[start, end]`` True where an end's bracket is open (a sample beyond the interior
        run).
    end_face, end_profile
        ``[start, end]`` the contact points (pinion grid) at ``end_inside``.
    contact_path
        ``(v, face, profile)`` of the samples in contact, sorted by v (:meth:`contact_at`);
        None until first needed.
    ho
        The hand-over's search (:class:`~gearopt.mesh.handover.HandOver`), None without a
        bracket (a flat TE).
    v_star
        The hand-over (relative rotation of the leaving pair; without a hand-over the contact
        interval's middle plus half a pitch), None until known.
    g_hand
        The lag at the hand-over where interpolated (else taken from ``ex``), None until known.
    near_extras
        Whether the extra positions are refined from nearby contact points (a hand-over being
        checked at a guess) rather than sampled.
    ex_phi
        ``(6,)`` the extra positions' pinion angles.
    ex
        The extra positions' sample, None until evaluated: both pairs at the hand-over, the TE
        peak, M and its neighbours a quarter step either side.
    """

    def __init__(
        self,
        index: int,
        field: ClearanceField,
        sample: FieldSample,
        interval_sample: FieldSample,
        u: NDArray,
        ids: NDArray,
        inv: NDArray,
        t: NDArray,
        pitch: float,
        step: float,
    ):
        self.index, self.field = index, field
        self.sample, self.interval_sample = sample, interval_sample
        self.u, self.ids, self.inv = u, ids, inv
        self.t, self.pitch, self.step = t, pitch, step
        self.interval_v = interval_sample.phi_rad * field.sense
        shape = u.shape
        self.g, self.cs, self.ch = np.empty(shape), np.empty(shape), np.empty(shape)
        self.edge_all = np.empty(shape, bool)
        (
            self.carrying,
            self.lag,
            self.pair_id,
            touching,
            v_peak,
            spread,
            spread_finite,
            bracket,
            d_lo,
            d_hi,
        ) = kernels.side_start(
            sample.minimum_rad,
            sample.edge,
            sample.contact_face_mm,
            sample.contact_profile_mm,
            inv,
            ids,
            t,
            pitch,
            step,
            1e-9 / ARCSEC,
            self.g,
            self.edge_all,
            self.cs,
            self.ch,
        )
        if not touching:
            raise ContactError(
                "tca", rule="at some positions no tooth pair touches inside the flanks"
            )
        self.requests: list[Request] = []
        self.probes: list[tuple[float, tuple]] = []
        self.answers: dict = {}
        self.interval: tuple[float, float] | None = None
        self.interval_done = False
        self.interval_flat = False
        self.centre_row: int | None = None
        self.point_contact = False
        self.end_inside: list[float] | None = None
        self.end_outside: list[float] | None = None
        self.end_open: list[bool] | None = None
        self.end_face: list[float] | None = None
        self.end_profile: list[float] | None = None
        self.contact_path: tuple[NDArray, NDArray, NDArray] | None = None
        self.ho: HandOver | None = None
        self.v_star: float | None = None
        self.g_hand: float | None = None
        self.near_extras = False
        self.ex_phi: NDArray | None = None
        self.ex: FieldSample | None = None
        self.start_interval()
        self.start_handover(bracket, d_lo, d_hi, spread)
        self.g_peak: float | None = None
        self.peak_at = float(v_peak)
        self.peak_lags: dict = {}
        if spread_finite >= FLAT_ARCSEC / ARCSEC:
            self.ask_peak([-1, 0, 1])  # a flat TE (line contact): its least lag is noise

    # -- the contact interval ---------------------------------------------------------------

    def start_interval(self) -> None:
        """Bracket the relative rotations between which a pair's contact stays inside the
        flanks (not at an edge) from the samples, and ask for the points a bisection of each
        open bracket can visit (warm-started Newton), all at once."""
        sample, v = self.interval_sample, self.interval_v
        inner = (~sample.edge) & np.isfinite(sample.minimum_rad)
        self.interval_done = False
        # the unbroken run of interior samples around the least lag (the mesh centre), or the
        # first longest run when the least lag is itself at an edge
        order = np.argsort(v)
        lo_k, hi_k, spread = kernels.interior_run(order, inner, sample.minimum_rad)
        if lo_k < 0:  # edge contact only: no interval, centred on the least lag
            gs = np.where(np.isfinite(sample.minimum_rad), sample.minimum_rad, np.inf)[order]
            best = float(v[order][np.argmin(gs)])
            self.interval, self.interval_done = (best, best), True
            return
        last = len(v) - 1
        self.interval_flat = bool(spread < FLAT_ARCSEC / ARCSEC)
        # (the rows of the ends and of the samples beyond them, as Python floats: the
        # bisection's arithmetic on two ends is cheaper than numpy's on arrays of two)
        at = order[[lo_k, hi_k, max(lo_k - 1, 0), min(hi_k + 1, last), (lo_k + hi_k) // 2]]
        self.centre_row = int(at[4])
        at = at[:4]
        ends = v[at].tolist()
        self.end_inside, self.end_outside = ends[:2], ends[2:]
        self.end_open = [lo_k > 0, hi_k < last]
        self.end_face = sample.contact_face_mm[at[:2]].tolist()
        self.end_profile = sample.contact_profile_mm[at[:2]].tolist()
        self.interval = (ends[0], ends[1])
        parts = 2**BISECTIONS
        for e in (0, 1):
            if self.end_open[e]:
                a, b = ends[e], ends[2 + e]
                s, h = self.end_face[e], self.end_profile[e]
                v = [a + (b - a) * j / parts for j in range(1, parts)]
                self.requests += map(Request, v, repeat(s), repeat(h), CI_TAGS[e])

    def interval_finish(self) -> None:
        """Bisect each open bracket on the answers of its candidate points, then move it to the
        tangency point's exit (:meth:`tangency_end`): the end is the middle of the last
        bracket, the contact point the last inside one's."""
        if self.interval_done:
            return
        self.interval_done = True
        parts = 2**BISECTIONS
        inside, outside = self.end_inside, self.end_outside
        for e in (0, 1):
            if not self.end_open[e]:
                continue
            a, b = inside[e], outside[e]
            ja, jb = 0, parts
            for _ in range(BISECTIONS):
                m = (ja + jb) // 2
                value, s1, h1, edge = self.answers[("ci", e, m)]
                if math.isfinite(value) and not edge:
                    ja = m
                    self.end_face[e], self.end_profile[e] = float(s1), float(h1)
                else:
                    jb = m
            inside[e] = a + (b - a) * ja / parts
            outside[e] = a + (b - a) * jb / parts
            self.tangency_end(e)
        self.interval = tuple(
            0.5 * (inside[e] + outside[e]) if self.end_open[e] else inside[e] for e in (0, 1)
        )

    def tangency_end(self, e: int) -> None:
        """Move end ``e``, bisected on the engine's edge flag, to where the tangency point
        leaves the flanks (:meth:`gearopt.contact.ClearanceField.interval_end`).

        The edge flag lags that point where the minimum slides along a boundary before the
        clearance beyond it falls by the edge tolerance (a path meeting the boundary at a
        grazing angle to the contact ellipse), and leads it where the tangency point lies below
        the engine's refinable cells (a pinion without fine cells at its generated boundary,
        :mod:`gearopt.contact.boundary`, whose refinement stays two cells above it). Kept
        as it is where Newton's method fails, and for a line contact (a flat lag,
        :data:`FLAT_ARCSEC`, whose zone does not close on the flanks: ``point_contact``), where
        the tangency point is not unique and its solve converges in the interpolants' error. A
        flat lag alone does not make a line contact: a point contact without TE (seed 003's
        case A) has a unique tangency point, which leaves the flanks where its path meets their
        boundary, which the edge flag brackets only to the grid's cells.
        """
        if self.interval_flat and not self.point_contact:
            return
        a, b = self.end_inside[e], self.end_outside[e]
        start = (self.end_face[e], self.end_profile[e])
        found = self.field.interval_end(a, start, b - a)
        if found is not None:
            (
                self.end_inside[e],
                self.end_outside[e],
                self.end_face[e],
                self.end_profile[e],
            ) = (float(x) for x in found)

    # -- the hand-over ----------------------------------------------------------------------

    def start_handover(self, bracket, d_lo: float, d_hi: float, spread: float) -> None:
        """Start the hand-over's search on its bracket (:func:`gearopt.mesh.kernels.side_start`:
        the first forward switch of the carrying pair, the next pair, one id lower, taking
        over, whose two pairs' lag difference ``d_lo``, ``d_hi`` changes sign;
        :class:`~gearopt.mesh.handover.HandOver`); its first guess is the crossing of the two
        pairs' interpolated lags (:meth:`crossing`) where there is one, else the iteration
        starts. Without a bracket (``bracket[0]`` -1) the TE is flat (line contact) and the
        cycle is centred on the contact interval. ``spread``: the carrying lag's range."""
        k, l0, l1, i0, i1 = bracket
        if k < 0:
            return
        leave, t, pitch, cs, ch = self.pair_id[k], self.t, self.pitch, self.cs, self.ch
        lo, hi = t[k] + leave * pitch, t[k + 1] + leave * pitch
        ends = [
            ((cs[k, c0], ch[k, c0]), (cs[k + 1, c1], ch[k + 1, c1]))
            for c0, c1 in ((l0, l1), (i0, i1))
        ]
        # a line contact: the TE flat, or the lags differing by noise
        flat = min(spread, d_hi - d_lo) < FLAT_ARCSEC / ARCSEC
        self.ho = HandOver(lo, hi, d_lo, d_hi, ends, self.step, flat)
        guess = self.crossing(lo, hi)
        if guess is None:
            self.ask_iteration(self.ho.x0)
        else:
            self.ask_fit(guess)

    def crossing(self, lo, hi) -> float | None:
        """The crossing of the two pairs' lags interpolated through the interval samples
        (:func:`~gearopt.mesh.handover.lag_crossing`), or None."""
        sample, v = self.interval_sample, self.interval_v
        return lag_crossing(v, sample.minimum_rad, sample.edge, lo, hi, self.pitch, self.step)

    def ask_fit(self, x) -> None:
        """Check a hand-over guess ``x``: both pairs at ``x`` (the extra positions) and a delta
        to either side."""
        self.v_star, self.ex = float(x), None
        self.requests += self.ho.fit_requests(x, self.pitch)

    def ask_iteration(self, x) -> None:
        """Sample both pairs at ``x`` (a point, or the points of a step) for the iteration on
        the bracket."""
        self.v_star = float(x[0] if isinstance(x, list) else np.atleast_1d(x)[0])
        if self.ho.flat:
            self.requests += self.ho.flat_requests(x, self.pitch)
        else:
            self.probes += self.ho.iteration_rows(x, self.pitch)

    def handover_step(self) -> None:
        """Take in the hand-over's evaluations, if they are in: ask for the next ones, or
        settle ``v_star`` (and ``g_hand`` when the lag there is interpolated)."""
        ho = self.ho
        if ho is None or ho.done:
            return
        if ho.mode == "fit":
            if self.ex is None or not all(tag in self.answers for tag in FIT_TAGS):
                return
            action, x = ho.take_fit([self.answers.pop(tag) for tag in FIT_TAGS], self.ex)
            if action == "settled":
                self.v_star, self.g_hand = x, ho.lag
            elif action == "fit":
                self.ask_fit(x)
            else:
                self.ex = None
                self.ask_iteration(x)
            return
        if ho.flat:
            if not all(tag in self.answers for tag in ITERATION_TAGS):
                return
            leaving, incoming = (self.answers.pop(tag)[0] for tag in ITERATION_TAGS)
            x = ho.take_flat(float(leaving - incoming))
            if x is None:
                self.v_star = ho.x
            else:
                self.ask_iteration(x)
            return
        answers = self.answers
        if not all(map(answers.__contains__, ho.asked)):
            return
        xs = ho.take_iteration({tag: float(answers.pop(tag)[0]) for tag in ho.asked})
        if xs is None:
            self.v_star, self.g_hand = ho.x, ho.lag
        else:
            self.ask_iteration(xs)

    # -- the extra positions ----------------------------------------------------------------

    def extras_due(self) -> bool:
        """Whether the extra positions can be evaluated: the hand-over is settled or guessed
        from smooth lags, or (no hand-over, or a point contact's flat hand-over: M is then
        centred on it) the contact interval is known."""
        if self.ho is None or (self.ho.flat and self.point_contact and not self.interval_done):
            return self.interval_done
        return self.ho.done or self.ho.mode == "fit"

    def fit_mode(self) -> bool:
        """Whether the hand-over is being checked at a guess from smooth lags."""
        return self.ho is not None and not self.ho.done and self.ho.mode == "fit"

    def extra_rows(self) -> tuple[list[float], list[bool]]:
        """Ask for the extra positions (:meth:`extra_angles`): the relative rotations to sample
        with this side's rows of the joint evaluation and whether each is refined. Where the
        hand-over is checked at a guess, all six minima are requests started from the contact
        points interpolated along the samples and only M's rows are sampled (for their node
        fields, unrefined); otherwise all six are sampled and refined."""
        angles = self.extra_angles()
        self.near_extras = self.fit_mode()
        if self.near_extras:
            faces, profiles = self.contact_at(np.array(angles))
            self.requests += map(Request, angles, faces.tolist(), profiles.tolist(), EX_TAGS)
            rows = angles[3:], [False] * 3
        else:
            rows = angles, [True] * 6
        self.ex_phi = self.field.sense * np.array(angles)
        return rows

    def take_extras(self, sample: FieldSample) -> None:
        """File the extra positions' rows of a joint evaluation (:meth:`extra_rows`)."""
        self.ex = self.near_extras_sample(sample) if self.near_extras else sample

    def take_requests(self) -> list[Request]:
        """The pending requests, handed over to the driver."""
        requests, self.requests = self.requests, []
        return requests

    def take_probes(self) -> list[tuple[float, tuple]]:
        """The pending rows to sample, handed over to the driver."""
        probes, self.probes = self.probes, []
        return probes

    def extra_angles(self) -> list[float]:
        """The extra positions: the hand-over (both pairs), the TE peak, the mean point M and
        its neighbours for the path direction; a flat TE (line contact, no hand-over) is
        centred on the contact interval."""
        if self.v_star is None:
            start, end = self.interval
            self.v_star = 0.5 * (start + end) + 0.5 * self.pitch
            self.g_hand = float(np.max(self.g.min(axis=1)))
        v_star, pitch = self.v_star, self.pitch
        v_mid = v_star - 0.5 * pitch
        if self.ho is not None and self.ho.flat and self.point_contact:
            # a point contact without TE: its hand-over lies in noise, M's position is the
            # middle of the contact interval (whose ends are solved, not noise)
            v_mid = 0.5 * (self.interval[0] + self.interval[1])
        dv = 0.25 * self.step
        return [v_star, v_star - pitch, self.peak_at, v_mid, v_mid - dv, v_mid + dv]

    # -- the TE peak (the least lag) ---------------------------------------------------------

    def ask_peak(self, offsets) -> None:
        """Sample the carrying pair at the peak's guess plus ``offsets`` eighths of a step."""
        delta = self.step / 8.0
        self.probes += [(self.peak_at + k * delta, ("pk", k)) for k in offsets]

    def peak_step(self) -> None:
        """Take in the peak's evaluations: the parabola through the lags an eighth of a step
        either side of the guess and at it, then its vertex once (where within half a step),
        then ``g_peak``: the least lag evaluated. The samples' parabola the guess comes from
        (:func:`gearopt.mesh.kernels.side_start`) misses the least lag by up to 0.02 arcsec
        where the lag is not symmetric about its minimum (a hand-over in edge contact
        nearby)."""
        if self.g_peak is not None:
            return
        for key in [k for k in self.answers if k[0] == "pk"]:
            self.peak_lags[key[1]] = float(self.answers.pop(key)[0])
        if "vertex" in self.peak_lags:
            self.g_peak = min(self.peak_lags.values())
            return
        if len(self.peak_lags) < 3:
            return
        g = [self.peak_lags[k] for k in (-1, 0, 1)]
        curvature = g[0] - 2.0 * g[1] + g[2]
        finite = all(math.isfinite(x) for x in g)
        if not (finite and curvature > 0.0):
            self.g_peak = min(x if math.isfinite(x) else math.inf for x in g)
            return
        z = 0.5 * (g[0] - g[2]) / curvature
        if abs(z) > 4.0:
            self.g_peak = min(g)
            return
        self.probes.append((self.peak_at + z * self.step / 8.0, ("pk", "vertex")))

    def contact_at(self, v: NDArray) -> tuple[NDArray, NDArray]:
        """Starts for refinements at relative rotations ``v``: the contact points interpolated
        (linearly in v) between the nearest samples in contact on either side."""
        if self.contact_path is None:
            sample = self.interval_sample
            ok = np.isfinite(sample.minimum_rad)
            vs = self.interval_v[ok]
            order = np.argsort(vs)
            self.contact_path = (
                vs[order],
                sample.contact_face_mm[ok][order],
                sample.contact_profile_mm[ok][order],
            )
        vs, cs, ch = self.contact_path
        return np.interp(v, vs, cs), np.interp(v, vs, ch)

    def near_extras_sample(self, mean: FieldSample) -> FieldSample:
        """The extra positions' sample from their refined minima (answers ``("ex", j)``) and
        the node fields of M's rows (``mean``); the other rows have no node fields (+inf)."""
        pop = self.answers.pop
        got = np.array([pop(tag) for tag in EX_TAGS], float).T.copy()
        fields = np.empty((3, 6) + mean.clearance_rad.shape[1:])
        fields[:, :3] = _NO_FIELDS
        fields[0, 3:], fields[1, 3:], fields[2, 3:] = (
            mean.clearance_rad,
            mean.normal_factor_mm,
            mean.radius_mm,
        )
        return FieldSample(
            phi_rad=self.ex_phi,
            clearance_rad=fields[0],
            normal_factor_mm=fields[1],
            radius_mm=fields[2],
            minimum_rad=got[0],
            contact_face_mm=got[1],
            contact_profile_mm=got[2],
            edge=got[3] != 0.0,
        )

    # -- the result -------------------------------------------------------------------------

    def assemble(self, name: str, frame: ToothFrame, compound_um: float, separation: str):
        """The side's :class:`~gearopt.mesh.cycle.ToothContact` but for the figures of its
        zones (:meth:`gearopt.mesh.cycle.MeshCycle.contacts` measures every side's at once).

        Returns
        -------
        tuple
            ``(lines, fields)``: ``lines`` the rows of the zones to measure (``mean_*``: M's
            position and its neighbours a quarter step either side; ``pattern_*``: the
            positions' pairs whose zones are not empty, with their positions and pair ids), each
            with its pinion angle, lag, node factors and contact point (the pattern rows' node
            factors as ``pattern_factor_rows``: the window sample's and the rows of it, copied
            once where every side's are gathered); ``fields`` the ToothContact's other fields.
        """
        field, ex, t, p1 = self.field, self.ex, self.t, self.pitch
        positions, pairs = self.u.shape
        lag, carrying = self.lag, self.carrying
        g_hand = self.g_hand
        if g_hand is None:
            g_hand = float(max(ex.minimum_rad[0], ex.minimum_rad[1]))
        g_min = min(float(ex.minimum_rad[2]), float(lag.min()))
        if self.g_peak is not None:
            g_min = min(g_min, self.g_peak)
        peak_to_peak = (max(g_hand, float(lag.max())) - g_min) * ARCSEC

        # separations at the contact gear angle of each position (same lag for every pair),
        # the pattern (um), the path (separation_mm, centroids), the TE and the zones to
        # measure (gearopt.mesh.zone, every side's at once: M's position and its neighbours',
        # and the pairs whose zones reach within five compounds, held or about to be: the
        # neighbours through which the motion is refined) in one compiled pass
        compound_mm = compound_um * 1e-3
        kind = "normal_factor_mm" if separation == "normal" else "radius_mm"
        node_factor = getattr(self.sample, kind)
        face = field.pinion.face_mm - frame.toe_mm
        profile = field.pinion.profile_mm - frame.root_mm
        size = face.size * profile.size
        sep_um = np.empty((positions * pairs, size))
        out = np.empty(size + (3 + pairs) * positions)
        held = np.empty(positions * pairs, np.intp)
        count = kernels.pattern_fields(
            np.ascontiguousarray(self.sample.clearance_rad).reshape(-1, size),
            np.ascontiguousarray(node_factor).reshape(-1, size),
            self.sample.minimum_rad,
            self.inv,
            lag,
            carrying,
            g_min,
            compound_mm,
            face,
            profile,
            sep_um,
            out,
            held,
        )
        pattern = out[:size].reshape(field.pinion.shape)
        path_s, path_h, te = out[size : size + 3 * positions].reshape(3, positions)
        pair_te = out[size + 3 * positions :].reshape(pairs, positions)
        # the held entries' rows and the carrying pair's contact points, one compiled pass
        ints, floats = np.empty((2, count), np.intp), np.empty(5 * count + 2 * positions)
        edge = np.empty(positions, bool)
        side_kernels.carried_rows(
            held[:count],
            pairs,
            self.inv,
            np.ascontiguousarray(self.sample.phi_rad),
            lag,
            self.cs.ravel(),
            self.ch.ravel(),
            self.ids.ravel(),
            carrying,
            self.edge_all.ravel(),
            float(frame.toe_mm),
            float(frame.root_mm),
            ints,
            floats,
            edge,
        )
        position, sample_row = ints
        pattern_phi, pattern_lag, pattern_pair = floats[: 3 * count].reshape(3, count)
        lines = dict(
            mean_phi_rad=ex.phi_rad[3:6],
            mean_lag_rad=ex.minimum_rad[3:6],
            mean_factor_mm=getattr(ex, kind)[3:6],
            mean_contact_mm=columns(ex.contact_face_mm[3:6], ex.contact_profile_mm[3:6]),
            pattern_phi_rad=pattern_phi,
            pattern_lag_rad=pattern_lag,
            pattern_factor_rows=(node_factor, sample_row),
            pattern_contact_mm=floats[3 * count : 5 * count].reshape(count, 2),
            pattern_position=position,
            pattern_pair=pattern_pair,
            interval=self.interval,
        )
        # bias: the contact line's extension along the face from the pair's entry into contact
        # to its exit (seed 003 section 6): the contact points at the ends of its contact
        # interval
        ends = self.end_face
        if ends is not None:
            bias = float(ends[1] - ends[0])
        else:
            cs, _ = centroids(
                separation_mm(ex, ex.minimum_rad, separation), compound_mm, face, profile
            )
            bias = float(cs[0] - cs[1])
        start, end = self.interval
        low, high = float(t[0]) - 1e-12, float(t[-1]) + 1e-12
        handovers = [self.v_star + p1 * k for k in range(-12, 13)]
        handovers = np.array([x for x in handovers if low <= x <= high], float)
        return lines, dict(
            side=name,
            phi1_deg=np.degrees(t),
            te_arcsec=te,
            pair_te_arcsec=pair_te,
            carrying=carrying,
            handover_phi1_deg=np.degrees(handovers),
            te_peak_to_peak_arcsec=float(peak_to_peak),
            path_face_mm=path_s,
            path_profile_mm=path_h,
            contact_face_mm=floats[5 * count : 5 * count + positions],
            contact_profile_mm=floats[5 * count + positions :],
            edge=edge,
            separation_um=sep_um.reshape((positions, pairs) + field.pinion.shape),
            pattern_um=pattern,
            face_mm=face,
            profile_mm=profile,
            path_angle_deg=gear_path_angle(field, ex, frame),
            bias_mm=bias,
            contact_ratio=float((end - start) / p1),
            compound_um=float(compound_um),
            separation=separation,
        )
