"""Compiled kernels of the face-hobbing family (numba): the envelope solver's evaluations.

The same formulas as :func:`gearopt_plugins.face_hobbing.family.components`,
:func:`~gearopt_plugins.face_hobbing.family.meshing_jacobian` and
:meth:`~gearopt_plugins.face_hobbing.generation.FaceHobbingFamily.geometry`, written point by
point in the same order of operations (the parity test holds them to the numpy functions), so
that a grid of a few hundred nodes costs its points rather than numpy's fixed overhead per call
(the numpy path makes some three hundred calls per evaluation, the solver a dozen evaluations
per member). The numpy functions stay the reference and the complex-step path.

The blade systems come as a table (:func:`system_table`), one row per system: the columns of
:data:`FIELDS`, then the constant sines and cosines of :data:`TRIG_FIELDS`; ``flank`` ``(n,)``
picks each point's row.

The point evaluations :func:`_point_meshing`, :func:`_point_jacobian` and the node's Newton
iteration :func:`_newton_node` are compiled once and called, not inlined: inlined, the
iteration's two Jacobians were compiled again into each of :func:`newton` and
:func:`bisected` (36 s of a cold compile, now 7-9 s; the same flanks, bit for bit). The calls
cost about 0.1 ms of a member's 3-4 ms generation (with :func:`_point_jacobian` inlined again:
0.05 ms, and 15 s of compile).
"""

from __future__ import annotations

import math

import numpy as np

from gearopt.jit import ENABLED, compiled

__all__ = [
    "ENABLED",
    "FIELDS",
    "bisected",
    "blade_heights",
    "geometries",
    "meshing",
    "meshing_jacobians",
    "newton",
    "system_table",
    "TRIG_FIELDS",
    "warm",
]

#: the columns of a system table: :class:`~gearopt_plugins.face_hobbing.family.BladeSystem`'s
#: fields, the work offset split into its three components
FIELDS = (
    "side",
    "cutter_radius_mm",
    "assembly_angle_rad",
    "machine_distance_mm",
    "cradle_angle_rad",
    "spiral_angle_rad",
    "pressure_angle_rad",
    "rake_angle_rad",
    "parabola_per_mm",
    "parabola_apex_mm",
    "machine_root_angle_rad",
    "gear_to_cradle_roll",
    "gear_to_blade_roll",
    "work_offset_dxd_mm",
    "work_offset_dem_mm",
    "work_offset_dxb_mm",
    "phase_rad",
    "profile_curvature_per_mm",
)


#: the columns after :data:`FIELDS`: the sines and cosines of the pressure angle and the
#: machine root angle, constant per system (math.sin and math.cos, the functions the kernels'
#: own calls are: the same bits, once per system instead of at every evaluation)
TRIG_FIELDS = ("sin_pressure", "cos_pressure", "sin_root", "cos_root")


def system_table(systems) -> np.ndarray:
    """``(n_systems, len(FIELDS) + len(TRIG_FIELDS))`` float table of blade systems
    (:data:`FIELDS`, then :data:`TRIG_FIELDS`)."""
    rows = []
    for b in systems:
        dxd, dem, dxb = b.work_offset_mm
        rows.append(
            [
                b.side,
                b.cutter_radius_mm,
                b.assembly_angle_rad,
                b.machine_distance_mm,
                b.cradle_angle_rad,
                b.spiral_angle_rad,
                b.pressure_angle_rad,
                b.rake_angle_rad,
                b.parabola_per_mm,
                b.parabola_apex_mm,
                b.machine_root_angle_rad,
                b.gear_to_cradle_roll,
                b.gear_to_blade_roll,
                dxd,
                dem,
                dxb,
                b.phase_rad,
                b.profile_curvature_per_mm,
                math.sin(b.pressure_angle_rad),
                math.cos(b.pressure_angle_rad),
                math.sin(b.machine_root_angle_rad),
                math.cos(b.machine_root_angle_rad),
            ]
        )
    width = len(FIELDS) + len(TRIG_FIELDS)
    return np.ascontiguousarray(np.array(rows, dtype=float).reshape(-1, width))


