"""The pinion's fine boundary cells (:mod:`gearopt.contact.boundary`): the compiled kernels
give the numpy reference's tables bit for bit (``tests/numpy_boundary.py``, the module's numpy
version), and the cells reproduce the exact surface at their corners."""

from __future__ import annotations

import math

import numpy as np
import pytest

import gearopt
from gearopt.analysis import generated_flanks
from gearopt.contact import boundary
from gearopt.contact.boundary_kernels import ENABLED, exact_values
from gearopt.flank import FlankGrid

from . import numpy_boundary
from .conftest import STUDIES

#: face-hobbed (a tip fillet on the concave side: corners that need the neighbour's start),
#: face-milled on uniform and on tapered depth, on the default and on other grids
CASES = {
    "section 5.3": ("seed001_section5_3.toml", (25, 21)),
    "section 5.3, fine grid": ("seed001_section5_3.toml", (31, 27)),
    "face milling, conjugate": ("face_milling_conjugate.toml", (25, 21)),
    "face milling, tapered depth": ("face_milling_tapered.toml", (19, 15)),
}


@pytest.fixture(scope="module", params=list(CASES))
def pinion(request):
    name, (n_face, n_profile) = CASES[request.param]
    design = gearopt.load_design(STUDIES / name)
    return generated_flanks(design, FlankGrid(n_face=n_face, n_profile=n_profile))[0]


@pytest.mark.skipif(not ENABLED, reason="numba not importable or GEAROPT_JIT=0")
@pytest.mark.parametrize("flank", ["convex", "concave"])
def test_kernels_give_the_numpy_tables_bit_for_bit(pinion, flank):
    band, coef = boundary.boundary_cells(pinion[flank])
    ref_band, ref_coef = numpy_boundary.boundary_cells(pinion[flank])
    assert np.array_equal(band, ref_band)
    assert coef.shape == ref_coef.shape
    assert np.array_equal(coef, ref_coef)


@pytest.mark.parametrize("flank", ["convex", "concave"])
def test_exact_values_are_exact_polar_bit_for_bit(pinion, flank):
    """The compiled polar angle and gradient of exact points (at the generated nodes, the
    branch taken near the node angle turned by up to a turn and a half), with the taper's
    chain rule as the boundary cells apply it, are the numpy reference's (``exact_polar``)
    bit for bit."""
    f = pinion[flank]
    i, j = np.nonzero(f.mask)
    s, t = f.face_mm[i], f.profile_mm[j]
    geo = f.surface.geometry_at(s, t)
    turns = np.random.default_rng(5).uniform(-1.5, 1.5, s.size)
    near = f.polar_angle_rad[i, j] + 2.0 * math.pi * turns
    g = math.radians(f.pitch_angle_deg)
    got = exact_values(geo["point"], geo["normal"], near, (math.sin(g), math.cos(g)))
    if f.taper is not None:
        got[1] = got[1] + got[2] * f.taper.dheight_dface(t)
        got[2] = got[2] * f.taper.dheight_dprofile(s)
    ref = numpy_boundary.exact_polar(f, geo["point"], geo["normal"], near, s, t)
    assert np.array_equal(got, np.stack(ref))


@pytest.mark.parametrize("flank", ["convex", "concave"])
@pytest.mark.parametrize("u", [0.0, 0.5])
def test_fine_cells_follow_the_exact_surface(pinion, flank, u):
    """Between the fine cells' corners (on a grid column, u = 0, and half-way across a cell,
    u = 0.5; 0.37 of a cell up) on the generated flank: within 0.002 um of the exact surface
    (measured: 1e-4 to 9e-4 um), twenty times closer than the flank's own cells (0.03 to
    0.9 um)."""
    f = pinion[flank]
    band, coef = boundary.boundary_cells(f)
    cell = np.flatnonzero(band[:, 0] >= 0.0)
    i, j = np.divmod(cell, len(f.profile_mm) - 1)
    s = f.face_mm[i] + u * (f.face_mm[i + 1] - f.face_mm[i])
    t = f.profile_mm[j] + 0.37 * (f.profile_mm[j + 1] - f.profile_mm[j])
    on = t >= np.maximum(f.lowest_profile_mm[i], f.lowest_profile_mm[i + 1])
    assert on.sum() > 40
    fine = boundary.band_theta(
        f.cells.coefficients, band, coef, cell[on], np.full(on.sum(), u), np.full(on.sum(), 0.37)
    )
    own = f.polar_angle_local(s[on], t[on])
    exact = f.surface.points_at(s[on], t[on])
    polar, radius = np.arctan2(exact[:, 1], exact[:, 0]), np.hypot(exact[:, 0], exact[:, 1])

    def error_um(theta):
        return 1e3 * np.max(np.abs((theta - polar + np.pi) % (2 * np.pi) - np.pi) * radius)

    assert error_um(fine) < 0.002
    assert error_um(fine) < error_um(own) / 20.0
