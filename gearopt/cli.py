"""The ``gearopt`` command.

``gearopt plugins`` lists every machine model, evaluator, objective, plugin command and benchmark;
``gearopt settings DESIGN.toml`` prints the blank and the basic machine-tool settings;
``gearopt flanks DESIGN.toml`` generates both members' flanks and measures them;
``gearopt analyze DESIGN.toml`` runs the contact analyses (TCA, pattern, backlash, ease-off);
``gearopt study run|enqueue|export STUDY.toml`` runs Optuna studies (:mod:`gearopt.study`);
``gearopt bench`` times the kernels; ``gearopt grid`` and ``gearopt correct`` the closed loop
from measured flanks (:mod:`gearopt.measurement_cli`); ``gearopt rexs export|import`` REXS files
(:mod:`gearopt.rexs_cli`). Plugins add commands of their own through the
``gearopt_commands`` hook (:class:`gearopt.commands.BaseCommand`). Errors in the input are
printed as one line naming the parameter, its value and the rule (exit status 2), the plugins'
commands' errors too.
"""

from __future__ import annotations

import argparse
import gc
import json
import os
import sys
from collections.abc import Sequence
from importlib import metadata
from typing import Any

import pluggy

from gearopt.analysis import AnalysisOptions, analysed_flanks
from gearopt.bench import run_benchmarks
from gearopt.blank_cli import add_blank_parser
from gearopt.commands import text_table as _table
from gearopt.declarations import Option, declared, describe, metric_names
from gearopt.design_files import load_design
from gearopt.errors import DesignError, GearoptError, PluginError
from gearopt.figures.report import write_report
from gearopt.flank import FLANKS, MEMBERS
from gearopt.flank_cli import add_flank_parser, parse_grid, print_warnings
from gearopt.measurement_cli import add_measurement_parsers
from gearopt.plausibility import caught, contact_findings, flank_findings
from gearopt.plots import DEDICATED_FIGURES, plot_analysis
from gearopt.plots_declared import plot_declared
from gearopt.plugins import default_plugin_manager, evaluators, get_machine_model, list_plugins
from gearopt.rexs_cli import add_rexs_parser
from gearopt.study_cli import add_study_parser
from gearopt.studyfile import load_study_spec
from gearopt.thickness import design_chordal_thickness

__all__ = ["main"]


def _format_value(value: Any) -> str:
    if isinstance(value, float):
        return f"{value:.6f}"
    if isinstance(value, list | tuple):
        return ", ".join(_format_value(v) for v in value)
    return str(value)


def _cmd_plugins(args: argparse.Namespace) -> int:
    entries = list_plugins()
    if args.json:
        print(
            json.dumps(
                [
                    {
                        "kind": e.kind,
                        "name": e.name,
                        "plugin": e.plugin,
                        "distribution": e.distribution,
                        "version": e.version,
                        "description": e.description,
                        **describe(e.obj),
                    }
                    for e in entries
                ],
                indent=2,
            )
        )
        return 0
    rows = [
        (e.kind, e.name, f"{e.distribution} {e.version}".strip(), e.description) for e in entries
    ]
    print(
        _table(rows, ("kind", "name", "distribution", "description"))
        if rows
        else "no plugins found"
    )
    if args.options:
        rows = [
            (
                e.name,
                o.name,
                "(required)" if o.required else _format_value(o.default),
                o.rule,
                o.description,
            )
            for e in entries
            for o in getattr(e.obj, "options", None) or ()
            if isinstance(o, Option)
        ]
        print()
        print(_table(rows, ("plugin", "option", "default", "rule", "description")))
    return 0


def _cmd_settings(args: argparse.Namespace) -> int:
    with caught() as numerical:
        design = load_design(args.design)
        settings = get_machine_model(design.model).basic_settings(design)
    out = settings.as_dict()
    out = {"design": design.name, **out, "blank": design.blank.as_dict(), "warnings": numerical}
    if args.json:
        print(json.dumps(out, indent=2))
        return 0
    print_warnings(out["warnings"])
    print(f"design {design.name!r}, machine model {design.model!r}")
    blank = out["blank"]
    blank_rows = [(k, _format_value(v)) for k, v in blank.items()]
    print()
    print(_table(blank_rows, ("blank", "[pinion, gear] or value")))
    keys = list(out["pinion"])
    rows = [(k, _format_value(out["pinion"][k]), _format_value(out["gear"][k])) for k in keys]
    print()
    print(_table(rows, ("basic machine-tool settings", "pinion", "gear")))
    for note in out["notes"]:
        print(f"\nnote: {note}")
    return 0


