"""Design files: loading, overrides, and bad input that must give a clear GearoptError."""

from __future__ import annotations

import copy
import dataclasses

import pytest

import gearopt
from gearopt.errors import DesignError, GearoptError, UnknownKeyError
from gearopt.studyfile import load_study_spec

from .conftest import STUDIES


def test_every_study_design_loads():
    # study files (a [study] table) sit beside the designs; tests/test_study.py reads those
    paths = [p for p in sorted(STUDIES.glob("*.toml")) if "[study]" not in p.read_text()]
    assert len(paths) >= 4
    for path in paths:
        design = gearopt.load_design(path)
        assert design.model in ("cyclo-palloid", "epicycloid", "face-milling")
        assert design.name == path.stem


def test_design_is_frozen(table3_design):
    with pytest.raises(dataclasses.FrozenInstanceError):
        table3_design.pair.pinion_teeth = 17  # type: ignore[misc]


def test_overrides_make_a_new_validated_design(table3_design):
    changed = gearopt.with_overrides(table3_design, {"machine.pinion.inner_cutter_radius_mm": 80.0})
    assert changed.machine.pinion.inner_cutter_radius_mm == 80.0
    assert table3_design.machine.pinion.inner_cutter_radius_mm == 75.0
    with pytest.raises(UnknownKeyError):
        gearopt.with_overrides(table3_design, {"machine.pinion.inner_cutter_radius_in": 3.0})


@pytest.mark.parametrize(
    "overrides",
    [
        {"machine.pinion.inner_cutter_radius_mm": 80.0},
        {"pair.face_width_mm": 24.0, "machine.gear.inner_cutter_radius_mm": 75.5},
        {"misalignment.offset_mm": 0.1, "meta.name": "moved"},
        {"analysis.positions": 17, "load.torque_nm": [100.0]},
    ],
)
def test_overrides_equal_a_design_parsed_anew(table3_design, overrides):
    # the same design as parsing the changed document, with a source of its own
    changed = gearopt.with_overrides(table3_design, overrides)
    data = copy.deepcopy(dict(table3_design.source))
    for dotted, value in overrides.items():
        *path, last = dotted.split(".")
        node = data
        for part in path:
            node = node.setdefault(part, {})
        node[last] = value
    fresh = gearopt.parse_design(data)
    assert changed == fresh
    assert changed.source == fresh.source and changed.path == table3_design.path
    again = gearopt.with_overrides(changed, {"machine.pinion.inner_cutter_radius_mm": 74.0})
    assert again.pair == fresh.pair and again.misalignment == fresh.misalignment
    changed.source["meta"]["name"] = "edited"  # (as gearopt.best writes it out)
    assert table3_design.source.get("meta", {}).get("name") != "edited"


def test_misalignment_and_compensation_tables(table3_text):
    text = table3_text + "\n[misalignment]\noffset_mm = 0.1\nshaft_angle_deg = 0.05\n"
    design = gearopt.loads_design(text)
    assert design.misalignment.offset_mm == 0.1
    assert design.misalignment.shaft_angle_deg == 0.05
    assert design.misalignment.pinion_axial_mm == 0.0
    assert design.compensation.is_zero


def _edit(text: str, old: str, new: str) -> str:
    assert old in text, old
    return text.replace(old, new, 1)


