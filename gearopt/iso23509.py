"""Bevel gear blank geometry from basic data after ISO 23509 (pairs without offset).

The ``[blank]`` table with ``standard = "iso23509"`` (:class:`BlankData`) and the pair's basic
data (teeth, shaft angle, face width, mean spiral and pressure angle, one size) give the whole
blank (:class:`StandardBlank`, :func:`standard_blank`). The formulas are the intersecting-axes
case of ISO 23509 (face milling, tapered depth; face hobbing, uniform depth) as public
material states them (AGMA 2005 tooth proportions, the ISO 10300 virtual cylindrical gears);
where a reading was needed it is said beside the formula. Symbols are the standard's.

Pitch cones and sizes::

    tan delta_1 = sin Sigma / (cos Sigma + u),  delta_2 = Sigma - delta_1,  u = z_2 / z_1
    R_e = d_e2 / (2 sin delta_2),  R_m = R_e - b / 2,  m_mn = 2 R_m sin delta_2 cos beta_m / z_2

Tooth depth at the mean point (data of type I: factors c_ham, k_d, k_c, k_t; type II: the
profile shift x_hm1 = k_d (1 - 2 c_ham) / 2 and thickness modification x_smn = k_t / 2)::

    u_a = z_2 cos delta_1 / (z_1 cos delta_2),   c_ham = 0.210 + 0.290 / u_a   (default)
    h_mw = k_d m_mn,  h_am2 = c_ham h_mw,  h_am1 = h_mw - h_am2,  c = k_c h_mw
    h_fm1 = h_am2 + c,  h_fm2 = h_am1 + c

Dedendum angles by depth form (sums Sigma theta_f; parallel clearance theta_a1 = theta_f2,
theta_a2 = theta_f1)::

    standard      theta_f = atan(h_fm / R_m)                      (root apex at the pitch apex)
    duplex        Sigma theta_fC = pi m_et / (2 R_e tan alpha_n cos beta_m)
                                   (1 - R_m sin beta_m / r_c0)   (constant slot width)
    tilted_root   Sigma theta_fM = min(Sigma theta_fC, 1.3 Sigma theta_fS)   (a reading: the
                  duplex sum capped at 1.3 times the standard's, the root lines tilted about
                  the mean point)
    uniform       0      (face hobbing: always)
    duplex and tilted root split the sum as the addenda: theta_f1 = c_ham Sigma, theta_f2 =
    (1 - c_ham) Sigma (the addendum ratio, hence the profile shift, constant along the face)

Given gear angles (``gear_addendum_angle_deg``, ``gear_dedendum_angle_deg``) take precedence.
Heel and toe: h_ae = h_am + (b/2) tan theta_a, h_ai = h_am - (b/2) tan theta_a (and so on).

Spiral angle along the face: face milling (circular tooth trace of radius r_c0)
sin beta(R) = (R^2 - R_m^2 + 2 R_m r_c0 sin beta_m) / (2 R r_c0); face hobbing (extended
epicycloid, z_0 blade groups, crown gear z_p = z_2 / sin delta_2, seed 001 eqs 9, 13):
sin nu = z_0 m_mn / (2 r_c0), M_d^2 = R_m^2 + r_c0^2 - 2 R_m r_c0 sin(beta_m - nu), the
rolling circles rho_p = M_d z_p / (z_p + z_0), rho_c = M_d - rho_p, and at a crown gear
radius R the instant centre I at distance q from the cutting point,
q^2 = r_c0^2 + rho_c^2 - rho_c (M_d^2 + r_c0^2 - R^2) / M_d, the trace normal through I, so
sin beta(R) = (R^2 + q^2 - rho_p^2) / (2 R q).

Thickness, chordal thickness and addendum (AGMA 2005 as seed 001 Table 2 applies it: the
chordal values on the transverse virtual gear d_v = d_m / cos delta; the outer normal backlash
j_en taken half from each member as a thinning of j_mn cos alpha_n / 2, j_mn = j_en R_m / R_e,
the one reading of the backlash under which that table's thicknesses follow; the chordal
addendum of the tooth before thinning)::

    s_mn1,0 = pi m_mn / 2 + 2 m_mn (x_smn + x_hm1 tan alpha_n),  s_mn2,0 = pi m_mn - s_mn1,0
    s_mn = s_mn,0 - j_mn cos alpha_n / 2
    s_mnc = d_v sin(s_mn / d_v),  h_amc = h_am + d_v (1 - cos(s_mn,0 / d_v)) / 2

Unequal pressure angles (``[pair] pressure_angle_deg = [drive, coast]``, alpha_nD and alpha_nC):
the rack shifted by x_hm1 m_mn thickens the tooth by x_hm1 m_mn tan alpha on each flank, so
s_mn1,0 = pi m_mn / 2 + 2 x_smn m_mn + x_hm1 m_mn (tan alpha_nD + tan alpha_nC); the duplex
slot keeps its width with the mean tangent (tan alpha_nD + tan alpha_nC) / 2 in place of
tan alpha_n; the backlash thinning takes the mean cosine; the top land is the mean of the two
sides' involute tips, the contact ratios are the worse side's and the undercut is checked on the
smaller angle (derivations of this code for a tooth with unequal flanks, not the standard's
text).

Top land: the involute tooth of the virtual normal spur gear d_vn = d_v / (1 - sin^2 beta_m
cos^2 alpha_n) at its tip circle d_vn + 2 h_am.

Virtual cylindrical gears (ISO 10300-1): d_v = d_m / cos delta, alpha_vet =
atan(tan alpha_n / cos beta_m), g_va = (sqrt(d_va1^2 - d_vb1^2) + sqrt(d_va2^2 - d_vb2^2)) / 2
- a_v sin alpha_vet, eps_va = g_va cos beta_m / (pi m_mn cos alpha_vet), eps_vb =
b sin beta_m / (pi m_mn), eps_vg = sqrt(eps_va^2 + eps_vb^2).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, replace
from typing import Any

from gearopt.blank import pitch_angles_rad
from gearopt.errors import DesignError
from gearopt.validate import check_keys, read_choice, read_integer, read_number

__all__ = [
    "STANDARDS",
    "TAPERS",
    "BlankData",
    "PairBasics",
    "StandardBlank",
    "standard_blank",
    "face_hobbing_circles_mm",
    "DEFAULT_DEPTH_FACTOR",
    "DEFAULT_CLEARANCE_FACTOR",
    "MODIFIED_SLOT_LIMIT",
]

STANDARDS = ("iso23509",)
TAPERS = ("standard", "uniform", "duplex", "tilted_root")
#: k_d: mean working depth over the mean normal module (ISO 23509 / AGMA 2005 spiral bevel)
DEFAULT_DEPTH_FACTOR = 2.0
#: k_c: clearance over the mean working depth
DEFAULT_CLEARANCE_FACTOR = 0.125
#: the tilted root line's sum of dedendum angles is at most this multiple of the standard's
MODIFIED_SLOT_LIMIT = 1.3
BLANK_KEYS = (
    "standard",
    "cutter_radius_mm",
    "blade_groups",
    "taper",
    "gear_addendum_angle_deg",
    "gear_dedendum_angle_deg",
    "mean_addendum_factor",
    "depth_factor",
    "clearance_factor",
    "thickness_factor",
    "thickness_modification_coefficient",
    "profile_shift_coefficient",
    "outer_normal_backlash_mm",
)
WHERE = "blank"


@dataclass(frozen=True, kw_only=True)
class BlankData:
    """The ``[blank]`` table: the standard's data beyond the pair's (ISO 23509 symbols).

    Attributes
    ----------
    cutter_radius_mm
        r_c0, the nominal cutter radius.
    blade_groups
        z_0: given for face hobbing (uniform depth); None for face milling.
    taper
        Depth form of face milling: ``"standard"``, ``"uniform"``, ``"duplex"`` or
        ``"tilted_root"``; None when the gear's angles are given or for face hobbing.
    gear_addendum_angle_deg, gear_dedendum_angle_deg
        theta_a2, theta_f2 given (data type II); they take precedence over ``taper``.
    mean_addendum_factor, profile_shift_coefficient
        c_ham or x_hm1 (one of the two; default c_ham = 0.210 + 0.290 / u_a).
    depth_factor, clearance_factor
        k_d (2.0), k_c (0.125).
    thickness_modification_coefficient
        x_smn (default 0); the table may give the thickness factor k_t instead
        (``thickness_factor``, read as x_smn = k_t / 2), not both.
    outer_normal_backlash_mm
        j_en (0), taken half from each member.
    """

    cutter_radius_mm: float
    blade_groups: int | None = None
    taper: str | None = None
    gear_addendum_angle_deg: float | None = None
    gear_dedendum_angle_deg: float | None = None
    mean_addendum_factor: float | None = None
    profile_shift_coefficient: float | None = None
    depth_factor: float = DEFAULT_DEPTH_FACTOR
    clearance_factor: float = DEFAULT_CLEARANCE_FACTOR
    thickness_modification_coefficient: float = 0.0
    outer_normal_backlash_mm: float = 0.0

    @property
    def face_hobbing(self) -> bool:
        """True when blade groups are given (face hobbing, uniform depth)."""
        return self.blade_groups is not None

    @classmethod
    def from_table(cls, table: Mapping[str, Any]) -> BlankData:
        """Read and check the ``[blank]`` table (``standard`` must be ``"iso23509"``)."""
        check_keys(table, BLANK_KEYS, WHERE)
        read_choice(table, "standard", WHERE, STANDARDS)
        rc = read_number(table, "cutter_radius_mm", WHERE, gt=0.0)
        groups = read_integer(table, "blade_groups", WHERE, None, ge=1, le=50)
        given = [
            read_number(table, key, WHERE, None, ge=0.0, lt=15.0)
            for key in ("gear_addendum_angle_deg", "gear_dedendum_angle_deg")
        ]
        if (given[0] is None) != (given[1] is None):
            missing = "gear_dedendum_angle_deg" if given[1] is None else "gear_addendum_angle_deg"
            raise DesignError(
                f"{WHERE}.{missing}",
                rule="give both of the gear's angles (addendum and dedendum) or neither",
            )
        default_taper = "uniform" if groups is not None or given[0] is not None else None
        taper = read_choice(table, "taper", WHERE, TAPERS, default_taper)
        if taper is None:
            raise DesignError(
                f"{WHERE}.taper",
                rule=f"required key is missing: one of {list(TAPERS)}, or give "
                "gear_addendum_angle_deg and gear_dedendum_angle_deg",
            )
        if groups is not None and (taper != "uniform" or given[0] is not None):
            name = "taper" if given[0] is None else "gear_addendum_angle_deg"
            raise DesignError(
                f"{WHERE}.{name}",
                table.get(name),
                "face hobbing (blade_groups given) cuts uniform depth: leave taper out or "
                "set it to 'uniform', and give no addendum or dedendum angles",
            )
        if given[0] is not None:
            taper = None
        cham = read_number(table, "mean_addendum_factor", WHERE, None, gt=0.0, lt=1.0)
        xhm = read_number(table, "profile_shift_coefficient", WHERE, None, gt=-1.0, lt=1.0)
        if cham is not None and xhm is not None:
            raise DesignError(
                f"{WHERE}.profile_shift_coefficient",
                xhm,
                "give mean_addendum_factor (c_ham) or profile_shift_coefficient (x_hm1), not "
                "both: x_hm1 = depth_factor (1 - 2 c_ham) / 2",
            )
        kt = read_number(table, "thickness_factor", WHERE, None, gt=-0.5, lt=0.5)
        xsmn = read_number(
            table, "thickness_modification_coefficient", WHERE, None, gt=-0.25, lt=0.25
        )
        if kt is not None and xsmn is not None:
            raise DesignError(
                f"{WHERE}.thickness_modification_coefficient",
                xsmn,
                "give thickness_factor (k_t) or thickness_modification_coefficient "
                "(x_smn = k_t / 2), not both",
            )
        if kt is not None:
            xsmn = 0.5 * kt
        return cls(
            cutter_radius_mm=rc,
            blade_groups=groups,
            taper=taper,
            gear_addendum_angle_deg=given[0],
            gear_dedendum_angle_deg=given[1],
            mean_addendum_factor=cham,
            profile_shift_coefficient=xhm,
            depth_factor=read_number(
                table, "depth_factor", WHERE, DEFAULT_DEPTH_FACTOR, gt=1.0, lt=3.0
            ),
            clearance_factor=read_number(
                table, "clearance_factor", WHERE, DEFAULT_CLEARANCE_FACTOR, ge=0.0, le=0.5
            ),
            thickness_modification_coefficient=0.0 if xsmn is None else xsmn,
            outer_normal_backlash_mm=read_number(
                table, "outer_normal_backlash_mm", WHERE, 0.0, ge=0.0
            ),
        )


@dataclass(frozen=True, kw_only=True)
class PairBasics:
    """The pair's basic data the standard reads (from a validated ``[pair]``)."""

    pinion_teeth: int
    gear_teeth: int
    shaft_angle_deg: float
    mean_spiral_angle_deg: float
    pressure_angle_deg: float
    face_width_mm: float
    mean_cone_distance_mm: float
    #: the coast side's alpha_nC when it differs from the drive side's (``pressure_angle_deg``)
    coast_pressure_angle_deg: float | None = None

    @property
    def pressure_angles_rad(self) -> tuple[float, float]:
        """(alpha_nD, alpha_nC): drive and coast."""
        coast = self.coast_pressure_angle_deg
        drive = self.pressure_angle_deg
        return math.radians(drive), math.radians(drive if coast is None else coast)


