"""Backlash along the mesh: an evaluator plugin on the contact engine.

At each contact position of the drive side the pinion is held and the gear turned forward
until its other flanks touch the pinion's (seed 001 section 5); the circumferential backlash is
that rotation times the gear's outer pitch radius m_ot N2 / 2. Interference (overlapping
flanks) is a negative backlash with ``interference`` = 1, never NaN.

Conditions: as the ``tca`` evaluator (:class:`gearopt.analysis.AnalysisOptions`).

Metrics (the report's places, :mod:`gearopt.declarations`): ``backlash.min_um``,
``backlash.mean_um``, ``backlash.max_um``, ``backlash.interference`` (0/1),
``backlash.radius_mm``. Curve ``backlash``. Arrays: ``phi1_deg``, ``circumferential_um``.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from gearopt import hookimpl
from gearopt.analysis import AnalysisOptions, meshed_pair, pair_backlash
from gearopt.analysis_options import ANALYSIS_OPTIONS
from gearopt.declarations import Curve, Metric, report_metrics
from gearopt.evaluation import BaseEvaluator, Evaluation
from gearopt.plausibility import contact_findings


class BacklashEvaluator(BaseEvaluator):
    """Circumferential backlash at the drive side's contact positions."""

    name = "backlash"
    description = "circumferential backlash along the mesh, interference flagged"
    section = "backlash"
    metrics = (
        Metric(name="min_um", unit="um", description="least circumferential backlash"),
        Metric(name="mean_um", unit="um", description="mean circumferential backlash"),
        Metric(name="max_um", unit="um", description="largest circumferential backlash"),
        Metric(name="interference", description="overlapping flanks somewhere (0/1)"),
        Metric(name="radius_mm", unit="mm", description="radius the backlash is measured at"),
    )
    curves = (
        Curve(
            name="backlash",
            x="phi1_deg",
            y="circumferential_um",
            x_unit="deg",
            y_unit="um",
            description="circumferential backlash at the drive side's positions",
        ),
    )
    options = ANALYSIS_OPTIONS
    analysis = True

    def evaluate(self, design, conditions: Mapping[str, Any] | None = None) -> Evaluation:
        options = AnalysisOptions.from_conditions(conditions, design=design)
        result = pair_backlash(meshed_pair(design, options), options)
        report = {"backlash": result.as_dict()}
        return Evaluation(
            evaluator=self.name,
            metrics=report_metrics(self, report),
            arrays={"phi1_deg": result.phi1_deg, "circumferential_um": result.circumferential_um},
            conditions=options.as_dict(),
            report=report,
            curves={"backlash": {"drive": (result.phi1_deg, result.circumferential_um)}},
            warnings=tuple(contact_findings(report, strict=False)),
        )


@hookimpl
def gearopt_evaluators() -> list[BaseEvaluator]:
    """The backlash evaluator."""
    return [BacklashEvaluator()]
