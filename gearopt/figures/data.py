"""The figures' data, computed on the analyses' public interfaces (no matplotlib here).

- :func:`te_curves`: every tooth pair's TE over its whole contact, the envelope, the solved
  hand-overs and the envelope's spectrum in orders of the tooth-mesh frequency;
- :func:`tooth_outline`: the blank's tooth on the true projection (toe, heel, root and face
  lines in the axial plane, tapered or uniform);
- :func:`member_patterns`: the contact pattern, the instantaneous contact zones along the path,
  the path, M and C on the pinion and on the gear (the gear's by mapping the pinion's points to
  the gear flank at the position where they touch).

Coordinates on the true projection of a member's tooth: ``x`` = cone distance from the toe
(mm, toe 0 -> heel), ``y`` = height h above the pitch cone (mm, root < 0 < top). The TE of a
tooth pair: the pair's own lag G(u) (:class:`gearopt.mesh.PairCurve`, the base pair at relative
rotation u; pair k is the base pair a pitch later, ``t = u - k p``) as TE = (g0 - G) in arcsec,
g0 the shift that makes the envelope (the least lag over the pairs) equal the reported TE at the
analysed positions.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from gearopt.contact import ClearanceField
from gearopt.mesh import ARCSEC, PairCurve
from gearopt.mesh.pattern import centroids

__all__ = [
    "MemberPattern",
    "TeCurves",
    "ToothOutline",
    "member_patterns",
    "te_curves",
    "tooth_outline",
]

#: relative-rotation samples per angular pitch of the figures' motion (the pair curves, the
#: pattern and the spectrum)
PER_PITCH = 48
#: pitches either side of the mesh centre searched for a pair's contact
REACH_PITCHES = 3
#: orders of the tooth-mesh frequency in the TE spectrum
ORDERS = 8
#: envelope samples over the pitch of the spectrum
SPECTRUM_SAMPLES = 256
#: two pairs' lags at a solved hand-over differ by at most this where the curves meet (a
#: bracket closing on a step of a pair's lag leaves more: arcsec)
MEET_ARCSEC = 1e-6


@dataclass(frozen=True, kw_only=True)
class TeCurves:
    """One side's TE figure data (arcsec of gear rotation, pinion degrees in the direction of
    motion).

    Attributes
    ----------
    pair_t_deg
        ``(pairs, m)`` each drawn pair's positions over its whole contact (NaN where out of
        contact).
    pair_te_arcsec
        ``(pairs, m)`` its TE.
    pair_carrying
        ``(pairs, m)`` True where the pair carries (its TE is the envelope).
    t_deg, envelope_arcsec
        The envelope (the carrying pair's TE) over the analysed range and the base pair's
        whole contact.
    analysed_deg
        The analysed range ``(first, last)`` position.
    handover_deg, handover_arcsec
        The hand-overs (where two pairs' TE curves cross, both carrying: bisected on the
        field here) and the TE there.
    reported_handover_deg, reported_peak_to_peak_arcsec
        The TCA's (the report's) hand-overs and peak-to-peak, for comparison.
    peak_to_peak_arcsec
        The envelope's max - min (hand-overs included).
    contact_ratio
        As reported.
    orders, amplitude_arcsec
        The envelope's harmonics: amplitude of order k of the tooth-mesh frequency.
    """

    pair_t_deg: NDArray
    pair_te_arcsec: NDArray
    pair_carrying: NDArray
    t_deg: NDArray
    envelope_arcsec: NDArray
    analysed_deg: tuple[float, float]
    handover_deg: NDArray
    handover_arcsec: NDArray
    reported_handover_deg: NDArray
    reported_peak_to_peak_arcsec: float
    peak_to_peak_arcsec: float
    contact_ratio: float
    orders: NDArray
    amplitude_arcsec: NDArray


@dataclass(frozen=True, kw_only=True)
class ToothOutline:
    """A member's tooth on the true projection: corners toe-root, heel-root, heel-top, toe-top
    (``(4, 2)``, ``x`` from the toe, ``y`` height above the pitch cone) and the face width."""

    corners_mm: NDArray
    face_width_mm: float


@dataclass(frozen=True, kw_only=True)
class MemberPattern:
    """One side's contact pattern on one member's flank (true projection).

    Attributes
    ----------
    member
        ``"pinion"`` or ``"gear"``.
    flank
        ``"convex"`` or ``"concave"``.
    outline
        The tooth (:class:`ToothOutline`).
    grid_x_mm, grid_y_mm, generated
        ``(n_f, n_p)`` the flank's nodes and where they are generated.
    pattern
        The pattern's boundary rings (each ``(k, 2)``, closed; a hole's runs the other way).
    zones
        The instantaneous contact zones at evenly spaced positions along the path (rings).
    path_mm, path_carrying
        ``(m, 2)`` the path of one tooth over its whole contact (NaN where it has no zone) and
        where that tooth carries.
    mean_point_mm, centre_mm
        M (the reported mean contact point) and C (the flank centre).
    """

    member: str
    flank: str
    outline: ToothOutline
    grid_x_mm: NDArray
    grid_y_mm: NDArray
    generated: NDArray
    pattern: list
    zones: list
    path_mm: NDArray
    path_carrying: NDArray
    mean_point_mm: NDArray
    centre_mm: NDArray


def tooth_outline(blank, member: str) -> ToothOutline:
    """The tooth of ``member`` (``"pinion"`` or ``"gear"``) of a :class:`gearopt.blank.Blank`
    on the true projection: toe and heel at the inner and outer cone distances, the root line
    at minus the dedendum and the face line at the addendum (each linear in the cone distance
    on a tapered tooth)."""
    k = 0 if member == "pinion" else 1
    inner, outer = blank.inner_cone_distance_mm, blank.outer_cone_distance_mm
    width = outer - inner
    corners = np.array(
        [
            [0.0, -blank.dedendum_at_mm(k, inner)],
            [width, -blank.dedendum_at_mm(k, outer)],
            [width, blank.addendum_at_mm(k, outer)],
            [0.0, blank.addendum_at_mm(k, inner)],
        ]
    )
    return ToothOutline(corners_mm=corners, face_width_mm=float(width))


class _Motion:
    """The base pair's field over its whole contact, sampled PER_PITCH times a pitch."""

    def __init__(self, field: ClearanceField, separation: str):
        self.field = field
        self.curve = PairCurve(field)
        p = self.curve.pitch
        self.pitch = p
        n = REACH_PITCHES * PER_PITCH
        self.u = np.arange(-n, n + 1) * (p / PER_PITCH)
        self.sample = self.curve.sample(self.u)
        g = self.sample.minimum_rad
        self.g = g
        # the envelope at u: the least lag over the pairs k pitches on (all on the grid)
        env = np.full_like(g, np.inf)
        for k in range(-2 * REACH_PITCHES, 2 * REACH_PITCHES + 1):
            shifted = np.full_like(g, np.inf)
            lo, hi = max(0, -k * PER_PITCH), min(len(g), len(g) - k * PER_PITCH)
            shifted[lo:hi] = g[lo + k * PER_PITCH : hi + k * PER_PITCH]
            env = np.minimum(env, shifted)
        self.envelope = env
        self.carrying = np.isfinite(g) & (g <= env + 1e-12)
        factor = self.sample.normal_factor_mm if separation == "normal" else self.sample.radius_mm
        with np.errstate(invalid="ignore"):
            sep = (self.sample.clearance_rad - env[:, None, None]) * factor
        self.sep_mm = np.where(np.isfinite(sep), sep, np.inf)

    def handovers(self, iterations: int = 40) -> tuple[NDArray, NDArray]:
        """The hand-overs of the base pair to the next: ``(u, lag)`` where G(u) = G(u + p)
        and both carry, bracketed on the samples and bisected on the field."""
        n = PER_PITCH
        g, nxt = self.g[:-n], self.g[n:]
        with np.errstate(invalid="ignore"):
            d = nxt - g
        both = np.isfinite(d[:-1]) & np.isfinite(d[1:])
        low = np.minimum(g, nxt)
        carrying = (low[:-1] <= self.envelope[:-n][:-1] + 1e-12) | (
            low[1:] <= self.envelope[:-n][1:] + 1e-12
        )
        k = np.flatnonzero(both & carrying & (np.sign(d[:-1]) * np.sign(d[1:]) < 0))
        if not k.size:
            return np.zeros(0), np.zeros(0)
        a, b = self.u[k], self.u[k + 1]
        da = d[k]
        for _ in range(iterations):
            m = 0.5 * (a + b)
            dm = self.curve(m + self.pitch) - self.curve(m)
            left = np.sign(dm) == np.sign(da)
            a, da = np.where(left, m, a), np.where(left, dm, da)
            b = np.where(left, b, m)
        u = 0.5 * (a + b)
        return u, np.maximum(self.curve(u), self.curve(u + self.pitch))

    def envelope_at(self, t: NDArray) -> NDArray:
        """The least lag over the pairs at relative rotations ``t`` (evaluated anew)."""
        t = np.asarray(t, float)
        ks = np.arange(-2 * REACH_PITCHES, 2 * REACH_PITCHES + 1)
        g = self.curve((t[:, None] + ks[None, :] * self.pitch).ravel()).reshape(len(t), -1)
        return g.min(axis=1)


