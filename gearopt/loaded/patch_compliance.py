"""The compliance of contact patches by columns, computed by compiled kernels and kept: the
data of the compiled load distribution (:func:`gearopt.loaded.lcp.solve_load_patches`)."""

from __future__ import annotations

import numpy as np

from gearopt.loaded import kernels
from gearopt.loaded.halfspace import FAR_FIELD_RATIO

__all__ = ["PatchCompliance", "with_room"]


def with_room(rows: np.ndarray, held: int, more: int) -> np.ndarray:
    """``rows`` (a column cache's ``(capacity, n)`` rows, the first ``held`` in use) with room
    for ``more`` rows: itself, or grown to twice its capacity (at least to ``held + more``, at
    most ``n``) with the rows in use copied."""
    if held + more <= rows.shape[0]:
        return rows
    n = rows.shape[1]
    grown = np.empty((min(n, max(2 * rows.shape[0], held + more)), n))
    grown[:held] = rows[:held]
    return grown


class PatchCompliance:
    """The compliance of contact patches from their data, for the compiled solver
    (:func:`solve_load_patches`, :mod:`gearopt.loaded.lcp_kernels`), with the columns it has
    computed (kept across the solves of one set of patches, e.g. the torques of a sweep).

    ``C`` is block-diagonal over groups of patches (the tooth pairs: separate bodies), the
    groups ``starts[g]:starts[g + 1]``; within a group the half-spaces' local compliance of
    rectangles centred at ``(x, y)`` with half-sides ``(a, b)`` (mm; ``composite`` in mm^2/N,
    :func:`gearopt.loaded.halfspace.halfspace_columns_mm_per_n`) plus each member's influence
    numbers: ``members``, ``((table, points, weights), ...)``, a table (mm/N, symmetric) and
    the stencils of the patches on it (``(n, 16)``,
    :meth:`gearopt.loaded.compliance.ToothCompliance.stencil`). One group:
    ``starts = [0, n]``; :meth:`join` stacks groups.
    """

    def __init__(self, *, starts, x_mm, y_mm, a_mm, b_mm, composite_mm2_per_n, members) -> None:
        self.starts = np.ascontiguousarray(starts, dtype=np.intp)
        self.x, self.y, self.a, self.b = (
            np.ascontiguousarray(v, dtype=float) for v in (x_mm, y_mm, a_mm, b_mm)
        )
        self.composite = float(composite_mm2_per_n)
        self.members = tuple(
            (
                np.ascontiguousarray(table, dtype=float),
                np.ascontiguousarray(points, dtype=np.intp),
                np.ascontiguousarray(weights, dtype=float),
            )
            for table, points, weights in members
        )
        n = self.x.size
        self.slot = np.full(n, -1, dtype=np.intp)
        self.rows = np.empty((min(max(n, 1), 32), n))
        self.count = 0

    @property
    def size(self) -> int:
        """The number of patches."""
        return int(self.x.size)

    @classmethod
    def join(cls, parts) -> PatchCompliance:
        """One compliance of the groups of ``parts`` (the same composite and tables)."""
        parts = list(parts)
        sizes = [p.size for p in parts]
        starts = np.concatenate([[0], np.cumsum(sizes)])
        ends = zip(parts, starts[:-1], strict=True)
        blocks = np.concatenate([p.starts[1:] - p.starts[0] + s0 for p, s0 in ends])
        first = parts[0]
        return cls(
            starts=np.concatenate([[0], blocks]),
            x_mm=np.concatenate([p.x for p in parts]),
            y_mm=np.concatenate([p.y for p in parts]),
            a_mm=np.concatenate([p.a for p in parts]),
            b_mm=np.concatenate([p.b for p in parts]),
            composite_mm2_per_n=first.composite,
            members=tuple(
                (
                    table,
                    np.concatenate([p.members[k][1] for p in parts]),
                    np.concatenate([p.members[k][2] for p in parts]),
                )
                for k, (table, _, _) in enumerate(first.members)
            ),
        )

    def subset(self, rows) -> PatchCompliance:
        """The compliance of the patches ``rows`` (ascending) among themselves."""
        rows = np.asarray(rows, dtype=np.intp)
        group = np.searchsorted(self.starts, rows, side="right") - 1
        counts = np.bincount(group, minlength=self.starts.size - 1)
        return PatchCompliance(
            starts=np.concatenate([[0], np.cumsum(counts)]),
            x_mm=self.x[rows],
            y_mm=self.y[rows],
            a_mm=self.a[rows],
            b_mm=self.b[rows],
            composite_mm2_per_n=self.composite,
            members=tuple((t, k[rows], w[rows]) for t, k, w in self.members),
        )

    def fetch(self, idx) -> None:
        """Compute the columns ``idx`` not held yet (in one call of
        :func:`gearopt.loaded.kernels.patch_columns`)."""
        idx = np.asarray(idx, dtype=np.intp)
        missing = np.unique(idx[self.slot[idx] < 0])
        m, k = missing.size, self.count
        if m == 0:
            return
        self.rows = with_room(self.rows, k, m)
        kernels.patch_columns(
            self.starts,
            self.x,
            self.y,
            self.a,
            self.b,
            missing,
            self.composite / np.pi,
            FAR_FIELD_RATIO,
            self.members,
            self.rows[k : k + m],
        )
        self.slot[missing] = np.arange(k, k + m)
        self.count = k + m

    def __call__(self, idx) -> np.ndarray:
        """``C[:, idx]`` (``(n, len(idx))``), computed where not held."""
        idx = np.asarray(idx, dtype=np.intp)
        self.fetch(idx)
        return self.rows[self.slot[idx]].T

    def bending_mm(self, forces_n) -> np.ndarray:
        """The members' part of ``C F`` at every patch (mm): all of it but the half-spaces'
        local part, which is positive (:func:`gearopt.loaded.kernels.influence_times`)."""
        f = np.ascontiguousarray(forces_n, dtype=float)
        out = np.zeros(self.size)
        for table, points, weights in self.members:
            kernels.influence_times(points, weights, self.starts, table, f, out)
        return out
