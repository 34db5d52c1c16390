"""The closed loop (gearopt.measurement, ``gearopt grid`` and ``gearopt correct``): the nominal
measuring grid, normal deviations, identification of the settings that cut a measured gear and
the corrective settings, for every machine model.

A "measured" gear here is the nominal design cut with known setting errors (its flanks
regenerated and measured on the nominal grid), sometimes with noise or a deviation no setting
makes: the loop must reproduce the topography, recover the errors the grid can see, name the
ones it cannot, and leave the rest in the residual.
"""

from __future__ import annotations

import csv
import io
import json
import math
import warnings
from pathlib import Path

import numpy as np
import pytest

import gearopt
from gearopt.cli import main
from gearopt.errors import DesignError, GearoptError, GearoptWarning
from gearopt.measurement.files import MEASURED_HEADER
from gearopt.measurement.grid import measuring_grid, normal_deviation_um
from gearopt.measurement.identify import correct, design_with, identify
from gearopt.measurement.topography import nominal_measurement, split_deviation
from gearopt.measurement_cli import GRID_HEADER
from gearopt.plugins import get_machine_model

STUDIES = Path(__file__).resolve().parents[1] / "studies"
FACE_MILLING = STUDIES / "face_milling_conjugate.toml"
CYCLO_PALLOID = STUDIES / "seed001_section5_3.toml"
EPICYCLOID = STUDIES / "seed003_case_A.toml"


@pytest.fixture(scope="module")
def face_milling():
    return gearopt.load_design(FACE_MILLING)


@pytest.fixture(scope="module")
def pinion(face_milling):
    return nominal_measurement(face_milling, "pinion")


def _cut(nominal, errors):
    """The nominal member cut with ``errors`` ({key: error}) and measured on its grid (NaN
    where the cut flank or the nominal one is not generated)."""
    model = get_machine_model(nominal.design.model)
    settings = model.correction_settings(nominal.design, nominal.member)
    by_key = {s.key: s for s in settings}
    values = {k: by_key[k].value + e for k, e in errors.items()}
    dev = nominal.deviations(design_with(nominal.design, settings, values))
    return {f: np.where(ok, v, np.nan) for f, (v, ok) in dev.items()}


# --- the grid ------------------------------------------------------------------------------------


def test_grid_positions_come_from_the_blank_alone(face_milling):
    grid = measuring_grid(face_milling.blank, "gear", points=(9, 5), margin_mm=1.0)
    blank = face_milling.blank
    assert grid.face_mm[0] == pytest.approx(blank.inner_cone_distance_mm + 1.0)
    assert grid.face_mm[-1] == pytest.approx(blank.outer_cone_distance_mm - 1.0)
    assert grid.profile_mm[:, 0] == pytest.approx(-blank.dedendum_at_mm(1, grid.face_mm) + 1.0)
    assert grid.profile_mm[:, -1] == pytest.approx(blank.addendum_at_mm(1, grid.face_mm) - 1.0)
    other = gearopt.with_overrides(face_milling, {"machine.gear.radial_setting_mm": 75.0})
    again = nominal_measurement(other, "gear", margin_mm=1.0).grid
    assert np.array_equal(again.face_mm, grid.face_mm)
    assert np.array_equal(again.profile_mm, grid.profile_mm)


def test_grid_points_and_normals_are_the_generated_flanks(pinion):
    model = get_machine_model(pinion.design.model)
    flanks = model.generate_flanks(pinion.design, member="pinion", grid=pinion.flank_grid)
    for flank, pts in pinion.points.items():
        fm = flanks[flank]
        on = pts.generated
        assert 0.5 * on.size < on.sum() < on.size  # the root's fillet region is marked
        s, t = fm.to_grid(pinion.grid.axial_mm[on], pinion.grid.radius_mm[on])
        exact = fm.surface.geometry_at(s, t)
        assert np.abs(pts.points_mm[on] - exact["point"]).max() < 1e-5
        assert np.abs(pts.normals[on] - exact["normal"]).max() < 1e-5
        assert np.linalg.norm(pts.normals, axis=-1) == pytest.approx(1.0)


def test_rotation_is_the_deviation_of_a_turned_flank(pinion):
    """delta = R dTheta (n . e_Theta): checked against the generator's own work phase."""
    for flank in ("convex", "concave"):
        turned = gearopt.with_overrides(
            pinion.design, {f"machine.pinion.{flank}.work_phase_deg": 0.002}
        )
        fm = get_machine_model("face-milling").generate_flank(
            turned, member="pinion", flank=flank, grid=pinion.flank_grid
        )
        dev, ok = normal_deviation_um(pinion.grid, pinion.points[flank], fm)
        formula = pinion.rotation_um_per_deg(flank) * 0.002
        assert np.abs(formula[ok]).min() > 0.3  # a real movement, of some tenths of a um
        # the left-hand pinion's work phase turns its flank backwards
        assert np.abs(np.abs(dev[ok]) - np.abs(formula[ok])).max() < 1e-6
        assert np.all(np.sign(dev[ok]) == -np.sign(formula[ok]))


