"""The ISO 23509 blank from basic data: published worked examples, the geometry it implies,
the checks and the ``[blank]`` table of design files."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from numpy.testing import assert_allclose

from gearopt.cli import main
from gearopt.design import pair_from_tables
from gearopt.design_files import loads_design
from gearopt.errors import DesignError
from gearopt.iso23509 import face_hobbing_circles_mm

#: the ``gearopt blank --json`` keys issue 24 names (a contract)
CONTRACT_KEYS = (
    "mean_cone_distance_mm",
    "outer_cone_distance_mm",
    "mean_normal_module_mm",
    "pitch_angle_deg",
    "face_angle_deg",
    "root_angle_deg",
    "addendum_angle_deg",
    "dedendum_angle_deg",
    "mean_addendum_mm",
    "mean_dedendum_mm",
    "outer_addendum_mm",
    "outer_dedendum_mm",
    "inner_addendum_mm",
    "inner_dedendum_mm",
    "outer_spiral_angle_deg",
    "inner_spiral_angle_deg",
    "mean_pitch_diameter_mm",
    "outer_pitch_diameter_mm",
    "outside_diameter_mm",
    "crown_to_crossing_point_mm",
    "mean_normal_circular_thickness_mm",
    "mean_normal_chordal_thickness_mm",
    "mean_chordal_addendum_mm",
    "clearance_mm",
    "mean_working_depth_mm",
    "outer_whole_depth_mm",
    "warnings",
)

PAIR_1439 = {
    "pinion_teeth": 14,
    "gear_teeth": 39,
    "mean_spiral_angle_deg": 35.0,
    "pressure_angle_deg": 20.0,
    "face_width_mm": 25.4,
    "outer_pitch_diameter_mm": 176.893,
}


#: NASA CR-191009's printed blank and settings (provenance: tests/data/README.md)
NASA_CR191009 = json.loads((Path(__file__).parent / "data" / "nasa_cr191009.json").read_text())
_NASA_BLANK = NASA_CR191009["blank"]
#: the report's 12 x 36 basic data (inches printed, mm here)
NASA_PAIR = {
    "pinion_teeth": _NASA_BLANK["pinion"]["teeth"],
    "gear_teeth": _NASA_BLANK["gear"]["teeth"],
    "mean_spiral_angle_deg": _NASA_BLANK["mean_spiral_angle_deg"],
    "pressure_angle_deg": _NASA_BLANK["pressure_angle_deg"],
    "face_width_mm": _NASA_BLANK["face_width_in"] * 25.4,
    "mean_cone_distance_mm": _NASA_BLANK["mean_cone_distance_in"] * 25.4,
}


def _blank(pair: dict, blank: dict):
    table = {"standard": "iso23509", **blank}
    _, out = pair_from_tables(pair, table)
    return out


def test_seed001_table2_from_basic_data(seed_cases):
    """Seed 001 Table 2 (ANSI/AGMA 2005-C96 applied to a cyclo-palloid pair) from its basic
    data: 16/41, m_mn 3.397 mm (the reference of this system), b 32 mm, beta_m 35 deg,
    r_c0 75 mm, z_0 5, uniform depth, equal addenda (x_hm1 = 0), dedendum 1.2 m_mn
    (k_c = 0.1), outer normal backlash 0.15 mm. The table prints three decimals: each value
    must round to the printed one (half a unit of the last digit)."""
    ref = seed_cases["cyclo_palloid_seed001"]["blank"]
    out = _blank(
        {
            "pinion_teeth": 16,
            "gear_teeth": 41,
            "mean_spiral_angle_deg": 35.0,
            "mean_normal_module_mm": 3.397,
            "face_width_mm": 32.0,
        },
        {
            "cutter_radius_mm": 75.0,
            "blade_groups": 5,
            "profile_shift_coefficient": 0.0,
            "clearance_factor": 0.1,
            "outer_normal_backlash_mm": ref["min_normal_backlash_mm"],
        },
    )
    rows = [
        ("pitch_angle_deg", out.pitch_angle_deg, ref["pitch_angle_deg"]),
        (
            "outer_transverse_module_mm",
            out.outer_transverse_module_mm,
            ref["outer_transverse_module_mm"],
        ),
        ("outer_addendum_mm", out.outer_addendum_mm, ref["outer_addendum_mm"]),
        ("outer_dedendum_mm", out.outer_dedendum_mm, ref["outer_dedendum_mm"]),
        ("face_angle_deg", out.face_angle_deg, ref["face_cone_angle_deg"]),
        ("root_angle_deg", out.root_angle_deg, ref["root_cone_angle_deg"]),
        (
            "mean_chordal_addendum_mm",
            out.mean_chordal_addendum_mm,
            ref["mean_normal_chordal_addendum_mm"],
        ),
        (
            "mean_normal_chordal_thickness_mm",
            out.mean_normal_chordal_thickness_mm,
            ref["mean_normal_chordal_thickness_mm"],
        ),
    ]
    for name, ours, printed in rows:
        print(f"{name:34s} seed 001 {printed}  gearopt {np.round(ours, 4).tolist()}")
        assert_allclose(ours, printed, atol=5e-4 + 1e-9, err_msg=name)
    # Table 2's A_m = 91.265 is printed beside m_mn = 3.397, which gives 91.257: the table's
    # cone distance carries the module's rounding (0.01 %)
    assert_allclose(out.mean_cone_distance_mm, ref["mean_cone_distance_mm"], rtol=1.5e-4)
    assert out.warnings == ()


def test_seed003_face_hobbing_circles(seed_cases):
    """Seed 003 Table 1: machine distance, base and rolling circle of the epicycloid pair
    (R_m 136.74, beta_m 29.686, m_n 6.1, z_0 5, z_p = 34 / sin 60.803) for both cutter head
    radii; printed to three decimals (two for 133.54)."""
    ref = seed_cases["epicycloid_seed003"]
    blank = ref["blank"]
    zp = blank["gear_teeth"] / math.sin(math.radians(blank["pitch_angle_deg"][1]))
    for case in (ref["pinion_convex_settings"]["case_A"], ref["gear_concave_settings"]):
        md, rho_p, rho_c = face_hobbing_circles_mm(
            mean_cone_distance_mm=blank["mean_cone_distance_mm"],
            mean_spiral_angle_deg=blank["mean_spiral_angle_deg"],
            cutter_radius_mm=case["cutter_head_radius_mm"],
            blade_groups=blank["cutter_groups"],
            mean_normal_module_mm=blank["normal_module_mm"],
            crown_gear_teeth=zp,
        )
        printed = (
            case["machine_distance_mm"],
            case["base_circle_radius_mm"],
            case["rolling_circle_radius_mm"],
        )
        print(
            f"R_h {case['cutter_head_radius_mm']}: seed 003 {printed}, gearopt "
            f"{(round(md, 4), round(rho_p, 4), round(rho_c, 4))}"
        )
        # three printed decimals, the inputs (R_m, beta_m, pitch angle) rounded too: 2e-3 mm
        assert_allclose((md, rho_p, rho_c), printed, atol=2e-3)


def test_seed003_table1_from_basic_data(seed_cases):
    """Seed 003 Table 1 (19/34 epicycloid pair): the pitch angles (three printed decimals) and
    the mean cone distance (two) from the teeth, the normal module 6.1 mm, the spiral angle
    29.686 deg and b = 53 mm; each must round to the printed value."""
    ref = seed_cases["epicycloid_seed003"]["blank"]
    out = _blank(
        {
            "pinion_teeth": ref["pinion_teeth"],
            "gear_teeth": ref["gear_teeth"],
            "mean_spiral_angle_deg": ref["mean_spiral_angle_deg"],
            "pressure_angle_deg": ref["pressure_angle_deg"],
            "mean_normal_module_mm": ref["normal_module_mm"],
            "face_width_mm": ref["face_width_mm"],
        },
        {"cutter_radius_mm": 135.0, "blade_groups": ref["cutter_groups"], "taper": "uniform"},
    )
    print(
        f"seed 003 pitch angles {ref['pitch_angle_deg']}, A_m {ref['mean_cone_distance_mm']}; "
        f"gearopt {np.round(out.pitch_angle_deg, 4).tolist()}, {out.mean_cone_distance_mm:.4f}"
    )
    assert_allclose(out.pitch_angle_deg, ref["pitch_angle_deg"], atol=5e-4 + 1e-9)
    assert_allclose(out.mean_cone_distance_mm, ref["mean_cone_distance_mm"], atol=5e-3 + 1e-9)


def test_nasa_cr191009_blank():
    """NASA CR-191009's 12 x 36 blank (pp. 4-6, tests/data/nasa_cr191009.json). The report
    prints its angles as decimals of whole arc-minutes (18.4333333 = 18 deg 26 min): the pitch
    angles from the teeth (18 deg 26.10 min, 71 deg 33.90 min) must round to the printed
    minute. Given the gear's addendum and dedendum angles (data type II), the pinion's follow
    from the constant clearance of the standard (theta_a1 = theta_f2, theta_f1 = theta_a2)
    and must equal the printed pinion angles, which the report prints in single precision
    (notes of the data file): to 1e-6 deg. The report prints no module or depths, so depths
    and thicknesses are not compared."""
    ref = _NASA_BLANK
    out = _blank(
        NASA_PAIR,
        {
            "cutter_radius_mm": 76.2,  # the gear cutter's printed blade radii: 3.0 in mean
            "gear_addendum_angle_deg": ref["gear"]["addendum_angle_deg"],
            "gear_dedendum_angle_deg": ref["gear"]["dedendum_angle_deg"],
        },
    )
    members = ("pinion", "gear")
    printed = {
        key: [ref[m][key] for m in members]
        for key in ("pitch_angle_deg", "addendum_angle_deg", "dedendum_angle_deg")
    }
    for key, ours in (
        ("pitch_angle_deg", out.pitch_angle_deg),
        ("addendum_angle_deg", out.addendum_angle_deg),
        ("dedendum_angle_deg", out.dedendum_angle_deg),
    ):
        print(f"{key:20s} CR-191009 {printed[key]}  gearopt {np.round(ours, 7).tolist()}")
    minutes = np.round(np.asarray(out.pitch_angle_deg) * 60.0) / 60.0
    assert_allclose(minutes, printed["pitch_angle_deg"], atol=1e-6)
    assert not np.allclose(out.pitch_angle_deg, printed["pitch_angle_deg"], atol=1e-3)
    assert_allclose(out.addendum_angle_deg, printed["addendum_angle_deg"], atol=1e-6)
    assert_allclose(out.dedendum_angle_deg, printed["dedendum_angle_deg"], atol=1e-6)
    assert_allclose(out.outer_cone_distance_mm, (3.191 + 0.5) * 25.4, rtol=1e-12)
    assert out.warnings == ()


def _traced_spiral_angles_deg(md, rho_p, rho_c, rc, radii):
    """Spiral angle where the cutting point's path in the crown gear plane crosses each
    radius, traced numerically: the cutter centre on a circle M_d about the crown gear's
    centre, the cutter turning (rho_p + rho_c) / rho_c times as fast (rolling circle on base
    circle); rho_c = 0 is face milling (a circle of radius r_c0 about the cutter centre)."""
    t = np.linspace(-1.5, 1.5, 200001)
    if rho_c == 0.0:
        x, y = md + rc * np.cos(t + math.pi), rc * np.sin(t + math.pi)
    else:
        k = (rho_p + rho_c) / rho_c
        x = md * np.cos(t * (1 / k)) + rc * np.cos(t + math.pi)
        y = md * np.sin(t * (1 / k)) + rc * np.sin(t + math.pi)
    r = np.hypot(x, y)
    dx, dy = np.gradient(x, t), np.gradient(y, t)
    cos_beta = np.abs(x * dx + y * dy) / (r * np.hypot(dx, dy))
    beta = np.degrees(np.arccos(np.clip(cos_beta, -1.0, 1.0)))
    order = np.argsort(r)
    inner = order[: len(order)]
    return np.interp(radii, r[inner], beta[inner])


@pytest.mark.parametrize("blank", [{"taper": "standard"}, {"blade_groups": 5}])
def test_spiral_angles_follow_the_traced_tooth_trace(blank):
    """Outer and inner spiral angles against the tooth trace traced point by point (circle
    for face milling, extended epicycloid for face hobbing); the mean spiral angle comes back
    at R_m. Tolerance 1e-3 deg: the trace's finite differences and interpolation."""
    pair = dict(PAIR_1439)
    out = _blank(pair, {"cutter_radius_mm": 76.2, **blank})
    rm = out.mean_cone_distance_mm
    rc, beta = 76.2, math.radians(35.0)
    if "blade_groups" in blank:
        md, rho_p, rho_c = face_hobbing_circles_mm(
            mean_cone_distance_mm=rm,
            mean_spiral_angle_deg=35.0,
            cutter_radius_mm=rc,
            blade_groups=5,
            mean_normal_module_mm=out.mean_normal_module_mm,
            crown_gear_teeth=39 / math.sin(math.radians(out.pitch_angle_deg[1])),
        )
    else:
        md, rho_p, rho_c = math.sqrt(rm**2 + rc**2 - 2 * rm * rc * math.sin(beta)), 0.0, 0.0
    radii = [out.inner_cone_distance_mm, rm, out.outer_cone_distance_mm]
    traced = _traced_spiral_angles_deg(md, rho_p, rho_c, rc, radii)
    ours = [out.inner_spiral_angle_deg, 35.0, out.outer_spiral_angle_deg]
    print(f"traced {traced.round(4).tolist()}, gearopt {np.round(ours, 4).tolist()}")
    assert_allclose(traced, ours, atol=1e-3)
    assert out.inner_spiral_angle_deg < 35.0 < out.outer_spiral_angle_deg


