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
