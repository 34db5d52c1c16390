"""optuna-dashboard on a gearopt study (issue 25 item 3): its API lists every trial's
constraints, and the front its Pareto plot draws holds feasible trials only.

The dashboard's WSGI app (``optuna_dashboard.wsgi``) is driven in-process, no server."""

from __future__ import annotations

import io
import json
import shutil
import subprocess
import sys
import urllib.request
from pathlib import Path
from wsgiref.util import setup_testing_defaults

import optuna
import pytest
import sqlalchemy as sa

from gearopt.dashboard import FeasibleBestTrials, feasible_best

optuna_dashboard = pytest.importorskip("optuna_dashboard")

ROOT = Path(__file__).resolve().parents[1]
STUDIES = ROOT / "studies"
NAME = "cyclo_palloid_contact"
#: two designs of the example study's space that meet both constraints (found by a 240-trial
#: run), given beside the published one that meets the heel's edge (infeasible)
FEASIBLE = (
    {
        "machine.pinion.inner_cutter_radius_mm": 74.11172142395345,
        "machine.pinion.outer_cutter_radius_mm": 75.7696219099353,
        "machine.pinion.additional_slope_angle_deg": -0.07459437909191523,
        "machine.pinion.blade_parabola_coefficient_per_mm": 0.001009994879353521,
    },
    {
        "machine.pinion.inner_cutter_radius_mm": 74.08326982972054,
        "machine.pinion.outer_cutter_radius_mm": 75.83953001570366,
        "machine.pinion.additional_slope_angle_deg": -0.059060273102912314,
        "machine.pinion.blade_parabola_coefficient_per_mm": 0.001022541851619727,
    },
)


def _get(app, path: str):
    """GET ``path`` from a WSGI app in this process; the decoded JSON body."""
    path, _, query = path.partition("?")
    environ: dict = {"PATH_INFO": path, "QUERY_STRING": query, "REQUEST_METHOD": "GET"}
    setup_testing_defaults(environ)
    environ["wsgi.input"] = io.BytesIO(b"")
    status: list[str] = []
    body = b"".join(app(environ, lambda s, headers, exc_info=None: status.append(s)))
    assert status[0].startswith("200"), (path, status, body[:300])
    return json.loads(body)


def _dominates(a: list[float], b: list[float]) -> bool:
    return all(x <= y for x, y in zip(a, b, strict=True)) and a != b


