"""Face milling from the blank: the gear's settings, and the pinion by local synthesis.

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
the blank's pressure angle. Machine root angle = root angle = pitch angle, sliding base = b
(the root line in the tip plane, the pitch apex on the cradle axis), ratio of roll c1 =
sin(gamma_2): the cradle is the crown gear. r_c: ``[synthesis] gear_cutter_radius_mm``, default
the standard cutter radius (Gleason's face-mill diameters 1.1 to 18 in) nearest to A_m, an
assumption of this code, not a standard's rule. W: pi m_mn / 2 (equal thickness) or, when the
pair gives ``mean_normal_chordal_thickness_mm``, pi m_mn minus the gear's (chordal read as
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

**Pinion by local synthesis (Litvin; Litvin and Zhang, NASA CR-4342), per flank.** Chosen:
cutter point radius, blade angle (and profile radius), machine root angle, machine centre to
back (``[machine.pinion]`` / ``[machine.pinion.<flank>]``, defaults below). Solved: radial
setting, cradle angle, blank offset, sliding base, ratio of roll c1 and the second-order roll
term c2, from six conditions at the mean contact point M:

1. M (given in the pinion's pattern coordinates, docs/architecture.md, Pattern coordinates) is
   generated at centre roll (phi_p = 0, so the modified roll is expanded about M): the meshing
   equation of the pinion's generation holds at the centre-roll tool point that lies at M's
   axial position and radius;
2. and 3. the pinion's normal there equals the gear's at M, in M's cylindrical frame (the
   pinion's angular position is free: that is the index of the cut);
4. the path of contact on the gear flank at M has the direction ``path_angle_deg``
   (:func:`gearopt.mesh.path_angle`: from the gear's root line, toward
   the heel, positive toward the tooth top);
5. the contact ellipse at M has the major axis ``ellipse_major_axis_mm`` at the separation
   ``compound_um`` (along the normal), measured as the contact engine measures it (the
   pattern's projection on the pinion's axial plane);
6. the transmission error is locally the parabola -0.5 m'21 u^2 (u the pinion rotation from M,
   m'21 = d m21 / d phi1, m21 = d phi2 / d phi1) that reaches ``te_level_arcsec`` at the
   transfer points half a pinion pitch from M: |m'21| = 2 |TE level| / (pi / N1)^2 (rad of gear).

M on the gear is where M's circle about the pinion axis (the pinion's polar angle is free)
meets the gear flank at a point where the meshing equation of the pair (nominal ratio) holds.
Conditions 4-6 come from a local tooth contact analysis of the two flanks' second-order Taylor
patches at M (:func:`gearopt_plugins.face_milling.local.local_mesh`), all on the exact
envelopes. The six equations are solved by Levenberg-Marquardt with finite-difference
Jacobians, with the targets reached by continuation from the complementary settings (the
gear's generating surface with the pinion's cutter radius), where the contact is already a
point contact (the path direction, a direction mod 180 deg, taken the shorter way round).
A tapered pinion is tilted by its own dedendum angle delta_1 (machine root angle = its root
angle; start: sliding base b_m cos(delta_1) - A_m sin(delta_1), ratio of roll sin(gamma_1) /
cos(delta_1)), and its default blade angle is the one that gives its flank the blank's
pressure angle at its pitch point on its cradle's pitch cone (the gear's blade angle when
delta_1 = 0).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import asdict, dataclass, replace
from typing import Any

import numpy as np
from scipy.optimize import brentq, least_squares, root

from gearopt.blank import Blank
from gearopt.contact import Placement
from gearopt.design import PairData
from gearopt.errors import DesignError, SettingsError
from gearopt.flank import axial_plane, cone_coordinates
from gearopt.mesh import ToothFrame
from gearopt.solve import newton
from gearopt.validate import check_keys, read_number, read_table
from gearopt_plugins.face_milling.family import flank_family
from gearopt_plugins.face_milling.local import (
    TaylorJet,
    envelope_jet,
    hand_sign,
    local_mesh,
    mirrored,
    solve_nodes,
)

__all__ = [
    "STANDARD_CUTTER_RADII_IN",
    "SideTargets",
    "SynthesisReport",
    "gear_flanks_from_blank",
    "read_synthesis",
    "synthesize_pinion_flank",
]

ARCSEC = 180.0 * 3600.0 / math.pi
#: nominal radii (in) of Gleason's standard face-mill cutters (diameters 1.1 ... 18 in)
STANDARD_CUTTER_RADII_IN = (0.55, 0.75, 1.0, 1.75, 2.5, 3.0, 3.75, 4.5, 5.25, 6.0, 7.5, 9.0)
#: pinion cutter radius at the pitch plane, default: the mating gear blade's radius there,
#: made this much smaller (convex flank) or larger (concave flank): the lengthwise mismatch
DEFAULT_RADIUS_MISMATCH = 0.03
SIDES = {"drive": ("convex", "concave"), "coast": ("concave", "convex")}  # pinion, gear flank
TARGET_KEYS = (
    "mean_point_face_mm",
    "mean_point_profile_mm",
    "path_angle_deg",
    "ellipse_major_axis_mm",
    "compound_um",
    "te_level_arcsec",
)
SYNTHESIS_KEYS = (*TARGET_KEYS, "gear_cutter_radius_mm", "backlash_mm", *SIDES)
#: keys of [machine.pinion] / [machine.pinion.<flank>] chosen before the synthesis
CHOSEN_KEYS = (
    "cutter_point_radius_mm",
    "blade_pressure_angle_deg",
    "blade_profile_radius_mm",
    "machine_root_angle_deg",
    "machine_center_to_back_mm",
)
SOLVED_KEYS = (
    "radial_setting_mm",
    "cradle_angle_deg",
    "blank_offset_mm",
    "sliding_base_mm",
    "ratio_of_roll",
    "roll_c2",
)
#: closing tolerances of the synthesis (met or SettingsError)
TOLERANCE = {"first_order": 1e-7, "path_deg": 1e-2, "relative": 1e-3}


@dataclass(frozen=True, kw_only=True)
class SideTargets:
    """What local synthesis asks of one side (``[synthesis]``, ``[synthesis.<side>]``)."""

    side: str
    mean_point_face_mm: float
    mean_point_profile_mm: float
    path_angle_deg: float
    ellipse_major_axis_mm: float
    compound_um: float
    te_level_arcsec: float


@dataclass(frozen=True, kw_only=True)
class SynthesisReport:
    """How the synthesis of one pinion flank closed: the targets, what the local analysis of
    the solved settings gives, the solver's evaluations."""

    targets: SideTargets
    path_angle_deg: float
    ellipse_major_axis_mm: float
    te_level_arcsec: float
    first_order_residual: float
    evaluations: int
    gear_turn_rad: float

    def as_dict(self) -> dict:
        t = self.targets
        return {
            "side": t.side,
            "mean_point_mm": [t.mean_point_face_mm, t.mean_point_profile_mm],
            "asked": {
                "path_angle_deg": t.path_angle_deg,
                "ellipse_major_axis_mm": t.ellipse_major_axis_mm,
                "te_level_arcsec": t.te_level_arcsec,
                "compound_um": t.compound_um,
            },
            "local": {
                "path_angle_deg": self.path_angle_deg,
                "ellipse_major_axis_mm": self.ellipse_major_axis_mm,
                "te_level_arcsec": self.te_level_arcsec,
                "first_order_residual": self.first_order_residual,
            },
            "evaluations": self.evaluations,
        }


