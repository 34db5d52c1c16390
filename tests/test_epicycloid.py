"""Epicycloid machine model (seed 003): Tables 2-3, the contract suites, the reuse of the
cyclo-palloid chain, the spiral angle measured on the generated flanks, the arc blade."""

from __future__ import annotations

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose

import gearopt
from gearopt.errors import DesignError
from gearopt.testing import FlankContract
from gearopt_plugins.cyclo_palloid import CycloPalloid
from gearopt_plugins.epicycloid import Epicycloid

from .conftest import SEED_CASES, STUDIES

MEMBERS = ("pinion", "gear")
FLANKS = ("convex", "concave")
CASE_A = STUDIES / "seed003_case_A.toml"
CASE_C_PINION = (
    "\n[machine.pinion.convex]\ncutter_head_radius_mm = 135.0\nblade_profile_radius_mm = 509.634\n"
)


def _case_c_text() -> str:
    text = CASE_A.read_text()
    head, _, tail = text.partition("[machine.pinion.convex]")
    _, _, rest = tail.partition("[machine.gear.concave]")
    return head + CASE_C_PINION + "\n[machine.gear.concave]" + rest


@pytest.fixture(scope="module")
def case_a():
    return gearopt.load_design(CASE_A)


class TestEpicycloidContract(FlankContract):
    @pytest.fixture
    def machine_model(self):
        return Epicycloid()

    @pytest.fixture(params=["case_A", "case_C"])
    def design_text(self, request):
        return CASE_A.read_text() if request.param == "case_A" else _case_c_text()


# --- Tables 2-3 ----------------------------------------------------------------------------------


def _drive_settings(design, member, rh, rb):
    flank = "convex" if member == "pinion" else "concave"
    design = gearopt.with_overrides(
        design,
        {
            f"machine.{member}.{flank}.cutter_head_radius_mm": rh,
            f"machine.{member}.{flank}.blade_profile_radius_mm": rb,
        },
    )
    return gearopt.basic_settings(design).member(member)


def _radius(value):
    return "inf" if value == "infinite" else value


@pytest.mark.parametrize("case", ["case_A", "case_B", "case_C"])
def test_table2_pinion_convex_settings(case_a, seed_cases, case):
    ref = seed_cases["epicycloid_seed003"]["pinion_convex_settings"][case]
    s = _drive_settings(
        case_a, "pinion", ref["cutter_head_radius_mm"], _radius(ref["cutter_edge_radius_mm"])
    )
    assert s.cutter_head_radius_mm == ref["cutter_head_radius_mm"]
    want_rb = ref["cutter_edge_radius_mm"]
    assert s.cutter_edge_radius_mm == (0.0 if want_rb == "infinite" else want_rb)
    # Tables 2-3 print three decimals: the tolerance is 1e-3 mm
    for key in ("machine_distance_mm", "base_circle_radius_mm", "rolling_circle_radius_mm"):
        assert_allclose(getattr(s, key), ref[key], rtol=0, atol=1e-3, err_msg=key)


def test_table3_gear_concave_settings(case_a, seed_cases):
    ref = seed_cases["epicycloid_seed003"]["gear_concave_settings"]
    s = gearopt.basic_settings(case_a).gear
    assert s.cutter_head_radius_mm == ref["cutter_head_radius_mm"]
    assert s.cutter_edge_radius_mm == 0.0 and s.cutter_edge_curvature_per_mm == 0.0
    for key in ("machine_distance_mm", "base_circle_radius_mm", "rolling_circle_radius_mm"):
        assert_allclose(getattr(s, key), ref[key], rtol=0, atol=1e-3, err_msg=key)


