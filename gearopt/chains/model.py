"""The parts of a machine's kinematic chains: shafts, elements, slots, meshes, chains, change gears.

A machine's indexing and envelope (generating) chains are gear trains: shafts joined by meshes
(gear pairs, worm drives), driven at one end (the rack of the indexing clutch, the cradle) and
ending at the work spindle, with change gears in quadrant slots (``a b c d``: ratio
``a c / (b d)``, ``a`` meshing ``b``, ``b`` and ``c`` on one stud, ``c`` meshing ``d``). This
module holds the machine-independent parts of that data model: frozen keyword-only dataclasses,
validated on construction (a :class:`~gearopt.errors.DesignError` names the offending key). The
machine that joins them is :class:`gearopt.chains.machine.Machine`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property
from typing import Any

import numpy as np

from gearopt.chains.parsing import MAX_TEETH, name_ok, optional_number
from gearopt.errors import DesignError
from gearopt.validate import check_integer, check_number

__all__ = [
    "ELEMENT_KINDS",
    "DIVISORS",
    "Shaft",
    "Element",
    "ChangeGearSlot",
    "Mesh",
    "Chain",
    "ToleranceBracket",
    "ChangeGearSet",
]

ELEMENT_KINDS = ("spur", "bevel", "worm", "worm_wheel", "rack")
DIVISORS = ("work_teeth", "crown_teeth")


@dataclass(frozen=True, kw_only=True)
class Shaft:
    """A shaft of the machine (``[shafts]`` of a machine file: ``name = "description"``)."""

    name: str
    description: str = ""

    def __post_init__(self) -> None:
        name_ok(self.name, "shafts")
        if not isinstance(self.description, str):
            raise DesignError(f"shafts.{self.name}", self.description, "must be a string")


@dataclass(frozen=True, kw_only=True)
class Element:
    """A fixed gear, worm, worm wheel or rack of a chain, with its errors.

    Parameters
    ----------
    name, shaft
        Unique name, and the shaft it is keyed to.
    kind
        ``"spur"``, ``"bevel"``, ``"worm"`` (``teeth`` = starts), ``"worm_wheel"`` or ``"rack"``.
        A rack drives the input shaft through its pinion: it sits on that shaft in a chain's
        ``extra_elements`` with the pinion's teeth and pitch diameter (seed 000 Table 3 counts the
        clutch rack L2 that way: D = 34 mm, fp = Fpr / 17).
    teeth
        Number of teeth (starts of a worm), >= 1.
    module_mm, pitch_diameter_mm
        Give one: the pitch diameter ``D`` that turns a linear error into an angle is
        ``pitch_diameter_mm``, else ``module_mm * teeth``, for a worm ``module_mm * teeth /
        tan(lead_angle_deg)``.
    lead_angle_deg
        Lead angle of a worm (information, and its pitch diameter when none is given).
    fi_um, fpr_um
        Kinematic error fi' and cumulative pitch error Fpr, micrometres.
    note
        Where the values come from.
    """

    name: str
    shaft: str
    kind: str = "spur"
    teeth: int
    module_mm: float | None = None
    pitch_diameter_mm: float | None = None
    lead_angle_deg: float | None = None
    fi_um: float
    fpr_um: float
    note: str = ""

    def __post_init__(self) -> None:
        where = f"elements.{name_ok(self.name, 'elements')}"
        set_ = object.__setattr__
        name_ok(self.shaft, f"{where}.shaft")
        if self.kind not in ELEMENT_KINDS:
            raise DesignError(f"{where}.kind", self.kind, f"must be one of {list(ELEMENT_KINDS)}")
        check_integer(f"{where}.teeth", self.teeth, ge=1, le=MAX_TEETH)
        set_(self, "module_mm", optional_number(f"{where}.module_mm", self.module_mm, gt=0.0))
        set_(
            self,
            "pitch_diameter_mm",
            optional_number(f"{where}.pitch_diameter_mm", self.pitch_diameter_mm, gt=0.0),
        )
        set_(
            self,
            "lead_angle_deg",
            optional_number(f"{where}.lead_angle_deg", self.lead_angle_deg, gt=0.0, lt=90.0),
        )
        if self.pitch_diameter_mm is None:
            if self.module_mm is None:
                raise DesignError(
                    f"{where}.module_mm", rule="give module_mm or pitch_diameter_mm (mm)"
                )
            if self.kind == "worm" and self.lead_angle_deg is None:
                raise DesignError(
                    f"{where}.lead_angle_deg",
                    rule="a worm needs pitch_diameter_mm, or module_mm and lead_angle_deg "
                    "(D = m z / tan(lead))",
                )
        set_(self, "fi_um", check_number(f"{where}.fi_um", self.fi_um, ge=0.0, unit="um"))
        set_(self, "fpr_um", check_number(f"{where}.fpr_um", self.fpr_um, ge=0.0, unit="um"))
        if not isinstance(self.note, str):
            raise DesignError(f"{where}.note", self.note, "must be a string")

    @property
    def diameter_mm(self) -> float:
        """The pitch diameter D used in dphi = 2F/D, mm."""
        if self.pitch_diameter_mm is not None:
            return self.pitch_diameter_mm
        assert self.module_mm is not None
        if self.kind == "worm":
            assert self.lead_angle_deg is not None
            return self.module_mm * self.teeth / math.tan(math.radians(self.lead_angle_deg))
        return self.module_mm * self.teeth


@dataclass(frozen=True, kw_only=True)
class ChangeGearSlot:
    """A place for a change gear: its teeth come from the chosen gears, its module from the set.

    ``fi_um`` and ``fpr_um`` pin the errors of whatever gear sits in the slot (seed 000 gives its
    errors per slot); when absent they come from the set's tolerance brackets by pitch diameter.
    """

    name: str
    shaft: str
    fi_um: float | None = None
    fpr_um: float | None = None
    note: str = ""

    def __post_init__(self) -> None:
        where = f"slots.{name_ok(self.name, 'slots')}"
        name_ok(self.shaft, f"{where}.shaft")
        for key in ("fi_um", "fpr_um"):
            value = optional_number(f"{where}.{key}", getattr(self, key), ge=0.0)
            object.__setattr__(self, key, value)
        if (self.fi_um is None) != (self.fpr_um is None):
            raise DesignError(
                f"{where}.fpr_um" if self.fpr_um is None else f"{where}.fi_um",
                rule="give both fi_um and fpr_um for a slot, or neither (then the set's "
                "tolerance brackets apply)",
            )


@dataclass(frozen=True, kw_only=True)
class Mesh:
    """A gear pair of a chain: ``driver`` turns ``driven`` (element or slot names)."""

    driver: str
    driven: str


@dataclass(frozen=True, kw_only=True)
class Chain:
    """A kinematic chain: from the input shaft through ``meshes`` to the work spindle.

    Parameters
    ----------
    name
        ``"indexing"``, ``"envelope"``, ...
    input_shaft
        The shaft whose rotation per cycle is ``input_angle_deg`` (the clutch pinion, the cradle).
    meshes
        In the order the power flows; each mesh's driver sits on the shaft of the previous mesh's
        driven gear (on ``input_shaft`` for the first).
    extra_elements
        Elements that count on their shaft though they are in no mesh of the chain (the rack of
        the indexing clutch and the pinion it drives); they come after the shaft's driven gear and
        before its driver.
    input_angle_deg
        Rotation of the input shaft per cycle (720 deg for one clutch stroke); None if it must be
        given at evaluation (the cradle swing).
    change_gear_slots
        The chain's quadrant ``(a, b, c, d)`` whose ratio ``a c / (b d)`` must equal
        ``change_gear_constant / (work or crown teeth)`` (``change_gear_divisor``).
    """

    name: str
    input_shaft: str
    meshes: tuple[Mesh, ...]
    extra_elements: tuple[str, ...] = ()
    input_angle_deg: float | None = None
    change_gear_slots: tuple[str, str, str, str] | None = None
    change_gear_constant: float | None = None
    change_gear_divisor: str | None = None
    description: str = ""

    def __post_init__(self) -> None:
        where = f"chains.{name_ok(self.name, 'chains')}"
        set_ = object.__setattr__
        name_ok(self.input_shaft, f"{where}.input_shaft")
        if not self.meshes:
            raise DesignError(f"{where}.meshes", [], "a chain needs at least one mesh")
        meshes = []
        for i, mesh in enumerate(self.meshes):
            if isinstance(mesh, Mesh):
                meshes.append(mesh)
                continue
            if (
                not isinstance(mesh, list | tuple)
                or len(mesh) != 2
                or not all(isinstance(m, str) for m in mesh)
            ):
                raise DesignError(
                    f"{where}.meshes[{i}]", mesh, 'must be a pair ["driver", "driven"] of names'
                )
            meshes.append(Mesh(driver=mesh[0], driven=mesh[1]))
        set_(self, "meshes", tuple(meshes))
        extras = self.extra_elements
        if not isinstance(extras, list | tuple) or not all(isinstance(e, str) for e in extras):
            raise DesignError(f"{where}.extra_elements", extras, "must be a list of element names")
        set_(self, "extra_elements", tuple(extras))
        if self.input_angle_deg is not None:
            set_(
                self,
                "input_angle_deg",
                check_number(f"{where}.input_angle_deg", self.input_angle_deg, gt=0.0),
            )
        slots = self.change_gear_slots
        if slots is not None:
            if (
                not isinstance(slots, list | tuple)
                or len(slots) != 4
                or len(set(slots)) != 4
                or not all(isinstance(s, str) for s in slots)
            ):
                raise DesignError(
                    f"{where}.change_gear_slots",
                    slots,
                    "must name four different slots [a, b, c, d] (ratio a c / (b d))",
                )
            set_(self, "change_gear_slots", tuple(slots))
            constant = check_number(
                f"{where}.change_gear_constant", self.change_gear_constant, gt=0.0
            )
            set_(self, "change_gear_constant", constant)
            if self.change_gear_divisor not in DIVISORS:
                raise DesignError(
                    f"{where}.change_gear_divisor",
                    self.change_gear_divisor,
                    f"must be one of {list(DIVISORS)}: a c / (b d) = constant / divisor",
                )


@dataclass(frozen=True, kw_only=True)
class ToleranceBracket:
    """fi' and Fpr (um) of the change gears up to ``max_pitch_diameter_mm`` pitch diameter."""

    max_pitch_diameter_mm: float
    fi_um: float
    fpr_um: float


