"""The nodes of :func:`gearopt.envelope.solve_envelope`'s grid: their face and profile
coordinates, heights and axial-plane targets (L, R) for every flank, made once per grid and
remembered (:func:`grid_nodes`): a study regenerates a member on one blank, so on the same
nodes, and their set-up was a fifth of the solver's numpy calls. And the nodes' sheet
(:func:`sheet_nodes`, compiled): which are on the envelope's sheet through the pitch row,
which are trimmed off above a fold, where each column leaves the sheet. And the grid's
values at points between its nodes (:func:`bilinear`, compiled: the solver's starts for points
off the nodes).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from gearopt.flank import DepthTaper, FlankGrid
from gearopt.jit import compiled

__all__ = ["GridNodes", "bilinear", "grid_nodes", "nearest_start", "sheet_nodes", "warm_kernels"]


@dataclass(frozen=True, kw_only=True, eq=False)
class GridNodes:
    """The nodes ``(s_i, t_j)`` of ``n_flanks`` grids ``(n_f, n_p)``, shared by every solve on
    the grid: read, never written. The arrays the compiled kernels take (``big_l``, ``big_r``,
    ``row_l``, ``row_r``) stay writable (a read-only array is another type to numba, another
    compilation); the others are read-only."""

    face_mm: NDArray  # (n_f,) cone distances s
    profile_mm: NDArray  # (n_p,) profile coordinates t (= h on uniform depth)
    height_mm: NDArray  # (n_f, n_p) heights h above the pitch cone
    flank: NDArray  # (k, n_f, n_p) each node's flank index (broadcast)
    big_l: NDArray  # (k, n_f, n_p) axial positions L of the nodes, contiguous
    big_r: NDArray  # (k, n_f, n_p) radii R
    row_l: NDArray  # (k n_f,) L on the pitch line (h = 0), flank by flank
    row_r: NDArray  # (k n_f,) R there
    row_flank: NDArray  # (k n_f,) their flank indices
    cos_sin: tuple[float, float]  # of the pitch angle
    pitch_row: int  # j0: the profile node nearest the pitch line
    neighbour: NDArray  # (n_p,) each node's neighbour toward the pitch row (j0 its own)


def grid_nodes(
    cone_distances_mm,
    heights_mm,
    pitch_angle_rad: float,
    grid: FlankGrid,
    taper: DepthTaper | None,
    n_flanks: int,
) -> GridNodes:
    """The :class:`GridNodes` of a grid (``solve_envelope``'s arguments), from the last few
    grids' when they are the same."""
    return _nodes(
        tuple(float(v) for v in cone_distances_mm),
        tuple(float(v) for v in heights_mm),
        float(pitch_angle_rad),
        grid,
        taper,
        int(n_flanks),
    )


def _read_only(a: NDArray) -> NDArray:
    a.setflags(write=False)
    return a


@functools.lru_cache(maxsize=8)
def _nodes(cone_distances_mm, heights_mm, pitch_angle_rad, grid, taper, k) -> GridNodes:
    s = np.linspace(*cone_distances_mm, grid.n_face)
    h = np.linspace(*heights_mm, grid.n_profile)
    n_f, n_p = grid.shape
    cg, sg = math.cos(pitch_angle_rad), math.sin(pitch_angle_rad)
    # the nodes' heights above the pitch cone (n_f, n_p): h in every column for uniform depth
    if taper is None:
        height = np.broadcast_to(h[None, :], (n_f, n_p))
    else:
        height = taper.height_mm(s[:, None], h[None, :])
    flank = np.broadcast_to(np.arange(k)[:, None, None], (k, n_f, n_p))
    j0 = int(np.argmin(np.abs(h)))
    return GridNodes(
        face_mm=_read_only(s),
        profile_mm=_read_only(h),
        height_mm=_read_only(np.array(height)),
        flank=flank,
        big_l=np.array(np.broadcast_to(s[:, None] * cg - height * sg, (k, n_f, n_p))),
        big_r=np.array(np.broadcast_to(s[:, None] * sg + height * cg, (k, n_f, n_p))),
        row_l=np.tile(s * cg, k),
        row_r=np.tile(s * sg, k),
        row_flank=_read_only(flank[:, :, 0].ravel()),
        cos_sin=(cg, sg),
        pitch_row=j0,
        neighbour=_read_only(np.arange(n_p) + np.sign(j0 - np.arange(n_p))),
    )


def sheet_nodes(converged: NDArray, det: NDArray, sign0: NDArray, nodes: GridNodes, trim_mm):
    """``(unfolded, connected, trimmed, top)`` of a solve on ``nodes``: from the nodes'
    convergence and Jacobian determinants' signs ``det`` ``(k, n_f, n_p)`` and the pitch row's
    ``sign0`` ``(k, n_f)``, the nodes whose sign is the pitch row's (unfolded), those connected
    to the pitch row through converged unfolded nodes of their column (the sheet), those at
    least ``trim_mm`` above the column's highest node below the pitch row off the sheet
    (trimmed; every node where there is none), and ``top`` ``(k, n_f)``, that highest node
    below the pitch row off the sheet (-1: none)."""
    k, n_f, n_p = converged.shape
    unfolded, connected = np.empty((k, n_f, n_p), bool), np.empty((k, n_f, n_p), bool)
    trimmed, top = np.empty((k, n_f, n_p), bool), np.empty((k, n_f), np.intp)
    _sheet_kernel(
        converged,
        det,
        sign0,
        nodes.height_mm,
        nodes.profile_mm,
        nodes.pitch_row,
        float(trim_mm),
        unfolded,
        connected,
        trimmed,
        top,
    )
    return unfolded, connected, trimmed, top


@compiled
def _sheet_kernel(converged, det, sign0, height, h, j0, trim_mm, unfolded, connected, trimmed, top):
    """:func:`sheet_nodes` column by column (into the last four arguments)."""
    k, n_f, n_p = converged.shape
    for f in range(k):
        for i in range(n_f):
            for j in range(n_p):
                unfolded[f, i, j] = det[f, i, j] == sign0[f, i]
            on = True
            for j in range(j0, n_p):
                on = on and converged[f, i, j] and unfolded[f, i, j]
                connected[f, i, j] = on
            on = True
            for j in range(j0, -1, -1):
                on = on and converged[f, i, j] and unfolded[f, i, j]
                connected[f, i, j] = on
            first_bad, highest = -math.inf, -1
            for j in range(n_p):
                if not connected[f, i, j]:
                    if h[j] < h[j0] and height[i, j] > first_bad:
                        first_bad = height[i, j]
                    if j < j0:
                        highest = j
            limit = first_bad + (trim_mm if math.isfinite(first_bad) else 0.0)
            for j in range(n_p):
                trimmed[f, i, j] = height[i, j] >= limit
            top[f, i] = highest


def bilinear(face_mm, profile_mm, values, s, h) -> NDArray:
    """``(n, c)`` bilinear interpolation of ``values`` ``(n_f, n_p, c)`` on the grid
    ``(face_mm, profile_mm)`` (ascending) at points ``(s, h)`` ``(n,)``, the edge cells'
    planes beyond the grid: the arithmetic of scipy's
    ``RegularGridInterpolator(method="linear", fill_value=None)``, the same bits, in one
    compiled pass (a NaN coordinate takes the last cell, as numpy's ``searchsorted``)."""
    face, profile = np.asarray(face_mm, float), np.asarray(profile_mm, float)
    flat = np.ascontiguousarray(values, dtype=float).reshape(-1, values.shape[-1])
    s, h = np.ascontiguousarray(s, dtype=float), np.ascontiguousarray(h, dtype=float)
    out = np.empty((len(s), flat.shape[1]))
    _bilinear_kernel(face, profile, flat, s, h, out)
    return out


@compiled
def _cell(grid, x):
    """The cell's index along one axis (numpy's ``searchsorted(side="right") - 1`` clipped
    to the cells) and the point's fraction across it."""
    n = len(grid)
    lo, hi = 0, n
    while lo < hi:  # the first node above x (NaN: none)
        mid = (lo + hi) // 2
        if x < grid[mid]:
            hi = mid
        else:
            lo = mid + 1
    k = min(max(lo - 1, 0), n - 2)
    return k, (x - grid[k]) / (grid[k + 1] - grid[k])


@compiled
def _bilinear_kernel(face, profile, flat, s, h, out):
    """:func:`bilinear` point by point into ``out`` (the corner terms in numpy's order)."""
    n_p = len(profile)
    for p in range(len(s)):
        i, y0 = _cell(face, s[p])
        j, y1 = _cell(profile, h[p])
        a0, a1 = 1.0 - y0, 1.0 - y1
        k = i * n_p + j
        w00, w01, w10, w11 = a0 * a1, a0 * y1, y0 * a1, y0 * y1
        for c in range(flat.shape[1]):
            v = flat[k, c] * w00
            v += flat[k + 1, c] * w01
            v += flat[k + n_p, c] * w10
            v += flat[k + n_p + 1, c] * w11
            out[p, c] = v


def nearest_start(face_mm, profile_mm, ok, ds, dh, reach):
    """``(bad, from_)``: the points not ``ok`` (indices) that have a point ``ok`` no farther
    from the pitch line (``|profile_mm|`` not greater) within ``reach`` grid cells (cell
    sizes ``ds``, ``dh``; finite coordinates), and the nearest such point of each (the first
    of equal distance): :meth:`gearopt.envelope.EnvelopeSurface.parameters_at`'s repair
    starts, the squared distances as numpy's ``((a - b) / ds) ** 2 + ((c - d) / dh) ** 2``,
    in one compiled pass over the pairs (no ``(bad, good)`` matrices)."""
    bad = np.flatnonzero(~ok)
    good = np.flatnonzero(ok)
    face = np.ascontiguousarray(face_mm, dtype=float)
    profile = np.ascontiguousarray(profile_mm, dtype=float)
    pick = np.empty(len(bad), np.intp)
    near = np.empty(len(bad), np.bool_)
    _nearest_kernel(face, profile, bad, good, float(ds), float(dh), float(reach), pick, near)
    return bad[near], good[pick[near]]


@compiled
def _nearest_kernel(face, profile, bad, good, ds, dh, reach, pick, near):
    """:func:`nearest_start` into ``pick`` (the index into ``good``) and ``near``."""
    for b in range(len(bad)):
        fb, pb = face[bad[b]], profile[bad[b]]
        best, at = math.inf, 0
        for g in range(len(good)):
            if abs(profile[good[g]]) > abs(pb):
                continue
            d_s = (face[good[g]] - fb) / ds
            d_h = (profile[good[g]] - pb) / dh
            gap = d_s * d_s
            gap += d_h * d_h
            if gap < best:
                best, at = gap, g
        pick[b] = at
        near[b] = best <= reach * reach


def warm_kernels() -> None:
    """Compile :func:`sheet_nodes`', :func:`bilinear`'s and :func:`nearest_start`'s kernels,
    or load them from numba's disk cache, with the argument types the solver passes (a
    grid's read-only heights)."""
    nodes = grid_nodes((1.0, 2.0), (-1.0, 1.0), 0.5, FlankGrid(n_face=4, n_profile=4), None, 1)
    shape = (1, 4, 4)
    sheet_nodes(np.ones(shape, bool), np.ones(shape), np.ones((1, 4)), nodes, 0.3)
    bilinear(np.arange(2.0), np.arange(2.0), np.zeros((2, 2, 3)), np.zeros(1), np.zeros(1))
    nearest_start(np.zeros(2), np.zeros(2), np.array([True, False]), 1.0, 1.0, 0.5)
