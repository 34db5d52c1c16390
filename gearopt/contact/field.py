"""The contact engine: the clearance field between two FlankMaps in the housing frame.

Machine-independent: it sees a pinion flank and a gear flank (FlankMaps, member frames as in
:mod:`gearopt.flank`), the shaft angle and the misalignment, nothing else.

Housing frame S_f (DESIGN.md): origin at the nominal crossing point of the axes, x_f along the
pinion axis toward the pinion's back, the gear axis in the x_f-z_f plane at the shaft angle Sigma
from x_f, y_f = z_f x x_f. The pinion frame maps x_p -> z_f, y_p -> -y_f, z_p -> x_f, so the
pitch point of tooth 0 (polar angle 0) lies in the x_f-z_f plane on the side z_f > 0; the gear
frame is S_f turned about y_f so that z_g = (cos Sigma, 0, sin Sigma). Misalignment: the pinion
moves by (dA1, dE, 0), the gear along its own axis by dA2 and its axis turns about y_f to
Sigma + dGamma.

Kinematics. The pinion turns by phi about +z_p; a pitch point then moves along -y_f, and the gear
follows by turning -(N1/N2) phi about +z_g. For a pinion node P turned by phi and expressed in the
gear frame at (L2, R2, theta), the gear flank at the ideal gear angle has the polar angle
Theta2(L2, R2) - (N1/N2) phi; the *angular clearance*

    delta(P, phi) = sigma2 * (Theta2(L2, R2) - (N1/N2) phi - theta)        (rad of gear rotation)

is how far the driven gear must lag behind its ideal position (sigma2 = -s is the sense of the
gear's polar angle when the pinion turns with sense s) before its flank reaches P. The gear's
actual position lags by the minimum over the flank and the tooth pairs, so the transmission error
is TE = -min delta (negative when the gear lags, seed 003 eqs 5-6). Tooth pair k (pinion tooth k
against gear tooth -k) at pinion angle phi is the base pair at phi + 2 pi k / N1, so one clearance
function of the relative angle serves every pair.

The node minimum is refined below the grid spacing by constrained Newton steps on the local
bicubic Hermite interpolants of both flanks (:meth:`gearopt.flank.FlankMap.polar_angle_local`):
a pseudo-inverse on the positive curvatures, so the valley of line contact is handled, and steps
cut back at the flanks' boundaries, so a minimum pressed against an edge slides along it (edge
contact). Separations for the pattern: the angular clearance above the minimum times
|n . (z_g x q)| (normal) or times R2 (circumferential at equal radius, seed 003 section 5).
"""

from __future__ import annotations

import ctypes
import math
import threading
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from gearopt.assembly import Placement
from gearopt.contact import kernels as _kernels
from gearopt.errors import GearoptError
from gearopt.flank import FlankMap, hermite_cells

__all__ = [
    "ContactError",
    "Placement",
    "ClearanceField",
    "JointField",
    "FieldSample",
    "PointClearance",
]


class ContactError(GearoptError):
    """The flanks cannot be brought into contact as asked (no contact inside the flanks)."""


@dataclass(frozen=True, kw_only=True)
class FieldSample:
    """The clearance field at a set of relative pinion angles (one row per angle).

    Attributes
    ----------
    phi_rad
        ``(n,)`` relative pinion angles of the base pair (pinion angle + k pitches).
    clearance_rad
        ``(n, n_f, n_p)`` angular clearance delta; +inf where the node is not on both flanks.
    normal_factor_mm, radius_mm
        ``(n, n_f, n_p)`` |n . (z_g x q)| and R2: mm of normal / circumferential separation per
        rad of gear rotation.
    minimum_rad
        ``(n,)`` refined minimum of the clearance (+inf when nothing is in contact).
    contact_face_mm, contact_profile_mm
        ``(n,)`` pinion grid coordinates (s, h) of the refined minimum.
    edge
        ``(n,)`` True where the minimum lies on the boundary of the flanks (edge contact).
    """

    phi_rad: NDArray
    clearance_rad: NDArray
    normal_factor_mm: NDArray
    radius_mm: NDArray
    minimum_rad: NDArray
    contact_face_mm: NDArray
    contact_profile_mm: NDArray
    edge: NDArray


@dataclass(frozen=True, kw_only=True)
class PointClearance:
    """The clearance field at given pinion points (:meth:`ClearanceField.clearance_of_points`).

    Attributes
    ----------
    clearance_rad
        The angular clearance delta: how far the gear must turn back (rad) before its flank
        reaches the point.
    normal_factor_mm, radius_mm
        |n . (z_g x q)| (zero without normals) and R2: mm of normal and of circumferential
        separation per rad of gear rotation.
    valid
        Whether the point faces the gear flank (its image lies on the gear's generated cells).
    """

    clearance_rad: NDArray
    normal_factor_mm: NDArray | None
    radius_mm: NDArray
    valid: NDArray

    def separation_mm(self, minimum_rad, kind: str = "normal") -> NDArray:
        """The separation above a contact whose clearance is ``minimum_rad``: ``"normal"``
        (along the pinion's normal) or ``"circumferential"`` (at equal radius, seed 003
        section 5)."""
        factor = self.normal_factor_mm if kind == "normal" else self.radius_mm
        return (self.clearance_rad - minimum_rad) * factor