def test_settings_follow_the_papers_relations(case_a):
    """M_d^2 = R_m^2 + R_h^2 - 2 R_m R_h sin(beta_m - nu), sin nu = N_b m_b / (2 R_h),
    M_d = rho + p, p / rho = N_b / N_c (seed_cases consistency checks), on both flanks."""
    blank = case_a.blank
    rm, beta = blank.mean_cone_distance_mm, math.radians(blank.mean_spiral_angle_deg)
    for member in MEMBERS:
        s = gearopt.basic_settings(case_a).member(member)
        for prefix in ("", "coast_"):
            rh = getattr(s, prefix + "cutter_head_radius_mm")
            nu = math.asin(s.blade_groups * s.blade_module_mm / (2.0 * rh))
            assert_allclose(math.radians(getattr(s, prefix + "slope_angle_deg")), nu, rtol=1e-14)
            md = getattr(s, prefix + "machine_distance_mm")
            assert_allclose(md**2, rm**2 + rh**2 - 2 * rm * rh * math.sin(beta - nu), rtol=1e-13)
            rho = getattr(s, prefix + "base_circle_radius_mm")
            p = getattr(s, prefix + "rolling_circle_radius_mm")
            assert_allclose(rho + p, md, rtol=1e-14)
            assert_allclose(p / rho, s.blade_groups / blank.crown_gear_teeth, rtol=1e-12)
        # eq 2: psi / psi_a = sin(delta_1)
        assert_allclose(
            s.gear_to_cradle_roll,
            1.0 / math.sin(math.radians(blank.pitch_angle_deg[MEMBERS.index(member)])),
            rtol=1e-14,
        )


# --- design keys ---------------------------------------------------------------------------------


def test_flank_tables_override_the_member_and_machine_keys(case_a):
    m = case_a.machine
    assert m.pinion.convex.cutter_head_radius_mm == 135.0
    assert m.pinion.concave.cutter_head_radius_mm == 137.4  # from [machine]
    assert math.isinf(m.pinion.convex.blade_profile_radius_mm)
    assert m.blade_module_mm == case_a.blank.mean_normal_module_mm  # default m_b = m_mn
    c = gearopt.loads_design(_case_c_text()).machine
    assert c.pinion.convex.blade_profile_radius_mm == 509.634
    assert math.isinf(c.pinion.concave.blade_profile_radius_mm)


@pytest.mark.parametrize(
    ("key", "value", "match"),
    [
        ("machine.pinion.convex.blade_profile_radius_mm", "straight", "inf"),
        ("machine.pinion.convex.blade_profile_radius_mm", 20.0, "whole depths"),
        ("machine.pinion.convex.blade_profile_radius_mm", -500.0, "> 0"),
        ("machine.gear.concave.cutter_head_radius_mm", 15.0, "slope"),
        ("machine.gear.cutter_head_radius_mm", -1.0, "> 0"),
        ("machine.gear.convex.inner_cutter_radius_mm", 75.0, "inner_cutter_radius_mm"),
    ],
)
def test_bad_keys_are_named(case_a, key, value, match):
    with pytest.raises(gearopt.GearoptError, match=match) as info:
        gearopt.with_overrides(case_a, {key: value})
    assert key.rsplit(".", 1)[-1] in str(info.value)


def test_missing_head_radius_is_a_design_error():
    text = CASE_A.read_text().replace("cutter_head_radius_mm = 137.4                 # both", "#")
    with pytest.raises(DesignError, match="cutter_head_radius_mm"):
        gearopt.loads_design(text)


# --- the cyclo-palloid chain reused --------------------------------------------------------------


def _epicycloid_like(cp_text: str, radii: dict[str, tuple[float, float]]) -> str:
    """The cyclo-palloid design's pair with an epicycloid machine whose flanks have the
    cyclo-palloid member's inner (convex) and outer (concave) radii, straight blades."""
    pair = cp_text[: cp_text.index("[machine]")]
    lines = ['[machine]\nmodel = "epicycloid"\nblade_groups = 5\nblade_module_mm = 3.3973\n']
    for member, (rci, rco) in radii.items():
        lines.append(f"[machine.{member}.convex]\ncutter_head_radius_mm = {rci}\n")
        lines.append(f"[machine.{member}.concave]\ncutter_head_radius_mm = {rco}\n")
        lines.append('blade_profile_radius_mm = "inf"\n')
    return pair + "\n".join(lines)


def _without_slope(text: str) -> str:
    for value in ("0.103669", "0.078489"):
        text = text.replace(f"additional_slope_angle_deg = {value}", "")
    return text


