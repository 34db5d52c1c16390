"""NASA CR-191009's face-milled 12 x 36 pair entered as printed (``studies/nasa_cr191009.toml``).

The design file must be the report's numbers (``tests/data/nasa_cr191009.json``) converted by the
rules of ``docs/printed_settings.md``, and those rules are derived from the report's own
generating model: the transformation chain of its program (POINTS.F, subroutine TRANSF, printed
pp. 25-33: cutter turned by h q about the cradle axis, the radial setting, the cradle roll, the
dedendum-angle tilt, the apex shift L_m and blank offset h E_m, the pitch angle, the work roll;
h = +1 pinion, -1 gear). :func:`report_point` re-implements that chain in numpy, independently
of gearopt's face-milling family, and the flanks gearopt generates from the design file must be
the report's surfaces: the same normals and the same polar angles (modulo the tooth pitch) at
points of the report's own grid. A wrong sign of q, E_m or L_m, the wrong hand, blade reading or
apex moves them by tenths of a degree or more.

The physics of the pair read that way (measured, not assumed): at the mean point of the pitch
cones (the pitch line, where the relative velocity vanishes, so flanks in mesh there must share
their normal) the mating flanks have the same spiral angle on both sides, but the pinion's
pressure angle is about 0.5 deg below the gear's on both sides: the printed pinion is not
first-order tangent to the printed gear at its mean point, as a local synthesis would make it.
Since the surfaces are the report's own, this is a property of the printed numbers, not of their
conversion (docs/printed_settings.md, "NASA CR-191009", gives the evidence).
"""

from __future__ import annotations

import json
import math
import tomllib
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import fsolve

from gearopt.design_files import load_design, parse_design
from gearopt.flank import FlankGrid
from gearopt.plugins import get_machine_model

ROOT = Path(__file__).resolve().parents[1]
DESIGN = ROOT / "studies" / "nasa_cr191009.toml"
PRINTED = ROOT / "tests" / "data" / "nasa_cr191009.json"
MM_PER_IN = 25.4
#: the report's program converted degrees with single-precision pi
EFFECTIVE = 3.1415927410125732 / math.pi
FLANK_OF = {"flank_1": "concave", "flank_2": "convex"}  # outside blade, inside blade
TEETH = {"pinion": 12, "gear": 36}
#: the pinion flank and the gear flank it meets
MATES = (("concave", "convex"), ("convex", "concave"))
GRID = FlankGrid(n_face=5, n_profile=5)
#: points of the report's grid (face fraction toe -> heel, height fraction over the working depth)
SECTIONS = ((0.25, 0.25), (0.25, 0.75), (0.75, 0.25), (0.75, 0.75), (0.5, 0.5))


def converted(entry: dict, flank: str) -> dict:
    """One printed flank setting in gearopt's keys (docs/printed_settings.md): q and E_m as
    printed (the report's h = +1 pinion frame is the mirror image of its gear frame, so both
    are right-hand numbers), the pitch apex at -L_m along x_m."""
    psi = entry["psi_deg"] * EFFECTIVE  # the program's trigonometry sees psi, not 180 - psi
    alpha = 180.0 - psi if flank == "concave" else psi
    return {
        "cutter_point_radius_mm": entry["r"] * MM_PER_IN,
        "blade_pressure_angle_deg": alpha,
        "radial_setting_mm": entry["s"] * MM_PER_IN,
        "cradle_angle_deg": entry["q_deg"] * EFFECTIVE,
        "blank_offset_mm": entry["E_m"] * MM_PER_IN,
        "ratio_of_roll": entry["m_cw"],
        "apex_shift_mm": -entry["L_m"] * MM_PER_IN,
    }


@pytest.fixture(scope="module")
def printed() -> dict:
    return json.loads(PRINTED.read_text())


@pytest.fixture(scope="module")
def source() -> dict:
    return tomllib.loads(DESIGN.read_text())


