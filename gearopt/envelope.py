"""Envelope of a generating family on a FlankMap grid: the solver every machine model shares.

A machine model describes its generation as a :class:`GeneratingFamily`: the tool point
r(q) in the member frame, q = (q_0, q_1, q_2) = (blade parameter, tool phase, roll angle) or
whatever three parameters the machine has. At each grid node (s, h) of the axial plane the
solver finds q with

    L(q) = s cos(gamma) - h sin(gamma),   R(q) = s sin(gamma) + h cos(gamma),   f(q) = 0

(f the meshing function, seed 001 eq 31) by Newton's method batched over the whole grid:
Jacobians by complex step (all three perturbations in one call), a first-order predictor from the
pitch row (h = 0, where the model knows a start), step clipping per unknown.

Then the region the tool really generates (DESIGN.md, pitfalls): a node is generated when Newton
converged there, the Jacobian keeps the sign it has on the pitch row (a sign change marks the
envelope's fold: below it Newton lands on the folded-back sheet), it is connected to the top land
through generated nodes of its face column, it lies ``fold_trim_mm`` or more above the first
folded node of its column, and the model says the tool reaches it (the blade's tip).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Protocol

import numpy as np
from numpy.typing import NDArray

from gearopt.errors import SettingsError
from gearopt.flank import FlankGrid, FlankMap

__all__ = ["GeneratingFamily", "EnvelopeSolution", "solve_envelope", "flank_map"]

_H = 1e-30  # complex step


class GeneratingFamily(Protocol):
    """What a machine model provides to :func:`solve_envelope` (all angles in radians).

    ``axial_radial_meshing(q)`` must use only numpy functions that accept complex input (complex
    step): no ``abs``, no comparisons, no ``np.linalg`` on the parameters.
    """

    #: largest change of each parameter per Newton step (e.g. 1 mm, 0.05 rad, 0.05 rad)
    max_step: tuple[float, float, float]
    #: length scale of the residuals, mm (the mean cone distance A_m)
    scale_mm: float

    def axial_radial_meshing(self, q: NDArray) -> tuple[NDArray, NDArray, NDArray]:
        """``(L, R, f / (|N| A_m))`` of the tool points ``q`` ``(..., 3)`` (complex-safe)."""
        ...

    def pitch_row(self, cone_distance_mm: NDArray) -> NDArray:
        """``(n, 3)`` parameters of the flank points on the pitch line (h = 0), approximately."""
        ...

    def geometry(self, q: NDArray) -> dict[str, NDArray]:
        """``point`` and unit ``normal`` ``(..., 3)`` in the member frame of a right-hand member,
        the normal pointing out of the tooth material."""
        ...

    def within_tool(self, q: NDArray) -> NDArray:
        """``(...)`` True where the tool has the point ``q`` (e.g. above the blade's tip)."""
        ...


@dataclass(frozen=True, kw_only=True)
class EnvelopeSolution:
    """Parameters and diagnostics at every node of a ``(n_f, n_p)`` grid."""

    face_mm: NDArray
    profile_mm: NDArray
    pitch_angle_rad: float
    q: NDArray
    residual: NDArray  # (n_f, n_p, 3) scaled residuals
    converged: NDArray
    unfolded: NDArray
    within_tool: NDArray
    mask: NDArray
    iterations: int


def _residual_and_jacobian(family, q, big_l, big_r):
    """Scaled residuals ``(n, 3)`` and Jacobians ``(n, 3, 3)`` by one complex-step call."""
    n = len(q)
    qs = np.repeat(q[None].astype(complex), 3, axis=0)
    for k in range(3):
        qs[k, :, k] += 1j * _H
    lc, rc, gc = family.axial_radial_meshing(qs)
    a = family.scale_mm
    res = np.stack([(lc - big_l) / a, (rc - big_r) / a, gc], axis=-1)  # (3, n, 3)
    f = res[0].real
    jac = np.moveaxis(res.imag / _H, 0, -1)  # (n, 3 eq, 3 var)
    assert jac.shape == (n, 3, 3)
    return f, jac


def _newton(family, q, big_l, big_r, *, tol, max_iter):
    """Batched Newton with per-unknown step clipping; returns (q, f, jac, converged, iters)."""
    limit = np.asarray(family.max_step, float)
    active = np.ones(len(q), bool)
    f, jac = _residual_and_jacobian(family, q, big_l, big_r)
    iterations = 0
    while iterations < max_iter:
        norm = np.max(np.abs(f), axis=1)
        active = np.isfinite(norm) & (norm > tol) & active
        if not active.any():
            break
        iterations += 1
        idx = np.flatnonzero(active)
        ja = jac[idx]
        ok = np.abs(np.linalg.det(ja)) > 1e-300
        step = np.zeros((len(idx), 3))
        if ok.any():
            step[ok] = np.linalg.solve(ja[ok], -f[idx[ok]][..., None])[..., 0]
        scale = np.min(limit / np.maximum(np.abs(step), 1e-300), axis=1)
        step *= np.minimum(scale, 1.0)[:, None]
        active[idx[~ok]] = False
        q[idx] += step
        f[idx], jac[idx] = _residual_and_jacobian(family, q[idx], big_l[idx], big_r[idx])
    norm = np.max(np.abs(f), axis=1)
    return q, f, jac, np.isfinite(norm) & (norm <= tol), iterations


def _predictor(family, jac, sg, cg):
    """d q / d h ``(n, 3)`` along the profile at fixed face position, from Jacobians ``jac``.

    The targets move by dL/dh = -sin(gamma), dR/dh = cos(gamma); J dq/dh = their change / A.
    """
    rhs = np.array([-sg, cg, 0.0]) / family.scale_mm
    return np.linalg.solve(jac, np.broadcast_to(rhs, jac.shape[:-1])[..., None])[..., 0]


def solve_envelope(
    family: GeneratingFamily,
    *,
    cone_distances_mm: tuple[float, float],
    heights_mm: tuple[float, float],
    pitch_angle_rad: float,
    grid: FlankGrid,
    tol: float = 1e-14,
    max_iter: int = 8,
    fold_trim_mm: float = 0.3,
    where: str = "flank",
) -> EnvelopeSolution:
    """Solve the envelope at every node of ``grid`` over the given face and profile ranges.

    Continuation along the profile: the pitch row (h = 0 when it lies in the range, else the row
    nearest to it) is solved from the model's start; then the rows above and below it are solved
    together, step by step outward, each from its inner neighbour plus the first-order predictor
    ``dq/dh`` of that neighbour's Jacobian. A column stops at its first node that does not
    converge or that lies past the fold (the Jacobian's determinant changes sign): the nodes
    beyond keep the predictor's values (finite, masked out).

    Parameters
    ----------
    family
        The generating family.
    cone_distances_mm
        ``(toe, heel)`` cone distances of the grid's face range.
    heights_mm
        ``(root, top)`` heights above the pitch cone (root negative) of its profile range.
    pitch_angle_rad
        Pitch angle gamma.
    tol
        Convergence tolerance on every scaled residual.
    fold_trim_mm
        Nodes less than this above a column's first folded or failed node are not generated.
    where
        Name used in errors.

    Raises
    ------
    SettingsError
        When Newton fails on the pitch row (the settings generate no flank there).
    """
    s = np.linspace(*cone_distances_mm, grid.n_face)
    h = np.linspace(*heights_mm, grid.n_profile)
    n_f, n_p = grid.shape
    cg, sg = math.cos(pitch_angle_rad), math.sin(pitch_angle_rad)
    big_l = s[:, None] * cg - h[None, :] * sg
    big_r = s[:, None] * sg + h[None, :] * cg
    j0 = int(np.argmin(np.abs(h)))
    # the row nearest the pitch line, from the model's start on the pitch line
    start = np.array(family.pitch_row(s), float)
    jac = _residual_and_jacobian(family, start, s * cg, s * sg)[1]
    start += h[j0] * _predictor(family, jac, sg, cg)
    q0, _, jac0, ok, iterations = _newton(
        family, start, big_l[:, j0], big_r[:, j0], tol=tol, max_iter=2 * max_iter
    )
    if not ok.all():
        raise SettingsError(
            where,
            rule=f"no envelope at cone distance {s[~ok][0]:.3f} mm, height {h[j0]:.3f} mm "
            "(Newton did not converge): the machine settings do not generate this flank",
        )
    sign0 = np.sign(np.linalg.det(jac0))
    # every node at once from the first-order predictor of that row
    dq_dh = _predictor(family, jac0, sg, cg)
    q = q0[:, None, :] + (h - h[j0])[None, :, None] * dq_dh[:, None, :]
    q, res, jac, converged, it = _newton(
        family, q.reshape(-1, 3), big_l.ravel(), big_r.ravel(), tol=tol, max_iter=max_iter
    )
    iterations = max(iterations, it)
    q, res, jac = q.reshape(n_f, n_p, 3), res.reshape(n_f, n_p, 3), jac.reshape(n_f, n_p, 3, 3)
    converged = converged.reshape(n_f, n_p)
    # repair: a node that failed next to a good node (toward the pitch row) restarts from it
    for _ in range(n_p):
        good = converged & (np.sign(np.linalg.det(jac)) == sign0[:, None])
        inner = np.zeros((n_f, n_p), int)
        inner[:, j0 + 1 :] = -1
        inner[:, :j0] = +1
        neighbour = np.arange(n_p)[None, :] + inner
        retry = ~converged & np.take_along_axis(good, neighbour, axis=1)
        retry[:, j0] = False
        if not retry.any():
            break
        fi, pj = np.nonzero(retry)
        nj = neighbour[fi, pj]
        guess = q[fi, nj] + (h[pj] - h[nj])[:, None] * _predictor(family, jac[fi, nj], sg, cg)
        qr, fr, jr, ok, it = _newton(
            family, guess, big_l[fi, pj], big_r[fi, pj], tol=tol, max_iter=max_iter
        )
        iterations = max(iterations, it)
        if not ok.any():
            break
        q[fi[ok], pj[ok]], res[fi[ok], pj[ok]], jac[fi[ok], pj[ok]] = qr[ok], fr[ok], jr[ok]
        converged[fi[ok], pj[ok]] = True
    det = np.linalg.det(jac)
    unfolded = np.sign(det) == sign0[:, None]
    good = converged & unfolded
    # generated: connected to the pitch row through good nodes of the column
    up = np.cumprod(good[:, j0:], axis=1).astype(bool)
    down = np.flip(np.cumprod(np.flip(good[:, : j0 + 1], axis=1), axis=1), axis=1).astype(bool)
    connected = np.concatenate([down[:, :j0], up], axis=1)
    # trim just above the first bad node below the pitch row, column by column
    first_bad = np.where(~connected & (h < h[j0])[None, :], h[None, :], -np.inf).max(axis=1)
    margin = np.where(np.isfinite(first_bad), fold_trim_mm, 0.0)
    trimmed = h[None, :] >= (first_bad + margin)[:, None]
    within = np.asarray(family.within_tool(q), bool)
    return EnvelopeSolution(
        face_mm=s,
        profile_mm=h,
        pitch_angle_rad=pitch_angle_rad,
        q=q,
        residual=res,
        converged=converged,
        unfolded=unfolded,
        within_tool=within,
        mask=connected & trimmed & within,
        iterations=iterations,
    )


def flank_map(
    family: GeneratingFamily,
    solution: EnvelopeSolution,
    *,
    member: str,
    flank: str,
    hand: str,
    teeth: int,
    turn_rad: float = 0.0,
    notes: tuple[str, ...] = (),
) -> FlankMap:
    """The right-hand FlankMap of a solution, turned by ``turn_rad``, mirrored if left-hand."""
    geo = family.geometry(solution.q)
    point, normal = geo["point"], geo["normal"]
    polar = np.arctan2(point[..., 1], point[..., 0])
    result = FlankMap(
        member=member,
        flank=flank,
        hand="right",
        teeth=teeth,
        pitch_angle_deg=math.degrees(solution.pitch_angle_rad),
        face_mm=solution.face_mm,
        profile_mm=solution.profile_mm,
        polar_angle_rad=polar,
        points_mm=point,
        normals=normal,
        residual=np.abs(solution.residual[..., 2]),
        mask=solution.mask,
        parameters=solution.q,
        notes=notes,
    )
    if turn_rad:
        result = result.rotated(turn_rad)
    return result.mirrored() if hand == "left" else result
