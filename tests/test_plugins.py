"""The plugin system: factory, entry points, registries, contract errors, a third-party plugin."""

from __future__ import annotations

import inspect
import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

import gearopt
from gearopt import hookspecs
from gearopt.errors import DesignError, PluginError
from gearopt.plugins import get_plugin_manager, list_plugins
from gearopt.testing import FlankContract
from gearopt_plugins.cyclo_palloid import CycloPalloid

TOY = Path(__file__).parent / "toy_plugin"


def test_hookspecs_are_documented_and_prefixed():
    specs = [name for name, obj in vars(hookspecs).items() if name.startswith("gearopt_")]
    assert sorted(specs) == [
        "gearopt_benchmarks",
        "gearopt_commands",
        "gearopt_evaluators",
        "gearopt_machine_models",
        "gearopt_objectives",
    ]
    for name in specs:
        doc = inspect.getdoc(getattr(hookspecs, name))
        assert doc and "Returns" in doc and "Notes" in doc, name
        # every argument a hook passes is documented
        for argument in inspect.signature(getattr(hookspecs, name)).parameters:
            assert "Parameters" in doc and f"\n{argument}\n" in doc, (name, argument)


def test_factory_builds_a_fresh_manager_each_time():
    assert get_plugin_manager() is not get_plugin_manager()


def test_hooks_are_called_once_per_manager():
    calls = []

    class Counting:
        @gearopt.hookimpl
        def gearopt_objectives(self):
            calls.append(1)
            return []

    pm = get_plugin_manager(entry_points=False, plugins=[Counting()])
    for _ in range(3):
        gearopt.objectives(pm)
        gearopt.machine_models(pm)
    assert len(calls) == 1


def test_builtin_found_through_the_entry_point_group():
    entries = list_plugins(get_plugin_manager())
    cyclo = [e for e in entries if e.name == "cyclo-palloid"]
    assert len(cyclo) == 1
    assert cyclo[0].kind == "machine-model"
    assert cyclo[0].distribution == "gearopt"
    assert cyclo[0].plugin == "cyclo-palloid"  # the entry point's name


def test_without_entry_points_there_are_no_builtins():
    assert gearopt.machine_models(get_plugin_manager(entry_points=False)) == {}


class _Duplicate:
    @gearopt.hookimpl
    def gearopt_machine_models(self):
        return [CycloPalloid()]


class _WrongType:
    @gearopt.hookimpl
    def gearopt_evaluators(self):
        return ["not an evaluator"]


class _NotAList:
    @gearopt.hookimpl
    def gearopt_objectives(self):
        return object()


def test_duplicate_name_names_both_plugins():
    pm = get_plugin_manager()
    pm.register(_Duplicate(), name="dup-plugin")
    with pytest.raises(PluginError) as info:
        gearopt.machine_models(pm)
    assert info.value.parameter == "machine-model name 'cyclo-palloid'"
    assert "'cyclo-palloid'" in info.value.rule and "'dup-plugin'" in info.value.rule


@pytest.mark.parametrize("plugin", [_WrongType(), _NotAList()])
def test_hooks_returning_the_wrong_thing_are_refused(plugin):
    pm = get_plugin_manager(entry_points=False, plugins=[plugin])
    with pytest.raises(PluginError):
        list_plugins(pm)


def test_unknown_hook_in_a_plugin_is_refused():
    class Typo:
        @gearopt.hookimpl
        def gearopt_machine_model(self):  # missing "s"
            return []

    with pytest.raises(PluginError, match="unknown hook"):
        get_plugin_manager(entry_points=False, plugins=[Typo()])


def test_unknown_model_lists_the_installed_ones(table3_text):
    with pytest.raises(DesignError) as info:
        gearopt.loads_design(table3_text.replace('"cyclo-palloid"', '"gleason"'))
    assert "cyclo-palloid" in info.value.rule


@pytest.fixture
def toy_on_path(toy_site, monkeypatch):
    monkeypatch.syspath_prepend(str(toy_site))
    yield toy_site
    sys.modules.pop("gearopt_toy", None)


def test_third_party_plugin_is_listed_with_its_distribution(toy_on_path):
    pm = get_plugin_manager()
    entries = {(e.kind, e.name): e for e in list_plugins(pm)}
    for key in [
        ("machine-model", "toy-planer"),
        ("evaluator", "toy-blank"),
        ("objective", "toy-crown-teeth"),
    ]:
        assert key in entries, key
        assert entries[key].distribution == "gearopt-toy-machine"
        assert entries[key].version == "0.0.1"
    assert entries[("machine-model", "cyclo-palloid")].distribution == "gearopt"


def test_third_party_plugin_is_usable(toy_on_path):
    pm = get_plugin_manager()
    text = (TOY / "gearopt_toy" / "toy_design.toml").read_text()
    design = gearopt.loads_design(text, plugin_manager=pm)
    settings = gearopt.basic_settings(design, plugin_manager=pm)
    # a cradle roll of 1 / sin(pitch angle) is N_c / N: the crown gear rolls on the member
    assert settings.gear.gear_to_cradle_roll == pytest.approx(
        design.blank.crown_gear_teeth / design.pair.gear_teeth, rel=1e-13
    )
    evaluation = gearopt.evaluators(pm)["toy-blank"].evaluate(design)
    value = gearopt.objectives(pm)["toy-crown-teeth"].value({"toy-blank": evaluation})
    assert value == pytest.approx(design.blank.crown_gear_teeth)


def test_third_party_plugin_through_the_cli(toy_site):
    env = {**os.environ, "PYTHONPATH": str(toy_site)}
    run = [sys.executable, "-m", "gearopt.cli"]
    out = subprocess.run(
        [*run, "plugins", "--json"], env=env, capture_output=True, text=True, check=True
    )
    names = {(p["name"], p["distribution"]) for p in json.loads(out.stdout)}
    assert ("toy-planer", "gearopt-toy-machine") in names
    assert ("cyclo-palloid", "gearopt") in names
    design = toy_site / "gearopt_toy" / "toy_design.toml"
    out = subprocess.run(
        [*run, "settings", str(design), "--json"],
        env=env,
        capture_output=True,
        text=True,
        check=True,
    )
    assert json.loads(out.stdout)["model"] == "toy-planer"


class TestToyModelPassesTheContract(FlankContract):
    @pytest.fixture
    def machine_model(self, toy_on_path):
        from gearopt_toy import ToyPlaner

        return ToyPlaner()

    @pytest.fixture
    def design_text(self):
        return (TOY / "gearopt_toy" / "toy_design.toml").read_text()
