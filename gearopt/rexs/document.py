"""A design as a REXS model (the JSON form, ``.rexsj``) and back: the components, relations and
the blank's attributes; the machine settings come from the design's machine model
(:meth:`gearopt.machine.BaseMachineModel.rexs_export`).

The model written: one ``bevel_stage`` (the pair: shaft angle, pressure angle, misalignment),
two ``bevel_gear`` (``gear_1`` the pinion, ``gear_2`` the gear of the ``stage`` relation), each
with a ``left`` and a ``right`` ``bevel_gear_flank`` (the ``flank`` relation) and, per flank,
a ``manufacturing_step`` relation to the ``bevel_gear_tool`` and the
``bevel_gear_manufacturing_settings`` that cut it. Left and right: looking at a tooth from its
heel toward the pitch apex, tip up, the left flank is on the left; it is the convex flank of a
left-hand member and the concave flank of a right-hand one (:func:`flank_of_side`).
"""

from __future__ import annotations

import datetime
from collections.abc import Mapping
from typing import Any

from gearopt.design import MEMBERS, Design
from gearopt.errors import RexsError
from gearopt.rexs.attributes import (
    REXS_VERSION,
    SCHEMA,
    RexsMachine,
    RexsStep,
    RexsValue,
    custom,
    standard,
)

__all__ = ["FLANK_SIDES", "components_by_type", "export_document", "flank_of_side", "parse_model"]

FLANK_SIDES = ("left", "right")
#: the attribute of each REXS value type in the JSON form
VALUE_KEYS = (
    "floating_point",
    "integer",
    "boolean",
    "string",
    "enum",
    "floating_point_array",
    "integer_array",
    "boolean_array",
    "string_array",
    "enum_array",
    "floating_point_array_coded",
    "floating_point_matrix",
    "floating_point_matrix_coded",
    "integer_matrix",
    "boolean_matrix",
    "string_matrix",
    "array_of_integer_arrays",
    "date_time",
    "file_reference",
    "reference_component",
)
#: gearopt's misalignment keys and the bevel_stage attributes that carry them
MISALIGNMENT = {
    "offset_mm": "deviation_of_offset",
    "pinion_axial_mm": "axial_displacement_pinion",
    "gear_axial_mm": "axial_displacement_gear",
    "shaft_angle_deg": "deviation_of_shaft_angle",
}
#: attributes gearopt reads whose ids REXS 2.0 renamed: their REXS 1.7 ids
RENAMED_FROM_1 = {
    "nominal_design_pressure_angle_drive": "nominal_design_pressure_angle_on_drive_side",
    "nominal_design_pressure_angle_coast": "nominal_design_pressure_angle_on_coast_side",
    "mean_normal_chordal_thickness": "mean_normal_chordal_tooth_thickness",
}
_COMPENSATION_UNITS = {"offset_mm": "mm", "pinion_axial_mm": "mm", "gear_axial_mm": "mm"}


def flank_of_side(hand: str, side: str) -> str:
    """The flank (``"convex"``/``"concave"``) on REXS's ``side`` (``"left"``/``"right"``) of
    a member of ``hand``: seen from the heel toward the apex, tip up, a left-hand member's
    convex flank is on the left (its outward normal points in the sense of increasing polar
    angle about the member's axis, the axis pointing toward the heel)."""
    convex_side = "left" if hand == "left" else "right"
    return "convex" if side == convex_side else "concave"


def _value_key(attribute: str, value: Any) -> str:
    if attribute in SCHEMA:
        return SCHEMA[attribute][1]
    if isinstance(value, bool):
        return "boolean"
    if isinstance(value, int):
        return "integer"
    if isinstance(value, float):
        return "floating_point"
    if isinstance(value, str):
        return "string"
    if isinstance(value, list | tuple):
        return "floating_point_array"
    raise RexsError(attribute, value, "has no REXS value type gearopt writes")


def _attributes(attrs: Mapping[str, RexsValue]) -> list[dict[str, Any]]:
    out = []
    for attribute, found in attrs.items():
        value = list(found.value) if isinstance(found.value, tuple) else found.value
        out.append({"id": attribute, "unit": found.unit, _value_key(attribute, value): value})
    return out


