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
