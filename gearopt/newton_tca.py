"""Point-by-point tooth contact analysis by Newton's method (Litvin's continuous tangency).

The textbook TCA, kept as an independent cross-check of the contact engine
(:class:`gearopt.contact.ClearanceField`) and as its speed reference. At each relative pinion
rotation u (direction of motion; pinion angle phi = sense * u) it solves five equations in five
unknowns x = (s1, h1, s2, h2, lambda):

    r1(s1, h1; phi) - r2(s2, h2; lambda) = 0          (3 equations, mm, gear frame)
    n1 . r2_s2 = 0,   n1 . r2_h2 = 0                  (2 equations, cosines)

with r1 the pinion flank point (pinion grid coordinates s1, h1) turned by phi about z_p and
mapped into the gear frame (q = B p + c), r2 the gear flank point (gear grid coordinates s2, h2)
at polar angle

    T = Theta2(s2, h2) - ratio * phi + gear_angle + phase - shift - gear_sense * lambda,

i.e. the gear lagging by lambda behind its ideal position (the engine's angular clearance at the
contact, see :mod:`gearopt.contact`), n1 = r1_s1 x r1_h1 and the normal equations normalised by
|n1| |r2_s2| and |n1| |r2_h2|. Theta1 and Theta2 are the flanks' local bicubic Hermite
interpolants (:meth:`gearopt.flank.FlankMap.polar_angle_local`), differentiated here twice for
an analytic Jacobian. The system is solved by MINPACK's hybrid method
(``scipy.optimize.root(method="hybr")``) one position after another, each started from the
previous converged solution.

Newton needs a regular point contact: where the flanks are (nearly) conjugate the contact is a
line and the Jacobian is singular; at edge contact the tangency lies outside a flank. Both are
reported as not converged.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import root

from gearopt.contact import ClearanceField
from gearopt.contact.tangency import TangencySystem
from gearopt.errors import GearoptError
from gearopt.flank_jet import FlankJet
from gearopt.mesh import PairCurve
from gearopt.units import ARCSEC

__all__ = ["NewtonTCA", "contact_interval_end", "newton_tca", "tangency_equations"]


RESIDUAL_LIMIT = 1e-8
"""Largest residual (mm for the point equations, cosine for the normal ones) of a converged
position."""


@dataclass(frozen=True, kw_only=True)
class NewtonTCA:
    """Solutions of the tangency equations, one per relative pinion rotation.

    Attributes
    ----------
    u_rad
        ``(n,)`` relative pinion rotations (direction of motion; pinion angle = sense * u).
    lag_rad
        ``(n,)`` lag lambda of the gear behind its ideal position at the contact (the engine's
        ``minimum_rad``).
    pinion_face_mm, pinion_profile_mm
        ``(n,)`` contact point (s1, h1) on the pinion grid.
    gear_face_mm, gear_profile_mm
        ``(n,)`` contact point (s2, h2) on the gear grid.
    converged
        ``(n,)`` True where the solver succeeded, the residual is at most
        :data:`RESIDUAL_LIMIT` and the point lies on both flanks. Elsewhere the other arrays hold
        the solver's last iterate (for diagnosis only).
    iterations
        ``(n,)`` evaluations of the equations by the solver (MINPACK hybrid: Newton steps with
        Broyden updates; the Jacobian is evaluated far less often).
    residual
        ``(n,)`` largest absolute residual of the five (scaled) equations at the solution.
    """

    u_rad: NDArray
    lag_rad: NDArray
    pinion_face_mm: NDArray
    pinion_profile_mm: NDArray
    gear_face_mm: NDArray
    gear_profile_mm: NDArray
    converged: NDArray
    iterations: NDArray
    residual: NDArray

    @property
    def te_arcsec(self) -> NDArray:
        """``(n,)`` transmission error of this tooth pair in arcsec of gear rotation:
        ``(min lag - lag)`` over the converged positions (maximum 0, negative when the gear lags
        more); NaN where not converged."""
        lag = np.where(self.converged, self.lag_rad, np.nan)
        if not self.converged.any():
            return lag
        return (np.nanmin(lag) - lag) * ARCSEC

    def unknowns(self, k: int) -> NDArray:
        """``(5,)`` the unknowns x = (s1, h1, s2, h2, lambda) of position ``k``."""
        return np.array(
            [
                self.pinion_face_mm[k],
                self.pinion_profile_mm[k],
                self.gear_face_mm[k],
                self.gear_profile_mm[k],
                self.lag_rad[k],
            ]
        )


def tangency_equations(
    field: ClearanceField, u_rad: float, x, *, gear_angle_rad: float = 0.0
) -> tuple[NDArray, NDArray]:
    """The five scaled tangency equations and their analytic Jacobian.

    Parameters
    ----------
    field
        The pair (pinion and gear flanks, placement, senses, phase).
    u_rad
        Relative pinion rotation in the direction of motion.
    x
        ``(5,)`` unknowns (s1, h1, s2, h2, lambda): mm, mm, mm, mm, rad.
    gear_angle_rad
        Extra turn of the gear about +z_g (as in :meth:`ClearanceField.sample`).

    Returns
    -------
    F, J
        ``(5,)`` residuals (three point differences in mm, two cosines) and ``(5, 5)``
        dF/dx.
    """
    system = TangencySystem(field)
    phi, turn = system.angles(float(u_rad), float(gear_angle_rad))
    F, J, _, _ = system(phi, turn, np.asarray(x, float))
    return F, J


def newton_tca(
    field: ClearanceField,
    u_rad,
    *,
    start: tuple[float, float] | None = None,
    gear_angle_rad: float = 0.0,
    tol: float = 1e-10,
) -> NewtonTCA:
    """Tooth contact analysis by Newton's method on the equations of continuous tangency.

    Parameters
    ----------
    field
        The pair, e.g. ``mesh_pair(design).drive``.
    u_rad
        ``(n,)`` relative pinion rotations in the direction of motion, solved in this order,
        each from the previous converged solution.
    start
        ``(s1, h1)`` pinion grid coordinates (mm) of the first guess; the lag guess is the
        engine's angular clearance there. Default: the engine's refined contact point and lag
        at ``u_rad[0]``.
    gear_angle_rad
        Extra turn of the gear about +z_g from its ideal angle (as in
        :meth:`ClearanceField.sample`).
    tol
        Relative step tolerance of the solver (``scipy.optimize.root(method="hybr")``).

    Returns
    -------
    NewtonTCA
        One solution per rotation; see ``converged``.
    """
    u = np.atleast_1d(np.asarray(u_rad, float))
    if u.ndim != 1 or u.size == 0:
        raise GearoptError("u_rad", u.shape, "must be a non-empty 1-d array of angles")
    gear_angle_rad = float(gear_angle_rad)
    system = TangencySystem(field)
    phi0, _ = system.angles(float(u[0]), gear_angle_rad)
    if start is None:
        first = PairCurve(field, gear_angle_rad).sample(u[:1])
        s1, h1 = float(first.contact_face_mm[0]), float(first.contact_profile_mm[0])
        lag = float(first.minimum_rad[0])
    else:
        s1, h1 = (float(v) for v in start)
        p = system.pinion_point(s1, h1, 0.0)[0]  # turned by phi there
        lag = float(field.clearance_of_points(p, None, phi0, gear_angle_rad).clearance_rad)
    # the gear guess: the pinion start point mapped into the gear frame
    q = system.pinion_point(s1, h1, phi0)[1]
    s2, h2 = (float(v) for v in field.gear.to_grid(q[2], math.hypot(q[0], q[1])))
    if not np.all(np.isfinite([s1, h1, s2, h2, lag])):
        raise GearoptError("start", (s1, h1, lag), "must give a finite contact guess")
    guess = np.array([s1, h1, s2, h2, lag])

    out = np.full((len(u), 5), np.nan)
    converged = np.zeros(len(u), bool)
    iterations = np.zeros(len(u), int)
    residual = np.full(len(u), np.inf)
    for k, uk in enumerate(u):
        phi, turn = system.angles(float(uk), gear_angle_rad)

        def fun(x, phi=phi, turn=turn):
            F, J, _, _ = system(phi, turn, x)
            return F, J

        sol = root(fun, guess, jac=True, method="hybr", tol=tol)
        F, _, in1, in2 = system(phi, turn, sol.x)
        res = float(np.max(np.abs(F)))
        ok = bool(sol.success) and bool(np.all(np.isfinite(sol.x))) and res <= RESIDUAL_LIMIT
        ok = ok and in1 and in2
        out[k], converged[k], iterations[k], residual[k] = sol.x, ok, sol.nfev, res
        if ok:
            guess = sol.x.copy()
    return NewtonTCA(
        u_rad=u,
        lag_rad=out[:, 4],
        pinion_face_mm=out[:, 0],
        pinion_profile_mm=out[:, 1],
        gear_face_mm=out[:, 2],
        gear_profile_mm=out[:, 3],
        converged=converged,
        iterations=iterations,
        residual=residual,
    )


#: a Jacobian of the tangency equations whose least singular value is below this fraction of its
#: largest is taken for line contact (the contact point is not unique; the least singular value
#: is about the relative curvature along the contact ellipse, 1/mm, the largest about the gear
#: radius, mm). Measured at the ends of contact intervals: point contacts 6e-7 and more (seed
#: 003, R_b = 10000 mm: 7.7e-7), conjugate flanks 1.7e-8 and less (the most on the coarse
#: default grid, where the interpolants are least conjugate)
LINE_CONTACT = 1e-7


def _point_contact(system: TangencySystem, u: float, x: NDArray) -> bool:
    """Whether the tangency equations' Jacobian at solution ``x`` is regular (a point contact:
    its least singular value at least :data:`LINE_CONTACT` times its largest)."""
    phi, turn = system.angles(u, 0.0)
    singular = np.linalg.svd(system(phi, turn, x)[1], compute_uv=False)
    return bool(singular[-1] >= LINE_CONTACT * singular[0])


def _tangency(system: TangencySystem, u: float, x: NDArray, iterations: int = 8):
    """Newton's iteration on the tangency equations at rotation ``u`` from ``x`` (a nearby
    solution): ``(x, inside)`` with ``inside`` whether the point lies on both flanks, or None
    when it does not converge (a singular or ill-conditioned Jacobian: line contact)."""
    phi, turn = system.angles(u, 0.0)
    x = np.array(x, float)
    for _ in range(iterations):
        F, J, in1, in2 = system(phi, turn, x)
        if np.max(np.abs(F)) <= RESIDUAL_LIMIT:
            return x, in1 and in2
        try:
            dx = np.linalg.solve(J, -F)
        except np.linalg.LinAlgError:
            return None
        if not np.all(np.isfinite(dx)) or np.max(np.abs(dx[:4])) > 5.0:  # no jumps of mm
            return None
        x += dx
    return None


def _grid_margin(jet: FlankJet, s: float, h: float) -> float:
    """How far (mm) the point (s, h) lies inside the jet's grid (negative outside)."""
    return min(
        s - jet.s0,
        jet.s0 + (jet.n_f - 1) * jet.ds - s,
        h - jet.h0,
        jet.h0 + (jet.n_p - 1) * jet.dh - h,
    )


