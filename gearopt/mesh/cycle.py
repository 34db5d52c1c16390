"""Unloaded tooth contact analysis over the mesh cycle: :func:`tooth_contacts` and
:func:`tooth_contact`, run by :class:`MeshCycle` on every side's :class:`SideCycle` at once.

Definitions: :mod:`gearopt.mesh`.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass, field
from functools import cached_property, partial
from typing import Any

import numpy as np
from numpy.typing import NDArray

from gearopt.analysis_options import check_options
from gearopt.contact import ClearanceField, FieldSample, JointField
from gearopt.mesh import kernels
from gearopt.mesh.frame import ARCSEC, ToothFrame, as_list
from gearopt.mesh.pattern import sample_rows
from gearopt.mesh.side import FLAT_ARCSEC, SideCycle
from gearopt.mesh.zone import ZoneRows, Zones

__all__ = ["EXTEND", "MeshCycle", "ToothContact", "tooth_contact", "tooth_contacts"]

EXTEND = np.array([1, 2, 3, 5, 10, 15])  # sample steps beyond the range (contact interval)
#: the most pairs a side's window is widened to (:meth:`MeshCycle.widen`)
WIDEST = 9


@dataclass(frozen=True, kw_only=True)
class ToothContact:
    """TCA of one side (see :mod:`gearopt.mesh` for every definition).

    Attributes
    ----------
    side
        ``"drive"`` or ``"coast"``.
    phi1_deg, te_arcsec
        ``(n,)`` pinion positions (direction of motion) and the TE there.
    pair_te_arcsec
        ``(pairs, n)`` TE of the pairs in the window of each position (row j: the j-th pair from
        the earliest in its cycle; the window moves on by one pair at every half pitch, so a
        row is not one physical pair throughout).
    carrying
        ``(n,)`` index of the carrying pair.
    handover_phi1_deg
        Positions of the hand-overs within the analysed range.
    te_peak_to_peak_arcsec
        Maximum minus minimum TE with the hand-over solved.
    path_face_mm, path_profile_mm
        ``(n,)`` contact path (zone centroid of the carrying pair) in pattern coordinates.
    contact_face_mm, contact_profile_mm
        ``(n,)`` the clearance minimum of the carrying pair (the classical contact point).
    edge
        ``(n,)`` True where the carrying pair touches at an edge of a flank.
    separation_um
        ``(n, pairs, n_f, n_p)`` separation of every pinion node from the mating flank at the
        contact gear angle (inf off the flanks).
    pattern_um
        ``(n_f, n_p)`` the pattern field: the least separation over positions and pairs.
    face_mm, profile_mm
        ``(n_f,)``, ``(n_p,)`` the nodes' pattern coordinates.
    width_mm, bias_mm, center_offset_mm, mean_point_mm
        Pattern width (the extent across the path at M of the pattern the zones sweep:
        :meth:`gearopt.mesh.zone.Zones.pattern_exits`), bias, M - C, and M (the middle of the
        major chord), in pattern coordinates.
    ellipse_major_axis_mm
        The instantaneous contact zone's chord at M's position through the contact point along
        the least curvature of the separation's quadratic form: the major axis of seed 003's
        contact ellipse, whatever its angle to the path (:mod:`gearopt.mesh.zone`).
    ellipse_minor_axis_mm
        The zone's chord across the major axis through M.
    path_angle_deg
        Direction of the path of contact at M on the gear flank, from the gear's root line
        (:func:`gearopt.mesh.frame.path_angle`; the contact points of two positions either
        side of M).
    contact_ratio
        Pinion rotation with interior contact over the angular pitch.
    outline_source
        What :attr:`outline_mm` is measured by (a callable; None: no outline).
    compound_um, separation
        The marking compound and how separation is measured.
    """

    side: str
    phi1_deg: NDArray
    te_arcsec: NDArray
    pair_te_arcsec: NDArray
    carrying: NDArray
    handover_phi1_deg: NDArray
    te_peak_to_peak_arcsec: float
    path_face_mm: NDArray
    path_profile_mm: NDArray
    contact_face_mm: NDArray
    contact_profile_mm: NDArray
    edge: NDArray
    separation_um: NDArray
    pattern_um: NDArray
    face_mm: NDArray
    profile_mm: NDArray
    width_mm: float
    ellipse_major_axis_mm: float
    ellipse_minor_axis_mm: float
    path_angle_deg: float
    bias_mm: float
    center_offset_mm: tuple[float, float]
    mean_point_mm: tuple[float, float]
    contact_ratio: float
    compound_um: float
    separation: str
    outline_source: Any = field(default=None, repr=False, compare=False)

    @cached_property
    def outline_mm(self) -> NDArray:
        """``(k, 2)`` the outline polygon of the pattern the zones sweep, in pattern
        coordinates, on the refined field (:meth:`gearopt.mesh.zone.Zones.outline`; ``(0, 2)``
        without), measured when first asked for (it costs about half a TCA)."""
        return np.zeros((0, 2)) if self.outline_source is None else self.outline_source()

    @property
    def edge_contact(self) -> bool:
        """True when the carrying pair touches at an edge at any position."""
        return bool(self.edge.any())

    def as_dict(self) -> dict:
        """JSON-ready summary (the ``tca`` object of ``gearopt analyze --json``)."""
        return {
            "side": self.side,
            "phi1_deg": as_list(self.phi1_deg),
            "te_arcsec": as_list(self.te_arcsec),
            "te_peak_to_peak_arcsec": float(self.te_peak_to_peak_arcsec),
            "handover_phi1_deg": as_list(self.handover_phi1_deg),
            "contact_ratio": float(self.contact_ratio),
            "path": {
                "face_mm": as_list(self.path_face_mm),
                "profile_mm": as_list(self.path_profile_mm),
            },
            "edge": np.asarray(self.edge, bool).tolist(),
            "pattern": {
                "width_mm": float(self.width_mm),
                "ellipse_major_axis_mm": float(self.ellipse_major_axis_mm),
                "ellipse_minor_axis_mm": float(self.ellipse_minor_axis_mm),
                "path_angle_deg": float(self.path_angle_deg),
                "bias_mm": float(self.bias_mm),
                "center_offset_mm": [float(v) for v in self.center_offset_mm],
                "mean_point_mm": [float(v) for v in self.mean_point_mm],
                "edge_contact": self.edge_contact,
                "compound_um": float(self.compound_um),
                "separation": self.separation,
            },
        }


class MeshCycle:
    """The TCA of several sides of one pair, evaluated together.

    Runs the rounds of joint evaluations (:class:`gearopt.contact.JointField`): each round
    gathers every side's pending requests and extra positions into one call. Rounds: the
    window sample (the pairs nearest each side's mesh centre at every position, and beyond
    both ends); the contact intervals' bisection points, the hand-overs' first evaluations and
    the extra positions that are due, with the pairs beyond the windows; again, for a side
    whose window is re-centred, or widened where a pair beyond it carries (:meth:`widen`);
    then further rounds until no side asks for more.

    Parameters
    ----------
    fields
        The sides' clearance fields.
    names
        Their names (``"drive"``, ``"coast"``).
    frame, positions, pairs, cycles, compound_um, separation
        As :func:`tooth_contacts`.

    Attributes
    ----------
    fields, names, frame, pairs, compound_um, separation
        As given.
    joint
        The fields' :class:`~gearopt.contact.JointField`.
    pitch
        The pinion's angular pitch (the first field's).
    sense
        ``(sides,)`` each field's sense (pinion angle = sense * relative rotation).
    t
        ``(positions,)`` relative rotations over ``cycles`` pitches, centred on 0.
    step
        The position step.
    offsets
        ``(pairs,)`` the window's pair offsets from the pair nearest the centre.
    sides
        The sides' :class:`SideCycle`, once sampled (:meth:`main_sample`).
    """

    def __init__(
        self,
        fields,
        names,
        *,
        frame: ToothFrame,
        positions: int,
        pairs: int,
        cycles: float,
        compound_um: float,
        separation: str,
    ):
        self.fields = list(fields)
        self.names = tuple(names)
        self.frame, self.pairs = frame, pairs
        self.compound_um, self.separation = compound_um, separation
        self.joint = JointField.of(self.fields)
        p1 = self.fields[0].pinion.pitch_rad
        self.pitch = p1
        self.sense = np.array([f.sense for f in self.fields], float)
        self.t = np.linspace(-0.5 * cycles * p1, 0.5 * cycles * p1, positions)
        self.step = self.t[1] - self.t[0]
        self.offsets = np.arange(pairs) - (pairs - 1) // 2
        #: each side's window (pair offsets), :attr:`offsets` unless widened (:meth:`widen`)
        self.windows = [self.offsets] * len(self.fields)
        self.widened = False
        self.sides: list[SideCycle] = []

    def run(self) -> list[ToothContact]:
        """Every side's TCA (a window sampled again takes the node fields of the rows sampled
        before: :meth:`gearopt.contact.JointField.recalling`)."""
        with self.joint.recalling():
            return self.cycle()

    def cycle(self) -> list[ToothContact]:
        """:meth:`run`'s rounds."""
        n_sides = len(self.fields)
        # the contact intervals' ends (bisection on the edge flag, its candidate points
        # evaluated at once), the first hand-over evaluations and, where the hand-over is
        # guessed from smooth lags, the extra positions, with the pairs beyond the windows:
        # one joint evaluation
        self.main_sample(np.zeros(n_sides))
        beyond = self.beyond_requests()
        more = self.evaluate([s for s in self.sides if s.extras_due()], beyond)
        centres, lower = self.window_checks(beyond, more)
        resample = bool(np.any(centres != 0.0)) | self.widen(lower, centres)
        # a window that stays (a flat lag) but misses a carrying pair beyond it (more pairs in
        # contact than the window holds) is widened by a pair either side until none beyond
        # carries
        while resample:
            self.main_sample(centres)
            beyond = self.beyond_requests() if self.widened else []
            more = self.evaluate([s for s in self.sides if s.extras_due()], beyond)
            resample = self.widen(self.window_checks(beyond, more)[1], centres)
        # the contact intervals' ends, the hand-overs' further steps (edge contact, or a poor
        # first guess) and the extra positions still missing (a flat TE is centred on its
        # contact interval)
        while True:
            for side in self.sides:
                side.interval_finish()
                side.handover_step()
                side.peak_step()
            due = [s for s in self.sides if s.ex is None and s.extras_due()]
            if not due and not any(s.requests or s.probes for s in self.sides):
                break
            self.evaluate(due)
        parts = [
            side.assemble(name, self.frame, self.compound_um, self.separation)
            for side, name in zip(self.sides, self.names, strict=True)
        ]
        return self.contacts(parts)

    def main_sample(self, centres: NDArray) -> None:
        """Sample the pairs nearest each side's mesh centre (relative rotation ``centres[k]``)
        at every position, once per distinct relative rotation, and 1.5 pitches on beyond both
        ends of that range (a contact still inside the flanks there would cut the contact
        interval short), all sides in one call; the sides start anew on it."""
        t, p1, step = self.t, self.pitch, self.step
        extend = step * EXTEND
        windows, rows_side, rows_u, start = [], [], [], 0
        for k in range(len(self.fields)):
            # (n, pairs): each pair's id and base-pair relative rotation; each distinct one's
            # first entry and each entry's distinct one
            shape = (len(t), len(self.windows[k]))
            ids, u = np.empty(shape), np.empty(shape)
            first, inv = np.empty(u.size, np.intp), np.empty(u.size, np.intp)
            count = kernels.window_rows(
                t, float(centres[k]), self.windows[k], p1, ids, u, first, inv
            )
            first = first[:count]
            uu = u.ravel()[first]
            rows_u += [uu, uu.min() - extend, uu.max() + extend]
            windows.append((u, ids, inv, start, len(first)))
            start += len(first) + 2 * len(EXTEND)
            rows_side.append(np.full(len(first) + 2 * len(EXTEND), k, np.intp))
        side_rows = np.concatenate(rows_side)
        phi = self.sense[side_rows] * np.concatenate(rows_u)
        main = self.joint.sample(side_rows, phi)
        self.sides = [
            SideCycle(
                k,
                self.fields[k],
                sample_rows(main, slice(start, start + count)),
                sample_rows(main, slice(start, start + count + 2 * len(EXTEND))),
                u,
                ids,
                inv,
                t,
                p1,
                step,
            )
            for k, (u, ids, inv, start, count) in enumerate(windows)
        ]
        self.classify()

    def classify(self) -> None:
        """Tell the point contacts among the sides whose lag is flat over their interior
        contacts (:attr:`SideCycle.interval_flat`) from the line contacts: a point contact's
        marking-compound zone at the middle of its interior samples closes on the flanks along
        its valley (:meth:`gearopt.mesh.zone.Zones.closed`), a line contact's runs to their
        edges. Sets :attr:`SideCycle.point_contact`, all sides in one evaluation."""
        flat = [s for s in self.sides if s.interval_flat and s.centre_row is not None]
        if not flat:
            return
        zones, contact = self.centre_zones(flat)
        closed = zones.closed(np.arange(len(flat)), contact[:, 0], contact[:, 1])
        for side, point in zip(flat, closed.tolist(), strict=True):
            side.point_contact = point

    def centre_zones(self, sides) -> tuple[Zones, NDArray]:
        """The zones (:class:`gearopt.mesh.zone.Zones`, row k the k-th side's) at the middle
        of the sides' interior samples (:attr:`SideCycle.centre_row`) and their contact points
        ``(K, 2)``."""
        kind = "normal_factor_mm" if self.separation == "normal" else "radius_mm"
        samples = [(s.interval_sample, s.centre_row) for s in sides]
        rows = ZoneRows(
            side=np.array([s.index for s in sides], np.intp),
            phi_rad=np.array([x.phi_rad[r] for x, r in samples]),
            lag_rad=np.array([x.minimum_rad[r] for x, r in samples]),
            factor_mm=np.stack([getattr(x, kind)[r] for x, r in samples]),
        )
        contact = np.array([[x.contact_face_mm[r], x.contact_profile_mm[r]] for x, r in samples])
        return self.zones(rows), contact

    def zones(self, rows: ZoneRows) -> Zones:
        """The zones of ``rows`` (:class:`gearopt.mesh.zone.Zones`), their node factors a copy
        made for them (extended in place)."""
        pinion = self.fields[0].pinion
        return Zones(
            self.joint, pinion.face_mm, pinion.profile_mm, rows, self.compound_um * 1e-3, owned=True
        )

    def beyond_requests(self) -> list[tuple[int, float]]:
        """The pair beyond a window whose end pair carries, where not sampled yet (is the
        window centred on the mesh? does it hold every pair in contact?), as ``(side,
        relative rotation)`` (:func:`gearopt.mesh.kernels.beyond_rows`)."""
        req = []
        for side in self.sides:
            out = np.empty(2 * len(side.u))
            count = kernels.beyond_rows(
                side.interval_v,
                side.u,
                side.carrying,
                self.pitch,
                out,
            )
            req += [(side.index, x) for x in out[:count].tolist()]
        return req

    def window_checks(self, beyond, more: FieldSample | None) -> tuple[NDArray, list[bool]]:
        """Every side's window checked on everything sampled for it (the window, the rows
        beyond it and the ``beyond`` rows, sampled in ``more``;
        :func:`gearopt.mesh.kernels.window_check`): ``(centres, lower)``.

        ``centres``: each side's mesh centre, the relative rotation of least lag; 0 (the window
        stays) where it lies within half a pitch of the window's centre or is not lower than
        the least lag there by more than :data:`FLAT_ARCSEC` (a flat TE, line contact: its
        least lag is noise). ``lower``: True where the pair beyond the window at a position
        where its end pair carries has a lower lag than that end pair (:meth:`widen`)."""
        centres, lower = np.zeros(len(self.fields)), []
        ext_side = np.array([r[0] for r in beyond], np.intp)
        for side in self.sides:
            v = side.interval_v
            g = side.interval_sample.minimum_rad
            if more is not None:
                rows = ext_side == side.index
                v = np.concatenate([v, more.phi_rad[rows] * side.field.sense])
                g = np.concatenate([g, more.minimum_rad[rows]])
            centre, low = kernels.window_check(
                v, g, side.u, side.carrying, side.lag, self.pitch, FLAT_ARCSEC / ARCSEC
            )
            centres[side.index] = centre
            lower.append(low)
        return centres, lower

    def widen(self, lower: list[bool], centres: NDArray) -> bool:
        """Widen by a pair either side (up to :data:`WIDEST` pairs) the window of every side
        whose window stays (``centres`` 0) and whose pair beyond it at a position where its end
        pair carries has a lower lag than that end pair (``lower``, :meth:`window_checks`): the
        TE is the least lag over every pair (a flat lag with more pairs in contact than the
        window holds: its least is any of them). True where a window was widened (sample
        again)."""
        grown = False
        for side, low in zip(self.sides, lower, strict=True):
            k = side.index
            if centres[k] != 0.0 or len(self.windows[k]) + 2 > WIDEST:
                continue
            if low:
                window = self.windows[k]
                self.windows[k] = np.arange(window[0] - 1, window[-1] + 2)
                grown = True
        self.widened |= grown
        return grown

    def evaluate(self, full, beyond=()) -> FieldSample | None:
        """One joint evaluation of every side's pending requests and rows to sample
        (:meth:`SideCycle.take_probes`), the extra positions of the sides ``full``
        (:meth:`SideCycle.extra_rows`) and the ``beyond`` rows ``(side, relative rotation)``;
        returns the beyond rows' sample (None without)."""
        sense = self.sense
        f_side, f_v, f_refine = [], [], []
        for side in full:
            angles, refine = side.extra_rows()
            f_side += [side.index] * len(angles)
            f_v += angles
            f_refine += refine
        # each side's rows to sample, then the beyond rows (their answers filed by side, as
        # the requests' are)
        first_probe = len(f_side)
        probed = []
        for side in self.sides:
            probes = side.take_probes()
            if probes:
                v, tags = zip(*probes, strict=True)
                f_side += [side.index] * len(probes)
                f_v += v
                probed.append((side, tags))
        n_probes = len(f_side) - first_probe
        if beyond:
            b_side, b_v = zip(*beyond, strict=True)
            f_side += b_side
            f_v += b_v
        f_refine += [True] * (n_probes + len(beyond))
        n_side, n_v, n_s, n_h, owners = [], [], [], [], []
        for side in self.sides:
            requests = side.take_requests()
            if requests:
                v, face, profile, tags = zip(*requests, strict=True)
                n_side += [side.index] * len(requests)
                n_v += v
                n_s += face
                n_h += profile
                owners.append((side, tags))
        f_side = np.array(f_side, np.intp)
        f_phi = sense[f_side] * np.array(f_v)
        f_refine = np.array(f_refine, bool)
        sample = answers = None
        if owners:
            n_side = np.array(n_side, np.intp)
            near = (n_side, sense[n_side] * np.array(n_v), np.array(n_s), np.array(n_h))
            if f_side.size:
                sample, answers = self.joint.sample(f_side, f_phi, refine=f_refine, near=near)
            else:
                answers = self.joint.minimum_near(*near)
            # each side's requests in turn: its tags first, so that zip stops at their end
            rows = zip(*(a.tolist() for a in answers), strict=True)
            for side, tags in owners:
                side.answers.update(zip(tags, rows, strict=False))
        elif f_side.size:
            sample = self.joint.sample(f_side, f_phi)
        start = 0
        for side in full:
            count = 3 if side.near_extras else 6
            side.take_extras(sample_rows(sample, slice(start, start + count)))
            start += count
        if probed:  # filed like the requests' answers
            at = slice(first_probe, first_probe + n_probes)
            rows = zip(
                sample.minimum_rad[at].tolist(),
                sample.contact_face_mm[at].tolist(),
                sample.contact_profile_mm[at].tolist(),
                sample.edge[at].tolist(),
                strict=True,
            )
            for side, tags in probed:
                side.answers.update(zip(tags, rows, strict=False))
        start += n_probes
        return sample_rows(sample, slice(start, None)) if beyond else None

    def contacts(self, parts) -> list[ToothContact]:
        """The ToothContacts of the sides' parts (:meth:`SideCycle.assemble`), every side's
        zone at M (its major chord: the ellipse's major axis, its middle M; the minor chord
        through M), the path's direction there (the middles of the zones a quarter step either
        side) and the pattern's width (across the path at M) measured at once on the refined
        field (:class:`gearopt.mesh.zone.Zones`)."""
        n_sides = len(parts)
        frame = self.frame
        lines = [lines for lines, _ in parts]
        pinion = self.fields[0].pinion
        counts = [len(x["pattern_phi_rad"]) for x in lines]
        sizes = [3 + n for n in counts]
        rows = ZoneRows(
            side=np.repeat(np.array([side.index for side in self.sides], np.intp), sizes),
            phi_rad=np.concatenate(
                [a for x in lines for a in (x["mean_phi_rad"], x["pattern_phi_rad"])]
            ),
            lag_rad=np.concatenate(
                [a for x in lines for a in (x["mean_lag_rad"], x["pattern_lag_rad"])]
            ),
            factor_mm=_gathered_factors(lines, counts),
        )
        zones = self.zones(rows)
        first = [0, *itertools.accumulate(sizes)][:-1]
        mean_rows = np.array([f + j for f in first for j in range(3)], np.intp)
        contact = np.concatenate([x["mean_contact_mm"] for x in lines])
        face, profile = pinion.face_mm, pinion.profile_mm  # (ascending)
        reach = float((face[-1] - face[0]) + (profile[-1] - profile[0]))
        major_dir = zones.axes(mean_rows, contact[:, 0], contact[:, 1])
        major, middle = zones.chords(mean_rows, contact, major_dir, np.full(len(contact), reach))
        major, middle, major_dir = (
            a.reshape((n_sides, 3) + a.shape[1:]) for a in (major, middle, major_dir)
        )
        # the path's direction at M: the zones' middles a quarter step either side
        path = middle[:, 2] - middle[:, 1]
        norm = np.hypot(path[:, 0], path[:, 1])
        # (unit vectors on floats: a side's two components; along +face where too short)
        path = np.array(
            [
                (p_s / n, p_h / n) if n > 1e-9 else (1.0, 0.0)
                for (p_s, p_h), n in zip(path.tolist(), norm.tolist(), strict=True)
            ]
        )
        # one batch: the minor chord at M (zone M's reach either side of M) and the pattern
        # across the path at M: how far the pattern the positions' zones sweep runs either
        # side of M along the line across the path (the pairs whose contact points lie within
        # a major axis of M along the path)
        ray, ray_rows, keys, positions = [], [], [], []
        for k, x in enumerate(lines):
            offset = np.abs((x["pattern_contact_mm"] - middle[k, 0]) @ path[k])
            near = np.flatnonzero(offset <= major[k, 0] + 1.0)
            if not near.size and offset.size:  # no pair near M along the path: the nearest
                near = np.array([int(np.argmin(offset))])
            at_m = ([first[k]], [-(10**6)], [0])  # zone M alone
            if near.size:
                across_m = (
                    (near + (first[k] + 3)).tolist(),
                    x["pattern_pair"][near].tolist(),
                    x["pattern_position"][near].tolist(),
                )
            else:
                across_m = at_m
            for slot, (rows_here, key, pos) in enumerate((at_m, at_m, across_m, across_m)):
                ray += [4 * k + slot] * len(rows_here)
                ray_rows += rows_here
                keys += key
                positions += pos
        origins = np.repeat(middle[:, 0], 4, axis=0)
        # each side's minor axis (across the major), either way, and across the path, either way
        directions = np.array(
            [
                ((-a_h, a_s), (a_h, -a_s), (-p_h, p_s), (p_h, -p_s))
                for (a_s, a_h), (p_s, p_h) in zip(
                    major_dir[:, 0].tolist(), path.tolist(), strict=True
                )
            ]
        )
        ray, ray_rows, keys, positions = np.array([ray, ray_rows, keys, positions], np.int64)
        ends = zones.pattern_exits(
            ray,
            ray_rows,
            keys,
            positions,
            origins,
            directions.reshape(-1, 2),
            np.array([False, False, True, True] * n_sides),
        ).reshape(n_sides, 4)
        corner = np.array([frame.toe_mm, frame.root_mm])
        outlines = _Outlines(
            zones,
            corner,
            partial(
                _outline_sides,
                lines,
                first,
                major[:, 0],
                self.sense,
                [side.point_contact for side in self.sides],
            ),
        )
        out = []
        for k, (_, kw) in enumerate(parts):
            mean = (
                float(middle[k, 0, 0] - frame.toe_mm),
                float(middle[k, 0, 1] - frame.root_mm),
            )
            centre = frame.centre_mm
            out.append(
                ToothContact(
                    **kw,
                    width_mm=float(ends[k, 2] + ends[k, 3]),
                    ellipse_major_axis_mm=float(major[k, 0]),
                    ellipse_minor_axis_mm=float(ends[k, 0] + ends[k, 1]),
                    mean_point_mm=mean,
                    outline_source=partial(outlines, k),
                    center_offset_mm=(mean[0] - centre[0], mean[1] - centre[1]),
                )
            )
        return out


