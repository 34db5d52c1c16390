"""The node tables of a clearance field's pinion flank (:func:`node_tables`): its generated
nodes, their points and normals, the refinable and generated cells, the fine cells at the
generated boundary; the contact engine (:mod:`gearopt.contact.engine`) stacks them per side.
"""

from __future__ import annotations

import numpy as np

from gearopt.contact.boundary import boundary_cells

__all__ = ["node_tables"]


def node_tables(pinion) -> dict:
    """The node tables of a field's pinion flank (a field keeps them: it is not changed once
    made): its generated nodes (flat indices), their points and normals (``geometry``
    ``(6, n)``: the points' x, y, z, then the normals'), each grid node's column among them
    (``slot``; off-mask nodes n), the refinable nodes and cells (the generated ones, evaluated
    on the fine cells at the generated boundary,
    :func:`gearopt.contact.boundary.boundary_cells`: the flank's own interpolant is poor near
    the envelope's fold; on a flank without them, two cells above the lowest generated nodes),
    the generated cells, the fine cells' tables (``fine``), the grid's cell size.

    A cell's entry is ``(c0, c1)``: its points at unit coordinates ``(u, v)`` are in where
    ``v >= c0 + c1 u`` (:func:`gearopt.contact.kernels.clearance_at`; ``(2, 0)``: none,
    ``(0, 0)``: all). The generated cells (``generated``: where the tangency point is inside
    the flank, and the zones' extent, :mod:`gearopt.mesh.zone`) end at the flank's lowest
    generated profile coordinate, linear across the cell
    (:attr:`gearopt.flank.FlankMap.lowest_profile_mm`, continuous: the envelope's fold
    solved), so that the contact interval's ends and the pattern reach the generated
    boundary wherever the grid's nodes lie; on a flank known to its nodes only, the cells of
    four generated nodes.
    """
    mask = pinion.mask
    nodes = np.flatnonzero(mask.ravel())
    n = nodes.size
    # points and normals in one table (3 + 3, n): contiguous parts for the stacking
    # (_stacked_tables) and the compiled kernels
    geometry = np.empty((6, n))
    np.take(pinion.points_mm.reshape(-1, 3), nodes, axis=0, out=geometry[:3].T)
    np.take(pinion.normals.reshape(-1, 3), nodes, axis=0, out=geometry[3:].T)
    profile = np.asarray(pinion.profile_mm, float)
    dp = float(np.mean(np.diff(profile)))
    fine = boundary_cells(pinion)
    keep = mask.copy()
    for _ in range(0 if fine else 2):
        below = np.zeros_like(keep)
        below[:, 1:] = keep[:, :-1]
        keep &= below
    generated = np.zeros(((mask.shape[0] - 1) * (mask.shape[1] - 1), 2))
    lowest = getattr(pinion, "lowest_profile_mm", None)
    if lowest is None:
        generated[~pinion.cells.generated, 0] = 2.0
    else:
        with np.errstate(invalid="ignore"):
            b0 = (lowest[:-1, None] - profile[None, :-1]) / dp
            b1 = (lowest[1:, None] - profile[None, :-1]) / dp
        top = mask[:-1, 1:] & mask[1:, 1:]
        on = top & np.isfinite(b0) & np.isfinite(b1) & (np.minimum(b0, b1) < 1.0)
        full = on & (b0 <= 0.0) & (b1 <= 0.0)
        part = on & ~full
        generated[:, 0] = np.where(full, 0.0, np.where(part, b0, 2.0)).ravel()
        generated[:, 1] = np.where(part, b1 - b0, 0.0).ravel()
    if fine:
        limits = generated  # the fine cells are accurate up to the generated boundary
    else:
        cells = keep[:-1, :-1] & keep[1:, :-1] & keep[:-1, 1:] & keep[1:, 1:]
        limits = np.zeros((cells.size, 2))
        limits[~cells.ravel(), 0] = 2.0
        fine = (np.full((cells.size, 4), -1.0), np.zeros((1, 16)))
    # each grid node's column in the node tables (off-mask: n, the padding after them)
    slot = np.full(mask.size, n, np.intp)
    slot[nodes] = np.arange(n)
    return {
        "fine": fine,
        "nodes": nodes,
        "slot": slot,
        "geometry": geometry,
        "keep": keep.ravel(),
        "cells": limits,
        "generated": generated,
        "cell_mm": (float(np.mean(np.diff(pinion.face_mm))), dp),
    }
