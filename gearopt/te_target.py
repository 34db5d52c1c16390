"""A designed transmission error: the symmetric fourth-order function of seed 002.

    delta_phi2(x) = quadratic x^2 + quartic x^4,     x = phi1 - phi1_0   (rad of pinion)

in rad of gear, negative away from the reference point phi1_0 (the TE convention of
docs/architecture.md, Transmission error: the maximum is 0). The classic parabola is
``quartic = 0``. The ``[te_target]`` table of a design gives either the coefficients
(``quadratic``, ``quartic``) or the two boundary conditions of seed 002: ``pitch_point_te_arcsec``
at the transfer point x_T = pi / N1 (half a pinion pitch from phi1_0, where the next pair takes
over) and ``mesh_in_te_arcsec`` at the mesh-in point x_in = CR pi / N1, with ``contact_ratio`` CR
the pinion rotation in contact on the flank over the angular pitch (entry and exit symmetric
about phi1_0). Then

    [x_T^2  x_T^4 ] [quadratic]   [pitch_point_te]
    [x_in^2 x_in^4] [quartic  ] = [mesh_in_te    ]      (rad; seed 002's two conditions)

Seed 002's Table 2 lists its "a" and "b"; ``tests/data/seed_cases.json`` explains why its
columns must be read as a = quadratic and b = quartic to be consistent.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from gearopt.errors import DesignError
from gearopt.units import ARCSEC
from gearopt.validate import check_keys, read_number

__all__ = ["ARCSEC", "TE_TARGET_KEYS", "TETarget", "compare"]

TE_TARGET_KEYS = (
    "quadratic",
    "quartic",
    "pitch_point_te_arcsec",
    "mesh_in_te_arcsec",
    "contact_ratio",
)


@dataclass(frozen=True, kw_only=True)
class TETarget:
    """The designed TE (module docstring): coefficients in rad of gear per rad^n of pinion, the
    contact ratio it is designed for (the span of the inverse TCA), the pinion's teeth."""

    quadratic: float
    quartic: float
    contact_ratio: float
    pinion_teeth: int

    def __post_init__(self) -> None:
        if self.quadratic > 0.0 or (self.quadratic == 0.0 and self.quartic >= 0.0):
            raise DesignError(
                "te_target.quadratic",
                self.quadratic,
                "the designed TE must fall away from phi1_0 (quadratic < 0, or quadratic = 0 "
                "and quartic < 0)",
            )
        delta = self.delta_rad(np.linspace(0.0, self.mesh_in_rad, 201))
        if delta.max() > 0.0 or np.any(np.diff(delta) > 0.0):
            raise DesignError(
                "te_target.quartic",
                self.quartic,
                "the designed TE must fall monotonically from phi1_0 to the mesh-in point",
            )

    @property
    def pitch_rad(self) -> float:
        """The pinion's angular pitch."""
        return 2.0 * math.pi / self.pinion_teeth

    @property
    def transfer_rad(self) -> float:
        """x_T = pi / N1."""
        return 0.5 * self.pitch_rad

    @property
    def mesh_in_rad(self) -> float:
        """x_in = CR pi / N1."""
        return 0.5 * self.contact_ratio * self.pitch_rad

    def delta_rad(self, x_rad: ArrayLike) -> NDArray:
        """delta_phi2(x) in rad of gear."""
        x = np.asarray(x_rad, float)
        return self.quadratic * x**2 + self.quartic * x**4

    def te_arcsec(self, x_rad: ArrayLike) -> NDArray:
        """The one-pair TE in arcsec (0 at phi1_0)."""
        return self.delta_rad(x_rad) * ARCSEC

    def envelope_arcsec(self, x_rad: ArrayLike) -> NDArray:
        """The TE of the mesh, unloaded: the highest of the pairs (the one-pair TE repeated
        every pitch), 0 at phi1_0."""
        x = np.asarray(x_rad, float)
        p = self.pitch_rad
        nearest = x - p * np.round(x / p)
        return self.te_arcsec(nearest)

    @property
    def pitch_point_te_arcsec(self) -> float:
        return float(self.te_arcsec(self.transfer_rad))

    @property
    def mesh_in_te_arcsec(self) -> float:
        return float(self.te_arcsec(self.mesh_in_rad))

    def as_dict(self) -> dict:
        return {
            "quadratic": self.quadratic,
            "quartic": self.quartic,
            "contact_ratio": self.contact_ratio,
            "pitch_point_te_arcsec": self.pitch_point_te_arcsec,
            "mesh_in_te_arcsec": self.mesh_in_te_arcsec,
        }

    @classmethod
    def from_table(cls, table: Mapping[str, Any], pinion_teeth: int) -> TETarget:
        """Build from a ``[te_target]`` table (errors name ``te_target.<key>``)."""
        where = "te_target"
        check_keys(table, TE_TARGET_KEYS, where)
        ratio = read_number(table, "contact_ratio", where, gt=1.0, le=4.0)
        given = {k for k in ("quadratic", "quartic") if k in table}
        bounds = {k for k in ("pitch_point_te_arcsec", "mesh_in_te_arcsec") if k in table}
        if given and bounds:
            raise DesignError(
                where,
                sorted(given | bounds),
                "give the coefficients (quadratic, quartic) or the boundary conditions "
                "(pitch_point_te_arcsec, mesh_in_te_arcsec), not both",
            )
        if given:
            return cls(
                quadratic=read_number(table, "quadratic", where),
                quartic=read_number(table, "quartic", where, 0.0),
                contact_ratio=ratio,
                pinion_teeth=pinion_teeth,
            )
        for key in ("pitch_point_te_arcsec", "mesh_in_te_arcsec"):
            if key not in table:
                raise DesignError(f"{where}.{key}", rule="required (or give quadratic, quartic)")
        te_t = read_number(table, "pitch_point_te_arcsec", where, lt=0.0) / ARCSEC
        te_in = read_number(table, "mesh_in_te_arcsec", where, lt=0.0) / ARCSEC
        x_t = math.pi / pinion_teeth
        x_in = ratio * x_t
        if ratio <= 1.0 + 1e-9:  # x_in on x_T: the two conditions are one
            raise DesignError(f"{where}.contact_ratio", ratio, "must exceed 1")
        quadratic, quartic = np.linalg.solve(
            np.array([[x_t**2, x_t**4], [x_in**2, x_in**4]]), np.array([te_t, te_in])
        )
        return cls(
            quadratic=float(quadratic),
            quartic=float(quartic),
            contact_ratio=ratio,
            pinion_teeth=pinion_teeth,
        )


def compare(target: TETarget, phi1_deg: ArrayLike, te_arcsec: ArrayLike, handover_deg) -> dict:
    """The target beside an achieved TE (the contact engine's, maximum 0): the target's
    maximum phi1_0 placed at the achieved maximum -- half a pitch from the first hand-over
    between pairs (the highest sample when there is none) -- and the target's envelope over the
    pairs evaluated at the achieved positions.

    Returns ``te_target_arcsec`` (array), ``te_target_max_deviation_arcsec`` and
    ``te_target_rms_deviation_arcsec`` (achieved minus target)."""
    phi = np.radians(np.asarray(phi1_deg, float))
    te = np.asarray(te_arcsec, float)
    handover = np.radians(np.asarray(handover_deg, float))
    if handover.size:
        phi1_0 = handover[0] + target.transfer_rad
    else:
        phi1_0 = phi[int(np.argmax(te))]
    want = target.envelope_arcsec(phi - phi1_0)
    deviation = te - want
    return {
        "te_target_arcsec": want,
        "te_target_max_deviation_arcsec": float(np.max(np.abs(deviation))),
        "te_target_rms_deviation_arcsec": float(np.sqrt(np.mean(deviation**2))),
    }