class ClearanceField:
    """Angular clearance between a driving pinion flank and a driven gear flank.

    Parameters
    ----------
    pinion, gear
        FlankMaps of tooth 0 (the pinion's driving flank, the gear's driven flank), each on a
        uniform grid; both flanks of a member share one grid when fields are joined.
    placement
        Shaft angle and misalignment.
    sense
        +1 or -1: the sense in which the pinion turns (about +z_p). With ``sense=None`` it is
        the sense in which the pinion flank pushes (its normal's circumferential component at the
        middle node), i.e. the flank drives.
    phase_rad
        The gear's rotation about +z_g at pinion angle 0 (the assembly's phase). ``None``: the
        angle that brings the two flanks together at the mean position (the drive side); the
        other side of the same pair takes the drive side's phase, so that both flanks face the
        same tooth space. The gear tooth that mates is picked by whole pitches.
    edge_tolerance_um
        A minimum pressed against a boundary is edge contact only when the clearance would fall
        on beyond it by more than this (normal separation); flat valleys of line contact
        reaching an edge are not.
    """

    def __init__(
        self,
        pinion: FlankMap,
        gear: FlankMap,
        *,
        placement: Placement,
        sense: int | None = None,
        phase_rad: float | None = None,
        edge_tolerance_um: float = 0.05,
    ) -> None:
        if pinion.member != "pinion" or gear.member != "gear":
            raise GearoptError(
                "flanks", (pinion.member, gear.member), "must be a pinion and a gear FlankMap"
            )
        self.pinion, self.gear, self.placement = pinion, gear, placement
        self.ratio = pinion.teeth / gear.teeth
        self.b, self.c = placement.pinion_to_gear
        if sense is None:
            mid = tuple(np.array(pinion.shape) // 2)
            p, n = pinion.points_mm[mid], pinion.normals[mid]
            sense = 1 if (p[0] * n[1] - p[1] * n[0]) > 0.0 else -1
        if sense not in (1, -1):
            raise GearoptError("sense", sense, "must be +1 or -1")
        self.sense = int(sense)
        self.edge_tolerance_um = float(edge_tolerance_um)
        if int(pinion.mask.sum()) < 4:
            raise ContactError(
                "pinion flank", int(pinion.mask.sum()), "needs at least 4 generated nodes"
            )
        self.phase_rad, self._shift = 0.0, 0.0
        self._engine = _Engine([self])
        if phase_rad is None:
            delta, valid = self._node_clearance()
            phase_rad = -self.gear_sense * float(np.median(delta[valid]))
        self.phase_rad = float(phase_rad)
        self._engine = _Engine([self])
        delta, valid = self._node_clearance()
        centre = float(np.median(self.gear_sense * delta[valid]))
        self._factor_mm = self._node_factor
        pitch = self.gear.pitch_rad
        self._shift = pitch * round(centre / pitch)
        self._engine = _Engine([self])

    def _node_clearance(self):
        sample = self._engine.sample(np.zeros(1, np.intp), np.zeros(1), 0.0, refine=False)
        valid = np.isfinite(sample.clearance_rad[0])
        if valid.any():
            self._node_factor = float(np.median(sample.normal_factor_mm[0][valid]))
        if not valid.any():
            raise ContactError(
                "flanks", rule="the pinion flank does not face the gear flank at the mean position"
            )
        return sample.clearance_rad[0], valid

    @property
    def gear_offset_rad(self) -> float:
        """The gear's polar-angle offset: the gear flank's polar angle at the contact is
        Theta2 - ratio * phi + gear angle + this (the phase less the whole pitches that pick
        the mating gear tooth)."""
        return self.phase_rad - self._shift

    @property
    def gear_sense(self) -> int:
        """Sense of the gear's polar angle while the pinion turns with ``sense``."""
        return -self.sense

    def clearance_of_points(
        self, points_mm, normals=None, phi_rad=0.0, gear_angle_rad=0.0
    ) -> PointClearance:
        """The angular clearance of pinion points (member frame of the unturned pinion,
        ``(..., 3)``; their unit ``normals`` for the normal separation) at pinion angles
        ``phi_rad`` with the gear turned by ``gear_angle_rad`` from its ideal angle (all
        broadcast). See :class:`PointClearance`."""
        p = np.asarray(points_mm, float)
        comps = (p[..., 0], p[..., 1], p[..., 2])
        n = None if normals is None else np.asarray(normals, float)
        comps_n = None if n is None else (n[..., 0], n[..., 1], n[..., 2])
        side = np.zeros(np.broadcast(p[..., 0], phi_rad).shape, np.intp)
        delta, factor, radius, valid = self._engine.gap(
            side, comps, comps_n, phi_rad, gear_angle_rad
        )
        return PointClearance(
            clearance_rad=delta, normal_factor_mm=factor, radius_mm=radius, valid=valid
        )

    def clearance_at_grid(self, face_mm, profile_mm, phi_rad, gear_angle_rad=0.0):
        """``(clearance_rad, valid)`` at pinion grid coordinates ``(s, h)`` off the nodes, by
        the flanks' local Hermite interpolants (broadcast with ``phi_rad``). The clearance is
        the interpolants' smooth extension beyond the flanks (finite everywhere); ``valid`` is
        False outside either flank and in the pinion's lowest generated cells, where the
        envelope's fold spoils any interpolant."""
        s, h = np.broadcast_arrays(np.asarray(face_mm, float), np.asarray(profile_mm, float))
        side = np.zeros(np.broadcast(s, phi_rad).shape, np.intp)
        return self._engine.at(side, np.stack([s, h]), phi_rad, gear_angle_rad)

    def interval_end(self, u_rad: float, start, toward_rad: float, *, tol_rad: float = 1e-6):
        """Where the pair leaves contact (seed 003 section 6: the tangency point -- the least
        clearance, where the flanks touch with a common normal -- leaves the flanks), near the
        relative rotation ``u_rad`` (in the pinion's direction of motion) where the contact
        point is near ``start`` = ``(face_mm, profile_mm)``: stepping by ``toward_rad`` (signed,
        toward the outside; up to 128 steps), then bisection to ``tol_rad``. Returns
        ``(u_inside, u_outside, face_mm, profile_mm)`` with the tangency point at ``u_inside``,
        or None where Newton's method fails (a line contact) or no bracket is found."""
        found = self._engine.interval_end(
            0, self.sense * u_rad, *start, self.sense * toward_rad, tol=tol_rad
        )
        if found is None:
            return None
        a, b, s, h = found
        return self.sense * a, self.sense * b, s, h

    def sample(
        self,
        phi_rad: NDArray,
        gear_angle_rad: NDArray | float = 0.0,
        *,
        refine: bool | NDArray = True,
    ) -> FieldSample:
        """The clearance field at relative pinion angles ``phi_rad`` (vectorised), each with
        the gear turned by ``gear_angle_rad`` (scalar or one per angle) from its ideal angle.

        ``refine``: refine every row's minimum (True), none (False: node values, no edge
        test) or the rows of a boolean mask."""
        phi = np.atleast_1d(np.asarray(phi_rad, float))
        return self._engine.sample(np.zeros(len(phi), np.intp), phi, gear_angle_rad, refine)


class JointField:
    """Several clearance fields of one pair (the drive and coast sides) evaluated together:
    the same computations as each field's, with one array operation for all sides, so that
    numpy's per-call overhead is paid once. Rows name their field by index (``side``)."""

    def __init__(self, fields) -> None:
        self.fields = list(fields)
        self._engine = _Engine(self.fields)

    def sample(self, side, phi_rad, gear_angle_rad=0.0, *, refine=True, near=None):
        """As :meth:`ClearanceField.sample`, row k on field ``side[k]``. With ``near`` =
        ``(side, phi_rad, face_mm, profile_mm)``, also :meth:`minimum_near` of those rows in
        the same refinement (the same results, fewer calls): returns ``(sample, near)``."""
        side = np.asarray(side, np.intp)
        if near is None:
            return self._engine.sample(side, phi_rad, gear_angle_rad, refine)
        return self._engine.sample(side, phi_rad, gear_angle_rad, refine, self._near_rows(near))

    @staticmethod
    def _near_rows(near):
        side, phi, s, h = (np.atleast_1d(np.asarray(a)) for a in near)
        return side.astype(np.intp), phi.astype(float), s.astype(float), h.astype(float)

    def minimum_near(self, side, phi_rad, face_mm, profile_mm, gear_angle_rad=0.0):
        """Refined minima at pinion angles ``phi_rad`` (row k on field ``side[k]``) started from
        known nearby contact points (``face_mm``, ``profile_mm`` on the pinion grid): no node
        field, for the extra evaluations of a mesh cycle (hand-overs, contact ends). Returns
        ``(value, s, h, edge)``; value +inf where the start is off the flanks."""
        side = np.asarray(side, np.intp)
        return self._engine.near(side, phi_rad, face_mm, profile_mm, gear_angle_rad)


_WORK = threading.local()
_HEAP = {"kept": False}


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


def _field_tables(field) -> dict:
    """A field's own node tables, kept on it (a field is not changed once made): its pinion
    flank's generated nodes (flat indices), their points and normals (components apart), the
    refinable nodes (two cells above the lowest generated ones) and cells, the grid's cell
    size."""
    tables = field.__dict__.get("_tables")
    if tables is None:
        pinion = field.pinion
        nodes = np.flatnonzero(pinion.mask.ravel())
        pts = pinion.points_mm.reshape(-1, 3)[nodes]
        nrm = pinion.normals.reshape(-1, 3)[nodes]
        keep = pinion.mask.copy()
        for _ in range(2):
            below = np.zeros_like(keep)
            below[:, 1:] = keep[:, :-1]
            keep &= below
        slot = np.full(pinion.mask.size, -1, np.intp)
        slot[nodes] = np.arange(nodes.size)
        tables = field.__dict__["_tables"] = {
            "nodes": nodes,
            "slot": slot,
            "points": tuple(np.ascontiguousarray(pts[:, a]) for a in range(3)),
            "normals": tuple(np.ascontiguousarray(nrm[:, a]) for a in range(3)),
            "keep": keep.ravel(),
            "cells": (keep[:-1, :-1] & keep[1:, :-1] & keep[:-1, 1:] & keep[1:, 1:]).ravel(),
            "cell_mm": (
                float(np.mean(np.diff(pinion.face_mm))),
                float(np.mean(np.diff(pinion.profile_mm))),
            ),
        }
    return tables


class _Rows:
    """Per-row constants of the clearance (:meth:`_Engine._rows`): the coefficients of x and y
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

    def subset(self, rows) -> _Rows:
        """The rows ``rows`` (an index or mask of the first axis)."""
        return _Rows(
            self.kx[:, rows],
            self.ky[:, rows],
            self.turn[rows],
            self.sense[rows],
            self.gear_offset[rows],
            self.pinion_offset[rows],
        )


class _Engine:
    """The clearance computations on stacked tables of K fields (sides).

    Per side: the sense, the gear's polar-angle offset (phase minus whole pitches), the pinion
    nodes, the local interpolants' cell tables (pinion and gear, concatenated with an offset of
    one table per side) and the refinable cells. Shared: the placement, the ratio and the grids
    (the fields must share them).
    """

    _AROUND_ROWS = 32  # batches up to this many rows evaluate the stencils of all cut-backs
    _JOINT_ROWS = 16  # node fields of up to this many rows: all sides in one evaluation
    _FRACTIONS = np.array([1.0, 0.5, 0.25, 0.125, 0.0625])
    _STENCIL = np.array(
        [(0, 0), (1, 0), (-1, 0), (0, 1), (0, -1), (1, 1), (1, -1), (-1, 1), (-1, -1)], float
    )

    def __init__(self, fields) -> None:
        _keep_heap()
        first = fields[0]
        for f in fields[1:]:
            same = (
                np.array_equal(f.pinion.face_mm, first.pinion.face_mm)
                and np.array_equal(f.pinion.profile_mm, first.pinion.profile_mm)
                and np.array_equal(f.gear.face_mm, first.gear.face_mm)
                and np.array_equal(f.gear.profile_mm, first.gear.profile_mm)
                and np.all(np.abs(f.b - first.b) <= 1e-8 + 1e-5 * np.abs(first.b))
                and np.all(np.abs(f.c - first.c) <= 1e-8 + 1e-5 * np.abs(first.c))
                and f.ratio == first.ratio
            )
            if not same:
                raise GearoptError("fields", rule="joined fields must share grids and placement")
        self.b, self.c, self.ratio = first.b, first.c, first.ratio
        self.pinion_grid, self.gear_grid = first.pinion, first.gear
        self.shape = first.pinion.shape
        self.sense = np.array([f.sense for f in fields], float)
        self.gear_sense = -self.sense
        self.turn0 = np.array([f.phase_rad - f._shift for f in fields])
        g = math.radians(first.pinion.pitch_angle_deg)
        self.cos_sin_pitch = (math.cos(g), math.sin(g))
        tables = [_field_tables(f) for f in fields]
        self.ds, self.dh = tables[0]["cell_mm"]
        # mm of normal separation per rad of gear rotation, typical of each side (a fixed
        # tolerance in rad for the refinement's edge test)
        scale = np.array([getattr(f, "_factor_mm", None) or 50.0 for f in fields])
        self.tol_rad = np.array([f.edge_tolerance_um * 1e-3 for f in fields]) / scale
        self.tol_um = np.array([f.edge_tolerance_um for f in fields])
        # node tables (all grid nodes; off-mask nodes are +inf in the fields)
        # the generated pinion nodes of each side, padded to one count with at least one more
        # (padding: the first generated node again, its result dropped); components stored
        # apart, contiguous
        sizes = [t["nodes"].size for t in tables]
        count = max(sizes) + 1
        pad = [np.r_[np.arange(n), np.zeros(count - n, np.intp)] for n in sizes]
        self.node_index = np.stack([t["nodes"][k] for t, k in zip(tables, pad, strict=True)])
        self.node_real = np.arange(count)[None, :] < np.array(sizes)[:, None]
        # each grid node's column in its side's node tables (off-mask: the padding after them)
        self.node_slot = np.stack(
            [np.where(t["slot"] < 0, n, t["slot"]) for t, n in zip(tables, sizes, strict=True)]
        )
        self.points = tuple(
            np.stack([t["points"][a][k] for t, k in zip(tables, pad, strict=True)])
            for a in range(3)
        )
        self.normals = tuple(
            np.stack([t["normals"][a][k] for t, k in zip(tables, pad, strict=True)])
            for a in range(3)
        )
        # the interpolant is poor in the lowest generated cells (the envelope's fold):
        # refinements stay two cells above them
        self.refine_nodes = np.stack([t["keep"] for t in tables])
        self.refine_cells = np.concatenate([t["cells"] for t in tables])
        self.pinion_cells = tables[0]["cells"].size
        self.pinion_coef = np.concatenate([f.pinion.cells.coefficients for f in fields])
        self.gear_cells = first.gear.cells.generated.size
        self.gear_coef = np.concatenate([f.gear.cells.coefficients for f in fields])
        self.gear_ok = np.concatenate([f.gear.cells.generated for f in fields])
        self.pinion_generated = np.concatenate([f.pinion.cells.generated for f in fields])
        self._linear_maps(fields)
        self._jit = self._kernel_tables() if _kernels.ENABLED else None

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
        s0, ia, imax, h0, ib = (
            gc.face0_mm,
            gc.face_scale,
            gc.last_row,
            gc.profile0_mm,
            gc.profile_scale,
        )
        jmax, n_cols = gc.last_column, gc.columns
        g = math.radians(first.gear.pitch_angle_deg)
        cg, sg = math.cos(g), math.sin(g)
        lin = np.array([b[0], b[1], ia * cg * b[2], -ib * sg * b[2]])
        const = np.array([c[0], c[1], ia * (cg * c[2] - s0), -ib * (sg * c[2] + h0)])
        self._rotation = np.concatenate(
            [np.stack([lin[:, 0], lin[:, 1]], 1), np.stack([lin[:, 1], -lin[:, 0]], 1)]
        )
        self._rho_coef = np.array([ia * sg, ib * cg])
        self._gear_table = (np.array([imax, jmax]), n_cols)
        self._lin_z, self._const = lin[:, 2], const
        # the node tables: x, y and the z terms (with the constants) of every side's nodes;
        # the normals' x, y and z terms of qx, qy (no constants)
        self.node_xy = np.stack([self.points[0], self.points[1]])
        self.node_z = lin[:, 2, None, None] * self.points[2] + const[:, None, None]
        self.node_nxy = np.stack([self.normals[0], self.normals[1]])
        self.node_nz = lin[:2, 2, None, None] * self.normals[2]
        # pinion grid coordinates (s, h) -> the pinion's unit grid coordinates, R1 and the
        # z terms (z = L1 = s cos g1 - h sin g1)
        pc = first.pinion.cells
        p0, pia, pimax, ph0, pib = (
            pc.face0_mm,
            pc.face_scale,
            pc.last_row,
            pc.profile0_mm,
            pc.profile_scale,
        )
        pjmax, p_cols = pc.last_column, pc.columns
        cg1, sg1 = self.cos_sin_pitch
        self._pinion_unit = (np.array([[p0], [ph0]]), np.array([[pia], [pib]]))
        self._pinion_table = (np.array([pimax, pjmax]), p_cols)
        self._pinion_map = np.concatenate(
            [np.array([[sg1, cg1]]), np.stack([lin[:, 2] * cg1, -lin[:, 2] * sg1], 1)]
        )
        self._pinion_const = np.concatenate([[0.0], const])[:, None]
        # tapered depth: the grids' profile coordinate is t, not the height (DepthTaper)
        self._pinion_taper = first.pinion.taper
        gear_taper = first.gear.taper
        self._gear_taper = None
        if gear_taper is not None:
            # unit coordinates (x, y) of (s, h) -> y of (s, t): with d = s - pivot,
            # y' = (y + ib (h0 - d alpha)) / (1 + d beta) - ib h0
            self._gear_taper = (
                s0 - gear_taper.pivot_mm,
                1.0 / ia,
                ib,
                h0,
                gear_taper.alpha,
                gear_taper.beta,
            )

    def _kernel_tables(self):
        """The tables of :mod:`gearopt.contact.kernels` (gear, pinion) and the node counts."""
        (imax, jmax), n_cols = self._gear_table
        taper = self._gear_taper or (0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
        gear = (
            *(float(a) for a in self._rho_coef),
            float(imax),
            float(jmax),
            int(n_cols),
            self._gear_taper is not None,
            *(float(a) for a in taper),
            self.gear_coef,
            np.ascontiguousarray(self.gear_ok),
        )
        (p0, ph0), (pia, pib) = (a[:, 0] for a in self._pinion_unit)
        (pimax, pjmax), p_cols = self._pinion_table
        ptaper = self._pinion_taper
        pinion = (
            float(p0),
            float(ph0),
            float(pia),
            float(pib),
            float(pimax),
            float(pjmax),
            int(p_cols),
            ptaper is not None,
            *((0.0, 0.0, 0.0) if ptaper is None else (ptaper.pivot_mm, ptaper.alpha, ptaper.beta)),
            np.ascontiguousarray(self._pinion_map),
            np.ascontiguousarray(self._pinion_const[:, 0]),
            self.pinion_coef,
            np.ascontiguousarray(self.refine_cells),
        )
        counts = self.node_real.sum(axis=1).astype(np.intp)
        return gear, pinion, counts

    def _untaper(self, xy) -> None:
        """Gear unit grid coordinates of (s, h) made those of (s, t), in place (tapered
        depth; nothing for uniform depth)."""
        if self._gear_taper is None:
            return
        d0, inv_ia, ib, h0, alpha, beta = self._gear_taper
        d = xy[0] * inv_ia + d0
        xy[1] = (xy[1] + ib * (h0 - d * alpha)) / (1.0 + d * beta) - ib * h0

    # --- evaluation ---------------------------------------------------------------------

    @staticmethod
    def _cells(coef, xy, table, offset):
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

    def _rows(self, side, phi, angle) -> _Rows:
        """The per-row constants of rows (side, pinion angle, gear angle), broadcast to one
        shape; the rows' points broadcast against it."""
        side, phi, angle = np.broadcast_arrays(side, np.asarray(phi, float), angle)
        flat = phi.reshape(-1)
        cs = np.empty((2, flat.size))
        np.cos(flat, out=cs[0])
        np.sin(flat, out=cs[1])
        k = (self._rotation @ cs).reshape((2, 4) + phi.shape)
        turn = (angle + self.turn0[side]) - self.ratio * phi
        return _Rows(
            k[0],
            k[1],
            turn,
            self.gear_sense[side],
            side * self.gear_cells,
            side * self.pinion_cells,
        )

    def _clearance(self, rows: _Rows, x, y, z, normals=None):
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
        xy += self._rho_coef.reshape((2,) + (1,) * radius.ndim) * radius
        self._untaper(xy)
        flank, cell, within = self._cells(self.gear_coef, xy, self._gear_table, rows.gear_offset)
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

    def _node_clearance(self, rows: _Rows, side, count: int):
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
        np.multiply(self._rho_coef[:, None, None], radius, out=tmp[:2])
        xy += tmp[:2]
        self._untaper(xy)
        # the gear's cells (as _cells)
        limit, n_cols = self._gear_table
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
        rows = self._rows(*(np.broadcast_to(a, shape) for a in (side, phi, gear_angle_rad)))
        zt = self._lin_z.reshape((4,) + (1,) * len(shape)) * z
        zt += self._const.reshape((4,) + (1,) * len(shape))
        normals = None
        if n is not None:
            nx, ny, nz = (np.broadcast_to(np.asarray(a, float), shape) for a in n)
            normals = (np.stack([nx, ny]), self._lin_z[:2].reshape((2,) + (1,) * len(shape)) * nz)
        delta, valid, radius, factor = self._clearance(rows, x, y, zt, normals)
        return delta, factor, radius, valid

    def at(self, side, sh, phi, gear_angle_rad):
        """Clearance at pinion grid coordinates ``sh = (s, h)`` (``(2, ...)``) off the nodes by
        the local Hermite interpolants: ``(delta, valid)``. ``delta`` is the smooth extension
        beyond the flanks (finite everywhere); ``valid`` is False outside either flank and in
        the pinion's lowest generated cells, where the envelope's fold spoils any
        interpolant."""
        shape = np.broadcast_shapes(sh.shape[1:], np.shape(side), np.shape(phi))
        if not shape:  # a single point: as a one-element array
            one = self.at(side, np.reshape(sh, (2, 1)), np.reshape(phi, 1), gear_angle_rad)
            return one[0][0], one[1][0]
        side, phi, angle = np.broadcast_arrays(side, np.asarray(phi, float), gear_angle_rad)
        lead = (1,) * (len(shape) - phi.ndim)
        rows = self._rows(*(a.reshape(lead + phi.shape) for a in (side, phi, angle)))
        return self._at(rows, np.broadcast_to(sh, (2,) + shape))

    def _at(self, rows: _Rows, sh):
        """:meth:`at` on known rows."""
        if self._jit is not None:
            return self._at_compiled(rows, sh)
        origin, scale = self._pinion_unit
        xy = sh - origin.reshape((2,) + (1,) * (sh.ndim - 1))
        xy *= scale.reshape((2,) + (1,) * (sh.ndim - 1))
        theta, cell, within = self._cells(
            self.pinion_coef, xy, self._pinion_table, rows.pinion_offset
        )
        flat = sh.reshape(2, -1)
        if self._pinion_taper is not None:  # (s, t) -> (s, h)
            flat = np.stack([flat[0], self._pinion_taper.height_mm(flat[0], flat[1])])
        lin = self._pinion_map @ flat
        lin += self._pinion_const
        lin = lin.reshape((5,) + sh.shape[1:])
        big_r = lin[0]
        delta, valid, _, _ = self._clearance(
            rows, big_r * np.cos(theta), big_r * np.sin(theta), lin[1:]
        )
        valid &= within
        valid &= self.refine_cells[cell]
        return delta, valid

    def _at_compiled(self, rows: _Rows, sh):
        """:meth:`_at` by :func:`gearopt.contact.kernels.clearance_at`: rows ``(n, 1)`` and
        points ``(2, n, m)`` as the refinement has them, anything else one row per point."""
        shape = sh.shape[1:]
        if len(shape) == 2 and rows.turn.shape == (shape[0], 1):
            n, m = shape
            constants = rows.kernel_rows(n)
        else:
            n, m = math.prod(shape), 1
            constants = _Rows(
                *(np.broadcast_to(k, (4,) + shape) for k in (rows.kx, rows.ky)),
                *(
                    np.broadcast_to(a, shape)
                    for a in (rows.turn, rows.sense, rows.gear_offset, rows.pinion_offset)
                ),
            ).kernel_rows(n)
        points = np.array(np.broadcast_to(sh, (2,) + shape)).reshape(2, n, m)
        delta, valid = np.empty((n, m)), np.empty((n, m), bool)
        gear, pinion, _ = self._jit
        _kernels.clearance_at(constants, points, pinion, gear, delta, valid)
        return delta.reshape(shape), valid.reshape(shape)

    def _node_fields(self, side, phi, angle):
        """The clearance, normal factor and R2 at every grid node for rows (side, phi, gear
        angle), each ``(n, nodes)``: +inf, 0, 0 off the pinion's generated nodes."""
        n, size = len(phi), self.shape[0] * self.shape[1]
        field_, fac, rad = np.empty((n, size)), np.empty((n, size)), np.empty((n, size))
        # each side's rows on its own generated nodes (its node tables broadcast over rows)
        # and a padding node, the grid gathered from them (off-mask nodes take the padding
        # node, set to +inf); a few rows of several sides go in one evaluation, each row with
        # its side's node tables
        sides = np.unique(side)
        joint = len(sides) > 1 and n <= self._JOINT_ROWS
        if joint:
            out = self._node_clearance(
                self._rows(side[:, None], phi[:, None], angle[:, None]),
                side,
                self.node_index.shape[1],
            )
        for k in sides:
            count = int(self.node_real[k].sum())
            rows = np.flatnonzero(side == k) if len(self.sense) > 1 else np.arange(n)
            if joint:
                delta, valid, radius, factor = (a[rows, : count + 1] for a in out)
            else:
                delta, valid, radius, factor = self._node_clearance(
                    self._rows(k, phi[rows, None], angle[rows, None]), k, count + 1
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

    def _node_fields_compiled(self, side, phi, angle):
        """:meth:`_node_fields` by :func:`gearopt.contact.kernels.node_fields` (the nodes'
        polar angles in between by numpy's vectorised arctan2)."""
        n = len(phi)
        rows = self._rows(side, phi, angle)
        out = np.empty((3, n, self.shape[0] * self.shape[1]))
        theta = np.empty((2, n, self.node_index.shape[1]))
        count = self._jit[2]
        constants, side = rows.kernel_rows(n), np.array(side, np.intp)
        _kernels.node_xy(constants, side, count, self.node_xy, self.node_z, theta)
        theta = np.arctan2(theta[1], theta[0], out=theta[0])
        _kernels.node_fields(
            constants,
            side,
            count,
            self.node_index,
            self.node_xy,
            self.node_z,
            self.node_nxy,
            self.node_nz,
            theta,
            self._jit[0],
            out,
        )
        return out[0], out[1], out[2]

    def sample(self, side, phi_rad, gear_angle_rad=0.0, refine=True, near=None):
        """The clearance field at the nodes for rows (side, phi, gear angle), minima refined
        on the rows ``refine`` selects; with ``near`` = ``(side, phi, s, h)`` (gear angle 0),
        also :meth:`near` of those rows in the same refinement: ``(sample, near)``."""
        phi = np.atleast_1d(np.asarray(phi_rad, float))
        side = np.broadcast_to(np.asarray(side, np.intp), phi.shape)
        angle = np.broadcast_to(np.asarray(gear_angle_rad, float), phi.shape).copy()
        n = len(phi)
        node_fields = self._node_fields if self._jit is None else self._node_fields_compiled
        field_, fac, rad = node_fields(side, phi, angle)
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
        elif rows.size or near is not None:
            f0, s, h = f0.copy(), s.copy(), h.copy()
            f0[rows], s[rows], h[rows], edge[rows], near_out = self._refined(
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

    def interval_end(self, side: int, phi_rad, face_mm, profile_mm, step_rad, steps=128, tol=1e-6):
        """Where the tangency point leaves the flanks near pinion angle ``phi_rad`` (the
        contact point near ``(face_mm, profile_mm)``), stepping by ``step_rad`` toward the
        outside: :func:`gearopt.contact.kernels.interval_end` (point by point in Python
        without the compiled kernels). ``(phi_inside, phi_outside, s, h)`` or None."""
        gear, pinion, _ = self._jit or self._kernel_tables()
        maker = (
            np.ascontiguousarray(self._rotation),
            float(self.turn0[side]),
            float(self.ratio),
            float(self.gear_sense[side]),
            int(side * self.gear_cells),
            int(side * self.pinion_cells),
        )
        end = _kernels.interval_end
        if self._jit is None:
            end = getattr(end, "py_func", end)
        found, a, b, s, h = end(
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

    def _refined(self, side, field_, fac, phi, angle, f0, s, h, candidates: int = 2, near=None):
        """Refine the minimum from the ``candidates`` lowest refinable nodes (constrained
        Newton, :meth:`refine`) and keep the least. A node minimum outside the refinable
        region (the pinion's lowest cells) lower than that by more than the edge tolerance
        stands as it is, flagged as edge contact. ``near`` rows ``(side, phi, s, h)`` are
        refined alongside (as :meth:`near`); their results come last (None without)."""
        n = len(phi)
        flat = field_.reshape(n, -1)
        pick = np.empty((n, min(candidates, flat.shape[1])), np.intp)
        values = np.empty(pick.shape)
        if self._jit is not None:
            _kernels.lowest_nodes(flat, self.refine_nodes, np.array(side, np.intp), pick, values)
        else:
            inner = np.where(self.refine_nodes[side], flat, np.inf)
            rows = np.arange(n)
            for c in range(pick.shape[1]):  # the lowest, the next lowest, ...
                pick[:, c] = inner.argmin(axis=1)
                values[:, c] = inner[rows, pick[:, c]]
                inner[rows, pick[:, c]] = np.inf
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
            first = np.r_[True, rows[1:] != rows[:-1]]
            best[rows[first]] = v[first]
            s_best[rows[first]], h_best[rows[first]] = s_r[first], h_r[first]
            e_best[rows[first]] = e_r[first]
        rows = np.arange(n)
        i, j = _argmin_nodes(field_)
        tol = self.tol_um[side] * 1e-3 / np.maximum(fac[rows, i, j], 1e-9)
        with np.errstate(invalid="ignore"):
            low = np.isfinite(f0) & ~(best - f0 <= tol)
        value = np.where(low, f0, best)
        s_best, h_best = np.where(low, s, s_best), np.where(low, h, h_best)
        return value, s_best, h_best, low | e_best, near_out

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
        if self._jit is not None:
            return self._refine_compiled(side, phi, angle, s, h, f0, iterations, group)
        cell = np.array([[self.ds], [self.dh]])
        quarter = self._STENCIL.T[:, None, :] * (0.25 * cell[:, :, None])  # (2, 1, 9) mm
        fr = self._FRACTIONS
        nf = len(fr)
        n = len(s)
        rows = np.arange(n)
        edge = np.zeros(n, bool)
        tol = self.tol_rad[side]
        sh = np.stack([s, h])
        every = self._rows(side[:, None], phi[:, None], angle[:, None])
        # a small batch costs numpy's per-call overhead, not points: it evaluates the stencils
        # around every cut-back point with the step, so that no point needs a call of its own
        around = nf if n <= self._AROUND_ROWS else 1
        f, ok0 = self._at(every, sh[:, :, None] + quarter)
        start = np.where(ok0[:, 0], f[:, 0], np.inf)
        best = start if f0 is None else np.where(np.isnan(f0), start, f0)
        caps = np.atleast_1d(iterations)
        groups = [np.ones(n, bool)] if group is None else [group == g for g in range(len(caps))]
        active = np.ones(n, bool)
        small = 1e-3 * min(self.ds, self.dh)
        for it in range(int(caps.max())):
            d = f @ self._DIFFERENCES  # gradient and Hessian in cell units
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
            fa, oka = self._at(every, np.concatenate(parts, axis=2))
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
                f[need], _ = self._at(every.subset(need), sh[:, need, None] + quarter)
        return best, sh[0], sh[1], edge

    def _refine_compiled(self, side, phi, angle, s, h, f0, iterations, group):
        """:meth:`refine` by :func:`gearopt.contact.kernels.refine`."""
        n = len(s)
        rows = self._rows(side, phi, angle)
        s, h = np.array(s, float), np.array(h, float)
        best = np.full(n, np.nan) if f0 is None else np.array(f0, float)
        caps = np.atleast_1d(np.asarray(iterations, np.intp))
        group = np.zeros(n, np.intp) if group is None else np.asarray(group, np.intp)
        edge = np.zeros(n, bool)
        gear, pinion, _ = self._jit
        _kernels.refine(
            rows.kernel_rows(n),
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


def _differences() -> NDArray:
    """``(9, 5)``: stencil values (``_Engine._STENCIL``, a quarter cell) to the gradient and
    the Hessian (ss, sh, hh) in cell units by central differences."""
    d = np.zeros((9, 5))
    d[1, 0], d[2, 0] = 2.0, -2.0
    d[3, 1], d[4, 1] = 2.0, -2.0
    d[[1, 2], 2], d[0, 2] = 16.0, -32.0
    d[[5, 8], 3], d[[6, 7], 3] = 4.0, -4.0
    d[[3, 4], 4], d[0, 4] = 16.0, -32.0
    return d


_Engine._DIFFERENCES = _differences()


def _argmin_nodes(field_: NDArray) -> tuple[NDArray, NDArray]:
    n = field_.shape[0]
    flat = field_.reshape(n, -1).argmin(axis=1)
    return np.unravel_index(flat, field_.shape[1:])


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
