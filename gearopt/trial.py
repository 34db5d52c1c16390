"""One trial's evaluation: the pure work a study sends to its worker processes.

:func:`evaluate_trial` builds the trial's design from the base design and the suggested
parameters, runs the study's evaluations, turns them into objective and constraint values, and
flattens the results into rows for the dashboard tables (:mod:`gearopt.results`). It never
touches storage; a bad design is an outcome (``error``), not an exception.
"""

from __future__ import annotations

import math
import os
import tempfile
import time
import traceback
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from gearopt.analysis import AnalysisOptions
from gearopt.errors import GearoptError
from gearopt.plausibility import caught
from gearopt.plots import plot_evaluations
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


def pattern_outline(
    pattern_um: np.ndarray, face_mm: np.ndarray, profile_mm: np.ndarray, compound_um: float
) -> np.ndarray:
    """The contact pattern's outline as a closed polygon ``(k, 2)`` of (face, profile) mm: the
    lowest and highest marked node of each marked face column, toe to heel along the root side
    and back along the top side (empty when nothing is marked)."""
    marked = np.isfinite(pattern_um) & (pattern_um <= compound_um)
    cols = np.flatnonzero(marked.any(axis=1))
    if cols.size == 0:
        return np.zeros((0, 2))
    rows = marked[cols]
    low = profile_mm[np.argmax(rows, axis=1)]
    high = profile_mm[rows.shape[1] - 1 - np.argmax(rows[:, ::-1], axis=1)]
    face = face_mm[cols]
    return np.concatenate(
        [np.column_stack([face, low]), np.column_stack([face[::-1], high[::-1]])], axis=0
    )


#: the sides of the contact evaluators' arrays: drive unprefixed, coast ``coast_``
_SIDES = (("drive", ""), ("coast", "coast_"))


def _curves(label: str, evaluation) -> list[tuple]:
    """Rows of the curves table: the curves an evaluation carries by the array names the
    built-in evaluators use, and those it names itself
    (:attr:`gearopt.evaluation.Evaluation.curves`); non-finite points left out."""
    pairs = {
        "te": ("phi1_deg", "te_arcsec"),
        "path": ("path_face_mm", "path_profile_mm"),
        "backlash": ("phi1_deg", "circumferential_um"),
    }
    arrays = evaluation.arrays
    found: dict[str, dict] = {}
    for curve, (xk, yk) in pairs.items():
        for side, prefix in _SIDES:
            x, y = arrays.get(prefix + xk), arrays.get(prefix + yk)
            if x is not None and y is not None and np.shape(x) == np.shape(y):
                found.setdefault(curve, {})[side] = (x, y)
    return [
        (label, curve, side, i, float(a), float(b))
        for named in (found, evaluation.curves)
        for curve, by_side in named.items()
        for side, (x, y) in by_side.items()
        for i, (a, b) in enumerate(zip(np.ravel(x), np.ravel(y), strict=True))
        if math.isfinite(a) and math.isfinite(b)
    ]


def _patterns(label: str, evaluation) -> list[tuple]:
    """Pattern outlines of an evaluation that carries the ``tca`` evaluator's pattern arrays,
    at the marking compound of its conditions."""

    arrays = evaluation.arrays
    if "face_mm" not in arrays or "profile_mm" not in arrays:
        return []
    compound_um = float(evaluation.conditions.get("compound_um", AnalysisOptions.compound_um))
    rows = []
    for side, prefix in _SIDES:
        if prefix + "pattern_um" not in arrays:
            continue
        outline = pattern_outline(
            arrays[prefix + "pattern_um"], arrays["face_mm"], arrays["profile_mm"], compound_um
        )
        rows += [(label, side, i, float(f), float(p)) for i, (f, p) in enumerate(outline)]
    return rows


def _settings(design) -> list[tuple[str, str, float]]:

    settings = get_machine_model(design.model).basic_settings(design).as_dict()
    return [
        (member, key, float(value))
        for member in ("pinion", "gear")
        for key, value in settings[member].items()
        if isinstance(value, int | float) and not isinstance(value, bool)
    ]


def _figures(spec: StudySpec, design, evaluations) -> list[tuple[str, bytes]]:
    """The trial's PNG figures (:func:`gearopt.plots.plot_evaluations`) as (name, bytes)."""

    with tempfile.TemporaryDirectory() as folder:
        paths = plot_evaluations(evaluations, folder, f"{spec.name}: {design.name}")
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
