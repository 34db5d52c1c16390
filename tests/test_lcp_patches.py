"""The load distribution on contact patches by compiled kernels
(gearopt.loaded.lcp.solve_load_patches, PatchCompliance): its columns against an independent
construction, its solutions against the dense solver's, the fall-back to the Python method."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.linalg import block_diag

from gearopt.errors import GearoptError
from gearopt.loaded import (
    PatchCompliance,
    halfspace_columns_mm_per_n,
    lcp_kernels,
    solve_load_distribution,
    solve_load_patches,
)

from .test_halfspace_columns import COMPOSITE, ltca_like_grid
from .test_lcp_columns import assert_conditions

N_TABLE = 30


def _table(seed):
    """A symmetric positive definite table of influence numbers (mm/N), bending-like."""
    rng = np.random.default_rng(seed)
    q = rng.normal(size=(N_TABLE, N_TABLE))
    return 2e-6 * (q @ q.T / N_TABLE + np.eye(N_TABLE))


def _group(seed, along, across, offset_mm):
    x, y, a, b, _ = ltca_like_grid(seed=seed, along=along, across=across)
    rng = np.random.default_rng(seed + 100)
    points = rng.integers(0, N_TABLE, size=(x.size, 16))
    weights = rng.uniform(0.0, 1.0 / 8.0, size=(x.size, 16))
    separation = offset_mm + 2e-4 * (x / x.max()) ** 2 + 5e-4 * (y / np.abs(y).max()) ** 2
    lever = 80.0 + rng.uniform(-2.0, 2.0, x.size)
    return (x, y, a, b, points, weights), separation, lever


@pytest.fixture(scope="module")
def problem():
    tables = (_table(1), _table(2))
    groups = [_group(5, 15, 9, 0.0), _group(6, 11, 7, 2e-5)]
    parts = [
        PatchCompliance(
            starts=[0, g[0].size],
            x_mm=g[0],
            y_mm=g[1],
            a_mm=g[2],
            b_mm=g[3],
            composite_mm2_per_n=COMPOSITE,
            members=tuple((t, g[4], g[5] * (1.0 + k)) for k, t in enumerate(tables)),
        )
        for g, _, _ in groups
    ]
    dense = []
    for g, _, _ in groups:
        x, y, a, b, points, weights = g
        c = halfspace_columns_mm_per_n(x, y, a, b, np.arange(x.size), COMPOSITE)
        for k, t in enumerate(tables):
            w = np.zeros((x.size, N_TABLE))
            np.add.at(w, (np.arange(x.size)[:, None], points), weights * (1.0 + k))
            c = c + w @ t @ w.T
        dense.append(c)
    separation = np.concatenate([s for _, s, _ in groups])
    lever = np.concatenate([r for _, _, r in groups])
    return parts, block_diag(*dense), separation, lever


def _fresh(parts):
    return PatchCompliance.join(parts)


def test_the_columns_are_the_block_diagonal_compliance(problem):
    parts, dense, _, _ = problem
    joined = _fresh(parts)
    idx = np.array([3, 140, 0, 200, 134, 211])
    np.testing.assert_allclose(joined(idx), dense[:, idx], rtol=1e-12, atol=0.0)
    rows = np.sort(np.random.default_rng(1).choice(joined.size, 90, replace=False))
    sub = joined.subset(rows)
    np.testing.assert_allclose(sub(np.arange(90)), dense[np.ix_(rows, rows)], rtol=1e-12)
    # the members' part of C F: C F less the half-spaces' (positive) part
    forces = np.random.default_rng(2).uniform(0.0, 1.0, joined.size)
    x, y, a, b = joined.x, joined.y, joined.a, joined.b
    local = block_diag(
        *[
            halfspace_columns_mm_per_n(
                x[lo:hi], y[lo:hi], a[lo:hi], b[lo:hi], np.arange(hi - lo), COMPOSITE
            )
            for lo, hi in zip(joined.starts[:-1], joined.starts[1:], strict=True)
        ]
    )
    np.testing.assert_allclose(joined.bending_mm(forces), (dense - local) @ forces, rtol=1e-10)
    assert (local >= 0.0).all()


@pytest.mark.parametrize("torque", [0.0, 200.0, 2000.0, 20000.0])
def test_the_solution_is_the_dense_solvers(problem, torque):
    parts, dense, separation, lever = problem
    area = 4.0 * _fresh(parts).a * _fresh(parts).b
    args = dict(separation_mm=separation, area_mm2=area, lever_arm_mm=lever, torque_n_mm=torque)
    reference = solve_load_distribution(compliance_mm_per_n=dense, **args)
    cold = solve_load_patches(compliance=_fresh(parts), **args)
    if torque > 0.0:
        assert_conditions(cold, (separation, area, dense, lever), torque)
    np.testing.assert_allclose(cold.forces_n, reference.forces_n, rtol=0, atol=1e-9 * torque)
    assert cold.theta_rad == pytest.approx(reference.theta_rad, rel=1e-12)
    if torque > 0.0:
        # warm: from another torque's forces, on the columns the last solve kept
        kept = _fresh(parts)
        above = solve_load_patches(compliance=kept, **{**args, "torque_n_mm": 1.5 * torque})
        warm = solve_load_patches(compliance=kept, start_forces_n=above.forces_n, **args)
        np.testing.assert_allclose(warm.forces_n, reference.forces_n, rtol=0, atol=1e-9 * torque)
        assert cold.active.size > 3, cold.active.size


def test_a_singular_block_falls_back_to_the_python_method(problem, monkeypatch):
    parts, dense, separation, lever = problem
    area = 4.0 * _fresh(parts).a * _fresh(parts).b
    args = dict(separation_mm=separation, area_mm2=area, lever_arm_mm=lever, torque_n_mm=2000.0)
    reference = solve_load_distribution(compliance_mm_per_n=dense, **args)
    calls = []

    def singular(*arguments):  # the kernel's answer where a block C_PP is singular
        calls.append(1)
        n = separation.size
        return 1, np.zeros(n), 0.0, np.zeros(n), np.zeros(n, bool), 0, np.zeros(0, np.intp)

    monkeypatch.setattr(lcp_kernels, "solve_patches", singular)
    solved = solve_load_patches(compliance=_fresh(parts), **args)
    assert calls == [1]
    np.testing.assert_allclose(solved.forces_n, reference.forces_n, rtol=0, atol=1e-9 * 2000.0)


def test_bad_input_is_refused(problem):
    parts, _, separation, lever = problem
    area = np.ones(separation.size)
    with pytest.raises(GearoptError) as error:
        solve_load_patches(
            separation_mm=separation[:-1],
            area_mm2=area[:-1],
            lever_arm_mm=lever[:-1],
            torque_n_mm=10.0,
            compliance=_fresh(parts),
        )
    assert error.value.parameter == "compliance"
    with pytest.raises(GearoptError) as error:
        solve_load_patches(
            separation_mm=separation,
            area_mm2=area,
            lever_arm_mm=lever,
            torque_n_mm=400.0,
            compliance=_fresh(parts),
            max_iterations=0,
        )
    assert "did not converge" in error.value.rule
