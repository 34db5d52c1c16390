"""The gearopt plugin contract: hook specifications (the plugin author's manual).

A plugin is a module (or an object) with functions marked ``@gearopt.hookimpl`` whose names are
the hooks below. Make it known to gearopt through the entry-point group ``gearopt`` of your
distribution, exactly as the built-ins do::

    # pyproject.toml of your distribution
    [project.entry-points.gearopt]
    my-machine = "my_package.my_machine"

    # my_package/my_machine.py
    import gearopt

    class MyMachine(gearopt.BaseMachineModel):
        name = "my-machine"
        ...

    @gearopt.hookimpl
    def gearopt_machine_models():
        return [MyMachine()]

Every hook is called once each time a plugin manager is built (``gearopt.get_plugin_manager()``),
in the coordinator and in each worker process; return fresh, stateless, picklable objects and do
no expensive work at import or call time. Names are unique across all plugins: a duplicate is a
:class:`~gearopt.errors.PluginError` naming both plugins. Prove your objects with the contract
suites of :mod:`gearopt.testing`.

A hook passes its arguments by name, and a hookimpl takes only those it needs (pluggy's rule):
``def gearopt_commands():`` and ``def gearopt_commands(plugin_manager):`` both implement
:func:`gearopt_commands`.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import pluggy

if TYPE_CHECKING:
    from gearopt.commands import BaseCommand, Benchmark
    from gearopt.evaluation import BaseEvaluator, BaseObjective
    from gearopt.machine import BaseMachineModel

PROJECT_NAME = "gearopt"
hookspec = pluggy.HookspecMarker(PROJECT_NAME)
hookimpl = pluggy.HookimplMarker(PROJECT_NAME)


@hookspec
def gearopt_machine_models() -> list[BaseMachineModel]:
    """Return the machine models this plugin provides.

    Returns
    -------
    list of gearopt.BaseMachineModel
        Instances; each ``name`` (e.g. ``"cyclo-palloid"``) is what a design file's
        ``[machine] model`` selects. A model parses its own ``[machine]`` table into a frozen
        dataclass (``parse_machine``), computes basic settings (``basic_settings``), declares its
        tunable keys (``search_space``) and generates flanks (``generate_flank``).

    Notes
    -----
    Called once per plugin manager; every plugin's answer is collected (no first-result rule).
    A model name that another plugin already provides raises :class:`gearopt.errors.PluginError`
    when the models are listed.
    """


@hookspec
def gearopt_evaluators() -> list[BaseEvaluator]:
    """Return the evaluators this plugin provides.

    Returns
    -------
    list of gearopt.BaseEvaluator
        Instances; ``evaluate(design, conditions)`` returns a :class:`gearopt.Evaluation` with
        finite scalar ``metrics`` named with units, optional ``arrays``, the ``conditions``
        that produced them, an optional ``report`` (JSON-ready details keyed by section, which
        ``gearopt analyze --json`` prints) and the ``curves`` and ``patterns`` it declares. An
        evaluator declares its metrics (named by their places in the report), curves, pattern
        and options as class attributes (:class:`gearopt.BaseEvaluator`, docs/declarations.md);
        the study tables, ``gearopt analyze`` and ``gearopt plugins`` read them. Evaluators
        run in worker processes and must not touch storage. The contact engine
        (:mod:`gearopt.contact`, :mod:`gearopt.mesh`) works on any machine model's FlankMaps,
        so a contact evaluator needs no machine knowledge.

    Notes
    -----
    Called once per plugin manager; all answers are collected; names are unique across plugins.
    """


@hookspec
def gearopt_objectives() -> list[BaseObjective]:
    """Return the objectives and constraints this plugin provides.

    Returns
    -------
    list of gearopt.BaseObjective
        Instances; ``value(evaluations, **options)`` maps the evaluations of one trial to one
        finite float. The evaluations are keyed by their labels in the study file
        (``[evaluations.<label>]``, a label defaulting to the evaluator's name); ``options`` are
        the other keys of the study file's ``[[objectives]]`` or ``[[constraints]]`` entry.
        ``reads(**options)`` says which labels ``value`` reads and of which evaluator each must
        be, and refuses bad options with a :class:`gearopt.errors.GearoptError` (the default
        checks the declared ``options``, :class:`gearopt.Option`): a study calls it when its
        file is read, before any trial. ``kind = "constraint"`` values are feasible
        when <= 0 (the study passes them to ``trial.set_constraint``); objectives are
        minimised unless ``direction = "maximize"``. The built-ins are in
        ``gearopt_plugins.objectives``.

    Notes
    -----
    Called once per plugin manager; all answers are collected; names are unique across plugins.
    """


@hookspec
def gearopt_commands(plugin_manager: pluggy.PluginManager) -> list[BaseCommand]:
    """Return the subcommands of ``gearopt`` this plugin provides (as pytest plugins add
    options).

    Parameters
    ----------
    plugin_manager
        The manager ``gearopt`` was built from. A command that looks up machine models,
        evaluators or objectives keeps it and passes it on
        (``gearopt.get_machine_model(name, plugin_manager=...)``, ``gearopt.evaluators(...)``),
        so that it sees the plugins the command line was built with.

    Returns
    -------
    list of gearopt.commands.BaseCommand
        Instances; ``name`` is the subcommand (``gearopt <name> ...``), ``help`` its one line
        in ``gearopt --help``, ``add_arguments(parser)`` fills its own argparse parser and
        ``run(args) -> int`` runs it and returns the exit status. A
        :class:`~gearopt.errors.GearoptError` raised by ``run`` is printed as one line with
        exit status 2, exactly as the core's commands report errors. Example::

            class Hello(gearopt.BaseCommand):
                name = "hello"
                help = "greet a design"

                def add_arguments(self, parser):
                    parser.add_argument("design")

                def run(self, args):
                    print(f"hello {gearopt.load_design(args.design).name}")
                    return 0

            @gearopt.hookimpl
            def gearopt_commands():
                return [Hello()]

    Notes
    -----
    Called once per plugin manager, when ``gearopt`` builds its argument parser (so every run
    of ``gearopt``, whichever command it runs); all answers are collected. A name that the core
    (``settings``, ``analyze``, ``study``, ...) or another plugin already uses raises
    :class:`gearopt.errors.PluginError` naming both.
    """


@hookspec
def gearopt_benchmarks() -> list[Benchmark]:
    """Return the benchmarks of ``gearopt bench`` this plugin provides.

    Returns
    -------
    list of gearopt.commands.Benchmark
        ``Benchmark(name=..., function=..., description=...)``: ``name`` is the key of the
        median time in ``gearopt bench --json`` (``"change_gears_ms"``); ``function`` is a
        module-level function ``() -> (milliseconds, info)`` that warms up, times its kernel
        with :func:`gearopt.commands.time_call_ms` (return its
        :class:`~gearopt.commands.CallTime` as it is: it carries the CPU time, which ``gearopt
        bench`` prints beside the wall time and reports as ``cpu_ms``; a plain float gives
        none) and returns JSON-ready facts to print beside the time (keys prefixed with its
        subject, as they share one JSON object with every other benchmark's). ``gearopt
        bench`` runs each repeat in a fresh one-thread process that imports ``function`` by
        its module and qualified name, so it must be importable
        without the plugin manager.

    Notes
    -----
    Called once per plugin manager; all answers are collected. A name that the core's
    benchmarks (``gearopt.bench``) or another plugin already uses raises
    :class:`gearopt.errors.PluginError` naming both. Never assert timings in tests.
    """
