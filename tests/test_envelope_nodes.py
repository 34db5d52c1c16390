"""The envelope solver's grid nodes (gearopt.envelope_nodes) against the numpy they replace:
the remembered set-up of a grid, the compiled sheet of its nodes, and the batched numpy
helpers of the generation (the unwrap and extension of gearopt.flank, the face-hobbing pitch
row), and the compiled bilinear starts of points off the nodes and their repair's nearest
converged points: the same bits."""

from __future__ import annotations

import math

import numpy as np
import pytest

from gearopt.envelope_nodes import bilinear, grid_nodes, nearest_start, sheet_nodes
from gearopt.flank import DepthTaper, FlankGrid, extended_below, unwrapped_along_face
from gearopt_plugins.face_hobbing.family import BladeSystem, pitch_line_start, pitch_line_starts

TAPER = DepthTaper(pivot_mm=60.0, root_mm=-4.0, top_mm=3.0, root_slope=-0.05, top_slope=0.04)


def _same(a, b) -> bool:
    a, b = np.asarray(a), np.asarray(b)
    return a.shape == b.shape and a.dtype == b.dtype and a.tobytes() == b.tobytes()


@pytest.mark.parametrize("taper", [None, TAPER])
def test_grid_nodes_are_the_solvers_set_up_remembered(taper):
    grid = FlankGrid(n_face=9, n_profile=7)
    nodes = grid_nodes((50.0, 70.0), (-4.0, 3.0), 0.4, grid, taper, 2)
    assert grid_nodes([50.0, 70.0], (-4.0, 3.0), 0.4, grid, taper, 2) is nodes
    s, h = np.linspace(50.0, 70.0, 9), np.linspace(-4.0, 3.0, 7)
    cg, sg = math.cos(0.4), math.sin(0.4)
    height = np.broadcast_to(h, (9, 7)) if taper is None else taper.height_mm(s[:, None], h)
    assert _same(nodes.face_mm, s) and _same(nodes.profile_mm, h)
    assert _same(nodes.height_mm, height)
    assert _same(nodes.big_l, np.broadcast_to(s[:, None] * cg - height * sg, (2, 9, 7)))
    assert _same(nodes.big_r, np.broadcast_to(s[:, None] * sg + height * cg, (2, 9, 7)))
    assert _same(nodes.row_l, np.tile(s * cg, 2)) and _same(nodes.row_r, np.tile(s * sg, 2))
    assert nodes.pitch_row == int(np.argmin(np.abs(h)))
    # the arrays the kernels take stay writable (numba types), the others are read-only
    assert nodes.big_l.flags.writeable and nodes.row_l.flags.writeable
    assert not nodes.face_mm.flags.writeable and not nodes.height_mm.flags.writeable


def _sheet_numpy(converged, det, sign0, nodes, trim_mm):
    """The solver's numpy reading that :func:`sheet_nodes` compiles."""
    h, height, j0 = nodes.profile_mm, nodes.height_mm, nodes.pitch_row
    unfolded = det == sign0[..., None]
    good = converged & unfolded
    up = np.cumprod(good[..., j0:], axis=-1).astype(bool)
    down = np.flip(np.cumprod(np.flip(good[..., : j0 + 1], axis=-1), axis=-1), axis=-1)
    connected = np.concatenate([down[..., :j0].astype(bool), up], axis=-1)
    first_bad = np.where(~connected & (h < h[j0]), height, -np.inf).max(axis=-1)
    margin = np.where(np.isfinite(first_bad), trim_mm, 0.0)
    trimmed = height >= (first_bad + margin)[..., None]
    below = ~connected & (np.arange(len(h)) < j0)
    top = np.where(below.any(axis=-1), len(h) - 1 - np.argmax(below[..., ::-1], axis=-1), -1)
    return unfolded, connected, trimmed, top


@pytest.mark.parametrize("taper", [None, TAPER])
def test_the_compiled_sheet_is_the_solvers_numpy(taper):
    rng = np.random.default_rng(7)
    for n_p, heights in ((13, (-4.0, 3.0)), (21, (-4.1, 2.9)), (6, (0.0, 3.0))):
        nodes = grid_nodes((50.0, 70.0), heights, 0.4, FlankGrid(n_face=8, n_profile=n_p), taper, 2)
        for p_bad in (0.0, 0.1, 0.4):
            converged = rng.random((2, 8, n_p)) > p_bad
            det = np.where(rng.random((2, 8, n_p)) > p_bad, 1.0, rng.choice([-1.0, 0.0, np.nan]))
            sign0 = rng.choice([1.0, -1.0], (2, 8))
            det *= sign0[..., None]
            got = sheet_nodes(converged, det, sign0, nodes, 0.3)
            ref = _sheet_numpy(converged, det, sign0, nodes, 0.3)
            for name, a, b in zip(
                ("unfolded", "connected", "trimmed", "top"), got, ref, strict=True
            ):
                assert np.array_equal(a, b), name


