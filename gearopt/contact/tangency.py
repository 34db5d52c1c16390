"""The equations of continuous tangency of a pinion flank and a gear flank (Litvin).

At a relative pinion rotation u (pinion angle phi = sense * u) five equations in five unknowns
x = (s1, h1, s2, h2, lambda):

    r1(s1, h1; phi) - r2(s2, h2; lambda) = 0          (3 equations, mm, gear frame)
    n1 . r2_s2 = 0,   n1 . r2_h2 = 0                  (2 equations, cosines)

with r1 the pinion flank point (pinion grid coordinates s1, h1) turned by phi about z_p and
mapped into the gear frame (q = B p + c), r2 the gear flank point (gear grid coordinates s2, h2)
at polar angle

    T = Theta2(s2, h2) - ratio * phi + gear_angle + offset - gear_sense * lambda,

i.e. the gear lagging by lambda behind its ideal position (the angular clearance at the contact,
:mod:`gearopt.contact.field`), n1 = r1_s1 x r1_h1 and the normal equations normalised by
|n1| |r2_s2| and |n1| |r2_h2|. The flanks are jets (:class:`gearopt.flank_jet.FlankJet`), so the
Jacobian is analytic. Local synthesis solves them on Taylor jets; the textbook TCA
(:mod:`gearopt.newton_tca`, the engine's reference) solves them position by position.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from gearopt.contact.boundary import boundary_cells
from gearopt.contact.field import ClearanceField
from gearopt.flank_jet import FlankJet, cosine, cross

__all__ = ["TangencySystem"]


class TangencySystem:
    """The tangency equations of one ClearanceField (module docstring), with their analytic
    Jacobian: the pinion point r1(s1, h1; phi) and the gear point r2(s2, h2; lambda) coincide
    and the pinion's normal is normal to the gear flank (seed 003 section 4)."""

    def __init__(self, field: ClearanceField) -> None:
        self.field = field
        # the pinion on the engine's fine cells at its generated boundary, as the engine has it
        self.pinion = FlankJet(field.pinion, boundary_cells(field.pinion))
        self.gear = FlankJet(field.gear)
        self.b, self.c = field.b, field.c
        self.gs = float(field.gear_sense)

    @classmethod
    def of_jets(cls, pinion, gear, *, b: NDArray, c: NDArray, gear_sense: float) -> TangencySystem:
        """The equations of two jets (anything with ``surface(s, h, turn)``, ``sg``, ``cg``
        like :class:`FlankJet`) placed by ``q = b p + c``, without a ClearanceField (the
        angles are then the caller's: :meth:`__call__` only)."""
        system = cls.__new__(cls)
        system.field = None
        system.pinion, system.gear = pinion, gear
        system.b, system.c = b, c
        system.gs = float(gear_sense)
        return system

    def angles(self, u: float, gear_angle_rad: float) -> tuple[float, float]:
        """Pinion angle phi and the gear's polar-angle offset (before the lag) at rotation u."""
        f = self.field
        phi = f.sense * u
        return phi, -f.ratio * phi + gear_angle_rad + f.gear_offset_rad

    def pinion_point(self, s1: float, h1: float, phi: float) -> tuple[NDArray, NDArray]:
        """The pinion point (s1, h1) at angle phi: ``(p, q)`` in the pinion and gear frames."""
        p = self.pinion.surface(s1, h1, phi)[0]
        return p, self.b @ p + self.c

    def __call__(self, phi: float, gear_turn: float, x: NDArray):
        """``(F, J, inside_pinion, inside_gear)`` at the unknowns x."""
        s1, h1, s2, h2, lag = (float(v) for v in x)
        b = self.b
        p, p_s, p_h, p_ss, p_sh, p_hh, _, _, _, _, in1 = self.pinion.surface(s1, h1, phi)
        q = b @ p + self.c
        a1, b1 = b @ p_s, b @ p_h
        n1 = cross(a1, b1)
        n1_s = cross(b @ p_ss, b1) + cross(a1, b @ p_sh)
        n1_h = cross(b @ p_sh, b1) + cross(a1, b @ p_hh)
        gs, sg2, cg2 = self.gs, self.gear.sg, self.gear.cg
        r, r_s, r_h, r_ss, r_sh, r_hh, big_r2, e_r, e_t, (t_s, t_h), in2 = self.gear.surface(
            s2, h2, gear_turn - gs * lag
        )
        # the lag turns the polar angle by -gs lambda: e_r' = -gs e_t, e_t' = gs e_r
        r_l = -gs * big_r2 * e_t
        r_sl = gs * (big_r2 * t_s * e_r - sg2 * e_t)
        r_hl = gs * (big_r2 * t_h * e_r - cg2 * e_t)
        f_s, ga_s, gb_s = cosine(n1, r_s)
        f_h, ga_h, gb_h = cosine(n1, r_h)
        F = np.empty(5)
        F[:3] = q - r
        F[3], F[4] = f_s, f_h
        J = np.empty((5, 5))
        J[:3, 0], J[:3, 1] = a1, b1
        J[:3, 2], J[:3, 3], J[:3, 4] = -r_s, -r_h, -r_l
        J[3] = [ga_s @ n1_s, ga_s @ n1_h, gb_s @ r_ss, gb_s @ r_sh, gb_s @ r_sl]
        J[4] = [ga_h @ n1_s, ga_h @ n1_h, gb_h @ r_sh, gb_h @ r_hh, gb_h @ r_hl]
        return F, J, in1, in2
