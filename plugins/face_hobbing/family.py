"""The face-hobbing generating family r(u, theta, psi_cr) and its meshing function (seed 001).

One blade system (inner or outer) of a face-hobbing head, as seed 001 writes it for a right-hand
member: the cutting edge in the blade frame (eqs 2-4), the cutter (eqs 7-8), the cutter rotation
theta (eqs 15-16), the cradle rotation psi_cr (eqs 17-19), the work (eqs 20-23). Everything is
evaluated in the machine frame S_m, where the derivatives are cross products:

* d r / d psi_cr: the cradle turns about z_m, the work about its axis a_w by m_gc psi_cr;
* d r / d theta: the cutter turns about its axis through its centre, the work by -m_gb theta;

so ``f = (r_u x r_theta) . r_psi`` (eq 31) and the axial-plane coordinates of the work point
(L along a_w, R from the axis) need no work-frame transform; only the polar angle does.

Outer blades are the inner blade's edge mirrored in its front plane (the edge faces the other
way); inner blades cut the convex flank, outer blades the concave flank.

Machine settings outside seed 001's chain (machine centre to back dX_D, blank offset dE_m, sliding
base dX_B) translate the work frame in S_m: along a_w, along y_m and along z_m.

All functions accept complex arrays (complex-step derivatives), and blade systems stacked by
:meth:`BladeSystem.stack` (every constant an array, one entry per blade system, indexed by
:meth:`BladeSystem.take`) so that both flanks of a member are solved in one batch.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields, replace

import numpy as np
from numpy.typing import NDArray

__all__ = [
    "BladeSystem",
    "components",
    "edge",
    "edge_second",
    "family",
    "meshing_jacobian",
    "pitch_line_start",
    "pitch_line_starts",
]


@dataclass(frozen=True, kw_only=True)
class BladeSystem:
    """Constants of one blade system of one member's machine (radians and mm).

    ``side`` is +1 for the inner blade (convex flank) and -1 for the outer blade (concave).
    In a stacked system (:meth:`stack`) every field is an array with one entry per system.
    """

    side: int
    cutter_radius_mm: float
    assembly_angle_rad: float  # delta_k = nu'_k (eqs 11, 38)
    machine_distance_mm: float  # M_dk (eq 34)
    cradle_angle_rad: float  # q_2k (eq 35)
    spiral_angle_rad: float  # psi_m
    pressure_angle_rad: float  # alpha_k on the front plane
    rake_angle_rad: float  # alpha_r (eq 4)
    parabola_per_mm: float  # a_p (eq 2)
    parabola_apex_mm: float  # u_o (eq 2)
    machine_root_angle_rad: float  # gamma_m (eq 22)
    gear_to_cradle_roll: float  # m_gc (eq 25)
    gear_to_blade_roll: float  # m_gb (eq 37)
    work_offset_mm: tuple[float, float, float] = (0.0, 0.0, 0.0)  # (dX_D, dE_m, dX_B)
    #: the blade's lag behind the paper's blade: it is where that blade is at theta - phase
    #: (k 2 pi / N_b for the k-th blade group)
    phase_rad: float = 0.0
    #: 1 / R_b of a circular-arc edge (seed 003), 0 for the straight edge of seed 001 eq 2; the
    #: arc is tangent to the straight edge at u = 0 and bends toward the tooth material
    profile_curvature_per_mm: float = 0.0

    @classmethod
    def stack(cls, systems) -> BladeSystem:
        """The blade systems ``systems`` as one with array fields (leading axis: the system)."""
        names = [f.name for f in fields(cls)]
        return cls(**{n: np.array([getattr(b, n) for b in systems], dtype=float) for n in names})

    def take(self, index) -> BladeSystem:
        """The stacked systems' constants at ``index`` (an integer array: one per point)."""
        return replace(self, **{f.name: getattr(self, f.name)[index] for f in fields(self)})

    @property
    def work_axis(self) -> NDArray:
        """Unit vector of the work axis in S_m (eq 22: the cone axis makes gamma_m with x_m)."""
        g = self.machine_root_angle_rad
        return np.array([math.cos(g), 0.0, math.sin(g)])

    @property
    def work_origin(self) -> NDArray:
        """Origin of the work frame in S_m (the cone apex, moved by dX_D, dE_m, dX_B)."""
        dxd, dem, dxb = self.work_offset_mm
        return dxd * self.work_axis + np.array([0.0, dem, dxb])