@dataclass(frozen=True, kw_only=True)
class ChangeGearSet:
    """The change gears a machine has, the quadrant's meshing rule and the gears' errors.

    Parameters
    ----------
    teeth
        The multiset of available gears (a tooth count listed twice is there twice).
    module_mm
        Module of every change gear.
    clearance_teeth
        Quadrant clearance: ``a + b >= c + clearance`` (gear c clears the shaft of a) and
        ``c + d >= b + clearance`` (gear b clears the shaft of d).
    shaft_distance_mm
        Distance between the quadrant's input and output shafts, if fixed: the stud must reach,
        ``|(a + b) - (c + d)| m / 2 <= distance <= (a + b + c + d) m / 2``. None: not checked.
    tolerances
        Brackets by pitch diameter, increasing, covering the largest gear of the set.
    """

    teeth: tuple[int, ...]
    module_mm: float
    clearance_teeth: int = 15
    shaft_distance_mm: float | None = None
    tolerances: tuple[ToleranceBracket, ...] = ()

    def __post_init__(self) -> None:
        where = "change_gears"
        set_ = object.__setattr__
        if not isinstance(self.teeth, list | tuple) or len(self.teeth) < 4:
            raise DesignError(
                f"{where}.teeth", self.teeth, "must list at least four gears (a quadrant)"
            )
        teeth = tuple(
            sorted(
                check_integer(f"{where}.teeth[{i}]", t, ge=5, le=MAX_TEETH)
                for i, t in enumerate(self.teeth)
            )
        )
        set_(self, "teeth", teeth)
        set_(self, "module_mm", check_number(f"{where}.module_mm", self.module_mm, gt=0.0))
        set_(
            self,
            "clearance_teeth",
            check_integer(f"{where}.clearance_teeth", self.clearance_teeth, ge=0, le=MAX_TEETH),
        )
        set_(
            self,
            "shaft_distance_mm",
            optional_number(f"{where}.shaft_distance_mm", self.shaft_distance_mm, gt=0.0),
        )
        brackets = []
        for i, row in enumerate(self.tolerances):
            name = f"{where}.tolerances[{i}]"
            if isinstance(row, ToleranceBracket):
                row = (row.max_pitch_diameter_mm, row.fi_um, row.fpr_um)
            if not isinstance(row, list | tuple) or len(row) != 3:
                raise DesignError(
                    name, row, "must be [max_pitch_diameter_mm, fi_um, fpr_um] (three numbers)"
                )
            d = check_number(f"{name}[0]", row[0], gt=0.0, unit="mm")
            if brackets and d <= brackets[-1].max_pitch_diameter_mm:
                raise DesignError(
                    f"{name}[0]", d, "bracket diameters must increase from row to row"
                )
            brackets.append(
                ToleranceBracket(
                    max_pitch_diameter_mm=d,
                    fi_um=check_number(f"{name}[1]", row[1], ge=0.0, unit="um"),
                    fpr_um=check_number(f"{name}[2]", row[2], ge=0.0, unit="um"),
                )
            )
        if not brackets:
            raise DesignError(
                f"{where}.tolerances", rule="give [max_pitch_diameter_mm, fi_um, fpr_um] rows"
            )
        set_(self, "tolerances", tuple(brackets))
        largest = teeth[-1] * self.module_mm
        if largest > brackets[-1].max_pitch_diameter_mm:
            raise DesignError(
                f"{where}.tolerances",
                [[b.max_pitch_diameter_mm, b.fi_um, b.fpr_um] for b in brackets],
                f"must cover the largest change gear, pitch diameter {largest:g} mm",
            )

    @cached_property
    def counts(self) -> dict[int, int]:
        """How many gears of each tooth count the set holds."""
        values, counts = np.unique(self.teeth, return_counts=True)
        return {int(v): int(c) for v, c in zip(values, counts, strict=True)}

    def tolerance_um(self, teeth: Any) -> tuple[np.ndarray, np.ndarray]:
        """fi' and Fpr (um) of change gears with ``teeth`` (array-like), from the brackets."""
        diameter = np.asarray(teeth, dtype=float) * self.module_mm
        limits = np.array([b.max_pitch_diameter_mm for b in self.tolerances])
        index = np.searchsorted(limits, diameter, side="left")
        if np.any(index >= len(limits)):
            raise DesignError(
                "change_gears.tolerances",
                float(np.max(diameter)),
                "no tolerance bracket covers this pitch diameter (mm)",
            )
        fi = np.array([b.fi_um for b in self.tolerances])[index]
        fpr = np.array([b.fpr_um for b in self.tolerances])[index]
        return fi, fpr
