"""Single-point jets of a FlankMap's local interpolant: the flank point with its first and
second derivatives in grid coordinates, for Newton's method on the tangency equations (the
contact interval ends' reference, local synthesis) and for the path's direction on a flank."""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from gearopt.flank import FlankMap

__all__ = ["FlankJet", "cosine", "cross"]


class FlankJet:
    """Theta of a FlankMap's local Hermite interpolant with its first and second derivatives,
    at single points. The cell is found by the arithmetic of
    :meth:`gearopt.flank.HermiteCells.locate` on Python floats (the same cell and unit
    coordinates, without numpy's per-call overhead); beyond the grid the edge cell's polynomial
    is extended, as in :meth:`gearopt.flank.FlankMap.polar_angle_local`. With ``fine`` (the
    ``(band, coefficients)`` of :func:`gearopt.contact.boundary.boundary_cells`) a cell that
    has fine cells is evaluated on them, as the contact engine evaluates the pinion."""

    def __init__(self, fm: FlankMap, fine: tuple[NDArray, NDArray] | None = None) -> None:
        self.cells = fm.cells
        self.fine = fine
        fs, fp = fm.face_mm, fm.profile_mm
        self.s0, self.h0 = float(fs[0]), float(fp[0])
        self.n_f, self.n_p = len(fs), len(fp)
        self.ds = float((fs[-1] - fs[0]) / (self.n_f - 1))
        self.dh = float((fp[-1] - fp[0]) / (self.n_p - 1))
        g = math.radians(fm.pitch_angle_deg)
        self.sg, self.cg = math.sin(g), math.cos(g)

    def polar(self, s: float, h: float):
        """``(theta, t_s, t_h, t_ss, t_sh, t_hh, inside)`` at ``(s, h)``."""
        x = (s - self.s0) / self.ds
        y = (h - self.h0) / self.dh
        i = min(max(math.floor(x), 0), self.n_f - 2)
        j = min(max(math.floor(y), 0), self.n_p - 2)
        within = 0.0 <= x <= self.n_f - 1 and 0.0 <= y <= self.n_p - 1
        u, v = x - i, y - j
        cell = i * self.cells.columns + j
        c = self.cells.polynomial(cell)
        ds, dh = self.ds, self.dh
        if self.fine is not None and self.fine[0][cell, 0] >= 0.0:
            b, o, k, m = self.fine[0][cell]
            y = (o + v) * k
            n = min(max(math.floor(y), 0.0), m - 1.0)
            c = self.fine[1][int(b + n)].reshape(4, 4)
            v, dh = y - n, dh / k
        uu = np.array([1.0, u, u * u, u * u * u])
        du = np.array([0.0, 1.0, 2.0 * u, 3.0 * u * u]) / ds
        d2u = np.array([0.0, 0.0, 2.0, 6.0 * u]) / (ds * ds)
        vv = np.array([1.0, v, v * v, v * v * v])
        dv = np.array([0.0, 1.0, 2.0 * v, 3.0 * v * v]) / dh
        d2v = np.array([0.0, 0.0, 2.0, 6.0 * v]) / (dh * dh)
        cv, cdv = c @ vv, c @ dv
        return (
            float(uu @ cv),
            float(du @ cv),
            float(uu @ cdv),
            float(d2u @ cv),
            float(du @ cdv),
            float(uu @ (c @ d2v)),
            bool(within and self.cells.generated[cell]),
        )

    def surface(self, s: float, h: float, turn: float):
        """Flank point at ``(s, h)`` with polar angle Theta + ``turn``, member frame:
        ``(p, p_s, p_h, p_ss, p_sh, p_hh, radius, e_r, e_t, (t_s, t_h), inside)``."""
        th, t_s, t_h, t_ss, t_sh, t_hh, inside = self.polar(s, h)
        sg, cg = self.sg, self.cg
        big_r = s * sg + h * cg
        big_l = s * cg - h * sg
        angle = th + turn
        ca, sa = math.cos(angle), math.sin(angle)
        e_r = np.array([ca, sa, 0.0])
        e_t = np.array([-sa, ca, 0.0])
        e_z = np.array([0.0, 0.0, 1.0])
        # P = R e_r + L e_z with R, L linear in (s, h): P_x = R_x e_r + R T_x e_t + L_x e_z,
        # P_xy = (R_x T_y + R_y T_x + R T_xy) e_t - R T_x T_y e_r
        p = big_r * e_r + big_l * e_z
        p_s = sg * e_r + big_r * t_s * e_t + cg * e_z
        p_h = cg * e_r + big_r * t_h * e_t - sg * e_z
        p_ss = (2.0 * sg * t_s + big_r * t_ss) * e_t - big_r * t_s * t_s * e_r
        p_sh = (sg * t_h + cg * t_s + big_r * t_sh) * e_t - big_r * t_s * t_h * e_r
        p_hh = (2.0 * cg * t_h + big_r * t_hh) * e_t - big_r * t_h * t_h * e_r
        return p, p_s, p_h, p_ss, p_sh, p_hh, big_r, e_r, e_t, (t_s, t_h), inside


def cross(a: NDArray, b: NDArray) -> NDArray:
    """a x b of two 3-vectors (np.cross costs more than the rest of an evaluation)."""
    return np.array(
        [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
    )


def cosine(a: NDArray, b: NDArray):
    """a.b / (|a| |b|) and its gradients with respect to a and b."""
    na, nb = math.sqrt(a @ a), math.sqrt(b @ b)
    ah, bh = a / na, b / nb
    f = float(ah @ bh)
    return f, (bh - f * ah) / na, (ah - f * bh) / nb