def test_split_reads_back_the_terms_it_names(pinion):
    grid = pinion.grid
    u = np.linspace(-1.0, 1.0, grid.shape[0])[:, None]
    v = np.linspace(-1.0, 1.0, grid.shape[1])[None, :]
    d = 3.0 + 1.0 * v + 2.0 * u - 4.0 * (u * u - 1 / 3) + 0.5 * u * v + 0.0 * u * v
    out = split_deviation(grid, np.broadcast_to(d, grid.shape), np.ones(grid.shape, bool))
    assert out["spacing_um"] == pytest.approx(3.0)
    assert out["pressure_angle_um"] == pytest.approx(2.0)
    assert out["spiral_angle_um"] == pytest.approx(4.0)
    assert out["lengthwise_crowning_um"] == pytest.approx(4.0)
    assert out["bias_um"] == pytest.approx(2.0)
    assert out["residual_rms_um"] == pytest.approx(0.0, abs=1e-12)


# --- identification: face milling -------------------------------------------------------------

ERRORS = {
    "machine.pinion.radial_setting_mm": 0.02,
    "machine.pinion.machine_root_angle_deg": 0.017,
    "machine.pinion.sliding_base_mm": -0.02,
    "machine.pinion.blank_offset_mm": 0.01,
    "machine.pinion.ratio_of_roll": 2e-4,
    "machine.pinion.convex.blade_pressure_angle_deg": 0.01,
}


@pytest.fixture(scope="module")
def identified(pinion):
    return identify(pinion, _cut(pinion, ERRORS))


def test_face_milling_identification_reproduces_and_recovers(identified):
    for flank in ("convex", "concave"):
        assert identified.rms_um(flank, "measured") > 5.0
        assert identified.rms_um(flank) < 0.1
    errors = identified.errors()
    for key, error in ERRORS.items():
        assert errors[key] == pytest.approx(error, rel=1e-3, abs=1e-6)
    for key in set(errors) - set(ERRORS):
        assert abs(errors[key]) < 1e-5
    # the cradle angle turns the generated flank as the work's index does: told apart from
    # nothing but the rotations, reported, kept nominal
    assert "machine.pinion.cradle_angle_deg" not in identified.kept
    assert "machine.pinion.cradle_angle_deg" in identified.aliases
    assert identified.condition_number < 1e3 < identified.condition_number_all


def test_face_milling_correction_is_verified_by_regenerating(identified):
    fix = correct(identified)
    report = fix.report()
    assert "machine.pinion.convex.blade_pressure_angle_deg" not in report["settings"]
    for flank in ("convex", "concave"):
        # the blade's error is compensated by the machine's settings, not removed
        assert report["flanks"][flank]["predicted_rms_um"] < 0.2 * identified.rms_um(
            flank, "measured"
        )
    # dialled on a machine that repeats the identified errors, the corrective settings cut
    # what was predicted
    errors = identified.errors()
    next_cut = {
        k: fix.values.get(k, by.value) + errors.get(k, 0.0) - by.value
        for k, by in {s.key: s for s in identified.settings}.items()
        if k in fix.values or k in errors
    }
    measured = _cut(identified.nominal, next_cut)
    for flank, pred in fix.predicted_um.items():
        ok = identified.valid[flank] & np.isfinite(measured[flank])
        assert np.abs(measured[flank][ok] - pred[ok]).max() < 0.05


def test_noise_is_not_forced_into_the_settings(pinion):
    rng = np.random.default_rng(7)
    clean = _cut(pinion, ERRORS)
    noisy = {f: v + rng.standard_normal(v.shape) for f, v in clean.items()}
    ident = identify(pinion, noisy)
    for flank in noisy:
        assert 0.6 < ident.rms_um(flank) < 1.2  # the noise, left as residual
    errors = ident.errors()
    for key, error in ERRORS.items():
        assert abs(errors[key] - error) < 4.0 * ident.sigma[key]  # the uncertainty is honest
    # correlated settings are uncertain one by one, the topography they make is not: the
    # model is the clean measurement to a fraction of the noise (about sqrt(p / n) of it, p
    # fitted terms on n points)
    for flank in noisy:
        ok = ident.valid[flank]
        share = math.sqrt((len(ident.kept) + 2) / sum(v.sum() for v in ident.valid.values()))
        miss = ident.modelled_um[flank][ok] - clean[flank][ok]
        assert np.sqrt(np.mean(miss**2)) < 2.0 * share


