"""Unit conversions shared across the layers: one home for each constant."""

from __future__ import annotations

import math

__all__ = ["ARCSEC"]

#: arcseconds per radian: an angle in radians times this is in arcseconds
ARCSEC = 180.0 * 3600.0 / math.pi
