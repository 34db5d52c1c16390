"""The epicycloid cutters and settings as REXS attributes (``docs/rexs.md``) and back.

Each flank is one REXS manufacturing step with its own single-radius head::

    blade_groups                  bevel_gear_tool.number_of_blade_groups_bevel_gear_tool (all agree)
    cutter_head_radius_mm         bevel_gear_tool.blade_point_radius (R_h)
    profile_pressure_angle_deg    bevel_gear_tool.blade_pressure_angle
    blade_profile_radius_mm       bevel_gear_tool.blade_spheric_radius (R_b; absent: straight)
    rake_angle_deg                bevel_gear_tool.custom_gearopt_rake_angle (deg; absent: 0)
    blade_module_mm               bevel_gear_tool.custom_gearopt_blade_module (mm; all agree;
                                    absent: the mean normal module)

Derived by gearopt and checked on import (:func:`gearopt.rexs.files.check_settings`): the
head's machine distance (``radial_distance``) and cradle angle (``center_roll_position``),
``machine_root_angle``, ``sliding_base``, ``work_offset``,
``machine_center_to_crossing_point`` and ``ratio_of_roll``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

from gearopt.design import MEMBERS
from gearopt.flank import FLANKS
from gearopt.rexs.attributes import (
    CUSTOM_PREFIX,
    RexsMachine,
    RexsStep,
    custom,
    read_integer,
    read_number,
    refuse_unmodelled,
    standard,
)
from gearopt_plugins.face_hobbing.rexs import DERIVED, agree, derived_settings

__all__ = ["from_rexs", "to_rexs"]

TOOL = {
    "cutter_head_radius_mm": "blade_point_radius",
    "profile_pressure_angle_deg": "blade_pressure_angle",
    "blade_profile_radius_mm": "blade_spheric_radius",
}
RAKE, MODULE = CUSTOM_PREFIX + "rake_angle", CUSTOM_PREFIX + "blade_module"


def to_rexs(
    machine: Any, settings: Mapping[str, Any], drive_flank: Mapping[str, str]
) -> RexsMachine:
    """The REXS attributes of an epicycloid ``machine`` with each member's basic ``settings``;
    ``drive_flank`` names the flank of each member whose settings are unprefixed (the others
    are ``coast_``)."""
    steps = {}
    for member in MEMBERS:
        for flank in FLANKS:
            spec = machine.member(member).flank(flank)
            tool = {
                "number_of_blade_groups_bevel_gear_tool": standard(
                    "number_of_blade_groups_bevel_gear_tool", int(machine.blade_groups)
                )
            }
            for key, attribute in TOOL.items():
                value = float(getattr(spec, key))
                if not math.isinf(value):
                    tool[attribute] = standard(attribute, value)
            for name, value, unit in (
                ("rake_angle", spec.rake_angle_deg, "deg"),
                ("blade_module", machine.blade_module_mm, "mm"),
            ):
                attribute, v = custom(name, float(value), unit)
                tool[attribute] = v
            prefix = "" if flank == drive_flank[member] else "coast_"
            steps[(member, flank)] = RexsStep(
                tool=tool, settings=derived_settings(settings[member], prefix)
            )
    return RexsMachine(steps=steps)


def from_rexs(machine: RexsMachine) -> dict[str, Any]:
    """The ``[machine]`` table (without ``model``) of the file's epicycloid steps."""
    tool_read = ("number_of_blade_groups_bevel_gear_tool", *TOOL.values(), RAKE, MODULE)
    groups: dict[str, int] = {}
    modules: dict[str, float] = {}
    out: dict[str, Any] = {}
    for member in MEMBERS:
        out[member] = {}
        for flank in FLANKS:
            step = machine.step(member, flank)
            where = f"bevel_gear_tool {member} {flank}"
            refuse_unmodelled(step.tool, tool_read, where)
            refuse_unmodelled(
                step.settings,
                (*DERIVED, "ratio_of_roll"),
                f"bevel_gear_manufacturing_settings {member} {flank}",
            )
            key = "number_of_blade_groups_bevel_gear_tool"
            groups[f"{where}.{key}"] = read_integer(step.tool, key, where)
            module = read_number(step.tool, MODULE, where, unit="mm", default=None)
            if module is not None:
                modules[f"{where}.{MODULE}"] = module
            out[member][flank] = {
                "cutter_head_radius_mm": read_number(step.tool, "blade_point_radius", where),
                "profile_pressure_angle_deg": read_number(step.tool, "blade_pressure_angle", where),
                "blade_profile_radius_mm": read_number(
                    step.tool, "blade_spheric_radius", where, default="inf"
                ),
                "rake_angle_deg": read_number(step.tool, RAKE, where, unit="deg", default=0.0),
            }
    out["blade_groups"] = agree(groups, "number of blade groups", "epicycloid")
    if modules:
        out["blade_module_mm"] = agree(modules, "blade module", "epicycloid")
    return out
