"""REXS helpers the face-hobbing models share (cyclo-palloid, epicycloid; ``docs/rexs.md``):
the settings they derive and write for gearopt's check, and one value several steps must agree
on."""

from __future__ import annotations

from typing import Any

from gearopt.errors import RexsError
from gearopt.rexs.attributes import RexsValue, standard

__all__ = ["DERIVED", "agree", "derived_settings"]

#: derived settings written for the import's check: attribute -> settings field, ``{p}`` the
#: blade system's prefix (cyclo-palloid ``inner_``/``outer_``, epicycloid ``""``/``coast_``)
DERIVED = {
    "radial_distance": "{p}machine_distance_mm",
    "center_roll_position": "{p}cradle_angle_deg",
    "machine_root_angle": "machine_root_angle_deg",
    "sliding_base": "sliding_base_mm",
    "work_offset": "blank_offset_mm",
    "machine_center_to_crossing_point": "machine_center_to_back_mm",
}


def derived_settings(settings: Any, prefix: str) -> dict[str, RexsValue]:
    """The REXS settings attributes of a member's basic ``settings`` for the blade system
    ``prefix``, with ``ratio_of_roll`` as cradle over work turn (1 / m_gc)."""
    out = {a: standard(a, float(getattr(settings, f.format(p=prefix)))) for a, f in DERIVED.items()}
    out["ratio_of_roll"] = standard("ratio_of_roll", 1.0 / settings.gear_to_cradle_roll)
    return out


def agree(found: dict[str, Any], what: str, model: str) -> Any:
    """The one value the steps give (``{where: value}``), else an error naming the step
    that differs."""
    first_where, first = next(iter(found.items()))
    for where, value in found.items():
        if value != first:
            raise RexsError(
                where,
                value,
                f"the {model} model has one {what} here; {first_where} gives {first!r}",
            )
    return first
