"""The contact engine's numpy reference: the computations its compiled kernels do
(:mod:`gearopt.contact.kernels`), in whole-array numpy, as the engine ran them before the
kernels existed. Kept for the kernels' parity test (``tests/test_contact_kernels.py``), which
puts these functions in place of the engine's methods and compares every output of the
analyses; production code never imports this module.
"""

from __future__ import annotations

import math
import threading

import numpy as np
from numpy.typing import NDArray

from gearopt.contact.boundary import band_theta
from gearopt.contact.engine import ContactEngine, EngineRows
from gearopt.contact.samples import FieldSample
from gearopt.flank import hermite_cells

from . import numpy_zone

AROUND_ROWS = 32  # batches up to this many rows evaluate the stencils of all cut-backs
JOINT_ROWS = 16  # node fields of up to this many rows: all sides in one evaluation
FRACTIONS = np.array([1.0, 0.5, 0.25, 0.125, 0.0625])
STENCIL = np.array(
    [(0, 0), (1, 0), (-1, 0), (0, 1), (0, -1), (1, 1), (1, -1), (-1, 1), (-1, -1)], float
)

_WORK = threading.local()

#: the engine's methods this module replaces
METHODS = ("sample", "clearance_on_rows", "refine")


def install(monkeypatch) -> None:
    """Put the numpy reference in place of the engine's compiled methods (pytest's
    ``monkeypatch``), and the zones' numpy scans in place of theirs
    (:mod:`tests.numpy_zone`): every engine then evaluates with numpy."""
    for name in METHODS:
        monkeypatch.setattr(ContactEngine, name, globals()[name])
    numpy_zone.install(monkeypatch)


def _work(name: str, shape, dtype=float) -> NDArray:
    """A scratch array kept between calls (per thread, grown as needed): the node fields'
    temporaries, so that they are neither allocated nor page-faulted in again at each
    evaluation (glibc returns freed heap tops to the system and maps them anew)."""
    size = math.prod(shape)
    store = getattr(_WORK, "arrays", None)
    if store is None:
        store = _WORK.arrays = {}
    buf = store.get(name)
    if buf is None or buf.size < size or buf.dtype != dtype:
        buf = store[name] = np.empty(size, dtype)
    return buf[:size].reshape(shape)


def node_clearance(self, rows: EngineRows, side, count: int):
    """:meth:`_clearance` of the first ``count`` node-table points of ``side`` (an index, or
    one per row) with the normal factor on ``rows`` (``(m, 1)``), every array in scratch
    space (:func:`_work`): the results are overwritten by the next call."""
    shape = (rows.turn.shape[0], count)
    if np.ndim(side):  # one side per row
        x, y = self.node_xy[0, side, :count], self.node_xy[1, side, :count]
        nx, ny = self.node_nxy[0, side, :count], self.node_nxy[1, side, :count]
        z, nz = self.node_z[:, side, :count], self.node_nz[:, side, :count]
    else:  # one side: its tables broadcast over the rows
        x, y = self.node_xy[0, side, :count], self.node_xy[1, side, :count]
        nx, ny = self.node_nxy[0, side, :count], self.node_nxy[1, side, :count]
        z, nz = self.node_z[:, side, None, :count], self.node_nz[:, side, None, :count]
    out, tmp = _work("out", (4,) + shape), _work("tmp", (4,) + shape)
    np.multiply(rows.kx, x, out=out)
    np.multiply(rows.ky, y, out=tmp)
    out += tmp
    out += z
    radius = _work("radius", shape)
    np.multiply(out[0], out[0], out=radius)
    np.multiply(out[1], out[1], out=tmp[0])
    radius += tmp[0]
    np.sqrt(radius, out=radius)
    theta = np.arctan2(out[1], out[0], out=_work("theta", shape))
    # the normal factor |m x q| with m the turned normal
    m = tmp[:2]
    np.multiply(rows.kx[:2], nx, out=m)
    np.multiply(rows.ky[:2], ny, out=tmp[2:])
    m += tmp[2:]
    m += nz
    factor = np.multiply(m[1], out[0], out=_work("factor", shape))
    np.multiply(m[0], out[1], out=tmp[2])
    factor -= tmp[2]
    np.abs(factor, out=factor)
    xy = out[2:]
    np.multiply(self.rho_coef[:, None, None], radius, out=tmp[:2])
    xy += tmp[:2]
    self.untaper(xy)
    # the gear's cells (as _cells)
    limit, n_cols = self.gear_table
    uv = np.fmax(xy, 0.0, out=tmp[:2])
    np.fmin(uv, limit[:, None, None], out=uv)
    np.trunc(uv, out=uv)
    corner = np.multiply(uv[0], n_cols, out=tmp[2])
    corner += uv[1]
    cell = _work("cell", shape, np.intp)
    np.copyto(cell, corner, casting="unsafe")
    cell += rows.gear_offset
    np.subtract(xy, uv, out=uv)
    inside = np.greater_equal(uv, 0.0, out=_work("inside", (2,) + shape, bool))
    inside &= np.less_equal(uv, 1.0, out=_work("inside2", (2,) + shape, bool))
    # (mode="clip": the cells are valid; the default "raise" buffers ``out``)
    c = np.take(self.gear_coef, cell, axis=0, out=_work("coef", shape + (16,)), mode="clip")
    gap = hermite_cells(c, None, uv[0], uv[1])
    valid = np.take(self.gear_ok, cell, out=_work("valid", shape, bool), mode="clip")
    valid &= inside[0]
    valid &= inside[1]
    gap -= theta
    gap += rows.turn
    turns = np.multiply(gap, 0.5 / math.pi, out=theta)
    np.rint(turns, out=turns)
    turns *= 2.0 * math.pi
    gap -= turns
    gap *= rows.sense
    return gap, valid, radius, factor


