"""The cyclo-palloid generating family against the paper's 4x4 matrices (seed 001 eqs 2-23)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose

import gearopt
from gearopt import kinematics as k
from gearopt_plugins.face_hobbing.family import BladeSystem, family, pitch_line_start

from .conftest import STUDIES


def blade_systems(member="gear", ap=0.0015, uo=0.4, rake=0.0, offsets=(0.0, 0.0, 0.0)):
    design = gearopt.load_design(STUDIES / "seed001_section5_3.toml")
    s = gearopt.basic_settings(design).member(member)
    out = []
    for side, name in ((1, "inner"), (-1, "outer")):
        out.append(
            BladeSystem(
                side=side,
                cutter_radius_mm=getattr(s, f"{name}_cutter_radius_mm"),
                assembly_angle_rad=math.radians(getattr(s, f"{name}_assembly_angle_deg")),
                machine_distance_mm=getattr(s, f"{name}_machine_distance_mm"),
                cradle_angle_rad=math.radians(getattr(s, f"{name}_cradle_angle_deg")),
                spiral_angle_rad=math.radians(35.0),
                pressure_angle_rad=math.radians(20.0),
                rake_angle_rad=math.radians(rake),
                parabola_per_mm=ap,
                parabola_apex_mm=uo,
                machine_root_angle_rad=math.radians(s.machine_root_angle_deg),
                gear_to_cradle_roll=s.gear_to_cradle_roll,
                gear_to_blade_roll=s.gear_to_blade_roll,
                work_offset_mm=offsets,
            )
        )
    return out


def paper_chain(b: BladeSystem, u, theta, psi):
    """Work-frame point by the paper's 4x4 matrices: eqs 2, 4, 8, 16, 19, 18, 22, 21, 23."""
    a, ar = b.pressure_angle_rad, b.rake_angle_rad
    q = b.parabola_per_mm * (u - b.parabola_apex_mm) ** 2
    r_a = np.stack(
        [b.side * (-u * np.sin(a) - q * np.cos(a)), u * np.cos(a) - q * np.sin(a), 0 * u], -1
    )
    m_ba = k.rot_y(ar)  # eq 4: [cos, 0, sin; 0, 1, 0; -sin, 0, cos]
    m_cb = k.compose(k.translation([b.cutter_radius_mm, 0, 0]), k.rot_y(-b.assembly_angle_rad))
    e = b.spiral_angle_rad - b.assembly_angle_rad
    m_dc = np.array(
        [
            [math.sin(e), 0, math.cos(e), b.machine_distance_mm * math.cos(b.cradle_angle_rad)],
            [-math.cos(e), 0, math.sin(e), b.machine_distance_mm * math.sin(b.cradle_angle_rad)],
            [0, -1, 0, 0],
            [0, 0, 0, 1],
        ]
    )
    g = b.machine_root_angle_rad
    m_qm = np.array(
        [
            [math.sin(g), 0, -math.cos(g), 0],
            [0, 1, 0, 0],
            [math.cos(g), 0, math.sin(g), 0],
            [0, 0, 0, 1],
        ]
    )
    shift = k.translation(-np.asarray(b.work_origin))
    psi_g = b.gear_to_cradle_roll * psi - b.gear_to_blade_roll * theta
    m = k.compose(k.rot_z(-psi_g), m_qm, shift, k.rot_z(psi), m_dc, k.rot_y(-theta), m_cb, m_ba)
    return k.apply(m, r_a), k.compose(k.rot_z(-psi_g), m_qm)


@pytest.mark.parametrize("member", ["pinion", "gear"])
@pytest.mark.parametrize("rake", [0.0, 4.0])
def test_family_and_derivatives_match_the_paper_chain(member, rake):
    rng = np.random.default_rng(11)
    u = rng.uniform(-4, 3, 40)
    theta = rng.uniform(-0.4, 0.4, 40)
    psi = rng.uniform(-0.5, 0.5, 40)
    for b in blade_systems(member, rake=rake, offsets=(0.2, -0.3, 0.1)):
        got = family(b, u, theta, psi)
        work, rot = paper_chain(b, u, theta, psi)
        # the point: same, once taken into the work frame
        back = k.apply_vector(rot, got["point"] - b.work_origin)
        assert_allclose(back, work, atol=1e-12)
        # each partial derivative by complex step through the paper's chain
        h = 1e-30
        for name, args in (
            ("r_u", (u + 1j * h, theta, psi)),
            ("r_theta", (u, theta + 1j * h, psi)),
            ("r_psi", (u, theta, psi + 1j * h)),
        ):
            d_work = paper_chain(b, *args)[0].imag / h
            assert_allclose(k.apply_vector(rot, got[name]), d_work, atol=1e-10, err_msg=name)
        # axial-plane coordinates of the work point
        assert_allclose(got["axial_mm"], work[:, 2], atol=1e-12)
        assert_allclose(got["radius_mm"], np.hypot(work[:, 0], work[:, 1]), atol=1e-12)


@pytest.mark.parametrize("member", ["pinion", "gear"])
def test_pitch_line_start_lies_on_the_pitch_cone_and_meshes(member):
    design = gearopt.load_design(STUDIES / "seed001_section5_3.toml")
    gamma = math.radians(design.blank.pitch_angle_deg[member == "gear"])
    s = np.linspace(design.blank.inner_cone_distance_mm, design.blank.outer_cone_distance_mm, 9)
    for b in blade_systems(member, ap=0.0, uo=0.0):
        u, theta, psi = pitch_line_start(b, s)
        got = family(b, u, theta, psi)
        assert_allclose(got["axial_mm"], s * math.cos(gamma), atol=1e-11)
        assert_allclose(got["radius_mm"], s * math.sin(gamma), atol=1e-11)
        # on the instantaneous axis the relative velocity vanishes: eq 31 holds
        scale = np.linalg.norm(got["normal"], axis=-1) * design.blank.mean_cone_distance_mm
        assert np.all(np.abs(got["meshing"]) / scale < 1e-14)
        assert_allclose(np.linalg.norm(got["r_psi"], axis=-1), 0.0, atol=1e-12)


@pytest.mark.parametrize("member", ["pinion", "gear"])
def test_analytic_jacobian_matches_complex_step(member):
    from gearopt_plugins.face_hobbing.family import components, meshing_jacobian

    rng = np.random.default_rng(5)
    u, theta, psi = rng.uniform(-4, 3, 30), rng.uniform(-0.4, 0.4, 30), rng.uniform(-0.5, 0.5, 30)
    for b in blade_systems(member, rake=3.0, offsets=(0.2, -0.3, 0.1)):

        def values(u_, t_, p_, b=b):
            f = components(b, u_, t_, p_)
            n = f["normal"]
            norm = np.sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2])
            return np.stack([f["axial_mm"], f["radius_mm"], f["meshing"] / (norm * 91.265)], -1)

        big_l, big_r, g, jac = meshing_jacobian(b, u, theta, psi, 91.265)
        assert_allclose(np.stack([big_l, big_r, g], -1), values(u, theta, psi), atol=1e-12)
        h = 1e-30
        for var, args in enumerate(
            ((u + 1j * h, theta, psi), (u, theta + 1j * h, psi), (u, theta, psi + 1j * h))
        ):
            assert_allclose(jac[..., var], values(*args).imag / h, atol=1e-12, err_msg=str(var))
