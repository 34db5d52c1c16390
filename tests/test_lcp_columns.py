"""The load distribution on compliance columns requested as needed
(gearopt.loaded.lcp.solve_load_columns): the LCP's conditions, cold and warm starts to the same
solution, the columns asked for, bad input."""

from __future__ import annotations

import numpy as np
import pytest

from gearopt.errors import GearoptError
from gearopt.loaded import (
    ColumnCache,
    halfspace_columns_mm_per_n,
    solve_load_columns,
    solve_load_distribution,
)

from .test_halfspace_columns import COMPOSITE, ltca_like_grid


class Provider:
    """``columns(idx) -> C[:, idx]`` of a dense matrix, counting what is asked."""

    def __init__(self, compliance):
        self.compliance = compliance
        self.calls = 0
        self.asked: list[int] = []

    def __call__(self, idx):
        assert idx.dtype == np.intp and idx.ndim == 1
        self.calls += 1
        self.asked.extend(idx.tolist())
        return self.compliance[:, idx]


def solve(problem, torque, start=None, provider=None):
    separation, area, compliance, lever_arm = problem
    return solve_load_columns(
        separation_mm=separation,
        area_mm2=area,
        lever_arm_mm=lever_arm,
        torque_n_mm=torque,
        columns=provider or Provider(compliance),
        start_forces_n=start,
    )


def assert_conditions(sol, problem, torque):
    """The LCP's conditions recomputed from the inputs (not from the solver's residuals)."""
    separation, _, compliance, lever_arm = problem
    f, theta = sol.forces_n, sol.theta_rad
    gaps = separation + compliance @ f - lever_arm * theta
    assert np.allclose(gaps, sol.gaps_mm, rtol=0.0, atol=1e-12)
    assert abs(lever_arm @ f - torque) <= 1e-10 * torque  # moment balance
    assert gaps.min() >= -1e-10  # no penetration
    assert f.min() >= 0.0  # no tension
    assert np.max(np.abs(gaps * f)) <= 1e-10 * f.max()  # complementarity
    assert np.all(f[sol.active] > 0.0) and not f[np.setdiff1d(np.arange(f.size), sol.active)].any()
    res = sol.residuals
    assert res.moment_relative <= 1e-10 and res.penetration_mm <= 1e-10
    assert res.tensile_force_n == 0.0 and res.contact_gap_mm <= 1e-10


def assert_same(a, b, rtol=1e-9):
    assert np.max(np.abs(a.forces_n - b.forces_n)) <= rtol * np.max(a.forces_n)
    assert b.theta_rad == pytest.approx(a.theta_rad, rel=rtol)
    assert np.array_equal(a.active, b.active)


def random_spd(n=300, seed=11):
    """A random positive definite compliance (mm/N), separations, unit areas, lever arms."""
    rng = np.random.default_rng(seed)
    basis = rng.normal(size=(n, n))
    compliance = (basis @ basis.T / n + 0.05 * np.eye(n)) * 1e-6
    return rng.uniform(0.0, 0.01, n), np.ones(n), compliance, rng.uniform(30.0, 70.0, n)


@pytest.fixture(scope="module")
def halfspace_lcp():
    """A crowned contact on the LTCA-like grid (615 patches): the half-space columns as the
    compliance plus a smooth positive definite bending part (4e-6 mm/N, 12 mm wide)."""
    x, y, half_a, half_b, across = ltca_like_grid()
    local = halfspace_columns_mm_per_n(x, y, half_a, half_b, np.arange(x.size), COMPOSITE)
    d2 = (x[:, None] - x[None, :]) ** 2 + (y[:, None] - y[None, :]) ** 2
    compliance = np.asarray(local) + 4e-6 * np.exp(-d2 / (2.0 * 12.0**2))
    separation = x**2 / (2.0 * 800.0) + across**2 / (2.0 * 15.0)
    lever_arm = 60.0 + 0.1 * x
    return separation, 4.0 * half_a * half_b, compliance, lever_arm


@pytest.fixture(scope="module")
def random_lcp():
    return random_spd()