def test_straight_blade_equals_the_cyclo_palloid_flank_to_1e_9_mm():
    """Seed 001 Table 3 pair without additional slope angles (r_ci = r_co = 75 mm): the
    epicycloid flanks with R_h = 75 mm and R_b = inf are the cyclo-palloid ones, node by node."""
    cp_text = _without_slope((STUDIES / "seed001_table3.toml").read_text())
    cp = gearopt.loads_design(cp_text)
    ep = gearopt.loads_design(_epicycloid_like(cp_text, {"pinion": (75, 75), "gear": (75, 75)}))
    for member in MEMBERS:
        a = CycloPalloid().generate_flanks(cp, member=member)
        b = Epicycloid().generate_flanks(ep, member=member)
        for flank in FLANKS:
            assert np.array_equal(a[flank].mask, b[flank].mask)
            on = a[flank].mask
            gap = np.abs(a[flank].points_mm - b[flank].points_mm)[on].max()
            assert gap <= 1e-9, f"{member} {flank}: {gap:.2e} mm"
            assert np.abs(a[flank].normals - b[flank].normals)[on].max() <= 1e-12


def test_unequal_radii_same_surfaces_thickness_set_differently():
    """Seed 001 section 5.2 (pinion r_ci = 75, r_co = 76.8 mm). The convex flank (inner blades)
    is the same to 1e-9 mm. The concave flank is the same surface, but turned: the cyclo-palloid
    dual head (eccentricity e) phases its outer blades against the inner ones, while the
    epicycloid puts every flank through the pitch point M at its nominal angle."""
    cp = gearopt.load_design(STUDIES / "seed001_section5_2.toml")
    ep = gearopt.loads_design(
        _epicycloid_like(
            (STUDIES / "seed001_section5_2.toml").read_text(),
            {"pinion": (75.0, 76.8), "gear": (75.0, 75.0)},
        )
    )
    a = CycloPalloid().generate_flanks(cp, member="pinion")
    b = Epicycloid().generate_flanks(ep, member="pinion")
    on = a["convex"].mask
    assert np.abs(a["convex"].points_mm - b["convex"].points_mm)[on].max() <= 1e-9
    on = a["concave"].mask & b["concave"].mask
    turn = b["concave"].polar_angle_rad[on] - a["concave"].polar_angle_rad[on]
    assert np.ptp(turn) <= 1e-9 / 80.0  # a rigid turn about the axis
    assert abs(turn.mean()) > 1e-5  # the thickness differs (about 1 mm of arc at R = 40 mm)
    turned = a["concave"].rotated(float(turn.mean()))
    assert np.abs(turned.points_mm - b["concave"].points_mm)[on].max() <= 1e-9


# --- measured on the generated flanks ------------------------------------------------------------


def _spiral_angle_deg(fm, cone_distance_mm):
    """Angle between the tooth trace on the pitch cone and the cone's generatrix at the point
    of cone distance A_m on the pitch cone, from the exact flank normal there."""
    geo = fm.surface.geometry_at(np.array(cone_distance_mm), np.array(0.0))
    p, n = geo["point"], geo["normal"]
    r = math.hypot(p[0], p[1])
    e_theta = np.array([-p[1], p[0], 0.0]) / r
    g = p / np.linalg.norm(p)  # the generatrix (the apex at the origin)
    cone_normal = np.cross(e_theta, g)
    t = np.cross(n, cone_normal)  # the trace: in the flank and in the cone
    return math.degrees(math.atan2(abs(t @ e_theta), abs(t @ g))), float(np.linalg.norm(p))


@pytest.mark.parametrize("text", ["case_A", "case_C"])
def test_generated_spiral_angle_at_the_mean_point(text):
    design = gearopt.loads_design(CASE_A.read_text() if text == "case_A" else _case_c_text())
    am = design.blank.mean_cone_distance_mm
    for member in MEMBERS:
        for flank, fm in Epicycloid().generate_flanks(design, member=member).items():
            beta, dist = _spiral_angle_deg(fm, am)
            assert_allclose(dist, am, rtol=1e-12)  # the point is on the pitch cone at A_m
            assert abs(beta - design.pair.mean_spiral_angle_deg) < 0.01, (member, flank, beta)