@dataclass(frozen=True, kw_only=True)
class StandardBlank:
    """ISO 23509 blank of a pair without offset (mm, degrees; pairs are ``(pinion, gear)``).

    Every field is a quantity of the standard's output list; :meth:`as_flat_dict` is the
    ``gearopt blank --json`` object. ``warnings`` name the rule each breaks.
    """

    method: str
    taper: str
    mean_cone_distance_mm: float
    outer_cone_distance_mm: float
    inner_cone_distance_mm: float
    mean_normal_module_mm: float
    outer_transverse_module_mm: float
    mean_spiral_angle_deg: float
    outer_spiral_angle_deg: float
    inner_spiral_angle_deg: float
    pitch_angle_deg: tuple[float, float]
    face_angle_deg: tuple[float, float]
    root_angle_deg: tuple[float, float]
    addendum_angle_deg: tuple[float, float]
    dedendum_angle_deg: tuple[float, float]
    mean_addendum_factor: float
    profile_shift_coefficient: float
    thickness_modification_coefficient: float
    mean_addendum_mm: tuple[float, float]
    mean_dedendum_mm: tuple[float, float]
    outer_addendum_mm: tuple[float, float]
    outer_dedendum_mm: tuple[float, float]
    inner_addendum_mm: tuple[float, float]
    inner_dedendum_mm: tuple[float, float]
    mean_working_depth_mm: float
    clearance_mm: float
    outer_whole_depth_mm: tuple[float, float]
    mean_pitch_diameter_mm: tuple[float, float]
    outer_pitch_diameter_mm: tuple[float, float]
    outside_diameter_mm: tuple[float, float]
    crown_to_crossing_point_mm: tuple[float, float]
    mean_normal_circular_thickness_mm: tuple[float, float]
    mean_normal_chordal_thickness_mm: tuple[float, float]
    mean_chordal_addendum_mm: tuple[float, float]
    mean_normal_top_land_mm: tuple[float, float]
    face_contact_ratio: float
    profile_contact_ratio: float
    total_contact_ratio: float
    warnings: tuple[str, ...] = ()

    def as_flat_dict(self) -> dict[str, Any]:
        """One flat JSON-ready object: numbers, ``[pinion, gear]`` lists, ``warnings``."""
        out: dict[str, Any] = {}
        for name in self.__dataclass_fields__:
            value = getattr(self, name)
            out[name] = list(value) if isinstance(value, tuple) else value
        return out


