"""``gearopt rexs export`` and ``gearopt rexs import``: designs to and from REXS files.

``gearopt rexs export DESIGN.toml --out FILE.rexsj [--date ISO] [--json]`` writes the design as a
REXS 2.0.0 model in the JSON form (:func:`gearopt.rexs.files.write_rexs`).
``gearopt rexs import FILE.rexsj --out DESIGN.toml [--model NAME] [--json]`` reads a REXS JSON
file into a design file (:func:`gearopt.rexs.files.read_rexs_model`); the design is parsed before it
is written, so a file gearopt cannot cut is refused with the attribute's name and nothing is
written. ``--model`` names the machine model that reads the settings of a file gearopt did not
write. ``docs/rexs.md`` lists the attributes and their conventions.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import tomli_w

from gearopt.design_files import load_design
from gearopt.rexs.files import read_rexs_file, read_rexs_model, write_rexs

__all__ = ["add_rexs_parser"]


def _cmd_export(args: argparse.Namespace) -> int:
    design = load_design(args.design)
    document = write_rexs(design, args.out, date=args.date)
    model = document["model"]
    report = {
        "design": design.name,
        "model": design.model,
        "rexs_version": model["version"],
        "components": len(model["components"]),
        "relations": len(model["relations"]),
        "written": str(args.out),
    }
    if args.json:
        print(json.dumps(report, indent=2))
    else:
        print(
            f"wrote {args.out}: design {design.name!r} ({design.model}) as REXS "
            f"{report['rexs_version']}, {report['components']} components, "
            f"{report['relations']} relations"
        )
    return 0


def _cmd_import(args: argparse.Namespace) -> int:
    tables, design = read_rexs_model(
        read_rexs_file(args.file),
        model=args.model,
        source=f"REXS file {Path(args.file).name}",
        path=str(args.out),
    )
    header = f"# {Path(args.out).name}: read from the REXS file {Path(args.file).name}\n\n"
    Path(args.out).write_text(header + tomli_w.dumps(tables), encoding="utf-8")
    report = {"design": design.name, "model": design.model, "written": str(args.out)}
    if args.json:
        print(json.dumps(report, indent=2))
    else:
        print(f"wrote {args.out}: design {design.name!r} ({design.model})")
    return 0


def add_rexs_parser(sub) -> None:
    """Add ``gearopt rexs export|import`` to the CLI's subparsers."""
    p = sub.add_parser("rexs", help="export a design to REXS (.rexsj) or import one")
    rexs = p.add_subparsers(dest="rexs_command", required=True)
    e = rexs.add_parser("export", help="write a design as a REXS 2.0.0 JSON file")
    e.add_argument("design", help="design TOML file")
    e.add_argument("--out", required=True, help="REXS JSON file to write (.rexsj)")
    e.add_argument("--date", help="the file's date (ISO 8601; default now)")
    e.add_argument("--json", action="store_true", help="print JSON")
    e.set_defaults(func=_cmd_export)
    i = rexs.add_parser("import", help="read a REXS JSON file into a design TOML file")
    i.add_argument("file", help="REXS JSON file (.rexsj)")
    i.add_argument("--out", required=True, help="design TOML file to write")
    i.add_argument(
        "--model", help="machine model that reads the settings (default: the one the file names)"
    )
    i.add_argument("--json", action="store_true", help="print JSON")
    i.set_defaults(func=_cmd_import)
