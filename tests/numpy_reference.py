"""Reference implementations in numpy of the compiled kernels' computations, for tests only:
each takes the same inputs and gives the same outputs as the production function it checks."""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from gearopt.flank import axial_plane

__all__ = ["catmull_rom_dense", "flank_point"]


def flank_point(flank, face_mm, profile_mm) -> NDArray:
    """:func:`gearopt.loaded.separations.flank_jets`'s points in numpy: ``(..., 3)`` points of a
    flank's local interpolant at grid coordinates ``(s, t)``, member frame, unturned."""
    s = np.asarray(face_mm, float)
    t = np.asarray(profile_mm, float)
    big_l, big_r = axial_plane(s, flank.height_at(s, t), math.radians(flank.pitch_angle_deg))
    theta = flank.polar_angle_local(s, t)
    return np.stack([big_r * np.cos(theta), big_r * np.sin(theta), big_l], axis=-1)


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