def _pairwise(f, *args) -> tuple[float, float]:
    return tuple(f(*a) for a in zip(*args, strict=True))  # type: ignore[return-value]


def _mean_addendum_factor(data: BlankData, d1: float, d2: float, z1: int, z2: int) -> float:
    if data.profile_shift_coefficient is not None:
        cham = 0.5 - data.profile_shift_coefficient / data.depth_factor
        if not 0.0 < cham < 1.0:
            raise DesignError(
                f"{WHERE}.profile_shift_coefficient",
                data.profile_shift_coefficient,
                f"leaves a member without addendum: |x_hm1| must be < depth_factor / 2 = "
                f"{0.5 * data.depth_factor:g}",
            )
        return cham
    if data.mean_addendum_factor is not None:
        return data.mean_addendum_factor
    ua = z2 * math.cos(d1) / (z1 * math.cos(d2))
    return 0.210 + 0.290 / ua


def _dedendum_angles_rad(
    data: BlankData, basics: PairBasics, *, cham: float, hfm, met: float, re: float
) -> tuple[float, float]:
    """theta_f1, theta_f2 of the depth form (module docstring)."""
    if data.gear_addendum_angle_deg is not None:
        return math.radians(data.gear_addendum_angle_deg), math.radians(
            data.gear_dedendum_angle_deg
        )
    rm = basics.mean_cone_distance_mm
    if data.taper == "uniform":
        return 0.0, 0.0
    standard = (math.atan(hfm[0] / rm), math.atan(hfm[1] / rm))
    if data.taper == "standard":
        return standard
    beta = math.radians(basics.mean_spiral_angle_deg)
    tan_alpha = 0.5 * sum(math.tan(a) for a in basics.pressure_angles_rad)
    rc = data.cutter_radius_mm
    duplex = (
        math.pi * met / (2.0 * re * tan_alpha * math.cos(beta)) * (1.0 - rm * math.sin(beta) / rc)
    )
    if duplex <= 0.0:
        raise DesignError(
            f"{WHERE}.cutter_radius_mm",
            rc,
            f"{data.taper} taper needs r_c0 > R_m sin(beta_m) = {rm * math.sin(beta):.4f} mm "
            "(else the sum of dedendum angles for constant slot width is <= 0)",
        )
    total = duplex if data.taper == "duplex" else min(duplex, MODIFIED_SLOT_LIMIT * sum(standard))
    return cham * total, (1.0 - cham) * total


