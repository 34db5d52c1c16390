"""The pinion by local synthesis (face milling, seed 002).

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
from gearopt.errors import SettingsError
from gearopt.flank import axial_plane, cone_coordinates
from gearopt.mesh import ToothFrame
from gearopt.solve import newton
from gearopt.units import ARCSEC
from gearopt_plugins.face_milling.family import flank_family
from gearopt_plugins.face_milling.local import (
    TaylorJet,
    envelope_jet,
    hand_sign,
    local_mesh,
    mirrored,
    solve_nodes,
)
from gearopt_plugins.face_milling.synthesis.gear import CradleCone, pitch_line_point
from gearopt_plugins.face_milling.synthesis.targets import (
    CHOSEN_KEYS,
    SOLVED_KEYS,
    TOLERANCE,
    SideTargets,
    SynthesisReport,
)

__all__ = ["default_chosen", "pinion_start", "synthesize_pinion_flank"]

#: pinion cutter radius at the pitch plane, default: the mating gear blade's radius there,
#: made this much smaller (convex flank) or larger (concave flank): the lengthwise mismatch
DEFAULT_RADIUS_MISMATCH = 0.03


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
    # the pinion's convex flank is the drive side, its concave the coast side
    target = math.sin(math.radians(blank.pressure_angles_deg[flank == "concave"]))

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
            abs(targets.te_level_arcsec),  # the magnitude the user gave (its sign is ignored)
            f"{abs(report.te_level_arcsec):.3f} arcsec",
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
            f"{targets.path_angle_deg:g} deg and te_level_arcsec = "
            f"{abs(targets.te_level_arcsec):g}: "
            "ask a shorter ellipse or a lower TE level, or move M (mean_point_face_mm, "
            "mean_point_profile_mm; default the flank centre)",
        )
