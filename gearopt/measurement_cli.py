"""``gearopt grid`` and ``gearopt correct``: the closed loop from the shop floor's measurement.

``gearopt grid DESIGN --member M [--points NFxNP] [--margin-mm MM] [--csv|--json]`` writes the
nominal measuring grid of the member's flanks (:mod:`gearopt.measurement.grid`). With ``--csv``
a header line ``flank,i_face,i_profile,face_mm,profile_mm,x_mm,y_mm,z_mm,nx,ny,nz`` and one row
per point, toe to heel (``i_face``) and root to top (``i_profile``): the cone distance and the
height above the pitch cone of the point, its position and unit normal (out of the tooth) in the
member frame (origin at the pitch apex, z along the axis toward the heel). A point the tool does
not generate keeps its row and its position on the blank, with empty x..nz: it is marked, not
moved. ``--json`` the same rows as objects, with ``"generated"`` and nulls.

``gearopt correct DESIGN --member M --measured FILE`` reads measured normal deviations on that
grid (CSV ``flank,i_face,i_profile,deviation_um``, + = material above nominal; a point left out
was not measured), identifies the settings that cut them and the corrective settings for the
next cut (:mod:`gearopt.measurement.identify`); ``--out`` writes the identified design,
``--corrective-out`` the design with the corrective settings.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import tomli_w

from gearopt.design_files import load_design
from gearopt.flank import FLANKS, MEMBERS
from gearopt.flank_cli import print_warnings
from gearopt.measurement.files import MEASURED_HEADER, read_measured
from gearopt.measurement.grid import parse_points
from gearopt.measurement.identify import correct, identify
from gearopt.measurement.topography import SPLIT_KEYS, nominal_measurement
from gearopt.plausibility import caught

__all__ = ["GRID_HEADER", "add_measurement_parsers"]

GRID_HEADER = "flank,i_face,i_profile,face_mm,profile_mm,x_mm,y_mm,z_mm,nx,ny,nz"


def _nominal(args):
    with caught() as found:
        design = load_design(args.design)
        nominal = nominal_measurement(
            design, args.member, points=parse_points(args.points), margin_mm=args.margin_mm
        )
    return design, nominal, found


def _grid_rows(nominal) -> list[dict]:
    grid = nominal.grid
    rows = []
    for flank in FLANKS:
        pts = nominal.points[flank]
        for i in range(grid.shape[0]):
            for j in range(grid.shape[1]):
                ok = bool(pts.generated[i, j])
                p, n = pts.points_mm[i, j], pts.normals[i, j]
                rows.append(
                    {
                        "flank": flank,
                        "i_face": i,
                        "i_profile": j,
                        "face_mm": float(grid.face_mm[i]),
                        "profile_mm": float(grid.profile_mm[i, j]),
                        **{
                            k: float(v) if ok else None
                            for k, v in zip(("x_mm", "y_mm", "z_mm"), p, strict=True)
                        },
                        **{
                            k: float(v) if ok else None
                            for k, v in zip(("nx", "ny", "nz"), n, strict=True)
                        },
                        "generated": ok,
                    }
                )
    return rows


def _cmd_grid(args: argparse.Namespace) -> int:
    design, nominal, found = _nominal(args)
    rows = _grid_rows(nominal)
    if args.json:
        out = {
            "design": design.name,
            "member": args.member,
            "points": list(nominal.grid.shape),
            "margin_mm": nominal.grid.margin_mm,
            "rows": rows,
            "warnings": found,
        }
        print(json.dumps(out, indent=2))
        return 0
    print_warnings(found)
    if args.csv:
        print(GRID_HEADER)
        for r in rows:
            cells = [r["flank"], str(r["i_face"]), str(r["i_profile"])]
            cells += [f"{r[k]:.6f}" for k in ("face_mm", "profile_mm")]
            cells += ["" if r[k] is None else f"{r[k]:.6f}" for k in ("x_mm", "y_mm", "z_mm")]
            cells += ["" if r[k] is None else f"{r[k]:.9f}" for k in ("nx", "ny", "nz")]
            print(",".join(cells))
        return 0
    grid = nominal.grid
    print(
        f"design {design.name!r}, {args.member}: {grid.shape[0]} x {grid.shape[1]} points "
        f"per flank, {grid.margin_mm:.3f} mm inside toe, heel, root and face lines"
    )
    print(f"face_mm (toe to heel): {', '.join(f'{s:.3f}' for s in grid.face_mm)}")
    for flank in FLANKS:
        gen = nominal.points[flank].generated
        print(f"{flank}: {int(gen.sum())} of {gen.size} points generated")
    print("(--csv or --json for the points and normals)")
    return 0


def _write_design(path: str, design, header: str) -> None:
    data = dict(design.source)
    Path(path).write_text(header + tomli_w.dumps(data), encoding="utf-8")


def _cmd_correct(args: argparse.Namespace) -> int:
    design, nominal, found = _nominal(args)
    measured = read_measured(args.measured, nominal.grid.shape)
    keys = [k.strip() for k in args.settings.split(",") if k.strip()] if args.settings else None
    with caught() as more:
        ident = identify(nominal, measured, settings=keys)
        report = ident.report()
        fix = correct(ident) if any(s.correctable for s in ident.settings) else None
        if fix is not None:
            report["corrective"] = fix.report()
        if args.out:
            _write_design(
                args.out,
                ident.design(),
                f"# {Path(args.design).name} with the settings identified by `gearopt correct` "
                f"from {Path(args.measured).name} ({args.member}).\n\n",
            )
            report["written"] = str(args.out)
        if args.corrective_out and fix is not None:
            _write_design(
                args.corrective_out,
                fix.design(),
                f"# {Path(args.design).name} with the corrective settings of `gearopt correct` "
                f"for {Path(args.measured).name} ({args.member}): dial these.\n\n",
            )
            report["corrective_written"] = str(args.corrective_out)
    report["warnings"] = found + more
    if args.json:
        print(json.dumps(report, indent=2))
        return 0
    print_warnings(report["warnings"])
    _print_report(report)
    return 0


def _print_report(report: dict) -> None:
    print(
        f"identified settings of the {report['member']} (condition number "
        f"{report['condition_number']:.3g}; of all candidates {report['condition_number_all']:.3g})"
    )
    for key, s in report["settings"].items():
        print(
            f"  {key}: {s['nominal']:.6f} -> {s['identified']:.6f} "
            f"(error {s['error']:+.6f} +/- {s['sigma']:.2g})"
        )
    for key, alias in report["not_identifiable"].items():
        mimic = ", ".join(f"{k} x {v:+.3g}" for k, v in alias.items() if k != "_alias")
        print(
            f"  not identifiable, kept nominal: {key} (mimicked {alias['_alias']:.3f} by {mimic})"
        )
    for flank, r in report["flanks"].items():
        rot = report["rotation_deg"][flank]
        print(
            f"{flank}: {r['points']} points, measured {r['measured_rms_um']:.3f} um rms, "
            f"residual {r['residual_rms_um']:.3f} um rms, rotation {rot:+.5f} deg"
        )
        print("  measured " + ", ".join(f"{k} {r['measured'][k]:+.2f}" for k in SPLIT_KEYS))
        print("  residual " + ", ".join(f"{k} {r['residual'][k]:+.2f}" for k in SPLIT_KEYS))
    if "corrective" in report:
        print("corrective settings for the next cut:")
        for key, s in report["corrective"]["settings"].items():
            print(f"  {key}: {s['nominal']:.6f} -> {s['corrective']:.6f} ({s['change']:+.6f})")
        for flank, r in report["corrective"]["flanks"].items():
            print(f"  {flank}: predicted {r['predicted_rms_um']:.3f} um rms")
    for key in ("written", "corrective_written"):
        if key in report:
            print(f"wrote {report[key]}")


def add_measurement_parsers(sub) -> None:
    """Add ``gearopt grid`` and ``gearopt correct`` to the CLI's subparsers."""
    for name, help_text in (
        ("grid", "the nominal measuring grid of a member's flanks (CMM points and normals)"),
        ("correct", "identify the settings that cut a measured gear; corrective settings"),
    ):
        p = sub.add_parser(name, help=help_text)
        p.add_argument("design", help="design TOML file")
        p.add_argument("--member", required=True, choices=MEMBERS)
        p.add_argument("--points", default="9x5", help="NFxNP points toe to heel x root to top")
        p.add_argument(
            "--margin-mm",
            type=float,
            help="distance kept inside toe, heel, root and face lines (default: a tenth of "
            "the member's whole depth)",
        )
        p.add_argument("--json", action="store_true", help="print JSON")
        if name == "grid":
            p.add_argument("--csv", action="store_true", help="print the points as CSV")
            p.set_defaults(func=_cmd_grid)
            continue
        p.add_argument("--measured", required=True, help=f"CSV file: {MEASURED_HEADER}")
        p.add_argument("--settings", help="comma-separated setting keys to identify")
        p.add_argument("--out", help="write the identified design here")
        p.add_argument("--corrective-out", help="write the design with corrective settings here")
        p.set_defaults(func=_cmd_correct)