def test_arc_blade_crowns_the_profile(case_a):
    """R_b = 509.634 mm: the pinion convex flank is relieved toward the tooth material above and
    below the pitch line, by (to first order) the blade's sagitta R_b (1 - cos(u / R_b)) at the
    edge point u that generates the node (u: arc length from the pitch-line point)."""
    rb = 509.634
    crowned = gearopt.with_overrides(case_a, {"machine.pinion.convex.blade_profile_radius_mm": rb})
    a = Epicycloid().generate_flank(case_a, member="pinion", flank="convex")
    b = Epicycloid().generate_flank(crowned, member="pinion", flank="convex")
    on = a.mask & b.mask
    relief = np.einsum("...k,...k->...", b.points_mm - a.points_mm, a.normals)  # out of the tooth
    assert relief[on].max() <= 1e-9
    u = b.parameters[..., 0]
    sagitta = rb * (1.0 - np.cos(u / rb))
    inner = on & (np.abs(u) > 1.0) & (np.abs(u) < 6.0)  # away from the fold near the root
    assert inner.sum() > 100
    # first order only (the contact line moves with the edge): within 5 %
    assert_allclose(-relief[inner], sagitta[inner], rtol=0.05)
    # the gear and the other flank do not change
    c = Epicycloid().generate_flank(crowned, member="pinion", flank="concave")
    d = Epicycloid().generate_flank(case_a, member="pinion", flank="concave")
    assert np.array_equal(c.points_mm, d.points_mm)


def test_arc_edge_jacobian_matches_complex_step(case_a):
    from gearopt_plugins.epicycloid import flank_system
    from gearopt_plugins.face_hobbing.family import components, meshing_jacobian

    crowned = gearopt.with_overrides(
        case_a,
        {
            "machine.pinion.convex.blade_profile_radius_mm": 300.0,
            "machine.pinion.concave.blade_profile_radius_mm": 400.0,
        },
    )
    rng = np.random.default_rng(3)
    u, theta, psi = rng.uniform(-8, 7, 30), rng.uniform(-0.4, 0.4, 30), rng.uniform(-0.5, 0.5, 30)
    for flank in FLANKS:
        b, _, _ = flank_system(crowned, "pinion", flank)
        assert b.profile_curvature_per_mm > 0.0

        def values(u_, t_, p_, b=b):
            f = components(b, u_, t_, p_)
            n = f["normal"]
            norm = np.sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2])
            return np.stack([f["axial_mm"], f["radius_mm"], f["meshing"] / (norm * 136.74)], -1)

        big_l, big_r, g, jac = meshing_jacobian(b, u, theta, psi, 136.74)
        assert_allclose(np.stack([big_l, big_r, g], -1), values(u, theta, psi), atol=1e-12)
        h = 1e-30
        for var, args in enumerate(
            ((u + 1j * h, theta, psi), (u, theta + 1j * h, psi), (u, theta, psi + 1j * h))
        ):
            assert_allclose(jac[..., var], values(*args).imag / h, atol=1e-12, err_msg=str(var))


def test_arc_edge_is_a_circle_of_radius_rb():
    from gearopt_plugins.face_hobbing.family import BladeSystem, edge

    b = BladeSystem(
        side=-1,
        cutter_radius_mm=100.0,
        assembly_angle_rad=0.1,
        machine_distance_mm=120.0,
        cradle_angle_rad=0.9,
        spiral_angle_rad=0.5,
        pressure_angle_rad=math.radians(20.0),
        rake_angle_rad=0.0,
        parabola_per_mm=0.0,
        parabola_apex_mm=0.0,
        machine_root_angle_rad=0.5,
        gear_to_cradle_roll=2.0,
        gear_to_blade_roll=0.3,
        profile_curvature_per_mm=1.0 / 250.0,
    )
    u = np.linspace(-9.0, 9.0, 41)  # u[20] = 0
    x, y, dx, dy = edge(b, u)
    straight = edge(replace_curvature(b, 0.0), u)
    # tangent to the straight edge at u = 0, unit speed (u is the arc length)
    assert_allclose((dx[20], dy[20]), (straight[2][20], straight[3][20]), atol=1e-15)
    assert_allclose(np.hypot(dx, dy), 1.0, rtol=1e-14)
    # every point 250 mm from the centre, which lies 250 mm from the pitch point along the
    # edge's normal toward the tooth material (for the outer blade: radially outward, +x_a)
    sa, ca = math.sin(b.pressure_angle_rad), math.cos(b.pressure_angle_rad)
    normal = np.array([b.side * -ca, -sa])
    centre = 250.0 * normal
    assert_allclose(np.hypot(x - centre[0], y - centre[1]), 250.0, rtol=1e-14)
    assert normal[0] > 0.0


