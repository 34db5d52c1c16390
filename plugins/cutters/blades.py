"""Blade keys that several machine models share, read the same way (the same key names serve
every model where the meaning is the same).

``blade_profile_radius_mm``: the radius of a circular-arc blade profile, tangent to the straight
blade at its pitch-line point with its centre on the tooth material's side (profile crowning),
or ``"inf"`` for a straight blade (epicycloid, face milling).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

from gearopt.errors import DesignError
from gearopt.validate import read_number

__all__ = ["INFINITE", "MIN_PROFILE_RADIUS_DEPTHS", "read_profile_radius"]

INFINITE = "inf"
#: a profile radius must exceed this many whole depths: the arc then turns by less than about
#: 30 deg over the blade, far from the quarter turn where the edge would fold back
MIN_PROFILE_RADIUS_DEPTHS = 2.0


def read_profile_radius(table: Mapping[str, Any], where: str, min_mm: float) -> float:
    """``blade_profile_radius_mm`` of ``table`` (default straight: ``math.inf``), which must
    exceed ``min_mm`` (``MIN_PROFILE_RADIUS_DEPTHS`` whole depths)."""
    value = table.get("blade_profile_radius_mm", INFINITE)
    name = f"{where}.blade_profile_radius_mm"
    if isinstance(value, str):
        if value.strip().lower() not in ("inf", "infinity", "+inf"):
            raise DesignError(name, value, 'must be a radius in mm or "inf" (a straight blade)')
        return math.inf
    radius = read_number(table, "blade_profile_radius_mm", where, gt=0.0)
    if radius <= min_mm:
        raise DesignError(
            name,
            radius,
            f"must exceed {MIN_PROFILE_RADIUS_DEPTHS:g} whole depths = {min_mm:.3f} mm (the arc "
            'must not turn far over the blade); "inf" for a straight blade',
        )
    return radius