def te_curves(field: ClearanceField, report: dict, *, separation: str = "normal") -> TeCurves:
    """One side's TE figure data (:class:`TeCurves`) from its clearance field and its
    reported TCA (the ``tca`` or ``tca_coast`` object of ``gearopt analyze --json``)."""
    motion = _Motion(field, separation)
    p = motion.pitch
    t_rep = np.radians(np.asarray(report["phi1_deg"], float))
    te_rep = np.asarray(report["te_arcsec"], float)
    g0 = float(np.median(motion.envelope_at(t_rep) + te_rep / ARCSEC))
    # the pairs whose contact overlaps the analysed range: pair k at t = u - k p
    inside = np.isfinite(motion.g)
    u_in = motion.u[inside]
    # the range drawn: the analysed positions and the whole contact of the base pair
    lo, hi = min(t_rep[0], u_in.min()), max(t_rep[-1], u_in.max())
    ks = [
        k
        for k in range(-2 * REACH_PITCHES, 2 * REACH_PITCHES + 1)
        if u_in.max() - k * p > lo and u_in.min() - k * p < hi
    ]
    te_pair = np.where(inside, (g0 - motion.g) * ARCSEC, np.nan)
    pair_t = np.array([np.where(inside, motion.u - k * p, np.nan) for k in ks])
    pair_te = np.tile(te_pair, (len(ks), 1))
    pair_carrying = np.tile(motion.carrying, (len(ks), 1))
    # the hand-overs solved on the field (they recur every pitch: those over the range drawn)
    u_hand, g_hand = motion.handovers()
    reported = np.radians(np.asarray(report["handover_phi1_deg"], float))
    if len(u_hand) > 1 and reported.size:
        # several crossings a pitch: a flat TE (line contact), where the curves cross in
        # their noise (and a bracket may close on a step of a pair's lag, where they do not
        # meet); the one nearest the TCA's hand-over among those where they meet
        gap = np.abs(motion.curve(u_hand) - motion.curve(u_hand + p)) * ARCSEC
        meet = gap <= MEET_ARCSEC
        if meet.any():
            u_hand, g_hand = u_hand[meet], g_hand[meet]
        off = (u_hand - reported[0] + 0.5 * p) % p - 0.5 * p
        pick = int(np.argmin(np.abs(off)))
        u_hand, g_hand = u_hand[pick : pick + 1], g_hand[pick : pick + 1]
    shifts = np.arange(-4 * REACH_PITCHES, 4 * REACH_PITCHES + 1) * p
    hand = (u_hand[:, None] + shifts[None, :]).ravel()
    hand_g = np.repeat(g_hand, len(shifts))
    keep = (hand >= lo) & (hand <= hi)
    hand, hand_g = hand[keep], hand_g[keep]
    order = np.argsort(hand)
    hand, hand_te = hand[order], (g0 - hand_g[order]) * ARCSEC
    t_fine = np.linspace(lo, hi, int(round((hi - lo) / p * PER_PITCH)) + 1)
    order = np.argsort(np.concatenate([t_fine, hand]))
    t_all = np.concatenate([t_fine, hand])[order]
    env = np.concatenate([(g0 - motion.envelope_at(t_fine)) * ARCSEC, hand_te])[order]
    # the spectrum: one pitch of the envelope (the TE is periodic in it), SPECTRUM_SAMPLES
    # samples (its kinks at the hand-overs alias little into the first orders)
    period = motion.envelope_at(t_rep[0] + np.arange(SPECTRUM_SAMPLES) * (p / SPECTRUM_SAMPLES))
    amp = np.abs(np.fft.rfft((g0 - period) * ARCSEC)) * 2.0 / SPECTRUM_SAMPLES
    finite = np.isfinite(env)
    return TeCurves(
        pair_t_deg=np.degrees(pair_t),
        pair_te_arcsec=pair_te,
        pair_carrying=pair_carrying,
        t_deg=np.degrees(t_all),
        envelope_arcsec=env,
        analysed_deg=(float(np.degrees(t_rep[0])), float(np.degrees(t_rep[-1]))),
        handover_deg=np.degrees(hand),
        handover_arcsec=hand_te,
        reported_handover_deg=np.asarray(report["handover_phi1_deg"], float),
        reported_peak_to_peak_arcsec=float(report["te_peak_to_peak_arcsec"]),
        peak_to_peak_arcsec=float(np.ptp(env[finite])) if finite.any() else float("nan"),
        contact_ratio=float(report["contact_ratio"]),
        orders=np.arange(1, ORDERS + 1),
        amplitude_arcsec=amp[1 : ORDERS + 1],
    )


