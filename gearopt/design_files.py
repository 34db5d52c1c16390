"""Design files: TOML documents read into validated :class:`gearopt.design.Design` objects.

Reading a design needs the plugin registry: the ``[machine]`` table is handed to the machine
model its ``model`` key names (:func:`gearopt.plugins.get_machine_model`), which parses it (or
synthesises the settings from a ``[synthesis]`` table). The file's tables are listed in
:mod:`gearopt.design`.
"""

from __future__ import annotations

import copy
import datetime
from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

from gearopt.analysis_options import AnalysisOptions
from gearopt.assembly import Misalignment
from gearopt.design import SECTIONS, Design, Meta, PairData, pair_from_tables
from gearopt.errors import DesignError, GearoptError
from gearopt.load_options import LoadOptions
from gearopt.plugins import get_machine_model
from gearopt.te_target import TETarget
from gearopt.validate import check_keys, read_table, read_toml, read_toml_file

if TYPE_CHECKING:
    import pluggy

    from gearopt.iso23509 import StandardBlank

__all__ = [
    "load_design",
    "loads_design",
    "parse_design",
    "source_with_machine",
    "with_overrides",
    "load_standard_blank",
]


#: the values a TOML document holds besides tables and arrays (immutable: copies share them)
_ATOMS = frozenset(
    {str, int, float, bool, type(None), datetime.datetime, datetime.date, datetime.time}
)


def _copied(value: Any) -> Any:
    """:func:`copy.deepcopy` of a parsed TOML document: tables (dicts) and arrays (lists)
    copied, scalars shared, anything else deep-copied."""
    kind = type(value)
    if kind is dict:
        return {key: _copied(item) for key, item in value.items()}
    if kind is list:
        return [_copied(item) for item in value]
    if kind in _ATOMS:
        return value
    return copy.deepcopy(value)


def _analysis_table(table: Mapping[str, Any]) -> dict[str, Any]:
    """The ``[analysis]`` table: default conditions of the contact evaluators for this design
    (the keys of :class:`gearopt.analysis.AnalysisOptions`), checked now."""
    try:
        AnalysisOptions.from_conditions(table, where="analysis")
    except DesignError:
        raise
    except GearoptError as exc:
        name = (
            exc.parameter if exc.parameter.startswith("analysis") else f"analysis.{exc.parameter}"
        )
        raise DesignError(name, exc.value, exc.rule) from None
    return dict(table)


def _load_table(table: Mapping[str, Any]) -> dict[str, Any]:
    """The ``[load]`` table: loaded contact's torques, materials and resolution
    (:class:`gearopt.load_options.LoadOptions`), checked now."""
    try:
        LoadOptions.from_table(table, where="load")
    except DesignError:
        raise
    except GearoptError as exc:
        raise DesignError(exc.parameter, exc.value, exc.rule) from None
    return dict(table)


def _te_target(table: Mapping[str, Any], pair: PairData):
    """The ``[te_target]`` table: a designed transmission error (:mod:`gearopt.te_target`)."""
    return TETarget.from_table(table, pair.pinion_teeth)


