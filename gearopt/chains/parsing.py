"""Checks shared by the machine description's dataclasses and the chain-error method.

The names of shafts, elements, slots and chains (:func:`name_ok`), optional positive numbers
(:func:`optional_number`) and the largest tooth count accepted anywhere (:data:`MAX_TEETH`).
"""

from __future__ import annotations

from typing import Any

from gearopt.errors import DesignError
from gearopt.validate import check_number

__all__ = ["MAX_TEETH", "name_ok", "optional_number"]

MAX_TEETH = 1000


def name_ok(name: Any, where: str) -> str:
    """Return ``name`` if it is a non-empty name of letters, digits and ``_``.

    Raises
    ------
    DesignError
        Anything else, reported at ``where``.
    """
    if not isinstance(name, str) or not name or not name.replace("_", "").isalnum():
        raise DesignError(where, name, "must be a non-empty name of letters, digits and '_'")
    return name


def optional_number(name: str, value: Any, **bounds: float) -> float | None:
    """None for None, else ``value`` checked by :func:`gearopt.validate.check_number`."""
    return None if value is None else check_number(name, value, **bounds)
