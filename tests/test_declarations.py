"""What evaluators and objectives declare, and where it goes (issue 21 item 1, issue 25 item 4).

A third-party evaluator (tests/toy_evaluator, pip-installed into a folder of its own) declares
a metric, a curve and a pattern; they reach ``gearopt plugins --json``, ``gearopt analyze
--json`` and ``--plot``, and a study's ``gearopt_metrics``, ``gearopt_curves`` and
``gearopt_patterns`` tables as the built-ins' do. The built-ins' metrics are named by their
places in ``gearopt analyze --json``: a test reads each back from the JSON.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import tomllib
from pathlib import Path

import numpy as np
import pytest
import sqlalchemy as sa

import gearopt
from gearopt.declarations import Option, OptionError, check_options, declared
from gearopt.errors import GearoptError, StudyError
from gearopt.json_schemas import json_schema
from gearopt.studyfile import parse_study_spec

from .conftest import STUDIES
from .test_json_schemas import validate

HERE = Path(__file__).parent
TOY_EVALUATOR = HERE / "toy_evaluator"
#: a small analysis: enough positions to bracket the hand-overs, a coarse grid (fast)
SMALL = ["--grid", "13,9", "--positions", "9"]


@pytest.fixture(scope="session")
def toy_evaluator_site(tmp_path_factory):
    """The toy third-party evaluator, pip-installed into a folder of its own."""
    target = tmp_path_factory.mktemp("toy_evaluator_site")
    subprocess.run(
        [sys.executable, "-m", "pip", "install", "--quiet", "--no-deps"]
        + ["--no-build-isolation", "--target", str(target), str(TOY_EVALUATOR)],
        check=True,
        capture_output=True,
    )
    return target


def _gearopt(args, site, **kw) -> subprocess.CompletedProcess:
    env = {**os.environ, "PYTHONPATH": str(site), "OMP_NUM_THREADS": "1"}
    run = subprocess.run(
        [sys.executable, "-m", "gearopt.cli", *map(str, args)],
        env=env,
        capture_output=True,
        text=True,
        timeout=500,
        **kw,
    )
    assert run.returncode == 0, f"gearopt {args}:\n{run.stdout}\n{run.stderr}"
    return run


def _schema_at(schema, dotted: str) -> dict:
    """The part of the analyze schema that describes a metric's dotted place."""
    node = schema
    for part in dotted.split("."):
        while "$ref" in node:
            node = schema["$defs"][node["$ref"].rsplit("/", 1)[1]]
        node = node["items"] if part.isdigit() else node["properties"][part]
    return node


def _at(document, dotted: str):
    """The value at a metric's dotted place in a JSON document."""
    value = document
    for part in dotted.split("."):
        value = value[int(part)] if isinstance(value, list) else value[part]
    return value


# --- options -------------------------------------------------------------------------------


def test_an_option_names_itself_its_value_and_its_rule():
    declared_options = (
        Option(name="positions", default=21, kind="integer", lower=3, upper=401),
        Option(name="side", default="drive", kind="string", choices=("drive", "coast")),
        Option(name="limit_mpa", kind="number", lower=0.0, required=True),
        Option(name="*_gears", kind="numbers", lower=1),
    )
    given = {"limit_mpa": 1500.0, "indexing_gears": [48, 45, 60, 60]}
    checked = check_options(declared_options, given, "conditions")
    assert checked == {**given, "positions": 21, "side": "drive"}
    with pytest.raises(OptionError) as info:
        check_options(declared_options, {**given, "positions": 2}, "conditions")
    assert (info.value.parameter, info.value.value) == ("conditions.positions", 2)
    assert info.value.rule == "must be an integer in [3, 401]"
    with pytest.raises(OptionError, match=r"conditions.side = 'left': must be one of"):
        check_options(declared_options, {**given, "side": "left"}, "conditions")
    with pytest.raises(OptionError, match="limit_mpa: is required"):
        check_options(declared_options, {}, "conditions")
    with pytest.raises(OptionError, match="positionz.*is not an option"):
        check_options(declared_options, {**given, "positionz": 21}, "conditions")
    with pytest.raises(OptionError, match="indexing_gears"):
        check_options(declared_options, {**given, "indexing_gears": [0, 45]}, "conditions")
    assert issubclass(OptionError, GearoptError)


def test_a_study_file_with_a_bad_option_fails_before_any_trial():
    text = (STUDIES / "cyclo_palloid_contact.toml").read_text()
    for old, new, parameter in [
        ("[evaluations.tca]", "[evaluations.tca]\nconditions = {cycles = 9.0}", "cycles"),
        ('side = "both"', 'side = "left"', "side"),
        ("min_um = ", "min_uum = 1.0\nmin_um = ", "min_uum"),
    ]:
        assert old in text
        with pytest.raises(StudyError, match=parameter) as info:
            data = tomllib.loads(text.replace(old, new, 1))
            parse_study_spec(data, path=STUDIES / "cyclo_palloid_contact.toml")
        assert parameter in str(info.value), info.value


