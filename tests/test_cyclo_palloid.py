"""Cyclo-palloid basic settings: seed 001 Table 3, eqs 5-38 as geometry, compensation eqs 49-59."""

from __future__ import annotations

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose

import gearopt
from gearopt.testing import FlankContract
from gearopt_plugins.cyclo_palloid import CycloPalloid

from .conftest import STUDIES

MEMBERS = ("pinion", "gear")


class TestCycloPalloidContract(FlankContract):
    @pytest.fixture
    def machine_model(self):
        return CycloPalloid()

    @pytest.fixture(params=["seed001_table3.toml", "seed001_section5_3.toml"])
    def design_text(self, request):
        return (STUDIES / request.param).read_text()

    @pytest.fixture
    def exact_indexing_design_text(self, table3_text):
        # m_b = m_mn and no additional slope angle: m_gb = N_b / N exactly
        text = table3_text.replace("blade_module_mm = 3.3973", "")
        return text.replace("additional_slope_angle_deg = 0.103669", "").replace(
            "additional_slope_angle_deg = 0.078489", ""
        )


def test_table3_reproduced(table3_design, seed_cases):
    ref = seed_cases["cyclo_palloid_seed001"]["expected_table3"]
    settings = gearopt.basic_settings(table3_design).as_dict()
    for member in MEMBERS:
        got, want = settings[member], ref[member]
        # Table 3 prints distances and angles to 1e-6 but the pitch angles only to 1e-3 deg
        # (21.318 = atan(16/41) = 21.317912 to 1e-4): the tolerance, 1e-4 mm / 1e-4 deg
        for key in (
            "inner_machine_distance_mm",
            "outer_machine_distance_mm",
            "inner_cradle_angle_deg",
            "outer_cradle_angle_deg",
            "machine_root_angle_deg",
            "machine_center_to_back_mm",
            "blank_offset_mm",
            "sliding_base_mm",
        ):
            assert_allclose(got[key], want[key], rtol=0, atol=1e-4, err_msg=f"{member}.{key}")
        # roll ratios printed to 1e-6
        for key in ("gear_to_cradle_roll", "gear_to_blade_roll"):
            assert_allclose(got[key], want[key], rtol=0, atol=1e-6, err_msg=f"{member}.{key}")
        # nu printed to 1e-6 deg; m_b = 3.3973 reproduces it (seed_cases note)
        assert_allclose(got["slope_angle_deg"], ref["slope_angle_deg"], rtol=0, atol=1e-6)
    assert_allclose(
        [settings[m]["additional_slope_angle_deg"] for m in MEMBERS],
        ref["additional_slope_angle_deg"],
        rtol=0,
        atol=0,
    )


def _member_settings(**member):
    text = (STUDIES / "seed001_table3.toml").read_text()
    design = gearopt.loads_design(text)
    overrides = {f"machine.pinion.{k}": v for k, v in member.items()}
    return gearopt.basic_settings(gearopt.with_overrides(design, overrides)).pinion, design


@pytest.mark.parametrize(
    ("rci", "rco", "dnu"),
    [(75.0, 75.0, 0.0), (75.0, 76.8, 0.0), (75.0, 75.5, 0.3), (62.0, 58.0, -0.2)],
)
def test_cutter_geometry_of_fig4(rci, rco, dnu):
    """Rebuild Fig. 4 from the computed settings and check its geometry.

    Both blade systems pass through the pitch point M = (A_m, 0) at their cutter radius; the line
    from the instantaneous centre C (on O_m O_c where base and rolling circles touch) to M is
    normal to the lengthwise tooth direction, which makes psi_m with x_m; that line makes the
    slope angle with O_c M; both systems share one roll circle rho' (eq 37).
    """
    s, design = _member_settings(
        inner_cutter_radius_mm=rci, outer_cutter_radius_mm=rco, additional_slope_angle_deg=dnu
    )
    am = design.blank.mean_cone_distance_mm
    psi = math.radians(35.0)
    tangent = np.array([math.cos(psi), math.sin(psi)])
    m_point = np.array([am, 0.0])
    for k, rc in (("inner", rci), ("outer", rco)):
        md = getattr(s, f"{k}_machine_distance_mm")
        q2 = math.radians(getattr(s, f"{k}_cradle_angle_deg"))
        centre = md * np.array([math.cos(q2), math.sin(q2)])  # eq 19: (M_d cos q2, M_d sin q2)
        assert_allclose(np.linalg.norm(m_point - centre), rc, rtol=1e-13)
        rb = getattr(s, f"{k}_base_circle_radius_mm")
        rr = getattr(s, f"{k}_rolling_circle_radius_mm")
        assert_allclose(rb + rr, md, rtol=1e-13)
        c_point = centre * rb / md
        normal = m_point - c_point
        assert_allclose(normal @ tangent, 0.0, atol=1e-11 * am)
        radius = m_point - centre
        cos_slope = normal @ radius / (np.linalg.norm(normal) * np.linalg.norm(radius))
        nu_k = math.radians(getattr(s, f"{k}_assembly_angle_deg"))
        assert_allclose(cos_slope, math.cos(nu_k), rtol=1e-12)
    # one roll circle for both systems: r_ci sin nu'_i = r_co sin nu'_o
    rho_i = rci * math.sin(math.radians(s.inner_assembly_angle_deg))
    rho_o = rco * math.sin(math.radians(s.outer_assembly_angle_deg))
    assert_allclose(rho_i, rho_o, rtol=1e-13)
    assert_allclose(s.roll_circle_radius_mm, rho_i, rtol=1e-13)
    if rci == rco:
        assert s.eccentricity_mm == pytest.approx(0.0, abs=1e-12)
        assert s.inner_machine_distance_mm == pytest.approx(s.outer_machine_distance_mm, rel=1e-14)


