"""The compiled kernels warmed once in a process (compiled, or loaded from numba's disk cache)
before work that needs them: a study's coordinator does it before its workers start, so that
they load the cache rather than compile it side by side (numba's cache is not safe for
concurrent writers), and before the trials' clock.

After an install (nothing in the cache yet) the compile takes minutes of CPU; it is split over
two processes: this one compiles the FlankMap, determinant and contact engine kernels and the
machine models', a helper process (:func:`warm_group` ``"helper"``) the marking-compound
zone's, the mesh cycle's and the loaded contact's at the same time. The two groups write disjoint
modules' cache files (a kernel inlined from another module, ``compiled(inline=True)``, writes no
cache file of its own); this process loads the helper's kernels after it has finished."""

from __future__ import annotations

import subprocess
import sys
import threading
import time

from gearopt import determinants, envelope_nodes, flank, jit
from gearopt.contact import kernel_warmup as contact_kernels
from gearopt.loaded import kernels as loaded_kernels
from gearopt.loaded import lcp_kernels
from gearopt.mesh import handover_kernels, side_kernels
from gearopt.mesh import kernels as mesh_kernels
from gearopt.plugins import machine_models

__all__ = ["ANNOUNCE_AFTER_S", "warm_group", "warm_kernels"]

#: seconds after which :func:`warm_kernels` says on stderr that it compiles (a load from the
#: cache takes 0.7-1.3 s on a 2-core machine, and up to 2.5 s where the machine models' plugins
#: are imported with it: only a compile takes longer)
ANNOUNCE_AFTER_S = 3.0


def _models() -> None:
    for model in machine_models().values():  # the models' own (flank generation)
        model.warm_kernels()


def _stages() -> dict[str, tuple]:
    """The warm-up's stages by group: ``"probe"`` (small, run first here: whether it compiled
    tells a first use), ``"main"`` (here, beside the helper), ``"helper"`` (the helper
    process's), ``"after"`` (here, after the helper: every kernel not yet warmed here, loaded
    from the cache where the helper compiled it). The groups' compile times are about equal
    (50-60 s of CPU each on the example's machine)."""
    return {
        "probe": (flank.warm_kernels, determinants.warm_kernels, envelope_nodes.warm_kernels),
        "main": (contact_kernels.warm_engine, _models),
        "helper": (
            contact_kernels.warm_zones,
            mesh_kernels.warm,
            handover_kernels.warm,
            side_kernels.warm,
            loaded_kernels.warm,
            lcp_kernels.warm,
        ),
        "after": (
            contact_kernels.warm,
            mesh_kernels.warm,
            handover_kernels.warm,
            side_kernels.warm,
            loaded_kernels.warm,
            lcp_kernels.warm,
        ),
    }


def warm_group(name: str) -> None:
    """Warm one group of :func:`warm_kernels`' stages in this process (the helper process
    runs ``"helper"``)."""
    for stage in _stages()[name]:
        stage()


def _start_helper() -> subprocess.Popen | None:
    """The helper process compiling the ``"helper"`` group, or None where it cannot start
    (this process then compiles the group itself)."""
    code = "from gearopt.warmup import warm_group; warm_group('helper')"
    try:
        return subprocess.Popen(
            [sys.executable, "-c", code],
            stdin=subprocess.DEVNULL,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )
    except OSError:
        return None


def warm_kernels(*, announce: bool = True) -> float:
    """Compile every compiled kernel (FlankMap cells, contact engine, mesh cycle, loaded
    contact, the machine models' :meth:`~gearopt.machine.BaseMachineModel.warm_kernels`) in this
    process, or load it from numba's disk cache, and return the seconds it took. A first use
    after an install compiles them (about a minute, in two processes); ``announce``: said on
    stderr when it takes longer than :data:`ANNOUNCE_AFTER_S` (a cached load takes less)."""
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
    stages = _stages()
    helper = None
    try:
        before = jit.compiled_here()  # (a process's count: earlier compiles stay in it)
        for stage in stages["probe"]:
            stage()
        if jit.compiled_here() > before:  # a first use: the helper's group compiled beside
            helper = _start_helper()
        for stage in stages["main"]:
            stage()
        if helper is not None:
            helper.wait()
            helper = None
        for stage in stages["after"]:
            stage()
    finally:
        if helper is not None:  # interrupted: no writer left behind (numba writes atomically)
            helper.kill()
            helper.wait()
        if timer is not None:
            timer.cancel()
    seconds = time.perf_counter() - start
    if said.is_set():
        print(f"gearopt: kernels compiled in {seconds:.1f} s", file=sys.stderr, flush=True)
    return seconds