def contact_interval_end(
    field: ClearanceField,
    u_rad: float,
    start: tuple[float, float],
    toward: float,
    step_rad: float,
    *,
    tol_rad: float = 1e-6,
    tol_mm: float = 1e-4,
    steps: int = 24,
) -> tuple[float, float, NDArray] | None:
    """Where the tangency point (the solution of the tangency equations) leaves the flanks: a
    pair's entry into or exit from contact (seed 003 section 6).

    From rotation ``u_rad``, where the contact point is near ``start`` = ``(s1, h1)``, the
    search steps by ``step_rad`` toward ``toward`` (+1 or -1) while the tangency point stays on
    both flanks (or back while it does not, up to ``steps`` steps each way). The bracket is
    then narrowed to ``tol_rad``: by the Illinois method on the point's distance inside the
    grids where it leaves through a grid edge (toe, heel, top, the grid's bottom), stopping
    once the point lies within ``tol_mm`` of it; by bisection where it leaves through the
    boundary of a flank's generated cells. Returns ``(u_inside, u_outside, x)`` with ``x`` the
    unknowns (s1, h1, s2, h2, lambda) at ``u_inside`` (``u_outside`` = ``u_inside`` when the
    point lies within ``tol_mm`` of a grid edge), or None where Newton's method fails or
    the contact is a line (:data:`LINE_CONTACT`), or no bracket is found."""
    system = TangencySystem(field)
    s1, h1 = (float(v) for v in start)
    phi, _ = system.angles(float(u_rad), 0.0)
    p = system.pinion_point(s1, h1, 0.0)[0]
    lag = float(field.clearance_of_points(p, None, phi).clearance_rad)
    q = system.pinion_point(s1, h1, phi)[1]
    s2, h2 = (float(v) for v in field.gear.to_grid(q[2], math.hypot(q[0], q[1])))
    got = _tangency(system, float(u_rad), np.array([s1, h1, s2, h2, lag]))
    if got is None:
        return None
    x, inside = got
    if inside and not _point_contact(system, float(u_rad), x):
        return None
    sign = math.copysign(1.0, toward)
    u_in = u_out = x_out = None
    if inside:
        u_in, x_in = u_rad, x
        for k in range(1, steps + 1):
            u = u_rad + sign * k * step_rad
            got = _tangency(system, u, x_in)
            if got is None or not got[1]:
                u_out, x_out = u, got and got[0]
                break
            u_in, x_in = u, got[0]
    else:
        u_out, x_out = u_rad, x
        for k in range(1, steps + 1):
            u = u_rad - sign * k * step_rad
            got = _tangency(system, u, x_out)
            if got is None:
                return None
            if got[1]:
                u_in, x_in = u, got[0]
                break
            u_out, x_out = u, got[0]
    if u_in is None or u_out is None:
        return None

    def margin(x: NDArray) -> float:
        return min(_grid_margin(system.pinion, x[0], x[1]), _grid_margin(system.gear, x[2], x[3]))

    m_in = margin(x_in)
    m_out = margin(x_out) if x_out is not None else math.nan
    w_in, w_out = m_in, m_out  # the Illinois method's weights: halved on a repeated side
    side = 0
    while abs(u_out - u_in) > tol_rad and m_in > tol_mm:
        if m_out < 0.0:  # through a grid edge: the margin is smooth in u
            u = u_in + w_in * (u_out - u_in) / (w_in - w_out)
            lo, hi = sorted((u_in, u_out))
            u = min(max(u, lo + 1e-3 * (hi - lo)), hi - 1e-3 * (hi - lo))
        else:  # through the boundary of the generated cells (or Newton failed): bisection
            u = 0.5 * (u_in + u_out)
        got = _tangency(system, u, x_in)
        if got is not None and got[1]:
            u_in, x_in = u, got[0]
            m_in = w_in = margin(x_in)
            w_out *= 0.5 if side == 1 else 1.0
            side = 1
        else:
            u_out = u
            m_out = w_out = margin(got[0]) if got is not None else math.nan
            w_in *= 0.5 if side == -1 else 1.0
            side = -1
    if m_in <= tol_mm:  # on the grid's edge: the end itself
        u_out = u_in
    return (u_in, u_out, x_in) if _point_contact(system, u_in, x_in) else None
