"""REXS attributes as machine models exchange them: values with their units, the manufacturing
steps of a pair's four flanks, and readers that refuse what gearopt does not model.

REXS (the gearbox data exchange format of the FVA, https://www.rexs.info) describes a bevel pair
as a ``bevel_stage`` with two ``bevel_gear`` components, each with a left and a right
``bevel_gear_flank``; a flank is cut in a ``manufacturing_step`` by a ``bevel_gear_tool`` with
``bevel_gear_manufacturing_settings``. A machine model (:meth:`gearopt.machine.BaseMachineModel.
rexs_export`) writes its settings as the attributes of those tools and settings (and of the stage),
and reads them back (:meth:`~gearopt.machine.BaseMachineModel.rexs_import`) from a
:class:`RexsMachine`. Attribute ids, units and value types are those of the released REXS
database (:data:`SCHEMA`, version :data:`REXS_VERSION`); what REXS has no attribute for is written
as a custom attribute (an id starting ``custom_``, as REXS reserves for them), prefixed
:data:`CUSTOM_PREFIX`. ``docs/rexs.md`` lists every attribute against gearopt's keys, with the
sign conventions gearopt assumes.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from gearopt.errors import RexsError

__all__ = [
    "CUSTOM_PREFIX",
    "METADATA",
    "REXS_VERSION",
    "SCHEMA",
    "RexsMachine",
    "RexsStep",
    "RexsValue",
    "custom",
    "read_array",
    "read_integer",
    "read_number",
    "read_string",
    "refuse_unmodelled",
    "standard",
]

#: the REXS version gearopt writes (the latest release) and reads
REXS_VERSION = "2.0.0"
#: the prefix of gearopt's custom attributes
CUSTOM_PREFIX = "custom_gearopt_"

#: ``attribute id: (unit, value type)`` of the REXS attributes gearopt writes or reads, as the
#: REXS 2.0.0 database gives them (checked against an extract of it by tests/test_rexs.py)
SCHEMA: dict[str, tuple[str, str]] = {
    # bevel_stage
    "shaft_angle": ("deg", "floating_point"),
    "hypoid_offset": ("mm", "floating_point"),
    "nominal_design_pressure_angle_on_drive_side": ("deg", "floating_point"),
    "nominal_design_pressure_angle_on_coast_side": ("deg", "floating_point"),
    "axial_displacement_pinion": ("mm", "floating_point"),
    "axial_displacement_gear": ("mm", "floating_point"),
    "deviation_of_offset": ("mm", "floating_point"),
    "deviation_of_shaft_angle": ("deg", "floating_point"),
    # bevel_gear
    "number_of_teeth": ("none", "integer"),
    "mean_spiral_angle": ("deg", "floating_point"),
    "spiral_angle_pitch_direction": ("none", "enum"),
    "face_width": ("mm", "floating_point"),
    "mean_cone_distance": ("mm", "floating_point"),
    "outer_addendum": ("mm", "floating_point"),
    "outer_dedendum": ("mm", "floating_point"),
    "face_angle": ("deg", "floating_point"),
    "root_angle": ("deg", "floating_point"),
    "pitch_angle": ("deg", "floating_point"),
    "mean_normal_module": ("mm", "floating_point"),
    "mean_normal_chordal_tooth_thickness": ("mm", "floating_point"),
    # bevel_gear_tool
    "blade_point_radius": ("mm", "floating_point"),
    "blade_pressure_angle": ("deg", "floating_point"),
    "blade_spheric_radius": ("mm", "floating_point"),
    "tool_edge_radius_bevel_gear_tool": ("mm", "floating_point"),
    "number_of_blade_groups_bevel_gear_tool": ("none", "integer"),
    "angle_of_blade_sequence": ("deg", "floating_point"),
    "blade_dedendum": ("mm", "floating_point"),
    "blade_profile_height": ("mm", "floating_point"),
    "protuberance_angle_bevel_gear_tool": ("deg", "floating_point"),
    "protuberance_height_bevel_gear_tool": ("mm", "floating_point"),
    "protuberance_radius_bevel_gear_tool": ("mm", "floating_point"),
    "rakeface_inclination_angle": ("deg", "floating_point"),
    "side_rake_angle": ("deg", "floating_point"),
    "tip_relief_angle_bevel_gear_tool": ("deg", "floating_point"),
    "tip_relief_height_bevel_gear_tool": ("mm", "floating_point"),
    "tip_relief_radius_bevel_gear_tool": ("mm", "floating_point"),
    "tool_profile_position_bevel_gear_tool": ("mm", "floating_point"),
    "tool_tip_height_bevel_gear_tool": ("mm", "floating_point"),
    # bevel_gear_manufacturing_settings
    "radial_distance": ("mm", "floating_point"),
    "center_roll_position": ("deg", "floating_point"),
    "machine_root_angle": ("deg", "floating_point"),
    "sliding_base": ("mm", "floating_point"),
    "work_offset": ("mm", "floating_point"),
    "machine_center_to_crossing_point": ("mm", "floating_point"),
    "ratio_of_roll": ("none", "floating_point"),
    "modified_roll_coefficients": ("none", "floating_point_array"),
    "horizontal_distance": ("mm", "floating_point"),
    "cutter_tilt": ("deg", "floating_point"),
    "cutter_swivel": ("deg", "floating_point"),
    "angular_motion_coefficients": ("none", "floating_point_array"),
    "helical_motion_coefficients": ("none", "floating_point_array"),
    "horizontal_motion_coefficients": ("none", "floating_point_array"),
    "radial_motion_coefficients": ("none", "floating_point_array"),
    "swivel_motion_coefficients": ("none", "floating_point_array"),
    "tilt_motion_coefficients": ("none", "floating_point_array"),
    "vertical_motion_coefficients": ("none", "floating_point_array"),
}

#: attributes that describe a component rather than the geometry: read and ignored
METADATA = frozenset(
    {
        "data_source",
        "modification_date",
        "part_number",
        "referenced_component_id",
        "revision_number",
        "sequence_number",
        "version",
    }
)


@dataclass(frozen=True)
class RexsValue:
    """An attribute's value and its unit as REXS names it (``"mm"``, ``"deg"``, ``"none"``)."""

    value: Any
    unit: str


