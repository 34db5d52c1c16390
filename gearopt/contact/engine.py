"""The contact engine's computations on stacked tables of one or more clearance fields.

:class:`ContactEngine` holds, per field (side), the pinion's generated nodes, the local
interpolants' cell tables of both flanks (:attr:`gearopt.flank.FlankMap.cells`) and the affine
maps of the placement folded into a few tables, and evaluates the angular clearance
(:mod:`gearopt.contact.field`) on them: at every node for a batch of rows (side, pinion angle,
gear angle), at points off the nodes by the interpolants, the refined minimum (constrained Newton
steps), and the contact interval's ends. The hot loops are the compiled kernels of
:mod:`gearopt.contact.kernels`; this module prepares their tables and batches.
"""

from __future__ import annotations

import ctypes
import math
import operator

import numpy as np

from gearopt.contact import kernels as _kernels
from gearopt.contact.minima import minima_pick, minima_starts
from gearopt.contact.nodes import node_tables
from gearopt.contact.recall import NodeFieldRecall
from gearopt.contact.rows import row_constants
from gearopt.contact.samples import FieldSample
from gearopt.errors import GearoptError
from gearopt.flank import hermite_cells

__all__ = ["ContactEngine", "EngineRows", "node_tables", "remembered_tables"]

_HEAP = {"kept": False}
#: the near rows' start points of a sample without them (:func:`minima_starts` reads none)
_NO_NEAR = np.empty((2, 0))
#: the flank-only tables of the last few fields and engines (:func:`remembered_tables`)
_REMEMBERED: list[tuple[str, tuple, object]] = []


def remembered_tables(kind: str, flanks: tuple, make):
    """``make()``, or what it gave for the same ``kind`` and the same flanks (FlankMaps, by
    identity: a FlankMap is never changed in place) among the last few: tables of the flanks
    alone, which a study's evaluations of one design (aligned, misaligned: only the placement
    differs) would otherwise build again for every placement. The last used first: a gear's
    tables outlive the trials' pinions."""
    for i, (known, key, value) in enumerate(_REMEMBERED):
        if known == kind and len(key) == len(flanks) and all(map(operator.is_, key, flanks)):
            if i:
                _REMEMBERED.insert(0, _REMEMBERED.pop(i))
            return value
    value = make()
    _REMEMBERED.insert(0, (kind, tuple(flanks), value))
    del _REMEMBERED[16:]
    return value


def _equal(a, b) -> bool:
    """Whether grid arrays ``a`` and ``b`` are equal (the same array, often)."""
    return a is b or np.array_equal(a, b)


def _keep_heap() -> None:
    """Ask glibc (once per process) to keep freed memory for reuse: the analyses allocate and
    free arrays of a few hundred kB at every call, which with glibc's default thresholds
    (128 kB until its own adjustment, which only a freed larger block triggers) are mapped and
    returned to the system each time and faulted in again (some 500 page faults a TCA).
    Elsewhere (no ``mallopt``) nothing is done."""
    if _HEAP["kept"]:
        return
    _HEAP["kept"] = True
    try:
        mallopt = ctypes.CDLL(None).mallopt
    except (OSError, AttributeError):
        return
    mallopt(-3, 16 << 20)  # M_MMAP_THRESHOLD: blocks below 16 MiB come from the heap
    mallopt(-1, 64 << 20)  # M_TRIM_THRESHOLD: the heap's free top kept up to 64 MiB


