"""The contact mechanics of loaded TCA: half-space influence numbers (Love's rectangle) and the
load distribution LCP (gearopt.loaded.halfspace, gearopt.loaded.lcp).

The Hertz cases check the pair against theory: two steel bodies whose initial separation is the
paraboloid ``x^2 / (2 R1) + y^2 / (2 R2)`` pressed together by ``P`` (lever arms 1, torque P:
the moment equation is the force balance and ``theta`` is the approach).
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy import integrate
from scipy.optimize import brentq
from scipy.special import ellipe, ellipk

from gearopt.errors import GearoptError
from gearopt.loaded import (
    composite_compliance_mm2_per_n,
    halfspace_compliance_mm_per_n,
    patch_grid,
    rectangle_influence_mm_per_mpa,
    solve_load_distribution,
)

R1_MM, R2_MM = 20.0, 200.0
E_MPA, NU = 206000.0, 0.3
COMPOSITE = composite_compliance_mm2_per_n(E_MPA, NU, E_MPA, NU)
#: Hertz's contact modulus E* of two like bodies (Johnson, Contact Mechanics, ch. 4)
E_STAR_MPA = E_MPA / (2.0 * (1.0 - NU**2))
P_LOW_N, P_HIGH_N = 1000.0, 3375.0  # 3375 = 1.5^3: p_max and the semi-axes grow by 1.5


def hertz_elliptic(load_n: float) -> dict[str, float]:
    """Hertz theory of the elliptic contact (Johnson, Contact Mechanics, 1985, ch. 4):
    ``a`` the semi-axis along y (the flatter direction, R2), ``b`` along x (R1)."""
    a_coef, b_coef = 1.0 / (2.0 * R2_MM), 1.0 / (2.0 * R1_MM)  # A < B
    e_star = E_STAR_MPA

    def ratio(m):  # B / A as a function of e^2 = 1 - b^2 / a^2
        k, e = ellipk(m), ellipe(m)
        return (e / (1.0 - m) - k) / (k - e) - b_coef / a_coef

    m = brentq(ratio, 1e-9, 1.0 - 1e-12, xtol=1e-15)
    k, e = ellipk(m), ellipe(m)
    a = (3.0 * load_n * (k - e) / (2.0 * np.pi * a_coef * e_star * m)) ** (1.0 / 3.0)
    b = a * np.sqrt(1.0 - m)
    p0 = 3.0 * load_n / (2.0 * np.pi * a * b)
    return {"a_mm": a, "b_mm": b, "p0_mpa": p0, "approach_mm": p0 * b * k / e_star}


@pytest.fixture(scope="module")
def hertz_grid():
    """35 x 35 patches over +-1.2 times the Hertz semi-axes of the higher load."""
    h = hertz_elliptic(P_HIGH_N)
    grid = patch_grid(
        np.linspace(-1.2 * h["b_mm"], 1.2 * h["b_mm"], 36),
        np.linspace(-1.2 * h["a_mm"], 1.2 * h["a_mm"], 36),
    )
    separation = grid.x_mm**2 / (2.0 * R1_MM) + grid.y_mm**2 / (2.0 * R2_MM)
    return grid, separation, grid.compliance_mm_per_n(COMPOSITE)


@pytest.fixture(scope="module")
def hertz_solutions(hertz_grid):
    grid, separation, compliance = hertz_grid
    return {
        load: solve_load_distribution(
            separation_mm=separation,
            area_mm2=grid.area_mm2,
            compliance_mm_per_n=compliance,
            lever_arm_mm=np.ones_like(separation),
            torque_n_mm=load,
        )
        for load in (P_LOW_N, P_HIGH_N)
    }


# --- the half-space influence numbers ------------------------------------------------------


def _quadrature(x, y, x_edges, y_edges):
    """Integral of 1 / distance from (x, y) over the rectangle, by scipy's adaptive
    quadrature, the rectangle cut at x and y so that the singularity sits at corners."""
    xs = sorted({*x_edges, *(v for v in [x] if x_edges[0] < v < x_edges[1])})
    ys = sorted({*y_edges, *(v for v in [y] if y_edges[0] < v < y_edges[1])})
    total = 0.0
    for x0, x1 in zip(xs[:-1], xs[1:], strict=True):
        for y0, y1 in zip(ys[:-1], ys[1:], strict=True):
            total += integrate.dblquad(
                lambda eta, xi: 1.0 / np.hypot(x - xi, y - eta), x0, x1, y0, y1, epsabs=1e-10
            )[0]
    return total


def test_love_rectangle_matches_quadrature():
    # D = composite / pi * integral of 1 / distance over the rectangle: at the centre, inside,
    # on an edge and far outside, against scipy's adaptive quadrature
    xc, yc, a, b = 0.3, -0.2, 1.0, 0.25
    for x, y in [(xc, yc), (xc + 0.7, yc + 0.1), (xc + a, yc), (3.0, 2.0)]:
        d = rectangle_influence_mm_per_mpa([x, xc], [y, yc], a, b, np.pi)[0, 1]
        quad = _quadrature(x, y, (xc - a, xc + a), (yc - b, yc + b))
        assert d == pytest.approx(quad, rel=1e-7)


def test_composite_compliance():
    assert COMPOSITE == pytest.approx(1.0 / E_STAR_MPA, rel=1e-15)
    steel_on_bronze = composite_compliance_mm2_per_n(206000.0, 0.3, 110000.0, 0.34)
    assert steel_on_bronze == pytest.approx(0.91 / 206000.0 + (1.0 - 0.34**2) / 110000.0)


def test_square_centre_displacement_is_johnsons():
    # centre of a square of side 2c: u = 8 ln(1 + sqrt 2) / pi * p c (1 - nu^2) / E = 2.24 ...
    c = 0.5
    d = rectangle_influence_mm_per_mpa([0.0], [0.0], c, c, 1.0)[0, 0]
    assert d == pytest.approx(8.0 * np.log(1.0 + np.sqrt(2.0)) / np.pi * c, rel=1e-14)
    assert 8.0 * np.log(1.0 + np.sqrt(2.0)) / np.pi == pytest.approx(2.24, abs=0.005)


def test_halfspace_compliance_is_symmetric_positive_definite():
    grid = patch_grid(np.linspace(0.0, 1.0, 7), np.linspace(0.0, 3.0, 5) ** 1.3)  # uneven
    c = grid.compliance_mm_per_n(COMPOSITE)
    assert np.array_equal(c, c.T)
    assert np.linalg.eigvalsh(c).min() > 0.0
    # the same numbers from the flat function, and D / A before symmetrisation
    flat = halfspace_compliance_mm_per_n(
        grid.x_mm, grid.y_mm, grid.half_a_mm, grid.half_b_mm, COMPOSITE
    )
    assert np.array_equal(flat, c)
    d = rectangle_influence_mm_per_mpa(
        grid.x_mm, grid.y_mm, grid.half_a_mm, grid.half_b_mm, COMPOSITE
    )
    assert np.allclose(0.5 * (d / grid.area_mm2 + (d / grid.area_mm2).T), c, rtol=1e-14)
    # an even grid: the Toeplitz shortcut gives the same numbers as the pairwise formula
    even = patch_grid(np.linspace(-0.4, 0.4, 9), np.linspace(-2.0, 2.0, 6))
    fast = even.compliance_mm_per_n(COMPOSITE)
    assert np.array_equal(fast, fast.T)
    slow = halfspace_compliance_mm_per_n(
        even.x_mm, even.y_mm, even.half_a_mm, even.half_b_mm, COMPOSITE
    )
    assert np.allclose(fast, slow, rtol=1e-12, atol=0.0)


# --- Hertz ------------------------------------------------------------------------------------


@pytest.mark.parametrize("load", [P_LOW_N, P_HIGH_N])
def test_hertz_pressure_ellipse_and_approach(hertz_grid, hertz_solutions, load):
    grid, _, _ = hertz_grid
    sol, theory = hertz_solutions[load], hertz_elliptic(load)
    loaded = sol.pressure_mpa > 0.0
    # the contact ellipse: the outer edges of the loaded patches
    b_mm = np.max(np.abs(grid.x_mm[loaded]) + grid.half_a_mm[loaded])
    a_mm = np.max(np.abs(grid.y_mm[loaded]) + grid.half_b_mm[loaded])
    assert sol.pressure_mpa.max() == pytest.approx(theory["p0_mpa"], rel=0.05)
    assert b_mm == pytest.approx(theory["b_mm"], rel=0.10)
    assert a_mm == pytest.approx(theory["a_mm"], rel=0.10)
    assert sol.theta_rad == pytest.approx(theory["approach_mm"], rel=0.05)
    # the loaded set is the active set, the contact lies inside the grid
    assert np.array_equal(np.flatnonzero(loaded), sol.active)
    assert not loaded.reshape(grid.shape)[[0, -1], :].any()
    assert not loaded.reshape(grid.shape)[:, [0, -1]].any()


def test_hertz_pmax_grows_as_cube_root_of_load(hertz_solutions):
    low, high = hertz_solutions[P_LOW_N], hertz_solutions[P_HIGH_N]
    ratio = high.pressure_mpa.max() / low.pressure_mpa.max()
    assert ratio == pytest.approx((P_HIGH_N / P_LOW_N) ** (1.0 / 3.0), rel=0.01)
    # the approach grows as P^(2/3)
    assert high.theta_rad / low.theta_rad == pytest.approx(1.5**2, rel=0.01)


@pytest.mark.parametrize("load", [P_LOW_N, P_HIGH_N])
def test_hertz_solution_meets_its_conditions(hertz_grid, hertz_solutions, load):
    grid, separation, compliance = hertz_grid
    sol = hertz_solutions[load]
    _assert_lcp(sol, separation, compliance, np.ones_like(separation), load)
    assert np.allclose(sol.pressure_mpa * grid.area_mm2, sol.forces_n, rtol=1e-14)


def _assert_lcp(sol, separation, compliance, lever_arm, torque):
    """The conditions, recomputed here from the inputs (not from the solver's residuals)."""
    f, theta = sol.forces_n, sol.theta_rad
    gaps = separation + compliance @ f - lever_arm * theta
    assert np.allclose(gaps, sol.gaps_mm, rtol=0.0, atol=1e-12)
    assert abs(lever_arm @ f - torque) <= 1e-9 * max(torque, 1.0)
    assert gaps.min() >= -1e-9
    assert f.min() >= 0.0
    assert np.max(np.abs(gaps * f)) <= 1e-9 * max(f.max(), 1.0)
    # the solver's own residuals agree
    res = sol.residuals
    assert res.moment_relative <= 1e-9 or torque == 0.0
    assert res.penetration_mm <= 1e-9 and res.tensile_force_n == 0.0
    assert res.contact_gap_mm <= 1e-9


# --- small cases with closed-form answers -------------------------------------------------------


def test_two_springs_closed_form():
    # two patches, C = diag(c1, c2), s = (0, g), r = 1: patch 1 alone until c1 T = g, then
    # F2 = (c1 T - g) / (c1 + c2)
    c1, c2, g = 2e-5, 3e-5, 0.01
    kw = dict(separation_mm=[0.0, g], area_mm2=[1.0, 1.0], lever_arm_mm=[1.0, 1.0])
    c = np.diag([c1, c2])
    low = solve_load_distribution(compliance_mm_per_n=c, torque_n_mm=0.5 * g / c1, **kw)
    assert low.forces_n.tolist() == [0.5 * g / c1, 0.0]
    assert low.theta_rad == pytest.approx(0.5 * g, rel=1e-15)
    assert low.active.tolist() == [0]
    t = 3.0 * g / c1
    high = solve_load_distribution(compliance_mm_per_n=c, torque_n_mm=t, **kw)
    f2 = (c1 * t - g) / (c1 + c2)
    assert high.forces_n == pytest.approx([t - f2, f2], rel=1e-12)
    assert high.theta_rad == pytest.approx(c1 * (t - f2), rel=1e-12)
    assert high.active.tolist() == [0, 1]


def test_rigid_bodies_semidefinite_compliance():
    # C = 0 (positive semidefinite): the whole torque on the patch that closes first
    s = np.array([0.03, 0.01, 0.02])
    r = np.array([50.0, 40.0, 60.0])  # closing rotations 6e-4, 2.5e-4, 3.3e-4
    sol = solve_load_distribution(
        separation_mm=s,
        area_mm2=np.ones(3),
        compliance_mm_per_n=np.zeros((3, 3)),
        lever_arm_mm=r,
        torque_n_mm=800.0,
    )
    assert sol.forces_n.tolist() == [0.0, 20.0, 0.0]
    assert sol.theta_rad == pytest.approx(0.01 / 40.0, rel=1e-15)
    _assert_lcp(sol, s, np.zeros((3, 3)), r, 800.0)


def test_random_semidefinite_compliances_meet_the_conditions():
    # low-rank (singular) and full-rank compliances, random separations, lever arms, torques:
    # the conditions recomputed from the inputs
    rng = np.random.default_rng(7)
    for trial in range(40):
        n = int(rng.integers(2, 60))
        rank = n if trial % 2 else max(1, n // 5)
        basis = rng.normal(size=(n, rank))
        compliance = basis @ basis.T * (1e-6 / rank)
        separation = rng.uniform(0.0, 0.01, n)
        lever_arm = rng.uniform(30.0, 70.0, n)
        torque = float(rng.choice([10.0, 1e3, 1e5, 1e6]))
        sol = solve_load_distribution(
            separation_mm=separation,
            area_mm2=np.ones(n),
            compliance_mm_per_n=compliance,
            lever_arm_mm=lever_arm,
            torque_n_mm=torque,
        )
        _assert_lcp(sol, separation, compliance, lever_arm, torque)


# --- two tooth pairs --------------------------------------------------------------------------


def two_pairs(offset_mm: float = 0.004):
    """Two tooth pairs of 10 x 10 patches (200 in all): the same crowned flank, the second
    pair ``offset_mm`` further away and on a shorter lever arm. The compliance is the
    half-space part within each pair plus a bending part (a smooth positive definite kernel)
    coupling all patches, weaker between the pairs."""
    grid = patch_grid(np.linspace(-0.5, 0.5, 11), np.linspace(-4.0, 4.0, 11))
    n = grid.x_mm.size
    s_pair = grid.x_mm**2 / (2.0 * 15.0) + grid.y_mm**2 / (2.0 * 300.0)
    separation = np.concatenate([s_pair, s_pair + offset_mm])
    lever_arm = np.concatenate([np.full(n, 60.0), np.full(n, 58.0)])
    area = np.concatenate([grid.area_mm2, grid.area_mm2])
    local = grid.compliance_mm_per_n(COMPOSITE)
    compliance = np.zeros((2 * n, 2 * n))
    compliance[:n, :n] = local
    compliance[n:, n:] = local
    # bending: 4e-6 mm/N at a patch itself, a Gaussian kernel (positive definite) over the
    # positions, the second pair 25 mm away along the face
    y = np.concatenate([grid.y_mm, grid.y_mm + 25.0])
    x = np.concatenate([grid.x_mm, grid.x_mm])
    d2 = (x[:, None] - x[None, :]) ** 2 + (y[:, None] - y[None, :]) ** 2
    compliance += 4e-6 * np.exp(-d2 / (2.0 * 12.0**2))
    return separation, area, compliance, lever_arm, n


def solve_pairs(torque_n_mm, pairs):
    separation, area, compliance, lever_arm, _ = pairs
    return solve_load_distribution(
        separation_mm=separation,
        area_mm2=area,
        compliance_mm_per_n=compliance,
        lever_arm_mm=lever_arm,
        torque_n_mm=torque_n_mm,
    )


def test_two_pairs_share_the_load_only_at_high_torque():
    pairs = two_pairs()
    separation, _, compliance, lever_arm, n = pairs
    torques = np.geomspace(600.0, 6e5, 9)  # 10 N to 10 kN of normal force
    sols = [solve_pairs(t, pairs) for t in torques]
    for t, sol in zip(torques, sols, strict=True):
        _assert_lcp(sol, separation, compliance, lever_arm, t)
    low, high = sols[0], sols[-1]
    # low torque: the nearer pair alone, the other one still open
    assert low.forces_n[n:].max() == 0.0 and low.forces_n[:n].sum() > 0.0
    assert low.gaps_mm[n:].min() > 0.0
    # high torque: both carry a good part
    share = lever_arm[n:] @ high.forces_n[n:] / torques[-1]
    assert 0.2 < share < 0.5
    # the rotation lag grows with torque, and the second pair comes in somewhere between
    thetas = np.array([sol.theta_rad for sol in sols])
    assert np.all(np.diff(thetas) > 0.0)
    second = [sol.forces_n[n:].sum() > 0.0 for sol in sols]
    assert second == sorted(second) and 1 < second.count(False) < len(sols) - 1


def test_zero_torque_is_the_unloaded_contact():
    pairs = two_pairs()
    separation, _, _, lever_arm, n = pairs
    sol = solve_pairs(0.0, pairs)
    assert not sol.forces_n.any() and not sol.pressure_mpa.any()
    assert sol.theta_rad == np.min(separation / lever_arm)
    assert sol.gaps_mm.min() == 0.0  # exactly
    assert np.all(sol.gaps_mm >= 0.0)
    assert sol.active.tolist() == [int(np.argmin(separation / lever_arm))]
    assert sol.iterations == 0
    # lever arms of 1: theta is the least separation
    ones = solve_load_distribution(
        separation_mm=separation,
        area_mm2=np.ones(2 * n),
        compliance_mm_per_n=np.eye(2 * n),
        lever_arm_mm=np.ones(2 * n),
        torque_n_mm=0.0,
    )
    assert ones.theta_rad == separation.min() and ones.gaps_mm.min() == 0.0


# --- bad input -------------------------------------------------------------------------------


def _bad(**change):
    kw = dict(
        separation_mm=np.array([0.0, 0.01, 0.02]),
        area_mm2=np.ones(3),
        compliance_mm_per_n=np.eye(3) * 1e-5,
        lever_arm_mm=np.full(3, 50.0),
        torque_n_mm=1000.0,
    )
    kw.update(change)
    return kw


@pytest.mark.parametrize(
    ("change", "parameter"),
    [
        ({"torque_n_mm": -1.0}, "torque_n_mm"),
        ({"torque_n_mm": np.inf}, "torque_n_mm"),
        ({"torque_n_mm": np.nan}, "torque_n_mm"),
        ({"separation_mm": np.array([0.0, np.nan, 0.02])}, "separation_mm[1]"),
        (
            {"compliance_mm_per_n": np.array([[1, 0.5, 0], [0, 1, 0], [0, 0, 1]]) * 1e-5},
            "compliance_mm_per_n",
        ),
        (
            {"compliance_mm_per_n": np.array([[1, 2, 0], [2, 1, 0], [0, 0, 1]]) * 1e-5},
            "compliance_mm_per_n",
        ),
        ({"compliance_mm_per_n": -np.eye(3) * 1e-5}, "compliance_mm_per_n"),
        ({"compliance_mm_per_n": np.eye(2)}, "compliance_mm_per_n"),
        ({"compliance_mm_per_n": np.diag([1.0, np.nan, 1.0])}, "compliance_mm_per_n"),
        ({"lever_arm_mm": np.array([50.0, 0.0, 50.0])}, "lever_arm_mm[1]"),
        ({"area_mm2": np.array([1.0, 1.0, -1.0])}, "area_mm2[2]"),
        ({"area_mm2": np.ones(4)}, "area_mm2"),
    ],
)
def test_bad_input_names_the_parameter(change, parameter):
    with pytest.raises(GearoptError) as err:
        solve_load_distribution(**_bad(**change))
    assert err.value.parameter == parameter
    assert parameter in str(err.value)


def test_bad_materials_and_grids():
    with pytest.raises(GearoptError, match="e2_mpa"):
        composite_compliance_mm2_per_n(206000.0, 0.3, 0.0, 0.3)
    with pytest.raises(GearoptError, match="nu1"):
        composite_compliance_mm2_per_n(206000.0, 0.6, 206000.0, 0.3)
    with pytest.raises(GearoptError, match="x_edges_mm"):
        patch_grid([0.0, 1.0, 0.5], [0.0, 1.0])
    with pytest.raises(GearoptError, match="half_b_mm"):
        rectangle_influence_mm_per_mpa([0.0], [0.0], 1.0, 0.0, COMPOSITE)
