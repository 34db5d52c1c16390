"""The contact engine: the clearance field between a pinion flank and a gear flank.

Machine-independent: it sees two FlankMaps (:mod:`gearopt.flank`), the shaft angle and the
misalignment (:class:`gearopt.assembly.Placement`), nothing else.

- :mod:`gearopt.contact.field`: :class:`ClearanceField` (one pinion flank against one gear
  flank: the angular clearance sampled along the motion, at given points, at grid coordinates;
  the contact interval's ends) and :class:`JointField` (several fields evaluated together);
- :mod:`gearopt.contact.samples`: what they answer, :class:`FieldSample` (the field at the
  nodes and its refined minimum) and :class:`PointClearance` (at given points, with the normal
  and circumferential separations);
- :mod:`gearopt.contact.engine`: :class:`~gearopt.contact.engine.ContactEngine`, the
  computations on the stacked tables of one or more fields;
- :mod:`gearopt.contact.kernels`: the engine's compiled loops (numba), one implementation each;
- :mod:`gearopt.contact.tangency`: Litvin's equations of continuous tangency with their
  analytic Jacobian (local synthesis; the textbook TCA of :mod:`gearopt.newton_tca`, the
  engine's reference, which production code does not import).

The mesh-cycle analyses built on the field (TCA, pattern, backlash, ease-off) are
:mod:`gearopt.mesh`.
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
