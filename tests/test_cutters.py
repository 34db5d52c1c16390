"""Standard cutter catalogues (plugins/cutters/catalogue.py), the categorical search over them,
and unequal drive and coast pressure angles (issue 24)."""

from __future__ import annotations

import json
import math
import shutil
import subprocess
import sys
import tomllib

import numpy as np
import optuna
import pytest

from gearopt.cli import main
from gearopt.design import pair_from_tables
from gearopt.design_files import load_design
from gearopt.errors import DesignError, PluginError, StudyError
from gearopt.machine import SearchDimension
from gearopt.plugins import get_machine_model
from gearopt.studyfile import parse_study_spec
from gearopt_plugins.cutters.catalogue import (
    CYCLO_PALLOID,
    EPICYCLOID,
    FACE_MILLING,
    INCH_MM,
    Catalogue,
    CutterSize,
    face_hobbing_rules,
    filtered,
)
from gearopt_plugins.face_milling.cutters import suitable

from .conftest import STUDIES
from .test_iso23509 import NASA_CR191009, NASA_PAIR, PAIR_1439  # printed basic data

DRIVE_COAST = STUDIES / "iso23509" / "face_milling_14x39_drive_coast.toml"


def test_every_catalogue_entry_names_its_source():
    for catalogue in (FACE_MILLING, CYCLO_PALLOID, EPICYCLOID):
        assert catalogue.sizes
        for size in catalogue.sizes:
            assert size.source.strip()
            # an entry no public document confirms says so in its source
            assert size.sourced or size.source.startswith("unsourced")
    # the face mills: nominal diameters in inches, radii in mm
    for size in FACE_MILLING.sizes:
        diameter_in = float(size.nominal.split()[0])
        assert size.radius_mm == pytest.approx(0.5 * diameter_in * INCH_MM, abs=1e-9)
    sourced = {s.radius_mm for s in FACE_MILLING.sizes if s.sourced}
    assert sourced == {76.2, 114.3}  # NASA CR-191009's gear cutter, ISO 23509 Annex F's r_c0
    assert [(s.radius_mm, s.blade_groups) for s in CYCLO_PALLOID.sizes] == [(75.0, 5)]
    assert [(s.radius_mm, s.blade_groups) for s in EPICYCLOID.sizes] == [(135.0, 5)]


@pytest.mark.parametrize("face_width_mm", [25.4, 40.0])
def test_face_mill_filter_keeps_exactly_the_cutters_with_a_tooth_trace(face_width_mm):
    """The filter's trace rule against the ISO 23509 blank, which computes the spiral angle at
    toe and heel from the cutter radius and refuses a cutter that gives none there."""
    pair_table = {**PAIR_1439, "face_width_mm": face_width_mm}
    pair, _ = pair_from_tables(
        pair_table, {"standard": "iso23509", "cutter_radius_mm": 76.2, "taper": "standard"}
    )
    kept, note = suitable(pair)
    kept_radii = {s.radius_mm for s in kept}
    for size in FACE_MILLING.sizes:
        blank = {"standard": "iso23509", "cutter_radius_mm": size.radius_mm, "taper": "standard"}
        try:
            pair_from_tables(pair_table, blank)
            traced = True
        except DesignError as exc:
            assert "tooth trace" in exc.rule
            traced = False
        assert (size.radius_mm in kept_radii) == traced, size
    assert note.startswith(f"Gleason face mills: {len(kept)} of {len(FACE_MILLING.sizes)} sizes")
    assert 0 < len(kept) < len(FACE_MILLING.sizes)  # the small face mills reach no toe