def node_fields(self, side, phi, angle):
    """The clearance, normal factor and R2 at every grid node for rows (side, phi, gear
    angle), each ``(n, nodes)``: +inf, 0, 0 off the pinion's generated nodes."""
    n, size = len(phi), self.shape[0] * self.shape[1]
    field_, fac, rad = np.empty((n, size)), np.empty((n, size)), np.empty((n, size))
    # each side's rows on its own generated nodes (its node tables broadcast over rows)
    # and a padding node, the grid gathered from them (off-mask nodes take the padding
    # node, set to +inf); a few rows of several sides go in one evaluation, each row with
    # its side's node tables
    sides = np.unique(side)
    joint = len(sides) > 1 and n <= JOINT_ROWS
    if joint:
        out = node_clearance(
            self,
            self.rows_of(side[:, None], phi[:, None], angle[:, None]),
            side,
            self.node_index.shape[1],
        )
    for k in sides:
        count = int(self.node_real[k].sum())
        rows = np.flatnonzero(side == k) if len(self.sense) > 1 else np.arange(n)
        if joint:
            delta, valid, radius, factor = (a[rows, : count + 1] for a in out)
        else:
            delta, valid, radius, factor = node_clearance(
                self, self.rows_of(k, phi[rows, None], angle[rows, None]), k, count + 1
            )
        values = np.where(valid, delta, np.inf)
        values[:, count] = np.inf
        factor[:, count] = 0.0
        radius[:, count] = 0.0
        slot = self.node_slot[k]
        if rows[-1] - rows[0] == len(rows) - 1:  # (the usual case: a block of rows)
            block = slice(rows[0], rows[-1] + 1)
            for dest, src in ((field_, values), (fac, factor), (rad, radius)):
                np.take(src, slot, axis=1, out=dest[block], mode="clip")
        else:
            field_[rows], fac[rows], rad[rows] = (
                values[:, slot],
                factor[:, slot],
                radius[:, slot],
            )
    return field_, fac, rad


def clearance_on_rows(self, rows: EngineRows, sh, generated=False):
    """``ContactEngine.clearance_on_rows``."""
    origin, scale = self.pinion_unit
    xy = sh - origin.reshape((2,) + (1,) * (sh.ndim - 1))
    xy *= scale.reshape((2,) + (1,) * (sh.ndim - 1))
    _, cell, within = self.cells_at(self.pinion_coef, xy, self.pinion_table, rows.pinion_offset)
    limit = self.pinion_table[0].reshape((2,) + (1,) * (xy.ndim - 1))
    corner = np.trunc(np.fmin(np.fmax(xy, 0.0), limit))
    u, v = xy[0] - corner[0], xy[1] - corner[1]
    # the pinion's fine cells at its generated boundary (gearopt.contact.boundary)
    theta = band_theta(self.pinion_coef, self.pinion_band, self.pinion_fine, cell, u, v)
    flat = sh.reshape(2, -1)
    if self.pinion_taper is not None:  # (s, t) -> (s, h)
        flat = np.stack([flat[0], self.pinion_taper.height_mm(flat[0], flat[1])])
    lin = self.pinion_map @ flat
    lin += self.pinion_const
    lin = lin.reshape((5,) + sh.shape[1:])
    big_r = lin[0]
    delta, valid, _, _ = self.clearance(rows, big_r * np.cos(theta), big_r * np.sin(theta), lin[1:])
    valid &= within
    table = self.pinion_generated if generated else self.refine_cells
    valid &= v >= table[cell, 0] + table[cell, 1] * u
    return delta, valid