def test_blade_roll_is_blade_groups_over_teeth_without_additional_slope():
    """Eq 30: with m_b = m_mn and dnu = 0, m_gb = N_b / N_g exactly."""
    text = (STUDIES / "seed001_table3.toml").read_text().replace("blade_module_mm = 3.3973", "")
    design = gearopt.loads_design(text)
    design = gearopt.with_overrides(
        design,
        {
            "machine.pinion.additional_slope_angle_deg": 0.0,
            "machine.gear.additional_slope_angle_deg": 0.0,
            "machine.pinion.outer_cutter_radius_mm": 77.0,
        },
    )
    settings = gearopt.basic_settings(design)
    assert_allclose(settings.pinion.gear_to_blade_roll, 5 / 16, rtol=1e-14)
    assert_allclose(settings.gear.gear_to_blade_roll, 5 / 41, rtol=1e-14)
    # the cradle/blade ratio is N_b / N_c: rolling over base circle
    s = settings.pinion
    assert_allclose(
        s.inner_rolling_circle_radius_mm / s.inner_base_circle_radius_mm,
        5 / design.blank.crown_gear_teeth,
        rtol=1e-13,
    )


def test_additional_slope_angle_changes_only_the_cutter_kinematics(table3_design):
    zero = gearopt.with_overrides(
        table3_design,
        {
            "machine.pinion.additional_slope_angle_deg": 0.0,
            "machine.gear.additional_slope_angle_deg": 0.0,
        },
    )
    base, shifted = (
        gearopt.basic_settings(zero).pinion,
        gearopt.basic_settings(table3_design).pinion,
    )
    assert base.slope_angle_deg == shifted.slope_angle_deg  # nu of eq 9 is the cutter's
    assert base.gear_to_cradle_roll == shifted.gear_to_cradle_roll  # eq 25: blank only
    assert shifted.gear_to_blade_roll > base.gear_to_blade_roll  # eq 37: larger roll circle
    # eq 34: a larger nu' lowers sin(psi_m - nu'), so the cutter centre moves away from O_m
    assert shifted.inner_machine_distance_mm > base.inner_machine_distance_mm


def test_compensation_eqs_49_to_59():
    design = gearopt.with_overrides(
        gearopt.load_design(STUDIES / "seed001_section5_4_compensated.toml"),
        {
            "machine.pinion.additional_slope_angle_deg": 0.0,
            "machine.gear.additional_slope_angle_deg": 0.0,
        },
    )
    settings = gearopt.basic_settings(design)
    p, g = settings.pinion, settings.gear
    # Hand-computed (30-digit arithmetic) for Sigma + dGamma = 89.938 deg, N2/N1 = 41/16:
    # g1' = atan(sin S' / (N2/N1 + cos S')), g2' = atan(sin S' / (N1/N2 + cos S'))  (eqs 49-52)
    assert_allclose(p.machine_root_angle_deg, 21.309709807167666, rtol=0, atol=1e-12)
    assert_allclose(g.machine_root_angle_deg, 68.628290192832334, rtol=0, atol=1e-12)
    # eqs 53-54: 1 / sin g'
    assert_allclose(p.gear_to_cradle_roll, 2.7517196257967902, rtol=1e-14)
    assert_allclose(g.gear_to_cradle_roll, 1.0738418051889913, rtol=1e-14)
    # eqs 55-56 with r_ci sin nu = 75 sin(asin(3.3973 * 5 / 150)), dnu = 0, A_m cos psi_m
    assert_allclose(p.gear_to_blade_roll, 0.31261463929679885, rtol=1e-14)
    assert_allclose(g.gear_to_blade_roll, 0.12199595679875077, rtol=1e-14)
    # eqs 57-59
    assert (p.machine_center_to_back_mm, p.blank_offset_mm, p.sliding_base_mm) == (
        -0.005,
        0.221,
        0.0,
    )
    assert (g.machine_center_to_back_mm, g.blank_offset_mm, g.sliding_base_mm) == (0.188, 0.0, 0.0)
    assert settings.notes
    # the cutter settings are kept (section 4): same as the uncompensated section 5.3 pair, whose
    # solved slope angles the 5.4 file holds (to 1e-6 deg)
    plain = gearopt.basic_settings(gearopt.load_design(STUDIES / "seed001_section5_3.toml"))
    kept = gearopt.basic_settings(
        gearopt.load_design(STUDIES / "seed001_section5_4_compensated.toml")
    )
    for member in MEMBERS:
        a, b = kept.member(member), plain.member(member)
        for key in (
            "inner_machine_distance_mm",
            "inner_cradle_angle_deg",
            "outer_machine_distance_mm",
            "outer_cradle_angle_deg",
            "eccentricity_mm",
            "slope_angle_deg",
        ):
            assert getattr(a, key) == pytest.approx(getattr(b, key), abs=1e-5), key


def test_zero_compensation_is_no_compensation(table3_design):
    zero = gearopt.with_overrides(table3_design, {"compensation.offset_mm": 0.0})
    assert gearopt.basic_settings(zero) == gearopt.basic_settings(table3_design)


def test_member_keys_in_machine_table_are_defaults_for_both(table3_design):
    design = gearopt.load_design(STUDIES / "seed001_section5_3.toml")
    for member in MEMBERS:
        spec = design.machine.member(member)
        assert (spec.inner_cutter_radius_mm, spec.outer_cutter_radius_mm) == (75.0, 75.5)
    assert design.machine.pinion.blade_parabola_coefficient_per_mm == 0.0015