def parse_design(
    data: Mapping[str, Any],
    *,
    plugin_manager: pluggy.PluginManager | None = None,
    path: str | None = None,
) -> Design:
    """Build a :class:`Design` from a parsed TOML document.

    The ``[machine]`` table is handed to the machine model named by its ``model`` key, found
    among the registered plugins (``plugin_manager``, default: the built-ins and every installed
    plugin).
    """
    if not isinstance(data, Mapping):
        raise DesignError("design", data, "must be a TOML document (a table of tables)")
    tables = {name: read_table(data, name, "") for name in SECTIONS}
    check_keys(data, SECTIONS, "")
    if "pair" not in data:
        raise DesignError("pair", rule="the [pair] table is required")
    if "machine" not in data:
        raise DesignError("machine", rule='the [machine] table is required (model = "...")')
    pair, standard = pair_from_tables(tables["pair"], tables["blank"] if "blank" in data else None)
    machine_table = dict(tables["machine"])
    if "model" not in machine_table:
        raise DesignError("machine.model", rule="required key is missing")
    model_name = machine_table.pop("model")
    if not isinstance(model_name, str):
        raise DesignError("machine.model", model_name, "must be a string naming a machine model")
    model = get_machine_model(model_name, plugin_manager=plugin_manager)
    if "synthesis" in data:
        machine = model.synthesize(machine_table, tables["synthesis"], pair)
    else:
        machine = model.parse_machine(machine_table, pair)
    meta_table = tables["meta"]
    check_keys(meta_table, ("name", "description", "source"), "meta")
    return Design(
        pair=pair,
        model=model.name,
        machine=machine,
        misalignment=Misalignment.from_table(tables["misalignment"], "misalignment"),
        compensation=Misalignment.from_table(tables["compensation"], "compensation"),
        meta=Meta(**meta_table),
        analysis=_analysis_table(tables["analysis"]),
        load=_load_table(tables["load"]),
        te_target=_te_target(tables["te_target"], pair) if "te_target" in data else None,
        standard_blank=standard,
        source=_copied(dict(data)),
        path=path,
    )


def loads_design(text: str, *, plugin_manager: pluggy.PluginManager | None = None) -> Design:
    """Parse a design from TOML text."""
    data = read_toml(text, lambda rule: DesignError("design", rule=rule))
    return parse_design(data, plugin_manager=plugin_manager)


def load_design(path: str | Path, *, plugin_manager: pluggy.PluginManager | None = None) -> Design:
    """Load and validate a design TOML file."""
    path = Path(path)
    data = read_toml_file(path, lambda rule: DesignError("design file", str(path), rule))
    return parse_design(data, plugin_manager=plugin_manager, path=str(path))


def load_standard_blank(path: str | Path) -> StandardBlank:
    """The standard blank of a design file from its ``[pair]`` and ``[blank]`` tables only
    (a design without ``[machine]`` is valid here; the other tables are not read)."""
    path = Path(path)
    data = read_toml_file(path, lambda rule: DesignError("design file", str(path), rule))
    if "pair" not in data:
        raise DesignError("pair", rule="the [pair] table is required")
    if "blank" not in data:
        raise DesignError(
            "blank",
            rule='the [blank] table is required (standard = "iso23509" and its data: '
            "cutter_radius_mm, taper or the gear's addendum and dedendum angles)",
        )
    _, standard = pair_from_tables(read_table(data, "pair", ""), read_table(data, "blank", ""))
    return standard


def source_with_machine(design: Design, table: Mapping[str, Any]) -> dict[str, Any]:
    """A copy of ``design``'s source tables with ``[machine]`` replaced by ``table`` (settings
    written out, without ``model``) and no ``[synthesis]``: what a design with plain settings
    parses from (:func:`parse_design`) or writes out (``tomli_w``)."""
    data = _copied(dict(design.source))
    data.pop("synthesis", None)
    data["machine"] = {"model": design.model, **table}
    return data


def with_overrides(
    design: Design,
    overrides: Mapping[str, Any],
    *,
    plugin_manager: pluggy.PluginManager | None = None,
) -> Design:
    """Return a new design with dotted keys replaced, e.g.
    ``{"machine.pinion.inner_cutter_radius_mm": 76.0}``; the result is validated anew."""
    data = _copied(dict(design.source))
    for dotted, value in overrides.items():
        parts = dotted.split(".")
        node = data
        for part in parts[:-1]:
            child = node.setdefault(part, {})
            if not isinstance(child, dict):
                raise DesignError(
                    dotted, value, f"'{part}' is not a table, cannot hold '{parts[-1]}'"
                )
            node = child
        node[parts[-1]] = value
    return parse_design(data, plugin_manager=plugin_manager, path=design.path)