# Each case: (description, edit of the seed 001 Table 3 design, error class, parameter named,
# a fragment of the rule). The value given must appear in the message too (checked below).
BAD = [
    (
        "zero teeth",
        ("pinion_teeth = 16", "pinion_teeth = 0"),
        DesignError,
        "pair.pinion_teeth",
        ">= 5",
    ),
    (
        "negative teeth",
        ("gear_teeth = 41", "gear_teeth = -41"),
        DesignError,
        "pair.gear_teeth",
        ">= 5",
    ),
    (
        "non-integer teeth",
        ("pinion_teeth = 16", "pinion_teeth = 16.5"),
        DesignError,
        "pair.pinion_teeth",
        "integer",
    ),
    (
        "teeth as text",
        ("gear_teeth = 41", 'gear_teeth = "41"'),
        DesignError,
        "pair.gear_teeth",
        "integer",
    ),
    (
        "gear smaller than pinion",
        ("gear_teeth = 41", "gear_teeth = 12"),
        DesignError,
        "pair.gear_teeth",
        "pinion",
    ),
    (
        "spiral angle out of range",
        ("mean_spiral_angle_deg = 35.0", "mean_spiral_angle_deg = 75.0"),
        DesignError,
        "pair.mean_spiral_angle_deg",
        "<= 60",
    ),
    (
        "shaft angle out of range",
        ("shaft_angle_deg = 90.0", "shaft_angle_deg = 180.0"),
        DesignError,
        "pair.shaft_angle_deg",
        "< 180",
    ),
    (
        "pressure angle out of range",
        ("pressure_angle_deg = 20.0", "pressure_angle_deg = 0.0"),
        DesignError,
        "pair.pressure_angle_deg",
        "> 0",
    ),
    (
        "module and cone distance disagree",
        ("mean_normal_module_mm = 3.397", "mean_normal_module_mm = 3.5"),
        DesignError,
        "pair.mean_normal_module_mm",
        "0.1 %",
    ),
    (
        "neither module nor cone distance",
        ("mean_normal_module_mm = 3.397\nmean_cone_distance_mm = 91.265", ""),
        DesignError,
        "pair.mean_cone_distance_mm",
        "give mean_cone_distance_mm or mean_normal_module_mm",
    ),
    (
        "negative cone distance",
        ("mean_cone_distance_mm = 91.265", "mean_cone_distance_mm = -91.265"),
        DesignError,
        "pair.mean_cone_distance_mm",
        "> 0",
    ),
    (
        "face width too large",
        ("face_width_mm = 32.0", "face_width_mm = 190.0"),
        DesignError,
        "pair.face_width_mm",
        "1/2 of the outer cone distance",
    ),
    (
        "face width over half the outer cone distance",  # A_m = 91.265: at most 60.84 mm
        ("face_width_mm = 32.0", "face_width_mm = 61.0"),
        DesignError,
        "pair.face_width_mm",
        "between 4.68 and 60.84 mm",
    ),
    (
        "face width under a twentieth of the outer cone distance",
        ("face_width_mm = 32.0", "face_width_mm = 0.001"),
        DesignError,
        "pair.face_width_mm",
        "between 1/20 and 1/2",
    ),
    (
        "bad hand",
        ('pinion_hand = "left"', 'pinion_hand = "sinister"'),
        DesignError,
        "pair.pinion_hand",
        "'left' or 'right'",
    ),
    (
        "addendum list of three",
        ("outer_addendum_mm = [3.397, 3.397]", "outer_addendum_mm = [3.4, 3.4, 3.4]"),
        DesignError,
        "pair.outer_addendum_mm",
        "two numbers",
    ),
    (
        "no clearance",
        ("outer_dedendum_mm = [4.076, 4.076]", "outer_dedendum_mm = [3.0, 4.076]"),
        DesignError,
        "pair.outer_dedendum_mm[pinion]",
        "clear the root",
    ),
    (
        "teeth thicker than the pitch",
        (
            "mean_normal_chordal_thickness_mm = [5.271, 5.276]",
            "mean_normal_chordal_thickness_mm = [6.0, 6.0]",
        ),
        DesignError,
        "pair.mean_normal_chordal_thickness_mm",
        "circular pitch",
    ),
    (
        "wrong units in a key",
        ("face_width_mm = 32.0", "face_width_in = 1.26"),
        UnknownKeyError,
        "pair.face_width_in",
        "face_width_mm",
    ),
    (
        "units in a value",
        ("face_width_mm = 32.0", 'face_width_mm = "32 mm"'),
        DesignError,
        "pair.face_width_mm",
        "no units in the value",
    ),
    (
        "unknown key",
        ("pinion_teeth = 16", "pinion_teeth = 16\nhelix_angle_deg = 35.0"),
        UnknownKeyError,
        "pair.helix_angle_deg",
        "unknown key",
    ),
    (
        "unknown section",
        ("[pair]", "[gearbox]\nratio = 2.5\n\n[pair]"),
        UnknownKeyError,
        "gearbox",
        "unknown key",
    ),
    (
        "missing pair key",
        ("face_width_mm = 32.0", ""),
        DesignError,
        "pair.face_width_mm",
        "required",
    ),
    (
        "unknown model",
        ('model = "cyclo-palloid"', 'model = "cyclopalloid"'),
        DesignError,
        "machine.model",
        "unknown machine model",
    ),
    (
        "blade groups not an integer",
        ("blade_groups = 5", "blade_groups = 5.5"),
        DesignError,
        "machine.blade_groups",
        "integer",
    ),
    (
        "zero blade groups",
        ("blade_groups = 5", "blade_groups = 0"),
        DesignError,
        "machine.blade_groups",
        ">= 1",
    ),
    (
        "negative blade module",
        ("blade_module_mm = 3.3973", "blade_module_mm = -3.3973"),
        DesignError,
        "machine.blade_module_mm",
        "> 0",
    ),
    (
        "cutter radius too small for the blade groups",
        (
            "[machine.pinion]\ninner_cutter_radius_mm = 75.0",
            "[machine.pinion]\ninner_cutter_radius_mm = 5.0",
        ),
        DesignError,
        "machine.pinion.inner_cutter_radius_mm",
        "eq 9",
    ),
    (
        "negative cutter radius",
        (
            "[machine.gear]\ninner_cutter_radius_mm = 75.0",
            "[machine.gear]\ninner_cutter_radius_mm = -75.0",
        ),
        DesignError,
        "machine.gear.inner_cutter_radius_mm",
        "> 0",
    ),
    (
        "outer radius without an eccentricity",
        (
            "[machine.gear]\ninner_cutter_radius_mm = 75.0\nouter_cutter_radius_mm = 75.0",
            "[machine.gear]\ninner_cutter_radius_mm = 75.0\nouter_cutter_radius_mm = 5.0",
        ),
        DesignError,
        "machine.gear.outer_cutter_radius_mm",
        "eq 33",
    ),
    (
        "slope angle below zero",
        (
            "inner_cutter_radius_mm = 75.0\nouter_cutter_radius_mm = 75.0\n"
            "additional_slope_angle_deg = 0.103669",
            "inner_cutter_radius_mm = 400.0\nouter_cutter_radius_mm = 400.0\n"
            "additional_slope_angle_deg = -2.0",
        ),
        DesignError,
        "machine.pinion.additional_slope_angle_deg",
        "(0, 90)",
    ),
    (
        "slope angle as a word",
        ("additional_slope_angle_deg = 0.103669", 'additional_slope_angle_deg = "big"'),
        DesignError,
        "machine.pinion.additional_slope_angle_deg",
        '"auto"',
    ),
    (
        "missing member table",
        (
            "[machine.gear]\ninner_cutter_radius_mm = 75.0\nouter_cutter_radius_mm = 75.0\n"
            "additional_slope_angle_deg = 0.078489",
            "",
        ),
        DesignError,
        "machine.gear",
        "required",
    ),
    (
        "unknown member key",
        ("[machine.gear]", "[machine.gear]\ncutter_radius_mm = 75.0"),
        UnknownKeyError,
        "machine.gear.cutter_radius_mm",
        "unknown key",
    ),
    (
        "misalignment out of range",
        ("[machine]", "[misalignment]\nshaft_angle_deg = 12.0\n\n[machine]"),
        DesignError,
        "misalignment.shaft_angle_deg",
        "< 5",
    ),
    (
        "unknown compensation key",
        ("[machine]", "[compensation]\noffset_um = 221\n\n[machine]"),
        UnknownKeyError,
        "compensation.offset_um",
        "offset_mm",
    ),
    (
        "malformed TOML",
        ("pinion_teeth = 16", "pinion_teeth = = 16"),
        DesignError,
        "design",
        "malformed TOML",
    ),
    ("meta not a table", ("[meta]", 'meta = "seed 001"'), DesignError, "meta", "table"),
]