def test_a_deviation_no_setting_makes_stays_residual(pinion):
    grid = pinion.grid
    u = np.linspace(-1.0, 1.0, grid.shape[0])[:, None]
    v = np.linspace(-1.0, 1.0, grid.shape[1])[None, :]
    bump = 2.0 * np.cos(1.5 * math.pi * u) * np.sin(1.5 * math.pi * v)  # a wavy flank
    clean = _cut(pinion, ERRORS)
    ident = identify(pinion, {f: v_ + bump for f, v_ in clean.items()})
    for flank in clean:
        ok = ident.valid[flank]
        assert ident.rms_um(flank) > 0.5 * np.sqrt(np.mean(bump[ok] ** 2))


def test_a_synthesised_tapered_design_is_identified_on_explicit_settings():
    """The ISO 23509 14/39 pair: tapered depth, the gear's settings from the blank and the
    pinion's by local synthesis; the closed loop works on the settings written out."""
    design = gearopt.load_design(STUDIES / "iso23509" / "face_milling_14x39.toml")
    nominal = nominal_measurement(design, "pinion")
    errors = {
        "machine.pinion.convex.radial_setting_mm": 0.02,
        "machine.pinion.concave.sliding_base_mm": -0.02,
    }
    ident = identify(nominal, _cut(nominal, errors))
    for flank in ("convex", "concave"):
        assert ident.rms_um(flank, "measured") > 2.0
        assert ident.rms_um(flank) < 0.1
    for key, error in errors.items():
        assert ident.errors()[key] == pytest.approx(error, rel=1e-2)


# --- identification: the face-hobbing models -----------------------------------------------------


@pytest.mark.parametrize("path", [CYCLO_PALLOID, EPICYCLOID], ids=["cyclo-palloid", "epicycloid"])
def test_face_hobbing_identification(path):
    design = gearopt.load_design(path)
    nominal = nominal_measurement(design, "pinion")
    settings = get_machine_model(design.model).correction_settings(design, "pinion")
    numeric = [s for s in settings if not s.key.endswith("blade_profile_radius_mm")]
    errors = {s.key: 20.0 * s.step for s in numeric[:3]}
    ident = identify(nominal, _cut(nominal, errors), settings=[s.key for s in numeric])
    for flank in ("convex", "concave"):
        assert ident.rms_um(flank, "measured") > 1.0
        assert ident.rms_um(flank) < 0.1
    for key, error in errors.items():
        if key in ident.kept:
            assert ident.errors()[key] == pytest.approx(error, rel=1e-2)


# --- root reach (a corrected gear stays readable) ---------------------------------------------


def test_a_root_cut_above_its_line_is_a_warning_not_an_error(face_milling):
    with warnings.catch_warnings(record=True) as records:
        warnings.simplefilter("always", GearoptWarning)
        design = gearopt.with_overrides(
            face_milling, {"machine.pinion.machine_root_angle_deg": 18.434948823 + 0.017}
        )
    assert design.machine.member("pinion").flank("convex").machine_root_angle_deg > 18.45
    assert any("clearance shrinks" in str(r.message) for r in records)
    with pytest.raises(DesignError, match="no less than the clearance"):
        gearopt.with_overrides(face_milling, {"machine.pinion.sliding_base_mm": 3.0})


# --- the commands --------------------------------------------------------------------------------