def test_columns_solve_matches_the_dense_solver_and_meets_the_conditions(random_lcp):
    problem = random_lcp
    separation, area, compliance, lever_arm = problem
    for torque in (30.0, 3e3, 3e5):
        sol = solve(problem, torque)
        assert_conditions(sol, problem, torque)
        dense = solve_load_distribution(
            separation_mm=separation,
            area_mm2=area,
            compliance_mm_per_n=compliance,
            lever_arm_mm=lever_arm,
            torque_n_mm=torque,
        )
        assert_same(dense, sol, rtol=1e-12)


@pytest.mark.parametrize("name", ["random_lcp", "halfspace_lcp"])
def test_warm_and_cold_starts_give_the_same_solution(name, request):
    problem = request.getfixturevalue(name)
    separation, _, compliance, lever_arm = problem
    assert np.linalg.eigvalsh(compliance).min() > 0.0  # a unique solution
    torques = np.geomspace(2e3, 6e5, 6) if name == "halfspace_lcp" else [30.0, 3e3, 3e5]
    cold = [solve(problem, t) for t in torques]
    for t, sol in zip(torques, cold, strict=True):
        assert_conditions(sol, problem, t)
    assert cold[0].active.size < cold[-1].active.size
    rng = np.random.default_rng(2)
    n = separation.size
    for k, t in enumerate(torques):
        starts = [
            rng.uniform(0.5, 1.5, n),  # every patch in the start
            np.where(rng.uniform(size=n) < 0.1, 1.0, 0.0),  # a random support
        ]
        if k > 0:
            starts.append(cold[k - 1].forces_n)  # the sweep upwards: a smaller support
        if k + 1 < len(torques):
            starts.append(cold[k + 1].forces_n)  # downwards: a larger one, with tension
        for start in starts:
            warm = solve(problem, t, start=start)
            assert_conditions(warm, problem, t)
            assert_same(cold[k], warm)


def test_warm_start_of_a_sweep_saves_iterations_and_columns(halfspace_lcp):
    problem = halfspace_lcp
    torques = np.geomspace(2e3, 6e5, 6)
    start, cold_asked, warm_asked = None, 0, 0
    for t in torques:
        cold_columns, warm_columns = Provider(problem[2]), Provider(problem[2])
        cold = solve(problem, t, provider=cold_columns)
        warm = solve(problem, t, start=start, provider=warm_columns)
        assert_same(cold, warm)
        assert warm.iterations <= cold.iterations
        cold_asked += len(cold_columns.asked)
        warm_asked += len(warm_columns.asked)
        start = warm.forces_n
    assert warm_asked <= cold_asked


def test_a_small_contact_asks_for_few_columns(halfspace_lcp):
    problem = halfspace_lcp
    n = problem[0].size
    for torque, most in ((2e3, 60), (6e4, 150)):
        columns = Provider(problem[2])
        sol = solve(problem, torque, provider=columns)
        assert_conditions(sol, problem, torque)
        # each column asked once, a few beyond the active set, far from all n = 615
        assert len(set(columns.asked)) == len(columns.asked)
        assert sol.active.size <= len(columns.asked) <= most < n // 4
        assert set(sol.active.tolist()) <= set(columns.asked)
    # the unloaded contact asks for none
    columns = Provider(problem[2])
    sol = solve(problem, 0.0, provider=columns)
    assert columns.calls == 0 and not sol.forces_n.any()
    assert sol.theta_rad == np.min(problem[0] / problem[3])