def test_the_flank_helpers_are_numpys():
    rng = np.random.default_rng(3)
    for k in range(300):
        shape = (1 + k % 2, 2 + k % 23, 3 + k % 19)
        p = rng.uniform(-math.pi, math.pi, shape) * (0.01, 0.5, 1.0, 3.0)[k % 4]
        if k % 3 == 0:
            p[..., k % shape[1], :] = math.pi * (-1) ** k
        assert _same(unwrapped_along_face(p), np.unwrap(p, axis=-2))
        mask = rng.random(shape) < 0.6
        got = extended_below(p, mask)
        for f in range(shape[0]):  # the per-flank numpy reading
            n_p = shape[-1]
            low = np.where(mask[f].any(axis=1), np.argmax(mask[f], axis=1), n_p - 3)
            low = np.minimum(low, n_p - 3)[:, None]
            rows = np.arange(shape[1])[:, None]
            p0, p1, p2 = p[f][rows, low], p[f][rows, low + 1], p[f][rows, low + 2]
            t = (np.arange(n_p)[None, :] - low).astype(float)
            quad = 0.5 * (t - 1) * (t - 2) * p0 - t * (t - 2) * p1 + 0.5 * t * (t - 1) * p2
            assert _same(got[f], np.where(np.arange(n_p)[None, :] < low, quad, p[f]))


def test_pitch_line_starts_are_pitch_line_start_stacked():
    base = dict(
        assembly_angle_rad=0.05,
        machine_distance_mm=70.0,
        cradle_angle_rad=0.6,
        spiral_angle_rad=0.6,
        pressure_angle_rad=0.35,
        rake_angle_rad=0.0,
        parabola_per_mm=0.001,
        parabola_apex_mm=0.0,
        machine_root_angle_rad=0.4,
        gear_to_cradle_roll=2.0,
        gear_to_blade_roll=0.3,
    )
    blades = (
        BladeSystem(side=1, cutter_radius_mm=75.0, **base),
        BladeSystem(side=-1, cutter_radius_mm=75.5, phase_rad=0.1, **base),
    )
    s = np.linspace(50.0, 70.0, 25)
    want = np.stack([np.stack(pitch_line_start(b, s), axis=-1) for b in blades])
    assert _same(pitch_line_starts(blades, s), want)


def _numpy_bilinear(face_mm, profile_mm, values, s, h):
    """The numpy form of the bilinear starts (scipy's arithmetic) that the compiled one replaced."""

    def cell(grid, x):
        k = np.clip(np.searchsorted(grid, x, side="right") - 1, 0, len(grid) - 2)
        return k, (x - grid[k]) / (grid[k + 1] - grid[k])

    (i, y0), (j, y1) = cell(face_mm, s), cell(profile_mm, h)
    a0, a1 = 1.0 - y0, 1.0 - y1
    n_p = values.shape[1]
    flat, k = values.reshape(-1, values.shape[-1]), i * n_p + j
    out = np.take(flat, k, axis=0) * (a0 * a1)[:, None]
    out += np.take(flat, k + 1, axis=0) * (a0 * y1)[:, None]
    out += np.take(flat, k + n_p, axis=0) * (y0 * a1)[:, None]
    out += np.take(flat, k + n_p + 1, axis=0) * (y0 * y1)[:, None]
    return out


def test_the_compiled_bilinear_is_numpys():
    rng = np.random.default_rng(3)
    face, profile = np.sort(rng.uniform(0.0, 30.0, 25)), np.linspace(-5.0, 6.0, 21)
    values = rng.normal(size=(25, 21, 3))
    s, h = rng.uniform(-5.0, 35.0, 400), rng.uniform(-8.0, 9.0, 400)
    s[:25], h[:21] = face, profile  # on the nodes, beyond the grid, not finite
    s[30], h[31], s[32], h[33] = math.nan, math.nan, math.inf, -math.inf
    with np.errstate(invalid="ignore"):
        want = _numpy_bilinear(face, profile, values, s, h)
    assert _same(bilinear(face, profile, values, s, h), want)


def test_the_compiled_nearest_start_is_numpys():
    rng = np.random.default_rng(5)
    face, profile = rng.uniform(0.0, 20.0, 300), rng.uniform(-6.0, 5.0, 300)
    face[:40], profile[:40] = np.round(face[:40]), np.round(profile[:40])  # equal distances
    ok = rng.uniform(size=300) < 0.7
    ds, dh, reach = 0.8, 0.5, 0.5
    bad, good = np.flatnonzero(~ok), np.flatnonzero(ok)
    gap = ((face[good][None, :] - face[bad, None]) / ds) ** 2
    gap += ((profile[good][None, :] - profile[bad, None]) / dh) ** 2
    gap[np.abs(profile[good])[None, :] > np.abs(profile[bad])[:, None]] = np.inf
    pick = np.argmin(gap, axis=1)
    near = gap[np.arange(len(bad)), pick] <= reach * reach
    got = nearest_start(face, profile, ok, ds, dh, reach)
    assert 0 < near.sum() < len(bad)
    assert _same(got[0], bad[near]) and _same(got[1], good[pick[near]])
