"""The contact engine: the clearance field between two FlankMaps in the housing frame.

Machine-independent: it sees a pinion flank and a gear flank (FlankMaps, member frames as in
:mod:`gearopt.flank`), the shaft angle and the misalignment, nothing else.

Housing frame S_f (docs/architecture.md, Frames and signs; :mod:`gearopt.assembly`): origin at
the nominal crossing point of the axes, x_f along the pinion axis toward the pinion's back, the
gear axis in the x_f-z_f plane at the shaft angle Sigma from x_f, y_f = z_f x x_f. The pinion
frame maps x_p -> z_f, y_p -> -y_f, z_p -> x_f, so the pitch point of tooth 0 (polar angle 0)
lies in the x_f-z_f plane on the side z_f > 0; the gear frame is S_f turned about y_f so that
z_g = (cos Sigma, 0, sin Sigma). Misalignment: the pinion moves by (dA1, dE, 0), the gear along
its own axis by dA2 and its axis turns about y_f to Sigma + dGamma.

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

import math
from contextlib import contextmanager

import numpy as np
from numpy.typing import NDArray

from gearopt.assembly import Placement
from gearopt.contact import kernels
from gearopt.contact.engine import ContactEngine, node_tables, remembered_tables
from gearopt.contact.samples import FieldSample, PointClearance
from gearopt.errors import GearoptError
from gearopt.flank import FlankMap

__all__ = [
    "ContactError",
    "Placement",
    "ClearanceField",
    "JointField",
    "FieldSample",
    "PointClearance",
]


def median(values) -> float:
    """The median of a 1-D array of at least one value: :func:`numpy.median`'s value (the same
    bits: the middle order statistics by a partition, the two middle ones' mean), without its
    general set-up."""
    n = values.size
    k = n // 2
    if np.isnan(values).any():
        return math.nan
    if n % 2:
        return float(np.partition(values, k)[k])
    part = np.partition(values, (k - 1, k))
    return float((part[k - 1] + part[k]) / 2.0)


class ContactError(GearoptError):
    """The flanks cannot be brought into contact as asked (no contact inside the flanks)."""


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
        self.node_tables = remembered_tables("nodes", (pinion,), lambda: node_tables(pinion))
        #: the joint fields made with this one first (:meth:`JointField.of`), by the other
        #: fields' identities
        self.joints: dict[tuple[int, ...], JointField] = {}
        #: mm of normal separation per rad of gear rotation at the mean position (the median
        #: over the nodes in contact; None until measured)
        self.node_factor_mm: float | None = None
        self.phase_rad = 0.0 if phase_rad is None else float(phase_rad)
        self._shift = 0.0
        self._engine = ContactEngine([self])
        delta, valid, factor = self._node_clearance()
        pitch = self.gear.pitch_rad
        centre = median(self.gear_sense * delta[valid])
        if phase_rad is None:
            self.phase_rad = -centre  # (the gear turned back by the median clearance)
            if np.all(np.abs(self.gear_sense * delta[valid] - centre) < 1.0) and pitch > 1e-3:
                # the clearance at this phase is the one at phase 0 less its median, turned by
                # no whole turn: its median is 0, no whole pitch
                centre = 0.0
            else:
                self._engine.place([self])
                delta, valid, _ = self._node_clearance()
                centre = median(self.gear_sense * delta[valid])
        self.node_factor_mm = factor
        self._shift = pitch * round(centre / pitch)
        self._engine.place([self])

    def _node_clearance(self):
        """The clearance at the nodes at the mean position, where it is finite and the median
        normal factor there (it does not depend on the phase)."""
        engine = self._engine  # its node fields of row (side 0, phi 0): sample's, no minimum
        side = np.zeros(1, np.intp)
        out = np.empty((3, 1, engine.shape[0] * engine.shape[1]))
        gear, _, counts = engine.kernel_tables
        nodes = (engine.node_index, engine.node_xy, engine.node_z, engine.node_nxy, engine.node_nz)
        kernels.node_fields(engine.row_tables(side, 0.0), side, counts, *nodes, gear, out)
        delta, factor = out[0, 0], out[1, 0]
        valid = np.isfinite(delta)
        if not valid.any():
            raise ContactError(
                "flanks", rule="the pinion flank does not face the gear flank at the mean position"
            )
        return delta, valid, median(factor[valid])

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

    def gear_frame_points(self, points_mm, phi_rad) -> NDArray:
        """Pinion points (member frame, unturned; ``(..., 3)``) turned by the pinion angles
        ``phi_rad`` (broadcast over the points' leading axes) and placed in the gear frame
        before the gear's own turn: ``q = B Rz(phi) p + c``."""
        p = np.asarray(points_mm, float)
        cp, sp = np.cos(phi_rad), np.sin(phi_rad)
        turned = np.stack(
            [cp * p[..., 0] - sp * p[..., 1], sp * p[..., 0] + cp * p[..., 1], p[..., 2]], -1
        )
        return turned @ self.b.T + self.c

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
        side = np.zeros(np.shape(phi_rad), np.intp)
        delta, factor, radius, valid = self._engine.gap(
            side, comps, comps_n, phi_rad, gear_angle_rad
        )
        return PointClearance(
            clearance_rad=delta, normal_factor_mm=factor, radius_mm=radius, valid=valid
        )

    def clearance_of_rows(self, points_mm, normals, phi_rad) -> PointClearance:
        """:meth:`clearance_of_points` of rows of points in one compiled pass: ``points_mm``
        and their unit ``normals`` ``(n, ..., 3)``, row r at the pinion angle ``phi_rad[r]``
        (``(n,)``, gear at its ideal angle); with the points' gear grid coordinates."""
        delta, factor, radius, valid, face, profile = self._engine.gap_of_rows(
            0, phi_rad, points_mm, normals
        )
        return PointClearance(
            clearance_rad=delta,
            normal_factor_mm=factor,
            radius_mm=radius,
            valid=valid,
            gear_face_mm=face,
            gear_profile_mm=profile,
        )

    def clearance_at_grid(self, face_mm, profile_mm, phi_rad, gear_angle_rad=0.0):
        """``(clearance_rad, valid)`` at pinion grid coordinates ``(s, h)`` off the nodes, by
        the flanks' local Hermite interpolants (broadcast with ``phi_rad``). The clearance is
        the interpolants' smooth extension beyond the flanks (finite everywhere); ``valid`` is
        False outside either flank and outside the pinion's refinable cells (up to its
        generated boundary on the fine cells there, :mod:`gearopt.contact.boundary`; on a
        flank without them two cells above its lowest generated nodes)."""
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
        self._engine = ContactEngine(self.fields)

    @classmethod
    def of(cls, fields) -> JointField:
        """The joint field of ``fields``, made once per combination (a field does not change
        once made, nor does its joint field's tables: the TCA of a pair reuses them); kept by
        the first field."""
        fields = list(fields)
        key = tuple(id(f) for f in fields[1:])
        joint = fields[0].joints.get(key)
        if joint is None or any(a is not b for a, b in zip(joint.fields, fields, strict=True)):
            joint = cls(fields)
            fields[0].joints[key] = joint
        return joint

    def sample(self, side, phi_rad, gear_angle_rad=0.0, *, refine=True, near=None):
        """As :meth:`ClearanceField.sample`, row k on field ``side[k]``. With ``near`` =
        ``(side, phi_rad, face_mm, profile_mm)``, also :meth:`minimum_near` of those rows in
        the same refinement (the same results, fewer calls): returns ``(sample, near)``."""
        side = np.asarray(side, np.intp)
        if near is None:
            return self._engine.sample(side, phi_rad, gear_angle_rad, refine)
        return self._engine.sample(side, phi_rad, gear_angle_rad, refine, self._near_rows(near))

    @contextmanager
    def recalling(self):
        """A context in which a sample of many rows (a mesh cycle's window) takes the node
        fields of the rows that the last such sample holds rather than evaluating them again
        (a row's node fields depend on it alone: the same results, to the bit;
        :mod:`gearopt.contact.recall`); nothing is kept after it."""
        recalled = self._engine.recalled
        recalled.switch(True)
        try:
            yield self
        finally:
            recalled.switch(False)

    def clearance_at_grid(
        self, side, face_mm, profile_mm, phi_rad, gear_angle_rad=0.0, generated=False
    ):
        """As :meth:`ClearanceField.clearance_at_grid`, on field ``side`` (broadcast with the
        pinion angles): ``side`` and ``phi_rad`` ``(n, 1)`` with points ``(n, m)`` evaluate
        row by row in one compiled call; ``generated`` as :meth:`point_tables`."""
        s, h = np.broadcast_arrays(np.asarray(face_mm, float), np.asarray(profile_mm, float))
        side = np.asarray(side, np.intp)
        return self._engine.at(side, np.stack([s, h]), phi_rad, gear_angle_rad, generated)

    def point_tables(self, side, phi_rad, generated=False) -> tuple:
        """For compiled callers: the tables of the clearance at pinion grid points on rows
        (field ``side[k]``, pinion angle ``phi_rad[k]``, the gear at its ideal angle), as
        :func:`gearopt.contact.kernels.clearance_at` takes them: ``(rows, pinion, gear)``. Its
        ``(delta, valid)`` on row k is :meth:`clearance_at_grid`'s; with ``generated``, valid
        up to the pinion's generated boundary (:func:`gearopt.contact.engine.node_tables`)."""
        return self._engine.point_tables(side, phi_rad, generated)

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