def test_face_hobbing_filter_applies_blade_groups_and_the_slope_angle_limit():
    kept, note = filtered(CYCLO_PALLOID, face_hobbing_rules(blade_groups=5, module_mm=4.0))
    assert [s.radius_mm for s in kept] == [75.0] and "1 of 1 sizes" in note
    kept, note = filtered(CYCLO_PALLOID, face_hobbing_rules(blade_groups=3, module_mm=4.0))
    assert kept == () and "blade groups other than the design's z0 = 3" in note
    # sin nu = z0 m / (2 r) < 1: a 30 mm module needs r > 75 mm
    kept, note = filtered(CYCLO_PALLOID, face_hobbing_rules(blade_groups=5, module_mm=30.0))
    assert kept == () and "radius <= z0 m / 2 = 75.000 mm" in note


def test_the_6_in_face_mill_is_the_gear_cutter_nasa_cr191009_prints():
    """The sourced 6 in entry is the mean of the gear's printed outside and inside blade point
    radii (tests/data/nasa_cr191009.json, transcribed from the report), and the face-mill
    filter keeps it for the report's own 12 x 36 blank (a pair that was cut with it)."""
    settings = NASA_CR191009["settings"]
    outside, inside = settings["gear_flank_1"]["r"], settings["gear_flank_2"]["r"]
    (six,) = [s for s in FACE_MILLING.sizes if s.nominal == "6 in diameter"]
    assert six.sourced and "CR-191009" in six.source
    assert six.radius_mm == pytest.approx(0.5 * (outside + inside) * INCH_MM, abs=1e-9)
    assert f"{outside:g} in" in six.source and f"{inside:g} in" in six.source
    blank = NASA_CR191009["blank"]
    pair, _ = pair_from_tables(
        NASA_PAIR,
        {
            "standard": "iso23509",
            "cutter_radius_mm": six.radius_mm,
            "gear_addendum_angle_deg": blank["gear"]["addendum_angle_deg"],
            "gear_dedendum_angle_deg": blank["gear"]["dedendum_angle_deg"],
        },
    )
    kept, _ = suitable(pair)
    assert six in kept


def test_the_module_range_drops_heads_made_for_other_modules():
    """No public source at hand gives a head's module range (docs/cutters.md), so the built-in
    heads have none; the rule is exercised on heads that have one."""
    heads = Catalogue(
        name="heads with module ranges",
        method="face hobbing",
        sizes=tuple(
            CutterSize(
                radius_mm=r,
                blade_groups=5,
                module_range_mm=rng,
                nominal=f"r = {r:g} mm",
                source="test data, not a catalogue",
            )
            for r, rng in ((55.0, (1.0, 3.0)), (75.0, (2.5, 5.0)), (100.0, None))
        ),
    )
    kept, note = filtered(heads, face_hobbing_rules(blade_groups=5, module_mm=4.0))
    assert [s.radius_mm for s in kept] == [75.0, 100.0]  # 100 mm: range unknown, kept
    assert "1 dropped: module range without m = 4 mm" in note
    kept, note = filtered(heads, face_hobbing_rules(blade_groups=5, module_mm=2.75))
    assert [s.radius_mm for s in kept] == [55.0, 75.0, 100.0]
    # the built-in heads carry no module range: the rule drops none of them
    assert all(s.module_range_mm is None for c in (CYCLO_PALLOID, EPICYCLOID) for s in c.sizes)


def test_categorical_dimension_suggests_only_its_choices():
    dim = SearchDimension.categorical("machine.x_mm", [114.3, 76.2, 76.2, 152.4], "note")
    assert dim.choices == (76.2, 114.3, 152.4) and (dim.low, dim.high) == (76.2, 152.4)
    assert dim.contains(114.3) and not dim.contains(100.0)
    assert dim.describe() == {"choices": [76.2, 114.3, 152.4]}
    study = optuna.create_study(sampler=optuna.samplers.RandomSampler(seed=3))
    seen = {dim.suggest(study.ask()) for _ in range(30)}
    assert seen == set(dim.choices)
    with pytest.raises(PluginError):
        SearchDimension.categorical("machine.x_mm", [])
    with pytest.raises(PluginError):  # bounds that are not the extreme choices
        SearchDimension(key="machine.x_mm", low=70.0, high=152.4, choices=(76.2, 152.4))


