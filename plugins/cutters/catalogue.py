"""Standard cutters one can buy, per cutting method, with the source of every entry.

A catalogue is plugin data: the machine models read it through
:meth:`gearopt.machine.BaseMachineModel.cutter_catalogue` (the core names no catalogue), as the
categorical search space of a study (``[search] "<key>" = "catalogue"``) and as a default where
a design gives no cutter. Each :class:`CutterSize` says where it comes from; an entry whose
value no public document at hand confirms says so (``sourced=False``) and is kept only because
gearopt already used it, never invented here. What is *not* in these lists is not claimed to
be unavailable: the published ranges (Gleason's full nominal list, Klingelnberg's cyclo-palloid
and epicycloid heads with their module ranges) could not be found in public material here
(``docs/cutters.md``).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

from gearopt.machine import SearchDimension

__all__ = [
    "INCH_MM",
    "CutterSize",
    "Catalogue",
    "FACE_MILLING",
    "CYCLO_PALLOID",
    "EPICYCLOID",
    "face_hobbing_rules",
    "face_hobbing_dimensions",
    "face_milling_rules",
    "filtered",
    "nearest",
]

INCH_MM = 25.4

_SEED_001 = (
    "seed 001 (Fuentes-Aznar et al., cyclo-palloid basic settings), Table 1 'Basic "
    "transmission and cyclo-palloid cutter data': cutter radius 75.0 mm, 5 blade groups, "
    "'selected according to Standard ANSI/AGMA 2005-C96 among the available tools' (section 3)"
)
_SEED_003 = (
    "seed 003 (Klingelnberg epicycloid, uniform depth), Table 1 'Number cutter group 5' and "
    "Table 2 case A 'Cutter head radius R_h 135 mm' (m_mn 6.1 mm)"
)
_ISO_SAMPLE = (
    "ISO 23509:2016 Annex F sample 1 (face milling, 14/39): r_c0 = 114.3 mm (4.5 in), as "
    "issue 24 quotes the standard's data"
)
_NASA_CR191009 = (
    "Bibel, Reddy, Kumar, NASA Contractor Report CR-191009 (1994), pp. 4-6, as transcribed in "
    "tests/data/nasa_cr191009.json: the 12 x 36 pair's gear is cut by one spread-blade face "
    "mill whose outside and inside blade point radii are printed as r = 3.0325 in and "
    "2.9675 in, so its nominal (mean point) radius is 3.0 in, a 6 in diameter, point width "
    "0.065 in"
)
_GEARFILE = (
    "unsourced: gearopt's list since commit b4d1a09 (plugins/face_milling/synthesis/gear.py, "
    "'Gleason's face-mill diameters 1.1 to 18 in'); no public document found here confirms it"
)


@dataclass(frozen=True, kw_only=True)
class CutterSize:
    """One standard cutter.

    Attributes
    ----------
    radius_mm
        Nominal cutter radius r_c0 (the mean of the inside and outside blades' radii).
    blade_groups
        z_0 of a face-hobbing head; None for a face mill (single indexing).
    module_range_mm
        ``(low, high)`` normal module the head is made for, None where no source gives it.
    nominal
        The size as published (``"9 in diameter"``, ``"r = 75 mm"``).
    source
        Where the value comes from (document, table, page).
    sourced
        False when no public document at hand confirms the value.
    """

    radius_mm: float
    blade_groups: int | None
    module_range_mm: tuple[float, float] | None
    nominal: str
    source: str
    sourced: bool = True


@dataclass(frozen=True, kw_only=True)
class Catalogue:
    """The standard cutters of one method (``name``), smallest first."""

    name: str
    method: str
    sizes: tuple[CutterSize, ...]

    @property
    def sourced_count(self) -> int:
        return sum(1 for s in self.sizes if s.sourced)


#: the face mills a public document uses, by nominal diameter in inches, with that document
_SOURCED_FACE_MILLS_IN = {6.0: _NASA_CR191009, 9.0: _ISO_SAMPLE}


def _face_mill(diameter_in: float, source: str, sourced: bool) -> CutterSize:
    return CutterSize(
        radius_mm=round(0.5 * diameter_in * INCH_MM, 6),
        blade_groups=None,
        module_range_mm=None,
        nominal=f"{diameter_in:g} in diameter",
        source=source,
        sourced=sourced,
    )


FACE_MILLING = Catalogue(
    name="Gleason face mills",
    method="face milling",
    sizes=tuple(
        _face_mill(d, _SOURCED_FACE_MILLS_IN[d], True)
        if d in _SOURCED_FACE_MILLS_IN
        else _face_mill(d, _GEARFILE, False)
        for d in (1.1, 1.5, 2.0, 3.5, 5.0, 6.0, 7.5, 9.0, 10.5, 12.0, 15.0, 18.0)
    ),
)

CYCLO_PALLOID = Catalogue(
    name="Klingelnberg cyclo-palloid heads",
    method="face hobbing (cyclo-palloid)",
    sizes=(
        CutterSize(
            radius_mm=75.0,
            blade_groups=5,
            module_range_mm=None,
            nominal="r = 75 mm, z0 = 5",
            source=_SEED_001,
        ),
    ),
)

EPICYCLOID = Catalogue(
    name="Klingelnberg epicycloid heads",
    method="face hobbing (epicycloid)",
    sizes=(
        CutterSize(
            radius_mm=135.0,
            blade_groups=5,
            module_range_mm=None,
            nominal="R_h = 135 mm, z0 = 5",
            source=_SEED_003,
        ),
    ),
)


def filtered(
    catalogue: Catalogue, rules: tuple[tuple[str, Callable[[CutterSize], bool]], ...]
) -> tuple[tuple[CutterSize, ...], str]:
    """The sizes every rule keeps, and one line saying how many remain of how many and which
    rule dropped the others (``rules`` pairs a rule's words with its test)."""
    kept = []
    dropped: dict[str, int] = {}
    for size in catalogue.sizes:
        failed = next((words for words, keep in rules if not keep(size)), None)
        if failed is None:
            kept.append(size)
        else:
            dropped[failed] = dropped.get(failed, 0) + 1
    why = "; ".join(f"{n} dropped: {words}" for words, n in dropped.items())
    sourced = sum(1 for s in kept if s.sourced)
    note = (
        f"{catalogue.name}: {len(kept)} of {len(catalogue.sizes)} sizes suit the design "
        f"({sourced} of them with a public source)" + (f"; {why}" if why else "")
    )
    return tuple(kept), note


def nearest(sizes: tuple[CutterSize, ...], radius_mm: float) -> CutterSize:
    """The size whose radius is nearest ``radius_mm`` (the first of a tie)."""
    return min(sizes, key=lambda s: abs(s.radius_mm - radius_mm))


def face_hobbing_rules(
    *, blade_groups: int, module_mm: float
) -> tuple[tuple[str, Callable[[CutterSize], bool]], ...]:
    """The rules a face-hobbing head must meet for a design: its blade groups, the slope
    angle's limit r_c0 > z_0 m / 2 (seed 001 eq 9: sin nu < 1), and its module range where
    known."""
    return (
        (
            f"blade groups other than the design's z0 = {blade_groups}",
            lambda s: s.blade_groups == blade_groups,
        ),
        (
            f"radius <= z0 m / 2 = {0.5 * blade_groups * module_mm:.3f} mm (seed 001 eq 9)",
            lambda s: s.radius_mm > 0.5 * blade_groups * module_mm,
        ),
        (
            f"module range without m = {module_mm:.4g} mm",
            lambda s: (
                s.module_range_mm is None
                or s.module_range_mm[0] <= module_mm <= s.module_range_mm[1]
            ),
        ),
    )


def face_milling_rules(
    *,
    mean_cone_distance_mm: float,
    face_width_mm: float,
    spiral_angle_deg: float,
    slot_width_mm: float,
    slot_reach_mm: float,
) -> tuple[tuple[str, Callable[[CutterSize], bool]], ...]:
    """The rules a face mill must meet for a design: a circular tooth trace at toe and heel
    (sin beta(R) = (R^2 - R_m^2 + 2 R_m r_c0 sin beta_m) / (2 R r_c0) inside (-1, 1), ISO
    23509's face-milling trace) and a positive inside-blade point radius
    r_c0 - W / 2 - h_f tan(alpha) > 0 (the gear's spread blade)."""
    rm, half = mean_cone_distance_mm, 0.5 * face_width_mm
    sb = math.sin(math.radians(spiral_angle_deg))

    def trace(s: CutterSize) -> bool:
        rc = s.radius_mm
        return all(
            abs((r * r - rm * rm + 2.0 * rm * rc * sb) / (2.0 * r * rc)) < 1.0
            for r in (rm - half, rm + half)
        )

    return (
        ("no circular tooth trace reaches toe and heel", trace),
        (
            f"inside blade's point radius <= 0 (r_c0 <= {0.5 * slot_width_mm + slot_reach_mm:.3f}"
            " mm)",
            lambda s: s.radius_mm - 0.5 * slot_width_mm - slot_reach_mm > 0.0,
        ),
    )


def face_hobbing_dimensions(
    catalogue: Catalogue, keys: tuple[str, ...], *, blade_groups: int, module_mm: float
) -> tuple[SearchDimension, ...]:
    """Categorical dimensions of ``keys`` over the heads of ``catalogue`` that suit a
    face-hobbing design (:func:`face_hobbing_rules`); () when none does. The note says for
    how many of the kept heads a module range is known (the others pass the module rule
    unchecked)."""
    sizes, note = filtered(
        catalogue, face_hobbing_rules(blade_groups=blade_groups, module_mm=module_mm)
    )
    if not sizes:
        return ()
    ranged = sum(1 for s in sizes if s.module_range_mm is not None)
    note += f"; module range known for {ranged} of the {len(sizes)} kept"
    radii = [s.radius_mm for s in sizes]
    return tuple(SearchDimension.categorical(key, radii, note) for key in keys)
