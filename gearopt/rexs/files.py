"""Export a design to a REXS file and read a REXS file into a design (``gearopt rexs``).

:func:`export_rexs` builds the REXS model of a design (the blank here, the settings by the
design's machine model, :meth:`gearopt.machine.BaseMachineModel.rexs_export`);
:func:`write_rexs` writes it in the JSON form (``.rexsj``). :func:`rexs_tables` reads a REXS
model back into the tables of a design file (``[meta]``, ``[pair]``, ``[machine]``,
``[misalignment]``, ``[compensation]``), the settings by the machine model the file names
(gearopt's custom attribute ``custom_gearopt_machine_model`` of the ``bevel_stage``) or the
caller gives; :func:`load_rexs` parses them into a :class:`~gearopt.design.Design`. A design
written and read back cuts identical flanks. What is not written: ``[analysis]``, ``[load]``,
``[te_target]``, ``[synthesis]`` (its settings are written out) and ``[blank]`` (its blank is).
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from gearopt.design import MEMBERS, Design, PairData, pair_from_table
from gearopt.design_files import parse_design
from gearopt.errors import GearoptError, RexsError
from gearopt.plugins import get_machine_model
from gearopt.rexs.attributes import (
    CUSTOM_PREFIX,
    RexsMachine,
    RexsValue,
    read_integer,
    read_number,
    read_string,
)
from gearopt.rexs.document import MISALIGNMENT, export_document, parse_model

if TYPE_CHECKING:
    import pluggy

__all__ = [
    "check_settings",
    "export_rexs",
    "load_rexs",
    "read_rexs_file",
    "read_rexs_model",
    "rexs_tables",
    "write_rexs",
]


def export_rexs(
    design: Design, *, date: str | None = None, plugin_manager: pluggy.PluginManager | None = None
) -> dict[str, Any]:
    """The REXS model of ``design`` in the JSON form (a dict for :func:`json.dumps`)."""
    model = get_machine_model(design.model, plugin_manager=plugin_manager)
    try:
        application_version = version("gearopt")
    except PackageNotFoundError:
        application_version = ""
    return export_document(
        design, model.rexs_export(design), date=date, application_version=application_version
    )


def write_rexs(
    design: Design,
    path: str | Path,
    *,
    date: str | None = None,
    plugin_manager: pluggy.PluginManager | None = None,
) -> dict[str, Any]:
    """Write ``design`` to ``path`` as a REXS JSON file; returns the model written."""
    document = export_rexs(design, date=date, plugin_manager=plugin_manager)
    Path(path).write_text(json.dumps(document, indent=2) + "\n", encoding="utf-8")
    return document


def read_rexs_file(path: str | Path) -> dict[str, Any]:
    """The REXS model of a JSON file (``.rexsj``); the XML form is refused with a
    :class:`~gearopt.errors.RexsError`."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise RexsError("REXS file", str(path), f"cannot be read: {exc.strerror}") from None
    if text.lstrip().startswith("<"):
        raise RexsError(
            "REXS file",
            str(path),
            "is in REXS's XML form; gearopt reads the JSON form (.rexsj): convert it with the "
            "REXS API or the tool that wrote it",
        )
    try:
        return json.loads(text)
    except json.JSONDecodeError as exc:
        raise RexsError("REXS file", str(path), f"is not JSON: {exc}") from None


def _same(values: dict[str, float], what: str, rule: str) -> float:
    first = next(iter(values.values()))
    for where, value in values.items():
        if value != first:
            raise RexsError(where, value, f"{rule}; the other gives {first!r} ({what})")
    return first