@pytest.mark.parametrize(
    ("what", "edit", "error", "parameter", "rule"), BAD, ids=[b[0] for b in BAD]
)
def test_bad_input_names_parameter_value_and_rule(table3_text, what, edit, error, parameter, rule):
    text = _edit(table3_text, *edit)
    with pytest.raises(error) as info:
        gearopt.basic_settings(gearopt.loads_design(text))
    exc = info.value
    assert isinstance(exc, GearoptError)
    assert exc.parameter == parameter, str(exc)
    assert rule in exc.rule, str(exc)
    message = str(exc)
    assert message.startswith(parameter)
    if exc.value is not None:  # a value was given: the message quotes it before the rule
        assert message == f"{parameter} = {exc.value!r}: {exc.rule}"
    else:  # nothing was given (a missing key): the rule alone
        assert message == f"{parameter}: {exc.rule}"


def test_at_least_fifteen_kinds_of_bad_input():
    assert len({case[3] for case in BAD}) >= 15


def test_missing_file_and_directory(tmp_path):
    with pytest.raises(DesignError, match="does not exist"):
        gearopt.load_design(tmp_path / "nope.toml")
    with pytest.raises(DesignError, match="cannot be read"):
        gearopt.load_design(tmp_path)


def test_errors_are_value_errors_and_carry_their_parts():
    with pytest.raises(ValueError) as info:  # a GearoptError is a ValueError
        gearopt.PairData(
            pinion_teeth=3,
            gear_teeth=41,
            mean_spiral_angle_deg=35.0,
            face_width_mm=10.0,
            mean_normal_module_mm=3.0,
        )
    exc = info.value
    assert isinstance(exc, GearoptError)
    assert (exc.parameter, exc.value) == ("pair.pinion_teeth", 3)
    assert str(exc) == "pair.pinion_teeth = 3: must be >= 5 and <= 500"


