"""Crash recovery of a study's trials, on Optuna's public API.

A trial in a coordinator's hand is RUNNING in Optuna. When its coordinator is gone the trial is
failed and its parameters are put back in the queue (:class:`Requeue`), at most
:data:`MAX_ATTEMPTS` times in all, under a new trial number:

- another host: Optuna's heartbeat. The coordinators open the storage with
  ``heartbeat_interval`` :data:`HEARTBEAT_S` and ``grace_period`` :data:`STALE_AFTER_S`, record
  a heartbeat (``RDBStorage.record_heartbeat``) for every trial in hand, and call
  :func:`optuna.storages.fail_stale_trials`, whose ``heartbeat_stale_trial_callback`` is
  :class:`Requeue` (Optuna's ``RetryHeartbeatStaleTrialCallback`` with gearopt's attempt count
  and without re-enqueueing a trial that was never given its parameters);
- the same host: at once, without waiting out the grace period, when the process named by the
  trial's ``gearopt_coordinator`` user attribute is dead (:func:`dead_here`);
- a trial asked but killed before it was marked with its coordinator (a moment's window): failed
  when no other coordinator is alive, or when it is older than the grace period.

Every id is found through Optuna's public storage API (``get_study_id_from_name``,
``get_trial_id_from_study_id_trial_number``), never from its objects' private attributes.
"""

from __future__ import annotations

import datetime as dt
import os
import shutil
import socket
import tempfile
import warnings
from pathlib import Path

import optuna
from optuna.trial import TrialState

from gearopt.results import ResultsStore
from gearopt.studyfile import StudySpec

__all__ = [
    "ATTEMPT",
    "COORDINATOR",
    "HEARTBEAT_S",
    "MARKERS_PREFIX",
    "MAX_ATTEMPTS",
    "STALE_AFTER_S",
    "Requeue",
    "alive",
    "coordinator_tag",
    "fail_and_requeue",
    "recover",
    "running_trials",
    "trial_markers",
    "trial_params",
]

#: seconds between two heartbeats of a coordinator's trials (Optuna's ``heartbeat_interval``)
HEARTBEAT_S = 5
#: a trial whose heartbeat is older than this is stale (Optuna's ``grace_period``)
STALE_AFTER_S = 120
#: attempts of one design: the first and two re-enqueued ones
MAX_ATTEMPTS = 3
#: user attributes: the trial's coordinator (``host:pid:id``) and its design's attempt
COORDINATOR = "gearopt_coordinator"
ATTEMPT = "gearopt_attempt"
#: the prefix of the coordinators' temporary folders (a worker's pid marker per trial)
MARKERS_PREFIX = "gearopt-trials-"


def coordinator_tag(host: str, pid: int, me: str) -> str:
    """The ``gearopt_coordinator`` user attribute of a coordinator's trials."""
    return f"{host}:{pid}:{me}"


def alive(pid: int) -> bool:
    """Whether process ``pid`` runs (a zombie, killed but not yet reaped, does not)."""
    if Path("/proc/self").exists():
        try:
            text = Path(f"/proc/{pid}/status").read_text()
        except OSError:
            return False
        return "\nState:\tZ" not in text and "\nState:\tX" not in text
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def trial_markers(pid: int) -> str:
    """A new temporary folder for the trials' markers, its owner's pid in ``owner``; first
    the folders of coordinators of this host that are gone (killed: nothing removed them)."""
    root = Path(tempfile.gettempdir())
    for folder in root.glob(MARKERS_PREFIX + "*"):
        try:
            owner = int((folder / "owner").read_text())
        except (OSError, ValueError):  # no owner file (yet): not ours to judge
            continue
        if not alive(owner):
            shutil.rmtree(folder, ignore_errors=True)
    markers = tempfile.mkdtemp(prefix=MARKERS_PREFIX)
    Path(markers, "owner").write_text(str(pid))
    return markers


def trial_params(trial: optuna.trial.FrozenTrial, spec: StudySpec) -> dict:
    """The trial's parameters (a given design's, or those suggested), or {} when a coordinator
    died before suggesting them all: such a trial never reached a worker."""
    params = {**trial.system_attrs.get("fixed_params", {}), **trial.params}
    return params if set(params) >= set(spec.dimensions) else {}


class Requeue:
    """Put a failed trial's design back in the queue, charging it an attempt unless ``charge``
    is False, when attempts remain and it had its parameters: the heartbeat-stale trial
    callback of the coordinators' storage, and what a coordinator calls for the trials it
    fails itself. The new trial carries ``gearopt_attempt`` and ``gearopt_retry_of``."""

    def __init__(
        self, spec: StudySpec, results: ResultsStore | None = None, *, charge: bool = True
    ) -> None:
        self.spec, self.charge = spec, charge
        #: set once the storage it is the callback of is open (the tables share its engine)
        self.results = results

    def __call__(self, study: optuna.Study, trial: optuna.trial.FrozenTrial) -> None:
        if self.results is not None:
            self.results.forget(self.spec.name, [trial.number])
        attempt = int(trial.user_attrs.get(ATTEMPT, 1)) + int(self.charge)
        params = trial_params(trial, self.spec)
        if params and attempt <= MAX_ATTEMPTS:
            attrs = {ATTEMPT: attempt, "gearopt_retry_of": trial.number}
            study.enqueue_trial(params, user_attrs=attrs)


