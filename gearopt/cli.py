"""The ``gearopt`` command.

``gearopt plugins`` lists every machine model, evaluator and objective with its distribution;
``gearopt settings DESIGN.toml`` prints the blank and the basic machine-tool settings;
``gearopt flanks DESIGN.toml`` generates both members' flanks and measures them;
``gearopt analyze DESIGN.toml`` runs the contact analyses (TCA, pattern, backlash, ease-off);
``gearopt study run|enqueue|export STUDY.toml`` runs Optuna studies (:mod:`gearopt.study`);
``gearopt bench`` times the kernels. Plugins add commands of their own through the
``gearopt_commands`` hook (:class:`gearopt.commands.BaseCommand`). Errors in the input are
printed as one line naming the parameter, its value and the rule (exit status 2), the plugins'
commands' errors too.
"""

from __future__ import annotations

import argparse
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
from gearopt.design_files import load_design
from gearopt.errors import DesignError, GearoptError, PluginError
from gearopt.flank import FLANKS, MEMBERS
from gearopt.flank_cli import add_flank_parser, parse_grid, print_warnings
from gearopt.plausibility import caught, contact_findings, flank_findings
from gearopt.plots import plot_analysis
from gearopt.plugins import default_plugin_manager, evaluators, get_machine_model, list_plugins
from gearopt.study_cli import add_study_parser
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
    out: dict[str, Any] = {"design": design.name, "model": design.model}
    out["conditions"] = options.as_dict()
    results = {}
    torques = _torques(args.torque_nm)
    with caught() as numerical:
        for name in ("tca", "backlash", "ease-off"):
            evaluation = registry[name].evaluate(design, conditions)
            results[name] = evaluation
            out.update(evaluation.report)
        found = [
            text
            for member, maps in zip(MEMBERS, analysed_flanks(design, options), strict=True)
            for flank, fm in maps.items()
            for text in flank_findings(
                design, member, flank, fm.summary(), row_mm=_row_mm(fm.profile_mm)
            )
        ]
        found += contact_findings(out)
        if torques is not None or design.load.get("torque_nm") is not None:
            load_conditions = dict(conditions)
            if torques is not None:
                load_conditions["torque_nm"] = torques
            evaluation = registry["ltca"].evaluate(design, load_conditions)
            results["ltca"] = evaluation
            out.update(evaluation.report)
    out["warnings"] = found + numerical
    if args.plot:
        out["plots"] = [str(p) for p in plot_analysis(design, results, args.plot)]
    if args.json:
        print(json.dumps(out, indent=2))
        return 0
    print_warnings(out["warnings"])
    print(
        f"design {design.name!r}, machine model {design.model!r}, grid {options.grid.shape}, "
        f"{options.positions} positions, compound {options.compound_um:g} um "
        f"({options.separation} separation)"
    )
    rows = []
    for key in ("tca", "tca_coast"):
        side = out[key]
        pattern = side["pattern"]
        rows.append(
            (
                side["side"],
                f"{side['te_peak_to_peak_arcsec']:.4f}",
                f"{side['contact_ratio']:.3f}",
                f"{pattern['width_mm']:.2f}",
                f"{pattern['bias_mm']:.2f}",
                f"{pattern['center_offset_mm'][0]:.2f}, {pattern['center_offset_mm'][1]:.2f}",
                "yes" if pattern["edge_contact"] else "no",
            )
        )
    print()
    header = (
        "side",
        "TE p-p (arcsec)",
        "contact ratio",
        "width (mm)",
        "bias (mm)",
        "M - C face, profile (mm)",
        "edge contact",
    )
    print(_table(rows, header))
    b = out["backlash"]
    print(
        f"\nbacklash (circumferential, at r = {b['radius_mm']:.3f} mm): min {b['min_um']:.2f}, "
        f"mean {b['mean_um']:.2f}, max {b['max_um']:.2f} um"
        + ("  INTERFERENCE" if b["interference"] else "")
    )
    e = out["ease_off"]
    print(
        f"ease-off (pinion, from the surface conjugate to the gear): drive max "
        f"{e['drive']['max_um']:.2f} um, coast max {e['coast']['max_um']:.2f} um"
    )
    if "ltca" in out:
        rows = [
            (
                side["side"] if "side" in side else name,
                f"{side['torque_nm']:g}",
                f"{side['lte_peak_to_peak_arcsec']:.3f}",
                f"{side['max_contact_pressure_mpa']:.0f}",
                f"{side['max_line_load_n_per_mm']:.1f}",
                f"{side['mesh_stiffness_n_per_mm_um']:.2f}",
                "yes" if side["edge_loading"] else "no",
            )
            for name, key in (("drive", "ltca"), ("coast", "ltca_coast"))
            for side in out[key]
        ]
        header = (
            "side",
            "torque (N m)",
            "LTE p-p (arcsec)",
            "p max (MPa)",
            "line load (N/mm)",
            "mesh stiffness (N/(mm um))",
            "edge loading",
        )
        print()
        print(_table(rows, header))
    for path in out.get("plots", []):
        print(f"wrote {path}")
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
    if args.json:
        print(json.dumps(out, indent=2))
        return 0
    rows = [
        (name, f"{r['median_ms']:.4f}", ", ".join(f"{k}={v}" for k, v in r["info"].items()))
        for name, r in results.items()
    ]
    print(f"medians over {args.repeats} fresh processes, 1 thread (BLAS/OpenMP)")
    print(_table(rows, ("benchmark", "median", "conditions")))
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
    p = sub.add_parser("plugins", help="list machine models, evaluators and objectives")
    p.add_argument("--json", action="store_true", help="print JSON")
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
    # defaults: the design's [analysis] table, else gearopt.analysis.AnalysisOptions
    p.set_defaults(func=_cmd_analyze)

    p = sub.add_parser("bench", help="time the kernels (medians over fresh one-thread processes)")
    p.add_argument("names", nargs="*", help="benchmarks to run (default: all)")
    p.add_argument("--repeats", type=int, default=5, help="fresh processes per benchmark")
    p.add_argument("--json", action="store_true", help="print JSON")
    p.set_defaults(func=_cmd_bench)
    add_flank_parser(sub)
    add_blank_parser(sub)
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


if __name__ == "__main__":
    sys.exit(main())