@pytest.fixture(scope="module")
def example_study(tmp_path_factory):
    """A short run of the example study: the published design, two feasible ones, and
    sampled ones."""
    folder = tmp_path_factory.mktemp("dashboard")
    for name in (f"{NAME}.toml", "seed001_section5_3.toml"):
        shutil.copy(STUDIES / name, folder)
    text = (folder / f"{NAME}.toml").read_text()
    for params in FEASIBLE:
        text += "\n[[enqueue]]\n" + "".join(f'"{k}" = {v!r}\n' for k, v in params.items())
    (folder / f"{NAME}.toml").write_text(text)
    run = subprocess.run(
        [sys.executable, "-m", "gearopt.cli", "study", "run", f"{NAME}.toml"]
        + ["--trials", "6", "--jobs", "2", "--json", "--no-progress"],
        cwd=folder,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert run.returncode == 0, run.stderr
    return f"sqlite:///{folder / f'{NAME}.db'}"


@pytest.mark.slow
def test_the_dashboard_lists_every_trials_constraints_and_a_feasible_front(example_study):
    storage = optuna.storages.RDBStorage(example_study)
    app = optuna_dashboard.wsgi(storage)
    (study_summary,) = _get(app, "/api/studies")["study_summaries"]
    detail = _get(app, f"/api/studies/{study_summary['study_id']}")
    trials = detail["trials"]
    assert len(trials) == 6 and all(t["state"] == "Complete" for t in trials)
    # every trial's constraints listed, in the study file's order, as gearopt's table has them
    engine = sa.create_engine(example_study)
    with engine.connect() as con:
        rows = con.execute(
            sa.text(
                "SELECT trial_number, label, value FROM gearopt_objectives"
                " WHERE kind = 'constraint'"
            )
        ).all()
    table = {(n, label): value for n, label, value in rows}
    for t in trials:
        assert t["constraints"] == [
            table[(t["number"], "backlash_window_um")],
            table[(t["number"], "edge_contact")],
        ]
    feasible = [t for t in trials if all(c <= 0 for c in t["constraints"])]
    assert 0 < len(feasible) < len(trials)  # both kinds, or the front tells nothing
    # the samplers see each constraint once
    study = optuna.load_study(study_name=NAME, storage=storage)
    assert all(len(t.constraints) == 2 for t in study.trials)
    # the front the dashboard's Pareto plot draws: the non-dominated ones among the trials
    # its API says are feasible (GraphParetoFront: getFeasibleTrials, then getIsDominated)
    drawn = {
        t["number"]
        for t in feasible
        if not any(_dominates(o["values"], t["values"]) for o in feasible)
    }
    assert drawn == {t.number for t in study.best_trials}  # Optuna's feasible front
    assert all(t["number"] not in drawn for t in trials if t not in feasible)


@pytest.mark.slow
def test_gearopts_dashboard_offers_feasible_best_trials_only(example_study):
    # optuna-dashboard 0.21 computes the API's ``best_trials`` (its "Best Trials" card) as the
    # Pareto front of every COMPLETE trial, constraints aside (_app.py, get_study_detail); the
    # upstream fix would filter the trials by their ``constraints`` first, as its Pareto plot
    # does. The first half says when upstream changes; gearopt's filter around the same app
    # (what ``gearopt dashboard`` serves) answers with the feasible front.
    storage = optuna.storages.RDBStorage(example_study)
    raw = optuna_dashboard.wsgi(storage)
    (study_summary,) = _get(raw, "/api/studies")["study_summaries"]
    path = f"/api/studies/{study_summary['study_id']}"
    detail = _get(raw, path)
    trials = detail["trials"]
    unconstrained = {
        t["number"] for t in trials if not any(_dominates(o["values"], t["values"]) for o in trials)
    }
    assert {t["number"] for t in detail["best_trials"]} == unconstrained

    app = FeasibleBestTrials(raw)
    filtered = _get(app, path)
    study = optuna.load_study(study_name=NAME, storage=storage)
    best = {t["number"] for t in filtered["best_trials"]}
    assert best == {t.number for t in study.best_trials}  # Optuna's feasible front
    assert best != unconstrained  # the example holds an infeasible trial on the raw front
    assert all(all(c <= 0 for c in t["constraints"]) for t in filtered["best_trials"])
    assert filtered["trials"] == trials  # the rest of the answer unchanged
    # a later page of trials: the front still over every trial
    page = _get(app, path + "?after=4")
    assert [t["number"] for t in page["trials"]] == [t["number"] for t in trials[4:]]
    assert {t["number"] for t in page["best_trials"]} == best
    # other endpoints pass through
    assert _get(app, "/api/studies") == _get(raw, "/api/studies")


def test_feasible_best_one_objective_and_maximised():
    trials = [
        {"number": 0, "state": "Complete", "values": [1.0], "constraints": [0.5]},
        {"number": 1, "state": "Complete", "values": [3.0], "constraints": [-1.0]},
        {"number": 2, "state": "Complete", "values": [2.0], "constraints": [0.0]},
        {"number": 3, "state": "Fail", "values": None, "constraints": []},
    ]
    assert [t["number"] for t in feasible_best(trials, ["minimize"])] == [2]
    assert [t["number"] for t in feasible_best(trials, ["maximize"])] == [1]
    assert feasible_best(trials[:1], ["minimize"]) == []


def test_the_dashboard_command_refuses_a_study_never_run(tmp_path):
    shutil.copy(STUDIES / f"{NAME}.toml", tmp_path)
    shutil.copy(STUDIES / "seed001_section5_3.toml", tmp_path)
    run = subprocess.run(
        [sys.executable, "-m", "gearopt.cli", "dashboard", f"{NAME}.toml", "--port", "0"],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert run.returncode == 2
    assert run.stderr.count("\n") == 1 and "run it first" in run.stderr
    assert not list(tmp_path.glob("*.db"))  # nothing created


@pytest.mark.slow
def test_the_dashboard_command_serves_the_filtered_api(example_study, tmp_path):
    folder = Path(example_study.removeprefix("sqlite:///")).parent
    server = subprocess.Popen(
        [sys.executable, "-m", "gearopt.cli", "dashboard", f"{NAME}.toml", "--port", "0"],
        cwd=folder,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        line = server.stdout.readline()
        url = line.split()[3]  # "gearopt dashboard on http://127.0.0.1:PORT/ (...)"
        with urllib.request.urlopen(url + "api/studies", timeout=30) as answer:
            (summary,) = json.load(answer)["study_summaries"]
        with urllib.request.urlopen(url + f"api/studies/{summary['study_id']}") as answer:
            detail = json.load(answer)
    finally:
        server.terminate()
        server.wait(timeout=30)
    study = optuna.load_study(study_name=NAME, storage=example_study)
    assert {t["number"] for t in detail["best_trials"]} == {t.number for t in study.best_trials}
