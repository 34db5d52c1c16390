"""The gear from its blank (face milling, seed 002).

**Gear (generated, spread blade: one cutter, one setting, both flanks in one pass).** In the
plane of the generating crown gear (uniform depth: the pitch plane), the mean point of the slot
is M = (A_m, 0) on the x_m axis (the pitch generatrix nearest the cradle at centre roll, see
:mod:`gearopt_plugins.face_milling`). The nominal cutter circle of radius r_c passes through M
tangent to the slot's centre line at the mean spiral angle beta:

    C = M + r_c (-sin beta, cos beta),   radial setting s_r = |C|,   cradle angle q = atan2(C)

(right-hand numbers; a left-hand member is the mirror image cut with the same numbers). The
blades lie W/2 either side of that circle at the pitch plane (W the slot's mean normal width
on the pitch line: the circles are concentric, so the normal width is W along the whole face),
their tips the mean dedendum b below: point radii r_c + W/2 - b tan(alpha) (outside blade,
concave flank) and r_c - W/2 + b tan(alpha) (inside blade, convex flank), blade angles alpha =
the blank's pressure angle (the drive side's on the concave flank, the coast side's on the
convex flank when ``[pair] pressure_angle_deg = [drive, coast]``). Machine root angle = root
angle = pitch angle, sliding base = b (the root line in the tip plane, the pitch apex on the
cradle axis), ratio of roll c1 = sin(gamma_2): the cradle is the crown gear. r_c:
``[synthesis] gear_cutter_radius_mm``, default (:mod:`gearopt_plugins.face_milling.cutters`)
the catalogue face mill nearest to A_m among those that suit the gear, an assumption of this
code, not a standard's rule. W: pi m_mn / 2 (equal thickness) or, when the pair gives
``mean_normal_chordal_thickness_mm``, pi m_mn minus the gear's (chordal read as
circular: the two differ by about s^3 / (6 d^2), well below 1 um here).

**Tapered depth** (dedendum angle delta = gamma_2 - gamma_R > 0): machine root angle = root
angle gamma_R, blank offset 0, machine centre to back 0, sliding base b_m cos(delta) - A_m
sin(delta) (the root line in the tip plane, the pitch apex on the cradle axis: the blade tips
sweep the root cone along the whole face), ratio of roll c1 = sin(gamma_2) / cos(delta): the
work's pitch cone rolls without slip on the *cradle's pitch cone*, of half angle 90 deg -
delta about the cradle axis, apex at the pitch apex (:class:`CradleCone`), the instantaneous
axis the work's pitch generatrix nearest the cradle (x_m at centre roll). The two pitch cones
are developable and roll on each other, so the gear flank's pitch line is the image, by that
rolling isometry, of the curve where the blade's cone meets the cradle's pitch cone (each
point of that curve is cut when it passes the instantaneous axis, where the relative velocity
vanishes). In the common development (cone distance rho, polar angle psi cos(delta) on the
cradle cone, theta sin(gamma_2) on the gear's) the spiral angle of a flank is the angle of
that curve to the generatrix, and its pressure angle the angle between the blade cone's normal
and the cradle cone's tangent plane there (:func:`pitch_line_point`, closed form). The tool is
then solved (:func:`gear_tool`, Newton with complex-step Jacobian, from the uniform formulas
with M projected on the tip plane) for radial setting, cradle angle, both point radii and both
blade angles (and the cone distances of the two ends of the slot's normal), so that at the
mean point, in the development:

* the pressure angle of each flank at the cone distance A_m is the blank's;
* the slot's normal -- the segment between the two pitch lines that makes equal angles with
  both (their common normal where they are parallel; with tapered depth the slot widens toward
  the heel, about 2 tan(alpha) sin(delta) cos(beta) per mm along it, so no segment is normal to
  both) -- has length W and its midpoint at (A_m, 0): on the generatrix of centre roll;
* the slot's centre line, the locus of those midpoints, has the spiral angle beta there (its
  direction from the two lines' tangents and curvatures: d(chord . (t1 + t2)) = 0 gives the
  ends' speeds);
* the cutter axis lies r_c from M's projection on the tip plane, (A_m cos(delta), 0) (the
  one-parameter family of cutters that meet the other conditions, as r_c is for uniform depth).

For delta = 0 the cradle cone is the pitch plane, the lines are the concentric circles above
and the solution is the closed form (a test checks it to 1e-9).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from gearopt.blank import Blank
from gearopt.design import PairData
from gearopt.errors import DesignError, SettingsError
from gearopt.solve import newton

__all__ = [
    "STANDARD_CUTTER_RADII_IN",
    "CradleCone",
    "PitchLinePoint",
    "default_cutter_radius_mm",
    "gear_flanks_from_blank",
    "gear_tool",
    "pitch_line_point",
    "slot_width_mm",
]

#: nominal radii (in) of Gleason's standard face-mill cutters (diameters 1.1 ... 18 in)
STANDARD_CUTTER_RADII_IN = (0.55, 0.75, 1.0, 1.75, 2.5, 3.0, 3.75, 4.5, 5.25, 6.0, 7.5, 9.0)


def default_cutter_radius_mm(blank: Blank) -> float:
    """The standard cutter radius nearest to the mean cone distance."""
    radii = np.array(STANDARD_CUTTER_RADII_IN) * 25.4
    return float(radii[np.argmin(np.abs(radii - blank.mean_cone_distance_mm))])


def slot_width_mm(pair: PairData) -> float:
    """The gear's mean normal slot width on the pitch line (module docstring)."""
    blank = pair.blank
    pitch = math.pi * blank.mean_normal_module_mm
    thickness = pair.mean_normal_chordal_thickness_mm
    return pitch / 2.0 if thickness is None else pitch - thickness[1]


