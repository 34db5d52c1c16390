"""REXS export and import (gearopt.rexs, issue 26 item 3): round trips cut identical flanks,
exported files validate against the released REXS 2.0.0 database (an extract in tests/data),
left and right flanks as docs/rexs.md says, bad files refused naming the attribute."""

from __future__ import annotations

import copy
import json
from pathlib import Path

import numpy as np
import pytest

from gearopt.cli import main
from gearopt.design_files import load_design, parse_design
from gearopt.errors import RexsError
from gearopt.plugins import get_machine_model
from gearopt.rexs.attributes import CUSTOM_PREFIX, SCHEMA
from gearopt.rexs.document import RENAMED_FROM_1, flank_of_side
from gearopt.rexs.files import export_rexs, load_rexs, rexs_tables

ROOT = Path(__file__).resolve().parents[1]
EXTRACT = json.loads((ROOT / "tests/data/rexs_2.0.0_bevel_extract.json").read_text("utf-8"))
DESIGNS = {
    "cyclo-palloid": ROOT / "studies/seed001_section5_3.toml",
    "epicycloid": ROOT / "studies/seed003_case_A.toml",
    "face-milling": ROOT / "studies/iso23509/face_milling_14x39.toml",
}
DATE = "2026-01-01T00:00:00+00:00"


@pytest.fixture(scope="module")
def designs():
    return {k: load_design(p) for k, p in DESIGNS.items()}


@pytest.fixture(scope="module")
def documents(designs):
    return {k: export_rexs(d, date=DATE) for k, d in designs.items()}


@pytest.fixture(scope="module")
def flanks_of():
    """Generated flanks of a design, by design name (each design generated once)."""
    found = {}

    def get(name, design):
        if name not in found:
            found[name] = _flanks(design)
        return found[name]

    return get


def _flanks(design):
    model = get_machine_model(design.model)
    return {m: model.generate_flanks(design, member=m) for m in ("pinion", "gear")}


@pytest.mark.parametrize("name", sorted(DESIGNS))
def test_a_round_trip_cuts_identical_flanks(name, designs, documents, flanks_of):
    original = designs[name]
    # through the text of the file, as another tool would receive it
    tables = rexs_tables(json.loads(json.dumps(documents[name])))
    back = parse_design(tables)
    assert back.model == original.model and back.blank == original.blank
    before, after = flanks_of(name, original), _flanks(back)
    for member, flanks in before.items():
        for flank, a in flanks.items():
            b = after[member][flank]
            # the same nodes generated, the same points to 1e-9 mm
            np.testing.assert_array_equal(np.isnan(a.points_mm), np.isnan(b.points_mm))
            ok = np.isfinite(a.points_mm)
            assert ok.sum() > 100
            np.testing.assert_allclose(b.points_mm[ok], a.points_mm[ok], rtol=0.0, atol=1e-9)


def test_the_face_milled_design_carries_its_modified_roll(documents):
    """The 14x39 pinion's synthesis uses a modified roll (c2 != 0): the file carries it."""
    model = documents["face-milling"]["model"]
    rolls = [
        a["floating_point_array"]
        for c in model["components"]
        if c["type"] == "bevel_gear_manufacturing_settings"
        for a in c["attributes"]
        if a["id"] == "modified_roll_coefficients"
    ]
    assert len(rolls) == 4
    assert any(r[0] != 0.0 for r in rolls)


def test_the_attribute_table_is_the_released_schemas():
    for attribute, (unit, kind) in SCHEMA.items():
        found = EXTRACT["attributes"][attribute]
        assert (found["unit"], found["value_type"]) == (unit, kind), attribute


