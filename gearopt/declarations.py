"""What a plugin declares: its options, and what an evaluator produces.

An evaluator lists its :class:`Metric`, :class:`Curve` and :class:`Pattern` declarations and an
evaluator or objective its :class:`Option` declarations, as OpenMDAO components declare their
options; the study tables, ``gearopt analyze`` and ``gearopt plugins`` read them, so a
third-party evaluator's results travel exactly as the built-ins' do.

One vocabulary: a metric's name is where its value sits in ``gearopt analyze --json``, keys
joined by dots and list items by their index (``tca.te_peak_to_peak_arcsec``,
``tca_coast.pattern.center_offset_mm.0``, ``backlash.min_um``); the same name is a key of
:attr:`gearopt.evaluation.Evaluation.metrics`, a ``metric`` of the ``gearopt_metrics`` table and
what the objectives read. A declaration's name may hold ``*`` for a part that depends on the
conditions (``lte_*nm``, ``*_change_gear_error``).
"""

from __future__ import annotations

import fnmatch
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from gearopt.errors import GearoptError

__all__ = [
    "Curve",
    "Metric",
    "Option",
    "OptionError",
    "Pattern",
    "SIDES",
    "check_options",
    "declared",
    "describe",
    "pattern_outline",
    "report_metrics",
]

#: the flank sides of a gear pair's results: drive (pinion convex driving), coast
SIDES = ("drive", "coast")
#: the value kinds an option may declare, with what each accepts
KINDS = {
    "number": "a number",
    "integer": "an integer",
    "string": "a string",
    "boolean": "true or false",
    "label": "a label (string)",
    "labels": "a label or a list of labels",
    "numbers": "a list of numbers",
    "table": "a table",
    "any": "any value",
}


class OptionError(GearoptError):
    """An option of an evaluator (a condition) or an objective breaks its declared rule."""


@dataclass(frozen=True, kw_only=True)
class Metric:
    """A scalar an evaluator reports (finite; booleans as 0/1).

    ``name`` is its dotted place in the evaluator's report (``pattern.width_mm``), its unit in
    the name; with ``per_side`` the evaluator's :attr:`~gearopt.evaluation.BaseEvaluator.sections`
    put one copy per side before it (``tca.pattern.width_mm``, ``tca_coast.pattern.width_mm``),
    else its :attr:`~gearopt.evaluation.BaseEvaluator.section` does (``backlash.min_um``).
    """

    name: str
    unit: str = ""
    description: str = ""
    per_side: bool = False
    always: bool = True


@dataclass(frozen=True, kw_only=True)
class Curve:
    """A curve an evaluator reports per side, y over x (rows of the ``gearopt_curves`` table).

    ``x`` and ``y`` name the quantities with their units (``phi1_deg``, ``te_arcsec``);
    ``x_unit`` and ``y_unit`` spell the units out for axes and listings.
    """

    name: str
    x: str
    y: str
    x_unit: str = ""
    y_unit: str = ""
    description: str = ""
    sides: tuple[str, ...] = ("drive",)


@dataclass(frozen=True, kw_only=True)
class Pattern:
    """A contact pattern's outline per side, a closed polygon of (face_mm, profile_mm) on the
    projected pinion tooth (rows of the ``gearopt_patterns`` table; at most one per
    evaluator)."""

    description: str = ""
    sides: tuple[str, ...] = ("drive",)


_MISSING = object()