def _contours(values: NDArray, x: NDArray, y: NDArray, level: float) -> list[NDArray]:
    """The closed rings bounding the region where ``values`` (on the grid ``x``, ``y``: its
    nodes' coordinates) is below ``level``, the flanks' boundary included where the region
    reaches it: the filled contours of the linear interpolant (contourpy, matplotlib's); a
    hole's ring runs the other way."""
    import contourpy

    z = np.where(np.isfinite(values), values, 1e9)
    generator = contourpy.contour_generator(x, y, z, fill_type=contourpy.FillType.OuterOffset)
    rings = []
    for points, offsets in zip(*generator.filled(-1e30, level), strict=True):
        rings += [points[a:b] for a, b in zip(offsets[:-1], offsets[1:], strict=True)]
    # islands of a node or two where the separation grazes the level: the linear
    # interpolant's noise, not a zone
    cell = np.ptp(x) / (x.shape[0] - 1) * np.ptp(y) / (y.shape[1] - 1)
    return [ring for ring in rings if len(ring) > 3 and _area(ring) > 0.5 * cell]


def _area(line: NDArray) -> float:
    """The area a closed line encloses (shoelace)."""
    x, y = line[:, 0], line[:, 1]
    return 0.5 * abs(float(np.dot(x, np.roll(y, 1)) - np.dot(y, np.roll(x, 1))))


