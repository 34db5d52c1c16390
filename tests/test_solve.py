"""Vectorised Newton: many systems at once, convergence flags, step limits, complex step."""

from __future__ import annotations

import numpy as np
from numpy.testing import assert_allclose

from gearopt.solve import complex_step_jacobian, newton


def circles(centres, radii):
    """Intersections of two circles per system (a well-posed 2 x 2 nonlinear system)."""

    def f(x, i):
        c, r = centres[i], radii[i]
        d1 = (x[:, 0] - c[:, 0]) ** 2 + (x[:, 1] - c[:, 1]) ** 2 - r[:, 0] ** 2
        d2 = (x[:, 0] - c[:, 2]) ** 2 + (x[:, 1] - c[:, 3]) ** 2 - r[:, 1] ** 2
        return np.stack([d1, d2], axis=1)

    return f


def test_many_systems_converge_to_true_roots():
    n = 500
    rng = np.random.default_rng(3)
    target = rng.uniform(-1, 1, size=(n, 2))
    c1 = target + rng.uniform(0.5, 1.0, size=(n, 2))
    c2 = target - rng.uniform(0.5, 1.0, size=(n, 2)) * np.array([1.0, -1.0])
    radii = np.stack([np.linalg.norm(target - c1, axis=1), np.linalg.norm(target - c2, axis=1)], 1)
    f = circles(np.hstack([c1, c2]), radii)
    result = newton(f, target + 0.05 * rng.normal(size=(n, 2)), tol=1e-13)
    assert result.all_converged
    assert_allclose(result.x, target, atol=1e-10)
    assert np.all(np.abs(result.residual) <= 1e-13)


def test_unsolvable_systems_are_flagged_not_nan():
    a = np.array([-1.0, 1.0, -4.0, 1.0])

    def f(x, i):  # x^2 + 1 = 0 has no real root for half of the systems
        return x**2 + a[i, None]

    result = newton(f, np.full((4, 1), 0.5), max_iter=30)
    assert result.converged.tolist() == [True, False, True, False]
    assert np.all(np.isfinite(result.x))
    assert_allclose(np.abs(result.x[[0, 2], 0]), [1.0, 2.0], rtol=1e-12)


def test_step_limit_is_respected():
    seen = []

    def f(x, i):
        seen.append(x.copy())
        return x - 10.0

    jac = lambda x, i: np.ones((len(x), 1, 1))  # noqa: E731
    newton(f, np.zeros((3, 1)), jac=jac, max_step=[0.5], max_iter=5)
    steps = np.abs(np.diff([s for s in seen if s.shape == (3, 1)], axis=0))
    assert np.all(steps <= 0.5 + 1e-15)


def test_complex_step_jacobian_is_exact():
    def f(x, i):
        return np.stack([np.sin(x[:, 0]) * x[:, 1], np.exp(x[:, 0] * x[:, 1])], axis=1)

    x = np.array([[0.3, -1.2], [1.1, 0.4]])
    jac = complex_step_jacobian(f, x)
    exact = np.empty((2, 2, 2))
    exact[:, 0, 0] = np.cos(x[:, 0]) * x[:, 1]
    exact[:, 0, 1] = np.sin(x[:, 0])
    e = np.exp(x[:, 0] * x[:, 1])
    exact[:, 1, 0] = e * x[:, 1]
    exact[:, 1, 1] = e * x[:, 0]
    assert_allclose(jac, exact, rtol=1e-15, atol=1e-15)


def test_jacobian_determinant_sign_is_reported():
    cubes = np.array([[8.0], [-27.0]])
    result = newton(lambda x, i: x**3 - cubes[i], np.array([[1.5], [-2.5]]))
    assert result.all_converged
    assert_allclose(result.x[:, 0], [2.0, -3.0], rtol=1e-13)
    assert np.all(result.jacobian_det > 0)  # 3 x^2
