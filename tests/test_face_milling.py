"""Face milling with modified roll (Litvin's model): the contract suites, the conjugate control,
the modified roll, the spiral angle measured on the generated gear, bad settings."""

from __future__ import annotations

import math
import tomllib
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from numpy.testing import assert_allclose

import gearopt
from gearopt.design_files import parse_design
from gearopt.errors import DesignError, GearoptError
from gearopt.flank import cone_coordinates
from gearopt.testing import FlankContract
from gearopt_plugins.face_milling import FaceMilling
from gearopt_plugins.face_milling.family import CutterFlank, FaceMillingFamily, design_family

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


#: the blade tip (edge) radius of the rounded-blade tests, mm (about 0.2 m_mn)
TIP_RADIUS_MM = 1.0


def _with_tip_radius(text: str, radius_mm: float = TIP_RADIUS_MM) -> str:
    """A design text with ``blade_tip_radius_mm`` on every blade of both members."""
    for member in MEMBERS:
        header = f"[machine.{member}]\n"
        text = text.replace(header, f"{header}blade_tip_radius_mm = {radius_mm!r}\n", 1)
    return text


@pytest.fixture(scope="module")
def conjugate():
    return gearopt.load_design(CONJUGATE)


class TestFaceMillingContract(FlankContract):
    @pytest.fixture
    def machine_model(self):
        return FaceMilling()

    @pytest.fixture(params=["conjugate", "modified", "rounded", "rounded-modified"])
    def design_text(self, request):
        text = CONJUGATE.read_text() if "modified" not in request.param else _modified_text()
        # rounded: a blade tip radius on every blade (with the profile arcs and modified roll)
        return _with_tip_radius(text) if request.param.startswith("rounded") else text


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
    family = design_family(design, member, (flank,))
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
        ("machine.gear.blade_tip_radius_mm", -0.5, DesignError, ">= 0"),
        ("machine.gear.blade_tip_radius_mm", 7.5, DesignError, "pitch-line point"),
        ("machine.pinion.concave.blade_tip_radius_mm", 7.5, DesignError, "< 7.38"),
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
    member = next(iter(overrides)).split(".")[1]
    try:  # refused when read (a ratio of roll of 40, issue 27) or when generated
        design = gearopt.with_overrides(conjugate, overrides)
        maps = FaceMilling().generate_flanks(design, member=member)
    except GearoptError:
        return
    for fm in maps.values():  # generated after all: finite and converged where masked
        assert np.all(np.isfinite(fm.points_mm)) and fm.residual[fm.mask].max() <= 1e-12


def _assert_complex_step_safe(family, q, flank, *, atol: float) -> None:
    """The meshing function's complex-step derivatives (each generation parameter in turn)
    equal its central differences (step 1e-6) to 1e-6 relative and ``atol``."""
    for k in range(3):
        dq = np.zeros(3)
        dq[k] = 1.0
        cs = np.stack(family.axial_radial_meshing(q + 1e-30j * dq, flank), -1).imag / 1e-30
        h = 1e-6
        fd = (
            np.stack(family.axial_radial_meshing(q + h * dq, flank), -1)
            - np.stack(family.axial_radial_meshing(q - h * dq, flank), -1)
        ) / (2 * h)
        assert_allclose(cs, fd, rtol=1e-6, atol=atol)


def test_family_is_complex_step_safe(conjugate):
    """The meshing function's complex-step derivatives equal central differences."""
    family = design_family(conjugate, "pinion", FLANKS)
    rng = np.random.default_rng(5)
    q = np.stack(
        [rng.uniform(0, 10, 20), rng.uniform(-0.5, 0.5, 20), rng.uniform(-0.5, 0.5, 20)], -1
    )
    flank = rng.integers(0, 2, 20)
    assert isinstance(family.cutters[0], CutterFlank)
    _assert_complex_step_safe(family, q, flank, atol=1e-8)


def test_profile_arc_is_tangent_at_the_pitch_line_point_and_crowns_both_ways():
    # the same meaning as the epicycloid model's blade_profile_radius_mm: the arc touches the
    # straight blade at its pitch-line point and leaves it toward the material on both sides
    from gearopt_plugins.face_milling.family import CutterFlank, edge

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


