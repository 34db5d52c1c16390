"""Inverse TCA: the pinion's modified roll that realises a designed TE (seed 002).

The gear is fixed. For pinion rotations u across the designed contact (|u| <= x_in, the
mesh-in point of the :class:`gearopt.te_target.TETarget`), the gear is put where the target
says, lagging lambda(u) = -delta_phi2(u) behind its ideal angle, and the equations of
continuous tangency are solved for the pinion flank point that touches it -- not on a given
pinion flank but on the tool: the unknowns are the blade point (u_t, theta_t), the work angle
phi_p and the cradle angle phi_c at which the tool generates it, and the gear point (its own
generation parameters):

    B R(phi1) p(u_t, theta_t, phi_p, phi_c) + c = R(psi) r(u_g, theta_g, phi_g)    (3)
    n1 + n2 = 0 in the tangent plane                                                  (2)
    f_p(u_t, theta_t, phi_p; phi_c, dphi_c/dphi_p) = 0   (the pinion's generation)     (1)
    f_g(u_g, theta_g, phi_g) = 0                          (the gear's generation)        (1)

with phi1 = phi1_0 + s u, psi = psi_0 - (N1/N2) s u + s lambda(u) (s the pinion's sense of
rotation; the frames of :mod:`gearopt.contact`). The reference (phi1_0, psi_0) is the contact
of the given pair at the pinion point generated at centre roll nearest the flank centre. The
meshing equation of the generation involves the roll's derivative, so the fit is iterated: the
data (phi_p, phi_c) are fitted by phi_c = c0 + c1 phi_p + ... + c6 phi_p^6 (least squares), the
fit's derivative goes back into f_p, until the coefficients stop moving. c0 is a change of the
cradle angle setting; c1 ... c6 replace the flank's roll terms.

:class:`RealiseTECommand` is ``gearopt realise-te DESIGN.toml``, which the face-milling plugin
adds to the command line: the design's machine model realises its ``[te_target]``
(:meth:`gearopt.BaseMachineModel.realise_te_target`) and the design is written with the fitted
settings.
"""

from __future__ import annotations

import argparse
import json
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pluggy
import tomli_w
from numpy.typing import NDArray

from gearopt.commands import BaseCommand
from gearopt.contact import Placement
from gearopt.design import Design
from gearopt.design_files import load_design, source_with_machine
from gearopt.errors import SettingsError
from gearopt.flank import cone_coordinates
from gearopt.kinematics import rot_z
from gearopt.mesh import ToothFrame
from gearopt.plugins import get_machine_model
from gearopt.solve import complex_step_jacobian, newton
from gearopt.te_target import ARCSEC, TETarget
from gearopt_plugins.face_milling.family import design_family
from gearopt_plugins.face_milling.local import hand_sign, mirrored, solve_nodes
from gearopt_plugins.face_milling.synthesis import SIDES

__all__ = ["InverseTCA", "RealiseTECommand", "inverse_tca"]


@dataclass(frozen=True, kw_only=True)
class InverseTCA:
    """Outcome of :func:`inverse_tca`.

    Attributes
    ----------
    roll
        ``(c1, ..., c6)`` fitted (rad of cradle per rad^k of work).
    cradle_shift_deg
        c0 in degrees: the change of the cradle angle setting.
    iterations
        Fixed-point iterations of the fit (the roll's derivative in the generation).
    history
        ``(iterations, 7)`` coefficients c0 ... c6 after each iteration.
    phi_p_rad, phi_c_rad
        The last iteration's data, one pair per position.
    fit_residual_arcsec
        Largest |phi_c - fit| over the data, arcsec of cradle.
    u_rad
        The pinion rotations (direction of motion) of the data.
    interval_rad
        ``(start, end)``: the pinion rotations (from phi1_0, direction of motion) where the
        contact of the fitted pair, continued beyond the data, leaves either blank (face width,
        root and face cones): the contact ratio is ``(end - start)`` over the angular pitch.
    """

    roll: tuple[float, ...]
    cradle_shift_deg: float
    iterations: int
    history: NDArray
    phi_p_rad: NDArray
    phi_c_rad: NDArray
    fit_residual_arcsec: float
    u_rad: NDArray
    interval_rad: tuple[float, float]

    def contact_ratio(self, pinion_teeth: int) -> float:
        """The interval over the angular pitch."""
        return (self.interval_rad[1] - self.interval_rad[0]) * pinion_teeth / (2.0 * math.pi)


