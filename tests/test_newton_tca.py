"""Newton TCA (Litvin's equations of continuous tangency) against the contact engine.

The crowned pair of seed 001 section 5.3 has a regular point contact, where Newton's five
equations are well posed: its solutions must agree with the engine's refined clearance minimum,
satisfy the tangency on the output and lie on both flanks.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from numpy.testing import assert_allclose

import gearopt
from gearopt.analysis import generated_flanks
from gearopt.flank import FlankGrid
from gearopt.flank_jet import FlankJet
from gearopt.mesh import PairCurve, mesh_pair
from gearopt.newton_tca import newton_tca, tangency_equations

STUDIES = Path(__file__).resolve().parents[1] / "studies"
ARCSEC_RAD = math.pi / 648000.0
U_RAD = np.linspace(-0.5, 0.5, 11) * (2.0 * math.pi / 16)
SIDES = ("drive", "coast")


@pytest.fixture(scope="module")
def pair():
    design = gearopt.load_design(STUDIES / "seed001_section5_3.toml")
    return mesh_pair(design, generated_flanks(design, FlankGrid(n_face=25, n_profile=21)))


@pytest.fixture(scope="module")
def solved(pair):
    """``side -> (Newton's solutions, the engine's samples)`` at U_RAD."""
    out = {}
    for side in SIDES:
        field = getattr(pair, side)
        out[side] = (newton_tca(field, U_RAD), PairCurve(field).sample(U_RAD))
    return out


def _in_cell(values, grid, fraction):
    """Move each value to ``fraction`` of the grid cell it lies in (away from cell borders,
    where the interpolant's second derivatives jump)."""
    step = grid[1] - grid[0]
    i = np.clip(np.floor((values - grid[0]) / step), 0, len(grid) - 2)
    return grid[0] + (i + fraction) * step


def test_local_interpolant_jet_is_the_flank_interpolant(pair):
    rng = np.random.default_rng(3)
    for fm in (pair.drive.pinion, pair.drive.gear, pair.coast.pinion, pair.coast.gear):
        s = rng.uniform(fm.face_mm[0] - 1.0, fm.face_mm[-1] + 1.0, 40)
        h = rng.uniform(fm.profile_mm[0] - 0.3, fm.profile_mm[-1] + 0.3, 40)
        s[:3], h[:3] = fm.face_mm[[0, 5, -1]], fm.profile_mm[[0, 7, -1]]  # nodes and corners
        theta, inside = fm.polar_angle_local(s, h, with_inside=True)
        jet = FlankJet(fm)
        got = [jet.polar(a, b) for a, b in zip(s, h, strict=True)]
        assert_allclose([g[0] for g in got], theta, rtol=0.0, atol=1e-14)
        assert [g[-1] for g in got] == list(inside)


@pytest.mark.parametrize("side", SIDES)
def test_analytic_jacobian_matches_finite_differences(pair, solved, side):
    field = getattr(pair, side)
    newton, _ = solved[side]
    k = 7
    assert newton.converged[k]
    u = U_RAD[k]
    # near the contact but off the solution, so that every term of the Jacobian counts
    x = newton.unknowns(k)
    x[0] = _in_cell(x[0], field.pinion.face_mm, 0.37)
    x[1] = _in_cell(x[1], field.pinion.profile_mm, 0.61)
    x[2] = _in_cell(x[2], field.gear.face_mm, 0.58)
    x[3] = _in_cell(x[3], field.gear.profile_mm, 0.29)
    x[4] += 1.0 * ARCSEC_RAD
    F, J = tangency_equations(field, u, x)
    assert np.all(np.isfinite(F)) and np.abs(F).max() > 1e-3
    steps = np.array([1e-5, 1e-5, 1e-5, 1e-5, 1e-8])
    fd = np.empty((5, 5))
    for m, step in enumerate(steps):
        e = np.zeros(5)
        e[m] = step
        fd[:, m] = (
            tangency_equations(field, u, x + e)[0] - tangency_equations(field, u, x - e)[0]
        ) / (2.0 * step)
    # relative 1e-6 per entry; an entry that vanishes (the lag turns the gear point about z_g,
    # so its z does not change) within 1e-10 of its row's largest
    floor = 1e-10 * np.abs(J).max(axis=1, keepdims=True)
    assert np.all(np.abs(J - fd) <= 1e-6 * np.abs(J) + floor), np.abs(J - fd) / np.abs(J)


@pytest.mark.parametrize("side", SIDES)
def test_newton_agrees_with_the_engine(solved, side):
    newton, engine = solved[side]
    compare = newton.converged & ~engine.edge
    assert compare.sum() >= 9  # a regular point contact: Newton converges almost everywhere
    lag = (newton.lag_rad - engine.minimum_rad)[compare] / ARCSEC_RAD
    point = np.hypot(
        newton.pinion_face_mm - engine.contact_face_mm,
        newton.pinion_profile_mm - engine.contact_profile_mm,
    )[compare]
    assert np.abs(lag).max() <= 0.05
    assert point.max() <= 0.2
    # both minimise the same interpolated clearance; the engine can never find less than the
    # tangency (up to rounding)
    assert lag.max() <= 1e-6
    # a crowned pair's TE is a parabola opening downward (Litvin's predesigned function)
    ok = newton.converged
    te = newton.te_arcsec[ok]
    coef = np.polyfit(U_RAD[ok], te, 2)
    assert coef[0] < 0.0
    assert np.abs(np.polyval(coef, U_RAD[ok]) - te).max() <= 0.1
    assert np.ptp(te) > 1.0


@pytest.mark.parametrize("side", SIDES)
def test_solutions_are_tangent_on_both_flanks(pair, solved, side):
    field = getattr(pair, side)
    newton, _ = solved[side]
    ok = newton.converged
    assert ok.sum() >= 9
    for k in np.flatnonzero(ok):
        F, _ = tangency_equations(field, U_RAD[k], newton.unknowns(k))
        assert np.abs(F).max() <= 1e-9
    s1, h1 = newton.pinion_face_mm[ok], newton.pinion_profile_mm[ok]
    s2, h2 = newton.gear_face_mm[ok], newton.gear_profile_mm[ok]
    assert field.pinion.inside(s1, h1).all()
    assert field.gear.inside(s2, h2).all()
    # cross-check through the engine's own clearance: at the pinion contact point the angular
    # clearance equals the lag, and it is stationary there (tangency)
    phi = field.sense * U_RAD[ok]
    zero = np.zeros_like(phi)
    delta, _ = field.clearance_at_grid(s1, h1, phi, zero)
    assert_allclose(delta, newton.lag_rad[ok], rtol=0.0, atol=1e-6 * ARCSEC_RAD)
    e = 1e-3  # mm
    d_s = (
        field.clearance_at_grid(s1 + e, h1, phi, zero)[0]
        - field.clearance_at_grid(s1 - e, h1, phi, zero)[0]
    ) / (2 * e)
    d_h = (
        field.clearance_at_grid(s1, h1 + e, phi, zero)[0]
        - field.clearance_at_grid(s1, h1 - e, phi, zero)[0]
    ) / (2 * e)
    assert np.abs(d_s).max() <= 1e-4 * ARCSEC_RAD  # per mm; ~10 arcsec/mm a millimetre away
    assert np.abs(d_h).max() <= 1e-4 * ARCSEC_RAD


@pytest.mark.parametrize("side", SIDES)
def test_engine_reports_edge_contact_where_newton_fails(pair, side):
    # toward the ends of a pair's cycle the contact runs onto an edge of a flank: the tangency
    # lies outside the flanks, so the textbook solver cannot find it, while the engine reports
    # the contact there (flagged) with a finite lag
    field = getattr(pair, side)
    u = np.linspace(-1.5, 1.5, 25) * (2.0 * math.pi / 16)
    engine = PairCurve(field).sample(u)
    edge = np.flatnonzero(engine.edge)
    assert edge.size >= 1
    assert np.all(np.isfinite(engine.minimum_rad))
    low = field.pinion.generated_depth_mm  # lowest generated height of each face column
    cell = field.pinion.profile_mm[1] - field.pinion.profile_mm[0]
    failed = 0
    for k in edge:
        start = (engine.contact_face_mm[k], engine.contact_profile_mm[k])
        newton = newton_tca(field, u[k : k + 1], start=start)
        if not newton.converged[0]:
            failed += 1
            continue
        # a tangency Newton does find there lies in the pinion's lowest generated cells, next
        # to the envelope's fold, which the engine leaves out (no interpolant is reliable there)
        i = np.argmin(np.abs(field.pinion.face_mm - newton.pinion_face_mm[0]))
        assert newton.pinion_profile_mm[0] < low[max(i - 1, 0) : i + 2].max() + 2.0 * cell
    assert failed >= 1
