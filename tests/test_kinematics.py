"""4x4 transforms: the paper's matrices, composition, inversion, complex step."""

from __future__ import annotations

import numpy as np
from numpy.testing import assert_allclose

from gearopt import kinematics as k

RNG = np.random.default_rng(7)


def test_rotations_follow_the_right_hand_rule():
    quarter = np.pi / 2
    assert_allclose(k.apply(k.rot_z(quarter), [1.0, 0.0, 0.0]), [0.0, 1.0, 0.0], atol=1e-16)
    assert_allclose(k.apply(k.rot_x(quarter), [0.0, 1.0, 0.0]), [0.0, 0.0, 1.0], atol=1e-16)
    assert_allclose(k.apply(k.rot_y(quarter), [0.0, 0.0, 1.0]), [1.0, 0.0, 0.0], atol=1e-16)


def test_seed001_matrices():
    a = 0.3
    c, s = np.cos(a), np.sin(a)
    m_md = np.array([[c, -s, 0, 0], [s, c, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]])  # eq 18
    m_gq = np.array([[c, s, 0, 0], [-s, c, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]])  # eq 21
    m_cc = np.array([[c, 0, -s, 0], [0, 1, 0, 0], [s, 0, c, 0], [0, 0, 0, 1]])  # eq 16
    assert_allclose(k.rot_z(a), m_md, atol=1e-16)
    assert_allclose(k.rot_z(-a), m_gq, atol=1e-16)
    assert_allclose(k.rot_y(-a), m_cc, atol=1e-16)


def test_vectorised_shapes_and_broadcasting():
    angles = RNG.uniform(-3, 3, size=(5, 7))
    m = k.compose(k.rot_z(angles), k.translation(np.array([1.0, 2.0, 3.0])), k.rot_x(0.2))
    assert m.shape == (5, 7, 4, 4)
    pts = RNG.normal(size=(5, 7, 3))
    one = k.apply(m[2, 3], pts[2, 3])
    assert_allclose(k.apply(m, pts)[2, 3], one, rtol=1e-14)


def test_rigid_inverse_and_lengths():
    m = k.compose(k.rot_z(0.4), k.translation([1.0, -2.0, 0.5]), k.rot_y(1.1), k.rot_x(-0.3))
    assert_allclose(k.compose(m, k.invert_rigid(m)), np.eye(4), atol=1e-14)
    p, q = RNG.normal(size=(2, 3))
    assert_allclose(
        np.linalg.norm(k.apply(m, p) - k.apply(m, q)), np.linalg.norm(p - q), rtol=1e-14
    )
    v = RNG.normal(size=3)
    assert_allclose(k.apply_vector(m, v), k.apply(m, v) - k.apply(m, np.zeros(3)), atol=1e-14)


def test_complex_step_through_a_chain():
    h = 1e-30
    a = 0.7

    def chain(t):
        return k.apply(
            k.compose(k.rot_z(t), k.translation([2.0, 0.0, 0.0]), k.rot_y(2 * t)), [1.0, 0.5, 0.0]
        )

    derivative = chain(a + 1j * h).imag / h
    central = (chain(a + 1e-6) - chain(a - 1e-6)) / 2e-6
    assert_allclose(derivative, central, atol=1e-8)
