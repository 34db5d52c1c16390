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

from gearopt.errors import PluginError, StudyError

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
        Named curves for the study's ``curves`` table, ``{curve: {side: (x, y)}}`` (x and y
        of one length, the curve's unit in its name: ``lte_50nm``, ``lte_fluctuation``); a
        study stores them as it stores the TCA's (rows of non-finite points left out).
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


class BaseEvaluator(abc.ABC):
    """Computes metrics of a design: TCA, backlash, chain error, loaded contact, ...

    Instances are stateless and picklable; ``evaluate`` is a pure function of its arguments and
    runs in worker processes. ``name`` is unique across plugins.
    """

    name: ClassVar[str]
    description: ClassVar[str] = ""

    @abc.abstractmethod
    def evaluate(self, design: Design, conditions: Mapping[str, Any] | None = None) -> Evaluation:
        """Evaluate ``design`` under ``conditions`` (evaluator-specific, documented by it)."""

    def check_conditions(self, design: Design, conditions: Mapping[str, Any]) -> None:
        """Raise a :class:`~gearopt.errors.GearoptError` naming a condition ``evaluate`` would
        refuse (an unknown key, a bad value), without evaluating anything.

        A study calls this once per evaluation when its file is read, so that a typo fails
        before its database is created and before the first trial. The default accepts
        anything (an evaluator that does not override it is checked by its first trial).
        """
        return None

    def __repr__(self) -> str:
        return f"<{type(self).__name__} {self.name!r}>"


class BaseObjective(abc.ABC):
    """Turns a trial's evaluations into one value for Optuna.

    ``kind`` is ``"objective"`` (minimised or maximised per ``direction``) or ``"constraint"``
    (feasible when the value is <= 0, passed to ``trial.set_constraint``). ``requires`` names the
    evaluators whose results ``value`` reads.
    """

    name: ClassVar[str]
    description: ClassVar[str] = ""
    kind: ClassVar[str] = "objective"
    direction: ClassVar[str] = "minimize"
    requires: ClassVar[tuple[str, ...]] = ()

    def reads(self, **options: Any) -> dict[str, str]:
        """The evaluation labels ``value`` reads with these options, each with the evaluator
        it must come from; raise a :class:`~gearopt.errors.StudyError` naming a bad option.

        A study checks this once, when its file is read, so that a typo fails before the first
        trial. The default reads each evaluator of ``requires`` under its own name and takes no
        options.
        """
        if options:
            raise StudyError(f"objective {self.name}", sorted(options), "takes no options")
        return {name: name for name in self.requires}

    @abc.abstractmethod
    def value(self, evaluations: Mapping[str, Evaluation], **options: Any) -> float:
        """Return a finite value from one trial's evaluations, keyed by their labels in the
        study (a label defaults to the evaluator's name)."""

    def __repr__(self) -> str:
        return f"<{type(self).__name__} {self.name!r}>"