def _gathered_factors(lines, counts) -> NDArray:
    """``(R, n_f, n_p)`` the sides' zone rows' node factors, M's rows then the pattern's of each
    side (:meth:`SideCycle.assemble`'s ``lines``), gathered in one copy."""
    shape = lines[0]["mean_factor_mm"].shape[1:]
    factor = np.empty((sum(counts) + 3 * len(counts),) + shape)
    at = 0
    for x, n in zip(lines, counts, strict=True):
        factor[at : at + 3] = x["mean_factor_mm"]
        source, rows = x["pattern_factor_rows"]
        np.take(source, rows, axis=0, out=factor[at + 3 : at + 3 + n], mode="clip")
        at += 3 + n
    return factor


def _outline_sides(lines, first, major, sense, point_contact) -> list[tuple]:
    """Each side's arguments of :meth:`gearopt.mesh.zone.Zones.outline` (``tangency`` last)
    from :meth:`MeshCycle.contacts`' rows: the pattern's rows, their contact points, relative
    rotations, pairs and positions, the reach (the major axis at M plus a mm), the contact
    interval and whether the side is a point contact."""
    return [
        (
            first[k] + 3 + np.arange(len(x["pattern_phi_rad"])),
            x["pattern_contact_mm"],
            sense[k] * x["pattern_phi_rad"],
            x["pattern_pair"],
            x["pattern_position"],
            major[k] + 1.0,
            x["interval"],
            point_contact[k],
        )
        for k, x in enumerate(lines)
    ]


