"""Supervised workers (:mod:`gearopt.study_workers`): one worker repeats its parameters as
the deterministic batches do; a killed run's trials that were asked but not yet marked with
their coordinator (a kill in that moment's window) are failed when the next run starts, with
no other coordinator alive, rather than after the grace period (the run's own heartbeat made
them look like a live coordinator's: a supervisor with no worker left waited without end)."""

from __future__ import annotations

import optuna
import pytest
from optuna.trial import TrialState

from .test_study import _gearopt, _states, _toy_study, _trials


@pytest.mark.parametrize("jobs", [1, 2])
def test_a_trial_asked_by_a_killed_run_and_never_marked_is_failed_when_the_next_starts(
    tmp_path, toy_site, jobs
):
    study = _toy_study(tmp_path)
    db = tmp_path / "toy_probe.db"
    args = ["study", "run", study, "--trials", 2, "--jobs", jobs, "--no-progress"]
    _gearopt(args, toy_site)
    # what a run killed between Optuna's ask and the coordinator's mark leaves behind
    unmarked = optuna.load_study(study_name="toy_probe", storage=f"sqlite:///{db}").ask()
    # the next run, with places for every trial but the one left RUNNING: it must free it
    # (within the test's timeout, far below the 120 s grace period of another host's trial)
    _gearopt([*args[:3], "--trials", 3, *args[5:]], toy_site, timeout_s=90)
    trials = {t.number: t for t in _trials(db)}
    assert trials[unmarked.number].state == TrialState.FAIL
    assert "before marking" in trials[unmarked.number].user_attrs["gearopt_error"]
    assert _states(trials.values()) == {"COMPLETE": 3, "FAIL": 1}


def test_one_worker_repeats_the_parameters_of_the_deterministic_batches(tmp_path, toy_site):
    sequences = []
    for run, flags in enumerate((["--deterministic"], [])):
        folder = tmp_path / f"run{run}"
        folder.mkdir()
        study = _toy_study(folder)
        _gearopt(
            ["study", "run", study, "--trials", 12, "--jobs", 1, "--no-progress", *flags], toy_site
        )
        trials = sorted(_trials(folder / "toy_probe.db"), key=lambda t: t.number)
        sequences.append([t.params["machine.tool_tip_width_mm"] for t in trials])
    # past the sampler's 10 random start-up trials: TPE's own suggestions too
    assert sequences[0] == sequences[1] and len(set(sequences[0])) == 12


@pytest.mark.parametrize("flags", [["--jobs", 1], ["--jobs", 2], ["--jobs", 1, "--deterministic"]])
def test_a_continued_study_draws_designs_its_first_run_did_not(tmp_path, toy_site, flags):
    # the random sampler repeats its whole sequence from one seed: a continued run seeded as
    # the first one drew the first run's designs again (each worker's seed was the study's
    # plus its number); the trials the study holds now mix into the seed
    study = _toy_study(tmp_path, sampler="random")
    args = ["study", "run", study, "--no-progress", *flags]
    _gearopt([*args, "--trials", 4], toy_site)
    first = {t.params["machine.tool_tip_width_mm"] for t in _trials(tmp_path / "toy_probe.db")}
    _gearopt([*args, "--trials", 8], toy_site)
    trials = _trials(tmp_path / "toy_probe.db")
    later = [t.params["machine.tool_tip_width_mm"] for t in trials if t.number >= 4]
    assert len(first) == 4 and len(later) == 4
    assert not first & set(later)
