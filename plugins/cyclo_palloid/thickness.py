"""The additional slope angle of a cyclo-palloid member from its tooth thickness (seed 001
eqs 39-48): the settings under dnu (eqs 33-38) whose flanks, generated as the model generates
them, have the pair's mean normal chordal thickness at its chordal addendum.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from gearopt.design import MEMBERS, Design
from gearopt.errors import SettingsError
from gearopt.solve import newton
from gearopt.thickness import NormalSection
from gearopt_plugins.cyclo_palloid.settings import blade_systems, flank_turn_rad
from gearopt_plugins.face_hobbing.family import pitch_line_start
from gearopt_plugins.face_hobbing.generation import BLADE_OF_FLANK, hobbing_family

__all__ = ["ThicknessSolution", "solve_additional_slope_angle"]


@dataclass(frozen=True, kw_only=True)
class ThicknessSolution:
    """The additional slope angle that gives the requested chordal thickness (eqs 39-48)."""

    additional_slope_angle_deg: float
    settings: Any
    thickness_mm: float
    residual_mm: float
    top_land_mm: float  # normal chordal thickness at the tip (x_n = a_m)


def solve_additional_slope_angle(
    design: Design, member: str, settings_for: Callable[[float], Any]
) -> ThicknessSolution:
    """Solve seed 001 eqs 39-48 for the member's additional slope angle.

    Eight unknowns: blade parameter, cutter phase and cradle angle of the chordal point on each
    flank (M_i on the convex, M_o on the concave flank), the additional slope angle dnu and the
    tooth's angular position phi. Eight equations: the two meshing equations (41-42) and the
    positions of the two points in S_n (43-48). ``settings_for(dnu_deg)`` gives the member's
    basic settings for a trial dnu (eqs 33-38).
    """
    pair = design.pair
    index = MEMBERS.index(member)
    blank = design.blank
    target = pair.mean_normal_chordal_thickness_mm[index]
    depth = blank.mean_addendum_mm[index] - pair.mean_normal_chordal_addendum_mm[index]
    section = NormalSection(
        cone_distance_mm=blank.mean_cone_distance_mm,
        pitch_angle_rad=math.radians(blank.pitch_angle_deg[index]),
        spiral_angle_rad=math.radians(pair.mean_spiral_angle_deg),
        spiral_sign=1,  # solved on the right-hand member; the left hand is its mirror
    )
    where = f"machine.{member}.additional_slope_angle_deg"

    def state(dnu_mrad):
        settings = settings_for(math.degrees(dnu_mrad * 1e-3))
        systems = blade_systems(design, member, settings)
        return settings, systems

    def points(x):
        settings, systems = state(x[6])
        out = []
        for k, flank in enumerate(("convex", "concave")):
            fam = hobbing_family(blank, member, [systems[BLADE_OF_FLANK[flank]]])
            q = np.asarray(x[3 * k : 3 * k + 3])
            g = fam.geometry(q, 0)
            turn = flank_turn_rad(design, member, flank, systems)
            c, s = math.cos(turn), math.sin(turn)
            p = g["point"]
            p = np.array([c * p[0] - s * p[1], s * p[0] + c * p[1], p[2]])
            _, _, f = fam.axial_radial_meshing(q, 0)
            out.append((section.coordinates(p, x[7]), float(f)))
        return out

    def residual(x, depth_mm, dnu_mrad=None):
        # x = (q_i, q_o, phi, dnu) when dnu is free, else (q_i, q_o, phi, thickness)
        free_dnu = dnu_mrad is None
        dnu = x[7] if free_dnu else dnu_mrad
        (p1, f1), (p2, f2) = points(np.array([*x[:6], dnu, x[6]]))
        thickness = target if free_dnu else x[7]
        return [
            f1 * 1e3,
            p1[0] - depth_mm,
            p1[2],
            f2 * 1e3,
            p2[0] - depth_mm,
            p2[2],
            p1[1] + p2[1],
            p2[1] - p1[1] - thickness,
        ]

    def solve(x0, depth_mm, dnu_mrad=None):
        steps = np.array([1e-5, 1e-7, 1e-7, 1e-5, 1e-7, 1e-7, 1e-7, 1e-5])

        def batch(x, idx):
            return np.array([residual(row, depth_mm, dnu_mrad) for row in x])

        def jacobian(x, idx):
            # central differences: the settings (eqs 33-38) are plain-float code
            out = np.empty((len(x), 8, 8))
            for k in range(8):
                dx = np.zeros(8)
                dx[k] = steps[k]
                out[:, :, k] = (batch(x + dx, idx) - batch(x - dx, idx)) / (2.0 * steps[k])
            return out

        return newton(
            batch,
            x0[None, :],
            jac=jacobian,
            tol=1e-11,
            max_iter=30,
            max_step=[1.0, 0.05, 0.05, 1.0, 0.05, 0.05, 0.05, 5.0],
        )

    # start: the pitch-line points at M and the middle of the tooth at dnu = 0
    _, systems = state(0.0)
    x0 = []
    for flank in ("convex", "concave"):
        b = systems[BLADE_OF_FLANK[flank]]
        x0.extend(np.ravel(np.stack(pitch_line_start(b, np.array([blank.mean_cone_distance_mm])))))
    teeth = pair.pinion_teeth if member == "pinion" else pair.gear_teeth
    x0 = np.array([*x0, 0.5 * math.pi / teeth, 0.0])
    x0[0] = x0[3] = depth / math.cos(math.radians(pair.pressure_angle_deg))
    sol = solve(x0, depth)
    worst = float(np.max(np.abs(sol.residual)))
    if not sol.all_converged:
        raise SettingsError(
            where,
            "auto",
            f"no additional slope angle gives the chordal thickness {target} mm "
            f"(eqs 39-48 did not converge, residual {worst:.2e} after {sol.iterations} steps)",
        )
    x = sol.x[0]
    dnu_mrad = x[7]
    # the same tooth at the tip: its top land must keep a positive width
    addendum = blank.mean_addendum_mm[index]
    start = np.array([*x[:7], target])
    start[0] = start[3] = addendum / math.cos(math.radians(pair.pressure_angle_deg))
    top = solve(start, addendum, dnu_mrad)
    top_land = float(top.x[0][7]) if top.all_converged else -1.0
    if top_land <= 0.0:
        raise SettingsError(
            where,
            "auto",
            f"the chordal thickness {target} mm needs dnu = "
            f"{math.degrees(dnu_mrad * 1e-3):.4f} deg, which makes the tooth pointed (no top "
            "land at the tip)",
        )
    settings, _ = state(dnu_mrad)
    (p1, _), (p2, _) = points(np.array([*x[:6], dnu_mrad, x[6]]))
    return ThicknessSolution(
        additional_slope_angle_deg=math.degrees(dnu_mrad * 1e-3),
        settings=settings,
        thickness_mm=float(p2[1] - p1[1]),
        residual_mm=worst,
        top_land_mm=top_land,
    )