def replace_curvature(b, k):
    from dataclasses import replace

    return replace(b, profile_curvature_per_mm=k)


# --- conjugate control ---------------------------------------------------------------------------


def test_pinion_cut_with_the_gears_cutter_is_conjugate(case_a):
    """Pinion convex with the gear's R_h = 137.4 mm and a straight blade (the coast flanks use
    137.4 mm on both members already): zero TE with the contact inside the flanks."""
    from gearopt.analysis import AnalysisOptions, contact_sides, meshed_pair

    design = gearopt.with_overrides(case_a, {"machine.pinion.convex.cutter_head_radius_mm": 137.4})
    opts = AnalysisOptions()
    sides = contact_sides(meshed_pair(design, opts), opts)
    for side in ("drive", "coast"):
        assert sides[side].te_peak_to_peak_arcsec < 0.05, side
        assert not sides[side].edge_contact, side


# --- seed 003 Tables 5-6: the maximum kinematic error through the contact engine -------------

#: seed 003's pattern: two points at equal radius 10 um apart (circumferential separation)
SEED003_ANALYSIS = {"separation": "circumferential", "compound_um": 10.0}


def _max_kinematic_error_arcsec(design, overrides) -> float:
    """The paper's (negative) maximum kinematic error: minus our TE peak-to-peak, which is taken
    at the solved hand-over between pairs (the TE maximum is 0 by convention)."""
    tca = gearopt.evaluators()["tca"]
    evaluation = tca.evaluate(gearopt.with_overrides(design, overrides), SEED003_ANALYSIS)
    assert evaluation.metrics["tca.pattern.edge_contact"] == 0.0
    return -evaluation.metrics["tca.te_peak_to_peak_arcsec"]


def test_table5_maximum_kinematic_error_against_the_blade_radius(case_a, seed_cases):
    # Table 5: R_h = 135 mm on the pinion convex flank, the blade profile radius R_b swept;
    # the tolerance 0.05 arcsec (the table prints 3 decimals)
    for row in seed_cases["epicycloid_seed003"]["table5_at_Rh_135"]:
        key = "machine.pinion.convex.blade_profile_radius_mm"
        ours = _max_kinematic_error_arcsec(case_a, {key: float(row["cutter_edge_radius_mm"])})
        assert ours == pytest.approx(row["max_kinematic_error_arcsec"], abs=0.05), row


def test_table6_maximum_kinematic_error_against_the_head_radius(case_a, seed_cases):
    # Table 6: R_b = 500 mm on the pinion convex flank, its head radius R_h swept
    for row in seed_cases["epicycloid_seed003"]["table6_at_Rb_500"]:
        overrides = {
            "machine.pinion.convex.blade_profile_radius_mm": 500.0,
            "machine.pinion.convex.cutter_head_radius_mm": row["cutter_head_radius_mm"],
        }
        ours = _max_kinematic_error_arcsec(case_a, overrides)
        assert ours == pytest.approx(row["max_kinematic_error_arcsec"], abs=0.05), row


def _drive(design, overrides):
    """The drive side's TCA with seed 003's pattern measure."""
    from gearopt.analysis import AnalysisOptions, contact_sides, meshed_pair

    trial = gearopt.with_overrides(design, overrides)
    options = AnalysisOptions.from_conditions(SEED003_ANALYSIS, design=trial)
    return contact_sides(meshed_pair(trial, options), options)["drive"]


