"""Compiled steps of the path's direction on the gear flank at M
(:func:`gearopt.mesh.frame.gear_path_angle`): the two contact points carried into the gear's
frame at their contact angles (:func:`gear_chord`), and the gear flank's tangents there with the
angle of the chord from the root line (:func:`root_line_angle`).

Each does the Python's arithmetic in its order, numpy's matrix products through numba's
``np.dot`` (scipy's OpenBLAS: the same kernels as numpy's ``@``, where a loop of the products
differs in the last bit): the results are the same to the bit (``tests/test_path_kernels.py``
holds them to the Python they replaced, and would see two BLAS builds that differ).
"""

from __future__ import annotations

import math

import numpy as np

from gearopt.jit import ENABLED, compiled

__all__ = ["ENABLED", "chord_angle", "gear_chord", "root_line_angle", "warm"]


@compiled
def gear_chord(face, height, theta, pitch, phi, lag, b, c, ratio, offset, gear_sense):
    """The two contact points, pinion grid ``(face, height)`` ``(2,)`` with polar angles
    ``theta`` ``(2,)``, in the gear's frame turned by the gear at the contact angles:
    :meth:`gearopt.flank.FlankMap.point_at`, :meth:`gearopt.contact.ClearanceField.
    gear_frame_points` and the gear's turn ``-ratio phi + offset - gear_sense lag``.

    Parameters
    ----------
    face, height, theta
        ``(2,)`` the points' cone distances, heights above the pitch cone and polar angles.
    pitch
        ``(cos, sin)`` of the pinion's pitch angle.
    phi, lag
        ``(2,)`` the pinion angles and the lags there.
    b, c
        The placement ``q = B p + c``.
    ratio, offset, gear_sense
        The field's ratio, gear offset and the gear's sense.

    Returns
    -------
    tuple
        ``(a, b)``: the two points ``(x, y, z)``.
    """
    cg, sg = pitch
    p = np.empty((2, 3))
    turned = np.empty((2, 3))
    for k in range(2):
        big_l = face[k] * cg - height[k] * sg
        big_r = face[k] * sg + height[k] * cg
        p[k, 0], p[k, 1], p[k, 2] = big_r * math.cos(theta[k]), big_r * math.sin(theta[k]), big_l
        cp, sp = math.cos(phi[k]), math.sin(phi[k])
        turned[k, 0] = cp * p[k, 0] - sp * p[k, 1]
        turned[k, 1] = sp * p[k, 0] + cp * p[k, 1]
        turned[k, 2] = p[k, 2]
    q = np.dot(turned, b.T)
    for k in range(2):
        for m in range(3):
            q[k, m] += c[m]
    return _turned(q, 0, phi, lag, ratio, offset, gear_sense), _turned(
        q, 1, phi, lag, ratio, offset, gear_sense
    )


@compiled
def _turned(q, k, phi, lag, ratio, offset, gear_sense):
    """Point ``q[k]`` turned by the gear's turn at the pinion angle ``phi[k]``."""
    turn = -ratio * phi[k] + offset - gear_sense * lag[k]
    co, si = math.cos(turn), math.sin(turn)
    x, y, z = q[k, 0], q[k, 1], q[k, 2]
    return co * x + si * y, -si * x + co * y, z


@compiled
def _unit(x, y, z):
    """``(x, y, z)`` over its length (:func:`gearopt.mesh.frame.path_angle`'s)."""
    norm = math.sqrt(x * x + y * y + z * z)
    return x / norm, y / norm, z / norm


@compiled
def _dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


@compiled
def _minus(a, k, b):
    return a[0] - k * b[0], a[1] - k * b[1], a[2] - k * b[2]