class _Outlines:
    """The sides' outlines (:meth:`gearopt.mesh.zone.Zones.outlines`) in pattern coordinates,
    measured together when the first is asked for (``sides``: a callable making each side's
    arguments of :meth:`~gearopt.mesh.zone.Zones.outline`, ``tangency`` last, then)."""

    def __init__(self, zones: Zones, corner, sides) -> None:
        self.zones, self.corner, self.sides = zones, corner, sides
        self.found: list[NDArray] | None = None

    def __call__(self, k: int) -> NDArray:
        if self.found is None:
            self.found = [o - self.corner for o in self.zones.outlines(self.sides())]
        return self.found[k]


def tooth_contact(
    field: ClearanceField,
    *,
    frame: ToothFrame,
    side: str = "drive",
    positions: int = 21,
    pairs: int = 3,
    cycles: float = 2.0,
    compound_um: float = 6.5,
    separation: str = "normal",
) -> ToothContact:
    """Unloaded TCA of one side on the clearance field (:mod:`gearopt.mesh` for definitions).

    Parameters
    ----------
    field
        The side's clearance field.
    frame
        Pattern coordinates.
    side
        Its name, ``"drive"`` or ``"coast"``.
    positions, pairs, cycles
        Positions over ``cycles`` angular pitches, tooth pairs at each.
    compound_um
        The marking compound.
    separation
        ``"normal"`` or ``"circumferential"``.

    Returns
    -------
    ToothContact
    """
    return tooth_contacts(
        [field],
        frame=frame,
        sides=(side,),
        positions=positions,
        pairs=pairs,
        cycles=cycles,
        compound_um=compound_um,
        separation=separation,
    )[0]


def tooth_contacts(
    fields,
    *,
    frame: ToothFrame,
    sides=("drive", "coast"),
    positions: int = 21,
    pairs: int = 3,
    cycles: float = 2.0,
    compound_um: float = 6.5,
    separation: str = "normal",
) -> list[ToothContact]:
    """Unloaded TCA of several sides of one pair, evaluated together.

    The same results as one :func:`tooth_contact` per side, at about half the cost for two
    sides (:class:`MeshCycle`).

    Parameters
    ----------
    fields
        The sides' clearance fields.
    frame
        Pattern coordinates.
    sides
        The sides' names.
    positions, pairs, cycles, compound_um, separation
        As :func:`tooth_contact`.

    Returns
    -------
    list of ToothContact
        One per side, in order.
    """
    check_options(positions, pairs, cycles, compound_um, separation)
    return MeshCycle(
        fields,
        sides,
        frame=frame,
        positions=positions,
        pairs=pairs,
        cycles=cycles,
        compound_um=compound_um,
        separation=separation,
    ).run()