@pytest.mark.parametrize(
    "blank",
    [
        {"taper": "standard"},
        {"taper": "duplex"},
        {"taper": "tilted_root"},
        {"taper": "uniform"},
        {"gear_addendum_angle_deg": 1.5, "gear_dedendum_angle_deg": 4.0},
        {"blade_groups": 5},
    ],
)
def test_blank_geometry_is_consistent(blank):
    """What the standard's blank implies, at 1e-9 (rounding only)."""
    out = _blank(PAIR_1439, {"cutter_radius_mm": 76.2, **blank})
    d = np.radians(out.pitch_angle_deg)
    assert_allclose(sum(out.pitch_angle_deg), 90.0, atol=1e-9)
    # the gear's outer pitch diameter as given, both members on one outer cone distance
    assert_allclose(out.outer_pitch_diameter_mm[1], 176.893, atol=1e-9)
    assert_allclose(
        np.array(out.outer_pitch_diameter_mm) / 2, out.outer_cone_distance_mm * np.sin(d)
    )
    assert_allclose(np.array(out.mean_pitch_diameter_mm) / 2, out.mean_cone_distance_mm * np.sin(d))
    assert_allclose(out.outer_cone_distance_mm - out.inner_cone_distance_mm, 25.4)
    assert_allclose(out.outer_transverse_module_mm * 39, 176.893)
    # faces and roots: angle = pitch +- taper; parallel clearance (theta_a1 = theta_f2)
    assert_allclose(out.face_angle_deg, np.add(out.pitch_angle_deg, out.addendum_angle_deg))
    assert_allclose(out.root_angle_deg, np.subtract(out.pitch_angle_deg, out.dedendum_angle_deg))
    assert_allclose(out.addendum_angle_deg, out.dedendum_angle_deg[::-1])
    # depths: whole = addendum + dedendum; the working depth and the clearance at the mean
    # point, and the clearance the same at heel, mean and toe
    assert_allclose(out.outer_whole_depth_mm, np.add(out.outer_addendum_mm, out.outer_dedendum_mm))
    assert_allclose(sum(out.mean_addendum_mm), out.mean_working_depth_mm)
    for add, ded in (
        (out.outer_addendum_mm, out.outer_dedendum_mm),
        (out.mean_addendum_mm, out.mean_dedendum_mm),
        (out.inner_addendum_mm, out.inner_dedendum_mm),
    ):
        assert_allclose(np.subtract(ded, add[::-1]), out.clearance_mm, atol=1e-9)
    # the face cone passes through both tip corners (heel: the crown point), the root cone
    # through both root corners, at their angles
    for k in range(2):
        s, c = math.sin(d[k]), math.cos(d[k])
        heel = np.array([out.outer_cone_distance_mm * c, out.outer_cone_distance_mm * s])
        toe = np.array([out.inner_cone_distance_mm * c, out.inner_cone_distance_mm * s])
        up = np.array([-s, c])
        tips = heel + out.outer_addendum_mm[k] * up, toe + out.inner_addendum_mm[k] * up
        roots = heel - out.outer_dedendum_mm[k] * up, toe - out.inner_dedendum_mm[k] * up
        face = math.degrees(math.atan2(*(tips[0] - tips[1])[::-1]))
        root = math.degrees(math.atan2(*(roots[0] - roots[1])[::-1]))
        assert_allclose(face, out.face_angle_deg[k], atol=1e-9)
        assert_allclose(root, out.root_angle_deg[k], atol=1e-9)
        assert_allclose(
            tips[0], [out.crown_to_crossing_point_mm[k], out.outside_diameter_mm[k] / 2]
        )
        if blank.get("taper") == "standard":
            # standard depth: the root cone's apex is the pitch apex
            assert_allclose(roots[0][0] * roots[1][1] - roots[0][1] * roots[1][0], 0.0, atol=1e-9)
    # thickness: the two members fill the normal pitch (no backlash)
    assert_allclose(sum(out.mean_normal_circular_thickness_mm), math.pi * out.mean_normal_module_mm)