@compiled(inline=True)
def _edge(t, u):
    """Edge point and first u-derivatives (x_a, y_a, x_a', y_a') of row ``t`` (family.edge)."""
    side = t[0]
    par, apex, k = t[8], t[9], t[17]
    sa, ca = t[18], t[19]  # sin, cos of the pressure angle t[6]
    w = u - apex
    q = par * w * w
    dq = 2.0 * par * w
    if k == 0.0:
        return side * (-u * sa - q * ca), u * ca - q * sa, side * (-sa - dq * ca), ca - dq * sa
    s, c = math.sin(k * u), math.cos(k * u)
    sh = math.sin(0.5 * k * u)
    along, off = s / k, 2.0 * sh * sh / k
    off, d_off = off + q, s + dq
    return (
        side * (-along * sa - off * ca),
        along * ca - off * sa,
        side * (-c * sa - d_off * ca),
        c * ca - d_off * sa,
    )


@compiled(inline=True)
def _edge_second(t, u):
    """Second u-derivatives (x_a'', y_a'') of row ``t`` (family.edge_second)."""
    side, par, k = t[0], t[8], t[17]
    sa, ca = t[18], t[19]  # sin, cos of the pressure angle t[6]
    if k == 0.0:
        return side * (-2.0 * par * ca), -2.0 * par * sa
    s, c = math.sin(k * u), math.cos(k * u)
    dd_along = -k * s
    dd_off = k * c + 2.0 * par
    return side * (-dd_along * sa - dd_off * ca), dd_along * ca - dd_off * sa


@compiled(inline=True)
def _components(t, u, theta, psi):
    """family.components at one point: edge, point, the centre, the edge direction, r_u,
    r_theta, r_psi, the relative point, the work axis (cos, sin)."""
    xa, ya, dxa, dya = _edge(t, u)
    chi = t[5] - t[2] + theta - t[16] + psi
    tilt = t[2] - t[7]
    s1, c1 = math.sin(chi), math.cos(chi)
    s2, c2 = math.sin(chi + tilt), math.cos(chi + tilt)
    md, q2 = t[3], t[4]
    sq, cq = math.sin(q2 + psi), math.cos(q2 + psi)
    cx, cy = md * cq, md * sq
    rc = t[1]
    px, py, pz = cx + rc * s1 + xa * s2, cy - rc * c1 - xa * c2, -ya
    ux, uy, uz = dxa * s2, -dxa * c2, -dya
    ca, sa = t[21], t[20]  # cos, sin of the machine root angle t[10]
    dxd, dem, dxb = t[13], t[14], t[15]
    ox, oy, oz = dxd * ca, dem, dxd * sa + dxb
    rx, ry, rz = px - ox, py - oy, pz - oz
    wx, wy, wz = -sa * ry, sa * rx - ca * rz, ca * ry
    mgc, mgb = t[11], t[12]
    ppx, ppy, ppz = -py - mgc * wx, px - mgc * wy, -mgc * wz
    tx, ty, tz = cy - py + mgb * wx, px - cx + mgb * wy, mgb * wz
    return (
        (px, py, pz),
        (cx, cy),
        (s2, -c2),
        (ux, uy, uz),
        (tx, ty, tz),
        (ppx, ppy, ppz),
        (rx, ry, rz),
        (ca, sa),
    )


@compiled(inline=True)
def _cross(a0, a1, a2, b0, b1, b2):
    return a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0


@compiled(inline=True)
def _axial_radial(rel, work_axis):
    rx, ry, rz = rel
    ca, sa = work_axis
    axial = rx * ca + rz * sa
    return axial, math.sqrt(rx * rx + ry * ry + rz * rz - axial * axial)


@compiled
def _point_meshing(t, u, theta, psi, scale_mm):
    """``(L, R, f / (|N| A))`` at one point (FaceHobbingFamily.axial_radial_meshing)."""
    _, _, _, r_u, r_t, r_p, rel, work_axis = _components(t, u, theta, psi)
    nx, ny, nz = _cross(r_u[0], r_u[1], r_u[2], r_t[0], r_t[1], r_t[2])
    m = nx * r_p[0] + ny * r_p[1] + nz * r_p[2]
    norm = math.sqrt(nx * nx + ny * ny + nz * nz)
    axial, radius = _axial_radial(rel, work_axis)
    return axial, radius, m / (norm * scale_mm)


@compiled
def meshing(table, flank, q, scale_mm, out):
    """``out[i] = (L, R, f / (|N| A))`` at the points ``q`` ``(n, 3)`` of systems ``flank``
    (FaceHobbingFamily.axial_radial_meshing)."""
    for i in range(q.shape[0]):
        out[i, 0], out[i, 1], out[i, 2] = _point_meshing(
            table[flank[i]], q[i, 0], q[i, 1], q[i, 2], scale_mm
        )


