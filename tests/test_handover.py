"""The TCA's hand-over where the pairs touch at an edge of a flank, and its peak-to-peak, against
the pairs' lag curves on the clearance field, found independently here.

The reference samples the base pair's lag G(u) (:class:`gearopt.mesh.PairCurve`: the node field
with its least nodes refined, as the TCA samples positions) over four pitches, brackets where
the next pair's lag G(u - p) crosses it with both the least of all pairs (both carry), bisects
that crossing to 1e-13 rad and takes the greater of the lower lag at the bracket's ends (the
common lag, or where one lag steps across the other, the envelope's value there). The least lag
of the envelope (the least over the pairs) comes from 1536 samples a pitch refined by a bounded
scalar search around the least. The peak-to-peak is the greater of the crossing's lag and the
envelope at the TCA's analysed positions (the TE it reports there) minus the least lag.

Tolerance 0.005 arcsec: the TCA's iteration stops on a bracket of 1e-9 rad and the lag's slope
is below 0.1 rad/rad (2e-5 arcsec of lag); its least lag is the vertex of a parabola through
evaluations an eighth of a position step apart (measured within 2e-5 arcsec of the reference on
the 14/39 pair). The former iteration (secant, parabola, secant on refinements started between
the bracket's contact points) missed by 0.75 arcsec on the 14/39 drive side (9.094 against
8.341) and 0.39 on its coast side (7.872 against 7.483), by 0.55 and 0.78 on section 5.3 under
the 5.4 errors (14.880 against 14.328, 10.737 against 9.962).

Not covered: on the 14/39 coast side the carrying pair's lag bends up between the hand-overs
(its contact moving from one edge to another) to 8.08 arcsec above the least, a crest that
neither the TCA's positions nor the figures' 48 samples a pitch resolve (docs/figures.md).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import minimize_scalar

import gearopt
from gearopt.analysis import AnalysisOptions, contact_sides, meshed_pair
from gearopt.design import Misalignment
from gearopt.mesh import ARCSEC, PairCurve

from .conftest import STUDIES

TOLERANCE_ARCSEC = 0.005
PER_PITCH = 96
DENSE = 1536  # the envelope's samples over a pitch
#: section 5.3 under seed 001 section 5.4's errors: drive in edge contact (README)
SECTION_5_4 = Misalignment(
    offset_mm=0.221, pinion_axial_mm=-0.005, gear_axial_mm=0.188, shaft_angle_deg=-0.062
)


def envelope(curve: PairCurve, t) -> np.ndarray:
    """The least lag over the pairs within three pitches at relative rotations ``t`` (the
    clearance of a pair further off, out of mesh, means nothing)."""
    p = curve.pitch
    t = (np.atleast_1d(np.asarray(t, float)) + 0.5 * p) % p - 0.5 * p  # it repeats every pitch
    ks = np.arange(-3, 4) * p
    return curve((t[:, None] + ks[None, :]).ravel()).reshape(len(t), -1).min(axis=1)


def reference_peak_to_peak(curve: PairCurve, positions) -> tuple[float, list[float]]:
    """The reference peak-to-peak (arcsec) with the TE at ``positions`` (relative rotations)
    and the crossings (deg, the leaving pair's relative rotation) over four pitches."""
    p = curve.pitch
    u = np.arange(-2 * PER_PITCH, 2 * PER_PITCH + 1) * (p / PER_PITCH)
    g, g_next = curve(u), curve(u - p)
    env = envelope(curve, u)
    with np.errstate(invalid="ignore"):
        d = g - g_next
        carry = (np.minimum(g, g_next) <= env + 1e-15) & np.isfinite(d)
    found = np.flatnonzero(carry[:-1] & carry[1:] & (np.sign(d[:-1]) * np.sign(d[1:]) < 0))
    lags, where = [], []
    for k in found:
        a, b, d_a = u[k], u[k + 1], d[k]
        while b - a > 1e-13:
            m = 0.5 * (a + b)
            d_m = float(curve(np.array([m]))[0] - curve(np.array([m - p]))[0])
            if np.sign(d_m) == np.sign(d_a):
                a, d_a = m, d_m
            else:
                b = m
        # the lower of the two lags either side (where one steps across the other, the
        # greater of the two: the TE's trough)
        ends = np.array([a, b])
        low = np.minimum(curve(ends), curve(ends - p))
        if np.all(low <= envelope(curve, ends) + 1e-12):  # still the least pairs there
            lags.append(float(low.max()))
            where.append(math.degrees(0.5 * (a + b)))
    assert lags, "no hand-over on the curves"
    # the envelope's least over one pitch, densely, refined around its least sample
    t = np.linspace(-0.5 * p, 0.5 * p, DENSE + 1)
    env = envelope(curve, t)
    k = int(np.argmin(env))
    best = minimize_scalar(
        lambda x: float(envelope(curve, x)[0]),
        bounds=(t[max(k - 1, 0)], t[min(k + 1, len(t) - 1)]),
        method="bounded",
        options={"xatol": 1e-10},
    )
    least = min(float(best.fun), float(env.min()))
    at_positions = float(envelope(curve, positions).max())
    return (max(max(lags), at_positions) - least) * ARCSEC, where


def analysed(path, misalignment=None):
    design = gearopt.load_design(path)
    opts = AnalysisOptions(misalignment=misalignment)
    pair = meshed_pair(design, opts)
    return pair, contact_sides(pair, opts)


@pytest.fixture(scope="module")
def face_milling_14x39():
    return analysed(STUDIES / "iso23509" / "face_milling_14x39.toml")


@pytest.fixture(scope="module")
def section53_misaligned():
    return analysed(STUDIES / "seed001_section5_3.toml", SECTION_5_4)


@pytest.mark.parametrize("side", ["drive", "coast"])
def test_14x39_peak_to_peak_is_the_pair_curves_crossing(face_milling_14x39, side):
    pair, sides = face_milling_14x39
    tca = sides[side]
    curve = PairCurve(getattr(pair, side))
    reference, where = reference_peak_to_peak(curve, np.radians(tca.phi1_deg))
    # the drive side hands over in edge contact: one of the two pairs touches at an edge
    # there; the coast side inside the flanks, down to the pinion's generated boundary (while
    # the refinement stayed two cells above the lowest generated nodes, that margin stopped it
    # at an edge: 7.483 arcsec at -13.664 deg against 6.176 at -14.521 deg at 81 x 161, now
    # both; gearopt.contact.boundary)
    hand = math.radians(where[0])
    at = curve.sample(np.array([hand - 1e-6, hand - curve.pitch + 1e-6]))
    assert at.edge.any() == (side == "drive")
    assert tca.te_peak_to_peak_arcsec == pytest.approx(reference, abs=TOLERANCE_ARCSEC)
    # the TCA's hand-over is that crossing (to a pitch)
    pitch_deg = math.degrees(curve.pitch)
    off = (tca.handover_phi1_deg[0] - where[0] + 0.5 * pitch_deg) % pitch_deg - 0.5 * pitch_deg
    assert abs(off) < 1e-5


@pytest.mark.parametrize("side", ["drive", "coast"])
def test_misaligned_section53_peak_to_peak_is_the_pair_curves_crossing(section53_misaligned, side):
    # the drive side touches at an edge while it carries; at the coast side's hand-over the
    # leaving pair's lag steps up across the incoming one's (its least clearance jumps)
    pair, sides = section53_misaligned
    tca = sides[side]
    assert tca.edge_contact
    curve = PairCurve(getattr(pair, side))
    reference, _ = reference_peak_to_peak(curve, np.radians(tca.phi1_deg))
    assert tca.te_peak_to_peak_arcsec == pytest.approx(reference, abs=TOLERANCE_ARCSEC)
