"""Face milling with modified roll (Litvin's model): the contract suites, the conjugate control,
the modified roll, the spiral angle measured on the generated gear, bad settings."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
from numpy.testing import assert_allclose

import gearopt
from gearopt.errors import DesignError, GearoptError, NotAvailableError
from gearopt.testing import FlankContract
from gearopt_plugins.face_milling import FaceMilling, _family
from gearopt_plugins.face_milling_family import CutterFlank, FaceMillingFamily

from .conftest import STUDIES

MEMBERS = ("pinion", "gear")
FLANKS = ("convex", "concave")
CONJUGATE = STUDIES / "face_milling_conjugate.toml"
#: a variant: arc blades and modified roll on the pinion (no longer conjugate)
MODIFIED = """
[machine.pinion.concave]
cutter_point_radius_mm = 58.680479125
blade_profile_radius_mm = 400.0
roll_c2 = 0.01
[machine.pinion.convex]
cutter_point_radius_mm = 68.319520875
roll_c3 = -0.02
"""


def _modified_text() -> str:
    text = CONJUGATE.read_text()
    head, _, tail = text.partition("[machine.pinion.concave]")
    _, _, rest = tail.partition("[machine.gear]")
    return head + MODIFIED + "\n[machine.gear]" + rest


@pytest.fixture(scope="module")
def conjugate():
    return gearopt.load_design(CONJUGATE)


class TestFaceMillingContract(FlankContract):
    @pytest.fixture
    def machine_model(self):
        return FaceMilling()

    @pytest.fixture(params=["conjugate", "modified"])
    def design_text(self, request):
        return CONJUGATE.read_text() if request.param == "conjugate" else _modified_text()


# --- the conjugate control -----------------------------------------------------------------------


def test_pinion_cut_by_the_gears_generating_surface_is_conjugate(conjugate):
    """Complementary settings, unmodified roll: zero TE (below 0.05 arcsec) on both sides."""
    from gearopt.analysis import AnalysisOptions, contact_sides, meshed_pair

    opts = AnalysisOptions()
    sides = contact_sides(meshed_pair(conjugate, opts), opts)
    for side in ("drive", "coast"):
        assert sides[side].te_peak_to_peak_arcsec < 0.05, side
        assert not sides[side].edge_contact, side


def test_modified_roll_breaks_the_conjugacy(conjugate):
    from gearopt.analysis import AnalysisOptions, contact_sides, meshed_pair

    design = gearopt.with_overrides(conjugate, {"machine.pinion.convex.roll_c2": 0.005})
    opts = AnalysisOptions()
    sides = contact_sides(meshed_pair(design, opts), opts)
    assert sides["drive"].te_peak_to_peak_arcsec > 1.0
    assert sides["coast"].te_peak_to_peak_arcsec < 0.05  # the other flank is untouched


# --- modified roll -------------------------------------------------------------------------------


def test_zero_roll_terms_equal_the_unmodified_roll(conjugate):
    zeros = {f"machine.{m}.roll_c{k}": 0.0 for m in MEMBERS for k in range(2, 7)}
    explicit = gearopt.with_overrides(conjugate, zeros)
    assert (
        explicit.machine.gear.concave.roll
        == (conjugate.machine.gear.concave.ratio_of_roll,) + (0.0,) * 5
    )
    for member in MEMBERS:
        a = FaceMilling().generate_flanks(conjugate, member=member)
        b = FaceMilling().generate_flanks(explicit, member=member)
        for flank in FLANKS:
            assert np.array_equal(a[flank].mask, b[flank].mask)
            on = a[flank].mask
            assert np.abs(a[flank].points_mm - b[flank].points_mm)[on].max() <= 1e-9


def _cradle_turn_displacement(design, member, flank, q):
    """d r / d phi_c at fixed (u, theta, phi_p) in the right-hand work frame, by central
    differences on the cradle angle (turning the cradle setting moves the cone as turning the
    cradle does, up to a slide along the cone, which has no normal component)."""
    family = _family(design, member, (flank,))
    h = 1e-6
    out = []
    for sign in (1.0, -1.0):
        c = family.cutters[0]
        moved = replace(c, cradle_angle_rad=c.cradle_angle_rad + sign * h)
        fam = FaceMillingFamily(
            cutters=(moved,), scale_mm=family.scale_mm, pitch_angle_rad=family.pitch_angle_rad
        )
        out.append(fam.geometry(q, np.zeros(q.shape[:-1], int))["point"])
    geo = family.geometry(q, np.zeros(q.shape[:-1], int))
    return (out[0] - out[1]) / (2.0 * h), geo["point"], geo["normal"]


@pytest.mark.parametrize("member", MEMBERS)
def test_small_roll_term_moves_nodes_by_the_first_order_variation(conjugate, member):
    """c2: the cradle turns further by c2 phi_p^2. To first order the flank moves along its
    normal by n . (d r / d phi_c) c2 phi_p^2, with phi_p the roll at which the node was generated;
    at a fixed grid node (L, R) its polar angle then changes by that over R (e_theta . n)."""
    index = MEMBERS.index(member)
    c1 = conjugate.machine.member(member).convex.ratio_of_roll
    c2 = 2e-4 * c1
    modified = gearopt.with_overrides(conjugate, {f"machine.{member}.roll_c2": c2})
    base = FaceMilling().generate_flanks(conjugate, member=member)
    moved = FaceMilling().generate_flanks(modified, member=member)
    hand = -1.0 if conjugate.blank.hand[index] == "left" else 1.0
    for flank in FLANKS:
        a, b = base[flank], moved[flank]
        on = a.mask & b.mask
        q = a.parameters[on]
        dr, point, normal = _cradle_turn_displacement(conjugate, member, flank, q)
        radius = np.hypot(point[:, 0], point[:, 1])
        e_theta = np.stack([-point[:, 1], point[:, 0], 0 * radius], -1) / radius[:, None]
        shift = c2 * q[:, 2] ** 2 * np.einsum("ij,ij->i", dr, normal)
        predicted = hand * shift / (radius * np.einsum("ij,ij->i", e_theta, normal))
        change = b.polar_angle_rad[on] - a.polar_angle_rad[on]
        scale = np.abs(predicted).max()
        assert scale > 1e-6  # the term moves the flank (about a micrometre)
        # the rest is second order: 2.6 % of the change at c2 = 2e-3 c1, 1.3 % at 1e-3 c1,
        # 0.65 % at 5e-4 c1 (measured on the gear's convex flank); 0.5 % here
        assert np.abs(change - predicted).max() <= 0.005 * scale, (member, flank)


# --- conventions and geometry measured on the flanks ---------------------------------------------


def _spiral_angle_deg(fm, cone_distance_mm):
    """Angle between the tooth trace on the pitch cone and the generatrix at cone distance
    A_m, from the exact flank normal there (as tests/test_epicycloid.py)."""
    geo = fm.surface.geometry_at(np.array(cone_distance_mm), np.array(0.0))
    p, n = geo["point"], geo["normal"]
    r = math.hypot(p[0], p[1])
    e_theta = np.array([-p[1], p[0], 0.0]) / r
    g = p / np.linalg.norm(p)
    t = np.cross(n, np.cross(e_theta, g))
    return math.degrees(math.atan2(abs(t @ e_theta), abs(t @ g)))


def test_generated_gear_spiral_angle_at_the_mean_point(conjugate):
    """The gear's flanks at the mean point of the pitch cone. Each flank is the development of
    its blade's circle in the crown gear's pitch plane (radius R = r_c +/- W/2 about the cutter
    centre at distance s_r): sin(beta) = (A^2 + R^2 - s_r^2) / (2 A R), to 1e-7 deg. The blank's
    beta_m = 35 deg is the angle of the circle r_c through the middle of the space: each flank
    lies W/2 = 3.05 mm from it, about 0.44 deg off (concave more, convex less); their mean is
    35 deg to second order (0.04 deg)."""
    blank = conjugate.blank
    am = blank.mean_cone_distance_mm
    spec = conjugate.machine.gear
    b = blank.mean_dedendum_mm[1]
    maps = FaceMilling().generate_flanks(conjugate, member="gear")
    betas = {}
    for flank, fm in maps.items():
        f = spec.flank(flank)
        sign = 1.0 if flank == "concave" else -1.0
        big_r = f.cutter_point_radius_mm + sign * b * math.tan(
            math.radians(f.blade_pressure_angle_deg)
        )
        sr = f.radial_setting_mm
        want = math.degrees(math.asin((am**2 + big_r**2 - sr**2) / (2.0 * am * big_r)))
        betas[flank] = _spiral_angle_deg(fm, am)
        assert abs(betas[flank] - want) < 1e-7, (flank, betas[flank], want)
        assert abs(betas[flank] - 35.0) < 0.5
    assert betas["concave"] > 35.0 > betas["convex"]
    assert abs(0.5 * (betas["concave"] + betas["convex"]) - 35.0) < 0.05


def test_right_hand_has_the_spiral_sense_of_the_other_models(conjugate):
    """A positive cradle angle cuts a right-hand member: its polar angle grows toward the heel
    along the pitch line, as on the cyclo-palloid right-hand gear (seed 001 Table 3)."""
    cp = gearopt.load_design(STUDIES / "seed001_table3.toml")
    assert cp.blank.hand[1] == conjugate.blank.hand[1] == "right"

    def slope(fm):
        j = int(np.argmin(np.abs(fm.profile_mm)))
        i = len(fm.face_mm) // 2
        return np.gradient(fm.polar_angle_rad[:, j], fm.face_mm)[i]

    ref = slope(gearopt.generate_flanks(cp, "gear")["concave"])
    for fm in FaceMilling().generate_flanks(conjugate, member="gear").values():
        assert slope(fm) * ref > 0.0


def test_flanks_bound_a_tooth_of_half_a_pitch(conjugate):
    """Tooth = space at the mean point (the blades W = half the normal pitch apart on the gear;
    the pinion between the cones of the gear's blades): the tooth's angular thickness at the
    pitch point is close to half a pitch on both members (the spiral changes it by little)."""
    am = conjugate.blank.mean_cone_distance_mm
    for member in MEMBERS:
        maps = FaceMilling().generate_flanks(conjugate, member=member)
        pitch = maps["convex"].pitch_rad
        tx = maps["convex"].polar_angle_exact(np.array([am]), np.array([0.0]))[0]
        tv = maps["concave"].polar_angle_exact(np.array([am]), np.array([0.0]))[0]
        assert abs(abs(tv - tx) - 0.5 * pitch) < 0.05 * pitch, member


def test_concave_is_the_outside_blade_and_convex_the_inside_blade(conjugate):
    """On the gear (one cutter, both blades about the same centre) the concave flank is cut
    by the blade of larger radius; the generated flank curves as the blade's circle: concave
    seen from the tooth (the normal out of the material turns toward the flank's side)."""
    m = conjugate.machine.gear
    assert m.concave.cutter_point_radius_mm > m.convex.cutter_point_radius_mm
    am = conjugate.blank.mean_cone_distance_mm
    maps = FaceMilling().generate_flanks(conjugate, member="gear")
    for flank, fm in maps.items():
        s = np.array([am - 5.0, am, am + 5.0])
        geo = fm.surface.geometry_at(s, np.zeros(3))
        p, n = geo["point"], geo["normal"]
        # second difference of the points along the trace against the normal out of the tooth:
        # a concave flank bends toward the tooth space (along +n), a convex one away from it
        bend = (p[0] + p[2] - 2.0 * p[1]) @ n[1]
        assert (bend > 0.0) == (flank == "concave"), flank


# --- bad settings --------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("key", "value", "error", "match"),
    [
        ("machine.gear.ratio_of_roll", -0.9, DesignError, "must be > 0"),
        ("machine.gear.ratio_of_roll", 0.0, DesignError, "must be > 0"),
        ("machine.pinion.sliding_base_mm", 3.0, DesignError, "cannot reach the root"),
        ("machine.gear.machine_center_to_back_mm", 2.0, DesignError, "cannot reach the root"),
        ("machine.gear.convex.cutter_point_radius_mm", 2.0, DesignError, "inside blade"),
        ("machine.gear.blade_tip_radius_mm", 1.0, NotAvailableError, "not supported"),
        ("machine.gear.blade_profile_radius_mm", 10.0, DesignError, "whole depths"),
        ("machine.gear.blade_profile_radius_mm", "round", DesignError, "inf"),
        ("machine.gear.blade_pressure_angle_deg", 50.0, DesignError, "blade_pressure_angle"),
        ("machine.gear.convex.cradle_ratio", 1.0, DesignError, "cradle_ratio"),
    ],
)
def test_bad_settings_are_named(conjugate, key, value, error, match):
    with pytest.raises(error, match=match) as info:
        gearopt.with_overrides(conjugate, {key: value})
    assert key.rsplit(".", 1)[-1] in str(info.value)


def test_missing_key_is_a_design_error():
    text = CONJUGATE.read_text().replace(
        "radial_setting_mm = 74.674435602\ncradle_angle", "cradle_angle", 1
    )
    with pytest.raises(DesignError, match="radial_setting_mm.*required"):
        gearopt.loads_design(text)


@pytest.mark.parametrize(
    "overrides",
    [
        {"machine.gear.radial_setting_mm": 400.0},  # the cutter passes far from the blank
        {"machine.pinion.convex.cradle_angle_deg": 200.0},
        {"machine.gear.concave.ratio_of_roll": 40.0},
    ],
)
def test_settings_without_an_envelope_raise_never_nan(conjugate, overrides):
    design = gearopt.with_overrides(conjugate, overrides)
    member = next(iter(overrides)).split(".")[1]
    try:
        maps = FaceMilling().generate_flanks(design, member=member)
    except GearoptError:
        return
    for fm in maps.values():  # generated after all: finite and converged where masked
        assert np.all(np.isfinite(fm.points_mm)) and fm.residual[fm.mask].max() <= 1e-12


def test_family_is_complex_step_safe(conjugate):
    """The meshing function's complex-step derivatives equal central differences."""
    family = _family(conjugate, "pinion", FLANKS)
    rng = np.random.default_rng(5)
    q = np.stack(
        [rng.uniform(0, 10, 20), rng.uniform(-0.5, 0.5, 20), rng.uniform(-0.5, 0.5, 20)], -1
    )
    flank = rng.integers(0, 2, 20)
    assert isinstance(family.cutters[0], CutterFlank)
    for k in range(3):
        dq = np.zeros(3)
        dq[k] = 1.0
        cs = np.stack(family.axial_radial_meshing(q + 1e-30j * dq, flank), -1).imag / 1e-30
        h = 1e-6
        fd = (
            np.stack(family.axial_radial_meshing(q + h * dq, flank), -1)
            - np.stack(family.axial_radial_meshing(q - h * dq, flank), -1)
        ) / (2 * h)
        assert_allclose(cs, fd, rtol=1e-6, atol=1e-8)


def test_profile_arc_is_tangent_at_the_pitch_line_point_and_crowns_both_ways():
    # the same meaning as the epicycloid model's blade_profile_radius_mm: the arc touches the
    # straight blade at its pitch-line point and leaves it toward the material on both sides
    from gearopt_plugins.face_milling_family import CutterFlank, edge

    straight = CutterFlank(
        side=1.0,
        point_radius_mm=60.0,
        pressure_angle_rad=np.radians(20.0),
        curvature_per_mm=0.0,
        radial_setting_mm=70.0,
        cradle_angle_rad=0.7,
        machine_root_angle_rad=0.3,
        center_to_back_mm=0.0,
        blank_offset_mm=0.0,
        sliding_base_mm=5.0,
        roll=(0.3, 0, 0, 0, 0, 0),
        tangent_mm=5.0 / np.cos(np.radians(20.0)),
    )
    arc = replace(straight, curvature_per_mm=1.0 / 400.0)
    u0 = straight.tangent_mm
    np.testing.assert_allclose(edge(arc, u0), edge(straight, u0), atol=1e-12)
    normal = np.array([np.cos(np.radians(20.0)), np.sin(np.radians(20.0))])  # toward material
    for du in (-4.0, 4.0):
        r_a, h_a, *_ = edge(arc, u0 + du)
        r_s, h_s, *_ = edge(straight, u0 + du)
        relief = np.dot([r_a - r_s, h_a - h_s], normal)
        assert relief == pytest.approx(du**2 / (2 * 400.0), rel=1e-3)
