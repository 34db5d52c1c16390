"""Node fields recalled between a mesh cycle's samples of its window.

A row's node fields (side, pinion angle, gear angle) depend on that row alone, so where a mesh
cycle samples its window again (re-centred or widened), the rows the last window sample held
take its node fields rather than being evaluated again: the same results, to the bit. The
refinement still runs on the whole batch (a refined minimum depends on its batch). The rows are
matched and their fields copied in one compiled pass (:func:`recall_rows`; numba, plain Python
without it, as :mod:`gearopt.contact.kernels`).
"""

from __future__ import annotations

import numpy as np

from gearopt.jit import ENABLED, compiled

__all__ = ["ENABLED", "RECALL_ROWS", "NodeFieldRecall", "recall_rows"]

#: the least rows of a sample whose node fields are remembered and recalled: a mesh cycle's
#: window, not its few extra rows
RECALL_ROWS = 32


@compiled
def recall_rows(side, phi, angle, last_side, last_phi, last_angle, fields, out):
    """Copy into ``out`` (``(3, n, nodes)``) the node fields ``fields`` (``(3, m, nodes)``) of
    the rows (``side``, ``phi``, ``angle``, each ``(n,)``) equal to one of the last rows
    (``last_side``, ``last_phi``, ``last_angle``, each ``(m,)``; ``==`` on each, as a dict of
    their tuples matches: no NaN matches); returns the rows matched by none, in order. Each
    row is looked for first after the last row matched (a window's rows follow one another)."""
    n, m = phi.shape[0], last_phi.shape[0]
    nodes = out.shape[2]
    new = np.empty(n, np.intp)
    k = 0
    hint = 0
    for r in range(n):
        found = -1
        for i in range(m):
            q = hint + i
            if q >= m:
                q -= m
            if side[r] == last_side[q] and phi[r] == last_phi[q] and angle[r] == last_angle[q]:
                found = q
                break
        if found < 0:
            new[k] = r
            k += 1
            continue
        hint = found + 1 if found + 1 < m else 0
        for c in range(3):
            for g in range(nodes):
                out[c, r, g] = fields[c, found, g]
    return new[:k]


class NodeFieldRecall:
    """The last window sample's rows and node fields, kept while :attr:`active` (a mesh
    cycle's run: :meth:`gearopt.contact.JointField.recalling`)."""

    def __init__(self) -> None:
        self.active = False
        self.last: tuple | None = None

    def switch(self, active: bool) -> None:
        """Start or end a run: nothing is kept from before."""
        self.active, self.last = active, None

    def fill(self, side, phi, angle, out) -> np.ndarray | None:
        """For a sample of at least :data:`RECALL_ROWS` rows while :attr:`active`: the node
        fields of those of its rows (side, pinion angle, gear angle; arrays the caller does
        not change afterwards) that the last such sample holds, copied into ``out``
        (``(3, n, nodes)``); this sample is remembered in its place. Returns the rows still to
        evaluate (None: all of them)."""
        if not self.active or len(phi) < RECALL_ROWS:
            return None
        last, self.last = self.last, (side, phi, angle, out)
        if last is None:
            return None
        new = recall_rows(side, phi, angle, *last, out)
        return None if len(new) == len(phi) else new