def face_hobbing_circles_mm(
    *,
    mean_cone_distance_mm: float,
    mean_spiral_angle_deg: float,
    cutter_radius_mm: float,
    blade_groups: int,
    mean_normal_module_mm: float,
    crown_gear_teeth: float,
) -> tuple[float, float, float]:
    """Machine distance M_d, base circle rho_p and rolling circle rho_c of face hobbing.

    sin nu = z_0 m_mn / (2 r_c0), M_d^2 = R_m^2 + r_c0^2 - 2 R_m r_c0 sin(beta_m - nu) (seed
    001 eqs 9, 13), rho_p = M_d z_p / (z_p + z_0), rho_c = M_d - rho_p (seed 003 Table 1).
    """
    rm, rc, z0 = mean_cone_distance_mm, cutter_radius_mm, blade_groups
    nu = math.asin(z0 * mean_normal_module_mm / (2.0 * rc))
    md = math.sqrt(
        rm**2 + rc**2 - 2.0 * rm * rc * math.sin(math.radians(mean_spiral_angle_deg) - nu)
    )
    rho_p = md * crown_gear_teeth / (crown_gear_teeth + z0)
    return md, rho_p, md - rho_p


def _spiral_angle_rad(data: BlankData, basics: PairBasics, *, r_mm: float, mmn: float, zp: float):
    """Spiral angle at cone distance ``r_mm`` (module docstring)."""
    rm = basics.mean_cone_distance_mm
    beta = math.radians(basics.mean_spiral_angle_deg)
    rc = data.cutter_radius_mm
    if data.blade_groups is None:
        s = (r_mm**2 - rm**2 + 2.0 * rm * rc * math.sin(beta)) / (2.0 * r_mm * rc)
    else:
        md, rho_p, rho_c = face_hobbing_circles_mm(
            mean_cone_distance_mm=rm,
            mean_spiral_angle_deg=basics.mean_spiral_angle_deg,
            cutter_radius_mm=rc,
            blade_groups=data.blade_groups,
            mean_normal_module_mm=mmn,
            crown_gear_teeth=zp,
        )
        reach = (md**2 + rc**2 - r_mm**2) / (2.0 * md * rc)
        q2 = rc**2 + rho_c**2 - 2.0 * rho_c * rc * reach
        if abs(reach) >= 1.0 or q2 <= 0.0:
            s = math.inf
        else:
            s = (r_mm**2 + q2 - rho_p**2) / (2.0 * r_mm * math.sqrt(q2))
    if not -1.0 < s < 1.0:
        raise DesignError(
            f"{WHERE}.cutter_radius_mm",
            rc,
            f"gives no tooth trace at cone distance {r_mm:.4f} mm ("
            + (f"sin beta = {s:.4f}" if math.isfinite(s) else "the cutting point never gets there")
            + "): the cutter radius does not suit the face width",
        )
    return math.asin(s)