def _study(search: dict, **extra) -> dict:
    return {
        "study": {"design": "seed001_section5_3.toml", "seed": 1},
        "search": search,
        "evaluations": {"tca": {}},
        "objectives": [{"name": "worst_te", "on": ["tca"], "side": "both"}],
        **extra,
    }


def test_study_file_catalogue_search_is_categorical_and_checks_given_designs():
    key = "machine.pinion.inner_cutter_radius_mm"
    spec = parse_study_spec(_study({key: "catalogue"}), path=STUDIES / "x.toml")
    (dim,) = spec.search
    assert dim.choices == (75.0,) and "cyclo-palloid heads: 1 of 1 sizes" in dim.note
    assert dim.note.endswith("module range known for 0 of the 1 kept")
    with pytest.raises(StudyError, match="must be one of the catalogue's"):
        parse_study_spec(_study({key: "catalogue"}, enqueue=[{key: 76.0}]), path=STUDIES / "x.toml")
    with pytest.raises(StudyError, match="offers the catalogue for"):
        parse_study_spec(
            _study({"machine.pinion.outer_cutter_radius_mm": "catalogue"}),
            path=STUDIES / "x.toml",
        )
    # no head of the catalogue has 3 blade groups: the model has none to offer
    with pytest.raises(StudyError, match="has no cutter catalogue for this design"):
        parse_study_spec(
            _study({key: "catalogue"}, fixed={"machine.blade_groups": 3}),
            path=STUDIES / "x.toml",
        )


def test_face_milling_offers_the_catalogue_for_the_gear_cutter_of_its_synthesis():
    design = load_design(STUDIES / "iso23509" / "face_milling_14x39.toml")
    (dim,) = get_machine_model(design.model).cutter_catalogue(design)
    assert dim.key == "synthesis.gear_cutter_radius_mm"
    assert set(dim.choices) == {s.radius_mm for s in suitable(design.pair)[0]}
    assert 76.2 in dim.choices and 114.3 in dim.choices
    # a design whose settings are given has no nominal cutter to search
    given = load_design(STUDIES / "seed002_pair.toml")
    assert "gear_cutter_radius_mm" not in given.source.get("synthesis", {})
    settings = get_machine_model(given.model).basic_settings(given)
    default = [n for n in settings.notes if n.startswith("default:")]
    assert len(default) == 1 and "9 in diameter (r_c0 = 114.3 mm)" in default[0]


def test_the_epicycloid_model_offers_seed003s_head_for_seed003s_design():
    """Seed 003 case A cuts its pinion with the R_h = 135 mm, z0 = 5 head (m_mn 6.1 mm): the
    epicycloid model's catalogue keeps that head for the seed's design, for the machine's and
    each member's head radius."""
    design = load_design(STUDIES / "seed003_case_A.toml")
    dims = get_machine_model(design.model).cutter_catalogue(design)
    assert [d.key for d in dims] == [
        "machine.cutter_head_radius_mm",
        "machine.pinion.cutter_head_radius_mm",
        "machine.gear.cutter_head_radius_mm",
    ]
    for dim in dims:
        assert dim.choices == (135.0,)
        assert dim.note.startswith("Klingelnberg epicycloid heads: 1 of 1 sizes")