def _pair_attributes(design: Design) -> tuple[dict, dict[str, dict]]:
    """``(bevel_stage attributes, {member: bevel_gear attributes})`` of the blank."""
    pair, blank = design.pair, design.blank
    stage = {
        "shaft_angle": standard("shaft_angle", pair.shaft_angle_deg),
        "hypoid_offset": standard("hypoid_offset", 0.0),
        "nominal_design_pressure_angle_on_drive_side": standard(
            "nominal_design_pressure_angle_on_drive_side", pair.pressure_angle_deg
        ),
        "nominal_design_pressure_angle_on_coast_side": standard(
            "nominal_design_pressure_angle_on_coast_side", pair.pressure_angle_deg
        ),
    }
    for key, attribute in MISALIGNMENT.items():
        value = getattr(design.misalignment, key)
        if value:
            stage[attribute] = standard(attribute, float(value))
    for key in MISALIGNMENT:
        value = getattr(design.compensation, key)
        if value:
            name, v = custom(
                f"compensation_{key}", float(value), _COMPENSATION_UNITS.get(key, "deg")
            )
            stage[name] = v
    gears = {}
    for k, member in enumerate(MEMBERS):
        hand = pair.pinion_hand if member == "pinion" else pair.gear_hand
        attrs = {
            "number_of_teeth": standard(
                "number_of_teeth", pair.pinion_teeth if k == 0 else pair.gear_teeth
            ),
            "mean_spiral_angle": standard("mean_spiral_angle", pair.mean_spiral_angle_deg),
            "spiral_angle_pitch_direction": standard("spiral_angle_pitch_direction", hand),
            "face_width": standard("face_width", pair.face_width_mm),
            "mean_cone_distance": standard("mean_cone_distance", pair.mean_cone_distance_mm),
            "outer_addendum": standard("outer_addendum", pair.outer_addendum_mm[k]),
            "outer_dedendum": standard("outer_dedendum", pair.outer_dedendum_mm[k]),
            "pitch_angle": standard("pitch_angle", blank.pitch_angle_deg[k]),
            "mean_normal_module": standard("mean_normal_module", pair.mean_normal_module_mm),
        }
        for key, attribute in (("face_angle_deg", "face_angle"), ("root_angle_deg", "root_angle")):
            if getattr(pair, key) is not None:
                attrs[attribute] = standard(attribute, getattr(pair, key)[k])
        if pair.mean_normal_chordal_thickness_mm is not None:
            attrs["mean_normal_chordal_tooth_thickness"] = standard(
                "mean_normal_chordal_tooth_thickness", pair.mean_normal_chordal_thickness_mm[k]
            )
        if pair.mean_normal_chordal_addendum_mm is not None:
            name, v = custom(
                "mean_normal_chordal_addendum", pair.mean_normal_chordal_addendum_mm[k], "mm"
            )
            attrs[name] = v
        gears[member] = attrs
    return stage, gears