def _involute(a: float) -> float:
    return math.tan(a) - a


def _top_land_mm(*, dvn: float, s_mn: float, ham: float, alpha: float) -> float:
    """Normal top land of the virtual normal spur gear (involute thickness at its tip)."""
    dvan = dvn + 2.0 * ham
    alpha_a = math.acos(min(1.0, dvn * math.cos(alpha) / dvan))
    return dvan * (s_mn / dvn + _involute(alpha) - _involute(alpha_a))


def standard_blank(basics: PairBasics, data: BlankData) -> StandardBlank:
    """The ISO 23509 blank of a pair without offset (module docstring); warnings included.

    Raises
    ------
    DesignError
        Naming the ``[blank]`` or ``[pair]`` key whose value gives no blank (a cutter too
        small for the face, a tooth without addendum at the toe, a total contact ratio < 1).
    """
    z1, z2 = basics.pinion_teeth, basics.gear_teeth
    d1, d2 = pitch_angles_rad(z1, z2, math.radians(basics.shaft_angle_deg))
    if d2 >= math.radians(89.0):
        raise DesignError(
            "pair.shaft_angle_deg",
            basics.shaft_angle_deg,
            f"gives a gear pitch angle {math.degrees(d2):.3f} deg >= 89 deg: the standard's "
            "virtual cylindrical gears need a gear that is not a crown or internal gear",
        )
    delta = (d1, d2)
    beta = math.radians(basics.mean_spiral_angle_deg)
    sides = basics.pressure_angles_rad
    b = basics.face_width_mm
    rm = basics.mean_cone_distance_mm
    re, ri = rm + 0.5 * b, rm - 0.5 * b
    mmn = 2.0 * rm * math.sin(d2) * math.cos(beta) / z2
    met = 2.0 * re * math.sin(d2) / z2
    zp = z2 / math.sin(d2)
    cham = _mean_addendum_factor(data, d1, d2, z1, z2)
    xhm = 0.5 * data.depth_factor * (1.0 - 2.0 * cham)
    hmw = data.depth_factor * mmn
    clearance = data.clearance_factor * hmw
    ham = (hmw - cham * hmw, cham * hmw)
    hfm = (ham[1] + clearance, ham[0] + clearance)
    if data.blade_groups is not None and data.blade_groups * mmn >= 2.0 * data.cutter_radius_mm:
        raise DesignError(
            f"{WHERE}.cutter_radius_mm",
            data.cutter_radius_mm,
            f"must exceed blade_groups * m_mn / 2 = {0.5 * data.blade_groups * mmn:.4f} mm "
            "(seed 001 eq 9: sin nu = z_0 m_mn / (2 r_c0) < 1)",
        )
    tf = _dedendum_angles_rad(data, basics, cham=cham, hfm=hfm, met=met, re=re)
    ta = (tf[1], tf[0])
    half = 0.5 * b
    hae = _pairwise(lambda h, t: h + half * math.tan(t), ham, ta)
    hfe = _pairwise(lambda h, t: h + half * math.tan(t), hfm, tf)
    hai = _pairwise(lambda h, t: h - half * math.tan(t), ham, ta)
    hfi = _pairwise(lambda h, t: h - half * math.tan(t), hfm, tf)
    for name, values in (("addendum", hai), ("dedendum", hfi)):
        for member, value in zip(("pinion", "gear"), values, strict=True):
            if value <= 0.0:
                raise DesignError(
                    f"{WHERE}.taper" if data.taper else f"{WHERE}.gear_addendum_angle_deg",
                    data.taper or data.gear_addendum_angle_deg,
                    f"leaves the {member}'s inner {name} {value:.4f} mm <= 0 (at the toe, "
                    f"face_width_mm = {b:g} inward of the heel)",
                )
    de = _pairwise(lambda d: 2.0 * re * math.sin(d), delta)
    dm = _pairwise(lambda d: 2.0 * rm * math.sin(d), delta)
    jmn = data.outer_normal_backlash_mm * rm / re
    s1 = 0.5 * math.pi * mmn + mmn * (
        2.0 * data.thickness_modification_coefficient
        + xhm * (math.tan(sides[0]) + math.tan(sides[1]))
    )
    s0 = (s1, math.pi * mmn - s1)
    cos_alpha = 0.5 * (math.cos(sides[0]) + math.cos(sides[1]))
    smn = _pairwise(lambda s: s - 0.5 * jmn * cos_alpha, s0)
    dv = _pairwise(lambda d, g: d / math.cos(g), dm, delta)
    dvn_sides = [
        _pairwise(lambda d, a=a: d / (1.0 - (math.sin(beta) * math.cos(a)) ** 2), dv) for a in sides
    ]
    smnc = _pairwise(lambda d, s: d * math.sin(s / d), dv, smn)
    hamc = _pairwise(lambda d, s, h: h + 0.5 * d * (1.0 - math.cos(s / d)), dv, s0, ham)
    top = _pairwise(
        lambda s, h, *dvn: (
            0.5
            * sum(
                _top_land_mm(dvn=d, s_mn=s, ham=h, alpha=a) for d, a in zip(dvn, sides, strict=True)
            )
        ),
        smn,
        ham,
        *dvn_sides,
    )
    per_side = [
        _contact_ratios(dm=dm, delta=delta, ham=ham, beta=beta, alpha=a, mmn=mmn, b=b)
        for a in sides
    ]
    worse = min(range(2), key=lambda k: per_side[k]["total_contact_ratio"])
    ratios = per_side[worse]
    blank = StandardBlank(
        method="face hobbing" if data.face_hobbing else "face milling",
        taper=data.taper or "given gear angles",
        mean_cone_distance_mm=rm,
        outer_cone_distance_mm=re,
        inner_cone_distance_mm=ri,
        mean_normal_module_mm=mmn,
        outer_transverse_module_mm=met,
        mean_spiral_angle_deg=basics.mean_spiral_angle_deg,
        outer_spiral_angle_deg=math.degrees(
            _spiral_angle_rad(data, basics, r_mm=re, mmn=mmn, zp=zp)
        ),
        inner_spiral_angle_deg=math.degrees(
            _spiral_angle_rad(data, basics, r_mm=ri, mmn=mmn, zp=zp)
        ),
        pitch_angle_deg=_pairwise(math.degrees, delta),
        face_angle_deg=_pairwise(lambda d, t: math.degrees(d + t), delta, ta),
        root_angle_deg=_pairwise(lambda d, t: math.degrees(d - t), delta, tf),
        addendum_angle_deg=_pairwise(math.degrees, ta),
        dedendum_angle_deg=_pairwise(math.degrees, tf),
        mean_addendum_factor=cham,
        profile_shift_coefficient=xhm,
        thickness_modification_coefficient=data.thickness_modification_coefficient,
        mean_addendum_mm=ham,
        mean_dedendum_mm=hfm,
        outer_addendum_mm=hae,
        outer_dedendum_mm=hfe,
        inner_addendum_mm=hai,
        inner_dedendum_mm=hfi,
        mean_working_depth_mm=hmw,
        clearance_mm=clearance,
        outer_whole_depth_mm=_pairwise(lambda a, f: a + f, hae, hfe),
        mean_pitch_diameter_mm=dm,
        outer_pitch_diameter_mm=de,
        outside_diameter_mm=_pairwise(lambda d, h, g: d + 2.0 * h * math.cos(g), de, hae, delta),
        crown_to_crossing_point_mm=_pairwise(
            lambda g, h: re * math.cos(g) - h * math.sin(g), delta, hae
        ),
        mean_normal_circular_thickness_mm=smn,
        mean_normal_chordal_thickness_mm=smnc,
        mean_chordal_addendum_mm=hamc,
        mean_normal_top_land_mm=top,
        **ratios,
    )
    if blank.total_contact_ratio < 1.0:
        raise DesignError(
            "pair.face_width_mm",
            b,
            "gives a total contact ratio of the virtual cylindrical gears "
            + (f"on the {('drive', 'coast')[worse]} side " if sides[0] != sides[1] else "")
            + f"eps_vg = {blank.total_contact_ratio:.4f} < 1 (face {blank.face_contact_ratio:.4f}, "
            + f"profile {blank.profile_contact_ratio:.4f}): the pair cannot mesh continuously",
        )
    undercut = min(range(2), key=lambda k: dvn_sides[k][0] * math.sin(sides[k]) ** 2)
    from_checks = _warnings(
        blank,
        data,
        dvn=dvn_sides[undercut],
        alpha=sides[undercut],
        side=("drive", "coast")[undercut] if sides[0] != sides[1] else "",
    )
    return replace(blank, warnings=from_checks)


