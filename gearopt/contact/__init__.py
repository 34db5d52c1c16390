"""The contact engine: the clearance field between a pinion flank and a gear flank.

Machine-independent: it sees two FlankMaps (:mod:`gearopt.flank`), the shaft angle and the
misalignment (:class:`gearopt.assembly.Placement`), nothing else.

- :mod:`gearopt.contact.field`: :class:`ClearanceField` (one pinion flank against one gear
  flank), :class:`JointField` (several fields evaluated together), :class:`FieldSample`;
- :mod:`gearopt.contact.kernels`: the compiled loops of the engine (numba).
"""

from gearopt.assembly import Placement
from gearopt.contact.field import (
    ClearanceField,
    ContactError,
    FieldSample,
    JointField,
    PointClearance,
)

__all__ = [
    "ClearanceField",
    "ContactError",
    "FieldSample",
    "JointField",
    "Placement",
    "PointClearance",
]