def running_trials(study: optuna.Study, storage: optuna.storages.BaseStorage) -> list:
    """The study's RUNNING trials, read from ``storage`` (the RDB storage itself): only they
    are read, where the study's cached storage would first read every trial finished since
    its last look (a supervisor's heartbeat every few seconds read the whole run that way)."""
    study_id = storage.get_study_id_from_name(study.study_name)
    return storage.get_all_trials(study_id, deepcopy=False, states=(TrialState.RUNNING,))


def fail_and_requeue(
    study: optuna.Study,
    storage: optuna.storages.BaseStorage,
    requeue: Requeue,
    trial: optuna.trial.FrozenTrial,
    reason: str,
) -> bool:
    """Fail ``trial`` (``gearopt_error``: ``reason``) and :class:`Requeue` it; False when
    another coordinator finished it first."""
    try:
        study_id = storage.get_study_id_from_name(study.study_name)
        trial_id = storage.get_trial_id_from_study_id_trial_number(study_id, trial.number)
        storage.set_trial_user_attr(trial_id, "gearopt_error", reason[:500])
        study.tell(trial.number, state=TrialState.FAIL)
    except (RuntimeError, ValueError):  # finished meanwhile (UpdateFinishedTrialError is one)
        return False
    requeue(study, trial)
    return True


def dead_here(owner: str | None) -> bool:
    """Whether a trial's coordinator (``host:pid:id``) ran on this host and is gone."""
    host, _, rest = (owner or "").partition(":")
    pid = rest.partition(":")[0]
    return host == socket.gethostname() and pid.isdigit() and not alive(int(pid))


def recover(
    study: optuna.Study,
    storage: optuna.storages.BaseStorage,
    results: ResultsStore,
    spec: StudySpec,
    me: str,
    skip: frozenset[str] | set[str] = frozenset(),
    *,
    starting: bool = False,
    running: list | None = None,
) -> list[int]:
    """Fail and re-enqueue the RUNNING trials whose coordinator is gone (Optuna's stale-trial
    handling, then this host's dead coordinators, then trials without a coordinator); the
    numbers of the trials failed here (the stale ones are Optuna's, its callback requeues).
    ``me``: the caller's tag (:func:`coordinator_tag`). ``skip``: the coordinator tags whose
    trials the caller sees to itself (a supervisor's workers: it fails a dead worker's trial as
    the worker's death, not a coordinator's). ``starting``: the caller holds no trial yet (a
    run's start, before its workers), so its own heartbeat does not stand for a trial asked a
    moment ago and not yet marked: with no other coordinator alive, such a trial is failed now,
    not after the grace period. ``running``: the RUNNING trials (:func:`running_trials`) when
    the caller has just read them."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", optuna.exceptions.ExperimentalWarning)
        optuna.storages.fail_stale_trials(study)
    now = dt.datetime.now(dt.UTC).replace(tzinfo=None)
    # the caller's row (its id) counts as alive while it runs, deliberately: a trial of no
    # coordinator may be one its workers asked a moment ago and mark next (left to the grace
    # period); at its start it holds none, so its own heartbeat stands for nobody's trial
    own = me.rpartition(":")[2] if starting else None
    living = {
        c
        for c, (o_host, o_pid, beat) in results.coordinators().items()
        if c not in (me, own)
        and (now - beat).total_seconds() < STALE_AFTER_S
        and (o_host != socket.gethostname() or alive(o_pid))
    }
    requeue = Requeue(spec, results)
    done = []
    for trial in running_trials(study, storage) if running is None else running:
        owner = trial.user_attrs.get(COORDINATOR)
        if owner in skip:
            continue
        if owner is not None and ":" not in owner:  # an earlier gearopt's: its table heartbeat
            if owner == me or owner in living:
                continue
            reason = f"coordinator {owner} died"
        elif owner is not None:
            if not dead_here(owner):
                continue  # alive, or on another host: its heartbeat says when it is stale
            reason = f"coordinator {owner} died"
        else:
            age = (now - trial.datetime_start).total_seconds()
            if living and age < STALE_AFTER_S:
                continue  # asked a moment ago by a live coordinator, not yet marked as its own
            reason = "its coordinator died before marking it"
        if fail_and_requeue(study, storage, requeue, trial, reason):
            done.append(trial.number)
    return done