@pytest.mark.parametrize("name", sorted(DESIGNS))
def test_the_exported_file_validates_against_the_schema(name, documents):
    assert EXTRACT["status"] == "RELEASED"
    model = documents[name]["model"]
    assert model["version"] == EXTRACT["version"]
    by_id = {c["id"]: c for c in model["components"]}
    assert len(by_id) == len(model["components"])
    custom = 0
    for c in model["components"]:
        assert c["type"] in EXTRACT["components"], c["type"]
        ids = [a["id"] for a in c["attributes"]]
        assert len(ids) == len(set(ids))
        for a in c["attributes"]:
            values = [k for k in a if k not in ("id", "unit")]
            assert len(values) == 1
            if a["id"].startswith("custom_"):
                assert a["id"].startswith(CUSTOM_PREFIX)
                custom += 1
                continue
            assert a["id"] in EXTRACT["components"][c["type"]], (c["type"], a["id"])
            spec = EXTRACT["attributes"][a["id"]]
            assert a["unit"] == spec["unit"], a["id"]
            assert values[0] == spec["value_type"], a["id"]
            value = a[values[0]]
            if spec["value_type"] == "floating_point":
                assert isinstance(value, float) and np.isfinite(value)
            elif spec["value_type"] == "integer":
                assert isinstance(value, int) and not isinstance(value, bool)
            elif spec["value_type"] == "floating_point_array":
                assert all(isinstance(v, float) for v in value)
            elif spec["value_type"] == "enum":
                assert value in spec["enum_values"]
    assert custom > 0
    kinds = {"stage": 0, "flank": 0, "manufacturing_step": 0}
    for rel in model["relations"]:
        spec = EXTRACT["relations"][rel["type"]]
        kinds[rel["type"]] += 1
        roles = {r["role"]: by_id[r["id"]]["type"] for r in rel["refs"]}
        assert roles in spec["allowed"], rel
        assert ("order" in rel) == spec["order_required"]
    assert kinds == {"stage": 1, "flank": 2, "manufacturing_step": 4}


@pytest.mark.parametrize("name", ["cyclo-palloid", "face-milling"])
def test_left_and_right_flanks_as_documented(name, designs, flanks_of):
    """Seen from the heel toward the apex, tip up, the left flank's outward normal points in
    the sense of increasing polar angle (the member axis toward the heel)."""
    design = designs[name]
    for member, flanks in flanks_of(name, design).items():
        hand = design.pair.pinion_hand if member == "pinion" else design.pair.gear_hand
        for side, sign in (("left", 1.0), ("right", -1.0)):
            fm = flanks[flank_of_side(hand, side)]
            i, j = fm.points_mm.shape[0] // 2, fm.points_mm.shape[1] // 2
            p, n = fm.points_mm[i, j], fm.normals[i, j]
            e_theta = np.array([-p[1], p[0], 0.0]) / np.hypot(p[0], p[1])
            assert sign * float(n @ e_theta) > 0.5, (member, side)


def _component(document, kind, name):
    for c in document["model"]["components"]:
        if c["type"] == kind and c["name"] == name:
            return c
    raise AssertionError((kind, name))


def test_bad_files_are_refused_naming_the_attribute(documents):
    base = documents["face-milling"]

    def refused(change, match, **kwargs):
        doc = copy.deepcopy(base)
        change(doc)
        with pytest.raises(RexsError, match=match):
            rexs_tables(doc, **kwargs)

    def drop(kind, name, attribute):
        def change(doc):
            c = _component(doc, kind, name)
            c["attributes"] = [a for a in c["attributes"] if a["id"] != attribute]

        return change

    def set_attr(kind, name, attribute, **item):
        def change(doc):
            c = _component(doc, kind, name)
            c["attributes"] = [a for a in c["attributes"] if a["id"] != attribute]
            c["attributes"].append({"id": attribute, **item})

        return change

    tool, settings = "bevel_gear_tool", "bevel_gear_manufacturing_settings"
    refused(drop(tool, "pinion convex tool", "blade_point_radius"), "pinion convex.blade_point")
    refused(
        set_attr(tool, "gear concave tool", "blade_pressure_angle", unit="rad", floating_point=0.3),
        "gear concave.blade_pressure_angle.*'deg'",
    )
    refused(
        set_attr(
            settings, "pinion concave settings", "cutter_tilt", unit="deg", floating_point=2.0
        ),
        "pinion concave.cutter_tilt.*not modelled",
    )
    refused(
        set_attr(
            settings,
            "gear convex settings",
            "modified_roll_coefficients",
            unit="none",
            floating_point_array=[0.0] * 6,
        ),
        "gear convex.modified_roll_coefficients",
    )
    refused(drop("bevel_gear", "gear", "number_of_teeth"), "gear.number_of_teeth")
    refused(
        set_attr(
            "bevel_stage",
            base["model"]["components"][0]["name"],
            "hypoid_offset",
            unit="mm",
            floating_point=5.0,
        ),
        "hypoid_offset",
    )
    refused(
        drop(
            "bevel_stage", base["model"]["components"][0]["name"], CUSTOM_PREFIX + "machine_model"
        ),
        "custom_gearopt_machine_model",
    )
    # a zero setting gearopt does not model is accepted, and so is the model named by the caller
    doc = copy.deepcopy(base)
    set_attr(settings, "pinion concave settings", "cutter_tilt", unit="deg", floating_point=0.0)(
        doc
    )
    drop("bevel_stage", doc["model"]["components"][0]["name"], CUSTOM_PREFIX + "machine_model")(doc)
    assert rexs_tables(doc, model="face-milling")["machine"]["model"] == "face-milling"


