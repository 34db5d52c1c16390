"""``gearopt flank DESIGN --member M --flank F --at AXIAL_MM,RADIUS_MM``: one flank point.

The point of a member's generated flank at an axial position (from the pitch-cone apex along the
member axis, toward the heel) and a radius, solved on the envelope itself (the FlankMap's
``surface``), whether or not it lies inside the blank (``inside_blank`` says which): its
``point_mm``, unit ``normal`` (out of the tooth material), ``generated`` (whether the tool cuts
it: above the blade's tip and not past the envelope's fold; the envelope beyond is reported with
a warning) and ``polar_angle_deg`` in the member
frame of :mod:`gearopt.flank` (origin at the pitch apex, z along the axis toward the heel). The
flank is tooth 0's of the model (a tooth of the pinion, the flank pair around a space of the
gear as the model documents it); the polar angle's zero is the model's, tied to its machine
(cyclo-palloid and epicycloid: tooth 0's convex flank passes through the pitch point M at polar
angle 0 for a right-hand member at the machine's zero; face milling: the pitch generatrix
nearest the cradle at centre roll; see each model's docstring). Works for every machine model
whose FlankMaps carry their generated surface (all built-in ones do).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from typing import Any

from gearopt.design_files import load_design
from gearopt.errors import DesignError, NotAvailableError
from gearopt.flank import MEMBERS, FlankGrid, check_member_and_flank
from gearopt.plugins import get_machine_model

__all__ = ["add_flank_parser", "flank_point", "print_warnings"]


def print_warnings(found: list[str]) -> None:
    """A command's warnings (``--json``'s ``warnings`` list), one line each on stderr."""
    for text in found:
        print(f"gearopt: warning: {text}", file=sys.stderr)


def flank_point(
    design, *, member: str, flank: str, axial_mm: float, radius_mm: float, grid=None
) -> dict[str, Any]:
    """The flank point of ``member``'s ``flank`` at (``axial_mm``, ``radius_mm``), as the CLI
    prints it."""
    check_member_and_flank(member, flank)
    for name, value in (("axial_mm", axial_mm), ("radius_mm", radius_mm)):
        if not math.isfinite(value):
            raise DesignError(f"--at {name}", value, "must be a finite number")
    if radius_mm <= 0.0:
        raise DesignError("--at radius_mm", radius_mm, "must be positive")
    model = get_machine_model(design.model)
    fm = model.generate_flank(design, member=member, flank=flank, grid=grid or FlankGrid())
    if fm.surface is None:
        raise NotAvailableError(
            "--at", (axial_mm, radius_mm), f"model {design.model!r} keeps no generated surface"
        )
    index = MEMBERS.index(member)
    blank = design.blank
    face, profile = (float(v) for v in fm.to_grid(axial_mm, radius_mm))
    geo = fm.surface.geometry_at(face, profile)
    point, normal = geo["point"], geo["normal"]
    generated = bool(fm.surface.generated_at(face, profile))
    # (tapered depth: ``profile`` is the grid coordinate t, which maps the root and face cones
    # to -b_m and a_m at every cone distance; the height is reported)
    inside = (
        blank.inner_cone_distance_mm <= face <= blank.outer_cone_distance_mm
        and -blank.mean_dedendum_mm[index] <= profile <= blank.mean_addendum_mm[index]
    )
    return {
        "design": design.name,
        "model": design.model,
        "member": member,
        "flank": flank,
        "axial_mm": axial_mm,
        "radius_mm": radius_mm,
        "cone_distance_mm": face,
        "height_mm": float(fm.height_at(face, profile)),
        "point_mm": [float(v) for v in point],
        "normal": [float(v) for v in normal],
        "polar_angle_deg": math.degrees(math.atan2(point[1], point[0])),
        "inside_blank": bool(inside),
        "generated": generated,
        "warnings": []
        if generated
        else [
            "not generated: the point lies on the envelope beyond the blade's tip or past the "
            "envelope's fold, flank the tool never cuts"
        ],
    }


def _cmd_flank(args: argparse.Namespace) -> int:
    try:
        axial, radius = (float(part) for part in args.at.split(","))
    except ValueError:
        raise DesignError("--at", args.at, "must be two numbers AXIAL_MM,RADIUS_MM") from None

    out = flank_point(
        load_design(args.design),
        member=args.member,
        flank=args.flank,
        axial_mm=axial,
        radius_mm=radius,
        grid=parse_grid(args.grid),
    )
    if args.json:
        print(json.dumps(out, indent=2))
        return 0
    print_warnings(out["warnings"])
    x, y, z = out["point_mm"]
    print(
        f"{out['member']} {out['flank']} flank of {out['design']!r} at axial {axial:g} mm, "
        f"radius {radius:g} mm ({'inside' if out['inside_blank'] else 'outside'} the blank, "
        f"{'generated' if out['generated'] else 'not generated'}):\n"
        f"  point  ({x:.6f}, {y:.6f}, {z:.6f}) mm\n"
        f"  normal ({', '.join(f'{v:.6f}' for v in out['normal'])})\n"
        f"  polar angle {out['polar_angle_deg']:.6f} deg"
    )
    return 0


def add_flank_parser(sub) -> None:
    """Add ``gearopt flank`` to the CLI's subparsers."""
    p = sub.add_parser("flank", help="one flank point at an axial position and radius")
    p.add_argument("design", help="design TOML file")
    p.add_argument("--member", choices=MEMBERS, required=True)
    p.add_argument("--flank", choices=("convex", "concave"), required=True)
    p.add_argument(
        "--at", required=True, metavar="AXIAL_MM,RADIUS_MM", help="axial position and radius"
    )
    p.add_argument("--grid", default="25,13", help="FlankMap grid the solve starts from")
    p.add_argument("--json", action="store_true", help="print JSON")
    p.set_defaults(func=_cmd_flank)


def parse_grid(text: str, option: str = "--grid") -> FlankGrid:
    """A FlankGrid from the command line's ``n_face,n_profile``."""

    try:
        n_face, n_profile = (int(part) for part in text.split(","))
    except ValueError:
        raise DesignError(option, text, "must be two integers n_face,n_profile") from None
    return FlankGrid(n_face=n_face, n_profile=n_profile)
