"""Errors raised by gearopt.

Every error a user can provoke with bad input is a :class:`GearoptError` that names the
parameter, the value it was given and the rule it breaks, so the message alone says what to fix::

    DesignError: machine.pinion.inner_cutter_radius_mm = 5.0: must exceed
    blade_module_mm * blade_groups / 2 = 8.493 (eq 9 of seed 001 has no solution)
"""

from __future__ import annotations

from typing import Any

__all__ = [
    "GearoptError",
    "shortened",
    "DesignError",
    "UnknownKeyError",
    "SettingsError",
    "NotAvailableError",
    "PluginError",
    "RexsError",
    "StudyError",
]

_MISSING = object()


#: the longest value an error message repeats (characters of its repr)
LONGEST_VALUE = 120


def shortened(value: Any) -> str:
    """``repr(value)``, cut to :data:`LONGEST_VALUE` characters with a note of its length
    (an error message names the value it was given, not all 50 MB of it)."""
    text = repr(value)
    if len(text) <= LONGEST_VALUE:
        return text
    return f"{text[: LONGEST_VALUE - 20]}... ({len(text)} characters)"


class GearoptError(ValueError):
    """Base class of every error gearopt raises on purpose.

    Parameters
    ----------
    parameter
        Dotted name of the offending parameter (``"pair.pinion_teeth"``), or a short
        description of what was being processed when no single parameter is to blame.
    value
        The value that was given (omit when there is none, e.g. a missing key).
    rule
        The rule that the value breaks, phrased so that ``f"{parameter} = {value}: {rule}"``
        reads as a sentence.
    """

    def __init__(self, parameter: str, value: Any = _MISSING, rule: str = "") -> None:
        self.parameter = parameter
        self.value = None if value is _MISSING else value
        self.rule = rule
        if value is _MISSING:
            message = f"{parameter}: {rule}"
        else:
            message = f"{parameter} = {shortened(value)}: {rule}"
        super().__init__(message)


class DesignError(GearoptError):
    """A design file or design value breaks a rule of the format or of the geometry."""


class UnknownKeyError(DesignError):
    """A table holds a key that the format does not define (often a typo or a wrong unit)."""


class SettingsError(GearoptError):
    """Machine settings cannot be computed for the given design (no solution exists)."""


class NotAvailableError(GearoptError):
    """A feature that was asked for is not available (yet, or without an optional extra)."""


class PluginError(GearoptError):
    """A plugin breaks the plugin contract (duplicate name, wrong return type, ...)."""


class RexsError(GearoptError):
    """A REXS file cannot be read into a design, or a design cannot be written as one (a missing
    or unknown attribute, a unit other than the schema's, a setting gearopt does not model)."""


class StudyError(GearoptError):
    """A study file, its storage or a study run breaks a rule (unknown objective, bad bounds,
    a storage that cannot be opened, ...)."""


class GearoptWarning(UserWarning):
    """A design or result that is legal but unusual: worth the engineer's attention, not a
    refusal. Commands collect these in their ``warnings`` list
    (:func:`gearopt.plausibility.caught`); the message names the parameter and the rule."""