def test_semidefinite_compliance_with_warm_starts_meets_the_conditions():
    rng = np.random.default_rng(4)
    for trial in range(20):
        n = int(rng.integers(3, 50))
        basis = rng.normal(size=(n, max(1, n // 5)))
        problem = (
            rng.uniform(0.0, 0.01, n),
            np.ones(n),
            basis @ basis.T * 1e-6,
            rng.uniform(30.0, 70.0, n),
        )
        torque = float(rng.choice([10.0, 1e3, 1e5]))
        start = rng.uniform(0.0, 1.0, n) * (rng.uniform(size=n) < 0.5)
        start[trial % n] = 1.0
        separation, _, compliance, lever_arm = problem
        for sol in (solve(problem, torque), solve(problem, torque, start=start)):
            gaps = separation + compliance @ sol.forces_n - lever_arm * sol.theta_rad
            assert abs(lever_arm @ sol.forces_n - torque) <= 1e-9 * torque
            assert gaps.min() >= -1e-9 and sol.forces_n.min() >= 0.0
            assert np.max(np.abs(gaps * sol.forces_n)) <= 1e-9 * max(sol.forces_n.max(), 1.0)


def test_a_zero_start_is_the_cold_start():
    problem = random_spd(n=40)
    cold = solve(problem, 3e3)
    zero = solve(problem, 3e3, start=np.zeros(40))
    assert np.array_equal(cold.forces_n, zero.forces_n) and cold.iterations == zero.iterations


def _columns_kw(**change):
    kw = dict(
        separation_mm=np.array([0.0, 0.01, 0.02]),
        area_mm2=np.ones(3),
        lever_arm_mm=np.full(3, 50.0),
        torque_n_mm=1000.0,
        columns=lambda idx: np.eye(3)[:, idx] * 1e-5,
    )
    kw.update(change)
    return kw


@pytest.mark.parametrize(
    ("change", "parameter"),
    [
        ({"torque_n_mm": -1.0}, "torque_n_mm"),
        ({"separation_mm": np.array([0.0, np.inf, 0.02])}, "separation_mm[1]"),
        ({"lever_arm_mm": np.array([50.0, 50.0, -1.0])}, "lever_arm_mm[2]"),
        ({"area_mm2": np.ones(2)}, "area_mm2"),
        ({"columns": np.eye(3)}, "columns"),
        ({"columns": lambda idx: np.eye(3)[:2, idx]}, "columns"),
        ({"columns": lambda idx: np.full((3, idx.size), np.nan)}, "columns"),
        ({"columns": lambda idx: -np.eye(3)[:, idx]}, "columns C[0, 0]"),
        ({"start_forces_n": np.ones(4)}, "start_forces_n"),
        ({"start_forces_n": np.array([1.0, -1.0, 0.0])}, "start_forces_n[1]"),
        ({"start_forces_n": np.array([1.0, 0.0, np.nan])}, "start_forces_n[2]"),
    ],
)
def test_bad_column_input_names_the_parameter(change, parameter):
    with pytest.raises(GearoptError) as err:
        solve_load_columns(**_columns_kw(**change))
    assert err.value.parameter == parameter


def test_asymmetric_columns_and_no_convergence_are_named():
    asymmetric = np.array([[1.0, 0.5, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]) * 1e-5
    start = np.ones(3)  # all three patches in the first block
    with pytest.raises(GearoptError, match="symmetric") as err:
        solve_load_columns(
            **_columns_kw(columns=lambda idx: asymmetric[:, idx], start_forces_n=start)
        )
    assert err.value.parameter == "columns"
    # the dense solver names its own parameter when the active set runs out of iterations
    separation, area, compliance, lever_arm = random_spd(n=40)
    kw = dict(separation_mm=separation, area_mm2=area, lever_arm_mm=lever_arm, torque_n_mm=3e5)
    with pytest.raises(GearoptError, match="did not converge") as err:
        solve_load_distribution(compliance_mm_per_n=compliance, max_iterations=0, **kw)
    assert err.value.parameter == "compliance_mm_per_n"
    with pytest.raises(GearoptError, match="did not converge") as err:
        solve_load_columns(columns=lambda idx: compliance[:, idx], max_iterations=0, **kw)
    assert err.value.parameter == "columns"


def test_a_cache_kept_across_a_sweep_asks_for_each_column_once(halfspace_lcp):
    # the torques of a sweep at one position share a ColumnCache: each column is fetched
    # (and checked) once over the sweep, and each solve is the one of a fresh provider
    problem = halfspace_lcp
    provider = Provider(problem[2])
    cache = ColumnCache(provider, problem[0].size)
    for t in np.geomspace(2e3, 6e5, 5)[::-1]:
        kept = solve(problem, t, provider=cache)
        fresh = solve(problem, t)
        assert_same(kept, fresh, rtol=1e-12)
        assert_conditions(kept, problem, t)
    assert len(provider.asked) == len(set(provider.asked)) < problem[0].size
    separation, area, compliance, lever_arm = problem
    shorter = (separation[:-1], area[:-1], compliance, lever_arm[:-1])
    with pytest.raises(GearoptError, match="columns"):  # a cache of another size
        solve(shorter, 1e3, provider=cache)