@dataclass(frozen=True, kw_only=True)
class CradleCone:
    """The cradle's pitch cone of a member cut with machine root angle = root angle (module
    docstring): apex on the cradle axis at ``z_m = apex_z_mm`` (minus the sliding base), half
    angle 90 deg - ``dedendum_angle_rad`` about the cradle axis, opening toward the cradle.
    A point of cone distance rho and azimuth psi (from x_m) is
    ``(rho cos(delta) cos(psi), rho cos(delta) sin(psi), apex_z - rho sin(delta))``; its
    development is the point of polar coordinates ``(rho, psi cos(delta))``."""

    dedendum_angle_rad: float
    apex_z_mm: float


@dataclass(frozen=True, kw_only=True)
class PitchLinePoint:
    """A blade cone's pitch line (its intersection with the cradle's pitch cone) at one cone
    distance, developed: ``point`` (2,) in the plane, ``tangent`` (2,) unit, toward the heel,
    ``sin_pressure`` the sine of the angle between the blade's normal and the cone's tangent
    plane (the flank's pressure angle there). Arrays may be complex (complex-step
    derivatives)."""

    point: np.ndarray
    tangent: np.ndarray
    sin_pressure: Any


def pitch_line_point(
    cone: CradleCone,
    *,
    radial_setting_mm,
    cradle_angle_rad,
    point_radius_mm,
    blade_angle_rad,
    side: float,
    cone_distance_mm,
    branch: float = 1.0,
) -> PitchLinePoint:
    """The point of the blade cone (``side`` +1 outside blade, -1 inside; the edge's radius
    ``r_p - side z tan(alpha)`` at height ``z <= 0`` below the tip plane) on the cradle's pitch
    cone at a cone distance, its azimuth ``psi = q - branch acos(...)`` (``branch`` +1: the
    intersection on the cradle-axis side of the cutter centre, the one near ``psi = 0`` for
    q > 0). Complex-safe in every length and angle (no comparisons on them)."""
    d = cone.dedendum_angle_rad
    cd, sd = math.cos(d), math.sin(d)
    rho = cone_distance_mm
    sr, q = radial_setting_mm, cradle_angle_rad
    z = cone.apex_z_mm - rho * sd
    ta = np.tan(blade_angle_rad)
    big_r = point_radius_mm - side * z * ta
    k = (rho**2 * cd**2 + sr**2 - big_r**2) / (2.0 * rho * cd * sr)
    psi = q - branch * np.arccos(k)
    cp, sp = np.cos(psi), np.sin(psi)
    # the blade's normal n (not oriented) at the point, the cone's normal nc, its generatrix g
    ct = (rho * cd * cp - sr * np.cos(q)) / big_r
    st = (rho * cd * sp - sr * np.sin(q)) / big_r
    ca, sa = np.cos(blade_angle_rad), np.sin(blade_angle_rad)
    n = np.array([ca * ct, ca * st, side * sa])
    nc = np.array([sd * cp, sd * sp, cd + 0.0 * cp])
    g = np.array([cd * cp, cd * sp, -sd + 0.0 * cp])
    e_psi = np.array([-sp, cp, 0.0 * cp])
    t = np.cross(nc, n)
    t_g, t_psi = t @ g, t @ e_psi
    orient = 1.0 if np.real(t_g) > 0.0 else -1.0
    t_g, t_psi = orient * t_g, orient * t_psi
    norm = np.sqrt(t_g**2 + t_psi**2)
    phi = psi * cd
    cf, sf = np.cos(phi), np.sin(phi)
    return PitchLinePoint(
        point=rho * np.array([cf, sf]),
        tangent=np.array([t_g * cf - t_psi * sf, t_g * sf + t_psi * cf]) / norm,
        sin_pressure=side * (n @ nc),
    )