def test_the_commands_round_trip_an_epicycloid_design(tmp_path):
    """``gearopt rexs export`` then ``import``: the epicycloid design (seed 003 case A) reads
    back with the same machine and blank. (A model without a mapping round-trips through the
    default hooks: the toy model's contract, tests/test_plugins.py.)"""
    path = ROOT / "studies/seed003_case_A.toml"
    design = load_design(path)
    out = tmp_path / "a.rexsj"
    assert main(["rexs", "export", str(path), "--out", str(out), "--date", DATE]) == 0
    assert main(["rexs", "import", str(out), "--out", str(tmp_path / "a.toml")]) == 0
    back = load_design(tmp_path / "a.toml")
    assert back.machine == design.machine and back.blank == design.blank
    assert load_rexs(out).machine == design.machine
    text = out.read_text(encoding="utf-8")
    assert "blade_point_radius" in text and "custom_gearopt_machine_table" not in text


def test_the_xml_form_is_refused_clearly(tmp_path):
    path = tmp_path / "a.rexs"
    path.write_text('<?xml version="1.0"?><model/>', encoding="utf-8")
    with pytest.raises(RexsError, match="XML form"):
        load_rexs(path)


def test_settings_gearopt_derives_are_checked_against_the_file(documents):
    """A cyclo-palloid file whose machine distance is not the one gearopt derives from the
    cutter (here 0.01 mm off, or without gearopt's additional slope angle) is refused."""
    base = documents["cyclo-palloid"]
    doc = copy.deepcopy(base)
    for a in _component(doc, "bevel_gear_manufacturing_settings", "gear convex settings")[
        "attributes"
    ]:
        if a["id"] == "radial_distance":
            a["floating_point"] += 0.01
    with pytest.raises(RexsError, match="gear convex.radial_distance"):
        rexs_tables(doc)
    doc = copy.deepcopy(base)
    c = _component(doc, "bevel_gear_manufacturing_settings", "pinion concave settings")
    c["attributes"] = [
        a for a in c["attributes"] if a["id"] != CUSTOM_PREFIX + "additional_slope_angle"
    ]
    with pytest.raises(RexsError, match="pinion concave"):
        rexs_tables(doc)


def test_a_rexs_1_7_file_reads_with_its_attribute_ids(documents):
    """REXS 1.7 (the bevel tool and settings components' first release) named the pressure
    angles and the chordal thickness otherwise; its file reads as the 2.0.0 one."""
    doc = copy.deepcopy(documents["cyclo-palloid"])
    doc["model"]["version"] = "1.7"
    old = {v: k for k, v in RENAMED_FROM_1.items()}
    for c in doc["model"]["components"]:
        for a in c["attributes"]:
            a["id"] = old.get(a["id"], a["id"])
    assert rexs_tables(doc) == rexs_tables(documents["cyclo-palloid"])
