"""The study coordinator: Optuna ask/tell over a pool of worker processes.

A coordinator asks trials, sends the pure evaluations (:func:`gearopt.trial.work`) to its
workers, writes the gearopt tables (:mod:`gearopt.results`) and tells Optuna, in that order.
With ``deterministic`` or Dask the workers are a joblib pool (loky, Dask) and never touch
the database. Otherwise (loky) each of the ``jobs`` worker processes (one or several) is a
coordinator of its own that evaluates its trials itself, and this process supervises them
(:mod:`gearopt.study_workers`: Optuna's own multi-process pattern, so the sampler's and the
storage's cost per trial is paid side by side rather than by one process).
:class:`Coordinator` holds a run's state; :func:`run_study` runs one. Only Optuna's public API
is used, never its private attributes or its tables through SQL.

Counting: a run ends when the study holds ``trials`` COMPLETE trials (infeasible ones count,
FAIL ones do not), so the same command again continues a study and is a no-op on a finished one.

Crashes (a supervised worker that dies: :mod:`gearopt.study_workers`):

- a worker that dies fails its trial (the one whose start marker names the dead process), which
  is re-enqueued with the same parameters, at most twice; loky fails every pending future when
  one worker dies, so the innocent trials are resubmitted as they are;
- a coordinator that dies leaves RUNNING trials: they are failed and their parameters
  re-enqueued (:mod:`gearopt.recovery`: Optuna's heartbeat and stale-trial handling, and at
  once for a dead coordinator of the same host). Trial numbers are never reused.

Constraints: each COMPLETE trial's constraint values are stored once, as the list in the study
file's order under Optuna's ``constraints`` system attribute (the form ``optuna-dashboard``
reads; Optuna reads it as constraints ``"0"``, ``"1"``, ...): :func:`constraint_values` names
them again.

Reproducibility: with ``deterministic`` trials are asked in synchronous batches of ``jobs`` and
told in order, so a seeded sampler suggests the same sequence of parameters (so does one
supervised worker, ``jobs = 1``, unless it dies and another takes over); otherwise the workers
sample side by side (each its seed plus its number).
"""

from __future__ import annotations

import concurrent.futures as cf
import contextlib
import os
import shutil
import socket
import sys
import time
import uuid
import warnings
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import optuna
from optuna.trial import TrialState
from tqdm import tqdm

from gearopt.best import CONSTRAINTS_KEY, constraint_values, pick_best, save_design
from gearopt.drafts import ask_drafted
from gearopt.errors import GearoptError, StudyError
from gearopt.pools import JoblibBatches, Resubmit, broken_pool, worker_pool
from gearopt.recovery import (
    ATTEMPT,
    COORDINATOR,
    HEARTBEAT_S,
    MARKERS_PREFIX,
    MAX_ATTEMPTS,
    STALE_AFTER_S,
    Requeue,
    coordinator_tag,
    fail_and_requeue,
    recover,
    trial_markers,
)
from gearopt.results import ResultsStore, artifact_dir, upload_figures
from gearopt.samplers import sampler_for, search_space
from gearopt.stops import held_stops
from gearopt.storage import (
    WorkerStorage,
    check_integrity,
    check_own_tables,
    check_storage_url,
    create_sqlite,
    default_storage_url,
    fast_sqlite,
    held_reads,
    masked_url,
    one_writer,
    rdb_storage,
    release,
    storage_error,
)
from gearopt.study_workers import supervise
from gearopt.studyfile import StudySpec
from gearopt.trial import TrialOutcome, evaluate_trial, work
from gearopt.warmup import warm_kernels

#: the state of a given design in the queue
WAIT = (TrialState.WAITING,)

__all__ = [
    "MARKERS_PREFIX",
    "MAX_ATTEMPTS",
    "STALE_AFTER_S",
    "Coordinator",
    "OpenStudy",
    "RunSummary",
    "constraint_values",
    "default_storage_url",
    "enqueue",
    "open_study",
    "pick_best",
    "run_study",
    "save_design",
    "trial_objective",
]


