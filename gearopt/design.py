"""The frozen, validated dataclasses a design file (TOML) loads into (reading the file, which
needs the plugin registry for its ``[machine]`` table, is :mod:`gearopt.design_files`).

A design file has the tables ``[meta]`` (optional), ``[pair]`` (the blank data of the pair),
``[blank]`` (optional: ``standard = "iso23509"`` and the standard's data, which then derive the
pair's addenda, dedenda, face and root angles and chordal thickness, :mod:`gearopt.iso23509`),
``[machine]`` (``model = "..."`` plus the machine model's own keys, parsed by that model's plugin),
``[misalignment]`` (how the pair is assembled; what the contact engine sees) and
``[compensation]`` (alignment errors the machine settings compensate, seed 001 section 4).
Every key carries its unit (``_mm``, ``_deg``); members are listed ``[pinion, gear]``.

Example (seed 001, Table 2)::

    [pair]
    pinion_teeth = 16
    gear_teeth = 41
    shaft_angle_deg = 90.0
    mean_spiral_angle_deg = 35.0
    mean_cone_distance_mm = 91.265        # or mean_normal_module_mm = 3.397, or
                                          # outer_pitch_diameter_mm (the gear's d_e2), or
                                          # outer_transverse_module_mm
    face_width_mm = 32.0
    pressure_angle_deg = 20.0             # or [drive, coast]: unequal flank pressure angles
    pinion_hand = "left"
    outer_addendum_mm = [3.397, 3.397]
    outer_dedendum_mm = [4.076, 4.076]
    # tapered depth (face-milling model only; uniform depth when absent):
    # face_angle_deg = [pinion, gear]      # face (tip) cone angles
    # root_angle_deg = [pinion, gear]      # root cone angles

or, from basic data, no addenda, dedenda or angles in ``[pair]`` but::

    [blank]
    standard = "iso23509"
    cutter_radius_mm = 75.0               # r_c0
    blade_groups = 5                      # face hobbing (uniform depth); absent: face milling
    # taper = "standard"                  # face milling: standard, uniform, duplex, tilted_root
    # gear_addendum_angle_deg, gear_dedendum_angle_deg: given angles instead of a taper
    # mean_addendum_factor or profile_shift_coefficient, depth_factor, clearance_factor,
    # thickness_factor or thickness_modification_coefficient, outer_normal_backlash_mm
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from functools import cached_property
from pathlib import Path
from typing import Any

from gearopt.assembly import Misalignment
from gearopt.blank import Blank, compute_blank, cone_distance_from_module_mm, pitch_angles_rad
from gearopt.errors import DesignError, NotAvailableError
from gearopt.iso23509 import BlankData, PairBasics, StandardBlank
from gearopt.iso23509 import standard_blank as iso23509_blank
from gearopt.validate import (
    check_integer,
    check_keys,
    check_number,
)

__all__ = [
    "MEMBERS",
    "PairData",
    "Misalignment",
    "Meta",
    "Design",
    "SECTIONS",
    "pair_from_table",
    "pair_from_tables",
    "STANDARD_BLANK_KEYS",
]

MEMBERS = ("pinion", "gear")
SECTIONS = (
    "meta",
    "pair",
    "blank",
    "machine",
    "misalignment",
    "compensation",
    "analysis",
    "load",
    "synthesis",
    "te_target",
)
MODULE_TOLERANCE = 1e-3  # module and cone distance, when both are given, agree within 0.1 %
#: the largest addendum or dedendum angle (face - pitch, pitch - root) of a tapered-depth blank
MAX_TAPER_ANGLE_DEG = 15.0

#: the ``[pair]`` keys a ``[blank]`` table's standard derives (a design gives one or the other)
STANDARD_BLANK_KEYS = (
    "outer_addendum_mm",
    "outer_dedendum_mm",
    "face_angle_deg",
    "root_angle_deg",
    "mean_normal_chordal_addendum_mm",
    "mean_normal_chordal_thickness_mm",
)

_PAIR_KEYS = (
    "pinion_teeth",
    "gear_teeth",
    "shaft_angle_deg",
    "mean_spiral_angle_deg",
    "mean_normal_module_mm",
    "mean_cone_distance_mm",
    "outer_pitch_diameter_mm",
    "outer_transverse_module_mm",
    "face_width_mm",
    "pressure_angle_deg",
    "pinion_hand",
    *STANDARD_BLANK_KEYS,
)


def _member_tuple(name: str, value: Any, *, gt: float | None = 0.0) -> tuple[float, float]:
    if isinstance(value, int | float) and not isinstance(value, bool):
        value = (value, value)
    if not isinstance(value, list | tuple) or len(value) != 2:
        raise DesignError(name, value, "must be a list of two numbers [pinion, gear]")
    return tuple(  # type: ignore[return-value]
        check_number(f"{name}[{m}]", v, gt=gt, unit="mm")
        for m, v in zip(MEMBERS, value, strict=True)
    )


@dataclass(frozen=True, kw_only=True)
class PairData:
    """Blank data of a spiral bevel pair (``[pair]`` of a design file).

    Give ``mean_cone_distance_mm`` or ``mean_normal_module_mm``; the other is derived. When both
    are given the cone distance is used and the module only checked against it (0.1 %).
    ``outer_addendum_mm`` and ``outer_dedendum_mm`` default to 1.0 and 1.25 mean normal modules;
    the chordal addendum and thickness are needed only to solve the additional slope angle.

    ``pressure_angle_deg`` is one angle or ``[drive, coast]`` (drive: pinion convex on gear
    concave; coast: pinion concave on gear convex). After validation ``pressure_angle_deg`` is
    the drive side's and ``pressure_angles_deg`` the pair ``(drive, coast)``; a model that
    cannot cut unequal angles refuses a pair whose ``unequal_pressure_angles`` is True.

    Tapered depth: ``face_angle_deg`` and ``root_angle_deg`` (``[pinion, gear]``, as published
    summaries print them) give the face and root cones; either absent means that cone is
    parallel to the pitch cone (uniform depth: face = root = pitch angle). The outer addendum
    and dedendum are then those at the heel (outer cone distance A_o), and the mean ones follow
    from the addendum angle theta_a = face - pitch and the dedendum angle
    theta_d = pitch - root (:func:`gearopt.blank.compute_blank`). Rules: root <= pitch <= face,
    each angle at most ``MAX_TAPER_ANGLE_DEG`` = 15 deg, root angle > 0, positive addendum and
    dedendum at the toe, and the mating top clearing the root at toe and heel.
    """

    pinion_teeth: int
    gear_teeth: int
    mean_spiral_angle_deg: float
    face_width_mm: float
    shaft_angle_deg: float = 90.0
    pressure_angle_deg: float | tuple[float, float] = 20.0
    pinion_hand: str = "left"
    mean_cone_distance_mm: float | None = None
    mean_normal_module_mm: float | None = None
    outer_pitch_diameter_mm: float | None = None
    outer_transverse_module_mm: float | None = None
    outer_addendum_mm: tuple[float, float] | None = None
    outer_dedendum_mm: tuple[float, float] | None = None
    face_angle_deg: tuple[float, float] | None = None
    root_angle_deg: tuple[float, float] | None = None
    mean_normal_chordal_addendum_mm: tuple[float, float] | None = None
    mean_normal_chordal_thickness_mm: tuple[float, float] | None = None
    #: ``(drive, coast)``, derived from ``pressure_angle_deg`` (given only by ``replace``)
    pressure_angles_deg: tuple[float, float] | None = None

    @property
    def unequal_pressure_angles(self) -> bool:
        """True when the drive and coast pressure angles differ."""
        return self.pressure_angles_deg[0] != self.pressure_angles_deg[1]

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        n1 = check_integer("pair.pinion_teeth", self.pinion_teeth, ge=5, le=500)
        check_integer("pair.gear_teeth", self.gear_teeth, ge=5, le=1000)
        if self.gear_teeth < n1:
            raise DesignError(
                "pair.gear_teeth",
                self.gear_teeth,
                f"must be >= pair.pinion_teeth = {n1} (member 1 is the pinion, the smaller member)",
            )
        check_number("pair.shaft_angle_deg", self.shaft_angle_deg, gt=0.0, lt=180.0, unit="degrees")
        psi = check_number(
            "pair.mean_spiral_angle_deg",
            self.mean_spiral_angle_deg,
            ge=0.0,
            le=60.0,
            unit="degrees",
        )
        angles = self.pressure_angle_deg
        kept = self.pressure_angles_deg  # a copy's (dataclasses.replace) two sides
        if not isinstance(angles, list | tuple) and kept is not None and kept[0] == angles:
            angles = kept
        if isinstance(angles, list | tuple):
            if len(angles) != 2:
                raise DesignError(
                    "pair.pressure_angle_deg",
                    list(angles),
                    "must be one angle or a list of two [drive, coast]",
                )
            names = ("pair.pressure_angle_deg[drive]", "pair.pressure_angle_deg[coast]")
        else:
            angles, names = (angles, angles), ("pair.pressure_angle_deg",) * 2
        angles = tuple(
            float(check_number(n, a, gt=0.0, lt=45.0, unit="degrees"))
            for n, a in zip(names, angles, strict=True)
        )
        set_(self, "pressure_angles_deg", angles)
        set_(self, "pressure_angle_deg", angles[0])
        if not isinstance(self.pinion_hand, str) or self.pinion_hand.lower() not in (
            "left",
            "right",
        ):
            raise DesignError("pair.pinion_hand", self.pinion_hand, "must be 'left' or 'right'")
        set_(self, "pinion_hand", self.pinion_hand.lower())

        g1, g2 = pitch_angles_rad(n1, self.gear_teeth, math.radians(self.shaft_angle_deg))
        am = self._mean_cone_distance_mm(g1, g2, psi)
        derived = 2.0 * am * math.sin(g1) * math.cos(math.radians(psi)) / n1
        set_(self, "mean_cone_distance_mm", am)
        set_(self, "mean_normal_module_mm", derived)

        face = check_number("pair.face_width_mm", self.face_width_mm, gt=0.0, unit="mm")
        for name in ("shaft_angle_deg", "mean_spiral_angle_deg"):
            set_(self, name, float(getattr(self, name)))
        set_(self, "face_width_mm", face)
        outer = am + 0.5 * face  # the outer cone distance R_e
        if not outer / 20.0 <= face <= 0.5 * outer:
            raise DesignError(
                "pair.face_width_mm",
                face,
                f"must lie between 1/20 and 1/2 of the outer cone distance R_e = "
                f"mean_cone_distance_mm + face_width_mm / 2 = {outer:g} mm, i.e. between "
                f"{am / 19.5:.4g} and {2.0 * am / 3.0:.4g} mm (a wider face leaves the toe's "
                "teeth too small to cut; ISO 23509 advises at most R_e / 3)",
            )
        add = self.outer_addendum_mm if self.outer_addendum_mm is not None else derived
        ded = self.outer_dedendum_mm if self.outer_dedendum_mm is not None else 1.25 * derived
        add = _member_tuple("pair.outer_addendum_mm", add)
        ded = _member_tuple("pair.outer_dedendum_mm", ded)
        for i, j in ((0, 1), (1, 0)):
            if ded[i] < add[j]:
                raise DesignError(
                    f"pair.outer_dedendum_mm[{MEMBERS[i]}]",
                    ded[i],
                    f"must be >= outer_addendum_mm[{MEMBERS[j]}] = {add[j]:g} "
                    "(the mating tooth's top must clear the root)",
                )
        set_(self, "outer_addendum_mm", add)
        set_(self, "outer_dedendum_mm", ded)
        self._check_taper(g1, face, add, ded)
        pitch = math.pi * derived
        for name in ("mean_normal_chordal_addendum_mm", "mean_normal_chordal_thickness_mm"):
            value = getattr(self, name)
            if value is not None:
                value = _member_tuple(f"pair.{name}", value)
                set_(self, name, value)
        thickness = self.mean_normal_chordal_thickness_mm
        if thickness is not None and sum(thickness) >= pitch:
            raise DesignError(
                "pair.mean_normal_chordal_thickness_mm",
                list(thickness),
                f"pinion + gear must be < the normal circular pitch pi m_mn = {pitch:.4f} mm",
            )
        chordal_add = self.mean_normal_chordal_addendum_mm
        if chordal_add is not None:
            for m, ca, a, d in zip(MEMBERS, chordal_add, add, ded, strict=True):
                if ca >= a + d:
                    raise DesignError(
                        f"pair.mean_normal_chordal_addendum_mm[{m}]",
                        ca,
                        f"must be < the whole depth {a + d:g} mm",
                    )

    def _mean_cone_distance_mm(self, g1: float, g2: float, psi_deg: float) -> float:
        """A_m from the one size given (the first of mean cone distance, gear outer pitch
        diameter d_e2, outer transverse module m_et, mean normal module); every other size
        given must agree with it within 0.1 %."""
        face = check_number("pair.face_width_mm", self.face_width_mm, gt=0.0, unit="mm")
        n1, n2, psi = self.pinion_teeth, self.gear_teeth, math.radians(psi_deg)
        to_am = {
            "mean_cone_distance_mm": lambda v: v,
            "outer_pitch_diameter_mm": lambda v: v / (2.0 * math.sin(g2)) - 0.5 * face,
            "outer_transverse_module_mm": lambda v: v * n2 / (2.0 * math.sin(g2)) - 0.5 * face,
            "mean_normal_module_mm": lambda v: cone_distance_from_module_mm(
                pinion_teeth=n1, pinion_pitch_angle_rad=g1, spiral_angle_rad=psi, module_mm=v
            ),
        }
        given = {
            k: check_number(f"pair.{k}", getattr(self, k), gt=0.0, unit="mm")
            for k in to_am
            if getattr(self, k) is not None
        }
        if not given:
            raise DesignError(
                "pair.mean_cone_distance_mm",
                rule="give mean_cone_distance_mm or mean_normal_module_mm or "
                "outer_pitch_diameter_mm (the gear's d_e2) or outer_transverse_module_mm: one "
                "size, the others are derived",
            )
        first = next(iter(given))
        am = to_am[first](given[first])
        if am <= 0.0:
            raise DesignError(
                f"pair.{first}",
                given[first],
                f"gives an outer cone distance <= face_width_mm / 2 = {0.5 * face:g} mm",
            )
        for name, value in given.items():
            implied = to_am[name](value)
            if abs(implied - am) > MODULE_TOLERANCE * am:
                raise DesignError(
                    f"pair.{name}",
                    value,
                    f"must agree within 0.1 % with {first} = {given[first]:g} mm: it gives "
                    f"A_m = {implied:.5f} mm, {first} gives {am:.5f} mm (give one size, or "
                    "consistent values)",
                )
        return am

    def _check_taper(self, g1: float, face: float, add, ded) -> None:
        """Validate ``face_angle_deg`` and ``root_angle_deg`` (tapered depth)."""
        pitch = (math.degrees(g1), self.shaft_angle_deg - math.degrees(g1))
        tans = {}
        for name, sign in (("face_angle_deg", 1.0), ("root_angle_deg", -1.0)):
            value = getattr(self, name)
            if value is None:
                tans[name] = (0.0, 0.0)
                continue
            where = f"pair.{name}"
            if not isinstance(value, list | tuple) or len(value) != 2:
                raise DesignError(where, value, "must be a list of two angles [pinion, gear]")
            angles = tuple(
                check_number(f"{where}[{m}]", v, gt=0.0, lt=180.0, unit="degrees")
                for m, v in zip(MEMBERS, value, strict=True)
            )
            for m, angle, p in zip(MEMBERS, angles, pitch, strict=True):
                taper = sign * (angle - p)  # addendum angle, or dedendum angle
                if taper < 0.0:
                    rule = (
                        f"must be >= the pitch angle {p:.6f} deg (the face cone lies outside the "
                        "pitch cone)"
                        if sign > 0
                        else f"must be <= the pitch angle {p:.6f} deg (the root cone lies "
                        "inside the pitch cone)"
                    )
                    raise DesignError(f"{where}[{m}]", angle, rule)
                if taper > MAX_TAPER_ANGLE_DEG:
                    which = "face - pitch" if sign > 0 else "pitch - root"
                    raise DesignError(
                        f"{where}[{m}]",
                        angle,
                        f"{which} = {taper:.4f} deg exceeds {MAX_TAPER_ANGLE_DEG:g} deg "
                        f"(pitch angle {p:.6f} deg): not a tapered-depth bevel blank",
                    )
            object.__setattr__(self, name, tuple(float(a) for a in angles))
            tans[name] = tuple(
                math.tan(math.radians(sign * (a - p))) for a, p in zip(angles, pitch, strict=True)
            )
        # at the toe (cone distance A_o - F): addenda and dedenda positive, tops clear roots
        toe_add = [a - face * t for a, t in zip(add, tans["face_angle_deg"], strict=True)]
        toe_ded = [b - face * t for b, t in zip(ded, tans["root_angle_deg"], strict=True)]
        for k, m in enumerate(MEMBERS):
            for name, value in (("face_angle_deg", toe_add[k]), ("root_angle_deg", toe_ded[k])):
                if value <= 0.0:
                    what = "addendum" if name == "face_angle_deg" else "dedendum"
                    raise DesignError(
                        f"pair.{name}[{m}]",
                        getattr(self, name)[k],
                        f"leaves the {what} at the toe {value:.4f} mm <= 0 (the outer {what} "
                        "is at the heel; the toe lies face_width_mm inward)",
                    )
        for i, j in ((0, 1), (1, 0)):
            if toe_ded[i] < toe_add[j] - 1e-9:
                name = "face_angle_deg" if self.face_angle_deg is not None else "root_angle_deg"
                raise DesignError(
                    f"pair.{name}",
                    list(getattr(self, name)),
                    f"at the toe the {MEMBERS[i]}'s dedendum {toe_ded[i]:.4f} mm is smaller than "
                    f"the {MEMBERS[j]}'s addendum {toe_add[j]:.4f} mm (the mating tooth's top "
                    "must clear the root)",
                )

    @property
    def tapered(self) -> bool:
        """True when a face or root angle is given (tapered depth)."""
        return self.face_angle_deg is not None or self.root_angle_deg is not None

    def require_uniform_depth(self, model: str) -> None:
        """Raise :class:`NotAvailableError` naming ``pair.face_angle_deg`` (or
        ``pair.root_angle_deg``) when the pair is tapered: for machine models that cut uniform
        depth only."""
        if self.tapered:
            name = "face_angle_deg" if self.face_angle_deg is not None else "root_angle_deg"
            raise NotAvailableError(
                f"pair.{name}",
                list(getattr(self, name)),
                f"the {model} model cuts uniform depth only (face = root = pitch angle): "
                "remove face_angle_deg and root_angle_deg from [pair]",
            )

    @property
    def gear_hand(self) -> str:
        """Hand of the gear: the opposite of the pinion's."""
        return "right" if self.pinion_hand == "left" else "left"

    @cached_property
    def blank(self) -> Blank:
        """Derived blank geometry (pitch angles, cone distances, modules, radii)."""
        return compute_blank(self)


