"""Blank geometry against seed 001 Table 2 and against the geometry of rolling cones."""

from __future__ import annotations

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose

import gearopt


def test_table2_blank(table3_design, seed_cases):
    blank = table3_design.blank
    ref = seed_cases["cyclo_palloid_seed001"]["blank"]
    # Table 2 prints three decimals: half a unit of the last digit
    assert_allclose(blank.pitch_angle_deg, ref["pitch_angle_deg"], atol=5e-4)
    assert_allclose(blank.outer_transverse_module_mm, ref["outer_transverse_module_mm"], atol=5e-4)
    assert_allclose(blank.mean_normal_module_mm, ref["mean_normal_module_mm"], atol=5e-4)
    assert_allclose(blank.face_angle_deg, ref["face_cone_angle_deg"], atol=5e-4)
    assert_allclose(blank.root_angle_deg, ref["root_cone_angle_deg"], atol=5e-4)
    assert blank.hand == (ref["pinion_hand"], ref["gear_hand"])
    # uniform depth: the mean addendum is the outer addendum
    assert blank.mean_addendum_mm == tuple(ref["outer_addendum_mm"])


@pytest.mark.parametrize("shaft_angle_deg", [60.0, 90.0, 115.0])
@pytest.mark.parametrize(("n1", "n2"), [(16, 41), (9, 37), (25, 25)])
def test_pitch_cones_roll_on_each_other(shaft_angle_deg, n1, n2):
    pair = gearopt.PairData(
        pinion_teeth=n1,
        gear_teeth=n2,
        shaft_angle_deg=shaft_angle_deg,
        mean_spiral_angle_deg=30.0,
        mean_normal_module_mm=3.0,
        face_width_mm=20.0,
    )
    blank = pair.blank
    g1, g2 = np.radians(blank.pitch_angle_deg)
    # the cones share the apex, touch along one generatrix and roll without slip: the angles add
    # up to the shaft angle and the pitch radii at any cone distance are as the tooth numbers
    assert_allclose(math.degrees(g1 + g2), shaft_angle_deg, rtol=0, atol=1e-12)
    assert_allclose(np.divide(*blank.mean_pitch_radius_mm), n1 / n2, rtol=1e-13)
    assert_allclose(
        blank.mean_pitch_radius_mm[0], n1 * blank.mean_transverse_module_mm / 2, rtol=1e-13
    )
    assert_allclose(blank.crown_gear_teeth, n2 / math.sin(g2), rtol=1e-13)
    # the module given is the module derived back from the cone distance
    assert_allclose(blank.mean_normal_module_mm, 3.0, rtol=1e-13)
    assert_allclose(
        blank.outer_pitch_radius_mm[1], blank.outer_transverse_module_mm * n2 / 2, rtol=1e-13
    )


def test_cone_distance_and_module_are_one_datum():
    common = dict(pinion_teeth=16, gear_teeth=41, mean_spiral_angle_deg=35.0, face_width_mm=32.0)
    from_module = gearopt.PairData(mean_normal_module_mm=3.397, **common)
    from_cone = gearopt.PairData(mean_cone_distance_mm=from_module.mean_cone_distance_mm, **common)
    assert_allclose(from_cone.mean_normal_module_mm, 3.397, rtol=1e-14)
    # Table 2's rounded pair (3.397, 91.265) agrees to 0.01 %: accepted, the cone distance wins
    both = gearopt.PairData(mean_normal_module_mm=3.397, mean_cone_distance_mm=91.265, **common)
    assert both.mean_cone_distance_mm == 91.265
    assert_allclose(both.mean_normal_module_mm, 3.3973, atol=5e-5)


# --- tapered depth -------------------------------------------------------------------------------

TAPERED = dict(
    pinion_teeth=12,
    gear_teeth=36,
    mean_spiral_angle_deg=35.0,
    mean_cone_distance_mm=90.0,
    face_width_mm=28.0,
    outer_addendum_mm=[4.5, 4.7],
    outer_dedendum_mm=[5.7, 5.5],
)


def _tapered_pair(face_delta=(2.5, 3.5), root_delta=(3.5, 2.5), **changes):
    g1 = math.degrees(math.atan2(1.0, 3.0))
    pitch = (g1, 90.0 - g1)
    data = dict(
        TAPERED,
        face_angle_deg=[p + d for p, d in zip(pitch, face_delta, strict=True)],
        root_angle_deg=[p - d for p, d in zip(pitch, root_delta, strict=True)],
    )
    data.update(changes)
    return gearopt.PairData(**data)


def _line_height(point_lr, angle_rad, blank, index, cone_distance_mm):
    """Height above the pitch cone, on the normal to the pitch generatrix at a cone distance,
    of the axial-plane line through ``point_lr`` at ``angle_rad`` from the member axis."""
    g = math.radians(blank.pitch_angle_deg[index])
    foot = cone_distance_mm * np.array([math.cos(g), math.sin(g)])
    normal = np.array([-math.sin(g), math.cos(g)])
    direction = np.array([math.cos(angle_rad), math.sin(angle_rad)])
    # foot + h normal = point + k direction
    h, _ = np.linalg.solve(np.stack([normal, -direction], axis=1), np.asarray(point_lr) - foot)
    return h