def test_depth_factors_and_their_type_ii_equivalents_agree():
    """Data type I (c_ham, k_t) and type II (x_hm1 = k_d (1 - 2 c_ham) / 2, x_smn = k_t / 2)
    give the same blank."""
    one = _blank(
        PAIR_1439,
        {
            "cutter_radius_mm": 76.2,
            "taper": "duplex",
            "mean_addendum_factor": 0.3,
            "thickness_factor": 0.06,
        },
    )
    two = _blank(
        PAIR_1439,
        {
            "cutter_radius_mm": 76.2,
            "taper": "duplex",
            "profile_shift_coefficient": 0.4,
            "thickness_modification_coefficient": 0.03,
        },
    )
    assert_allclose(one.outer_addendum_mm, two.outer_addendum_mm, rtol=1e-12)
    assert_allclose(
        one.mean_normal_circular_thickness_mm, two.mean_normal_circular_thickness_mm, rtol=1e-12
    )
    # the default c_ham = 0.210 + 0.290 / u_a with u_a = u^2 at 90 deg
    default = _blank(PAIR_1439, {"cutter_radius_mm": 76.2, "taper": "standard"})
    assert_allclose(default.mean_addendum_factor, 0.21 + 0.29 / (39 / 14) ** 2)
    # the pinion, with the long addendum, gets the thicker tooth: s1 - s2 = 4 x_hm1 m tan a
    s1, s2 = default.mean_normal_circular_thickness_mm
    x = default.profile_shift_coefficient
    assert_allclose(s1 - s2, 4 * x * default.mean_normal_module_mm * math.tan(math.radians(20)))


