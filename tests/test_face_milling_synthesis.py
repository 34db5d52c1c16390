"""Face milling from the blank (issue 9): the gear's settings measured on the generated gear,
and the pinion by local synthesis closed through the contact engine (seed 002's pair)."""

from __future__ import annotations

import copy
import math
import tomllib

import numpy as np
import pytest
from scipy.optimize import brentq, minimize_scalar

import gearopt
from gearopt.analysis import AnalysisOptions, contact_sides, meshed_pair, pair_backlash
from gearopt.design import parse_design
from gearopt.errors import DesignError, NotAvailableError, SettingsError
from gearopt.flank import FlankGrid
from gearopt_plugins.face_milling import FaceMilling, _family

from .conftest import STUDIES

SEED002 = STUDIES / "seed002_pair.toml"


@pytest.fixture(scope="module")
def seed002():
    return gearopt.load_design(SEED002)


@pytest.fixture(scope="module")
def gear_flanks(seed002):
    return FaceMilling().generate_flanks(
        seed002, member="gear", grid=FlankGrid(n_face=25, n_profile=13)
    )


def _pitch_line_circle(fm, blank, member_index):
    """The flank's line on the pitch cone (exact envelope points), developed into the plane
    (polar angle x sin(gamma)) and fitted by a circle: ``(centre, radius, rms residual)``."""
    s = blank.mean_cone_distance_mm + np.linspace(-8.0, 8.0, 17)
    p = fm.surface.geometry_at(s, np.zeros_like(s))["point"]
    gamma = math.radians(blank.pitch_angle_deg[member_index])
    psi = np.unwrap(np.arctan2(p[:, 1], p[:, 0])) * math.sin(gamma)
    x, y = s * np.cos(psi), s * np.sin(psi)
    # Kasa fit: x^2 + y^2 = 2 a x + 2 b y + c
    a, b, c = np.linalg.lstsq(
        np.stack([2 * x, 2 * y, np.ones_like(x)], 1), x**2 + y**2, rcond=None
    )[0]
    radius = math.sqrt(c + a * a + b * b)
    rms = float(np.sqrt(np.mean((np.hypot(x - a, y - b) - radius) ** 2)))
    return np.array([a, b]), radius, rms


def test_gear_from_blank_spiral_angle_and_slot_width_on_the_generated_gear(seed002, gear_flanks):
    """Each flank's pitch line, developed, is a circle about one centre (spread blade); the
    slot's centre line (the mean radius) has the blank's spiral angle at A_m within 0.01 deg
    and the slot between the flanks is the blank's normal width (half the normal pitch) within
    1 um, measured on the exact envelopes."""
    blank = seed002.blank
    fits = {f: _pitch_line_circle(fm, blank, 1) for f, fm in gear_flanks.items()}
    for flank, (_, _, rms) in fits.items():
        assert rms < 1e-6, flank
    (c_v, r_v, _), (c_x, r_x, _) = fits["concave"], fits["convex"]
    # the concave flank of tooth 0 is its slot's flank turned by whole pitches: turn it back
    step = 2.0 * math.pi / blank.gear_teeth * math.sin(math.radians(blank.pitch_angle_deg[1]))
    k = round((math.atan2(c_x[1], c_x[0]) - math.atan2(c_v[1], c_v[0])) / step)
    rot = np.array(
        [[math.cos(k * step), -math.sin(k * step)], [math.sin(k * step), math.cos(k * step)]]
    )
    c_v = rot @ c_v
    assert np.linalg.norm(c_v - c_x) < 1e-5
    width = r_v - r_x
    assert abs(width - 0.5 * math.pi * blank.mean_normal_module_mm) < 1e-3
    r_m, centre = 0.5 * (r_v + r_x), 0.5 * (c_v + c_x)
    am = blank.mean_cone_distance_mm
    beta = math.degrees(math.asin((am**2 + r_m**2 - centre @ centre) / (2.0 * am * r_m)))
    assert abs(beta - blank.mean_spiral_angle_deg) < 0.01


def test_gear_from_blank_pressure_angles_at_the_mean_point(seed002, gear_flanks):
    """The flank normal's angle to the pitch cone's tangent plane at the pitch point of A_m:
    the blank's 25 deg on both flanks within 0.01 deg."""
    blank = seed002.blank
    gamma = math.radians(blank.pitch_angle_deg[1])
    for flank, fm in gear_flanks.items():
        geo = fm.surface.geometry_at(np.array(blank.mean_cone_distance_mm), np.array(0.0))
        p, n = geo["point"], geo["normal"]
        theta = math.atan2(p[1], p[0])
        cone = np.array(
            [math.cos(gamma) * math.cos(theta), math.cos(gamma) * math.sin(theta), -math.sin(gamma)]
        )
        alpha = math.degrees(math.asin(abs(n @ cone) / np.linalg.norm(n)))
        assert abs(alpha - blank.pressure_angle_deg) < 0.01, (flank, alpha)


