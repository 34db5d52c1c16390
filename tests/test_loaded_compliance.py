"""Tooth compliance by finite elements (gearopt.loaded.compliance): the FE layer against beam
theory, the tooth model's mesh convergence, its physics and its input checks."""

from __future__ import annotations

import math

import numpy as np
import pytest

import gearopt
from gearopt.analysis import generated_flanks
from gearopt.analysis_options import TCA_GRID
from gearopt.errors import GearoptError
from gearopt.loaded import (
    DEFAULT_MESH,
    Material,
    factorise,
    kernels,
    member_compliance,
    solid_model,
    tooth_compliance,
)

from . import numpy_reference

STEEL = Material(youngs_modulus_mpa=206000.0, poisson_ratio=0.3)


@pytest.fixture(scope="module")
def section_5_3():
    design = gearopt.load_design("studies/seed001_section5_3.toml")
    pinion, gear = generated_flanks(design, TCA_GRID)
    return design, pinion, gear


def _edge_weights(n_elements: int, length_mm: float) -> np.ndarray:
    """Consistent nodal weights of a uniform traction along one edge of quadratic elements."""
    out = np.zeros(2 * n_elements + 1)
    for e in range(n_elements):
        out[2 * e : 2 * e + 3] += np.array([1.0, 4.0, 1.0]) / 6.0 * length_mm / n_elements
    return out


def test_the_hex_layer_bends_a_cantilever_as_timoshenko():
    # 40 x 10 x 10 mm block clamped at x = 0, end load P spread uniformly over x = 40
    length, height, width, load = 40.0, 10.0, 10.0, 1000.0
    n = (16, 4, 4)
    corners = np.stack(
        np.meshgrid(
            np.linspace(0.0, length, n[0] + 1),
            np.linspace(0.0, height, n[1] + 1),
            np.linspace(0.0, width, n[2] + 1),
            indexing="ij",
        ),
        axis=-1,
    )
    model = solid_model(corners, STEEL)
    factors = factorise(model, model.nodes_mm[..., 0] < 1e-9)
    forces = np.zeros(model.n_dofs)
    weights = np.outer(_edge_weights(n[1], height), _edge_weights(n[2], width))
    forces[3 * model.node_dof[-1] + 1] = load * weights / (height * width)
    deflection = forces @ factors.displacements_mm(forces) / load  # work-conjugate average
    nu, e = STEEL.poisson_ratio, STEEL.youngs_modulus_mpa
    k = 10.0 * (1.0 + nu) / (12.0 + 11.0 * nu)
    inertia, area = width * height**3 / 12.0, width * height
    beam = load * length**3 / (3.0 * e * inertia) + load * length / (
        k * STEEL.shear_modulus_mpa * area
    )
    assert deflection == pytest.approx(beam, rel=0.02)
    # and the stiffness is the symmetric matrix of an elastic body
    assert abs(model.stiffness - model.stiffness.T).max() < 1e-9 * abs(model.stiffness).max()


def test_the_tooth_compliance_is_mesh_converged(section_5_3):
    design, pinion, _ = section_5_3
    mean = design.blank.mean_cone_distance_mm
    coarse = tooth_compliance(pinion["convex"], pinion["concave"], design.blank, material=STEEL)
    fine = tooth_compliance(
        pinion["convex"],
        pinion["concave"],
        design.blank,
        material=STEEL,
        mesh=(16, 8, 4),
    )
    c0 = float(coarse.compliance_mm_per_n(mean, 0.0))
    c1 = float(fine.compliance_mm_per_n(mean, 0.0))
    print(f"mean-point compliance: default {DEFAULT_MESH} {c0:.4e}, fine {c1:.4e} mm/N")
    assert c0 == pytest.approx(c1, rel=0.03)


def test_the_influence_numbers_are_physical(section_5_3):
    design, pinion, gear = section_5_3
    mean = design.blank.mean_cone_distance_mm
    for member in (pinion, gear):
        both = member_compliance(member, design.blank, material=STEEL)
        for compliance in both.values():
            table = compliance.table_mm_per_n
            diagonal = np.diag(table)
            assert (diagonal > 0.0).all()
            # Maxwell-Betti: the FE readings (mid-surface) are symmetric within a few %, the
            # table handed over is their symmetric part
            assert compliance.asymmetry < 0.1
            np.testing.assert_array_equal(table, table.T)
            # a load at the tip bends the tooth more than one at the root
            face, profile = compliance.table_points_mm()
            column = compliance.compliance_mm_per_n(
                np.full(6, mean), np.linspace(profile[0, 0], profile[0, -1], 6)
            )
            assert (np.diff(column) > 0.0).all()
            # the interpolant reproduces the table at its points
            i = np.array([3, 17, 40])
            f, p = face.ravel()[i], profile.ravel()[i]
            np.testing.assert_allclose(
                compliance.influence_mm_per_n(f, p, f, p), table[np.ix_(i, i)], rtol=1e-9
            )