@compiled(inline=True)
def _dot(a0, a1, a2, b0, b1, b2):
    return a0 * b0 + a1 * b1 + a2 * b2


@compiled
def _point_jacobian(t, u, theta, psi, scale_mm):
    """``(L, R, g)`` and the rows of their Jacobian in (u, theta, psi) at one point
    (family.meshing_jacobian): ``(L, R, g, dL, dR, dg)``, each row a 3-tuple."""
    p, centre, e, r_u, r_t, r_p, rel, work_axis = _components(t, u, theta, psi)
    d2xa, d2ya = _edge_second(t, u)
    ca, sa = work_axis
    px, py, pz = p
    cx, cy = centre
    ex, ey = e
    mgb, mgc = t[12], t[11]
    # V_theta = z x (P - C), V_psi = z x P (third components zero)
    vtx, vty = -(py - cy), px - cx
    vpx, vpy = -py, px
    # z x r_u
    zux, zuy = -r_u[1], r_u[0]
    # a x v for v = r_u, V_theta, V_psi (a = (cos g, 0, sin g))
    aux, auy, auz = -sa * r_u[1], sa * r_u[0] - ca * r_u[2], ca * r_u[1]
    atx, aty, atz = -sa * vty, sa * vtx - ca * 0.0, ca * vty
    apx, apy, apz = -sa * vpy, sa * vpx - ca * 0.0, ca * vpy
    # zx(V_theta) and zx(V_psi)
    ztx, zty = -vty, vtx
    # d r_u / d q_k
    du = ((d2xa * ex, d2xa * ey, -d2ya), (zux, zuy, 0.0), (zux, zuy, 0.0))
    # d r_theta / d q_k = zx(.) + m_gb ax(.)
    dt = (
        (zux + mgb * aux, zuy + mgb * auy, 0.0 + mgb * auz),
        (ztx + mgb * atx, zty + mgb * aty, 0.0 + mgb * atz),
        (ztx + mgb * apx, zty + mgb * apy, 0.0 + mgb * apz),
    )
    # d r_psi / d q_k = zx(v) - m_gc ax(v) for v = r_u, V_theta, V_psi
    k = -mgc
    zpx, zpy = -vpy, vpx
    dp = (
        (zux + k * aux, zuy + k * auy, 0.0 + k * auz),
        (ztx + k * atx, zty + k * aty, 0.0 + k * atz),
        (zpx + k * apx, zpy + k * apy, 0.0 + k * apz),
    )
    big_l, big_r = _axial_radial(rel, work_axis)
    radial = (rel[0] - big_l * ca, rel[1], rel[2] - big_l * sa)
    nx, ny, nz = _cross(r_u[0], r_u[1], r_u[2], r_t[0], r_t[1], r_t[2])
    norm2 = nx * nx + ny * ny + nz * nz
    norm = math.sqrt(norm2)
    m = nx * r_p[0] + ny * r_p[1] + nz * r_p[2]
    den = norm * scale_mm
    rows_l = (ca * r_u[0] + sa * r_u[2], ca * r_t[0] + sa * r_t[2], ca * r_p[0] + sa * r_p[2])
    rows_r = (
        _dot(radial[0], radial[1], radial[2], r_u[0], r_u[1], r_u[2]) / big_r,
        _dot(radial[0], radial[1], radial[2], r_t[0], r_t[1], r_t[2]) / big_r,
        _dot(radial[0], radial[1], radial[2], r_p[0], r_p[1], r_p[2]) / big_r,
    )
    rows_g = (
        _meshing_column(du[0], dt[0], dp[0], r_u, r_t, r_p, nx, ny, nz, m, norm2, den),
        _meshing_column(du[1], dt[1], dp[1], r_u, r_t, r_p, nx, ny, nz, m, norm2, den),
        _meshing_column(du[2], dt[2], dp[2], r_u, r_t, r_p, nx, ny, nz, m, norm2, den),
    )
    return big_l, big_r, m / den, rows_l, rows_r, rows_g


@compiled(inline=True)
def _meshing_column(du, dt, dp, r_u, r_t, r_p, nx, ny, nz, m, norm2, den):
    """d g / d q_k from the derivatives of r_u, r_theta, r_psi in q_k."""
    a = _cross(du[0], du[1], du[2], r_t[0], r_t[1], r_t[2])
    b = _cross(r_u[0], r_u[1], r_u[2], dt[0], dt[1], dt[2])
    dnx, dny, dnz = a[0] + b[0], a[1] + b[1], a[2] + b[2]
    dm = _dot(dnx, dny, dnz, r_p[0], r_p[1], r_p[2]) + _dot(nx, ny, nz, dp[0], dp[1], dp[2])
    return (dm - m * _dot(nx, ny, nz, dnx, dny, dnz) / norm2) / den


