"""The compiled steps around a clearance-field sample against plain numpy/Python references, to
the bit: :func:`gearopt.contact.minima.minima_starts` (each row's node minimum, numpy's argmin
with its NaN rule, and its lowest refinable nodes) and :func:`gearopt.contact.recall.recall_rows`
(the last window sample's rows matched as a dict of their tuples matches them)."""

from __future__ import annotations

import numpy as np
import pytest

from gearopt.contact.minima import minima_starts
from gearopt.contact.recall import NodeFieldRecall, recall_rows


def _fields(rng, n, nodes):
    field = rng.normal(size=(n, nodes))
    field[rng.random((n, nodes)) < 0.3] = np.inf
    field[1, :] = np.inf  # a row off the flanks
    field[2, rng.integers(0, nodes, 3)] = np.nan  # NaNs after numbers
    field[3, 0] = np.nan  # a NaN first
    field[4, 5:9] = field[4, 5]  # equal values: the first wins
    return field


@pytest.mark.parametrize("candidates", [1, 2, 3])
def test_minima_starts_gives_numpys_minima_and_lowest_refinable_nodes(candidates):
    rng = np.random.default_rng(5)
    n, n_f, n_p = 12, 5, 7
    field = _fields(rng, n, n_f * n_p)
    side = rng.integers(0, 2, n + 2)
    refined = rng.random(n) < 0.7
    keep = rng.random((2, n_f * n_p)) < 0.8
    grid = (np.linspace(0.0, 4.0, n_f), np.linspace(-1.0, 1.0, n_p))
    tolerances = np.array([[1e-5, 2e-5], [0.05, 0.1]])
    point = np.empty((3, n))
    near = np.array([[0.5, 1.5], [0.1, -0.2]])
    at, which, s, t, best, caps, group, tol = minima_starts(
        field, side, refined, keep, candidates, near, True, tolerances, grid, point
    )
    ref_at = field.argmin(axis=1)
    assert np.array_equal(at, ref_at)
    assert np.array_equal(point[0], field[np.arange(n), ref_at], equal_nan=True)
    assert np.array_equal(point[1], grid[0][ref_at // n_p])
    assert np.array_equal(point[2], grid[1][ref_at % n_p])
    starts = []
    for r in np.flatnonzero(
        refined
    ):  # the lowest refinable nodes in turn, the first of equals first, no NaN
        inner = np.where(keep[side[r]] & ~np.isnan(field[r]), field[r], np.inf)
        for _ in range(candidates):
            g = int(inner.argmin())
            if np.isfinite(inner[g]):
                starts.append((r, g, inner[g]))
            inner[g] = np.inf
    k = len(starts)
    assert which[:k].tolist() == [r for r, _, _ in starts]
    assert which[k:].tolist() == [n, n + 1]
    assert np.array_equal(s[:k], [grid[0][g // n_p] for _, g, _ in starts])
    assert np.array_equal(t[:k], [grid[1][g % n_p] for _, g, _ in starts])
    assert np.array_equal(best[:k], [v for _, _, v in starts])
    assert np.array_equal(s[k:], near[0]) and np.array_equal(t[k:], near[1])
    assert np.isnan(best[k:]).all() and group[k:].tolist() == [1, 1]
    assert np.array_equal(tol, tolerances[0, side[which]])
    assert caps.tolist() == [4, 3]


def _dict_recall(side, phi, angle, last, fields, out):
    """The recall's Python reference: the last rows as a dict of their tuples."""
    where = {key: r for r, key in enumerate(zip(*(a.tolist() for a in last), strict=True))}
    keys = zip(side.tolist(), phi.tolist(), angle.tolist(), strict=True)
    at = [where.get(key, -1) for key in keys]
    for r, a in enumerate(at):
        if a >= 0:
            out[:, r] = fields[:, a]
    return np.flatnonzero(np.array(at) < 0)


def test_recall_rows_matches_the_rows_as_a_dict_of_their_tuples():
    rng = np.random.default_rng(3)
    m, nodes = 40, 11
    last = (rng.integers(0, 2, m), np.linspace(-0.3, 0.4, m), np.zeros(m))
    last[1][7] = np.nan  # NaN never matches
    last[1][8] = -0.0
    fields = rng.normal(size=(3, m, nodes))
    # a window shifted and widened, a row of another side, a gear angle, -0.0 and 0.0
    side = np.concatenate([last[0][5:], [0, 1, 0, last[0][8]]])
    phi = np.concatenate([last[1][5:], [0.9, last[1][12], last[1][13], 0.0]])
    angle = np.zeros(len(phi))
    angle[-3] = 1e-3
    side[-2] = 1 - last[0][13]
    out, ref = np.full((3, len(phi), nodes), -1.0), np.full((3, len(phi), nodes), -1.0)
    new = recall_rows(side, phi, angle, *last, fields, out)
    assert np.array_equal(new, _dict_recall(side, phi, angle, last, fields, ref))
    assert np.array_equal(out, ref)
    assert new.tolist() == [2, 35, 36, 37]  # the NaN, a new angle, a gear angle, a side


def test_recall_remembers_window_samples_only_while_active():
    recall = NodeFieldRecall()
    n, nodes = 40, 3
    phi, side, angle = np.linspace(0.0, 1.0, n), np.zeros(n, np.intp), np.zeros(n)
    out = np.arange(3.0 * n * nodes).reshape(3, n, nodes)
    assert recall.fill(side, phi, angle, out) is None  # not active
    recall.switch(True)
    assert recall.fill(side, phi, angle, out) is None  # nothing before
    shifted = np.concatenate([phi[4:], [2.0, 3.0, 4.0, 5.0]])
    again = np.empty_like(out)
    new = recall.fill(side, shifted, angle, again)
    assert new.tolist() == [36, 37, 38, 39]
    assert np.array_equal(again[:, :36], out[:, 4:])
    assert recall.fill(side[:5], shifted[:5], angle[:5], again[:, :5]) is None  # few rows
