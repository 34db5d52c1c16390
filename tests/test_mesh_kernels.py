"""The mesh cycle's compiled steps (:mod:`gearopt.mesh.kernels`) against the Python they replaced
(kept here as their reference): the hand-over guess's crossing against the cubics in Newton's
form and the Illinois method on Python floats, on the same four samples a pair; the contact
interval's run against the run search on numpy arrays; the hand-over iteration's interpolants
(the parabola through the nearest samples, the inverse interpolants' roots) against the sorted
picks on Python floats; the zones' node factors continued below the generated boundary, a
side's window and its start (carrying pair, TE peak guess, hand-over bracket), the swept
pairs' neighbours and the window's checks (the rows beyond it, its mesh centre, a lower pair
beyond it) against the numpy steps they replaced; all to the last bit, compiled and as
plain Python.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from types import SimpleNamespace

import numpy as np
import pytest

from gearopt.contact import zone_kernels
from gearopt.mesh import kernels
from gearopt.mesh.handover import newton_form, newton_value
from gearopt.mesh.zone import NEAR, SPREAD, Zones

from .numpy_zone import neighbours

VARIANTS = [kernels.crossing_root, getattr(kernels.crossing_root, "py_func", None)]
RUNS = [kernels.interior_run, getattr(kernels.interior_run, "py_func", None)]
PARABOLAS = [kernels.nearest_parabola, getattr(kernels.nearest_parabola, "py_func", None)]
ROOTS = [kernels.inverse_roots, getattr(kernels.inverse_roots, "py_func", None)]
EXTENDS = [kernels.extend_factors, getattr(kernels.extend_factors, "py_func", None)]
WINDOWS = [kernels.window_rows, getattr(kernels.window_rows, "py_func", None)]
SWEPT = [kernels.swept_pairs, getattr(kernels.swept_pairs, "py_func", None)]
STARTS = [kernels.side_start, getattr(kernels.side_start, "py_func", None)]
BEYOND = [kernels.beyond_rows, getattr(kernels.beyond_rows, "py_func", None)]
CHECKS = [kernels.window_check, getattr(kernels.window_check, "py_func", None)]


def illinois(func: Callable[[float], float], a: float, b: float, tol: float = 1e-12):
    """A root of ``func`` in [a, b] by the Illinois method (None without a sign change)."""
    fa, fb = func(a), func(b)
    if fa == 0.0:
        return a
    if fb == 0.0:
        return b
    if fa * fb > 0.0:
        return None
    for _ in range(100):
        c = b - fb * (b - a) / (fb - fa)
        fc = func(c)
        if fc == 0.0 or abs(c - b) <= tol:
            return c
        if fc * fb < 0.0:
            a, fa = b, fb
        else:
            fa *= 0.5
        b, fb = c, fc
    return b


def python_crossing(v, lag, near, centres, step, half):
    """The crossing (steps from the centres) by the Python functions, or NaN."""
    fits = []
    for rows, centre in zip(near, centres, strict=True):
        z = (v[rows] - centre) / step
        fits.append(newton_form(z.tolist(), lag[rows].tolist()))
    (za, ca), (zb, cb) = fits
    root = illinois(lambda x: newton_value(za, ca, x) - newton_value(zb, cb, x), -half, half)
    return math.nan if root is None else root


def python_run(v, inner, lag):
    """``(lo, hi, spread)`` of the run of interior samples holding the least lag, else the
    first longest, in the samples' order by ``v``."""
    order = np.argsort(v)
    inner, lag = inner[order], np.where(np.isfinite(lag), lag, np.inf)[order]
    first = np.flatnonzero(np.diff(inner.astype(int))) + 1
    last = np.append(first - 1, len(v) - 1).tolist()
    runs = [(a, b) for a, b in zip([0, *first.tolist()], last, strict=True) if inner[a]]
    if not runs:
        return -1, -1
    centre = int(np.argmin(lag))
    around = [r for r in runs if r[0] <= centre <= r[1]]
    lo, hi = around[0] if around else max(runs, key=lambda r: r[1] - r[0])
    return lo, hi, float(np.ptp(lag[lo : hi + 1]))