def test_correction_classes_of_section_7(case_a, seed_cases):
    # seed 003 section 7 on its own pair: a length correction alone (case A: R_h 135 against
    # 137.4, straight blades) and a height correction alone (case B: the gear's R_h with an arc
    # blade) keep zero kinematic error; the first puts the contact across the tooth (no bias),
    # the second along it (a longitudinal pattern); both together (case C) give a parabolic one
    arc = seed_cases["epicycloid_seed003"]["pinion_convex_settings"]["case_C"]
    rb = arc["cutter_edge_radius_mm"]
    key = "machine.pinion.convex."
    length = _drive(case_a, {})
    height = _drive(
        case_a, {key + "cutter_head_radius_mm": 137.4, key + "blade_profile_radius_mm": rb}
    )
    both = _drive(case_a, {key + "blade_profile_radius_mm": rb})
    for side in (length, height):
        assert side.te_peak_to_peak_arcsec < 0.05 and not side.edge_contact
    spans = {
        name: (np.ptp(side.path_face_mm), np.ptp(side.path_profile_mm))
        for name, side in (("length", length), ("height", height))
    }
    # "no bias": the length correction's contact line crosses the tooth, its face extension
    # from entry to exit a few per cent of the face width (the height correction's: > 20 mm)
    face_mm = case_a.pair.face_width_mm
    assert spans["length"][1] > 3.0 * spans["length"][0] and abs(length.bias_mm) < 0.05 * face_mm
    assert spans["height"][0] > 3.0 * spans["height"][1] and height.bias_mm > 20.0
    amplitude = both.te_peak_to_peak_arcsec
    assert amplitude > 5.0
    h = both.handover_phi1_deg
    on = (both.phi1_deg > h[0]) & (both.phi1_deg < h[1])
    x, y = both.phi1_deg[on], both.te_arcsec[on]
    c = np.polyfit(x, y, 2)
    assert c[0] < 0.0 and np.max(np.abs(np.polyval(c, x) - y)) < 0.1 * amplitude


#: seed 003's biases need a finer profile grid than the default: the path ends where the
#: contact leaves the flanks, near the pinion's lowest generated nodes at the toe
SEED003_BIAS_ANALYSIS = {**SEED003_ANALYSIS, "grid": [41, 61]}


def _bias_cases(seed_cases_path):
    import json

    ref = json.loads(seed_cases_path.read_text())["epicycloid_seed003"]
    key = "machine.pinion.convex."
    cases = []
    for row in ref["table5_at_Rh_135"]:
        rb = float(row["cutter_edge_radius_mm"])
        cases.append((f"table5 R_b {rb:g}", {key + "blade_profile_radius_mm": rb}, row["bias_mm"]))
    for row in ref["table6_at_Rb_500"]:
        rh = row["cutter_head_radius_mm"]
        overrides = {key + "blade_profile_radius_mm": 500.0, key + "cutter_head_radius_mm": rh}
        cases.append((f"table6 R_h {rh:g}", overrides, row["bias_mm"]))
    return cases


# known gaps: none since the contact interval's ends are where the tangency point leaves the
# flanks (gearopt.mesh.SideCycle.tangency_end); before, the engine's edge flag let the contact
# slide along the pinion's top (R_h 135.6 read 42.3 against 40.406) and stopped the path of
# R_b 250 at the pinion's lowest generated cells, 2.2 mm short of the toe corner
_KNOWN_GAPS: set[str] = set()


_BIAS_CASES = [
    pytest.param(
        overrides,
        published,
        id=name,
        marks=[pytest.mark.xfail(strict=True, reason="known gap")] if name in _KNOWN_GAPS else [],
    )
    for name, overrides, published in (_bias_cases(SEED_CASES) if SEED_CASES.exists() else [])
]


@pytest.mark.parametrize(("overrides", "published"), _BIAS_CASES)
def test_tables_5_6_bias_is_the_contact_lines_extension(case_a, overrides, published):
    # seed 003 section 6: the bias is the contact line's extension along the face between the
    # pair's entry into and exit from contact; 1 mm (the tolerance); an entry of 53,
    # the face width, is a path that ends at a flank corner: at least 52.5
    trial = gearopt.with_overrides(case_a, overrides)
    bias = gearopt.evaluators()["tca"].evaluate(trial, SEED003_BIAS_ANALYSIS).metrics
    if published >= case_a.pair.face_width_mm:
        assert bias["tca.pattern.bias_mm"] >= 52.5
    else:
        assert bias["tca.pattern.bias_mm"] == pytest.approx(published, abs=1.0)


