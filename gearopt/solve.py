"""Damped, step-clipped Newton iteration for many small nonlinear systems at once.

``N`` independent systems of ``n`` equations in ``n`` unknowns (``n`` is 2 to 8 here: a flank
node, a contact position) are solved together: one vectorised residual call per iteration, the
Jacobians analytic or by complex step, a batched linear solve, a per-unknown step limit and a
backtracking line search per system. Each system reports whether it converged; nothing is
silently returned as NaN.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["NewtonResult", "newton", "complex_step_jacobian"]

Residual = Callable[[NDArray, NDArray], NDArray]


@dataclass(frozen=True, kw_only=True)
class NewtonResult:
    """Outcome of :func:`newton` for ``N`` systems.

    Attributes
    ----------
    x
        ``(N, n)`` solutions (the last iterate where a system did not converge).
    residual
        ``(N, n)`` residuals at ``x``.
    converged
        ``(N,)`` True where max |residual| <= tol.
    iterations
        Iterations used (the same for all systems; converged ones stop moving).
    jacobian_det
        ``(N,)`` determinant of the Jacobian at ``x`` (its sign marks folds of an envelope).
    """

    x: NDArray
    residual: NDArray
    converged: NDArray
    iterations: int
    jacobian_det: NDArray

    @property
    def all_converged(self) -> bool:
        """True when every system converged."""
        return bool(np.all(self.converged))


def complex_step_jacobian(
    func: Residual, x: NDArray, idx: NDArray | None = None, *, h: float = 1e-30
) -> NDArray:
    """Jacobian ``(N, n, n)`` of ``func`` at ``x`` ``(N, n)`` by complex step.

    ``func(x, idx)`` must be written with numpy functions that accept complex input (no ``abs``,
    no comparisons on the perturbed values). All ``n`` perturbed copies go in one call.
    """
    big_n, n = x.shape
    idx = np.arange(big_n) if idx is None else idx
    xs = np.repeat(x[None, :, :].astype(complex), n, axis=0)  # (n, N, n)
    xs[np.arange(n), :, np.arange(n)] += 1j * h
    f = func(xs.reshape(n * big_n, n), np.tile(idx, n)).reshape(n, big_n, -1)
    return np.moveaxis(f.imag / h, 0, -1)  # (N, m, n): d f_i / d x_k


def newton(
    func: Residual,
    x0: ArrayLike,
    *,
    jac: Callable[[NDArray, NDArray], NDArray] | None = None,
    tol: float = 1e-12,
    max_iter: int = 50,
    max_step: ArrayLike | None = None,
    line_search: int = 6,
) -> NewtonResult:
    """Solve ``func(x) = 0`` for every row of ``x0``.

    Parameters
    ----------
    func
        ``func(x, idx)`` maps ``(M, n)`` unknowns of the systems numbered ``idx`` ``(M,)`` to
        ``(M, n)`` residuals, row by row (``idx`` selects each system's own parameters; it is
        called on the still-active systems only). Scale the residuals so that ``tol`` means the
        same for every equation.
    x0
        ``(N, n)`` starting points.
    jac
        ``jac(x, idx)`` gives the ``(M, n, n)`` Jacobians; default: complex step of ``func``.
    tol
        Convergence when max |residual| of a system is <= tol.
    max_step
        ``(n,)`` largest change of each unknown per iteration (the step is scaled down as a whole,
        keeping the Newton direction); default unlimited.
    line_search
        Step halvings tried when a step does not reduce the residual norm.
    """
    x = np.array(x0, dtype=float, copy=True)
    if x.ndim != 2:
        raise ValueError(f"x0 must have shape (N, n), got {x.shape}")
    jac = jac or (lambda z, i: complex_step_jacobian(func, z, i))
    limit = None if max_step is None else np.broadcast_to(np.asarray(max_step, float), x.shape[1:])
    every = np.arange(len(x))
    f = func(x, every)
    norm = np.max(np.abs(f), axis=1)
    active = norm > tol
    iterations = 0
    while iterations < max_iter and np.any(active):
        iterations += 1
        idx = np.flatnonzero(active)
        xa, fa = x[idx], f[idx]
        ja = jac(xa, idx)
        step = _solve(ja, -fa)
        if limit is not None:
            scale = np.min(limit / np.maximum(np.abs(step), 1e-300), axis=1, initial=1.0)
            step *= np.minimum(scale, 1.0)[:, None]
        # backtracking: halve the step of systems whose residual grew
        t = np.ones(len(idx))
        trial = xa + step
        ft = func(trial, idx)
        nt = np.max(np.abs(ft), axis=1)
        for _ in range(line_search):
            worse = ~(nt < norm[idx]) & (t > 2.0**-line_search)
            if not np.any(worse):
                break
            t[worse] *= 0.5
            trial[worse] = xa[worse] + t[worse, None] * step[worse]
            ft[worse] = func(trial[worse], idx[worse])
            nt[worse] = np.max(np.abs(ft[worse]), axis=1)
        ok = np.isfinite(nt)
        x[idx[ok]], f[idx[ok]], norm[idx[ok]] = trial[ok], ft[ok], nt[ok]
        stalled = ~ok | (np.max(np.abs(t[:, None] * step), axis=1) == 0.0)
        active[idx] = (norm[idx] > tol) & ~stalled
    det = np.linalg.det(jac(x, every)) if len(x) else np.zeros(0)
    return NewtonResult(
        x=x, residual=f, converged=norm <= tol, iterations=iterations, jacobian_det=det
    )


def _solve(a: NDArray, b: NDArray) -> NDArray:
    """Batched ``a x = b``; if any system is singular, a batched least-squares step instead."""
    try:
        return np.linalg.solve(a, b[..., None])[..., 0]
    except np.linalg.LinAlgError:
        return np.einsum("...ij,...j->...i", np.linalg.pinv(a), b)
