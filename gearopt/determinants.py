"""Signs of 3 x 3 determinants over a grid, compiled: the envelope solver's fold test
(:mod:`gearopt.envelope`) reads only these signs of its Jacobians."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from gearopt.jit import ENABLED, compiled

__all__ = ["det_signs", "warm_kernels"]


def det_signs(jac: NDArray) -> NDArray:
    """``np.sign(np.linalg.det(jac))`` of Jacobians ``(..., 3, 3)``, compiled when the kernels
    are (:func:`_signs_kernel`), without numpy's cost per matrix."""
    if not ENABLED:
        return np.sign(np.linalg.det(jac))
    flat = np.ascontiguousarray(jac, float).reshape(-1, 3, 3)
    out = np.empty(len(flat))
    _signs_kernel(flat, out)
    return out.reshape(jac.shape[:-2])


@compiled
def _signs_kernel(jac, out):
    """The signs of the determinants of ``jac`` ``(n, 3, 3)`` into ``out``, as numpy's det
    has them: LAPACK's LU with partial pivoting (the first largest pivot; the multipliers by
    the pivot's reciprocal), the sign the row swaps' times the pivots' (0 with a zero pivot,
    NaN with a NaN)."""
    for k in range(jac.shape[0]):
        a00, a01, a02 = jac[k, 0, 0], jac[k, 0, 1], jac[k, 0, 2]
        a10, a11, a12 = jac[k, 1, 0], jac[k, 1, 1], jac[k, 1, 2]
        a20, a21, a22 = jac[k, 2, 0], jac[k, 2, 1], jac[k, 2, 2]
        sign = 1.0
        if abs(a10) > abs(a00) and abs(a10) >= abs(a20):
            a00, a01, a02, a10, a11, a12 = a10, a11, a12, a00, a01, a02
            sign = -sign
        elif abs(a20) > abs(a00) and abs(a20) > abs(a10):
            a00, a01, a02, a20, a21, a22 = a20, a21, a22, a00, a01, a02
            sign = -sign
        if a00 != 0.0:
            r = 1.0 / a00
            l1, l2 = a10 * r, a20 * r
            a11, a12 = a11 - l1 * a01, a12 - l1 * a02
            a21, a22 = a21 - l2 * a01, a22 - l2 * a02
        if abs(a21) > abs(a11):
            a11, a12, a21, a22 = a21, a22, a11, a12
            sign = -sign
        if a11 != 0.0:
            a22 = a22 - a21 * (1.0 / a11) * a12
        for d in (a00, a11, a22):
            sign = sign * (1.0 if d > 0.0 else (-1.0 if d < 0.0 else (0.0 if d == 0.0 else d)))
        out[k] = sign


def warm_kernels() -> None:
    """Compile the solver's own kernel (:func:`det_signs`), or load it from numba's disk
    cache, in this process (:func:`gearopt.warmup.warm_kernels`). Nothing without kernels."""
    det_signs(np.eye(3)[None])