def lowest_nodes(self, flat, side, pick, values) -> None:
    """The refinement's candidate nodes (:func:`gearopt.contact.minima.minima_starts`)."""
    n = len(flat)
    inner = np.where(self.refine_nodes[side], flat, np.inf)
    rows = np.arange(n)
    for c in range(pick.shape[1]):  # the lowest, the next lowest, ...
        pick[:, c] = inner.argmin(axis=1)
        values[:, c] = inner[rows, pick[:, c]]
        inner[rows, pick[:, c]] = np.inf


def refine(self, side, phi, angle, s, h, f0, iterations=4, group=None):
    """``ContactEngine.refine``."""
    cell = np.array([[self.ds], [self.dh]])
    quarter = STENCIL.T[:, None, :] * (0.25 * cell[:, :, None])  # (2, 1, 9) mm
    fr = FRACTIONS
    nf = len(fr)
    n = len(s)
    rows = np.arange(n)
    edge = np.zeros(n, bool)
    tol = self.tol_rad[side]
    sh = np.stack([s, h])
    every = self.rows_of(side[:, None], phi[:, None], angle[:, None])
    # a small batch costs numpy's per-call overhead, not points: it evaluates the stencils
    # around every cut-back point with the step, so that no point needs a call of its own
    around = nf if n <= AROUND_ROWS else 1
    f, ok0 = self.clearance_on_rows(every, sh[:, :, None] + quarter)
    start = np.where(ok0[:, 0], f[:, 0], np.inf)
    best = start if f0 is None else np.where(np.isnan(f0), start, f0)
    caps = np.atleast_1d(iterations)
    groups = [np.ones(n, bool)] if group is None else [group == g for g in range(len(caps))]
    active = np.ones(n, bool)
    small = 1e-3 * min(self.ds, self.dh)
    for it in range(int(caps.max())):
        d = f @ DIFFERENCES  # gradient and Hessian in cell units
        g2, h2 = d[:, :2].T, (d[:, 2], d[:, 3], d[:, 4])
        step, curved = _pseudo_newton(g2, *h2)
        # the Newton part's predicted fall (a valley's slope along itself is not edge)
        fall = -(
            g2[0] * curved[0]
            + g2[1] * curved[1]
            + 0.5 * (h2[0] * curved[0] ** 2 + 2 * h2[1] * curved[0] * curved[1])
            + 0.5 * h2[2] * curved[1] ** 2
        )
        # the step cut back by halvings, the Newton part's end, and the stencil around the
        # full step (not after the last step), at once
        ts = sh[:, :, None] + fr * (step * cell)[:, :, None]
        parts = [ts, sh[:, :, None] + (curved * cell)[:, :, None]]
        if it < max(c for c, g in zip(caps, groups, strict=True) if (g & active).any()) - 1:
            parts.append((ts[:, :, :around, None] + quarter[:, :, None, 1:]).reshape(2, n, -1))
        fa, oka = self.clearance_on_rows(every, np.concatenate(parts, axis=2))
        ft, ok = fa[:, :nf], oka[:, :nf]
        ok &= ft <= best[:, None] + 1e-13 * np.abs(best[:, None])
        k = np.argmax(ok, axis=1)
        take = ok[rows, k]
        take &= active
        # edge: the Newton part would take the point off the flanks, where the clearance
        # falls on by more than the tolerance (the minimum is pressed against the boundary)
        edge = np.where(active, ~oka[:, nf] & (fall > tol), edge)
        new = ts[:, rows, k]
        moved = np.abs(new - sh).sum(axis=0)
        sh = np.where(take, new, sh)
        best = np.where(take, ft[rows, k], best)
        # a group stops at its last step or converged: none of its rows moved more than a
        # thousandth of a cell
        moving = take & (moved > small)
        for cap, g in zip(caps, groups, strict=True):
            if it == cap - 1 or not (moving & g).any():
                active &= ~g
        if not active.any():
            break
        take &= active
        known = np.flatnonzero(take & (k < around))
        f[known, 0] = ft[known, k[known]]
        f[known, 1:] = fa[:, nf + 1 :].reshape(n, around, -1)[known, k[known]]
        need = take & (k >= around)  # a point that stayed keeps its stencil
        if need.any():
            f[need], _ = self.clearance_on_rows(every.subset(need), sh[:, need, None] + quarter)
    return best, sh[0], sh[1], edge


