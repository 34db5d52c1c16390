"""The cyclo-palloid cutter and settings as REXS attributes (``docs/rexs.md``) and back.

Each flank is one REXS manufacturing step: the inner blades cut the convex flank, the outer
blades the concave flank. Read back (the design's inputs)::

    blade_groups                       bevel_gear_tool.number_of_blade_groups_bevel_gear_tool
    inner_cutter_radius_mm (convex),   bevel_gear_tool.blade_point_radius (the blades' radius
      outer_cutter_radius_mm (concave)   at the pitch line, seed 001's r_ci and r_co)
    profile_pressure_angle_deg         bevel_gear_tool.blade_pressure_angle
    blade_module_mm                    bevel_gear_tool.custom_gearopt_blade_module (mm)
    blade_parabola_coefficient_per_mm  bevel_gear_tool.custom_gearopt_blade_parabola_coefficient
    parabola_apex_mm                   bevel_gear_tool.custom_gearopt_parabola_apex (mm)
    rake_angle_deg                     bevel_gear_tool.custom_gearopt_rake_angle (deg)
    additional_slope_angle_deg         bevel_gear_manufacturing_settings.
                                         custom_gearopt_additional_slope_angle (deg; the value
                                         solved from the thickness when the design says "auto";
                                         absent: 0)

Written for information, derived by gearopt from the above and the blank, not read back: the
machine distance (``radial_distance``) and cradle angle (``center_roll_position``) of the
flank's blade system, ``machine_root_angle``, ``sliding_base``, ``work_offset``,
``machine_center_to_crossing_point`` and ``ratio_of_roll`` (cradle over work turn, 1 / m_gc).
"""

from __future__ import annotations

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

BLADES = {"convex": "inner", "concave": "outer"}
#: custom tool attributes: design key -> (name, unit)
CUSTOM_TOOL = {
    "blade_module_mm": ("blade_module", "mm"),
    "blade_parabola_coefficient_per_mm": ("blade_parabola_coefficient", "1 / mm"),
    "parabola_apex_mm": ("parabola_apex", "mm"),
    "rake_angle_deg": ("rake_angle", "deg"),
}
SLOPE = CUSTOM_PREFIX + "additional_slope_angle"


def to_rexs(machine: Any, settings: Mapping[str, Any]) -> RexsMachine:
    """The REXS attributes of a cyclo-palloid ``machine`` (its parsed ``[machine]`` table)
    with each member's basic ``settings`` (``{member: CycloPalloidSettings}``)."""
    steps = {}
    for member in MEMBERS:
        spec, basic = machine.member(member), settings[member]
        for flank in FLANKS:
            blades = BLADES[flank]
            tool = {
                "number_of_blade_groups_bevel_gear_tool": standard(
                    "number_of_blade_groups_bevel_gear_tool", int(machine.blade_groups)
                ),
                "blade_point_radius": standard(
                    "blade_point_radius", float(getattr(spec, f"{blades}_cutter_radius_mm"))
                ),
                "blade_pressure_angle": standard(
                    "blade_pressure_angle", float(spec.profile_pressure_angle_deg)
                ),
            }
            values = {
                "blade_module_mm": machine.blade_module_mm,
                "blade_parabola_coefficient_per_mm": spec.blade_parabola_coefficient_per_mm,
                "parabola_apex_mm": spec.parabola_apex_mm,
                "rake_angle_deg": spec.rake_angle_deg,
            }
            for key, (name, unit) in CUSTOM_TOOL.items():
                attribute, value = custom(name, float(values[key]), unit)
                tool[attribute] = value
            derived = derived_settings(basic, f"{blades}_")
            name, value = custom("additional_slope_angle", basic.additional_slope_angle_deg, "deg")
            steps[(member, flank)] = RexsStep(tool=tool, settings={name: value, **derived})
    return RexsMachine(steps=steps)


def from_rexs(machine: RexsMachine) -> dict[str, Any]:
    """The ``[machine]`` table (without ``model``) of the file's cyclo-palloid steps."""
    tool_read = (
        "number_of_blade_groups_bevel_gear_tool",
        "blade_point_radius",
        "blade_pressure_angle",
        *(CUSTOM_PREFIX + name for name, _ in CUSTOM_TOOL.values()),
    )
    shared: dict[str, dict[str, Any]] = {"blade_groups": {}, "blade_module_mm": {}}
    out: dict[str, Any] = {}
    for member in MEMBERS:
        member_values: dict[str, dict[str, Any]] = {}
        table: dict[str, Any] = {}
        for flank in FLANKS:
            step = machine.step(member, flank)
            where_tool = f"bevel_gear_tool {member} {flank}"
            where_set = f"bevel_gear_manufacturing_settings {member} {flank}"
            refuse_unmodelled(step.tool, tool_read, where_tool)
            refuse_unmodelled(step.settings, (SLOPE, *DERIVED, "ratio_of_roll"), where_set)
            table[f"{BLADES[flank]}_cutter_radius_mm"] = read_number(
                step.tool, "blade_point_radius", where_tool
            )
            shared["blade_groups"][f"{where_tool}.number_of_blade_groups_bevel_gear_tool"] = (
                read_integer(step.tool, "number_of_blade_groups_bevel_gear_tool", where_tool)
            )
            for key, (name, unit) in CUSTOM_TOOL.items():
                value = read_number(
                    step.tool, CUSTOM_PREFIX + name, where_tool, unit=unit, default=None
                )
                if value is None:
                    continue
                found = (
                    shared[key] if key == "blade_module_mm" else member_values.setdefault(key, {})
                )
                found[f"{where_tool}.{CUSTOM_PREFIX}{name}"] = value
            member_values.setdefault("profile_pressure_angle_deg", {})[
                f"{where_tool}.blade_pressure_angle"
            ] = read_number(step.tool, "blade_pressure_angle", where_tool)
            member_values.setdefault("additional_slope_angle_deg", {})[f"{where_set}.{SLOPE}"] = (
                read_number(step.settings, SLOPE, where_set, unit="deg", default=0.0)
            )
        for key, found in member_values.items():
            table[key] = agree(found, key, "cyclo-palloid")
        out[member] = table
    out["blade_groups"] = agree(shared["blade_groups"], "number of blade groups", "cyclo-palloid")
    if shared["blade_module_mm"]:
        out["blade_module_mm"] = agree(shared["blade_module_mm"], "blade module", "cyclo-palloid")
    return out
