"""The face-milling model's standard cutters: the Gleason face mills of
:data:`gearopt_plugins.cutters.catalogue.FACE_MILLING` that suit a design, as the categorical
search space of the gear's cutter radius (``synthesis.gear_cutter_radius_mm``, the key the
settings synthesis reads) and as its default (the suitable size nearest the mean cone distance,
the rule this model has always used, with a note saying so)."""

from __future__ import annotations

import math

from gearopt.design import PairData
from gearopt.errors import DesignError
from gearopt.machine import SearchDimension
from gearopt_plugins.cutters.catalogue import (
    FACE_MILLING,
    CutterSize,
    face_milling_rules,
    filtered,
    nearest,
)
from gearopt_plugins.face_milling.synthesis import slot_width_mm

__all__ = ["CATALOGUE_KEY", "catalogue_dimensions", "default_gear_cutter"]

#: the design key the catalogue searches (the gear's nominal cutter radius of the synthesis)
CATALOGUE_KEY = "synthesis.gear_cutter_radius_mm"


def suitable(pair: PairData) -> tuple[tuple[CutterSize, ...], str]:
    """The catalogue's face mills that can cut the gear of ``pair``, and the filter's note."""
    blank = pair.blank
    delta = math.radians(blank.dedendum_angle_deg[1])
    alpha = math.radians(max(blank.pressure_angles_deg))
    reach = blank.mean_dedendum_mm[1] * math.cos(delta) * math.tan(alpha)
    rules = face_milling_rules(
        mean_cone_distance_mm=blank.mean_cone_distance_mm,
        face_width_mm=blank.face_width_mm,
        spiral_angle_deg=blank.mean_spiral_angle_deg,
        slot_width_mm=slot_width_mm(pair),
        slot_reach_mm=reach,
    )
    return filtered(FACE_MILLING, rules)


def catalogue_dimensions(pair: PairData, has_synthesis: bool) -> tuple[SearchDimension, ...]:
    """The categorical search of the gear's cutter radius, when the design derives the gear
    from its blank (``[synthesis]``); () otherwise (given settings have no nominal radius)."""
    if not has_synthesis:
        return ()
    sizes, note = suitable(pair)
    if not sizes:
        return ()
    return (SearchDimension.categorical(CATALOGUE_KEY, [s.radius_mm for s in sizes], note),)


def default_gear_cutter(pair: PairData) -> tuple[float, str]:
    """The default gear cutter radius and the note that says where it comes from."""
    sizes, note = suitable(pair)
    if not sizes:
        raise DesignError(
            CATALOGUE_KEY,
            rule=f"is not given and no catalogue face mill suits the design ({note}): give "
            "gear_cutter_radius_mm",
        )
    size = nearest(sizes, pair.blank.mean_cone_distance_mm)
    origin = size.source if size.sourced else "an unsourced entry (docs/cutters.md)"
    return size.radius_mm, (
        f"default: no gear_cutter_radius_mm given, so the {FACE_MILLING.name} catalogue's "
        f"{size.nominal} (r_c0 = {size.radius_mm:g} mm), the suitable size nearest A_m = "
        f"{pair.blank.mean_cone_distance_mm:.3f} mm; {origin}; {note}"
    )