def sample(self, side, phi_rad, gear_angle_rad=0.0, refine=True, near=None):
    """``ContactEngine.sample`` as numpy ran it before
    :func:`gearopt.contact.minima.sample_minima`: the clearance field at the nodes for rows
    (side, phi, gear angle), minima refined on the rows ``refine`` selects; with ``near`` =
    ``(side, phi, s, h)`` (gear angle 0), also :meth:`near` of those rows in the same
    refinement: ``(sample, near)``."""
    phi = np.atleast_1d(np.asarray(phi_rad, float))
    side = np.broadcast_to(np.asarray(side, np.intp), phi.shape)
    angle = np.broadcast_to(np.asarray(gear_angle_rad, float), phi.shape).copy()
    n = len(phi)
    field_, fac, rad = node_fields(self, side, phi, angle)
    shape = (n,) + self.shape
    field_, fac, rad = field_.reshape(shape), fac.reshape(shape), rad.reshape(shape)
    i, j = _argmin_nodes(field_)
    rows = np.arange(len(phi))
    f0 = field_[rows, i, j]
    s = self.pinion_grid.face_mm[i]
    h = self.pinion_grid.profile_mm[j]
    edge = np.zeros(len(phi), bool)
    rows = np.flatnonzero(np.broadcast_to(np.asarray(refine, bool), phi.shape))
    near_out = None
    if near is not None and not rows.size:
        near_out = self.near(*near)
    elif rows.size == n:  # every row refined: no copies of the node fields
        f0, s, h, edge, near_out = _refined(
            self, side, field_, fac, phi, angle, f0, s, h, near=near, node_min=(i, j)
        )
    elif rows.size or near is not None:
        f0, s, h = f0.copy(), s.copy(), h.copy()
        f0[rows], s[rows], h[rows], edge[rows], near_out = _refined(
            self,
            side[rows],
            field_[rows],
            fac[rows],
            phi[rows],
            angle[rows],
            f0[rows],
            s[rows],
            h[rows],
            near=near,
        )
    out = FieldSample(
        phi_rad=phi,
        clearance_rad=field_,
        normal_factor_mm=fac,
        radius_mm=rad,
        minimum_rad=f0,
        contact_face_mm=s,
        contact_profile_mm=h,
        edge=edge,
    )
    return out if near is None else (out, near_out)


def _refined(
    self, side, field_, fac, phi, angle, f0, s, h, candidates: int = 2, near=None, node_min=None
):
    """Refine the minimum from the ``candidates`` lowest refinable nodes (constrained
    Newton, :meth:`refine`) and keep the least. A node minimum outside the refinable
    region (the pinion's lowest cells) lower than that by more than the edge tolerance
    stands as it is, flagged as edge contact. ``near`` rows ``(side, phi, s, h)`` are
    refined alongside (as :meth:`near`); their results come last (None without).
    ``node_min``: the rows' node minima ``(i, j)`` where known."""
    n = len(phi)
    flat = field_.reshape(n, -1)
    pick = np.empty((n, min(candidates, flat.shape[1])), np.intp)
    values = np.empty(pick.shape)
    lowest_nodes(self, flat, np.array(side, np.intp), pick, values)
    ci, cj = np.unravel_index(pick, self.shape)
    ok = np.isfinite(values)
    best = np.full(n, np.inf)
    s_best, h_best = s.copy(), h.copy()
    e_best = np.zeros(n, bool)
    near_out = None
    if ok.any() or near is not None:
        rows = np.broadcast_to(np.arange(n)[:, None], ok.shape)[ok]
        starts = (
            side[rows],
            phi[rows],
            angle[rows],
            self.pinion_grid.face_mm[ci[ok]],
            self.pinion_grid.profile_mm[cj[ok]],
            values[ok],
        )
        if near is None:
            v, s_r, h_r, e_r = self.refine(*starts)
        else:  # the near rows: a second group, started from their points
            m = len(near[0])
            extra = (near[0], near[1], np.zeros(m), near[2], near[3], np.full(m, np.nan))
            group = np.repeat([0, 1], [rows.size, m])
            joined = [np.concatenate(pair) for pair in zip(starts, extra, strict=True)]
            out = self.refine(*joined, iterations=(4, 3), group=group)
            near_out = tuple(a[rows.size :] for a in out)
            v, s_r, h_r, e_r = (a[: rows.size] for a in out)
        order = np.lexsort((v, rows))
        rows, v, s_r, h_r, e_r = rows[order], v[order], s_r[order], h_r[order], e_r[order]
        first = np.ones(rows.size, bool)  # each row's least (none where no node is)
        first[1:] = rows[1:] != rows[:-1]
        best[rows[first]] = v[first]
        s_best[rows[first]], h_best[rows[first]] = s_r[first], h_r[first]
        e_best[rows[first]] = e_r[first]
    rows = np.arange(n)
    i, j = _argmin_nodes(field_) if node_min is None else node_min
    tol = self.tol_um[side] * 1e-3 / np.maximum(fac[rows, i, j], 1e-9)
    with np.errstate(invalid="ignore"):
        low = np.isfinite(f0) & ~(best - f0 <= tol)
    value = np.where(low, f0, best)
    s_best, h_best = np.where(low, s, s_best), np.where(low, h, h_best)
    return value, s_best, h_best, low | e_best, near_out


