"""The compiled kernels' warm-up covers what a study trial runs: after
:func:`gearopt.warmup.warm_kernels` a trial of the example study compiles nothing (a kernel
called with argument types the warm-up did not use is compiled again, on the first trial of
every worker of a fresh install, inside the trials' statistics and ETA)."""

from __future__ import annotations

import sys

import pytest

from gearopt.studyfile import load_study_spec
from gearopt.trial import evaluate_trial
from gearopt.warmup import warm_kernels

from .conftest import STUDIES

numba = pytest.importorskip("numba")


def _signatures() -> dict[str, int]:
    """Every numba dispatcher of gearopt and its plugins, with its compiled signatures."""
    found = {}
    for name, module in list(sys.modules.items()):
        if not name.startswith(("gearopt", "gearopt_plugins")) or module is None:
            continue
        for attr, value in list(vars(module).items()):
            if isinstance(value, numba.core.dispatcher.Dispatcher):
                found[f"{name}.{attr}"] = len(value.signatures)
    return found


def test_a_study_trial_after_the_warm_up_compiles_no_kernel():
    spec = load_study_spec(STUDIES / "cyclo_palloid_contact.toml")
    warm_kernels(announce=False)
    before = _signatures()
    assert before, "no compiled kernel found"
    for number, params in enumerate(spec.enqueue):
        outcome = evaluate_trial(spec, number, dict(params))
        assert not outcome.failed, outcome.error
    after = _signatures()
    grown = {k: (before.get(k, 0), n) for k, n in after.items() if n > before.get(k, 0)}
    assert not grown, f"compiled after the warm-up (signatures before, after): {grown}"


def _recorded_processes(monkeypatch, compiled: int, earlier: int = 0) -> list:
    """The processes :func:`warm_kernels` starts, with ``earlier`` kernels compiled in this
    process before it and the probe's kernels counted as ``compiled`` (a first use, or a
    cached load)."""
    import itertools
    import subprocess

    import gearopt.warmup as warmup

    started, popen = [], subprocess.Popen

    def record(*args, **kwargs):
        started.append(popen(*args, **kwargs))
        return started[-1]

    monkeypatch.setattr(warmup.subprocess, "Popen", record)
    counts = itertools.chain([earlier], itertools.repeat(earlier + compiled))
    monkeypatch.setattr(warmup.jit, "compiled_here", lambda: next(counts))
    return started


def test_a_first_use_compiles_the_helper_group_in_a_second_process(monkeypatch):
    import gearopt.warmup as warmup

    started = _recorded_processes(monkeypatch, compiled=1)
    calls = []
    monkeypatch.setattr(warmup.contact_kernels, "warm", lambda: calls.append("contact"))
    monkeypatch.setattr(
        warmup.mesh_kernels, "warm", lambda: calls.append(("mesh", started[0].poll()))
    )
    warmup.warm_kernels(announce=False)
    # one helper, finished (its group warmed without error) before this process loads it
    assert len(started) == 1 and started[0].returncode == 0
    assert calls == ["contact", ("mesh", 0)]


def test_a_cached_warm_up_starts_no_process(monkeypatch):
    import gearopt.warmup as warmup

    started = _recorded_processes(monkeypatch, compiled=0)
    warmup.warm_kernels(announce=False)
    assert started == []


def test_a_cached_warm_up_after_other_compiles_in_the_process_starts_no_process(monkeypatch):
    # a process that compiled a kernel earlier (another signature, a test's) kept counting
    # it: every later warm-up started a helper process and said it compiled (stop 40's CI)
    import gearopt.warmup as warmup

    started = _recorded_processes(monkeypatch, compiled=0, earlier=3)
    warmup.warm_kernels(announce=False)
    assert started == []
