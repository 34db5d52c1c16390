"""The face-milling settings as REXS attributes (``docs/rexs.md``) and back.

Each flank of each member is one REXS manufacturing step: its blade (``bevel_gear_tool``) and its
machine settings (``bevel_gear_manufacturing_settings``), with the numbers of the design file
(the settings of the right-hand machine; a left-hand member is cut on its mirror image with the
same numbers, as :mod:`gearopt_plugins.face_milling` states)::

    cutter_point_radius_mm     bevel_gear_tool.blade_point_radius (at the blade's tip)
    blade_pressure_angle_deg   bevel_gear_tool.blade_pressure_angle
    blade_tip_radius_mm        bevel_gear_tool.tool_edge_radius_bevel_gear_tool
    blade_profile_radius_mm    bevel_gear_tool.blade_spheric_radius (absent: a straight blade)
    radial_setting_mm          radial_distance
    cradle_angle_deg           center_roll_position
    machine_root_angle_deg     machine_root_angle
    machine_center_to_back_mm  machine_center_to_crossing_point
    sliding_base_mm            sliding_base
    blank_offset_mm            work_offset
    ratio_of_roll              ratio_of_roll (c1, cradle turn over work turn)
    roll_c2 ... roll_c6        modified_roll_coefficients = [c2, c3, c4, c5, c6]
    work_phase_deg             custom_gearopt_work_phase (deg; absent: 0)

A file may leave out the edge radius (0), the profile radius (straight blade) and the modified
roll (none); any other attribute of the tool or the settings that is not zero (a cutter tilt, a
motion polynomial) is refused with the attribute's name.
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
    read_array,
    read_number,
    refuse_unmodelled,
    standard,
)

__all__ = ["from_rexs", "to_rexs"]

#: design key -> bevel_gear_tool attribute
TOOL = {
    "cutter_point_radius_mm": "blade_point_radius",
    "blade_pressure_angle_deg": "blade_pressure_angle",
    "blade_tip_radius_mm": "tool_edge_radius_bevel_gear_tool",
    "blade_profile_radius_mm": "blade_spheric_radius",
}
#: design key -> bevel_gear_manufacturing_settings attribute
SETTINGS = {
    "radial_setting_mm": "radial_distance",
    "cradle_angle_deg": "center_roll_position",
    "machine_root_angle_deg": "machine_root_angle",
    "machine_center_to_back_mm": "machine_center_to_crossing_point",
    "sliding_base_mm": "sliding_base",
    "blank_offset_mm": "work_offset",
    "ratio_of_roll": "ratio_of_roll",
}
ROLL = ("roll_c2", "roll_c3", "roll_c4", "roll_c5", "roll_c6")
WORK_PHASE = CUSTOM_PREFIX + "work_phase"


def to_rexs(table: Mapping[str, Any]) -> RexsMachine:
    """The REXS attributes of a face-milling ``[machine]`` table with every flank written out
    (``machine_table``)."""
    steps = {}
    for member in MEMBERS:
        for flank in FLANKS:
            values = table[member][flank]
            tool = {}
            for key, attribute in TOOL.items():
                value = values[key]
                if key == "blade_profile_radius_mm" and (
                    isinstance(value, str) or math.isinf(value)
                ):
                    continue
                tool[attribute] = standard(attribute, float(value))
            settings = {a: standard(a, float(values[k])) for k, a in SETTINGS.items()}
            settings["modified_roll_coefficients"] = standard(
                "modified_roll_coefficients", [float(values[k]) for k in ROLL]
            )
            if values["work_phase_deg"]:
                name, value = custom("work_phase", float(values["work_phase_deg"]), "deg")
                settings[name] = value
            steps[(member, flank)] = RexsStep(tool=tool, settings=settings)
    return RexsMachine(steps=steps)


def from_rexs(machine: RexsMachine) -> dict[str, Any]:
    """The ``[machine]`` table (without ``model``) of the file's face-milling steps."""
    out: dict[str, Any] = {}
    for member in MEMBERS:
        out[member] = {}
        for flank in FLANKS:
            step = machine.step(member, flank)
            where_tool = f"bevel_gear_tool {member} {flank}"
            where_set = f"bevel_gear_manufacturing_settings {member} {flank}"
            refuse_unmodelled(step.tool, tuple(TOOL.values()), where_tool)
            refuse_unmodelled(
                step.settings,
                (*SETTINGS.values(), "modified_roll_coefficients", WORK_PHASE),
                where_set,
            )
            values: dict[str, Any] = {
                "cutter_point_radius_mm": read_number(step.tool, "blade_point_radius", where_tool),
                "blade_pressure_angle_deg": read_number(
                    step.tool, "blade_pressure_angle", where_tool
                ),
                "blade_tip_radius_mm": read_number(
                    step.tool, "tool_edge_radius_bevel_gear_tool", where_tool, default=0.0
                ),
                "blade_profile_radius_mm": read_number(
                    step.tool, "blade_spheric_radius", where_tool, default="inf"
                ),
            }
            for key, attribute in SETTINGS.items():
                values[key] = read_number(step.settings, attribute, where_set)
            roll = read_array(
                step.settings,
                "modified_roll_coefficients",
                where_set,
                max_length=len(ROLL),
                default=(),
            )
            values.update({k: (roll[i] if i < len(roll) else 0.0) for i, k in enumerate(ROLL)})
            values["work_phase_deg"] = read_number(
                step.settings, WORK_PHASE, where_set, unit="deg", default=0.0
            )
            out[member][flank] = values
    return out