@pytest.mark.parametrize("flank", ["concave", "convex"])
def test_gear_from_blank_cuts_the_dedendum_deep(seed002, flank):
    """The blade tips' sweep (u = 0, every cutter angle and roll) reaches down to the root
    cone at the mean cone distance and not below: its lowest height there is -b within 1 um."""
    blank = seed002.blank
    gamma = math.radians(blank.pitch_angle_deg[1])
    am = blank.mean_cone_distance_mm
    family = _family(seed002, "gear", (flank,))
    start = family.pitch_row(np.array([am]))[0, 0]

    def coords(theta, phi):
        q = np.array([[0.0, theta, phi]])
        big_l, big_r, _ = family.axial_radial_meshing(q, np.zeros(1, int))
        s = big_l[0] * math.cos(gamma) + big_r[0] * math.sin(gamma)
        h = -big_l[0] * math.sin(gamma) + big_r[0] * math.cos(gamma)
        return s, h

    def lowest(phi):
        theta = brentq(lambda t: coords(t, phi)[0] - am, start[1] - 0.3, start[1] + 0.3, xtol=1e-14)
        return coords(theta, phi)[1]

    best = minimize_scalar(lowest, bounds=(-0.2, 0.2), method="bounded", options={"xatol": 1e-10})
    assert abs(best.fun + blank.mean_dedendum_mm[1]) < 1e-3


# --- local synthesis closed by the contact engine -----------------------------------------------


@pytest.fixture(scope="module")
def closed_loop(seed002):
    opts = AnalysisOptions.from_conditions({}, design=seed002)
    pair = meshed_pair(seed002, opts)
    return contact_sides(pair, opts), pair_backlash(pair, opts)


@pytest.mark.parametrize("side", ["drive", "coast"])
def test_local_synthesis_closes_through_the_contact_engine(seed002, closed_loop, side):
    """What the pinion was synthesised for at M, read by the engine's TCA over the whole mesh of
    the generated FlankMaps: M within 0.5 mm, path direction within 2 deg, contact ellipse
    within 10 %, the parabolic TE level (peak to peak at the hand-overs) within 10 %."""
    asked = tomllib.loads(SEED002.read_text())["synthesis"]
    path = asked.get(side, {}).get("path_angle_deg", asked["path_angle_deg"])
    tca = closed_loop[0][side]
    assert np.hypot(*tca.center_offset_mm) < 0.5
    assert abs(tca.path_angle_deg - path) < 2.0
    assert abs(tca.ellipse_major_axis_mm / asked["ellipse_major_axis_mm"] - 1.0) < 0.10
    assert abs(tca.te_peak_to_peak_arcsec / abs(asked["te_level_arcsec"]) - 1.0) < 0.10
    assert not tca.edge_contact
    report = {r.targets.side: r for r in seed002.machine.synthesis}[side]
    assert report.first_order_residual < 1e-8


def test_synthesised_pinion_has_the_asked_backlash(seed002, closed_loop):
    """Both pinion flanks sit in one assembly: the circumferential backlash is the asked
    0.1 mm where a side's contact is at its M, plus the two parabolic TEs elsewhere (each at
    most the TE level), never less."""
    backlash = closed_loop[1]
    asked = tomllib.loads(SEED002.read_text())["synthesis"]
    level_um = 2.0 * asked["te_level_arcsec"] / 206264.8 * backlash.radius_mm * 1e3
    b = backlash.circumferential_um
    assert b.min() > 100.0 - 0.5
    assert b.max() < 100.0 + level_um + 0.5
    assert not backlash.interference


# --- inputs without a solution -------------------------------------------------------------------


def _with(**synthesis):
    data = tomllib.loads(SEED002.read_text())
    data = copy.deepcopy(data)
    data["synthesis"].update(synthesis)
    return data


@pytest.mark.parametrize(
    ("key", "value"),
    [
        ("ellipse_major_axis_mm", 40.0),
        ("te_level_arcsec", 0.0),
        ("mean_point_face_mm", 37.5),
        ("mean_point_profile_mm", -1.0),
        ("path_angle_deg", 95.0),
    ],
)
def test_impossible_inputs_are_named(key, value):
    with pytest.raises(DesignError, match=f"synthesis.{key}"):
        parse_design(_with(**{key: value}))


def test_a_path_the_pinion_cannot_realise_is_named():
    """A path along the root line (0 deg) is out of reach of the chosen cutter: the error names
    the path, not NaN settings."""
    with pytest.raises(SettingsError, match="synthesis.drive.path_angle_deg"):
        parse_design(_with(path_angle_deg=0.0))


def test_synthesis_refuses_models_without_one():
    data = tomllib.loads((STUDIES / "seed001_table3.toml").read_text())
    data["synthesis"] = {"path_angle_deg": 80.0}
    with pytest.raises(NotAvailableError, match="synthesis"):
        parse_design(data)


def test_settings_cli_prints_the_derived_settings(capsys):
    from gearopt.cli import main

    assert main(["settings", str(SEED002), "--json"]) == 0
    import json

    out = json.loads(capsys.readouterr().out)
    settings = out["settings"] if "settings" in out else out
    pinion = settings["pinion"]
    assert pinion["convex_roll_c2"] != 0.0 and pinion["concave_roll_c2"] != 0.0
    assert any("local synthesis" in n for n in settings["notes"])