@dataclass(frozen=True, kw_only=True)
class OpenStudy:
    """A study opened for a coordinator: the Optuna study, its RDB storage (the public handle
    for trial ids, attributes and heartbeats), the study's id there and the gearopt tables."""

    study: optuna.Study
    storage: optuna.storages.RDBStorage
    study_id: int
    results: ResultsStore
    requeue: Requeue
    #: the trials the study held when the run opened it, given designs waiting excluded
    previous: int = 0
    #: a supervised worker's view of the storage (its study's: one read per ask at most)
    view: WorkerStorage | None = None


def open_study(spec: StudySpec, storage: str | None = None):
    """The Optuna study of ``spec`` (created when new) and its :class:`ResultsStore`; a new
    study gets its metric names and the study file's given designs, an existing one the given
    designs added to the file since (a design with a trial already is skipped)."""
    opened = _open(spec, storage)
    return opened.study, opened.results


def _open(
    spec: StudySpec, storage: str | None, stream: int = 0, *, worker=False, previous=0
) -> OpenStudy:
    """The study opened (``worker``: by a supervised worker, on a storage its supervisor has
    checked and opened: no checks, no given designs enqueued again, ``previous`` its
    supervisor's count of the study's trials; otherwise counted here)."""
    url = storage or default_storage_url(spec)
    made = False
    if not worker:
        check_storage_url(url)
        made = create_sqlite(url)  # a new SQLite file made whole, schema and all
        if not made:  # (one this call made is sound and holds only Optuna's and gearopt's)
            check_integrity(url)
            if not spec.shared_storage:
                check_own_tables(url)
    optuna.logging.set_verbosity(optuna.logging.WARNING)
    requeue = Requeue(spec)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", optuna.exceptions.ExperimentalWarning)
            rdb = rdb_storage(
                url,
                heartbeat_interval=HEARTBEAT_S,
                grace_period=STALE_AFTER_S,
                heartbeat_stale_trial_callback=requeue,
                skip_table_creation=worker,
                # (a schema made just now by this Optuna: its version check reads every
                # migration script, about half a second)
                skip_compatibility_check=worker or made,
            )
        view = WorkerStorage(rdb) if worker else None
        study = optuna.create_study(
            storage=view or rdb,
            sampler=sampler_for(spec, stream, previous),
            study_name=spec.name,
            directions=spec.directions,
            load_if_exists=True,
        )
    except (ImportError, ModuleNotFoundError) as exc:
        raise StudyError(
            "storage", masked_url(url), f"needs a driver that is not installed ({exc})"
        ) from None
    except Exception as exc:  # SQLAlchemy/driver errors: a storage that cannot be opened
        if isinstance(exc, GearoptError):
            raise
        raise storage_error(url, "cannot be opened", exc) from None
    wanted = [optuna.study.StudyDirection[d.upper()] for d in spec.directions]
    if list(study.directions) != wanted:
        raise StudyError(
            "study.name",
            spec.name,
            f"exists in {masked_url(url)} with other directions "
            f"{[d.name for d in study.directions]}",
        )
    fast_sqlite(rdb.engine)
    results = ResultsStore(url, engine=rdb.engine, create=not worker)
    requeue.results = results
    if not worker:
        first = results.register_study(spec.name, {d.key: d.describe() for d in spec.search})
        if first:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", optuna.exceptions.ExperimentalWarning)
                study.set_metric_names(spec.metric_names)
        # the study file's given designs: all of them the first time, later the ones added since
        for params in spec.enqueue:
            study.enqueue_trial(dict(params), user_attrs={ATTEMPT: 1}, skip_if_exists=not first)
        waiting = optuna.trial.TrialState.WAITING
        states = tuple(t for t in optuna.trial.TrialState if t != waiting)
        previous = len(study.get_trials(deepcopy=False, states=states))
        if previous:  # (a worker is given its supervisor's count: its sampler is built once)
            study.sampler = sampler_for(spec, stream, previous)
    study_id = rdb.get_study_id_from_name(spec.name)
    return OpenStudy(
        study=study,
        storage=rdb,
        study_id=study_id,
        results=results,
        requeue=requeue,
        previous=previous,
        view=view,
    )


