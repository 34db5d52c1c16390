"""Designed fourth-order TE (issue 10): the target, the inverse TCA, the five seed 002 cases
closed through the forward contact engine, the objective and the study over the roll terms."""

from __future__ import annotations

import importlib.util
import json
import math
import tomllib

import numpy as np
import pytest

import gearopt
from gearopt.analysis import AnalysisOptions, contact_sides, meshed_pair
from gearopt.design_files import parse_design
from gearopt.errors import DesignError
from gearopt.newton_tca import newton_tca
from gearopt.te_target import ARCSEC, TETarget, compare

from .conftest import SEED_CASES, STUDIES

CASES = STUDIES / "fourth_order_te"
REFERENCE = json.loads(SEED_CASES.read_text())
SEED = REFERENCE["fourth_order_te_seed002"]


def _make_cases():
    spec = importlib.util.spec_from_file_location("make_cases", CASES / "make_cases.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


# --- the target --------------------------------------------------------------------------------


@pytest.mark.parametrize("case", SEED["table2_cases"], ids=lambda c: f"case{c['case']}")
def test_table2_coefficients_read_as_quadratic_and_quartic_give_the_pitch_point_te(case):
    """seed_cases.json's caveat: Table 2's a is the quadratic, b the quartic coefficient; then
    the pitch-point TE at x_T = pi / 23 is the published one within 3 %."""
    target = TETarget(quadratic=case["a"], quartic=case["b"], contact_ratio=2.3, pinion_teeth=23)
    assert target.pitch_point_te_arcsec == pytest.approx(case["pitch_point_te_arcsec"], rel=0.03)


def test_boundary_conditions_give_the_coefficients():
    target = TETarget.from_table(
        {"pitch_point_te_arcsec": -6.156, "mesh_in_te_arcsec": -80.0, "contact_ratio": 2.3}, 23
    )
    x_t, x_in = math.pi / 23, 2.3 * math.pi / 23
    assert target.te_arcsec(x_t) == pytest.approx(-6.156, abs=1e-9)
    assert target.te_arcsec(-x_in) == pytest.approx(-80.0, abs=1e-9)
    assert target.quartic < 0.0 < -target.quadratic  # a flat middle: the quartic carries it
    parabola = TETarget.from_table({"quadratic": -0.0039, "contact_ratio": 2.3}, 23)
    assert parabola.quartic == 0.0
    # the envelope repeats every pitch, 0 at the reference, the pitch-point TE at hand-over
    x = np.linspace(-0.5, 0.5, 1001)
    env = target.envelope_arcsec(x)
    assert env.max() == pytest.approx(0.0, abs=1e-6)
    assert env.min() >= -6.156 - 1e-9
    assert target.envelope_arcsec(3 * x_t) == pytest.approx(-6.156, abs=1e-9)
    assert target.envelope_arcsec(2 * x_t) == pytest.approx(0.0, abs=1e-12)


@pytest.mark.parametrize(
    ("table", "key"),
    [
        ({"quadratic": 0.001, "contact_ratio": 2.3}, "te_target.quadratic"),
        ({"quadratic": -0.001, "pitch_point_te_arcsec": -5, "contact_ratio": 2.3}, "te_target"),
        ({"pitch_point_te_arcsec": -5.0, "contact_ratio": 2.3}, "te_target.mesh_in_te_arcsec"),
        ({"quadratic": -0.001, "contact_ratio": 0.9}, "te_target.contact_ratio"),
        (
            {"pitch_point_te_arcsec": -50.0, "mesh_in_te_arcsec": -20.0, "contact_ratio": 2.3},
            "te_target",
        ),
        ({"quadratic": -0.001, "contact_ratio": 2.3, "level": 3}, "te_target"),
    ],
)
def test_bad_targets_are_named(table, key):
    with pytest.raises(DesignError, match=key):
        TETarget.from_table(table, 23)


# --- the five cases ----------------------------------------------------------------------------


def _pair_curve(design):
    """One pair's TE over its whole contact, by the textbook forward TCA (Litvin's tangency
    equations, Newton with continuation, :func:`gearopt.newton_tca.newton_tca`) on the
    generated FlankMaps, from the engine's TE maximum outward in steps of 0.0005 rad until the
    contact leaves a flank: ``(tca, contact ratio, entry TE, exit TE, pitch-point TE either
    side of the maximum)``. (The engine's own edge flags are coarser at the flank boundaries:
    at 61 x 41 they end case 1's contact 0.09 pitch early.)"""
    opts = AnalysisOptions.from_conditions({}, design=design)
    pair = meshed_pair(design, opts)
    tca = contact_sides(pair, opts)["drive"]
    pitch = 2.0 * math.pi / design.pair.pinion_teeth
    centre = math.radians(tca.handover_phi1_deg[0]) + 0.5 * pitch
    sides = []
    for way in (1.0, -1.0):
        u = centre + way * np.arange(0.0, 0.45, 0.0005)
        result = newton_tca(pair.drive, u)
        inside = int(np.argmin(result.converged)) if not result.converged.all() else len(u)
        assert inside > 100, "the contact must run on from the maximum"
        sides.append((u[:inside] - centre, result.lag_rad[:inside]))
    lag0 = sides[0][1][0]
    te = [(lag0 - lag) * ARCSEC for _, lag in sides]
    ratio = (sides[0][0][-1] - sides[1][0][-1]) / pitch
    pitch_te = [np.interp(0.5 * pitch, abs(x), t) for (x, _), t in zip(sides, te, strict=True)]
    return tca, ratio, te[1][-1], te[0][-1], np.array(pitch_te)


@pytest.fixture(scope="module")
def cases():
    out = {}
    for n in range(1, 6):
        design = gearopt.load_design(CASES / f"case{n}.toml")
        out[n] = (design, *_pair_curve(design))
    return out


@pytest.mark.parametrize("n", range(1, 6))
def test_forward_tca_reproduces_the_designed_te(cases, n):
    """The pinion generated with the fitted roll, meshed with the unchanged gear by the
    forward contact engine: TE within 0.1 arcsec of the target at every position of the mesh
    cycle (aligned at the maximum), drive side."""
    design, tca = cases[n][0], cases[n][1]
    versus = compare(design.te_target, tca.phi1_deg, tca.te_arcsec, tca.handover_phi1_deg)
    assert versus["te_target_max_deviation_arcsec"] < 0.1
    assert not tca.edge_contact


def test_cases_share_contact_ratio_and_entry_exit_te(cases):
    """Per-pair curves of the forward TCA: the five cases share the contact ratio within 2 %
    and the entry/exit TE within 5 %; each pitch-point TE follows its target within 0.2
    arcsec."""
    ratios = np.array([cases[n][2] for n in cases])
    ends = np.array([[cases[n][3], cases[n][4]] for n in cases])
    assert np.all(np.abs(ratios / ratios.mean() - 1.0) < 0.02), ratios
    assert np.all(np.abs(ends / ends.mean() - 1.0) < 0.05), ends
    for n in cases:
        design, pitch_te = cases[n][0], cases[n][5]
        assert np.all(np.abs(pitch_te - design.te_target.pitch_point_te_arcsec) < 0.2), n


def test_roll_terms_follow_the_target(cases):
    """Across the cases the change of c2 is proportional to the change of the quadratic
    coefficient and the change of c4 to that of the quartic one (within 5 %), measured from
    case 3 (the parabola)."""
    targets = {n: cases[n][0].te_target for n in cases}
    roll = {n: cases[n][0].machine.pinion.convex.roll for n in cases}
    k2 = [
        (roll[n][1] - roll[3][1]) / (targets[n].quadratic - targets[3].quadratic)
        for n in (1, 2, 4, 5)
    ]
    k4 = [
        (roll[n][3] - roll[3][3]) / (targets[n].quartic - targets[3].quartic) for n in (1, 2, 4, 5)
    ]
    for ks in (k2, k4):
        ks = np.array(ks)
        assert np.all(np.abs(ks / ks.mean() - 1.0) < 0.05), ks


def test_case_files_are_what_the_inverse_tca_gives():
    """make_cases.py reproduces the committed case 5 (its fitted roll and cradle angle), and
    the fixed point of the fit converged in more than one iteration."""
    data, report = _make_cases().case_design(5)
    committed = tomllib.loads((CASES / "case5.toml").read_text())
    got, want = data["machine"]["pinion"]["convex"], committed["machine"]["pinion"]["convex"]
    for key in ("ratio_of_roll", "roll_c2", "roll_c3", "roll_c4", "cradle_angle_deg"):
        assert got[key] == pytest.approx(want[key], rel=1e-7, abs=1e-12), key
    assert report["iterations"] > 1
    assert report["fit_residual_arcsec"] < 0.01


# --- the objective and the study ---------------------------------------------------------------


def test_te_target_objective_and_evaluator_metrics():
    from gearopt.plugins import evaluators, objectives

    design = gearopt.load_design(CASES / "case3.toml")
    evaluation = evaluators()["tca"].evaluate(design, {"grid": [31, 21]})
    assert evaluation.metrics["tca.te_target_max_deviation_arcsec"] < 0.1
    report = evaluation.report["tca"]
    assert len(report["te_target_arcsec"]) == len(report["te_arcsec"])
    objective = objectives()["te_target"]
    assert (
        objective.value({"tca": evaluation})
        == evaluation.metrics["tca.te_target_rms_deviation_arcsec"]
    )
    # a design without [te_target] cannot be compared
    plain = parse_design({k: v for k, v in design.source.items() if k != "te_target"})
    bare = evaluators()["tca"].evaluate(plain, {"grid": [31, 21]})
    with pytest.raises(gearopt.errors.StudyError, match="te_target"):
        objective.value({"tca": bare})


def test_roll_study_is_bounded_at_three_times_the_answer_without_its_sign():
    study = tomllib.loads((CASES / "roll_study.toml").read_text())
    design = tomllib.loads((CASES / study["study"]["design"]).read_text())
    fitted = design["machine"]["pinion"]["convex"]
    for key, (low, high) in study["search"].items():
        value = fitted[key.rsplit(".", 1)[1]]
        assert low == pytest.approx(-high)
        assert high == pytest.approx(3.0 * abs(value), rel=1e-3)
    assert study["objectives"][0]["name"] == "te_target"


def test_realise_te_cli_writes_a_design_that_parses(tmp_path, capsys):
    from gearopt.cli import main

    out = tmp_path / "case.toml"
    assert main(["realise-te", str(CASES / "base.toml"), "--out", str(out), "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    design = gearopt.load_design(out)
    assert design.machine.pinion.convex.roll_c4 == pytest.approx(report["after"]["roll_c4"])
    assert design.te_target is not None and not design.machine.synthesis
