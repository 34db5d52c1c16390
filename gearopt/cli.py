"""The ``gearopt`` command.

``gearopt plugins`` lists every machine model, evaluator and objective with its distribution;
``gearopt settings DESIGN.toml`` prints the blank and the basic machine-tool settings;
``gearopt flanks DESIGN.toml`` generates both members' flanks and measures them;
``gearopt analyze DESIGN.toml`` runs the contact analyses (TCA, pattern, backlash, ease-off);
``gearopt realise-te DESIGN.toml --out NEW.toml`` fits the settings to its ``[te_target]``;
``gearopt chain MACHINE ...`` the errors of a machine's kinematic chains (seed 000) and
``gearopt change-gears MACHINE --ratio R`` the best change gears of its set;
``gearopt grid`` and ``gearopt correct`` the closed loop from measured flanks
(:mod:`gearopt.measurement_cli`);
``gearopt study run|enqueue|export STUDY.toml`` runs Optuna studies (:mod:`gearopt.study`).
Errors in the input are printed as one line naming the parameter, its value and the rule
(exit status 2).
"""

from __future__ import annotations

import argparse
import copy
import dataclasses
import json
import os
import sys
from collections.abc import Sequence
from importlib import metadata
from pathlib import Path
from typing import Any

import pandas as pd
import tomli_w

from gearopt.analysis import AnalysisOptions, analysed_flanks
from gearopt.bench import run_benchmarks
from gearopt.blank_cli import add_blank_parser
from gearopt.chains import WorkGear, evaluate_machine, load_machine, select_change_gears
from gearopt.design_files import load_design
from gearopt.errors import DesignError, GearoptError
from gearopt.flank import FLANKS, MEMBERS
from gearopt.flank_cli import add_flank_parser, parse_grid, print_warnings
from gearopt.measurement_cli import add_measurement_parsers
from gearopt.plausibility import caught, contact_findings, flank_findings
from gearopt.plots import plot_analysis
from gearopt.plugins import evaluators, get_machine_model, list_plugins
from gearopt.study_cli import add_study_parser
from gearopt.thickness import design_chordal_thickness

__all__ = ["main"]


def _format_value(value: Any) -> str:
    if isinstance(value, float):
        return f"{value:.6f}"
    if isinstance(value, list | tuple):
        return ", ".join(_format_value(v) for v in value)
    return str(value)


def _is_number(cell: str) -> bool:
    try:
        float(cell.split(",")[0])
    except ValueError:
        return False
    return True


def _table(rows: list[tuple[str, ...]], header: tuple[str, ...]) -> str:
    """Plain-text table: first column and text left-aligned, numbers right-aligned."""
    widths = [max(len(r[i]) for r in [header, *rows]) for i in range(len(header))]
    lines = ["  ".join(h.ljust(w) for h, w in zip(header, widths, strict=True)).rstrip()]
    lines.append("  ".join("-" * w for w in widths))
    for row in rows:
        cells = [row[0].ljust(widths[0])] + [
            c.rjust(w) if _is_number(c) else c.ljust(w)
            for c, w in zip(row[1:], widths[1:], strict=True)
        ]
        lines.append("  ".join(cells).rstrip())
    return "\n".join(lines)


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


