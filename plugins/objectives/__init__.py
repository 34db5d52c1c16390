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
from collections.abc import Mapping, Sequence
from typing import Any, ClassVar

from gearopt import hookimpl
from gearopt.errors import StudyError
from gearopt.evaluation import BaseObjective, Evaluation

SIDES = {"drive": ("",), "coast": ("coast_",), "both": ("", "coast_")}


def _side(objective: str, options: Mapping[str, Any]) -> tuple[str, ...]:
    side = options.get("side", "drive")
    if side not in SIDES:
        raise StudyError(f"objective {objective}.side", side, f"must be one of {sorted(SIDES)}")
    return SIDES[side]


def _labels(objective: str, value: Any) -> tuple[str, ...]:
    labels = (value,) if isinstance(value, str) else value
    if (
        not isinstance(labels, Sequence)
        or not labels
        or not all(isinstance(x, str) for x in labels)
    ):
        raise StudyError(f"objective {objective}.on", value, "must be a label or a list of labels")
    return tuple(labels)


def _known_options(objective: BaseObjective, options: Mapping[str, Any]) -> None:
    unknown = set(options) - set(objective.options)
    if unknown:
        raise StudyError(
            f"{objective.kind} {objective.name}",
            sorted(unknown),
            f"unknown options; known: {objective.options}",
        )


def _metric(evaluations: Mapping[str, Evaluation], label: str, key: str) -> float:
    return float(evaluations[label].metrics[key])


def _te(evaluations):
    return lambda label, p: _metric(evaluations, label, f"{p}te_peak_to_peak_arcsec")


class _ContactObjective(BaseObjective):
    """An objective on TCA results: ``on`` labels of ``tca`` evaluations, ``side``."""

    requires = ("tca",)
    options: ClassVar[tuple[str, ...]] = ("on", "side")
    default_on: ClassVar[Any] = "tca"

    def reads(self, **options: Any) -> dict[str, str]:
        """Labels this objective reads, with the evaluator each must be."""
        _known_options(self, options)
        _side(self.name, options)
        labels = _labels(self.name, options.get("on", self.default_on))
        return {label: self.requires[0] for label in labels}

    def _worst(self, evaluations, options, of) -> float:
        """The largest ``of(label, prefix)`` over the TCAs ``on`` and the sides ``side``
        (``prefix``: the side's metric prefix)."""
        return max(
            of(label, prefix)
            for label in _labels(self.name, options.get("on", self.default_on))
            for prefix in _side(self.name, options)
        )


class TePeakToPeak(_ContactObjective):
    name = "te_peak_to_peak"
    description = "TE peak-to-peak of one TCA (arcsec)"

    def value(self, evaluations, **options):
        return self._worst(evaluations, options, _te(evaluations))


class WorstTe(_ContactObjective):
    name = "worst_te"
    description = "largest TE peak-to-peak over several TCAs, e.g. misalignments (arcsec)"
    default_on = None

    def reads(self, **options):
        if "on" not in options:
            raise StudyError(f"objective {self.name}.on", rule="list the TCA labels to compare")
        return super().reads(**options)

    def value(self, evaluations, **options):
        return self._worst(evaluations, options, _te(evaluations))


class TeTarget(_ContactObjective):
    name = "te_target"
    description = "deviation of the drive side's TE from the design's [te_target] (arcsec)"
    options = ("on", "measure")

    def reads(self, **options):
        measure = options.get("measure", "rms")
        if measure not in ("rms", "max"):
            raise StudyError(f"objective {self.name}.measure", measure, "must be 'rms' or 'max'")
        return super().reads(**{k: v for k, v in options.items() if k != "measure"})

    def value(self, evaluations, **options):
        key = f"te_target_{options.get('measure', 'rms')}_deviation_arcsec"
        labels = _labels(self.name, options.get("on", self.default_on))
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
    options = ("on", "side", "level_arcsec")

    def reads(self, **options):
        level = options.get("level_arcsec")
        if (
            isinstance(level, bool)
            or not isinstance(level, int | float)
            or not 0.0 <= level < math.inf
        ):
            raise StudyError(
                f"objective {self.name}.level_arcsec", level, "needs a finite level >= 0"
            )
        return super().reads(**options)

    def value(self, evaluations, **options):
        te = self._worst(evaluations, options, _te(evaluations))
        return abs(te - float(options["level_arcsec"]))


