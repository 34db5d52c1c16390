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