@pytest.mark.parametrize("index", [0, 1])
def test_tapered_blank_is_the_cones_through_the_heel(index):
    """The face and root cones drawn in the axial plane through the heel's tip and root points
    (the outer addendum and dedendum on the back cone) at the face and root angles: their
    heights above the pitch cone at the mean cone distance are the blank's mean addendum and
    dedendum, the heel tip point gives the outside diameter, and the FlankMap grid's first and
    last rows (DepthTaper) lie on those cones at every cone distance."""
    pair = _tapered_pair()
    blank = pair.blank
    g = math.radians(blank.pitch_angle_deg[index])
    ao = blank.outer_cone_distance_mm
    pitch_heel = ao * np.array([math.cos(g), math.sin(g)])
    back = np.array([-math.sin(g), math.cos(g)])  # the back cone's element (normal to pitch)
    tip_heel = pitch_heel + pair.outer_addendum_mm[index] * back
    root_heel = pitch_heel - pair.outer_dedendum_mm[index] * back
    face = math.radians(pair.face_angle_deg[index])
    root = math.radians(pair.root_angle_deg[index])
    am = blank.mean_cone_distance_mm
    assert_allclose(
        _line_height(tip_heel, face, blank, index, am), blank.mean_addendum_mm[index], atol=1e-12
    )
    assert_allclose(
        -_line_height(root_heel, root, blank, index, am),
        blank.mean_dedendum_mm[index],
        atol=1e-12,
    )
    assert_allclose(blank.outside_diameter_mm[index], 2.0 * tip_heel[1], rtol=1e-14)
    taper = blank.depth_taper(index)
    s = np.linspace(blank.inner_cone_distance_mm, ao, 5)
    for t, point, angle in ((taper.root_mm, root_heel, root), (taper.top_mm, tip_heel, face)):
        want = [_line_height(point, angle, blank, index, a) for a in s]
        assert_allclose(taper.height_mm(s, t), want, atol=1e-12)
        assert_allclose(taper.profile_of(s, taper.height_mm(s, t)), t, atol=1e-12)
    # the mean whole depth and clearance are those between the cones at A_m
    assert_allclose(
        blank.whole_depth_mm[index],
        blank.mean_addendum_mm[index] + blank.mean_dedendum_mm[index],
        rtol=1e-15,
    )


def test_uniform_depth_blank_is_unchanged():
    pair = gearopt.PairData(**TAPERED)
    blank = pair.blank
    assert blank.face_angle_deg == blank.root_angle_deg == blank.pitch_angle_deg
    assert blank.mean_addendum_mm == blank.outer_addendum_mm == (4.5, 4.7)
    assert blank.mean_dedendum_mm == (5.7, 5.5)
    assert blank.depth_taper(0) is None and blank.depth_taper(1) is None
    assert not pair.tapered and blank.tapered == (False, False)


@pytest.mark.parametrize(
    ("changes", "parameter", "rule"),
    [
        (dict(root_delta=(3.5, -0.1)), "pair.root_angle_deg[gear]", "<= the pitch angle"),
        (dict(face_delta=(-0.2, 3.5)), "pair.face_angle_deg[pinion]", ">= the pitch angle"),
        (dict(root_delta=(16.0, 2.5)), "pair.root_angle_deg[pinion]", "exceeds 15"),
        (dict(face_delta=(2.5, 9.6)), "pair.face_angle_deg[gear]", "addendum at the toe"),
        (dict(root_delta=(11.8, 2.5)), "pair.root_angle_deg[pinion]", "dedendum at the toe"),
        (dict(face_delta=(2.5, 0.5)), "pair.face_angle_deg", "must clear the root"),
        (dict(face_angle_deg=20.0), "pair.face_angle_deg", "list of two angles"),
        (dict(root_angle_deg=[14.0, "x"]), "pair.root_angle_deg[gear]", ""),
    ],
)
def test_bad_taper_names_the_parameter(changes, parameter, rule):
    with pytest.raises(gearopt.DesignError) as info:
        _tapered_pair(**changes)
    assert info.value.parameter == parameter
    assert rule in str(info.value)


@pytest.mark.parametrize("study", ["seed001_table3.toml", "seed003_case_A.toml"])
def test_uniform_depth_models_refuse_a_tapered_pair(study):
    """Cyclo-palloid and epicycloid cut uniform depth only."""
    from .conftest import STUDIES

    design = gearopt.load_design(STUDIES / study)
    g = design.blank.pitch_angle_deg
    with pytest.raises(gearopt.NotAvailableError) as info:
        gearopt.with_overrides(design, {"pair.face_angle_deg": [g[0] + 1.0, g[1] + 1.0]})
    assert info.value.parameter == "pair.face_angle_deg"
    assert "uniform depth" in str(info.value)