@compiled
def root_line_angle(chord, mid, s, h, jet, coefficients, root_angle):
    """The angle (radians) from the gear's root line to the chord ``chord`` through ``mid``
    on the gear flank at grid ``(s, h)``: :class:`gearopt.flank_jet.FlankJet`'s polar jet,
    :meth:`gearopt.flank_jet.FlankJet.surface`'s tangents, their cross product and
    :func:`chord_angle`.

    Parameters
    ----------
    chord, mid
        ``(x, y, z)`` the chord and its middle, gear frame.
    s, h
        The middle's grid coordinates on the gear flank.
    jet
        ``(s0, h0, ds, dh, n_f, n_p, columns, sin, cos)`` of the gear's :class:`FlankJet` (its
        grid, cells per row and pitch angle).
    coefficients
        ``(cells, 16)`` the gear's Hermite cells.
    root_angle
        The gear's root angle (radians).
    """
    s0, h0, ds, dh, n_f, n_p, columns, sg, cg = jet
    x = (s - s0) / ds
    y = (h - h0) / dh
    i = min(max(math.floor(x), 0), n_f - 2)
    j = min(max(math.floor(y), 0), n_p - 2)
    u, v = x - i, y - j
    cm = coefficients[i * columns + j].reshape(4, 4)
    uu, du, vv, dv = np.empty(4), np.empty(4), np.empty(4), np.empty(4)
    uu[0], uu[1], uu[2], uu[3] = 1.0, u, u * u, u * u * u
    du[0], du[1], du[2], du[3] = 0.0 / ds, 1.0 / ds, 2.0 * u / ds, 3.0 * u * u / ds
    vv[0], vv[1], vv[2], vv[3] = 1.0, v, v * v, v * v * v
    dv[0], dv[1], dv[2], dv[3] = 0.0 / dh, 1.0 / dh, 2.0 * v / dh, 3.0 * v * v / dh
    cv, cdv = np.dot(cm, vv), np.dot(cm, dv)
    theta, t_s, t_h = np.dot(uu, cv), np.dot(du, cv), np.dot(uu, cdv)
    # the tangents (p_s, p_h) and the normal p_s x p_h
    big_r = s * sg + h * cg
    ca, sa = math.cos(theta + 0.0), math.sin(theta + 0.0)
    r_s, r_h = big_r * t_s, big_r * t_h
    a = (sg * ca + r_s * -sa + cg * 0.0, sg * sa + r_s * ca + cg * 0.0, sg * 0.0 + r_s * 0.0 + cg)
    b = (cg * ca + r_h * -sa - sg * 0.0, cg * sa + r_h * ca - sg * 0.0, cg * 0.0 + r_h * 0.0 - sg)
    normal = (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])
    return chord_angle(chord, normal, mid, root_angle)


@compiled
def chord_angle(chord, normal, point, root_angle):
    """The angle (radians) from the gear's root line through ``point`` (the root cone's
    generatrix projected on the tangent plane of normal ``normal``, toward the heel) to the
    chord ``chord`` projected there (oriented toward the heel too), positive toward the tooth
    top: :func:`gearopt.mesh.frame.path_angle` but for the degrees. Each ``(x, y, z)``."""
    n = _unit(*normal)
    th = math.atan2(point[1], point[0])
    c_r, s_r = math.cos(th), math.sin(th)
    sin_g, cos_g = math.sin(root_angle), math.cos(root_angle)
    along = (sin_g * c_r + cos_g * 0.0, sin_g * s_r + cos_g * 0.0, sin_g * 0.0 + cos_g * 1.0)
    up = (cos_g * c_r - sin_g * 0.0, cos_g * s_r - sin_g * 0.0, cos_g * 0.0 - sin_g * 1.0)
    along = _unit(*_minus(along, _dot(along, n), n))
    up = _unit(*_minus(_minus(up, _dot(up, n), n), _dot(up, along), along))
    t = _minus(chord, _dot(chord, n), n)
    if _dot(t, along) < 0.0:
        t = (-t[0], -t[1], -t[2])
    return math.atan2(_dot(t, up), _dot(t, along))


def warm() -> None:
    """Compile the kernels, or load them from the disk cache; nothing without them."""
    if not ENABLED:
        return
    two, eye = np.ones(2), np.eye(3)
    gear_chord(two, two, two, (1.0, 0.0), two, two, eye, np.zeros(3), 1.0, 0.0, 1.0)
    jet = (0.0, 0.0, 1.0, 1.0, 2, 2, 1, 0.0, 1.0)
    one = (1.0, 0.0, 0.0)
    root_line_angle(one, one, 0.5, 0.5, jet, np.zeros((1, 16)), 0.5)
    chord_angle(one, one, one, 0.5)
