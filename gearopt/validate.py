"""Reading validated values out of design tables.

Small helpers shared by the design loader and by machine-model plugins: each reads one key of a
TOML table, checks its type and range, and raises a :class:`~gearopt.errors.DesignError` naming
the dotted parameter, the value and the rule. Plugin authors use them so that their machine
tables report bad input exactly as the core format does.
"""

from __future__ import annotations

import difflib
import math
import tomllib
from collections.abc import Callable, Iterable, Mapping
from pathlib import Path
from typing import Any

from gearopt.errors import DesignError, GearoptError, UnknownKeyError

__all__ = [
    "check_keys",
    "check_number",
    "check_integer",
    "read_number",
    "read_integer",
    "read_choice",
    "read_member_pair",
    "read_table",
    "read_toml",
    "read_toml_file",
    "MAX_TOML_CHARACTERS",
]

#: the longest design or study file read (characters): the largest real ones hold a few thousand
MAX_TOML_CHARACTERS = 1_000_000


def read_toml_file(path: Path, error: Callable[[str], GearoptError]) -> dict:
    """The tables of a design or study file (:func:`read_toml`); a file that does not exist or
    cannot be read as UTF-8 text raises ``error(rule)`` too."""
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise error("does not exist") from None
    except (IsADirectoryError, UnicodeDecodeError, PermissionError) as exc:
        raise error(f"cannot be read as UTF-8 text ({exc})") from None
    return read_toml(text, error)


def read_toml(text: str, error: Callable[[str], GearoptError]) -> dict:
    """The tables of a design or study file's TOML text. A UTF-8 byte-order mark is dropped;
    text over :data:`MAX_TOML_CHARACTERS`, malformed TOML and nesting deeper than the parser
    goes raise ``error(rule)``."""
    if text.startswith("\ufeff"):
        text = text[1:]
    if len(text) > MAX_TOML_CHARACTERS:
        raise error(
            f"holds {len(text)} characters: a design or study file holds at most "
            f"{MAX_TOML_CHARACTERS}"
        )
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise error(f"malformed TOML: {exc}") from None
    except RecursionError:
        raise error("malformed TOML: arrays or tables nested too deeply") from None


_UNIT_SUFFIXES = ("_mm", "_deg", "_rad", "_in", "_inch", "_m", "_um", "_arcsec", "_per_mm")


def _stem(key: str) -> str:
    for suffix in sorted(_UNIT_SUFFIXES, key=len, reverse=True):
        if key.endswith(suffix):
            return key[: -len(suffix)]
    return key


def check_keys(table: Mapping[str, Any], allowed: Iterable[str], where: str) -> None:
    """Raise :class:`UnknownKeyError` for the first key of ``table`` not in ``allowed``.

    The message suggests the closest allowed key, and says so when only the unit suffix differs
    (``face_width_in`` for ``face_width_mm``): gearopt takes millimetres and degrees only.
    """
    allowed = list(allowed)
    for key in table:
        if key in allowed:
            continue
        same_stem = [a for a in allowed if _stem(a) == _stem(key)]
        if same_stem:
            rule = (
                f"unknown key; units are part of the key name and gearopt takes "
                f"millimetres and degrees: did you mean '{same_stem[0]}' (convert the value)?"
            )
        else:
            close = difflib.get_close_matches(key, allowed, n=1)
            hint = f" did you mean '{close[0]}'?" if close else ""
            rule = f"unknown key; allowed keys are {sorted(allowed)}.{hint}"
        name = f"{where}.{key}" if where else key
        raise UnknownKeyError(name, table[key], rule)


def read_table(table: Mapping[str, Any], key: str, where: str) -> dict[str, Any]:
    """Return the sub-table ``key`` of ``table`` (empty if absent); it must be a table."""
    value = table.get(key, {})
    name = f"{where}.{key}" if where else key
    if not isinstance(value, Mapping):
        raise DesignError(name, value, "must be a table ([section] in TOML)")
    return dict(value)


def _as_float(value: Any, name: str, unit: str) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float):
        unit_text = f" in {unit}" if unit else ""
        raise DesignError(name, value, f"must be a number{unit_text} (no units in the value)")
    result = float(value)
    if not math.isfinite(result):
        raise DesignError(name, value, "must be a finite number")
    return result


def _unit_of(key: str) -> str:
    for suffix, unit in (("_mm", "mm"), ("_deg", "degrees"), ("_per_mm", "1/mm"), ("_um", "um")):
        if key.endswith(suffix):
            return unit
    return ""