#: unknowns of the gear's tool: radial setting, cradle angle, point radii (outside, inside
#: blade), blade angles (outside, inside), the cone distances of the slot's normal's ends
_GEAR_STEP = np.array([5.0, 0.05, 2.0, 2.0, 0.02, 0.02, 2.0, 2.0])
#: cone-distance step (mm) of the central differences of a pitch line's tangent
_FD_STEP_MM = 0.01


def gear_tool(
    *,
    cone: CradleCone,
    mean_cone_distance_mm: float,
    spiral_angle_rad: float,
    pressure_angle_rad: float | tuple[float, float],
    slot_width_mm: float,
    cutter_radius_mm: float,
) -> dict:
    """The gear's spread-blade tool from the blank (module docstring): ``radial_setting_mm``,
    ``cradle_angle_rad``, ``point_radius_mm`` and ``blade_angle_rad`` ``(outside, inside)``,
    and the developed ends of the slot's normal at the mean point (``ends``). Solved by Newton
    (complex-step Jacobian) from the uniform-depth formulas, exact for delta = 0.
    ``pressure_angle_rad`` is one angle or ``(outside blade, inside blade)``: the gear's
    concave flank (drive side) and convex flank (coast side)."""
    am, beta, width, rc = (
        mean_cone_distance_mm,
        spiral_angle_rad,
        slot_width_mm,
        cutter_radius_mm,
    )
    alphas = (
        tuple(pressure_angle_rad)
        if isinstance(pressure_angle_rad, tuple | list)
        else (pressure_angle_rad,) * 2
    )
    d = cone.dedendum_angle_rad
    mean_xy = np.array([am * math.cos(d), 0.0])  # the mean pitch point, projected on z_m = 0
    depth = -(cone.apex_z_mm - am * math.sin(d))  # its depth below the tip plane
    centre = mean_xy + rc * np.array([-math.sin(beta), math.cos(beta)])
    reach = [depth * math.tan(a) for a in alphas]
    toward = np.array([math.sin(beta), -math.cos(beta)])  # from the cutter centre outward at M
    ends0 = [np.array([am, 0.0]) + side * 0.5 * width * toward for side in (1.0, -1.0)]
    x0 = np.array(
        [
            math.hypot(*centre),
            math.atan2(centre[1], centre[0]),
            rc + 0.5 * width - reach[0],
            rc - 0.5 * width + reach[1],
            alphas[0],
            alphas[1],
            math.hypot(*ends0[0]),
            math.hypot(*ends0[1]),
        ]
    )
    sides = (1.0, -1.0)
    branch = 1.0 if x0[1] > 0.0 else -1.0

    def line(x, k, rho):
        return pitch_line_point(
            cone,
            radial_setting_mm=x[0],
            cradle_angle_rad=x[1],
            point_radius_mm=x[2 + k],
            blade_angle_rad=x[4 + k],
            side=sides[k],
            cone_distance_mm=rho,
            branch=branch,
        )

    def jet(x, k, rho):
        """Point, unit tangent and curvature vector dT/dsigma of a developed pitch line."""
        lo, mid, hi = (line(x, k, rho + e) for e in (-_FD_STEP_MM, 0.0, _FD_STEP_MM))
        dpoint = hi.point - lo.point
        return mid.point, mid.tangent, (hi.tangent - lo.tangent) / np.sqrt(dpoint @ dpoint)

    def residual(xs, idx):
        rows = []
        for x in xs:
            (d1, t1, k1), (d2, t2, k2) = jet(x, 0, x[6]), jet(x, 1, x[7])
            mid = 0.5 * (d1 + d2)
            chord = d1 - d2
            length = np.sqrt(chord @ chord)
            bis = t1 + t2
            # the centre line (the midpoints' locus) where the normal moves on: d(chord . bis)
            # = 0 gives dsigma1 : dsigma2 = (t2 . bis - chord . k2) : (t1 . bis + chord . k1)
            centre = t1 * (t2 @ bis - chord @ k2) + t2 * (t1 @ bis + chord @ k1)
            centre = centre / np.sqrt(centre @ centre)
            at_am = [line(x, k, am) for k in (0, 1)]  # pressure angles at the mean cone distance
            cx, cy = x[0] * np.cos(x[1]) - mean_xy[0], x[0] * np.sin(x[1])
            rows.append(
                [
                    (mid[0] - am) / am,
                    mid[1] / am,
                    (length - width) / am,
                    chord @ bis / am,  # the normal makes equal angles with both lines
                    centre[1] * math.cos(beta) - centre[0] * math.sin(beta),
                    at_am[0].sin_pressure - math.sin(alphas[0]),
                    at_am[1].sin_pressure - math.sin(alphas[1]),
                    (np.sqrt(cx * cx + cy * cy) - rc) / am,
                ]
            )
        return np.array(rows)

    sol = newton(residual, x0[None], tol=1e-15, max_iter=40, max_step=_GEAR_STEP)
    if not sol.all_converged or np.any(np.isnan(sol.x)):
        raise SettingsError(
            "synthesis.gear_cutter_radius_mm",
            rc,
            "no spread-blade tool meets the blank's spiral angle, pressure angle and slot width "
            "at the mean point with this cutter radius (Newton did not converge)",
        )
    x = sol.x[0]
    out, inn = line(x, 0, x[6]), line(x, 1, x[7])
    return {
        "radial_setting_mm": float(x[0]),
        "cradle_angle_rad": float(x[1]),
        "point_radius_mm": (float(x[2]), float(x[3])),
        "blade_angle_rad": (float(x[4]), float(x[5])),
        "ends": (np.real(out.point), np.real(inn.point)),
    }