def test_tapers_order_their_dedendum_angle_sums():
    """Duplex taper with a large cutter (its sum grows with r_c0 as 1 - R_m sin b / r_c0)
    tapers more than standard depth; the tilted root line caps the duplex sum at 1.3 times
    the standard's; uniform has none; a smaller cutter gives a smaller duplex sum."""
    sums = {
        taper: sum(
            _blank(PAIR_1439, {"cutter_radius_mm": 114.3, "taper": taper}).dedendum_angle_deg
        )
        for taper in ("standard", "duplex", "tilted_root", "uniform")
    }
    assert sums["uniform"] == 0.0
    assert sums["duplex"] > 1.3 * sums["standard"]
    assert_allclose(sums["tilted_root"], 1.3 * sums["standard"])
    small = _blank(PAIR_1439, {"cutter_radius_mm": 63.5, "taper": "duplex"})
    assert sum(small.dedendum_angle_deg) < sums["duplex"]


def test_size_inputs_agree():
    """d_e2, m_et and m_mn of the same pair give one mean cone distance; a size that
    disagrees with another by more than 0.1 % is refused, naming both."""
    base = {k: v for k, v in PAIR_1439.items() if k != "outer_pitch_diameter_mm"}
    pair_d, _ = pair_from_tables(PAIR_1439, None)
    pair_m, _ = pair_from_tables({**base, "outer_transverse_module_mm": 176.893 / 39}, None)
    pair_n, _ = pair_from_tables(
        {**base, "mean_normal_module_mm": pair_d.mean_normal_module_mm}, None
    )
    assert_allclose(pair_m.mean_cone_distance_mm, pair_d.mean_cone_distance_mm, rtol=1e-12)
    assert_allclose(pair_n.mean_cone_distance_mm, pair_d.mean_cone_distance_mm, rtol=1e-12)
    assert_allclose(pair_d.blank.outer_pitch_radius_mm[1], 176.893 / 2, rtol=1e-12)
    with pytest.raises(DesignError, match=r"pair\.outer_transverse_module_mm.*0\.1 %"):
        pair_from_tables({**PAIR_1439, "outer_transverse_module_mm": 4.6}, None)