def _cmd_realise_te(args: argparse.Namespace) -> int:

    design = load_design(args.design)
    table, report = get_machine_model(design.model).realise_te_target(design, side=args.side)
    data = copy.deepcopy(dict(design.source))
    data.pop("synthesis", None)
    data["machine"] = {"model": design.model, **table}
    header = (
        f"# {Path(args.design).name} with the pinion's {report.get('pinion_flank', '')} roll "
        f"fitted to [te_target] by `gearopt realise-te` (inverse TCA).\n"
        + "".join(f"# {k}: {v}\n" for k, v in report.items() if k not in ("before", "after"))
        + "\n"
    )
    if args.out:
        Path(args.out).write_text(header + tomli_w.dumps(data), encoding="utf-8")
        report["written"] = str(args.out)
    if args.json or not args.out:
        print(json.dumps(report, indent=2))
    else:
        print(
            f"wrote {args.out}: " + ", ".join(f"{k} = {v:.6g}" for k, v in report["after"].items())
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


def _parse_teeth(text: str, option: str, *, count: int | None = None) -> list[int]:
    rule = "must be tooth counts separated by commas"
    if count == 4:
        rule = "must be four tooth counts a,b,c,d (a/b x c/d)"
    try:
        teeth = [int(part) for part in text.replace(" ", "").split(",") if part]
    except ValueError:
        raise DesignError(option, text, rule) from None
    if count is not None and len(teeth) != count:
        raise DesignError(option, text, rule)
    return teeth


def _chain_text(name: str, out: dict[str, Any]) -> str:

    summary = [
        (key, f"{out[key]:.8g}" if out[key] is not None else "-")
        for key in (
            "input_angle_deg",
            "theoretical_ratio",
            "max_ratio",
            "min_ratio",
            "ratio_error",
            "ratio_error_plus",
            "ratio_error_minus",
            "ratio_error_percent",
            "angle_error_deg",
            "pitch_error_um",
        )
    ]
    gears = ", ".join(f"{k}={v}" for k, v in out["gears"].items())
    lines = [f"{name} chain of {out['machine']!r} (change gears {gears or 'none'})"]
    if "change_gears" in out:
        choice = out["change_gears"]
        how = "chosen from the set" if choice["chosen"] else "given"
        line = f"quadrant {choice['gears']} ({how}): ratio {choice['ratio']:.8f}"
        if choice["required_ratio"] is not None:
            line += f" for {choice['required_ratio']:.8f} (error {choice['error']:+.3e})"
        lines.append(line)
    lines += ["", _table(summary, ("result", "value")), ""]
    columns = {
        "revolutions": "n",
        "odd_teeth": "zk",
        "fi_um": "fi_um",
        "fpr_um": "Fpr_um",
        "error_um": "F_um",
        "pitch_diameter_mm": "D_mm",
        "angle_error_deg": "dphi_deg",
        "max_rotation_deg": "max_deg",
        "min_rotation_deg": "min_deg",
    }
    frame = pd.DataFrame(out["elements"]).set_index("element")[list(columns)]
    frame = frame.rename(columns=columns)
    lines.append(frame.to_string(float_format=lambda v: f"{v:.4f}"))
    lines.append("")
    meshes = pd.DataFrame(out["meshes"])
    lines.append(meshes.to_string(index=False, float_format=lambda v: f"{v:.6f}"))
    return "\n".join(lines)


def _cmd_chain(args: argparse.Namespace) -> int:

    machine = load_machine(args.machine)
    work = WorkGear(
        teeth=args.work_teeth,
        normal_module_mm=args.normal_module_mm,
        spiral_angle_deg=args.spiral_angle_deg,
    )
    gears = {
        chain: _parse_teeth(text, f"--{chain}-gears", count=4)
        for chain, text in (("indexing", args.indexing_gears), ("envelope", args.envelope_gears))
        if text is not None
    }
    swing = {} if args.cradle_swing_deg is None else {"envelope": args.cradle_swing_deg}
    result = evaluate_machine(
        machine, work=work, crown_teeth=args.crown_teeth, gears=gears, input_angles_deg=swing
    )
    out: dict[str, Any] = {}
    for name, chain in result.chains.items():
        out[name] = chain.as_dict()
        out[name]["work"] = dataclasses.asdict(work)
        if name in result.quadrants:
            out[name]["change_gears"] = result.quadrants[name].as_dict()
    if args.json:
        print(json.dumps(out, indent=2))
        return 0
    print(
        f"work gear: z = {work.teeth}, m_n = {work.normal_module_mm:g} mm, "
        f"beta = {work.spiral_angle_deg:g} deg"
    )
    for name, chain_out in out.items():
        print()
        print(_chain_text(name, chain_out))
    return 0


def _cmd_change_gears(args: argparse.Namespace) -> int:

    machine = load_machine(args.machine)
    reserved = [] if args.reserve is None else _parse_teeth(args.reserve, "--reserve")
    choices = select_change_gears(
        args.ratio, machine.change_gears, top_k=args.top_k, reserved=reserved
    )
    best = choices[0].as_dict()
    gear_set = machine.change_gears
    out = {
        "machine": machine.name,
        **best,
        "candidates": [c.as_dict() for c in choices],
        "set_size": len(gear_set.teeth),
        "rule": f"a + b >= c + {gear_set.clearance_teeth}, c + d >= b + {gear_set.clearance_teeth}",
    }
    if args.json:
        print(json.dumps(out, indent=2))
        return 0
    print(
        f"change gears a/b x c/d of {machine.name!r} for ratio {args.ratio:g} "
        f"({len(gear_set.teeth)} gears; {out['rule']})"
    )
    rows = [
        (
            "/".join(str(g) for g in c.gears),
            f"{c.ratio:.8f}",
            f"{c.error:+.3e}",
            f"{c.error_percent:+.5f}",
        )
        for c in choices
    ]
    print(_table(rows, ("a/b/c/d", "ratio", "error", "error %")))
    return 0


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


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of the ``gearopt`` command."""
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
    p = sub.add_parser(
        "realise-te",
        help="fit the machine settings to the design's [te_target] (inverse TCA)",
    )
    p.add_argument("design", help="design TOML file with a [te_target] table")
    p.add_argument("--side", default="drive", choices=("drive", "coast"))
    p.add_argument("--out", help="write the design with the fitted settings here")
    p.add_argument("--json", action="store_true", help="print the report as JSON")
    p.set_defaults(func=_cmd_realise_te)
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
    p = sub.add_parser(
        "chain", help="errors of a machine's indexing and envelope chains (seed 000)"
    )
    p.add_argument("machine", help="machine name (e.g. zftkk250x5) or machine TOML file")
    p.add_argument("--work-teeth", type=int, required=True, help="teeth of the gear being cut")
    p.add_argument("--normal-module-mm", type=float, required=True, help="mean normal module")
    p.add_argument("--spiral-angle-deg", type=float, required=True, help="mean spiral angle")
    p.add_argument("--indexing-gears", help="a,b,c,d of the indexing quadrant (default: best)")
    p.add_argument("--envelope-gears", help="a,b,c,d of the envelope quadrant")
    p.add_argument(
        "--crown-teeth", type=float, help="crown gear teeth, to choose the envelope gears"
    )
    p.add_argument(
        "--cradle-swing-deg", type=float, help="cradle swing per cycle (default: the machine's)"
    )
    p.add_argument("--json", action="store_true", help="print JSON")
    p.set_defaults(func=_cmd_chain)
    p = sub.add_parser("change-gears", help="best change gears a/b x c/d for a ratio")
    p.add_argument("machine", help="machine name (e.g. zftkk250x5) or machine TOML file")
    p.add_argument("--ratio", type=float, required=True, help="required ratio a c / (b d)")
    p.add_argument("--top-k", type=int, default=5, help="how many quadrants to list")
    p.add_argument("--reserve", help="gears already in use, e.g. 48,45,60,60")
    p.add_argument("--json", action="store_true", help="print JSON")
    p.set_defaults(func=_cmd_change_gears)
    add_flank_parser(sub)
    add_blank_parser(sub)
    add_measurement_parsers(sub)
    add_study_parser(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``gearopt`` command; returns the exit status."""
    args = build_parser().parse_args(argv)
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
