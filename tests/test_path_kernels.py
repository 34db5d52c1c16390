"""The path's direction on the gear flank at M (:func:`gearopt.mesh.frame.gear_path_angle`, its
arithmetic compiled in :mod:`gearopt.mesh.path_kernels`) against the Python it replaced (kept
here as its reference: the flank's point by its splines, the gear frame's numpy products, the
gear flank's jet and tangents and the angle from the root line on Python floats), compiled and
as plain Python, on the section 5.3 pair's two sides at contact points over both flanks (within
:data:`ANGLE_TOLERANCE_DEG`: the same to the bit on the machine it was written on), and
:func:`gearopt.mesh.frame.path_angle` on random chords and normals, to the last bit.
"""

from __future__ import annotations

import dataclasses
import math
from types import MethodType, SimpleNamespace

import numpy as np
import pytest

from gearopt import bench
from gearopt.analysis import contact_sides
from gearopt.contact import ClearanceField
from gearopt.flank_jet import FlankJet
from gearopt.mesh import frame, path_kernels, side

VARIANTS = ["compiled", "python"]
#: the kernels' angle against the Python's: a last-bit difference of a BLAS product (numba's
#: np.dot calls scipy's BLAS, numpy's @ its own build): far below any figure's tolerance
ANGLE_TOLERANCE_DEG = 1e-9


def reference_angle(field, ex, tooth_frame) -> float:
    """The Python :func:`gearopt.mesh.frame.gear_path_angle` replaced (db029ef's)."""
    phi = ex.phi_rad[4:6]
    p = field.pinion.point_at(ex.contact_face_mm[4:6], ex.contact_profile_mm[4:6])
    q = field.gear_frame_points(p, phi)
    turn = -field.ratio * phi + field.gear_offset_rad - field.gear_sense * ex.minimum_rad[4:6]
    cos, sin = np.cos(turn).tolist(), np.sin(turn).tolist()
    a, b = (
        (c * x + s * y, -s * x + c * y, z)
        for c, s, (x, y, z) in zip(cos, sin, q.tolist(), strict=True)
    )
    mid = (0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1]), 0.5 * (a[2] + b[2]))
    s2, h2 = field.gear.to_grid(mid[2], math.hypot(mid[0], mid[1]))
    jet = FlankJet(field.gear)
    theta, t_s, t_h, *_ = jet.polar(float(s2), float(h2))
    sg, cg = jet.sg, jet.cg
    s, h = float(s2), float(h2)
    big_r = s * sg + h * cg
    ca, sa = math.cos(theta + 0.0), math.sin(theta + 0.0)
    r_s, r_h = big_r * t_s, big_r * t_h
    p_s = (sg * ca + r_s * -sa + cg * 0.0, sg * sa + r_s * ca + cg * 0.0, sg * 0.0 + r_s * 0.0 + cg)
    p_h = (cg * ca + r_h * -sa - sg * 0.0, cg * sa + r_h * ca - sg * 0.0, cg * 0.0 + r_h * 0.0 - sg)
    normal = (
        p_s[1] * p_h[2] - p_s[2] * p_h[1],
        p_s[2] * p_h[0] - p_s[0] * p_h[2],
        p_s[0] * p_h[1] - p_s[1] * p_h[0],
    )
    return reference_path_angle(
        (b[0] - a[0], b[1] - a[1], b[2] - a[2]),
        normal,
        mid,
        math.radians(tooth_frame.gear_root_angle_deg),
    )


def reference_path_angle(tangent, normal, point, root_angle_rad) -> float:
    """The Python :func:`gearopt.mesh.frame.path_angle` replaced (db029ef's)."""

    def unit(x, y, z):
        norm = math.sqrt(x * x + y * y + z * z)
        return (x / norm, y / norm, z / norm)

    def dot(a, b):
        return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]

    def minus(a, k, b):
        return (a[0] - k * b[0], a[1] - k * b[1], a[2] - k * b[2])

    n = unit(*(float(a) for a in normal))
    theta = math.atan2(point[1], point[0])
    c_r, s_r = math.cos(theta), math.sin(theta)
    sin_g, cos_g = math.sin(root_angle_rad), math.cos(root_angle_rad)
    along = (sin_g * c_r + cos_g * 0.0, sin_g * s_r + cos_g * 0.0, sin_g * 0.0 + cos_g * 1.0)
    up = (cos_g * c_r - sin_g * 0.0, cos_g * s_r - sin_g * 0.0, cos_g * 0.0 - sin_g * 1.0)
    along = unit(*minus(along, dot(along, n), n))
    up = unit(*minus(minus(up, dot(up, n), n), dot(up, along), along))
    t = tuple(float(a) for a in tangent)
    t = minus(t, dot(t, n), n)
    if dot(t, along) < 0.0:
        t = (-t[0], -t[1], -t[2])
    angle = math.degrees(math.atan2(dot(t, up), dot(t, along)))
    return 90.0 if angle <= -90.0 + 1e-12 else angle