def _stacked_tables(fields) -> dict:
    """The tables of :class:`ContactEngine` that depend on its fields' flanks alone (not on the
    placement): the sides' pinion node tables, padded and stacked, the cell tables of both
    flanks concatenated, the refinable and generated cells, the grid's cell size."""
    first = fields[0]
    tables = [f.node_tables for f in fields]
    ds, dh = tables[0]["cell_mm"]
    cell = np.array([ds, dh])
    # node tables (all grid nodes; off-mask nodes are +inf in the fields)
    # the generated pinion nodes of each side, padded to one count with at least one more
    # (padding: the first generated node again, its result dropped); components stored
    # apart, contiguous
    sizes = [t["nodes"].size for t in tables]
    count = max(sizes) + 1
    k = len(tables)
    node_index = np.empty((k, count), np.intp)
    node_slot = np.empty((k, tables[0]["slot"].size), np.intp)
    # points and normals ``(6, K, count)``: (x, y) of each side's nodes and of their normals
    # ``(2, K, count)``, z ``(K, count)``, contiguous parts of one table
    geometry = np.empty((6, k, count))
    for i, (t, n) in enumerate(zip(tables, sizes, strict=True)):
        node_index[i, :n] = t["nodes"]
        node_index[i, n:] = t["nodes"][0]
        geometry[:, i, :n] = t["geometry"]
        geometry[:, i, n:] = t["geometry"][:, :1]
        # each grid node's column in its side's node tables (off-mask: the padding after them)
        node_slot[i] = t["slot"]
    node_real = np.arange(count)[None, :] < np.array(sizes)[:, None]
    node_xy, node_nxy = geometry[:2], geometry[3:5]
    point_z, normal_z = geometry[2], geometry[5]
    points, normals = (node_xy[0], node_xy[1], point_z), (node_nxy[0], node_nxy[1], normal_z)
    # the refinable nodes and cells: the generated ones on the fine cells at the
    # generated boundary, else two cells above the lowest generated nodes (node_tables)
    refine_nodes = np.stack([t["keep"] for t in tables])
    refine_cells = np.ascontiguousarray(np.concatenate([t["cells"] for t in tables]))
    pinion_cells = len(tables[0]["cells"])
    # the kernels' one table of the flanks' cells and the fine cells at each side's generated
    # boundary after them, the band pointing there (:func:`gearopt.contact.kernels.pinion_at`)
    own = [f.pinion.cells.coefficients for f in fields]
    fine = [t["fine"][1] for t in tables]
    n_own = sum(len(c) for c in own)
    kernel_coef = np.concatenate(own + fine)
    pinion_coef, pinion_fine = kernel_coef[:n_own], kernel_coef[n_own:]
    # the fine cells' indices offset per side (in the fine cells' table; the band's -1: none)
    pinion_band = np.concatenate([t["fine"][0] for t in tables])
    start, offset = 0, 0
    for t, cells in zip(tables, fine, strict=True):
        side = pinion_band[start : start + len(t["fine"][0]), 0]
        side[side >= 0.0] += offset
        start, offset = start + len(t["fine"][0]), offset + len(cells)
    kernel_band = pinion_band.copy()
    kernel_band[:, 0] = np.where(pinion_band[:, 0] >= 0.0, pinion_band[:, 0] + n_own, -1.0)
    gear_cells = first.gear.cells.generated.size
    gear_coef, gear_ok = remembered_tables(
        "gear", tuple(f.gear for f in fields), lambda: _gear_tables(fields)
    )
    # where the tangency point is inside the pinion flank
    pinion_generated = np.ascontiguousarray(np.concatenate([t["generated"] for t in tables]))
    maps = _flank_maps(first)
    (imax, jmax), n_cols = maps["gear_table"]
    taper = maps["gear_taper"] or (0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    maps["gear_kernel"] = (
        *(float(a) for a in maps["rho_coef"]),
        float(imax),
        float(jmax),
        int(n_cols),
        maps["gear_taper"] is not None,
        *(float(a) for a in taper),
        gear_coef,
        np.ascontiguousarray(gear_ok),
    )
    (p0, ph0), (pia, pib) = (a[:, 0] for a in maps["pinion_unit"])
    (pimax, pjmax), p_cols = maps["pinion_table"]
    ptaper = maps["pinion_taper"]
    maps["pinion_kernel"] = (
        (
            float(p0),
            float(ph0),
            float(pia),
            float(pib),
            float(pimax),
            float(pjmax),
            int(p_cols),
            ptaper is not None,
            *((0.0, 0.0, 0.0) if ptaper is None else (ptaper.pivot_mm, ptaper.alpha, ptaper.beta)),
        ),
        (
            kernel_coef,
            np.ascontiguousarray(refine_cells),
            np.ascontiguousarray(kernel_band),
        ),
    )
    return maps | {
        "ds": ds,
        "dh": dh,
        "cell": cell,
        "node_index": node_index,
        "node_real": node_real,
        "node_counts": np.array(sizes, np.intp),
        "node_slot": node_slot,
        "points": points,
        "normals": normals,
        "node_xy": node_xy,
        "node_nxy": node_nxy,
        "refine_nodes": refine_nodes,
        "refine_cells": refine_cells,
        "pinion_cells": pinion_cells,
        "pinion_coef": pinion_coef,
        "pinion_band": pinion_band,
        "pinion_fine": pinion_fine,
        "kernel_coef": kernel_coef,
        "kernel_band": kernel_band,
        "gear_cells": gear_cells,
        "gear_coef": gear_coef,
        "gear_ok": gear_ok,
        "pinion_generated": pinion_generated,
    }


def _flank_maps(first) -> dict:
    """The parts of :meth:`ContactEngine._linear_maps` that depend on the grids alone (of the
    first field; the fields share them): the gear's unit grid coordinates' R2 coefficients and
    cell table's limits, its taper, the pinion's unit grid coordinates, cell table's limits,
    taper and pitch angle's cosine and sine."""
    gc, pc = first.gear.cells, first.pinion.cells
    s0, h0, ia, ib = gc.face0_mm, gc.profile0_mm, gc.face_scale, gc.profile_scale
    g = math.radians(first.gear.pitch_angle_deg)
    cg, sg = math.cos(g), math.sin(g)
    g1 = math.radians(first.pinion.pitch_angle_deg)
    gear_taper = first.gear.taper
    if gear_taper is not None:
        # unit coordinates (x, y) of (s, h) -> y of (s, t): with d = s - pivot,
        # y' = (y + ib (h0 - d alpha)) / (1 + d beta) - ib h0
        gear_taper = (s0 - gear_taper.pivot_mm, 1.0 / ia, ib, h0, gear_taper.alpha, gear_taper.beta)
    return {
        "rho_coef": np.array([ia * sg, ib * cg]),
        "gear_table": (np.array([gc.last_row, gc.last_column]), gc.columns),
        "gear_taper": gear_taper,
        "cos_sin_pitch": (math.cos(g1), math.sin(g1)),
        "pinion_unit": (
            np.array([[pc.face0_mm], [pc.profile0_mm]]),
            np.array([[pc.face_scale], [pc.profile_scale]]),
        ),
        "pinion_table": (np.array([pc.last_row, pc.last_column]), pc.columns),
        # tapered depth: the grids' profile coordinate is t, not the height (DepthTaper)
        "pinion_taper": first.pinion.taper,
    }


def _gear_tables(fields) -> tuple:
    """The gear flanks' cell tables of :func:`_stacked_tables` (they depend on the gears alone:
    a study's trials place new pinions against one gear): the coefficients and the generated
    cells, concatenated over the fields. Shared by the engines that remember them: never
    written."""
    gear_coef = np.concatenate([f.gear.cells.coefficients for f in fields])
    gear_ok = np.concatenate([f.gear.cells.generated for f in fields])
    return gear_coef, gear_ok


class EngineRows:
    """Per-row constants of the clearance (:meth:`ContactEngine._rows`): the coefficients of x and y
    in the four linear outputs (``kx``, ``ky``, each ``(4, ...)``), the gear's ideal turn, the
    gear's sense and the sides' offsets into the gear and pinion cell tables."""

    __slots__ = ("kx", "ky", "turn", "sense", "gear_offset", "pinion_offset")

    def __init__(self, kx, ky, turn, sense, gear_offset, pinion_offset) -> None:
        self.kx, self.ky, self.turn, self.sense = kx, ky, turn, sense
        self.gear_offset, self.pinion_offset = gear_offset, pinion_offset

    def kernel_rows(self, n: int) -> tuple:
        """The constants of n rows as :mod:`gearopt.contact.kernels` takes them: ``kx``, ``ky``
        ``(4, n)``, turn, sense, gear and pinion offsets ``(n,)``, each a writable contiguous
        array of one dtype (numba compiles one version per array type)."""
        return (
            np.array(self.kx, float).reshape(4, n),
            np.array(self.ky, float).reshape(4, n),
            np.array(self.turn, float).reshape(n),
            np.array(self.sense, float).reshape(n),
            np.array(self.gear_offset, np.intp).reshape(n),
            np.array(self.pinion_offset, np.intp).reshape(n),
        )

    def subset(self, rows) -> EngineRows:
        """The rows ``rows`` (an index or mask of the first axis)."""
        return EngineRows(
            self.kx[:, rows],
            self.ky[:, rows],
            self.turn[rows],
            self.sense[rows],
            self.gear_offset[rows],
            self.pinion_offset[rows],
        )


class ContactEngine:
    """The clearance computations on stacked tables of K fields (sides).

    Per side: the sense, the gear's polar-angle offset (phase minus whole pitches), the pinion
    nodes, the local interpolants' cell tables (pinion and gear, concatenated with an offset of
    one table per side) and the refinable cells. Shared: the placement, the ratio and the grids
    (the fields must share them).
    """

    def __init__(self, fields) -> None:
        _keep_heap()
        first = fields[0]
        for f in fields[1:]:
            # (one placement gives the same b and c: a pair's fields share theirs)
            same = (
                _equal(f.pinion.face_mm, first.pinion.face_mm)
                and _equal(f.pinion.profile_mm, first.pinion.profile_mm)
                and _equal(f.gear.face_mm, first.gear.face_mm)
                and _equal(f.gear.profile_mm, first.gear.profile_mm)
                and (
                    f.placement is first.placement
                    or (
                        np.all(np.abs(f.b - first.b) <= 1e-8 + 1e-5 * np.abs(first.b))
                        and np.all(np.abs(f.c - first.c) <= 1e-8 + 1e-5 * np.abs(first.c))
                    )
                )
                and f.ratio == first.ratio
            )
            if not same:
                raise GearoptError("fields", rule="joined fields must share grids and placement")
        self.b, self.c, self.ratio = first.b, first.c, first.ratio
        self.pinion_grid, self.gear_grid = first.pinion, first.gear
        self.pinion_nodes = (first.pinion.face_mm, first.pinion.profile_mm)
        self.shape = first.pinion.shape
        self.sense = np.array([f.sense for f in fields], float)
        self.gear_sense = -self.sense
        self.place(fields)
        flanks = tuple(m for f in fields for m in (f.pinion, f.gear))
        stacked = remembered_tables("engine", flanks, lambda: _stacked_tables(fields))
        for name, value in stacked.items():
            setattr(self, name, value)
        self._linear_maps(fields)
        self.kernel_tables = self._kernel_tables()

    def place(self, fields) -> None:
        """Take the fields' phases (the gears' polar-angle offsets) and node factors anew: the
        constants a field settles while it places its gear, once the engine is built (its other
        tables do not change)."""
        self.turn0 = np.array([f.gear_offset_rad for f in fields], float)
        self._maker = None  # (its turns changed: _row_maker)
        # mm of normal separation per rad of gear rotation, typical of each side (a fixed
        # tolerance in rad for the refinement's edge test)
        scale = np.array([f.node_factor_mm or 50.0 for f in fields])
        self.tol_rad = np.array([f.edge_tolerance_um * 1e-3 for f in fields]) / scale
        self.tol_um = np.array([f.edge_tolerance_um for f in fields])
        self.tolerances = np.empty((2, len(fields)))
        self.tolerances[0], self.tolerances[1] = self.tol_rad, self.tol_um
        #: the node fields a mesh cycle's window samples recall (off outside its runs)
        self.recalled = NodeFieldRecall()

    def _linear_maps(self, fields) -> None:
        """The affine maps of the evaluations, folded into a few tables.

        With the pinion turned by phi, ``q = B Rz(phi) p + c``; the gear's unit grid coordinates
        are ``x2 = (s2 - s0) / ds2``, ``y2 = (h2 - h0) / dh2`` with ``s2 = qz cos g + R2 sin g``,
        ``h2 = -qz sin g + R2 cos g``. Four outputs are linear in p: qx, qy and the qz parts of
        x2, y2 (``lin @ p + const``); x2, y2 add ``rho_coef * R2``. Turned by phi, output o is
        ``kx_o x + ky_o y + (lin_o2 z + const_o)`` with ``kx_o = lin_o0 cos + lin_o1 sin`` and
        ``ky_o = lin_o1 cos - lin_o0 sin``: ``rotation @ (cos, sin)`` gives (kx, ky).
        """
        first = fields[0]
        b, c = first.b, first.c
        gc = first.gear.cells
        s0, h0, ia, ib = gc.face0_mm, gc.profile0_mm, gc.face_scale, gc.profile_scale
        g = math.radians(first.gear.pitch_angle_deg)
        cg, sg = math.cos(g), math.sin(g)
        lin = np.array([b[0], b[1], ia * cg * b[2], -ib * sg * b[2]])
        const = np.array([c[0], c[1], ia * (cg * c[2] - s0), -ib * (sg * c[2] + h0)])
        self.rotation = np.empty((8, 2))
        self.rotation[:4, 0], self.rotation[:4, 1] = lin[:, 0], lin[:, 1]
        self.rotation[4:, 0], self.rotation[4:, 1] = lin[:, 1], -lin[:, 0]
        self.lin_z, self.const = np.ascontiguousarray(lin[:, 2]), const
        # the node tables: the z terms (with the constants) of every side's nodes; the
        # normals' z terms of qx, qy (no constants); their x, y: the flanks' (node_xy, node_nxy)
        self.node_z = lin[:, 2, None, None] * self.points[2] + const[:, None, None]
        self.node_nz = lin[:2, 2, None, None] * self.normals[2]
        # pinion grid coordinates (s, h) -> the pinion's unit grid coordinates, R1 and the
        # z terms (z = L1 = s cos g1 - h sin g1); the grids' parts: _flank_maps
        cg1, sg1 = self.cos_sin_pitch
        self.pinion_map = np.empty((5, 2))
        self.pinion_map[0] = sg1, cg1
        self.pinion_map[1:, 0], self.pinion_map[1:, 1] = lin[:, 2] * cg1, -lin[:, 2] * sg1
        self.pinion_const = np.zeros((5, 1))
        self.pinion_const[1:, 0] = const

    def _kernel_tables(self):
        """The tables of :mod:`gearopt.contact.kernels` (gear, pinion) and the node counts: the
        grids' parts made with the stacked tables (:func:`_stacked_tables`), the placement's."""
        head, tail = self.pinion_kernel
        pinion = (
            *head,
            np.ascontiguousarray(self.pinion_map),
            np.ascontiguousarray(self.pinion_const[:, 0]),
            *tail,
        )
        return self.gear_kernel, pinion, self.node_counts

    def untaper(self, xy) -> None:
        """Gear unit grid coordinates of (s, h) made those of (s, t), in place (tapered
        depth; nothing for uniform depth)."""
        if self.gear_taper is None:
            return
        d0, inv_ia, ib, h0, alpha, beta = self.gear_taper
        d = xy[0] * inv_ia + d0
        xy[1] = (xy[1] + ib * (h0 - d * alpha)) / (1.0 + d * beta) - ib * h0

    # --- evaluation ---------------------------------------------------------------------

    @staticmethod
    def cells_at(coef, xy, table, offset):
        """The local interpolant at unit grid coordinates ``xy`` (``(2, ...)``; cell tables
        ``coef``, ``offset`` cells in): ``(Theta, cell index, within the grid)``. Beyond the
        grid the edge cell's polynomial goes on (unit coordinates outside [0, 1])."""
        limit, n_cols = table
        uv = np.fmax(xy, 0.0)  # (fmax: a NaN coordinate takes cell 0, never a bad index)
        np.fmin(uv, limit.reshape((2,) + (1,) * (xy.ndim - 1)), out=uv)
        np.trunc(uv, out=uv)  # the cell's corner, in floats (no integer casts but one)
        corner = uv[0] * n_cols
        corner += uv[1]
        cell = corner.astype(np.intp)
        cell += offset
        np.subtract(xy, uv, out=uv)
        inside = uv >= 0.0
        inside &= uv <= 1.0
        return hermite_cells(coef, cell, uv[0], uv[1]), cell, inside[0] & inside[1]

    def row_tables(self, side, phi, angle=0.0) -> tuple:
        """The constants of rows (side, pinion angle, gear angle; 1-D, broadcast to one length)
        as the kernels take them (:meth:`EngineRows.kernel_rows`), in one compiled pass
        (:func:`gearopt.contact.rows.row_constants`): the same values as :meth:`rows_of`."""
        # (writable contiguous copies: numba compiles one version per array type)
        phi = np.array(np.atleast_1d(np.asarray(phi, float)).reshape(-1))
        n = phi.shape[0]
        side = np.array(np.broadcast_to(np.asarray(side, np.intp), (n,)))
        angle = np.array(np.broadcast_to(np.asarray(angle, float), (n,)))
        return row_constants(self._row_maker(), side, phi, angle)

    def _row_maker(self) -> tuple:
        """The engine's part of :func:`gearopt.contact.rows.row_constants`'s arguments (made
        once a placement, :meth:`place`)."""
        if self._maker is None:
            self._maker = (
                self.rotation,
                self.turn0,
                self.gear_sense,
                float(self.ratio),
                int(self.gear_cells),
                int(self.pinion_cells),
            )
        return self._maker

    def rows_of(self, side, phi, angle) -> EngineRows:
        """The per-row constants of rows (side, pinion angle, gear angle), broadcast to one
        shape; the rows' points broadcast against it."""
        side, phi, angle = np.broadcast_arrays(side, np.asarray(phi, float), angle)
        flat = phi.reshape(-1)
        cs = np.empty((2, flat.size))
        np.cos(flat, out=cs[0])
        np.sin(flat, out=cs[1])
        k = (self.rotation @ cs).reshape((2, 4) + phi.shape)
        turn = (angle + self.turn0[side]) - self.ratio * phi
        return EngineRows(
            k[0],
            k[1],
            turn,
            self.gear_sense[side],
            side * self.gear_cells,
            side * self.pinion_cells,
        )

    def clearance(self, rows: EngineRows, x, y, z, normals=None):
        """Angular clearance of pinion points with coordinates ``x``, ``y`` and z terms ``z``
        (``(4, ...)``, :meth:`_linear_maps`) on ``rows``:
        ``(delta, valid, R2, normal factor or None)``."""
        out = rows.kx * x
        out += rows.ky * y
        out += z
        radius = out[0] * out[0]
        radius += np.square(out[1])
        np.sqrt(radius, out=radius)
        theta = np.arctan2(out[1], out[0])
        xy = out[2:]
        xy += self.rho_coef.reshape((2,) + (1,) * radius.ndim) * radius
        self.untaper(xy)
        flank, cell, within = self.cells_at(self.gear_coef, xy, self.gear_table, rows.gear_offset)
        valid = self.gear_ok[cell]
        valid &= within
        gap = flank - theta
        gap += rows.turn
        turns = np.rint(gap * (0.5 / math.pi))
        turns *= 2.0 * math.pi
        gap -= turns
        gap *= rows.sense
        if normals is None:
            return gap, valid, radius, None
        nxy, nz = normals
        m = rows.kx[:2] * nxy[0]
        m += rows.ky[:2] * nxy[1]
        m += nz
        factor = m[1] * out[0]
        factor -= m[0] * out[1]
        return gap, valid, radius, np.abs(factor, out=factor)

    def gap(self, side, p, n, phi, gear_angle_rad=0.0):
        """Angular clearance of pinion points ``p = (x, y, z)`` (normals ``n``) at pinion angles
        ``phi`` on fields ``side`` (all broadcast): ``(delta, normal factor, R2, valid)``."""
        x, y, z = (np.asarray(a, float) for a in p)
        shape = np.broadcast_shapes(x.shape, y.shape, z.shape, np.shape(phi), np.shape(side))
        if not shape:  # a single point: as a one-element array
            one = self.gap(
                np.reshape(side, 1),
                [np.reshape(a, 1) for a in p],
                n and [np.reshape(a, 1) for a in n],
                np.reshape(phi, 1),
                np.reshape(gear_angle_rad, 1),
            )
            return tuple(None if a is None else a[0] for a in one)
        x, y, z = (np.broadcast_to(a, shape) for a in (x, y, z))
        # the rows' constants on their own shape (a pinion angle per row of points, say),
        # broadcast against the points where used
        side, phi, angle = np.broadcast_arrays(side, np.asarray(phi, float), gear_angle_rad)
        lead = (1,) * (len(shape) - phi.ndim)
        rows = self.rows_of(*(a.reshape(lead + phi.shape) for a in (side, phi, angle)))
        zt = self.lin_z.reshape((4,) + (1,) * len(shape)) * z
        zt += self.const.reshape((4,) + (1,) * len(shape))
        normals = None
        if n is not None:
            nx, ny, nz = (np.broadcast_to(np.asarray(a, float), shape) for a in n)
            normals = (np.stack([nx, ny]), self.lin_z[:2].reshape((2,) + (1,) * len(shape)) * nz)
        delta, valid, radius, factor = self.clearance(rows, x, y, zt, normals)
        return delta, factor, radius, valid

    def gap_of_rows(self, side, phi, points, normals, gear_angle_rad=0.0):
        """:meth:`gap` of row-wise points in one compiled pass
        (:func:`gearopt.contact.kernels.point_fields`): ``points`` and ``normals``
        ``(n, ..., 3)`` (member frame, unturned pinion), row r's points at side ``side[r]``,
        pinion angle ``phi[r]`` and gear angle ``gear_angle_rad[r]`` (each ``(n,)`` or a
        scalar). Returns ``(delta, normal factor, R2, valid, gear face, gear profile)``, each
        ``(n, ...)``: :meth:`gap`'s and the points' gear grid coordinates (mm; t on tapered
        depth)."""
        points = np.asarray(points, float)
        shape = points.shape[:-1]
        n = shape[0] if shape else 1
        side, phi, angle = (
            np.broadcast_to(np.asarray(a, dtype), (n,))
            for a, dtype in ((side, np.intp), (phi, float), (gear_angle_rad, float))
        )
        rows = self.rows_of(side, phi, angle).kernel_rows(n)
        flat = np.ascontiguousarray(points).reshape(n, -1, 3)
        out = np.empty((5,) + flat.shape[:2])
        valid = np.empty(flat.shape[:2], bool)
        normals = np.ascontiguousarray(np.broadcast_to(normals, points.shape), float)
        gear, _, _ = self.kernel_tables
        _kernels.point_fields(
            rows, flat, normals.reshape(flat.shape), self.lin_z, self.const, gear, out, valid
        )
        cells = self.gear_grid.cells
        face = cells.face0_mm + out[3] / cells.face_scale
        profile = cells.profile0_mm + out[4] / cells.profile_scale
        return tuple(a.reshape(shape) for a in (*out[:3], valid, face, profile))

    def at(self, side, sh, phi, gear_angle_rad, generated=False):
        """Clearance at pinion grid coordinates ``sh = (s, h)`` (``(2, ...)``) off the nodes by
        the local Hermite interpolants: ``(delta, valid)``. ``delta`` is the smooth extension
        beyond the flanks (finite everywhere); ``valid`` is False outside either flank and
        outside the pinion's refinable cells; with ``generated``, up to the pinion's generated
        boundary (:func:`node_tables`)."""
        shape = np.broadcast_shapes(sh.shape[1:], np.shape(side), np.shape(phi))
        if not shape:  # a single point: as a one-element array
            one = self.at(
                side, np.reshape(sh, (2, 1)), np.reshape(phi, 1), gear_angle_rad, generated
            )
            return one[0][0], one[1][0]
        side, phi, angle = np.broadcast_arrays(side, np.asarray(phi, float), gear_angle_rad)
        lead = (1,) * (len(shape) - phi.ndim)
        rows = self.rows_of(*(a.reshape(lead + phi.shape) for a in (side, phi, angle)))
        return self.clearance_on_rows(rows, np.broadcast_to(sh, (2,) + shape), generated)

    def point_tables(self, side, phi, generated=False):
        """The tables of the compiled point evaluations
        (:func:`gearopt.contact.kernels.clearance_at`) on rows (side, pinion angle; gear angle
        0), each ``(n,)``: ``(rows, pinion, gear)``; with ``generated``, valid on the
        generated cells rather than the refinable ones (:func:`node_tables`)."""
        return (self.row_tables(side, phi), *self.cell_tables(generated))

    def cell_tables(self, generated=False):
        """``(pinion, gear)``: the cell tables of the compiled point evaluations, the pinion's
        valid on its refinable cells or, with ``generated``, on its generated cells
        (:func:`node_tables`)."""
        gear, pinion, _ = self.kernel_tables
        if generated:
            pinion = (*pinion[:14], self.pinion_generated, *pinion[15:])
        return pinion, gear

    def clearance_on_rows(self, rows: EngineRows, sh, generated=False):
        """:meth:`at` on known rows by :func:`gearopt.contact.kernels.clearance_at`: rows
        ``(n, 1)`` and points ``(2, n, m)`` as the refinement has them, anything else one row
        per point; ``generated``: valid on the generated cells (:func:`node_tables`)."""
        shape = sh.shape[1:]
        if len(shape) == 2 and rows.turn.shape == (shape[0], 1):
            n, m = shape
            constants = rows.kernel_rows(n)
        else:
            n, m = math.prod(shape), 1
            constants = EngineRows(
                *(np.broadcast_to(k, (4,) + shape) for k in (rows.kx, rows.ky)),
                *(
                    np.broadcast_to(a, shape)
                    for a in (rows.turn, rows.sense, rows.gear_offset, rows.pinion_offset)
                ),
            ).kernel_rows(n)
        points = np.array(np.broadcast_to(sh, (2,) + shape)).reshape(2, n, m)
        delta, valid = np.empty((n, m)), np.empty((n, m), bool)
        _kernels.clearance_at(constants, points, *self.cell_tables(generated), delta, valid)
        return delta.reshape(shape), valid.reshape(shape)

    def sample(self, side, phi_rad, gear_angle_rad=0.0, refine=True, near=None):
        """The clearance field at the nodes for rows (side, phi, gear angle), minima refined
        on the rows ``refine`` selects; with ``near`` = ``(side, phi, s, h)`` (gear angle 0),
        also :meth:`near` of those rows in the same refinement: ``(sample, near)``. The node
        fields (a row's depend on it alone: those of a large sample's rows that the last large
        sample holds are taken from it, :meth:`recall`), then the minima in compiled calls
        (:mod:`gearopt.contact.minima`)."""
        phi = np.atleast_1d(np.asarray(phi_rad, float))
        n = len(phi)
        m = 0 if near is None else np.size(near[1])
        # the sampled rows, then the near rows (one table of constants for both)
        side_all, phi_all = np.empty(n + m, np.intp), np.empty(n + m)
        angle_all = np.zeros(n + m)
        side_all[:n], phi_all[:n], angle_all[:n] = side, phi, gear_angle_rad
        sh = _NO_NEAR
        if near is not None:
            sh = np.empty((2, m))
            side_all[n:], phi_all[n:], sh[0], sh[1] = near
        rows = row_constants(self._row_maker(), side_all, phi_all, angle_all)
        out = np.empty((3, n, self.shape[0] * self.shape[1]))
        gear, pinion, counts = self.kernel_tables
        new = self.recalled.fill(side_all[:n], phi_all[:n], angle_all[:n], out)
        part = out if new is None else np.empty((3, len(new), out.shape[2]))
        if part.shape[1]:
            _kernels.node_fields(
                rows if new is None else tuple(np.take(a, new, axis=-1) for a in rows),
                side_all if new is None else side_all[new],
                counts,
                self.node_index,
                self.node_xy,
                self.node_z,
                self.node_nxy,
                self.node_nz,
                gear,
                part,
            )
        if new is not None:
            out[:, new] = part
        point = np.empty((3, n))
        refined = np.empty(n, bool)
        refined[:] = refine
        at, which, s, h, best, caps, group, tol = minima_starts(
            out[0],
            side_all,
            refined,
            self.refine_nodes,
            2,
            sh,
            near is not None,
            self.tolerances,
            self.pinion_nodes,
            point,
        )
        flags = np.zeros(len(s), bool)
        if len(s):
            _kernels.refine(
                rows, which, s, h, best, caps, group, tol, self.cell, pinion, gear, flags
            )
        edge = np.empty(n, bool)
        minima_pick(
            out[1], side_all, refined, at, which, s, h, best, flags, self.tolerances, point, edge
        )
        fields = out.reshape((3, n) + self.shape)
        sample = FieldSample(
            phi_rad=phi,
            clearance_rad=fields[0],
            normal_factor_mm=fields[1],
            radius_mm=fields[2],
            minimum_rad=point[0],
            contact_face_mm=point[1],
            contact_profile_mm=point[2],
            edge=edge,
        )
        if near is None:
            return sample
        k = len(s) - m
        return sample, (best[k:], s[k:], h[k:], flags[k:])

    def interval_end(self, side: int, phi_rad, face_mm, profile_mm, step_rad, steps=128, tol=1e-6):
        """Where the tangency point leaves the flanks near pinion angle ``phi_rad`` (the
        contact point near ``(face_mm, profile_mm)``), stepping by ``step_rad`` toward the
        outside: :func:`gearopt.contact.kernels.interval_end` (point by point in Python
        without the compiled kernels). ``(phi_inside, phi_outside, s, h)`` or None."""
        gear, pinion, _ = self.kernel_tables
        maker = (
            np.ascontiguousarray(self.rotation),
            float(self.turn0[side]),
            float(self.ratio),
            float(self.gear_sense[side]),
            int(side * self.gear_cells),
            int(side * self.pinion_cells),
        )
        found, a, b, s, h = _kernels.interval_end(
            maker,
            float(phi_rad),
            float(face_mm),
            float(profile_mm),
            float(step_rad),
            int(steps),
            float(tol),
            np.array([self.ds, self.dh]),
            pinion,
            gear,
            self.pinion_generated,
        )
        return (float(a), float(b), float(s), float(h)) if found else None

    def near(self, side, phi_rad, face_mm, profile_mm, gear_angle_rad=0.0):
        """Refined minima started from known nearby contact points (no node field)."""
        phi = np.atleast_1d(np.asarray(phi_rad, float))
        side = np.broadcast_to(np.asarray(side, np.intp), phi.shape)
        angle = np.broadcast_to(np.asarray(gear_angle_rad, float), phi.shape).copy()
        s = np.broadcast_to(np.asarray(face_mm, float), phi.shape).copy()
        h = np.broadcast_to(np.asarray(profile_mm, float), phi.shape).copy()
        return self.refine(side, phi, angle, s, h, None, iterations=3)

    def refine(self, side, phi, angle, s, h, f0, iterations=4, group=None):
        """Constrained Newton steps on the clearance between the node grid's lines.

        Gradient and Hessian by central differences (a quarter cell) of the interpolated
        clearance, extended smoothly beyond the flanks; the step is Newton's on the positive
        curvatures and a descent of up to two cells along the others (the valley of line
        contact), at most two cells in all. A step leaving the flanks is cut back (halvings,
        evaluated at once with the next stencil) to the last valid point: repeated, this slides
        the point along the boundary to the least clearance on it, second order for straight
        edges.

        ``f0``: the start values (None or NaN: the interpolated value there). ``iterations``:
        the most steps, or one count per group of rows (``group``: each row's group); each
        group stops on its own, its rows then left as they are, so a group's results are those
        of a refinement of its rows alone.

        Returns ``(value, s, h, edge)``: edge where the Newton part of the last step would take
        the point off the flanks to a clearance lower by more than the edge tolerance.
        """
        n = len(s)
        s, h = np.array(s, float), np.array(h, float)
        best = np.full(n, np.nan) if f0 is None else np.array(f0, float)
        caps = np.atleast_1d(np.asarray(iterations, np.intp))
        group = np.zeros(n, np.intp) if group is None else np.asarray(group, np.intp)
        edge = np.zeros(n, bool)
        gear, pinion, _ = self.kernel_tables
        _kernels.refine(
            self.row_tables(side, phi, angle),
            np.arange(n),
            s,
            h,
            best,
            caps,
            group,
            self.tol_rad[side],
            np.array([self.ds, self.dh]),
            pinion,
            gear,
            edge,
        )
        return best, s, h, edge