def _poly(coef, x):
    """phi_c and its derivative for c0 ... c6."""
    value = np.polyval(coef[::-1], x)
    slope = np.polyval((coef[1:] * np.arange(1, len(coef)))[::-1], x)
    return value, slope


class _Pair:
    """The pinion tool, the gear, their placement and the reference contact."""

    def __init__(self, design: Design, side: str, mean_point_mm=None, region=None) -> None:
        pinion_flank, gear_flank = SIDES[side]
        blank = design.blank
        self.pinion = design_family(design, "pinion", (pinion_flank,))
        self.gear = design_family(design, "gear", (gear_flank,))
        self.hand1, self.hand2 = (hand_sign(h) for h in blank.hand)
        self.b, self.c = Placement(shaft_angle_deg=design.pair.shaft_angle_deg).pinion_to_gear
        self.ratio = design.pair.pinion_teeth / design.pair.gear_teeth
        self.scale = blank.mean_cone_distance_mm
        spec = design.machine.pinion.flank(pinion_flank)
        self.base_roll = np.array([0.0, *spec.roll])
        self.zero = np.zeros(1, int)
        self.blank = blank
        self.region = region
        self._reference(design, blank, mean_point_mm)

    def pinion_point(self, q, cradle):
        geo = self.pinion.geometry(q, np.zeros(q.shape[:-1], int), cradle=cradle)
        return (
            mirrored(geo["point"], self.hand1),
            mirrored(geo["normal"], self.hand1),
            geo["meshing"],
        )

    def gear_point(self, q):
        geo = self.gear.geometry(q, np.zeros(q.shape[:-1], int))
        f = self.gear.axial_radial_meshing(q, np.zeros(q.shape[:-1], int))[2]
        return mirrored(geo["point"], self.hand2), mirrored(geo["normal"], self.hand2), f

    def fold(self, x, coef) -> NDArray:
        """``(N, 2)`` determinants of the envelope equations (L, R, f) in the generating
        parameters of the pinion (with the roll ``coef``) and of the gear at the contact
        points of ``x``: each changes sign where its flank folds (the limit line of the
        envelope, below which the tool undercuts)."""
        out = []
        for family, q, roll in (
            (self.pinion, x[:, 0:3], coef),
            (self.gear, x[:, 4:7], None),
        ):

            def lrf(z, idx, family=family, roll=roll):
                zero = np.zeros(len(z), int)
                if roll is None:
                    return np.stack(family.axial_radial_meshing(z, zero), -1)
                big_l, big_r, _ = family.axial_radial_meshing(z, zero)
                value, slope = _poly(roll, z[:, 2])
                f = family.geometry(z, zero, cradle=(value, slope))["meshing"]
                return np.stack([big_l / self.scale, big_r / self.scale, f], -1)

            out.append(np.linalg.det(complex_step_jacobian(lrf, q)))
        return np.stack(out, -1)

    def margin_mm(self, x, coef=None) -> NDArray:
        """How far inside both blanks the contact points of unknowns ``x`` ``(N, 7)`` lie
        (mm; negative outside): the least distance to the toe, heel, root and face lines in
        each member's axial plane; with ``coef`` (the pinion's roll) also negative beyond a
        flank's fold (the sign of :meth:`fold` against its sign at the reference)."""
        out = []
        b = self.blank
        for index, (family, q) in enumerate(((self.pinion, x[:, 0:3]), (self.gear, x[:, 4:7]))):
            big_l, big_r, _ = family.axial_radial_meshing(q, np.zeros(len(q), int))
            s, h = cone_coordinates(big_l, big_r, math.radians(b.pitch_angle_deg[index]))
            out += [
                s - b.inner_cone_distance_mm,
                b.outer_cone_distance_mm - s,
                h + b.dedendum_at_mm(index, s),
                b.addendum_at_mm(index, s) - h,
            ]
            if index == 0 and self.region is not None:  # the pinion flank as generated
                inside = self.region(s, h)  # (it ends above its fold)
        margin = np.min(np.stack(out), axis=0)
        if self.region is not None:
            margin = np.where(inside, margin, -1.0)
        if coef is not None:
            folded = np.any(self.fold(x, coef) * self.fold_sign <= 0.0, axis=-1)
            margin = np.where(folded, -1.0, margin)
        return margin

    def equations(self, x, phi1, psi, roll_slope=None):
        """Residuals ``(N, 7)`` of the seven equations at unknowns ``x`` ``(N, 7)``:
        (u_t, theta_t, phi_p, phi_c, u_g, theta_g, phi_g); ``roll_slope(phi_p)`` gives
        dphi_c/dphi_p."""
        q1 = x[..., 0:3]
        slope = roll_slope(x[..., 2])
        p, n1, f1 = self.pinion_point(q1, (x[..., 3], slope))
        r, n2, f2 = self.gear_point(x[..., 4:7])
        rot1, rot2 = rot_z(phi1)[..., :3, :3], rot_z(psi)[..., :3, :3]
        q = np.einsum("ij,...jk,...k->...i", self.b, rot1, p) + self.c
        g = np.einsum("...ij,...j->...i", rot2, r)
        m1 = np.einsum("ij,...jk,...k->...i", self.b, rot1, n1)
        m2 = np.einsum("...ij,...j->...i", rot2, n2)
        s = m1 + m2
        return np.concatenate(
            [
                (q - g) / self.scale,
                np.einsum("...j,j->...", s, self.t_a)[..., None],
                np.einsum("...j,j->...", s, self.t_b)[..., None],
                f1[..., None],
                f2[..., None],
            ],
            axis=-1,
        )

    def _reference(self, design, blank, mean_point_mm) -> None:
        """The contact at the pinion point generated at centre roll nearest M (pattern
        coordinates; default the flank centre): (phi1_0, psi_0), the sense of rotation, the
        starting unknowns."""
        frame = ToothFrame.from_blank(blank)
        g1 = math.radians(blank.pitch_angle_deg[0])
        face, profile = frame.centre_mm if mean_point_mm is None else mean_point_mm
        s1 = frame.toe_mm + face
        h1 = frame.root_mm + profile
        start1 = self.pinion.pitch_row(np.array([s1]))[0, 0]
        sol = solve_nodes(self.pinion, np.array([s1]), np.array([h1]), start1, g1)
        q1 = sol.x[0]
        p = mirrored(self.pinion.geometry(q1[None], self.zero)["point"][0], self.hand1)
        n = mirrored(self.pinion.geometry(q1[None], self.zero)["normal"][0], self.hand1)
        self.sense = 1 if p[0] * n[1] - p[1] * n[0] > 0.0 else -1
        qg = self.b @ p + self.c
        g2 = math.radians(blank.pitch_angle_deg[1])
        big_l2, big_r2 = qg[2], math.hypot(qg[0], qg[1])
        s2, h2 = cone_coordinates(big_l2, big_r2, g2)
        start2 = self.gear.pitch_row(np.array([blank.mean_cone_distance_mm]))[0, 0]
        q2 = solve_nodes(self.gear, np.array([s2]), np.array([h2]), start2, g2).x[0]
        r = mirrored(self.gear.geometry(q2[None], self.zero)["point"][0], self.hand2)
        psi0 = math.atan2(qg[1], qg[0]) - math.atan2(r[1], r[0])
        # the tangent basis of the normal equations: the pinion's tangent plane at the guess
        m = self.b @ n
        t_a = np.cross(m, [0.0, 0.0, 1.0])
        self.t_a = t_a / np.linalg.norm(t_a)
        self.t_b = np.cross(m, self.t_a)
        base = self.base_roll

        # unknowns: u_t, theta_t, u_g, theta_g, phi_g, psi_0, phi1_0 (phi_p = phi_c = 0)
        def residual(z, idx):
            x = np.concatenate([z[:, 0:2], 0.0 * z[:, :2], z[:, 2:5]], axis=1)
            return self.equations(x, z[:, 6], z[:, 5], lambda phi: _poly(base, phi)[1] + 0.0 * phi)

        z0 = np.array([[q1[0], q1[1], *q2, psi0, 0.0]])
        ref = newton(
            residual, z0, tol=1e-13, max_iter=60, max_step=(1.0, 0.05, 1.0, 0.05, 0.05, 0.05, 0.05)
        )
        if not ref.all_converged:
            raise SettingsError(
                "te_target",
                rule="the pair has no point contact at the pinion point generated at centre "
                "roll near the flank centre (the reference of the designed TE)",
            )
        z = ref.x[0]
        self.phi1_0, self.psi_0 = float(z[6]), float(z[5])
        self.start = np.array([z[0], z[1], 0.0, 0.0, z[2], z[3], z[4]])