def _cmd_flanks(args: argparse.Namespace) -> int:

    design = load_design(args.design)
    model = get_machine_model(design.model)
    grid = parse_grid(args.grid)
    out: dict[str, Any] = {"design": design.name, "model": design.model, "grid": list(grid.shape)}
    found: list[str] = []
    with caught() as numerical:
        for member in MEMBERS:
            maps = model.generate_flanks(design, member=member, grid=grid)
            entry: dict[str, Any] = {}
            for flank in FLANKS:
                fm = maps[flank]
                entry[flank] = {
                    **fm.summary(),
                    "tool_penetration_mm": fm.tool_penetration_mm() if fm.surface else None,
                }
                row_mm = _row_mm(fm.profile_mm)
                found += flank_findings(design, member, flank, entry[flank], row_mm=row_mm)
            if design.pair.mean_normal_chordal_addendum_mm is not None:
                measured = design_chordal_thickness(design, member, maps)
                entry["mean_normal_chordal_thickness_mm"] = measured.thickness_mm
                entry["chordal_addendum_mm"] = design.pair.mean_normal_chordal_addendum_mm[
                    MEMBERS.index(member)
                ]
            out[member] = entry
    out["warnings"] = found + numerical
    if args.json:
        print(json.dumps(out, indent=2))
        return 0
    print_warnings(out["warnings"])
    print(f"design {design.name!r}, machine model {design.model!r}, grid {grid.shape}")
    rows = []
    for member in MEMBERS:
        for flank in FLANKS:
            e = out[member][flank]
            low = e["lowest_generated_height_mm"]
            rows.append(
                (
                    f"{member} {flank}",
                    e["hand"],
                    f"{e['generated_nodes']}",
                    f"{e['max_residual']:.1e}",
                    f"{low['toe']:.3f}, {low['middle']:.3f}, {low['heel']:.3f}",
                    f"{e['tool_penetration_mm']:.1e}",
                )
            )
    print()
    header = (
        "flank",
        "hand",
        "generated nodes",
        "max residual",
        "lowest generated h toe, mid, heel (mm)",
        "tool penetration (mm)",
    )
    print(_table(rows, header))
    for member in MEMBERS:
        if "mean_normal_chordal_thickness_mm" in out[member]:
            print(
                f"\n{member}: mean normal chordal thickness "
                f"{out[member]['mean_normal_chordal_thickness_mm']:.5f} mm at chordal addendum "
                f"{out[member]['chordal_addendum_mm']} mm (measured on the generated flanks)"
            )
    return 0


def _row_mm(profile_mm) -> float:
    """The profile spacing of a FlankMap grid (mm)."""
    return float(profile_mm[1] - profile_mm[0])


def _analysis_conditions(evaluator, conditions: dict, torques) -> dict:
    """The command line's conditions an evaluator declares (``torque_nm`` too, when given)."""
    declared = {o.name for o in evaluator.options or ()}
    given = {k: v for k, v in conditions.items() if k in declared}
    if torques is not None and "torque_nm" in declared:
        given["torque_nm"] = torques
    return given


def _metric_rows(evaluator, evaluation) -> list[tuple[str, ...]]:
    """Text rows (metric, unit, value per side or one value) of an evaluation's declared
    metrics; the sides' columns follow the evaluator's ``sections``."""
    rows = []
    for metric in evaluator.metrics:
        names = metric_names(evaluator, metric)
        values = [evaluation.metrics.get(n) for n in names]
        if "*" in metric.name:
            rows += [
                (name, metric.unit, f"{value:.6g}")
                for name, value in evaluation.metrics.items()
                if declared(evaluator, name) is metric
            ]
        elif any(v is not None for v in values):
            cells = ["-" if v is None else f"{v:.6g}" for v in values]
            rows.append((metric.name, metric.unit, *cells))
    return rows