def _cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def _sincos(x):
    """``(sin x, cos x)``; for a complex-step argument ``a + i h`` (h tiny) from real trig,
    sin = sin a + i h cos a and cos = cos a - i h sin a: exact to machine precision and three
    times cheaper than complex trig."""
    if not np.iscomplexobj(x):
        return np.sin(x), np.cos(x)
    a, h = x.real, x.imag
    s, c = np.sin(a), np.cos(a)
    return s + 1j * (h * c), c - 1j * (h * s)


def edge(b: BladeSystem, u):
    """Cutting edge in the blade frame S_a (eq 2): x_a, y_a and their u-derivatives.

    With a profile curvature k = 1 / R_b (seed 003's cutter edge radius) the straight part of
    the edge becomes the exact circular arc of radius R_b tangent to it at u = 0, u its arc
    length: along the straight edge sin(k u) / k, toward the tooth material (the direction of
    a positive parabola, eq 2) (1 - cos(k u)) / k, so the arc's centre lies on the material
    side (profile crowning). The parabola of eq 2 is added on top, along the same normal.
    """
    sa, ca = np.sin(b.pressure_angle_rad), np.cos(b.pressure_angle_rad)
    w = u - b.parabola_apex_mm
    q = b.parabola_per_mm * w * w
    dq = 2.0 * b.parabola_per_mm * w
    if not np.any(b.profile_curvature_per_mm):
        return b.side * (-u * sa - q * ca), u * ca - q * sa, b.side * (-sa - dq * ca), ca - dq * sa
    along, off, d_along, d_off = _arc(b.profile_curvature_per_mm, u)
    off, d_off = off + q, d_off + dq
    return (
        b.side * (-along * sa - off * ca),
        along * ca - off * sa,
        b.side * (-d_along * sa - d_off * ca),
        d_along * ca - d_off * sa,
    )


def _arc(k, u):
    """The arc of curvature ``k`` (array; 0 = straight) tangent to the u axis at u = 0, by arc
    length u: ``(along, off, d along / du, d off / du)`` with along = sin(k u) / k and
    off = (1 - cos(k u)) / k = 2 sin^2(k u / 2) / k (no cancellation for small k u)."""
    k = np.asarray(k, dtype=float)
    straight = k == 0.0
    kk = np.where(straight, 1.0, k)
    s, c = _sincos(k * u)
    sh, _ = _sincos(0.5 * k * u)
    along = np.where(straight, u, s / kk)
    off = np.where(straight, 0.0 * u, 2.0 * sh * sh / kk)
    return along, off, np.where(straight, 1.0 + 0.0 * u, c), s


def edge_second(b: BladeSystem, u):
    """Second u-derivatives of the edge (x_a'', y_a'')."""
    sa, ca = np.sin(b.pressure_angle_rad), np.cos(b.pressure_angle_rad)
    if not np.any(b.profile_curvature_per_mm):
        return (
            b.side * (-2.0 * b.parabola_per_mm * np.cos(b.pressure_angle_rad)) + 0.0 * u,
            -2.0 * b.parabola_per_mm * np.sin(b.pressure_angle_rad) + 0.0 * u,
        )
    k = np.asarray(b.profile_curvature_per_mm, dtype=float)
    s, c = _sincos(k * u)
    dd_along = -k * s
    dd_off = k * c + 2.0 * b.parabola_per_mm
    return b.side * (-dd_along * sa - dd_off * ca), dd_along * ca - dd_off * sa


