"""A design's flanks placed in the housing (:class:`MeshedPair`), and the base pair's lag as a
function of the pinion's rotation (:class:`PairCurve`)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from gearopt.assembly import Placement
from gearopt.contact import ClearanceField, FieldSample
from gearopt.mesh.frame import ToothFrame

__all__ = ["MeshedPair", "PairCurve", "mesh_pair"]


class PairCurve:
    """The base pair's lag G(u) at relative pinion rotations u (direction of motion).

    Parameters
    ----------
    field
        The side's clearance field.
    gear_angle_rad
        Extra turn of the gear (as in :meth:`gearopt.contact.ClearanceField.sample`).

    Attributes
    ----------
    field, gear_angle_rad
        As given.
    pitch
        The pinion's angular pitch.
    """

    def __init__(self, field: ClearanceField, gear_angle_rad=0.0):
        self.field = field
        self.gear_angle_rad = gear_angle_rad
        self.pitch = field.pinion.pitch_rad

    def sample(self, u: NDArray, gear_angle_rad=None) -> FieldSample:
        """The field's sample at relative rotations ``u`` (the gear turned by
        ``gear_angle_rad``, default the curve's)."""
        angle = self.gear_angle_rad if gear_angle_rad is None else gear_angle_rad
        return self.field.sample(self.field.sense * np.asarray(u, float), angle)

    def __call__(self, u: NDArray) -> NDArray:
        """G at ``u`` (rad of gear rotation; +inf without contact on the flanks)."""
        return self.sample(u).minimum_rad


@dataclass(frozen=True, kw_only=True)
class MeshedPair:
    """A design's generated flanks placed in the housing.

    Attributes
    ----------
    drive, coast
        The drive and coast clearance fields (the coast field takes the drive field's phase,
        so both face the same tooth space).
    frame
        Pattern coordinates.
    backlash_radius_mm
        The gear's outer pitch radius (circumferential backlash).
    """

    drive: ClearanceField
    coast: ClearanceField
    frame: ToothFrame
    backlash_radius_mm: float


def mesh_pair(design, flanks, *, misalignment=None) -> MeshedPair:
    """Place a design's generated flanks in the housing.

    Parameters
    ----------
    design
        The design (:class:`gearopt.design.Design`).
    flanks
        ``(pinion, gear)``, each ``{"convex": FlankMap, "concave": FlankMap}`` as a machine
        model generates them (:meth:`gearopt.machine.BaseMachineModel.generate_flanks`).
    misalignment
        How the pair is assembled; defaults to the design's ``[misalignment]``.

    Returns
    -------
    MeshedPair
    """
    pinion, gear = flanks
    placement = Placement(
        shaft_angle_deg=design.pair.shaft_angle_deg,
        misalignment=design.misalignment if misalignment is None else misalignment,
    )
    drive = ClearanceField(pinion["convex"], gear["concave"], placement=placement)
    coast = ClearanceField(
        pinion["concave"],
        gear["convex"],
        placement=placement,
        sense=-drive.sense,
        phase_rad=drive.phase_rad,
    )
    blank = design.blank
    return MeshedPair(
        drive=drive,
        coast=coast,
        frame=ToothFrame.from_blank(blank),
        backlash_radius_mm=blank.outer_pitch_radius_mm[1],
    )