def test_contact_interval_ends_where_the_tangency_point_leaves_the_flanks(case_a):
    # Table 6, R_h 135.6: the pair enters contact where the tangency point (the solution of the
    # tangency equations, seed 003 eqs 7-8) crosses the gear's top and leaves where it crosses
    # the pinion's top; found from contact points inside, on two grids, the same to 0.01 mm.
    # The engine's own search (the least clearance by Newton steps on its stencil,
    # ClearanceField.interval_end, which the TCA's bias uses) finds the same ends as the
    # textbook solver's tangency equations: within 2e-5 rad of pinion rotation (a
    # two-hundredth of a position step) and 0.005 mm along the face (measured: 1.1e-5 rad and
    # 1e-3 mm at 41 x 61, 3e-6 rad and 2e-4 mm at 81 x 161: the difference stencil's error)
    from gearopt.analysis import AnalysisOptions, meshed_pair
    from gearopt.newton_tca import contact_interval_end

    key = "machine.pinion.convex."
    trial = gearopt.with_overrides(
        case_a, {key + "blade_profile_radius_mm": 500.0, key + "cutter_head_radius_mm": 135.6}
    )
    extensions = []
    for grid in ([41, 61], [81, 161]):
        options = AnalysisOptions.from_conditions({**SEED003_ANALYSIS, "grid": grid}, design=trial)
        field = meshed_pair(trial, options).drive
        u = np.array([-0.4, 0.35])  # inside the contact interval (about -0.455 to 0.385)
        inside = field.sample(field.sense * u)
        assert not inside.edge.any()
        entry, leave = (
            contact_interval_end(
                field,
                u[k],
                (inside.contact_face_mm[k], inside.contact_profile_mm[k]),
                toward,
                0.004,
            )
            for k, toward in ((0, -1.0), (1, 1.0))
        )
        assert entry[0] < u[0] and leave[0] > u[1]
        for k, (end, toward) in enumerate(((entry, -1.0), (leave, 1.0))):
            start = (inside.contact_face_mm[k], inside.contact_profile_mm[k])
            engine = field.interval_end(u[k], start, toward * 0.004)
            assert engine[0] == pytest.approx(end[0], abs=2e-5)
            assert engine[2] == pytest.approx(end[2][0], abs=0.005)
        assert entry[2][3] == pytest.approx(field.gear.profile_mm[-1], abs=1e-3)
        assert leave[2][1] == pytest.approx(field.pinion.profile_mm[-1], abs=1e-3)
        extensions.append(leave[2][0] - entry[2][0])
    assert extensions[0] == pytest.approx(extensions[1], abs=0.01)


#: the tip height seed 003's biases imply (it gives no tooth depth): an addendum of 6.0 mm on
#: both members (0.984 m_n), found by a least-squares fit of the addendum to the four distinct
#: designs whose path ends inside the face (closing note of the session that added this);
#: with it the six such entries agree to the printed digits, at m_n = 6.1 mm they read 0.2 to
#: 0.6 mm long
IMPLIED_ADDENDUM_MM = 6.0


@pytest.mark.parametrize(
    ("overrides", "published"),
    [case for case in _BIAS_CASES if case.values[1] < 53.0],
)
def test_tables_5_6_bias_at_the_implied_tip_height(case_a, overrides, published):
    # 0.01 mm: the published values' last digit (13.844, 40.406) and the contact interval
    # ends' grid error at 41 x 61 (0.005 mm between 41 x 61 and 81 x 161)
    tips = {"pair.outer_addendum_mm": [IMPLIED_ADDENDUM_MM, IMPLIED_ADDENDUM_MM]}
    trial = gearopt.with_overrides(case_a, {**overrides, **tips})
    bias = gearopt.evaluators()["tca"].evaluate(trial, SEED003_BIAS_ANALYSIS).metrics
    assert bias["tca.pattern.bias_mm"] == pytest.approx(published, abs=0.01)
