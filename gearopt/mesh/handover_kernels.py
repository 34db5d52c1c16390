"""The hand-over iteration's step compiled (numba; plain Python without it, as
:mod:`gearopt.contact.kernels`): :func:`iteration_step` takes in a step's lags, moves the
bracket and picks the next points in one call, on the state of
:class:`gearopt.mesh.handover.HandOver` held in arrays (:data:`STATE` names its entries), where
the Python of :meth:`~gearopt.mesh.handover.HandOver.take_iteration` cost more than the
evaluations it steers on the misaligned TCAs of a study (some ten steps a TCA). The same
operations on the same floats, in the same order (Python's ``min`` and ``max`` keep the first
of equals): the same results to the bit.
"""

from __future__ import annotations

import math

import numpy as np

from gearopt.jit import ENABLED, compiled
from gearopt.mesh.kernels import inverse_roots, nearest_parabola

__all__ = ["ENABLED", "STATE", "iteration_step", "warm"]

#: the entries of the iteration's state vector (``has_*``: 1.0 where the value is known, the
#: Python's None otherwise; ``end_*``: both pairs' lags at the bracket's ends, leaving then
#: incoming; ``smooth``: -1 for None)
STATE = (
    "a",
    "b",
    "d_a",
    "d_b",
    "low_a",
    "low_b",
    "has_low_a",
    "has_low_b",
    "end_a0",
    "end_a1",
    "end_b0",
    "end_b1",
    "has_end_a",
    "has_end_b",
    "width",
    "rise",
    "steps",
    "guarded",
    "smooth",
    "done",
    "x",
    "lag",
    "has_lag",
)

#: the index of each entry of :data:`STATE`
(
    A,
    B,
    D_A,
    D_B,
    LOW_A,
    LOW_B,
    HAS_LOW_A,
    HAS_LOW_B,
    END_A0,
    END_A1,
    END_B0,
    END_B1,
    HAS_END_A,
    HAS_END_B,
    WIDTH,
    RISE,
    STEPS,
    GUARDED,
    SMOOTH,
    DONE,
    X,
    LAG,
    HAS_LAG,
) = range(len(STATE))


@compiled
def _smooth_pair(state, counts, single):
    """:meth:`gearopt.mesh.handover.HandOver.smooth_pair` on the state: the pair (0, 1) whose
    lag is smooth across the bracket, or -1."""
    a, b, d_a, d_b = state[A], state[B], state[D_A], state[D_B]
    if b - a > single or state[HAS_END_A] == 0.0 or state[HAS_END_B] == 0.0:
        return -1
    for k in range(END_A0, END_B1 + 1):
        if not math.isfinite(state[k]):
            return -1
    for pair in range(2):
        change = abs(state[END_B0 + pair] - state[END_A0 + pair])
        if change <= 0.05 * (d_b - d_a) and counts[pair] >= 3:
            return pair
    return -1