def _true_projection(fm, s, t):
    """Grid coordinates (s, t) of the flank ``fm`` to (s, h): h its height at (s, t)."""
    return np.asarray(s, float), fm.height_at(np.asarray(s, float), np.asarray(t, float))


def member_patterns(
    field: ClearanceField,
    report: dict,
    blank,
    *,
    flank_names=("convex", "concave"),
    zones: int = 9,
) -> tuple[MemberPattern, MemberPattern]:
    """One side's contact pattern on the pinion and on the gear (:class:`MemberPattern`).

    The pattern: the pinion nodes whose separation from the mating flank (at the carrying
    pair's contact gear angle) falls below the marking compound at some position of one tooth's
    whole contact; the zones: the same at ``zones`` positions evenly spaced over the positions
    where the tooth has a zone. The gear's: the pinion's boundaries, zones and path mapped to
    the gear flank at the position where they touch (each pinion point at the position of its
    least separation).

    Parameters
    ----------
    field
        The side's clearance field.
    report
        The side's reported TCA (``tca`` or ``tca_coast``): its ``pattern`` object gives the
        compound, the separation kind and M.
    blank
        The pair's :class:`gearopt.blank.Blank`.
    flank_names
        The pinion's and the gear's flank on this side.
    zones
        How many instantaneous zones to draw.
    """
    pat = report["pattern"]
    compound_mm = float(pat["compound_um"]) * 1e-3
    motion = _Motion(field, pat["separation"])
    pinion, gear = field.pinion, field.gear
    inner = blank.inner_cone_distance_mm
    s_nodes, t_nodes = pinion.face_mm, pinion.profile_mm
    sep = motion.sep_mm
    has_zone = (sep.reshape(len(sep), -1) < compound_mm).any(axis=1)
    rows = np.flatnonzero(has_zone)
    least = sep.min(axis=0)
    when = motion.u[np.argmin(sep, axis=0)]  # (n_f, n_p) the position of least separation

    def pinion_xy(s, t):
        x, h = _true_projection(pinion, s, t)
        return np.stack([x - inner, h], -1)

    def gear_xy(s, t, u):
        points = pinion.point_at(s, t)
        phi = field.sense * np.asarray(u, float)
        got = field.clearance_of_rows(points[:, None, :], np.array([1.0, 0.0, 0.0]), phi)
        sg, tg = got.gear_face_mm[:, 0], got.gear_profile_mm[:, 0]
        return np.stack([sg - inner, gear.height_at(sg, tg)], -1)

    def when_at(s, t):
        """The position of least separation at grid points (bilinear in the nodes')."""
        i = np.clip(np.interp(s, s_nodes, np.arange(len(s_nodes))), 0, len(s_nodes) - 1.001)
        j = np.clip(np.interp(t, t_nodes, np.arange(len(t_nodes))), 0, len(t_nodes) - 1.001)
        i0, j0 = i.astype(int), j.astype(int)
        a, b = i - i0, j - j0
        w = when
        return (
            w[i0, j0] * (1 - a) * (1 - b)
            + w[i0 + 1, j0] * a * (1 - b)
            + w[i0, j0 + 1] * (1 - a) * b
            + w[i0 + 1, j0 + 1] * a * b
        )

    s_grid, t_grid = np.meshgrid(s_nodes, t_nodes, indexing="ij")
    pattern_lines = _contours(least, s_grid, t_grid, compound_mm)
    pick = (
        rows[np.unique(np.round(np.linspace(0, len(rows) - 1, zones)).astype(int))]
        if len(rows)
        else rows
    )
    zone_lines = [
        (motion.u[r], line) for r in pick for line in _contours(sep[r], s_grid, t_grid, compound_mm)
    ]
    cs, ch = centroids(sep, compound_mm, s_nodes, t_nodes)
    cs = np.where(has_zone, cs, np.nan)
    ch = np.where(has_zone, ch, np.nan)
    frame_root = -blank.mean_dedendum_mm[0]
    toe = blank.mean_cone_distance_mm - 0.5 * blank.face_width_mm
    m_s = toe + pat["mean_point_mm"][0]
    m_t = frame_root + pat["mean_point_mm"][1]
    a1, a2 = blank.mean_addendum_mm
    c_s, c_t = blank.mean_cone_distance_mm, 0.5 * (a1 - a2)
    # the position at M: where the tooth's path passes nearest M
    ok = np.flatnonzero(has_zone)
    u_m = motion.u[ok[np.argmin(np.hypot(cs[ok] - m_s, ch[ok] - m_t))]] if ok.size else 0.0

    def pinion_member():
        gx, gy = pinion_xy(s_grid, t_grid).transpose(2, 0, 1)
        return MemberPattern(
            member="pinion",
            flank=flank_names[0],
            outline=tooth_outline(blank, "pinion"),
            grid_x_mm=gx,
            grid_y_mm=gy,
            generated=np.asarray(pinion.mask, bool),
            pattern=[pinion_xy(*line.T) for line in pattern_lines],
            zones=[pinion_xy(*line.T) for _, line in zone_lines],
            path_mm=np.where(
                has_zone[:, None], pinion_xy(np.nan_to_num(cs), np.nan_to_num(ch)), np.nan
            ),
            path_carrying=motion.carrying.copy(),
            mean_point_mm=pinion_xy(np.array(m_s), np.array(m_t)),
            centre_mm=pinion_xy(np.array(c_s), np.array(c_t)),
        )

    def gear_member():
        sg, tg = np.meshgrid(gear.face_mm, gear.profile_mm, indexing="ij")
        path = np.full((len(motion.u), 2), np.nan)
        if ok.size:
            path[ok] = gear_xy(cs[ok], ch[ok], motion.u[ok])
        return MemberPattern(
            member="gear",
            flank=flank_names[1],
            outline=tooth_outline(blank, "gear"),
            grid_x_mm=sg - inner,
            grid_y_mm=gear.height_at(sg, tg),
            generated=np.asarray(gear.mask, bool),
            pattern=[
                gear_xy(line[:, 0], line[:, 1], when_at(line[:, 0], line[:, 1]))
                for line in pattern_lines
            ],
            zones=[
                gear_xy(line[:, 0], line[:, 1], np.full(len(line), u)) for u, line in zone_lines
            ],
            path_mm=path,
            path_carrying=motion.carrying.copy(),
            mean_point_mm=gear_xy(np.array([m_s]), np.array([m_t]), np.array([u_m]))[0],
            centre_mm=np.array(
                [
                    blank.mean_cone_distance_mm - inner,
                    0.5 * (blank.mean_addendum_mm[1] - blank.mean_addendum_mm[0]),
                ]
            ),
        )

    return pinion_member(), gear_member()