def _pair_table(parsed: Mapping[str, Any]) -> dict[str, Any]:
    stage, gears, hands = parsed["stage"], parsed["gears"], parsed["hands"]
    where = {m: f"bevel_gear {m}" for m in MEMBERS}
    hypoid = read_number(stage, "hypoid_offset", "bevel_stage", default=0.0)
    if hypoid:
        raise RexsError(
            "bevel_stage.hypoid_offset", hypoid, "gearopt models spiral bevel gears without offset"
        )
    drive = read_number(stage, "nominal_design_pressure_angle_on_drive_side", "bevel_stage")
    coast = read_number(
        stage, "nominal_design_pressure_angle_on_coast_side", "bevel_stage", default=drive
    )
    if coast != drive:
        raise RexsError(
            "bevel_stage.nominal_design_pressure_angle_on_coast_side",
            coast,
            f"gearopt's pair has one pressure angle: must equal the drive side's {drive!r} deg "
            "(the blades' own pressure angles may differ per flank)",
        )
    if hands["gear"] == hands["pinion"]:
        raise RexsError(
            "bevel_gear gear.spiral_angle_pitch_direction",
            hands["gear"],
            "must be the opposite of the pinion's (a mating pair has opposite hands)",
        )

    def both(attribute: str) -> dict[str, float]:
        return {
            f"{where[m]}.{attribute}": read_number(gears[m], attribute, where[m]) for m in MEMBERS
        }

    table: dict[str, Any] = {
        "pinion_teeth": read_integer(gears["pinion"], "number_of_teeth", where["pinion"]),
        "gear_teeth": read_integer(gears["gear"], "number_of_teeth", where["gear"]),
        "shaft_angle_deg": read_number(stage, "shaft_angle", "bevel_stage"),
        "mean_spiral_angle_deg": _same(
            both("mean_spiral_angle"), "mean spiral angle", "pinion and gear must agree"
        ),
        "face_width_mm": _same(both("face_width"), "face width", "gearopt's pair has one"),
        "pressure_angle_deg": drive,
        "pinion_hand": hands["pinion"],
    }
    if all("mean_cone_distance" in gears[m] for m in MEMBERS):
        table["mean_cone_distance_mm"] = _same(
            both("mean_cone_distance"), "mean cone distance", "pinion and gear must agree"
        )
    elif "outer_pitch_diameter" in gears["gear"]:
        table["outer_pitch_diameter_mm"] = read_number(
            gears["gear"], "outer_pitch_diameter", where["gear"], unit="mm"
        )
    else:
        raise RexsError(
            f"{where['gear']}.mean_cone_distance",
            rule="required attribute is missing (or the gear's outer_pitch_diameter)",
        )
    for key, attribute in (
        ("outer_addendum_mm", "outer_addendum"),
        ("outer_dedendum_mm", "outer_dedendum"),
    ):
        table[key] = [read_number(gears[m], attribute, where[m]) for m in MEMBERS]
    optional = (
        ("face_angle_deg", "face_angle", None),
        ("root_angle_deg", "root_angle", None),
        ("mean_normal_chordal_thickness_mm", "mean_normal_chordal_tooth_thickness", None),
        ("mean_normal_chordal_addendum_mm", CUSTOM_PREFIX + "mean_normal_chordal_addendum", "mm"),
    )
    for key, attribute, unit in optional:
        values = [
            read_number(gears[m], attribute, where[m], unit=unit, default=None) for m in MEMBERS
        ]
        if all(v is not None for v in values):
            table[key] = values
        elif any(v is not None for v in values):
            missing = MEMBERS[values.index(None)]
            raise RexsError(f"{where[missing]}.{attribute}", rule="given for one member only")
    return table


def _conditions(stage: Mapping[str, RexsValue]) -> tuple[dict, dict]:
    misalignment, compensation = {}, {}
    for key, attribute in MISALIGNMENT.items():
        value = read_number(stage, attribute, "bevel_stage", default=0.0)
        if value:
            misalignment[key] = value
        unit = "deg" if key.endswith("_deg") else "mm"
        value = read_number(
            stage, f"{CUSTOM_PREFIX}compensation_{key}", "bevel_stage", unit=unit, default=0.0
        )
        if value:
            compensation[key] = value
    return misalignment, compensation


def rexs_tables(
    document: Mapping[str, Any],
    *,
    model: str | None = None,
    source: str = "",
    plugin_manager: pluggy.PluginManager | None = None,
) -> dict[str, Any]:
    """The tables of a design file (for ``tomli_w``) read from a REXS model in the JSON form.

    ``model`` names the machine model that reads the settings; default the one the file names
    (``custom_gearopt_machine_model``), else a :class:`~gearopt.errors.RexsError` asks for it.
    The design is parsed and its settings checked against the file (:func:`check_settings`).
    """
    return read_rexs_model(document, model=model, source=source, plugin_manager=plugin_manager)[0]


