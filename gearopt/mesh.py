"""Mesh-cycle analyses on the clearance field: TCA, contact pattern, backlash, ease-off.

Everything here works on :class:`gearopt.contact.ClearanceField` objects and knows nothing of
machines. Conventions (DESIGN.md): the drive side is the pinion's convex flank driving the
gear's concave flank, the coast side the pinion's concave driving the gear's convex. TE is in
arcsec of gear rotation, negative when the driven gear lags, shifted so its maximum over the mesh
is 0. Pattern coordinates on the pinion flank projected to the axial plane: ``face`` from the toe
(0) toward the heel, ``profile`` from the root (0) toward the top.

Definitions used by the outputs:

- positions: ``positions`` pinion angles over ``cycles`` angular pitches, centred on the mean
  position, in the pinion's direction of motion (``phi1_deg``);
- at each position the ``pairs`` tooth pairs nearest the mesh centre; the carrying pair is the
  one on which the gear lags least;
- hand-over: where the TE curves of two successive pairs intersect, solved on the clearance
  field, not read off the samples: where the samples around it are interior contacts (smooth
  lags), guessed where the cubic interpolants of the two pairs' sampled lags cross, then the
  root of the parabola through the lag differences evaluated at the guess and an eighth of a
  step to either side (a guess further off is evaluated anew); otherwise (edge contact) a
  secant step, the parabola through three differences and a last secant step; peak-to-peak
  TE = the TE maximum (refined by parabolas) minus the TE at the hand-over, or minus a lower
  sampled value if any;
- instantaneous contact zone: the nodes within the marking compound of the mating flank; the
  contact path is the zone's centroid (weights ``compound - separation``, so a paraboloid's
  centroid is its vertex and a line contact's is its middle) along the carrying pair's cycle;
- mean contact point M: the path point midway between the carrying pair's hand-overs; bias =
  the contact line's extension along the face (seed 003 section 6): the face coordinate of the
  contact point where the pair leaves contact inside the flanks minus where it enters (the ends
  of its contact interval: bracketed by bisection on the engine's edge flag to an eighth of a
  position step, the points it can visit evaluated at once, then moved to where the tangency
  point -- the solution of the tangency equations, :mod:`gearopt.newton_tca` -- leaves the
  flanks, but for line contact; the carrying cycle's ends when the contact never leaves the
  flanks' interior); width = extent of the zone at M perpendicular to the path;
  ``center_offset_mm`` = M minus the flank centre C (the mean cone distance, mid working
  depth: h = (a1 - a2) / 2 with a the mean addenda);
- contact ratio: the pinion rotation over which a pair's contact stays inside the flanks (not
  at an edge), over the angular pitch (sampled on beyond the analysed range when a pair is
  still in contact at its ends, up to 1.5 pitches more).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from dataclasses import fields as dataclass_fields

import numpy as np
from numpy.typing import NDArray

from gearopt.analysis_options import check_options
from gearopt.assembly import Placement
from gearopt.contact import ClearanceField, ContactError, FieldSample, JointField
from gearopt.contact import kernels as contact_kernels
from gearopt.flank_jet import FlankJet, cross

__all__ = [
    "ToothFrame",
    "ToothContact",
    "Backlash",
    "EaseOff",
    "tooth_contact",
    "backlash",
    "ease_off",
]

ARCSEC = 180.0 * 3600.0 / math.pi
#: lags that vary by less than this (arcsec) are flat: a line contact, or noise on one
FLAT_ARCSEC = 0.1


@dataclass(frozen=True, kw_only=True)
class ToothFrame:
    """Pattern coordinates on the pinion flank: ``face = s - toe_mm``, ``profile = h - root_mm``
    and the flank centre C in those coordinates."""

    toe_mm: float
    root_mm: float
    centre_mm: tuple[float, float]
    face_width_mm: float
    gear_root_angle_deg: float = 90.0

    @classmethod
    def from_blank(cls, blank) -> ToothFrame:
        a1, a2 = blank.mean_addendum_mm
        root = -blank.mean_dedendum_mm[0]
        return cls(
            toe_mm=blank.mean_cone_distance_mm - 0.5 * blank.face_width_mm,
            root_mm=root,
            centre_mm=(0.5 * blank.face_width_mm, 0.5 * (a1 - a2) - root),
            face_width_mm=blank.face_width_mm,
            gear_root_angle_deg=blank.root_angle_deg[1],
        )


def path_angle(tangent, normal, point, root_angle_rad: float) -> float:
    """Direction (deg) of a path of contact on the gear flank at ``point`` (gear member frame,
    ``normal`` the flank's): the angle from the gear's root line -- the root cone's generatrix
    through the point, projected on the tangent plane, toward the heel -- to the path's tangent
    (oriented toward the heel too), positive when the path rises toward the tooth top. Range
    (-90, 90]; Litvin's eta_2 of local synthesis with this sign."""
    n = np.asarray(normal, float)
    n = n / np.linalg.norm(n)
    theta = math.atan2(point[1], point[0])
    e_r = np.array([math.cos(theta), math.sin(theta), 0.0])
    e_z = np.array([0.0, 0.0, 1.0])
    along = math.sin(root_angle_rad) * e_r + math.cos(root_angle_rad) * e_z
    up = math.cos(root_angle_rad) * e_r - math.sin(root_angle_rad) * e_z
    along = along - (along @ n) * n
    along /= np.linalg.norm(along)
    up = up - (up @ n) * n - (up @ along) * along
    up /= np.linalg.norm(up)
    t = np.asarray(tangent, float)
    t = t - (t @ n) * n
    if t @ along < 0.0:
        t = -t
    angle = math.degrees(math.atan2(t @ up, t @ along))
    return 90.0 if angle <= -90.0 + 1e-12 else angle


def _gear_path_angle(field: ClearanceField, ex: FieldSample, frame: ToothFrame) -> float:
    """The path's direction on the gear flank at M (:func:`path_angle`) from the contact points
    of the two positions either side of M (rows 4 and 5 of the extra positions), carried into
    the gear's frame at their contact angles."""
    phi = ex.phi_rad[4:6]
    p = field.pinion.point_at(ex.contact_face_mm[4:6], ex.contact_profile_mm[4:6])
    cp, sp = np.cos(phi), np.sin(phi)
    p = np.stack([cp * p[:, 0] - sp * p[:, 1], sp * p[:, 0] + cp * p[:, 1], p[:, 2]], -1)
    q = p @ field.b.T + field.c
    turn = -field.ratio * phi + field.gear_offset_rad - field.gear_sense * ex.minimum_rad[4:6]
    ct, st = np.cos(turn), np.sin(turn)
    points = np.stack([ct * q[:, 0] + st * q[:, 1], -st * q[:, 0] + ct * q[:, 1], q[:, 2]], -1)
    mid = 0.5 * (points[0] + points[1])
    s2, h2 = field.gear.to_grid(mid[2], math.hypot(mid[0], mid[1]))
    _, p_s, p_h, *_ = FlankJet(field.gear).surface(float(s2), float(h2), 0.0)
    return path_angle(
        points[1] - points[0], cross(p_s, p_h), mid, math.radians(frame.gear_root_angle_deg)
    )


@dataclass(frozen=True, kw_only=True)
class ToothContact:
    """TCA of one side (see the module docstring for every definition).

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
    width_mm, bias_mm, center_offset_mm, mean_point_mm
        Pattern width (the whole pattern's extent across the path at M), bias, M - C, and M,
        in pattern coordinates.
    ellipse_major_axis_mm
        Length of the instantaneous contact zone at M along its principal (long) axis: the
        major axis of seed 003's contact ellipse, whatever its angle to the path.
    path_angle_deg
        Direction of the path of contact at M on the gear flank, from the gear's root line
        (:func:`path_angle`; the contact points of two positions either side of M).
    contact_ratio
        Pinion rotation with interior contact over the angular pitch.
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
    path_angle_deg: float
    bias_mm: float
    center_offset_mm: tuple[float, float]
    mean_point_mm: tuple[float, float]
    contact_ratio: float
    compound_um: float
    separation: str

    @property
    def edge_contact(self) -> bool:
        """True when the carrying pair touches at an edge at any position."""
        return bool(self.edge.any())

    def as_dict(self) -> dict:
        """JSON-ready summary (the ``tca`` object of ``gearopt analyze --json``)."""
        return {
            "side": self.side,
            "phi1_deg": _list(self.phi1_deg),
            "te_arcsec": _list(self.te_arcsec),
            "te_peak_to_peak_arcsec": float(self.te_peak_to_peak_arcsec),
            "handover_phi1_deg": _list(self.handover_phi1_deg),
            "contact_ratio": float(self.contact_ratio),
            "path": {
                "face_mm": _list(self.path_face_mm),
                "profile_mm": _list(self.path_profile_mm),
            },
            "edge": [bool(e) for e in self.edge],
            "pattern": {
                "width_mm": float(self.width_mm),
                "ellipse_major_axis_mm": float(self.ellipse_major_axis_mm),
                "path_angle_deg": float(self.path_angle_deg),
                "bias_mm": float(self.bias_mm),
                "center_offset_mm": [float(v) for v in self.center_offset_mm],
                "mean_point_mm": [float(v) for v in self.mean_point_mm],
                "edge_contact": self.edge_contact,
                "compound_um": float(self.compound_um),
                "separation": self.separation,
            },
        }


def _list(values) -> list[float]:
    return [float(v) for v in np.asarray(values).ravel()]


class _PairCurve:
    """The base pair's lag G(u) at relative pinion rotations u (direction of motion)."""

    def __init__(self, field: ClearanceField, gear_angle_rad=0.0):
        self.field = field
        self.gear_angle_rad = gear_angle_rad
        self.pitch = field.pinion.pitch_rad

    def sample(self, u: NDArray, gear_angle_rad=None) -> FieldSample:
        angle = self.gear_angle_rad if gear_angle_rad is None else gear_angle_rad
        return self.field.sample(self.field.sense * np.asarray(u, float), angle)

    def __call__(self, u: NDArray) -> NDArray:
        return self.sample(u).minimum_rad


def _separation_mm(
    sample: FieldSample, reference_rad: NDArray, separation: str, rows=slice(None)
) -> NDArray:
    """Separation of every node from the mating flank with the gear at ``reference_rad`` lag
    (one per row), on the sample's rows ``rows``."""
    factor = sample.normal_factor_mm if separation == "normal" else sample.radius_mm
    reference = reference_rad.reshape(-1, 1, 1)
    # (NaN, then +inf: inf - inf, a row with nothing on the flanks; inf * 0, off the flanks)
    with np.errstate(invalid="ignore"):
        if isinstance(rows, slice):
            extra = sample.clearance_rad[rows] - reference
        else:  # a gathered copy, worked on in place
            extra = sample.clearance_rad[rows]
            extra -= reference
        extra *= factor[rows]
    np.copyto(extra, np.inf, where=np.isnan(extra))
    return extra


def _centroids(sep_mm: NDArray, compound_mm: float, face_mm, profile_mm):
    """Weighted centroids (weights compound - separation) of each row's zone; NaN-free: a row
    without a zone reports its least-separated node."""
    w = np.clip(compound_mm - sep_mm, 0.0, None)  # (finite: separations are never NaN)
    total = w.sum(axis=(1, 2))
    s = np.broadcast_to(face_mm[:, None], sep_mm.shape[1:])
    h = np.broadcast_to(profile_mm[None, :], sep_mm.shape[1:])
    flat = sep_mm.reshape(len(sep_mm), -1).argmin(axis=1)
    s0, h0 = s.ravel()[flat], h.ravel()[flat]
    safe = np.where(total > 0.0, total, 1.0)
    cs = np.where(total > 0.0, (w * s).sum(axis=(1, 2)) / safe, s0)
    ch = np.where(total > 0.0, (w * h).sum(axis=(1, 2)) / safe, h0)
    return cs, ch


def _minor_axis(sep_mm: NDArray, compound_mm, face_mm, profile_mm) -> NDArray:
    """Unit vector of the zone's minor axis (weighted second moments), in (face, profile);
    along the face for a zone without extent (no node, or one: its moments are rounding
    noise, whose eigenvectors would point anywhere)."""
    w = np.clip(compound_mm - sep_mm, 0.0, None)  # (finite: separations are never NaN)
    if np.count_nonzero(w) <= 1:
        return np.array([1.0, 0.0])
    s = np.broadcast_to(face_mm[:, None], w.shape)
    h = np.broadcast_to(profile_mm[None, :], w.shape)
    ms, mh = (w * s).sum() / w.sum(), (w * h).sum() / w.sum()
    cov = np.array(
        [
            [(w * (s - ms) ** 2).sum(), (w * (s - ms) * (h - mh)).sum()],
            [(w * (s - ms) * (h - mh)).sum(), (w * (h - mh) ** 2).sum()],
        ]
    )
    vals, vecs = np.linalg.eigh(cov)
    minor = vecs[:, np.argmin(vals)]
    return np.array([minor[0], minor[1]])


def _widths(sep_mm: NDArray, compound_mm, face_mm, profile_mm, points, directions) -> NDArray:
    """Extent of {separation < compound} along the line through ``points[k]`` perpendicular
    to ``directions[k]`` on the field ``sep_mm[k]`` (``(K, n_f, n_p)``), for K lines at once,
    by bilinear interpolation of the node field (sampled at 2001 points; from the middle
    outward, the first sample out of the zone on each side bounds it)."""
    points, directions = np.asarray(points, float), np.asarray(directions, float)
    n_lines = len(sep_mm)
    perp = np.stack([-directions[:, 1], directions[:, 0]], axis=1)
    reach = float(face_mm[-1] - face_mm[0] + profile_mm[-1] - profile_mm[0])
    tau = np.linspace(-reach, reach, 2001)
    big = 10.0 * compound_mm
    f = np.where(np.isfinite(sep_mm), np.minimum(sep_mm, big), big)
    if contact_kernels.ENABLED:  # the same samples, line by line
        width = np.empty(n_lines)
        grid = (np.asarray(face_mm, float), np.asarray(profile_mm, float))
        contact_kernels.zone_widths(f, compound_mm, *grid, points, perp, tau, big, width)
        return width
    flat, n_p, size = f.ravel(), f.shape[2], f.shape[1] * f.shape[2]

    def value(line, k):
        """The interpolated separation minus the compound at the samples ``k`` of lines
        ``line``."""
        tk = tau[k]
        s = points[line, 0] + tk * perp[line, 0]
        h = points[line, 1] + tk * perp[line, 1]
        inside = (s >= face_mm[0]) & (s <= face_mm[-1])
        inside &= (h >= profile_mm[0]) & (h <= profile_mm[-1])
        i = np.minimum(np.maximum(np.searchsorted(face_mm, s) - 1, 0), len(face_mm) - 2)
        j = np.minimum(np.maximum(np.searchsorted(profile_mm, h) - 1, 0), len(profile_mm) - 2)
        s0, h0 = face_mm[i], profile_mm[j]
        u = np.minimum(np.maximum((s - s0) / (face_mm[i + 1] - s0), 0.0), 1.0)
        v = np.minimum(np.maximum((h - h0) / (profile_mm[j + 1] - h0), 0.0), 1.0)
        at = line * size + i * n_p + j
        val = (
            (1 - u) * (1 - v) * flat[at]
            + u * (1 - v) * flat[at + n_p]
            + (1 - u) * v * flat[at + 1]
            + u * v * flat[at + n_p + 1]
        )
        val[~inside] = big
        val -= compound_mm
        return val

    centre = len(tau) // 2
    # from the middle outward on each side: every 25th sample, then all of them up to the
    # first coarse one out of the zone (or to the end), each side's first sample out bounds it
    ways = (np.arange(centre, len(tau)), np.arange(centre, -1, -1))
    coarse = np.concatenate([w[::25] for w in ways])
    n_coarse = len(coarse) // 2
    lines = np.repeat(np.arange(n_lines), len(coarse))
    val = value(lines, np.tile(coarse, n_lines)).reshape(n_lines, 2, n_coarse)
    hits = val >= 0.0
    spans = [
        ways[w] if not hits[k, w].any() else ways[w][: 25 * np.argmax(hits[k, w]) + 1]
        for k in range(n_lines)
        for w in (0, 1)
    ]
    fine_lines = np.repeat(np.repeat(np.arange(n_lines), 2), [len(a) for a in spans])
    fine = np.split(
        value(fine_lines, np.concatenate(spans)), np.cumsum([len(a) for a in spans])[:-1]
    )
    width = np.zeros(n_lines)
    for k in range(n_lines):
        if val[k, 0, 0] >= 0.0:
            continue
        ends = []
        for span, v, edge in zip(
            spans[2 * k : 2 * k + 2], fine[2 * k : 2 * k + 2], (tau[-1], tau[0]), strict=True
        ):
            out = np.flatnonzero(v >= 0.0)
            if not out.size:
                ends.append(edge)
                continue
            k_in, k_out, a, b = span[out[0] - 1], span[out[0]], v[out[0] - 1], v[out[0]]
            ends.append(tau[k_in] + (tau[k_out] - tau[k_in]) * a / (a - b))
        width[k] = ends[0] - ends[1]
    return width


def _slice(sample: FieldSample, rows) -> FieldSample:
    """The rows ``rows`` of a sample (a slice or an index array)."""
    return FieldSample(
        **{f.name: getattr(sample, f.name)[rows] for f in dataclass_fields(FieldSample)}
    )


EXTEND = np.array([1, 2, 3, 5, 10, 15])  # sample steps beyond the range (contact interval)


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
    """Unloaded TCA of one side on the clearance field (module docstring for definitions)."""
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


class _Side:
    """The per-side state of :func:`tooth_contacts` between its joint evaluations."""

    def __init__(self, index, field, sample, u, ids, inv):
        self.index, self.field = index, field
        self.sample = sample
        self.u, self.ids, self.inv = u, ids, inv
        shape = u.shape
        self.g = sample.minimum_rad[inv].reshape(shape)
        self.edge_all = sample.edge[inv].reshape(shape)
        if not np.isfinite(self.g).any(axis=1).all():
            raise ContactError(
                "tca", rule="at some positions no tooth pair touches inside the flanks"
            )
        rows = np.arange(shape[0])
        self.carrying = np.argmin(self.g, axis=1)
        self.lag = self.g[rows, self.carrying]
        self.pair_id = ids[rows, self.carrying]
        self.cs = sample.contact_face_mm[inv].reshape(shape)
        self.ch = sample.contact_profile_mm[inv].reshape(shape)


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
    """Unloaded TCA of several sides of one pair (``fields``, named by ``sides``), evaluated
    together (:class:`gearopt.contact.JointField`): the same results as one
    :func:`tooth_contact` per side, at about half the cost for two sides."""
    check_options(positions, pairs, cycles, compound_um, separation)
    fields = list(fields)
    joint = JointField(fields)
    n_sides = len(fields)
    p1 = fields[0].pinion.pitch_rad
    sense = np.array([f.sense for f in fields], float)
    t = np.linspace(-0.5 * cycles * p1, 0.5 * cycles * p1, positions)
    step = t[1] - t[0]
    offsets = np.arange(pairs) - (pairs - 1) // 2

    def main_sample(centres):
        """The pairs nearest each side's mesh centre (relative angle ``centres[k]``) at every
        position, sampled once per distinct relative angle, and 1.5 pitches on beyond both ends
        of that range (a contact still inside the flanks there would cut the contact interval
        short), all sides in one call."""
        windows, rows_side, rows_u = [], [], []
        for k in range(n_sides):
            ids = np.round((centres[k] - t) / p1)[:, None] + offsets[None, :]
            u = t[:, None] + ids * p1  # (n, pairs): each pair's base-pair relative angle
            key = np.round(u.ravel() / p1 * 1e9).astype(np.int64)
            _, first, inv = np.unique(key, return_index=True, return_inverse=True)
            uu = u.ravel()[first]
            ext = np.concatenate([uu.min() - step * EXTEND, uu.max() + step * EXTEND])
            windows.append((u, ids, inv, len(rows_u), len(first)))
            rows_side += [k] * (len(first) + len(ext))
            rows_u += list(uu) + list(ext)
        side_rows = np.array(rows_side, np.intp)
        main = joint.sample(side_rows, sense[side_rows] * np.array(rows_u))
        out = []
        for k, (u, ids, inv, start, count) in enumerate(windows):
            st = _Side(k, fields[k], _slice(main, slice(start, start + count)), u, ids, inv)
            st.interval_sample = _slice(main, slice(start, start + count + 2 * len(EXTEND)))
            out.append(st)
        return out

    def beyond_requests(states):
        """The pair beyond a window whose end pair carries, where not sampled yet (is the
        window centred on the mesh?)."""
        req = []
        for st in states:
            v = st.interval_sample.phi_rad * st.field.sense
            known = set(np.round(v / p1 * 1e9).tolist())
            for slot, sign in ((0, -1.0), (pairs - 1, 1.0)):
                beyond = st.u[st.carrying == slot, slot] + sign * p1
                keys = np.round(beyond / p1 * 1e9).tolist()
                req += [
                    (st.index, x) for x, key in zip(beyond, keys, strict=True) if key not in known
                ]
        return req

    def evaluate(states, full, beyond=()):
        """One joint evaluation of every side's pending refinements started from nearby
        contact points (contact-interval ends, hand-over), the extra positions of the sides
        ``full`` (hand-over, TE peak, mean point M and its neighbours) and the ``beyond`` rows
        ``(side, v)``; returns the beyond rows' sample. Where the hand-over is guessed from
        smooth lags, the extra positions' minima are refined from the contact points
        interpolated along the samples and only M's rows take node fields; otherwise each
        takes node fields and a refined minimum."""
        f_side, f_v, f_refine = [], [], []
        for st in full:
            angles = _extra_angles(st, t, p1, step)
            st.near_extras = _fit_mode(st)
            if st.near_extras:
                f_side += [st.index] * 3
                f_v += angles[3:]
                f_refine += [False] * 3
                for j, v in enumerate(angles):
                    st.requests.append((v, *_contact_at(st, v), ("ex", j)))
            else:
                f_side += [st.index] * 6
                f_v += angles
                f_refine += [True] * 6
            st.ex_phi = st.field.sense * np.array(angles)
        f_side += [r[0] for r in beyond]
        f_v += [r[1] for r in beyond]
        f_refine += [True] * len(beyond)
        n_side, n_v, n_s, n_h, owners = [], [], [], [], []
        for st in states:
            for v, s, h, tag in st.requests:
                n_side.append(st.index)
                n_v.append(v)
                n_s.append(s)
                n_h.append(h)
                owners.append((st, tag))
            st.requests = []
        f_side = np.array(f_side, np.intp)
        f_phi = sense[f_side] * np.array(f_v)
        f_refine = np.array(f_refine, bool)
        sample = answers = None
        if owners:
            n_side = np.array(n_side, np.intp)
            near = (n_side, sense[n_side] * np.array(n_v), np.array(n_s), np.array(n_h))
            if f_side.size:
                sample, answers = joint.sample(f_side, f_phi, refine=f_refine, near=near)
            else:
                answers = joint.minimum_near(*near)
            for k, (st, tag) in enumerate(owners):
                st.answers[tag] = tuple(a[k] for a in answers)
        elif f_side.size:
            sample = joint.sample(f_side, f_phi)
        start = 0
        for st in full:
            if st.near_extras:
                st.ex = _near_extras(st, _slice(sample, slice(start, start + 3)))
                start += 3
            else:
                st.ex = _slice(sample, slice(start, start + 6))
                start += 6
        return _slice(sample, slice(start, None)) if beyond else None

    def begin(states):
        for st in states:
            st.ex, st.answers, st.requests = None, {}, []
            _start_interval(st)
            _start_handover(st, t, p1, step)

    # the contact intervals' ends (bisection on the edge flag, its candidate points evaluated
    # at once), the first hand-over evaluations and, where the hand-over is guessed from
    # smooth lags, the extra positions, with the pairs beyond the windows: one joint evaluation
    states = main_sample(np.zeros(n_sides))
    begin(states)
    req = beyond_requests(states)
    more = evaluate(states, [st for st in states if _extras_due(st)], req)
    # the mesh centre of each side: the relative angle of least lag over everything sampled;
    # a window not centred on it (the contact moved by misalignment) is centred and resampled
    centres = np.zeros(n_sides)
    ext_side = np.array([r[0] for r in req], np.intp)
    for st in states:
        v = st.interval_sample.phi_rad * st.field.sense
        g = st.interval_sample.minimum_rad
        if more is not None:
            rows = ext_side == st.index
            v = np.concatenate([v, more.phi_rad[rows] * st.field.sense])
            g = np.concatenate([g, more.minimum_rad[rows]])
        g = np.where(np.isfinite(g), g, np.inf)
        central = np.abs(v) <= 0.5 * p1 + 1e-9
        best = int(np.argmin(g))
        # (a flat TE, line contact, keeps the window: its least lag is noise)
        flat = FLAT_ARCSEC / ARCSEC
        if not central[best] and g[best] < np.min(g[central], initial=np.inf) - flat:
            centres[st.index] = float(v[best])
    if np.any(centres != 0.0):
        states = main_sample(centres)
        begin(states)
        evaluate(states, [st for st in states if _extras_due(st)])
    # the contact intervals' ends, the hand-overs' further steps (edge contact, or a poor first
    # guess) and the extra positions still missing (a flat TE is centred on its contact
    # interval)
    while True:
        for st in states:
            _interval_finish(st)
            _handover_step(st, p1)
        due = [st for st in states if st.ex is None and _extras_due(st)]
        if not due and not any(st.requests for st in states):
            break
        evaluate(states, due)
    return _contacts(
        [
            _assemble(st, name, st.ex, t, p1, frame, pairs, compound_um, separation)
            for st, name in zip(states, sides, strict=True)
        ],
        compound_um * 1e-3,
    )


def _contacts(parts, compound_mm) -> list[ToothContact]:
    """The ToothContacts of :func:`_assemble`'s parts, every side's pattern width (across the
    path at M) and contact-ellipse major axis (along the zone's long axis at M) measured at
    once."""
    fields = [f for lines, _ in parts for f in lines[:2]]
    points = [lines[2] for lines, _ in parts for _ in (0, 1)]
    directions = [d for lines, _ in parts for d in lines[3:]]
    face, profile = parts[0][1]["face_mm"], parts[0][1]["profile_mm"]
    widths = _widths(np.stack(fields), compound_mm, face, profile, points, directions)
    return [
        ToothContact(
            **kw, width_mm=float(widths[2 * k]), ellipse_major_axis_mm=float(widths[2 * k + 1])
        )
        for k, (_, kw) in enumerate(parts)
    ]


def _extras_due(st) -> bool:
    """Whether a side's extra positions can be evaluated: its hand-over is settled or guessed
    from smooth lags, or (no hand-over) its contact interval is known."""
    ho = st.ho
    if ho is None:
        return st.interval_done
    return ho.get("done", False) or ho["mode"] == "fit"


def _fit_mode(st) -> bool:
    """Whether a side's hand-over is being checked at a guess from smooth lags."""
    return st.ho is not None and not st.ho.get("done") and st.ho["mode"] == "fit"


def _contact_at(st, v: float) -> tuple[float, float]:
    """A start for a refinement at relative angle ``v``: the contact point interpolated
    (linearly in v) between the nearest samples in contact on either side."""
    sample = st.interval_sample
    if not hasattr(st, "path"):
        ok = np.isfinite(sample.minimum_rad)
        vs = sample.phi_rad[ok] * st.field.sense
        order = np.argsort(vs)
        st.path = (
            vs[order],
            sample.contact_face_mm[ok][order],
            sample.contact_profile_mm[ok][order],
        )
    vs, cs, ch = st.path
    return float(np.interp(v, vs, cs)), float(np.interp(v, vs, ch))


def _near_extras(st, mean: FieldSample) -> FieldSample:
    """The extra positions' sample from their refined minima (answers ``("ex", j)``) and the
    node fields of M's rows (``mean``); the other rows have no node fields (+inf)."""
    got = [st.answers.pop(("ex", j)) for j in range(6)]
    blank = np.full((3,) + mean.clearance_rad.shape[1:], np.inf)
    ones = np.ones_like(blank)
    return FieldSample(
        phi_rad=st.ex_phi,
        clearance_rad=np.concatenate([blank, mean.clearance_rad]),
        normal_factor_mm=np.concatenate([ones, mean.normal_factor_mm]),
        radius_mm=np.concatenate([ones, mean.radius_mm]),
        minimum_rad=np.array([a[0] for a in got], float),
        contact_face_mm=np.array([a[1] for a in got], float),
        contact_profile_mm=np.array([a[2] for a in got], float),
        edge=np.array([a[3] for a in got], bool),
    )


def _extra_angles(st, t, p1, step) -> list[float]:
    """The extra positions of a side: the hand-over (both pairs), the TE peak, the mean point
    M and its neighbours for the path direction; a flat TE (line contact, no hand-over) is
    centred on the contact interval."""
    if st.v_star is None:
        start, end = st.interval
        st.v_star = 0.5 * (start + end) + 0.5 * p1
        st.g_hand = float(np.max(st.g.min(axis=1)))
    v_mid = st.v_star - 0.5 * p1
    dv = 0.25 * step
    return [st.v_star, st.v_star - p1, _peak_guess(st, t, p1, step), v_mid, v_mid - dv, v_mid + dv]


def _peak_guess(st, t, p1, step) -> float:
    """The TE maximum's relative angle: the parabola through the least sample of the
    carrying pair and its neighbours on the same pair."""
    lag, pair_id = st.lag, st.pair_id
    act = np.flatnonzero(pair_id == pair_id[np.argmin(lag)])
    kk = act[np.argmin(lag[act])]
    v_peak = t[kk] + pair_id[kk] * p1
    if 0 < kk < len(t) - 1 and pair_id[kk - 1] == pair_id[kk] == pair_id[kk + 1]:
        gm, g0, gp = lag[kk - 1], lag[kk], lag[kk + 1]
        curv = gm - 2.0 * g0 + gp
        if curv > 0.0:
            v_peak += float(np.clip(0.5 * (gm - gp) / curv, -1.0, 1.0)) * step
    return float(v_peak)


BISECTIONS = 3  # contact-interval ends to an eighth of a position step


def _start_interval(st) -> None:
    """Bracket the relative angles between which a pair's contact stays inside the flanks
    (not at an edge) from the samples, and ask for the points a bisection of each open bracket
    can visit (warm-started Newton), all at once."""
    sample = getattr(st, "interval_sample", st.sample)
    v = sample.phi_rad * st.field.sense
    inner = (~sample.edge) & np.isfinite(sample.minimum_rad)
    order = np.argsort(v)
    v, inner = v[order], inner[order]
    st.interval_done = False
    if not inner.any():  # edge contact only: no interval, centred on the least lag
        gs = np.where(np.isfinite(sample.minimum_rad), sample.minimum_rad, np.inf)[order]
        best = float(v[np.argmin(gs)])
        st.interval, st.bisect, st.interval_done = (best, best), False, True
        return
    # the unbroken run of interior samples around the least lag (the mesh centre), or the
    # longest run when the least lag is itself at an edge
    gs = np.where(np.isfinite(sample.minimum_rad), sample.minimum_rad, np.inf)[order]
    runs = np.split(np.arange(len(v)), np.flatnonzero(np.diff(inner.astype(int))) + 1)
    runs = [r for r in runs if inner[r[0]]]
    centre = int(np.argmin(gs))
    around = [r for r in runs if r[0] <= centre <= r[-1]]
    run = around[0] if around else max(runs, key=len)
    lo_k, hi_k = run[0], run[-1]
    st.ci_flat = bool(np.ptp(gs[lo_k : hi_k + 1]) < FLAT_ARCSEC / ARCSEC)
    st.ci_a = np.array([v[lo_k], v[hi_k]])  # inside
    st.ci_b = np.array([v[max(lo_k - 1, 0)], v[min(hi_k + 1, len(v) - 1)]])  # outside
    st.ci_open = np.array([lo_k > 0, hi_k < len(v) - 1])
    cs, ch = sample.contact_face_mm[order], sample.contact_profile_mm[order]
    st.ci_s, st.ci_h = cs[[lo_k, hi_k]], ch[[lo_k, hi_k]]
    st.bisect, st.interval_done = True, False
    st.interval = (float(st.ci_a[0]), float(st.ci_a[1]))
    parts = 2**BISECTIONS
    for e in np.flatnonzero(st.ci_open):
        a, b = st.ci_a[e], st.ci_b[e]
        for j in range(1, parts):
            st.requests.append((a + (b - a) * j / parts, st.ci_s[e], st.ci_h[e], ("ci", e, j)))


def _interval_finish(st) -> None:
    """Bisect each open bracket on the answers of its candidate points, then move it to the
    tangency point's exit (:func:`_tangency_end`): the end is the middle of the last bracket,
    the contact point the last inside one's."""
    if st.interval_done:
        return
    st.interval_done = True
    parts = 2**BISECTIONS
    for e in np.flatnonzero(st.ci_open):
        a, b = st.ci_a[e], st.ci_b[e]
        ja, jb = 0, parts
        for _ in range(BISECTIONS):
            m = (ja + jb) // 2
            value, s1, h1, edge = st.answers[("ci", e, m)]
            if np.isfinite(value) and not edge:
                ja = m
                st.ci_s[e], st.ci_h[e] = s1, h1
            else:
                jb = m
        st.ci_a[e], st.ci_b[e] = a + (b - a) * ja / parts, a + (b - a) * jb / parts
        _tangency_end(st, e)
    ends = np.where(st.ci_open, 0.5 * (st.ci_a + st.ci_b), st.ci_a)
    st.interval = (float(ends[0]), float(ends[1]))


def _tangency_end(st, e: int) -> None:
    """An interval end bisected on the engine's edge flag, moved to where the tangency point
    leaves the flanks (:meth:`gearopt.contact.ClearanceField.interval_end`). The edge flag lags
    that point where the minimum slides along a boundary before the clearance beyond it falls
    by the edge tolerance (a path meeting the boundary at a grazing angle to the contact
    ellipse), and leads it where the tangency point lies in the pinion's lowest generated
    cells, which the engine's refinement does not enter. Kept as it is where Newton's method
    fails, and where the pair's lag is flat over its interior contacts (:data:`FLAT_ARCSEC`:
    a line contact, where the tangency point is not unique, or nearly one)."""
    if st.ci_flat:
        return
    a, b = float(st.ci_a[e]), float(st.ci_b[e])
    found = st.field.interval_end(a, (float(st.ci_s[e]), float(st.ci_h[e])), b - a)
    if found is not None:
        st.ci_a[e], st.ci_b[e], st.ci_s[e], st.ci_h[e] = found


def _start_handover(st, t, p1, step) -> None:
    """Find a forward switch of the carrying pair (the next pair, one id lower, takes over)
    whose two pairs' lag difference D changes sign: it brackets the hand-over. Where the
    samples around both pairs' ends of the bracket are interior contacts, the first guess is
    the crossing of the two pairs' interpolated lags, checked by evaluations at it and an
    eighth of a step to either side (:func:`_handover_step`: the root of the parabola through
    the three lag differences stands within a tenth of that from the guess, is evaluated anew
    once if further); otherwise (edge contact: the lags are not smooth), or if the guesses do
    not settle, a secant step, the parabola through three differences and a last secant step.
    Without a bracket the TE is flat (line contact) and the cycle is centred on the contact
    interval."""
    st.v_star, st.g_hand, st.ho = None, None, None
    g, ids, pair_id = st.g, st.ids, st.pair_id
    n = len(t)
    for k in np.flatnonzero(np.diff(pair_id) == -1):
        leave = pair_id[k]
        col_l = [np.flatnonzero(ids[k + d] == leave) for d in (0, 1)]
        col_i = [np.flatnonzero(ids[k + d] == leave - 1) for d in (0, 1)]
        if any(c.size == 0 for c in col_l + col_i) or k + 1 >= n:
            continue
        with np.errstate(invalid="ignore"):  # inf - inf where a pair is off the flanks
            d_lo = g[k, col_l[0][0]] - g[k, col_i[0][0]]
            d_hi = g[k + 1, col_l[1][0]] - g[k + 1, col_i[1][0]]
        finite = np.isfinite(d_lo) and np.isfinite(d_hi)
        if finite and d_lo <= 0.0 <= d_hi and d_hi - d_lo > 1e-9 / ARCSEC:
            lo, hi = t[k] + leave * p1, t[k + 1] + leave * p1
            cs, ch = st.cs, st.ch
            ends = [
                ((cs[k, c[0][0]], ch[k, c[0][0]]), (cs[k + 1, c[1][0]], ch[k + 1, c[1][0]]))
                for c in (col_l, col_i)
            ]
            x0 = lo - d_lo * (hi - lo) / (d_hi - d_lo)
            st.ho = {"lo": lo, "hi": hi, "d_lo": d_lo, "d_hi": d_hi, "x0": x0, "ends": ends}
            st.ho["delta"] = step / 8.0
            guess = _crossing(st, lo, hi, p1, step)
            if guess is None:
                _ask_iteration(st, x0, p1)
            else:
                st.ho["round"] = 0
                _ask_fit(st, guess, p1)
            return


def _ask_fit(st, x, p1) -> None:
    """Evaluations of a hand-over guess ``x``: both pairs at ``x`` (the extra positions) and a
    delta to either side, started from the contact points interpolated along the bracket."""
    ho = st.ho
    ho["mode"], ho["x"], st.v_star, st.ex = "fit", float(x), float(x), None
    f = (x - ho["lo"]) / (ho["hi"] - ho["lo"])
    for pair, shift in ((0, 0.0), (1, -p1)):
        (s0, h0), (s1, h1) = ho["ends"][pair]
        s, h = (1.0 - f) * s0 + f * s1, (1.0 - f) * h0 + f * h1
        for sign in (-1, 1):
            st.requests.append((x + shift + sign * ho["delta"], s, h, ("ho", pair, sign)))


def _ask_iteration(st, x, p1) -> None:
    """An evaluation of both pairs at ``x`` for the iteration on the bracket (started from the
    middle of each pair's contact points at the bracket's ends)."""
    ho = st.ho
    ho["mode"], ho["x"], st.v_star = "iterate", float(x), float(x)
    ho.setdefault("round", 0)
    for pair, shift in ((0, 0.0), (1, -p1)):
        (s0, h0), (s1, h1) = ho["ends"][pair]
        st.requests.append((x + shift, 0.5 * (s0 + s1), 0.5 * (h0 + h1), ("ho", pair, 0)))


def _crossing(st, lo, hi, p1, step) -> float | None:
    """Where the lag of the leaving pair G(x) meets the incoming pair's G(x - p1) in
    [lo, hi], both interpolated (cubic) through the four nearest samples of G; None when any
    of them is missing or not an interior contact (the lags are smooth only there)."""
    sample = st.interval_sample
    v = sample.phi_rad * st.field.sense
    mid = 0.5 * (lo + hi)
    fits = []
    for centre in (mid, mid - p1):
        near = np.argsort(np.abs(v - centre))[:4]
        z = (v[near] - centre) / step
        g = sample.minimum_rad[near]
        if np.abs(z).max() > 2.0 or not np.all(np.isfinite(g)) or sample.edge[near].any():
            return None
        fits.append(_newton_form(z.tolist(), g.tolist()))
    (za, ca), (zb, cb) = fits

    def difference(x: float) -> float:
        return _newton_value(za, ca, x) - _newton_value(zb, cb, x)

    half = 0.5 * (hi - lo) / step
    root = _illinois(difference, -half, half)
    return None if root is None else mid + step * root


def _newton_form(z: list, g: list) -> tuple[list, list]:
    """The polynomial through the points (z, g) by divided differences: ``(z, coefficients)``
    for :func:`_newton_value`."""
    c = list(g)
    for j in range(1, len(z)):
        for i in range(len(z) - 1, j - 1, -1):
            c[i] = (c[i] - c[i - 1]) / (z[i] - z[i - j])
    return z, c


def _newton_value(z: list, c: list, x: float) -> float:
    """The polynomial of :func:`_newton_form` at x (nested multiplication)."""
    value = c[-1]
    for i in range(len(c) - 2, -1, -1):
        value = value * (x - z[i]) + c[i]
    return value


def _illinois(func, a: float, b: float, tol: float = 1e-12) -> float | None:
    """A root of ``func`` in [a, b] by the Illinois method (None without a sign change)."""
    fa, fb = func(a), func(b)
    if fa == 0.0:
        return a
    if fb == 0.0:
        return b
    if fa * fb > 0.0:
        return None
    for _ in range(100):
        c = b - fb * (b - a) / (fb - fa)
        fc = func(c)
        if fc == 0.0 or abs(c - b) <= tol:
            return c
        if fc * fb < 0.0:
            a, fa = b, fb
        else:
            fa *= 0.5
        b, fb = c, fc
    return b


def _handover_step(st, p1) -> None:
    """Take in a hand-over's evaluations, if they are in: ask for the next ones, or settle
    ``v_star`` (and the lag there, ``g_hand``, when it is interpolated)."""
    ho = st.ho
    if ho is None or ho.get("done"):
        return
    if ho["mode"] == "fit":
        tags = [("ho", pair, sign) for pair in (0, 1) for sign in (-1, 1)]
        if st.ex is None or not all(tag in st.answers for tag in tags):
            return
        got = [st.answers.pop(tag) for tag in tags]
        gl = np.array([got[0][0], st.ex.minimum_rad[0], got[1][0]])
        gi = np.array([got[2][0], st.ex.minimum_rad[1], got[3][0]])
        interior = np.all(np.isfinite(gl)) and np.all(np.isfinite(gi))
        interior = interior and not (st.ex.edge[:2].any() or any(a[3] for a in got))
        interior = interior and bool(np.all(np.isfinite(st.ex.minimum_rad)))
        z = _parabola_root(gl - gi) if interior else math.inf
        x = ho["x"] + ho["delta"] * z
        # the root within a tenth of a delta of the guess: the extra positions (M among them)
        # stand; further off: the root is evaluated anew once
        if abs(z) <= 0.1 and ho["lo"] <= x <= ho["hi"]:
            ho["done"] = True
            st.v_star = float(x)
            st.g_hand = float(max(_parabola_at(gl, z), _parabola_at(gi, z)))
        elif abs(z) <= 2.0 and ho["round"] == 0:
            ho["round"] += 1
            _ask_fit(st, min(max(x, ho["lo"]), ho["hi"]), p1)
        else:  # not smooth there after all: the iteration on the bracket
            st.ex = None
            ho["round"] = 0
            _ask_iteration(st, ho["x0"], p1)
        return
    if not (("ho", 0, 0) in st.answers and ("ho", 1, 0) in st.answers):
        return
    d = float(st.answers.pop(("ho", 0, 0))[0] - st.answers.pop(("ho", 1, 0))[0])
    if not np.isfinite(d):
        ho["done"] = True
        return
    lo, hi, d_lo, d_hi = ho["lo"], ho["hi"], ho["d_lo"], ho["d_hi"]
    if ho["round"] == 0:
        x0 = ho["x"]
        ho["x0"], ho["d0"] = x0, d
        a, b, c = _parabola(lo - x0, hi - x0, d_lo, d, d_hi)
        roots = np.roots([a, b, c]) if abs(a) > 0.0 else np.array([-c / b])
        roots = np.real(roots[np.isreal(roots)]) + x0
        ho["bracket"] = (lo, x0) if d > 0.0 else (x0, hi)
        good = roots[(roots >= ho["bracket"][0]) & (roots <= ho["bracket"][1])]
        ho["round"] = 1
        _ask_iteration(st, float(good[0]) if good.size else x0, p1)
    else:
        x0, d0, x1 = ho["x0"], ho["d0"], ho["x"]
        if d != d0:  # one last secant step between the two best points
            x2 = x1 - d * (x1 - x0) / (d - d0)
            if ho["bracket"][0] <= x2 <= ho["bracket"][1]:
                st.v_star = float(x2)
        ho["done"] = True


def _parabola(xa: float, xb: float, ya: float, y0: float, yb: float):
    """``(a, b, c)`` of the parabola a x^2 + b x + c through (xa, ya), (0, y0), (xb, yb)."""
    sa, sb = (ya - y0) / xa, (yb - y0) / xb
    a = (sb - sa) / (xb - xa)
    return a, sa - a * xa, y0


def _parabola_root(d: NDArray) -> float:
    """The root nearest 0 of the parabola through (-1, d0), (0, d1), (1, d2) (inf if none)."""
    a = 0.5 * (d[0] + d[2]) - d[1]
    b = 0.5 * (d[2] - d[0])
    c = d[1]
    disc = b * b - 4.0 * a * c
    if disc < 0.0 or (a == 0.0 and b == 0.0):
        return math.inf
    q = -0.5 * (b + math.copysign(math.sqrt(disc), b))
    roots = [c / q] if q != 0.0 else []
    if a != 0.0:
        roots.append(q / a)
    return min(roots, key=abs, default=math.inf)


def _parabola_at(y: NDArray, z: float) -> float:
    """The parabola through (-1, y0), (0, y1), (1, y2) at z."""
    return float(y[1] + 0.5 * (y[2] - y[0]) * z + (0.5 * (y[0] + y[2]) - y[1]) * z * z)


def _assemble(st, name, ex, t, p1, frame, pairs, compound_um, separation):
    """One side's ToothContact from its samples and extra evaluations, but for its two widths:
    ``(lines, fields)`` with ``lines`` = ``(pattern, zone at M, M, path direction, minor axis)``
    (:func:`_contacts` measures every side's at once)."""
    field = st.field
    positions = len(t)
    rows = np.arange(positions)
    g, lag, carrying = st.g, st.lag, st.carrying
    g_hand = st.g_hand
    if g_hand is None:
        g_hand = float(max(ex.minimum_rad[0], ex.minimum_rad[1]))
    g_min = float(min(ex.minimum_rad[2], lag.min()))
    te = (g_min - lag) * ARCSEC
    pair_te = ((g_min - g) * ARCSEC).T
    peak_to_peak = (max(g_hand, float(lag.max())) - g_min) * ARCSEC

    # separations at the contact gear angle of each position (same lag for every pair)
    compound_mm = compound_um * 1e-3
    main = st.sample
    sep = _separation_mm(main, np.repeat(lag, pairs), separation, st.inv)
    sep = sep.reshape((positions, pairs) + field.pinion.shape)
    pattern = sep.min(axis=(0, 1)) * 1e3
    face = field.pinion.face_mm - frame.toe_mm
    profile = field.pinion.profile_mm - frame.root_mm
    path_s, path_h = _centroids(sep[rows, carrying], compound_mm, face, profile)

    # the mean point M, the path's direction there, and the path's ends (bias)
    ex_sep = _separation_mm(ex, ex.minimum_rad, separation)
    cs, ch = _centroids(ex_sep, compound_mm, face, profile)
    mean_point = (float(cs[3]), float(ch[3]))
    direction = np.array([cs[5] - cs[4], ch[5] - ch[4]])
    norm = float(np.hypot(*direction))
    direction = direction / norm if norm > 1e-9 else np.array([1.0, 0.0])
    # the pattern's width: the extent of the whole pattern across the path at M
    # and the contact ellipse's major axis: measured with every side's (:func:`_widths`)
    minor = _minor_axis(ex_sep[3], compound_mm, face, profile)
    lines = (pattern * 1e-3, ex_sep[3], mean_point, direction, minor)
    # bias: the contact line's extension along the face from the pair's entry into contact to
    # its exit (seed 003 section 6): the contact points at the ends of its contact interval
    ends = getattr(st, "ci_s", None)
    bias = float(ends[1] - ends[0]) if ends is not None else float(cs[0] - cs[1])
    start, end = st.interval
    centre = frame.centre_mm
    handovers = st.v_star + p1 * np.arange(-12, 13)
    handovers = handovers[(handovers >= t[0] - 1e-12) & (handovers <= t[-1] + 1e-12)]
    return lines, dict(
        side=name,
        phi1_deg=np.degrees(t),
        te_arcsec=te,
        pair_te_arcsec=pair_te,
        carrying=carrying,
        handover_phi1_deg=np.degrees(handovers),
        te_peak_to_peak_arcsec=float(peak_to_peak),
        path_face_mm=path_s,
        path_profile_mm=path_h,
        contact_face_mm=st.cs[rows, carrying] - frame.toe_mm,
        contact_profile_mm=st.ch[rows, carrying] - frame.root_mm,
        edge=st.edge_all[rows, carrying],
        separation_um=sep * 1e3,
        pattern_um=pattern,
        face_mm=face,
        profile_mm=profile,
        path_angle_deg=_gear_path_angle(field, ex, frame),
        bias_mm=bias,
        center_offset_mm=(mean_point[0] - centre[0], mean_point[1] - centre[1]),
        mean_point_mm=mean_point,
        contact_ratio=float((end - start) / p1),
        compound_um=float(compound_um),
        separation=separation,
    )


@dataclass(frozen=True, kw_only=True)
class Backlash:
    """Circumferential backlash along the mesh (pinion held, gear turned to the other flank).

    ``circumferential_um`` = rotational backlash times the gear's outer pitch radius; negative
    values are interference (``interference`` True)."""

    phi1_deg: NDArray
    rotational_arcsec: NDArray
    circumferential_um: NDArray
    radius_mm: float

    #: circumferential backlash below this (um) is interference, above it numerical zero
    INTERFERENCE_UM = -0.05

    @property
    def interference(self) -> bool:
        """True where the flanks overlap (backlash below ``INTERFERENCE_UM``)."""
        return bool(np.any(self.circumferential_um < self.INTERFERENCE_UM))

    def as_dict(self) -> dict:
        c = self.circumferential_um
        return {
            "phi1_deg": _list(self.phi1_deg),
            "circumferential_um": _list(c),
            "min_um": float(c.min()),
            "mean_um": float(c.mean()),
            "max_um": float(c.max()),
            "interference": self.interference,
            "radius_mm": float(self.radius_mm),
        }


def backlash(
    drive: ClearanceField,
    coast: ClearanceField,
    *,
    radius_mm: float,
    positions: int = 21,
    pairs: int = 3,
    cycles: float = 2.0,
) -> Backlash:
    """Backlash at the drive side's positions: the gear at its drive contact angle, turned
    forward until its other flanks touch the pinion's (``coast`` is the coast-side field with
    the drive side's phase)."""
    check_options(positions, pairs, cycles, 6.5, "normal")
    pairs += 2  # a pair more on each side: misalignment may move the mesh by a pitch
    curve = _PairCurve(drive)
    p1 = curve.pitch
    t = np.linspace(-0.5 * cycles * p1, 0.5 * cycles * p1, positions)
    offsets = np.arange(pairs) - (pairs - 1) // 2
    u = t[:, None] + (np.round(-t / p1)[:, None] + offsets[None, :]) * p1
    key = np.round(u.ravel() / p1 * 1e9).astype(np.int64)
    _, first, inv = np.unique(key, return_index=True, return_inverse=True)
    g = curve(u.ravel()[first])[inv].reshape(u.shape)  # each relative angle once
    lag = g.min(axis=1)
    if not np.all(np.isfinite(lag)):
        raise ContactError("backlash", rule="at some positions no pair touches on the drive side")
    gear_angle = -drive.gear_sense * lag
    phi = drive.sense * u
    c = coast.sample(phi.ravel(), np.repeat(gear_angle, pairs)).minimum_rad.reshape(u.shape)
    rotational = c.min(axis=1)
    if not np.all(np.isfinite(rotational)):
        raise ContactError(
            "backlash", rule="at some positions the other flanks do not face each other"
        )
    return Backlash(
        phi1_deg=np.degrees(t),
        rotational_arcsec=rotational * ARCSEC,
        circumferential_um=rotational * radius_mm * 1e3,
        radius_mm=float(radius_mm),
    )


@dataclass(frozen=True, kw_only=True)
class EaseOff:
    """Normal deviation of the pinion flank from the surface conjugate to the gear.

    ``ease_off_um`` ``(n_f, n_p)`` is zero at its least node; ``mask`` marks the nodes where it
    is defined (the conjugate contact inside both flanks); other nodes hold 0."""

    face_mm: NDArray
    profile_mm: NDArray
    ease_off_um: NDArray
    mask: NDArray
    side: str

    def as_dict(self) -> dict:
        e = self.ease_off_um[self.mask]
        return {
            "side": self.side,
            "max_um": float(e.max(initial=0.0)),
            "face_mm": _list(self.face_mm),
            "profile_mm": _list(self.profile_mm),
            "ease_off_um": self.ease_off_um.tolist(),
            "mask": self.mask.tolist(),
        }


def ease_off(
    field: ClearanceField,
    *,
    frame: ToothFrame,
    side: str = "drive",
    samples: int = 121,
    span_pitches: float = 4.0,
) -> EaseOff:
    """Ease-off: for each pinion node, the least normal clearance to the gear flank over the
    ideal (conjugate) motion; a conjugate node touches at some angle (zero). Each node's
    minimum over the angle samples is refined by the parabola through its neighbours."""
    p1 = field.pinion.pitch_rad
    v = np.linspace(-0.5 * span_pitches * p1, 0.5 * span_pitches * p1, samples)
    s = field.sample(field.sense * v, refine=False)
    d = s.clearance_rad.reshape(samples, -1)
    fac = s.normal_factor_mm.reshape(samples, -1)
    k = np.argmin(d, axis=0)
    cols = np.arange(d.shape[1])
    d0 = d[k, cols]
    ok = np.isfinite(d0) & (k > 0) & (k < samples - 1)
    km, kp = np.clip(k - 1, 0, samples - 1), np.clip(k + 1, 0, samples - 1)
    dm, dp = d[km, cols], d[kp, cols]
    ok &= np.isfinite(dm) & np.isfinite(dp)
    with np.errstate(invalid="ignore"):
        curv = np.where(ok, dm - 2.0 * d0 + dp, 1.0)
        slope = np.where(ok, 0.5 * (dp - dm), 0.0)
        step = np.where(curv > 0.0, np.clip(-slope / curv, -1.0, 1.0), 0.0)
        value = np.where(ok, d0 + slope * step + 0.5 * curv * step**2, 0.0)
    mask = ok.reshape(field.pinion.shape)
    if not mask.any():
        raise ContactError("ease_off", rule="no pinion node meets the gear flank")
    # the conjugate surface is defined up to a turn of the gear: take the turn that makes it
    # touch the pinion, then convert each node's angular clearance along its normal
    normal = (value - value[ok].min()) * fac[k, cols]
    e = np.where(ok, normal * 1e3, 0.0).reshape(field.pinion.shape)
    return EaseOff(
        face_mm=field.pinion.face_mm - frame.toe_mm,
        profile_mm=field.pinion.profile_mm - frame.root_mm,
        ease_off_um=e,
        mask=mask,
        side=side,
    )


@dataclass(frozen=True, kw_only=True)
class MeshedPair:
    """A design's generated flanks placed in the housing: the drive and coast clearance fields
    (the coast field takes the drive field's phase, so both face the same tooth space)."""

    drive: ClearanceField
    coast: ClearanceField
    frame: ToothFrame
    backlash_radius_mm: float


def mesh_pair(design, flanks, *, misalignment=None) -> MeshedPair:
    """Place a design's generated flanks in the housing: ``flanks`` is ``(pinion, gear)``, each
    ``{"convex": FlankMap, "concave": FlankMap}`` as a machine model generates them
    (:meth:`gearopt.machine.BaseMachineModel.generate_flanks`); ``misalignment`` defaults to the
    design's ``[misalignment]``."""
    pinion, gear = flanks
    placement = Placement(
        shaft_angle_deg=design.pair.shaft_angle_deg,
        misalignment=design.misalignment if misalignment is None else misalignment,
    )
    drive = ClearanceField(pinion["convex"], gear["concave"], placement=placement)
    coast = ClearanceField(
        pinion["concave"],
        gear["convex"],
        placement=placement,
        sense=-drive.sense,
        phase_rad=drive.phase_rad,
    )
    blank = design.blank
    return MeshedPair(
        drive=drive,
        coast=coast,
        frame=ToothFrame.from_blank(blank),
        backlash_radius_mm=blank.outer_pitch_radius_mm[1],
    )
