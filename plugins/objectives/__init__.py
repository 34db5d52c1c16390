"""Objectives and constraints on the contact evaluators: what a study minimises.

Each objective reads the evaluations of one trial, keyed by their labels in the study file
(``[evaluations.<label>]``; a label defaults to the evaluator's name), and returns one finite
number. Options come from the study file's ``[[objectives]]`` / ``[[constraints]]`` entries:

``te_peak_to_peak``
    The TE peak-to-peak (arcsec) of one TCA. ``on`` (label, default ``"tca"``), ``side``
    (``"drive"``, ``"coast"`` or ``"both"``, the larger; default ``"drive"``). Given several
    labels in ``on``, this and the other TCA objectives take the worst of them.
``worst_te``
    The largest TE peak-to-peak (arcsec) over several TCAs, e.g. a set of misalignments.
    ``on`` (list of labels, required), ``side`` as above.
``te_level``
    How far (arcsec) the TE peak-to-peak of one TCA is from ``level_arcsec`` (required): the
    design with a prescribed kinematic error (seed 003 Table 7). ``on``, ``side``.
``te_target``
    How far (arcsec) the drive side's TE of one TCA is from the design's ``[te_target]``
    (:func:`gearopt.te_target.compare`): ``measure`` ``"rms"`` (default) or ``"max"`` over the
    positions; ``on``. A design without ``[te_target]`` is an error.
``pattern_center_offset``
    The distance (mm) of the mean contact point M from the flank centre C, in the pattern
    coordinates (face, profile). ``on``, ``side``, ``component`` (``"both"``, ``"face"`` or
    ``"profile"``: the magnitude of one coordinate).
``pattern_bias``
    The magnitude (mm) of the pattern's bias (face coordinate of the path's end minus its start).
    ``on``, ``side``.
``pattern_movement``
    How far (mm) the mean contact point moves between two assemblies: ``nominal`` (label,
    default ``"tca"``) and ``misaligned`` (label, required), ``side``.
``backlash_window`` (constraint)
    Circumferential backlash inside ``[min_um, max_um]`` at every position: the value is the
    largest excursion outside the window in um (feasible when <= 0); interference adds the
    window's width. ``on`` (label, default ``"backlash"``), ``min_um``, ``max_um``.
``edge_contact`` (constraint)
    Contact stays inside the flanks: +0.5 when any of the TCAs ``on`` (list of labels, default
    ``["tca"]``) reports edge contact on ``side``, else -0.5.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

from gearopt import hookimpl
from gearopt.declarations import Option, check_options
from gearopt.errors import StudyError
from gearopt.evaluation import BaseObjective, Evaluation

#: the ``tca`` evaluator's report section of each side, before its metrics' names
SIDES = {"drive": ("tca.",), "coast": ("tca_coast.",), "both": ("tca.", "tca_coast.")}

SIDE = Option(
    name="side",
    default="drive",
    kind="string",
    choices=tuple(SIDES),
    description="the flank side read; both: the larger",
)


def _on(default: Any, required: bool = False, what: str = "TCA") -> Option:
    return Option(
        name="on",
        default=default,
        kind="labels",
        required=required,
        description=f"label(s) of the {what} evaluations read; several: the worst",
    )


def _labels(value: Any) -> tuple[str, ...]:
    return (value,) if isinstance(value, str) else tuple(value)


def _metric(evaluations: Mapping[str, Evaluation], label: str, key: str) -> float:
    return float(evaluations[label].metrics[key])


def _te(evaluations):
    return lambda label, p: _metric(evaluations, label, f"{p}te_peak_to_peak_arcsec")


class _ContactObjective(BaseObjective):
    """An objective on TCA results: ``on`` labels of ``tca`` evaluations, ``side``."""

    requires = ("tca",)
    options = (_on("tca"), SIDE)

    def _worst(self, evaluations, options, of) -> float:
        """The largest ``of(label, prefix)`` over the TCAs ``on`` and the sides ``side``
        (``prefix``: the side's report section and a dot)."""
        checked = check_options(self.options, options, f"{self.kind} {self.name}")
        return max(
            of(label, prefix)
            for label in _labels(checked["on"])
            for prefix in SIDES[checked.get("side") or "drive"]
        )


class TePeakToPeak(_ContactObjective):
    name = "te_peak_to_peak"
    description = "TE peak-to-peak of one TCA (arcsec)"

    def value(self, evaluations, **options):
        return self._worst(evaluations, options, _te(evaluations))


class WorstTe(_ContactObjective):
    name = "worst_te"
    description = "largest TE peak-to-peak over several TCAs, e.g. misalignments (arcsec)"
    options = (_on(None, required=True), SIDE)

    def value(self, evaluations, **options):
        return self._worst(evaluations, options, _te(evaluations))


class TeTarget(_ContactObjective):
    name = "te_target"
    description = "deviation of the drive side's TE from the design's [te_target] (arcsec)"
    options = (
        _on("tca"),
        Option(
            name="measure",
            default="rms",
            kind="string",
            choices=("rms", "max"),
            description="rms or largest deviation over the positions",
        ),
    )

    def value(self, evaluations, **options):
        key = f"tca.te_target_{options.get('measure', 'rms')}_deviation_arcsec"
        labels = _labels(options.get("on", "tca"))
        for label in labels:
            if key not in evaluations[label].metrics:
                raise StudyError(
                    f"objective {self.name}",
                    label,
                    "the design has no [te_target] table: nothing to compare the TE with",
                )
        return max(_metric(evaluations, label, key) for label in labels)


class TeLevel(_ContactObjective):
    name = "te_level"
    description = "distance of the TE peak-to-peak from a prescribed level (arcsec)"
    options = (
        _on("tca"),
        SIDE,
        Option(
            name="level_arcsec",
            kind="number",
            lower=0.0,
            required=True,
            description="the prescribed TE peak-to-peak (arcsec)",
        ),
    )

    def value(self, evaluations, **options):
        te = self._worst(evaluations, options, _te(evaluations))
        return abs(te - float(options["level_arcsec"]))


class PatternCenterOffset(_ContactObjective):
    name = "pattern_center_offset"
    description = "distance of the mean contact point from the flank centre (mm)"
    options = (
        _on("tca"),
        SIDE,
        Option(
            name="component",
            default="both",
            kind="string",
            choices=("both", "face", "profile"),
            description="the distance (both) or the magnitude of one coordinate",
        ),
    )

    def value(self, evaluations, **options):
        component = options.get("component", "both")

        def size(label, p):
            face = _metric(evaluations, label, f"{p}pattern.center_offset_mm.0")
            profile = _metric(evaluations, label, f"{p}pattern.center_offset_mm.1")
            return {"both": math.hypot(face, profile), "face": abs(face), "profile": abs(profile)}[
                component
            ]

        return self._worst(evaluations, options, size)


class PatternBias(_ContactObjective):
    name = "pattern_bias"
    description = "magnitude of the contact pattern's bias (mm)"

    def value(self, evaluations, **options):
        return self._worst(
            evaluations,
            options,
            lambda label, p: abs(_metric(evaluations, label, f"{p}pattern.bias_mm")),
        )


class PatternMovement(_ContactObjective):
    name = "pattern_movement"
    description = "movement of the mean contact point between two assemblies (mm)"
    options = (
        Option(
            name="nominal",
            default="tca",
            kind="label",
            description="label of the nominal assembly's TCA",
        ),
        Option(
            name="misaligned",
            kind="label",
            required=True,
            description="label of the misaligned assembly's TCA",
        ),
        SIDE,
    )

    def reads(self, **options):
        checked = check_options(self.options, options, f"{self.kind} {self.name}")
        return {checked["nominal"]: "tca", checked["misaligned"]: "tca"}

    def value(self, evaluations, **options):
        nominal, misaligned = options.get("nominal", "tca"), options["misaligned"]
        worst = 0.0
        for p in SIDES[options.get("side", "drive")]:
            moves = [
                _metric(evaluations, misaligned, f"{p}pattern.center_offset_mm.{i}")
                - _metric(evaluations, nominal, f"{p}pattern.center_offset_mm.{i}")
                for i in (0, 1)
            ]
            worst = max(worst, math.hypot(*moves))
        return worst


class BacklashWindow(BaseObjective):
    name = "backlash_window"
    description = "backlash inside [min_um, max_um] (constraint, um outside the window)"
    kind = "constraint"
    requires = ("backlash",)
    options = (
        _on("backlash", what="backlash"),
        Option(name="min_um", kind="number", required=True, description="least backlash (um)"),
        Option(name="max_um", kind="number", required=True, description="largest backlash (um)"),
    )

    def reads(self, **options):
        labels = super().reads(**options)
        if not options["min_um"] < options["max_um"]:
            raise StudyError(
                f"constraint {self.name}",
                (options["min_um"], options["max_um"]),
                "needs min_um < max_um",
            )
        return dict(list(labels.items())[:1])

    def value(self, evaluations, **options):
        label = _labels(options.get("on", "backlash"))[0]
        low, high = float(options["min_um"]), float(options["max_um"])
        excess = max(
            low - _metric(evaluations, label, "backlash.min_um"),
            _metric(evaluations, label, "backlash.max_um") - high,
        )
        if _metric(evaluations, label, "backlash.interference"):
            excess = max(excess, 0.0) + (high - low)
        return excess


class EdgeContact(_ContactObjective):
    name = "edge_contact"
    description = "contact stays inside the flanks (constraint: +0.5 with edge contact)"
    kind = "constraint"
    options = (_on(["tca"]), SIDE)

    def value(self, evaluations, **options):
        edge = self._worst(
            evaluations,
            options,
            lambda label, p: _metric(evaluations, label, f"{p}pattern.edge_contact"),
        )
        return edge - 0.5


@hookimpl
def gearopt_objectives() -> list[BaseObjective]:
    """The contact objectives and constraints."""
    return [
        TePeakToPeak(),
        WorstTe(),
        TeLevel(),
        TeTarget(),
        PatternCenterOffset(),
        PatternBias(),
        PatternMovement(),
        BacklashWindow(),
        EdgeContact(),
    ]
