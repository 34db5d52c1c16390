"""Plugins' commands and benchmarks (``gearopt_commands``, ``gearopt_benchmarks``), and a core
that names no built-in plugin."""

from __future__ import annotations

import ast
import io
import json
import math
import os
import re
import subprocess
import sys
import tokenize
from importlib import metadata
from pathlib import Path

import pytest

import gearopt
from gearopt.bench import CORE_BENCHMARKS, all_benchmarks
from gearopt.chains import machine as chains_machine
from gearopt.cli import main
from gearopt.commands import BaseCommand, Benchmark
from gearopt.errors import DesignError, PluginError
from gearopt.plugins import benchmarks, commands, get_plugin_manager, list_plugins

from .conftest import ROOT, STUDIES

TABLE3 = STUDIES / "seed001_table3.toml"


class TeethCommand(BaseCommand):
    """Prints a design's tooth counts, read with the manager it was built from."""

    name = "teeth"
    help = "tooth counts of a design (test command)"

    def __init__(self, plugin_manager=None):
        self.plugin_manager = plugin_manager

    def add_arguments(self, parser):
        parser.add_argument("design")
        parser.add_argument("--member", choices=("pinion", "gear"), default="pinion")

    def run(self, args):
        design = gearopt.load_design(args.design, plugin_manager=self.plugin_manager)
        print(json.dumps({args.member: getattr(design.pair, f"{args.member}_teeth")}))
        return 0


class TeethPlugin:
    @gearopt.hookimpl
    def gearopt_commands(self, plugin_manager):
        return [TeethCommand(plugin_manager)]


class NamedCommand(BaseCommand):
    help = "a command called anything (test command)"

    def __init__(self, name):
        self.name = name

    def run(self, args):
        return 0


def _command_plugin(name):
    class Plugin:
        @gearopt.hookimpl
        def gearopt_commands(self):
            return [NamedCommand(name)]

    return Plugin()


def bench_nothing():
    """Times nothing (a test benchmark)."""
    return 0.0, {}


def test_a_plugin_command_runs_with_its_manager(capsys):
    pm = get_plugin_manager(plugins=[TeethPlugin()])
    assert commands(pm)["teeth"].plugin_manager is pm  # the hook's argument
    assert main(["teeth", str(TABLE3), "--member", "gear"], plugin_manager=pm) == 0
    design = gearopt.load_design(TABLE3)
    assert json.loads(capsys.readouterr().out) == {"gear": design.pair.gear_teeth}


def test_a_plugin_commands_error_is_one_line_with_status_2(tmp_path, capsys):
    pm = get_plugin_manager(plugins=[TeethPlugin()])
    assert main(["teeth", str(tmp_path / "missing.toml")], plugin_manager=pm) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    lines = captured.err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("gearopt: error: DesignError: design file")


def test_two_plugins_with_one_command_name_are_both_named(capsys):
    pm = get_plugin_manager(entry_points=False)
    pm.register(_command_plugin("twice"), name="first-plugin")
    pm.register(_command_plugin("twice"), name="second-plugin")
    with pytest.raises(PluginError) as info:
        commands(pm)
    assert info.value.parameter == "command name 'twice'"
    assert "'first-plugin'" in info.value.rule and "'second-plugin'" in info.value.rule
    assert main(["plugins"], plugin_manager=pm) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "first-plugin" in err[0] and "second-plugin" in err[0]


def test_a_plugin_command_may_not_take_a_core_commands_name(capsys):
    pm = get_plugin_manager(entry_points=False)
    pm.register(_command_plugin("analyze"), name="greedy-plugin")
    assert main(["plugins"], plugin_manager=pm) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1
    assert "command name 'analyze'" in err[0] and "core" in err[0] and "greedy-plugin" in err[0]


def test_the_builtin_commands_come_from_their_plugins():
    entries = {e.name: e for e in list_plugins(get_plugin_manager(), "command")}
    assert {"chain", "change-gears", "realise-te"} <= set(entries)
    assert entries["chain"].plugin == entries["change-gears"].plugin == "chain-error"
    assert entries["realise-te"].plugin == "face-milling"
    assert all(entries[n].distribution == "gearopt" for n in ("chain", "realise-te"))


