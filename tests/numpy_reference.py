"""Reference implementations in numpy of the compiled kernels' computations, for tests only:
each takes the same inputs and gives the same outputs as the production function it checks."""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from gearopt.flank import axial_plane

__all__ = ["flank_point", "widths"]


def flank_point(flank, face_mm, profile_mm) -> NDArray:
    """:func:`gearopt.loaded.separations.flank_jets`'s points in numpy: ``(..., 3)`` points of a
    flank's local interpolant at grid coordinates ``(s, t)``, member frame, unturned."""
    s = np.asarray(face_mm, float)
    t = np.asarray(profile_mm, float)
    big_l, big_r = axial_plane(s, flank.height_at(s, t), math.radians(flank.pitch_angle_deg))
    theta = flank.polar_angle_local(s, t)
    return np.stack([big_r * np.cos(theta), big_r * np.sin(theta), big_l], axis=-1)


def widths(sep_mm: NDArray, compound_mm, face_mm, profile_mm, points, directions) -> NDArray:
    """:func:`gearopt.mesh.pattern.widths` in numpy: the extent of {separation < compound}
    along the line through ``points[k]`` perpendicular to ``directions[k]`` on the field
    ``sep_mm[k]`` (``(K, n_f, n_p)``), for K lines at once, by bilinear interpolation of the
    node field (sampled at 2001 points; from the middle outward, the first sample out of the
    zone on each side bounds it). Every 25th sample first, then all of them up to the first
    coarse one out of the zone: the same samples and arithmetic as the kernel's walk, so the
    same widths."""
    points, directions = np.asarray(points, float), np.asarray(directions, float)
    n_lines = len(sep_mm)
    perp = np.stack([-directions[:, 1], directions[:, 0]], axis=1)
    reach = float(face_mm[-1] - face_mm[0] + profile_mm[-1] - profile_mm[0])
    tau = np.linspace(-reach, reach, 2001)
    big = 10.0 * compound_mm
    f = np.where(np.isfinite(sep_mm), np.minimum(sep_mm, big), big)
    flat, n_p, size = f.ravel(), f.shape[2], f.shape[1] * f.shape[2]

    def value(line, k):
        """The interpolated separation minus the compound at the samples ``k`` of lines
        ``line``."""
        tk = tau[k]
        s = points[line, 0] + tk * perp[line, 0]
        h = points[line, 1] + tk * perp[line, 1]
        inside = (s >= face_mm[0]) & (s <= face_mm[-1])
        inside &= (h >= profile_mm[0]) & (h <= profile_mm[-1])
        i = np.minimum(np.maximum(np.searchsorted(face_mm, s) - 1, 0), len(face_mm) - 2)
        j = np.minimum(np.maximum(np.searchsorted(profile_mm, h) - 1, 0), len(profile_mm) - 2)
        s0, h0 = face_mm[i], profile_mm[j]
        u = np.minimum(np.maximum((s - s0) / (face_mm[i + 1] - s0), 0.0), 1.0)
        v = np.minimum(np.maximum((h - h0) / (profile_mm[j + 1] - h0), 0.0), 1.0)
        at = line * size + i * n_p + j
        val = (
            (1 - u) * (1 - v) * flat[at]
            + u * (1 - v) * flat[at + n_p]
            + (1 - u) * v * flat[at + 1]
            + u * v * flat[at + n_p + 1]
        )
        val[~inside] = big
        val -= compound_mm
        return val

    centre = len(tau) // 2
    # from the middle outward on each side: every 25th sample, then all of them up to the
    # first coarse one out of the zone (or to the end), each side's first sample out bounds it
    ways = (np.arange(centre, len(tau)), np.arange(centre, -1, -1))
    coarse = np.concatenate([w[::25] for w in ways])
    n_coarse = len(coarse) // 2
    lines = np.repeat(np.arange(n_lines), len(coarse))
    val = value(lines, np.tile(coarse, n_lines)).reshape(n_lines, 2, n_coarse)
    hits = val >= 0.0
    spans = [
        ways[w] if not hits[k, w].any() else ways[w][: 25 * np.argmax(hits[k, w]) + 1]
        for k in range(n_lines)
        for w in (0, 1)
    ]
    fine_lines = np.repeat(np.repeat(np.arange(n_lines), 2), [len(a) for a in spans])
    fine = np.split(
        value(fine_lines, np.concatenate(spans)), np.cumsum([len(a) for a in spans])[:-1]
    )
    width = np.zeros(n_lines)
    for k in range(n_lines):
        if val[k, 0, 0] >= 0.0:
            continue
        ends = []
        for span, v, edge in zip(
            spans[2 * k : 2 * k + 2], fine[2 * k : 2 * k + 2], (tau[-1], tau[0]), strict=True
        ):
            out = np.flatnonzero(v >= 0.0)
            if not out.size:
                ends.append(edge)
                continue
            k_in, k_out, a, b = span[out[0] - 1], span[out[0]], v[out[0] - 1], v[out[0]]
            ends.append(tau[k_in] + (tau[k_out] - tau[k_in]) * a / (a - b))
        width[k] = ends[0] - ends[1]
    return width


def catmull_rom_dense(x, n: int) -> NDArray:
    """``(m, n)`` dense Catmull-Rom weights on nodes 0..n-1 at index coordinates ``x``
    (clamped; linear ghost nodes at both ends): the numpy reference of
    ``ToothCompliance.stencil`` (each node's weight, the ghosts folded in)."""
    x = np.clip(np.asarray(x, float).ravel(), 0.0, n - 1.0)
    i = np.minimum(x.astype(np.intp), n - 2)
    f = (x - i)[:, None]
    w = 0.5 * np.hstack(
        [-(f**3) + 2 * f**2 - f, 3 * f**3 - 5 * f**2 + 2, -3 * f**3 + 4 * f**2 + f, f**3 - f**2]
    )
    out = np.zeros((len(x), n + 2))
    np.add.at(out, (np.arange(len(x))[:, None], i[:, None] + np.arange(4)), w)
    inner = out[:, 1:-1]  # column k of out is node k - 1
    inner[:, :2] += out[:, :1] * np.array([2.0, -1.0])
    inner[:, -2:] += out[:, -1:] * np.array([-1.0, 2.0])
    return inner
