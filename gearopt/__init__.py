"""gearopt: open, plugin-based design optimisation of spiral bevel gears.

Public API: design files (:func:`load_design`), machine settings (:func:`basic_settings`), the
plugin contract (:data:`hookimpl`, the ``Base*`` classes), the plugin registries and studies
(:func:`load_study_spec`, :func:`run_study`).
"""

from gearopt.blank import Blank, compute_blank
from gearopt.commands import BaseCommand, Benchmark
from gearopt.declarations import Curve, Metric, Option, OptionError, Pattern
from gearopt.design import Design, Meta, Misalignment, PairData
from gearopt.design_files import load_design, loads_design, parse_design, with_overrides
from gearopt.errors import (
    DesignError,
    GearoptError,
    NotAvailableError,
    PluginError,
    SettingsError,
    StudyError,
    UnknownKeyError,
)
from gearopt.evaluation import BaseEvaluator, BaseObjective, Evaluation
from gearopt.flank import FlankGrid, FlankMap
from gearopt.hookspecs import hookimpl, hookspec
from gearopt.machine import BaseMachineModel, MachineSettings, SearchDimension
from gearopt.plugins import (
    evaluators,
    get_machine_model,
    get_plugin_manager,
    list_plugins,
    machine_models,
    objectives,
)
from gearopt.rexs.files import export_rexs, load_rexs, write_rexs
from gearopt.studyfile import load_study_spec

__version__ = "0.1.0"


def basic_settings(design: Design, *, plugin_manager=None) -> MachineSettings:
    """Basic machine-tool settings of a design, computed by its machine model's plugin."""
    return get_machine_model(design.model, plugin_manager=plugin_manager).basic_settings(design)


def generate_flanks(
    design: Design, member: str, *, grid: FlankGrid | None = None, plugin_manager=None
) -> dict[str, FlankMap]:
    """``{"convex": FlankMap, "concave": FlankMap}`` of tooth 0 of ``member``, generated as
    the design's machine cuts them."""
    model = get_machine_model(design.model, plugin_manager=plugin_manager)
    return model.generate_flanks(design, member=member, grid=grid or FlankGrid())


__all__ = [
    "BaseCommand",
    "Curve",
    "Metric",
    "Option",
    "OptionError",
    "Pattern",
    "BaseEvaluator",
    "BaseMachineModel",
    "BaseObjective",
    "Benchmark",
    "Blank",
    "Design",
    "DesignError",
    "Evaluation",
    "FlankGrid",
    "FlankMap",
    "GearoptError",
    "MachineSettings",
    "Meta",
    "Misalignment",
    "NotAvailableError",
    "PairData",
    "PluginError",
    "SearchDimension",
    "SettingsError",
    "StudyError",
    "UnknownKeyError",
    "__version__",
    "basic_settings",
    "export_rexs",
    "load_rexs",
    "write_rexs",
    "load_study_spec",
    "run_study",
    "compute_blank",
    "evaluators",
    "generate_flanks",
    "get_machine_model",
    "get_plugin_manager",
    "hookimpl",
    "hookspec",
    "list_plugins",
    "load_design",
    "loads_design",
    "machine_models",
    "objectives",
    "parse_design",
    "with_overrides",
]


def __getattr__(name: str):
    # the study layer imports Optuna and SQLAlchemy (about 2 s): loaded when it is asked for,
    # so that the CLI and every worker process start without it
    if name == "run_study":
        from gearopt.study import run_study

        return run_study
    raise AttributeError(f"module 'gearopt' has no attribute {name!r}")