class PatternCenterOffset(_ContactObjective):
    name = "pattern_center_offset"
    description = "distance of the mean contact point from the flank centre (mm)"
    options = ("on", "side", "component")

    def reads(self, **options):
        component = options.get("component", "both")
        if component not in ("both", "face", "profile"):
            raise StudyError(
                f"objective {self.name}.component", component, "must be both, face or profile"
            )
        return super().reads(**options)

    def value(self, evaluations, **options):
        component = options.get("component", "both")

        def size(label, p):
            face = _metric(evaluations, label, f"{p}pattern_center_offset_face_mm")
            profile = _metric(evaluations, label, f"{p}pattern_center_offset_profile_mm")
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
            lambda label, p: abs(_metric(evaluations, label, f"{p}pattern_bias_mm")),
        )


class PatternMovement(_ContactObjective):
    name = "pattern_movement"
    description = "movement of the mean contact point between two assemblies (mm)"
    options = ("nominal", "misaligned", "side")

    def reads(self, **options):
        _known_options(self, options)
        if "misaligned" not in options:
            raise StudyError(
                f"objective {self.name}.misaligned", rule="name the misaligned TCA's label"
            )
        _side(self.name, options)
        labels = _labels(self.name, [options.get("nominal", "tca"), options["misaligned"]])
        return {label: "tca" for label in labels}

    def value(self, evaluations, **options):
        nominal, misaligned = options.get("nominal", "tca"), options["misaligned"]
        worst = 0.0
        for p in _side(self.name, options):
            moves = [
                _metric(evaluations, misaligned, f"{p}pattern_center_offset_{c}_mm")
                - _metric(evaluations, nominal, f"{p}pattern_center_offset_{c}_mm")
                for c in ("face", "profile")
            ]
            worst = max(worst, math.hypot(*moves))
        return worst


class BacklashWindow(BaseObjective):
    name = "backlash_window"
    description = "backlash inside [min_um, max_um] (constraint, um outside the window)"
    kind = "constraint"
    requires = ("backlash",)
    options: ClassVar[tuple[str, ...]] = ("on", "min_um", "max_um")

    def reads(self, **options):
        _known_options(self, options)
        for key in ("min_um", "max_um"):
            value = options.get(key)
            if isinstance(value, bool) or not isinstance(value, int | float):
                raise StudyError(f"constraint {self.name}.{key}", value, "is required (um)")
            if not math.isfinite(value):
                raise StudyError(f"constraint {self.name}.{key}", value, "must be finite (um)")
        if not options["min_um"] < options["max_um"]:
            raise StudyError(
                f"constraint {self.name}",
                (options["min_um"], options["max_um"]),
                "needs min_um < max_um",
            )
        (label,) = _labels(self.name, options.get("on", "backlash"))[:1]
        return {label: "backlash"}

    def value(self, evaluations, **options):
        label = options.get("on", "backlash")
        low, high = float(options["min_um"]), float(options["max_um"])
        excess = max(
            low - _metric(evaluations, label, "backlash_min_um"),
            _metric(evaluations, label, "backlash_max_um") - high,
        )
        if _metric(evaluations, label, "interference"):
            excess = max(excess, 0.0) + (high - low)
        return excess


class EdgeContact(_ContactObjective):
    name = "edge_contact"
    description = "contact stays inside the flanks (constraint: +0.5 with edge contact)"
    kind = "constraint"
    default_on = ("tca",)

    def value(self, evaluations, **options):
        edge = self._worst(
            evaluations, options, lambda label, p: _metric(evaluations, label, f"{p}edge_contact")
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