@pytest.mark.parametrize("crossing", [f for f in VARIANTS if f is not None])
def test_crossing_is_the_python_crossing_bit_for_bit(crossing):
    rng = np.random.default_rng(23)
    step, found = 0.01, 0
    for _ in range(300):
        v = np.sort(rng.uniform(-0.2, 0.2, 40))
        centres = np.array([rng.uniform(-0.1, 0.1), rng.uniform(-0.1, 0.1)])
        near = np.argsort(np.abs(v[None, :] - centres[:, None]), axis=1)[:, :4]
        near = np.ascontiguousarray(near)
        # two lag curves that cross near the centres: a parabola and a line, with noise
        x = (v - centres[0]) / step
        lag = 1e-4 * np.where(np.arange(40) % 2 == 0, x * x, 1.0 + x) + rng.normal(0, 1e-6, 40)
        edge = np.zeros(40, bool)
        half = rng.uniform(0.2, 1.0)
        got = crossing(v, lag, edge, near, centres, step, half)
        z = np.abs((v[near] - centres[:, None]) / step)
        if z.max() > 2.0:
            assert math.isnan(got)
            continue
        want = python_crossing(v, lag, near, centres, step, half)
        assert got == want or (math.isnan(got) and math.isnan(want))
        found += not math.isnan(got)
    assert found > 20  # crossings found, not only refusals


@pytest.mark.parametrize("run", [f for f in RUNS if f is not None])
def test_interior_run_is_the_run_search(run):
    rng = np.random.default_rng(7)
    for _ in range(300):
        m = int(rng.integers(1, 30))
        v = rng.permutation(np.arange(m) * 0.1 - 1.0)
        inner = rng.random(m) < 0.7
        lag = np.where(rng.random(m) < 0.1, np.inf, rng.normal(0.0, 1.0, m))
        inner &= np.isfinite(lag)
        lo, hi, spread = run(np.argsort(v), inner, lag)
        want = python_run(v, inner, lag)
        assert (lo, hi) == want[:2]
        if lo >= 0:
            assert spread == want[2]


def numpy_extended(factor_mm):
    """The node factors with the node below each column's lowest generated node continued
    linearly from the two above it, by numpy array steps (a copy)."""
    f = np.array(factor_mm, float)
    n_p = f.shape[-1]
    gen = f > 0.0
    low = np.argmax(gen, axis=-1)
    r, i = np.nonzero((low >= 1) & (low + 1 < n_p) & gen.any(axis=-1))
    j = low[r, i]
    above = f[r, i, j + 1]
    f[r, i, j - 1] = np.where(above > 0.0, 2.0 * f[r, i, j] - above, f[r, i, j])
    return f


@pytest.mark.parametrize("extend", [f for f in EXTENDS if f is not None])
def test_extend_factors_is_the_numpy_steps(extend):
    rng = np.random.default_rng(19)
    changed = 0
    for _ in range(50):
        rows, n_f, n_p = (int(k) for k in rng.integers(1, 9, 3))
        f = rng.uniform(10.0, 60.0, (rows, n_f, n_p))
        # generated from a random lowest node up (none, all, or the top one alone), some
        # nodes above it off the flank too
        low = rng.integers(0, n_p + 1, (rows, n_f))
        f[np.arange(n_p)[None, None, :] < low[..., None]] = 0.0
        f[rng.random(f.shape) < 0.1] = 0.0
        want = numpy_extended(f)
        got = f.copy()
        extend(got)
        assert np.array_equal(got, want)
        changed += int(np.sum(got != f))
    assert changed > 100  # nodes continued, not only copies


def python_parabola(samples, x):
    """The parabola through the three samples ``(x, lag)`` nearest ``x`` (a stable sort's
    first three) at ``x``."""
    near = sorted(samples, key=lambda p: abs(p[0] - x))[:3]
    z, c = newton_form([p[0] for p in near], [p[1] for p in near])
    return newton_value(z, c, x)


