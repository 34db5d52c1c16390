"""The contact pattern on the pinion flank at the nodes: separations from the mating flank and
the instantaneous contact zones' centroids (the contact path); the zones' chords are measured on
the refined field (:mod:`gearopt.mesh.zone`).

A node is in the instantaneous contact zone when its separation from the mating flank is less
than the marking compound; grids are the pattern coordinates ``face_mm`` ``(n_f,)`` and
``profile_mm`` ``(n_p,)`` of :class:`gearopt.mesh.frame.ToothFrame`.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from gearopt.contact import FieldSample

__all__ = ["centroids", "columns", "sample_rows", "separation_mm"]


def columns(*cols) -> NDArray:
    """``(n, k)`` the ``k`` arrays ``(n,)`` side by side: ``np.stack(cols, 1)`` without its
    overhead on a few rows."""
    out = np.empty((len(cols[0]), len(cols)))
    for j, col in enumerate(cols):
        out[:, j] = col
    return out


def sample_rows(sample: FieldSample, rows) -> FieldSample:
    """The rows ``rows`` (a slice or an index array) of a sample."""
    return FieldSample(
        phi_rad=sample.phi_rad[rows],
        clearance_rad=sample.clearance_rad[rows],
        normal_factor_mm=sample.normal_factor_mm[rows],
        radius_mm=sample.radius_mm[rows],
        minimum_rad=sample.minimum_rad[rows],
        contact_face_mm=sample.contact_face_mm[rows],
        contact_profile_mm=sample.contact_profile_mm[rows],
        edge=sample.edge[rows],
    )


def separation_mm(
    sample: FieldSample, reference_rad: NDArray, separation: str, rows=slice(None)
) -> NDArray:
    """Separation of every node from the mating flank with the gear at a given lag.

    Parameters
    ----------
    sample
        Node fields of a :class:`gearopt.contact.FieldSample`.
    reference_rad
        The gear's lag, one per row taken.
    separation
        ``"normal"`` (along the pinion's normal) or ``"circumferential"`` (the gear's
        rotation at the node's radius).
    rows
        The sample's rows to take (a slice or an index array).

    Returns
    -------
    NDArray
        ``(rows, n_f, n_p)`` separations in mm, +inf off the flanks.
    """
    factor = sample.normal_factor_mm if separation == "normal" else sample.radius_mm
    reference = reference_rad.reshape(-1, 1, 1)
    # (NaN, then +inf: inf - inf, a row with nothing on the flanks; inf * 0, off the flanks)
    with np.errstate(invalid="ignore"):
        if isinstance(rows, slice):
            extra = sample.clearance_rad[rows] - reference
        else:  # a gathered copy, worked on in place
            extra = sample.clearance_rad[rows]
            extra -= reference
        extra *= factor[rows]
    np.copyto(extra, np.inf, where=np.isnan(extra))
    return extra


def centroids(sep_mm: NDArray, compound_mm: float, face_mm, profile_mm):
    """Weighted centroids (weights compound - separation) of each row's zone.

    Parameters
    ----------
    sep_mm
        ``(rows, n_f, n_p)`` separations (never NaN).
    compound_mm
        The marking compound.
    face_mm, profile_mm
        The grid's pattern coordinates.

    Returns
    -------
    tuple of NDArray
        ``(face, profile)``, each ``(rows,)``; NaN-free: a row without a zone reports its
        least-separated node.
    """
    w = np.clip(compound_mm - sep_mm, 0.0, None)  # (finite: separations are never NaN)
    total = w.sum(axis=(1, 2))
    s = np.broadcast_to(face_mm[:, None], sep_mm.shape[1:])
    h = np.broadcast_to(profile_mm[None, :], sep_mm.shape[1:])
    flat = sep_mm.reshape(len(sep_mm), -1).argmin(axis=1)
    s0, h0 = s.ravel()[flat], h.ravel()[flat]
    safe = np.where(total > 0.0, total, 1.0)
    cs = np.where(total > 0.0, (w * s).sum(axis=(1, 2)) / safe, s0)
    ch = np.where(total > 0.0, (w * h).sum(axis=(1, 2)) / safe, h0)
    return cs, ch