@compiled
def meshing_jacobians(table, flank, q, scale_mm, out, jac):
    """``out[i] = (L, R, g)`` and ``jac[i]`` their ``(3, 3)`` Jacobian in (u, theta, psi) at
    the points ``q`` ``(n, 3)`` of systems ``flank`` (family.meshing_jacobian)."""
    for i in range(q.shape[0]):
        big_l, big_r, g, dl, dr, dg = _point_jacobian(
            table[flank[i]], q[i, 0], q[i, 1], q[i, 2], scale_mm
        )
        out[i, 0], out[i, 1], out[i, 2] = big_l, big_r, g
        for c in range(3):
            jac[i, 0, c], jac[i, 1, c], jac[i, 2, c] = dl[c], dr[c], dg[c]


@compiled(inline=True)
def _scaled(t, u, theta, psi, big_l, big_r, scale_mm):
    """The envelope solver's residuals ``((L - L0) / A, (R - R0) / A, g)`` and Jacobian rows
    (those of L and R times 1 / A), as gearopt.envelope scales them."""
    l_, r_, g, dl, dr, dg = _point_jacobian(t, u, theta, psi, scale_mm)
    inv = 1.0 / scale_mm
    f = ((l_ - big_l) / scale_mm, (r_ - big_r) / scale_mm, g)
    jac = ((dl[0] * inv, dl[1] * inv, dl[2] * inv), (dr[0] * inv, dr[1] * inv, dr[2] * inv), dg)
    return f, jac


@compiled(inline=True)
def _max_abs(f):
    """max |f_k|, NaN when any is NaN (as numpy's max)."""
    a, b, c = abs(f[0]), abs(f[1]), abs(f[2])
    if a != a or b != b or c != c:
        return math.nan
    return max(a, max(b, c))


@compiled(inline=True)
def _solve3(jac, b):
    """``(x, det)``: the solution of ``jac x = b`` by LU with partial pivoting and the
    determinant (LAPACK's getrf/getrs order of operations for a 3 x 3 system)."""
    (a00, a01, a02), (a10, a11, a12), (a20, a21, a22) = jac
    b0, b1, b2 = b
    sign = 1.0
    # column 0: pivot, multipliers by the pivot's reciprocal, update
    if abs(a10) > abs(a00) and abs(a10) >= abs(a20):
        a00, a01, a02, a10, a11, a12 = a10, a11, a12, a00, a01, a02
        b0, b1 = b1, b0
        sign = -sign
    elif abs(a20) > abs(a00) and abs(a20) > abs(a10):
        a00, a01, a02, a20, a21, a22 = a20, a21, a22, a00, a01, a02
        b0, b2 = b2, b0
        sign = -sign
    r = 1.0 / a00
    l1, l2 = a10 * r, a20 * r
    a11, a12 = a11 - l1 * a01, a12 - l1 * a02
    a21, a22 = a21 - l2 * a01, a22 - l2 * a02
    b1, b2 = b1 - l1 * b0, b2 - l2 * b0
    # column 1
    if abs(a21) > abs(a11):
        a11, a12, a21, a22 = a21, a22, a11, a12
        b1, b2 = b2, b1
        sign = -sign
    l21 = a21 * (1.0 / a11)
    a22 = a22 - l21 * a12
    b2 = b2 - l21 * b1
    det = sign * (a00 * a11 * a22)
    # back substitution, column by column
    x2 = b2 / a22
    b0, b1 = b0 - x2 * a02, b1 - x2 * a12
    x1 = b1 / a11
    b0 = b0 - x1 * a01
    return (b0 / a00, x1, x2), det


@compiled(inline=True)
def _clipped(step, limit):
    """``step`` scaled so that no component exceeds its ``limit`` (gearopt.envelope)."""
    s0, s1, s2 = step
    if s0 != s0 or s1 != s1 or s2 != s2:
        return (math.nan, math.nan, math.nan)
    scale = min(
        limit[0] / max(abs(s0), 1e-300),
        min(limit[1] / max(abs(s1), 1e-300), limit[2] / max(abs(s2), 1e-300)),
    )
    scale = min(scale, 1.0)
    return (s0 * scale, s1 * scale, s2 * scale)