def inverse_tca(
    design: Design,
    target: TETarget,
    *,
    side: str = "drive",
    positions: int = 41,
    degree: int = 6,
    max_iterations: int = 40,
    tol: float = 1e-12,
    mean_point_mm: tuple[float, float] | None = None,
    pinion_region=None,
) -> InverseTCA:
    """The roll coefficients of the pinion's ``side`` flank that realise ``target`` (module
    docstring). Raises :class:`SettingsError` when the tangency has no solution at some
    position (the target asks for contact the geometry cannot give). ``mean_point_mm``: the
    reference point M in pattern coordinates (default the flank centre). ``pinion_region``:
    ``(s, h) -> bool``, where the pinion flank is generated (e.g. a FlankMap's ``inside``,
    the region the contact engine uses): the contact interval then also ends where the contact
    leaves it."""
    pair = _Pair(design, side, mean_point_mm, pinion_region)
    s = pair.sense
    u = np.linspace(-target.mesh_in_rad, target.mesh_in_rad, positions)
    coef = np.zeros(degree + 1)
    coef[: len(pair.base_roll)] = pair.base_roll[: degree + 1]
    steps = (1.0, 0.05, 0.05, 0.05, 1.0, 0.05, 0.05)

    def solve(x0, coef, at):
        """The seven equations at the rotations ``at`` (one row each)."""
        lag = -target.delta_rad(at)
        phi1 = pair.phi1_0 + s * at
        psi = pair.psi_0 - pair.ratio * s * at + s * lag

        def residual(z, idx):
            return pair.equations(z, phi1[idx], psi[idx], lambda phi: _poly(coef, phi)[1])

        return newton(residual, x0, tol=1e-13, max_iter=60, max_step=steps)

    # the first pass by continuation outward from the reference (u = 0 in the middle)
    x = np.empty((positions, 7))
    mid = positions // 2
    x[mid] = pair.start
    for order in (range(mid + 1, positions), range(mid - 1, -1, -1)):
        last = [mid]
        for k in order:  # one row at a time: continuation, linear extrapolation
            guess = x[last[-1]] if len(last) < 2 else 2.0 * x[last[-1]] - x[last[-2]]
            sol = solve(guess[None], coef, u[k : k + 1])
            if not sol.all_converged:
                raise SettingsError(
                    "te_target",
                    float(u[k]),
                    "no contact of the pinion tool with the gear at this pinion rotation "
                    "(rad from the reference) for the designed TE",
                )
            x[k] = sol.x[0]
            last.append(k)
    history = []
    iteration = 0
    while iteration < max_iterations:
        iteration += 1
        sol = solve(x, coef, u)
        if not sol.all_converged:
            raise SettingsError(
                "te_target", rule="the inverse TCA lost the contact while its roll was refitted"
            )
        x = sol.x
        phi_p, phi_c = x[:, 2], x[:, 3]
        new = np.polynomial.polynomial.polyfit(phi_p, phi_c, degree)
        history.append(new)
        change = np.max(np.abs(new - coef) * np.max(np.abs(phi_p)) ** np.arange(degree + 1))
        coef = new
        if change < tol:
            break
    fit = np.polynomial.polynomial.polyval(phi_p, coef)
    mid = positions // 2  # the folds' sides at the reference, with the fitted roll
    pair.fold_sign = np.sign(pair.fold(x[mid : mid + 1], coef)[0])
    ends = tuple(_interval_end(pair, solve, coef, u, x, way) for way in (-1, 1))
    return InverseTCA(
        roll=tuple(float(c) for c in coef[1:]) + (0.0,) * (6 - degree),
        cradle_shift_deg=math.degrees(coef[0]),
        iterations=iteration,
        history=np.array(history),
        phi_p_rad=phi_p,
        phi_c_rad=phi_c,
        fit_residual_arcsec=float(np.max(np.abs(fit - phi_c)) * ARCSEC),
        u_rad=u,
        interval_rad=ends,
    )


