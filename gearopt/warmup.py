"""The compiled kernels warmed once in a process (compiled, or loaded from numba's disk cache)
before work that needs them: a study's coordinator does it before its workers start, so that
they load the cache rather than compile it side by side (numba's cache is not safe for
concurrent writers), and before the trials' clock."""

from __future__ import annotations

import sys
import threading
import time

from gearopt import determinants, flank
from gearopt.contact import kernel_warmup as contact_kernels
from gearopt.loaded import kernels as loaded_kernels
from gearopt.loaded import lcp_kernels
from gearopt.mesh import kernels as mesh_kernels
from gearopt.plugins import machine_models

__all__ = ["ANNOUNCE_AFTER_S", "warm_kernels"]

#: seconds after which :func:`warm_kernels` says on stderr that it compiles
ANNOUNCE_AFTER_S = 1.0


def warm_kernels(*, announce: bool = True) -> float:
    """Compile every compiled kernel (FlankMap cells, contact engine, mesh cycle, loaded
    contact, the machine models' :meth:`~gearopt.machine.BaseMachineModel.warm_kernels`) in this
    process, or load it from numba's disk cache, and return the seconds it took. A first use
    after an install compiles them (about half a minute); ``announce``: said on stderr when it
    takes longer than :data:`ANNOUNCE_AFTER_S` (a cached load takes well under a second)."""
    start = time.perf_counter()
    said = threading.Event()

    def say() -> None:
        said.set()
        print(
            "gearopt: compiling the numerical kernels (once after an install; later runs load "
            "them from the cache) ...",
            file=sys.stderr,
            flush=True,
        )

    timer = threading.Timer(ANNOUNCE_AFTER_S, say) if announce else None
    if timer is not None:
        timer.daemon = True
        timer.start()
    try:
        flank.warm_kernels()
        determinants.warm_kernels()
        contact_kernels.warm()
        mesh_kernels.warm()
        loaded_kernels.warm()
        lcp_kernels.warm()
        for model in machine_models().values():  # the models' own (flank generation)
            model.warm_kernels()
    finally:
        if timer is not None:
            timer.cancel()
    seconds = time.perf_counter() - start
    if said.is_set():
        print(f"gearopt: kernels compiled in {seconds:.1f} s", file=sys.stderr, flush=True)
    return seconds
