"""Tooth bending and shear compliance of one member by finite elements: influence numbers.

The loaded tooth contact analysis splits the approach of two flanks under load into the local
contact deformation (a half-space, Boussinesq, added by the contact solver) and the deflection
of the tooth as a body (bending, shear, the fillet and the rim), which this module computes once
per member with a small finite-element model and hands over as influence numbers: the normal
displacement of flank point i under a unit normal load at flank point j (mm/N).

Model
-----
One tooth with its fillets and a rim section, meshed by structured hexahedra with 27-node
triquadratic (Lagrange) elements: scikit-fem's :class:`skfem.MeshHex` from our own corner nodes
and connectivity (trilinear geometry) and :class:`skfem.ElementHex2` shape functions on 3 x 3 x 3
Gauss points; the stiffness is assembled here, vectorised over the elements (scikit-fem's generic
bilinear-form assembly costs about 8 ms per 81-dof element), and factorised by a block Cholesky
of the banded matrix (:func:`factorise`; scipy's SuperLU needed 26 ms per right-hand side).
Linear elements lock in bending: on a 40 x 10 x 10 mm cantilever under an end load Hex1 with
16 x 4 x 4 elements is 5.7 % stiffer than Timoshenko's beam, Hex2 with 8 x 2 x 2 2.2 % and with
16 x 4 x 4 1.75 % (the clamped end's restraint of the Poisson contraction; measured).

Nodes are placed by the coordinates (face s, profile t, thickness fraction w): the axial-plane
point of (s, t) (:func:`gearopt.flank.axial_plane`, the taper of a tapered-depth member applied)
turned to the polar angle interpolated linearly in w between the two sides of the tooth, each
side's Theta from its flank's local interpolant (:meth:`FlankMap.polar_angle_local`), so the FE
mesh density does not depend on the FlankMap grid. The face runs from the blank's inner to its
outer cone distance, the tooth from the root cone (-b_m) to the face cone (a_m). From the top
down:

- flank rows, from the top to ``t_low(s)``, a line in s at or above the lowest generated cells of
  the flank (each side its own line);
- fillet rows (at least two), from ``t_low(s)`` to the root cone: each side continues the flank
  tangentially (linear extrapolation of Theta) plus a parabolic widening, zero with zero slope at
  ``t_low``, that reaches the middle of the tooth space (the tooth's centre angle +- half a
  pitch) at the root: a full-round root whose shape is an approximation (the tool's edge radius
  and the true trochoidal fillet are not modelled);
- rim rows, from the root cone down by ``rim_depth_mm`` (default one mean normal module) and one
  angular pitch wide, the sector between the middles of the neighbouring tooth spaces.

Boundary conditions: the rim's bottom face and its two side faces (the cuts through the
neighbouring spaces' middles, from the root down) are fixed; the rest is free (top land, toe,
heel, both flanks and fillets). The neighbouring teeth are left out: their rim is replaced by the
fixed cuts, which makes the foundation stiffer than in a whole gear.

Local contact deformation
-------------------------
The contact solver adds the half-space (Boussinesq) compliance of the contact itself, so the
singular local response near the load must not be counted here. We follow Conry and Seireg: the
unit load is a point force on the flank's surface node, along the inward normal, and the
displacement is read on the tooth's mid-surface (w = 1/2), where the flank normal through the
loaded point pierces it (biquadratic interpolation of the mid-surface nodes), projected on that
normal. The local field of a point force decays like 1/r, so half a tooth thickness away the
reading carries the bending, shear, fillet and rim deflection of the tooth and is mesh-converged
(tested); what is left out besides the singular part is the compression of the half thickness
between flank and mid-surface. Load and reading points differ, so the FE readings are symmetric
only within a few % (:attr:`ToothCompliance.asymmetry`); the table handed over is their
symmetric part. It is not positive definite by itself (its smallest eigenvalues are about -0.2 %
of the largest, measured): the half-space part the contact solver adds makes the sum so.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import lru_cache

import numpy as np
from numpy.typing import NDArray
from scipy.linalg import LinAlgError, cholesky, solve_triangular
from scipy.sparse import coo_matrix, csc_matrix

from gearopt.blank import Blank
from gearopt.errors import GearoptError
from gearopt.flank import FLANKS, MEMBERS, FlankMap, axial_plane
from gearopt.jit import blas_threads
from gearopt.loaded import kernels

__all__ = [
    "DEFAULT_MESH",
    "Material",
    "SolidModel",
    "Factorised",
    "solid_model",
    "factorise",
    "ToothCompliance",
    "tooth_compliance",
    "member_compliance",
]

#: default tooth mesh: elements (along the face, over the tooth height, through the thickness)
DEFAULT_MESH = (12, 6, 3)

#: element corners in scikit-fem's MeshHex order (reference coordinates)
_CORNERS = np.array(
    [[0, 0, 0], [0, 0, 1], [0, 1, 0], [1, 0, 0], [0, 1, 1], [1, 0, 1], [1, 1, 0], [1, 1, 1]]
)
#: BLAS threads in the factorisation and the solves: the blocks (a few hundred rows) are too
#: small for threads to pay; on a shared 2-core machine multi-threaded OpenBLAS made the set-up
#: of both members of seed 001 section 5.3 about 12 s instead of 2 s (measured)
ONE_BLAS_THREAD = 1
#: Gauss order: 3 points per direction (the triquadratic stiffness exactly on parallelepipeds)
_INTORDER = 4


@dataclass(frozen=True, kw_only=True)
class Material:
    """Isotropic linear-elastic material.

    Parameters
    ----------
    youngs_modulus_mpa
        Young's modulus E (MPa = N/mm^2), steel 206000.
    poisson_ratio
        Poisson's ratio nu, in (0, 0.5).
    """

    youngs_modulus_mpa: float = 206000.0
    poisson_ratio: float = 0.3

    def __post_init__(self):
        e, nu = self.youngs_modulus_mpa, self.poisson_ratio
        if (
            isinstance(e, bool)
            or not isinstance(e, int | float)
            or not (math.isfinite(e) and e > 0)
        ):
            raise GearoptError("material.youngs_modulus_mpa", e, "must be a positive number")
        if isinstance(nu, bool) or not isinstance(nu, int | float) or not 0.0 < nu < 0.5:
            raise GearoptError("material.poisson_ratio", nu, "must lie in (0, 0.5)")
        object.__setattr__(self, "youngs_modulus_mpa", float(e))
        object.__setattr__(self, "poisson_ratio", float(nu))

    @property
    def shear_modulus_mpa(self) -> float:
        """G = E / (2 (1 + nu))."""
        return self.youngs_modulus_mpa / (2.0 * (1.0 + self.poisson_ratio))

    @property
    def lame_lambda_mpa(self) -> float:
        """Lame's first parameter E nu / ((1 + nu)(1 - 2 nu))."""
        nu = self.poisson_ratio
        return self.youngs_modulus_mpa * nu / ((1.0 + nu) * (1.0 - 2.0 * nu))


