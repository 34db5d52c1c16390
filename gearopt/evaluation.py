"""The evaluator and objective contracts.

An evaluator turns a design (plus conditions such as a misalignment) into named metrics: scalars
for Optuna and dashboards, arrays for curves and patterns. An objective turns the evaluations of
a trial into one number that Optuna minimises (or a constraint value, feasible when <= 0).
"""

from __future__ import annotations

import abc
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, ClassVar

from gearopt.declarations import Curve, Metric, Option, Pattern, check_options
from gearopt.errors import PluginError

if TYPE_CHECKING:
    import numpy as np

    from gearopt.design import Design

__all__ = ["Evaluation", "BaseEvaluator", "BaseObjective"]


@dataclass(frozen=True, kw_only=True)
class Evaluation:
    """What an evaluator returns.

    Attributes
    ----------
    evaluator
        Name of the evaluator that produced it.
    metrics
        Finite scalars named with their units (``te_peak_to_peak_arcsec``); booleans as 0/1.
    arrays
        Curves and fields (``phi1_deg``, ``te_arcsec``), small enough to store per trial.
    conditions
        The conditions that produced it (misalignment, grid, ...), so a number can be traced.
    report
        JSON-ready details for people (what ``gearopt analyze --json`` prints), keyed by
        section (``{"tca": {...}}``); optional.
    curves
        The evaluator's declared curves (:attr:`BaseEvaluator.curves`), ``{curve: {side: (x,
        y)}}`` (x and y of one length); a study stores them in its ``gearopt_curves`` table
        (rows of non-finite points left out).
    patterns
        The declared contact pattern's outline (:attr:`BaseEvaluator.pattern`) per side,
        ``{side: (k, 2) array of (face_mm, profile_mm)}``, a closed polygon
        (:func:`gearopt.declarations.pattern_outline`); stored in ``gearopt_patterns``.
    warnings
        What is legal but unusual in the result, each string naming its rule (edge contact,
        a contact ratio below one, ...); a study stores them per trial (the user attribute
        ``gearopt_warnings``).
    """

    evaluator: str
    metrics: Mapping[str, float]
    arrays: Mapping[str, np.ndarray] = field(default_factory=dict)
    conditions: Mapping[str, Any] = field(default_factory=dict)
    report: Mapping[str, Any] = field(default_factory=dict)
    curves: Mapping[str, Mapping[str, tuple[Any, Any]]] = field(default_factory=dict)
    patterns: Mapping[str, Any] = field(default_factory=dict)
    warnings: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        for key, value in self.metrics.items():
            if not isinstance(value, int | float) or not math.isfinite(float(value)):
                raise PluginError(
                    f"evaluator {self.evaluator!r} metric {key!r}", value, "must be a finite number"
                )
        for name, by_side in self.curves.items():
            for side, xy in by_side.items():
                shapes = [len(v) for v in xy] if len(xy) == 2 else None
                if shapes is None or shapes[0] != shapes[1]:
                    raise PluginError(
                        f"evaluator {self.evaluator!r} curve {name!r} ({side})",
                        shapes,
                        "must be (x, y) of one length",
                    )
        for side, outline in self.patterns.items():
            shape = getattr(outline, "shape", None)
            if shape is None or len(shape) != 2 or shape[1] != 2:
                raise PluginError(
                    f"evaluator {self.evaluator!r} pattern ({side})",
                    shape,
                    "must be a (k, 2) array of (face_mm, profile_mm)",
                )