@pytest.mark.slow
def test_a_short_catalogue_study_ends_with_a_catalogue_cutter(tmp_path):
    shutil.copy(STUDIES / "seed001_section5_3.toml", tmp_path)
    key = "machine.pinion.inner_cutter_radius_mm"
    (tmp_path / "cat.toml").write_text(
        "[study]\nname = 'cat'\ndesign = 'seed001_section5_3.toml'\nseed = 5\n"
        f"[search]\n'{key}' = 'catalogue'\n"
        "'machine.pinion.outer_cutter_radius_mm' = [75.0, 76.0]\n"
        "[evaluations.tca]\n[[objectives]]\nname = 'worst_te'\non = ['tca']\nside = 'both'\n"
    )
    run = subprocess.run(
        [sys.executable, "-m", "gearopt.cli", "study", "run", "cat.toml"]
        + ["--trials", "2", "--jobs", "1", "--json", "--no-progress"],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert run.returncode == 0, run.stderr
    assert json.loads(run.stdout)["complete"] == 2
    best = tomllib.loads((tmp_path / "cat_best.toml").read_text())
    assert best["machine"]["pinion"]["inner_cutter_radius_mm"] in {
        s.radius_mm for s in CYCLO_PALLOID.sizes
    }


def test_one_pressure_angle_is_both_sides_and_a_bad_list_names_the_rule():
    pair, blank = pair_from_tables(
        PAIR_1439, {"standard": "iso23509", "cutter_radius_mm": 76.2, "taper": "duplex"}
    )
    same, same_blank = pair_from_tables(
        {**PAIR_1439, "pressure_angle_deg": [20.0, 20.0]},
        {"standard": "iso23509", "cutter_radius_mm": 76.2, "taper": "duplex"},
    )
    assert pair.pressure_angles_deg == (20.0, 20.0) and not pair.unequal_pressure_angles
    assert same_blank == blank  # [a, a] is the one angle a
    with pytest.raises(DesignError, match=r"pressure_angle_deg\[coast\]"):
        pair_from_tables({**PAIR_1439, "pressure_angle_deg": [20.0, 50.0]}, None)
    with pytest.raises(DesignError, match="two \\[drive, coast\\]"):
        pair_from_tables({**PAIR_1439, "pressure_angle_deg": [20.0, 18.0, 16.0]}, None)


def test_unequal_pressure_angles_in_the_standard_blank():
    """The tooth thickness grows by x_hm1 m_mn on each flank times that flank's tangent; the
    duplex taper's slot keeps its width with the mean tangent; both as equal angles whose
    tangent is the mean."""
    blank = {"standard": "iso23509", "cutter_radius_mm": 76.2, "taper": "duplex"}
    drive, coast = 22.0, 18.0
    _, both = pair_from_tables({**PAIR_1439, "pressure_angle_deg": [drive, coast]}, blank)
    mean_tan = 0.5 * (math.tan(math.radians(drive)) + math.tan(math.radians(coast)))
    _, equal = pair_from_tables(
        {**PAIR_1439, "pressure_angle_deg": math.degrees(math.atan(mean_tan))}, blank
    )
    np.testing.assert_allclose(both.dedendum_angle_deg, equal.dedendum_angle_deg, rtol=1e-12)
    x, m = both.profile_shift_coefficient, both.mean_normal_module_mm
    expected = 0.5 * math.pi * m + x * m * 2.0 * mean_tan
    assert both.mean_normal_circular_thickness_mm[0] == pytest.approx(expected, abs=1e-12)
    # the profile contact ratio reported is the worse side's: the smaller angle's is larger
    _, d = pair_from_tables({**PAIR_1439, "pressure_angle_deg": drive}, blank)
    _, c = pair_from_tables({**PAIR_1439, "pressure_angle_deg": coast}, blank)
    assert both.total_contact_ratio == pytest.approx(
        min(d.total_contact_ratio, c.total_contact_ratio), rel=1e-3
    )


def test_models_that_cannot_cut_unequal_angles_say_so():
    design = load_design(STUDIES / "iso23509" / "cyclo_palloid_17x43.toml")
    source = {**design.source, "pair": {**design.source["pair"], "pressure_angle_deg": [22, 18]}}
    from gearopt.design_files import parse_design

    with pytest.raises(DesignError, match="cannot cut unequal drive and coast pressure angles"):
        parse_design(source)
    # the epicycloid grinds each flank's blade: each defaults to its side's angle
    epi = load_design(STUDIES / "iso23509" / "epicycloid_19x34.toml")
    source = {**epi.source, "pair": {**epi.source["pair"], "pressure_angle_deg": [22, 18]}}
    machine = parse_design(source).machine
    assert machine.pinion.convex.profile_pressure_angle_deg == 22.0  # drive
    assert machine.pinion.concave.profile_pressure_angle_deg == 18.0  # coast
    assert machine.gear.concave.profile_pressure_angle_deg == 22.0  # drive
    assert machine.gear.convex.profile_pressure_angle_deg == 18.0  # coast


def _pitch_pressure_angle_deg(flank, mean_cone_distance_mm: float) -> float:
    """The flank's pressure angle at the mean pitch point, measured on the generated flank:
    the angle between its normal and the pitch cone's tangent plane (member frame: z along the
    axis toward the heel), read on the row nearest A_m and interpolated to height 0 along the
    profile."""
    i = int(np.argmin(np.abs(flank.face_mm - mean_cone_distance_mm)))
    g = math.radians(flank.pitch_angle_deg)
    p, n = flank.points_mm[i], flank.normals[i]
    radial = p[:, :2] / np.linalg.norm(p[:, :2], axis=1)[:, None]
    cone_normal = np.column_stack([math.cos(g) * radial, -math.sin(g) * np.ones(len(p))])
    angle = np.degrees(np.arcsin(np.abs(np.sum(n * cone_normal, axis=1))))
    keep = flank.mask[i]
    heights = np.asarray(flank.heights_mm)[i]
    return float(np.interp(0.0, heights[keep], angle[keep]))


@pytest.mark.slow
def test_unequal_pressure_angles_end_to_end_on_a_face_milled_pair(capsys):
    """settings, flanks and analyze on the 14/39 pair with 22 deg drive and 18 deg coast.
    Measured on the generated flanks at the mean pitch point against the same pair at 20 deg:
    each flank's pressure angle moves by its side's change, +2 deg (drive) or -2 deg (coast),
    to 0.02 deg (measured 0.012 at most: the grid row is up to half a step, 0.53 mm, off A_m);
    the values themselves are within 0.1 deg of the design's (the pinion's from the local
    synthesis at M, measured 0.08 deg off at 20 deg too)."""
    assert main(["settings", str(DRIVE_COAST), "--json"]) == 0
    settings = json.loads(capsys.readouterr().out)
    assert settings["model"] == "face-milling"
    assert settings["blank"]["pressure_angles_deg"] == [22.0, 18.0]
    measured = {}
    for path in (DRIVE_COAST, STUDIES / "iso23509" / "face_milling_14x39.toml"):
        design = load_design(path)
        model = get_machine_model(design.model)
        am = design.blank.mean_cone_distance_mm
        for member in ("pinion", "gear"):
            for flank, generated in model.generate_flanks(design, member=member).items():
                measured[path, member, flank] = _pitch_pressure_angle_deg(generated, am)
    for member, flank, change in (
        ("pinion", "convex", 2.0),  # drive
        ("pinion", "concave", -2.0),  # coast
        ("gear", "concave", 2.0),  # drive
        ("gear", "convex", -2.0),  # coast
    ):
        unequal = measured[DRIVE_COAST, member, flank]
        equal = measured[STUDIES / "iso23509" / "face_milling_14x39.toml", member, flank]
        assert unequal - equal == pytest.approx(change, abs=0.02), (member, flank)
        assert unequal == pytest.approx(20.0 + change, abs=0.1), (member, flank)
    assert main(["flanks", str(DRIVE_COAST), "--json", "--grid", "13,9"]) == 0
    capsys.readouterr()
    assert main(["analyze", str(DRIVE_COAST), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    for key in ("tca", "tca_coast"):
        te = out[key]["te_arcsec"]
        assert all(math.isfinite(v) for v in te) and out[key]["te_peak_to_peak_arcsec"] < 60.0
    assert out["backlash"]["interference"] is False