def enqueue(spec: StudySpec, params: Mapping[str, float], storage: str | None = None) -> None:
    """Put a given design at the head of the study's queue."""
    params = spec.check_params(params, "enqueue")
    spec.design_for(params)  # refuse an invalid design now, not in a worker
    study, _ = open_study(spec, storage)
    study.enqueue_trial(dict(params), user_attrs={ATTEMPT: 1})


@dataclass(frozen=True, kw_only=True)
class RunSummary:
    """What a run did: counts, times, the best (or picked) trial and where its design went."""

    study: str
    storage: str
    complete: int
    failed_this_run: int
    evaluated_this_run: int
    wall_s: float
    worker_s: float
    kernels_s: float = 0.0  # the compiled kernels' compilation or loading, before the trials
    coordinator_s: float  # asking, telling, writing the tables, recovering: waits excluded
    coordinator_cpu_s: float = 0.0  # the same, the coordinator thread's CPU time
    ask_tell_cpu_s: float = 0.0  # the same, and the supervised workers' own (CPU time)
    jobs: int
    best: optuna.trial.FrozenTrial | None = None
    best_design_path: str | None = None
    recovered: list[int] = field(default_factory=list)

    @property
    def trials_s(self) -> float:
        """The run's time less the kernels' (:attr:`kernels_s`): the trials' time."""
        return max(self.wall_s - self.kernels_s, 0.0)

    @property
    def trials_per_s(self) -> float:
        return self.evaluated_this_run / self.trials_s if self.trials_s > 0 else 0.0

    @property
    def worker_efficiency(self) -> float:
        """Time the workers spent evaluating over the time they were there (the trials' time x
        jobs)."""
        return self.worker_s / (self.trials_s * self.jobs) if self.trials_s > 0 else 0.0

    @property
    def coordinator_ms_per_trial(self) -> float:
        n = max(self.evaluated_this_run, 1)
        return 1e3 * self.coordinator_s / n

    @property
    def coordinator_cpu_ms_per_trial(self) -> float:
        """:attr:`coordinator_ms_per_trial` in CPU time (not inflated by a busy machine)."""
        return 1e3 * self.coordinator_cpu_s / max(self.evaluated_this_run, 1)

    @property
    def ask_tell_cpu_ms_per_trial(self) -> float:
        """:attr:`ask_tell_cpu_s` per trial evaluated."""
        return 1e3 * self.ask_tell_cpu_s / max(self.evaluated_this_run, 1)


@dataclass(kw_only=True)
class InHand:
    """A trial this coordinator holds: asked (RUNNING in Optuna), sent or to be sent."""

    trial: optuna.Trial
    trial_id: int  # Optuna's, from its storage's public API
    params: dict
    attempt: int
    future: cf.Future | None = None


