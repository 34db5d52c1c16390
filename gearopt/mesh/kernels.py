"""Compiled kernels of the mesh cycle's pattern at the nodes (numba; plain Python without it, as
:mod:`gearopt.contact.kernels`): the separations of every position's pairs, the pattern field
and the carrying zones' centroids in one pass over the node fields, where numpy makes a
temporary of every position's nodes at each step (:func:`gearopt.mesh.pattern.separation_mm`,
:func:`gearopt.mesh.pattern.centroids`: the same arithmetic, array by array).
"""

from __future__ import annotations

import math

import numpy as np

from gearopt.jit import ENABLED, compiled

__all__ = ["ENABLED", "pattern_fields", "warm"]


@compiled
def pattern_fields(clearance, factor, inv, lag, carrying, compound, face, profile, sep, out):
    """The pattern's node fields of a side's positions.

    Parameters
    ----------
    clearance, factor
        ``(R, N)`` the window sample's node clearances and node factors (normal or
        circumferential; N = n_f * n_p nodes, profile fastest).
    inv
        ``(n * pairs,)`` the sample's row of each position's pair (position-major).
    lag
        ``(n,)`` the carrying pair's lag at each position.
    carrying
        ``(n,)`` the carrying pair's column.
    compound
        The marking compound (mm).
    face, profile
        ``(n_f,)``, ``(n_p,)`` the nodes' pattern coordinates.
    sep
        ``(n * pairs, N)`` out: separations (mm) at the carrying lag, +inf off the flanks
        (:func:`gearopt.mesh.pattern.separation_mm`).
    out
        ``(N + 2 n,)`` out: the pattern field (the least separation over the positions and
        pairs, mm), then the carrying zones' centroids, face then profile
        (:func:`gearopt.mesh.pattern.centroids`).
    """
    n = lag.shape[0]
    pairs = inv.shape[0] // n
    n_p = profile.shape[0]
    size = clearance.shape[1]
    for g in range(size):
        out[g] = math.inf
    for k in range(inv.shape[0]):
        row = inv[k]
        ref = lag[k // pairs]
        for g in range(size):
            v = (clearance[row, g] - ref) * factor[row, g]
            if v != v:  # (inf - inf: nothing on the flanks; inf * 0: off them)
                v = math.inf
            sep[k, g] = v
            if v < out[g]:
                out[g] = v
    for i in range(n):
        k = i * pairs + carrying[i]
        total = ws = wh = 0.0
        least = math.inf
        at = 0
        for g in range(size):
            v = sep[k, g]
            if v < least:
                least, at = v, g
            w = compound - v
            if w > 0.0:
                total += w
                ws += w * face[g // n_p]
                wh += w * profile[g % n_p]
        if total > 0.0:
            out[size + i] = ws / total
            out[size + n + i] = wh / total
        else:  # no zone: its least-separated node
            out[size + i] = face[at // n_p]
            out[size + n + i] = profile[at % n_p]


def warm() -> None:
    """Compile the kernels, or load them from the disk cache (as
    :func:`gearopt.contact.kernel_warmup.warm`); nothing without them."""
    if not ENABLED:
        return
    one, index = np.zeros((1, 1)), np.zeros(1, np.intp)
    pattern_fields(
        one, one, index, np.zeros(1), index, 1.0, np.zeros(1), np.zeros(1), one.copy(), np.empty(3)
    )