def _check_range(
    value: float,
    name: str,
    *,
    gt: float | None,
    ge: float | None,
    lt: float | None,
    le: float | None,
) -> None:
    parts = []
    if gt is not None:
        parts.append(f"> {gt:g}")
    if ge is not None:
        parts.append(f">= {ge:g}")
    if lt is not None:
        parts.append(f"< {lt:g}")
    if le is not None:
        parts.append(f"<= {le:g}")
    ok = (
        (gt is None or value > gt)
        and (ge is None or value >= ge)
        and (lt is None or value < lt)
        and (le is None or value <= le)
    )
    if not ok:
        raise DesignError(name, value, "must be " + " and ".join(parts))


def check_number(
    name: str,
    value: Any,
    *,
    gt: float | None = None,
    ge: float | None = None,
    lt: float | None = None,
    le: float | None = None,
    unit: str = "",
) -> float:
    """Check that ``value`` is a finite number within the bounds; return it as a float."""
    number = _as_float(value, name, unit)
    _check_range(number, name, gt=gt, ge=ge, lt=lt, le=le)
    return number


def check_integer(name: str, value: Any, *, ge: int | None = None, le: int | None = None) -> int:
    """Check that ``value`` is an integer (not a float, not a bool) within the bounds."""
    if isinstance(value, bool) or not isinstance(value, int):
        raise DesignError(name, value, "must be an integer (a count, written without a point)")
    _check_range(value, name, gt=None, ge=ge, lt=None, le=le)
    return int(value)


_REQUIRED = object()


def _lookup(table: Mapping[str, Any], key: str, where: str, default: Any) -> tuple[str, bool]:
    """Dotted name of ``key`` and whether it is present; a missing required key raises."""
    name = f"{where}.{key}" if where else key
    if key not in table and default is _REQUIRED:
        raise DesignError(name, rule="required key is missing")
    return name, key in table


def read_number(
    table: Mapping[str, Any],
    key: str,
    where: str,
    default: Any = _REQUIRED,
    *,
    gt: float | None = None,
    ge: float | None = None,
    lt: float | None = None,
    le: float | None = None,
) -> float:
    """Read a finite float, optionally bounded; ``default`` makes the key optional."""
    name, present = _lookup(table, key, where, default)
    if not present:
        return default
    return check_number(name, table[key], gt=gt, ge=ge, lt=lt, le=le, unit=_unit_of(key))


def read_integer(
    table: Mapping[str, Any],
    key: str,
    where: str,
    default: Any = _REQUIRED,
    *,
    ge: int | None = None,
    le: int | None = None,
) -> int:
    """Read an integer (a float such as ``16.0`` or ``16.5`` is refused), optionally bounded."""
    name, present = _lookup(table, key, where, default)
    if not present:
        return default
    return check_integer(name, table[key], ge=ge, le=le)


def read_choice(
    table: Mapping[str, Any],
    key: str,
    where: str,
    choices: Iterable[str],
    default: Any = _REQUIRED,
) -> str:
    """Read a string that must be one of ``choices`` (compared in lower case)."""
    name = f"{where}.{key}" if where else key
    choices = tuple(choices)
    if key not in table:
        if default is _REQUIRED:
            raise DesignError(name, rule=f"required key is missing; one of {list(choices)}")
        return default
    value = table[key]
    if not isinstance(value, str) or value.lower() not in choices:
        raise DesignError(name, value, f"must be one of {list(choices)}")
    return value.lower()


def read_member_pair(
    table: Mapping[str, Any],
    key: str,
    where: str,
    default: Any = _REQUIRED,
    *,
    gt: float | None = None,
    ge: float | None = None,
    lt: float | None = None,
) -> tuple[float, float]:
    """Read a ``[pinion, gear]`` pair of numbers; a single number applies to both members."""
    name = f"{where}.{key}" if where else key
    if key not in table:
        if default is _REQUIRED:
            raise DesignError(name, rule="required key is missing; give [pinion, gear]")
        return default
    value = table[key]
    if isinstance(value, int | float) and not isinstance(value, bool):
        value = [value, value]
    if not isinstance(value, list | tuple) or len(value) != 2:
        raise DesignError(name, value, "must be a list of two numbers [pinion, gear]")
    out = []
    for member, item in zip(("pinion", "gear"), value, strict=True):
        item_name = f"{name}[{member}]"
        number = _as_float(item, item_name, _unit_of(key))
        _check_range(number, item_name, gt=gt, ge=ge, lt=lt, le=None)
        out.append(number)
    return out[0], out[1]