@compiled
def _newton_node(t, q0, q1, q2, l0, r0, scale_mm, limit, tol, max_iter, give_up, chords):
    """:func:`newton` at one node of system row ``t`` from ``(q0, q1, q2)`` toward the axial
    plane target ``(l0, r0)``: ``(q, f, jac, iterations)`` (``give_up``: iterations,
    residual)."""
    f, jac = _scaled(t, q0, q1, q2, l0, r0, scale_mm)
    it = 0
    while it < max_iter:
        norm = _max_abs(f)
        if not (math.isfinite(norm) and norm > tol):
            break
        if it >= give_up[0] and not norm < give_up[1]:
            break
        it += 1
        step, det = _solve3(jac, (-f[0], -f[1], -f[2]))
        if not abs(det) > 1e-300:
            break
        step = _clipped(step, limit)
        q0, q1, q2 = q0 + step[0], q1 + step[1], q2 + step[2]
        # chord step: same Jacobian, residual from a real evaluation
        if chords:
            big, rad, g = _point_meshing(t, q0, q1, q2, scale_mm)
            fr = ((big - l0) / scale_mm, (rad - r0) / scale_mm, g)
            if _max_abs(fr) > tol:
                chord = _clipped(_solve3(jac, (-fr[0], -fr[1], -fr[2]))[0], limit)
                q0, q1, q2 = q0 + chord[0], q1 + chord[1], q2 + chord[2]
        f, jac = _scaled(t, q0, q1, q2, l0, r0, scale_mm)
    return (q0, q1, q2), f, jac, it


@compiled
def newton(
    table,
    flank,
    q,
    big_l,
    big_r,
    scale_mm,
    limit,
    tol,
    max_iter,
    give_up_iterations,
    give_up_residual,
    chords,
    f_out,
    jac_out,
    converged,
):
    """gearopt.envelope's batched Newton-Shamanskii iteration, node by node: ``q`` ``(n, 3)``
    solved in place; the final scaled residuals ``f_out``, Jacobians ``jac_out``, convergence;
    returns the number of iterations (the most any node made).

    Each iteration: a Newton step with a fresh Jacobian, then (``chords``) a chord step with the
    same Jacobian from a real evaluation of the residual where it is still above ``tol``; steps
    clipped per unknown to ``limit``; a node stops when its residual is within ``tol``, is not
    finite, its Jacobian is singular, or after ``give_up_iterations`` it is still above
    ``give_up_residual``."""
    most = 0
    give_up = (give_up_iterations, give_up_residual)
    for i in range(q.shape[0]):
        qi, f, jac, it = _newton_node(
            table[flank[i]],
            q[i, 0],
            q[i, 1],
            q[i, 2],
            big_l[i],
            big_r[i],
            scale_mm,
            limit,
            tol,
            max_iter,
            give_up,
            chords,
        )
        most = max(most, it)
        q[i, 0], q[i, 1], q[i, 2] = qi
        for r in range(3):
            f_out[i, r] = f[r]
            for c in range(3):
                jac_out[i, r, c] = jac[r][c]
        norm = _max_abs(f)
        converged[i] = math.isfinite(norm) and norm <= tol
    return most


@compiled
def bisected(
    table,
    flank,
    q_up,
    face_mm,
    lower,
    upper,
    cos_sin,
    scale_mm,
    limit,
    tol,
    bisections,
    by_sheet,
    sheet,
    least_height_mm,
    out,
):
    """gearopt.envelope's bisection of where a column's accepted points end
    (``gearopt.envelope._bisected`` on uniform depth), node by node: between ``lower[i]`` (not
    accepted) and ``upper[i]`` (accepted, parameters ``q_up[i]``) on the face position
    ``face_mm[i]``, ``bisections`` times the middle solved by :func:`newton` (8 iterations,
    given up after 3 above 1e-6, chords) from the last accepted point; ``out[i]`` the last
    accepted profile coordinate. Accepted: converged and, ``by_sheet``, the Jacobian's
    determinant of the sign ``sheet[i]`` (on the envelope's sheet, LAPACK's LU as numpy's
    det), else the edge point's height at least ``least_height_mm`` (the tool reaches it)."""
    cg, sg = cos_sin[0], cos_sin[1]
    # typed as newton's arguments (not literals), so that _newton_node compiles once for both
    give_up, iterations, chords = (np.int64(3), 1e-6), np.int64(8), np.bool_(True)
    zero = (0.0, 0.0, 0.0)
    for i in range(q_up.shape[0]):
        t = table[flank[i]]
        s = face_mm[i]
        lo, up = lower[i], upper[i]
        q0, q1, q2 = q_up[i, 0], q_up[i, 1], q_up[i, 2]
        for _ in range(bisections):
            mid = 0.5 * (lo + up)
            big_l, big_r = s * cg - mid * sg, s * sg + mid * cg
            qm, f, jac, _ = _newton_node(
                t, q0, q1, q2, big_l, big_r, scale_mm, limit, tol, iterations, give_up, chords
            )
            norm = _max_abs(f)
            ok = math.isfinite(norm) and norm <= tol
            if ok and by_sheet:
                det = _solve3(jac, zero)[1]
                ok = (1.0 if det > 0.0 else (-1.0 if det < 0.0 else 0.0)) == sheet[i]
            elif ok:
                ok = _edge(t, qm[0])[1] >= least_height_mm
            if ok:
                up = mid
                q0, q1, q2 = qm
            else:
                lo = mid
        out[i] = up


