"""Unloaded tooth contact analysis and ease-off: evaluator plugins on the contact engine.

``tca`` runs the TCA of both sides (drive: pinion convex driving gear concave; coast: pinion
concave driving gear convex) over two mesh cycles; ``ease-off`` measures the pinion flanks'
deviation from the surfaces conjugate to the gear. Definitions: :mod:`gearopt.mesh`.

Conditions (all optional; :class:`gearopt.analysis.AnalysisOptions`)::

    positions = 21            # contact positions over `cycles` mesh cycles
    pairs = 3                 # tooth pairs at each position
    cycles = 2.0
    compound_um = 6.5         # marking compound of the pattern
    separation = "normal"     # or "circumferential" (seed 003)
    grid = [25, 21]           # FlankMap grid [n_face, n_profile]
    misalignment = {offset_mm = 0.1, ...}   # default: the design's [misalignment]

``tca`` metrics (drive side; the coast side the same names prefixed ``coast_``):
``te_peak_to_peak_arcsec``, ``pattern_width_mm``, ``pattern_bias_mm``,
``pattern_center_offset_face_mm``, ``pattern_center_offset_profile_mm``, ``edge_contact``
(0/1), ``contact_ratio``. Arrays: ``phi1_deg``, ``te_arcsec``, ``path_face_mm``,
``path_profile_mm``, ``pattern_um`` (the least separation of each pinion node over the
mesh, inf off the flanks), ``flank_mask`` (generated pinion nodes), ``face_mm`` and
``profile_mm`` (pattern coordinates of the grid), and the ``coast_*`` of each. With a
``[te_target]`` in the design (drive side): metrics ``te_target_max_deviation_arcsec`` and
``te_target_rms_deviation_arcsec``, array ``te_target_arcsec`` (:func:`gearopt.te_target.compare`).

``ease-off`` metrics: ``ease_off_max_um`` and ``coast_ease_off_max_um`` (the largest ease-off
over the flank where it is defined); arrays ``ease_off_um`` and ``coast_ease_off_um``. The
ease-off is a property of the flanks: it is measured in the nominal assembly whatever the
``misalignment`` condition says.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import replace
from typing import Any

from gearopt import hookimpl
from gearopt.analysis import (
    AnalysisOptions,
    contact_sides,
    meshed_pair,
    pair_ease_off,
)
from gearopt.design import Misalignment
from gearopt.evaluation import BaseEvaluator, Evaluation
from gearopt.mesh import ToothContact
from gearopt.plausibility import contact_findings
from gearopt.te_target import compare


def contact_metrics(result: ToothContact, prefix: str = "") -> dict[str, float]:
    """The scalar metrics of one side's TCA."""
    return {
        f"{prefix}te_peak_to_peak_arcsec": result.te_peak_to_peak_arcsec,
        f"{prefix}pattern_width_mm": result.width_mm,
        f"{prefix}pattern_bias_mm": result.bias_mm,
        f"{prefix}pattern_center_offset_face_mm": result.center_offset_mm[0],
        f"{prefix}pattern_center_offset_profile_mm": result.center_offset_mm[1],
        f"{prefix}edge_contact": float(result.edge_contact),
        f"{prefix}contact_ratio": result.contact_ratio,
    }


class TcaEvaluator(BaseEvaluator):
    """Unloaded TCA of both sides: TE, contact path and pattern (seed 001 section 5)."""

    name = "tca"
    description = "unloaded TCA of drive and coast sides: TE, contact path, pattern"

    def check_conditions(self, design, conditions: Mapping[str, Any]) -> None:
        """The contact analyses' options (:class:`~gearopt.analysis.AnalysisOptions`)."""
        AnalysisOptions.from_conditions(conditions, design=design)

    def evaluate(self, design, conditions: Mapping[str, Any] | None = None) -> Evaluation:
        options = AnalysisOptions.from_conditions(conditions, design=design)
        pair = meshed_pair(design, options)
        sides = contact_sides(pair, options)
        drive, coast = sides["drive"], sides["coast"]
        arrays = {"face_mm": drive.face_mm, "profile_mm": drive.profile_mm}
        for prefix, side, field in (("", drive, pair.drive), ("coast_", coast, pair.coast)):
            arrays[f"{prefix}phi1_deg"] = side.phi1_deg
            arrays[f"{prefix}te_arcsec"] = side.te_arcsec
            arrays[f"{prefix}path_face_mm"] = side.path_face_mm
            arrays[f"{prefix}path_profile_mm"] = side.path_profile_mm
            arrays[f"{prefix}pattern_um"] = side.pattern_um
            arrays[f"{prefix}flank_mask"] = field.pinion.mask
        metrics = {**contact_metrics(drive), **contact_metrics(coast, "coast_")}
        report = {"tca": drive.as_dict(), "tca_coast": coast.as_dict()}
        if design.te_target is not None:  # the designed TE (drive side) beside the achieved
            versus = compare(
                design.te_target, drive.phi1_deg, drive.te_arcsec, drive.handover_phi1_deg
            )
            arrays["te_target_arcsec"] = versus["te_target_arcsec"]
            for key in ("te_target_max_deviation_arcsec", "te_target_rms_deviation_arcsec"):
                metrics[key] = versus[key]
            report["tca"]["te_target_arcsec"] = [float(v) for v in versus["te_target_arcsec"]]
            report["tca"]["te_target_max_deviation_arcsec"] = versus[
                "te_target_max_deviation_arcsec"
            ]
        return Evaluation(
            evaluator=self.name,
            metrics=metrics,
            arrays=arrays,
            conditions=options.as_dict(),
            report=report,
            warnings=tuple(contact_findings(report, strict=False)),
        )


class EaseOffEvaluator(BaseEvaluator):
    """The pinion flanks' normal deviation from the surfaces conjugate to the gear."""

    name = "ease-off"
    description = "pinion ease-off of drive and coast flanks against the conjugate surfaces"

    def check_conditions(self, design, conditions: Mapping[str, Any]) -> None:
        """The contact analyses' options (:class:`~gearopt.analysis.AnalysisOptions`)."""
        AnalysisOptions.from_conditions(conditions, design=design)

    def evaluate(self, design, conditions: Mapping[str, Any] | None = None) -> Evaluation:
        options = AnalysisOptions.from_conditions(conditions, design=design)
        # the deviation from the conjugate surface is a property of the flanks: nominal assembly
        options = replace(options, misalignment=Misalignment())
        result = pair_ease_off(meshed_pair(design, options))
        drive, coast = result["drive"], result["coast"]
        return Evaluation(
            evaluator=self.name,
            metrics={
                "ease_off_max_um": float(drive.ease_off_um[drive.mask].max(initial=0.0)),
                "coast_ease_off_max_um": float(coast.ease_off_um[coast.mask].max(initial=0.0)),
            },
            arrays={"ease_off_um": drive.ease_off_um, "coast_ease_off_um": coast.ease_off_um},
            conditions=options.as_dict(),
            report={"ease_off": {"drive": drive.as_dict(), "coast": coast.as_dict()}},
        )


@hookimpl
def gearopt_evaluators() -> list[BaseEvaluator]:
    """The TCA and ease-off evaluators."""
    return [TcaEvaluator(), EaseOffEvaluator()]
