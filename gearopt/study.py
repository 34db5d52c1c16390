"""The study coordinator: Optuna ask/tell over a pool of worker processes.

One coordinator process owns the storage (Optuna discourages several processes writing one
SQLite file): it asks trials, sends the pure evaluations (:func:`gearopt.trial.work`) to a
joblib/loky pool of ``jobs`` workers, writes the gearopt tables (:mod:`gearopt.results`) and
tells Optuna, in that order. Workers never touch the database.

Counting: a run ends when the study holds ``trials`` COMPLETE trials (infeasible ones count,
FAIL ones do not), so the same command again continues a study and is a no-op on a finished one.

Crashes:

- a worker that dies fails its trial (the one whose start marker names the dead process), which
  is re-enqueued with the same parameters, at most twice; loky fails every pending future when
  one worker dies, so the innocent trials are resubmitted as they are;
- a coordinator that dies leaves RUNNING trials: the next coordinator fails them and re-enqueues
  their parameters, when their coordinator is gone (same host: its process is dead; another
  host: no heartbeat for ``STALE_AFTER_S``). Trial numbers are never reused.

Reproducibility: with ``jobs = 1``, or ``deterministic``, trials are asked in synchronous batches
of ``jobs`` and told in order, so a seeded sampler suggests the same sequence of parameters;
otherwise the workers are kept busy asynchronously.
"""

from __future__ import annotations

import concurrent.futures as cf
import contextlib
import datetime as dt
import math
import os
import shutil
import signal
import socket
import sys
import tempfile
import threading
import time
import uuid
import warnings
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import optuna
import sqlalchemy as sa
import sqlalchemy.exc
import tomli_w
from optuna.artifacts import FileSystemArtifactStore, upload_artifact
from optuna.trial import TrialState
from tqdm import tqdm

from gearopt.errors import GearoptError, StudyError
from gearopt.pools import JoblibBatches, Resubmit, broken_pool, worker_pool
from gearopt.results import ResultsStore
from gearopt.storage import (
    check_integrity,
    check_own_tables,
    check_storage_url,
    default_storage_url,
    fast_sqlite,
    masked_url,
    rdb_storage,
    storage_error,
    storage_tag,
)
from gearopt.studyfile import StudySpec
from gearopt.trial import TrialOutcome, evaluate_trial, work
from gearopt.warmup import warm_kernels

__all__ = [
    "STALE_AFTER_S",
    "RunSummary",
    "default_storage_url",
    "enqueue",
    "open_study",
    "pick_best",
    "run_study",
    "save_design",
    "trial_objective",
]

#: a coordinator on another host whose heartbeat is older than this is taken for dead
STALE_AFTER_S = 120.0
#: attempts of one design: the first and two re-enqueued ones
MAX_ATTEMPTS = 3
_COORD = "gearopt_coordinator"
_ATTEMPT = "gearopt_attempt"
_COUNTS = sa.text("SELECT state, COUNT(*) FROM trials WHERE study_id = :id GROUP BY state")
_AHEAD = sa.text(
    "SELECT COUNT(*) FROM trials WHERE study_id = :id AND number < :n"
    " AND state IN ('COMPLETE', 'RUNNING')"
)


#: the prefix of the coordinators' temporary folders (a worker's pid marker per trial)
MARKERS_PREFIX = "gearopt-trials-"


def _trial_markers(pid: int) -> str:
    """A new temporary folder for the trials' markers, its owner's pid in ``owner``; first
    the folders of coordinators of this host that are gone (killed: nothing removed them)."""
    root = Path(tempfile.gettempdir())
    for folder in root.glob(MARKERS_PREFIX + "*"):
        try:
            owner = int((folder / "owner").read_text())
        except (OSError, ValueError):  # no owner file (yet): not ours to judge
            continue
        if not _alive(owner):
            shutil.rmtree(folder, ignore_errors=True)
    markers = tempfile.mkdtemp(prefix=MARKERS_PREFIX)
    Path(markers, "owner").write_text(str(pid))
    return markers