# --- input ---------------------------------------------------------------------------------------


def read_synthesis(table: Mapping[str, Any], blank: Blank) -> tuple[dict, dict]:
    """``({side: SideTargets}, options)`` from the ``[synthesis]`` table; options:
    ``gear_cutter_radius_mm`` (None: the default) and ``backlash_mm`` (default 0)."""
    check_keys(table, SYNTHESIS_KEYS, "synthesis")

    centre = ToothFrame.from_blank(blank).centre_mm
    common = {k: v for k, v in table.items() if k in TARGET_KEYS}
    tables = {side: read_table(table, side, "synthesis") for side in SIDES}
    missing = [
        f"{key} ({side})"
        for side in SIDES
        for key in ("path_angle_deg", "ellipse_major_axis_mm", "te_level_arcsec")
        if key not in {**common, **tables[side]}
    ]
    if missing:  # all of them at once, not one error at a time
        raise DesignError(
            "synthesis",
            rule=f"local synthesis needs {', '.join(missing)}: give each in [synthesis] for "
            "both sides or in [synthesis.drive] / [synthesis.coast]",
        )
    out = {}
    for side in SIDES:
        own = tables[side]
        check_keys(own, TARGET_KEYS, f"synthesis.{side}")
        merged = {**common, **own}
        where = f"synthesis.{side}" if own else "synthesis"
        face = read_number(merged, "mean_point_face_mm", where, centre[0])
        if not 0.0 < face < blank.face_width_mm:
            raise DesignError(
                f"{where}.mean_point_face_mm",
                face,
                f"must lie inside the face width (0, {blank.face_width_mm:g}) mm",
            )
        depth = blank.mean_dedendum_mm[0] + blank.mean_addendum_mm[0]
        profile = read_number(merged, "mean_point_profile_mm", where, centre[1])
        if not 0.0 < profile < depth:
            raise DesignError(
                f"{where}.mean_point_profile_mm",
                profile,
                f"must lie on the pinion flank, between its root (0) and top ({depth:.3f}) mm",
            )
        ellipse = read_number(merged, "ellipse_major_axis_mm", where, gt=0.0)
        if ellipse >= blank.face_width_mm:
            raise DesignError(
                f"{where}.ellipse_major_axis_mm",
                ellipse,
                f"the contact ellipse must be shorter than the face width "
                f"{blank.face_width_mm:g} mm (its projection on the flank)",
            )
        level = read_number(merged, "te_level_arcsec", where)
        if level == 0.0 or abs(level) > 300.0:
            raise DesignError(
                f"{where}.te_level_arcsec",
                level,
                "must be non-zero (a parabolic transmission error; its sign is ignored: the "
                "TE is negative away from M) and at most 300 arcsec in magnitude",
            )
        out[side] = SideTargets(
            side=side,
            mean_point_face_mm=face,
            mean_point_profile_mm=profile,
            path_angle_deg=read_number(merged, "path_angle_deg", where, gt=-90.0, le=90.0),
            ellipse_major_axis_mm=ellipse,
            compound_um=read_number(merged, "compound_um", where, 6.5, gt=0.0, le=100.0),
            te_level_arcsec=-abs(level),
        )
    radius = table.get("gear_cutter_radius_mm")
    if radius is not None:
        radius = read_number(table, "gear_cutter_radius_mm", "synthesis", gt=0.0)
    backlash = read_number(table, "backlash_mm", "synthesis", 0.0, ge=0.0, le=1.0)
    return out, {"gear_cutter_radius_mm": radius, "backlash_mm": backlash}