def export_document(
    design: Design, machine: RexsMachine, *, date: str | None = None, application_version: str = ""
) -> dict[str, Any]:
    """The REXS model (JSON form) of ``design`` with the machine model's attributes
    ``machine``; ``date`` (ISO 8601) defaults to now."""
    stage_attrs, gear_attrs = _pair_attributes(design)
    stage_attrs.update(machine.stage)
    name, model = custom("machine_model", design.model, "none")
    stage_attrs[name] = model
    for key in ("description", "source"):
        text = getattr(design.meta, key)
        if text:
            name, value = custom(key, text, "none")
            stage_attrs[name] = value
    components: list[dict[str, Any]] = []
    relations: list[dict[str, Any]] = []

    def add(kind: str, label: str, attrs: Mapping[str, RexsValue]) -> int:
        components.append(
            {
                "id": len(components) + 1,
                "type": kind,
                "name": label,
                "attributes": _attributes(attrs),
            }
        )
        return len(components)

    def relate(kind: str, refs: list[tuple[int, str]], order: int | None = None) -> None:
        rel: dict[str, Any] = {"id": len(relations) + 1, "type": kind}
        if order is not None:
            rel["order"] = order
        rel["refs"] = [{"id": i, "role": role} for i, role in refs]
        relations.append(rel)

    stage = add("bevel_stage", design.name, stage_attrs)
    gears = {m: add("bevel_gear", m, gear_attrs[m]) for m in MEMBERS}
    relate("stage", [(stage, "stage"), (gears["pinion"], "gear_1"), (gears["gear"], "gear_2")])
    for member in MEMBERS:
        hand = design.pair.pinion_hand if member == "pinion" else design.pair.gear_hand
        flanks = {}
        for side in FLANK_SIDES:
            flank = flank_of_side(hand, side)
            flanks[side] = add("bevel_gear_flank", f"{member} {flank}", {})
            step = machine.steps.get((member, flank))
            if step is None:
                continue
            tool = add("bevel_gear_tool", f"{member} {flank} tool", step.tool)
            settings = add(
                "bevel_gear_manufacturing_settings", f"{member} {flank} settings", step.settings
            )
            relate(
                "manufacturing_step",
                [(flanks[side], "workpiece"), (tool, "tool"), (settings, "manufacturing_settings")],
                order=1,
            )
        relate(
            "flank", [(gears[member], "gear"), (flanks["left"], "left"), (flanks["right"], "right")]
        )
    when = date or datetime.datetime.now(datetime.UTC).replace(microsecond=0).isoformat()
    return {
        "model": {
            "version": REXS_VERSION,
            "applicationId": "gearopt",
            "applicationVersion": application_version,
            "date": when,
            "applicationLanguage": "en",
            "relations": relations,
            "components": components,
        }
    }


# --- reading ---------------------------------------------------------------------------------


def _read_attributes(
    component: Mapping[str, Any], where: str, renames: Mapping[str, str]
) -> dict[str, RexsValue]:
    attrs: dict[str, RexsValue] = {}
    found = component.get("attributes", [])
    if not isinstance(found, list):
        raise RexsError(f"{where}.attributes", found, "must be a list")
    for item in found:
        if not isinstance(item, Mapping) or not isinstance(item.get("id"), str):
            raise RexsError(f"{where}.attributes", item, "each attribute needs a string id")
        attribute = renames.get(item["id"], item["id"])
        values = [k for k in item if k in VALUE_KEYS]
        if len(values) != 1:
            raise RexsError(f"{where}.{attribute}", item, "needs exactly one value")
        if attribute in attrs:
            raise RexsError(f"{where}.{attribute}", item, "is given twice")
        unit = item.get("unit", "none")
        if attribute in SCHEMA and unit != SCHEMA[attribute][0]:
            raise RexsError(
                f"{where}.{attribute}",
                f"{item[values[0]]!r} {unit}",
                f"must be given in {SCHEMA[attribute][0]!r} (the unit REXS defines for it)",
            )
        attrs[attribute] = RexsValue(item[values[0]], unit)
    return attrs


def components_by_type(document: Mapping[str, Any]) -> tuple[dict[int, dict], list[dict]]:
    """``({id: component}, relations)`` of a REXS model in the JSON form."""
    model = document.get("model") if isinstance(document, Mapping) else None
    if not isinstance(model, Mapping):
        raise RexsError("REXS file", rule='must hold a JSON object with a "model" object')
    components = model.get("components")
    relations = model.get("relations", [])
    if not isinstance(components, list) or not isinstance(relations, list):
        raise RexsError("REXS model", rule='needs a "components" list and a "relations" list')
    by_id = {}
    for c in components:
        if not isinstance(c, Mapping) or not isinstance(c.get("id"), int):
            raise RexsError("REXS model.components", c, "each component needs an integer id")
        by_id[c["id"]] = c
    return by_id, [r for r in relations if isinstance(r, Mapping)]


def _refs(relation: Mapping[str, Any]) -> dict[str, int]:
    return {ref.get("role"): ref.get("id") for ref in relation.get("refs", [])}


def _component(by_id, ident, kind: str, where: str) -> dict:
    c = by_id.get(ident)
    if c is None or c.get("type") != kind:
        raise RexsError(where, ident, f"must reference a {kind} component of the file")
    return c