def test_grid_and_correct_commands_close_the_loop(tmp_path, capsys, face_milling):
    assert main(["grid", str(FACE_MILLING), "--member", "gear", "--csv"]) == 0
    text = capsys.readouterr().out
    assert text.splitlines()[0] == GRID_HEADER
    rows = list(csv.DictReader(io.StringIO(text)))
    assert len(rows) == 2 * 9 * 5
    assert any(r["x_mm"] == "" for r in rows) or all(r["x_mm"] for r in rows)
    nominal = nominal_measurement(face_milling, "gear")
    errors = {"machine.gear.radial_setting_mm": 0.03, "machine.gear.machine_root_angle_deg": -0.02}
    measured = _cut(nominal, errors)
    lines = [MEASURED_HEADER]
    for r in rows:
        value = measured[r["flank"]][int(r["i_face"]), int(r["i_profile"])]
        if r["x_mm"] and np.isfinite(value):
            lines.append(f"{r['flank']},{r['i_face']},{r['i_profile']},{value:.6f}")
    (tmp_path / "measured.csv").write_text("\n".join(lines) + "\n")
    args = ["correct", str(FACE_MILLING), "--member", "gear"]
    args += ["--measured", str(tmp_path / "measured.csv"), "--json"]
    args += ["--out", str(tmp_path / "cut.toml"), "--corrective-out", str(tmp_path / "next.toml")]
    assert main(args) == 0
    report = json.loads(capsys.readouterr().out)
    for key, error in errors.items():
        assert report["settings"][key]["error"] == pytest.approx(error, rel=1e-3)
    assert all(f["residual_rms_um"] < 0.1 for f in report["flanks"].values())
    # the identified design written out cuts what was measured
    cut = gearopt.load_design(tmp_path / "cut.toml")
    again = nominal.deviations(cut)
    for flank, (dev, ok) in again.items():
        both = ok & np.isfinite(measured[flank])
        assert np.abs(dev[both] - measured[flank][both]).max() < 0.01
    corrective = gearopt.load_design(tmp_path / "next.toml")
    change = corrective.machine.member("gear").flank("convex").radial_setting_mm - 74.674435602
    assert change == pytest.approx(-0.03, abs=2e-3)


@pytest.mark.parametrize(
    ("content", "match"),
    [
        ("flank,i,j,d\n", "must start with the line"),
        (MEASURED_HEADER + "\nconvex,0,0\n", "needs 4 fields"),
        (MEASURED_HEADER + "\nflat,0,0,1.0\n", "flank must be one of"),
        (MEASURED_HEADER + "\nconvex,9,0,1.0\n", "outside the 9x5 grid"),
        (MEASURED_HEADER + "\nconvex,0,0,nan\n", "must be finite"),
        (MEASURED_HEADER + "\nconvex,1,1,1\nconvex,1,1,2\n", "given twice"),
        (MEASURED_HEADER + "\n", "no measured point"),
    ],
)
def test_bad_measurement_files_are_named(tmp_path, capsys, content, match):
    path = tmp_path / "m.csv"
    path.write_text(content)
    code = main(["correct", str(FACE_MILLING), "--member", "gear", "--measured", str(path)])
    assert code == 2
    err = capsys.readouterr().err
    assert match in err and "--measured" in err


def test_unknown_settings_are_named(tmp_path, capsys, pinion):
    with pytest.raises(GearoptError, match="must be among"):
        identify(pinion, _cut(pinion, {}), settings=["machine.pinion.spindle_speed"])


# --- a study against a measured topography -------------------------------------------------------

CLOSED_LOOP = STUDIES / "closed_loop"


def test_topography_evaluator_and_objective_measure_against_the_target(face_milling):
    """The shipped measurement (the conjugate design's gear cut with a radial setting 0.03 mm
    too large and a machine root angle 0.02 deg too small, four decimals): the nominal design
    misses it by its own RMS, the design with those errors by the rounding only."""
    evaluator = gearopt.evaluators()["topography"]
    objective = gearopt.objectives()["topography"]
    conditions = {
        "member": "gear",
        "reference": "face_milling_conjugate.toml",
        "target": "closed_loop/face_milling_gear_measured.csv",
    }
    evaluator.check_conditions(face_milling, conditions)
    assert objective.reads() == {"topography": "topography"}
    nominal = evaluator.evaluate(face_milling, conditions)
    rows = list(csv.DictReader((CLOSED_LOOP / "face_milling_gear_measured.csv").open()))
    given = np.array([float(r["deviation_um"]) for r in rows])
    assert nominal.metrics["topography.rms_um"] == pytest.approx(np.sqrt(np.mean(given**2)))
    cut = gearopt.with_overrides(
        face_milling,
        {
            "machine.gear.radial_setting_mm": 74.704435602,
            "machine.gear.machine_root_angle_deg": 71.545051177,
        },
    )
    found = evaluator.evaluate(cut, conditions)
    assert found.metrics["topography.rms_um"] < 1e-4
    assert objective.value({"topography": found}) == found.metrics["topography.rms_um"]
    with pytest.raises(DesignError, match="no such file"):
        evaluator.check_conditions(face_milling, {**conditions, "target": "missing.csv"})
    with pytest.raises(GearoptError, match="grid"):
        evaluator.check_conditions(face_milling, {**conditions, "grid": "9x5"})


def test_closed_loop_study_file_reads():
    spec = gearopt.load_study_spec(CLOSED_LOOP / "face_milling_gear_study.toml")
    assert [o.name for o in spec.objectives] == ["topography"]