def python_inverse_root(a, b, d_a, d_b, trail, count):
    """The inverse interpolant's root through the bracket's ends and the ``count`` trail
    points nearest it (a stable sort's first), or NaN."""
    others = sorted(
        ((x, d) for x, d in trail if x != a and x != b),
        key=lambda p: min(abs(p[0] - a), abs(p[0] - b)),
    )[:count]
    d = [d_a, d_b] + [p[1] for p in others]
    if len(others) < count or len(set(d)) < len(d):
        return math.nan
    z, c = newton_form(d, [a, b] + [p[0] for p in others])
    return newton_value(z, c, 0.0)


@pytest.mark.parametrize("parabola", [f for f in PARABOLAS if f is not None])
def test_nearest_parabola_is_the_sorted_pick(parabola):
    rng = np.random.default_rng(29)
    for _ in range(300):
        m = int(rng.integers(3, 40))
        # abscissae on a coarse lattice: equal distances (ties) are common
        xs = rng.permutation(rng.choice(np.arange(-20, 21) * 0.25, m, replace=False))
        samples = [(float(x), float(np.sin(x) + 1e-3 * x * x)) for x in xs]
        x = float(rng.choice(np.arange(-40, 41) * 0.125))
        want = python_parabola(samples, x)
        assert parabola(np.array(samples), x) == want


@pytest.mark.parametrize("roots", [f for f in ROOTS if f is not None])
def test_inverse_roots_are_the_sorted_picks(roots):
    rng = np.random.default_rng(31)
    found = 0
    for _ in range(300):
        a, b = -0.5, 0.5
        m = int(rng.integers(0, 12))
        xs = rng.choice(np.arange(-12, 13) * 0.125, m)  # repeats, ends and ties among them
        d = [(x - 0.1) * (1.0 + 0.2 * x) for x in xs.tolist()]
        trail = [(a, -0.6), (b, 0.4)] + list(zip(xs.tolist(), d, strict=True))
        if rng.random() < 0.2 and m:  # a D value repeated
            trail.append((0.3, d[0]))
        got = roots(a, b, -0.6, 0.4, np.array(trail))
        for count in (1, 2):
            want = python_inverse_root(a, b, -0.6, 0.4, trail, count)
            assert got[count - 1] == want or (math.isnan(got[count - 1]) and math.isnan(want))
            found += not math.isnan(want)
    assert found > 200  # roots found, not only refusals


@pytest.mark.parametrize("rows", [f for f in WINDOWS if f is not None])
def test_window_rows_are_numpy_round_and_unique(rows):
    rng = np.random.default_rng(23)
    for trial in range(300):
        n, pitch = int(rng.integers(2, 30)), 2.0 * math.pi / int(rng.integers(5, 40))
        t = np.linspace(-pitch, pitch, n)
        window = np.arange(int(rng.integers(1, 6)))
        window -= (len(window) - 1) // 2 + int(trial % 4 == 0)
        centre = 0.0 if trial % 3 == 0 else float(rng.uniform(-2.0, 2.0) * pitch)
        ids = np.round((centre - t) / pitch)[:, None] + window[None, :]
        u = t[:, None] + ids * pitch
        key = np.round(u.ravel() / pitch * 1e9).astype(np.int64)
        _, first, inv = np.unique(key, return_index=True, return_inverse=True)
        got_ids, got_u = np.empty(ids.shape), np.empty(ids.shape)
        got_first, got_inv = np.empty(u.size, np.intp), np.empty(u.size, np.intp)
        count = rows(t, centre, window, pitch, got_ids, got_u, got_first, got_inv)
        assert np.array_equal(got_ids.view(np.int64), ids.view(np.int64))
        assert np.array_equal(got_u.view(np.int64), u.view(np.int64))
        assert count == len(first) and np.array_equal(got_first[:count], first)
        assert np.array_equal(got_inv, inv.ravel())