# --- tapered depth -------------------------------------------------------------------------------

TAPERED = STUDIES / "face_milling_tapered.toml"
MAIN_REFERENCE = Path(__file__).parent / "data" / "face_milling_conjugate_main.npz"


@pytest.fixture(scope="module")
def tapered():
    return gearopt.load_design(TAPERED)


def test_uniform_depth_output_is_mains(conjugate):
    """The conjugate design's flanks (9 x 7 grid) equal those of main before tapered depth
    (tests/data, written by main at 5122773) to 1e-12, and its TCA metrics agree."""
    from gearopt.flank import FlankGrid

    ref = np.load(MAIN_REFERENCE)
    for member in MEMBERS:
        maps = gearopt.generate_flanks(conjugate, member, grid=FlankGrid(n_face=9, n_profile=7))
        for flank, fm in maps.items():
            key = f"{member}_{flank}_"
            assert np.array_equal(fm.mask, ref[key + "mask"])
            for name in ("polar_angle_rad", "points_mm", "normals"):
                assert_allclose(getattr(fm, name), ref[key + name], rtol=0, atol=1e-12)
    # the TCA metrics: the engine's contact-interval ends are bisected differently since the
    # reference was written (candidate points evaluated at once, 1/80 pitch steps): the
    # contact ratio may move by one step and the bias with it; the rest to 1e-6 (the compiled
    # kernels, gearopt.contact.kernels, choose the refinement's closed-form Newton step row by
    # row rather than for a whole batch: the same step to rounding, refined positions within
    # about 1e-7 mm)
    # (the pattern's width and M are measured on the refined field since issue 19: not
    # the reference's node-counted figures, so not compared)
    # (the reference names the metrics as gearopt 0.1 did: ``renamed`` maps today's names)
    # (since the refinement reaches the pinion's generated boundary on fine cells of the exact
    # surface, gearopt.contact.boundary, the TE of this line contact is noise of 0.0032 /
    # 0.0045 arcsec drive / coast rather than the reference's 0.0073 / 0.0138; its contact
    # interval, the edge flag's bracket in noise for a line contact, moved with it: contact
    # ratio 2.01 -> 2.38 drive, 2.36 -> 2.43 at 81 x 161; not compared, nor the bias)
    tca = gearopt.evaluators()["tca"]
    metrics = tca.evaluate(conjugate, None).metrics
    skipped = ("pattern_width_mm", "pattern_center_offset", "contact_ratio", "pattern_bias_mm")
    for new, value in metrics.items():
        name = tca.renamed.get(new)
        if name is None or any(part in name for part in skipped):
            continue
        atol = 1e-6
        if name.endswith("te_peak_to_peak_arcsec"):
            atol = 0.01
        assert_allclose(value, ref["metric_" + name], rtol=0, atol=atol, err_msg=name)


def _tip_line_heights(fm):
    """Per face column, the height at which the envelope's blade parameter u crosses 0: the
    line the blade's tip generates on the flank (interpolated between the grid's rows along
    the envelope, which the solver continues past the tip)."""
    u, h = fm.parameters[..., 0], fm.heights_mm
    out = []
    for c in range(fm.shape[0]):
        j = int(np.flatnonzero((u[c, :-1] < 0.0) & (u[c, 1:] >= 0.0))[0])
        w = u[c, j] / (u[c, j] - u[c, j + 1])
        out.append(h[c, j] + w * (h[c, j + 1] - h[c, j]))
    return np.array(out)