@dataclass(frozen=True, kw_only=True)
class Meta:
    """Free text about a design: its name, where it comes from, notes."""

    name: str = ""
    description: str = ""
    source: str = ""

    def __post_init__(self) -> None:
        for key in ("name", "description", "source"):
            if not isinstance(getattr(self, key), str):
                raise DesignError(f"meta.{key}", getattr(self, key), "must be a string")


@dataclass(frozen=True, kw_only=True)
class Design:
    """A complete design: the pair, the machine (parsed by its model's plugin) and conditions.

    ``machine`` is the machine model's own frozen settings dataclass; ``model`` names the model.
    ``standard_blank`` is the blank the ``[blank]`` table's standard computed (None when the
    design gives its blank in ``[pair]``). ``source`` keeps the parsed TOML document, so a
    design can be re-derived with overrides (:func:`with_overrides`) and written back.
    """

    pair: PairData
    model: str
    machine: Any
    misalignment: Misalignment = field(default_factory=Misalignment)
    compensation: Misalignment = field(default_factory=Misalignment)
    meta: Meta = field(default_factory=Meta)
    analysis: Mapping[str, Any] = field(default_factory=dict)
    load: Mapping[str, Any] = field(default_factory=dict)
    te_target: Any = None
    standard_blank: StandardBlank | None = None
    source: Mapping[str, Any] = field(default_factory=dict, repr=False, compare=False)
    path: str | None = field(default=None, compare=False)

    @property
    def blank(self) -> Blank:
        """Derived blank geometry of the pair."""
        return self.pair.blank

    @property
    def name(self) -> str:
        """The design's name: ``[meta] name``, else the file's stem, else ``"design"``."""
        if self.meta.name:
            return self.meta.name
        if self.path:
            return Path(self.path).stem
        return "design"