def test_the_benchmarks_are_the_cores_and_the_plugins():
    found = all_benchmarks(get_plugin_manager())
    assert list(found)[: len(CORE_BENCHMARKS)] == [b.name for b in CORE_BENCHMARKS]
    assert set(found) == {
        "basic_settings_ms",
        "change_gears_ms",
        "flank_generation_ms",
        "thickness_solve_ms",
        "tca_ms",
        "backlash_ms",
        "tca_newton_ms",
        "study_trial_ms",
        "ltca_setup_ms",
        "ltca_ms",
        "ltca_sweep_ms",
    }
    entry = {e.name: e for e in list_plugins(get_plugin_manager(), "benchmark")}
    assert entry["change_gears_ms"].plugin == "chain-error"
    # a fresh process imports the function by this reference
    module, name = found["change_gears_ms"].target.split(":")
    assert getattr(sys.modules[module], name) is found["change_gears_ms"].function


def test_a_plugin_benchmark_may_not_take_a_core_benchmarks_name():
    class Plugin:
        @gearopt.hookimpl
        def gearopt_benchmarks(self):
            return [Benchmark(name="tca_ms", function=bench_nothing)]

    pm = get_plugin_manager(entry_points=False)
    pm.register(Plugin(), name="greedy-plugin")
    assert list(benchmarks(pm)) == ["tca_ms"]
    with pytest.raises(PluginError, match="core.*greedy-plugin"):
        all_benchmarks(pm)


def test_a_benchmark_must_be_importable_by_name():
    with pytest.raises(PluginError, match="module-level function"):
        Benchmark(name="lambda_ms", function=lambda: (0.0, {}))
    assert Benchmark(name="nothing_ms", function=bench_nothing).target == (
        f"{__name__}:bench_nothing"
    )


def test_a_third_party_command_and_benchmark_through_the_cli(toy_site):
    """The toy distribution's ``toy-roll`` command and ``toy_roll_ms`` benchmark, found through
    its entry point and run by the installed ``gearopt`` (the benchmark in a fresh process)."""
    env = {**os.environ, "PYTHONPATH": str(toy_site)}
    run = [sys.executable, "-m", "gearopt.cli"]
    design = toy_site / "gearopt_toy" / "toy_design.toml"

    def gearopt_cli(*args):
        out = subprocess.run([*run, *args], env=env, capture_output=True, text=True)
        assert out.returncode == 0, out.stderr
        return out.stdout

    entries = json.loads(gearopt_cli("plugins", "--json"))
    listed = {(p["kind"], p["name"], p["distribution"]) for p in entries}
    assert ("command", "toy-roll", "gearopt-toy-machine") in listed
    assert ("benchmark", "toy_roll_ms", "gearopt-toy-machine") in listed
    out = json.loads(gearopt_cli("toy-roll", str(design), "--member", "gear", "--json"))
    # the planer rolls the crown gear on the member: 1 / sin(pitch angle) = N_c / N_gear,
    # with N_c = sqrt(16^2 + 41^2) at a shaft angle of 90 deg
    assert out["gear_to_cradle_roll"] == pytest.approx(math.hypot(16, 41) / 41, rel=1e-12)
    assert gearopt_cli("toy-roll", str(design)).startswith("pinion cradle roll 2.750")
    bench = json.loads(gearopt_cli("bench", "toy_roll_ms", "--repeats", "1", "--json"))
    assert bench["toy_roll_ms"] > 0.0 and bench["toy_design"] == "toy"
    failed = subprocess.run(
        [*run, "toy-roll", str(STUDIES / "seed001_table3.toml")],
        env=env,
        capture_output=True,
        text=True,
    )
    assert failed.returncode == 2 and failed.stdout == ""
    assert failed.stderr.strip().splitlines() == [
        "gearopt: error: DesignError: machine.model = 'cyclo-palloid': must be 'toy-planer'"
    ]