@pytest.mark.parametrize("pairs", [f for f in SWEPT if f is not None])
def test_swept_pairs_are_the_numpy_neighbours(pairs):
    rng = np.random.default_rng(29)
    linked = 0
    for _ in range(300):
        n = int(rng.integers(0, 200))
        ray = np.sort(rng.integers(0, 9, n)).astype(np.intp)
        key, position = rng.integers(-3, 3, n), rng.integers(0, 6, n)
        prev, nxt = neighbours(ray, key, position)
        got_prev, got_nxt, start = (
            np.empty(n, np.intp),
            np.empty(n, np.intp),
            np.empty(n + 2, np.intp),
        )
        count, ordered = pairs(ray, key, position, got_prev, got_nxt, start)
        first = np.flatnonzero(np.r_[True, np.diff(ray) != 0])
        assert ordered and np.array_equal(got_prev, prev) and np.array_equal(got_nxt, nxt)
        assert count == len(first) and np.array_equal(start[:count], first)
        linked += int((prev >= 0).sum())
    assert linked > 1000  # neighbours found, not only -1


def python_start(minimum, inv, ids, t, pitch, step):
    """A side's carrying pair, TE peak guess and hand-over bracket by the numpy and Python
    steps :func:`gearopt.mesh.kernels.side_start` replaced."""
    g = minimum[inv].reshape(ids.shape)
    rows = np.arange(len(t))
    carrying = np.argmin(g, axis=1)
    lag, pair_id = g[rows, carrying], ids[rows, carrying]
    act = np.flatnonzero(pair_id == pair_id[np.argmin(lag)])
    kk = act[np.argmin(lag[act])]
    v_peak = t[kk] + pair_id[kk] * pitch
    if 0 < kk < len(t) - 1 and pair_id[kk - 1] == pair_id[kk] == pair_id[kk + 1]:
        gm, g0, gp = lag[kk - 1], lag[kk], lag[kk + 1]
        if gm - 2.0 * g0 + gp > 0.0:
            v_peak += float(np.clip(0.5 * (gm - gp) / (gm - 2.0 * g0 + gp), -1.0, 1.0)) * step
    bracket = None
    for k in [k for k in range(len(t) - 1) if pair_id[k + 1] - pair_id[k] == -1]:
        cols = [
            [c for c, x in enumerate(ids[k + j].tolist()) if x == pair_id[k] - m]
            for m in (0, 1)
            for j in (0, 1)
        ]
        if not all(cols):
            continue
        d_lo = float(g[k, cols[0][0]]) - float(g[k, cols[2][0]])
        d_hi = float(g[k + 1, cols[1][0]]) - float(g[k + 1, cols[3][0]])
        if math.isfinite(d_lo) and math.isfinite(d_hi) and d_lo <= 0.0 <= d_hi and d_hi > d_lo:
            bracket = ((k, *(c[0] for c in cols)), d_lo, d_hi)
            break
    return g, carrying, lag, pair_id, float(v_peak), bracket