def _print_analysis(registry, results: dict) -> None:
    """Each evaluation's declared metrics as a table, one column per side."""
    for name, evaluation in results.items():
        evaluator = registry[name]
        sides = list(evaluator.sections) if evaluator.sections else ["value"]
        rows = _metric_rows(evaluator, evaluation)
        width = max((len(r) for r in rows), default=3)
        rows = [r + ("",) * (width - len(r)) for r in rows]
        header = ("metric", "unit", *sides[: width - 2], *("",) * (width - 2 - len(sides)))
        print(f"\n{name}: {evaluator.description}")
        print(_table(rows, header) if rows else "(no metrics)")


def _cmd_analyze(args: argparse.Namespace) -> int:

    design = load_design(args.design)
    # the options given on the command line override the design's [analysis] table
    conditions: dict[str, Any] = {
        key: value
        for key, value in (
            ("separation", args.separation),
            ("compound_um", args.compound_um),
            ("positions", args.positions),
            ("grid", None if args.grid is None else list(parse_grid(args.grid).shape)),
        )
        if value is not None
    }
    options = AnalysisOptions.from_conditions(conditions, design=design)
    registry = evaluators()
    torques = _torques(args.torque_nm)
    chosen = {
        name: evaluator
        for name, evaluator in registry.items()
        if evaluator.in_analysis(design)
        or (torques is not None and any(o.name == "torque_nm" for o in evaluator.options or ()))
    }
    for name in args.evaluator or ():
        if name not in registry:
            raise GearoptError("--evaluator", name, f"unknown; installed: {sorted(registry)}")
        chosen[name] = registry[name]
    out: dict[str, Any] = {"design": design.name, "model": design.model}
    out["conditions"] = options.as_dict()
    results = {}
    with caught() as numerical:
        for name, evaluator in chosen.items():
            given = _analysis_conditions(evaluator, conditions, torques)
            evaluator.check_conditions(design, given)
            evaluation = evaluator.evaluate(design, given)
            results[name] = evaluation
            out.update(evaluation.report or {name: dict(evaluation.metrics)})
        found = [
            text
            for member, maps in zip(MEMBERS, analysed_flanks(design, options), strict=True)
            for flank, fm in maps.items()
            for text in flank_findings(
                design, member, flank, fm.summary(), row_mm=_row_mm(fm.profile_mm)
            )
        ]
        found += contact_findings(out)
    out["warnings"] = found + numerical
    if args.plot:
        paths = plot_analysis(design, results, args.plot)
        rest = {k: v for k, v in results.items() if k not in DEDICATED_FIGURES}
        paths += plot_declared(rest, registry, args.plot, title=design.name)
        out["plots"] = [str(p) for p in paths]
    if args.json:
        print(json.dumps(out, indent=2))
        return 0
    print_warnings(out["warnings"])
    print(
        f"design {design.name!r}, machine model {design.model!r}, grid {options.grid.shape}, "
        f"{options.positions} positions, compound {options.compound_um:g} um "
        f"({options.separation} separation)"
    )
    _print_analysis(registry, results)
    for path in out.get("plots", []):
        print(f"wrote {path}")
    return 0


def _cmd_report(args: argparse.Namespace) -> int:
    window = None
    if args.backlash_window_um is not None:
        try:
            window = [float(part) for part in args.backlash_window_um.split(",")]
        except ValueError:
            window = []
        if len(window) != 2 or not window[0] < window[1]:
            raise DesignError(
                "--backlash-window-um", args.backlash_window_um, "must be MIN,MAX in um, MIN < MAX"
            )
    print(f"wrote {write_report(load_design(args.design), args.out, window_um=window)}")
    return 0


def _cmd_dashboard(args: argparse.Namespace) -> int:
    from gearopt.dashboard import dashboard_app, serve

    serve(dashboard_app(load_study_spec(args.study), args.storage), args.host, args.port)
    return 0