def test_every_option_default_passes_its_own_rule():
    for plugin in [*gearopt.evaluators().values(), *gearopt.objectives().values()]:
        for option in plugin.options or ():
            assert isinstance(option, Option), (plugin, option)
            if option.default is not None and "*" not in option.name:
                option.check(option.default, plugin.name)


# --- one vocabulary: the metrics are the places in analyze --json ---------------------------


def test_the_metrics_are_the_places_of_the_analyze_json(capsys):
    from gearopt.cli import main

    design_path = STUDIES / "seed001_section5_3.toml"
    assert main(["analyze", str(design_path), "--json", *SMALL]) == 0
    document = json.loads(capsys.readouterr().out)
    validate(document, "analyze")
    schema = json_schema("analyze")
    design = gearopt.load_design(design_path)
    conditions = {"grid": [13, 9], "positions": 9}
    registry = gearopt.evaluators()
    seen = set()
    for name in ("tca", "backlash", "ease-off"):
        evaluator = registry[name]
        evaluation = evaluator.evaluate(design, conditions)
        for metric, value in evaluation.metrics.items():
            assert declared(evaluator, metric) is not None, metric
            # the same numbers, read back from the JSON (booleans as 0/1)
            assert float(_at(document, metric)) == pytest.approx(value, rel=1e-12, abs=1e-12)
            # and the schema describes that place (a number, or 0/1 as a boolean)
            assert _schema_at(schema, metric)["type"] in ("number", "integer", "boolean")
            seen.add(metric)
    # issue 25: every figure analyze reports is a metric, the coast side under tca_coast
    for metric in (
        "tca.pattern.path_angle_deg",
        "tca.pattern.ellipse_major_axis_mm",
        "tca_coast.te_peak_to_peak_arcsec",
        "tca_coast.pattern.center_offset_mm.1",
        "backlash.min_um",
        "ease_off.coast.max_um",
    ):
        assert metric in seen, metric
    for section in ("tca", "tca_coast"):
        numbers = [k for k, v in document[section].items() if isinstance(v, int | float)]
        numbers += [f"pattern.{k}" for k, v in document[section]["pattern"].items()]
        for key in numbers:
            if not isinstance(_at(document[section], key), str):
                assert f"{section}.{key}" in seen or key.endswith("_mm"), key


# --- a third-party evaluator's declarations travel like the built-ins' ----------------------


def test_a_third_party_evaluator_is_listed_with_its_declarations(toy_evaluator_site):
    out = _gearopt(["plugins", "--json"], toy_evaluator_site)
    entries = {(p["kind"], p["name"]): p for p in json.loads(out.stdout)}
    toy = entries[("evaluator", "toy-depth")]
    assert toy["distribution"] == "gearopt-toy-evaluator"
    assert {m["name"] for m in toy["metrics"]} == {
        "toy_depth.depth_taper_mm",
        "toy_depth.box_area_mm2",
        "toy_depth_coast.box_area_mm2",
    }
    assert [(c["name"], c["x"], c["y"]) for c in toy["curves"]] == [
        ("whole_depth", "cone_distance_mm", "whole_depth_mm")
    ]
    assert toy["pattern"]["sides"] == ["drive", "coast"]
    assert [o["name"] for o in toy["options"]] == ["margin"]
    assert [o["name"] for o in entries[("objective", "toy-box-area")]["options"]] == ["on"]
    # the built-ins declare theirs the same way
    tca = entries[("evaluator", "tca")]
    assert "tca_coast.te_peak_to_peak_arcsec" in {m["name"] for m in tca["metrics"]}
    text = _gearopt(["plugins", "--options"], toy_evaluator_site).stdout
    assert "margin" in text and "an integer in [3, 401]" in text


def test_a_third_party_evaluator_reaches_analyze_json_and_plot(toy_evaluator_site, tmp_path):
    design = STUDIES / "seed001_section5_3.toml"
    out = _gearopt(
        ["analyze", design, "--json", "--plot", tmp_path / "plots", *SMALL], toy_evaluator_site
    )
    document = json.loads(out.stdout)
    validate(document, "analyze")
    blank = gearopt.load_design(design).blank
    area = document["toy_depth"]["box_area_mm2"]
    face = blank.outer_cone_distance_mm - blank.inner_cone_distance_mm
    depth = blank.mean_addendum_mm[0] + blank.mean_dedendum_mm[0]
    assert area == pytest.approx(0.25 * face * depth, rel=1e-12)  # margin 0.25 a side
    assert document["toy_depth_coast"]["box_area_mm2"] == area
    assert {"tca", "tca_coast", "backlash", "ease_off"} <= set(document)  # as before
    figure = tmp_path / "plots" / "toy-depth.png"
    assert str(figure) in document["plots"]
    assert figure.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and figure.stat().st_size > 10_000
    assert (tmp_path / "plots" / "te.png").exists()
    text = _gearopt(["analyze", design, *SMALL], toy_evaluator_site).stdout
    assert "toy-depth: toy" in text and "box_area_mm2" in text


