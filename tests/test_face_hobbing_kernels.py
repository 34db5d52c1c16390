"""The face-hobbing family's compiled kernels (gearopt_plugins.face_hobbing.kernels) against the
numpy functions they repeat: every evaluation of the family and the envelope solver's Newton
iteration, on a straight blade with rake, parabola and work offsets (cyclo-palloid, seed 001)
and on circular-arc blades (epicycloid, seed 003)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from numpy.testing import assert_allclose

import gearopt
from gearopt.envelope import solve_envelope
from gearopt.flank import FlankGrid
from gearopt_plugins.cyclo_palloid.settings import blade_systems
from gearopt_plugins.epicycloid import flank_system
from gearopt_plugins.face_hobbing import kernels
from gearopt_plugins.face_hobbing.generation import hobbing_family

pytestmark = pytest.mark.skipif(not kernels.ENABLED, reason="numba not importable or GEAROPT_JIT=0")


def _cyclo_palloid_family(studies):
    design = gearopt.load_design(studies / "seed001_table3.toml")
    design = gearopt.with_overrides(
        design,
        {
            "machine.pinion.rake_angle_deg": 4.0,
            "machine.pinion.blade_parabola_coefficient_per_mm": 0.002,
            "machine.pinion.parabola_apex_mm": 0.5,
        },
    )
    settings = gearopt.basic_settings(design).pinion
    systems = blade_systems(design, "pinion", settings)
    return design, hobbing_family(design.blank, "pinion", [systems["inner"], systems["outer"]])


def _epicycloid_family(studies):
    design = gearopt.with_overrides(
        gearopt.load_design(studies / "seed003_case_A.toml"),
        {
            "machine.pinion.convex.blade_profile_radius_mm": 300.0,
            "machine.pinion.concave.blade_profile_radius_mm": 400.0,
        },
    )
    systems = [flank_system(design, "pinion", f)[0] for f in ("convex", "concave")]
    assert all(b.profile_curvature_per_mm > 0.0 for b in systems)
    return design, hobbing_family(design.blank, "pinion", systems)


STUDIES = Path(__file__).resolve().parents[1] / "studies"


@pytest.fixture(params=["cyclo-palloid", "epicycloid"])
def case(request):
    studies = STUDIES
    if request.param == "cyclo-palloid":
        return _cyclo_palloid_family(studies)
    return _epicycloid_family(studies)


def test_kernels_match_the_numpy_family(case):
    # complex parameters (zero imaginary parts) take the numpy path, real ones the kernels
    _, family = case
    rng = np.random.default_rng(11)
    n = 200
    pitch = family.pitch_row(np.full(n, family.scale_mm))
    flank = rng.integers(0, 2, n)
    q = pitch[flank, np.arange(n)] + rng.uniform(-1.0, 1.0, (n, 3)) * [3.0, 0.1, 0.1]
    qc = q.astype(complex)
    for got, ref in zip(
        family.axial_radial_meshing(q, flank),
        family.axial_radial_meshing(qc, flank),
        strict=True,
    ):
        assert_allclose(got, ref.real, rtol=1e-13, atol=1e-13)
    got = family.axial_radial_meshing_jacobian(q, flank)
    ref = family.axial_radial_meshing_jacobian(qc, flank)
    for a, b in zip(got, ref, strict=True):
        assert_allclose(a, b.real, rtol=1e-12, atol=1e-12)
    geo, geo_ref = family.geometry(q, flank), family.geometry(qc, flank)
    for key in ("point", "normal"):
        assert_allclose(geo[key], geo_ref[key].real, rtol=1e-13, atol=1e-12, err_msg=key)
    assert_allclose(np.linalg.norm(geo["normal"], axis=-1), 1.0, atol=1e-14)
    assert_allclose(
        family.blade_height_mm(q[:, 0], flank),
        family.blade_height_mm(qc[:, 0], flank).real,
        rtol=1e-14,
        atol=1e-14,
    )
    # one point without a batch axis, as the thickness solve asks
    one = family.geometry(q[0], flank[0])["point"]
    assert one.shape == (3,)
    assert_allclose(one, geo["point"][0], rtol=0, atol=0)


class _Without:
    """The family without one of its optional compiled hooks (``newton``: the solver iterates
    in numpy; ``bisect``: the solver bisects, with the compiled Newton iteration)."""

    def __init__(self, family, hook: str):
        self._family, self._hook = family, hook

    def __getattr__(self, name):
        if name == self._hook:
            raise AttributeError(name)
        return getattr(self._family, name)


def _envelope_args(design) -> dict:
    """The pinion's :func:`solve_envelope` arguments on a 15 x 17 grid."""
    blank = design.blank
    return {
        "cone_distances_mm": (blank.inner_cone_distance_mm, blank.outer_cone_distance_mm),
        "heights_mm": (-blank.mean_dedendum_mm[0], blank.mean_addendum_mm[0]),
        "pitch_angle_rad": math.radians(blank.pitch_angle_deg[0]),
        "grid": FlankGrid(n_face=15, n_profile=17),
    }


def test_compiled_newton_solves_as_the_solver(case):
    # the same nodes generated, the same sheet, the same parameters to rounding
    design, family = case
    args = _envelope_args(design)
    got = solve_envelope(family, **args)
    ref = solve_envelope(_Without(family, "newton"), **args)
    assert got.mask.sum() > 100
    for name in ("converged", "unfolded", "sheet", "mask", "within_tool"):
        assert np.array_equal(getattr(got, name), getattr(ref, name)), name
    assert got.iterations == ref.iterations
    assert_allclose(got.q, ref.q, rtol=0, atol=1e-11)
    assert np.all(np.abs(got.residual[got.converged]) <= 1e-14)


def test_compiled_bisection_ends_the_columns_as_the_solver(case):
    # the fold and the blade tip bisected node by node in one kernel: the same Newton solves in
    # the same order as the solver's vectorised bisection, so the same coordinates to the bit
    design, family = case
    args = _envelope_args(design)
    got = solve_envelope(family, **args).lowest_profile_mm
    ref = solve_envelope(_Without(family, "bisect"), **args).lowest_profile_mm
    h = np.linspace(*args["heights_mm"], 17)
    between = np.isfinite(ref) & (np.min(np.abs(ref[..., None] - h), axis=-1) > 1e-9)
    assert between.sum() >= 5  # columns ended between nodes: bisected
    np.testing.assert_array_equal(got, ref)


def test_the_warm_up_compiles_the_models_kernels(monkeypatch):
    # gearopt.warmup.warm_kernels asks every installed machine model to warm its own kernels
    import gearopt.warmup as warmup
    from gearopt.plugins import machine_models

    calls = []
    models = machine_models()
    for name in ("cyclo-palloid", "epicycloid"):
        model = models[name]
        monkeypatch.setattr(
            model, "warm_kernels", lambda m=model: (calls.append(m.name), type(m).warm_kernels(m))
        )
    warmup.warm_kernels(announce=False)
    assert sorted(calls) == ["cyclo-palloid", "epicycloid"]
    for kernel in (
        kernels.meshing_jacobians,
        kernels.newton,
        kernels.bisected,
        kernels.geometries,
    ):
        assert kernel.signatures  # compiled or loaded from the cache