def standard(attribute: str, value: Any) -> RexsValue:
    """A value of a REXS attribute in :data:`SCHEMA`, with the schema's unit."""
    if attribute not in SCHEMA:
        raise RexsError(attribute, value, "is not a REXS attribute gearopt knows (gearopt.rexs)")
    return RexsValue(value, SCHEMA[attribute][0])


def custom(name: str, value: Any, unit: str) -> tuple[str, RexsValue]:
    """``(id, value)`` of gearopt's custom attribute ``custom_gearopt_<name>``."""
    return CUSTOM_PREFIX + name, RexsValue(value, unit)


@dataclass(frozen=True, kw_only=True)
class RexsStep:
    """One manufacturing step: the tool and the machine settings that cut one flank
    (``{attribute id: RexsValue}`` each)."""

    tool: Mapping[str, RexsValue] = field(default_factory=dict)
    settings: Mapping[str, RexsValue] = field(default_factory=dict)


@dataclass(frozen=True, kw_only=True)
class RexsMachine:
    """A machine model's part of a REXS file.

    Attributes
    ----------
    stage
        Attributes of the ``bevel_stage`` (settings of the pair, e.g. the cutter module).
    steps
        ``{(member, flank): RexsStep}`` for ``member`` in ``"pinion"``/``"gear"`` and ``flank``
        in ``"convex"``/``"concave"``: the step that cuts that flank.
    """

    stage: Mapping[str, RexsValue] = field(default_factory=dict)
    steps: Mapping[tuple[str, str], RexsStep] = field(default_factory=dict)

    def step(self, member: str, flank: str) -> RexsStep:
        """The step of ``member``'s ``flank``; an error naming it when the file has none."""
        try:
            return self.steps[(member, flank)]
        except KeyError:
            raise RexsError(
                f"{member} {flank} flank",
                rule="has no manufacturing_step (bevel_gear_tool and "
                "bevel_gear_manufacturing_settings) in the REXS file",
            ) from None


