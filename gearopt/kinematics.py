"""4x4 homogeneous transforms, vectorised over leading axes.

Every function takes angles or offsets of any shape ``S`` and returns matrices of shape
``S + (4, 4)``; :func:`compose` multiplies chains with broadcasting and :func:`apply` maps points
of shape ``S + (3,)``. Complex inputs are kept complex, so derivatives of a whole transformation
chain can be taken by complex step (exact to machine precision, no step-size tuning).

Sign conventions are those of the right-hand rule: ``rot_z(a)`` turns a point by ``a`` about +z,
which is seed 001's M_md (eq 18); its M_gq (eq 21) is ``rot_z(-psi_g)`` and M_ck',ck (eq 16) is
``rot_y(-theta)``.
"""

from __future__ import annotations

from functools import reduce

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = [
    "rot_x",
    "rot_y",
    "rot_z",
    "translation",
    "compose",
    "apply",
    "apply_vector",
    "invert_rigid",
]

_AXES = {"x": (1, 2), "y": (2, 0), "z": (0, 1)}


def _rotation(axis: str, angle: ArrayLike) -> NDArray:
    angle = np.asarray(angle)
    dtype = np.result_type(angle.dtype, np.float64)
    out = np.zeros(angle.shape + (4, 4), dtype=dtype)
    i, j = _AXES[axis]
    k = 3 - i - j
    c, s = np.cos(angle), np.sin(angle)
    out[..., i, i] = c
    out[..., j, j] = c
    out[..., i, j] = -s
    out[..., j, i] = s
    out[..., k, k] = 1.0
    out[..., 3, 3] = 1.0
    return out


def rot_x(angle: ArrayLike) -> NDArray:
    """Rotation by ``angle`` (rad) about +x."""
    return _rotation("x", angle)


def rot_y(angle: ArrayLike) -> NDArray:
    """Rotation by ``angle`` (rad) about +y."""
    return _rotation("y", angle)


def rot_z(angle: ArrayLike) -> NDArray:
    """Rotation by ``angle`` (rad) about +z."""
    return _rotation("z", angle)


def translation(offset: ArrayLike) -> NDArray:
    """Translation by ``offset`` of shape ``S + (3,)``."""
    offset = np.asarray(offset)
    if offset.shape[-1:] != (3,):
        raise ValueError(f"offset must have a last axis of length 3, got shape {offset.shape}")
    dtype = np.result_type(offset.dtype, np.float64)
    out = np.zeros(offset.shape[:-1] + (4, 4), dtype=dtype)
    out[..., [0, 1, 2, 3], [0, 1, 2, 3]] = 1.0
    out[..., :3, 3] = offset
    return out


def compose(*matrices: ArrayLike) -> NDArray:
    """Product ``M1 @ M2 @ ...`` with broadcasting over leading axes (applied right to left)."""
    if not matrices:
        return np.eye(4)
    return reduce(np.matmul, (np.asarray(m) for m in matrices))


def apply(matrix: ArrayLike, points: ArrayLike) -> NDArray:
    """Map points ``S + (3,)`` by homogeneous matrices ``S' + (4, 4)`` (broadcast)."""
    matrix, points = np.asarray(matrix), np.asarray(points)
    return np.einsum("...ij,...j->...i", matrix[..., :3, :3], points) + matrix[..., :3, 3]


def apply_vector(matrix: ArrayLike, vectors: ArrayLike) -> NDArray:
    """Map free vectors (normals, tangents): the rotation part only."""
    matrix = np.asarray(matrix)
    return np.einsum("...ij,...j->...i", matrix[..., :3, :3], np.asarray(vectors))


def invert_rigid(matrix: ArrayLike) -> NDArray:
    """Inverse of a rigid transform [R t; 0 1]: [R^T, -R^T t; 0 1]."""
    matrix = np.asarray(matrix)
    out = np.zeros_like(matrix)
    rt = np.swapaxes(matrix[..., :3, :3], -1, -2)
    out[..., :3, :3] = rt
    out[..., :3, 3] = -np.einsum("...ij,...j->...i", rt, matrix[..., :3, 3])
    out[..., 3, 3] = 1.0
    return out
