"""How the pair is assembled in the housing: the misalignment and the members' placement.

Housing frame S_f (docs/architecture.md, Frames and signs): origin at the nominal crossing point
of the axes, x_f along the pinion axis toward the pinion's back, the gear axis in the x_f-z_f
plane at the shaft angle Sigma from x_f, y_f = z_f x x_f. The pinion frame maps x_p -> z_f,
y_p -> -y_f, z_p -> x_f; the gear frame is S_f turned about y_f so that
z_g = (cos Sigma, 0, sin Sigma). Misalignment: the pinion moves by (dA1, dE, 0), the gear along
its own axis by dA2 and its axis turns about y_f to Sigma + dGamma.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from gearopt.errors import DesignError
from gearopt.validate import check_keys, check_number

__all__ = ["Misalignment", "Placement"]

_PINION_TO_HOUSING = np.array([[0.0, 0.0, 1.0], [0.0, -1.0, 0.0], [1.0, 0.0, 0.0]])


_MISALIGNMENT_KEYS = ("offset_mm", "pinion_axial_mm", "gear_axial_mm", "shaft_angle_deg")


@dataclass(frozen=True, kw_only=True)
class Misalignment:
    """Displacements of the assembled pair in the housing frame (module docstring).

    ``offset_mm`` (dE) moves the pinion along +y_f, ``pinion_axial_mm`` (dA1) the pinion along its
    axis out of mesh, ``gear_axial_mm`` (dA2) the gear along its axis out of mesh,
    ``shaft_angle_deg`` (dGamma) makes the shaft angle Sigma + dGamma. The same keys form the
    ``[compensation]`` table: errors the machine settings compensate (seed 001 section 4).
    """

    offset_mm: float = 0.0
    pinion_axial_mm: float = 0.0
    gear_axial_mm: float = 0.0
    shaft_angle_deg: float = 0.0

    def __post_init__(self) -> None:
        for key in ("offset_mm", "pinion_axial_mm", "gear_axial_mm"):
            value = check_number(key, getattr(self, key), gt=-10.0, lt=10.0, unit="mm")
            object.__setattr__(self, key, value)
        value = check_number(
            "shaft_angle_deg", self.shaft_angle_deg, gt=-5.0, lt=5.0, unit="degrees"
        )
        object.__setattr__(self, "shaft_angle_deg", value)

    @property
    def is_zero(self) -> bool:
        """True when every displacement is zero."""
        return not any(
            (self.offset_mm, self.pinion_axial_mm, self.gear_axial_mm, self.shaft_angle_deg)
        )

    @classmethod
    def from_table(cls, table: Mapping[str, Any], where: str) -> Misalignment:
        """Build from a TOML table, naming errors ``where.key``."""
        check_keys(table, _MISALIGNMENT_KEYS, where)
        try:
            return cls(**table)
        except DesignError as exc:
            raise type(exc)(f"{where}.{exc.parameter}", exc.value, exc.rule) from None


@dataclass(frozen=True, kw_only=True)
class Placement:
    """Where the pinion and the gear sit in the housing frame (module docstring).

    Attributes
    ----------
    shaft_angle_deg
        Nominal shaft angle Sigma.
    misalignment
        dE, dA1, dA2 and dGamma of the assembled pair.
    """

    shaft_angle_deg: float = 90.0
    misalignment: Misalignment = field(default_factory=Misalignment)

    @property
    def gear_axes(self) -> NDArray:
        """3 x 3 matrix whose columns are x_g, y_g, z_g in S_f."""
        sigma = math.radians(self.shaft_angle_deg + self.misalignment.shaft_angle_deg)
        c, s = math.cos(sigma), math.sin(sigma)
        return np.array([[s, 0.0, c], [0.0, 1.0, 0.0], [-c, 0.0, s]])

    @property
    def pinion_to_gear(self) -> tuple[NDArray, NDArray]:
        """``(B, c)`` with q = B p + c: a point p of the (unturned) pinion frame in the gear
        frame."""
        m = self.misalignment
        axes = self.gear_axes
        pinion_origin = np.array([m.pinion_axial_mm, m.offset_mm, 0.0])
        gear_origin = m.gear_axial_mm * axes[:, 2]
        return axes.T @ _PINION_TO_HOUSING, axes.T @ (pinion_origin - gear_origin)