@compiled
def geometries(table, flank, q, point, normal):
    """``point[i]`` and unit ``normal[i]`` in the work frame at the points ``q`` ``(n, 3)`` of
    systems ``flank`` (FaceHobbingFamily.geometry)."""
    for i in range(q.shape[0]):
        t = table[flank[i]]
        theta, psi = q[i, 1], q[i, 2]
        p, _, _, r_u, r_t, _, _, _ = _components(t, q[i, 0], theta, psi)
        sg, cg = t[20], t[21]  # of the machine root angle t[10]
        psi_g = t[11] * psi - t[12] * theta  # eq 23
        cp, sp = math.cos(psi_g), math.sin(psi_g)
        dxd, dem, dxb = t[13], t[14], t[15]
        # eq 22 (M_qm) then eq 21 (M_gq = rot_z(-psi_g))
        x, y, z = p[0] - dxd * cg, p[1] - dem, p[2] - dxd * sg - dxb
        xq, zq = sg * x - cg * z, cg * x + sg * z
        point[i, 0] = cp * xq + sp * y
        point[i, 1] = -sp * xq + cp * y
        point[i, 2] = zq
        x, y, z = _cross(r_u[0], r_u[1], r_u[2], r_t[0], r_t[1], r_t[2])
        xq, zq = sg * x - cg * z, cg * x + sg * z
        nx, ny, nz = cp * xq + sp * y, -sp * xq + cp * y, zq
        norm = math.sqrt(nx * nx + ny * ny + nz * nz)
        side = t[0]
        normal[i, 0] = side * (nx / norm)
        normal[i, 1] = side * (ny / norm)
        normal[i, 2] = side * (nz / norm)


@compiled
def blade_heights(table, flank, u, out):
    """``out[i]``: the height y_c of the edge point ``u[i]`` of system ``flank[i]``."""
    for i in range(u.shape[0]):
        out[i] = _edge(table[flank[i]], u[i])[1]


def warm() -> None:
    """Compile every kernel, or load it from numba's disk cache, in this process (on one
    point of a straight and a curved blade), with the argument types the generation passes
    (:mod:`~gearopt_plugins.face_hobbing.generation`: writable, contiguous arrays). Nothing
    without the kernels."""
    if not ENABLED:
        return
    table = np.zeros((2, len(FIELDS) + len(TRIG_FIELDS)))
    table[:, 0], table[:, 1], table[:, 3] = 1.0, 100.0, 50.0
    table[1, 17] = 1e-3
    flank, q, u = np.array([0, 1], np.intp), np.zeros((2, 3)), np.zeros(2)
    out, jac = np.empty((2, 3)), np.empty((2, 3, 3))
    meshing(table, flank, q, 100.0, out)
    meshing_jacobians(table, flank, q, 100.0, out, jac)
    geometries(table, flank, q, np.empty((2, 3)), np.empty((2, 3)))
    blade_heights(table, flank, u, np.empty(2))
    limit = np.ones(3)
    for by_sheet in (True, False):
        bisected(
            table,
            flank,
            q,
            u,
            u,
            u + 1.0,
            np.array([1.0, 0.0]),
            100.0,
            limit,
            1e-14,
            1,
            by_sheet,
            np.ones(2),
            -1.0,
            np.empty(2),
        )
    newton(
        table,
        flank,
        q,
        u,
        u.copy(),
        100.0,
        np.ones(3),
        1e-14,
        1,
        1,
        1e-6,
        True,
        out,
        jac,
        np.empty(2, np.bool_),
    )