@compiled
def iteration_step(state, xs, got, asked, samples, counts, trail, limits, out):
    """Take in an iteration step's lags and choose the next points
    (:meth:`gearopt.mesh.handover.HandOver.take_iteration` and its ``next_points``).

    Parameters
    ----------
    state
        The iteration's state (:data:`STATE`), updated.
    xs
        ``(k,)`` the step's points.
    got, asked
        ``(k, 2)`` the lags sampled at the points (pair 0 leaving, 1 incoming) and where they
        were (elsewhere the pair's lag is interpolated, the parabola through its three nearest
        samples).
    samples
        ``(2, cap, 2)`` each pair's finite sampled ``(x, lag)`` so far, appended to.
    counts
        ``(3,)`` how many of ``samples``' rows each pair holds, then of ``trail``'s; updated.
    trail
        ``(cap, 2)`` every ``(x, D)`` with D finite so far, appended to.
    limits
        ``(tolerance, iterations, spread, single)``: :data:`~gearopt.mesh.handover.TOLERANCE_RAD`,
        :data:`~gearopt.mesh.handover.ITERATIONS`, :data:`~gearopt.mesh.handover.SPREAD`,
        :data:`~gearopt.mesh.handover.SINGLE_RAD`.
    out
        ``(spread,)`` out: the next points, in the Python's order.

    Returns
    -------
    int
        How many next points (0: settled, at ``state`` x with its lag where ``has_lag``).
    """
    tolerance, iterations, spread, single = limits[0], limits[1], limits[2], limits[3]
    state[STEPS] += 1.0
    a, b, d_a, d_b = state[A], state[B], state[D_A], state[D_B]
    k = xs.shape[0]
    # the points: the bracket's ends and the step's points inside it with D not NaN
    px, pd, pl = np.empty(k + 2), np.empty(k + 2), np.empty(k + 2)
    pe0, pe1 = np.empty(k + 2), np.empty(k + 2)
    phl, phe = np.empty(k + 2), np.empty(k + 2)
    px[0], pd[0], pl[0], phl[0] = a, d_a, state[LOW_A], state[HAS_LOW_A]
    pe0[0], pe1[0], phe[0] = state[END_A0], state[END_A1], state[HAS_END_A]
    m = 1
    for j in range(k):
        x = xs[j]
        g0 = 0.0
        g1 = 0.0
        for pair in range(2):
            if asked[j, pair]:
                value = got[j, pair]
                if math.isfinite(value):
                    c = counts[pair]
                    samples[pair, c, 0] = x
                    samples[pair, c, 1] = value
                    counts[pair] = c + 1
            else:
                value = nearest_parabola(samples[pair, : counts[pair]], x)
            if pair == 0:
                g0 = value
            else:
                g1 = value
        d = g0 - g1
        if math.isfinite(d):
            c = counts[2]
            trail[c, 0] = x
            trail[c, 1] = d
            counts[2] = c + 1
        if a < x < b and d == d:
            px[m], pd[m] = x, d
            pl[m] = g1 if g1 < g0 else g0  # Python's min(g)
            phl[m] = 1.0
            pe0[m], pe1[m], phe[m] = g0, g1, 1.0
            m += 1
    px[m], pd[m], pl[m], phl[m] = b, d_b, state[LOW_B], state[HAS_LOW_B]
    pe0[m], pe1[m], phe[m] = state[END_B0], state[END_B1], state[HAS_END_B]
    m += 1
    for i in range(m - 1):
        d0, d1 = pd[i], pd[i + 1]
        if d0 <= 0.0 < d1 or d1 == 0.0:
            state[A], state[B], state[D_A], state[D_B] = px[i], px[i + 1], d0, d1
            state[LOW_A], state[LOW_B], state[HAS_LOW_A], state[HAS_LOW_B] = (
                pl[i],
                pl[i + 1],
                phl[i],
                phl[i + 1],
            )
            state[END_A0], state[END_A1], state[HAS_END_A] = pe0[i], pe1[i], phe[i]
            state[END_B0], state[END_B1], state[HAS_END_B] = pe0[i + 1], pe1[i + 1], phe[i + 1]
            break
    a, b, d_a, d_b = state[A], state[B], state[D_A], state[D_B]
    if d_b == 0.0:
        state[DONE], state[X] = 1.0, b
        state[LAG], state[HAS_LAG] = state[LOW_B], state[HAS_LOW_B]
        return 0
    if b - a <= tolerance or state[STEPS] >= iterations:
        state[DONE], state[X] = 1.0, 0.5 * (a + b)
        if b - a <= tolerance and state[HAS_LOW_A] != 0.0 and state[HAS_LOW_B] != 0.0:
            low_a, low_b = state[LOW_A], state[LOW_B]
            state[LAG], state[HAS_LAG] = (low_b if low_b > low_a else low_a), 1.0  # Python's max
        return 0
    # the next points (HandOver.next_points)
    w = b - a
    width = state[WIDTH]
    state[WIDTH] = w
    rise = d_b - d_a
    previous = state[RISE]
    state[RISE] = rise
    closing = w <= 0.25 * width
    stepping = not math.isfinite(rise) or (closing and rise > 0.5 * previous)
    least = d_b if d_b < -d_a else -d_a
    retry = not closing and state[GUARDED] == 1.0 and least < 0.01 * rise
    if stepping or not (closing or retry):
        state[GUARDED] = 0.0
        state[SMOOTH] = _smooth_pair(state, counts, single) if stepping else -1.0
        n = int(spread)
        for j in range(n):
            out[j] = a + w * float(j + 1) / float(n + 1)
        return n
    state[GUARDED] = 2.0 if retry else 1.0
    state[SMOOTH] = -1.0
    secant = a - d_a * w / (d_b - d_a)
    r1, r2 = inverse_roots(a, b, d_a, d_b, trail[: counts[2]])
    x = secant
    before = math.nan
    found = 1
    for r in (r1, r2):
        if a < r < b:
            before, x = x, r
            found += 1
    error = abs(x - before) if found > 1 else 0.005 * w
    guard = 2.0 * error
    if 0.25 * tolerance > guard:  # Python's max
        guard = 0.25 * tolerance
    guard = guard * (10.0 if retry else 1.0)
    half = 0.5 * (x - a)
    cand = np.empty(4)
    cand[0] = x - (half if half < guard else guard)
    cand[1] = x
    half = 0.5 * (b - x)
    cand[2] = x + (half if half < guard else guard)
    n_cand = 3
    if guard > 0.125 * w or retry:
        cand[3] = 0.5 * (a + b)
        n_cand = 4
    n = 0
    for j in range(n_cand):
        if a < cand[j] < b:
            out[n] = cand[j]
            n += 1
    return n


def warm() -> None:
    """Compile the kernel, or load it from the disk cache (as
    :func:`gearopt.mesh.kernels.warm`); nothing without the kernels."""
    if not ENABLED:
        return
    state = np.zeros(len(STATE))
    state[B], state[D_A], state[D_B] = 1.0, -1.0, 1.0
    samples, trail = np.zeros((2, 4, 2)), np.zeros((4, 2))
    iteration_step(
        state,
        np.array([0.5]),
        np.zeros((1, 2)),
        np.ones((1, 2), np.bool_),
        samples,
        np.zeros(3, np.intp),
        trail,
        np.array([1e-9, 40.0, 7.0, 1e-4]),
        np.empty(7),
    )
