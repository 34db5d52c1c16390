"""The per-row constants of the contact engine's compiled kernels (numba; plain Python without
it, as :mod:`gearopt.contact.kernels`): :func:`row_constants`, the tables of rows (side, pinion
angle, gear angle) in one compiled pass, where numpy's fixed cost per call exceeded the work on
the few dozen rows of a sample."""

from __future__ import annotations

import numpy as np

from gearopt.jit import ENABLED, compiled

__all__ = ["ENABLED", "row_constants"]


@compiled
def row_constants(maker, side, phi, angle):
    """The constants of rows (side ``side[r]``, pinion angle ``phi[r]``, gear angle
    ``angle[r]``) as the kernels take them (:func:`clearance_at`): ``kx``, ``ky`` ``(4, n)``,
    the gear's turn, its sense, the gear's and the pinion's cell offsets ``(n,)``. ``maker``:
    the rotation table ``(8, 2)`` (:meth:`gearopt.contact.engine.ContactEngine._linear_maps`),
    each side's gear turn at phi = 0 and gear sense ``(sides,)``, the ratio, the cells per side
    of the gear's and the pinion's tables. The same operations as the engine's numpy rows."""
    rotation, turn0, gear_sense, ratio, gear_cells, pinion_cells = maker
    n = phi.shape[0]
    kx, ky = np.empty((4, n)), np.empty((4, n))
    turn, sense = np.empty(n), np.empty(n)
    offset, pinion_offset = np.empty(n, np.intp), np.empty(n, np.intp)
    for r in range(n):
        c, s = np.cos(phi[r]), np.sin(phi[r])
        for i in range(4):
            kx[i, r] = rotation[i, 0] * c + rotation[i, 1] * s
            ky[i, r] = rotation[i + 4, 0] * c + rotation[i + 4, 1] * s
        k = side[r]
        turn[r] = (angle[r] + turn0[k]) - ratio * phi[r]
        sense[r] = gear_sense[k]
        offset[r] = k * gear_cells
        pinion_offset[r] = k * pinion_cells
    return kx, ky, turn, sense, offset, pinion_offset
