"""Load distribution at one mesh position: a linear complementarity problem (LCP).

The candidate contact patches (of one or several tooth pairs) have initial separations ``s_i``
(mm, from the unloaded clearance field), areas ``A_i`` (mm^2) and lever arms ``r_i`` (mm, the
moment about the gear axis of a unit normal force at the patch). The gear, loaded by the torque
``T`` (N mm), turns by ``theta`` (rad) further than unloaded (its rotation lag, the loaded
transmission error contribution), which closes patch ``i`` rigidly by ``r_i theta``; the patch
forces ``F_i`` (N) deform the bodies by ``(C F)_i`` with the total compliance ``C`` (mm/N:
tooth bending from FE plus the local half-space part, :mod:`gearopt.loaded.halfspace`). The
conditions (Conry & Seireg 1971, 1973) are::

    gap_i = s_i + (C F)_i - r_i theta >= 0,   F_i >= 0,   gap_i F_i = 0,   sum_i r_i F_i = T.

They are the Karush-Kuhn-Tucker conditions of the convex quadratic programme

    minimise  1/2 F^T C F + s^T F   subject to   F >= 0,   r^T F = T,

with ``theta`` the multiplier of the moment equation and ``gap`` the multipliers of ``F >= 0``
(the principle of minimum complementary energy of Kalker's variational contact theory: Kalker
& van Randen 1972; Kalker, *Three-dimensional elastic bodies in rolling contact*, 1990).

Method: a primal active-set method, Lawson & Hanson's NNLS algorithm (*Solving Least Squares
Problems*, 1974, ch. 23) carried over to this programme. The support ``P`` (patches in contact)
starts as the patch that closes first, ``argmin s_i / r_i``, carrying all the load, or as the
support of a warm start (any forces ``>= 0`` scaled to the torque, e.g. the previous torque's
of a sweep: a feasible point; while the solution on its support has tensile forces, they are
all dropped at once, the rest scaled to the torque, a feasible point again, before the steps
below). On ``P``
the equations hold with equality: ``C_PP F_P - r_P theta = -s_P``, ``r_P^T F_P = T``, solved by
Cholesky of ``C_PP`` and the Schur complement ``theta = (T + r^T C^-1 s) / (r^T C^-1 r)``. Each
outer iteration adds patches outside ``P`` whose gap is negative (interpenetration): the most
penetrating ones, at most ``max(32, |P| / 2)`` at a time (the support grows geometrically and
the columns of ``C`` the method touches stay near the final support); of those, the ones that
would take a tensile force are taken out again at once, and when none remain the single most
penetrating patch is added (Lawson-Hanson's rule, for which the new force is provably
positive). The method only ever reads the columns ``C[:, P]`` of the patches it has tried
(:func:`solve_load_columns` requests them as needed). Patches of ``P`` that would go tensile
are dropped with the
Lawson-Hanson step back along the segment to the new solution, which keeps every force
non-negative and the moment equation exact. The objective strictly decreases from one support
to the next, so no support repeats and the method ends in finitely many steps with the exact
solution (up to round-off) when ``C`` is positive definite. A singular block ``C_PP`` (a
semidefinite ``C``, e.g. bending alone) is solved by the null-space method; when the
subproblem is then unbounded (a direction of zero compliance along which the objective falls)
the step follows that direction until a force reaches 0, as the step back does. The result is
the exact, penalty-free solution that Conry & Seireg obtained with a modified simplex method.
A patch that, added alone, takes no load although its gap is below ``-tolerance_mm`` (round-off
only) is left out; the residuals report what remains.

``T = 0`` gives the unloaded contact: no force, ``theta = min_i s_i / r_i`` (the least gap 0).

References
----------
Conry, T. F., Seireg, A. (1971). A mathematical programming method for design of elastic
bodies in contact. *J. Appl. Mech.* 38(2), 387-392.
Conry, T. F., Seireg, A. (1973). A mathematical programming technique for the evaluation of
load distribution and optimal modifications for gear systems. *J. Eng. Ind.* 95(4), 1115-1122.
Kalker, J. J., van Randen, Y. (1972). A minimum principle for frictionless elastic contact with
application to non-Hertzian half-space contact problems. *J. Eng. Math.* 6(2), 193-206.
Lawson, C. L., Hanson, R. J. (1974). *Solving Least Squares Problems*. Prentice-Hall.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg

from gearopt.errors import GearoptError
from gearopt.loaded import lcp_kernels
from gearopt.loaded.patch_compliance import PatchCompliance, with_room

__all__ = [
    "ColumnCache",
    "ComplementarityResiduals",
    "LoadDistribution",
    "solve_load_columns",
    "solve_load_distribution",
    "solve_load_patches",
]

_POTRF, _POTRS = scipy.linalg.get_lapack_funcs(("potrf", "potrs"), (np.zeros(1),))

#: relative tolerance of the symmetry and semidefiniteness checks of the compliance
COMPLIANCE_RTOL = 1e-8
#: a compliance block whose Cholesky pivots fall below this fraction of its largest diagonal
#: entry, or whose reduced eigenvalues below this fraction of the largest, counts as singular
SINGULAR_RTOL = 1e-10
#: the block addition takes at most the ``max(_BLOCK_LEAST, _BLOCK_SHARE |P|)`` most
#: penetrating patches at a time (module docstring)
_BLOCK_LEAST = 32
_BLOCK_SHARE = 0.5


@dataclass(frozen=True, kw_only=True)
class ComplementarityResiduals:
    """How well a :class:`LoadDistribution` meets its conditions (all 0 for an exact solution).

    Attributes
    ----------
    moment_n_mm
        ``|sum_i r_i F_i - T|`` (N mm).
    moment_relative
        ``moment_n_mm / T`` (``moment_n_mm`` when ``T = 0``).
    penetration_mm
        ``max(0, -min_i gap_i)``: the deepest interpenetration (mm).
    tensile_force_n
        ``max(0, -min_i F_i)``: the largest tensile (negative) force (N).
    complementarity_n_mm
        ``max_i |gap_i F_i|`` (N mm).
    contact_gap_mm
        ``max |gap_i|`` over the active set, where the gap equation is enforced (mm).
    """

    moment_n_mm: float
    moment_relative: float
    penetration_mm: float
    tensile_force_n: float
    complementarity_n_mm: float
    contact_gap_mm: float


@dataclass(frozen=True, kw_only=True)
class LoadDistribution:
    """The solution of the contact LCP at one mesh position (module docstring).

    Attributes
    ----------
    forces_n
        Normal force of each patch ``F_i >= 0`` (N), shape ``(n,)``.
    pressure_mpa
        ``F_i / A_i`` (MPa).
    theta_rad
        The gear's loaded rotation lag ``theta`` (rad): the rigid approach at patch ``i`` is
        ``r_i theta``. With ``r_i = 1`` it is the rigid approach itself (mm).
    gaps_mm
        ``s_i + (C F)_i - r_i theta`` (mm): 0 (to round-off) on the active set, ``>= 0`` off it.
    active
        Indices of the active set (ascending): the patches on which the gap equation was
        enforced, those in contact. With ``T > 0`` their forces are positive; with ``T = 0``
        it is the patch (or patches) where the unloaded gap is least.
    iterations
        Outer iterations of the active-set method (0 when ``T = 0``).
    residuals
        :class:`ComplementarityResiduals` of the conditions.
    """

    forces_n: np.ndarray
    pressure_mpa: np.ndarray
    theta_rad: float
    gaps_mm: np.ndarray
    active: np.ndarray
    iterations: int
    residuals: ComplementarityResiduals


def _check_vectors(separation_mm, area_mm2, lever_arm_mm, torque_n_mm):
    s = np.asarray(separation_mm, dtype=float)
    if s.ndim != 1 or s.size == 0:
        raise GearoptError("separation_mm", s.shape, "must be a non-empty 1-D array (one a patch)")
    if not np.all(np.isfinite(s)):
        bad = int(np.flatnonzero(~np.isfinite(s))[0])
        raise GearoptError(f"separation_mm[{bad}]", float(s[bad]), "must be finite")
    n = s.size
    area = np.asarray(area_mm2, dtype=float)
    if area.shape != (n,):
        raise GearoptError("area_mm2", area.shape, f"must have the shape of separation_mm {(n,)}")
    if not np.all(np.isfinite(area) & (area > 0.0)):
        bad = int(np.flatnonzero(~(np.isfinite(area) & (area > 0.0)))[0])
        raise GearoptError(f"area_mm2[{bad}]", float(area[bad]), "must be positive and finite")
    r = np.asarray(lever_arm_mm, dtype=float)
    if r.shape != (n,):
        raise GearoptError("lever_arm_mm", r.shape, f"must have the shape of separation_mm {(n,)}")
    if not np.all(np.isfinite(r) & (r > 0.0)):
        bad = int(np.flatnonzero(~(np.isfinite(r) & (r > 0.0)))[0])
        raise GearoptError(
            f"lever_arm_mm[{bad}]",
            float(r[bad]),
            "must be positive and finite (a normal force on the loaded flank resists the torque)",
        )
    t = float(torque_n_mm)
    if not np.isfinite(t) or t < 0.0:
        raise GearoptError("torque_n_mm", t, "must be finite and >= 0")
    return s, area, r, t


def _check_inputs(separation_mm, area_mm2, compliance_mm_per_n, lever_arm_mm, torque_n_mm):
    s, area, r, t = _check_vectors(separation_mm, area_mm2, lever_arm_mm, torque_n_mm)
    n = s.size
    c = np.asarray(compliance_mm_per_n, dtype=float)
    if c.shape != (n, n):
        raise GearoptError("compliance_mm_per_n", c.shape, f"must be square of size {n}")
    if not np.all(np.isfinite(c)):
        raise GearoptError("compliance_mm_per_n", "non-finite entries", "must be finite")
    scale = float(np.max(np.abs(np.diag(c)))) if n else 0.0
    asym = float(np.max(np.abs(c - c.T)))
    if asym > COMPLIANCE_RTOL * max(scale, float(np.max(np.abs(c)))):
        raise GearoptError(
            "compliance_mm_per_n",
            f"max |C - C^T| = {asym:.3g}",
            f"must be symmetric (relative tolerance {COMPLIANCE_RTOL:g})",
        )
    c = 0.5 * (c + c.T)
    # positive semidefinite within tolerance <=> C + eps I is positive definite
    eps = COMPLIANCE_RTOL * scale
    try:
        if np.any(np.diag(c) < -eps):
            raise np.linalg.LinAlgError
        scipy.linalg.cholesky(c + (eps + np.finfo(float).tiny) * np.eye(n), check_finite=False)
    except np.linalg.LinAlgError:
        raise GearoptError(
            "compliance_mm_per_n",
            "indefinite",
            f"must be positive semidefinite (relative tolerance {COMPLIANCE_RTOL:g})",
        ) from None
    return s, area, c, r, t


def _check_start(start_forces_n, r, t):
    """The warm start scaled to the torque, ``F T / (r^T F)``, or None for no force at all."""
    f = np.asarray(start_forces_n, dtype=float)
    if f.shape != r.shape:
        raise GearoptError(
            "start_forces_n", f.shape, f"must have the shape of separation_mm {r.shape}"
        )
    if not np.all(np.isfinite(f) & (f >= 0.0)):
        bad = int(np.flatnonzero(~(np.isfinite(f) & (f >= 0.0)))[0])
        raise GearoptError(f"start_forces_n[{bad}]", float(f[bad]), "must be finite and >= 0")
    moment = float(r @ f)
    return f * (t / moment) if moment > 0.0 else None


class ColumnCache:
    """The compliance columns requested of a provider, each once and checked as fetched;
    :func:`solve_load_columns` makes one per solve, or takes one kept across the solves of
    one matrix (the torques of a sweep at one position).

    Column ``j`` of ``C`` is stored as row ``slot[j]`` of ``rows`` (``C`` is symmetric, so it is
    also row ``j`` of ``C``); ``requested`` counts the columns asked of the provider.
    """

    def __init__(self, provider, n):
        self.provider = provider
        self.n = n
        self.slot = np.full(n, -1, dtype=np.intp)
        self.rows = np.empty((min(n, 32), n))
        self.requested = 0

    def fetch(self, idx):
        """Request the columns ``idx`` not yet held."""
        missing = idx[self.slot[idx] < 0]
        m, k = missing.size, self.requested
        if m == 0:
            return
        block = np.asarray(self.provider(missing.copy()), dtype=float)
        if block.shape != (self.n, m):
            raise GearoptError(
                "columns",
                block.shape,
                f"must return C[:, idx], shape (n, len(idx)) = {(self.n, m)}",
            )
        if not np.all(np.isfinite(block)):
            raise GearoptError("columns", "non-finite entries", "must return finite compliances")
        diagonal = block[missing, np.arange(m)]
        if np.any(diagonal < -COMPLIANCE_RTOL * np.max(np.abs(block), axis=0)):
            bad = int(missing[np.argmin(diagonal)])
            raise GearoptError(
                f"columns C[{bad}, {bad}]",
                float(np.min(diagonal)),
                "must be >= 0 (a positive semidefinite compliance)",
            )
        # symmetry: against the columns held, C[held, new] (the new block) = C[new, held],
        # and among the new ones, each relative to the entries it compares
        held = np.flatnonzero(self.slot >= 0)
        own = block[missing]
        pairs = [(own - own.T, own)]
        if held.size:
            pairs.insert(0, (block[held] - self.rows[self.slot[held]][:, missing], block))
        for difference, scale in pairs:
            asym = float(np.max(np.abs(difference)))
            if asym > COMPLIANCE_RTOL * float(np.max(np.abs(scale))):
                raise GearoptError(
                    "columns",
                    f"max |C - C^T| = {asym:.3g}",
                    f"must be symmetric (relative tolerance {COMPLIANCE_RTOL:g})",
                )
        self.rows = with_room(self.rows, k, m)
        self.rows[k : k + m] = block.T
        self.slot[missing] = np.arange(k, k + m)
        self.requested = k + m

    def block(self, idx):
        """``C[np.ix_(idx, idx)]`` (symmetric: each column checked as it was fetched)."""
        self.fetch(idx)
        return self.rows[np.ix_(self.slot[idx], idx)]

    def times(self, idx, f):
        """``C[:, idx] @ f[idx]`` (the columns ``idx`` held)."""
        w = np.zeros(self.requested)
        w[self.slot[idx]] = f[idx]
        return w @ self.rows[: self.requested]


def _solve_on_support(c_pp, s, r, t, support):
    """The equality-constrained subproblem on the support ``P``, ``c_pp = C[np.ix_(P, P)]``.

    Returns ``(z, theta, direction)`` with ``z`` of length ``n`` (0 off ``P``). Bounded case
    (``direction`` None): ``C_PP z_P - r_P theta = -s_P``, ``r_P^T z_P = T``, by Cholesky of
    ``C_PP`` and the Schur complement ``theta = (T + r^T C^-1 s) / (r^T C^-1 r)``. When
    ``C_PP`` is singular (a pivot below :data:`SINGULAR_RTOL` of the largest), by the null-space
    method: ``z = r T / |r|^2 + Q y`` with ``Q`` an orthonormal basis of ``r^T d = 0``, ``y`` the
    least-norm minimiser of the reduced quadratic (its eigen-decomposition). Unbounded case
    (the reduced quadratic has a null direction with a slope): ``z`` and ``theta`` are None and
    ``direction`` (``C d = 0``, ``r^T d = 0``, ``s^T d < 0``) the steepest such direction.
    """
    n, k = s.size, support.size
    s_p, r_p = s[support], r[support]
    z = np.zeros(n)
    # LAPACK directly (scipy's wrappers cost more than a small factorisation): the lower
    # triangle of c_pp, r and s solved together
    low, info = _POTRF(c_pp, lower=1, clean=0)
    if info == 0 and np.min(np.diag(low)) ** 2 > SINGULAR_RTOL * np.max(np.diag(c_pp)):
        solved, _ = _POTRS(low, np.stack([r_p, s_p], axis=1), lower=1)
        cinv_r, cinv_s = solved[:, 0], solved[:, 1]
        theta = (t + r_p @ cinv_s) / (r_p @ cinv_r)
        z[support] = theta * cinv_r - cinv_s
        return z, float(theta), None
    c_pp = 0.5 * (c_pp + c_pp.T)
    # the null-space method on r^T z = T
    z0 = r_p * (t / (r_p @ r_p))
    q = np.linalg.qr(r_p[:, None], mode="complete")[0][:, 1:]
    gradient = q.T @ (c_pp @ z0 + s_p)
    values, vectors = np.linalg.eigh(q.T @ c_pp @ q)
    top = float(np.max(values)) if k > 1 else 0.0
    null = values <= SINGULAR_RTOL * top
    slope = vectors[:, null] @ (vectors[:, null].T @ gradient)
    scale = np.linalg.norm(q.T @ s_p) + np.linalg.norm(q.T @ (c_pp @ z0))
    if np.linalg.norm(slope) > 1e-8 * scale:
        direction = np.zeros(n)
        direction[support] = -(q @ slope)
        return None, None, direction
    keep = ~null
    y = -vectors[:, keep] @ ((vectors[:, keep].T @ gradient) / values[keep])
    z[support] = z0 + q @ y
    theta = r_p @ (c_pp @ z[support] + s_p) / (r_p @ r_p)
    return z, float(theta), None


def _solve_support(cols, s, r, t, support):
    return _solve_on_support(cols.block(support), s, r, t, support)


def _descend(cols, s, r, t, forces, in_p, solved):
    """Lawson-Hanson's inner loop from the feasible ``forces`` (``>= 0``, ``r^T F = T``) with
    the support ``in_p`` and ``solved``, the subproblem's answer on it: step towards the
    subproblem's solution (or along its descent direction when unbounded) as far as all forces
    stay >= 0, drop the ones reaching 0, solve again. Returns ``(forces, theta, in_p)``."""
    z, z_theta, direction = solved
    while True:
        p_idx = np.flatnonzero(in_p)
        if direction is None:
            neg = p_idx[z[p_idx] <= 0.0]
            if neg.size == 0:
                return z, z_theta, in_p
            step = z - forces
        else:
            step = direction
            neg = p_idx[direction[p_idx] < 0.0]
            if neg.size == 0:  # cannot happen for r > 0 (r^T d = 0): guard only
                raise GearoptError("columns", "semidefinite", "unbounded load distribution")
        ratio = forces[neg] / -step[neg]
        alpha = float(np.min(ratio))
        forces = forces + alpha * step
        forces[neg[ratio <= alpha]] = 0.0
        in_p = in_p & (forces > 0.0)
        forces[~in_p] = 0.0
        z, z_theta, direction = _solve_support(cols, s, r, t, np.flatnonzero(in_p))


def _warm_start(cols, s, r, t, start):
    """The first support from a warm start (feasible: ``>= 0``, ``r^T F = T``): solved on its
    support; while the solution has tensile forces, all of them are dropped at once and the
    rest, scaled to the torque, is the feasible point solved again (a support far larger than
    the contact shrinks in a few solves, where Lawson-Hanson's step back drops about one
    patch a solve); then the inner loop (:func:`_descend`) from the last feasible point.
    Returns ``(forces, theta, in_p)``."""
    forces, in_p = start, start > 0.0
    while True:
        solved = _solve_support(cols, s, r, t, np.flatnonzero(in_p))
        z, _, direction = solved
        if direction is not None or np.all(z[in_p] > 0.0):
            return _descend(cols, s, r, t, forces, in_p, solved)
        forces = np.where(in_p & (z > 0.0), z, 0.0)  # some z > 0: r > 0 and r^T z = T > 0
        forces *= t / (r @ forces)
        in_p = forces > 0.0


def solve_load_columns(
    *,
    separation_mm,
    area_mm2,
    lever_arm_mm,
    torque_n_mm: float,
    columns,
    start_forces_n=None,
    tolerance_mm: float = 1e-11,
    max_iterations: int | None = None,
) -> LoadDistribution:
    """Patch forces and rotation lag at one mesh position from compliance columns on demand.

    The LCP of the module docstring, solved by the same active-set method as
    :func:`solve_load_distribution`, which only ever needs the columns ``C[:, P]`` of the
    patches ``P`` it has tried in contact (for the gaps and the blocks ``C_PP``): a small
    contact among many candidate patches asks for a small part of ``C``.

    Parameters
    ----------
    separation_mm, area_mm2, lever_arm_mm, torque_n_mm
        As :func:`solve_load_distribution`.
    columns
        A :class:`ColumnCache` of ``C`` (kept across solves), or its provider
        ``columns(idx) -> C[:, idx]``: ``idx`` an ``intp`` array of patch indices (distinct,
        not in order), the result of shape ``(n, len(idx))``, the compliance (mm/N) of a
        symmetric positive semidefinite ``C``. Each column is requested once per solve (the
        solver keeps those it has); the provider may cache across solves. Only what is
        requested is checked: finite, symmetric blocks ``C_PP`` (relative tolerance
        :data:`COMPLIANCE_RTOL`), diagonal ``>= 0``; semidefiniteness of the whole of ``C``
        is not (an indefinite ``C`` gives an answer without guarantee).
    start_forces_n
        Optional warm start, shape ``(n,)``, finite, ``>= 0``: scaled to the torque
        (``F T / (r^T F)``), its support is the initial active set (e.g. the previous
        torque's forces of a sweep). Without it, or with no force at all (the forces of
        ``T = 0``), the patch that closes first carries the torque. Either start leads to the
        same solution, unique for a positive definite ``C``. Checked but not used when
        ``T = 0``.
    tolerance_mm, max_iterations
        As :func:`solve_load_distribution`.

    Returns
    -------
    LoadDistribution

    Raises
    ------
    gearopt.errors.GearoptError
        For bad vectors as :func:`solve_load_distribution`, a bad warm start, columns of the
        wrong shape, non-finite or not symmetric, or no convergence within
        ``max_iterations``.
    """
    s, area, r, t = _check_vectors(separation_mm, area_mm2, lever_arm_mm, torque_n_mm)
    if not (isinstance(columns, ColumnCache) or callable(columns)):
        raise GearoptError(
            "columns", type(columns).__name__, "must be callable: columns(idx) -> C[:, idx]"
        )
    start = None if start_forces_n is None else _check_start(start_forces_n, r, t)
    n = s.size
    closing = s / r  # the rotation at which each patch closes unloaded
    first = int(np.argmin(closing))
    iterations = 0
    if t == 0.0:
        theta = float(closing[first])
        gaps = r * (closing - theta)  # exactly 0 where the closing rotation is least
        support = np.flatnonzero(closing == closing[first])
        return _result(area, r, t, np.zeros(n), theta, gaps, support, iterations)

    cols = columns if isinstance(columns, ColumnCache) else ColumnCache(columns, n)
    if cols.n != n:
        raise GearoptError("columns", cols.n, f"must hold columns of {n} patches")
    if start is None:
        in_p = np.zeros(n, dtype=bool)
        in_p[first] = True
        forces = np.zeros(n)
        forces[first] = t / r[first]
        c_ff = cols.block(np.array([first]))[0, 0]
        theta = float((s[first] + c_ff * forces[first]) / r[first])
    else:
        forces, theta, in_p = _warm_start(cols, s, r, t, start)
    cap = 2 * n + 10 if max_iterations is None else int(max_iterations)
    stuck = np.zeros(n, dtype=bool)  # added alone yet not loaded: round-off at the tolerance
    while True:
        p_idx = np.flatnonzero(in_p)
        gaps = s + cols.times(p_idx, forces) - r * theta
        candidates = ~in_p & ~stuck & (gaps < -tolerance_mm)
        if not candidates.any():
            break
        if iterations >= cap:
            raise GearoptError(
                "columns",
                f"{n} patches",
                f"active set did not converge in {cap} iterations (ill-conditioned compliance?)",
            )
        iterations += 1
        new = np.flatnonzero(candidates)
        single = np.array([new[int(np.argmin(gaps[new]))]])  # Lawson-Hanson's choice
        limit = max(_BLOCK_LEAST, int(_BLOCK_SHARE * p_idx.size))
        if new.size > limit:
            new = np.sort(new[np.argsort(gaps[new], kind="stable")[:limit]])
        # block addition: take out again the new patches that would carry tension
        while True:
            z, z_theta, direction = _solve_support(cols, s, r, t, np.union1d(p_idx, new))
            if direction is not None:  # unbounded: only Lawson-Hanson's single patch
                if new.size == 1:
                    break
                new = single
                continue
            keep = z[new] > 0.0
            if keep.all() or (new.size == 1 and not keep.any()):
                break
            new = new[keep] if keep.any() else single
        if direction is None and z[new[0]] <= 0.0:  # single patch, unloaded: round-off
            stuck[new[0]] = True
            continue
        in_p[new] = True
        forces, theta, in_p = _descend(cols, s, r, t, forces, in_p, (z, z_theta, direction))
    support = np.flatnonzero(in_p)
    gaps = s + cols.times(support, forces) - r * theta
    return _result(area, r, t, forces, theta, gaps, support, iterations)


def solve_load_patches(
    *,
    separation_mm,
    area_mm2,
    lever_arm_mm,
    torque_n_mm: float,
    compliance: PatchCompliance,
    start_forces_n=None,
    tolerance_mm: float = 1e-11,
    max_iterations: int | None = None,
) -> LoadDistribution:
    """:func:`solve_load_columns` with the compliance of contact patches computed and the
    method run by compiled kernels (:mod:`gearopt.loaded.lcp_kernels`): the same solution,
    without an interpreter step per support. A singular block ``C_PP`` hands the problem to
    :func:`solve_load_columns` (its null-space branch), the columns computed so far kept.

    Parameters
    ----------
    separation_mm, area_mm2, lever_arm_mm, torque_n_mm, start_forces_n, tolerance_mm, max_iterations
        As :func:`solve_load_columns`.
    compliance
        :class:`PatchCompliance` of the patches (its columns are kept in it for the next
        solves).
    """
    s, area, r, t = _check_vectors(separation_mm, area_mm2, lever_arm_mm, torque_n_mm)
    if compliance.size != s.size:
        raise GearoptError("compliance", compliance.size, f"must hold {s.size} patches")
    start = None if start_forces_n is None else _check_start(start_forces_n, r, t)
    n = s.size
    if t == 0.0:
        return solve_load_columns(
            separation_mm=s, area_mm2=area, lever_arm_mm=r, torque_n_mm=t, columns=compliance
        )
    cap = 2 * n + 10 if max_iterations is None else int(max_iterations)
    forces, iterations = np.zeros(n) if start is None else start, 0
    while True:  # the kernel stops where it needs columns not held: computed, it goes on
        status, forces, theta, gaps, active, iterations, need = lcp_kernels.solve_patches(
            s,
            r,
            t,
            forces,
            float(tolerance_mm),
            cap,
            iterations,
            SINGULAR_RTOL,
            (float(_BLOCK_LEAST), _BLOCK_SHARE),
            compliance.rows,
            compliance.slot,
        )
        if status != 3:
            break
        compliance.fetch(need)
    if status == 1:
        return solve_load_columns(
            separation_mm=s,
            area_mm2=area,
            lever_arm_mm=r,
            torque_n_mm=t,
            columns=compliance,
            start_forces_n=start,
            tolerance_mm=tolerance_mm,
            max_iterations=max_iterations,
        )
    if status == 2:
        raise GearoptError(
            "columns",
            f"{n} patches",
            f"active set did not converge in {cap} iterations (ill-conditioned compliance?)",
        )
    return _result(area, r, t, forces, theta, gaps, np.flatnonzero(active), iterations)


def solve_load_distribution(
    *,
    separation_mm,
    area_mm2,
    compliance_mm_per_n,
    lever_arm_mm,
    torque_n_mm: float,
    tolerance_mm: float = 1e-11,
    max_iterations: int | None = None,
) -> LoadDistribution:
    """Patch forces and rotation lag at one mesh position (the LCP of the module docstring).

    Parameters
    ----------
    separation_mm
        Initial (unloaded) separations ``s_i`` of the ``n`` candidate patches (mm), usually
        ``>= 0`` with 0 at the unloaded contact; any finite values are accepted.
    area_mm2
        Patch areas ``A_i`` (mm^2), for the pressures only.
    compliance_mm_per_n
        Total compliance ``C`` (mm/N), ``(n, n)``, symmetric positive semidefinite (checked
        within the relative tolerance :data:`COMPLIANCE_RTOL`): ``C_ij`` the approach of the two
        flanks at patch ``i`` for a unit normal force at patch ``j``.
    lever_arm_mm
        ``r_i > 0`` (mm): the moment about the gear axis of a unit normal force at patch ``i``.
    torque_n_mm
        Gear torque ``T >= 0`` (N mm).
    tolerance_mm
        A patch off the active set counts as penetrating when its gap is below
        ``-tolerance_mm``.
    max_iterations
        Cap on outer iterations (default ``2 n + 10``; the method is finite, the cap guards
        against round-off cycling).

    Returns
    -------
    LoadDistribution

    Raises
    ------
    gearopt.errors.GearoptError
        For non-finite separations, negative or non-finite torque, areas or lever arms that are
        not positive, a compliance that is not symmetric positive semidefinite, shapes that
        disagree, or no convergence within ``max_iterations``.

    See Also
    --------
    solve_load_columns : the same solver on compliance columns requested as needed, which this
        function calls after checking the whole matrix.
    """
    s, area, c, r, t = _check_inputs(
        separation_mm, area_mm2, compliance_mm_per_n, lever_arm_mm, torque_n_mm
    )
    try:
        return solve_load_columns(
            separation_mm=s,
            area_mm2=area,
            lever_arm_mm=r,
            torque_n_mm=t,
            columns=lambda idx: c[:, idx],
            tolerance_mm=tolerance_mm,
            max_iterations=max_iterations,
        )
    except GearoptError as err:  # the columns are this compliance's
        if not err.parameter.startswith("columns"):
            raise
        raise GearoptError("compliance_mm_per_n", err.value, err.rule) from None


def _result(area, r, t, forces, theta, gaps, support, iterations) -> LoadDistribution:
    moment = abs(float(r @ forces) - t)
    residuals = ComplementarityResiduals(
        moment_n_mm=moment,
        moment_relative=moment / t if t > 0.0 else moment,
        penetration_mm=max(0.0, -float(np.min(gaps))),
        tensile_force_n=max(0.0, -float(np.min(forces))),
        complementarity_n_mm=float(np.max(np.abs(gaps * forces))),
        contact_gap_mm=float(np.max(np.abs(gaps[support]))) if support.size else 0.0,
    )
    for arr in (forces, gaps, support):
        arr.setflags(write=False)
    pressure = forces / area
    pressure.setflags(write=False)
    return LoadDistribution(
        forces_n=forces,
        pressure_mpa=pressure,
        theta_rad=float(theta),
        gaps_mm=gaps,
        active=support,
        iterations=iterations,
        residuals=residuals,
    )
