"""Initial separations for loaded contact: a fine grid of contact patches around each tooth
pair's unloaded contact, on the flanks' local interpolants.

A light-load contact is a millimetre or two wide, far below the FlankMap's node spacing, so the
potential contact zone of every tooth pair at a mesh position is sampled afresh: strips along the
instantaneous contact line (the long axis of the contact ellipse, the direction of least
curvature of the separation at the unloaded contact point), each strip centred on the valley of
the separation across it and divided into patches across. At every patch centre the clearance
field (:meth:`gearopt.contact.ClearanceField.clearance_of_points`, the same interpolants as the
unloaded TCA) gives the angular clearance delta (how far the gear must turn back from its ideal
position before its flank reaches the point) and the normal factor f = |n . (z_g x q)|, which is
both the normal separation per radian of gear rotation and the moment of a unit normal force
about the gear axis. With the gear turned back by theta, the normal gap at the patch is
(delta - theta) f: the load distribution (:mod:`gearopt.loaded.lcp`) solves for theta and the
patch forces.

One patch lies at the pair's refined unloaded contact point itself, so that at zero load the
least gap over the patches is the unloaded TCA's clearance minimum.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from gearopt.contact import ClearanceField
from gearopt.flank import FlankMap, axial_plane
from gearopt.load_options import PatchOptions

__all__ = ["PatchOptions", "PairPatches", "contact_patches", "flank_point", "flank_points"]

#: finite-difference step of the separation's curvature and of the surface's tangents (mm)
_STEP_MM = 0.05


def flank_point(flank: FlankMap, face_mm, profile_mm) -> NDArray:
    """``(..., 3)`` points of a flank's local interpolant (the clearance field's) at grid
    coordinates ``(s, t)``, member frame, unturned."""
    s = np.asarray(face_mm, float)
    t = np.asarray(profile_mm, float)
    big_l, big_r = axial_plane(s, flank.height_at(s, t), math.radians(flank.pitch_angle_deg))
    theta = flank.polar_angle_local(s, t)
    return np.stack([big_r * np.cos(theta), big_r * np.sin(theta), big_l], axis=-1)


def flank_points(flank: FlankMap, face_mm: NDArray, profile_mm: NDArray):
    """Points, unit normals (out of the tooth) and tangents of a flank's local interpolant at
    grid coordinates ``(s, t)`` (member frame, unturned): ``(p, n, p_s, p_t)``, each
    ``(..., 3)``; the tangents by central differences of :func:`flank_point`."""
    s = np.asarray(face_mm, float)
    t = np.asarray(profile_mm, float)
    e = 1e-3
    p = flank_point(flank, s, t)
    p_s = (flank_point(flank, s + e, t) - flank_point(flank, s - e, t)) / (2.0 * e)
    p_t = (flank_point(flank, s, t + e) - flank_point(flank, s, t - e)) / (2.0 * e)
    cross = np.cross(p_s, p_t)
    n = cross / np.linalg.norm(cross, axis=-1)[..., None]
    # out of the tooth: as the FlankMap's own normals
    mid = tuple(np.array(flank.shape) // 2)
    reference = flank.normals[mid]
    sign = np.sign(np.sum(n.reshape(-1, 3) @ reference))
    return p, n * (sign if sign != 0.0 else 1.0), p_s, p_t


@dataclass(frozen=True, kw_only=True)
class PairPatches:
    """The contact patches of one tooth pair at one mesh position.

    Attributes
    ----------
    pair
        The pair's offset in pitches from the base pair.
    phi_rad
        The pair's relative pinion angle (the field's angle, base pair turned by whole pitches).
    face_mm, profile_mm
        ``(along, across)`` pinion grid coordinates of the patch centres.
    gear_face_mm, gear_profile_mm
        ``(along, across)`` the gear grid coordinates of the same points.
    clearance_rad, factor_mm
        ``(along, across)`` the angular clearance delta and the normal factor f (mm of normal
        separation per rad of gear rotation; the moment arm of a normal force about the gear
        axis, mm).
    area_mm2
        ``(along, across)`` the patches' areas on the pinion flank.
    length_mm, width_mm
        ``(along, across)`` the patches' sides along and across the contact line (mm, on the
        flank).
    x_mm, y_mm
        ``(along, across)`` the patch centres' coordinates along and across the contact line
        (mm on the flank, from the unloaded contact point): where the local contact
        compliance of the half-spaces is evaluated.
    valid
        ``(along, across)`` True where the patch lies on both flanks.
    boundary
        ``(along, across)`` True on a valid patch next to a point off the flanks (along or
        across the contact line, one patch further, also beyond the patch grid): the flanks'
        boundary (edge loading where loaded).
    open_end
        ``(along, across)`` True on a valid patch at the patch grid's end whose neighbour beyond
        the grid is on the flanks: the potential contact zone is cut short there (loaded, it
        asks for a longer reach).
    contact_rad
        The pair's refined unloaded clearance minimum (+inf where it does not touch).
    """

    pair: int
    phi_rad: float
    face_mm: NDArray
    profile_mm: NDArray
    gear_face_mm: NDArray
    gear_profile_mm: NDArray
    clearance_rad: NDArray
    factor_mm: NDArray
    area_mm2: NDArray
    length_mm: NDArray
    width_mm: NDArray
    x_mm: NDArray
    y_mm: NDArray
    valid: NDArray
    boundary: NDArray
    open_end: NDArray
    contact_rad: float


def _curvature(field: ClearanceField, phi: float, s0: float, h0: float, factor: float):
    """The separation's second derivatives (mm per mm^2) at ``(s0, h0)`` by differences."""
    e = _STEP_MM
    ds = np.array([0.0, e, -e, 0.0, 0.0, e, e, -e, -e])
    dh = np.array([0.0, 0.0, 0.0, e, -e, e, -e, e, -e])
    d, _ = field.clearance_at_grid(s0 + ds, h0 + dh, phi)
    hss = (d[1] - 2.0 * d[0] + d[2]) / (e * e)
    hhh = (d[3] - 2.0 * d[0] + d[4]) / (e * e)
    hsh = (d[5] - d[6] - d[7] + d[8]) / (4.0 * e * e)
    return factor * np.array([[hss, hsh], [hsh, hhh]])