def _sampler(spec: StudySpec) -> optuna.samplers.BaseSampler:
    seed = spec.seed
    if spec.sampler == "tpe":
        return optuna.samplers.TPESampler(seed=seed, multivariate=True, constant_liar=True)
    if spec.sampler == "random":
        return optuna.samplers.RandomSampler(seed=seed)
    if spec.sampler == "nsga2":
        return optuna.samplers.NSGAIISampler(seed=seed)
    return optuna.samplers.QMCSampler(seed=seed)


def open_study(spec: StudySpec, storage: str | None = None):
    """The Optuna study of ``spec`` (created when new) and its :class:`ResultsStore`; a new
    study gets its metric names and the study file's given designs, an existing one the given
    designs added to the file since (a design with a trial already is skipped)."""

    url = storage or default_storage_url(spec)
    check_storage_url(url)
    check_integrity(url)
    if not spec.shared_storage:
        check_own_tables(url)
    optuna.logging.set_verbosity(optuna.logging.WARNING)
    try:
        rdb = rdb_storage(url)
        study = optuna.create_study(
            storage=rdb,
            sampler=_sampler(spec),
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
    results = ResultsStore(url, engine=rdb.engine)
    search = {d.key: [d.low, d.high, d.log] for d in spec.search}
    first = results.register_study(spec.name, search)
    if first:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", optuna.exceptions.ExperimentalWarning)
            study.set_metric_names(spec.metric_names)
    # the study file's given designs: all of them the first time, later the ones added since
    for params in spec.enqueue:
        study.enqueue_trial(dict(params), user_attrs={_ATTEMPT: 1}, skip_if_exists=not first)
    return study, results


def enqueue(spec: StudySpec, params: Mapping[str, float], storage: str | None = None) -> None:
    """Put a given design at the head of the study's queue."""
    params = spec.check_params(params, "enqueue")
    spec.design_for(params)  # refuse an invalid design now, not in a worker
    study, _ = open_study(spec, storage)
    study.enqueue_trial(dict(params), user_attrs={_ATTEMPT: 1})


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


def _alive(pid: int) -> bool:
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


def _params(trial: optuna.trial.FrozenTrial, spec: StudySpec) -> dict:
    """The trial's parameters (a given design's, or those suggested), or {} when a coordinator
    died before suggesting them all: such a trial never reached a worker."""
    params = {**trial.system_attrs.get("fixed_params", {}), **trial.params}
    return params if set(params) >= set(spec.dimensions) else {}


def _retry(study, results, spec: StudySpec, trial, reason: str, *, charge: bool = True) -> bool:
    """Fail ``trial`` (a FrozenTrial) and re-enqueue its parameters when attempts remain (an
    attempt is charged unless ``charge`` is False: the trial was not to blame); False when
    another coordinator finished it first."""
    number = trial.number
    try:
        study._storage.set_trial_user_attr(trial._trial_id, "gearopt_error", reason[:500])
        study.tell(number, state=TrialState.FAIL)
    except (RuntimeError, ValueError):
        return False
    results.forget(spec.name, [number])
    attempt = int(trial.user_attrs.get(_ATTEMPT, 1)) + int(charge)
    params = _params(trial, spec)
    if params and attempt <= MAX_ATTEMPTS:
        study.enqueue_trial(params, user_attrs={_ATTEMPT: attempt, "gearopt_retry_of": number})
    return True


def recover(study, results, spec: StudySpec, me: str) -> list[int]:
    """Fail and re-enqueue the RUNNING trials whose coordinator is gone; their numbers."""
    host = socket.gethostname()
    now = dt.datetime.now(dt.UTC).replace(tzinfo=None)

    def alive(known) -> bool:
        o_host, o_pid, beat = known
        fresh = (now - beat).total_seconds() < STALE_AFTER_S
        return fresh and (o_host != host or _alive(o_pid))

    living = {c for c, known in results.coordinators().items() if c != me and alive(known)}
    done = []
    for trial in study.get_trials(deepcopy=False, states=(TrialState.RUNNING,)):
        owner = trial.user_attrs.get(_COORD)
        if owner == me or owner in living:
            continue
        if owner is None and living and (now - trial.datetime_start).total_seconds() < 60:
            continue  # asked a moment ago by a live coordinator, not yet marked as its own
        if _retry(study, results, spec, trial, f"coordinator {owner} died"):
            done.append(trial.number)
    return done


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
    """Run ``spec`` until its study holds ``trials`` COMPLETE trials.

    Parameters
    ----------
    trials
        COMPLETE trials the study must hold at the end (FAIL ones do not count).
    jobs
        Worker processes (loky).
    storage
        SQLAlchemy URL (default :func:`default_storage_url`); PostgreSQL works the same, and
        several coordinators may share one study there.
    deterministic
        Synchronous batches of ``jobs`` trials told in order (``jobs = 1`` always is).
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
    if not isinstance(trials, int) or trials < 1:
        raise StudyError("--trials", trials, "must be a positive integer")
    if not isinstance(jobs, int) or jobs < 1:
        raise StudyError("--jobs", jobs, "must be a positive integer")
    if backend not in ("loky", "dask"):
        raise StudyError("--backend", backend, "must be loky or dask")
    start = time.perf_counter()
    url = storage or default_storage_url(spec)
    study, results = open_study(spec, url)
    me, host, pid = uuid.uuid4().hex, socket.gethostname(), os.getpid()
    results.heartbeat(me, spec.name, host, pid)
    recovered = recover(study, results, spec, me)
    labels = {o.label: "objective" for o in spec.objectives}
    labels.update({c.label: "constraint" for c in spec.constraints})
    limit = max(10, trials) if max_failures is None else max_failures
    batch = deterministic or jobs == 1 or backend == "dask"
    markers = _trial_markers(pid)
    pending: dict[int, tuple[Any, cf.Future, dict, int]] = {}
    failed = evaluated = 0
    worker_s = 0.0
    # the compiled kernels compiled (or loaded) here once, before the workers start (they load
    # the cache rather than compile it side by side) and before the clock of the trials
    kernels_s = warm_kernels(announce=progress)
    bar = _progress(progress, trials, spec)
    shown = [0.0]  # when the bar last showed the best value
    last_beat = time.monotonic()

    def counts() -> tuple[int, int]:
        """COMPLETE and RUNNING trials of the study, every coordinator's (one small query)."""
        with results.engine.connect() as con:
            rows = dict(con.execute(_COUNTS, {"id": study._study_id}).all())
        return rows.get("COMPLETE", 0), rows.get("RUNNING", 0)

    def submit(trial, params, attempt):
        try:
            future = executor.submit(work, spec, trial.number, params, markers)
        except Exception as exc:  # the pool broke since the last look: sorted out below
            if not broken_pool(exc):
                raise
            future = cf.Future()
            future.set_exception(exc)
        pending[trial.number] = (trial, future, params, attempt)

    def ask() -> bool:
        with _held_stops():  # asked and in hand at once
            trial = study.ask()
            trial.set_user_attr(_COORD, me)
            if ahead(trial.number) >= trials:  # another coordinator took the last place
                surplus(trial)
                return False
            attempt = int(trial.user_attrs.get(_ATTEMPT, 1))  # retries carry theirs
            params = {
                d.key: trial.suggest_float(d.key, d.low, d.high, log=d.log) for d in spec.search
            }
            submit(trial, params, attempt)
            return True

    def ahead(number: int) -> int:
        """COMPLETE and RUNNING trials numbered before ``number`` (every coordinator's): the
        trials that come first when several coordinators ask for the last places at once."""
        with results.engine.connect() as con:
            return con.execute(_AHEAD, {"id": study._study_id, "n": number}).scalar_one()

    def surplus(trial) -> None:
        """Give back a trial asked beyond the study's count: a given design (or a retry) to
        the queue, uncharged; a sampled one failed before it is suggested anything."""
        frozen = study._storage.get_trial(trial._trial_id)
        reason = f"surplus: {trials} trials were complete or running before it"
        if "fixed_params" in frozen.system_attrs:
            _retry(study, results, spec, frozen, reason, charge=False)
        else:
            trial.set_user_attr("gearopt_error", reason)
            study.tell(trial, state=TrialState.FAIL)

    def tell(number: int, outcome: TrialOutcome) -> None:
        with _held_stops():  # out of hand and told at once
            _tell(number, outcome)

    def _tell(number: int, outcome: TrialOutcome) -> None:
        nonlocal failed, evaluated, worker_s
        trial, _, params, attempt = pending.pop(number)
        evaluated += 1
        worker_s += outcome.seconds
        if outcome.failed:
            failed += 1
            trial.set_user_attr("gearopt_error", (outcome.error or "")[:500])
            study.tell(trial, state=TrialState.FAIL)
        else:
            results.write(spec.name, outcome, attempt=attempt, coordinator=me, labels=labels)
            if outcome.figures:
                _upload(spec, study, trial, outcome.figures)
            for label, value in outcome.constraints.items():
                trial.set_constraint(label, value)
            if outcome.warnings:
                trial.set_user_attr("gearopt_warnings", outcome.warnings[:20])
            study.tell(trial, list(outcome.values))
            if bar is not None:
                bar.update(1)
                if time.monotonic() - shown[0] > 1.0:  # reading every trial costs: once a second
                    _best_postfix(bar, study, spec)
                    shown[0] = time.monotonic()

    held: list[tuple[Any, dict, int]] = []  # innocent trials to resubmit
    suspects: list[tuple[Any, dict, int]] = []  # started when a worker died: run each alone
    alone: set[int] = set()

    def worker_died() -> None:
        """Sort the trials of a broken pool. loky fails every pending future and stops every
        worker when one dies, so a dead process does not say whose trial killed it: a trial
        that had not started is innocent (resubmitted); of those that had started, a lone one
        is guilty (failed and re-enqueued); several are run again one at a time, and the one
        that breaks the pool alone is guilty."""
        nonlocal executor, failed
        if backend == "loky":
            executor = worker_pool(jobs)
        broken = {
            n: pending.pop(n)
            for n in list(pending)
            if pending[n][1].done()
            and pending[n][1].exception() is not None
            and broken_pool(pending[n][1].exception())
        }
        started = [n for n in broken if Path(markers, f"{n}.pid").exists()]
        for number, (trial, future, params, attempt) in broken.items():
            Path(markers, f"{number}.pid").unlink(missing_ok=True)
            killer = type(future.exception()).__name__ == "KilledWorker"  # Dask names it
            if killer or number in alone or started == [number]:
                failed += 1
                frozen = study._storage.get_trial(trial._trial_id)
                _retry(study, results, spec, frozen, "its worker process died")
            elif number in started:
                suspects.append((trial, params, attempt))
            else:
                held.append((trial, params, attempt))
        alone.clear()

    def refill(free: int) -> None:
        if suspects:
            if not pending:
                with _held_stops():
                    trial, params, attempt = suspects.pop(0)
                    alone.add(trial.number)
                    submit(trial, params, attempt)
            return
        # busy workers: the pending trials not finished (finished ones are told after this)
        busy = sum(not p[1].done() for p in pending.values())
        while held and busy < jobs:
            with _held_stops():
                submit(*held.pop(0))
            busy += 1
        if batch and pending and not held:
            return
        for _ in range(min(jobs - busy, max(free, 0))):
            if not ask():
                break

    executor = worker_pool(jobs, backend, scheduler)
    busy_s, mark = 0.0, time.perf_counter()  # the coordinator's own time, waits excluded
    try:
        while True:
            if time.monotonic() - last_beat > 5.0:
                results.heartbeat(me, spec.name, host, pid)
                recovered += recover(study, results, spec, me)
                last_beat = time.monotonic()
            if failed > limit:
                raise StudyError(
                    "study", spec.name, f"{failed} trials failed in this run (limit {limit})"
                )
            complete, running = counts()
            free = trials - complete - running
            if not (pending or held or suspects):
                if complete >= trials:
                    break
                if free <= 0:  # the rest runs on other coordinators
                    time.sleep(0.5)
                    mark = time.perf_counter()
                    continue
            if not batch or not pending:
                refill(free)
            futures = [p[1] for p in pending.values()]
            busy_s += time.perf_counter() - mark
            if hasattr(executor, "flush"):
                executor.flush()
            # wake every few seconds to keep the heartbeat fresh while long trials run
            until = "ALL_COMPLETED" if batch else "FIRST_COMPLETED"
            while futures and (
                not cf.wait(futures, timeout=5.0, return_when=until).done
                or (batch and not all(f.done() for f in futures))
            ):
                results.heartbeat(me, spec.name, host, pid)
            mark = time.perf_counter()
            if not batch and not suspects:
                # keep the workers busy first: the next trials are asked and sent before the
                # finished ones are told (TPE's constant liar counts those as pending)
                complete, running = counts()
                refill(trials - complete - running)
            broken = False
            for number in sorted(pending):
                future = pending[number][1]
                if not future.done():
                    if batch:
                        break  # told in order
                    continue
                exc = future.exception()
                if exc is None:
                    tell(number, future.result())
                elif isinstance(exc, Resubmit):
                    with _held_stops():
                        trial, _, params, attempt = pending.pop(number)
                        held.append((trial, params, attempt))
                elif broken_pool(exc):
                    broken = True
                    if batch:
                        break
                else:  # pickling or pool errors: the trial fails, the run goes on
                    outcome = TrialOutcome(number=number, error=f"{type(exc).__name__}: {exc}")
                    tell(number, outcome)
            if broken:
                with _held_stops():
                    worker_died()
    except BaseException as exc:
        # stopping (an error, Ctrl-C): the trials in hand go back to the queue as they are,
        # and the workers are stopped; only a killed coordinator leaves RUNNING trials
        if backend == "loky":
            executor.shutdown(wait=False, kill_workers=True)
        mine = [p[0] for p in pending.values()] + [h[0] for h in held + suspects]
        reason = f"the coordinator stopped: {type(exc).__name__}: {exc}"
        for trial in mine:
            frozen = study._storage.get_trial(trial._trial_id)
            _retry(study, results, spec, frozen, reason, charge=False)
        raise
    finally:
        if bar is not None:
            if evaluated:
                _best_postfix(bar, study, spec)
            bar.close()
        if isinstance(executor, JoblibBatches):
            executor.client.close()
        shutil.rmtree(markers, ignore_errors=True)
    complete, _ = counts()
    best = pick_best(study, spec)
    path = save_design(spec, best, url) if (save_best and best is not None) else None
    wall = time.perf_counter() - start
    return RunSummary(
        study=spec.name,
        storage=masked_url(url),
        complete=complete,
        failed_this_run=failed,
        evaluated_this_run=evaluated,
        wall_s=wall,
        kernels_s=kernels_s,
        worker_s=worker_s,
        coordinator_s=busy_s,
        jobs=jobs,
        best=best,
        best_design_path=path,
        recovered=recovered,
    )


_STOPS = (signal.SIGINT, signal.SIGTERM)


def _swap_handlers(handlers: dict) -> dict:
    """Set the stop signals' handlers at once (both blocked meanwhile where signals can be
    masked: a stop between the two swaps is delivered after them, to the new handler);
    returns the previous ones (None, a handler set outside Python, as the default)."""
    masked = hasattr(signal, "pthread_sigmask")
    if masked:
        mask = signal.pthread_sigmask(signal.SIG_BLOCK, _STOPS)
    try:
        previous = {sig: signal.signal(sig, handler) for sig, handler in handlers.items()}
    finally:
        if masked:
            signal.pthread_sigmask(signal.SIG_SETMASK, mask)
    return {sig: signal.SIG_DFL if h is None else h for sig, h in previous.items()}


@contextlib.contextmanager
def _held_stops():
    """SIGINT and SIGTERM (a polite stop: Ctrl-C, a scheduler) held back while a trial changes
    hands (asked and put in hand, or taken out of hand and told), then raised again for the
    handlers they had: a stop then finds every trial of this coordinator either in hand (put
    back in the queue) or finished, never RUNNING and forgotten. (Handlers, masked only while
    they are swapped: worker processes started meanwhile must not inherit blocked signals.)
    Off the main thread, where handlers cannot be set, nothing is held."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    caught: list[int] = []
    previous = _swap_handlers({sig: lambda signum, _: caught.append(signum) for sig in _STOPS})
    try:
        yield
    finally:
        _swap_handlers(previous)
        if caught:
            signal.raise_signal(caught[0])


def artifact_dir(spec: StudySpec) -> Path:
    """Where a study's artifacts go: ``<study name>_artifacts`` beside the study file (give
    it to ``optuna-dashboard --artifact-dir``)."""
    return spec.folder / f"{spec.name}_artifacts"


def _upload(spec: StudySpec, study, trial, figures) -> None:

    base = artifact_dir(spec)
    base.mkdir(parents=True, exist_ok=True)
    store = FileSystemArtifactStore(str(base))
    with tempfile.TemporaryDirectory() as folder:
        for name, data in figures:
            path = Path(folder, f"trial{trial.number}_{name}")
            path.write_bytes(data)
            upload_artifact(
                artifact_store=store,
                file_path=str(path),
                study_or_trial=trial,
                mimetype="image/png",
            )


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


def _feasible(trial: optuna.trial.FrozenTrial) -> bool:
    return all(c <= 0.0 for c in trial.constraints.values())


def pick_best(study, spec: StudySpec) -> optuna.trial.FrozenTrial | None:
    """The best feasible COMPLETE trial; for several objectives the Pareto design the study's
    ``pick`` rule chooses: ``utopia`` (least distance to the front's ideal point, each
    objective scaled by its range on the front) or ``objective:<label>`` (the front's best of
    that objective). None when no feasible trial exists."""
    done = [
        t
        for t in study.get_trials(deepcopy=False, states=(TrialState.COMPLETE,))
        if _feasible(t) and t.values is not None
    ]
    if not done:
        return None
    signs = [1.0 if d == "minimize" else -1.0 for d in spec.directions]
    if len(signs) == 1:
        return min(done, key=lambda t: (signs[0] * t.values[0], t.number))
    scored = [[s * v for s, v in zip(signs, t.values, strict=True)] for t in done]
    front = [
        i
        for i, a in enumerate(scored)
        if not any(all(x <= y for x, y in zip(b, a, strict=True)) and b != a for b in scored)
    ]
    if spec.pick.startswith("objective:"):
        k = spec.metric_names.index(spec.pick.removeprefix("objective:"))
        return done[min(front, key=lambda i: (scored[i][k], done[i].number))]
    lows = [min(scored[i][k] for i in front) for k in range(len(signs))]
    highs = [max(scored[i][k] for i in front) for k in range(len(signs))]

    def distance(i: int) -> float:
        return math.hypot(
            *[
                (scored[i][k] - lows[k]) / (highs[k] - lows[k]) if highs[k] > lows[k] else 0.0
                for k in range(len(signs))
            ]
        )

    return done[min(front, key=lambda i: (distance(i), done[i].number))]


def save_design(
    spec: StudySpec, trial: optuna.trial.FrozenTrial, storage: str | None = None
) -> str:
    """Write the trial's design beside the study file as ``<study name>_best.toml`` (the
    study's default storage) or ``<study name>_best_<storage>.toml`` (another storage: its
    SQLite file's stem, or a digest of its URL), so that a run on another storage never
    overwrites the default study's best design."""

    data = dict(spec.design_for(trial.params).source)
    meta = data.setdefault("meta", {})
    meta["name"] = f"{spec.name}_best"
    meta["source"] = f"study {spec.name}, trial {trial.number}"
    path = spec.folder / f"{spec.name}_best{storage_tag(spec, storage)}.toml"
    path.write_text(tomli_w.dumps(data), encoding="utf-8")
    return str(path)


def trial_objective(spec: StudySpec) -> Callable[[optuna.trial.Trial], Any]:
    """An Optuna objective function of ``spec`` for ``study.optimize`` in one process (a
    notebook, a debugger): it suggests the searched keys, evaluates the trial in this process,
    sets the constraints and returns the objective values. :func:`run_study` is the way to run
    a study on several workers with crash recovery and the gearopt tables."""

    def objective(trial: optuna.trial.Trial):
        params = {d.key: trial.suggest_float(d.key, d.low, d.high, log=d.log) for d in spec.search}
        outcome = evaluate_trial(spec, trial.number, params)
        if outcome.failed:
            raise StudyError(f"trial {trial.number}", params, outcome.error or "failed")
        for label, value in outcome.constraints.items():
            trial.set_constraint(label, value)
        values = outcome.values
        return values[0] if len(values) == 1 else values

    return objective
