"""The contact engine's compiled kernels (``gearopt.contact.kernels``, numba)
against their numpy reference (``tests/numpy_engine.py``, the engine's numpy paths before the
kernels): every output of the TCA of both sides, the backlash and the ease-off,
on designs that visit each branch of the kernels (crowned contact inside the flanks, edge
contact under misalignment, tapered depth on both members, a path that runs into the pinion's
fold-trimmed boundary).

Tolerances: the kernels do the same arithmetic in the same order, but they choose the
refinement's closed-form Newton step row by row where numpy chooses it for a whole batch, and a
BLAS product on the numpy side may fuse a multiply-add; the refinement stops when a step is
below a thousandth of a cell, so refined positions may differ far below that (measured: at most
about 1e-7 mm, TE 1e-10 arcsec). Flags must be identical.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import gearopt
from gearopt.analysis import (
    AnalysisOptions,
    contact_sides,
    generated_flanks,
    pair_backlash,
    pair_ease_off,
)
from gearopt.contact import kernels as contact_kernels
from gearopt.design import Misalignment
from gearopt.flank import FlankGrid
from gearopt.mesh import mesh_pair

from . import numpy_engine
from .conftest import STUDIES

pytestmark = pytest.mark.skipif(
    not contact_kernels.ENABLED, reason="numba not importable or GEAROPT_JIT=0"
)

SECTION_5_4 = Misalignment(
    offset_mm=0.221, pinion_axial_mm=-0.005, gear_axial_mm=0.188, shaft_angle_deg=-0.062
)

CASES = {
    "section 5.3, aligned": ("seed001_section5_3.toml", {}, {}),
    "section 5.3, section 5.4 misalignment": (
        "seed001_section5_3.toml",
        {},
        {"misalignment": SECTION_5_4},
    ),
    "section 5.3, edge contact": (
        "seed001_section5_3.toml",
        {},
        {"misalignment": Misalignment(shaft_angle_deg=-0.5)},
    ),
    "face milling, tapered depth": ("face_milling_tapered.toml", {}, {}),
    "epicycloid R_b 250, toe-root corner": (
        "seed003_case_A.toml",
        {"machine.pinion.convex.blade_profile_radius_mm": 250.0},
        {
            "separation": "circumferential",
            "compound_um": 10.0,
            "grid": FlankGrid(n_face=41, n_profile=61),
        },
    ),
}


def _analyses(design, options):
    """TCA of both sides, backlash and ease-off on a freshly placed pair (its engines built
    now)."""
    flanks = generated_flanks(design, options.grid)
    pair = mesh_pair(design, flanks, misalignment=options.misalignment)
    return {
        **contact_sides(pair, options),
        "backlash": pair_backlash(pair, options),
        **{f"ease_off {k}": v for k, v in pair_ease_off(pair).items()},
    }


MEMBERS = ("pinion", "gear")


def _fields(result) -> dict:
    return {f.name: getattr(result, f.name) for f in dataclasses.fields(result)}


#: the zones' chords (gearopt.mesh.zone) end where the separation crosses the compound; along
#: a line contact it does so at a grazing slope, and the contact point the chords start from
#: is any point of the line, so the refinements' 1e-7 mm differences move the chords' ends
#: further (measured: 5e-5 mm, the coast line contact of the R_b 250 case)
ZONE_FIGURES = (
    "width_mm",
    "ellipse_major_axis_mm",
    "ellipse_minor_axis_mm",
    "mean_point_mm",
    "center_offset_mm",
)


def _tolerance(name: str) -> float:
    if "arcsec" in name:
        return 1e-6
    if name.endswith("_deg"):
        return 1e-5
    if name in ZONE_FIGURES:
        return 2e-4
    return 1e-5  # mm, um, contact ratio


@pytest.mark.parametrize("case", list(CASES))
def test_kernels_give_the_numpy_paths_results(case, monkeypatch):
    name, overrides, conditions = CASES[case]
    design = gearopt.with_overrides(gearopt.load_design(STUDIES / name), overrides)
    options = AnalysisOptions(**conditions)
    compiled = _analyses(design, options)
    numpy_engine.install(monkeypatch)
    plain = _analyses(design, options)
    checked = 0
    for key, result in compiled.items():
        other = _fields(plain[key])
        for field, value in _fields(result).items():
            ref = other[field]
            where = f"{case}: {key}.{field}"
            if isinstance(value, str) or value is None:
                assert value == ref, where
                continue
            a, b = np.asarray(value), np.asarray(ref)
            if a.dtype.kind in "biu":
                assert np.array_equal(a, b), where
            elif a.dtype.kind == "f":
                np.testing.assert_allclose(
                    a, b, rtol=0, atol=_tolerance(field), equal_nan=True, err_msg=where
                )
            else:
                continue
            checked += 1
    assert checked > 40  # (every side's curves, pattern, flags, backlash and ease-off maps)


def test_a_misalignment_that_leaves_no_refinable_node_is_reported_not_raised():
    # seed 003 case A with a 4.99 deg shaft-angle error: at some positions no refinable node
    # of a pair faces the gear, while the cycle's extra evaluations (near rows) still refine;
    # the engine raised IndexError there (an empty row set and one "first" flag). Now every
    # position reports its contact, at the flanks' edges
    design = gearopt.load_design(STUDIES / "seed003_case_A.toml")
    options = AnalysisOptions.from_conditions(
        {"misalignment": Misalignment(shaft_angle_deg=4.99)}, design=design
    )
    pair = mesh_pair(
        design, generated_flanks(design, options.grid), misalignment=options.misalignment
    )
    tca = contact_sides(pair, options)["drive"]
    assert np.all(np.isfinite(tca.te_arcsec))
    assert all(tca.edge)


@pytest.mark.parametrize(
    ("name", "misalignment"),
    [
        ("seed001_section5_3.toml", Misalignment()),
        ("seed001_section5_3.toml", SECTION_5_4),
        ("face_milling_tapered.toml", Misalignment()),
    ],
)
def test_row_wise_point_kernels_give_the_numpy_paths_results(name, misalignment):
    """The loaded contact's compiled passes over patch points (the clearance, normal factor,
    R2 and gear grid coordinates of member-frame points, one pinion angle per row; whether
    grid coordinates lie on generated cells) against the numpy paths of the engine and the
    FlankMap, on points inside, across and beyond both flanks (uniform and tapered depth)."""
    from gearopt.loaded.separations import flank_inside, flank_points

    design = gearopt.load_design(STUDIES / name)
    options = AnalysisOptions(misalignment=misalignment)
    pair = mesh_pair(design, generated_flanks(design, options.grid), misalignment=misalignment)
    field = pair.drive
    pinion = field.pinion
    rng = np.random.default_rng(7)
    span_s = pinion.face_mm[-1] - pinion.face_mm[0]
    span_h = pinion.profile_mm[-1] - pinion.profile_mm[0]
    s = rng.uniform(pinion.face_mm[0] - 0.1 * span_s, pinion.face_mm[-1] + 0.1 * span_s, (6, 400))
    h = rng.uniform(
        pinion.profile_mm[0] - 0.1 * span_h, pinion.profile_mm[-1] + 0.1 * span_h, (6, 400)
    )
    nodes = np.meshgrid(pinion.face_mm[:5], pinion.profile_mm[:5])
    s[0, :25], h[0, :25] = nodes[0].ravel(), nodes[1].ravel()
    p, n, _, _ = flank_points(pinion, s, h)
    phi = rng.uniform(-1.5, 1.5, 6) * pinion.pitch_rad
    plain = field.clearance_of_points(p, n, phi[:, None])
    rows = field.clearance_of_rows(p, n, phi)
    for key in ("clearance_rad", "normal_factor_mm", "radius_mm"):
        np.testing.assert_allclose(
            getattr(rows, key), getattr(plain, key), rtol=1e-13, atol=1e-13, err_msg=key
        )
    assert np.array_equal(rows.valid, plain.valid)
    assert 0.2 < plain.valid.mean() < 0.9  # points on and off the gear flank
    q = field.gear_frame_points(p, phi[:, None])
    gs, gt = field.gear.to_grid(q[..., 2], np.hypot(q[..., 0], q[..., 1]))
    np.testing.assert_allclose(rows.gear_face_mm, gs, rtol=0, atol=1e-11)
    np.testing.assert_allclose(rows.gear_profile_mm, gt, rtol=0, atol=1e-11)
    inside = pinion.inside(s, h)
    assert np.array_equal(flank_inside(pinion, s, h), inside)
    assert 0.2 < inside.mean() < 0.95
