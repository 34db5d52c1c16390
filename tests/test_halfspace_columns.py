"""The half-space compliance's columns on demand: Love's rectangle near, its multipole expansion
far (gearopt.loaded.halfspace.halfspace_columns_mm_per_n, gearopt.loaded.kernels), against the
dense matrix (halfspace_compliance_mm_per_n)."""

from __future__ import annotations

import numpy as np
import pytest

from gearopt.errors import GearoptError
from gearopt.loaded import (
    FAR_FIELD_RATIO,
    composite_compliance_mm2_per_n,
    halfspace_columns_mm_per_n,
    halfspace_compliance_mm_per_n,
)
from gearopt.loaded import kernels as loaded_kernels

COMPOSITE = composite_compliance_mm2_per_n(206000.0, 0.3, 206000.0, 0.3)


def ltca_like_grid(seed=5, along=41, across=15, length_mm=0.4, width_mm=0.15, jitter=0.05):
    """Patches as the loaded TCA lays them out: strips of ``across`` patches along y, the
    strips spaced ``length_mm`` along x and shifted in y by different amounts, each patch's
    size off the nominal by up to ``jitter``: ``(x, y, half_a, half_b, y - shift)``."""
    rng = np.random.default_rng(seed)
    t = (np.arange(along) - along // 2) * length_mm
    w = (np.arange(across) - across // 2) * width_mm
    shift = rng.uniform(-0.5, 0.5, along) * width_mm * 2.0
    shift[along // 2] = 0.0
    x = np.repeat(t, across)
    y = (shift[:, None] + w[None, :]).ravel()
    half_a = 0.5 * length_mm * (1.0 + jitter * rng.uniform(-1.0, 1.0, x.size))
    half_b = 0.5 * width_mm * (1.0 + jitter * rng.uniform(-1.0, 1.0, x.size))
    return x, y, half_a, half_b, np.tile(w, along)


def uneven_patches(seed=3, nx=24, ny=12):
    """Patches of sizes varying by about 30 % whose centres are off a lattice."""
    rng = np.random.default_rng(seed)
    gx, gy = np.meshgrid(np.arange(nx) * 0.3, np.arange(ny) * 0.2)
    x = gx.ravel() + rng.uniform(-0.06, 0.06, gx.size)
    y = gy.ravel() + rng.uniform(-0.04, 0.04, gy.size)
    half_a = 0.15 * rng.uniform(0.85, 1.15, x.size)
    half_b = 0.10 * rng.uniform(0.85, 1.15, x.size)
    return x, y, half_a, half_b


def _far(x, y, half_a, half_b):
    """Which pairs of patches take the multipole expansion."""
    reach = np.maximum(half_a, half_b) * FAR_FIELD_RATIO
    d2 = (x[:, None] - x[None, :]) ** 2 + (y[:, None] - y[None, :]) ** 2
    return d2 > np.maximum(reach[:, None], reach[None, :]) ** 2


@pytest.mark.parametrize("layout", ["uneven", "ltca"])
def test_halfspace_columns_are_the_dense_matrix_within_1e4(layout):
    x, y, half_a, half_b = uneven_patches() if layout == "uneven" else ltca_like_grid()[:4]
    n = x.size
    dense = halfspace_compliance_mm_per_n(x, y, half_a, half_b, COMPOSITE)
    full = halfspace_columns_mm_per_n(x, y, half_a, half_b, np.arange(n), COMPOSITE)
    assert full.shape == (n, n)
    assert np.array_equal(full, full.T)
    relative = np.abs(full / dense - 1.0)
    far = _far(x, y, half_a, half_b)
    assert 0.3 * n * n < far.sum() < n * n - n  # both parts exercised
    assert relative.max() < 1e-4
    assert relative[~far].max() < 1e-12  # Love's exact integral near
    assert relative[far].max() > 1e-9  # (the expansion does differ)
    # any columns, in any order, repeated: the same numbers as the whole
    cols = np.array([n - 1, 7, 7, 0, n // 2])
    part = halfspace_columns_mm_per_n(x, y, half_a, half_b, cols, COMPOSITE)
    assert part.shape == (n, cols.size)
    assert np.array_equal(part, full[:, cols])
    assert halfspace_columns_mm_per_n(x, y, half_a, half_b, [], COMPOSITE).shape == (n, 0)


def test_multipole_error_just_beyond_the_switch_distance():
    # two patches of all aspect ratios and size ratios at 1.0001 times the switch distance,
    # all directions: the worst entry against Love's exact integral
    worst = 0.0
    angles = np.linspace(0.0, 2.0 * np.pi, 73)  # every 5 degrees
    for aspect in (1e-3, 0.2, 0.5, 0.8, 1.0):
        for other, crossed in ((1.0, False), (0.7, False), (0.3, False), (1.0, True)):
            half_a = np.array([1.0, other * (aspect if crossed else 1.0)])
            half_b = np.array([aspect, other * (1.0 if crossed else aspect)])
            distance = 1.0001 * FAR_FIELD_RATIO * max(half_a.max(), half_b.max())
            for angle in angles:
                x = np.array([0.0, distance * np.cos(angle)])
                y = np.array([0.0, distance * np.sin(angle)])
                exact = halfspace_compliance_mm_per_n(x, y, half_a, half_b, COMPOSITE)[0, 1]
                far = halfspace_columns_mm_per_n(x, y, half_a, half_b, [1], COMPOSITE)[0, 0]
                worst = max(worst, abs(far / exact - 1.0))
    assert 1e-5 < worst < 5e-5


def test_halfspace_columns_in_plain_python_are_the_compiled_ones():
    x, y, half_a, half_b = uneven_patches(nx=6, ny=4)
    cols = np.array([0, 5, 17], dtype=np.intp)
    compiled = halfspace_columns_mm_per_n(x, y, half_a, half_b, cols, COMPOSITE)
    kernel = getattr(loaded_kernels.halfspace_columns, "py_func", loaded_kernels.halfspace_columns)
    out = np.empty((cols.size, x.size))
    kernel(x, y, half_a, half_b, cols, COMPOSITE / np.pi, FAR_FIELD_RATIO, out)
    assert np.allclose(out.T, compiled, rtol=1e-14, atol=0.0)


def test_bad_halfspace_columns():
    x, y = np.zeros(3), np.arange(3.0)
    with pytest.raises(GearoptError, match="columns"):
        halfspace_columns_mm_per_n(x, y, 0.1, 0.1, [0, 3], COMPOSITE)
    with pytest.raises(GearoptError, match="columns"):
        halfspace_columns_mm_per_n(x, y, 0.1, 0.1, [-1], COMPOSITE)
    with pytest.raises(GearoptError, match="columns"):
        halfspace_columns_mm_per_n(x, y, 0.1, 0.1, [0.5], COMPOSITE)
    with pytest.raises(GearoptError, match="columns"):
        halfspace_columns_mm_per_n(x, y, 0.1, 0.1, [[0]], COMPOSITE)
    with pytest.raises(GearoptError, match="composite_mm2_per_n"):
        halfspace_columns_mm_per_n(x, y, 0.1, 0.1, [0], 0.0)
    with pytest.raises(GearoptError, match="half_a_mm"):
        halfspace_columns_mm_per_n(x, y, -0.1, 0.1, [0], COMPOSITE)