def test_the_checks_fire_with_their_rules():
    wide = _blank(
        {**PAIR_1439, "face_width_mm": 36.0}, {"cutter_radius_mm": 76.2, "taper": "standard"}
    )
    assert any(w.startswith("face width: b = 36.000 mm > R_e / 3") for w in wide.warnings)
    assert any("> 10 m_mn" in w for w in wide.warnings)
    # a long-addendum straight pinion of few teeth: pointed
    pointed = _blank(
        {**PAIR_1439, "pinion_teeth": 9, "gear_teeth": 45, "mean_spiral_angle_deg": 0.0},
        {"cutter_radius_mm": 76.2, "taper": "uniform", "profile_shift_coefficient": 0.9},
    )
    assert any(w.startswith("pointed tooth: the pinion's") for w in pointed.warnings)
    # a short-addendum pinion of few teeth: undercut
    cut = _blank(
        {**PAIR_1439, "pinion_teeth": 9, "gear_teeth": 45},
        {"cutter_radius_mm": 76.2, "taper": "uniform", "profile_shift_coefficient": -0.2},
    )
    assert any(w.startswith("undercut: the pinion's") for w in cut.warnings)
    assert not any(w.startswith("undercut") for w in pointed.warnings)
    # a duplex cutter far from the usual range
    big = _blank(PAIR_1439, {"cutter_radius_mm": 114.3, "taper": "duplex"})
    assert any(w.startswith("cutter radius: r_c0 = 114.3 mm") for w in big.warnings)
    # a narrow straight pair with shallow teeth cannot mesh continuously
    with pytest.raises(DesignError, match="total contact ratio"):
        _blank(
            {**PAIR_1439, "mean_spiral_angle_deg": 0.0},
            {"cutter_radius_mm": 76.2, "taper": "uniform", "depth_factor": 1.1},
        )


