"""A study run on worker processes that ask and tell themselves (Optuna's own multi-process
pattern), supervised by the coordinator.

Each of the ``jobs`` workers is a coordinator of its own with one trial in hand at a time,
evaluated in its own process (:class:`gearopt.study.Coordinator` on
:class:`gearopt.pools.InlineCalls`): it asks Optuna (its sampler seeded with the study's seed
plus its number), evaluates, writes the gearopt tables and tells, on the one storage, so the
sampler's and the storage's cost per trial is paid by the workers side by side rather than by
one process for all. The workers are forked on Linux (they inherit the supervisor's imports
and warmed kernels), spawned elsewhere. The supervisor (:class:`Supervisor`, this process)
opens the study, recovers what earlier runs left, starts the workers, shows the progress,
keeps the heartbeats of the workers' longer trials and watches them:

- the run's places (COMPLETE trials still missing, less those running) are shared by the
  workers: one takes a place before it asks and gives it back when its trial does not
  complete, so together they stop at the count exactly;
- a worker that dies (its evaluation killed the process) fails its trial, charged an attempt
  and re-enqueued (:func:`gearopt.recovery.fail_and_requeue`), and another worker starts;
- a stop (Ctrl-C, SIGTERM) stops the workers, which put their trials back in the queue
  uncharged, as one coordinator does; a worker that does not stop in time is killed and its
  trial put back likewise;
- a killed supervisor: the workers see it gone and stop (their trials back in the queue); a
  whole process group killed leaves RUNNING trials that the next run recovers, as a killed
  coordinator's.
"""

from __future__ import annotations

import contextlib
import gc
import multiprocessing as mp
import multiprocessing.connection as mpc
import os
import signal
import sys
import threading
import time
from dataclasses import dataclass, field
from typing import Any

from optuna.trial import TrialState

import gearopt.errors
from gearopt.errors import GearoptError, StudyError
from gearopt.recovery import (
    COORDINATOR,
    HEARTBEAT_S,
    Requeue,
    fail_and_requeue,
    recover,
    running_trials,
)
from gearopt.studyfile import StudySpec

__all__ = ["Supervisor", "WorkerRole", "supervise"]

#: seconds a stopped worker has to put its trial back before it is killed
STOP_WAIT_S = 30.0

#: seconds the supervisor lets its workers' messages gather before it reads them again (it
#: wakes at once when a worker ends): a read per trial was a wake-up per trial, on cores the
#: workers keep busy
TICK_S = 0.25

#: seconds a worker waits for another's ask (:meth:`WorkerRole.asking`) before it asks anyway
ASK_WAIT_S = 10.0

#: how workers start: forked on Linux (they inherit the imports and the warmed kernels: a
#: worker starts in milliseconds, not seconds), spawned elsewhere (fork is unsafe on macOS)
START_METHOD = "fork" if sys.platform == "linux" else "spawn"


@dataclass(kw_only=True)
class WorkerRole:
    """What makes a :class:`gearopt.study.Coordinator` one of a supervisor's workers: its
    ``stream`` (sampler seed offset), the run's shared ``places`` and the pipe to the
    supervisor."""

    stream: int
    places: Any  # a multiprocessing Value('i'): the places no worker holds
    conn: Any
    owner: str  # the supervisor's id: the ``coordinator`` of the workers' gearopt rows
    previous: int = 0  # the study's trials when the run opened it (the samplers' seeds)
    lock: Any = None  # a multiprocessing Lock: one worker at a time asks Optuna for a trial
    #: the run's lock file for the workers' database writes (:func:`gearopt.storage.one_writer`)
    writes: str = ""

    @contextlib.contextmanager
    def asking(self):
        """One of the run's workers at a time in Optuna's ``Study.ask`` when given designs
        wait in the queue: it pops one by reading it WAITING and setting it RUNNING in two
        transactions, so on SQLite two workers asking at once (a run's start, with given
        designs queued) could both pop the same trial (under the lock, a worker whose read
        is older finds the trial RUNNING and asks the next). With none waiting, a worker
        creates its trial without the lock. A worker killed while it holds the lock does not
        stop the others for long: they wait at most :data:`ASK_WAIT_S`."""
        held = self.lock is not None and self.lock.acquire(timeout=ASK_WAIT_S)
        try:
            yield
        finally:
            if held:
                self.lock.release()

    def take(self) -> bool:
        """Take a place for a trial; False when every place is held."""
        with self.places.get_lock():
            if self.places.value <= 0:
                return False
            self.places.value -= 1
            return True

    def give(self) -> None:
        """Give back the place of a trial that did not complete."""
        with self.places.get_lock():
            self.places.value += 1

    def told(self, outcome) -> None:
        """A trial told: its evaluation time and whether it failed, for the run's figures."""
        self.conn.send(("told", outcome.seconds, outcome.failed))