# --- the finite-element layer -------------------------------------------------------------


@dataclass(frozen=True, kw_only=True, eq=False)
class SolidModel:
    """A structured block of 27-node hexahedra and its stiffness matrix.

    Attributes
    ----------
    shape
        ``(n1, n2, n3)`` elements along the block's three index directions.
    nodes_mm
        ``(2 n1 + 1, 2 n2 + 1, 2 n3 + 1, 3)`` positions of the element nodes (corners, edge,
        face and body midpoints of the trilinear geometry): node ``[a, b, c]``.
    node_dof
        ``(2 n1 + 1, 2 n2 + 1, 2 n3 + 1)`` the node's number: its displacement components are
        degrees of freedom ``3 * node_dof + (0, 1, 2)`` (x, y, z).
    stiffness
        ``(3 N, 3 N)`` sparse stiffness matrix (N/mm).
    """

    shape: tuple[int, int, int]
    nodes_mm: NDArray = field(repr=False)
    node_dof: NDArray = field(repr=False)
    stiffness: csc_matrix = field(repr=False)

    @property
    def n_dofs(self) -> int:
        """3 N."""
        return self.stiffness.shape[0]


def _hex_mesh(corners_mm: NDArray):
    """scikit-fem MeshHex of a structured ``(n1 + 1, n2 + 1, n3 + 1, 3)`` corner array."""
    from skfem import MeshHex  # (scikit-fem loaded by a loaded contact only, not at start-up)

    n1, n2, n3 = (d - 1 for d in corners_mm.shape[:3])
    index = np.arange((n1 + 1) * (n2 + 1) * (n3 + 1)).reshape(n1 + 1, n2 + 1, n3 + 1)
    t = np.stack([index[a : a + n1, b : b + n2, c : c + n3].ravel() for a, b, c in _CORNERS])
    return MeshHex(np.ascontiguousarray(corners_mm.reshape(-1, 3).T), t.astype(np.int32))


@lru_cache(maxsize=32)
def _structured_dofs(shape: tuple[int, int, int]) -> NDArray:
    """Node number of each Hex2 node ``[a, b, c]`` of a structured mesh: scikit-fem numbers
    the nodes by topology only, so a mesh in index space (corners at integers, midpoints at
    half-integers) gives the numbers for any geometry of the same connectivity."""
    from skfem import Basis, ElementHex2

    n1, n2, n3 = shape
    grid = np.stack(np.meshgrid(*(np.arange(n + 1.0) for n in shape), indexing="ij"), axis=-1)
    basis = Basis(_hex_mesh(grid), ElementHex2(), intorder=1)
    where = np.rint(2.0 * basis.doflocs).astype(np.intp)
    out = np.full((2 * n1 + 1, 2 * n2 + 1, 2 * n3 + 1), -1, dtype=np.intp)
    out[where[0], where[1], where[2]] = np.arange(basis.N)
    if (out < 0).any():  # pragma: no cover - scikit-fem's numbering changed
        raise GearoptError("solid_model", rule="scikit-fem's Hex2 nodes are not the 27-node grid")
    return out