def _interval_end(pair, solve, coef, u, x, way: int, step: float = 0.01) -> float:
    """Where the contact, followed from u = 0 toward ``way`` (+1 or -1), leaves a blank: the
    first sign change of the blank margin, continued beyond the data if need be, refined by
    bisection to 1e-7 rad."""
    mid = len(u) // 2
    rows = range(mid, len(u)) if way > 0 else range(mid, -1, -1)
    margin = pair.margin_mm(x, coef)
    last = mid
    for k in rows:
        if margin[k] <= 0.0:
            break
        last = k
    u_in, x_in = float(u[last]), x[last]
    if last == (len(u) - 1 if way > 0 else 0):  # still inside at the end of the data
        previous = x[last - way]
        while True:
            guess = 2.0 * x_in - previous
            sol = solve(guess[None], coef, np.array([u_in + way * step]))
            if not sol.all_converged or abs(u_in) > 1.0:
                raise SettingsError(
                    "te_target",
                    u_in,
                    "the contact does not leave the flanks (rad from the reference)",
                )
            if pair.margin_mm(sol.x, coef)[0] <= 0.0:
                u_out = u_in + way * step
                break
            previous, x_in, u_in = x_in, sol.x[0], u_in + way * step
    else:
        u_out = float(u[last + way])
    while abs(u_out - u_in) > 1e-7:
        middle = 0.5 * (u_in + u_out)
        sol = solve(x_in[None], coef, np.array([middle]))
        if not sol.all_converged:
            raise SettingsError("te_target", middle, "contact lost near the flank's edge")
        if pair.margin_mm(sol.x, coef)[0] > 0.0:
            u_in, x_in = middle, sol.x[0]
        else:
            u_out = middle
    return 0.5 * (u_in + u_out)


