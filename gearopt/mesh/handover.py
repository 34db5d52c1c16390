"""The hand-over between two successive tooth pairs: where their TE curves intersect.

The search (:class:`HandOver`) works on a bracket [lo, hi] of relative pinion rotations
(direction of motion, the leaving pair's) over which the lag difference D = G_leaving -
G_incoming changes sign. Where the lags around it are interior contacts (smooth), the first
guess is where the cubic interpolants of the two pairs' sampled lags cross
(:func:`lag_crossing`), checked by evaluations at the guess and an eighth of a position step to
either side: the root of the parabola through the three differences stands when it is within a
tenth of that from the guess, is evaluated anew once when further. Otherwise (edge contact, or
a guess that does not settle) an iteration on the bracket (:meth:`HandOver.take_iteration`)
until it is narrower than :data:`TOLERANCE_RAD`: where D is smooth, the root of its inverse
interpolants guarded either side as far as they disagree (it closes in about three steps);
where D steps (a lag's least clearance jumping to another part of its flank: only D's sign
tells the root) or is infinite, points evenly across the bracket, the stepping lag sampled
alone once the other's is smooth across it. A line contact (``flat``: its crossing lies in
noise) keeps three steps on refinements (:meth:`HandOver.take_flat`).

A guess's checks are asked for as :class:`Request` rows, answered by the joint field's
refinement from nearby contact points (:meth:`gearopt.contact.JointField.minimum_near`): the
lags there are smooth and the contact points known. The iteration's evaluations are the lags
themselves, ``(relative rotation, tag)`` rows sampled like every position (the node field's
least nodes refined, :meth:`gearopt.contact.JointField.sample`): in edge contact a refinement
from a point interpolated between the bracket's contact points can settle on another edge's
local minimum (a lag difference several arcsec off), and the lag, a minimum over the flank,
can bend or step between positions, where a fixed number of secant steps does not converge.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from gearopt.contact import FieldSample
from gearopt.mesh import handover_kernels, kernels
from gearopt.mesh.handover_kernels import STATE

__all__ = [
    "FIT_TAGS",
    "ITERATIONS",
    "ITERATION_TAGS",
    "HandOver",
    "Request",
    "inverse_root",
    "lag_crossing",
    "newton_form",
    "newton_value",
    "parabola",
    "parabola_at",
    "parabola_root",
    "SPREAD",
    "TOLERANCE_RAD",
]


class Request(NamedTuple):
    """A refinement asked of the joint field: the least clearance of a side's base pair at
    relative rotation ``v``, started from the pinion grid point ``(face, profile)``; the answer
    ``(minimum_rad, face, profile, edge)`` is filed under ``tag``."""

    v: float
    face: float
    profile: float
    tag: tuple


#: the answers of a guess's check: both pairs (0 leaving, 1 incoming) a delta before and after
FIT_TAGS = tuple(("ho", pair, sign) for pair in (0, 1) for sign in (-1, 1))
#: the answers of an iteration step: both pairs at the point
ITERATION_TAGS = (("ho", 0, 0), ("ho", 1, 0))
#: the iteration stops once the bracket is narrower (relative rotation; the lag then moves by
#: well under 1e-3 arcsec)
TOLERANCE_RAD = 1e-9
#: the most steps of the iteration (bisection of a position step to 1e-9 rad takes about 26)
ITERATIONS = 40
#: the points evenly across the bracket of an iteration's step where D is not smooth (both
#: pairs sampled, or the stepping pair alone)
SPREAD = 7
#: the widest bracket on which a stepping lag is sampled alone
SINGLE_RAD = 1e-4
#: the rows :class:`HandOver` holds for its samples and trail at first (grown as needed)
ROWS = 64

_LIMITS = np.array([TOLERANCE_RAD, ITERATIONS, SPREAD, SINGLE_RAD], float)
_WIDTH, _RISE, _STEPS, _SMOOTH = (
    handover_kernels.WIDTH,
    handover_kernels.RISE,
    handover_kernels.STEPS,
    handover_kernels.SMOOTH,
)
#: :attr:`HandOver.state` before its bracket is set (no smooth pair), and its first counts
_START = np.zeros(len(STATE))
_START[_SMOOTH] = -1.0
_COUNTS = np.array([0, 0, 2], np.intp)


class HandOver:
    """The search for one hand-over on its bracket (see the module docstring).

    Parameters
    ----------
    lo, hi
        The bracket (relative rotations of the leaving pair, consecutive positions).
    d_lo, d_hi
        The lag difference D (leaving minus incoming) at ``lo`` (<= 0) and ``hi`` (>= 0).
    ends
        The two pairs' contact points at the bracket's ends, ``ends[pair] = ((face, profile)
        at lo, (face, profile) at hi)``, pair 0 leaving, 1 incoming: the starts of the
        refinements.
    step
        The position step.
    flat
        Whether the TE is flat (a line contact: the TE within 0.1 arcsec, or the lags differing
        by noise over the bracket; their crossing is then any point of it): its iteration
        then takes three steps on refinements (:meth:`flat_requests`, :meth:`take_flat`), which
        place the hand-over, and with it M, where they always have.

    Attributes
    ----------
    lo, hi, d_lo, d_hi, ends, flat
        As given.
    d0
        D at ``x0`` once evaluated (a line contact's iteration).
    x0
        The secant guess on the bracket: the iteration's first point.
    delta
        Offset of a guess's check evaluations (an eighth of a step).
    mode
        ``"fit"`` (checking a guess from smooth lags) or ``"iterate"`` (the iteration).
    x
        The point being evaluated, then the hand-over when ``done``.
    lag
        The lag at the hand-over when interpolated by the check's parabolas or found by the
        iteration on a closed bracket, else None (it is then taken from the extra positions'
        evaluation at ``x``).
    round
        0 at a guess's first check, 1 at its second.
    bracket
        ``[a, b, d_a, d_b, low_a, low_b]`` the iteration's bracket, D at its ends and the lower
        of the two pairs' lags there (None at the bracket's first ends), from ``state``; a line
        contact's: ``flat_bracket``, ``[a, b]``.
    xs
        The points of the iteration's step being evaluated.
    state
        The iteration's state (:data:`gearopt.mesh.handover_kernels.STATE`): the bracket, both
        pairs' lags at its ends, its width and D's rise across it before the last step, the
        steps so far, whether the last step was even (0), guarded (1) or its retry with wider
        guards (2), the smooth pair, and the hand-over once settled.
    smooth
        The pair (0 leaving, 1 incoming) whose lag is interpolated, not sampled, in the step
        being evaluated, or None.
    asked
        The tags of the lags asked for by the step being evaluated.
    samples, counts, trail
        Each pair's sampled ``(x, lag)`` points (finite lags; ``samples[pair, :counts[pair]]``):
        the smooth pair's interpolation; every ``(x, D)`` with D finite so far, the bracket's
        first ends among them (``trail[:counts[2]]``).
    steps
        The iteration's evaluations so far.
    done
        True once settled.
    """

    def __init__(self, lo, hi, d_lo, d_hi, ends, step, flat=False):
        self.lo, self.hi, self.d_lo, self.d_hi, self.ends = lo, hi, d_lo, d_hi, ends
        self.flat = flat
        self.d0 = None
        self.x0 = lo - d_lo * (hi - lo) / (d_hi - d_lo)
        self.delta = step / 8.0
        self.mode = None
        self.x = None
        self.lag = None
        self.round = 0
        self.flat_bracket = [lo, hi]
        self.xs = []
        self.done = False
        self.asked = []
        state = _START.copy()
        state[:4] = lo, hi, d_lo, d_hi
        state[_WIDTH], state[_RISE] = hi - lo, d_hi - d_lo
        self.state = state
        self.samples, self.trail = np.empty((2, ROWS, 2)), np.empty((ROWS, 2))
        self.trail[:2] = (lo, d_lo), (hi, d_hi)
        self.counts = _COUNTS.copy()
        self.out = np.empty(SPREAD)

    def fit_requests(self, x, pitch: float) -> list[Request]:
        """Check a guess ``x``: both pairs a delta either side of it (the evaluations at ``x``
        itself are the side's extra positions), started from the contact points interpolated
        along the bracket."""
        self.mode, self.x = "fit", float(x)
        f = (x - self.lo) / (self.hi - self.lo)
        out = []
        for pair, shift in ((0, 0.0), (1, -pitch)):
            (s0, h0), (s1, h1) = self.ends[pair]
            s, h = (1.0 - f) * s0 + f * s1, (1.0 - f) * h0 + f * h1
            for sign in (-1, 1):
                out.append(Request(x + shift + sign * self.delta, s, h, ("ho", pair, sign)))
        return out

    def iteration_rows(self, xs, pitch: float) -> list[tuple[float, tuple]]:
        """An iteration step: the pairs at each of the points ``xs``, as ``(relative rotation,
        tag)`` rows to sample (the lags as at every position; see the module docstring); where
        one pair's lag steps and the other's is smooth across the bracket (:attr:`smooth`),
        only the stepping pair. The tags asked for are :attr:`asked`."""
        self.mode = "iterate"
        self.xs = sorted(set(map(float, xs if isinstance(xs, list) else np.atleast_1d(xs))))
        self.x = self.xs[0]
        smooth = int(self.state[_SMOOTH])  # (-1: none)
        pairs = [(pair, shift) for pair, shift in ((0, 0.0), (1, pitch)) if pair != smooth]
        out = [(x - shift, ("ho", pair, j)) for j, x in enumerate(self.xs) for pair, shift in pairs]
        self.asked = [tag for _, tag in out]
        return out

    def take_fit(self, got: list, ex: FieldSample) -> tuple[str, float]:
        """Take in a guess's check.

        Parameters
        ----------
        got
            The answers of :data:`FIT_TAGS`, in that order.
        ex
            The extra positions' sample: rows 0 and 1 are both pairs at the guess.

        Returns
        -------
        tuple
            ``("settled", x)`` (``lag`` set), ``("fit", x)``: check ``x`` next, or
            ``("iterate", x)``: start the iteration at ``x``.
        """
        # (on Python floats: three points a pair)
        minimum = ex.minimum_rad.tolist()
        gl = (float(got[0][0]), minimum[0], float(got[1][0]))
        gi = (float(got[2][0]), minimum[1], float(got[3][0]))
        interior = all(math.isfinite(g) for g in gl + gi)
        interior = interior and not (bool(ex.edge[0] or ex.edge[1]) or any(a[3] for a in got))
        interior = interior and all(math.isfinite(g) for g in minimum)
        z = parabola_root([a - b for a, b in zip(gl, gi, strict=True)]) if interior else math.inf
        x = self.x + self.delta * z
        # the root within a tenth of a delta of the guess: the extra positions (M among them)
        # stand; further off: the root is evaluated anew once
        if abs(z) <= 0.1 and self.lo <= x <= self.hi:
            self.done = True
            self.x = float(x)
            self.lag = float(max(parabola_at(gl, z), parabola_at(gi, z)))
            return "settled", self.x
        if abs(z) <= 2.0 and self.round == 0:
            self.round += 1
            return "fit", min(max(x, self.lo), self.hi)
        self.round = 0  # not smooth there after all: the iteration on the bracket
        return "iterate", self.x0

    def take_iteration(self, got: dict) -> list[float] | None:
        """Take in the lags asked for (:attr:`asked`; ``got[tag]``, tags ``("ho", pair, j)``,
        pair 0 leaving, 1 incoming, at the ``j``-th point of ``xs``): the next points to
        evaluate, or None once settled (at ``x``).

        The bracket moves to the first sign change of D = leaving - incoming along the points;
        D is +-inf where one pair is off the flanks (its sign still tells the side), NaN
        (both off) drops the point. Settled once the bracket is narrower than
        :data:`TOLERANCE_RAD`, at its middle, ``lag`` the greater of the lower lags at its ends:
        at a crossing of continuous lags their common value, where a pair's lag steps across
        the other's (its least clearance jumping to another part of its flank) the TE's trough
        there.

        Next: where D is smooth, its root interpolated through the bracket's ends and the
        nearest other point and two guards either side, as far as the interpolation's error;
        where D steps (the bracket closes in but D's rise across it does not shrink with it),
        is infinite or a step left more than a quarter of the bracket, :data:`SPREAD` points
        evenly across it. A stepping lag is sampled alone once the other pair's lag changes by
        at most a twentieth of D's rise across a bracket narrower than 1e-4 rad: the other's is
        then interpolated (a parabola through its three nearest samples), which cannot move
        D's sign. One compiled step (:func:`gearopt.mesh.handover_kernels.iteration_step`).
        """
        k = len(self.xs)
        values, asked = np.empty((k, 2)), np.zeros((k, 2), bool)
        for tag in self.asked:
            values[tag[2], tag[1]] = got[tag]
            asked[tag[2], tag[1]] = True
        if self.trail.shape[0] < max(self.counts.tolist()) + k:  # (room for the step's points)
            self.grow(k)
        count = handover_kernels.iteration_step(
            self.state,
            np.array(self.xs),
            values,
            asked,
            self.samples,
            self.counts,
            self.trail,
            _LIMITS,
            self.out,
        )
        state = self.state
        if count:
            return self.out[:count].tolist()
        self.done, self.x = True, float(state[handover_kernels.X])
        if state[handover_kernels.HAS_LAG]:
            self.lag = float(state[handover_kernels.LAG])
        return None

    def grow(self, k: int) -> None:
        """Room for ``k`` more rows in :attr:`samples` and :attr:`trail`."""
        rows = 2 * self.trail.shape[0] + k
        samples, trail = np.empty((2, rows, 2)), np.empty((rows, 2))
        samples[:, : self.samples.shape[1]] = self.samples
        trail[: self.trail.shape[0]] = self.trail
        self.samples, self.trail = samples, trail

    @property
    def bracket(self) -> list:
        """``[a, b, d_a, d_b, low_a, low_b]`` the iteration's bracket, D at its ends and the
        lower of the two pairs' lags there (None at the bracket's first ends); a line
        contact's iteration: its bracket ``[a, b]``."""
        if self.flat:
            return self.flat_bracket
        s, k = self.state, handover_kernels
        return [
            float(s[k.A]),
            float(s[k.B]),
            float(s[k.D_A]),
            float(s[k.D_B]),
            float(s[k.LOW_A]) if s[k.HAS_LOW_A] else None,
            float(s[k.LOW_B]) if s[k.HAS_LOW_B] else None,
        ]

    @property
    def smooth(self) -> int | None:
        """The pair (0 leaving, 1 incoming) whose lag is interpolated, not sampled, in the step
        being evaluated, or None."""
        pair = int(self.state[_SMOOTH])
        return None if pair < 0 else pair

    @property
    def steps(self) -> int:
        """The iteration's evaluations so far."""
        return int(self.state[_STEPS])

    def flat_requests(self, x, pitch: float) -> list[Request]:
        """A step of a line contact's iteration (``flat``): both pairs at ``x``, refined from
        the middle of each pair's contact points at the bracket's ends."""
        self.mode, self.x = "iterate", float(x)
        out = []
        for pair, shift in ((0, 0.0), (1, -pitch)):
            (s0, h0), (s1, h1) = self.ends[pair]
            out.append(Request(x + shift, 0.5 * (s0 + s1), 0.5 * (h0 + h1), ITERATION_TAGS[pair]))
        return out

    def take_flat(self, d: float) -> float | None:
        """Take in D at ``x`` for a line contact (``flat``): the secant guess, the parabola
        through three differences, a last secant step; None once settled (at ``x``)."""
        if not np.isfinite(d):
            self.done = True
            return None
        lo, hi, d_lo, d_hi = self.lo, self.hi, self.d_lo, self.d_hi
        if self.steps == 0:
            self.state[_STEPS], self.d0, x0 = 1.0, d, self.x
            a, b, c = parabola(lo - x0, hi - x0, d_lo, d, d_hi)
            roots = np.roots([a, b, c]) if abs(a) > 0.0 else np.array([-c / b])
            roots = np.real(roots[np.isreal(roots)]) + x0
            self.flat_bracket = [lo, x0] if d > 0.0 else [x0, hi]
            good = roots[(roots >= self.flat_bracket[0]) & (roots <= self.flat_bracket[1])]
            return float(good[0]) if good.size else x0
        x0, d0, x1 = self.x0, self.d0, self.x
        if d != d0:
            x2 = x1 - d * (x1 - x0) / (d - d0)
            if self.flat_bracket[0] <= x2 <= self.flat_bracket[1]:
                self.x = float(x2)
        self.done = True
        return None


def lag_crossing(v, minimum, edge, lo, hi, pitch, step) -> float | None:
    """Where the lag of the leaving pair G(x) meets the incoming pair's G(x - pitch) in
    [lo, hi], both interpolated (cubic) through the four nearest samples of G.

    Parameters
    ----------
    v, minimum, edge
        The samples of G: relative rotations, lags and edge flags.
    lo, hi
        The bracket.
    pitch, step
        The angular pitch and the position step.

    Returns
    -------
    float or None
        The crossing; None when any of the samples is missing or not an interior contact (the
        lags are smooth only there).
    """
    mid = 0.5 * (lo + hi)
    centres = np.array([mid, mid - pitch])
    near = np.ascontiguousarray(np.argsort(np.abs(v[None, :] - centres[:, None]), axis=1)[:, :4])
    # the cubics' divided differences and the Illinois method, compiled
    root = kernels.crossing_root(v, minimum, edge, near, centres, step, 0.5 * (hi - lo) / step)
    return None if math.isnan(root) else mid + step * root


def newton_form(z: list, g: list) -> tuple[list, list]:
    """The polynomial through the points (z, g) by divided differences: ``(z, coefficients)``
    for :func:`newton_value`."""
    c = list(g)
    for j in range(1, len(z)):
        for i in range(len(z) - 1, j - 1, -1):
            c[i] = (c[i] - c[i - 1]) / (z[i] - z[i - j])
    return z, c


def newton_value(z: list, c: list, x: float) -> float:
    """The polynomial of :func:`newton_form` at x (nested multiplication)."""
    value = c[-1]
    for i in range(len(c) - 2, -1, -1):
        value = value * (x - z[i]) + c[i]
    return value


def inverse_root(bracket, trail, count: int) -> float | None:
    """The root of the inverse interpolant (x as a polynomial of D) through the bracket's ends
    ``(a, b, d_a, d_b)`` and the ``count`` (1 or 2) points of ``trail`` (``(x, d)`` rows)
    nearest the bracket outside its ends, or None (too few such points, or D's values not
    distinct): :func:`gearopt.mesh.kernels.inverse_roots`."""
    a, b, d_a, d_b = (float(v) for v in bracket)
    if not trail:
        return None
    root = kernels.inverse_roots(a, b, d_a, d_b, np.array(trail, float))[count - 1]
    return None if math.isnan(root) else root


def parabola(xa: float, xb: float, ya: float, y0: float, yb: float):
    """``(a, b, c)`` of the parabola a x^2 + b x + c through (xa, ya), (0, y0), (xb, yb)."""
    sa, sb = (ya - y0) / xa, (yb - y0) / xb
    a = (sb - sa) / (xb - xa)
    return a, sa - a * xa, y0


def parabola_root(d: NDArray) -> float:
    """The root nearest 0 of the parabola through (-1, d0), (0, d1), (1, d2) (inf if none)."""
    a = 0.5 * (d[0] + d[2]) - d[1]
    b = 0.5 * (d[2] - d[0])
    c = d[1]
    disc = b * b - 4.0 * a * c
    if disc < 0.0 or (a == 0.0 and b == 0.0):
        return math.inf
    q = -0.5 * (b + math.copysign(math.sqrt(disc), b))
    roots = [c / q] if q != 0.0 else []
    if a != 0.0:
        roots.append(q / a)
    return min(roots, key=abs, default=math.inf)


def parabola_at(y: NDArray, z: float) -> float:
    """The parabola through (-1, y0), (0, y1), (1, y2) at z."""
    return float(y[1] + 0.5 * (y[2] - y[0]) * z + (0.5 * (y[0] + y[2]) - y[1]) * z * z)