class Coordinator:
    """One coordinator's run of a study until it holds ``trials`` COMPLETE trials (the
    parameters: :func:`run_study`).

    State: the opened study (:class:`OpenStudy`); the trials in hand, by number
    (``pending``, sent to the pool), ``held`` (innocent trials of a broken pool, to resubmit),
    ``suspects`` (started when a worker died, run again one at a time; ``alone``: the one
    running alone); the counters of this run (``asked``, ``failed``, ``evaluated``,
    ``worker_s``, the coordinator's own ``busy_s`` and ``busy_cpu_s``, ``recovered``); the pool
    (``executor``) and the workers' start markers (``markers``)."""

    def __init__(
        self,
        spec: StudySpec,
        *,
        trials: int,
        jobs: int,
        storage: str | None,
        deterministic: bool,
        progress: bool,
        max_failures: int | None,
        backend: str,
        scheduler: str | None,
        role: Any = None,
    ) -> None:
        if not isinstance(trials, int) or trials < 1:
            raise StudyError("--trials", trials, "must be a positive integer")
        if not isinstance(jobs, int) or jobs < 1:
            raise StudyError("--jobs", jobs, "must be a positive integer")
        if backend not in ("loky", "dask") and not (backend == "inline" and jobs == 1):
            raise StudyError("--backend", backend, "must be loky or dask")
        self.spec, self.trials, self.jobs = spec, trials, jobs
        self.backend, self.scheduler, self.progress = backend, scheduler, progress
        self.url = storage or default_storage_url(spec)
        self.batch = deterministic or jobs == 1 or backend == "dask"
        self.role = role  # a worker of :mod:`gearopt.study_workers` (None: a coordinator)
        #: workers that ask and tell themselves, this process their supervisor
        self.supervised = role is None and not deterministic and backend == "loky"
        self.limit = max(10, trials) if max_failures is None else max_failures
        self.labels = {o.label: "objective" for o in spec.objectives}
        self.labels.update({c.label: "constraint" for c in spec.constraints})
        self.me, self.host, self.pid = uuid.uuid4().hex, socket.gethostname(), os.getpid()
        self.tag = coordinator_tag(self.host, self.pid, self.me)
        self.pending: dict[int, InHand] = {}
        self.held: list[InHand] = []
        self.suspects: list[InHand] = []
        self.alone: set[int] = set()
        self.failed = self.evaluated = self.asked = 0
        self.worker_s = self.busy_s = self.busy_cpu_s = self.kernels_s = 0.0
        self.workers_cpu_s = 0.0  # the workers' own asking and telling (supervised)
        self.recovered: list[int] = []
        self.executor: Any = None
        self.markers = ""
        self.bar = None
        self.shown = self.last_beat = 0.0
        self.opened: OpenStudy | None = None

    # --- the study -----------------------------------------------------------------------

    @property
    def study(self) -> optuna.Study:
        return self.opened.study

    def counts(self) -> tuple[int, int]:
        """COMPLETE and RUNNING trials of the study, every coordinator's (Optuna's cached
        storage reads only the trials not finished at its last look)."""
        complete = running = 0
        for t in self.study.get_trials(
            deepcopy=False, states=(TrialState.COMPLETE, TrialState.RUNNING)
        ):
            complete += t.state == TrialState.COMPLETE
            running += t.state == TrialState.RUNNING
        return complete, running

    def ahead(self, number: int) -> int:
        """COMPLETE and RUNNING trials numbered before ``number`` (every coordinator's): the
        trials that come first when several coordinators ask for the last places at once;
        read from the database, not a worker's hold (the trials created since it count)."""
        if self.opened.view is not None:
            self.opened.view.refresh()
        states = (TrialState.COMPLETE, TrialState.RUNNING)
        return sum(t.number < number for t in self.study.get_trials(deepcopy=False, states=states))

    def beat(self) -> None:
        """The coordinator's heartbeat (gearopt's table) and its trials' (Optuna's)."""
        self.opened.results.heartbeat(self.me, self.spec.name, self.host, self.pid)
        for hand in [*self.pending.values(), *self.held, *self.suspects]:
            self.opened.storage.record_heartbeat(hand.trial_id)

    def recover(self, *, starting: bool = False) -> None:
        if self.role is not None:
            return  # its supervisor recovers (it knows which of its workers died)
        o = self.opened
        self.recovered += recover(
            o.study, o.storage, o.results, self.spec, self.tag, starting=starting
        )

    def fail(self, hand: InHand, reason: str, *, charge: bool) -> None:
        """Fail a trial in hand and put its design back in the queue."""
        frozen = self.opened.storage.get_trial(hand.trial_id)
        requeue = (
            self.opened.requeue if charge else Requeue(self.spec, self.opened.results, charge=False)
        )
        # (a worker's through its view, which keeps its copy of the trial as written)
        storage = self.opened.view or self.opened.storage
        fail_and_requeue(self.study, storage, requeue, frozen, reason)
        if self.role is not None:
            self.role.give()

    # --- trials changing hands -----------------------------------------------------------

    def submit(self, hand: InHand) -> None:
        try:
            hand.future = self.executor.submit(
                work, self.spec, hand.trial.number, hand.params, self.markers
            )
        except Exception as exc:  # the pool broke since the last look: sorted out below
            if not broken_pool(exc):
                raise
            hand.future = cf.Future()
            hand.future.set_exception(exc)
        self.pending[hand.trial.number] = hand

    def ask(self) -> bool:
        """Ask a trial, suggest its parameters and send it; False when the study's places
        are taken."""
        with held_stops(), held_reads(self.opened.view):  # asked and in hand at once
            # a worker pops given designs one at a time (the hold's read, which Optuna's ask
            # reads again, says whether any wait); with none it creates its trial side by side
            waiting = self.role is not None and self.study.get_trials(deepcopy=False, states=WAIT)
            view, tag = self.opened.view, {COORDINATOR: self.tag}
            if view is not None and not waiting:  # sampled, then written (gearopt.drafts)
                space = search_space(self.spec)
                space = [(d.key, space[d.key]) for d in self.spec.search]
                trial_id, number = ask_drafted(self.study, view, self.opened.study_id, space, tag)
                self.opened.storage.record_heartbeat(trial_id)
                surplus = number >= self.trials and self.ahead(number) >= self.trials
                if not surplus:  # (a surplus trial is given back without parameters)
                    view.write_params(trial_id)
                trial = optuna.Trial(self.study, trial_id)
            else:
                asking = self.role.asking() if waiting else contextlib.nullcontext()
                with warnings.catch_warnings(), asking:  # (Optuna: heartbeats for optimize)
                    warnings.simplefilter("ignore", UserWarning)
                    trial = self.study.ask()
                trial_id = trial.storage.get_trial_id_from_study_id_trial_number(
                    self.opened.study_id, trial.number
                )
                self.opened.storage.record_heartbeat(trial_id)
                trial.set_user_attr(COORDINATOR, self.tag)
                # another coordinator took the last place (only trials numbered from
                # ``trials`` on can find ``trials`` before them: the common case asks nothing)
                surplus = trial.number >= self.trials and self.ahead(trial.number) >= self.trials
            attempt = int(trial.user_attrs.get(ATTEMPT, 1))  # retries carry theirs
            hand = InHand(trial=trial, trial_id=trial_id, params={}, attempt=attempt)
            if surplus:
                self.surplus(hand)
                return False
            hand.params = {d.key: d.suggest(trial) for d in self.spec.search}
            self.submit(hand)
            self.asked += 1
            return True

    def surplus(self, hand: InHand) -> None:
        """Give back a trial asked beyond the study's count: a given design (or a retry) to
        the queue, uncharged; a sampled one failed before it is suggested anything."""
        reason = f"surplus: {self.trials} trials were complete or running before it"
        if "fixed_params" in self.opened.storage.get_trial(hand.trial_id).system_attrs:
            self.fail(hand, reason, charge=False)
        else:
            hand.trial.set_user_attr("gearopt_error", reason)
            self.study.tell(hand.trial, state=TrialState.FAIL)
            if self.role is not None:
                self.role.give()

    def tell(self, number: int, outcome: TrialOutcome) -> None:
        with held_stops(), held_reads(self.opened.view):  # out of hand and told at once
            self._tell(number, outcome)

    def _tell(self, number: int, outcome: TrialOutcome) -> None:
        hand = self.pending.pop(number)
        trial = hand.trial
        self.evaluated += 1
        self.worker_s += outcome.seconds
        if outcome.failed:
            self.failed += 1
            trial.set_user_attr("gearopt_error", (outcome.error or "")[:500])
            self.study.tell(trial, state=TrialState.FAIL)
            if self.role is not None:
                self.role.give()
                self.role.told(outcome)
            return
        self.opened.results.write(
            self.spec.name, outcome, attempt=hand.attempt, coordinator=self.me, labels=self.labels
        )
        if outcome.figures:
            upload_figures(artifact_dir(self.spec), trial, outcome.figures)
        if outcome.constraints:  # (through the study's storage: a worker's keeps the trial)
            values = list(outcome.constraints.values())
            trial.storage.set_trial_system_attr(hand.trial_id, CONSTRAINTS_KEY, values)
        if outcome.warnings:
            trial.set_user_attr("gearopt_warnings", outcome.warnings[:20])
        self.study.tell(trial, list(outcome.values))
        if self.role is not None:
            self.role.told(outcome)
        if self.bar is not None:
            self.bar.update(1)
            if time.monotonic() - self.shown > 1.0:  # reading every trial costs: once a second
                _best_postfix(self.bar, self.study, self.spec)
                self.shown = time.monotonic()

    def worker_died(self) -> None:
        """Sort the trials of a broken pool. loky fails every pending future and stops every
        worker when one dies, so a dead process does not say whose trial killed it: a trial
        that had not started is innocent (resubmitted); of those that had started, a lone one
        is guilty (failed and re-enqueued); several are run again one at a time, and the one
        that breaks the pool alone is guilty."""
        if self.backend == "loky":
            self.executor = worker_pool(self.jobs)
        broken = {
            n: self.pending.pop(n)
            for n, hand in list(self.pending.items())
            if hand.future.done()
            and hand.future.exception() is not None
            and broken_pool(hand.future.exception())
        }
        started = [n for n in broken if Path(self.markers, f"{n}.pid").exists()]
        for number, hand in broken.items():
            Path(self.markers, f"{number}.pid").unlink(missing_ok=True)
            killer = type(hand.future.exception()).__name__ == "KilledWorker"  # Dask names it
            if killer or number in self.alone or started == [number]:
                self.failed += 1
                self.fail(hand, "its worker process died", charge=True)
            elif number in started:
                self.suspects.append(hand)
            else:
                self.held.append(hand)
        self.alone.clear()

    def refill(self, free: int) -> None:
        if self.suspects:
            if not self.pending:
                with held_stops():
                    hand = self.suspects.pop(0)
                    self.alone.add(hand.trial.number)
                    self.submit(hand)
            return
        # busy workers: the pending trials not finished (finished ones are told after this)
        busy = sum(not h.future.done() for h in self.pending.values())
        while self.held and busy < self.jobs:
            with held_stops():
                self.submit(self.held.pop(0))
            busy += 1
        if self.batch and self.pending and not self.held:
            return
        for _ in range(min(self.jobs - busy, max(free, 0))):
            if self.role is not None and not self.role.take():
                break  # the run's places are in the hands of the other workers
            if not self.ask():
                break

    # --- the run -------------------------------------------------------------------------

    def run(self, *, save_best: bool = True) -> RunSummary:
        start = time.perf_counter()
        stream, previous = (0, 0) if self.role is None else (self.role.stream, self.role.previous)
        self.opened = _open(
            self.spec, self.url, stream, worker=self.role is not None, previous=previous
        )
        if self.role is not None and self.role.writes:  # the run's workers write in turn
            one_writer(self.opened.storage.engine, self.role.writes)
        self.opened.results.heartbeat(self.me, self.spec.name, self.host, self.pid)
        self.recover(starting=True)
        self.markers = trial_markers(self.pid) if self.role is None else ""  # (a worker: none)
        # the compiled kernels compiled (or loaded) here once, before the workers start (they
        # load the cache rather than compile it side by side) and before the trials' clock
        self.kernels_s = warm_kernels(announce=self.progress)
        self.bar = _progress(self.progress, self.trials, self.spec)
        self.last_beat = time.monotonic()
        try:
            if self.supervised:
                supervise(self)  # (it stops its workers itself)
            else:
                self.executor = worker_pool(self.jobs, self.backend, self.scheduler)
                self._loop()
        except BaseException as exc:
            if not self.supervised:
                self._stop(exc)
            raise
        finally:
            if self.bar is not None:
                if self.evaluated:
                    _best_postfix(self.bar, self.study, self.spec)
                self.bar.close()
            if isinstance(self.executor, JoblibBatches):
                self.executor.client.close()
            if self.markers:
                shutil.rmtree(self.markers, ignore_errors=True)
        complete, _ = self.counts()
        best = pick_best(self.study, self.spec) if self.role is None else None
        path = save_design(self.spec, best, self.url) if (save_best and best is not None) else None
        release(self.opened.storage)  # (closed now, not at the interpreter's exit)
        return RunSummary(
            study=self.spec.name,
            storage=masked_url(self.url),
            complete=complete,
            failed_this_run=self.failed,
            evaluated_this_run=self.evaluated,
            wall_s=time.perf_counter() - start,
            kernels_s=self.kernels_s,
            worker_s=self.worker_s,
            coordinator_s=self.busy_s,
            coordinator_cpu_s=self.busy_cpu_s,
            ask_tell_cpu_s=self.busy_cpu_s + self.workers_cpu_s,
            jobs=self.jobs,
            best=best,
            best_design_path=path,
            recovered=self.recovered,
        )

    def _stop(self, exc: BaseException) -> None:
        """Stopping (an error, Ctrl-C): the trials in hand go back to the queue as they are,
        and the workers are stopped; only a killed coordinator leaves RUNNING trials."""
        if self.backend == "loky":
            self.executor.shutdown(wait=False, kill_workers=True)
        reason = f"the coordinator stopped: {type(exc).__name__}: {exc}"
        for hand in [*self.pending.values(), *self.held, *self.suspects]:
            self.fail(hand, reason, charge=False)

    def _loop(self) -> None:
        # the coordinator's own time, waits excluded (wall, and this thread's CPU time)
        mark, cpu = time.perf_counter(), time.thread_time()
        while True:
            if time.monotonic() - self.last_beat > HEARTBEAT_S:
                self.beat()
                self.recover()
                self.last_beat = time.monotonic()
            if self.failed > self.limit:
                raise StudyError(
                    "study",
                    self.spec.name,
                    f"{self.failed} trials failed in this run (limit {self.limit})",
                )
            if self.role is not None:  # a supervised worker: the run's places say, no count
                complete, free = 0, 1
            else:
                complete, running = self.counts()
                free = self.trials - complete - running
            if not (self.pending or self.held or self.suspects):
                if complete >= self.trials:
                    break
                if free <= 0 and self.role is not None:
                    break  # the supervisor waits for the others
                if free <= 0:  # the rest runs on other coordinators
                    time.sleep(0.5)
                    mark, cpu = time.perf_counter(), time.thread_time()
                    continue
            asked = self.asked
            if not self.batch or not self.pending:
                self.refill(free)
            if self.role is not None and not self.pending:
                break  # no place left for this worker: the others hold them
            futures = [h.future for h in self.pending.values()]
            self.busy_s += time.perf_counter() - mark
            self.busy_cpu_s += time.thread_time() - cpu
            if hasattr(self.executor, "flush"):
                self.executor.flush()
            # wake every few seconds to keep the heartbeats fresh while long trials run
            until = "ALL_COMPLETED" if self.batch else "FIRST_COMPLETED"
            while futures and (
                not cf.wait(futures, timeout=HEARTBEAT_S, return_when=until).done
                or (self.batch and not all(f.done() for f in futures))
            ):
                self.beat()
            mark, cpu = time.perf_counter(), time.thread_time()
            if not self.batch and not self.suspects:
                # keep the workers busy first: the next trials are asked and sent before the
                # finished ones are told (TPE's constant liar counts those as pending)
                # (the counts read above, less the trials asked since: a trial asked for a
                # place another coordinator took meanwhile is given back by ``ask``)
                self.refill(free - (self.asked - asked))
            self._collect()

    def _collect(self) -> None:
        """Tell the finished trials (in order when in batches); sort a broken pool's."""
        broken = False
        for number in sorted(self.pending):
            future = self.pending[number].future
            if not future.done():
                if self.batch:
                    break  # told in order
                continue
            exc = future.exception()
            if exc is None:
                self.tell(number, future.result())
            elif isinstance(exc, Resubmit):
                with held_stops():
                    self.held.append(self.pending.pop(number))
            elif broken_pool(exc):
                broken = True
                if self.batch:
                    break
            else:  # pickling or pool errors: the trial fails, the run goes on
                outcome = TrialOutcome(number=number, error=f"{type(exc).__name__}: {exc}")
                self.tell(number, outcome)
        if broken:
            with held_stops():
                self.worker_died()