def _worker(kind, spec: StudySpec, trials: int, url: str, role: WorkerRole, limit: int | None):
    """A worker process: one coordinator (``kind``: the supervisor's class, given rather than
    imported) on :class:`~gearopt.pools.InlineCalls`."""
    # what it inherited (modules, kernels) left out of its garbage collections, which would
    # otherwise go through it all and write to every page of it, shared with the supervisor
    # until written (Python's advice for a process forked without exec)
    gc.freeze()
    signal.signal(signal.SIGTERM, _interrupt)
    parent = os.getppid()
    threading.Thread(target=_watch_parent, args=(parent,), daemon=True).start()
    os.environ.setdefault("OMP_NUM_THREADS", "1")
    coordinator = kind(
        spec,
        trials=trials,
        jobs=1,
        storage=url,
        deterministic=False,
        progress=False,
        max_failures=limit,
        backend="inline",
        scheduler=None,
        role=role,
    )
    coordinator.me = role.owner  # its rows are the run's (its trials' tag stays its own)
    role.conn.send(("tag", coordinator.tag))
    try:
        coordinator.run(save_best=False)
    except KeyboardInterrupt:
        role.conn.send(("stopped",))
        return
    except GearoptError as exc:
        value = exc.value
        role.conn.send(("error", type(exc).__name__, exc.parameter, value, exc.rule))
        return
    role.conn.send(("done", coordinator.busy_cpu_s))


def _interrupt(signum, frame) -> None:
    raise KeyboardInterrupt


def _watch_parent(parent: int) -> None:
    """Stop this worker (as SIGTERM does) when its supervisor is gone."""
    while os.getppid() == parent:
        time.sleep(1.0)
    os.kill(os.getpid(), signal.SIGTERM)


@dataclass(kw_only=True)
class _Child:
    process: Any
    conn: Any
    stream: int
    tag: str | None = None
    finished: bool = False
    stopped: bool = False
    messages: list = field(default_factory=list)
    #: when it last told a trial (or started): its trial in hand was asked since, and its
    #: heartbeat recorded then
    told: float = field(default_factory=time.monotonic)