@pytest.mark.parametrize(
    ("pair", "blank", "parameter", "rule"),
    [
        (
            {},
            {"gear_addendum_angle_deg": 2.0, "taper": None},
            "blank.gear_dedendum_angle_deg",
            "both",
        ),
        ({}, {"taper": None}, "blank.taper", "required"),
        ({}, {"taper": "conical"}, "blank.taper", "must be one of"),
        ({}, {"blade_groups": 5}, "blank.taper", "uniform depth"),
        (
            {},
            {"mean_addendum_factor": 0.3, "profile_shift_coefficient": 0.2},
            "blank.profile_shift_coefficient",
            "not both",
        ),
        ({}, {"cutter_radius_mm": 30.0}, "blank.cutter_radius_mm", "r_c0 > R_m sin"),
        (
            {},
            {"cutter_radius_mm": 5.0, "blade_groups": 5, "taper": None},
            "blank.cutter_radius_mm",
            "blade_groups",
        ),
        (
            {},
            {"cutter_radius_mm": 20.0, "taper": "standard"},
            "blank.cutter_radius_mm",
            "no tooth trace",
        ),
        ({"outer_addendum_mm": 3.0}, {}, "pair.outer_addendum_mm", "derived by [blank]"),
        ({}, {"cutter_radius_in": 3.0}, "blank.cutter_radius_in", "millimetres"),
        ({}, {"standard": "agma2005"}, "blank.standard", "iso23509"),
    ],
)
def test_bad_blank_data_is_named(pair, blank, parameter, rule):
    table = {"standard": "iso23509", "cutter_radius_mm": 76.2, "taper": "duplex", **blank}
    table = {k: v for k, v in table.items() if v is not None}
    with pytest.raises(DesignError) as info:
        pair_from_tables({**PAIR_1439, **pair}, table)
    assert info.value.parameter == parameter
    assert rule in str(info.value)