_MISSING = object()


def _get(attrs: Mapping[str, RexsValue], attribute: str, where: str, unit: str, default: Any):
    if attribute not in attrs:
        if default is _MISSING:
            raise RexsError(f"{where}.{attribute}", rule="required attribute is missing")
        return _MISSING
    found = attrs[attribute]
    if found.unit != unit:
        raise RexsError(
            f"{where}.{attribute}",
            f"{found.value!r} {found.unit}",
            f"must be given in {unit!r} (the unit REXS defines for it)",
        )
    return found.value


def read_number(
    attrs: Mapping[str, RexsValue],
    attribute: str,
    where: str,
    *,
    unit: str | None = None,
    default: Any = _MISSING,
) -> float:
    """A finite number of attribute ``attribute`` in ``unit`` (default: the schema's), or
    ``default`` when absent; a :class:`~gearopt.errors.RexsError` naming it otherwise."""
    unit = unit if unit is not None else SCHEMA[attribute][0]
    value = _get(attrs, attribute, where, unit, default)
    if value is _MISSING:
        return default
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise RexsError(f"{where}.{attribute}", value, "must be a finite number")
    return float(value)


def read_integer(
    attrs: Mapping[str, RexsValue], attribute: str, where: str, *, default: Any = _MISSING
) -> int:
    """An integer attribute (unit ``none``), or ``default`` when absent."""
    value = _get(attrs, attribute, where, "none", default)
    if value is _MISSING:
        return default
    if isinstance(value, bool) or not isinstance(value, int):
        raise RexsError(f"{where}.{attribute}", value, "must be an integer")
    return value


def read_string(
    attrs: Mapping[str, RexsValue],
    attribute: str,
    where: str,
    *,
    choices: tuple[str, ...] | None = None,
    default: Any = _MISSING,
) -> str:
    """A string or enum attribute (unit ``none``), one of ``choices`` when given."""
    value = _get(attrs, attribute, where, "none", default)
    if value is _MISSING:
        return default
    if not isinstance(value, str) or (choices is not None and value not in choices):
        rule = f"must be one of {', '.join(choices)}" if choices else "must be a string"
        raise RexsError(f"{where}.{attribute}", value, rule)
    return value


def read_array(
    attrs: Mapping[str, RexsValue],
    attribute: str,
    where: str,
    *,
    unit: str | None = None,
    max_length: int | None = None,
    default: Any = _MISSING,
) -> tuple[float, ...]:
    """A floating-point array attribute (at most ``max_length`` numbers), or ``default``."""
    unit = unit if unit is not None else SCHEMA[attribute][0]
    value = _get(attrs, attribute, where, unit, default)
    if value is _MISSING:
        return default
    if not isinstance(value, list | tuple) or not all(
        isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v) for v in value
    ):
        raise RexsError(f"{where}.{attribute}", value, "must be an array of finite numbers")
    if max_length is not None and len(value) > max_length:
        raise RexsError(
            f"{where}.{attribute}",
            list(value),
            f"gearopt models at most {max_length} coefficients here; the further ones are not zero",
        )
    return tuple(float(v) for v in value)


def _is_zero(value: Any) -> bool:
    if isinstance(value, list | tuple):
        return all(_is_zero(v) for v in value)
    return isinstance(value, int | float) and not isinstance(value, bool) and value == 0


def refuse_unmodelled(
    attrs: Mapping[str, RexsValue], read: tuple[str, ...] | frozenset[str], where: str
) -> None:
    """Refuse an attribute that the reading model does not read (``read``) unless it is
    metadata (:data:`METADATA`) or zero (an empty array): a setting of another tool that gearopt
    does not model (a cutter tilt, a helical motion, a protuberance) would change the flanks."""
    for attribute, found in attrs.items():
        if attribute in read or attribute in METADATA or _is_zero(found.value):
            continue
        raise RexsError(
            f"{where}.{attribute}",
            found.value,
            "is not modelled by this machine model: gearopt cannot cut this flank as the file "
            "says (remove the attribute or set it to zero to accept the flank without it)",
        )
