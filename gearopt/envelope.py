"""Envelope of a generating family on a FlankMap grid: the solver every machine model shares.

A machine model describes its generation as a :class:`GeneratingFamily`: the tool point r(q) of
one or more flanks (a dual head's inner and outer blades, say), q = (q_0, q_1, q_2) = (blade
parameter, tool phase, roll angle) or whatever three parameters the machine has. At each grid
node (s, h) of the axial plane the solver finds q with

    L(q) = s cos(gamma) - h sin(gamma),   R(q) = s sin(gamma) + h cos(gamma),   f(q) = 0

(f the meshing function, seed 001 eq 31) by Newton's method batched over every node of every
flank: Jacobians by complex step (all three perturbations in one call), a second-order predictor
from the pitch line (h = 0, where the model knows a start), step clipping per unknown, and one
repair pass that restarts a failed node from its converged neighbour.

Then the region the tool really generates (docs/architecture.md, Numerical notes): a node is
generated when Newton converged there, the Jacobian keeps the sign it has on the pitch line (a
sign change marks the envelope's fold: below it Newton lands on the folded-back sheet), it is
connected to the pitch row through such nodes of its face column, it lies ``fold_trim_mm`` or
more above the first folded or failed node of its column, and the model says the tool reaches it
(the blade's tip).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Protocol

import numpy as np
from numpy.typing import NDArray

from gearopt.determinants import det_signs
from gearopt.envelope_nodes import bilinear, grid_nodes, nearest_start, sheet_nodes
from gearopt.errors import GearoptError, SettingsError
from gearopt.flank import (
    DepthTaper,
    FlankGrid,
    FlankMap,
    axial_plane,
    extended_below,
    mirror_image,
    turned,
    unwrapped_along_face,
)

__all__ = [
    "GeneratingFamily",
    "EnvelopeSolution",
    "EnvelopeSurface",
    "solve_envelope",
    "flank_map",
    "extended_geometry",
    "require_flank",
]

_H = 1e-30  # complex step
#: bisections of a column's fold between two nodes (to 2**-12 of a cell)
FOLD_BISECTIONS = 12


class GeneratingFamily(Protocol):
    """What a machine model provides to :func:`solve_envelope` (all angles in radians).

    A family generates ``n_flanks`` flanks of one member at once; every method takes, beside the
    parameters ``q`` ``(..., 3)``, the integer array ``flank`` (broadcastable to ``q[..., 0]``)
    that says which flank each point belongs to. ``axial_radial_meshing`` must use only numpy
    functions that accept complex input (complex step): no ``abs``, no comparisons, no
    ``np.linalg`` on the parameters.
    """

    #: number of flanks the family generates (flank indices 0 .. n_flanks - 1)
    n_flanks: int
    #: largest change of each parameter per Newton step (e.g. 1 mm, 0.05 rad, 0.05 rad)
    max_step: tuple[float, float, float]
    #: length scale of the residuals, mm (the mean cone distance A_m)
    scale_mm: float

    def axial_radial_meshing(self, q: NDArray, flank: NDArray) -> tuple[NDArray, NDArray, NDArray]:
        """``(L, R, f / (|N| A_m))`` of the tool points ``q`` (complex-safe)."""
        ...

    # optional: ``axial_radial_meshing_jacobian(q, flank) -> (L, R, g, J)`` with J ``(..., 3, 3)``
    # the Jacobian of (L, R, g) in q, analytically; the solver uses it instead of complex step
    #
    # optional: ``newton(q, flank, big_l, big_r, *, tol, max_iter, give_up, chords)`` the
    # solver's Newton iteration (``_newton``: same arguments, same result ``(q, f, jac,
    # converged, iterations)``, ``q`` ``(n, 3)``) done by the family, compiled, or None where it
    # cannot (then the solver iterates itself)
    #
    # optional: ``bisect(q_up, flank, face_mm, lower, upper, *, cos_sin, tol, bisections,
    # sheet)`` the solver's bisection of a column's generated end on uniform depth
    # (``_bisected``: each middle solved by ``_newton`` with ``max_iter=8`` from the last
    # accepted point, accepted where it converged with the meshing Jacobian's determinant of
    # the sign ``sheet`` (``(m,)``), or with ``sheet`` None where ``within_tool``) done by the
    # family, compiled: the last accepted profile coordinates ``(m,)``, or None where it cannot

    def pitch_row(self, cone_distance_mm: NDArray) -> NDArray:
        """``(n_flanks, n, 3)`` parameters of the flank points on the pitch line (h = 0),
        approximately."""
        ...

    def geometry(self, q: NDArray, flank: NDArray) -> dict[str, NDArray]:
        """``point`` and unit ``normal`` ``(..., 3)`` in the member frame of a right-hand member,
        the normal pointing out of the tooth material."""
        ...

    def within_tool(self, q: NDArray, flank: NDArray) -> NDArray:
        """``(...)`` True where the tool has the point ``q`` (e.g. above the blade's tip)."""
        ...


@dataclass(frozen=True, kw_only=True)
class EnvelopeSolution:
    """Parameters and diagnostics at every node of ``n_flanks`` grids ``(n_f, n_p)``.

    Every array has the leading shape ``(n_flanks, n_f, n_p)``.
    """

    face_mm: NDArray
    profile_mm: NDArray
    pitch_angle_rad: float
    q: NDArray
    residual: NDArray  # (..., 3) scaled residuals
    converged: NDArray
    unfolded: NDArray
    within_tool: NDArray
    mask: NDArray
    sheet: NDArray  # nodes on the envelope's sheet, connected to the pitch row
    iterations: int
    taper: DepthTaper | None = None  # tapered depth: profile_mm holds the grid coordinate t
    #: ``(n_flanks, n_f)`` each column's lowest generated profile coordinate (continuous:
    #: the fold solved, trimmed; +inf without generated nodes)
    lowest_profile_mm: NDArray | None = None


def _residual_and_jacobian(family, q, flank, big_l, big_r):
    """Scaled residuals ``(n, 3)`` and Jacobians ``(n, 3, 3)``: the family's own when it has
    ``axial_radial_meshing_jacobian``, else by one complex-step call."""
    a = family.scale_mm
    analytic = getattr(family, "axial_radial_meshing_jacobian", None)
    if analytic is not None:
        big_lq, big_rq, g, jac = analytic(q, flank)
        jac = jac * np.array([1.0 / a, 1.0 / a, 1.0])[:, None]
        return np.stack([(big_lq - big_l) / a, (big_rq - big_r) / a, g], axis=-1), jac
    qs = np.repeat(q[None].astype(complex), 3, axis=0)
    for k in range(3):
        qs[k, :, k] += 1j * _H
    lc, rc, gc = family.axial_radial_meshing(qs, flank)
    res = np.stack([(lc - big_l) / a, (rc - big_r) / a, gc], axis=-1)  # (3 var, n, 3 eq)
    return res[0].real, np.moveaxis(res.imag / _H, 0, -1)


def _residual(family, q, flank, big_l, big_r):
    """Scaled residuals ``(n, 3)`` alone (a real evaluation: a fraction of the Jacobian's cost)."""
    big_lq, big_rq, g = family.axial_radial_meshing(q, flank)
    a = family.scale_mm
    return np.stack([(big_lq - big_l) / a, (big_rq - big_r) / a, g], axis=-1)


def _newton(family, q, flank, big_l, big_r, *, tol, max_iter, give_up=(3, 1e-6), chords=True):
    """Batched Newton-Shamanskii iteration with per-unknown step clipping.

    Each iteration makes a Newton step with a fresh Jacobian, then a chord step with the same
    Jacobian from a real evaluation of the residual (convergence of order three for the cost of
    little more than one complex-step evaluation). Returns ``(q, f, jac, converged, iters)``
    with ``jac`` evaluated at the final ``q``.

    ``give_up = (k, r)``: after k iterations a node whose scaled residual is still above r is
    not in Newton's quadratic range (it lies past the envelope's fold or needs a better start)
    and stops iterating; it is reported as not converged. ``chords=False``: plain Newton steps
    (a chord step with a Jacobian from across a jump of the tool's curvature can cycle).
    """
    own = getattr(family, "newton", None)
    if own is not None:
        done = own(
            q, flank, big_l, big_r, tol=tol, max_iter=max_iter, give_up=give_up, chords=chords
        )
        if done is not None:
            return done
    limit = np.asarray(family.max_step, float)
    active = np.ones(len(q), bool)
    f, jac = _residual_and_jacobian(family, q, flank, big_l, big_r)
    iterations = 0

    def clipped(step):
        scale = np.min(limit / np.maximum(np.abs(step), 1e-300), axis=1)
        return step * np.minimum(scale, 1.0)[:, None]

    while iterations < max_iter:
        norm = np.max(np.abs(f), axis=1)
        active = np.isfinite(norm) & (norm > tol) & active
        if iterations >= give_up[0]:
            active &= norm < give_up[1]
        if not active.any():
            break
        iterations += 1
        idx = np.flatnonzero(active)
        ja = jac[idx]
        ok = np.abs(np.linalg.det(ja)) > 1e-300
        active[idx[~ok]] = False
        idx, ja = idx[ok], ja[ok]
        step = clipped(np.linalg.solve(ja, -f[idx][..., None])[..., 0])
        q[idx] += step
        # chord step: same Jacobian, residual from a real evaluation
        fr = _residual(family, q[idx], flank[idx], big_l[idx], big_r[idx])
        far = (np.max(np.abs(fr), axis=1) > tol) & chords
        chord = clipped(np.linalg.solve(ja[far], -fr[far][..., None])[..., 0])
        q[idx[far]] += chord
        f[idx], jac[idx] = _residual_and_jacobian(
            family, q[idx], flank[idx], big_l[idx], big_r[idx]
        )
    norm = np.max(np.abs(f), axis=1)
    return q, f, jac, np.isfinite(norm) & (norm <= tol), iterations


def _predictor(family, jac, sg, cg):
    """d q / d h ``(n, 3)`` along the profile at fixed face position, from Jacobians ``jac``.

    The targets move by dL/dh = -sin(gamma), dR/dh = cos(gamma); J dq/dh = their change / A.
    """
    rhs = np.empty(jac.shape[:-1])  # contiguous: numpy's solve copies a broadcast one slowly
    rhs[...] = np.array([-sg, cg, 0.0]) / family.scale_mm
    return np.linalg.solve(jac, rhs[..., None])[..., 0]


def solve_envelope(
    family: GeneratingFamily,
    *,
    cone_distances_mm: tuple[float, float],
    heights_mm: tuple[float, float],
    pitch_angle_rad: float,
    grid: FlankGrid,
    taper: DepthTaper | None = None,
    tol: float = 1e-14,
    max_iter: int = 8,
    fold_trim_mm: float = 0.3,
    where: str = "flank",
) -> EnvelopeSolution:
    """Solve the envelope at every node of ``grid`` for every flank of ``family``.

    Parameters
    ----------
    family
        The generating family.
    cone_distances_mm
        ``(toe, heel)`` cone distances of the grid's face range.
    heights_mm
        ``(root, top)`` heights above the pitch cone (root negative) of its profile range
        (with ``taper``: of the profile coordinate t, i.e. at the taper's pivot).
    pitch_angle_rad
        Pitch angle gamma.
    taper
        Tapered depth: node (s_i, t_j) lies at the height ``taper.height_mm(s_i, t_j)``, so
        the grid spans root cone to face cone in every column (None: uniform depth, h = t).
    tol
        Convergence tolerance on every scaled residual.
    fold_trim_mm
        Nodes less than this above a column's first folded or failed node are not generated.
    where
        Name used in errors.

    Raises
    ------
    SettingsError
        When Newton fails on the pitch line (the settings generate no flank there).
    """
    nodes = grid_nodes(cone_distances_mm, heights_mm, pitch_angle_rad, grid, taper, family.n_flanks)
    s, h, height, flank = nodes.face_mm, nodes.profile_mm, nodes.height_mm, nodes.flank
    big_l, big_r, row_l, row_r = nodes.big_l, nodes.big_r, nodes.row_l, nodes.row_r
    k, (n_f, n_p), (cg, sg) = family.n_flanks, grid.shape, nodes.cos_sin
    # the pitch line (h = 0) from the model's start there (often exact: no iteration)
    row_flank = nodes.row_flank.copy()
    q0, _, jac0, ok, iterations = _newton(
        family,
        np.array(family.pitch_row(s), float).reshape(-1, 3),
        row_flank,
        row_l,
        row_r,
        tol=tol,
        max_iter=2 * max_iter,
    )
    if not ok.all():
        bad = int(np.flatnonzero(~ok)[0])
        raise SettingsError(
            where,
            rule=f"no envelope on the pitch line of flank {bad // n_f} at cone distance "
            f"{s[bad % n_f]:.3f} mm (Newton did not converge): the machine settings do not "
            "generate this flank",
        )
    sign0 = det_signs(jac0).reshape(k, n_f)
    # every node at once from a second-order predictor along the profile (the curvature of
    # q(h) by a difference of the first-order predictor over a short step eps)
    dq_dh = _predictor(family, jac0, sg, cg)
    eps = 0.05
    jac1 = _residual_and_jacobian(
        family, q0 + eps * dq_dh, row_flank, row_l - eps * sg, row_r + eps * cg
    )[1]
    d2q_dh2 = (_predictor(family, jac1, sg, cg) - dq_dh) / eps
    q0, dq_dh, d2q_dh2 = (a.reshape(k, n_f, 1, 3) for a in (q0, dq_dh, d2q_dh2))
    hh = height[None, :, :, None]
    q = q0 + hh * dq_dh + 0.5 * hh**2 * d2q_dh2
    q, res, jac, converged, it = _newton(
        family,
        q.reshape(-1, 3),
        flank.ravel(),
        big_l.ravel(),
        big_r.ravel(),
        tol=tol,
        max_iter=max_iter,
    )
    iterations = max(iterations, it)
    shape = (k, n_f, n_p)
    # contiguous (the repair writes through flat views of them)
    q, res = (
        np.ascontiguousarray(q.reshape(*shape, 3)),
        np.ascontiguousarray(res.reshape(*shape, 3)),
    )
    jac, converged = np.ascontiguousarray(jac.reshape(*shape, 3, 3)), converged.reshape(shape)
    # repair: a node that failed next to a good node (toward the pitch row) restarts from it;
    # one pass recovers what the predictor missed (past the fold, a second finds nothing)
    det = det_signs(jac)  # (the determinants' signs: all the solver reads of them)
    good = converged & (det == sign0[..., None])
    neighbour = nodes.neighbour
    retry = ~converged & good[..., neighbour]
    if retry.any():  # (flat node indices into the contiguous arrays, their neighbours')
        node = np.flatnonzero(retry)
        fk, column = np.divmod(node, n_f * n_p)
        pj = node % n_p
        step = neighbour[pj] - pj
        dq = _predictor(family, jac.reshape(-1, 3, 3)[node + step], sg, cg)
        hn = height.reshape(-1)
        qr, fr, jr, ok, it = _newton(
            family,
            q.reshape(-1, 3)[node + step] + (hn[column] - hn[column + step])[:, None] * dq,
            fk,
            big_l.reshape(-1)[node],
            big_r.reshape(-1)[node],
            tol=tol,
            max_iter=3,  # from a converged neighbour: converges at once, or lies past the fold
        )
        iterations = max(iterations, it)
        sel = node[ok]
        q.reshape(-1, 3)[sel], res.reshape(-1, 3)[sel] = qr[ok], fr[ok]
        jac.reshape(-1, 3, 3)[sel], converged.reshape(-1)[sel] = jr[ok], True
        det.reshape(-1)[sel] = det_signs(jr[ok])
    # on the sheet: connected to the pitch row through good nodes of the column; trimmed
    # fold_trim_mm above the first bad node below the pitch row, column by column
    unfolded, connected, trimmed, top = sheet_nodes(converged, det, sign0, nodes, fold_trim_mm)
    within = np.asarray(family.within_tool(q, flank), bool)
    # the generated boundary, continuous: the fold solved, trimmed by fold_trim_mm
    fold = _fold_profiles(family, q, top, sign0, s, h, (cg, sg), taper, tol)
    limit = fold + fold_trim_mm  # -inf without a fold
    above = h[None, None, :] >= limit[..., None]
    lowest = _lowest_profiles(
        family,
        q,
        h,
        connected & above,
        connected & above & within,
        limit,
        (s, (cg, sg), taper, tol),
    )
    return EnvelopeSolution(
        face_mm=s.copy(),  # (writable, not the shared grid's)
        profile_mm=h.copy(),
        pitch_angle_rad=pitch_angle_rad,
        q=q,
        residual=res,
        converged=converged,
        unfolded=unfolded,
        within_tool=within,
        mask=connected & trimmed & within,
        sheet=connected,
        iterations=iterations,
        taper=taper,
        lowest_profile_mm=lowest,
    )


def _bisected(
    family, q_up, fk, fi, lo, up, accept, s, cos_sin, taper, tol, *, sheet=None
) -> NDArray:
    """The profile coordinates ``(m,)`` where ``accept(q, jac, flank)`` ends between ``lo``
    (not accepted) and ``up`` (accepted, parameters ``q_up``) on face columns ``fi`` of flanks
    ``fk``: :data:`FOLD_BISECTIONS` bisections, each Newton solve started from the last
    accepted point; the last accepted coordinate. ``accept`` is the Jacobian's sign ``sheet``
    when given, else :meth:`GeneratingFamily.within_tool` (a family's compiled ``bisect``
    does the same)."""
    own = getattr(family, "bisect", None)
    if own is not None and taper is None:
        done = own(
            q_up,
            fk,
            s[fi],
            lo,
            up,
            cos_sin=cos_sin,
            tol=tol,
            bisections=FOLD_BISECTIONS,
            sheet=sheet,
        )
        if done is not None:
            return done
    q_up = np.array(q_up, float)
    cg, sg = cos_sin
    for _ in range(FOLD_BISECTIONS):
        mid = 0.5 * (lo + up)
        hm = mid if taper is None else taper.height_mm(s[fi], mid)
        big_l, big_r = s[fi] * cg - hm * sg, s[fi] * sg + hm * cg
        qm, _, jac, ok, _ = _newton(family, q_up.copy(), fk, big_l, big_r, tol=tol, max_iter=8)
        ok &= accept(qm, jac, fk)
        up, q_up[ok] = np.where(ok, mid, up), qm[ok]
        lo = np.where(ok, lo, mid)
    return up


def _fold_profiles(family, q, top, sign0, s, h, cos_sin, taper, tol) -> NDArray:
    """``(k, n_f)`` the profile coordinate of each column's fold: the lowest point of the
    envelope's sheet through the pitch row, between the first node below the pitch row off
    it (folded, or Newton failed) and the node above it (:func:`_bisected`: Newton converges
    with the meshing Jacobian's sign unchanged); -inf where the column has no such node
    (``top`` ``(k, n_f)``: the highest node below the pitch row off the sheet, -1 none)."""
    fold = np.full(top.shape, -np.inf)
    fk, fi = np.nonzero(top >= 0)
    if not fk.size:
        return fold
    jb = top[fk, fi]
    sheet = sign0[fk, fi]

    def on_sheet(qm, jac, flank):
        return np.sign(np.linalg.det(jac)) == sheet

    fold[fk, fi] = _bisected(
        family,
        q[fk, fi, jb + 1],
        fk,
        fi,
        h[jb],
        h[jb + 1],
        on_sheet,
        s,
        cos_sin,
        taper,
        tol,
        sheet=sheet,
    )
    return fold


def _lowest_profiles(family, q, h, trimmed, mask, limit, solve) -> NDArray:
    """``(k, n_f)`` the lowest generated profile coordinate of each column: the fold's trim
    ``limit``, or where the tool's reach ends the column higher (its lowest trimmed node not
    generated), the blade tip's line between its lowest generated node and the one below
    (:func:`_bisected` on :meth:`GeneratingFamily.within_tool`; ``solve`` its other
    arguments); the lowest node where neither ends it on the grid; +inf without generated
    nodes."""
    n_p = len(h)
    first = np.where(trimmed.any(axis=-1), np.argmax(trimmed, axis=-1), n_p)
    low = np.where(mask.any(axis=-1), np.argmax(mask, axis=-1), n_p)
    out = np.where(low < n_p, h[np.minimum(low, n_p - 1)], np.inf)
    out = np.where(np.isfinite(limit) & (low == first), limit, out)
    fk, fi = np.nonzero((low > first) & (low < n_p))
    if fk.size:
        jl = low[fk, fi]

        def within(qm, jac, flank):
            return np.asarray(family.within_tool(qm, flank), bool)

        out[fk, fi] = _bisected(family, q[fk, fi, jl], fk, fi, h[jl - 1], h[jl], within, *solve)
    return out


@dataclass(frozen=True, kw_only=True, eq=False)
class EnvelopeSurface:
    """The generated flank itself, beyond its grid: exact points and the tool that cut it.

    A FlankMap keeps one (``FlankMap.surface``) so that checks and refinements can go back to
    the envelope: :meth:`points_at` solves the envelope at any (face, profile) point, starting
    from the grid's parameters; :meth:`tool_points` samples the tool's cutting edges over the
    positions that generated the flank. Both in the FlankMap's frame: the generated right-hand
    flank, then Theta -> ``sign`` Theta + ``offset`` (mirror and turns of the FlankMap).
    """

    family: GeneratingFamily
    index: int
    pitch_angle_rad: float
    face_mm: NDArray
    profile_mm: NDArray
    q: NDArray = field(repr=False)
    mask: NDArray = field(repr=False)
    sign: float = 1.0
    offset_rad: float = 0.0
    tol: float = 1e-14
    taper: DepthTaper | None = None

    def transformed(self, *, sign: float = 1.0, offset_rad: float = 0.0) -> EnvelopeSurface:
        """The surface after Theta -> sign Theta + offset_rad."""
        return replace(self, sign=sign * self.sign, offset_rad=sign * self.offset_rad + offset_rad)

    def _to_frame(self, point: NDArray) -> NDArray:
        c, s = math.cos(self.offset_rad), math.sin(self.offset_rad)
        x, y, z = point[..., 0], self.sign * point[..., 1], point[..., 2]
        return np.stack([c * x - s * y, s * x + c * y, z], axis=-1)

    def _axial_plane(self, face_mm, profile_mm):
        """``(L, R)`` of grid coordinates (the profile coordinate t made the height first on
        tapered depth)."""
        h = profile_mm if self.taper is None else self.taper.height_mm(face_mm, profile_mm)
        return axial_plane(face_mm, h, self.pitch_angle_rad)

    def parameters_at(self, face_mm, profile_mm) -> NDArray:
        """``(..., 3)`` generation parameters at grid coordinates, by Newton from the grid."""
        s, h = np.broadcast_arrays(np.asarray(face_mm, float), np.asarray(profile_mm, float))
        start = bilinear(self.face_mm, self.profile_mm, self.q, s.ravel(), h.ravel())
        flank = np.full(s.size, self.index)
        q, _, jac, ok, _ = _newton(
            self.family,
            start,
            flank,
            *self._axial_plane(s.ravel(), h.ravel()),
            tol=self.tol,
            max_iter=30,
            give_up=(30, np.inf),
        )
        if not ok.all() and ok.any():  # a tool whose edge changes curvature (a blade's tip
            # fillet, say) can stall Newton from the grid's start: from a converged neighbour
            self._from_neighbours(s.ravel(), h.ravel(), q, jac, ok)
        if not ok.all():  # else continuation from the nearest generated node
            bad = np.flatnonzero(~ok)
            q[bad], ok[bad] = self._continued(s.ravel()[bad], h.ravel()[bad])
        if not ok.all():
            raise GearoptError(
                "EnvelopeSurface.parameters_at",
                rule="Newton did not converge at "
                f"{int((~ok).sum())} of {len(ok)} points (outside the generated flank?)",
            )
        return q.reshape(*s.shape, 3)

    def _from_neighbours(self, face_mm, profile_mm, q, jac, ok, reach: float = 0.5) -> None:
        """Solve the points not ``ok`` again by plain Newton from the nearest converged point
        of the same call no farther from the pitch line, where one lies within ``reach`` grid
        cells (the next level of :mod:`gearopt.contact.boundary`'s fine cells), moved by the
        first-order predictor of its Jacobian; accepted on that point's sheet (the
        Jacobian's sign: not past a fold). ``q``, ``jac``, ``ok`` ``(n, ...)`` in place: the
        16-step continuation (:meth:`_continued`, a millisecond) only where this fails."""
        ds = float(np.ptp(self.face_mm)) / max(len(self.face_mm) - 1, 1)
        dh = float(np.ptp(self.profile_mm)) / max(len(self.profile_mm) - 1, 1)
        # only from points no farther from the pitch line (as the solver's repair)
        bad, from_ = nearest_start(face_mm, profile_mm, ok, ds, dh, reach)
        if not bad.size:
            return
        flank = np.full(bad.size, self.index)
        big_l, big_r = self._axial_plane(face_mm[bad], profile_mm[bad])
        l0, r0 = self._axial_plane(face_mm[from_], profile_mm[from_])
        a = self.family.scale_mm
        rhs = np.stack([(big_l - l0) / a, (big_r - r0) / a, np.zeros(bad.size)], axis=-1)
        start = q[from_] + np.linalg.solve(jac[from_], rhs[..., None])[..., 0]
        qn, _, jn, conv, _ = _newton(
            self.family,
            start,
            flank,
            big_l,
            big_r,
            tol=self.tol,
            max_iter=30,
            give_up=(30, np.inf),
            chords=False,
        )
        conv &= np.sign(np.linalg.det(jn)) == np.sign(np.linalg.det(jac[from_]))
        q[bad[conv]], jac[bad[conv]], ok[bad[conv]] = qn[conv], jn[conv], True

    def _continued(self, face_mm: NDArray, profile_mm: NDArray, steps: int = 16, tries: int = 4):
        """Parameters ``(n, 3)`` and convergence ``(n,)`` at grid coordinates, by plain Newton
        along the straight path (in grid coordinates) from a generated node, in ``steps`` steps
        (each from the previous solution): from the nearest node, then from the next nearest
        (``tries`` in all) where the path crossed a fold. A solution is accepted on the node's
        sheet only (its Jacobian's sign unchanged: not past a fold of the envelope)."""
        n = len(face_mm)
        q_out, ok = np.zeros((n, 3)), np.zeros(n, bool)
        nodes = np.argwhere(self.mask)
        if not len(nodes):
            return q_out, ok
        ds = float(np.ptp(self.face_mm)) / max(len(self.face_mm) - 1, 1)
        dh = float(np.ptp(self.profile_mm)) / max(len(self.profile_mm) - 1, 1)
        gap_s = (self.face_mm[nodes[:, 0]][None, :] - face_mm[:, None]) / ds
        gap_h = (self.profile_mm[nodes[:, 1]][None, :] - profile_mm[:, None]) / dh
        order = np.argsort(gap_s**2 + gap_h**2, axis=1, kind="stable")
        for attempt in range(min(tries, len(nodes))):
            todo = np.flatnonzero(~ok)
            if not len(todo):
                break
            near = nodes[order[todo, attempt]]
            s0, t0 = self.face_mm[near[:, 0]], self.profile_mm[near[:, 1]]
            q = self.q[near[:, 0], near[:, 1]].astype(float)
            flank = np.full(len(q), self.index)
            _, jac = _residual_and_jacobian(self.family, q, flank, *self._axial_plane(s0, t0))
            sheet = np.sign(np.linalg.det(jac))  # the generated node's side of any fold
            for k in range(1, steps + 1):
                w = k / steps
                sk = s0 + w * (face_mm[todo] - s0)
                tk = t0 + w * (profile_mm[todo] - t0)
                q, _, jac, conv, _ = _newton(
                    self.family,
                    q,
                    flank,
                    *self._axial_plane(sk, tk),
                    tol=self.tol,
                    max_iter=30,
                    give_up=(30, np.inf),
                    chords=False,
                )
            conv &= np.sign(np.linalg.det(jac)) == sheet  # not past a fold
            q_out[todo[conv]], ok[todo[conv]] = q[conv], True
        return q_out, ok

    def generated_at(self, face_mm, profile_mm) -> NDArray:
        """``(...)`` True where the tool generates the flank point at grid coordinates: the
        blade reaches it (above its tip, :meth:`GeneratingFamily.within_tool`) and it lies on
        the envelope's sheet through the pitch line (the meshing Jacobian's sign there), not
        past the envelope's fold. (The FlankMap's mask keeps 0.3 mm clear of the fold too.)"""
        q = self.parameters_at(face_mm, profile_mm)
        shape = q.shape[:-1]
        s, h = (np.broadcast_to(np.asarray(v, float), shape).ravel() for v in (face_mm, profile_mm))
        pitch = self.parameters_at(s, np.zeros_like(s)).reshape(-1, 3)
        flank = np.full(len(s), self.index)
        q = q.reshape(-1, 3)
        _, jac = _residual_and_jacobian(self.family, q, flank, *self._axial_plane(s, h))
        _, jac0 = _residual_and_jacobian(
            self.family, pitch, flank, *self._axial_plane(s, np.zeros_like(s))
        )
        same_sheet = np.sign(np.linalg.det(jac)) == np.sign(np.linalg.det(jac0))
        return (self.family.within_tool(q, flank) & same_sheet).reshape(shape)

    def points_at(self, face_mm, profile_mm) -> NDArray:
        """``(..., 3)`` exact flank points at grid coordinates, in the FlankMap's frame."""
        return self.geometry_at(face_mm, profile_mm)["point"]

    def geometry_at(self, face_mm, profile_mm) -> dict[str, NDArray]:
        """Exact ``point`` and unit ``normal`` ``(..., 3)`` at grid coordinates, in the
        FlankMap's frame (the normal out of the tooth material)."""
        q = self.parameters_at(face_mm, profile_mm)
        geo = self.family.geometry(q, np.full(q.shape[:-1], self.index))
        return {key: self._to_frame(geo[key]) for key in ("point", "normal")}

    def tool_points(self, count: int = 9) -> NDArray:
        """Cutting-edge points near the flank ``(n, 3, count, 3)``: from the tool position and
        edge point that generated each generated node, each parameter in turn moved over
        ``count`` values within a quarter of the range it spans on the flank (other roll and
        tool positions, other points of the edge). An envelope touches all of them from the
        tooth space."""
        q = self.q[self.mask]
        span = 0.25 * (q.max(axis=0) - q.min(axis=0))
        delta = np.linspace(-1.0, 1.0, count)[None, :, None] * (np.eye(3) * span)[:, None, :]
        moved = q[:, None, None, :] + delta[None]
        geo = self.family.geometry(moved, np.full(moved.shape[:-1], self.index))
        return self._to_frame(geo["point"])


def extended_geometry(family: GeneratingFamily, solution: EnvelopeSolution, indices=None):
    """``(polar, point, normal)`` ``(m, n_f, n_p[, 3])`` of flanks ``indices`` (None: all) of a
    solution as generated, for :func:`flank_map`, in one batch: the polar angle unwrapped along
    the face and extended below the sheet (:func:`gearopt.flank.extended_below`), the points
    off the flank moved onto that extended surface (finite, smooth for the spline)."""
    k = slice(None) if indices is None else np.asarray(indices)
    flank = np.arange(solution.q.shape[0])[k]
    geo = family.geometry(solution.q[k], flank[:, None, None])
    point, normal = geo["point"], geo["normal"]
    polar = unwrapped_along_face(np.arctan2(point[..., 1], point[..., 0]))
    polar = extended_below(polar, solution.sheet[k])
    point, off = np.array(point, float), ~solution.mask[k]
    radius = np.hypot(point[..., 0][off], point[..., 1][off])
    point[off, 0], point[off, 1] = radius * np.cos(polar[off]), radius * np.sin(polar[off])
    return polar, point, normal


def require_flank(solution: EnvelopeSolution, index: int, *, member: str, flank: str) -> None:
    """A :class:`SettingsError` when flank ``index`` of a solution has fewer than 4 generated
    nodes (the settings generate (almost) nothing of it)."""
    if solution.mask[index].sum() < 4:
        raise SettingsError(
            f"{member} {flank} flank", rule="the settings generate (almost) nothing of this flank"
        )


def flank_map(
    family: GeneratingFamily,
    solution: EnvelopeSolution,
    *,
    index: int = 0,
    member: str,
    flank: str,
    hand: str,
    teeth: int,
    turn_rad: float = 0.0,
    notes: tuple[str, ...] = (),
    tooth: int = 0,
    geometry: tuple[NDArray, NDArray, NDArray] | None = None,
) -> FlankMap:
    """FlankMap of flank ``index`` of a solution: right-hand as generated, turned by
    ``turn_rad`` about the member axis, then mirrored if ``hand`` is left (as
    :meth:`FlankMap.rotated` and :meth:`FlankMap.mirrored` would, the map made once);
    ``tooth``: the index of the tooth it is on. ``geometry``: :func:`extended_geometry` of
    the solution when the caller has it (made once for all flanks), else made here."""
    q, mask = solution.q[index], solution.mask[index]
    found = geometry or extended_geometry(family, solution, (index,))
    polar, point, normal = (a[0 if geometry is None else index] for a in found)
    # the surface's frame: EnvelopeSurface.transformed's arithmetic, the surface made once
    sign, offset_rad = 1.0, 0.0
    if turn_rad:
        polar, point, normal = turned(polar, point, normal, turn_rad)
        sign, offset_rad = 1.0 * sign, 1.0 * offset_rad + turn_rad
    if hand == "left":
        polar, point, normal = mirror_image(polar, point, normal)
        sign, offset_rad = -1.0 * sign, -1.0 * offset_rad + 0.0
    surface = EnvelopeSurface(
        family=family,
        index=index,
        pitch_angle_rad=solution.pitch_angle_rad,
        face_mm=solution.face_mm,
        profile_mm=solution.profile_mm,
        q=q,
        mask=mask,
        sign=sign,
        offset_rad=offset_rad,
        taper=solution.taper,
    )
    return FlankMap(
        member=member,
        flank=flank,
        hand="left" if hand == "left" else "right",
        teeth=teeth,
        tooth=tooth,
        pitch_angle_deg=math.degrees(solution.pitch_angle_rad),
        face_mm=solution.face_mm,
        profile_mm=solution.profile_mm,
        polar_angle_rad=polar,
        points_mm=point,
        normals=normal,
        residual=np.abs(solution.residual[index, ..., 2]),
        mask=mask,
        parameters=q,
        notes=notes,
        surface=surface,
        taper=solution.taper,
        lowest_profile_mm=(
            None if solution.lowest_profile_mm is None else solution.lowest_profile_mm[index]
        ),
    )
