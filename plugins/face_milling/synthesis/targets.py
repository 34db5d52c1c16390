"""What local synthesis asks and answers: the ``[synthesis]`` table read into targets per
side (:class:`SideTargets`, :func:`read_synthesis`), the keys of the settings it chooses and
solves, its closing tolerances and its report (:class:`SynthesisReport`).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from gearopt.blank import Blank
from gearopt.errors import DesignError
from gearopt.mesh import ToothFrame
from gearopt.validate import check_keys, read_number, read_table

__all__ = [
    "CHOSEN_KEYS",
    "SIDES",
    "SOLVED_KEYS",
    "SYNTHESIS_KEYS",
    "TARGET_KEYS",
    "TOLERANCE",
    "SideTargets",
    "SynthesisReport",
    "read_synthesis",
]

SIDES = {"drive": ("convex", "concave"), "coast": ("concave", "convex")}  # pinion, gear flank
TARGET_KEYS = (
    "mean_point_face_mm",
    "mean_point_profile_mm",
    "path_angle_deg",
    "ellipse_major_axis_mm",
    "compound_um",
    "te_level_arcsec",
)
SYNTHESIS_KEYS = (*TARGET_KEYS, "gear_cutter_radius_mm", "backlash_mm", *SIDES)
#: keys of [machine.pinion] / [machine.pinion.<flank>] chosen before the synthesis
CHOSEN_KEYS = (
    "cutter_point_radius_mm",
    "blade_pressure_angle_deg",
    "blade_profile_radius_mm",
    "machine_root_angle_deg",
    "machine_center_to_back_mm",
)
SOLVED_KEYS = (
    "radial_setting_mm",
    "cradle_angle_deg",
    "blank_offset_mm",
    "sliding_base_mm",
    "ratio_of_roll",
    "roll_c2",
)
#: closing tolerances of the synthesis (met or SettingsError)
TOLERANCE = {"first_order": 1e-7, "path_deg": 1e-2, "relative": 1e-3}


@dataclass(frozen=True, kw_only=True)
class SideTargets:
    """What local synthesis asks of one side (``[synthesis]``, ``[synthesis.<side>]``)."""

    side: str
    mean_point_face_mm: float
    mean_point_profile_mm: float
    path_angle_deg: float
    ellipse_major_axis_mm: float
    compound_um: float
    te_level_arcsec: float


@dataclass(frozen=True, kw_only=True)
class SynthesisReport:
    """How the synthesis of one pinion flank closed: the targets, what the local analysis of
    the solved settings gives, the solver's evaluations."""

    targets: SideTargets
    path_angle_deg: float
    ellipse_major_axis_mm: float
    te_level_arcsec: float
    first_order_residual: float
    evaluations: int
    gear_turn_rad: float

    def as_dict(self) -> dict:
        t = self.targets
        return {
            "side": t.side,
            "mean_point_mm": [t.mean_point_face_mm, t.mean_point_profile_mm],
            "asked": {
                "path_angle_deg": t.path_angle_deg,
                "ellipse_major_axis_mm": t.ellipse_major_axis_mm,
                "te_level_arcsec": t.te_level_arcsec,
                "compound_um": t.compound_um,
            },
            "local": {
                "path_angle_deg": self.path_angle_deg,
                "ellipse_major_axis_mm": self.ellipse_major_axis_mm,
                "te_level_arcsec": self.te_level_arcsec,
                "first_order_residual": self.first_order_residual,
            },
            "evaluations": self.evaluations,
        }


def read_synthesis(table: Mapping[str, Any], blank: Blank) -> tuple[dict, dict]:
    """``({side: SideTargets}, options)`` from the ``[synthesis]`` table; options:
    ``gear_cutter_radius_mm`` (None: the default) and ``backlash_mm`` (default 0)."""
    check_keys(table, SYNTHESIS_KEYS, "synthesis")

    centre = ToothFrame.from_blank(blank).centre_mm
    common = {k: v for k, v in table.items() if k in TARGET_KEYS}
    tables = {side: read_table(table, side, "synthesis") for side in SIDES}
    missing = [
        f"{key} ({side})"
        for side in SIDES
        for key in ("path_angle_deg", "ellipse_major_axis_mm", "te_level_arcsec")
        if key not in {**common, **tables[side]}
    ]
    if missing:  # all of them at once, not one error at a time
        raise DesignError(
            "synthesis",
            rule=f"local synthesis needs {', '.join(missing)}: give each in [synthesis] for "
            "both sides or in [synthesis.drive] / [synthesis.coast]",
        )
    out = {}
    for side in SIDES:
        own = tables[side]
        check_keys(own, TARGET_KEYS, f"synthesis.{side}")
        merged = {**common, **own}
        where = f"synthesis.{side}" if own else "synthesis"
        face = read_number(merged, "mean_point_face_mm", where, centre[0])
        if not 0.0 < face < blank.face_width_mm:
            raise DesignError(
                f"{where}.mean_point_face_mm",
                face,
                f"must lie inside the face width (0, {blank.face_width_mm:g}) mm",
            )
        depth = blank.mean_dedendum_mm[0] + blank.mean_addendum_mm[0]
        profile = read_number(merged, "mean_point_profile_mm", where, centre[1])
        if not 0.0 < profile < depth:
            raise DesignError(
                f"{where}.mean_point_profile_mm",
                profile,
                f"must lie on the pinion flank, between its root (0) and top ({depth:.3f}) mm",
            )
        ellipse = read_number(merged, "ellipse_major_axis_mm", where, gt=0.0)
        if ellipse >= blank.face_width_mm:
            raise DesignError(
                f"{where}.ellipse_major_axis_mm",
                ellipse,
                f"the contact ellipse must be shorter than the face width "
                f"{blank.face_width_mm:g} mm (its projection on the flank)",
            )
        level = read_number(merged, "te_level_arcsec", where)
        if level == 0.0 or abs(level) > 300.0:
            raise DesignError(
                f"{where}.te_level_arcsec",
                level,
                "must be non-zero (a parabolic transmission error; its sign is ignored: the "
                "TE is negative away from M) and at most 300 arcsec in magnitude",
            )
        out[side] = SideTargets(
            side=side,
            mean_point_face_mm=face,
            mean_point_profile_mm=profile,
            path_angle_deg=read_number(merged, "path_angle_deg", where, gt=-90.0, le=90.0),
            ellipse_major_axis_mm=ellipse,
            compound_um=read_number(merged, "compound_um", where, 6.5, gt=0.0, le=100.0),
            te_level_arcsec=-abs(level),
        )
    radius = table.get("gear_cutter_radius_mm")
    if radius is not None:
        radius = read_number(table, "gear_cutter_radius_mm", "synthesis", gt=0.0)
    backlash = read_number(table, "backlash_mm", "synthesis", 0.0, ge=0.0, le=1.0)
    return out, {"gear_cutter_radius_mm": radius, "backlash_mm": backlash}