TOY_DEPTH_STUDY = """
[study]
name = "toy_depth"
design = "seed001_section5_3.toml"
sampler = "random"
seed = 3

[search]
"machine.pinion.inner_cutter_radius_mm" = [74.0, 76.0]

[evaluations.depth]
evaluator = "toy-depth"
conditions = {margin = 0.1}

[[objectives]]
name = "toy-box-area"
on = "depth"
"""


def test_a_third_party_evaluator_reaches_the_study_tables(toy_evaluator_site, tmp_path):
    shutil.copy(STUDIES / "seed001_section5_3.toml", tmp_path)
    study = tmp_path / "toy_depth.toml"
    study.write_text(TOY_DEPTH_STUDY)
    out = _gearopt(
        ["study", "run", study, "--trials", "2", "--no-progress", "--json"], toy_evaluator_site
    )
    summary = json.loads(out.stdout)
    validate(summary, "study-run")
    assert summary["complete"] == 2 and summary["best"]["values"]["toy-box-area"] < 0
    engine = sa.create_engine(f"sqlite:///{tmp_path / 'toy_depth.db'}")
    with engine.connect() as con:
        metrics = con.execute(
            sa.text("SELECT metric, value FROM gearopt_trial_metrics WHERE evaluation = 'depth'")
        ).all()
        curves = con.execute(
            sa.text(
                "SELECT trial_number, curve, side, idx, x, y FROM gearopt_curves"
                " WHERE evaluation = 'depth' ORDER BY trial_number, side, idx"
            )
        ).all()
        patterns = con.execute(
            sa.text(
                "SELECT trial_number, side, idx, face_mm, profile_mm FROM gearopt_patterns"
                " WHERE evaluation = 'depth' ORDER BY trial_number, side, idx"
            )
        ).all()
    assert len(metrics) == 2 * 3
    assert {m for m, _ in metrics} == {
        "toy_depth.depth_taper_mm",
        "toy_depth.box_area_mm2",
        "toy_depth_coast.box_area_mm2",
    }
    blank = gearopt.load_design(STUDIES / "seed001_section5_3.toml").blank
    face = blank.outer_cone_distance_mm - blank.inner_cone_distance_mm
    depth = blank.mean_addendum_mm[0] + blank.mean_dedendum_mm[0]
    for name, value in metrics:
        if name.endswith("box_area_mm2"):
            assert value == pytest.approx(0.8 * face * 0.8 * depth, rel=1e-12)  # margin 0.1
    assert {(c[1], c[2]) for c in curves} == {("whole_depth", "drive"), ("whole_depth", "coast")}
    x = np.array([c[4] for c in curves if c[0] == 0 and c[2] == "drive"])
    assert x[0] == pytest.approx(blank.inner_cone_distance_mm)
    assert x[-1] == pytest.approx(blank.outer_cone_distance_mm)
    assert len(patterns) == 2 * 2 * 4  # two trials, two sides, a box of four corners
    box = np.array([(p[3], p[4]) for p in patterns if p[0] == 0 and p[1] == "drive"])
    np.testing.assert_allclose(np.ptp(box, axis=0), [0.8 * face, 0.8 * depth], rtol=1e-12)


def test_report_metrics_read_the_declared_places():
    # the declared places as the report holds them, read anew when the declarations change
    from gearopt.declarations import Metric, report_metrics

    class Toy:
        section = "toy"
        sections = {"drive": "toy", "coast": "toy_coast"}
        metrics = (
            Metric(name="a.1"),
            Metric(name="flag"),
            Metric(name="side_mm", per_side=True),
            Metric(name="absent.0"),
            Metric(name="a.7"),
        )

    toy = Toy()
    report = {
        "toy": {"a": [0.5, 2], "flag": True, "side_mm": np.float64(1.25)},
        "toy_coast": {"side_mm": float("inf")},
    }
    expected = {"toy.a.1": 2.0, "toy.flag": 1.0, "toy.side_mm": 1.25}
    assert report_metrics(toy, report) == expected
    assert report_metrics(toy, report) == expected
    toy.sections = {"drive": "toy_coast", "coast": "toy"}
    assert report_metrics(toy, report) == {"toy.a.1": 2.0, "toy.flag": 1.0, "toy.side_mm": 1.25}
    toy.metrics = (*Toy.metrics, Metric(name="a.0"))
    assert report_metrics(toy, report)["toy.a.0"] == 0.5
    toy.section = "toy_coast"
    assert report_metrics(toy, report) == {"toy.side_mm": 1.25}
