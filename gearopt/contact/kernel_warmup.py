"""The contact engine's compiled kernels (:mod:`gearopt.contact.kernels`) warmed in a process:
:func:`warm` compiles each on tables of the engine's types, or loads it from numba's disk
cache."""

from __future__ import annotations

import numpy as np

from gearopt.contact import boundary_kernels, kernels, zone_kernels
from gearopt.contact.minima import minima_pick, minima_starts
from gearopt.contact.recall import recall_rows
from gearopt.contact.rows import row_constants

__all__ = ["warm", "warm_engine", "warm_zones"]


def _tables() -> tuple:
    """``(rows, pinion, gear)``: tables of the engine's types (one cell, zero coefficients)."""
    ip = np.intp
    coef, ok = np.zeros((1, 16)), np.ones(1, np.bool_)
    gear = (0.0, 0.0, 0.0, 0.0, 1, False, 0.0, 1.0, 1.0, 0.0, 0.0, 0.0, coef, ok)
    lin, const = np.zeros((5, 2)), np.zeros(5)
    limits = np.zeros((1, 2))
    band = np.full((1, 4), -1.0)
    pinion = (0.0, 0.0, 1.0, 1.0, 0.0, 0.0, 1, False, 0.0, 0.0, 0.0, lin, const, coef, limits)
    pinion += (band,)
    rows = (
        np.zeros((4, 1)),
        np.zeros((4, 1)),
        np.zeros(1),
        np.ones(1),
        np.zeros(1, ip),
        np.zeros(1, ip),
    )
    return rows, pinion, gear


def warm() -> None:
    """Compile every kernel, or load it from the disk cache, in this process, on tables of the
    engine's types (one cell, zero coefficients): done once before worker processes start, so
    that they load the cache rather than compile it side by side (numba's cache is not safe
    for concurrent writers). Nothing without the kernels."""
    warm_engine()
    warm_zones()


def warm_engine() -> None:
    """:func:`warm` of the engine's kernels (:mod:`gearopt.contact.kernels`, the minima, the
    rows' constants, the recall, the boundary cells), not the zones'."""
    if not kernels.ENABLED:
        return
    ip = np.intp
    rows, pinion, gear = _tables()
    limits = pinion[14]
    side, count, index = np.zeros(1, ip), np.ones(1, ip), np.zeros((1, 1), ip)
    one_side = np.zeros(1)
    maker = (np.zeros((8, 2)), one_side, one_side, 1.0, 1, 1)
    row_constants(maker, side, np.zeros(1), np.zeros(1))
    xy, z = np.zeros((2, 1, 1)), np.zeros((4, 1, 1))
    kernels.node_fields(
        rows, side, count, index, xy, z, xy.copy(), xy.copy(), gear, np.empty((3, 1, 1))
    )
    kernels.clearance_at(
        rows, np.zeros((2, 1, 1)), pinion, gear, np.empty((1, 1)), np.empty((1, 1), np.bool_)
    )
    kernels.point_fields(
        rows,
        np.zeros((1, 1, 3)),
        np.zeros((1, 1, 3)),
        np.zeros(4),
        np.zeros(4),
        gear,
        np.empty((5, 1, 1)),
        np.empty((1, 1), np.bool_),
    )
    cell = np.ones(2)
    kernels.refine(
        rows,
        np.zeros(1, ip),
        np.zeros(1),
        np.zeros(1),
        np.full(1, np.nan),
        np.ones(1, ip),
        np.zeros(1, ip),
        np.zeros(1),
        cell,
        pinion,
        gear,
        np.zeros(1, np.bool_),
    )
    maker = (np.zeros((8, 2)), 0.0, 1.0, 1.0, 0, 0)
    kernels.interval_end(maker, 0.0, 0.0, 0.0, 0.01, 1, 1e-3, cell, pinion, gear, limits)
    one, flag = np.zeros((1, 1)), np.ones(1, np.bool_)
    tolerances, grid = np.ones((2, 1)), (np.zeros(1), np.zeros(1))
    keep, point = flag.reshape(1, 1), np.empty((3, 1))
    at, which, *_ = minima_starts(
        one, side, flag, keep, 2, np.zeros((2, 1)), False, tolerances, grid, point
    )
    minima_pick(
        one,
        side,
        flag,
        at,
        which,
        np.zeros(1),
        np.zeros(1),
        np.zeros(1),
        flag,
        tolerances,
        np.zeros((3, 1)),
        np.empty(1, np.bool_),
    )
    fields = np.zeros((3, 1, 1))
    recall_rows(side, np.zeros(1), np.zeros(1), side, np.zeros(1), np.zeros(1), fields, fields)
    boundary_kernels.warm()


def warm_zones() -> None:
    """:func:`warm` of the marking-compound zone's kernels (:mod:`gearopt.contact.zone_kernels`:
    they inline the engine's point helpers and write no cache file of the engine's)."""
    if not kernels.ENABLED:
        return
    ip = np.intp
    rows, pinion, gear = _tables()
    zone = (np.zeros(1), np.zeros((1, 2, 2)), 0.0, 1.0, 0.0, 1.0, 0.0, 0.0, 1.0)
    start, pair_row, tau = np.array([0, 1], ip), np.zeros(1, ip), np.zeros((1, 2))
    rays, zoom, out = np.zeros((1, 4)), np.linspace(0.0, 1.0, 3), np.empty(1)
    zone_kernels.ray_samples(rays, np.zeros(4), out, np.ones(1, np.bool_), zoom, zoom, tau)
    zone_kernels.union_exits(rows, pinion, gear, zone, start, pair_row, rays, tau, zoom, out)
    zone_kernels.separations(rows, pinion, gear, zone, pair_row, np.zeros((1, 2)), out)
    zone_kernels.ring_clearances(
        rows, pinion, gear, pair_row, out, out.copy(), np.zeros((1, 2)), np.empty((1, 2))
    )
    none = np.full(1, -1, ip)
    zone_kernels.swept_exits(
        rows, pinion, gear, zone, start, pair_row, none, none, rays, tau, zoom, out
    )
    two, index = np.zeros((2, 2)), np.zeros(6, ip)
    zone_kernels.outline_stations(out, out, 1.0, 0.0, 1.0, 2, index)
    zone_kernels.outline_rays(two, two[:1], 1.0, np.empty((6, 2)), np.empty((6, 2)), index, index)