def solid_model(corners_mm: NDArray, material: Material) -> SolidModel:
    """Stiffness of a structured hexahedral block of 27-node (triquadratic) elements.

    Parameters
    ----------
    corners_mm
        ``(n1 + 1, n2 + 1, n3 + 1, 3)`` element corner positions (mm); each element is the
        trilinear map of its 8 corners.
    material
        The :class:`Material`.

    Returns
    -------
    SolidModel
        Nodes, their numbers and the assembled stiffness (one vectorised pass over the elements:
        B^T D B on 27 Gauss points per element with scikit-fem's mapped shape-function gradients).
    """
    corners_mm = np.asarray(corners_mm, float)
    shape = tuple(int(d) - 1 for d in corners_mm.shape[:3])
    if corners_mm.ndim != 4 or corners_mm.shape[3] != 3 or min(shape) < 1:
        raise GearoptError("corners_mm", corners_mm.shape, "must be (n1 + 1, n2 + 1, n3 + 1, 3)")
    from skfem import Basis, ElementHex2

    basis = Basis(_hex_mesh(corners_mm), ElementHex2(), intorder=_INTORDER)
    # (elements, 3 directions, 27 functions, quadrature points)
    grad = np.stack([basis.basis[k][0].grad for k in range(basis.Nbfun)], axis=1)
    grad = np.ascontiguousarray(np.moveaxis(grad, 2, 0))
    n_el, _, n_fun, n_q = grad.shape
    weighted = grad * basis.dx[:, None, None, :]
    m = np.matmul(weighted.reshape(n_el, 3 * n_fun, n_q), grad.reshape(n_el, 3 * n_fun, n_q).mT)
    m = m.reshape(n_el, 3, n_fun, 3, n_fun)  # m[e, i, a, j, b] = int d_i N_a d_j N_b
    lam, mu = material.lame_lambda_mpa, material.shear_modulus_mpa
    k = lam * m.transpose(0, 2, 1, 4, 3) + mu * m.transpose(0, 2, 3, 4, 1)
    trace = m[:, 0, :, 0, :] + m[:, 1, :, 1, :] + m[:, 2, :, 2, :]
    for i in range(3):
        k[:, :, i, :, i] += mu * trace
    dofs = (3 * basis.element_dofs.T[:, :, None] + np.arange(3)).reshape(n_el, 3 * n_fun)
    rows = np.broadcast_to(dofs[:, :, None], (n_el, 3 * n_fun, 3 * n_fun))
    cols = np.broadcast_to(dofs[:, None, :], (n_el, 3 * n_fun, 3 * n_fun))
    n = 3 * basis.N
    stiffness = coo_matrix((k.ravel(), (rows.ravel(), cols.ravel())), shape=(n, n)).tocsc()
    node_dof = _structured_dofs(shape)
    nodes = np.empty(node_dof.shape + (3,))
    nodes[...] = basis.doflocs.T[node_dof]
    return SolidModel(shape=shape, nodes_mm=nodes, node_dof=node_dof, stiffness=stiffness)


@dataclass(frozen=True, kw_only=True, eq=False)
class Factorised:
    """A solid model with fixed nodes, its stiffness factorised once for many load cases.

    The free degrees of freedom, numbered node by node in the structured order (the first index
    slowest), make a banded matrix; cut into blocks of the bandwidth it is block tridiagonal,
    and its Cholesky factor L (K = L L^T) is computed and applied block by block with dense
    BLAS-3 kernels (many right-hand sides at once).

    Attributes
    ----------
    n_dofs
        Degrees of freedom of the model (fixed ones included).
    order
        ``(n,)`` the free degrees of freedom in elimination order.
    diagonal, below
        ``(n_blocks, nb, nb)`` the factor's diagonal blocks (lower triangular) and
        ``(n_blocks - 1, nb, nb)`` the blocks below them (the last block padded with identity).
    """

    n_dofs: int
    order: NDArray = field(repr=False)
    diagonal: NDArray = field(repr=False)
    below: NDArray = field(repr=False)

    def _blocks(self, values: NDArray) -> NDArray:
        nb = self.diagonal.shape[1]
        out = np.zeros((self.diagonal.shape[0] * nb, values.shape[1]))
        out[: len(self.order)] = values[self.order]
        return out.reshape(self.diagonal.shape[0], nb, -1)

    def forward(self, loads_n: NDArray) -> NDArray:
        """``L^-1 f`` of ``(3 N, k)`` nodal vectors: blocks ``(n_blocks, nb, k)``. The
        compliance between load cases F and readings R is ``forward(R^T)^T forward(F)``."""
        y = self._blocks(np.asarray(loads_n, float).reshape(self.n_dofs, -1))
        with blas_threads(ONE_BLAS_THREAD):
            self._forward(y)
        return y

    def _forward(self, y: NDArray) -> None:
        for i in range(y.shape[0]):
            if i:
                y[i] -= self.below[i - 1] @ y[i - 1]
            y[i] = solve_triangular(self.diagonal[i], y[i], lower=True, check_finite=False)

    def displacements_mm(self, loads_n: NDArray) -> NDArray:
        """``(3 N, k)`` displacements (mm) under ``(3 N, k)`` nodal forces (N), one column per
        load case (the fixed degrees of freedom stay zero, their loads are ignored)."""
        loads = np.asarray(loads_n, float)
        y = self.forward(loads)
        with blas_threads(ONE_BLAS_THREAD):
            for i in range(y.shape[0] - 1, -1, -1):
                if i < y.shape[0] - 1:
                    y[i] -= self.below[i].T @ y[i + 1]
                y[i] = solve_triangular(
                    self.diagonal[i], y[i], lower=True, trans="T", check_finite=False
                )
        out = np.zeros((self.n_dofs, y.shape[2]))
        out[self.order] = y.reshape(-1, y.shape[2])[: len(self.order)]
        return out[:, 0] if loads.ndim == 1 else out


