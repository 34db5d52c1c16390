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

``tca`` metrics: the report's places (:mod:`gearopt.declarations`), ``tca.`` for the drive
side and ``tca_coast.`` for the coast: ``te_peak_to_peak_arcsec``, ``contact_ratio``,
``pattern.width_mm``, ``pattern.bias_mm``, ``pattern.center_offset_mm.0`` (face) and ``.1``
(profile), ``pattern.edge_contact`` (0/1), ... (``TcaEvaluator.metrics`` lists them). Curves
``te``, ``path`` (and ``te_target``); the pattern's outline per side. Arrays: ``phi1_deg``,
``te_arcsec``, ``path_face_mm``, ``path_profile_mm``, ``pattern_um`` (the least separation
of each pinion node over the mesh, inf off the flanks), ``flank_mask`` (generated pinion
nodes), ``face_mm`` and ``profile_mm`` (pattern coordinates of the grid), and the
``coast_*`` of each. With a
``[te_target]`` in the design (drive side): metrics ``tca.te_target_max_deviation_arcsec`` and
``tca.te_target_rms_deviation_arcsec``, array ``te_target_arcsec``
(:func:`gearopt.te_target.compare`).

``ease-off`` metrics: ``ease_off.drive.max_um`` and ``ease_off.coast.max_um`` (the largest
ease-off over the flank where it is defined); arrays ``ease_off_um`` and ``coast_ease_off_um``. The
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
from gearopt.analysis_options import ANALYSIS_OPTIONS
from gearopt.declarations import SIDES, Curve, Metric, Pattern, pattern_outline, report_metrics
from gearopt.design import Misalignment
from gearopt.evaluation import BaseEvaluator, Evaluation
from gearopt.plausibility import contact_findings
from gearopt.te_target import compare

#: the report section of each side (``gearopt analyze --json``'s keys), before each metric
SECTIONS = {"drive": "tca", "coast": "tca_coast"}


def _per_side(name: str, unit: str, description: str) -> Metric:
    return Metric(name=name, unit=unit, description=description, per_side=True)


TCA_METRICS = (
    _per_side("te_peak_to_peak_arcsec", "arcsec", "TE peak-to-peak (gear rotation)"),
    _per_side("contact_ratio", "", "mean number of pairs in contact"),
    _per_side("pattern.width_mm", "mm", "pattern width across the path"),
    _per_side("pattern.ellipse_major_axis_mm", "mm", "largest contact ellipse's major axis"),
    _per_side("pattern.ellipse_minor_axis_mm", "mm", "its minor axis"),
    _per_side("pattern.path_angle_deg", "deg", "contact path's angle to the root line"),
    _per_side("pattern.bias_mm", "mm", "face coordinate of the path's end minus its start"),
    _per_side("pattern.center_offset_mm.0", "mm", "mean point M minus centre C, face"),
    _per_side("pattern.center_offset_mm.1", "mm", "mean point M minus centre C, profile"),
    _per_side("pattern.mean_point_mm.0", "mm", "mean contact point M, face"),
    _per_side("pattern.mean_point_mm.1", "mm", "mean contact point M, profile"),
    _per_side("pattern.edge_contact", "", "contact on a flank's boundary (0/1)"),
    _per_side("pattern.compound_um", "um", "marking compound of the pattern"),
    Metric(
        name="te_target_max_deviation_arcsec",
        unit="arcsec",
        description="largest deviation of the drive TE from [te_target]",
        always=False,
    ),
    Metric(
        name="te_target_rms_deviation_arcsec",
        unit="arcsec",
        description="rms deviation of the drive TE from [te_target]",
        always=False,
    ),
)


#: the metrics' names before gearopt 0.2 (``coast_`` prefixed the coast side), by their names
#: now: for old queries of the ``gearopt_metrics`` table (docs/declarations.md)
RENAMED = {
    f"{section}.{new}": f"{prefix}{old}"
    for prefix, section in (("", "tca"), ("coast_", "tca_coast"))
    for old, new in (
        ("te_peak_to_peak_arcsec", "te_peak_to_peak_arcsec"),
        ("contact_ratio", "contact_ratio"),
        ("pattern_width_mm", "pattern.width_mm"),
        ("pattern_bias_mm", "pattern.bias_mm"),
        ("pattern_center_offset_face_mm", "pattern.center_offset_mm.0"),
        ("pattern_center_offset_profile_mm", "pattern.center_offset_mm.1"),
        ("edge_contact", "pattern.edge_contact"),
    )
} | {
    "tca.te_target_max_deviation_arcsec": "te_target_max_deviation_arcsec",
    "tca.te_target_rms_deviation_arcsec": "te_target_rms_deviation_arcsec",
    "ease_off.drive.max_um": "ease_off_max_um",
    "ease_off.coast.max_um": "coast_ease_off_max_um",
}