@pytest.fixture(scope="module")
def sides():
    """The section 5.3 pair's sides' ``(field, ex, frame)`` as :meth:`SideCycle.assemble`
    passes them."""
    pair, options = bench._meshed_section53()
    got = []
    original = side.gear_path_angle
    side.gear_path_angle = lambda *args: (got.append(args), original(*args))[1]
    try:
        contact_sides(pair, options)
    finally:
        side.gear_path_angle = original
    return got


def _tilted(field, rng):
    """The field with its placement tilted a little about a random axis: products with
    nothing exact in them (the pair's shaft angle of 90 degrees makes B's entries 0 and 1)."""
    axis = rng.normal(size=3)
    axis /= np.linalg.norm(axis)
    k = np.array([[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]], [-axis[1], axis[0], 0.0]])
    angle = rng.uniform(0.01, 0.2)
    turn = np.eye(3) + math.sin(angle) * k + (1.0 - math.cos(angle)) * (k @ k)
    tilted = SimpleNamespace(
        pinion=field.pinion,
        gear=field.gear,
        ratio=field.ratio,
        gear_offset_rad=field.gear_offset_rad,
        gear_sense=field.gear_sense,
        b=np.ascontiguousarray(turn @ field.b),
        c=field.c + rng.normal(size=3),
    )
    tilted.gear_frame_points = MethodType(ClearanceField.gear_frame_points, tilted)
    return tilted


def _cases(sides, count=150):
    """The sides' extra positions with the two rows either side of M moved: contact points
    over the flank (its edges included), pinion angles and lags about the true ones; every
    other one on the field with its placement tilted (:func:`_tilted`)."""
    rng = np.random.default_rng(39)
    for field, ex, tooth_frame in sides:
        yield field, ex, tooth_frame
        tilted = _tilted(field, rng)
        face, profile = field.pinion.face_mm, field.pinion.profile_mm
        for j in range(count):
            moved = {}
            for name, low, high in (
                ("contact_face_mm", face[0], face[-1]),
                ("contact_profile_mm", profile[0], profile[-1]),
            ):
                values = getattr(ex, name).copy()
                values[4:6] = rng.uniform(low, high, 2)
                moved[name] = values
            moved["phi_rad"] = ex.phi_rad + rng.normal(size=ex.phi_rad.shape) * 0.05
            moved["minimum_rad"] = ex.minimum_rad + rng.normal(size=ex.phi_rad.shape) * 1e-4
            yield (tilted if j % 2 else field), dataclasses.replace(ex, **moved), tooth_frame


@pytest.mark.parametrize("variant", VARIANTS)
def test_gear_path_angle_is_the_python(sides, variant, monkeypatch):
    if variant == "python":
        for name in (
            "gear_chord",
            "root_line_angle",
            "chord_angle",
            "_turned",
            "_unit",
            "_dot",
            "_minus",
        ):
            kernel = getattr(path_kernels, name)
            monkeypatch.setattr(path_kernels, name, getattr(kernel, "py_func", kernel))
    angles = []
    for field, ex, tooth_frame in _cases(sides):
        want = reference_angle(field, ex, tooth_frame)
        got = frame.gear_path_angle(field, ex, tooth_frame)
        # bit for bit here; not asked of every machine: the kernels' np.dot calls scipy's
        # BLAS, numpy's @ its own, and two builds may round a product differently
        assert abs(got - want) <= ANGLE_TOLERANCE_DEG
        angles.append(got)
    assert len(angles) == 302 and np.ptp(angles) > 10.0  # (the points spread over the flank)


@pytest.mark.parametrize("variant", VARIANTS)
def test_path_angle_is_the_python_bit_for_bit(variant, monkeypatch):
    if variant == "python":
        for name in ("chord_angle", "_unit", "_dot", "_minus"):
            kernel = getattr(path_kernels, name)
            monkeypatch.setattr(path_kernels, name, getattr(kernel, "py_func", kernel))
    rng = np.random.default_rng(23)
    for _ in range(2000):
        tangent, normal, point = rng.normal(size=(3, 3)) * rng.uniform(0.01, 100.0, (3, 1))
        root = float(rng.uniform(0.5, 1.5))
        want = reference_path_angle(tangent, normal, point, root)
        got = frame.path_angle(tangent, normal, point, root)
        assert np.float64(got).view(np.int64) == np.float64(want).view(np.int64)


def test_a_point_off_the_grid_fails_as_the_python(sides):
    field, ex, tooth_frame = sides[0]
    values = ex.contact_face_mm.copy()
    values[4] = np.nan
    ex = dataclasses.replace(ex, contact_face_mm=values)
    with pytest.raises(ValueError):
        reference_angle(field, ex, tooth_frame)
    with pytest.raises(ValueError):
        frame.gear_path_angle(field, ex, tooth_frame)
