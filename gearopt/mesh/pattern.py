"""The contact pattern on the pinion flank: separations from the mating flank, the instantaneous
contact zone's centroid and minor axis, and zone widths along lines.

A node is in the instantaneous contact zone when its separation from the mating flank is less
than the marking compound; grids are the pattern coordinates ``face_mm`` ``(n_f,)`` and
``profile_mm`` ``(n_p,)`` of :class:`gearopt.mesh.frame.ToothFrame`.
"""

from __future__ import annotations

from dataclasses import fields as dataclass_fields

import numpy as np
from numpy.typing import NDArray

from gearopt.contact import FieldSample, kernels

__all__ = ["centroids", "minor_axis", "sample_rows", "separation_mm", "widths"]


def sample_rows(sample: FieldSample, rows) -> FieldSample:
    """The rows ``rows`` (a slice or an index array) of a sample."""
    return FieldSample(
        **{f.name: getattr(sample, f.name)[rows] for f in dataclass_fields(FieldSample)}
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


def minor_axis(sep_mm: NDArray, compound_mm, face_mm, profile_mm) -> NDArray:
    """Unit vector of one zone's minor axis (weighted second moments), in (face, profile).

    Along the face for a zone without extent (no node, or one: its moments are rounding noise,
    whose eigenvectors would point anywhere). ``sep_mm`` is ``(n_f, n_p)``.
    """
    w = np.clip(compound_mm - sep_mm, 0.0, None)  # (finite: separations are never NaN)
    if np.count_nonzero(w) <= 1:
        return np.array([1.0, 0.0])
    s = np.broadcast_to(face_mm[:, None], w.shape)
    h = np.broadcast_to(profile_mm[None, :], w.shape)
    ms, mh = (w * s).sum() / w.sum(), (w * h).sum() / w.sum()
    cov = np.array(
        [
            [(w * (s - ms) ** 2).sum(), (w * (s - ms) * (h - mh)).sum()],
            [(w * (s - ms) * (h - mh)).sum(), (w * (h - mh) ** 2).sum()],
        ]
    )
    vals, vecs = np.linalg.eigh(cov)
    minor = vecs[:, np.argmin(vals)]
    return np.array([minor[0], minor[1]])


def widths(sep_mm: NDArray, compound_mm, face_mm, profile_mm, points, directions) -> NDArray:
    """Extent of the zones {separation < compound} along K lines at once.

    Line k passes through ``points[k]`` perpendicular to ``directions[k]`` on the field
    ``sep_mm[k]``, interpolated bilinearly between the nodes and sampled at 2001 points; from
    the middle outward, the first sample out of the zone on each side bounds it (interpolated;
    the line's end when there is none). The compiled kernel
    :func:`gearopt.contact.kernels.zone_widths` walks each line.

    Parameters
    ----------
    sep_mm
        ``(K, n_f, n_p)`` separations.
    compound_mm
        The marking compound.
    face_mm, profile_mm
        The grid's pattern coordinates.
    points, directions
        ``(K, 2)`` a point of each line and the direction it is perpendicular to.

    Returns
    -------
    NDArray
        ``(K,)`` widths in mm; 0 where the middle sample is out of the zone.
    """
    points, directions = np.asarray(points, float), np.asarray(directions, float)
    perp = np.stack([-directions[:, 1], directions[:, 0]], axis=1)
    reach = float(face_mm[-1] - face_mm[0] + profile_mm[-1] - profile_mm[0])
    tau = np.linspace(-reach, reach, 2001)
    big = 10.0 * compound_mm
    f = np.where(np.isfinite(sep_mm), np.minimum(sep_mm, big), big)
    width = np.empty(len(sep_mm))
    grid = (np.asarray(face_mm, float), np.asarray(profile_mm, float))
    kernels.zone_widths(f, compound_mm, *grid, points, perp, tau, big, width)
    return width