def pair_from_table(table: Mapping[str, Any]) -> PairData:
    """The ``[pair]`` table of a design file as :class:`PairData` (unknown keys refused)."""
    check_keys(table, _PAIR_KEYS, "pair")
    for key in ("pinion_teeth", "gear_teeth", "mean_spiral_angle_deg", "face_width_mm"):
        if key not in table:
            raise DesignError(f"pair.{key}", rule="required key is missing")
    return PairData(**table)


def pair_from_tables(
    pair_table: Mapping[str, Any], blank_table: Mapping[str, Any] | None
) -> tuple[PairData, StandardBlank | None]:
    """The ``[pair]`` table, its blank completed by the ``[blank]`` table's standard.

    Without ``[blank]`` the pair is read as :func:`pair_from_table` reads it (the blank as
    given) and no standard blank is returned. With ``[blank] standard = "iso23509"`` the
    standard's outer addenda and dedenda, face and root angles (tapered depth) and mean normal
    chordal thickness and addendum fill the pair, so every machine model cuts that blank; the
    ``[pair]`` then gives none of :data:`STANDARD_BLANK_KEYS`.
    """
    if blank_table is None:
        return pair_from_table(pair_table), None
    for key in STANDARD_BLANK_KEYS:
        if key in pair_table:
            raise DesignError(
                f"pair.{key}",
                pair_table[key],
                "is derived by [blank] standard = 'iso23509': remove it from [pair] (or remove "
                "the [blank] table to give the blank by hand)",
            )
    data = BlankData.from_table(blank_table)
    base = pair_from_table(pair_table)
    blank = iso23509_blank(
        PairBasics(
            pinion_teeth=base.pinion_teeth,
            gear_teeth=base.gear_teeth,
            shaft_angle_deg=base.shaft_angle_deg,
            mean_spiral_angle_deg=base.mean_spiral_angle_deg,
            pressure_angle_deg=base.pressure_angle_deg,
            coast_pressure_angle_deg=base.pressure_angles_deg[1],
            face_width_mm=base.face_width_mm,
            mean_cone_distance_mm=base.mean_cone_distance_mm,
        ),
        data,
    )
    tapered = any(a != 0.0 for a in (*blank.addendum_angle_deg, *blank.dedendum_angle_deg))
    pair = replace(
        base,
        outer_addendum_mm=blank.outer_addendum_mm,
        outer_dedendum_mm=blank.outer_dedendum_mm,
        face_angle_deg=blank.face_angle_deg if tapered else None,
        root_angle_deg=blank.root_angle_deg if tapered else None,
        mean_normal_chordal_addendum_mm=blank.mean_chordal_addendum_mm,
        mean_normal_chordal_thickness_mm=blank.mean_normal_chordal_thickness_mm,
    )
    return pair, blank
