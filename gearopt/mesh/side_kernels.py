"""The compiled gathers of a side's result (:meth:`gearopt.mesh.side.SideCycle.assemble`): the
rows of the zones to measure and the carrying pair's contact points, in one pass rather than a
dozen numpy calls on arrays of a few dozen entries.

Definitions: :mod:`gearopt.mesh`.
"""

from __future__ import annotations

import numpy as np

from gearopt.jit import ENABLED, compiled

__all__ = ["carried_rows", "warm"]


@compiled
def carried_rows(
    held, pairs, inv, phi, lag, cs, ch, ids, carrying, edge_all, toe, root, ints, floats, edge
):
    """A side's pattern rows and carrying contact points (:meth:`SideCycle.assemble`).

    Parameters
    ----------
    held
        ``(m,)`` the entries (position * pairs + pair) whose zones are measured.
    pairs
        The pairs at each position.
    inv, phi
        ``(n * pairs,)`` each entry's row of the window's sample; ``(rows,)`` the rows' pinion
        angles.
    lag
        ``(n,)`` the carrying pair's lag at each position.
    cs, ch, ids, edge_all
        ``(n * pairs,)`` the entries' contact points (pinion grid), pair ids and edge flags.
    carrying
        ``(n,)`` the carrying pair's column at each position.
    toe, root
        The pattern coordinates' origin on the pinion grid.
    ints
        ``(2, m)`` out: each held entry's position and its row of the sample.
    floats
        ``(5 m + 2 n,)`` out: the held entries' pinion angles, lags (the carrying pair's at their
        position), pair ids, contact points ``(m, 2)`` (face, profile), then the carrying
        pair's contact face and profile in pattern coordinates at each position.
    edge
        ``(n,)`` out: the carrying pair's edge flag at each position.
    """
    m = held.shape[0]
    n = carrying.shape[0]
    for k in range(m):
        entry = held[k]
        position = entry // pairs
        row = inv[entry]
        ints[0, k] = position
        ints[1, k] = row
        floats[k] = phi[row]
        floats[m + k] = lag[position]
        floats[2 * m + k] = ids[entry]
        floats[3 * m + 2 * k] = cs[entry]
        floats[3 * m + 2 * k + 1] = ch[entry]
    for i in range(n):
        entry = i * pairs + carrying[i]
        floats[5 * m + i] = cs[entry] - toe
        floats[5 * m + n + i] = ch[entry] - root
        edge[i] = edge_all[entry]


def warm() -> None:
    """Compile the kernel, or load it from the disk cache (as
    :func:`gearopt.mesh.kernels.warm`); nothing without the kernels."""
    if not ENABLED:
        return
    entries = np.zeros(2, np.intp)
    values = np.zeros(2)
    carried_rows(
        np.zeros(1, np.intp),
        2,
        entries,
        values,
        np.zeros(1),
        values,
        values,
        values,
        np.zeros(1, np.intp),
        np.zeros(2, np.bool_),
        0.0,
        0.0,
        np.empty((2, 1), np.intp),
        np.empty(7),
        np.empty(1, np.bool_),
    )
