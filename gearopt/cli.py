"""The ``gearopt`` command.

``gearopt plugins`` lists every machine model, evaluator and objective with its distribution;
``gearopt settings DESIGN.toml`` prints the blank and the basic machine-tool settings. Errors in
the input are printed as one line naming the parameter, its value and the rule (exit status 2).
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Sequence
from typing import Any

from gearopt.design import load_design
from gearopt.errors import GearoptError
from gearopt.plugins import get_machine_model, list_plugins

__all__ = ["main"]


def _format_value(value: Any) -> str:
    if isinstance(value, float):
        return f"{value:.6f}"
    if isinstance(value, list | tuple):
        return ", ".join(_format_value(v) for v in value)
    return str(value)


def _table(rows: list[tuple[str, ...]], header: tuple[str, ...]) -> str:
    widths = [max(len(r[i]) for r in [header, *rows]) for i in range(len(header))]
    lines = ["  ".join(h.ljust(w) for h, w in zip(header, widths, strict=True))]
    lines.append("  ".join("-" * w for w in widths))
    for row in rows:
        cells = [row[0].ljust(widths[0])] + [
            c.rjust(w) for c, w in zip(row[1:], widths[1:], strict=True)
        ]
        lines.append("  ".join(cells))
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


def _cmd_settings(args: argparse.Namespace) -> int:
    design = load_design(args.design)
    settings = get_machine_model(design.model).basic_settings(design)
    out = settings.as_dict()
    out = {"design": design.name, **out, "blank": design.blank.as_dict()}
    if args.json:
        print(json.dumps(out, indent=2))
        return 0
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


def _cmd_bench(args: argparse.Namespace) -> int:
    from gearopt.bench import run_benchmarks

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


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of the ``gearopt`` command."""
    parser = argparse.ArgumentParser(
        prog="gearopt",
        description="Spiral bevel gear design: machine settings, TCA, Optuna studies.",
    )
    sub = parser.add_subparsers(dest="command", required=True)
    p = sub.add_parser("plugins", help="list machine models, evaluators and objectives")
    p.add_argument("--json", action="store_true", help="print JSON")
    p.set_defaults(func=_cmd_plugins)
    p = sub.add_parser("settings", help="basic machine-tool settings of a design")
    p.add_argument("design", help="design TOML file")
    p.add_argument("--json", action="store_true", help="print JSON")
    p.set_defaults(func=_cmd_settings)
    p = sub.add_parser("bench", help="time the kernels (medians over fresh one-thread processes)")
    p.add_argument("names", nargs="*", help="benchmarks to run (default: all)")
    p.add_argument("--repeats", type=int, default=5, help="fresh processes per benchmark")
    p.add_argument("--json", action="store_true", help="print JSON")
    p.set_defaults(func=_cmd_bench)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``gearopt`` command; returns the exit status."""
    args = build_parser().parse_args(argv)
    try:
        return args.func(args)
    except GearoptError as exc:
        print(f"gearopt: error: {type(exc).__name__}: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