def test_tapered_gear_flank_spans_the_face_and_root_cones(tapered):
    """Gear of the tapered design (machine root angle = root angle): the generated points of
    the top row lie on the face cone at every cone distance (toe and heel included); the tip
    line (u = 0) follows the root cone: it stays between 0.2 and 0.4 mm above it (the blade's
    tip corner touches the flank off the root cone's contact line) while the root cone drops
    F tan(theta_d) = 1.22 mm from heel to toe."""
    from gearopt.flank import FlankGrid

    blank = tapered.blank
    maps = gearopt.generate_flanks(tapered, "gear", grid=FlankGrid(n_face=15, n_profile=25))
    g = math.radians(blank.pitch_angle_deg[1])
    face_angle = math.radians(blank.face_angle_deg[1])
    heel = blank.outer_cone_distance_mm * np.array([math.cos(g), math.sin(g)])
    heel_tip = heel + blank.outer_addendum_mm[1] * np.array([-math.sin(g), math.cos(g)])
    along = np.array([math.cos(face_angle), math.sin(face_angle)])
    drop = blank.face_width_mm * math.tan(math.radians(blank.dedendum_angle_deg[1]))
    assert drop == pytest.approx(1.2226, abs=1e-4)
    for fm in maps.values():
        assert fm.taper is not None
        assert fm.mask[:, -1].all()  # generated up to the face cone, toe to heel
        p = fm.points_mm[:, -1]
        lr = np.stack([p[:, 2], np.hypot(p[:, 0], p[:, 1])], axis=-1) - heel_tip
        off_face_cone = lr[:, 0] * along[1] - lr[:, 1] * along[0]
        assert np.abs(off_face_cone).max() < 1e-9
        above = _tip_line_heights(fm) + blank.dedendum_at_mm(1, fm.face_mm)
        assert above.min() > 0.2 and above.max() < 0.4, above
        assert np.ptp(above) < 0.15
        # the lowest generated nodes lie within a row of the tip line
        step = float(np.max(np.diff(fm.heights_mm, axis=1)))
        depth = fm.generated_depth_mm + blank.dedendum_at_mm(1, fm.face_mm)
        assert np.all(depth >= above - 1e-9) and np.all(depth <= above + step + 1e-9)


@pytest.mark.parametrize("member", MEMBERS)
def test_tapered_tip_sweeps_the_root_cone(tapered, member):
    """The blade's tip (u = 0) over cutter phases and roll angles, in the work: never below
    the root cone, and touching it all along the face (machine root angle = root angle: the
    tip plane holds the root cone's generatrix), measured as the least height above the root
    cone in each of 7 bins of the face width."""
    lowest, least = _tip_sweep_above_root(tapered, member)
    assert lowest > -1e-9
    assert least < 0.01, least


def test_root_reach_is_checked_at_toe_and_heel(conjugate, tapered):
    """The blade's tip should reach the root line over the whole face: a tapered root cut with
    the machine root angle at the pitch angle misses the heel's root; a uniform-depth member
    with the work tilted (the mean root line just reached) misses one end. Below the clearance
    the root is cut there, shallower (a warning naming the end); beyond it, the mating tip
    would hit the root (an error)."""

    def tilted(deg, sign):
        g = conjugate.blank.pitch_angle_deg[1]
        a_m, b_m = 90.0, conjugate.blank.mean_dedendum_mm[1]
        tilt = math.radians(deg)
        reach = sign * a_m * math.sin(tilt) + b_m * math.cos(tilt)  # the mean root line
        return gearopt.with_overrides(
            conjugate,
            {
                "machine.gear.machine_root_angle_deg": g + sign * deg,
                "machine.gear.sliding_base_mm": reach,
            },
        )

    g = tapered.blank.pitch_angle_deg[1]
    for case, end in (
        (lambda: tilted(1.0, 1.0), "at the heel"),
        (lambda: tilted(1.0, -1.0), "at the toe"),
        (
            lambda: gearopt.with_overrides(
                tapered,
                {"machine.gear.machine_root_angle_deg": g, "machine.gear.sliding_base_mm": 4.857},
            ),
            "at the heel",
        ),
    ):
        with pytest.warns(gearopt.errors.GearoptWarning, match=end) as records:
            case()
        assert "clearance shrinks" in str(records[0].message)
    with pytest.raises(DesignError, match="at the heel") as info:
        tilted(5.0, 1.0)  # 14 mm x sin 5 deg = 1.2 mm above the root: more than the clearance
    assert info.value.parameter == "machine.gear.convex.sliding_base_mm"
    with pytest.raises(DesignError, match="at the toe"):
        tilted(5.0, -1.0)


