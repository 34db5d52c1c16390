"""Ease-off: the pinion flank's normal deviation from the surface conjugate to the gear."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from gearopt.contact import ClearanceField, ContactError
from gearopt.mesh.frame import ToothFrame, as_list

__all__ = ["EaseOff", "ease_off"]


@dataclass(frozen=True, kw_only=True)
class EaseOff:
    """Normal deviation of the pinion flank from the surface conjugate to the gear.

    Attributes
    ----------
    face_mm, profile_mm
        ``(n_f,)``, ``(n_p,)`` the nodes' pattern coordinates.
    ease_off_um
        ``(n_f, n_p)`` the deviation, zero at its least node; other nodes than ``mask``'s hold
        0.
    mask
        ``(n_f, n_p)`` the nodes where it is defined (the conjugate contact inside both
        flanks).
    side
        ``"drive"`` or ``"coast"``.
    """

    face_mm: NDArray
    profile_mm: NDArray
    ease_off_um: NDArray
    mask: NDArray
    side: str

    def as_dict(self) -> dict:
        """JSON-ready summary (an ``ease_off`` side of ``gearopt analyze --json``)."""
        e = self.ease_off_um[self.mask]
        return {
            "side": self.side,
            "max_um": float(e.max(initial=0.0)),
            "face_mm": as_list(self.face_mm),
            "profile_mm": as_list(self.profile_mm),
            "ease_off_um": self.ease_off_um.tolist(),
            "mask": self.mask.tolist(),
        }


def ease_off(
    field: ClearanceField,
    *,
    frame: ToothFrame,
    side: str = "drive",
    samples: int = 121,
    span_pitches: float = 4.0,
) -> EaseOff:
    """Ease-off: for each pinion node, the least normal clearance to the gear flank over the
    ideal (conjugate) motion; a conjugate node touches at some angle (zero). Each node's
    minimum over the angle samples is refined by the parabola through its neighbours.

    Parameters
    ----------
    field
        The side's clearance field.
    frame
        Pattern coordinates.
    side
        Its name.
    samples
        Pinion angles sampled over ``span_pitches`` angular pitches.
    span_pitches
        The span, centred on the mean position.

    Returns
    -------
    EaseOff
    """
    p1 = field.pinion.pitch_rad
    v = np.linspace(-0.5 * span_pitches * p1, 0.5 * span_pitches * p1, samples)
    s = field.sample(field.sense * v, refine=False)
    d = s.clearance_rad.reshape(samples, -1)
    fac = s.normal_factor_mm.reshape(samples, -1)
    k = np.argmin(d, axis=0)
    cols = np.arange(d.shape[1])
    d0 = d[k, cols]
    ok = np.isfinite(d0) & (k > 0) & (k < samples - 1)
    km, kp = np.clip(k - 1, 0, samples - 1), np.clip(k + 1, 0, samples - 1)
    dm, dp = d[km, cols], d[kp, cols]
    ok &= np.isfinite(dm) & np.isfinite(dp)
    with np.errstate(invalid="ignore"):
        curv = np.where(ok, dm - 2.0 * d0 + dp, 1.0)
        slope = np.where(ok, 0.5 * (dp - dm), 0.0)
        step = np.where(curv > 0.0, np.clip(-slope / curv, -1.0, 1.0), 0.0)
        value = np.where(ok, d0 + slope * step + 0.5 * curv * step**2, 0.0)
    mask = ok.reshape(field.pinion.shape)
    if not mask.any():
        raise ContactError("ease_off", rule="no pinion node meets the gear flank")
    # the conjugate surface is defined up to a turn of the gear: take the turn that makes it
    # touch the pinion, then convert each node's angular clearance along its normal
    normal = (value - value[ok].min()) * fac[k, cols]
    e = np.where(ok, normal * 1e3, 0.0).reshape(field.pinion.shape)
    return EaseOff(
        face_mm=field.pinion.face_mm - frame.toe_mm,
        profile_mm=field.pinion.profile_mm - frame.root_mm,
        ease_off_um=e,
        mask=mask,
        side=side,
    )
