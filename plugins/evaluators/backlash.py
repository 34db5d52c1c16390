"""Backlash along the mesh: an evaluator plugin on the contact engine.

At each contact position of the drive side the pinion is held and the gear turned forward
until its other flanks touch the pinion's (seed 001 section 5); the circumferential backlash is
that rotation times the gear's outer pitch radius m_ot N2 / 2. Interference (overlapping
flanks) is a negative backlash with ``interference`` = 1, never NaN.

Conditions: as the ``tca`` evaluator (:class:`gearopt.analysis.AnalysisOptions`).

Metrics: ``backlash_min_um``, ``backlash_mean_um``, ``backlash_max_um``, ``interference``
(0/1). Arrays: ``phi1_deg``, ``circumferential_um``.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from gearopt import hookimpl
from gearopt.analysis import AnalysisOptions, meshed_pair, pair_backlash
from gearopt.evaluation import BaseEvaluator, Evaluation
from gearopt.plausibility import contact_findings


class BacklashEvaluator(BaseEvaluator):
    """Circumferential backlash at the drive side's contact positions."""

    name = "backlash"
    description = "circumferential backlash along the mesh, interference flagged"

    def check_conditions(self, design, conditions: Mapping[str, Any]) -> None:
        """The contact analyses' options (:class:`~gearopt.analysis.AnalysisOptions`)."""
        AnalysisOptions.from_conditions(conditions, design=design)

    def evaluate(self, design, conditions: Mapping[str, Any] | None = None) -> Evaluation:
        options = AnalysisOptions.from_conditions(conditions, design=design)
        result = pair_backlash(meshed_pair(design, options), options)
        report = result.as_dict()
        return Evaluation(
            evaluator=self.name,
            metrics={
                "backlash_min_um": report["min_um"],
                "backlash_mean_um": report["mean_um"],
                "backlash_max_um": report["max_um"],
                "interference": float(result.interference),
            },
            arrays={"phi1_deg": result.phi1_deg, "circumferential_um": result.circumferential_um},
            conditions=options.as_dict(),
            report={"backlash": report},
            warnings=tuple(contact_findings({"backlash": report}, strict=False)),
        )


@hookimpl
def gearopt_evaluators() -> list[BaseEvaluator]:
    """The backlash evaluator."""
    return [BacklashEvaluator()]