class Supervisor:
    """Runs ``coordinator``'s study (a :class:`gearopt.study.Coordinator` of ``jobs`` workers
    on loky, not deterministic) on workers that ask and tell themselves (the module's text)."""

    def __init__(self, coordinator) -> None:
        self.c = coordinator
        self.context = mp.get_context(START_METHOD)
        self.places = self.context.Value("i", 0)
        self.lock = self.context.Lock()
        self.children: list[_Child] = []
        self.streams = 0
        self.error: GearoptError | None = None

    def start(self) -> None:
        """Start a worker."""
        c = self.c
        ours, theirs = self.context.Pipe(duplex=False)
        # no database connection crosses a fork (SQLite's rule): the pool's are closed, and
        # made again when this process next reads
        c.opened.storage.engine.dispose()
        role = WorkerRole(
            stream=self.streams,
            places=self.places,
            conn=theirs,
            owner=c.me,
            previous=c.opened.previous,
            lock=self.lock,
            writes=os.path.join(c.markers, "writes.lock") if c.markers else "",
        )
        limit = c.limit
        process = self.context.Process(
            target=_worker, args=(type(c), c.spec, c.trials, c.url, role, limit), daemon=True
        )
        process.start()
        theirs.close()
        self.children.append(_Child(process=process, conn=ours, stream=self.streams))
        self.streams += 1

    def mine(self) -> set[str]:
        return {child.tag for child in self.children if child.tag is not None}

    def run(self) -> None:
        """The run (``coordinator.run`` does the opening and the summary around it)."""
        c = self.c
        complete, running = c.counts()
        self.places.value = max(c.trials - complete - running, 0)
        for _ in range(min(c.jobs, self.places.value)):
            self.start()
        try:
            self._watch()
        except BaseException as exc:
            self._stop(exc)
            raise

    def _watch(self) -> None:
        c = self.c
        mark, cpu = time.perf_counter(), time.thread_time()
        while True:
            live = [ch for ch in self.children if not ch.finished]
            if not live:
                complete, running = c.counts()
                missing = c.trials - complete - running
                if complete >= c.trials or self.error is not None:
                    break
                if missing > 0:  # places given back after the workers had left
                    with self.places.get_lock():
                        self.places.value = missing
                    for _ in range(min(c.jobs, missing)):
                        self.start()
                    continue
                # the rest runs on other coordinators, or was left RUNNING by a dead one
                # (recovered by the heartbeats, after the grace period)
                time.sleep(0.5)
                mark, cpu = time.perf_counter(), time.thread_time()
                if time.monotonic() - c.last_beat > HEARTBEAT_S:
                    self.beat()
                    c.last_beat = time.monotonic()
                continue
            c.busy_s += time.perf_counter() - mark
            c.busy_cpu_s += time.thread_time() - cpu
            sentinels = [ch.process.sentinel for ch in live]
            mpc.wait([ch.conn for ch in live] + sentinels, timeout=HEARTBEAT_S)
            mpc.wait(sentinels, timeout=TICK_S)  # (the messages of the next few trials)
            mark, cpu = time.perf_counter(), time.thread_time()
            for child in live:
                self._read(child)
                if not child.finished and child.process.exitcode is not None:
                    self._read(child)  # what it said before it ended
                    self._ended(child)
            if time.monotonic() - c.last_beat > HEARTBEAT_S:
                self.beat()
                c.last_beat = time.monotonic()
            if c.failed > c.limit and self.error is None:
                self.error = StudyError(
                    "study", c.spec.name, f"{c.failed} trials failed in this run (limit {c.limit})"
                )
            if self.error is not None:
                self._stop(self.error)
                break
        if self.error is not None:
            raise self.error

    def _read(self, child: _Child) -> None:
        c = self.c
        try:
            while child.conn.poll():
                message = child.conn.recv()
                kind = message[0]
                if kind == "tag":
                    child.tag = message[1]
                elif kind == "told":
                    child.told = time.monotonic()
                    c.evaluated += 1
                    c.worker_s += message[1]
                    c.failed += bool(message[2])
                    if c.bar is not None:
                        c.bar.update(1)
                elif kind == "done":
                    c.workers_cpu_s += message[1]
                    child.finished = True
                elif kind == "stopped":
                    child.finished = child.stopped = True
                elif kind == "error":
                    name, parameter, value, rule = message[1:]
                    cls = getattr(gearopt.errors, name, StudyError)
                    if self.error is None:
                        self.error = cls(parameter, value, rule)
                    child.finished = True
        except (EOFError, OSError):
            pass

    def _ended(self, child: _Child) -> None:
        """A worker that ended without saying so died: its trial failed (charged an attempt)
        and re-enqueued, and another worker takes its place."""
        child.finished = True
        child.process.join()
        if child.tag is None and self.error is None:  # it never started: no use starting more
            self.error = StudyError(
                "--jobs",
                self.c.jobs,
                f"a worker process ended before it started (exit code {child.process.exitcode})",
            )
            return
        failed = self._fail_trials_of(child, "its worker process died", charge=True)
        self.c.failed += failed
        if failed:
            with self.places.get_lock():
                self.places.value += failed
        if self.error is None:
            self.start()

    def _fail_trials_of(self, child: _Child, reason: str, *, charge: bool) -> int:
        c = self.c
        if child.tag is None:
            return 0
        o = c.opened
        requeue = o.requeue if charge else Requeue(c.spec, o.results, charge=False)
        done = 0
        for trial in c.study.get_trials(deepcopy=False, states=(TrialState.RUNNING,)):
            if trial.user_attrs.get(COORDINATOR) == child.tag:
                done += fail_and_requeue(c.study, o.storage, requeue, trial, reason)
        return done

    def beat(self) -> None:
        """The supervisor's heartbeat, its workers' trials' (a long evaluation does not stop
        them) and the recovery of other coordinators' trials."""
        c = self.c
        o = c.opened
        o.results.heartbeat(c.me, c.spec.name, c.host, c.pid)
        mine = self.mine()
        # a worker that told a trial less than a beat ago asked its trial in hand since (and
        # recorded its heartbeat then): only a longer trial needs one now
        now = time.monotonic()
        long = {ch.tag for ch in self.children if not ch.finished and now - ch.told > HEARTBEAT_S}
        running = running_trials(c.study, o.storage)
        for trial in running:
            if trial.user_attrs.get(COORDINATOR) in long - {None}:
                trial_id = o.storage.get_trial_id_from_study_id_trial_number(
                    o.study_id, trial.number
                )
                o.storage.record_heartbeat(trial_id)
        c.recovered += recover(
            c.study, o.storage, o.results, c.spec, c.tag, skip=mine, running=running
        )

    def _stop(self, exc: BaseException) -> None:
        """Stop the workers (they put their trials back uncharged); kill the ones that do not
        stop in time and put theirs back."""
        live = [ch for ch in self.children if ch.process.exitcode is None]
        for child in live:
            child.process.terminate()  # SIGTERM: a KeyboardInterrupt in the worker
        deadline = time.monotonic() + STOP_WAIT_S
        for child in live:
            child.process.join(max(deadline - time.monotonic(), 0.1))
            if child.process.exitcode is None:
                child.process.kill()
                child.process.join()
        reason = f"the coordinator stopped: {type(exc).__name__}: {exc}"
        for child in self.children:
            self._read(child)
            self._fail_trials_of(child, reason, charge=False)


def supervise(coordinator) -> None:
    """Run ``coordinator``'s loop as a :class:`Supervisor` of worker processes."""
    Supervisor(coordinator).run()
