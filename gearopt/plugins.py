"""The plugin manager factory and the registries built from it.

Built-in plugins and third-party plugins are all found through the entry-point group
``gearopt``; nothing special-cases the built-ins. The manager is built by
:func:`get_plugin_manager`, never at import time, so every worker process can rebuild it.
"""

from __future__ import annotations

import functools
import weakref
from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any

import pluggy

from gearopt import hookspecs
from gearopt.commands import BaseCommand, Benchmark
from gearopt.errors import DesignError, PluginError
from gearopt.evaluation import BaseEvaluator, BaseObjective
from gearopt.machine import BaseMachineModel

__all__ = [
    "ENTRY_POINT_GROUP",
    "PluginEntry",
    "get_plugin_manager",
    "default_plugin_manager",
    "list_plugins",
    "machine_models",
    "evaluators",
    "objectives",
    "commands",
    "benchmarks",
    "get_machine_model",
]

ENTRY_POINT_GROUP = "gearopt"

_KINDS: dict[str, tuple[str, type]] = {
    "machine-model": ("gearopt_machine_models", BaseMachineModel),
    "evaluator": ("gearopt_evaluators", BaseEvaluator),
    "objective": ("gearopt_objectives", BaseObjective),
    "command": ("gearopt_commands", BaseCommand),
    "benchmark": ("gearopt_benchmarks", Benchmark),
}


def get_plugin_manager(
    *, entry_points: bool = True, plugins: Iterable[Any] = ()
) -> pluggy.PluginManager:
    """Build a fresh plugin manager.

    Parameters
    ----------
    entry_points
        Load every plugin of the entry-point group ``gearopt`` (the built-ins included).
    plugins
        Extra plugin objects or modules to register (tests, scripts).
    """
    pm = pluggy.PluginManager(hookspecs.PROJECT_NAME)
    pm.add_hookspecs(hookspecs)
    try:
        if entry_points:
            pm.load_setuptools_entrypoints(ENTRY_POINT_GROUP)
        for plugin in plugins:
            pm.register(plugin)
        pm.check_pending()
    except pluggy.PluginValidationError as exc:
        raise PluginError(
            f"plugin {exc.plugin!r}", rule=f"breaks the hook specifications: {exc}"
        ) from exc
    except (ImportError, AttributeError, SyntaxError) as exc:
        raise PluginError(
            f"entry-point group {ENTRY_POINT_GROUP!r}", rule=f"a plugin failed to load: {exc!r}"
        ) from exc
    return pm


@functools.cache
def default_plugin_manager() -> pluggy.PluginManager:
    """The process's shared manager with every installed plugin, built on first use."""
    return get_plugin_manager()


@dataclass(frozen=True, kw_only=True)
class PluginEntry:
    """One object a plugin provides, with where it comes from."""

    kind: str
    name: str
    obj: Any
    plugin: str
    distribution: str
    version: str
    description: str


def _distributions(pm: pluggy.PluginManager) -> dict[int, tuple[str, str]]:
    found = {}
    for plugin, dist in pm.list_plugin_distinfo():
        found[id(plugin)] = (dist.project_name, dist.version)
    return found


_CACHE: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def list_plugins(
    pm: pluggy.PluginManager | None = None, kind: str | None = None
) -> list[PluginEntry]:
    """Every machine model, evaluator, objective, command and benchmark, with the distribution
    that provides it.

    The hooks are called once per manager and set of registered plugins; the answer is cached.
    Raises :class:`PluginError` when a hook returns something that is not a list of the right
    base class, or when two plugins provide the same name.
    """
    pm = pm or default_plugin_manager()
    signature = tuple(sorted(id(p) for p in pm.get_plugins()))
    cached = _CACHE.get(pm)
    if cached is None or cached[0] != signature:
        cached = (signature, _collect(pm))
        _CACHE[pm] = cached
    return [e for e in cached[1] if kind is None or e.kind == kind]


def _collect(pm: pluggy.PluginManager) -> list[PluginEntry]:
    dists = _distributions(pm)
    # the hooks' arguments (gearopt.hookspecs), by name: each hookimpl takes those it names
    arguments = {"plugin_manager": pm}
    entries: list[PluginEntry] = []
    for this_kind, (hook_name, base) in _KINDS.items():
        seen: dict[str, str] = {}
        for impl in getattr(pm.hook, hook_name).get_hookimpls():
            result = impl.function(**{name: arguments[name] for name in impl.argnames})
            if result is None:
                continue
            if not isinstance(result, list | tuple):
                raise PluginError(
                    f"plugin {impl.plugin_name!r} hook {hook_name}", result, "must return a list"
                )
            dist, version = dists.get(id(impl.plugin), ("(registered directly)", ""))
            for obj in result:
                if not isinstance(obj, base):
                    raise PluginError(
                        f"plugin {impl.plugin_name!r} hook {hook_name}",
                        obj,
                        f"must return {base.__name__} instances",
                    )
                name = getattr(obj, "name", None)
                if not isinstance(name, str) or not name:
                    raise PluginError(
                        f"plugin {impl.plugin_name!r} {this_kind}", obj, "needs a non-empty name"
                    )
                if name in seen:
                    raise PluginError(
                        f"{this_kind} name {name!r}",
                        rule=f"provided by both plugins {seen[name]!r} and {impl.plugin_name!r}",
                    )
                seen[name] = impl.plugin_name
                entries.append(
                    PluginEntry(
                        kind=this_kind,
                        name=name,
                        obj=obj,
                        plugin=impl.plugin_name,
                        distribution=dist,
                        version=version,
                        description=getattr(obj, "description", ""),
                    )
                )
    return sorted(entries, key=lambda e: (list(_KINDS).index(e.kind), e.name))


def _registry(kind: str, pm: pluggy.PluginManager | None) -> dict[str, Any]:
    return {e.name: e.obj for e in list_plugins(pm, kind)}


def machine_models(pm: pluggy.PluginManager | None = None) -> dict[str, BaseMachineModel]:
    """Machine models by name."""
    return _registry("machine-model", pm)


def evaluators(pm: pluggy.PluginManager | None = None) -> dict[str, BaseEvaluator]:
    """Evaluators by name."""
    return _registry("evaluator", pm)


def objectives(pm: pluggy.PluginManager | None = None) -> dict[str, BaseObjective]:
    """Objectives and constraints by name."""
    return _registry("objective", pm)


def commands(pm: pluggy.PluginManager | None = None) -> dict[str, BaseCommand]:
    """The plugins' subcommands of ``gearopt`` by name."""
    return _registry("command", pm)


def benchmarks(pm: pluggy.PluginManager | None = None) -> dict[str, Benchmark]:
    """The plugins' benchmarks of ``gearopt bench`` by name."""
    return _registry("benchmark", pm)


def get_machine_model(
    name: str, *, plugin_manager: pluggy.PluginManager | None = None
) -> BaseMachineModel:
    """The machine model called ``name``; a :class:`DesignError` lists the known ones."""
    models = machine_models(plugin_manager)
    if name not in models:
        known = sorted(models) or ["(none: is gearopt installed with `pip install -e .`?)"]
        raise DesignError("machine.model", name, f"unknown machine model; installed: {known}")
    return models[name]
