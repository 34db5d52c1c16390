"""Local contact compliance of two elastic bodies: half-space influence coefficients.

Each body near the contact is an elastic half-space (Boussinesq). A uniform pressure ``p`` on the
rectangle ``|xi - xj| <= aj, |eta - yj| <= bj`` of the surface displaces the surface point
``(x, y)`` normally by (Love 1929; Johnson, *Contact Mechanics*, 1985, ch. 3, a uniform pressure
on a rectangle)

.. math::

    u_z(x, y) = \\frac{1 - \\nu^2}{\\pi E}\\, p\\, I(x, y), \\qquad
    I = \\int_{x_j - a_j}^{x_j + a_j} \\int_{y_j - b_j}^{y_j + b_j}
        \\frac{d\\xi\\, d\\eta}{\\sqrt{(x - \\xi)^2 + (y - \\eta)^2}},

evaluated in closed form with the primitive
``H(u, v) = u asinh(v / |u|) + v asinh(u / |v|)`` (``d2H / du dv = 1 / sqrt(u^2 + v^2)``, the
``u asinh(v / |u|)`` term taken as 0 at ``u = 0``)::

    I = H(u2, v2) - H(u1, v2) - H(u2, v1) + H(u1, v1),
    u1,2 = xj -+ aj - x,  v1,2 = yj -+ bj - y.

This is Love's logarithmic formula rewritten with ``asinh``. The two bodies pressed together
by the same pressure approach each other by the sum of their displacements, so the factor
``(1 - nu^2) / E`` becomes the composite compliance ``(1 - nu1^2) / E1 + (1 - nu2^2) / E2``
(``1 / E*`` in Johnson's notation, mm^2/N = 1/MPa).

The influence coefficient ``D_ij`` (mm/MPa) is the displacement at the centre of patch ``i`` per
unit pressure on patch ``j``; the compliance ``C_ij = D_ij / A_j`` (mm/N) is the displacement per
unit force (the force spread uniformly over the patch). Coordinates are the patches' centres in
the common tangent plane of the contact (a half-space knows no curvature), in mm.

References
----------
Love, A. E. H. (1929). The stress produced in a semi-infinite solid by pressure on part of the
boundary. *Phil. Trans. R. Soc. A* 228, 377-420.
Johnson, K. L. (1985). *Contact Mechanics*. Cambridge University Press.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gearopt.errors import GearoptError
from gearopt.loaded import kernels

__all__ = [
    "FAR_FIELD_RATIO",
    "PatchGrid",
    "composite_compliance_mm2_per_n",
    "rectangle_influence_mm_per_mpa",
    "halfspace_columns_mm_per_n",
    "halfspace_compliance_mm_per_n",
    "patch_grid",
]

#: :func:`halfspace_columns_mm_per_n` takes the multipole expansion for two patches whose
#: centres lie further apart than this many times the largest half-width of the two: its
#: relative error there is below 5e-5 (the worst case, 4.4e-5, a square seen along its
#: diagonal), Love's exact integral nearer
FAR_FIELD_RATIO = 4.0


def composite_compliance_mm2_per_n(e1_mpa: float, nu1: float, e2_mpa: float, nu2: float) -> float:
    """The composite compliance ``(1 - nu1^2) / E1 + (1 - nu2^2) / E2`` (mm^2/N, ``1 / E*``).

    Raises :class:`~gearopt.errors.GearoptError` for a modulus that is not positive and finite
    or a Poisson ratio outside ``(-1, 0.5]``.
    """
    for name, e in (("e1_mpa", e1_mpa), ("e2_mpa", e2_mpa)):
        if not (np.isfinite(e) and e > 0.0):
            raise GearoptError(name, e, "must be a positive finite Young's modulus (MPa)")
    for name, nu in (("nu1", nu1), ("nu2", nu2)):
        if not (np.isfinite(nu) and -1.0 < nu <= 0.5):
            raise GearoptError(name, nu, "must be a Poisson ratio in (-1, 0.5]")
    return float((1.0 - nu1**2) / e1_mpa + (1.0 - nu2**2) / e2_mpa)


def _primitive(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """``H(u, v) = u asinh(v / |u|) + v asinh(u / |v|)``, 0 terms where ``u`` or ``v`` is 0."""
    au, av = np.abs(u), np.abs(v)
    with np.errstate(divide="ignore", invalid="ignore"):
        t1 = np.where(au > 0.0, u * np.arcsinh(v / np.where(au > 0.0, au, 1.0)), 0.0)
        t2 = np.where(av > 0.0, v * np.arcsinh(u / np.where(av > 0.0, av, 1.0)), 0.0)
    return t1 + t2


def _as_patches(x_mm, y_mm, half_a_mm, half_b_mm) -> tuple[np.ndarray, ...]:
    x = np.asarray(x_mm, dtype=float).ravel()
    y = np.asarray(y_mm, dtype=float).ravel()
    if x.shape != y.shape:
        raise GearoptError("y_mm", y.shape, f"must have the shape of x_mm {x.shape}")
    a = np.broadcast_to(np.asarray(half_a_mm, dtype=float).ravel(), x.shape)
    b = np.broadcast_to(np.asarray(half_b_mm, dtype=float).ravel(), x.shape)
    for name, arr in (("x_mm", x), ("y_mm", y)):
        if not np.all(np.isfinite(arr)):
            raise GearoptError(name, arr, "must be finite")
    for name, arr in (("half_a_mm", a), ("half_b_mm", b)):
        if not np.all(np.isfinite(arr) & (arr > 0.0)):
            raise GearoptError(name, arr, "must be positive and finite (half-widths of patches)")
    return x, y, a, b


def rectangle_influence_mm_per_mpa(
    x_mm, y_mm, half_a_mm, half_b_mm, composite_mm2_per_n: float
) -> np.ndarray:
    """Influence coefficients ``D_ij`` (mm/MPa) of rectangular patches on two half-spaces.

    Parameters
    ----------
    x_mm, y_mm
        Patch centres in the tangent plane, shape ``(n,)`` (mm).
    half_a_mm, half_b_mm
        Half-widths of the patches along x and y, scalars or shape ``(n,)`` (mm).
    composite_mm2_per_n
        ``(1 - nu1^2) / E1 + (1 - nu2^2) / E2`` (mm^2/N), see
        :func:`composite_compliance_mm2_per_n`.

    Returns
    -------
    numpy.ndarray
        ``D`` of shape ``(n, n)``: ``D[i, j]`` is the normal approach of the two surfaces at the
        centre of patch ``i`` for a uniform unit pressure (1 MPa) on patch ``j`` (Love's
        rectangle, Johnson 1985 ch. 3, module docstring), ``composite / pi * I_ij``.
        Symmetric when all patches have the same size.
    """
    if not (np.isfinite(composite_mm2_per_n) and composite_mm2_per_n > 0.0):
        raise GearoptError("composite_mm2_per_n", composite_mm2_per_n, "must be positive, finite")
    x, y, a, b = _as_patches(x_mm, y_mm, half_a_mm, half_b_mm)
    # source j minus field point i
    integral_mm = _love_integral_mm(x[None, :] - x[:, None], y[None, :] - y[:, None], a, b)
    return composite_mm2_per_n / np.pi * integral_mm


def _love_integral_mm(dx, dy, a, b):
    """The integral ``I`` of 1 / distance over a rectangle of half-widths ``a, b`` whose centre
    lies at ``(dx, dy)`` from the field point (module docstring)."""
    u1, u2 = dx - a, dx + a
    v1, v2 = dy - b, dy + b
    integral_mm = _primitive(u2, v2) - _primitive(u1, v2) - _primitive(u2, v1)
    integral_mm += _primitive(u1, v1)
    return integral_mm


def halfspace_compliance_mm_per_n(
    x_mm, y_mm, half_a_mm, half_b_mm, composite_mm2_per_n: float
) -> np.ndarray:
    """Half-space compliance ``C_ij = D_ij / A_j`` (mm/N) of rectangular patches.

    ``D`` is :func:`rectangle_influence_mm_per_mpa` and ``A_j = 4 a_j b_j`` the area of patch
    ``j``. With patches of unequal sizes the collocated ``D_ij / A_j`` is not exactly symmetric
    (the Maxwell-Betti reciprocity holds for the exact continuous operator, not for its
    piecewise-constant collocation); the symmetric part ``(C + C^T) / 2`` is returned, as the
    load distribution (:func:`gearopt.loaded.lcp.solve_load_distribution`) requires a symmetric
    compliance. For equal patches this changes nothing but round-off. A few columns of it, at
    their own cost: :func:`halfspace_columns_mm_per_n`.
    """
    x, y, a, b = _as_patches(x_mm, y_mm, half_a_mm, half_b_mm)
    area_mm2 = 4.0 * a * b
    c = rectangle_influence_mm_per_mpa(x, y, a, b, composite_mm2_per_n) / area_mm2[None, :]
    return 0.5 * (c + c.T)


def halfspace_columns_mm_per_n(
    x_mm, y_mm, half_a_mm, half_b_mm, columns, composite_mm2_per_n: float
) -> np.ndarray:
    """Columns of the half-space compliance, ``halfspace_compliance_mm_per_n(...)[:, columns]``
    to a relative error below 5e-5 per entry, at a cost proportional to the columns asked.

    Entry ``(i, j)`` is the symmetric part
    ``composite / pi * (L(x_j - x_i; a_j, b_j) / A_j + L(x_i - x_j; a_i, b_i) / A_i) / 2``,
    ``L(d; a, b)`` Love's integral of 1 / distance over a rectangle of half-widths ``a, b``
    centred at the offset ``d`` from the field point (module docstring) and ``A = 4 a b``. Far
    from the rectangle, ``L / A`` is the mean of ``1 / |d + xi|`` over it; the Taylor series
    of ``1 / |d + xi|`` (Legendre polynomials ``P_l`` of the angle between ``d`` and ``xi``)
    averaged with the rectangle's moments ``<xi^2> = a^2 / 3``, ``<xi^4> = a^4 / 5``,
    ``<xi^2 eta^2> = a^2 b^2 / 9`` (the odd ones 0) gives, with ``p = dx / |d|``,
    ``q = dy / |d|``::

        L / A = 1 / |d| (1 + ((2 p^2 - q^2) a^2 + (2 q^2 - p^2) b^2) / (6 |d|^2)
                  + (a^4 (7 p^4 - 6 p^2 + 3/5) + b^4 (7 q^4 - 6 q^2 + 3/5)
                     + a^2 b^2 (70/3 p^2 q^2 - 8/3)) / (8 |d|^4)) + O((a / |d|)^6 / |d|).

    It is taken where ``|d|`` exceeds :data:`FAR_FIELD_RATIO` times the largest half-width
    of the two patches; Love's exact integral nearer (the same numbers as the dense matrix to
    round-off). Compiled (:mod:`gearopt.loaded.kernels`).

    Parameters
    ----------
    x_mm, y_mm
        Patch centres in the tangent plane, shape ``(n,)`` (mm).
    half_a_mm, half_b_mm
        Patch half-widths along x and y, scalars or shape ``(n,)`` (mm).
    columns
        Indices of the columns, integers in ``[0, n)``, shape ``(m,)``.
    composite_mm2_per_n
        ``(1 - nu1^2) / E1 + (1 - nu2^2) / E2`` (mm^2/N).

    Returns
    -------
    numpy.ndarray
        Shape ``(n, m)`` (a transposed view of a C-ordered ``(m, n)`` array: each column
        contiguous), mm/N.
    """
    if not (np.isfinite(composite_mm2_per_n) and composite_mm2_per_n > 0.0):
        raise GearoptError("composite_mm2_per_n", composite_mm2_per_n, "must be positive, finite")
    x, y, a, b = _as_patches(x_mm, y_mm, half_a_mm, half_b_mm)
    idx = np.asarray(columns)
    if idx.ndim != 1 or not (idx.size == 0 or np.issubdtype(idx.dtype, np.integer)):
        raise GearoptError("columns", idx, "must be a 1-D array of integer patch indices")
    if idx.size and (idx.min() < 0 or idx.max() >= x.size):
        raise GearoptError("columns", idx, f"must be indices in [0, {x.size})")
    out = np.empty((idx.size, x.size))
    kernels.halfspace_columns(
        np.ascontiguousarray(x),
        np.ascontiguousarray(y),
        np.ascontiguousarray(a),
        np.ascontiguousarray(b),
        idx.astype(np.intp),
        float(composite_mm2_per_n) / np.pi,
        FAR_FIELD_RATIO,
        out,
    )
    return out.T


@dataclass(frozen=True, kw_only=True)
class PatchGrid:
    """A rectangular grid of patches, flattened row by row (x fastest).

    Attributes
    ----------
    x_mm, y_mm
        Patch centres, shape ``(ny * nx,)`` (mm).
    half_a_mm, half_b_mm
        Patch half-widths along x and y, shape ``(ny * nx,)`` (mm).
    shape
        ``(ny, nx)``: reshape a per-patch array with ``values.reshape(grid.shape)``.
    """

    x_mm: np.ndarray
    y_mm: np.ndarray
    half_a_mm: np.ndarray
    half_b_mm: np.ndarray
    shape: tuple[int, int]

    @property
    def area_mm2(self) -> np.ndarray:
        """Patch areas ``4 a b`` (mm^2)."""
        return 4.0 * self.half_a_mm * self.half_b_mm

    def compliance_mm_per_n(self, composite_mm2_per_n: float) -> np.ndarray:
        """:func:`halfspace_compliance_mm_per_n` of the grid's patches.

        On an evenly spaced grid ``C_ij`` depends on the index offsets only (a block Toeplitz
        matrix): the ``(2 ny - 1) (2 nx - 1)`` distinct values are computed once and gathered,
        the same numbers to round-off, about 10 times faster.
        """
        a, b = self.half_a_mm, self.half_b_mm
        even = np.allclose(a, a[0], rtol=1e-12, atol=0.0)
        even = even and np.allclose(b, b[0], rtol=1e-12, atol=0.0)
        if not even:
            return halfspace_compliance_mm_per_n(self.x_mm, self.y_mm, a, b, composite_mm2_per_n)
        if not (np.isfinite(composite_mm2_per_n) and composite_mm2_per_n > 0.0):
            raise GearoptError(
                "composite_mm2_per_n", composite_mm2_per_n, "must be positive, finite"
            )
        ny, nx = self.shape
        ha, hb = float(np.mean(a)), float(np.mean(b))
        ox, oy = np.meshgrid(np.arange(1 - nx, nx) * 2.0 * ha, np.arange(1 - ny, ny) * 2.0 * hb)
        kernel = _love_integral_mm(ox, oy, ha, hb) * (composite_mm2_per_n / np.pi / (4 * ha * hb))
        kernel = 0.5 * (kernel + kernel[::-1, ::-1])  # exactly symmetric
        ix, iy = np.tile(np.arange(nx), ny), np.repeat(np.arange(ny), nx)
        return kernel[iy[None, :] - iy[:, None] + ny - 1, ix[None, :] - ix[:, None] + nx - 1]


def patch_grid(x_edges_mm, y_edges_mm) -> PatchGrid:
    """The patches between consecutive edges: ``len(x_edges) - 1`` by ``len(y_edges) - 1``.

    Edges must be strictly increasing (mm); the spacing may vary.
    """
    xe = np.asarray(x_edges_mm, dtype=float).ravel()
    ye = np.asarray(y_edges_mm, dtype=float).ravel()
    for name, e in (("x_edges_mm", xe), ("y_edges_mm", ye)):
        if e.size < 2 or not np.all(np.isfinite(e)) or not np.all(np.diff(e) > 0.0):
            raise GearoptError(name, e, "must be at least 2 finite, strictly increasing edges")
    xc, yc = 0.5 * (xe[1:] + xe[:-1]), 0.5 * (ye[1:] + ye[:-1])
    ha, hb = 0.5 * np.diff(xe), 0.5 * np.diff(ye)
    xx, yy = np.meshgrid(xc, yc)
    aa, bb = np.meshgrid(ha, hb)
    return PatchGrid(
        x_mm=xx.ravel(),
        y_mm=yy.ravel(),
        half_a_mm=aa.ravel(),
        half_b_mm=bb.ravel(),
        shape=(yc.size, xc.size),
    )
