"""Pattern coordinates on the pinion flank, the direction of a path of contact, and the units
of the mesh analyses' results.

Pattern coordinates (docs/architecture.md, "Pattern coordinates"): on the pinion flank projected
to the axial plane, ``face`` from the toe (0) toward the heel, ``profile`` from the root (0)
toward the top.
"""

from __future__ import annotations

import math
import weakref
from dataclasses import dataclass

import numpy as np

from gearopt.contact import ClearanceField, FieldSample
from gearopt.flank_jet import FlankJet
from gearopt.mesh import path_kernels
from gearopt.units import ARCSEC

__all__ = ["ARCSEC", "ToothFrame", "as_list", "gear_path_angle", "path_angle"]


def as_list(values) -> list[float]:
    """The values of an array, flattened, as a list of floats (the results' JSON)."""
    return np.asarray(values).ravel().astype(float).tolist()


@dataclass(frozen=True, kw_only=True)
class ToothFrame:
    """Pattern coordinates on the pinion flank: ``face = s - toe_mm``, ``profile = h - root_mm``
    and the flank centre C in those coordinates.

    Attributes
    ----------
    toe_mm
        Pinion grid face coordinate s of the toe (mean cone distance minus half the face width).
    root_mm
        Pinion grid profile coordinate h of the root (minus the pinion's mean dedendum).
    centre_mm
        The flank centre C ``(face, profile)``: the mean cone distance, mid working depth
        (h = (a1 - a2) / 2 with a the mean addenda).
    face_width_mm
        Face width.
    gear_root_angle_deg
        The gear's root angle (the reference line of :func:`path_angle`).
    """

    toe_mm: float
    root_mm: float
    centre_mm: tuple[float, float]
    face_width_mm: float
    gear_root_angle_deg: float = 90.0

    @classmethod
    def from_blank(cls, blank) -> ToothFrame:
        """The frame of a pair's blank (:class:`gearopt.blank.Blank`)."""
        a1, a2 = blank.mean_addendum_mm
        root = -blank.mean_dedendum_mm[0]
        return cls(
            toe_mm=blank.mean_cone_distance_mm - 0.5 * blank.face_width_mm,
            root_mm=root,
            centre_mm=(0.5 * blank.face_width_mm, 0.5 * (a1 - a2) - root),
            face_width_mm=blank.face_width_mm,
            gear_root_angle_deg=blank.root_angle_deg[1],
        )


def path_angle(tangent, normal, point, root_angle_rad: float) -> float:
    """Direction of a path of contact on the gear flank.

    The angle from the gear's root line -- the root cone's generatrix through the point,
    projected on the tangent plane, toward the heel -- to the path's tangent (oriented toward
    the heel too), positive when the path rises toward the tooth top: Litvin's eta_2 of local
    synthesis with this sign.

    Parameters
    ----------
    tangent
        ``(3,)`` the path's tangent (either orientation).
    normal
        ``(3,)`` the gear flank's normal at ``point`` (any length).
    point
        ``(3,)`` the point, gear member frame.
    root_angle_rad
        The gear's root angle.

    Returns
    -------
    float
        The angle in degrees, range (-90, 90].
    """
    # (compiled: on floats, the products summed in order, as numpy's dot of 3-vectors)
    return _folded_degrees(
        path_kernels.chord_angle(
            tuple(float(a) for a in tangent),
            tuple(float(a) for a in normal),
            (float(point[0]), float(point[1]), float(point[2])),
            float(root_angle_rad),
        )
    )


def _folded_degrees(angle_rad: float) -> float:
    """``angle_rad`` in degrees, -90 (the same line as 90) folded to 90: range (-90, 90]."""
    angle = math.degrees(angle_rad)
    return 90.0 if angle <= -90.0 + 1e-12 else angle


def gear_path_angle(field: ClearanceField, ex: FieldSample, frame: ToothFrame) -> float:
    """The path's direction on the gear flank at M (:func:`path_angle`).

    Parameters
    ----------
    field
        The side's clearance field.
    ex
        The side's extra positions (:class:`gearopt.mesh.side.SideCycle`); rows 4 and 5 are
        the two positions either side of M, whose contact points are carried into the gear's
        frame at their contact angles.
    frame
        Pattern coordinates (the gear's root angle).

    Returns
    -------
    float
        The angle in degrees.

    Notes
    -----
    The points' arithmetic and the flank's tangents are compiled
    (:mod:`gearopt.mesh.path_kernels`; the same results to the bit); the splines stay numpy's.
    """
    face, profile = ex.contact_face_mm[4:6], ex.contact_profile_mm[4:6]
    pinion = field.pinion
    g = math.radians(pinion.pitch_angle_deg)
    a, b = path_kernels.gear_chord(
        face,
        pinion.height_at(face, profile),
        pinion.polar_angle_at(face, profile),
        (math.cos(g), math.sin(g)),
        ex.phi_rad[4:6],
        ex.minimum_rad[4:6],
        field.b,
        field.c,
        float(field.ratio),
        float(field.gear_offset_rad),
        float(field.gear_sense),
    )
    mid = (0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1]), 0.5 * (a[2] + b[2]))
    chord = (b[0] - a[0], b[1] - a[1], b[2] - a[2])
    s2, h2 = field.gear.to_grid(mid[2], math.hypot(mid[0], mid[1]))
    s2, h2 = float(s2), float(h2)
    cells, coefficients = _gear_jet(field.gear)
    root = math.radians(frame.gear_root_angle_deg)
    angle = path_kernels.root_line_angle
    if not (math.isfinite(s2) and math.isfinite(h2)):  # off the grid: the plain Python raises
        angle = getattr(angle, "py_func", angle)  # at the cell's floor, as FlankJet.polar
    return _folded_degrees(angle(chord, mid, s2, h2, cells, coefficients, root))


#: each gear flank's :func:`_gear_jet`, while the flank lives
_JETS: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def _gear_jet(gear) -> tuple[tuple, np.ndarray]:
    """The gear flank's :class:`~gearopt.flank_jet.FlankJet` as
    :func:`gearopt.mesh.path_kernels.root_line_angle` takes it, ``(jet, coefficients)``,
    made once per flank map."""
    found = _JETS.get(gear)
    if found is None:
        jet = FlankJet(gear)
        grid = (jet.s0, jet.h0, jet.ds, jet.dh, jet.n_f, jet.n_p)
        cells = (*grid, jet.cells.columns, jet.sg, jet.cg)
        found = _JETS[gear] = (cells, jet.cells.coefficients)
    return found