def test_machine_files_come_from_the_entry_point_group(tmp_path, monkeypatch):
    shipped = chains_machine.load_machine("zftkk250x5")
    folder = tmp_path / "my_machines" / "files"
    folder.mkdir(parents=True)
    (folder.parent / "__init__.py").write_text("")
    (folder / "copy250.toml").write_text(Path(shipped.path).read_text())
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.delenv(chains_machine.MACHINE_PATH_ENV, raising=False)
    group = chains_machine.MACHINE_FILES_GROUP
    entries = [metadata.EntryPoint(name="mine", value="my_machines:files", group=group)]

    def entry_points(*, group):
        return entries if group == chains_machine.MACHINE_FILES_GROUP else []

    monkeypatch.setattr(chains_machine.metadata, "entry_points", entry_points)
    assert chains_machine.machine_dirs() == [folder]
    assert chains_machine.machine_names() == ["copy250"]
    assert chains_machine.load_machine("copy250").change_gears == shipped.change_gears
    # the core knows no machine folder of its own
    with pytest.raises(DesignError, match="unknown machine"):
        chains_machine.load_machine("zftkk250x5")
    entries[:] = [metadata.EntryPoint(name="broken", value="no_such_package_0:files", group=group)]
    with pytest.raises(PluginError, match="'broken'.*cannot be imported"):
        chains_machine.machine_dirs()
    sys.modules.pop("my_machines", None)


# -- the core names no built-in plugin ----------------------------------------------------------


def _builtin_modules() -> tuple[set[str], set[str]]:
    """The built-in plugins' top-level packages and their modules' dotted names below them."""
    packages, modules = set(), set()
    for entry in metadata.entry_points(group="gearopt"):
        if entry.dist is not None and entry.dist.name == "gearopt":
            packages.add(entry.module.split(".")[0])
    for path in (ROOT / "plugins").rglob("*.py"):
        parts = path.relative_to(ROOT / "plugins").with_suffix("").parts
        if parts[-1] == "__init__":  # a package: its folder's name
            parts = parts[:-1]
        if parts:
            modules.add(".".join(parts))
    return packages, modules


def _docstrings(tree: ast.AST) -> set[int]:
    """Line numbers where the docstrings of a module, its classes and functions start."""
    found = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Module | ast.ClassDef | ast.FunctionDef | ast.AsyncFunctionDef):
            body = node.body
            if (
                body
                and isinstance(body[0], ast.Expr)
                and isinstance(body[0].value, ast.Constant)
                and isinstance(body[0].value.value, str)
            ):
                found.add(body[0].lineno)
    return found


def test_the_core_names_no_builtin_plugin():
    """``gearopt/`` names neither the built-ins' package nor a module of theirs in code (an
    import, a name, a string such as ``"package.module:function"``); only documentation
    (docstrings, comments) may, as examples."""
    packages, modules = _builtin_modules()
    assert packages == {"gearopt_plugins"} and "chain_error" in modules
    alternatives = "|".join(map(re.escape, sorted(modules, key=len, reverse=True)))
    # "module:function" or "module.name:function", the way an entry point or a registry
    # names a plugin's object (file names such as "ltca.png" are not references)
    reference = re.compile(rf"(?<![\w.])(?:{alternatives})(?:\.\w+)*:[A-Za-z_]")
    found = []
    for path in sorted((ROOT / "gearopt").rglob("*.py")):
        text = path.read_text(encoding="utf-8")
        tree = ast.parse(text)
        for node in ast.walk(tree):
            if isinstance(node, ast.Import | ast.ImportFrom):
                names = [a.name for a in node.names] if isinstance(node, ast.Import) else []
                for name in [*names, getattr(node, "module", None) or ""]:
                    if name.split(".")[0] in packages:
                        found.append(f"{path.relative_to(ROOT)}:{node.lineno} imports {name}")
        docs = _docstrings(tree)
        for token in tokenize.generate_tokens(io.StringIO(text).readline):
            if token.type not in (tokenize.NAME, tokenize.STRING):
                continue
            if token.type == tokenize.STRING and token.start[0] in docs:
                continue
            words = token.string.strip("\"'frbFRB")
            if any(p in token.string for p in packages) or (
                token.type == tokenize.STRING and reference.search(words)
            ):
                found.append(f"{path.relative_to(ROOT)}:{token.start[0]} {token.string[:60]}")
    assert found == []