def gear_flanks_from_blank(pair: PairData, cutter_radius_mm: float | None = None) -> dict:
    """The gear's ``{flank: {key: value}}`` settings (module docstring)."""
    blank = pair.blank
    rc = default_cutter_radius_mm(blank) if cutter_radius_mm is None else cutter_radius_mm
    am = blank.mean_cone_distance_mm
    width = slot_width_mm(pair)
    b = blank.mean_dedendum_mm[1]
    # the gear's concave flank (outside blade) is the drive side, its convex the coast side
    alphas = tuple(math.radians(a) for a in blank.pressure_angles_deg)
    gamma = math.radians(blank.pitch_angle_deg[1])
    delta = math.radians(blank.dedendum_angle_deg[1])
    sliding = b * math.cos(delta) - am * math.sin(delta)
    reach = b * math.cos(delta) * math.tan(alphas[1])
    if rc - width / 2.0 - reach <= 0.0:
        raise DesignError(
            "synthesis.gear_cutter_radius_mm",
            rc,
            "too small for the slot: the inside blade's point radius would not be positive",
        )
    tool = gear_tool(
        cone=CradleCone(dedendum_angle_rad=delta, apex_z_mm=-sliding),
        mean_cone_distance_mm=am,
        spiral_angle_rad=math.radians(blank.mean_spiral_angle_deg),
        pressure_angle_rad=alphas,
        slot_width_mm=width,
        cutter_radius_mm=rc,
    )
    common = dict(
        radial_setting_mm=tool["radial_setting_mm"],
        cradle_angle_deg=math.degrees(tool["cradle_angle_rad"]),
        machine_root_angle_deg=blank.root_angle_deg[1],
        machine_center_to_back_mm=0.0,
        sliding_base_mm=sliding,
        blank_offset_mm=0.0,
        ratio_of_roll=math.sin(gamma) / math.cos(delta),
    )
    return {
        flank: {
            **common,
            "blade_pressure_angle_deg": math.degrees(tool["blade_angle_rad"][k]),
            "cutter_point_radius_mm": tool["point_radius_mm"][k],
        }
        for k, flank in enumerate(("concave", "convex"))
    }


# --- local synthesis of a pinion flank -----------------------------------------------------------
