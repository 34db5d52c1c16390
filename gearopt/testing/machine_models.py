"""The machine-model contract suite (:class:`MachineModelContract`)."""

from __future__ import annotations

import dataclasses
import json
import math
import pickle
import re
import tomllib

import pytest

from gearopt.design import Design
from gearopt.design_files import loads_design, parse_design, with_overrides
from gearopt.errors import GearoptError, UnknownKeyError
from gearopt.hookspecs import hookimpl
from gearopt.machine import BaseMachineModel, MachineSettings, SearchDimension
from gearopt.plugins import get_plugin_manager, machine_models
from gearopt.rexs.files import export_rexs, rexs_tables

__all__ = ["MachineModelContract"]

UNIT_SUFFIXES = ("_mm", "_deg", "_um", "_arcsec", "_per_mm", "_mm2", "_n", "_nm")
DIMENSIONLESS_WORDS = (
    "roll",
    "ratio",
    "groups",
    "teeth",
    "count",
    "coefficient",
    "starts",
    "factor",
)


class _Provider:
    """A throwaway plugin that provides one machine model."""

    def __init__(self, model: BaseMachineModel) -> None:
        self.model = model

    @hookimpl
    def gearopt_machine_models(self) -> list[BaseMachineModel]:
        return [self.model]


def _finite_scalar(value: object) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool) and math.isfinite(value)


class MachineModelContract:
    """Checks every machine model must pass. Subclass it and provide two fixtures:

    ``machine_model``
        An instance of the model under test.
    ``design_text``
        The TOML text of a valid design that uses the model (``[machine] model = name``).
    """

    @pytest.fixture
    def plugin_manager(self, machine_model):
        return get_plugin_manager(entry_points=False, plugins=[_Provider(machine_model)])

    @pytest.fixture
    def design(self, design_text, plugin_manager) -> Design:
        return loads_design(design_text, plugin_manager=plugin_manager)

    def test_is_a_machine_model_with_a_valid_name(self, machine_model):
        assert isinstance(machine_model, BaseMachineModel)
        assert re.fullmatch(r"[a-z][a-z0-9]*(-[a-z0-9]+)*", machine_model.name), machine_model.name
        assert isinstance(machine_model.description, str) and machine_model.description

    def test_listed_by_the_plugin_manager(self, machine_model, plugin_manager):
        assert machine_models(plugin_manager) == {machine_model.name: machine_model}

    def test_design_selects_the_model_and_is_frozen(self, design, machine_model):
        assert design.model == machine_model.name
        assert dataclasses.is_dataclass(design.machine)
        field = dataclasses.fields(design.machine)[0].name
        with pytest.raises(dataclasses.FrozenInstanceError):
            setattr(design.machine, field, None)

    def test_unknown_machine_key_is_refused(self, design_text, plugin_manager):
        data = tomllib.loads(design_text)
        data["machine"]["no_such_key_mm"] = 1.0
        with pytest.raises(UnknownKeyError) as info:
            parse_design(data, plugin_manager=plugin_manager)
        assert "no_such_key_mm" in str(info.value)

    def test_settings_are_finite_scalars_named_with_units(self, design, machine_model):
        settings = machine_model.basic_settings(design)
        assert isinstance(settings, MachineSettings)
        assert settings.model == machine_model.name
        out = settings.as_dict()
        for member in ("pinion", "gear"):
            assert out[member], f"no {member} settings"
            for key, value in out[member].items():
                assert _finite_scalar(value), f"{member}.{key} = {value!r} is not a finite number"
                assert key.endswith(UNIT_SUFFIXES) or any(w in key for w in DIMENSIONLESS_WORDS), (
                    f"{member}.{key}: name a setting with its unit ({UNIT_SUFFIXES}) or say what "
                    "ratio it is"
                )

    def test_settings_are_deterministic(self, design, machine_model):
        assert machine_model.basic_settings(design) == machine_model.basic_settings(design)

    def test_model_and_design_survive_pickling(self, design, machine_model):
        model = pickle.loads(pickle.dumps(machine_model))
        assert model.basic_settings(pickle.loads(pickle.dumps(design))) == (
            machine_model.basic_settings(design)
        )

    def test_catalogue_sizes_are_valid_designs(self, design, machine_model, plugin_manager):
        """Every size a model's cutter catalogue offers for the design (categorical
        dimensions, filtered by the model's own rules) gives a design it can set up."""
        for dim in machine_model.cutter_catalogue(design):
            assert isinstance(dim, SearchDimension) and dim.choices, dim
            for value in dim.choices:
                try:
                    changed = with_overrides(
                        design, {dim.key: value}, plugin_manager=plugin_manager
                    )
                    machine_model.basic_settings(changed)
                except GearoptError as exc:  # pragma: no cover - the failure message is the point
                    pytest.fail(f"catalogue size {dim.key} = {value} is refused: {exc}")

    def test_search_space_corners_are_valid_designs(self, design, machine_model, plugin_manager):
        space = machine_model.search_space(design)
        assert isinstance(space, tuple)
        assert len({d.key for d in space}) == len(space), "duplicate search keys"
        for dim in space:
            assert isinstance(dim, SearchDimension)
            for value in (dim.low, 0.5 * (dim.low + dim.high), dim.high):
                try:
                    changed = with_overrides(
                        design, {dim.key: value}, plugin_manager=plugin_manager
                    )
                    settings = machine_model.basic_settings(changed)
                except GearoptError as exc:  # pragma: no cover - the failure message is the point
                    pytest.fail(f"{dim.key} = {value} inside its bounds is refused: {exc}")
                for member in ("pinion", "gear"):
                    assert all(_finite_scalar(v) for v in settings.as_dict()[member].values())

    def test_a_rexs_round_trip_keeps_the_settings(self, design, machine_model, plugin_manager):
        """The design written as REXS (:meth:`~gearopt.machine.BaseMachineModel.rexs_export`)
        and read back (:meth:`~gearopt.machine.BaseMachineModel.rexs_import`) has the same
        basic settings, through the file's text."""
        document = export_rexs(design, date="2026-01-01T00:00:00", plugin_manager=plugin_manager)
        tables = rexs_tables(json.loads(json.dumps(document)), plugin_manager=plugin_manager)
        back = parse_design(tables, plugin_manager=plugin_manager)
        assert back.model == machine_model.name
        before, after = machine_model.basic_settings(design), machine_model.basic_settings(back)
        assert (after.pinion, after.gear) == (before.pinion, before.gear)
