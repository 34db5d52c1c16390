"""What the clearance field answers: its values at the nodes with the refined minimum
(:class:`FieldSample`) and at given pinion points (:class:`PointClearance`)."""

from __future__ import annotations

from dataclasses import dataclass

from numpy.typing import NDArray

__all__ = ["FieldSample", "PointClearance"]


@dataclass(frozen=True, kw_only=True)
class FieldSample:
    """The clearance field at a set of relative pinion angles (one row per angle).

    Attributes
    ----------
    phi_rad
        ``(n,)`` relative pinion angles of the base pair (pinion angle + k pitches).
    clearance_rad
        ``(n, n_f, n_p)`` angular clearance delta; +inf where the node is not on both flanks.
    normal_factor_mm, radius_mm
        ``(n, n_f, n_p)`` |n . (z_g x q)| and R2: mm of normal / circumferential separation per
        rad of gear rotation.
    minimum_rad
        ``(n,)`` refined minimum of the clearance (+inf when nothing is in contact).
    contact_face_mm, contact_profile_mm
        ``(n,)`` pinion grid coordinates (s, h) of the refined minimum.
    edge
        ``(n,)`` True where the minimum lies on the boundary of the flanks (edge contact).
    """

    phi_rad: NDArray
    clearance_rad: NDArray
    normal_factor_mm: NDArray
    radius_mm: NDArray
    minimum_rad: NDArray
    contact_face_mm: NDArray
    contact_profile_mm: NDArray
    edge: NDArray


@dataclass(frozen=True, kw_only=True)
class PointClearance:
    """The clearance field at given pinion points (:meth:`ClearanceField.clearance_of_points`).

    Attributes
    ----------
    clearance_rad
        The angular clearance delta: how far the gear must turn back (rad) before its flank
        reaches the point.
    normal_factor_mm, radius_mm
        |n . (z_g x q)| (zero without normals) and R2: mm of normal and of circumferential
        separation per rad of gear rotation.
    valid
        Whether the point faces the gear flank (its image lies on the gear's generated cells).
    gear_face_mm, gear_profile_mm
        The points' gear grid coordinates ``(s, t)`` (None where not asked for).
    """

    clearance_rad: NDArray
    normal_factor_mm: NDArray | None
    radius_mm: NDArray
    valid: NDArray
    gear_face_mm: NDArray | None = None
    gear_profile_mm: NDArray | None = None

    def separation_mm(self, minimum_rad, kind: str = "normal") -> NDArray:
        """The separation above a contact whose clearance is ``minimum_rad``: ``"normal"``
        (along the pinion's normal) or ``"circumferential"`` (at equal radius, seed 003
        section 5)."""
        factor = self.normal_factor_mm if kind == "normal" else self.radius_mm
        return (self.clearance_rad - minimum_rad) * factor
