"""Backlash along the mesh: the pinion held at the drive contact, the gear turned forward until
its other flanks touch the pinion's."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from gearopt.analysis_options import check_options
from gearopt.contact import ClearanceField, ContactError
from gearopt.mesh.frame import ARCSEC, as_list
from gearopt.mesh.pair import PairCurve

__all__ = ["Backlash", "backlash"]


@dataclass(frozen=True, kw_only=True)
class Backlash:
    """Circumferential backlash along the mesh (pinion held, gear turned to the other flank).

    Attributes
    ----------
    phi1_deg
        ``(n,)`` pinion positions (the drive side's direction of motion).
    rotational_arcsec
        ``(n,)`` the gear's rotation to the other flank.
    circumferential_um
        ``(n,)`` rotational backlash times the gear's outer pitch radius; negative values are
        interference (``interference`` True).
    radius_mm
        That radius.
    """

    phi1_deg: NDArray
    rotational_arcsec: NDArray
    circumferential_um: NDArray
    radius_mm: float

    #: circumferential backlash below this (um) is interference, above it numerical zero
    INTERFERENCE_UM = -0.05

    @property
    def interference(self) -> bool:
        """True where the flanks overlap (backlash below ``INTERFERENCE_UM``)."""
        return bool(np.any(self.circumferential_um < self.INTERFERENCE_UM))

    def as_dict(self) -> dict:
        """JSON-ready summary (the ``backlash`` object of ``gearopt analyze --json``)."""
        c = self.circumferential_um
        return {
            "phi1_deg": as_list(self.phi1_deg),
            "circumferential_um": as_list(c),
            "min_um": float(c.min()),
            "mean_um": float(c.mean()),
            "max_um": float(c.max()),
            "interference": self.interference,
            "radius_mm": float(self.radius_mm),
        }


def _unique_rows(rows: NDArray) -> tuple:
    """:func:`numpy.unique` of the rows of a non-negative integer array (``axis=0``,
    ``return_index``, ``return_inverse``): the same results, each row read as one integer
    whose digits (base: the largest entry plus one) are its entries, first most significant
    (so the rows' order is kept), where that integer fits; its general set-up otherwise."""
    base = int(rows.max()) + 1 if rows.size else 1
    if base ** rows.shape[1] >= 2**62:
        return np.unique(rows, axis=0, return_index=True, return_inverse=True)
    key = np.zeros(rows.shape[0], np.int64)
    for column in rows.T:
        key = key * base + column
    return np.unique(key, return_index=True, return_inverse=True)


def backlash(
    drive: ClearanceField,
    coast: ClearanceField,
    *,
    radius_mm: float,
    positions: int = 21,
    pairs: int = 3,
    cycles: float = 2.0,
) -> Backlash:
    """Backlash at the drive side's positions: the gear at its drive contact angle, turned
    forward until its other flanks touch the pinion's.

    Parameters
    ----------
    drive
        The drive side's clearance field.
    coast
        The coast side's, with the drive side's phase.
    radius_mm
        The radius of the circumferential backlash (the gear's outer pitch radius).
    positions, pairs, cycles
        Positions over ``cycles`` angular pitches, tooth pairs at each (a pair more is taken on
        each side: misalignment may move the mesh by a pitch).

    Returns
    -------
    Backlash
    """
    check_options(positions, pairs, cycles, 6.5, "normal")
    pairs += 2  # a pair more on each side: misalignment may move the mesh by a pitch
    curve = PairCurve(drive)
    p1 = curve.pitch
    t = np.linspace(-0.5 * cycles * p1, 0.5 * cycles * p1, positions)
    offsets = np.arange(pairs) - (pairs - 1) // 2
    u = t[:, None] + (np.round(-t / p1)[:, None] + offsets[None, :]) * p1
    key = np.round(u.ravel() / p1 * 1e9).astype(np.int64)
    _, first, inv = np.unique(key, return_index=True, return_inverse=True)
    g = curve(u.ravel()[first])[inv].reshape(u.shape)  # each relative angle once
    lag = g.min(axis=1)
    if not np.all(np.isfinite(lag)):
        raise ContactError("backlash", rule="at some positions no pair touches on the drive side")
    gear_angle = -drive.gear_sense * lag
    # positions a pitch apart put the same relative rotations on their pairs (the same keys
    # in the same order): the same drive lag, the same coast configuration, sampled once
    _, once, again = _unique_rows(inv.reshape(u.shape))
    phi = drive.sense * u[once]
    c = coast.sample(phi.ravel(), np.repeat(gear_angle[once], pairs)).minimum_rad
    rotational = c.reshape(phi.shape).min(axis=1)[again.ravel()]
    if not np.all(np.isfinite(rotational)):
        raise ContactError(
            "backlash", rule="at some positions the other flanks do not face each other"
        )
    return Backlash(
        phi1_deg=np.degrees(t),
        rotational_arcsec=rotational * ARCSEC,
        circumferential_um=rotational * radius_mm * 1e3,
        radius_mm=float(radius_mm),
    )
