"""Node fields recalled between a mesh cycle's samples of its window.

A row's node fields (side, pinion angle, gear angle) depend on that row alone, so where a mesh
cycle samples its window again (re-centred or widened), the rows the last window sample held
take its node fields rather than being evaluated again: the same results, to the bit. The
refinement still runs on the whole batch (a refined minimum depends on its batch).
"""

from __future__ import annotations

import numpy as np

__all__ = ["RECALL_ROWS", "NodeFieldRecall"]

#: the least rows of a sample whose node fields are remembered and recalled: a mesh cycle's
#: window, not its few extra rows
RECALL_ROWS = 32


class NodeFieldRecall:
    """The last window sample's rows and node fields, kept while :attr:`active` (a mesh
    cycle's run: :meth:`gearopt.contact.JointField.recalling`)."""

    def __init__(self) -> None:
        self.active = False
        self.last: tuple[dict, np.ndarray] | None = None

    def switch(self, active: bool) -> None:
        """Start or end a run: nothing is kept from before."""
        self.active, self.last = active, None

    def fill(self, side, phi, angle, out) -> np.ndarray | None:
        """For a sample of at least :data:`RECALL_ROWS` rows while :attr:`active`: the node
        fields of those of its rows (side, pinion angle, gear angle) that the last such sample
        holds, copied into ``out`` (``(3, n, nodes)``); this sample is remembered in its place.
        Returns the rows still to evaluate (None: all of them)."""
        if not self.active or len(phi) < RECALL_ROWS:
            return None
        keys = list(zip(side.tolist(), phi.tolist(), angle.tolist(), strict=True))
        last, self.last = self.last, ({key: r for r, key in enumerate(keys)}, out)
        if last is None:
            return None
        where, fields = last
        at = [where.get(key, -1) for key in keys]
        known = [r for r, a in enumerate(at) if a >= 0]
        if not known:
            return None
        out[:, known] = fields[:, [at[r] for r in known]]
        return np.flatnonzero(np.array(at) < 0)