class TcaEvaluator(BaseEvaluator):
    """Unloaded TCA of both sides: TE, contact path and pattern (seed 001 section 5)."""

    name = "tca"
    description = "unloaded TCA of drive and coast sides: TE, contact path, pattern"
    section = "tca"
    sections = SECTIONS
    metrics = TCA_METRICS
    curves = (
        Curve(
            name="te",
            x="phi1_deg",
            y="te_arcsec",
            x_unit="deg",
            y_unit="arcsec",
            description="TE of the carrying pair over the pinion rotation",
            sides=SIDES,
        ),
        Curve(
            name="path",
            x="face_mm",
            y="profile_mm",
            x_unit="mm",
            y_unit="mm",
            description="contact path on the projected pinion tooth",
            sides=SIDES,
        ),
        Curve(
            name="te_target",
            x="phi1_deg",
            y="te_target_arcsec",
            x_unit="deg",
            y_unit="arcsec",
            description="the designed TE ([te_target]) at the TCA's positions",
        ),
    )
    pattern = Pattern(description="contact pattern at the marking compound", sides=SIDES)
    options = ANALYSIS_OPTIONS
    analysis = True
    #: the metrics' names before gearopt 0.2 by their names now (docs/declarations.md)
    renamed = RENAMED

    def evaluate(self, design, conditions: Mapping[str, Any] | None = None) -> Evaluation:
        options = AnalysisOptions.from_conditions(conditions, design=design)
        pair = meshed_pair(design, options)
        sides = contact_sides(pair, options)
        drive, coast = sides["drive"], sides["coast"]
        arrays = {"face_mm": drive.face_mm, "profile_mm": drive.profile_mm}
        curves: dict[str, dict] = {"te": {}, "path": {}}
        patterns = {}
        for prefix, side, field in (("", drive, pair.drive), ("coast_", coast, pair.coast)):
            arrays[f"{prefix}phi1_deg"] = side.phi1_deg
            arrays[f"{prefix}te_arcsec"] = side.te_arcsec
            arrays[f"{prefix}path_face_mm"] = side.path_face_mm
            arrays[f"{prefix}path_profile_mm"] = side.path_profile_mm
            arrays[f"{prefix}pattern_um"] = side.pattern_um
            arrays[f"{prefix}flank_mask"] = field.pinion.mask
            curves["te"][side.side] = (side.phi1_deg, side.te_arcsec)
            curves["path"][side.side] = (side.path_face_mm, side.path_profile_mm)
            patterns[side.side] = (
                side.outline_mm
                if len(side.outline_mm)
                else pattern_outline(
                    side.pattern_um, drive.face_mm, drive.profile_mm, options.compound_um
                )
            )
        report = {SECTIONS["drive"]: drive.as_dict(), SECTIONS["coast"]: coast.as_dict()}
        if design.te_target is not None:  # the designed TE (drive side) beside the achieved
            versus = compare(
                design.te_target, drive.phi1_deg, drive.te_arcsec, drive.handover_phi1_deg
            )
            arrays["te_target_arcsec"] = versus["te_target_arcsec"]
            curves["te_target"] = {"drive": (drive.phi1_deg, versus["te_target_arcsec"])}
            report["tca"]["te_target_arcsec"] = [float(v) for v in versus["te_target_arcsec"]]
            for key in ("te_target_max_deviation_arcsec", "te_target_rms_deviation_arcsec"):
                report["tca"][key] = versus[key]
        return Evaluation(
            evaluator=self.name,
            metrics=report_metrics(self, report),
            arrays=arrays,
            conditions=options.as_dict(),
            report=report,
            curves=curves,
            patterns=patterns,
            warnings=tuple(contact_findings(report, strict=False)),
        )


class EaseOffEvaluator(BaseEvaluator):
    """The pinion flanks' normal deviation from the surfaces conjugate to the gear."""

    name = "ease-off"
    description = "pinion ease-off of drive and coast flanks against the conjugate surfaces"
    section = "ease_off"
    sections = {"drive": "ease_off.drive", "coast": "ease_off.coast"}
    metrics = (
        Metric(
            name="max_um",
            unit="um",
            description="largest ease-off where the flank is defined",
            per_side=True,
        ),
    )
    options = ANALYSIS_OPTIONS
    analysis = True

    def evaluate(self, design, conditions: Mapping[str, Any] | None = None) -> Evaluation:
        options = AnalysisOptions.from_conditions(conditions, design=design)
        # the deviation from the conjugate surface is a property of the flanks: nominal assembly
        options = replace(options, misalignment=Misalignment())
        result = pair_ease_off(meshed_pair(design, options))
        drive, coast = result["drive"], result["coast"]
        report = {"ease_off": {"drive": drive.as_dict(), "coast": coast.as_dict()}}
        return Evaluation(
            evaluator=self.name,
            metrics=report_metrics(self, report),
            arrays={"ease_off_um": drive.ease_off_um, "coast_ease_off_um": coast.ease_off_um},
            conditions=options.as_dict(),
            report=report,
        )


@hookimpl
def gearopt_evaluators() -> list[BaseEvaluator]:
    """The TCA and ease-off evaluators."""
    return [TcaEvaluator(), EaseOffEvaluator()]