def test_design_is_the_printed_summary_converted(printed):
    design = load_design(DESIGN)
    blank = printed["blank"]
    assert design.pair.mean_cone_distance_mm == pytest.approx(
        blank["mean_cone_distance_in"] * MM_PER_IN, rel=1e-12
    )
    assert design.pair.face_width_mm == pytest.approx(blank["face_width_in"] * MM_PER_IN)
    for member in ("pinion", "gear"):
        data = blank[member]
        root_deg = (data["pitch_angle_deg"] - data["dedendum_angle_deg"]) * EFFECTIVE
        face_deg = (data["pitch_angle_deg"] + data["addendum_angle_deg"]) * EFFECTIVE
        index = ("pinion", "gear").index(member)
        assert design.blank.root_angle_deg[index] == pytest.approx(root_deg, abs=1e-9)
        assert design.blank.face_angle_deg[index] == pytest.approx(face_deg, abs=1e-9)
        # root apex at the pitch apex: the outer dedendum on the exact pitch cone
        pitch = design.blank.pitch_angle_deg[index]
        outer = design.blank.outer_cone_distance_mm
        assert design.blank.outer_dedendum_mm[index] == pytest.approx(
            outer * math.tan(math.radians(pitch - root_deg)), abs=1e-8
        )
        for key, flank in FLANK_OF.items():
            entry = printed["settings"][f"{member}_{key}"]
            spec = design.machine.member(member).flank(flank)
            want = converted(entry, flank)
            for name in (
                "cutter_point_radius_mm",
                "blade_pressure_angle_deg",
                "radial_setting_mm",
                "cradle_angle_deg",
                "blank_offset_mm",
                "ratio_of_roll",
            ):
                assert getattr(spec, name) == pytest.approx(want[name], rel=1e-9, abs=1e-9), (
                    member,
                    flank,
                    name,
                )
            assert spec.machine_root_angle_deg == pytest.approx(root_deg, abs=1e-9)
            gamma = math.radians(spec.machine_root_angle_deg)
            # the apex shift along x_m: centre to back L / cos, sliding base L tan
            assert spec.machine_center_to_back_mm == pytest.approx(
                want["apex_shift_mm"] / math.cos(gamma), abs=1e-9
            )
            assert spec.sliding_base_mm == pytest.approx(
                want["apex_shift_mm"] * math.tan(gamma), abs=1e-9
            )


