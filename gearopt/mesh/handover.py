"""The hand-over between two successive tooth pairs: where their TE curves intersect.

The search (:class:`HandOver`) works on a bracket [lo, hi] of relative pinion rotations
(direction of motion, the leaving pair's) over which the lag difference D = G_leaving -
G_incoming changes sign. Where the lags around it are interior contacts (smooth), the first
guess is where the cubic interpolants of the two pairs' sampled lags cross
(:func:`lag_crossing`), checked by evaluations at the guess and an eighth of a position step to
either side: the root of the parabola through the three differences stands when it is within a
tenth of that from the guess, is evaluated anew once when further. Otherwise (edge contact, or
a guess that does not settle) an iteration on the bracket (:meth:`HandOver.take_iteration`:
secant points guarded either side and the middle, four a step) until it is narrower than
:data:`TOLERANCE_RAD`. A line contact (``flat``: its crossing lies in noise) keeps three steps
on refinements (:meth:`HandOver.take_flat`).

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
from gearopt.mesh import kernels

__all__ = [
    "FIT_TAGS",
    "ITERATIONS",
    "ITERATION_TAGS",
    "HandOver",
    "Request",
    "lag_crossing",
    "parabola",
    "parabola_at",
    "parabola_root",
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
        of the two pairs' lags there (None at the bracket's first ends).
    xs
        The points of the iteration's step being evaluated.
    width
        The bracket's width before the last step.
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
        self.bracket = [lo, hi, d_lo, d_hi, None, None]
        self.width = hi - lo
        self.xs = []
        self.steps = 0
        self.done = False

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
        """An iteration step: both pairs at each of the points ``xs``, as ``(relative rotation,
        tag)`` rows to sample (the lags as at every position; see the module docstring)."""
        self.mode = "iterate"
        self.xs = sorted({float(x) for x in np.atleast_1d(xs)})
        self.x = self.xs[0]
        out = []
        for j, x in enumerate(self.xs):
            out += [(x, ("ho", 0, j)), (x - pitch, ("ho", 1, j))]
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
        gl = np.array([got[0][0], ex.minimum_rad[0], got[1][0]])
        gi = np.array([got[2][0], ex.minimum_rad[1], got[3][0]])
        interior = np.all(np.isfinite(gl)) and np.all(np.isfinite(gi))
        interior = interior and not (ex.edge[:2].any() or any(a[3] for a in got))
        interior = interior and bool(np.all(np.isfinite(ex.minimum_rad)))
        z = parabola_root(gl - gi) if interior else math.inf
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

    def take_iteration(self, lags) -> list[float] | None:
        """Take in both pairs' lags ``(leaving, incoming)`` at each point of ``xs``: the next
        points to evaluate, or None once settled (at ``x``).

        The bracket moves to the first sign change of D = leaving - incoming along the points;
        D is +-inf where one pair is off the flanks (its sign still tells the side), NaN
        (both off) drops the point. Next: the secant (regula falsi) point on the bracket, a
        hundredth of the bracket either side of it (on smooth lags the root falls between
        them) and the bracket's middle (where a lag steps, at least a halving); where a step left
        more than a quarter of the bracket, eight points evenly across it. Settled once
        the bracket is narrower than :data:`TOLERANCE_RAD`, at its middle, ``lag`` the greater
        of the lower lags at its ends: at a crossing of continuous lags their common value,
        where a pair's lag steps across the other's (its least clearance jumping to another
        part of its flank) the TE's trough there.
        """
        self.steps += 1
        a, b, d_a, d_b, low_a, low_b = self.bracket
        points = [(a, d_a, low_a)]
        with np.errstate(invalid="ignore"):  # inf - inf: both off the flanks
            for x, (g_l, g_i) in zip(self.xs, lags, strict=True):
                d = g_l - g_i
                if a < x < b and not np.isnan(d):
                    points.append((x, d, min(g_l, g_i)))
        points.append((b, d_b, low_b))
        for (x0, d0, l0), (x1, d1, l1) in zip(points[:-1], points[1:], strict=True):
            if d0 <= 0.0 < d1 or d1 == 0.0:
                a, b, d_a, d_b, low_a, low_b = x0, x1, d0, d1, l0, l1
                break
        self.bracket = [a, b, d_a, d_b, low_a, low_b]
        if d_b == 0.0:
            self.done, self.x, self.lag = True, float(b), low_b
            return None
        if b - a <= TOLERANCE_RAD or self.steps >= ITERATIONS:
            self.done, self.x = True, float(0.5 * (a + b))
            if b - a <= TOLERANCE_RAD and low_a is not None and low_b is not None:
                self.lag = float(max(low_a, low_b))
            return None
        width, self.width = self.width, b - a
        if b - a > 0.25 * width:  # not closing in (a lag steps): eight points across it
            return list(a + (b - a) * np.arange(1, 9) / 9.0)
        mid = 0.5 * (a + b)
        secant = a - d_a * (b - a) / (d_b - d_a) if np.isfinite(d_a - d_b) else mid
        if not a < secant < b:
            secant = mid
        guard = 0.01 * (b - a)
        xs = [secant, secant - guard, secant + guard, mid]
        return [x for x in xs if a < x < b]

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
            self.steps, self.d0, x0 = 1, d, self.x
            a, b, c = parabola(lo - x0, hi - x0, d_lo, d, d_hi)
            roots = np.roots([a, b, c]) if abs(a) > 0.0 else np.array([-c / b])
            roots = np.real(roots[np.isreal(roots)]) + x0
            self.bracket = [lo, x0] if d > 0.0 else [x0, hi]
            good = roots[(roots >= self.bracket[0]) & (roots <= self.bracket[1])]
            return float(good[0]) if good.size else x0
        x0, d0, x1 = self.x0, self.d0, self.x
        if d != d0:
            x2 = x1 - d * (x1 - x0) / (d - d0)
            if self.bracket[0] <= x2 <= self.bracket[1]:
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