def components(b: BladeSystem, u, theta, psi) -> dict[str, tuple]:
    """:func:`family` as ``(x, y, z)`` component tuples (the fast path of the envelope solver).

    The chain S_a -> S_b (eq 4) -> S_c (eq 8) -> S_ck' (eq 16) -> S_d (eq 19) -> S_m (eq 18)
    collapses, for an edge point in the front plane z_a = 0, to rotations in the cradle plane:
    with chi = psi_m - delta + theta + psi_cr,

        x_m + i y_m = M_d e^{i (q_2 + psi_cr)} - i e^{i chi} (r_c + x_a e^{i (delta - alpha_r)}),

    and z_m = -y_a: eq 4 (rake alpha_r) and eq 8 (assembly angle delta) turn x_a together by
    delta - alpha_r about y_c, eq 16 (theta), eq 19 and eq 18 (psi_cr) about z_m.
    """
    xa, ya, dxa, dya = edge(b, u)
    chi = b.spiral_angle_rad - b.assembly_angle_rad + theta - b.phase_rad + psi
    tilt = b.assembly_angle_rad - b.rake_angle_rad
    s1, c1 = _sincos(chi)
    s2, c2 = _sincos(chi + tilt)
    # the cutter axis -y_c is +z_m (eq 19: z_d = -y_c; the cradle turns about z_m); its centre
    # O_c = M_d (cos q_2, sin q_2, 0) turns with the cradle
    md, q2 = b.machine_distance_mm, b.cradle_angle_rad
    sq, cq = _sincos(q2 + psi)
    cx, cy = md * cq, md * sq
    rc = b.cutter_radius_mm
    px, py, pz = cx + rc * s1 + xa * s2, cy - rc * c1 - xa * c2, -ya
    r_u = (dxa * s2, -dxa * c2, -dya)
    g = b.machine_root_angle_rad
    ca, sa = np.cos(g), np.sin(g)
    offset = np.asarray(b.work_offset_mm)
    dxd, dem, dxb = offset[..., 0], offset[..., 1], offset[..., 2]
    ox, oy, oz = dxd * ca, dem, dxd * sa + dxb  # the work origin, as work_origin
    rx, ry, rz = px - ox, py - oy, pz - oz
    # a_w x rel: velocity of the work point per unit work rotation
    wx, wy, wz = -sa * ry, sa * rx - ca * rz, ca * ry
    mgc, mgb = b.gear_to_cradle_roll, b.gear_to_blade_roll
    # d/d psi: cradle about z_m, work by m_gc psi (eq 23); relative to the work
    r_psi = (-py - mgc * wx, px - mgc * wy, -mgc * wz)
    # d/d theta: cutter about its axis, work by -m_gb theta (eq 23)
    r_theta = (cy - py + mgb * wx, px - cx + mgb * wy, mgb * wz)
    normal = _cross(r_u, r_theta)
    axial = rx * ca + rz * sa
    return {
        "point": (px, py, pz),
        "r_u": r_u,
        "r_theta": r_theta,
        "r_psi": r_psi,
        "normal": normal,
        "meshing": normal[0] * r_psi[0] + normal[1] * r_psi[1] + normal[2] * r_psi[2],
        "axial_mm": axial,
        "radius_mm": np.sqrt(rx * rx + ry * ry + rz * rz - axial * axial),
        "relative": (rx, ry, rz),
        "centre": (cx, cy),
        "edge_direction": (s2, -c2),
        "work_axis": (ca, sa),
    }


def _dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def _add(a, b, k=1.0):
    return (a[0] + k * b[0], a[1] + k * b[1], a[2] + k * b[2])


def meshing_jacobian(b: BladeSystem, u, theta, psi, scale_mm: float):
    """``(L, R, g)`` with g = (N . r_psi) / (|N| A) (eq 31 normalised) and their Jacobian
    ``(..., 3, 3)`` with respect to (u, theta, psi), analytically (real arithmetic).

    The Jacobian of the dot products is taken in S_m, where they are plain functions of q. The
    machine-frame velocities of the edge point are V_u = r_u, V_theta = z x (P - C) (the cutter
    turns about its axis through C) and V_psi = z x P (the cradle), C turning with the cradle;
    r_theta = V_theta + m_gb a x (P - O), r_psi = V_psi - m_gc a x (P - O), and
    d/dq_k (a x (P - O)) = a x V_k, d/dq_k r_u = z x r_u for theta and psi.
    """
    f = components(b, u, theta, psi)
    xa, ya, dxa, dya = edge(b, u)
    d2xa, d2ya = edge_second(b, u)
    ca, sa = f["work_axis"]
    zero = 0.0 * u

    def zx(v):  # z x v
        return (-v[1], v[0], zero)

    def ax(v):  # a x v, a = (cos g, 0, sin g)
        return (-sa * v[1], sa * v[0] - ca * v[2], ca * v[1])

    px, py, pz = f["point"]
    cx, cy = f["centre"]
    ex, ey = f["edge_direction"]
    r_u, r_t, r_p, n = f["r_u"], f["r_theta"], f["r_psi"], f["normal"]
    v_t = zx((px - cx, py - cy, pz))
    v_p = zx((px, py, pz))
    mgb, mgc = b.gear_to_blade_roll, b.gear_to_cradle_roll
    d_ru = ((d2xa * ex, d2xa * ey, -d2ya), zx(r_u), zx(r_u))
    d_rt = (
        _add(zx(r_u), ax(r_u), mgb),
        _add(zx(v_t), ax(v_t), mgb),
        _add(zx(v_t), ax(v_p), mgb),
    )
    d_rp = tuple(_add(zx(v), ax(v), -mgc) for v in (r_u, v_t, v_p))
    rel = f["relative"]
    big_l, big_r = f["axial_mm"], f["radius_mm"]
    radial = (rel[0] - big_l * ca, rel[1], rel[2] - big_l * sa)
    norm2 = _dot(n, n)
    norm = np.sqrt(norm2)
    meshing = _dot(n, r_p)
    g = meshing / (norm * scale_mm)
    rows = [[], [], []]
    for k, v in enumerate((r_u, r_t, r_p)):
        rows[0].append(ca * v[0] + sa * v[2])
        rows[1].append(_dot(radial, v) / big_r)
        dn = _add(_cross(d_ru[k], r_t), _cross(r_u, d_rt[k]))
        dm = _dot(dn, r_p) + _dot(n, d_rp[k])
        rows[2].append((dm - meshing * _dot(n, dn) / norm2) / (norm * scale_mm))
    jac = np.stack([np.stack(np.broadcast_arrays(*row), axis=-1) for row in rows], axis=-2)
    return big_l, big_r, g, jac