# --- the gear from its blank ---------------------------------------------------------------------


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
    pressure_angle_rad: float,
    slot_width_mm: float,
    cutter_radius_mm: float,
) -> dict:
    """The gear's spread-blade tool from the blank (module docstring): ``radial_setting_mm``,
    ``cradle_angle_rad``, ``point_radius_mm`` and ``blade_angle_rad`` ``(outside, inside)``,
    and the developed ends of the slot's normal at the mean point (``ends``). Solved by Newton
    (complex-step Jacobian) from the uniform-depth formulas, exact for delta = 0."""
    am, beta, alpha, width, rc = (
        mean_cone_distance_mm,
        spiral_angle_rad,
        pressure_angle_rad,
        slot_width_mm,
        cutter_radius_mm,
    )
    d = cone.dedendum_angle_rad
    mean_xy = np.array([am * math.cos(d), 0.0])  # the mean pitch point, projected on z_m = 0
    depth = -(cone.apex_z_mm - am * math.sin(d))  # its depth below the tip plane
    centre = mean_xy + rc * np.array([-math.sin(beta), math.cos(beta)])
    reach = depth * math.tan(alpha)
    toward = np.array([math.sin(beta), -math.cos(beta)])  # from the cutter centre outward at M
    ends0 = [np.array([am, 0.0]) + side * 0.5 * width * toward for side in (1.0, -1.0)]
    x0 = np.array(
        [
            math.hypot(*centre),
            math.atan2(centre[1], centre[0]),
            rc + 0.5 * width - reach,
            rc - 0.5 * width + reach,
            alpha,
            alpha,
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
                    at_am[0].sin_pressure - math.sin(alpha),
                    at_am[1].sin_pressure - math.sin(alpha),
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
    alpha = math.radians(blank.pressure_angle_deg)
    gamma = math.radians(blank.pitch_angle_deg[1])
    delta = math.radians(blank.dedendum_angle_deg[1])
    sliding = b * math.cos(delta) - am * math.sin(delta)
    reach = b * math.cos(delta) * math.tan(alpha)
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
        pressure_angle_rad=alpha,
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


@dataclass(frozen=True, kw_only=True)
class _MeanPoint:
    """M on both members at the mean position (pinion angle 0)."""

    s1: float
    h1: float
    axial_mm: float  # M's axial position and radius on the pinion
    radius_mm: float
    omega: float  # M's polar angle on the pinion
    normal1: np.ndarray  # the pinion's out-of-material normal at M, pinion frame
    gear_jet: Any
    gear_turn: float


def _mean_point(pair, gear_spec, gear_flank, targets: SideTargets, placement) -> _MeanPoint:
    """Where the gear flank meets M's circle about the pinion axis at a point of contact."""

    blank = pair.blank
    frame = ToothFrame.from_blank(blank)
    s1 = frame.toe_mm + targets.mean_point_face_mm
    h1 = frame.root_mm + targets.mean_point_profile_mm
    taper = blank.depth_taper(0)
    if taper is not None:  # the pattern's profile coordinate is t (DepthTaper): h at s1
        h1 = float(taper.height_mm(s1, h1))
    g1, g2 = (math.radians(a) for a in blank.pitch_angle_deg)
    big_l1, big_r1 = axial_plane(s1, h1, g1)
    b, c = placement.pinion_to_gear
    ratio = pair.pinion_teeth / pair.gear_teeth
    hand2 = hand_sign(blank.hand[1])
    family = flank_family(blank, 1, {gear_flank: gear_spec})
    start = family.pitch_row(np.array([blank.mean_cone_distance_mm]))[0, 0]
    axis1 = b[:, 2]

    def state(omega):
        omega = np.atleast_1d(omega)
        p = np.stack(
            [big_r1 * np.cos(omega), big_r1 * np.sin(omega), np.full_like(omega, big_l1)], -1
        )
        q = p @ b.T + c
        big_l2, big_r2 = q[:, 2], np.hypot(q[:, 0], q[:, 1])
        s2, h2 = cone_coordinates(big_l2, big_r2, g2)
        sol = solve_nodes(family, s2, h2, start, g2)
        geo = family.geometry(sol.x, np.zeros(len(omega), int))
        point, normal = mirrored(geo["point"], hand2), mirrored(geo["normal"], hand2)
        turn = np.arctan2(q[:, 1], q[:, 0]) - np.arctan2(point[:, 1], point[:, 0])
        ct, st = np.cos(turn), np.sin(turn)
        n = np.stack(
            [
                ct * normal[:, 0] - st * normal[:, 1],
                st * normal[:, 0] + ct * normal[:, 1],
                normal[:, 2],
            ],
            -1,
        )
        v = np.cross(axis1, q - c) + ratio * np.cross([0.0, 0.0, 1.0], q)
        meshing = np.einsum("ij,ij->i", n, v) / np.maximum(np.linalg.norm(v, axis=1), 1e-300)
        return meshing, sol, s2, h2, turn, n, p

    grid = np.linspace(-0.6, 0.6, 48)  # not through 0: v12 = 0 on the instantaneous axis
    values, sol, *_ = state(grid)
    values = np.where(sol.converged, values, np.nan)
    change = np.flatnonzero(
        np.isfinite(values[:-1])
        & np.isfinite(values[1:])
        & (np.sign(values[:-1]) != np.sign(values[1:]))
    )
    if change.size == 0:
        raise SettingsError(
            f"synthesis.{targets.side}: the mean contact point M",
            _m_text(targets),
            f"no point of the gear's {gear_flank} flank meets M's circle about the pinion axis "
            "in contact: M is off the gear flank; move it with mean_point_face_mm and "
            "mean_point_profile_mm (pattern coordinates from the toe and the root; default the "
            "flank centre)",
        )
    k = change[np.argmin(np.abs(grid[change]))]
    omega = brentq(lambda w: float(state(w)[0][0]), grid[k], grid[k + 1], xtol=1e-15)
    _, sol, s2, h2, turn, n, p = state(omega)
    jet = envelope_jet(
        family,
        s_mm=float(s2[0]),
        h_mm=float(h2[0]),
        pitch_angle_rad=g2,
        hand_sign=hand2,
        guess=sol.x[0],
    )
    return _MeanPoint(
        s1=s1,
        h1=h1,
        axial_mm=float(big_l1),
        radius_mm=float(big_r1),
        omega=float(omega),
        normal1=-(b.T @ n[0]),
        gear_jet=jet,
        gear_turn=float(turn[0]),
    )


def _pitch_depth_mm(blank: Blank, index: int) -> float:
    """Depth of the member's mean pitch point below the tip plane when its root line lies in
    it (machine root angle = root angle): b_m cos(delta)."""
    return blank.mean_dedendum_mm[index] * math.cos(math.radians(blank.dedendum_angle_deg[index]))


def _blade_radius_at_pitch_mm(flank_settings: Mapping, flank: str, depth_mm: float) -> float:
    """A blade's radius at the depth of the pitch point (outside blade: concave flank)."""
    side = 1.0 if flank == "concave" else -1.0
    alpha = math.radians(flank_settings["blade_pressure_angle_deg"])
    return flank_settings["cutter_point_radius_mm"] + side * depth_mm * math.tan(alpha)


def pinion_start(pair: PairData, gear_flanks: dict, flank: str, chosen: Mapping) -> dict:
    """The complementary settings of a pinion flank with the chosen cutter: the gear's
    generating surface seen from the pinion (the same cutter centre relative to the mean
    pitch point projected on the tip plane), the centre moved along the line to the gear
    flank's mean point so the chosen radius passes through it; the pinion tilted by its
    chosen machine root angle: the root line in the tip plane at A_m (sliding base) and the
    ratio of roll of rolling without slip on the cradle's pitch cone,
    c1 = sin(gamma_1) / cos(gamma_1 - gamma_m)."""
    blank = pair.blank
    am = blank.mean_cone_distance_mm
    gear_flank = "concave" if flank == "convex" else "convex"
    g = gear_flanks[gear_flank]
    r2 = _blade_radius_at_pitch_mm(g, gear_flank, _pitch_depth_mm(blank, 1))
    q2 = math.radians(g["cradle_angle_deg"])
    centre = g["radial_setting_mm"] * np.array([math.cos(q2), math.sin(q2)])
    delta2 = math.radians(blank.dedendum_angle_deg[1])
    mean2 = np.array([am * math.cos(delta2), 0.0])
    toward = (mean2 - centre) / np.linalg.norm(mean2 - centre)
    gamma1 = math.radians(blank.pitch_angle_deg[0])
    tilt = math.radians(chosen["machine_root_angle_deg"]) - gamma1  # -delta_1 at the root angle
    b1 = blank.mean_dedendum_mm[0]
    depth1 = b1 * math.cos(tilt)
    mean1 = np.array([am * math.cos(tilt), 0.0])
    r1 = _blade_radius_at_pitch_mm(chosen, flank, depth1)
    point = centre + r2 * toward
    c1 = point - r1 * toward + (mean1 - mean2)
    return dict(
        radial_setting_mm=float(np.hypot(*c1)),
        cradle_angle_deg=math.degrees(math.atan2(c1[1], c1[0])),
        blank_offset_mm=0.0,
        sliding_base_mm=depth1
        + am * math.sin(tilt)
        + chosen["machine_center_to_back_mm"]
        * math.sin(math.radians(chosen["machine_root_angle_deg"])),
        ratio_of_roll=math.sin(gamma1) / math.cos(tilt),
        roll_c2=0.0,
    )


def default_chosen(pair: PairData, gear_flanks: dict, flank: str) -> dict:
    """Defaults of the chosen pinion inputs: the mating gear blade's angle (a tilted pinion:
    the blade angle that gives the blank's pressure angle at its pitch point), the gear blade's
    radius at its pitch point made :data:`DEFAULT_RADIUS_MISMATCH` smaller (convex) or larger
    (concave) at the pinion's pitch point, machine root angle = root angle (the pinion tilted
    by its dedendum angle), machine centre to back 0."""
    blank = pair.blank
    gear_flank = "concave" if flank == "convex" else "convex"
    g = gear_flanks[gear_flank]
    alpha = g["blade_pressure_angle_deg"]
    r2 = _blade_radius_at_pitch_mm(g, gear_flank, _pitch_depth_mm(blank, 1))
    side1 = 1.0 if flank == "concave" else -1.0
    r1 = r2 * (1.0 + side1 * DEFAULT_RADIUS_MISMATCH)
    depth1 = _pitch_depth_mm(blank, 0)
    chosen = dict(
        cutter_point_radius_mm=r1 - side1 * depth1 * math.tan(math.radians(alpha)),
        blade_pressure_angle_deg=alpha,
        blade_profile_radius_mm=math.inf,
        machine_root_angle_deg=blank.root_angle_deg[0],
        machine_center_to_back_mm=0.0,
    )
    delta1 = math.radians(blank.dedendum_angle_deg[0])
    if delta1 == 0.0:
        return chosen
    # tilted pinion: the blade angle that gives its flank the blank's pressure angle at its
    # pitch point of A_m on its cradle's pitch cone (the complementary start's cutter centre)
    start = pinion_start(pair, gear_flanks, flank, chosen)
    am = blank.mean_cone_distance_mm
    cone = CradleCone(dedendum_angle_rad=delta1, apex_z_mm=-start["sliding_base_mm"])
    target = math.sin(math.radians(blank.pressure_angle_deg))

    def miss(a):
        return (
            pitch_line_point(
                cone,
                radial_setting_mm=start["radial_setting_mm"],
                cradle_angle_rad=math.radians(start["cradle_angle_deg"]),
                point_radius_mm=r1 - side1 * depth1 * math.tan(a),
                blade_angle_rad=a,
                side=side1,
                cone_distance_mm=am,
            ).sin_pressure
            - target
        )

    a = math.radians(alpha)
    a = brentq(miss, a - 0.1, a + 0.1, xtol=1e-14)
    chosen["blade_pressure_angle_deg"] = math.degrees(a)
    chosen["cutter_point_radius_mm"] = r1 - side1 * depth1 * math.tan(a)
    return chosen


_SCALES = np.array([1.0, 0.01, 1.0, 1.0, 0.01, 0.01])  # mm, rad, mm, mm, c1 and c2 (x c1)


def synthesize_pinion_flank(
    pair: PairData,
    *,
    flank: str,
    gear_specs: Mapping[str, Any],
    chosen: Mapping[str, Any],
    targets: SideTargets,
    flank_type,
    place_tip: bool = True,
    backlash_mm: float = 0.0,
    reference_gear_turn_rad: float | None = None,
) -> tuple[Any, SynthesisReport]:
    """The pinion flank's settings (a ``flank_type`` instance) by local synthesis;
    ``place_tip``: then put a straight blade's tip on the root line (:func:`_tip_on_root`;
    the chosen cutter radius is then the blade's radius at M's height, not at its tip).
    ``work_phase_deg`` is set so that the flank meets the gear at M in the assembly, the coast flank
    turned further by ``backlash_mm`` (circumferential at the gear's outer pitch radius,
    docs/architecture.md, Backlash and ease-off) to thin the tooth; ``reference_gear_turn_rad``: the
    gear's angle when the other side touched at its M at pinion angle 0 (the report's
    ``gear_turn_rad``), so that both flanks sit in one assembly."""
    blank = pair.blank
    key = repr((pair, flank, sorted(chosen.items()), targets, sorted(gear_specs.items())))
    if key not in _SOLVED:
        _SOLVED[key] = _solve_flank(pair, flank, gear_specs, chosen, targets, flank_type)
        while len(_SOLVED) > 128:
            _SOLVED.pop(next(iter(_SOLVED)))
    spec, report, mean, analysis = _SOLVED[key]
    ratio = pair.pinion_teeth / pair.gear_teeth
    hand1 = hand_sign(blank.hand[0])
    # the work's index that puts the flank's M at its place in the mesh (its polar angle omega
    # at pinion angle 0), less the backlash on the coast flank (a thinner tooth)
    thinning = 0.0
    if targets.side == "coast":
        gear_turn = backlash_mm / blank.outer_pitch_radius_mm[1]
        thinning = -analysis["sense"] * gear_turn / ratio
    # the pinion angle at which this side touches at M when the other side touched its M at
    # pinion angle 0 (the gear turns by -ratio phi1 as the pinion turns by phi1)
    phi = (
        0.0
        if reference_gear_turn_rad is None
        else (reference_gear_turn_rad - mean.gear_turn) / ratio
    )
    turn = mean.omega - phi - analysis["theta"] + thinning
    spec = replace(spec, work_phase_deg=math.degrees(hand1 * turn))
    if place_tip and math.isinf(spec.blade_profile_radius_mm):
        spec = _tip_on_root(spec, flank, blank)
    return spec, report


_SOLVED: dict = {}


def _solve_flank(pair, flank, gear_specs, chosen, targets, flank_type):
    """The six conditions at M solved (module docstring): ``(spec, report, mean point,
    {"theta": M's generated polar angle, "sense": the flank's sense of rotation})``."""
    blank = pair.blank
    gear_flank = "concave" if flank == "convex" else "convex"
    placement = Placement(shaft_angle_deg=pair.shaft_angle_deg)
    mean = _mean_point(pair, gear_specs[gear_flank], gear_flank, targets, placement)
    g1 = math.radians(blank.pitch_angle_deg[0])
    big_l1, big_r1 = mean.axial_mm, mean.radius_mm
    e_t = np.array([-math.sin(mean.omega), math.cos(mean.omega), 0.0])
    n_target = np.array([mean.normal1 @ e_t, mean.normal1[2]])
    hand1 = hand_sign(blank.hand[0])
    ratio = pair.pinion_teeth / pair.gear_teeth
    lag_target = 2.0 * abs(targets.te_level_arcsec) / ARCSEC / (math.pi / pair.pinion_teeth) ** 2
    start = pinion_start(pair, {f: asdict(s) for f, s in gear_specs.items()}, flank, chosen)
    x_start = np.array([start[k] for k in SOLVED_KEYS])
    x_start[1] = math.radians(x_start[1])
    scales = _SCALES * np.array([1, 1, 1, 1, x_start[4], x_start[4]])
    root_angle = math.radians(blank.root_angle_deg[1])
    guess = {"q": None}
    count = {"n": 0}
    analysis = {}

    def spec_of(x):
        values = dict(zip(SOLVED_KEYS, x, strict=True))
        values["cradle_angle_deg"] = math.degrees(values["cradle_angle_deg"])
        return flank_type(**{k: chosen[k] for k in CHOSEN_KEYS}, blade_tip_radius_mm=0.0, **values)

    def analyse(x, second=True):
        count["n"] += 1
        spec = spec_of(x)
        family = flank_family(blank, 0, {flank: spec})
        q0 = guess["q"]
        if q0 is None:
            q0 = family.pitch_row(np.array([mean.s1]))[0, 0]
        scale = family.scale_mm

        def residual(z, idx):
            q = np.concatenate([z, 0.0 * z[:, :1]], axis=1)
            big_l, big_r, _ = family.axial_radial_meshing(q, np.zeros(len(z), int))
            return np.stack([(big_l - big_l1) / scale, (big_r - big_r1) / scale], -1)

        sol = newton(residual, q0[None, :2], tol=1e-15, max_iter=40, max_step=(1.0, 0.05))
        if not sol.all_converged:
            raise SettingsError(
                f"synthesis.{targets.side}",
                rule="at centre roll the pinion cutter does not reach M's position",
            )
        q = np.array([sol.x[0, 0], sol.x[0, 1], 0.0])
        f = family.axial_radial_meshing(q[None], np.zeros(1, int))[2][0]
        geo = family.geometry(q[None], np.zeros(1, int))
        point, normal = mirrored(geo["point"][0], hand1), mirrored(geo["normal"][0], hand1)
        theta = math.atan2(point[1], point[0])
        et = np.array([-math.sin(theta), math.cos(theta), 0.0])
        first = np.array([f, normal @ et - n_target[0], normal[2] - n_target[1]])
        guess["q"] = q
        if not second:
            return first, None
        jet = envelope_jet(
            family, s_mm=mean.s1, h_mm=mean.h1, pitch_angle_rad=g1, hand_sign=hand1, guess=q
        )
        guess["q"] = q
        sense = 1 if (point[0] * normal[1] - point[1] * normal[0]) > 0.0 else -1
        analysis.update(theta=theta, sense=sense)
        orientation = 1.0 if TaylorJet(jet).frame()[-1] @ normal > 0.0 else -1.0
        local = local_mesh(
            TaylorJet(jet, turn_rad=mean.omega - jet.theta),
            TaylorJet(mean.gear_jet),
            placement=placement,
            ratio=ratio,
            sense=sense,
            gear_turn_rad=mean.gear_turn,
            root_angle_rad=root_angle,
            compound_um=targets.compound_um,
            orientation=orientation,
        )
        return first, local

    def residuals(z, goal):
        try:
            first, local = analyse(x_start + scales * z)
        except SettingsError:
            return np.full(6, 1e3)  # no regular contact there: the solver steps back
        return np.concatenate(
            [
                first * 100.0,
                [
                    (local.lag_curvature - goal[0]) / lag_target,
                    math.radians(_line_difference_deg(local.path_angle_deg, goal[1])) * 10.0,
                    local.ellipse_form * goal[2] ** 2 / 4.0 - 1.0,
                ],
            ]
        )

    # first order alone (tangency at M, generated at centre roll), then the second order by
    # continuation from what the first-order solution gives
    z = least_squares(
        lambda z: analyse(x_start + scales * z, second=False)[0],
        np.zeros(6),
        method="trf",
        diff_step=1e-5,
        xtol=1e-15,
        ftol=1e-15,
        gtol=1e-15,
    ).x
    _, local0 = analyse(x_start + scales * z)
    begin = np.array(
        [local0.lag_curvature, local0.path_angle_deg, min(local0.ellipse_major_axis_mm, 1e3)]
    )
    end = np.array([lag_target, targets.path_angle_deg, targets.ellipse_major_axis_mm])
    # the path is a line: continue along the shorter way round (through +-90 deg if need be)
    end[1] = begin[1] + _line_difference_deg(end[1], begin[1])
    for t in (0.25, 0.5, 0.75, 1.0):
        goal = begin + t * (end - begin)
        fit = least_squares(
            residuals,
            z,
            args=(goal,),
            method="lm",
            diff_step=1e-5,
            xtol=1e-14,
            ftol=1e-14,
            gtol=1e-14,
            max_nfev=150,
        )
        z = fit.x
    if fit.cost > 1e-20:  # LM stalled: a last Powell hybrid from where it stopped
        polish = root(lambda w: residuals(w, end), z, method="hybr", options={"xtol": 1e-14})
        if np.sum(residuals(polish.x, end) ** 2) < 2.0 * fit.cost:
            z = polish.x
    first, local = analyse(x_start + scales * z)
    report = SynthesisReport(
        targets=targets,
        path_angle_deg=local.path_angle_deg,
        ellipse_major_axis_mm=local.ellipse_major_axis_mm,
        te_level_arcsec=-0.5 * local.lag_curvature * (math.pi / pair.pinion_teeth) ** 2 * ARCSEC,
        first_order_residual=float(np.max(np.abs(first))),
        evaluations=count["n"],
        gear_turn_rad=mean.gear_turn,
    )
    _check(report, lag_target, local, targets)
    return spec_of(x_start + scales * z), report, mean, dict(analysis)


def _tip_on_root(spec, flank: str, blank: Blank):
    """The same cone with its tip moved along the cutter axis onto the root line at the mean
    cone distance (a straight blade: the generated flank is unchanged, only how deep the blade
    reaches): sliding base and point radius change together."""
    g = math.radians(spec.machine_root_angle_deg)
    dg = g - math.radians(blank.pitch_angle_deg[0])
    apex_z = spec.machine_center_to_back_mm * math.sin(g) - spec.sliding_base_mm
    root_z = (
        apex_z
        + blank.mean_cone_distance_mm * math.sin(dg)
        + blank.mean_dedendum_mm[0] * math.cos(dg)
    )
    side = 1.0 if flank == "concave" else -1.0
    return replace(
        spec,
        sliding_base_mm=spec.sliding_base_mm + root_z,
        cutter_point_radius_mm=spec.cutter_point_radius_mm
        - side * root_z * math.tan(math.radians(spec.blade_pressure_angle_deg)),
    )


def _m_text(targets: SideTargets) -> str:
    """M as the user gives it: pattern coordinates with units."""
    return (
        f"face {targets.mean_point_face_mm:.3f} mm, profile {targets.mean_point_profile_mm:.3f} mm"
    )


def _line_difference_deg(a: float, b: float) -> float:
    """a - b for directions of lines (mod 180 deg), in [-90, 90)."""
    return (a - b + 90.0) % 180.0 - 90.0


def _check(report: SynthesisReport, lag_target, local, targets: SideTargets) -> None:
    """A :class:`SettingsError` naming the input the solution misses most (relative to its
    tolerance): a second-order target the pinion cannot realise with the chosen inputs, or M
    itself when only the tangency there fails."""
    where = f"synthesis.{targets.side}"
    misses = {
        "path_angle_deg": (
            abs(_line_difference_deg(report.path_angle_deg, targets.path_angle_deg))
            / TOLERANCE["path_deg"],
            targets.path_angle_deg,
            f"{report.path_angle_deg:.3f} deg",
        ),
        "ellipse_major_axis_mm": (
            abs(report.ellipse_major_axis_mm / targets.ellipse_major_axis_mm - 1.0)
            / TOLERANCE["relative"],
            targets.ellipse_major_axis_mm,
            f"{report.ellipse_major_axis_mm:.3f} mm",
        ),
        "te_level_arcsec": (
            abs(local.lag_curvature / lag_target - 1.0) / TOLERANCE["relative"],
            targets.te_level_arcsec,
            f"{report.te_level_arcsec:.3f} arcsec",
        ),
    }
    key = max(misses, key=lambda k: misses[k][0])
    ratio, value, reached = misses[key]
    if ratio > 1.0:
        raise SettingsError(
            f"{where}.{key}",
            value,
            f"the pinion cannot realise it with the chosen inputs (the closest solution reaches "
            f"{reached}): ask for less, or change the chosen pinion cutter "
            "(cutter_point_radius_mm, blade_pressure_angle_deg in [machine.pinion])",
        )
    if report.first_order_residual > TOLERANCE["first_order"]:
        raise SettingsError(
            f"{where}: the mean contact point M",
            _m_text(targets),
            "the pinion cannot be made tangent to the gear there (the meshing equation and the "
            f"unit normals' match close to {report.first_order_residual:.1e} only, "
            f"{TOLERANCE['first_order']:g} needed) while meeting ellipse_major_axis_mm = "
            f"{targets.ellipse_major_axis_mm:g} mm, path_angle_deg = "
            f"{targets.path_angle_deg:g} deg and te_level_arcsec = {targets.te_level_arcsec:g}: "
            "ask a shorter ellipse or a lower TE level, or move M (mean_point_face_mm, "
            "mean_point_profile_mm; default the flank centre)",
        )
