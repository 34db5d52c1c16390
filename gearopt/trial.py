"""One trial's evaluation: the pure work a study sends to its worker processes.

:func:`evaluate_trial` builds the trial's design from the base design and the suggested
parameters, runs the study's evaluations, turns them into objective and constraint values, and
flattens the results into rows for the dashboard tables (:mod:`gearopt.results`). It never
touches storage; a bad design is an outcome (``error``), not an exception.
"""

from __future__ import annotations

import dataclasses
import math
import os
import tempfile
import time
import traceback
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from gearopt.declarations import pattern_outline
from gearopt.errors import GearoptError
from gearopt.plausibility import caught
from gearopt.plots import DEDICATED_FIGURES, plot_evaluations
from gearopt.plots_declared import plot_declared
from gearopt.plugins import evaluators, get_machine_model, objectives
from gearopt.studyfile import StudySpec

__all__ = ["TrialOutcome", "evaluate_trial", "pattern_outline"]


@dataclass(frozen=True, kw_only=True)
class TrialOutcome:
    """What a worker returns for one trial.

        ``values`` are the objectives in the study's order (``None`` when the trial failed),
        ``constraints`` the constraint values by label (feasible when <= 0). The row lists feed
        the dashboard tables: ``metrics`` (evaluation, metric, value), ``curves`` (evaluation,
        curve, side, index, x, y), ``patterns`` (evaluation, side, index, face_mm, profile_mm),
        ``settings`` (member, key, value); ``figures`` the PNG files (name, bytes) a study with
        ``artifacts = true`` stores as Optuna artifacts; ``warnings`` the evaluations' (each
    labelled) and the numerical ones raised while evaluating. ``error`` says why it failed.
    """

    number: int
    values: tuple[float, ...] | None = None
    constraints: Mapping[str, float] = field(default_factory=dict)
    metrics: list[tuple[str, str, float]] = field(default_factory=list)
    curves: list[tuple[str, str, str, int, float, float]] = field(default_factory=list)
    patterns: list[tuple[str, str, int, float, float]] = field(default_factory=list)
    settings: list[tuple[str, str, float]] = field(default_factory=list)
    figures: list[tuple[str, bytes]] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)
    error: str | None = None
    seconds: float = 0.0
    pid: int = 0

    @property
    def failed(self) -> bool:
        return self.values is None


def _curves(label: str, evaluation) -> list[tuple]:
    """Rows of the curves table: the curves the evaluation carries (its evaluator's declared
    :attr:`~gearopt.evaluation.BaseEvaluator.curves`), non-finite points left out."""
    rows = []
    for curve, by_side in evaluation.curves.items():
        for side, (x, y) in by_side.items():
            x, y = np.ravel(np.asarray(x, float)), np.ravel(np.asarray(y, float))
            if x.size != y.size:
                raise ValueError(f"curve {curve!r} ({side}): x and y of different lengths")
            keep = np.flatnonzero(np.isfinite(x) & np.isfinite(y))
            rows += [
                (label, curve, side, i, a, b)
                for i, a, b in zip(keep.tolist(), x[keep].tolist(), y[keep].tolist(), strict=True)
            ]
    return rows


def _patterns(label: str, evaluation) -> list[tuple]:
    """Rows of the patterns table: the pattern outline of each side the evaluation carries
    (its evaluator's declared :attr:`~gearopt.evaluation.BaseEvaluator.pattern`)."""
    return [
        (label, side, i, f, p)
        for side, outline in evaluation.patterns.items()
        for i, (f, p) in enumerate(np.asarray(outline, float).tolist())
    ]


def _settings(design) -> list[tuple[str, str, float]]:
    """Rows of the settings table: each member's scalar settings (the numbers of
    :meth:`~gearopt.machine.MachineSettings.as_dict`, read off the fields without its copies)."""
    settings = get_machine_model(design.model).basic_settings(design)
    rows = []
    for member in ("pinion", "gear"):
        of = getattr(settings, member)
        for f in dataclasses.fields(of):
            value = getattr(of, f.name)
            if isinstance(value, int | float) and not isinstance(value, bool):
                rows.append((member, f.name, float(value)))
    return rows


def _figures(spec: StudySpec, design, evaluations) -> list[tuple[str, bytes]]:
    """The trial's PNG figures (:func:`gearopt.plots.plot_evaluations`, and
    :func:`gearopt.plots_declared.plot_declared` for the other evaluators) as (name, bytes)."""

    title = f"{spec.name}: {design.name}"
    rest = {k: e for k, e in evaluations.items() if e.evaluator not in DEDICATED_FIGURES}
    with tempfile.TemporaryDirectory() as folder:
        paths = plot_evaluations(evaluations, folder, title, design=design)
        paths += plot_declared(rest, evaluators(), folder, title=title)
        return [(p.name, p.read_bytes()) for p in paths]


def evaluate_trial(spec: StudySpec, number: int, params: Mapping[str, float]) -> TrialOutcome:
    """Evaluate trial ``number`` of ``spec`` with the searched keys set to ``params``.

    A design the model refuses, or an evaluation that raises a
    :class:`~gearopt.errors.GearoptError`, gives a failed outcome naming the error; any other
    exception too, with its traceback's last lines (a bug, to be reported). Objective values
    that are not finite fail the trial as well, so Optuna never sees a NaN.
    """

    start = time.perf_counter()
    pid = os.getpid()
    try:
        installed = evaluators()
        with caught() as numerical:  # numerical warnings and legal-but-unusual designs
            design = spec.design_for(params)
            evaluations = {
                e.label: installed[e.evaluator].evaluate(design, e.conditions)
                for e in spec.evaluations
            }
        found = [f"{label}: {w}" for label, e in evaluations.items() for w in e.warnings]
        plugins = objectives()
        values = tuple(
            float(plugins[o.name].value(evaluations, **o.options)) for o in spec.objectives
        )
        constraints = {
            c.label: float(plugins[c.name].value(evaluations, **c.options))
            for c in spec.constraints
        }
        bad = [v for v in (*values, *constraints.values()) if not math.isfinite(v)]
        if bad:
            raise GearoptError("objectives", bad, "an objective or constraint is not finite")
        metrics, curves, patterns = [], [], []
        for label, evaluation in evaluations.items():
            metrics += [(label, k, float(v)) for k, v in evaluation.metrics.items()]
            curves += _curves(label, evaluation)
            patterns += _patterns(label, evaluation)
        return TrialOutcome(
            number=number,
            values=values,
            constraints=constraints,
            metrics=metrics,
            curves=curves,
            patterns=patterns,
            settings=_settings(design),
            figures=_figures(spec, design, evaluations) if spec.artifacts else [],
            warnings=found + numerical,
            seconds=time.perf_counter() - start,
            pid=pid,
        )
    except GearoptError as exc:
        error = f"{type(exc).__name__}: {exc}"
    except Exception as exc:  # a bug in a plugin: fail the trial, keep the study going
        tail = "".join(traceback.format_exception(exc)[-3:])
        error = f"{type(exc).__name__}: {exc}\n{tail}"
    return TrialOutcome(number=number, error=error, seconds=time.perf_counter() - start, pid=pid)


def work(spec: StudySpec, number: int, params: Mapping[str, Any], marker_dir: str | None):
    """The task a worker runs: mark the trial as started by this process (so a coordinator can
    tell which trial a dead worker held), then :func:`evaluate_trial`."""
    if marker_dir:
        with open(os.path.join(marker_dir, f"{number}.pid"), "w") as f:
            f.write(str(os.getpid()))
    return evaluate_trial(spec, number, params)