def _torques(text: str | None) -> list[float] | None:
    """The ``--torque-nm`` list, or None."""
    if text is None:
        return None
    try:
        return [float(part) for part in text.split(",")]
    except ValueError:
        raise DesignError(
            "--torque-nm", text, "must be numbers of N m separated by commas"
        ) from None


def _cmd_bench(args: argparse.Namespace) -> int:

    results = run_benchmarks(args.names or None, repeats=args.repeats)
    out: dict[str, Any] = {"threads": 1, "repeats": args.repeats}
    for name, result in results.items():
        out[name] = result["median_ms"]
        out.update(result["info"])
    out["runs_ms"] = {name: result["runs_ms"] for name, result in results.items()}
    out["cpu_ms"] = {name: result["median_cpu_ms"] for name, result in results.items()}
    out["runs_cpu_ms"] = {name: result["runs_cpu_ms"] for name, result in results.items()}
    if args.json:
        print(json.dumps(out, indent=2))
        return 0
    rows = [
        (
            name,
            f"{r['median_ms']:.4f}",
            "-" if r["median_cpu_ms"] is None else f"{r['median_cpu_ms']:.4f}",
            ", ".join(f"{k}={v}" for k, v in r["info"].items()),
        )
        for name, r in results.items()
    ]
    print(f"medians over {args.repeats} fresh processes, 1 thread (BLAS/OpenMP); ms per call")
    print(_table(rows, ("benchmark", "wall", "cpu", "conditions")))
    return 0


def _version() -> str:
    """The installed distribution's version (``unknown`` when run from a bare source tree)."""
    try:
        return metadata.version("gearopt")
    except metadata.PackageNotFoundError:
        return "unknown"


def add_plugin_commands(sub, plugin_manager: pluggy.PluginManager | None = None) -> None:
    """Add the plugins' commands (the ``gearopt_commands`` hook) to the CLI's subparsers.

    Raises :class:`PluginError` when a plugin's command takes a name the core already uses
    (two plugins' are refused by the registry).
    """
    core = set(sub.choices)
    for entry in list_plugins(plugin_manager, "command"):
        if entry.name in core:
            raise PluginError(
                f"command name {entry.name!r}",
                rule=f"provided by both the core (gearopt.cli) and plugin {entry.plugin!r}",
            )
        command = entry.obj
        p = sub.add_parser(command.name, help=command.help)
        command.add_arguments(p)
        p.set_defaults(func=command.run)