def test_tapered_face_keeps_the_conjugate_pair_conjugate(conjugate):
    """The conjugate pair with face cones 2 deg outside the pitch cones (the outer addendum
    raised to keep the mean one): the same generated surfaces on a tapered grid, so the TE
    stays below 0.05 arcsec (a wrong height on the gear's grid would read as hundreds of
    arcsec), and the taller heel raises the drive side's contact ratio (the coast side's, a line
    contact's edge-flag bracket, reads lower tapered at every grid: 2.44 / 2.50 at 25 x 21,
    2.33 / 2.46 at 41 x 41, 2.43 / 2.45 at 81 x 161; the default grid read 2.33 / 2.18 while the
    refinement stayed two cells above the pinion's lowest generated nodes)."""
    from gearopt.analysis import AnalysisOptions, contact_sides, meshed_pair

    pitch = conjugate.blank.pitch_angle_deg
    a_m = conjugate.blank.mean_addendum_mm
    rise = 14.0 * math.tan(math.radians(2.0))
    design = gearopt.with_overrides(
        conjugate,
        {
            "pair.face_angle_deg": [pitch[0] + 2.0, pitch[1] + 2.0],
            "pair.outer_addendum_mm": [a_m[0] + rise, a_m[1] + rise],
        },
    )
    assert design.blank.tapered == (True, True)
    assert_allclose(design.blank.mean_addendum_mm, a_m, rtol=1e-14)
    opts = AnalysisOptions()
    base = contact_sides(meshed_pair(conjugate, opts), opts)
    sides = contact_sides(meshed_pair(design, opts), opts)
    for side in ("drive", "coast"):
        assert sides[side].te_peak_to_peak_arcsec < 0.05, side
        assert not sides[side].edge_contact, side
    assert sides["drive"].contact_ratio > base["drive"].contact_ratio


