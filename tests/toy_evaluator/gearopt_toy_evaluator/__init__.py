"""A toy third-party evaluator that declares a metric, a curve and a pattern, and an objective.

It shows (and tests) that what a distribution installed next to gearopt declares reaches the
study tables (``gearopt_metrics``, ``gearopt_curves``, ``gearopt_patterns``), ``gearopt analyze
--json`` and ``--plot`` exactly as the built-ins' results do, without gearopt naming it.

``toy-depth`` reads the design's blank only: the pinion's whole depth along the face (a curve
per side, x the cone distance), the depth's taper (a metric) and a nominal contact-pattern box
in the middle of the projected tooth, ``margin`` of the face width and depth left free on each
side (a pattern per side, and its area per side as a metric).
"""

from __future__ import annotations

import numpy as np

import gearopt
from gearopt.declarations import Curve, Metric, Option, Pattern, check_options

SECTIONS = {"drive": "toy_depth", "coast": "toy_depth_coast"}


class ToyDepthEvaluator(gearopt.BaseEvaluator):
    name = "toy-depth"
    description = "toy: the pinion's whole depth along the face and a nominal pattern box"
    section = "toy_depth"
    sections = SECTIONS
    metrics = (
        Metric(name="depth_taper_mm", unit="mm", description="heel depth minus toe depth"),
        Metric(
            name="box_area_mm2",
            unit="mm2",
            description="area of the nominal pattern box",
            per_side=True,
        ),
    )
    curves = (
        Curve(
            name="whole_depth",
            x="cone_distance_mm",
            y="whole_depth_mm",
            x_unit="mm",
            y_unit="mm",
            description="the pinion's whole depth from toe to heel",
            sides=("drive", "coast"),
        ),
    )
    pattern = Pattern(description="nominal pattern box", sides=("drive", "coast"))
    options = (
        Option(
            name="margin",
            default=0.25,
            kind="number",
            lower=0.0,
            upper=0.45,
            description="share of the face width and depth left free on each side of the box",
        ),
    )
    analysis = True

    def evaluate(self, design, conditions=None):
        margin = check_options(self.options, conditions, "conditions")["margin"]
        blank = design.blank
        inner, outer = blank.inner_cone_distance_mm, blank.outer_cone_distance_mm
        cone = np.linspace(inner, outer, 9)
        mean = 0.5 * (inner + outer)
        depth_mean = blank.mean_addendum_mm[0] + blank.mean_dedendum_mm[0]
        depth = depth_mean * cone / mean  # a tapered tooth: depth proportional to the cone
        face = outer - inner
        half_face, half_depth = (0.5 - margin) * face, (0.5 - margin) * depth_mean
        box = np.array(
            [
                [-half_face, -half_depth],
                [half_face, -half_depth],
                [half_face, half_depth],
                [-half_face, half_depth],
            ]
        )
        side = {"box_area_mm2": float(4.0 * half_face * half_depth)}
        report = {
            SECTIONS["drive"]: {"depth_taper_mm": float(depth[-1] - depth[0]), **side},
            SECTIONS["coast"]: dict(side),
        }
        metrics = {
            "toy_depth.depth_taper_mm": report["toy_depth"]["depth_taper_mm"],
            "toy_depth.box_area_mm2": side["box_area_mm2"],
            "toy_depth_coast.box_area_mm2": side["box_area_mm2"],
        }
        return gearopt.Evaluation(
            evaluator=self.name,
            metrics=metrics,
            conditions={"margin": margin},
            report=report,
            curves={"whole_depth": {s: (cone, depth) for s in ("drive", "coast")}},
            patterns={"drive": box, "coast": box.copy()},
        )


class ToyBoxArea(gearopt.BaseObjective):
    name = "toy-box-area"
    description = "toy: minus the nominal pattern box's area (mm2), larger is better"
    requires = ("toy-depth",)
    options = (
        Option(name="on", default="toy-depth", kind="label", description="the evaluation read"),
    )

    def value(self, evaluations, **options):
        evaluation = evaluations[options.get("on", "toy-depth")]
        return -evaluation.metrics["toy_depth.box_area_mm2"]


@gearopt.hookimpl
def gearopt_evaluators():
    return [ToyDepthEvaluator()]


@gearopt.hookimpl
def gearopt_objectives():
    return [ToyBoxArea()]