class RealiseTECommand(BaseCommand):
    """``gearopt realise-te DESIGN.toml [--out NEW.toml] [--side drive|coast] [--json]``: the
    machine settings fitted to the design's ``[te_target]`` by its machine model."""

    name = "realise-te"
    help = "fit the machine settings to the design's [te_target] (inverse TCA)"

    def __init__(self, *, plugin_manager: pluggy.PluginManager | None = None) -> None:
        self.plugin_manager = plugin_manager

    def add_arguments(self, parser: argparse.ArgumentParser) -> None:
        parser.add_argument("design", help="design TOML file with a [te_target] table")
        parser.add_argument("--side", default="drive", choices=("drive", "coast"))
        parser.add_argument("--out", help="write the design with the fitted settings here")
        parser.add_argument("--json", action="store_true", help="print the report as JSON")

    def run(self, args: argparse.Namespace) -> int:
        design = load_design(args.design, plugin_manager=self.plugin_manager)
        model = get_machine_model(design.model, plugin_manager=self.plugin_manager)
        table, report = model.realise_te_target(design, side=args.side)
        data = source_with_machine(design, table)
        header = (
            f"# {Path(args.design).name} with the pinion's {report.get('pinion_flank', '')} roll "
            f"fitted to [te_target] by `gearopt realise-te` (inverse TCA).\n"
            + "".join(f"# {k}: {v}\n" for k, v in report.items() if k not in ("before", "after"))
            + "\n"
        )
        if args.out:
            Path(args.out).write_text(header + tomli_w.dumps(data), encoding="utf-8")
            report["written"] = str(args.out)
        if args.json or not args.out:
            print(json.dumps(report, indent=2))
        else:
            after = report["after"]
            print(f"wrote {args.out}: " + ", ".join(f"{k} = {v:.6g}" for k, v in after.items()))
        return 0