def test_tapered_design_analyses_and_plots(tapered, tmp_path, capsys):
    """The tapered design file through the contact engine, the analyses and their plots, and
    the flank summary: finite metrics, the figures written. Its teeth interfere (a test case
    of the tapered domain, not a tuned design): the CLI refuses it as no gear mesh (issue 27),
    in one line; the evaluators keep it as a warning."""
    from gearopt.cli import main
    from gearopt.plots import plot_analysis

    installed = gearopt.evaluators()
    results = {name: installed[name].evaluate(tapered, None) for name in ("tca", "backlash")}
    results["ease-off"] = installed["ease-off"].evaluate(tapered, None)
    assert all(math.isfinite(v) for v in results["tca"].metrics.values())
    assert any("interference" in w for w in results["backlash"].warnings)
    assert main(["analyze", str(TAPERED), "--json"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "interference deeper than 5 um" in err[0]
    plot_analysis(tapered, results, tmp_path)
    for name in ("te", "pattern", "backlash", "ease_off"):
        assert (tmp_path / f"{name}.png").stat().st_size > 0
    summary = gearopt.generate_flanks(tapered, "pinion")["convex"].summary()
    assert summary["generated_nodes"] > 0 and math.isfinite(summary["generated_depth_mm"])


def test_flank_query_on_a_tapered_grid(tapered):
    """``gearopt flank --at`` on a tapered member: the point lies at the asked axial position
    and radius, its height is the true height above the pitch cone."""
    from gearopt.flank_cli import flank_point

    out = flank_point(tapered, member="gear", flank="convex", axial_mm=30.0, radius_mm=86.0)
    p = np.array(out["point_mm"])
    assert_allclose([p[2], np.hypot(p[0], p[1])], [30.0, 86.0], atol=1e-9)
    g = math.radians(tapered.blank.pitch_angle_deg[1])
    assert_allclose(out["height_mm"], -30.0 * math.sin(g) + 86.0 * math.cos(g), atol=1e-12)
    assert out["inside_blank"]


# --- the blade tip (edge) radius -----------------------------------------------------------------


def test_sharp_blade_output_is_bit_for_bit_mains(conjugate):
    """``blade_tip_radius_mm = 0`` (the default, or given) leaves the flanks bit for bit as
    main wrote them (tests/data, unchanged since 5122773), and the TCA metrics as the default."""
    from gearopt.flank import FlankGrid

    ref = np.load(MAIN_REFERENCE)
    given = gearopt.with_overrides(
        conjugate, {f"machine.{m}.blade_tip_radius_mm": 0.0 for m in MEMBERS}
    )
    for design in (conjugate, given):
        for member in MEMBERS:
            maps = gearopt.generate_flanks(design, member, grid=FlankGrid(n_face=9, n_profile=7))
            for flank, fm in maps.items():
                key = f"{member}_{flank}_"
                # against the stored file, to rounding: its bits depend on the machine's BLAS
                # and CPU (measured on another machine: 4e-15 rad, 9e-14 mm)
                assert np.array_equal(fm.mask, ref[key + "mask"]), key
                for name, tol in (("polar_angle_rad", 1e-12), ("points_mm", 1e-10)):
                    np.testing.assert_allclose(
                        getattr(fm, name), ref[key + name], rtol=0, atol=tol, err_msg=key + name
                    )
                np.testing.assert_allclose(fm.normals, ref[key + "normals"], rtol=0, atol=1e-12)
            # the given zero radius is the default, bit for bit
            if design is given:
                for member_maps in (maps,):
                    default = gearopt.generate_flanks(
                        conjugate, member, grid=FlankGrid(n_face=9, n_profile=7)
                    )
                    for flank, fm in member_maps.items():
                        assert np.array_equal(fm.polar_angle_rad, default[flank].polar_angle_rad)
    # the TCA metrics: the given zero radius is the default, bit for bit (against the stored
    # reference they agree within the engine's interval-bisection step, see above)
    metrics = gearopt.evaluators()["tca"].evaluate(given, None).metrics
    default = gearopt.evaluators()["tca"].evaluate(conjugate, None).metrics
    for name, value in metrics.items():
        assert value == default[name], name


def _cutter(side: float, curvature_per_mm: float, tip_radius_mm: float) -> CutterFlank:
    alpha = math.radians(20.0)
    return CutterFlank(
        side=side,
        point_radius_mm=60.0,
        pressure_angle_rad=alpha,
        curvature_per_mm=curvature_per_mm,
        radial_setting_mm=70.0,
        cradle_angle_rad=0.7,
        machine_root_angle_rad=0.3,
        center_to_back_mm=0.0,
        blank_offset_mm=0.0,
        sliding_base_mm=5.0,
        roll=(0.3, 0, 0, 0, 0, 0),
        tangent_mm=5.0 / math.cos(alpha),
        tip_radius_mm=tip_radius_mm,
    )


@pytest.mark.parametrize("side", [1.0, -1.0])
@pytest.mark.parametrize("curvature_per_mm", [0.0, 1.0 / 400.0])
def test_tip_fillet_is_a_circle_of_the_tip_radius_on_the_tool(side, curvature_per_mm):
    """In the tool's axial section (radius, height) the edge from u = 0 to the fillet's end:
    unit speed, curvature 1/rho_t (second derivatives by complex step of edge()'s first ones),
    the centre of curvature fixed, rho_t above the tip plane and on the blade's side (away from
    the material); the fillet touches the tip plane at u = 0 (height 0, horizontal tangent)
    and never crosses it; at its end it joins the edge with the edge's point and tangent, and
    beyond it the edge is the sharp blade's edge (the same line or profile arc)."""
    from gearopt_plugins.face_milling.family import _fillet, edge

    rho = 1.3
    sharp, rounded = _cutter(side, curvature_per_mm, 0.0), _cutter(side, curvature_per_mm, rho)
    length, u_edge, _ = (float(v) for v in _fillet(rounded))
    alpha = math.radians(20.0)
    if curvature_per_mm == 0.0:
        assert length == pytest.approx(rho * (0.5 * math.pi - alpha), rel=1e-14)
    u = np.linspace(0.0, length, 41)[1:-1]
    r, h, dr, dh = edge(rounded, u)
    _, _, d2r, d2h = (v.imag / 1e-30 for v in edge(rounded, u + 1e-30j))
    assert_allclose(np.hypot(dr, dh), 1.0, atol=1e-14)
    curvature = dr * d2h - dh * d2r  # signed, positive turning left in (r, h)
    assert_allclose(np.abs(curvature), 1.0 / rho, rtol=1e-12)
    centre_r, centre_h = r - dh / curvature, h + dr / curvature
    assert_allclose(centre_h, -rho, atol=1e-12)  # rho_t above the tip plane (z_m < 0)
    assert np.ptp(centre_r) < 1e-12
    # the centre lies on the blade's side: radially away from the tooth material
    r_tip = edge(rounded, np.array(0.0))[0]
    assert (centre_r[0] - r_tip) * side == pytest.approx(0.0, abs=1e-12)
    assert np.all((centre_r[0] - r) * side < 0.0)
    h0, dh0 = edge(rounded, np.array(0.0))[1], edge(rounded, np.array(0.0))[3]
    assert abs(h0) < 1e-15 and abs(dh0) < 1e-15
    assert np.all(h < 0.0)
    eps = 1e-7
    before = np.array(edge(rounded, np.array(length - eps)), float)
    after = np.array(edge(rounded, np.array(length + eps)), float)
    assert_allclose(before, after, atol=1e-6)
    # beyond the fillet: the sharp blade's edge itself, shifted along its arc length
    v = np.linspace(length, length + 8.0, 9)
    assert_allclose(
        np.array(edge(rounded, v)), np.array(edge(sharp, v - length + u_edge)), atol=1e-12
    )


@pytest.fixture(scope="module")
def rounded_pairs():
    """(sharp, rounded) flanks of the conjugate and modified designs, blade tip radius 1 mm."""
    from gearopt.flank import FlankGrid

    grid = FlankGrid(n_face=9, n_profile=25)
    out = {}
    for name, text in (("conjugate", CONJUGATE.read_text()), ("modified", _modified_text())):
        sharp, rounded = gearopt.loads_design(text), gearopt.loads_design(_with_tip_radius(text))
        for member in MEMBERS:
            a = FaceMilling().generate_flanks(sharp, member=member, grid=grid)
            b = FaceMilling().generate_flanks(rounded, member=member, grid=grid)
            for flank in FLANKS:
                length = float(_fillet_length(rounded, member, flank))
                out[name, member, flank] = (a[flank], b[flank], length)
    return out


def _fillet_length(design, member, flank):
    from gearopt_plugins.face_milling.family import _fillet

    return _fillet(design_family(design, member, (flank,)).cutters[0])[0]


@pytest.mark.parametrize("design", ["conjugate", "modified"])
def test_tip_radius_leaves_the_flank_above_the_fillet(rounded_pairs, design):
    """Nodes generated by the blade's edge above its fillet (u past the fillet's end) are the
    sharp blade's flank points (the same cone: 5e-14 mm measured)."""
    for member in MEMBERS:
        for flank in FLANKS:
            sharp, rounded, length = rounded_pairs[design, member, flank]
            above = sharp.mask & rounded.mask & (rounded.parameters[..., 0] > length)
            assert above.sum() > 100
            gap = np.abs(rounded.points_mm - sharp.points_mm)[above].max()
            assert gap <= 1e-9, (member, flank, gap)


@pytest.mark.parametrize("design", ["conjugate", "modified"])
def test_tip_radius_leaves_material_at_the_root(rounded_pairs, design):
    """Where the fillet generates the flank (u on the fillet) the rounded blade, which lacks
    the sharp blade's corner, removes less: the flank lies off the sharp blade's flank toward
    the tooth space (along the normal out of the material), never into the material; by tens
    of micrometres on the gear near its root (0.086 / 0.091 mm measured, 1 mm radius)."""
    for member in MEMBERS:
        for flank in FLANKS:
            sharp, rounded, length = rounded_pairs[design, member, flank]
            fillet = sharp.mask & rounded.mask & (rounded.parameters[..., 0] < length)
            assert fillet.any(), (member, flank)
            d = rounded.points_mm - sharp.points_mm
            along = np.einsum("...i,...i", d, rounded.normals)[fillet]
            assert along.min() > 0.0, (member, flank)
            if member == "gear":
                assert along.max() > 0.05, (flank, along.max())


def _tip_sweep_above_root(design, member, flank="convex"):
    """The blade's tip (u = 0: the tip plane, the fillet's lowest point) over cutter phases
    and roll angles, in the work: its height above the root cone, and the least of it in each
    of 7 bins of the face width."""
    index = MEMBERS.index(member)
    blank = design.blank
    family = design_family(design, member, (flank,))
    theta = np.linspace(-math.pi, math.pi, 2001)
    phi = np.linspace(-0.6, 0.6, 121)
    q = np.stack(np.broadcast_arrays(0.0, theta[:, None], phi[None, :]), axis=-1)
    p = family.geometry(q, np.zeros(q.shape[:-1], int))["point"].reshape(-1, 3)
    g = math.radians(blank.pitch_angle_deg[index])
    s, h = cone_coordinates(p[:, 2], np.hypot(p[:, 0], p[:, 1]), g)
    above = h + blank.dedendum_at_mm(index, s)
    ai, ao = blank.inner_cone_distance_mm, blank.outer_cone_distance_mm
    on = (s >= ai) & (s <= ao)
    bins = np.linspace(ai, ao, 8)
    least = [above[(s >= a) & (s < b)].min() for a, b in zip(bins[:-1], bins[1:], strict=True)]
    return above[on].min(), max(least)


@pytest.mark.parametrize("path", [CONJUGATE, TAPERED])
@pytest.mark.parametrize("member", MEMBERS)
def test_rounded_tip_still_sweeps_the_root(path, member):
    """With a blade tip radius the blade's lowest points (the fillet touching the tip plane)
    still sweep the root cone over the whole face, never below it: the depth is unchanged."""
    design = gearopt.loads_design(_with_tip_radius(path.read_text()))
    for flank in FLANKS:
        lowest, least = _tip_sweep_above_root(design, member, flank)
        assert lowest > -1e-9 and least < 0.01, (flank, lowest, least)


@pytest.mark.parametrize("tip_radius_mm", [0.0, TIP_RADIUS_MM])
def test_family_with_tip_radius_is_complex_step_safe(tip_radius_mm):
    """edge() on and off the fillet: complex-step derivatives of the meshing equations equal
    central differences (u spans the fillet, its end and the edge; the differences round
    off at 1e-8 on L, R of about 100 mm)."""
    design = gearopt.loads_design(_with_tip_radius(_modified_text(), tip_radius_mm))
    family = design_family(design, "pinion", FLANKS)
    rng = np.random.default_rng(7)
    q = np.stack(
        [rng.uniform(0, 4, 40), rng.uniform(-0.5, 0.5, 40), rng.uniform(-0.5, 0.5, 40)], -1
    )
    flank = rng.integers(0, 2, 40)
    # (atol: the differences' rounding on L, R of about 100 mm)
    _assert_complex_step_safe(family, q, flank, atol=1e-7)


@pytest.mark.parametrize(
    ("key", "value", "named"),
    [
        ("ratio_of_roll", 1e308, "ratio_of_roll"),
        ("ratio_of_roll", 2.5, "ratio_of_roll"),
        ("roll_c2", 1e18, "roll_c2"),
        ("roll_c4", -12.0, "roll_c4"),
    ],
)
def test_a_roll_that_generates_no_flank_is_refused(key, value, named):
    # issue 27: face-milling settings accepted ratio_of_roll = 1e308 and roll_c2 = 1e18
    data = tomllib.loads((STUDIES / "face_milling_conjugate.toml").read_text())
    data["machine"]["pinion"][key] = value
    with pytest.raises(DesignError) as info:
        parse_design(data)
    assert info.value.parameter.endswith(named)