def run_study(
    spec: StudySpec,
    *,
    trials: int,
    jobs: int = 2,
    storage: str | None = None,
    deterministic: bool = False,
    progress: bool = True,
    save_best: bool = True,
    max_failures: int | None = None,
    backend: str = "loky",
    scheduler: str | None = None,
) -> RunSummary:
    """Run ``spec`` until its study holds ``trials`` COMPLETE trials (a :class:`Coordinator`).

    Parameters
    ----------
    trials
        COMPLETE trials the study must hold at the end (FAIL ones do not count).
    jobs
        Worker processes (not deterministic: started by multiprocessing, forked on Linux,
        spawned elsewhere, where a script calling this needs ``if __name__ == "__main__":``).
    storage
        SQLAlchemy URL (default :func:`default_storage_url`); PostgreSQL works the same, and
        several coordinators may share one study there.
    deterministic
        Synchronous batches of ``jobs`` trials told in order, on a loky pool.
    save_best
        Save the best (or picked) design as ``<study name>_best.toml`` beside the study file.
    max_failures
        Stop with a :class:`StudyError` when more trials than this fail in this run (default:
        ``max(10, trials)``): a search space that only gives failing designs.
    backend, scheduler
        ``"loky"`` (local worker processes) or ``"dask"``: the evaluations go through joblib's
        dask backend to the Dask cluster at ``scheduler`` (default: a local cluster of
        ``jobs`` workers), in synchronous batches of ``jobs`` trials.
    """
    coordinator = Coordinator(
        spec,
        trials=trials,
        jobs=jobs,
        storage=storage,
        deterministic=deterministic,
        progress=progress,
        max_failures=max_failures,
        backend=backend,
        scheduler=scheduler,
    )
    return coordinator.run(save_best=save_best)


