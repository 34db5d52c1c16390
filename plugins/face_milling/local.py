"""Local geometry of face-milled flanks and of their mesh at one point (for local synthesis).

Everything here is computed on the exact envelope of the generating family (Newton on the
generation's equations at a few points), never on a FlankMap grid, so that a synthesis solved
here and a tooth contact analysis of the generated FlankMaps are independent computations.

* :func:`envelope_jet` -- the polar angle Theta(s, h) of the flank of one member (the actual
  hand) and its first and second derivatives in the axial-plane coordinates (s along the pitch
  generatrix, h above the pitch cone) at one point: a second-order Taylor patch of the flank.
* :class:`TaylorJet` -- that patch in the interface of :mod:`gearopt.newton_tca`, so that the
  textbook tangency equations (Litvin's five equations of continuous tangency, with their
  analytic Jacobian) solve the mesh of two patches.
* :func:`local_mesh` -- the mesh of a pinion patch and a gear patch near their contact point M:
  the second derivative of the lag (the parabolic transmission error, m'21), the direction of
  the path of contact on the gear flank, and the contact ellipse's major axis in the pattern
  coordinates of the pinion flank (docs/architecture.md, Pattern coordinates), all at M.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from gearopt.contact import Placement
from gearopt.contact.tangency import TangencySystem
from gearopt.errors import SettingsError
from gearopt.flank import axial_plane
from gearopt.flank_jet import FlankJet
from gearopt.kinematics import rot_z
from gearopt.mesh import path_angle
from gearopt.solve import newton

__all__ = [
    "EnvelopeJet",
    "LocalMesh",
    "TaylorJet",
    "envelope_jet",
    "hand_sign",
    "local_mesh",
    "mirrored",
]


def hand_sign(hand: str) -> float:
    """+1 for a right-hand member, -1 for a left-hand one (the mirror image in the member's
    x-z plane of the right-hand flank the families generate)."""
    return 1.0 if hand == "right" else -1.0


def mirrored(vectors, sign: float):
    """Points or normals ``(..., 3)`` of the family's right-hand flank as the member of hand
    ``sign`` (:func:`hand_sign`) has them."""
    return vectors * np.array([1.0, sign, 1.0])


#: stencil step (mm) of the finite differences of Theta on the exact envelope
JET_STEP_MM = 0.1
#: pinion rotation step (rad) of the local tooth contact analysis
MESH_STEP_RAD = 2e-3


@dataclass(frozen=True, kw_only=True)
class EnvelopeJet:
    """Second-order Taylor data of a flank's polar angle at ``(s, h)`` (actual hand).

    ``theta`` and its derivatives ``theta_s``, ``theta_h``, ``theta_ss``, ``theta_sh``,
    ``theta_hh`` (rad, per mm); ``q`` the generating parameters of the point (the family's
    right-hand generation) and ``meshing`` the meshing function there (0 on the envelope)."""

    s_mm: float
    h_mm: float
    pitch_angle_rad: float
    theta: float
    theta_s: float
    theta_h: float
    theta_ss: float
    theta_sh: float
    theta_hh: float
    q: NDArray


def solve_nodes(family, s, h, guess, pitch_angle_rad):
    """Envelope points at the axial-plane coordinates ``(s, h)`` ``(N,)`` (family's hand)."""
    target_l, target_r = axial_plane(s, h, pitch_angle_rad)
    scale = family.scale_mm

    def residual(x, idx):
        big_l, big_r, f = family.axial_radial_meshing(x, np.zeros(len(x), int))
        return np.stack(
            [(big_l - target_l[idx]) / scale, (big_r - target_r[idx]) / scale, f], axis=-1
        )

    start = np.broadcast_to(guess, (len(s), 3))
    sol = newton(residual, start, tol=1e-15, max_iter=40, max_step=family.max_step)
    return sol


def envelope_jet(
    family, *, s_mm: float, h_mm: float, pitch_angle_rad: float, hand_sign: float, guess
) -> EnvelopeJet:
    """The flank's Taylor data at ``(s_mm, h_mm)`` from a 3 x 3 stencil of exact envelope
    points (central differences, step :data:`JET_STEP_MM`); ``hand_sign`` = -1 mirrors the
    family's right-hand flank into a left-hand one (Theta -> -Theta). ``guess``: generating
    parameters near the point. Raises :class:`SettingsError` when the envelope has no regular
    point there."""
    d = JET_STEP_MM
    ks, kh = np.meshgrid([-1.0, 0.0, 1.0], [-1.0, 0.0, 1.0], indexing="ij")
    s = s_mm + d * ks.ravel()
    h = h_mm + d * kh.ravel()
    centre = solve_nodes(family, np.array([s_mm]), np.array([h_mm]), guess, pitch_angle_rad)
    if not centre.all_converged:
        raise SettingsError(
            "local synthesis",
            (s_mm, h_mm),
            "the settings generate no flank point at this position (Newton on the envelope "
            "did not converge)",
        )
    sol = solve_nodes(family, s, h, centre.x[0], pitch_angle_rad)
    if not sol.all_converged:
        raise SettingsError(
            "local synthesis", (s_mm, h_mm), "the envelope is not regular around this point"
        )
    point = family.geometry(sol.x, np.zeros(len(s), int))["point"]
    theta = hand_sign * np.unwrap(np.arctan2(point[:, 1], point[:, 0])).reshape(3, 3)
    return EnvelopeJet(
        s_mm=s_mm,
        h_mm=h_mm,
        pitch_angle_rad=pitch_angle_rad,
        theta=float(theta[1, 1]),
        theta_s=float((theta[2, 1] - theta[0, 1]) / (2 * d)),
        theta_h=float((theta[1, 2] - theta[1, 0]) / (2 * d)),
        theta_ss=float((theta[2, 1] - 2 * theta[1, 1] + theta[0, 1]) / d**2),
        theta_sh=float((theta[2, 2] - theta[2, 0] - theta[0, 2] + theta[0, 0]) / (4 * d * d)),
        theta_hh=float((theta[1, 2] - 2 * theta[1, 1] + theta[1, 0]) / d**2),
        q=centre.x[0],
    )


class TaylorJet(FlankJet):
    """An :class:`EnvelopeJet` as the quadratic polar angle of a flank, in the interface the
    textbook tangency equations use (:class:`gearopt.flank_jet.FlankJet`)."""

    def __init__(self, jet: EnvelopeJet, *, turn_rad: float = 0.0) -> None:
        self.jet = jet
        self.turn = float(turn_rad)
        self.sg, self.cg = math.sin(jet.pitch_angle_rad), math.cos(jet.pitch_angle_rad)

    def polar(self, s: float, h: float):
        j = self.jet
        ds, dh = s - j.s_mm, h - j.h_mm
        t_s = j.theta_s + j.theta_ss * ds + j.theta_sh * dh
        t_h = j.theta_h + j.theta_sh * ds + j.theta_hh * dh
        theta = (
            self.turn
            + j.theta
            + j.theta_s * ds
            + j.theta_h * dh
            + 0.5 * (j.theta_ss * ds * ds + 2.0 * j.theta_sh * ds * dh + j.theta_hh * dh * dh)
        )
        return theta, t_s, t_h, j.theta_ss, j.theta_sh, j.theta_hh, True

    def frame(self):
        """``(p, p_s, p_h, p_ss, p_sh, p_hh, n)`` at the jet's point (member frame, turned by
        the jet's turn), ``n`` the unit normal p_s x p_h."""
        p, p_s, p_h, p_ss, p_sh, p_hh, *_ = self.surface(self.jet.s_mm, self.jet.h_mm, 0.0)
        n = np.cross(p_s, p_h)
        return p, p_s, p_h, p_ss, p_sh, p_hh, n / np.linalg.norm(n)


def _shape(p_s, p_h, p_ss, p_sh, p_hh, n, basis):
    """The second fundamental form (normal ``n``) in the orthonormal tangent ``basis`` (3 x 2),
    and the map from tangent coordinates to the surface parameters (2 x 2)."""
    jac = np.stack([p_s, p_h], axis=1)  # 3 x 2
    to_params = np.linalg.solve(jac.T @ jac, jac.T @ basis)  # 2 x 2: d(s, h) / d(xi)
    second = np.array([[p_ss @ n, p_sh @ n], [p_sh @ n, p_hh @ n]])
    return to_params.T @ second @ to_params, to_params


@dataclass(frozen=True, kw_only=True)
class LocalMesh:
    """The mesh of two flanks near their contact point M (:func:`local_mesh`).

    Attributes
    ----------
    lag_curvature
        d^2 lambda / d u^2 at M: the lag of the gear behind its ideal position (rad of gear)
        per rad^2 of pinion rotation (m'21 in magnitude; > 0 when the transmission error is a
        parabola with its maximum at M).
    path_angle_deg
        Direction of the path of contact on the gear flank at M (:func:`gearopt.mesh.path_angle`).
    ellipse_major_axis_mm
        Major axis of the contact ellipse at M (separation ``compound_um`` along the normal),
        measured in the pinion's pattern coordinates (its axial-plane projection, as the
        contact engine measures the pattern).
    ellipse_form
        4 / (major axis)^2 in 1/mm^2, signed: <= 0 when the flanks cross at M (no point
        contact; the major axis is then inf).
    """

    lag_curvature: float
    path_angle_deg: float
    ellipse_major_axis_mm: float
    ellipse_form: float


def local_mesh(
    pinion: TaylorJet,
    gear: TaylorJet,
    *,
    placement: Placement,
    ratio: float,
    sense: int,
    gear_turn_rad: float,
    root_angle_rad: float,
    compound_um: float,
    orientation: float,
) -> LocalMesh:
    """Local tooth contact analysis of two Taylor patches in contact at M.

    The pinion patch is placed (its ``turn``) so that its point M is at pinion angle 0, the
    gear patch is turned by ``gear_turn_rad`` at pinion angle 0. The five tangency equations
    are solved at pinion rotations u = 0, +-h, +-2h (h = :data:`MESH_STEP_RAD`, direction of
    motion ``sense``); the lag's second difference gives its curvature, the gear contact
    points' first difference the path. The ellipse follows from the difference of the two
    second fundamental forms at M; ``orientation`` = +1 when the pinion patch's normal
    p_s x p_h points out of the pinion's material, else -1.
    """
    b, c = placement.pinion_to_gear
    system = TangencySystem.of_jets(pinion, gear, b=b, c=c, gear_sense=-sense)
    s1, h1, s2, h2 = pinion.jet.s_mm, pinion.jet.h_mm, gear.jet.s_mm, gear.jet.h_mm
    x = np.array([s1, h1, s2, h2, 0.0])
    steps = np.array([0.0, 1.0, -1.0, 2.0, -2.0]) * MESH_STEP_RAD
    out = np.empty((len(steps), 5))
    for k, u in enumerate(steps):
        phi = sense * u

        def fun(z, phi=phi):
            F, J, _, _ = system(phi, gear_turn_rad - ratio * phi, z)
            return F, J

        z = x.copy() if k < 3 else 2.0 * out[k - 2] - out[0]  # linear extrapolation
        try:
            for _ in range(30):  # Newton: the lag's second difference needs machine precision
                F, J = fun(z)
                step = np.linalg.solve(J, F)
                z = z - step
                if np.max(np.abs(step)) < 1e-14 * (1.0 + np.max(np.abs(z))):
                    break
        except np.linalg.LinAlgError:
            z = np.full(5, np.nan)
        if not np.all(np.isfinite(z)) or np.max(np.abs(fun(z)[0])) > 1e-10:
            raise SettingsError(
                "local synthesis",
                rule="the tangency equations have no regular solution near M (line contact "
                "or no contact): the pinion and gear flanks do not touch at a point there",
            )
        out[k] = z
    lag = out[:, 4]
    h = MESH_STEP_RAD
    curvature = (-lag[3] + 16 * lag[1] - 30 * lag[0] + 16 * lag[2] - lag[4]) / (12 * h * h)
    ds2 = (8 * (out[1, 2] - out[2, 2]) - (out[3, 2] - out[4, 2])) / (12 * h)
    dh2 = (8 * (out[1, 3] - out[2, 3]) - (out[3, 3] - out[4, 3])) / (12 * h)

    # the path on the gear flank at M (gear frame as generated: turn 0)
    gear_here = TaylorJet(gear.jet)
    g_point, g_s, g_h, g_ss, g_sh, g_hh, g_n = gear_here.frame()
    angle = path_angle(ds2 * g_s + dh2 * g_h, g_n, g_point, root_angle_rad)

    # the ellipse: both second fundamental forms in the gear frame at u = 0
    rot = rot_z(gear_turn_rad)[:3, :3]
    _, p_s, p_h, p_ss, p_sh, p_hh, p_n = pinion.frame()
    m = rot.T @ b  # pinion frame -> gear member frame (as generated)
    p_s, p_h, p_ss, p_sh, p_hh, p_n = (m @ v for v in (p_s, p_h, p_ss, p_sh, p_hh, p_n))
    basis = np.stack([p_s / np.linalg.norm(p_s), np.zeros(3)], axis=1)
    basis[:, 1] = np.cross(p_n, basis[:, 0])
    try:
        k1, to_pinion = _shape(p_s, p_h, p_ss, p_sh, p_hh, p_n, basis)
        k2, _ = _shape(g_s, g_h, g_ss, g_sh, g_hh, p_n, basis)
        from_pinion = np.linalg.inv(to_pinion)
    except np.linalg.LinAlgError:
        raise SettingsError(
            "local synthesis", rule="a flank is singular at M (no tangent plane)"
        ) from None
    rel = (k2 - k1) * orientation  # the gap's Hessian: positive definite for point contact
    # the ellipse {xi: xi^T rel xi <= 2 delta} seen in the pinion's (s, h) coordinates:
    # {a: a^T form a <= 1}, its major axis 2 / sqrt(smallest eigenvalue of form)
    delta = compound_um * 1e-3
    form = from_pinion.T @ rel @ from_pinion / (2.0 * delta)
    w = np.linalg.eigh(form)[0]
    major = 2.0 / math.sqrt(w[0]) if w[0] > 0.0 else math.inf
    return LocalMesh(
        lag_curvature=float(curvature),
        path_angle_deg=angle,
        ellipse_major_axis_mm=major,
        ellipse_form=float(w[0]),
    )