def family(b: BladeSystem, u, theta, psi):
    """Point and partial derivatives of the generating family in S_m, relative to the work.

    Parameters
    ----------
    u, theta, psi
        Blade parameter (mm), cutter phase and cradle angle (rad), arrays of one shape ``S``.

    Returns
    -------
    dict
        ``point`` (S, 3) in S_m; ``r_u``, ``r_theta``, ``r_psi`` (S, 3): the partial
        derivatives of the work-frame point expressed in S_m; ``normal`` = r_u x r_theta;
        ``meshing`` = normal . r_psi (eq 31); ``axial_mm`` L and ``radius_mm`` R of the point
        in the work's axial plane.
    """
    u, theta, psi = np.broadcast_arrays(u, theta, psi)
    out = components(b, u, theta, psi)
    for key in ("point", "r_u", "r_theta", "r_psi", "normal"):
        out[key] = np.stack(np.broadcast_arrays(*out[key]), axis=-1)
    return out


def pitch_line_start(b: BladeSystem, cone_distance_mm):
    """Closed-form (u, theta, psi_cr) where the blade's pitch point meets the pitch line.

    With u = 0 the edge point lies in the cradle plane on the circle of radius r_c about the
    cutter centre O_c = M_d (cos q_2, sin q_2); the law of cosines gives the cutter phase at which
    it is ``cone_distance_mm`` from O_m, and an atan2 the cradle angle that puts it on x_m, the
    line where the crown gear's pitch plane touches the work's pitch cone.
    """
    s = np.asarray(cone_distance_mm, dtype=float)
    md, q2, rc = b.machine_distance_mm, b.cradle_angle_rad, b.cutter_radius_mm
    e = b.spiral_angle_rad - b.assembly_angle_rad
    phi = q2 + np.arcsin((s**2 - md**2 - rc**2) / (2.0 * md * rc))
    theta = phi - e + b.phase_rad
    xd = rc * np.sin(phi) + md * math.cos(q2)
    yd = -rc * np.cos(phi) + md * math.sin(q2)
    return np.zeros_like(s), theta, -np.arctan2(yd, xd)


def pitch_line_starts(blades, cone_distance_mm) -> NDArray:
    """``(len(blades), n, 3)``: :func:`pitch_line_start` of each blade system at the cone
    distances ``(n,)``, stacked, in one batch of numpy calls (the same operations on the same
    values: the same bits)."""
    s = np.asarray(cone_distance_mm, dtype=float)
    # per system (k, 1), each constant as pitch_line_start's Python arithmetic makes it
    md2, rc2, den, e, phase, rc, minus_rc, xc, yc = np.array(
        [
            [
                b.machine_distance_mm**2,
                b.cutter_radius_mm**2,
                2.0 * b.machine_distance_mm * b.cutter_radius_mm,
                b.spiral_angle_rad - b.assembly_angle_rad,
                b.phase_rad,
                b.cutter_radius_mm,
                -b.cutter_radius_mm,
                b.machine_distance_mm * math.cos(b.cradle_angle_rad),
                b.machine_distance_mm * math.sin(b.cradle_angle_rad),
            ]
            for b in blades
        ],
        dtype=float,
    ).T[:, :, None]
    q2 = np.array([[b.cradle_angle_rad] for b in blades], dtype=float)
    phi = q2 + np.arcsin((s**2 - md2 - rc2) / den)
    theta = phi - e + phase
    xd = rc * np.sin(phi) + xc
    yd = minus_rc * np.cos(phi) + yc
    return np.stack([np.zeros_like(theta), theta, -np.arctan2(yd, xd)], axis=-1)