class BaseEvaluator(abc.ABC):
    """Computes metrics of a design: TCA, backlash, chain error, loaded contact, ...

    Instances are stateless and picklable; ``evaluate`` is a pure function of its arguments and
    runs in worker processes. ``name`` is unique across plugins.

    An evaluator declares what it produces, and the study tables, ``gearopt analyze`` (its
    ``--json`` and ``--plot``) and ``gearopt plugins`` read the declarations
    (:mod:`gearopt.declarations`); :class:`gearopt.testing.EvaluatorContract` checks that
    ``evaluate`` returns what is declared:

    ``metrics``
        :class:`~gearopt.declarations.Metric` declarations; the keys of
        :attr:`Evaluation.metrics` are their full names, ``section`` (or, for a metric
        ``per_side``, each side's entry of ``sections``) and the metric's name joined by a dot:
        the metric's place in the evaluation's ``report`` (``gearopt analyze --json``).
    ``curves``, ``pattern``
        :class:`~gearopt.declarations.Curve` declarations (``Evaluation.curves``) and at most
        one :class:`~gearopt.declarations.Pattern` (``Evaluation.patterns``).
    ``options``
        :class:`~gearopt.declarations.Option` declarations of the keys of ``conditions``,
        checked by :meth:`check_conditions` when a study file is read; ``None`` (undeclared):
        any conditions are accepted.
    ``analysis``
        ``gearopt analyze`` runs it (with the analysis options it declares from the command
        line) when :meth:`in_analysis` says so; by default when this is True.
    """

    name: ClassVar[str]
    description: ClassVar[str] = ""
    section: ClassVar[str] = ""
    sections: ClassVar[Mapping[str, str]] = {}
    metrics: ClassVar[tuple[Metric, ...]] = ()
    curves: ClassVar[tuple[Curve, ...]] = ()
    pattern: ClassVar[Pattern | None] = None
    options: ClassVar[tuple[Option, ...] | None] = None
    analysis: ClassVar[bool] = False

    @abc.abstractmethod
    def evaluate(self, design: Design, conditions: Mapping[str, Any] | None = None) -> Evaluation:
        """Evaluate ``design`` under ``conditions`` (evaluator-specific, documented by it)."""

    def check_conditions(self, design: Design, conditions: Mapping[str, Any]) -> None:
        """Raise a :class:`~gearopt.errors.GearoptError` naming a condition ``evaluate`` would
        refuse (an unknown key, a bad value), without evaluating anything.

        A study calls this once per evaluation when its file is read, so that a typo fails
        before its database is created and before the first trial. The default checks the
        declared ``options`` (:func:`gearopt.declarations.check_options`) and accepts anything
        when none are declared (such an evaluator is checked by its first trial).
        """
        if self.options is not None:
            check_options(self.options, conditions, "conditions")

    def in_analysis(self, design: Design) -> bool:
        """Whether ``gearopt analyze`` runs this evaluator on ``design`` (default:
        :attr:`analysis`)."""
        return self.analysis

    def __repr__(self) -> str:
        return f"<{type(self).__name__} {self.name!r}>"


class BaseObjective(abc.ABC):
    """Turns a trial's evaluations into one value for Optuna.

    ``kind`` is ``"objective"`` (minimised or maximised per ``direction``) or ``"constraint"``
    (feasible when the value is <= 0, passed to ``trial.set_constraint``). ``requires`` names the
    evaluators whose results ``value`` reads. ``options`` declares the keys of its study-file
    entry (:class:`~gearopt.declarations.Option`), checked by :meth:`reads`.
    """

    name: ClassVar[str]
    description: ClassVar[str] = ""
    kind: ClassVar[str] = "objective"
    direction: ClassVar[str] = "minimize"
    requires: ClassVar[tuple[str, ...]] = ()
    options: ClassVar[tuple[Option, ...]] = ()

    def reads(self, **options: Any) -> dict[str, str]:
        """The evaluation labels ``value`` reads with these options, each with the evaluator
        it must come from; raise a :class:`~gearopt.errors.GearoptError` naming a bad option.

        A study checks this once, when its file is read, so that a typo fails before the first
        trial. The default checks the declared ``options``
        (:func:`gearopt.declarations.check_options`) and reads each evaluator of ``requires``
        under its own name (or under the labels of an option ``on``, when declared).
        """
        checked = check_options(self.options, options, f"{self.kind} {self.name}")
        on = checked.get("on")
        if on is not None and len(self.requires) == 1:
            labels = (on,) if isinstance(on, str) else tuple(on)
            return {label: self.requires[0] for label in labels}
        return {name: name for name in self.requires}

    @abc.abstractmethod
    def value(self, evaluations: Mapping[str, Evaluation], **options: Any) -> float:
        """Return a finite value from one trial's evaluations, keyed by their labels in the
        study (a label defaults to the evaluator's name)."""

    def __repr__(self) -> str:
        return f"<{type(self).__name__} {self.name!r}>"