def test_blank_command_reads_pair_and_blank_only(tmp_path, capsys):
    path = tmp_path / "d.toml"
    path.write_text(
        "[pair]\npinion_teeth = 14\ngear_teeth = 39\nmean_spiral_angle_deg = 35.0\n"
        "face_width_mm = 25.4\nouter_pitch_diameter_mm = 176.893\n"
        '[blank]\nstandard = "iso23509"\ncutter_radius_mm = 76.2\ntaper = "duplex"\n',
        encoding="utf-8",
    )
    assert main(["blank", str(path), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert set(CONTRACT_KEYS) <= set(out)
    assert isinstance(out["warnings"], list)
    for key, value in out.items():
        assert isinstance(value, str | float | list), key
    assert main(["blank", str(path)]) == 0
    assert "crown_to_crossing_point_mm" in capsys.readouterr().out
    path.write_text(path.read_text().replace("76.2", "-1.0"), encoding="utf-8")
    assert main(["blank", str(path)]) == 2
    assert "blank.cutter_radius_mm = -1.0" in capsys.readouterr().err


def test_blank_table_feeds_the_machine_model():
    """A design from basic data: the standard's blank reaches [pair] and the model (the
    cyclo-palloid model's thickness-solved slope angle reads its chordal thickness)."""
    text = """
[pair]
pinion_teeth = 16
gear_teeth = 41
mean_spiral_angle_deg = 35.0
mean_normal_module_mm = 3.397
face_width_mm = 32.0
[blank]
standard = "iso23509"
cutter_radius_mm = 75.0
blade_groups = 5
profile_shift_coefficient = 0.0
clearance_factor = 0.1
outer_normal_backlash_mm = 0.15
[machine]
model = "cyclo-palloid"
blade_groups = 5
inner_cutter_radius_mm = 75.0
"""
    design = loads_design(text)
    assert design.standard_blank is not None
    assert design.pair.outer_addendum_mm == design.standard_blank.outer_addendum_mm
    assert design.pair.mean_normal_chordal_thickness_mm == (
        design.standard_blank.mean_normal_chordal_thickness_mm
    )
    assert not design.pair.tapered


@pytest.mark.parametrize("name", ["face_milling_14x39", "cyclo_palloid_17x43", "epicycloid_19x34"])
def test_studies_from_basic_data_have_usual_blanks(name):
    """The designs of studies/iso23509 give their blank from basic data alone, inside the
    usual range (no warning) except the checks their comments name."""
    from gearopt.design_files import load_standard_blank

    from .conftest import STUDIES

    blank = load_standard_blank(STUDIES / "iso23509" / f"{name}.toml")
    assert blank.warnings == ()
    assert blank.total_contact_ratio > 1.5


def test_blank_command_needs_the_blank_table(tmp_path, capsys):
    path = tmp_path / "d.toml"
    path.write_text(
        "[pair]\npinion_teeth = 14\ngear_teeth = 39\nmean_spiral_angle_deg = 35.0\n"
        "face_width_mm = 25.4\nouter_pitch_diameter_mm = 176.893\n",
        encoding="utf-8",
    )
    assert main(["blank", str(path)]) == 2
    assert "blank: the [blank] table is required" in capsys.readouterr().err


def test_every_blank_is_finite_or_a_named_error():
    """Over a spread of pairs and blank data the blank is finite everywhere, or a
    GearoptError naming a [pair] or [blank] key: never NaN, never a bare exception."""
    rng = np.random.default_rng(24)
    outcomes = {"blank": 0, "error": 0}
    for _ in range(300):
        z1 = int(rng.integers(5, 40))
        pair = {
            "pinion_teeth": z1,
            "gear_teeth": int(rng.integers(z1, 90)),
            "shaft_angle_deg": float(rng.choice([60.0, 90.0, 100.0])),
            "mean_spiral_angle_deg": float(rng.uniform(0.0, 45.0)),
            "pressure_angle_deg": float(rng.uniform(14.0, 25.0)),
            "mean_normal_module_mm": float(rng.uniform(1.0, 10.0)),
            "face_width_mm": float(rng.uniform(5.0, 60.0)),
        }
        blank = {"standard": "iso23509", "cutter_radius_mm": float(rng.uniform(10.0, 250.0))}
        kind = int(rng.integers(0, 3))
        if kind == 0:
            blank["taper"] = str(rng.choice(["standard", "uniform", "duplex", "tilted_root"]))
        elif kind == 1:
            blank["gear_addendum_angle_deg"] = float(rng.uniform(0.0, 5.0))
            blank["gear_dedendum_angle_deg"] = float(rng.uniform(0.0, 8.0))
        else:
            blank["blade_groups"] = int(rng.integers(1, 14))
        blank["profile_shift_coefficient"] = float(rng.uniform(-0.6, 0.6))
        try:
            _, out = pair_from_tables(pair, blank)
        except DesignError as exc:
            assert exc.parameter.split(".")[0] in ("pair", "blank"), exc
            outcomes["error"] += 1
            continue
        flat = out.as_flat_dict()
        numbers = [v for k, v in flat.items() if k not in ("method", "taper", "warnings")]
        assert np.all(np.isfinite(np.hstack([np.ravel(v) for v in numbers]))), flat
        outcomes["blank"] += 1
    assert min(outcomes.values()) > 30, outcomes