def read_rexs_model(
    document: Mapping[str, Any],
    *,
    model: str | None = None,
    source: str = "",
    path: str | None = None,
    plugin_manager: pluggy.PluginManager | None = None,
) -> tuple[dict[str, Any], Design]:
    """``(tables, design)`` of a REXS model: :func:`rexs_tables` and the design they parse
    into (``path`` recorded as the design's)."""
    parsed = parse_model(document)
    stage = parsed["stage"]
    named = read_string(stage, CUSTOM_PREFIX + "machine_model", "bevel_stage", default=None)
    if model is None and named is None:
        raise RexsError(
            f"bevel_stage.{CUSTOM_PREFIX}machine_model",
            rule="is missing (a file gearopt did not write): name the machine model that reads "
            "the settings (gearopt rexs import --model face-milling, or model=...)",
        )
    machine_model = get_machine_model(model or named, plugin_manager=plugin_manager)
    pair = _pair_table(parsed)
    # the machine model reads its settings against the pair they cut
    machine = machine_model.rexs_import(parsed["machine"], _pair_data(pair))
    meta = {"name": parsed["name"] or "rexs"}
    for key in ("description", "source"):
        text = read_string(stage, f"{CUSTOM_PREFIX}{key}", "bevel_stage", default="")
        if text:
            meta[key] = text
    if source and "source" not in meta:
        meta["source"] = source
    misalignment, compensation = _conditions(stage)
    tables: dict[str, Any] = {
        "meta": meta,
        "pair": pair,
        "machine": {"model": machine_model.name, **machine},
    }
    if misalignment:
        tables["misalignment"] = misalignment
    if compensation:
        tables["compensation"] = compensation
    design = parse_design(tables, plugin_manager=plugin_manager, path=path)
    check_settings(parsed["machine"], machine_model.rexs_export(design))
    return tables, design


#: how far a setting of the file may lie from the one gearopt derives (mm, deg or none): the
#: rounding of printed settings, far below what moves a flank by a micrometre in the check
SETTING_TOLERANCE = 1e-4


def check_settings(given: RexsMachine, derived: RexsMachine) -> None:
    """Refuse a file whose settings gearopt derives otherwise: every REXS attribute of a tool
    or settings component that both the file (``given``) and the machine model's export of the
    design read from it (``derived``) hold must agree within :data:`SETTING_TOLERANCE` (a
    cyclo-palloid machine distance that gearopt computes from the cutter, read as another tool
    wrote it). Custom attributes are not compared."""
    for (member, flank), step in derived.steps.items():
        if (member, flank) not in given.steps:
            continue
        theirs = given.steps[(member, flank)]
        for kind, ours, found in (
            ("bevel_gear_tool", step.tool, theirs.tool),
            ("bevel_gear_manufacturing_settings", step.settings, theirs.settings),
        ):
            for attribute, value in ours.items():
                if attribute.startswith(CUSTOM_PREFIX) or attribute not in found:
                    continue
                a = np.atleast_1d(np.asarray(value.value, dtype=float))
                b = np.atleast_1d(np.asarray(found[attribute].value, dtype=float))
                n = max(a.size, b.size)
                a, b = np.pad(a, (0, n - a.size)), np.pad(b, (0, n - b.size))
                if np.any(np.abs(a - b) > SETTING_TOLERANCE * np.maximum(1.0, np.abs(a))):
                    raise RexsError(
                        f"{kind} {member} {flank}.{attribute}",
                        found[attribute].value,
                        f"gearopt derives {value.value!r} {value.unit} from the file's other "
                        "data (the machine model's inputs, docs/rexs.md); the file's value "
                        "disagrees, so gearopt would cut another flank",
                    )


def _pair_data(pair: Mapping[str, Any]) -> PairData:
    try:
        return pair_from_table(dict(pair))
    except GearoptError as exc:
        raise RexsError(f"REXS blank ({exc.parameter})", exc.value, exc.rule) from None


def load_rexs(
    path: str | Path,
    *,
    model: str | None = None,
    plugin_manager: pluggy.PluginManager | None = None,
) -> Design:
    """The design of a REXS JSON file (:func:`read_rexs_model`)."""
    return read_rexs_model(
        read_rexs_file(path),
        model=model,
        source=f"REXS file {Path(path).name}",
        path=str(path),
        plugin_manager=plugin_manager,
    )[1]