def _progress(progress: bool, total: int, spec: StudySpec):
    if not progress:
        return None
    return tqdm(total=total, desc=spec.name, unit="trial", file=sys.stderr, dynamic_ncols=True)


def _best_postfix(bar, study, spec: StudySpec) -> None:
    best = pick_best(study, spec)
    if best is not None:
        pairs = zip(spec.metric_names, best.values, strict=True)
        text = ", ".join(f"{k}={v:.4g}" for k, v in pairs)
        bar.set_postfix_str(f"best {text}")


def trial_objective(spec: StudySpec) -> Callable[[optuna.trial.Trial], Any]:
    """An Optuna objective function of ``spec`` for ``study.optimize`` in one process (a
    notebook, a debugger): it suggests the searched keys, evaluates the trial in this process,
    sets the constraints and returns the objective values. :func:`run_study` is the way to run
    a study on several workers with crash recovery and the gearopt tables."""

    def objective(trial: optuna.trial.Trial):
        params = {d.key: d.suggest(trial) for d in spec.search}
        outcome = evaluate_trial(spec, trial.number, params)
        if outcome.failed:
            raise StudyError(f"trial {trial.number}", params, outcome.error or "failed")
        if outcome.constraints:  # once, as a list: what optuna-dashboard reads
            storage = trial.storage
            study_id = storage.get_study_id_from_name(trial.study.study_name)
            trial_id = storage.get_trial_id_from_study_id_trial_number(study_id, trial.number)
            values = list(outcome.constraints.values())
            storage.set_trial_system_attr(trial_id, CONSTRAINTS_KEY, values)
        values = outcome.values
        return values[0] if len(values) == 1 else values

    return objective