def contact_patches(
    field: ClearanceField, u_rad: float, pairs, grid: PatchOptions | None = None
) -> list[PairPatches]:
    """The contact patches of the tooth pairs ``pairs`` (offsets in pitches from the base pair)
    at relative pinion rotation ``u_rad`` (direction of motion), each around its refined
    unloaded contact point (module docstring). Pairs that do not touch are left out."""
    grid = grid or PatchOptions()
    pinion, gear = field.pinion, field.gear
    pitch = pinion.pitch_rad
    phis = field.sense * (u_rad + np.asarray(pairs, float) * pitch)
    sample = field.sample(phis)
    reach_mm = grid.reach_um * 1e-3
    out = []
    span_s = float(pinion.face_mm[-1] - pinion.face_mm[0])
    span_h = float(pinion.profile_mm[-1] - pinion.profile_mm[0])
    for k, phi in enumerate(phis):
        m0 = float(sample.minimum_rad[k])
        if not math.isfinite(m0):
            continue
        s0, h0 = float(sample.contact_face_mm[k]), float(sample.contact_profile_mm[k])
        p0, n0, _, _ = flank_points(pinion, np.array([s0]), np.array([h0]))
        f0 = float(field.clearance_of_points(p0, n0, phi).normal_factor_mm[0])
        curv = _curvature(field, phi, s0, h0, f0)
        lam, vec = np.linalg.eigh(curv)
        major, minor = vec[:, 0], vec[:, 1]  # least curvature: along the contact line
        longest = math.hypot(span_s, span_h)
        half_l = longest if lam[0] <= 0.0 else min(math.sqrt(2.0 * reach_mm / lam[0]), longest)
        half_w = grid.max_half_width_mm
        if lam[1] > 0.0:
            half_w = min(math.sqrt(2.0 * reach_mm / lam[1]), half_w)
        t = np.linspace(-half_l, half_l, grid.along)
        w = np.linspace(-half_w, half_w, grid.across)
        # each strip centred on the valley across it (a parabola through three points)
        cs = s0 + t * major[0]
        ch = h0 + t * major[1]
        probe = np.array([-0.5, 0.0, 0.5]) * half_w
        ps = cs[:, None] + probe[None, :] * minor[0]
        ph = ch[:, None] + probe[None, :] * minor[1]
        d, _ = field.clearance_at_grid(ps, ph, phi)
        curve = d[:, 0] - 2.0 * d[:, 1] + d[:, 2]
        with np.errstate(divide="ignore", invalid="ignore"):
            shift = np.where(curve > 0.0, 0.25 * half_w * (d[:, 0] - d[:, 2]) / curve, 0.0)
        shift = np.clip(shift, -0.5 * half_w, 0.5 * half_w)
        shift[grid.along // 2] = 0.0  # the strip through the contact point itself
        s = cs[:, None] + (shift[:, None] + w[None, :]) * minor[0]
        h = ch[:, None] + (shift[:, None] + w[None, :]) * minor[1]
        p, n, p_s, p_t = flank_points(pinion, s, h)
        at = field.clearance_of_points(p, n, phi)
        on_pinion = pinion.inside(s, h)
        valid = at.valid & on_pinion & np.isfinite(at.clearance_rad)
        # the gear's grid coordinates of the points (for the gear's compliance)
        q = field.gear_frame_points(p, phi)
        gs, gh = gear.to_grid(q[..., 2], np.hypot(q[..., 0], q[..., 1]))
        dt = t[1] - t[0]
        dw = w[1] - w[0]
        scale_a = np.linalg.norm(p_s * major[0] + p_t * major[1], axis=-1)
        scale_w = np.linalg.norm(p_s * minor[0] + p_t * minor[1], axis=-1)
        along_mm, across_mm = scale_a * dt, scale_w * dw
        centre = (grid.along // 2, grid.across // 2)
        x_mm = np.broadcast_to(t[:, None] * scale_a[centre], s.shape)
        y_mm = (shift[:, None] + w[None, :]) * scale_w[centre]
        # one patch further on every side, beyond the grid too: on the flanks?
        ext_t = np.concatenate([[t[0] - dt], t, [t[-1] + dt]])
        ext_shift = np.concatenate([[shift[0]], shift, [shift[-1]]])
        ext_w = np.concatenate([[w[0] - dw], w, [w[-1] + dw]])
        es = s0 + ext_t[:, None] * major[0] + (ext_shift[:, None] + ext_w[None, :]) * minor[0]
        eh = h0 + ext_t[:, None] * major[1] + (ext_shift[:, None] + ext_w[None, :]) * minor[1]
        ext = field.clearance_of_points(flank_point(pinion, es, eh), None, phi)
        ext_valid = ext.valid & pinion.inside(es, eh)
        ext_valid[1:-1, 1:-1] = valid
        off = (
            ~ext_valid[:-2, 1:-1]
            | ~ext_valid[2:, 1:-1]
            | ~ext_valid[1:-1, :-2]
            | ~ext_valid[1:-1, 2:]
        )
        boundary = valid & off
        at_end = np.zeros_like(valid)
        at_end[0, :] = at_end[-1, :] = at_end[:, 0] = at_end[:, -1] = True
        open_end = valid & at_end & ~off
        out.append(
            PairPatches(
                pair=int(pairs[k]),
                phi_rad=float(phi),
                face_mm=s,
                profile_mm=h,
                gear_face_mm=np.asarray(gs),
                gear_profile_mm=np.asarray(gh),
                clearance_rad=np.where(valid, at.clearance_rad, np.inf),
                factor_mm=np.asarray(at.normal_factor_mm),
                area_mm2=np.linalg.norm(np.cross(p_s, p_t), axis=-1) * dt * dw,
                length_mm=along_mm,
                width_mm=across_mm,
                x_mm=np.array(x_mm),
                y_mm=y_mm,
                valid=valid,
                boundary=boundary,
                open_end=open_end,
                contact_rad=m0,
            )
        )
    return out
