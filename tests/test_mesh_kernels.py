"""The mesh cycle's compiled steps (:mod:`gearopt.mesh.kernels`) against the Python they replaced
(kept here as their reference): the hand-over guess's crossing against the cubics in Newton's
form and the Illinois method on Python floats, on the same four samples a pair; the contact
interval's run against the run search on numpy arrays; the hand-over iteration's interpolants
(the parabola through the nearest samples, the inverse interpolants' roots) against the sorted
picks on Python floats; the zones' node factors continued below the generated boundary against
the numpy steps they replaced; all to the last bit, compiled and as plain Python.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
import pytest

from gearopt.mesh import kernels
from gearopt.mesh.handover import newton_form, newton_value

VARIANTS = [kernels.crossing_root, getattr(kernels.crossing_root, "py_func", None)]
RUNS = [kernels.interior_run, getattr(kernels.interior_run, "py_func", None)]
PARABOLAS = [kernels.nearest_parabola, getattr(kernels.nearest_parabola, "py_func", None)]
ROOTS = [kernels.inverse_roots, getattr(kernels.inverse_roots, "py_func", None)]
EXTENDS = [kernels.extend_factors, getattr(kernels.extend_factors, "py_func", None)]


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