@pytest.mark.parametrize("start", [f for f in STARTS if f is not None])
def test_side_start_is_the_numpy_steps(start):
    rng = np.random.default_rng(31)
    brackets = 0
    for _ in range(300):
        n, pairs, pitch = int(rng.integers(3, 25)), int(rng.integers(1, 5)), 0.3
        t = np.linspace(-pitch, pitch, n)
        ids = np.round(-t / pitch)[:, None] + (np.arange(pairs) - (pairs - 1) // 2)[None, :]
        u = t[:, None] + ids * pitch
        minimum = (u.ravel() - 0.05) ** 2 + rng.normal(0.0, 1e-4, u.size)
        minimum[rng.random(u.size) < 0.1] = np.inf
        minimum[np.arange(n) * pairs + rng.integers(0, pairs, n)] = rng.random(n)  # one touches
        inv = np.arange(u.size)
        out = [np.empty(ids.shape) for _ in range(4)]
        out[1] = np.empty(ids.shape, bool)
        edge = rng.random(u.size) < 0.2
        carrying, lag, pair_id, touching, v_peak, _, _, bracket, d_lo, d_hi = start(
            minimum, edge, minimum + 1.0, minimum + 2.0, inv, ids, t, pitch, t[1] - t[0], 0.0, *out
        )
        g, want_carrying, want_lag, want_id, want_peak, want_bracket = python_start(
            minimum, inv, ids, t, pitch, t[1] - t[0]
        )
        assert (
            touching and np.array_equal(out[0], g) and np.array_equal(out[1], edge.reshape(g.shape))
        )
        assert np.array_equal(out[2], g + 1.0) and np.array_equal(carrying, want_carrying)
        assert np.array_equal(lag, want_lag) and np.array_equal(pair_id, want_id)
        assert v_peak == want_peak
        if want_bracket is None:
            assert bracket[0] == -1
        else:
            assert (tuple(bracket), d_lo, d_hi) == want_bracket
            brackets += 1
    assert brackets > 30  # hand-overs bracketed, not only refusals


RAYS = [zone_kernels.ray_samples, getattr(zone_kernels.ray_samples, "py_func", None)]


@pytest.mark.parametrize("samples", [f for f in RAYS if f is not None])
def test_ray_samples_are_to_edge_and_the_fractions_bit_for_bit(samples):
    """The rays' samples to the grid's edge (or their reach) as :meth:`Zones.to_edge` and
    numpy's minimum give them, NaN and the sign of zero included (a ray along the grid's
    edge, from a corner, from outside, a NaN origin or reach, zero directions)."""
    rng = np.random.default_rng(31)
    box = np.array([-1.5, -0.5, 2.0, 3.0])
    grid = SimpleNamespace(box=box)
    picks = np.array([-2.0, -1.5, -0.5, -0.0, 0.0, 0.5, 2.0, 3.0, 4.0, np.nan])
    bits = 0
    for _ in range(200):
        k = int(rng.integers(1, 40))
        origins = np.where(rng.random((k, 2)) < 0.4, rng.choice(picks, (k, 2)), 0.0)
        origins += np.where(rng.random((k, 2)) < 0.5, rng.uniform(-2.0, 3.5, (k, 2)), 0.0)
        directions = np.where(
            rng.random((k, 2)) < 0.3,
            rng.choice([-0.0, 0.0, np.nan], (k, 2)),
            rng.normal(size=(k, 2)),
        )
        reach = np.where(
            rng.random(k) < 0.2, rng.choice([np.inf, np.nan, 0.0], k), rng.uniform(0, 5, k)
        )
        spread = rng.random(k) < 0.5
        tau = np.empty((k, len(SPREAD)))
        with np.errstate(invalid="ignore"):  # (inf times a zero fraction: NaN, as numpy's)
            samples(Zones.rays(origins, directions), box, reach, spread, SPREAD, NEAR, tau)
            far = np.minimum(reach, Zones.to_edge(grid, origins, directions))
            want = far[:, None] * np.where(spread[:, None], SPREAD[None, :], NEAR[None, :])
        assert np.array_equal(np.isnan(tau), np.isnan(want))
        same = ~np.isnan(want)
        assert np.array_equal(tau[same], want[same])
        assert np.array_equal(np.signbit(tau[same]), np.signbit(want[same]))
        bits += int((np.isnan(want).any(axis=1) | (want == 0.0).any(axis=1)).sum())
    assert bits > 200  # the NaN and zero cases met, not only clean rays


def numpy_outline_rays(u, sep, compound, interval, contact, reach):
    """:meth:`Zones.outline`'s stations and rays, numpy's steps (before the kernels)."""
    on = (u >= interval[0] - 1e-9) & (u <= interval[1] + 1e-9)
    inside = np.flatnonzero((sep <= compound) & on)
    _, first = np.unique(np.round(u[inside] * 1e9), return_index=True)
    station = inside[first]
    if station.size > 12:
        station = station[np.linspace(0, station.size - 1, 12).round().astype(np.intp)]
    if station.size < 2:
        return station, None
    c = contact[station]
    tangent = np.empty_like(c)
    tangent[1:-1] = (c[2:] - c[:-2]) / 2.0
    tangent[0], tangent[-1] = c[1] - c[0], c[-1] - c[-2]
    tangent /= np.maximum(np.hypot(tangent[:, 0], tangent[:, 1]), 1e-300)[:, None]
    across = np.stack([-tangent[:, 1], tangent[:, 0]], axis=1)
    origins = np.concatenate([c, c, c[[0, -1]]])
    directions = np.concatenate([across, -across, [-tangent[0], tangent[-1]]])
    from_station = np.concatenate([np.arange(len(c))] * 2 + [[0, len(c) - 1]])
    offset = np.abs(
        (contact[None, :, 0] - c[:, None, 0]) * tangent[:, 0, None]
        + (contact[None, :, 1] - c[:, None, 1]) * tangent[:, 1, None]
    )
    ray, near = np.nonzero(offset[from_station] <= reach)
    return station, (origins, directions, ray, near)


OUTLINES = [
    (zone_kernels.outline_stations, zone_kernels.outline_rays),
    tuple(
        getattr(f, "py_func", None)
        for f in (zone_kernels.outline_stations, zone_kernels.outline_rays)
    ),
]


@pytest.mark.parametrize("kernel", [k for k in OUTLINES if k[0] is not None])
def test_outline_stations_and_rays_are_the_numpy_steps(kernel):
    """The outline's stations (inside, on the interval, one per rotation to a billionth, at
    most twelve evenly) and rays (the path's tangents, the rays across and along it, the rows
    near each station) as numpy's unique, linspace, gradient and nonzero give them, bit for
    bit: repeated rotations, few and many stations."""
    stations, rays = kernel
    rng = np.random.default_rng(41)
    many = 0
    for _ in range(400):
        n = int(rng.integers(0, 90))
        u = np.round(rng.uniform(-1.0, 1.0, n), int(rng.integers(1, 4)))  # (repeats)
        u[rng.random(n) < 0.1] += 3e-10  # (the same rotation to a billionth, or the next)
        sep = rng.uniform(-0.005, 0.02, n)
        interval = np.sort(rng.uniform(-1.2, 1.2, 2))
        contact = rng.normal(size=(n, 2)) * rng.uniform(0.1, 20.0)
        if rng.random() < 0.1:
            contact[:, 1] = 0.0
        reach = float(rng.uniform(0.0, 10.0))
        want, want_rays = numpy_outline_rays(u, sep, 0.0065, interval, contact, reach)
        got = np.empty(n, np.intp)
        count = stations(u, sep, 0.0065, interval[0] - 1e-9, interval[1] + 1e-9, 12, got)
        assert np.array_equal(got[:count], want)
        if want_rays is None:
            continue
        many += count == 12
        k = 2 * count + 2
        origins, directions = np.empty((k, 2)), np.empty((k, 2))
        ray, near = np.empty(k * n, np.intp), np.empty(k * n, np.intp)
        found = rays(
            np.ascontiguousarray(contact[want]), contact, reach, origins, directions, ray, near
        )
        for a, b in zip((origins, directions, ray[:found], near[:found]), want_rays, strict=True):
            assert np.array_equal(a, b) and np.array_equal(np.signbit(a), np.signbit(b))
    assert many > 30  # the evenly picked stations met, not only the few


def python_keys(u, pitch) -> list:
    """Relative rotations as keys that match to a billionth of a pitch (numpy's round)."""
    return np.round(u / pitch * 1e9).tolist()


def python_ends(u, carrying, pitch):
    """At each end of a window: where its end pair carries and the rotations beyond it."""
    for slot, sign in ((0, -1.0), (u.shape[1] - 1, 1.0)):
        at = np.flatnonzero(carrying == slot)
        yield at, u[at, slot] + sign * pitch


def python_beyond(v, u, carrying, pitch) -> list:
    """The rotations beyond the window's ends that the sample ``v`` does not hold."""
    known = set(python_keys(v, pitch))
    out = []
    for _, beyond in python_ends(u, carrying, pitch):
        keys = python_keys(beyond, pitch)
        out += [x for x, key in zip(beyond.tolist(), keys, strict=True) if key not in known]
    return out


def python_check(v, g, u, carrying, lag, pitch, flat):
    """The mesh centre and the lower pair beyond the window, as numpy steps and a dict."""
    gg = np.where(np.isfinite(g), g, np.inf)
    central = np.abs(v) <= 0.5 * pitch + 1e-9
    best = int(np.argmin(gg))
    centre = 0.0
    if not central[best] and gg[best] < np.min(gg[central], initial=np.inf) - flat:
        centre = float(v[best])
    known = dict(zip(python_keys(v, pitch), g.tolist(), strict=True))
    lower = False
    for at, beyond in python_ends(u, carrying, pitch):
        low = np.array([known.get(key, np.inf) for key in python_keys(beyond, pitch)])
        lower |= bool(np.any(low < lag[at]))
    return centre, lower


def window_case(rng, trial):
    """A random window, its carrying pairs and lags, and samples that hold some of the rotations
    beyond it (repeated: the last one counts), with infinite and NaN lags among them."""
    n, pairs = int(rng.integers(2, 25)), int(rng.integers(1, 6))
    pitch = 2.0 * math.pi / int(rng.integers(5, 40))
    t = np.linspace(-pitch, pitch, n)
    u = t[:, None] + (np.arange(pairs) - (pairs - 1) // 2)[None, :] * pitch
    carrying = rng.integers(0, pairs, n).astype(np.intp)
    lag = rng.normal(size=n) * 1e-4
    beyond = np.concatenate([u[:, 0] - pitch, u[:, -1] + pitch])
    v = np.concatenate([u.ravel(), rng.choice(beyond, int(rng.integers(0, 2 * n)))])
    v = v + rng.normal(size=v.size) * pitch * 1e-12 * (trial % 2)  # (within a key, or not)
    rng.shuffle(v)
    g = rng.normal(size=v.size) * 1e-4 - 0.5e-4 * (trial % 3)
    g[rng.random(v.size) < 0.1] = np.inf
    g[rng.random(v.size) < 0.05] = np.nan
    g[rng.random(v.size) < 0.02] = -np.inf
    if trial % 5 == 0:
        v = v - float(rng.uniform(-1.5, 1.5)) * pitch
    return v, g, u, carrying, lag, pitch


@pytest.mark.parametrize("beyond", [f for f in BEYOND if f is not None])
def test_beyond_rows_are_the_keyed_set_steps(beyond):
    rng = np.random.default_rng(39)
    for trial in range(400):
        v, _, u, carrying, _, pitch = window_case(rng, trial)
        want = python_beyond(v, u, carrying, pitch)
        out = np.empty(2 * len(u))
        count = beyond(v, u, carrying, pitch, out)
        assert np.array_equal(out[:count].view(np.int64), np.array(want).view(np.int64))


@pytest.mark.parametrize("check", [f for f in CHECKS if f is not None])
def test_window_check_is_the_numpy_and_dict_steps(check):
    rng = np.random.default_rng(41)
    found = set()
    for trial in range(400):
        v, g, u, carrying, lag, pitch = window_case(rng, trial)
        flat = 1e-6 * (trial % 4)
        want = python_check(v, g, u, carrying, lag, pitch, flat)
        centre, lower = check(v, g, u, carrying, lag, pitch, flat)
        assert np.float64(centre).view(np.int64) == np.float64(want[0]).view(np.int64)
        assert bool(lower) == want[1]
        found.add((want[0] != 0.0, want[1]))
    assert found == {(False, False), (False, True), (True, False), (True, True)}
