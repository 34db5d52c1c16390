"""``gearopt blank DESIGN [--json]``: the blank of a design from basic data (ISO 23509).

Reads the design's ``[pair]`` and ``[blank]`` tables only (a design without ``[machine]`` is
valid here) and prints the standard's output list (:class:`gearopt.iso23509.StandardBlank`):
``--json`` one flat object, numbers or ``[pinion, gear]``, and ``warnings``, each naming its
rule. A blank that cannot be cut or meshed is an error (exit status 2).
"""

from __future__ import annotations

import argparse
import json

from gearopt.design_files import load_standard_blank

__all__ = ["add_blank_parser"]


def _cell(value) -> str:
    if isinstance(value, float):
        return f"{value:.4f}"
    return str(value)


def _cmd_blank(args: argparse.Namespace) -> int:
    out = load_standard_blank(args.design).as_flat_dict()
    if args.json:
        print(json.dumps(out, indent=2))
        return 0
    warnings = out.pop("warnings")
    width = max(len(k) for k in out)
    print(f"{'ISO 23509 blank'.ljust(width)}  pinion      gear")
    for key, value in out.items():
        if isinstance(value, list):
            print(f"{key.ljust(width)}  {_cell(value[0]):>10}  {_cell(value[1]):>10}")
        else:
            print(f"{key.ljust(width)}  {_cell(value):>10}")
    for warning in warnings:
        print(f"warning: {warning}")
    return 0


def add_blank_parser(sub) -> None:
    """Add ``gearopt blank`` to the CLI's subparsers."""
    p = sub.add_parser("blank", help="the blank from basic data ([pair] and [blank], ISO 23509)")
    p.add_argument("design", help="design TOML file (its [pair] and [blank] tables are read)")
    p.add_argument("--json", action="store_true", help="print one flat JSON object")
    p.set_defaults(func=_cmd_blank)
