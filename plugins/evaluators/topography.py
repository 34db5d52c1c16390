"""Flank topography against a target on a measuring grid: an evaluator and an objective.

A study that should cut a prescribed topography (a measured gear to reproduce, a designed
ease-off, the corrective cut of a closed loop) measures each trial's flanks on the nominal grid
of a reference design (:mod:`gearopt.measurement`) and minimises their distance from the target.

Evaluator ``topography``, conditions:

``member``
    ``"pinion"`` or ``"gear"`` (required).
``reference``
    The reference design file whose nominal grid and flanks the deviations refer to (required;
    a relative path is taken from the trial design's folder, i.e. the study's base design's).
``target``
    A measured-deviation CSV file on that grid (``flank,i_face,i_profile,deviation_um``, as
    ``gearopt correct`` reads it); default: none, i.e. the reference's own flanks (deviation 0).
``points``, ``margin_mm``
    The grid (``"9x5"`` and a tenth of the whole depth by default), as ``gearopt grid``.

Metrics (:mod:`gearopt.declarations`): ``topography.rms_um`` over both flanks' target points,
``topography.max_um`` the largest distance, ``topography.convex_rms_um`` and
``topography.concave_rms_um``; a point the trial's tool does not generate counts as missing by
its target's magnitude plus 10 um.

Objective ``topography``: the ``topography.rms_um`` of the evaluation ``on`` (label, default
``"topography"``), or of one ``flank`` (``"convex"``, ``"concave"``, default ``"both"``).
"""

from __future__ import annotations

from collections.abc import Mapping
from functools import lru_cache
from pathlib import Path
from typing import Any

import numpy as np

from gearopt import hookimpl
from gearopt.declarations import Metric, Option, check_options
from gearopt.design_files import load_design
from gearopt.errors import DesignError
from gearopt.evaluation import BaseEvaluator, BaseObjective, Evaluation
from gearopt.flank import FLANKS, MEMBERS
from gearopt.measurement.files import read_measured
from gearopt.measurement.grid import parse_points
from gearopt.measurement.topography import nominal_measurement

#: the distance a target point counts for when the trial does not generate it (um, added to
#: the target's magnitude)
MISSING_UM = 10.0
OPTIONS = (
    Option(
        name="member", kind="string", choices=MEMBERS, required=True, description="pinion or gear"
    ),
    Option(
        name="reference",
        kind="string",
        required=True,
        description="design file whose nominal grid the deviations refer to",
    ),
    Option(name="target", kind="string", description="measured-deviation CSV (default: none, 0)"),
    Option(name="points", default="9x5", kind="string", description="grid NFxNP"),
    Option(
        name="margin_mm",
        kind="number",
        lower=0.0,
        description="margin inside the blank's lines (default: a tenth of the whole depth)",
    ),
)


def _path(design, value: Any, where: str) -> Path:
    if not isinstance(value, str) or not value:
        raise DesignError(f"topography.{where}", value, "must be a file path")
    path = Path(value)
    if not path.is_absolute() and design.path:
        path = Path(design.path).parent / path
    if not path.is_file():
        raise DesignError(f"topography.{where}", value, f"no such file ({path})")
    return path


def _options(design, conditions: Mapping[str, Any] | None) -> dict:
    conditions = dict(conditions or {})
    check_options(OPTIONS, conditions, "conditions")
    target = conditions.get("target")
    margin = conditions.get("margin_mm")
    return {
        "member": conditions["member"],
        "reference": str(_path(design, conditions["reference"], "reference")),
        "target": None if target is None else str(_path(design, target, "target")),
        "points": parse_points(conditions.get("points", "9x5")),
        "margin_mm": None if margin is None else float(margin),
    }


@lru_cache(maxsize=8)
def _reference(reference: str, member: str, points, margin_mm, target):
    nominal = nominal_measurement(
        load_design(reference), member, points=points, margin_mm=margin_mm
    )
    if target is None:
        wanted = {f: np.where(nominal.points[f].generated, 0.0, np.nan) for f in FLANKS}
    else:
        wanted = read_measured(target, nominal.grid.shape)
    return nominal, wanted


class TopographyEvaluator(BaseEvaluator):
    """Distance of a member's flanks from a target topography on a measuring grid."""

    name = "topography"
    description = "flank topography against a target on a reference design's measuring grid"
    section = "topography"
    metrics = (
        Metric(name="rms_um", unit="um", description="RMS distance from the target, both flanks"),
        Metric(name="max_um", unit="um", description="largest distance from the target"),
        Metric(name="convex_rms_um", unit="um", description="RMS distance, convex flank"),
        Metric(name="concave_rms_um", unit="um", description="RMS distance, concave flank"),
    )
    options = OPTIONS

    def check_conditions(self, design, conditions: Mapping[str, Any]) -> None:
        """The declared options, and the files must exist."""
        _options(design, conditions)

    def evaluate(self, design, conditions: Mapping[str, Any] | None = None) -> Evaluation:
        options = _options(design, conditions)
        nominal, wanted = _reference(
            options["reference"],
            options["member"],
            options["points"],
            options["margin_mm"],
            options["target"],
        )
        dev = nominal.deviations(design)
        metrics, worst, squares, count = {}, 0.0, 0.0, 0
        for flank, target in wanted.items():
            given = np.isfinite(target)
            value, ok = dev[flank]
            miss = np.where(ok, np.abs(value - np.where(given, target, 0.0)), 0.0)
            miss = np.where(ok, miss, np.abs(np.nan_to_num(target)) + MISSING_UM)[given]
            metrics[f"topography.{flank}_rms_um"] = (
                float(np.sqrt(np.mean(miss**2))) if miss.size else 0.0
            )
            worst = max(worst, float(miss.max()) if miss.size else 0.0)
            squares += float(np.sum(miss**2))
            count += int(miss.size)
        metrics["topography.rms_um"] = float(np.sqrt(squares / count)) if count else 0.0
        metrics["topography.max_um"] = worst
        return Evaluation(
            evaluator=self.name,
            metrics=metrics,
            report={"topography": {k.split(".", 1)[1]: v for k, v in metrics.items()}},
            conditions={
                **options,
                "points": "x".join(map(str, options["points"])),
            },
        )


class TopographyObjective(BaseObjective):
    """RMS distance of the flanks from the target topography (um)."""

    name = "topography"
    description = "RMS distance (um) of a member's flanks from a target topography"
    requires = ("topography",)
    options = (
        Option(name="on", default="topography", kind="label", description="the evaluation"),
        Option(
            name="flank",
            default="both",
            kind="string",
            choices=("both", *FLANKS),
            description="both flanks or one",
        ),
    )

    def reads(self, **options: Any) -> dict[str, str]:
        super().reads(**options)
        return {options.get("on", "topography"): "topography"}

    def value(self, evaluations, **options) -> float:
        flank = options.get("flank", "both")
        key = "topography.rms_um" if flank == "both" else f"topography.{flank}_rms_um"
        return float(evaluations[options.get("on", "topography")].metrics[key])


@hookimpl
def gearopt_evaluators() -> list[BaseEvaluator]:
    """The topography evaluator."""
    return [TopographyEvaluator()]


@hookimpl
def gearopt_objectives() -> list[BaseObjective]:
    """The topography objective."""
    return [TopographyObjective()]