def parse_model(document: Mapping[str, Any]) -> dict[str, Any]:
    """The parts of a REXS model gearopt reads: ``{"name", "stage": attrs,
    "gears": {member: attrs}, "hands": {member: hand}, "machine": RexsMachine}``; the pinion is
    the gear with fewer teeth (``gear_1`` when equal)."""
    by_id, relations = components_by_type(document)
    model = document["model"]
    version = str(model.get("version", ""))
    if version.split(".")[0] not in ("1", "2"):
        raise RexsError("REXS model.version", version, "gearopt reads REXS 1.x and 2.x files")
    renames = RENAMED_FROM_1 if version.startswith("1") else {}
    stages = [r for r in relations if r.get("type") == "stage"]
    bevel = [r for r in stages if by_id.get(_refs(r).get("stage"), {}).get("type") == "bevel_stage"]
    if len(bevel) != 1:
        raise RexsError(
            "REXS model.relations",
            len(bevel),
            "gearopt reads a file with exactly one bevel_stage and its stage relation",
        )
    refs = _refs(bevel[0])
    stage = _component(by_id, refs.get("stage"), "bevel_stage", "stage relation.stage")
    pair = [
        _component(by_id, refs.get(role), "bevel_gear", f"stage relation.{role}")
        for role in ("gear_1", "gear_2")
    ]
    attrs = [_read_attributes(c, f"bevel_gear {c.get('name') or c['id']}", renames) for c in pair]
    teeth = [a.get("number_of_teeth", RexsValue(None, "none")).value for a in attrs]
    counted = all(isinstance(t, int) and not isinstance(t, bool) for t in teeth)
    order = (1, 0) if counted and teeth[1] < teeth[0] else (0, 1)
    gears = {m: pair[i] for m, i in zip(MEMBERS, order, strict=True)}
    gear_attrs = {m: attrs[i] for m, i in zip(MEMBERS, order, strict=True)}
    hands = {}
    for member in MEMBERS:
        hand = gear_attrs[member].get("spiral_angle_pitch_direction")
        if hand is None or hand.value not in ("left", "right"):
            raise RexsError(
                f"bevel_gear {member}.spiral_angle_pitch_direction",
                None if hand is None else hand.value,
                "required: left or right",
            )
        hands[member] = hand.value
    steps: dict[tuple[str, str], RexsStep] = {}
    for member in MEMBERS:
        gear_id = gears[member]["id"]
        rels = [
            r for r in relations if r.get("type") == "flank" and _refs(r).get("gear") == gear_id
        ]
        if not rels:
            continue
        flank_refs = _refs(rels[0])
        for side in FLANK_SIDES:
            flank_id = flank_refs.get(side)
            if flank_id is None:
                continue
            flank = flank_of_side(hands[member], side)
            cuts = sorted(
                (
                    r
                    for r in relations
                    if r.get("type") == "manufacturing_step"
                    and _refs(r).get("workpiece") == flank_id
                ),
                key=lambda r: r.get("order", 0),
            )
            if not cuts:
                continue
            # the last step (the highest order) is the finishing cut that leaves the flank
            cut = _refs(cuts[-1])
            where = f"{member} {flank} ({side}) flank"
            tool = _component(by_id, cut.get("tool"), "bevel_gear_tool", f"{where} tool")
            settings = _component(
                by_id,
                cut.get("manufacturing_settings"),
                "bevel_gear_manufacturing_settings",
                f"{where} manufacturing_settings",
            )
            steps[(member, flank)] = RexsStep(
                tool=_read_attributes(tool, f"bevel_gear_tool {member} {flank}", renames),
                settings=_read_attributes(
                    settings, f"bevel_gear_manufacturing_settings {member} {flank}", renames
                ),
            )
    stage_attrs = _read_attributes(stage, "bevel_stage", renames)
    return {
        "name": stage.get("name") or "",
        "stage": stage_attrs,
        "gears": gear_attrs,
        "hands": hands,
        "machine": RexsMachine(stage=stage_attrs, steps=steps),
    }
