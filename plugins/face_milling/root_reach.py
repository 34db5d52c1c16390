"""Root reach of a face-milling set-up: does the blade's tip reach the member's root line?

The root line is the root cone's generatrix nearest the cradle at centre roll; the blade's tip is
the plane z_m = 0 of the cutter (the machine frame of :mod:`gearopt_plugins.face_milling`). Where
the tip stays above the line by less than the member's clearance the root is cut there,
shallower: a :class:`~gearopt.errors.GearoptWarning` (setting errors and corrections of some
hundredths do this); by the clearance or more the mating tip would hit the root: a
:class:`~gearopt.errors.DesignError`.
"""

from __future__ import annotations

import math
import warnings

from gearopt.errors import DesignError, GearoptWarning

__all__ = ["ROOT_REACH_TOL_MM", "check_root_reach", "root_height_mm"]

#: how far (mm) the tip may stay above the root line and still count as reaching it
ROOT_REACH_TOL_MM = 1e-6


def root_height_mm(spec, blank, index: int, cone_distance_mm):
    """z_m of the member's root line at a cone distance (``spec``: a flank's settings, a
    ``FaceMillingFlank``): the blade's tip (the plane z_m = 0) reaches it where this is <= 0.
    The line is linear in the cone distance, so toe and heel bound it."""
    g = math.radians(spec.machine_root_angle_deg)
    dg = g - math.radians(blank.pitch_angle_deg[index])
    apex_z = spec.machine_center_to_back_mm * math.sin(g) - spec.sliding_base_mm
    return (
        apex_z
        + cone_distance_mm * math.sin(dg)
        + blank.dedendum_at_mm(index, cone_distance_mm) * math.cos(dg)
    )


def check_root_reach(spec, blank, index: int, where: str) -> None:
    """The blade's tip should reach the root line over the whole face (toe and heel; the root
    cone's generatrix with tapered depth). Where it stays above the line by less than the
    clearance the root is cut there, shallower (a warning: setting errors and corrections of
    some hundredths do this); by more, the mating tip would hit the root (an error)."""
    ends = (("toe", blank.inner_cone_distance_mm), ("heel", blank.outer_cone_distance_mm))
    heights = [(root_height_mm(spec, blank, index, a), name, a) for name, a in ends]
    root_z, name, a = max(heights)
    if root_z <= ROOT_REACH_TOL_MM:
        return
    clearance = blank.clearance_mm[index]
    where_z = (
        f"its tip stays {root_z:.4f} mm above the root line at the {name} (cone distance "
        f"{a:.3f} mm)"
    )
    if root_z >= clearance:
        raise DesignError(
            f"{where}.sliding_base_mm",
            spec.sliding_base_mm,
            f"the blade cannot reach the root: {where_z}, no less than the clearance "
            f"{clearance:.4f} mm, so the mating tip would hit the root; the tip must reach "
            "the root cone over the whole face (sliding_base_mm, machine_center_to_back_mm "
            "and machine_root_angle_deg place the work; module docstring)",
        )
    warnings.warn(
        GearoptWarning(
            f"{where}.sliding_base_mm = {spec.sliding_base_mm:.6g}: the blade's tip does not "
            f"reach the root line: {where_z}; the root is cut there and the clearance shrinks "
            f"to {clearance - root_z:.4f} mm"
        ),
        stacklevel=2,
    )
