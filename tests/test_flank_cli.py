"""``gearopt flank --at``: one flank point on the envelope, for every machine model."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

import gearopt
from gearopt.cli import main
from gearopt.flank import FlankGrid
from gearopt.flank_cli import flank_point

from .conftest import STUDIES

DESIGNS = ["seed001_table3.toml", "seed003_case_A.toml", "face_milling_conjugate.toml"]


@pytest.mark.parametrize("name", DESIGNS)
@pytest.mark.parametrize(("member", "flank"), [("pinion", "convex"), ("gear", "concave")])
def test_the_point_at_a_node_is_the_flankmaps_node(name, member, flank):
    design = gearopt.load_design(STUDIES / name)
    grid = FlankGrid(n_face=25, n_profile=13)
    fm = gearopt.generate_flanks(design, member, grid=grid)[flank]
    i, j = 12, int(np.flatnonzero(fm.mask[12])[len(np.flatnonzero(fm.mask[12])) // 2])
    x, y, z = fm.points_mm[i, j]
    out = flank_point(
        design, member=member, flank=flank, axial_mm=z, radius_mm=math.hypot(x, y), grid=grid
    )
    np.testing.assert_allclose(out["point_mm"], fm.points_mm[i, j], atol=1e-7)
    np.testing.assert_allclose(out["normal"], fm.normals[i, j], atol=1e-7)
    assert out["polar_angle_deg"] == pytest.approx(math.degrees(fm.polar_angle_rad[i, j]), abs=1e-7)
    assert out["inside_blank"] is True
    assert out["cone_distance_mm"] == pytest.approx(fm.face_mm[i], abs=1e-9)


@pytest.mark.parametrize("name", DESIGNS)
def test_a_point_beyond_the_heel_is_solved_on_the_envelope(name):
    design = gearopt.load_design(STUDIES / name)
    blank = design.blank
    gamma = math.radians(blank.pitch_angle_deg[0])
    s, h = blank.outer_cone_distance_mm + 2.0, 0.5
    axial, radius = (
        s * math.cos(gamma) - h * math.sin(gamma),
        s * math.sin(gamma) + h * math.cos(gamma),
    )
    out = flank_point(design, member="pinion", flank="concave", axial_mm=axial, radius_mm=radius)
    x, y, z = out["point_mm"]
    assert out["inside_blank"] is False
    assert z == pytest.approx(axial, abs=1e-9) and math.hypot(x, y) == pytest.approx(
        radius, abs=1e-9
    )
    assert np.linalg.norm(out["normal"]) == pytest.approx(1.0, abs=1e-12)


def test_cli_prints_the_contract_keys_and_refuses_bad_input(capsys):
    design = str(STUDIES / "face_milling_conjugate.toml")
    args = ["flank", design, "--member", "gear", "--flank", "convex", "--at", "60,60", "--json"]
    assert main(args) == 0
    out = json.loads(capsys.readouterr().out)
    assert {"point_mm", "normal", "polar_angle_deg", "inside_blank"} <= set(out)
    assert main(["flank", design, "--member", "gear", "--flank", "convex", "--at", "60"]) == 2
    assert "--at" in capsys.readouterr().err