def test_the_stencils_interpolate_the_table(section_5_3):
    """The sparse stencils (16 table points a flank point) against dense Catmull-Rom weights
    built independently, the compiled influence columns against the dense product W T W^T,
    and linear fields reproduced exactly (also beyond the table, clamped onto its edge)."""
    design, pinion, _ = section_5_3
    compliance = member_compliance(pinion, design.blank, material=STEEL)["convex"]
    face, profile = compliance.table_points_mm()
    n_f, n_p = compliance.table_shape
    rng = np.random.default_rng(7)
    s = rng.uniform(face.min() - 1.0, face.max() + 1.0, 60)
    low = compliance.low_mm + compliance.low_slope * s
    t = low + rng.uniform(-0.1, 1.1, 60) * (compliance.top_mm - low)
    u = (s - compliance.face_mm[0]) / (compliance.face_mm[-1] - compliance.face_mm[0])
    v = (t - low) / (compliance.top_mm - low)
    dense = (
        numpy_reference.catmull_rom_dense(u * (n_f - 1), n_f)[:, :, None]
        * numpy_reference.catmull_rom_dense(v * (n_p - 1), n_p)[:, None, :]
    ).reshape(60, -1)
    np.testing.assert_allclose(compliance.weights(s, t), dense, atol=1e-14)
    # a field linear in the table's coordinates (face, fraction of the height)
    a, b = np.meshgrid(np.linspace(0.0, 1.0, n_f), np.linspace(0.0, 1.0, n_p), indexing="ij")
    points, w = compliance.stencil(s, t)
    interpolated = (w * (2.0 + 3.0 * a - 0.5 * b).ravel()[points]).sum(axis=1)
    expected = 2.0 + 3.0 * np.clip(u, 0.0, 1.0) - 0.5 * np.clip(v, 0.0, 1.0)
    np.testing.assert_allclose(interpolated, expected, rtol=1e-12)
    columns = np.array([0, 7, 31, 59])
    out = np.zeros((columns.size, 60))
    kernels.influence_columns(points, w, columns, compliance.table_mm_per_n, out)
    full = dense @ compliance.table_mm_per_n @ dense.T
    np.testing.assert_allclose(out.T, full[:, columns], rtol=1e-12, atol=1e-12 * full.max())


def test_both_flanks_share_one_model(section_5_3):
    design, pinion, _ = section_5_3
    a = tooth_compliance(pinion["convex"], pinion["concave"], design.blank)
    b = tooth_compliance(pinion["concave"], pinion["convex"], design.blank)
    both = member_compliance(pinion, design.blank)
    assert both["convex"] is a and both["concave"] is b
    assert (a.flank, b.flank) == ("convex", "concave")


@pytest.mark.parametrize(
    ("kwargs", "parameter"),
    [
        ({"youngs_modulus_mpa": 0.0}, "material.youngs_modulus_mpa"),
        ({"youngs_modulus_mpa": -1.0}, "material.youngs_modulus_mpa"),
        ({"poisson_ratio": 0.5}, "material.poisson_ratio"),
        ({"poisson_ratio": 0.0}, "material.poisson_ratio"),
    ],
)
def test_bad_material_is_refused(kwargs, parameter):
    with pytest.raises(GearoptError) as error:
        Material(**kwargs)
    assert error.value.parameter == parameter


@pytest.mark.parametrize(
    ("mesh", "parameter"),
    [
        ((10, 6, 1), "mesh.n_thickness"),
        ((1, 6, 3), "mesh.n_face"),
        ((10, 2, 3), "mesh.n_profile"),
        ((10, 6), "mesh"),
    ],
)
def test_a_too_coarse_mesh_is_refused(section_5_3, mesh, parameter):
    design, pinion, _ = section_5_3
    with pytest.raises(GearoptError) as error:
        tooth_compliance(pinion["convex"], pinion["concave"], design.blank, mesh=mesh)
    assert error.value.parameter == parameter


def test_the_flanks_must_bound_one_tooth(section_5_3):
    design, pinion, gear = section_5_3
    with pytest.raises(GearoptError) as error:
        tooth_compliance(pinion["convex"], gear["concave"], design.blank)
    assert error.value.parameter == "other"
    assert math.isfinite(
        float(
            tooth_compliance(
                pinion["convex"], pinion["concave"].tooth_turned(3), design.blank
            ).compliance_mm_per_n(design.blank.mean_cone_distance_mm, 0.0)
        )
    )
