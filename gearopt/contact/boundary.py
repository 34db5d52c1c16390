"""The pinion's interpolant near its generated boundary, on finer cells of the exact surface.

Toward the root the pinion's flank ends ``fold_trim_mm`` (0.3 mm) above the envelope's fold
(:func:`gearopt.envelope.solve_envelope`). Near a fold Theta(s, t) is not polynomial: its
second derivative across the fold grows as the inverse square root of the distance to it, so
the flank's bicubic cells (:attr:`gearopt.flank.FlankMap.cells`) are wrong by tenths of a
micrometre in the cell through the boundary (whose lower corners are not generated) and by
hundredths in the two above it (seed 001 Table 3's pinion, default grid). That is the size of a
line contact's whole clearance budget and enough to move a tangency point along a long contact
ellipse by tenths of a millimetre.

:func:`boundary_cells` replaces, in each face row of cells, the cells from the one through the
generated boundary up to :data:`REACH_MM` above it (and at least two cells above the lowest
generated nodes) by ``k`` cells each along the profile (``k`` = the cell's height over
:data:`STEP_MM`, at least one), bicubic Hermite cells through the exact surface's points and
normals at their corners (:meth:`gearopt.envelope.EnvelopeSurface.geometry_at`; the cross
derivative by differences along the profile): the error of a cubic falls as the fourth power of
the step, and the corners lie at least 0.05 mm clear of the fold (a corner more than
:data:`BELOW_MM` below its column's boundary takes the quadratic extension of the exact points
above it). The fine cells meet the flank's own cells above them on nodes whose data they share
(C1 across that line). Below the lowest fine cell its polynomial goes on (the smooth extension
the tangency point is solved on beyond the flank). On the conjugate face-milled pinion
(``studies/face_milling_conjugate.toml``) they are within 0.001 um of the exact surface, its own
cells 4 um off in the cell through the boundary and 0.03 um in the one above.

The table is made once per flank (both fields of a flank and its aligned and misaligned
placements share it): the exact surface solved at the corners in one batch (a corner where
Newton stalls from the grid's start is solved from its converged neighbour,
:meth:`gearopt.envelope.EnvelopeSurface.parameters_at`), the rest in the compiled kernels of
:mod:`gearopt.contact.boundary_kernels`.

The contact engine evaluates the pinion through this table (:mod:`gearopt.contact.kernels`'s
point evaluations), so its refined minimum, tangency points and zones reach the generated
boundary on the same accurate interpolant (:func:`gearopt.contact.engine.node_tables`). A flank
without an exact surface or a solved boundary has none: the engine then keeps its refinement two
cells above the lowest generated nodes.
"""

from __future__ import annotations

import math
import weakref

import numpy as np

from gearopt.contact.boundary_kernels import (
    exact_values,
    fine_corners,
    fine_layout,
    local_theta,
)
from gearopt.errors import GearoptError
from gearopt.flank import hermite_cells, hermite_coefficients

__all__ = ["BELOW_MM", "STEP_MM", "boundary_cells", "band_theta"]

#: the fine cells' height along the profile at most (mm)
STEP_MM = 0.1
#: corners more than this below their column's generated boundary take an extension (mm; the
#: envelope keeps its flank 0.3 mm clear of the fold)
BELOW_MM = 0.25
#: the fine cells reach this far above the generated boundary at least (mm): the flank's own
#: cells err by 0.008 um 0.8 mm above a fold, 0.002 um 1.5 mm above (0.37 mm cells)
REACH_MM = 1.5
#: and this many cells above the lowest generated nodes
ROWS_ABOVE = 2

_CACHE: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def boundary_cells(pinion):
    """The pinion's fine cells at its generated boundary: ``(band, coefficients)`` or None.

    ``band`` ``(n_cells, 4)`` per cell of the flank's table: the index of its face row's first
    fine cell (-1: the flank's own cell), the cell's row above the face row's lowest fine row,
    the fine cells per cell ``k`` and the face row's fine cells ``m``; ``coefficients``
    ``(cells, 16)`` as :class:`gearopt.flank.HermiteCells`'s, in the fine cell's unit
    coordinates. A point at unit coordinates ``(u, v)`` of a cell with ``band = (b, o, k, m)``
    lies in fine cell ``b + clip(floor((o + v) k), 0, m - 1)`` (:func:`band_theta`). None
    without an exact surface or a solved boundary, or where the surface cannot be solved at a
    corner (the flank's own cells then). Kept per FlankMap (the same flank's fields share it).
    """
    if pinion.surface is None or pinion.lowest_profile_mm is None:
        return None
    if pinion not in _CACHE:
        try:
            _CACHE[pinion] = _made(pinion)
        except GearoptError:
            _CACHE[pinion] = None
    return _CACHE[pinion]


def _made(pinion):
    face, profile = np.asarray(pinion.face_mm, float), np.asarray(pinion.profile_mm, float)
    dp = float(np.mean(np.diff(profile)))
    mask = np.ascontiguousarray(pinion.mask)
    low = np.ascontiguousarray(pinion.lowest_profile_mm, float)
    k, level0, _, top, rows, cols, exact, s_pts, t_pts, band = fine_layout(
        face, profile, low, mask, dp, STEP_MM, REACH_MM, BELOW_MM, ROWS_ABOVE
    )
    if not k:
        return None
    if exact.shape[1] < 3:
        raise ValueError("too few fine levels for second-order differences")
    step = dp / k
    geo = pinion.surface.geometry_at(s_pts, t_pts)
    point, normal = geo["point"], geo["normal"]
    cells = pinion.cells
    near = local_theta(
        (
            cells.face0_mm,
            cells.face_scale,
            cells.last_row,
            cells.profile0_mm,
            cells.profile_scale,
            cells.last_column,
            cells.columns,
        ),
        cells.coefficients,
        s_pts,
        t_pts,
    )
    g = math.radians(pinion.pitch_angle_deg)
    values = exact_values(point, normal, near, (math.sin(g), math.cos(g)))
    if pinion.taper is not None:  # to grid coordinates (s, t): the chain rule
        values[1] = values[1] + values[2] * pinion.taper.dheight_dface(t_pts)
        values[2] = values[2] * pinion.taper.dheight_dprofile(s_pts)
    corners = fine_corners(
        len(face),
        cols,
        exact,
        values,
        step,
        (k, level0, top, rows),
        mask,
        np.stack([pinion.polar_angle_rad, *pinion.node_derivatives]),
    )
    coef = hermite_coefficients(*corners, np.diff(face), np.full(exact.shape[1] - 1, step))
    return band, coef


def band_theta(coef, band, band_coef, cell, u, v):
    """Theta of the pinion at unit coordinates ``(u, v)`` of cells ``cell`` (arrays) through the
    fine cells where ``band`` has them (:func:`boundary_cells`), else the cell's own
    polynomial ``coef``: numpy's path of :func:`gearopt.contact.kernels`'s evaluation."""
    out = hermite_cells(coef, cell, u, v)
    if band is None:
        return out
    entry = band[cell]
    fine = entry[..., 0] >= 0.0
    if not np.any(fine):
        return out
    y = (entry[..., 1] + v) * entry[..., 2]
    m = np.clip(np.floor(y), 0.0, entry[..., 3] - 1.0)
    index = np.where(fine, entry[..., 0] + m, 0).astype(np.intp)
    return np.where(fine, hermite_cells(band_coef, index, u, y - m), out)