@dataclass(frozen=True, kw_only=True)
class Option:
    """An option of an evaluator (one key of an evaluation's ``conditions``) or of an objective
    (one key of its ``[[objectives]]`` entry), checked when a study file is read.

    Attributes
    ----------
    name
        The key, its unit in the name.
    default
        The value when the key is left out (``None``: the plugin decides, e.g. from the design).
    kind
        What it accepts (:data:`KINDS`): ``number``, ``integer``, ``string``, ``boolean``,
        ``label``, ``labels``, ``numbers``, ``table`` or ``any``.
    lower, upper
        Inclusive bounds of a number (of each of ``numbers``).
    choices
        The values allowed, when they are few.
    required
        The key must be given.
    description
        One line for ``gearopt plugins --options``.
    validate
        A module-level function ``(value, where)`` raising a
        :class:`~gearopt.errors.GearoptError` for a rule beyond the kind and bounds (the keys of
        a table), called after them.
    """

    name: str
    default: Any = None
    kind: str = "any"
    lower: float | None = None
    upper: float | None = None
    choices: tuple[Any, ...] = ()
    required: bool = False
    description: str = ""
    validate: Callable[[Any, str], Any] | None = None

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise GearoptError(f"option {self.name}.kind", self.kind, f"must be one of {KINDS}")

    @property
    def rule(self) -> str:
        """The rule in words (``an integer in [3, 401]``)."""
        text = KINDS[self.kind]
        if self.choices:
            return f"one of {list(self.choices)}"
        if self.lower is not None or self.upper is not None:
            low = "-inf" if self.lower is None else f"{self.lower:g}"
            high = "inf" if self.upper is None else f"{self.upper:g}"
            text += f" in [{low}, {high}]"
        return text

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready form (``gearopt plugins --json``)."""
        return {
            "name": self.name,
            "default": self.default,
            "kind": self.kind,
            "lower": self.lower,
            "upper": self.upper,
            "choices": list(self.choices),
            "required": self.required,
            "description": self.description,
        }

    def check(self, value: Any, where: str, key: str | None = None) -> None:
        """Raise :class:`OptionError` naming ``where``, the option (``key``, the given name
        of a ``*`` declaration), the value and the rule if ``value`` breaks this
        declaration."""
        if not _accepts(self, value):
            raise OptionError(f"{where}.{key or self.name}", value, f"must be {self.rule}")
        if self.validate is not None:
            self.validate(value, f"{where}.{key or self.name}")


def _number(value: Any) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool) and math.isfinite(value)


def _within(option: Option, value: float) -> bool:
    return (option.lower is None or value >= option.lower) and (
        option.upper is None or value <= option.upper
    )


def _accepts(option: Option, value: Any) -> bool:
    kind = option.kind
    if option.choices:
        return any(value == c and type(value) is type(c) for c in option.choices)
    if kind == "number":
        return _number(value) and _within(option, value)
    if kind == "integer":
        return isinstance(value, int) and not isinstance(value, bool) and _within(option, value)
    if kind in ("string", "label"):
        return isinstance(value, str) and bool(value)
    if kind == "boolean":
        return isinstance(value, bool)
    if kind == "labels":
        items = [value] if isinstance(value, str) else value
        return (
            isinstance(items, Sequence)
            and bool(items)
            and all(isinstance(x, str) and x for x in items)
        )
    if kind == "numbers":
        return (
            isinstance(value, Sequence)
            and not isinstance(value, str)
            and bool(value)
            and all(_number(x) and _within(option, x) for x in value)
        )
    if kind == "table":
        return isinstance(value, Mapping)
    return True


def check_options(
    declared: Sequence[Option], given: Mapping[str, Any] | None, where: str
) -> dict[str, Any]:
    """Check ``given`` against the ``declared`` options and return them with the defaults of
    those left out; :class:`OptionError` names the first unknown key, missing required option
    or value that breaks its rule. A declared name with ``*`` matches any key of its form."""
    given = dict(given or {})
    out: dict[str, Any] = {}
    for key, value in given.items():
        option = declared_match(declared, key)
        if option is None:
            known = [o.name for o in declared]
            raise OptionError(where, key, f"is not an option; known: {known}")
        option.check(value, where, key)
        out[key] = value
    for option in declared:
        if "*" in option.name or option.name in out:
            continue
        if option.required:
            raise OptionError(f"{where}.{option.name}", rule=f"is required: {option.rule}")
        out[option.name] = option.default
    return out


def declared_match(declarations: Sequence[Any], name: str) -> Any:
    """The declaration whose name is ``name`` or whose ``*`` pattern matches it, else None."""
    for d in declarations:
        if d.name == name or ("*" in d.name and fnmatch.fnmatchcase(name, d.name)):
            return d
    return None


def declared(evaluator: Any, name: str) -> Metric | None:
    """The metric declaration of ``evaluator`` that names metric ``name`` (with its section
    or side's section before it), else None."""
    for metric in evaluator.metrics:
        for full in metric_names(evaluator, metric):
            if full == name or ("*" in full and fnmatch.fnmatchcase(name, full)):
                return metric
    return None


def metric_names(evaluator: Any, metric: Metric) -> list[str]:
    """The full names of one declared metric of ``evaluator`` (one per side with
    ``per_side``)."""
    sections = list(evaluator.sections.values()) if metric.per_side else [evaluator.section]
    return [f"{s}.{metric.name}" if s else metric.name for s in sections]


def pattern_outline(
    pattern_um: np.ndarray, face_mm: np.ndarray, profile_mm: np.ndarray, compound_um: float
) -> np.ndarray:
    """The contact pattern's outline as a closed polygon ``(k, 2)`` of (face, profile) mm: the
    lowest and highest marked node of each marked face column, toe to heel along the root side
    and back along the top side (empty when nothing is marked)."""
    marked = np.isfinite(pattern_um) & (pattern_um <= compound_um)
    cols = np.flatnonzero(marked.any(axis=1))
    if cols.size == 0:
        return np.zeros((0, 2))
    rows = marked[cols]
    low = profile_mm[np.argmax(rows, axis=1)]
    high = profile_mm[rows.shape[1] - 1 - np.argmax(rows[:, ::-1], axis=1)]
    face = face_mm[cols]
    return np.concatenate(
        [np.column_stack([face, low]), np.column_stack([face[::-1], high[::-1]])], axis=0
    )


def report_metrics(evaluator: Any, report: Mapping[str, Any]) -> dict[str, float]:
    """The declared metrics of ``evaluator`` read from its JSON-ready ``report`` by their
    dotted places (booleans as 0/1, list items by index); a declared metric the report does
    not hold (one present only under some conditions) is left out."""
    out: dict[str, float] = {}
    for metric in evaluator.metrics:
        for name in metric_names(evaluator, metric):
            value: Any = report
            for part in name.split("."):
                if isinstance(value, Mapping) and part in value:
                    value = value[part]
                elif isinstance(value, list | tuple) and part.isdigit() and int(part) < len(value):
                    value = value[int(part)]
                else:
                    value = None
                    break
            if isinstance(value, bool) or _number(value):
                out[name] = float(value)
    return out


def describe(plugin: Any) -> dict[str, Any]:
    """JSON-ready declarations of an evaluator or objective (``gearopt plugins --json``): its
    options and, for an evaluator, its metrics (full names), curves and pattern."""
    out: dict[str, Any] = {}
    options = getattr(plugin, "options", None)
    if options is not None and not isinstance(options, str):
        out["options"] = [o.as_dict() for o in options if isinstance(o, Option)]
    if hasattr(plugin, "sections"):
        out["metrics"] = [
            {"name": name, "unit": m.unit, "description": m.description, "always": m.always}
            for m in plugin.metrics
            for name in metric_names(plugin, m)
        ]
        out["curves"] = [
            {
                "name": c.name,
                "x": c.x,
                "y": c.y,
                "x_unit": c.x_unit,
                "y_unit": c.y_unit,
                "sides": list(c.sides),
                "description": c.description,
            }
            for c in plugin.curves
        ]
        pattern = plugin.pattern
        out["pattern"] = (
            None
            if pattern is None
            else {"sides": list(pattern.sides), "description": pattern.description}
        )
    return out