def _rotation(axis: int, angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    i, j = [(1, 2), (2, 0), (0, 1)][axis]
    out = np.eye(3)
    out[i, i], out[i, j], out[j, i], out[j, j] = c, -s, s, c
    return out


def program_radians(degrees: float) -> float:
    """A printed angle as the report's program took it (single-precision pi)."""
    return math.radians(degrees * EFFECTIVE)


def report_point(entry: dict, data: dict, member: str, u: float, theta: float, phi: float):
    """The report's generated family (TRANSF of POINTS.F), inches, radians: the cutter cone
    (axis x, tip plane x = 0, radius u sin(psi), u from the cone's apex) carried to the work
    frame (z the work axis from the pitch apex) at cradle roll ``phi``."""
    h = 1.0 if member == "pinion" else -1.0
    psi, q = program_radians(entry["psi_deg"]), program_radians(entry["q_deg"])
    delta = program_radians(data["dedendum_angle_deg"])
    mu = program_radians(data["pitch_angle_deg"])
    s_psi, c_psi = math.sin(psi), math.cos(psi)
    x = np.array([entry["r"] * c_psi / s_psi - u * c_psi, u * s_psi * math.sin(theta)])
    x = np.append(x, u * s_psi * math.cos(theta))
    x = _rotation(0, h * q) @ x
    x = x + [0.0, -h * entry["s"] * math.sin(q), entry["s"] * math.cos(q)]
    x = _rotation(1, -delta) @ (_rotation(0, -h * phi) @ x)
    x = x + [-entry["L_m"] * math.sin(delta), h * entry["E_m"], entry["L_m"] * math.cos(delta)]
    return _rotation(2, -h * phi / entry["m_cw"]) @ (_rotation(1, mu) @ x)


def report_section(data: dict, blank: dict, face: float, height: float) -> tuple[float, float]:
    """(axial, radius) in inches of a point of the report's grid: ``face`` from toe (0) to heel
    (1), ``height`` from the mate's face cone (the root cone offset by the clearance) to the
    face cone."""
    delta, mu = (
        program_radians(data["dedendum_angle_deg"]),
        program_radians(data["pitch_angle_deg"]),
    )
    addendum = program_radians(data["addendum_angle_deg"])
    gamma, clearance = mu - delta, data["clearance_in"]
    toe = (blank["mean_cone_distance_in"] - blank["face_width_in"] / 2.0) * math.cos(delta)
    axial = (toe + face * blank["face_width_in"]) * math.cos(gamma) - clearance * math.sin(gamma)
    radius = axial * math.tan(gamma) + clearance / math.cos(gamma)
    depth = axial * math.tan(addendum + delta) / math.cos(gamma) - clearance
    return axial - height * depth * math.sin(gamma), radius + height * depth * math.cos(gamma)


def report_flank(printed: dict, member: str, key: str, face: float, height: float):
    """The report's flank point and unit normal (inches) at a point of its grid: the envelope of
    :func:`report_point` (normal . d/dphi = 0, derivatives by central differences)."""
    entry, data = printed["settings"][f"{member}_{key}"], printed["blank"][member]
    axial, radius = report_section(data, printed["blank"], face, height)
    h = 1.0 if member == "pinion" else -1.0
    q = program_radians(entry["q_deg"])
    mean = printed["blank"]["mean_cone_distance_in"]
    # seed: the edge point in the tip plane pointing from the cutter centre to the mean point
    theta0 = h * q + math.atan2(h * entry["s"] * math.sin(q), mean - entry["s"] * math.cos(q))
    u0 = entry["r"] / math.sin(program_radians(entry["psi_deg"]))
    step = 1e-6

    def geometry(x):
        p = report_point(entry, data, member, *x)
        d = [
            (
                report_point(entry, data, member, *(x + e))
                - report_point(entry, data, member, *(x - e))
            )
            / (2 * step)
            for e in np.eye(3) * step
        ]
        normal = np.cross(d[0], d[1])
        return p, normal / np.linalg.norm(normal), d[2]

    def residual(x):
        p, n, dphi = geometry(x)
        return [p[2] - axial, math.hypot(p[0], p[1]) - radius, n @ dphi]

    solution, info, ier, message = fsolve(residual, [u0, theta0, 0.0], xtol=1e-13, full_output=True)
    assert np.abs(residual(solution)).max() < 1e-8, (member, key, face, height, message)
    point, normal, _ = geometry(solution)
    return point, normal


def cylindrical(point: np.ndarray, normal: np.ndarray) -> tuple[float, np.ndarray]:
    """Polar angle of ``point`` about the axis z and ``normal``'s (radial, tangential, axial)
    components there (invariant under a turn of the member about its axis)."""
    polar = math.atan2(point[1], point[0])
    radial = np.array([math.cos(polar), math.sin(polar), 0.0])
    around = np.array([-math.sin(polar), math.cos(polar), 0.0])
    return polar, np.array([normal @ radial, normal @ around, normal[2]])


def gearopt_flanks(design, member: str) -> dict:
    model = get_machine_model(design.model)
    return model.generate_flanks(design, member=member, grid=GRID)


def surface_misfit(printed: dict, design, member: str) -> dict[str, tuple[float, float]]:
    """Per flank of ``member``: the largest angle (deg) between gearopt's normal and the
    report's at the points of :data:`SECTIONS`, and the largest difference (deg) of their
    polar angles there, modulo the tooth pitch, less its mean (a common turn of the work)."""
    maps = gearopt_flanks(design, member)
    pitch = 2.0 * math.pi / TEETH[member]
    out = {}
    for key, flank in FLANK_OF.items():
        angles, phases = [], []
        for face, height in SECTIONS:
            point_in, normal_r = report_flank(printed, member, key, face, height)
            point_mm = point_in * MM_PER_IN
            fm = maps[flank]
            s, t = fm.to_grid(point_mm[2], math.hypot(point_mm[0], point_mm[1]))
            geo = fm.surface.geometry_at(float(s), float(t))
            polar_g, n_g = cylindrical(np.asarray(geo["point"]), np.asarray(geo["normal"]))
            polar_r, n_r = cylindrical(point_mm, normal_r)
            cosine = abs(float(n_g @ n_r))
            angles.append(math.degrees(math.acos(min(1.0, cosine))))
            phases.append(polar_g - polar_r)
        phases = np.unwrap(np.asarray(phases))
        spread = np.abs(phases - phases.mean()).max()
        offset = (phases.mean() + 0.5 * pitch) % pitch - 0.5 * pitch
        out[flank] = (max(angles), math.degrees(spread), math.degrees(offset))
    return out


@pytest.mark.parametrize("member", ["pinion", "gear"])
def test_flanks_are_the_reports_surfaces(printed, source, member):
    found = surface_misfit(printed, parse_design(source), member)
    for flank, (angle_deg, spread_deg, offset_deg) in found.items():
        # the same surface: normals (central differences in the chain: 1e-6 deg) and polar
        # angles agree at every point of the report's grid, and so does the work's phase
        # modulo the pitch (the tooth thickness the report cut)
        assert angle_deg < 1e-4, (member, flank, found)
        assert spread_deg < 1e-7, (member, flank, found)
        assert abs(offset_deg) < 1e-7, (member, flank, found)


@pytest.mark.parametrize(
    "keys",
    [
        ("blank_offset_mm",),  # E_m negated
        ("machine_center_to_back_mm", "sliding_base_mm"),  # the apex at +L_m
        ("cradle_angle_deg", "blank_offset_mm"),  # the pinion read in the gear's frame
    ],
)
def test_another_sign_is_not_the_reports_surface(printed, source, keys):
    data = json.loads(json.dumps(source))
    for flank in ("concave", "convex"):
        for key in keys:
            data["machine"]["pinion"][flank][key] *= -1.0
    found = surface_misfit(printed, parse_design(data), "pinion")
    assert all(angle > 0.1 for angle, _, _ in found.values()), found


def pitch_point_angles(maps: dict, design, member: str, flank: str) -> tuple[float, float]:
    """(pressure angle, spiral angle) in degrees of a flank where it crosses the pitch cone at
    the mean cone distance, from its exact envelope: the normal's elevation out of the pitch
    cone's tangent plane and the tooth line's angle to the pitch generatrix."""
    index = ("pinion", "gear").index(member)
    gamma = math.radians(design.blank.pitch_angle_deg[index])
    am = design.blank.mean_cone_distance_mm
    fm = maps[flank]
    s, t = fm.to_grid(am * math.cos(gamma), am * math.sin(gamma))
    assert fm.surface.generated_at(float(s), float(t))
    geo = fm.surface.geometry_at(float(s), float(t))
    polar, (radial, around, axial) = cylindrical(np.asarray(geo["point"]), geo["normal"])
    off_cone = math.cos(gamma) * radial - math.sin(gamma) * axial
    along = math.sin(gamma) * radial + math.cos(gamma) * axial
    return math.degrees(math.asin(abs(off_cone))), math.degrees(math.atan2(abs(along), abs(around)))


def test_mean_point_tangency_of_the_printed_pair(source):
    """Mating flanks in mesh at the pitch line must have one normal there. The printed pair, read
    as the report's own surfaces (above), has it lengthwise (the spiral angles agree on both
    sides) but not in profile: the pinion's pressure angle is below the gear's by the same
    amount on both sides, a first-order error common to both flanks (every sign of E_m or L_m
    moves the two sides apart instead). A local synthesis leaves none: the printed pinion is
    not one for this gear (docs/printed_settings.md)."""
    design = parse_design(source)
    maps = {member: gearopt_flanks(design, member) for member in ("pinion", "gear")}
    rows = []
    for pinion_flank, gear_flank in MATES:
        p = pitch_point_angles(maps["pinion"], design, "pinion", pinion_flank)
        g = pitch_point_angles(maps["gear"], design, "gear", gear_flank)
        rows.append((p[0] - g[0], p[1] - g[1]))
    found = np.array(rows)
    assert np.all(np.abs(found[:, 1]) < 0.1), found  # lengthwise tangent on both sides
    assert abs(found[0, 0] - found[1, 0]) < 0.1, found  # one profile misfit, common to both
    assert np.all(found[:, 0] < -0.3), found  # and not zero: no tangency at the mean point