def _argmin_nodes(field_: NDArray) -> tuple[NDArray, NDArray]:
    n = field_.shape[0]
    flat = field_.reshape(n, -1).argmin(axis=1)
    return np.unravel_index(flat, field_.shape[1:])


def _differences() -> NDArray:
    """``(9, 5)``: stencil values (:data:`STENCIL`, a quarter cell) to the gradient and
    the Hessian (ss, sh, hh) in cell units by central differences."""
    d = np.zeros((9, 5))
    d[1, 0], d[2, 0] = 2.0, -2.0
    d[3, 1], d[4, 1] = 2.0, -2.0
    d[[1, 2], 2], d[0, 2] = 16.0, -32.0
    d[[5, 8], 3], d[[6, 7], 3] = 4.0, -4.0
    d[[3, 4], 4], d[0, 4] = 16.0, -32.0
    return d


DIFFERENCES = _differences()


def _pseudo_newton(g, hss, hsh, hhh, free: float = 2.0) -> tuple[NDArray, NDArray]:
    """``(2, n)`` steps of 2 x 2 symmetric systems (gradient ``g``, ``(2, n)``): Newton's
    -H^+ g on the positive eigenvalues plus a descent of at most ``free`` cells along the others
    (a valley or a ridge keeps its slope), at most two cells per component; and the Newton part
    alone."""
    n = hss.shape[0]
    mean = hss + hhh
    mean *= 0.5
    half = hss - hhh
    half *= 0.5
    root = half * half
    root += hsh * hsh
    np.sqrt(root, out=root)
    scale = np.abs(hss)
    scale += np.abs(hhh)
    np.maximum(scale, 1e-300, out=scale)
    lam = np.empty((2, n))
    np.add(mean, root, out=lam[0])
    np.subtract(mean, root, out=lam[1])
    tiny = 1e-6 * scale
    if np.all(lam[1] > tiny):
        # both curvatures positive everywhere: the Newton step -H^-1 g, which is the same
        # when it is within ``free`` cells along both eigenvectors (shorter than ``free``)
        det = hss * hhh - hsh * hsh
        step = np.empty_like(g)
        np.divide(hsh * g[1] - hhh * g[0], det, out=step[0])
        np.divide(hsh * g[0] - hss * g[1], det, out=step[1])
        if np.all(np.einsum("ij,ij->j", step, step) <= free * free):
            return step, step
    # unit eigenvectors (ex, ey) of lam[0] and (-ey, ex) of lam[1]
    diagonal = np.abs(hsh) <= 1e-12 * scale
    larger = hss >= hhh
    v = np.empty((2, 2, n))  # (eigenpair, component, row)
    np.copyto(v[0, 0], hsh)
    np.subtract(lam[0], hss, out=v[0, 1])
    v[0, 0, diagonal] = larger[diagonal]
    v[0, 1, diagonal] = ~larger[diagonal]
    norm = np.hypot(v[0, 0], v[0, 1])
    norm[~(norm > 0.0)] = 1.0
    v[0] /= norm
    np.negative(v[0, 1], out=v[1, 0])
    v[1, 1] = v[0, 0]
    slope = v[:, 0] * g[0]
    slope += v[:, 1] * g[1]
    use = lam > tiny
    along = -slope / np.where(use, lam, 1.0)
    np.minimum(along, free, out=along)
    np.maximum(along, -free, out=along)
    steep = np.abs(slope) > 1e-9 * np.maximum(np.hypot(g[0], g[1]), 1e-300)
    descent = np.sign(slope)
    descent *= -free
    descent *= steep
    along = np.where(use, along, descent)
    step = along[0] * v[0]
    step += along[1] * v[1]
    along *= use
    curved = along[0] * v[0]
    curved += along[1] * v[1]
    for a in (step, curved):
        np.minimum(a, 2.0, out=a)
        np.maximum(a, -2.0, out=a)
    return step, curved