def test_what_a_careless_or_hostile_file_holds_is_read_or_refused_in_one_line(
    table3_text, tmp_path
):
    # issue 27: a byte-order mark (Windows editors write one) is no reason to refuse a file
    marked = tmp_path / "marked.toml"
    marked.write_text("\ufeff" + table3_text, encoding="utf-8")
    assert gearopt.load_design(marked).pair.face_width_mm == 32.0
    # arrays nested 2000 deep: one line, not a 3000-line RecursionError
    deep = table3_text + "\n[te_target]\nv = " + "[" * 2000 + "]" * 2000 + "\n"
    with pytest.raises(DesignError) as info:
        gearopt.loads_design(deep)
    assert "nested too deeply" in str(info.value) and "\n" not in str(info.value)
    # a file far beyond any design's size is refused before it is parsed
    huge = table3_text.replace("[pair]", '[pair]\nnote = "' + "x" * 2_000_000 + '"')
    with pytest.raises(DesignError, match="at most 1000000"):
        gearopt.loads_design(huge)
    # an unknown key holding a long string: the message names it, not all of it
    long = table3_text.replace("[pair]", '[pair]\nnote = "' + "x" * 50_000 + '"')
    with pytest.raises(UnknownKeyError) as info:
        gearopt.loads_design(long)
    assert len(str(info.value)) < 1000 and "(50002 characters)" in str(info.value)
    study = tmp_path / "study.toml"
    study.write_bytes(b"\xff\xfe" + b"\x00" * 10)
    with pytest.raises(GearoptError, match="cannot be read as UTF-8 text"):
        load_study_spec(study)