def _contact_ratios(*, dm, delta, ham, beta, alpha, mmn, b) -> dict[str, float]:
    """Face, profile and total contact ratio of the virtual cylindrical gears (ISO 10300-1)."""
    dv = _pairwise(lambda d, g: d / math.cos(g), dm, delta)
    avet = math.atan(math.tan(alpha) / math.cos(beta))
    dvb = _pairwise(lambda d: d * math.cos(avet), dv)
    dva = _pairwise(lambda d, h: d + 2.0 * h, dv, ham)
    av = 0.5 * (dv[0] + dv[1])
    gva = 0.5 * sum(math.sqrt(a**2 - c**2) for a, c in zip(dva, dvb, strict=True))
    gva -= av * math.sin(avet)
    eps_a = gva * math.cos(beta) / (math.pi * mmn * math.cos(avet))
    eps_b = b * math.sin(beta) / (math.pi * mmn)
    return {
        "face_contact_ratio": eps_b,
        "profile_contact_ratio": eps_a,
        "total_contact_ratio": math.hypot(eps_a, eps_b),
    }


def _warnings(
    blank: StandardBlank, data: BlankData, *, dvn, alpha: float, side: str
) -> tuple[str, ...]:
    """The checks of a blank that is cuttable but outside the usual range, each naming its
    rule and values (the undercut on the side of the smaller pressure angle, ``side``)."""
    out = []
    b, re, mmn = (
        blank.outer_cone_distance_mm - blank.inner_cone_distance_mm,
        blank.outer_cone_distance_mm,
        blank.mean_normal_module_mm,
    )
    if b > re / 3.0:
        out.append(
            f"face width: b = {b:.3f} mm > R_e / 3 = {re / 3.0:.3f} mm (ISO 23509 advises "
            f"b <= R_e / 3; here b / R_e = {b / re:.3f})"
        )
    if b > 10.0 * mmn:
        out.append(f"face width: b = {b:.3f} mm > 10 m_mn = {10.0 * mmn:.3f} mm")
    for member, top in zip(("pinion", "gear"), blank.mean_normal_top_land_mm, strict=True):
        if top <= 0.0:
            out.append(
                f"pointed tooth: the {member}'s mean normal top land s_mna = {top:.4f} mm <= 0 "
                "(the flanks meet below the face cone)"
            )
        elif top < 0.2 * mmn:
            out.append(
                f"top land: the {member}'s mean normal top land s_mna = {top:.4f} mm < "
                f"0.2 m_mn = {0.2 * mmn:.4f} mm"
            )
    limit = 0.5 * dvn[0] * math.sin(alpha) ** 2
    working = blank.mean_working_depth_mm - blank.mean_addendum_mm[0]
    if working > limit:
        out.append(
            f"undercut: the pinion's mean working dedendum h_mw - h_am1 = {working:.4f} mm "
            f"exceeds d_vn1 sin^2(alpha_n) / 2 = {limit:.4f} mm of its virtual normal spur "
            "gear (the generating rack undercuts the pinion"
            + (f" on its {side} flank)" if side else ")")
        )
    if blank.profile_contact_ratio < 1.0:
        out.append(
            f"contact ratio: profile contact ratio eps_va = {blank.profile_contact_ratio:.4f} "
            "< 1 (the face contact ratio carries the mesh)"
        )
    if blank.mean_spiral_angle_deg > 0.0 and blank.face_contact_ratio < 1.0:
        out.append(
            f"contact ratio: face contact ratio eps_vb = {blank.face_contact_ratio:.4f} < 1 "
            "(a spiral bevel pair usually has eps_vb >= 1.25)"
        )
    rm, beta = blank.mean_cone_distance_mm, math.radians(blank.mean_spiral_angle_deg)
    if blank.taper in ("duplex", "tilted_root") and not (
        1.1 * rm * math.sin(beta) <= data.cutter_radius_mm <= rm
    ):
        out.append(
            f"cutter radius: r_c0 = {data.cutter_radius_mm:g} mm outside 1.1 R_m sin(beta_m) = "
            f"{1.1 * rm * math.sin(beta):.3f} mm ... R_m = {rm:.3f} mm (the usual range for "
            f"{blank.taper} taper)"
        )
    return tuple(out)