def factorise(model: SolidModel, fixed_nodes: NDArray) -> Factorised:
    """Fix the nodes where ``fixed_nodes`` (``model.node_dof.shape``, bool) is True (all three
    displacement components zero) and factorise the remaining stiffness (block Cholesky of the
    banded matrix, :class:`Factorised`; BLAS on one thread, see :data:`ONE_BLAS_THREAD`)."""
    with blas_threads(ONE_BLAS_THREAD):
        return _factorise(model, fixed_nodes)


def _factorise(model: SolidModel, fixed_nodes: NDArray) -> Factorised:
    fixed_nodes = np.asarray(fixed_nodes, bool)
    if fixed_nodes.shape != model.node_dof.shape or not fixed_nodes.any():
        raise GearoptError("fixed_nodes", rule="must mark at least one node of the model")
    order = (3 * model.node_dof[~fixed_nodes][:, None] + np.arange(3)).ravel()
    k = model.stiffness[order][:, order].tocoo()
    n = len(order)
    nb = max(int(np.max(np.abs(k.row - k.col))), 1)
    n_blocks = -(-n // nb)
    diagonal = np.zeros((n_blocks, nb, nb))
    below = np.zeros((max(n_blocks - 1, 0), nb, nb))
    bi, bj = k.row // nb, k.col // nb
    on = bi == bj
    diagonal[bi[on], k.row[on] % nb, k.col[on] % nb] = k.data[on]
    under = bi == bj + 1
    below[bj[under], k.row[under] % nb, k.col[under] % nb] = k.data[under]
    pad = np.arange(n, n_blocks * nb)
    diagonal[-1, pad % nb, pad % nb] = 1.0
    for i in range(n_blocks):
        if i:
            diagonal[i] -= below[i - 1] @ below[i - 1].T
        try:
            diagonal[i] = cholesky(diagonal[i], lower=True, check_finite=False)
        except LinAlgError as error:
            raise GearoptError(
                "fixed_nodes", rule="the stiffness is singular: fix enough nodes"
            ) from error
        if i < n_blocks - 1:
            below[i] = solve_triangular(diagonal[i], below[i].T, lower=True, check_finite=False).T
    return Factorised(n_dofs=model.n_dofs, order=order, diagonal=diagonal, below=below)


# --- the tooth model ------------------------------------------------------------------------


def _check_mesh(mesh) -> tuple[int, int, int]:
    names = ("mesh.n_face", "mesh.n_profile", "mesh.n_thickness")
    lows, high = (2, 4, 2), 40
    if not isinstance(mesh, tuple | list) or len(mesh) != 3:
        raise GearoptError("mesh", mesh, "must be (n_face, n_profile, n_thickness)")
    for name, value, low in zip(names, mesh, lows, strict=True):
        if isinstance(value, bool) or not isinstance(value, int | np.integer):
            raise GearoptError(name, value, "must be an integer")
        if not low <= value <= high:
            raise GearoptError(name, value, f"must be from {low} to {high} elements")
    return tuple(int(v) for v in mesh)


def _circumferential(flank: FlankMap, i: int, j: int) -> float:
    """Circumferential (+Theta) component of the flank's normal at node ``[i, j]``."""
    n = flank.normals[i, j]
    th = flank.polar_angle_rad[i, j]
    return float(-n[0] * math.sin(th) + n[1] * math.cos(th))


def _same_tooth(flank: FlankMap, other: FlankMap) -> tuple[FlankMap, FlankMap]:
    """``(lower, upper)``: the two flanks of one tooth, lower and higher Theta, with ``other``
    turned by whole pitches onto the tooth that ``flank`` bounds (the material lies on the
    side opposite the normals)."""
    if flank.member != other.member or flank.teeth != other.teeth or flank.flank == other.flank:
        raise GearoptError(
            "other",
            (other.member, other.flank),
            f"must be the other flank of the same member as {flank.member} {flank.flank}",
        )
    i, j = np.argwhere(flank.mask & other.mask)[len(np.argwhere(flank.mask & other.mask)) // 2]
    s, t = flank.face_mm[i], flank.profile_mm[j]
    sign = math.copysign(1.0, _circumferential(flank, i, j))
    gap = sign * float(flank.polar_angle_local(s, t) - other.polar_angle_local(s, t))
    turn = int(sign * math.floor(gap / flank.pitch_rad))
    if turn:
        other = other.tooth_turned(turn)
    if math.copysign(1.0, _circumferential(other, i, j)) == sign:
        raise GearoptError(
            "other", other.flank, "its normals must point away from the tooth that flank bounds"
        )
    return (other, flank) if sign > 0 else (flank, other)


def _low_line(flank: FlankMap) -> tuple[float, float]:
    """``(intercept, slope)`` of t_low(s) = intercept + slope s: a line at or above the lowest
    fully generated cell of every cell column of the flank."""
    t = np.where(flank.mask, flank.profile_mm[None, :], np.inf).min(axis=1)
    cell = np.maximum(t[:-1], t[1:])
    ok = np.isfinite(cell)
    if ok.sum() < 2:
        raise GearoptError(f"{flank.member} {flank.flank}", rule="too few generated nodes")
    s = np.concatenate([flank.face_mm[:-1][ok], flank.face_mm[1:][ok]])
    v = np.concatenate([cell[ok], cell[ok]])
    slope, intercept = np.polyfit(s, v, 1)
    intercept += max(float(np.max(v - (intercept + slope * s))), 0.0)
    return float(intercept), float(slope)


@dataclass(frozen=True, kw_only=True, eq=False)
class _Side:
    """One side of the tooth on the FE mesh: t and Theta of its corner nodes ``[a, b]``."""

    flank: FlankMap
    low: tuple[float, float]
    profile_mm: NDArray
    polar_angle_rad: NDArray


def _side(flank, face, rows, t_root, t_top, t_rim, centre, half_pitch, low) -> _Side:
    """t and Theta of one side's corner nodes: rim rows at the tooth space's middle, fillet
    rows widening parabolically from the flank's tangent to it, flank rows on the flank."""
    n_rim, n_fil, n_fl = rows
    t_low = low[0] + low[1] * face
    t_low = np.clip(t_low, t_root + 0.05 * (t_top - t_root), t_top - 0.2 * (t_top - t_root))
    x_rim = np.linspace(0.0, 1.0, n_rim + 1)[:-1]
    x_fil = np.linspace(0.0, 1.0, n_fil + 1)[:-1]
    x_fl = np.linspace(0.0, 1.0, n_fl + 1)
    t = np.concatenate(
        [
            np.broadcast_to(t_rim + (t_root - t_rim) * x_rim, (len(face), n_rim)),
            t_root + (t_low - t_root)[:, None] * x_fil,
            t_low[:, None] + (t_top - t_low)[:, None] * x_fl,
        ],
        axis=1,
    )
    ss = np.broadcast_to(face[:, None], t.shape)
    theta = flank.polar_angle_local(ss, t)
    step = 0.02 * (t_top - t_low)
    slope = (
        flank.polar_angle_local(face, t_low + step) - flank.polar_angle_local(face, t_low)
    ) / step
    at_low = flank.polar_angle_local(face, t_low)
    target = centre + half_pitch
    straight = at_low[:, None] + slope[:, None] * (t - t_low[:, None])
    x = (t_low[:, None] - t) / (t_low - t_root)[:, None]
    widen = (target - (at_low + slope * (t_root - t_low)))[:, None] * x**2
    theta = np.where(t >= t_low[:, None], theta, straight + widen)
    theta[:, :n_rim] = target[:, None]
    return _Side(flank=flank, low=low, profile_mm=t, polar_angle_rad=theta)


@dataclass(frozen=True, kw_only=True, eq=False)
class ToothCompliance:
    """Influence numbers of one flank of a member's tooth (bending, shear, fillet and rim; the
    local contact deformation excluded, see the module docstring).

    Attributes
    ----------
    member, flank, tooth
        The flank they belong to (as handed to :func:`tooth_compliance`).
    material, mesh
        The :class:`Material` and the FE mesh ``(n_face, n_profile, n_thickness)``.
    face_mm
        ``(n_f,)`` cone distances of the table's points (the FE mesh's corner nodes).
    low_mm, low_slope
        The table's lowest profile line t_low(s) = low_mm + low_slope s (grid coordinate t of
        the FlankMap, the height h for uniform depth): the lowest generated flank.
    top_mm
        Profile coordinate of the tooth top.
    table_mm_per_n
        ``(n_f n_p, n_f n_p)`` influence numbers at the table's points, point ``k = a n_p + b``
        at face ``face_mm[a]`` and profile ``t_low + b / (n_p - 1) (top_mm - t_low)``: row i the
        reading, column j the unit load: the symmetric part of the FE readings (Maxwell-Betti;
        the mid-surface readings are not exactly the load points' conjugates).
    asymmetry
        ``max |a_ij - a_ji| / max a_ii`` of the FE readings before symmetrising (a few %).
    """

    member: str
    flank: str
    tooth: int
    material: Material
    mesh: tuple[int, int, int]
    face_mm: NDArray = field(repr=False)
    low_mm: float
    low_slope: float
    top_mm: float
    table_mm_per_n: NDArray = field(repr=False)
    asymmetry: float

    @property
    def table_shape(self) -> tuple[int, int]:
        """``(n_f, n_p)`` points of the table along the face and the profile."""
        n_f = len(self.face_mm)
        return n_f, self.table_mm_per_n.shape[0] // n_f

    def table_points_mm(self) -> tuple[NDArray, NDArray]:
        """``(face, profile)``, each ``(n_f, n_p)``: grid coordinates of the table's points."""
        n_f, n_p = self.table_shape
        low = self.low_mm + self.low_slope * self.face_mm
        frac = np.linspace(0.0, 1.0, n_p)
        profile = low[:, None] + (self.top_mm - low)[:, None] * frac
        return np.broadcast_to(self.face_mm[:, None], (n_f, n_p)), profile

    def stencil(self, face_mm, profile_mm) -> tuple[NDArray, NDArray]:
        """``(points, weights)``, each ``(m, 16)``: the interpolation of the table at flank
        points, the 16 table points of each one's stencil (flat indices, some repeated with
        weight 0 at the table's edges) and their weights: local cubic (Catmull-Rom) in the
        face and in the fraction of the flank's height, points beyond the table clamped onto
        its edge. The influence between flank points i and j is ``sum_pq w_ip T_pq w_jq``."""
        s = np.asarray(face_mm, float).ravel()
        t = np.asarray(profile_mm, float).ravel()
        n_f, n_p = self.table_shape
        u = (s - self.face_mm[0]) / (self.face_mm[-1] - self.face_mm[0]) * (n_f - 1)
        low = self.low_mm + self.low_slope * s
        v = (t - low) / (self.top_mm - low) * (n_p - 1)
        points = np.empty((len(s), 16), np.intp)
        weights = np.empty((len(s), 16))
        kernels.table_stencil(u, v, n_f, n_p, points, weights)
        return points, weights

    def weights(self, face_mm, profile_mm) -> NDArray:
        """``(m, n_f n_p)`` interpolation weights of the table at flank points (the dense form
        of :meth:`stencil`)."""
        points, w = self.stencil(face_mm, profile_mm)
        out = np.zeros((len(points), self.table_mm_per_n.shape[0]))
        np.add.at(out, (np.arange(len(points))[:, None], points), w)
        return out

    def influence_mm_per_n(self, face_mm_i, profile_mm_i, face_mm_j, profile_mm_j) -> NDArray:
        """``(m, n)`` normal displacement (mm, into the tooth) of flank points i under a unit
        normal load (N, pressing into the tooth) at flank points j (grid coordinates of the
        flank: cone distance and profile t)."""
        wi = self.weights(face_mm_i, profile_mm_i)
        wj = self.weights(face_mm_j, profile_mm_j)
        return wi @ self.table_mm_per_n @ wj.T

    def compliance_mm_per_n(self, face_mm, profile_mm) -> NDArray:
        """Point compliance (the influence of a point on itself) at flank points, in the shape
        of the arguments."""
        s, t = np.broadcast_arrays(np.asarray(face_mm, float), np.asarray(profile_mm, float))
        w = self.weights(s, t)
        return np.einsum("ik,kl,il->i", w, self.table_mm_per_n, w).reshape(s.shape)


def _surface_normals(points: NDArray, inward: NDArray) -> NDArray:
    """``(n_f, n_p, 3)`` unit normals of a structured surface, oriented against ``inward``."""
    da = np.gradient(points, axis=0, edge_order=2)
    db = np.gradient(points, axis=1, edge_order=2)
    n = np.cross(da, db)
    n /= np.linalg.norm(n, axis=-1, keepdims=True)
    return n * -np.sign(np.sum(n * inward, axis=-1, keepdims=True))


def _lagrange(x: NDArray) -> tuple[NDArray, NDArray]:
    """Quadratic Lagrange functions on nodes 0, 1, 2 and their derivatives, ``(..., 3)``."""
    x = x[..., None]
    values = np.concatenate([(x - 1) * (x - 2) / 2, -x * (x - 2), x * (x - 1) / 2], axis=-1)
    slopes = np.concatenate([x - 1.5, 2 - 2 * x, x - 0.5], axis=-1)
    return values, slopes


def _normal_foot(surface: NDArray, points: NDArray, normals: NDArray):
    """Where the inward normals of ``points`` pierce a node surface of the mesh (the
    biquadratic surface through ``surface``, ``(2 n1 + 1, 2 n2 + 1, 3)`` nodes): per point
    the 9 nodes ``(m, 9, 2)`` of its element and their weights ``(m, 9)`` (Newton on the node
    coordinates, clamped to the surface)."""
    top = np.array(surface.shape[:2]) - 1.0
    flat = surface.reshape(-1, 3)
    guess = np.linalg.norm(surface[..., None, :] - points, axis=-1).reshape(-1, len(points))
    k = np.argmin(guess, axis=0)
    x = np.stack([k // surface.shape[1], k % surface.shape[1]], axis=-1).astype(float)
    depth = np.linalg.norm(points - flat[k], axis=-1)
    for _ in range(8):
        e = np.clip(np.floor(x / 2.0), 0, top / 2 - 1).astype(np.intp)
        (fa, da), (fb, db) = _lagrange(x[:, 0] - 2 * e[:, 0]), _lagrange(x[:, 1] - 2 * e[:, 1])
        ia = 2 * e[:, :1] + np.arange(3)
        ib = 2 * e[:, 1:] + np.arange(3)
        patch = surface[ia[:, :, None], ib[:, None, :]]  # (m, 3, 3, 3)
        at = np.einsum("mi,mj,mijk->mk", fa, fb, patch)
        jac = np.stack(
            [
                np.einsum("mi,mj,mijk->mk", da, fb, patch),
                np.einsum("mi,mj,mijk->mk", fa, db, patch),
                normals,
            ],
            axis=-1,
        )
        step = np.linalg.solve(jac, (points - depth[:, None] * normals - at)[..., None])[..., 0]
        x = np.clip(x + step[:, :2], 0.0, top)
        depth = depth - step[:, 2]
    nodes = np.stack(np.broadcast_arrays(ia[:, :, None], ib[:, None, :]), axis=-1)
    return nodes.reshape(-1, 9, 2), (fa[:, :, None] * fb[:, None, :]).reshape(-1, 9)


@lru_cache(maxsize=8)
def _member_tables(
    lower: FlankMap,
    upper: FlankMap,
    blank: Blank,
    material: Material,
    mesh: tuple[int, int, int],
    rim_depth_mm: float | None,
) -> dict[str, ToothCompliance]:
    """Both flanks' :class:`ToothCompliance` of one tooth model (one factorisation)."""
    n_face, n_profile, n_thickness = mesh
    index = MEMBERS.index(lower.member)
    t_root, t_top = -blank.mean_dedendum_mm[index], blank.mean_addendum_mm[index]
    depth = t_top - t_root
    rim = blank.mean_normal_module_mm if rim_depth_mm is None else rim_depth_mm
    lows = (_low_line(lower), _low_line(upper))
    face = np.linspace(blank.inner_cone_distance_mm, blank.outer_cone_distance_mm, n_face + 1)
    fillet = np.mean([t_lo - t_root for t_lo, _ in lows]) + np.mean([sl for _, sl in lows]) * (
        blank.mean_cone_distance_mm
    )
    n_fil = int(np.clip(round(n_profile * fillet / depth), 2, n_profile - 2))
    rows = (max(1, round(n_profile * rim / depth)), n_fil, n_profile - n_fil)
    t_low = [np.clip(lo + sl * face, t_root, t_top) for lo, sl in lows]
    centre = 0.5 * (
        lower.polar_angle_local(face, t_low[0]) + upper.polar_angle_local(face, t_low[1])
    )
    half = 0.5 * lower.pitch_rad
    sides = [
        _side(f, face, rows, t_root, t_top, t_root - rim, centre, sign * half, low)
        for f, sign, low in ((lower, -1.0, lows[0]), (upper, 1.0, lows[1]))
    ]
    if np.any(sides[1].polar_angle_rad <= sides[0].polar_angle_rad):
        raise GearoptError(f"{lower.member} tooth", rule="its two sides cross (pointed tooth?)")
    w = np.linspace(0.0, 1.0, n_thickness + 1)
    t = sides[0].profile_mm[..., None] * (1 - w) + sides[1].profile_mm[..., None] * w
    theta = sides[0].polar_angle_rad[..., None] * (1 - w) + sides[1].polar_angle_rad[..., None] * w
    s = np.broadcast_to(face[:, None, None], t.shape)
    big_l, big_r = axial_plane(s, lower.height_at(s, t), math.radians(lower.pitch_angle_deg))
    corners = np.stack([big_r * np.cos(theta), big_r * np.sin(theta), big_l], axis=-1)
    model = solid_model(corners, material)
    fixed = np.zeros(model.node_dof.shape, bool)
    fixed[:, 0, :] = True  # the rim's bottom
    fixed[:, : 2 * rows[0] + 1, [0, -1]] = True  # the rim's sides
    factors = factorise(model, fixed)
    # the table: corner nodes of the flank rows on each side, read at the mid-surface
    top = 2 * sum(rows)
    b = np.arange(2 * (rows[0] + rows[1]), top + 1, 2)
    a = np.arange(0, 2 * n_face + 1, 2)
    mid = model.nodes_mm[a][:, b, n_thickness]
    loads, reads, normals = [], [], []
    for c in (0, 2 * n_thickness):
        p = model.nodes_mm[a][:, b, c]
        normal = _surface_normals(p, mid - p).reshape(-1, 3)
        normals.append(normal)
        columns = np.arange(len(normal))
        vec = np.zeros((model.n_dofs, len(normal)))
        dofs = 3 * model.node_dof[a][:, b, c].reshape(-1)[:, None] + np.arange(3)
        vec[dofs, columns[:, None]] = -normal
        loads.append(vec)
        nodes, weights = _normal_foot(model.nodes_mm[:, :, n_thickness], p.reshape(-1, 3), normal)
        vec = np.zeros((model.n_dofs, len(normal)))
        dofs = 3 * model.node_dof[:, :, n_thickness][nodes[..., 0], nodes[..., 1]]
        for k in range(3):  # nodes on the same point add up
            np.add.at(vec, (dofs + k, columns[:, None]), -normal[:, None, k] * weights)
        reads.append(vec)
    y_load = factors.forward(np.hstack(loads)).reshape(-1, 2 * len(normals[0]))
    y_read = factors.forward(np.hstack(reads)).reshape(-1, 2 * len(normals[0]))
    table = y_read.T @ y_load
    n = len(normals[0])
    out = {}
    for k, (side, low) in enumerate(zip((lower, upper), lows, strict=True)):
        raw = table[k * n : (k + 1) * n, k * n : (k + 1) * n]
        out[side.flank] = ToothCompliance(
            member=side.member,
            flank=side.flank,
            tooth=side.tooth,
            material=material,
            mesh=mesh,
            face_mm=face,
            low_mm=low[0],
            low_slope=low[1],
            top_mm=t_top,
            table_mm_per_n=0.5 * (raw + raw.T),
            asymmetry=float(np.abs(raw - raw.T).max() / np.diag(raw).max()),
        )
    return out


def member_compliance(
    flanks, blank: Blank, *, material: Material | None = None, mesh=DEFAULT_MESH, rim_depth_mm=None
) -> dict[str, ToothCompliance]:
    """``{"convex": ToothCompliance, "concave": ToothCompliance}`` of one member from one FE
    model of its tooth (one factorisation; cached per flanks, blank, material and mesh).

    Parameters
    ----------
    flanks
        ``{"convex": FlankMap, "concave": FlankMap}`` of the member (as generated: the concave
        flank is turned by whole pitches onto the tooth the convex flank bounds when needed).
    blank
        The pair's :class:`gearopt.blank.Blank` (root and top of the tooth, face width, module).
    material
        :class:`Material`, steel by default.
    mesh
        ``(n_face, n_profile, n_thickness)`` elements along the face, over the tooth's height
        (fillet and flank; the rim gets its share on top) and through the thickness.
    rim_depth_mm
        Depth of the rim section below the root cone, the mean normal module by default.
    """
    for name in FLANKS:
        if name not in flanks:
            raise GearoptError("flanks", sorted(flanks), f"must hold the {name} flank")
    material = Material() if material is None else material
    mesh = _check_mesh(mesh)
    if rim_depth_mm is not None and not (math.isfinite(rim_depth_mm) and rim_depth_mm > 0):
        raise GearoptError("rim_depth_mm", rim_depth_mm, "must be positive")
    lower, upper = _same_tooth(flanks["convex"], flanks["concave"])
    with blas_threads(ONE_BLAS_THREAD):
        tables = _member_tables(lower, upper, blank, material, mesh, rim_depth_mm)
    return {name: tables[name] for name in FLANKS}


def tooth_compliance(
    flank: FlankMap,
    other: FlankMap,
    blank: Blank,
    *,
    material: Material | None = None,
    mesh=DEFAULT_MESH,
    rim_depth_mm=None,
) -> ToothCompliance:
    """:class:`ToothCompliance` of ``flank``, from the FE model of the tooth it bounds with
    ``other`` (the member's other flank; both flanks share the model, see
    :func:`member_compliance` for the parameters)."""
    pair = {flank.flank: flank, other.flank: other}
    if len(pair) != 2:
        raise GearoptError("other", other.flank, "must be the other flank of the member")
    return member_compliance(pair, blank, material=material, mesh=mesh, rim_depth_mm=rim_depth_mm)[
        flank.flank
    ]
