"""The worker pools of a study run (:func:`gearopt.study.run_study`): loky's reusable process
pool, joblib's dask backend in synchronous batches, or the coordinator's own process
(:class:`InlineCalls`, the workers of :mod:`gearopt.study_workers`); and which errors say a
worker died."""

from __future__ import annotations

import concurrent.futures as cf
from collections.abc import Callable
from concurrent.futures.process import BrokenProcessPool

import joblib
from joblib.externals.loky import get_reusable_executor
from joblib.externals.loky.process_executor import TerminatedWorkerError

from gearopt.errors import StudyError

__all__ = ["InlineCalls", "JoblibBatches", "Resubmit", "broken_pool", "worker_pool"]


def worker_pool(jobs: int, backend: str = "loky", scheduler: str | None = None):
    """The workers of a run: loky's reusable pool of ``jobs`` processes, or
    :class:`JoblibBatches` on a Dask cluster."""
    if backend == "dask":
        return JoblibBatches(jobs, scheduler)
    if backend == "inline":
        return InlineCalls()

    return get_reusable_executor(max_workers=jobs, timeout=60)


class InlineCalls:
    """Runs submitted calls in this process, in order, when :meth:`flush` is called (not when
    they are submitted: a stop signal then finds the trial in hand, not in a hand-over). A
    call's exception is its future's; a call that kills the process kills its coordinator."""

    def __init__(self) -> None:
        self.queue: list[tuple[cf.Future, Callable, tuple]] = []

    def submit(self, fn, *args) -> cf.Future:
        future: cf.Future = cf.Future()
        self.queue.append((future, fn, args))
        return future

    def flush(self) -> None:
        while self.queue:
            future, fn, args = self.queue.pop(0)
            try:
                result = fn(*args)
            except Exception as exc:  # noqa: BLE001 - the trial's own error, told as a failure
                future.set_exception(exc)
            else:
                future.set_result(result)

    def shutdown(self, wait: bool = True, **_) -> None:
        self.queue.clear()


class Resubmit(Exception):
    """A batch stopped before this task ran: submit it again."""


class JoblibBatches(InlineCalls):
    """Runs submitted calls in batches through joblib's ``dask`` backend on a Dask cluster
    (``scheduler``: its address; default a local cluster of ``jobs`` workers) and resolves
    their futures in order. A task that kills Dask workers ends as ``KilledWorker`` (Dask
    retries it on other workers first); the calls after it in the batch are resubmitted."""

    def __init__(self, jobs: int, scheduler: str | None) -> None:
        try:
            from dask.distributed import Client, LocalCluster
        except ImportError:
            raise StudyError("--backend", "dask", "needs dask: pip install -e '.[dask]'") from None
        if scheduler:
            self.client = Client(scheduler)
        else:
            cluster = LocalCluster(n_workers=jobs, threads_per_worker=1, processes=True)
            self.client = Client(cluster)
        super().__init__()
        self.jobs = jobs

    def flush(self) -> None:
        queue, self.queue = self.queue, []
        if not queue:
            return
        done = 0
        try:
            with joblib.parallel_config(backend="dask", n_jobs=self.jobs):
                results = joblib.Parallel(return_as="generator")(
                    joblib.delayed(fn)(*args) for _, fn, args in queue
                )
                for future, _ in zip((q[0] for q in queue), results, strict=False):
                    future.set_result(_)
                    done += 1
        except Exception as exc:  # noqa: BLE001 - the failing task's own error
            queue[done][0].set_exception(exc)
            for future, _, _ in queue[done + 1 :]:
                future.set_exception(Resubmit())


def broken_pool(exc: BaseException) -> bool:
    """A worker process died under the trial (loky), or the trial killed Dask workers."""

    return isinstance(exc, TerminatedWorkerError | BrokenProcessPool) or (
        type(exc).__name__ == "KilledWorker"
    )
