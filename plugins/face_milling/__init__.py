"""Gleason face milling with modified roll (Litvin's model of face-milled generation), seed 002.

A head cutter whose blades sweep cones (surfaces of revolution about the cutter axis) is carried
by the cradle; the cradle turns by phi_c while the work turns by phi_p, with the modified roll

    phi_c = c1 phi_p + c2 phi_p^2 + c3 phi_p^3 + c4 phi_p^4 + c5 phi_p^5 + c6 phi_p^6

(phi_p in rad from the centre-roll position, c1 = ``ratio_of_roll``). Each flank of each member
has its own settings (a spread-blade gear cut in one pass simply repeats the radial setting,
cradle angle... in both flank tables; a fixed-setting or modified-roll pinion differs per flank).
The tooth flank is the envelope of the blade's cone in the work frame (Litvin, Gear Geometry and
Applied Theory, ch. 21 (face milling); Litvin et al., NASA CR-4342), solved on the FlankMap grid
by the shared solver (:mod:`gearopt.envelope`) with the family of
:mod:`gearopt_plugins.face_milling.family`.

Frames and sign conventions (every setting of a right-hand member; a left-hand member is cut on
the mirror image of the machine, so its flanks are the mirror images of the right-hand member's
cut with the same numbers, :meth:`gearopt.flank.FlankMap.mirrored`)::

                      y_m (blank offset +)
                       ^
                       |         . C  cutter centre: radial setting s_r, cradle angle q
                       |      .      (measured from x_m toward y_m, with the cradle)
                       |   .  q
     cradle axis z_m  (o)-------------------> x_m   the work's pitch generatrix nearest the
     (out of the page, O_m machine centre          cradle at centre roll, apex -> heel
      toward the work)

     side view (x_m, z_m):        z_m ^  work axis a_w at the machine root angle gamma_m
                                       |    /
                                       |   /  work (apex -> heel along +a_w)
                                       |  /
                                       | / gamma_m
     cutter tip plane  z_m = 0  ------O_m-----------------> x_m
     cutter body and cradle:  z_m < 0 (the blades point toward +z_m, the work)

* Machine frame S_m: origin O_m the machine centre on the cradle axis; z_m along the cradle axis,
  from the cradle toward the work; the plane z_m = 0 holds the blades' tips (the cutter's tip
  plane); x_m such that the work axis lies in the x_m-z_m plane, a_w = (cos gamma_m, 0,
  sin gamma_m) pointing from the work's apex toward its heel; y_m = z_m x x_m.
* Cutter: its axis parallel to z_m through C = s_r (cos(q + phi_c), sin(q + phi_c), 0). Blade
  edge (arc length u from the tip): straight at the blade pressure angle alpha, radius
  r_p +/- u sin(alpha) and height -u cos(alpha) (+ outside blade, - inside blade); with
  ``blade_profile_radius_mm`` rho a circular arc tangent to that line at the pitch-line point
  (the blade point the member's mean dedendum above the tip, as in the epicycloid model), its
  centre on the tooth material's side (profile crowning: relief growing both ways from there).
  ``cutter_point_radius_mm`` r_p is the blade's radius at its tip (the point radius). The
  outside blade cuts the concave flank, the inside blade the convex flank, on both members.
* Cradle: turns by phi_c about +z_m; the cradle angle q is measured in the sense of the cradle's
  rotation from x_m (the direction of the pitch generatrix toward the heel). With q > 0 the
  cutter centre lies on the +y_m side and the member is right-hand (gearopt's convention: the
  same sense of spiral as the cyclo-palloid and epicycloid right-hand members, checked by a
  test).
* Work: its pitch apex at O_m + dX_D a_w + dE_m y_m - dX_B z_m. ``machine_center_to_back_mm``
  dX_D: along the work axis, positive withdrawing the work toward its back (shallower cut);
  ``blank_offset_mm`` dE_m: along +y_m; ``sliding_base_mm`` dX_B: along the cradle axis,
  positive moving the work toward the cradle (deeper cut). Uniform depth with the machine root
  angle = pitch angle puts the root line in the tip plane with dX_B = the member's dedendum,
  dX_D = dE_m = 0: the work axis then meets the cradle axis at the pitch apex and the plane
  z_m = -dX_B is the generating crown gear's pitch plane.
* Work rotation: phi_p about +a_w. With c1 > 0 cradle and work turn as in rolling (the
  velocities of the crown gear and of the work agree along the pitch generatrix); c1 = sin
  gamma for a crown gear generating a member of pitch angle gamma. ``ratio_of_roll`` must be
  positive.
* Work phase: ``work_phase_deg`` turns the work about +a_w before the cut (right-hand
  numbers; the work's index for this flank: a pinion whose flanks are cut with separate
  settings sets its tooth thickness with it, the stock division of the second cut).
* Member frame (FlankMap): origin at the pitch apex, z along a_w; at centre roll x lies in the
  x_m-z_m plane, x = (sin gamma_m, 0, -cos gamma_m), so the pitch generatrix nearest the cradle
  has polar angle 0 (the angular zero is tied to the machine at centre roll).

Converting Gleason's printed modified-roll coefficients (a summary prints the ratio of roll
R_a = 1 / c1 as work over cradle, or the cradle over work, and the higher terms as 2C, 6D, 24E,
120F, i.e. the derivatives of the cradle angle in the work angle, or of the work angle in the
cradle angle, depending on the machine): with the work angle as the free variable,
c2 = 2C / 2, c3 = 6D / 6, c4 = 24E / 24, c5 = 120F / 120 (per rad^k). When the summary expands
the work angle in the cradle angle instead, invert the series first. This slice reproduces no
printed summary yet; the conversion is stated here for the next one.

Tooth numbering: the convex flank (inside blade) is not turned; the concave flank (outside blade)
is cut in the same tooth space, and tooth 0's concave flank is it turned by one pitch toward the
tooth material of the convex flank (the sense read from the generated normal), so that tooth 0
lies between them. ``tool_pass`` k: the work indexed by k pitches, the flank of tooth k of a
right-hand member (-k of a left-hand one).

Design keys (``[machine.<member>.<flank>]``; keys common to both flanks may sit in
``[machine.<member>]``)::

    [machine]                          # studies/face_milling_conjugate.toml, its gear
    model = "face-milling"

    [machine.gear]
    blade_pressure_angle_deg = 20.0
    radial_setting_mm = 74.674435602
    cradle_angle_deg = 44.152654237
    machine_root_angle_deg = 71.565051177
    machine_center_to_back_mm = 0.0
    sliding_base_mm = 4.856974144
    blank_offset_mm = 0.0
    ratio_of_roll = 0.948683298051     # c1
    # roll_c2 ... roll_c6 = 0.0        # modified roll (default 0)
    # work_phase_deg = 0.0             # the work's index for this flank's cut (default 0)
    # blade_profile_radius_mm = "inf"  # or a radius in mm
    # blade_tip_radius_mm = 0.0        # the blade's edge radius rho_t (0: a sharp corner)

    [machine.gear.concave]             # outside blade
    cutter_point_radius_mm = 64.783932841

    [machine.gear.convex]              # inside blade
    cutter_point_radius_mm = 62.216067159

Tapered depth: ``face_angle_deg`` and ``root_angle_deg`` in ``[pair]`` (``[pinion, gear]``;
uniform depth when absent; :mod:`gearopt.blank` for the mean addendum and dedendum from the
outer ones at the heel). The flanks are then generated on the tapered grid, root cone to face
cone in every face column (:class:`gearopt.flank.DepthTaper`). The machine root angle stays a
setting: with it equal to the root angle and the root line in the tip plane (the sliding base
b_m cos(theta_d) - A_m sin(theta_d) with dX_D = dE_m = 0, theta_d = pitch - root angle) the
blade's tip sweeps the root cone along the whole face, and the ratio of roll for rolling
without slip is c1 = sin(gamma) / cos(theta_d) (``studies/face_milling_tapered.toml``).
Root reach: the blade's tip (the plane z_m = 0) must reach the root line (the root cone's
generatrix nearest the cradle at centre roll) at the toe and at the heel, else a
``DesignError`` names ``sliding_base_mm``.

Blade tip (edge) radius ``blade_tip_radius_mm`` rho_t (Gleason's edge radius; default 0, a
sharp corner): the corner between the cutting edge and the tip line is a circular arc of radius
rho_t tangent to the tip plane z_m = 0 (which stays the blade's lowest plane: the settings, the
root reach and the depth keep their meaning) and to the edge (the straight blade, or the profile
arc when there is one); its centre lies rho_t above the tip plane (z_m = -rho_t) on the blade's
side. The edge's arc length u runs from the fillet's point on the tip plane (u = 0; the tip
line, u < 0, generates nothing) along the fillet (to u = rho_t (pi/2 - alpha) on a straight
blade) and on along the edge; the edge above the fillet is the sharp blade's. The fillet
generates the flank's root fillet, tangent to the root cone where the blade's tip sweeps it: the
flank there leaves more material than the sharp blade's (tens of micrometres at 1 mm on the
conjugate gear), and the envelope's fold (the flank tangent to the root cone) lies at the
bottom of the fillet region, so the generated region (the FlankMap's mask) stops the envelope
solver's fold margin above it. rho_t must stay below b_m / (1 - sin alpha) (the fillet ends
below the blade's pitch-line point, the mean dedendum b_m above the tip plane; a
``DesignError`` names ``blade_tip_radius_mm``). With a profile arc the fillet meets the arc
itself, and its lowest point lies on the tip plane exactly (the sharp arc blade's corner, at
arc length ``tangent_mm`` from the pitch-line point, sits about u_p^2 sin(alpha) / (2 R) past
it toward the work: 11 micrometres at R = 400 mm, u_p = 5.2 mm).

Settings from the blank and local synthesis: a design with a ``[synthesis]`` table
(:meth:`FaceMilling.synthesize`, :mod:`gearopt_plugins.face_milling.synthesis`; the synthesis
gives the pinion a sharp blade); a designed TE by inverse TCA:
:meth:`FaceMilling.realise_te_target` (:mod:`gearopt_plugins.face_milling.inverse`). Not yet: a
check against a published settings summary (none readable was found).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import asdict, dataclass, field, replace
from typing import Any

import numpy as np

from gearopt import hookimpl
from gearopt.commands import BaseCommand
from gearopt.design import MEMBERS, Design, PairData
from gearopt.envelope import flank_map, require_flank, solve_envelope
from gearopt.errors import DesignError, NotAvailableError, SettingsError
from gearopt.flank import FLANKS, FlankGrid, FlankMap, check_member_and_flank
from gearopt.machine import BaseMachineModel, CorrectionSetting, MachineSettings, SearchDimension
from gearopt.rexs.attributes import RexsMachine
from gearopt.solve import newton
from gearopt.validate import check_keys, read_number, read_table
from gearopt_plugins.cutters.blades import MIN_PROFILE_RADIUS_DEPTHS, read_profile_radius
from gearopt_plugins.face_milling import correction
from gearopt_plugins.face_milling import rexs as fm_rexs
from gearopt_plugins.face_milling import synthesis as fs
from gearopt_plugins.face_milling.cutters import catalogue_dimensions, default_gear_cutter
from gearopt_plugins.face_milling.family import (
    CutterFlank,
    design_family,
)
from gearopt_plugins.face_milling.inverse import RealiseTECommand, inverse_tca
from gearopt_plugins.face_milling.root_reach import check_root_reach
from gearopt_plugins.face_milling.synthesis import SIDES

__all__ = ["FaceMilling", "FaceMillingFlank", "FaceMillingMachine", "FaceMillingMember"]

ROLL_KEYS = ("roll_c2", "roll_c3", "roll_c4", "roll_c5", "roll_c6")
#: the largest ratio of roll c1 accepted (a crown gear's is at most 1/cos(15 deg) = 1.035)
MAX_RATIO_OF_ROLL = 2.0
#: the work's roll (rad from centre roll) over which the modified roll must keep rolling forward
ROLL_RANGE_RAD = 0.5


def _check_roll_rate(c1: float, roll: dict, where: str) -> None:
    """The roll's rate d phi_c / d phi_p = c1 + 2 c2 phi + ... + 6 c6 phi^5 positive over
    |phi_p| <= :data:`ROLL_RANGE_RAD`: a cradle that stops or turns back there generates no
    flank (``roll_c2 = 1e18`` was accepted)."""
    phi = np.linspace(-ROLL_RANGE_RAD, ROLL_RANGE_RAD, 101)
    rate = c1 + sum((k + 2) * roll[key] * phi ** (k + 1) for k, key in enumerate(ROLL_KEYS))
    if not np.all(np.isfinite(rate)) or rate.min() <= 0.0:
        worst = max(ROLL_KEYS, key=lambda key: abs(roll[key]))
        raise DesignError(
            f"{where}.{worst}",
            roll[worst],
            f"the modified roll must keep the cradle rolling forward over the work's roll "
            f"|phi_p| <= {ROLL_RANGE_RAD:g} rad: its rate c1 + 2 c2 phi + ... + 6 c6 phi^5 "
            f"falls to {float(np.nanmin(rate)):.3g} (c1 = {c1:g}); reduce the roll terms",
        )


FLANK_KEYS = (
    "cutter_point_radius_mm",
    "blade_pressure_angle_deg",
    "blade_profile_radius_mm",
    "blade_tip_radius_mm",
    "radial_setting_mm",
    "cradle_angle_deg",
    "machine_root_angle_deg",
    "machine_center_to_back_mm",
    "sliding_base_mm",
    "blank_offset_mm",
    "ratio_of_roll",
    *ROLL_KEYS,
    "work_phase_deg",
)
MEMBER_KEYS = (*FLANK_KEYS, *FLANKS)
MACHINE_KEYS = MEMBERS
#: the outside blade cuts the concave flank (+1: material radially outside the edge)
BLADE_SIDE = {"concave": 1.0, "convex": -1.0}
BLADE_OF_FLANK = {"concave": "outside", "convex": "inside"}
#: the blade's tip may stay this far above the root line (rounding of printed settings)


@dataclass(frozen=True, kw_only=True)
class FaceMillingFlank:
    """Settings of one flank (the key names of the design file)."""

    cutter_point_radius_mm: float
    blade_pressure_angle_deg: float
    blade_profile_radius_mm: float
    blade_tip_radius_mm: float
    radial_setting_mm: float
    cradle_angle_deg: float
    machine_root_angle_deg: float
    machine_center_to_back_mm: float
    sliding_base_mm: float
    blank_offset_mm: float
    ratio_of_roll: float
    roll_c2: float = 0.0
    roll_c3: float = 0.0
    roll_c4: float = 0.0
    roll_c5: float = 0.0
    roll_c6: float = 0.0
    work_phase_deg: float = 0.0

    @property
    def roll(self) -> tuple[float, ...]:
        """(c1, ..., c6)."""
        return (self.ratio_of_roll, *(getattr(self, k) for k in ROLL_KEYS))

    @property
    def profile_curvature_per_mm(self) -> float:
        r = self.blade_profile_radius_mm
        return 0.0 if math.isinf(r) else 1.0 / r

    def cutter(
        self, flank: str, *, index_rad: float = 0.0, pitch_depth_mm: float = 0.0
    ) -> CutterFlank:
        """The flank's cutter; a profile arc is tangent to the straight blade at its pitch-line
        point, ``pitch_depth_mm`` (the member's mean dedendum) above the tip."""
        alpha = math.radians(self.blade_pressure_angle_deg)
        return CutterFlank(
            tangent_mm=pitch_depth_mm / math.cos(alpha),
            side=BLADE_SIDE[flank],
            point_radius_mm=self.cutter_point_radius_mm,
            pressure_angle_rad=math.radians(self.blade_pressure_angle_deg),
            curvature_per_mm=self.profile_curvature_per_mm,
            radial_setting_mm=self.radial_setting_mm,
            cradle_angle_rad=math.radians(self.cradle_angle_deg),
            machine_root_angle_rad=math.radians(self.machine_root_angle_deg),
            center_to_back_mm=self.machine_center_to_back_mm,
            blank_offset_mm=self.blank_offset_mm,
            sliding_base_mm=self.sliding_base_mm,
            roll=self.roll,
            index_rad=index_rad + math.radians(self.work_phase_deg),
            tip_radius_mm=self.blade_tip_radius_mm,
        )


@dataclass(frozen=True, kw_only=True)
class FaceMillingMember:
    convex: FaceMillingFlank
    concave: FaceMillingFlank

    def flank(self, name: str) -> FaceMillingFlank:
        return getattr(self, name)


@dataclass(frozen=True, kw_only=True)
class FaceMillingMachine:
    """The ``[machine]`` table of a face-milling design."""

    pinion: FaceMillingMember
    gear: FaceMillingMember
    #: how the settings were derived when the design has a ``[synthesis]`` table
    synthesis: tuple = field(default=(), compare=False)
    #: what the settings took by default (a catalogue cutter), for the settings' notes
    notes: tuple[str, ...] = field(default=(), compare=False)

    def member(self, name: str) -> FaceMillingMember:
        return getattr(self, name)


@dataclass(frozen=True, kw_only=True)
class FaceMillingSettings:
    """The settings of one member as given (``basic_settings`` derives none in this slice);
    ``*_blade_profile_curvature_per_mm`` = 1 / profile radius (0: straight blade),
    ``*_blade_tip_radius_mm`` the blade's edge radius (0: a sharp corner)."""

    concave_cutter_point_radius_mm: float
    concave_blade_pressure_angle_deg: float
    concave_blade_profile_curvature_per_mm: float
    concave_blade_tip_radius_mm: float
    concave_radial_setting_mm: float
    concave_cradle_angle_deg: float
    concave_machine_root_angle_deg: float
    concave_machine_center_to_back_mm: float
    concave_sliding_base_mm: float
    concave_blank_offset_mm: float
    concave_ratio_of_roll: float
    concave_roll_c2: float
    concave_roll_c3: float
    concave_roll_c4: float
    concave_roll_c5: float
    concave_roll_c6: float
    concave_work_phase_deg: float
    convex_cutter_point_radius_mm: float
    convex_blade_pressure_angle_deg: float
    convex_blade_profile_curvature_per_mm: float
    convex_blade_tip_radius_mm: float
    convex_radial_setting_mm: float
    convex_cradle_angle_deg: float
    convex_machine_root_angle_deg: float
    convex_machine_center_to_back_mm: float
    convex_sliding_base_mm: float
    convex_blank_offset_mm: float
    convex_ratio_of_roll: float
    convex_roll_c2: float
    convex_roll_c3: float
    convex_roll_c4: float
    convex_roll_c5: float
    convex_roll_c6: float
    convex_work_phase_deg: float


# --- parsing -------------------------------------------------------------------------------------


def _parse_flank(
    merged: Mapping[str, Any], where: str, pair: PairData, member: str, flank: str
) -> FaceMillingFlank:
    index = MEMBERS.index(member)
    blank = pair.blank
    # the deepest tooth: at the heel (tapered depth) or anywhere (uniform)
    depth = blank.outer_addendum_mm[index] + blank.outer_dedendum_mm[index]
    for key in FLANK_KEYS:
        if key not in merged and key not in (
            "blade_profile_radius_mm",
            "blade_tip_radius_mm",
            *ROLL_KEYS,
            "work_phase_deg",
        ):
            raise DesignError(
                f"{where}.{key}", rule="required (in this flank's table or its member's)"
            )
    alpha = read_number(merged, "blade_pressure_angle_deg", where, gt=0.0, lt=45.0)
    tip = read_number(merged, "blade_tip_radius_mm", where, 0.0, ge=0.0)
    # the fillet must end on the blade below its pitch-line point (the mean dedendum above the
    # tip plane, where a profile arc touches the straight blade): rho_t (1 - sin alpha) < b_m
    tip_reach = blank.mean_dedendum_mm[index] / (1.0 - math.sin(math.radians(alpha)))
    if tip >= tip_reach:
        raise DesignError(
            f"{where}.blade_tip_radius_mm",
            tip,
            f"the tip fillet (tangent to the tip plane and the edge) rises rho_t (1 - sin "
            f"alpha) above the tip plane and must end below the blade's pitch-line point (the "
            f"mean dedendum {blank.mean_dedendum_mm[index]:.3f} mm above it): rho_t must be "
            f"< {tip_reach:.3f} mm",
        )
    rp = read_number(merged, "cutter_point_radius_mm", where, gt=0.0)
    reach = depth * math.tan(math.radians(alpha))
    if flank == "convex" and rp <= reach:
        raise DesignError(
            f"{where}.cutter_point_radius_mm",
            rp,
            f"the inside blade's radius r_p - h tan(alpha) must stay positive over the whole "
            f"depth h = {depth:.3f} mm: r_p must exceed {reach:.3f} mm",
        )
    c1 = read_number(merged, "ratio_of_roll", where)
    if c1 <= 0.0:
        raise DesignError(
            f"{where}.ratio_of_roll",
            c1,
            "must be > 0: c1 = cradle rotation / work rotation, both in the senses of the "
            "rolling generation (module docstring); a reversed roll generates no flank",
        )
    if c1 > MAX_RATIO_OF_ROLL:
        raise DesignError(
            f"{where}.ratio_of_roll",
            c1,
            f"must be at most {MAX_RATIO_OF_ROLL:g}: a generating crown gear turns the cradle "
            "sin(gamma) / cos(delta) <= 1.04 times the work (delta <= 15 deg); beyond, the roll "
            "generates no flank of this blank",
        )
    roll = {k: read_number(merged, k, where, 0.0) for k in ROLL_KEYS}
    _check_roll_rate(c1, roll, where)
    values = dict(
        cutter_point_radius_mm=rp,
        blade_pressure_angle_deg=alpha,
        blade_profile_radius_mm=read_profile_radius(
            merged, where, MIN_PROFILE_RADIUS_DEPTHS * max(blank.whole_depth_mm)
        ),
        blade_tip_radius_mm=tip,
        radial_setting_mm=read_number(merged, "radial_setting_mm", where, gt=0.0),
        cradle_angle_deg=read_number(merged, "cradle_angle_deg", where, ge=-360.0, le=360.0),
        machine_root_angle_deg=read_number(
            merged, "machine_root_angle_deg", where, gt=0.0, lt=90.0
        ),
        machine_center_to_back_mm=read_number(merged, "machine_center_to_back_mm", where),
        sliding_base_mm=read_number(merged, "sliding_base_mm", where),
        blank_offset_mm=read_number(merged, "blank_offset_mm", where),
        ratio_of_roll=c1,
        **roll,
        work_phase_deg=read_number(merged, "work_phase_deg", where, 0.0, gt=-360.0, lt=360.0),
    )
    spec = FaceMillingFlank(**values)
    check_root_reach(spec, blank, index, where)
    return spec


def _parse_member(table: Mapping[str, Any], member: str, pair: PairData) -> FaceMillingMember:
    sub = read_table(table, member, "machine")
    check_keys(sub, MEMBER_KEYS, f"machine.{member}")
    common = {k: v for k, v in sub.items() if k in FLANK_KEYS}
    flanks = {}
    for flank in FLANKS:
        where = f"machine.{member}.{flank}"
        own = read_table(sub, flank, f"machine.{member}")
        check_keys(own, FLANK_KEYS, where)
        flanks[flank] = _parse_flank({**common, **own}, where, pair, member, flank)
    return FaceMillingMember(**flanks)


def machine_table(machine: FaceMillingMachine) -> dict[str, Any]:
    """The ``[machine]`` table (without ``model``) that parses back to ``machine``: every flank's
    settings written out (a synthesised design as plain settings)."""
    out: dict[str, Any] = {}
    for member in MEMBERS:
        out[member] = {}
        for flank in FLANKS:
            spec = machine.member(member).flank(flank)
            values = {k: float(getattr(spec, k)) for k in FLANK_KEYS}
            if math.isinf(values["blade_profile_radius_mm"]):
                values["blade_profile_radius_mm"] = "inf"
            out[member][flank] = values
    return out


# --- settings by synthesis -----------------------------------------------------------------------

_SYNTHESIS_NOTE = (
    "derived: the gear's settings from the blank (unless [machine.gear] gives them), the "
    "pinion's by local synthesis at M ([synthesis]; gearopt_plugins.face_milling.synthesis)"
)


def _synthesize(table, synthesis, pair) -> FaceMillingMachine:
    check_keys(table, MACHINE_KEYS, "machine")
    targets, options = fs.read_synthesis(synthesis, pair.blank)
    notes = ()
    if "gear" in table:
        gear = _parse_member(table, "gear", pair)
    else:
        radius = options["gear_cutter_radius_mm"]
        if radius is None:
            radius, note = default_gear_cutter(pair)
            notes = (note,)
        given = fs.gear_flanks_from_blank(pair, radius)
        gear = FaceMillingMember(
            **{
                f: _parse_flank(given[f], f"machine.gear.{f} (from the blank)", pair, "gear", f)
                for f in FLANKS
            }
        )
    sub = read_table(table, "pinion", "machine")
    check_keys(sub, (*fs.CHOSEN_KEYS, *FLANKS), "machine.pinion")
    gear_dicts = {f: asdict(gear.flank(f)) for f in FLANKS}
    flanks, reports = {}, []
    for side, (flank, _) in fs.SIDES.items():
        where = f"machine.pinion.{flank}"
        own = read_table(sub, flank, "machine.pinion")
        check_keys(own, fs.CHOSEN_KEYS, where)
        merged = {**{k: v for k, v in sub.items() if k in fs.CHOSEN_KEYS}, **own}
        chosen = fs.default_chosen(pair, gear_dicts, flank)
        for key in fs.CHOSEN_KEYS:
            if key == "blade_profile_radius_mm":
                chosen[key] = read_profile_radius(
                    merged, where, MIN_PROFILE_RADIUS_DEPTHS * max(pair.blank.whole_depth_mm)
                )
            elif key in merged:
                chosen[key] = read_number(merged, key, where)
        spec, report = fs.synthesize_pinion_flank(
            pair,
            flank=flank,
            gear_specs={f: gear.flank(f) for f in FLANKS},
            chosen=chosen,
            targets=targets[side],
            flank_type=FaceMillingFlank,
            place_tip="cutter_point_radius_mm" not in merged,
            backlash_mm=options["backlash_mm"],
            reference_gear_turn_rad=reports[0].gear_turn_rad if reports else None,
        )
        values = {k: float(v) for k, v in asdict(spec).items()}
        if math.isinf(values["blade_profile_radius_mm"]):
            values["blade_profile_radius_mm"] = "inf"
        flanks[flank] = _parse_flank(values, where + " (synthesised)", pair, "pinion", flank)
        reports.append(report)
    return FaceMillingMachine(
        pinion=FaceMillingMember(**flanks), gear=gear, synthesis=tuple(reports), notes=notes
    )


# --- the model -----------------------------------------------------------------------------------


class FaceMilling(BaseMachineModel):
    """Gleason face milling with modified roll (Litvin's model), generated pinion and gear."""

    name = "face-milling"
    description = (
        "Gleason face milling (head cutter, cradle, modified roll; Litvin's model), generated "
        "pinion and gear, uniform or tapered depth (seed 002)"
    )

    def parse_machine(self, table: Mapping[str, Any], pair: PairData) -> FaceMillingMachine:
        check_keys(table, MACHINE_KEYS, "machine")
        return FaceMillingMachine(**{m: _parse_member(table, m, pair) for m in MEMBERS})

    def synthesize(
        self, table: Mapping[str, Any], synthesis: Mapping[str, Any], pair: PairData
    ) -> FaceMillingMachine:
        """The gear's settings from the blank (unless ``[machine.gear]`` gives them) and the
        pinion's by local synthesis, per flank, from the ``[synthesis]`` table
        (:mod:`gearopt_plugins.face_milling.synthesis`). ``[machine.pinion]`` and
        ``[machine.pinion.<flank>]`` may hold the chosen inputs only."""
        return _synthesize(table, synthesis, pair)

    def realise_te_target(self, design: Design, *, side: str = "drive") -> tuple[dict, dict]:
        """The pinion's roll on ``side`` fitted by inverse TCA to the design's ``[te_target]``
        (:mod:`gearopt_plugins.face_milling.inverse`): c0 moves the cradle angle, c1 ... c6
        replace ``ratio_of_roll`` and ``roll_c2`` ... ``roll_c6``; the gear is unchanged."""
        if design.te_target is None:
            raise DesignError("te_target", rule="the design has no [te_target] table")
        if side not in SIDES:
            raise DesignError("side", side, f"must be one of {sorted(SIDES)}")
        mean = None
        for report in design.machine.synthesis:  # M of the local synthesis, when there is one
            if report.targets.side == side:
                mean = (report.targets.mean_point_face_mm, report.targets.mean_point_profile_mm)
        result = inverse_tca(design, design.te_target, side=side, mean_point_mm=mean)
        table = machine_table(design.machine)
        flank = SIDES[side][0]
        values = table["pinion"][flank]
        before = {k: values[k] for k in ("cradle_angle_deg", "ratio_of_roll", *ROLL_KEYS)}
        values["cradle_angle_deg"] += result.cradle_shift_deg
        values["ratio_of_roll"] = result.roll[0]
        for k, key in enumerate(ROLL_KEYS, start=1):
            values[key] = result.roll[k]
        report = {
            "side": side,
            "pinion_flank": flank,
            "te_target": design.te_target.as_dict(),
            "before": before,
            "after": {k: values[k] for k in before},
            "cradle_shift_deg": result.cradle_shift_deg,
            "iterations": result.iterations,
            "positions": len(result.u_rad),
            "fit_residual_arcsec": result.fit_residual_arcsec,
            "contact_interval_deg": [math.degrees(v) for v in result.interval_rad],
            "contact_ratio": result.contact_ratio(design.pair.pinion_teeth),
            "work_angle_range_deg": [
                math.degrees(float(result.phi_p_rad.min())),
                math.degrees(float(result.phi_p_rad.max())),
            ],
        }
        return table, report

    def basic_settings(self, design: Design) -> MachineSettings:
        if not design.compensation.is_zero:
            raise NotAvailableError(
                "compensation", rule="the face-milling model does not compensate errors yet"
            )
        out = {}
        for member in MEMBERS:
            values = {}
            for flank in FLANKS:
                spec = design.machine.member(member).flank(flank)
                for key in FLANK_KEYS:
                    if key == "blade_profile_radius_mm":
                        continue
                    values[f"{flank}_{key}"] = getattr(spec, key)
                values[f"{flank}_blade_profile_curvature_per_mm"] = spec.profile_curvature_per_mm
            out[member] = FaceMillingSettings(**values)
        machine: FaceMillingMachine = design.machine
        notes = ["blade_profile_curvature_per_mm = 0 means a straight blade"]
        if machine.synthesis:
            notes.insert(0, _SYNTHESIS_NOTE)
            for report in machine.synthesis:
                local = report.as_dict()["local"]
                notes.append(
                    f"{report.targets.side} (pinion {SIDES[report.targets.side][0]}): local "
                    f"path {local['path_angle_deg']:.4f} deg, ellipse "
                    f"{local['ellipse_major_axis_mm']:.4f} mm, TE level "
                    f"{local['te_level_arcsec']:.4f} arcsec at M"
                )
        else:
            notes.insert(0, "the settings as given in [machine]")
        return MachineSettings(model=self.name, notes=(*notes, *machine.notes), **out)

    def generate_flanks(
        self,
        design: Design,
        *,
        member: str,
        grid: FlankGrid | None = None,
        flanks: tuple[str, ...] = ("convex", "concave"),
        tool_pass: int = 0,
    ) -> dict[str, FlankMap]:
        """Both flanks (or ``flanks``) of tooth 0 (of tooth ``tool_pass`` when the work is
        indexed by that many pitches) in one batch."""
        for flank in flanks:
            check_member_and_flank(member, flank)
        index = MEMBERS.index(member)
        blank = design.blank
        teeth = (design.pair.pinion_teeth, design.pair.gear_teeth)[index]
        family = design_family(design, member, flanks, tool_pass=tool_pass)
        gamma = math.radians(blank.pitch_angle_deg[index])
        solution = solve_envelope(
            family,
            cone_distances_mm=(blank.inner_cone_distance_mm, blank.outer_cone_distance_mm),
            heights_mm=(-blank.mean_dedendum_mm[index], blank.mean_addendum_mm[index]),
            pitch_angle_rad=gamma,
            grid=grid or FlankGrid(),
            taper=blank.depth_taper(index),
            where=f"{member} flanks {', '.join(flanks)}",
        )
        hand = blank.hand[index]
        out = {}
        for k, flank in enumerate(flanks):
            require_flank(solution, k, member=member, flank=flank)
            spec = design.machine.member(member).flank(flank)
            out[flank] = flank_map(
                family,
                solution,
                index=k,
                member=member,
                flank=flank,
                hand=hand,
                teeth=teeth,
                turn_rad=_tooth_turn_rad(design, member, flank, teeth),
                notes=(
                    f"{BLADE_OF_FLANK[flank]} blade (face milling): r_p = "
                    f"{spec.cutter_point_radius_mm:g} mm, c1 = {spec.ratio_of_roll:g}"
                    + (
                        f", edge radius {spec.blade_tip_radius_mm:g} mm"
                        if spec.blade_tip_radius_mm
                        else ""
                    ),
                ),
            )
            if tool_pass:
                out[flank] = replace(out[flank], tooth=tool_pass if hand == "right" else -tool_pass)
        return out

    def correction_settings(self, design: Design, member: str) -> tuple[CorrectionSetting, ...]:
        return correction.correction_settings(design, member)

    def machine_table(self, design: Design) -> dict[str, Any]:
        return machine_table(design.machine)

    def rexs_export(self, design: Design) -> RexsMachine:
        """Each flank's blade and settings (:mod:`gearopt_plugins.face_milling.rexs`)."""
        return fm_rexs.to_rexs(machine_table(design.machine))

    def rexs_import(self, machine: RexsMachine, pair: PairData) -> dict[str, Any]:
        return fm_rexs.from_rexs(machine)

    def cutter_catalogue(self, design: Design) -> tuple[SearchDimension, ...]:
        """The Gleason face mills that suit the gear (``synthesis.gear_cutter_radius_mm``,
        :mod:`gearopt_plugins.face_milling.cutters`), when the design has ``[synthesis]``."""
        return catalogue_dimensions(design.pair, "synthesis" in design.source)

    def search_space(self, design: Design) -> tuple[SearchDimension, ...]:
        machine: FaceMillingMachine = design.machine
        min_rb = MIN_PROFILE_RADIUS_DEPTHS * max(design.blank.whole_depth_mm)
        dims = []
        for member in MEMBERS:
            for flank in FLANKS:
                spec = machine.member(member).flank(flank)
                prefix = f"machine.{member}.{flank}."
                c1, rp = spec.ratio_of_roll, spec.cutter_point_radius_mm
                dims += [
                    SearchDimension(key=prefix + "ratio_of_roll", low=0.99 * c1, high=1.01 * c1),
                    SearchDimension(key=prefix + "roll_c2", low=-0.05 * c1, high=0.05 * c1),
                    SearchDimension(
                        key=prefix + "cutter_point_radius_mm", low=0.99 * rp, high=1.01 * rp
                    ),
                    SearchDimension(
                        key=prefix + "blade_profile_radius_mm",
                        low=max(250.0, 1.01 * min_rb),
                        high=20000.0,
                        log=True,
                    ),
                ]
        return tuple(dims)


def _mean_pitch_point(design: Design, member: str, flank: str) -> tuple[float, float]:
    """Polar angle and circumferential component of the normal (out of the material) of the
    right-hand flank as generated (before any turn) at its point of cone distance A_m on the
    pitch cone (solved by Newton from the pitch-line start)."""
    family = design_family(design, member, (flank,))
    a = family.scale_mm
    g = family.pitch_angle_rad
    target = np.array([a * math.cos(g), a * math.sin(g)])

    def residual(x, idx):
        big_l, big_r, f = family.axial_radial_meshing(x, np.zeros(len(x), int))
        return np.stack([(big_l - target[0]) / a, (big_r - target[1]) / a, f], axis=-1)

    start = family.pitch_row(np.array([a]))[0]
    sol = newton(residual, start, tol=1e-13, max_iter=30, max_step=family.max_step)
    if not sol.all_converged:
        raise SettingsError(
            f"machine.{member}.{flank}",
            rule="no envelope at the mean point of the pitch cone (Newton did not converge): "
            "the settings do not generate this flank there",
        )
    geo = family.geometry(sol.x[0], np.array(0))
    p, n = geo["point"], geo["normal"]
    return float(math.atan2(p[1], p[0])), float(p[0] * n[1] - p[1] * n[0])


def _tooth_turn_rad(design: Design, member: str, flank: str, teeth: int) -> float:
    """0 for the convex flank. The concave flank of tooth 0 is the generated concave flank
    turned by the whole pitches that put it on the material side of the convex flank, less
    than a pitch away (at the mean point of the pitch cone). The generated convex and concave
    flanks may bound a tooth space (one cutter with both blades) or a tooth (a pinion cut by
    the gear's generating surface: its outside blade on the smaller cone)."""
    if flank == "convex":
        return 0.0
    pitch = 2.0 * math.pi / teeth
    theta_x, around_x = _mean_pitch_point(design, member, "convex")
    theta_v, _ = _mean_pitch_point(design, member, "concave")
    toward = -1.0 if around_x > 0.0 else 1.0  # the convex flank's material side
    d0 = (theta_v - theta_x) * toward
    return -toward * math.floor(d0 / pitch) * pitch


@hookimpl
def gearopt_machine_models() -> list[BaseMachineModel]:
    """The face-milling machine model."""
    return [FaceMilling()]


@hookimpl
def gearopt_commands(plugin_manager) -> list[BaseCommand]:
    """``gearopt realise-te``: the settings realising a designed TE (inverse TCA)."""
    return [RealiseTECommand(plugin_manager=plugin_manager)]