def build_parser(plugin_manager: pluggy.PluginManager | None = None) -> argparse.ArgumentParser:
    """The argument parser of the ``gearopt`` command: the core's commands, then the commands
    of the plugins of ``plugin_manager`` (default: every installed plugin)."""
    parser = argparse.ArgumentParser(
        prog="gearopt",
        description="Spiral bevel gear design: machine settings, TCA, Optuna studies.",
    )
    parser.add_argument("--version", action="version", version=f"gearopt {_version()}")
    sub = parser.add_subparsers(dest="command", required=True)
    p = sub.add_parser(
        "plugins",
        help="list machine models, evaluators, objectives, plugin commands and benchmarks",
    )
    p.add_argument("--json", action="store_true", help="print JSON (with the declarations)")
    p.add_argument(
        "--options", action="store_true", help="also list the evaluators' and objectives' options"
    )
    p.set_defaults(func=_cmd_plugins)
    p = sub.add_parser("settings", help="basic machine-tool settings of a design")
    p.add_argument("design", help="design TOML file")
    p.add_argument("--json", action="store_true", help="print JSON")
    p.set_defaults(func=_cmd_settings)
    p = sub.add_parser("flanks", help="generate the flanks of a design and measure them")
    p.add_argument("design", help="design TOML file")
    p.add_argument("--grid", default="25,13", help="FlankMap grid n_face,n_profile")
    p.add_argument("--json", action="store_true", help="print JSON")
    p.set_defaults(func=_cmd_flanks)
    p = sub.add_parser("analyze", help="unloaded TCA, pattern, backlash and ease-off")
    p.add_argument("design", help="design TOML file")
    p.add_argument("--json", action="store_true", help="print JSON")
    p.add_argument("--plot", metavar="DIR", help="write PNG figures into DIR (needs matplotlib)")
    p.add_argument(
        "--separation",
        choices=("normal", "circumferential"),
        help="how the pattern's separation is measured (default normal; seed 003: circumferential)",
    )
    p.add_argument("--compound-um", type=float, help="marking-compound thickness (um; 6.5)")
    p.add_argument("--positions", type=int, help="contact positions over two cycles (21)")
    p.add_argument("--grid", help="FlankMap grid n_face,n_profile (25,21)")
    p.add_argument(
        "--torque-nm",
        help="loaded TCA at these output torques (N m on the gear, comma-separated); "
        "default: the design's [load] torque_nm, if any",
    )
    p.add_argument(
        "--evaluator",
        action="append",
        metavar="NAME",
        help="run this installed evaluator too (repeatable; `gearopt plugins` lists them)",
    )
    # defaults: the design's [analysis] table, else gearopt.analysis.AnalysisOptions
    p.set_defaults(func=_cmd_analyze)

    p = sub.add_parser("report", help="one self-contained HTML page of a design's analysis")
    p.add_argument("design", help="design TOML file")
    p.add_argument("--out", required=True, metavar="DIR", help="folder of the HTML page")
    p.add_argument("--backlash-window-um", metavar="MIN,MAX", help="backlash window to draw")
    p.set_defaults(func=_cmd_report)

    p = sub.add_parser(
        "dashboard", help="optuna-dashboard on a study, its best trials the feasible ones"
    )
    p.add_argument("study", help="study TOML file")
    p.add_argument("--storage", help="SQLAlchemy storage URL (default: the study's own)")
    p.add_argument("--host", default="127.0.0.1", help="address to listen on (127.0.0.1)")
    p.add_argument("--port", type=int, default=8080, help="port (8080; 0: any free port)")
    p.set_defaults(func=_cmd_dashboard)

    p = sub.add_parser("bench", help="time the kernels (medians over fresh one-thread processes)")
    p.add_argument("names", nargs="*", help="benchmarks to run (default: all)")
    p.add_argument("--repeats", type=int, default=5, help="fresh processes per benchmark")
    p.add_argument("--json", action="store_true", help="print JSON")
    p.set_defaults(func=_cmd_bench)
    add_flank_parser(sub)
    add_blank_parser(sub)
    add_measurement_parsers(sub)
    add_rexs_parser(sub)
    add_study_parser(sub)
    add_plugin_commands(sub, plugin_manager or default_plugin_manager())
    return parser


def main(
    argv: Sequence[str] | None = None, *, plugin_manager: pluggy.PluginManager | None = None
) -> int:
    """Entry point of the ``gearopt`` command; returns the exit status. ``plugin_manager``
    gives the plugins whose commands it offers (default: every installed plugin)."""
    try:
        parser = build_parser(plugin_manager)
    except GearoptError as exc:  # a plugin that fails to load or clashes
        print(f"gearopt: error: {type(exc).__name__}: {exc}", file=sys.stderr)
        return 2
    args = parser.parse_args(argv)
    try:
        return args.func(args)
    except GearoptError as exc:
        print(f"gearopt: error: {type(exc).__name__}: {exc}", file=sys.stderr)
        return 2
    except BrokenPipeError:
        # the reader went away (``gearopt settings X | head``): no traceback, and none when
        # Python flushes standard output on exit either
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        return 1


def console() -> int:
    """The ``gearopt`` console command: :func:`main` with the modules imported so far left out
    of its garbage collections (and of a study's worker processes forked from it); after a
    study run, which closes its database connections itself, the objects still alive are left
    to the process's end (``gc.freeze``) rather than to the interpreter's last collections,
    which took about a second (the modules, compiled kernels and trials). Other commands end
    as usual: their objects' finalizers close what they opened (SQLite's write-ahead log)."""
    gc.freeze()
    argv = sys.argv[1:]
    status = main(argv)
    if status == 0 and argv[:2] == ["study", "run"]:
        sys.stdout.flush()
        gc.freeze()
    return status


if __name__ == "__main__":
    sys.exit(console())
