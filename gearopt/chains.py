"""Kinematic chains of a generating machine: their errors and the choice of change gears.

A machine's indexing and envelope (generating) chains are gear trains: shafts joined by meshes
(gear pairs, worm drives), driven at one end (the rack of the indexing clutch, the cradle) and
ending at the work spindle, with change gears in quadrant slots (``a b c d``: ratio
``a c / (b d)``, ``a`` meshing ``b``, ``b`` and ``c`` on one stud, ``c`` meshing ``d``). This
module holds the machine-independent data model (frozen dataclasses, validated on
construction), the loader of machine files (TOML, see ``plugins/data/zftkk250x5.toml``), the
chain-error method of seed 000 and the change-gear selection.

The method (seed 000, Step 3 and Tables 3, 4, 7, 8; the paper states it through its tables)
---------------------------------------------------------------------------------------------
For one cycle of the chain (one stroke of the indexing clutch, one swing of the cradle) the
input shaft turns ``input_angle_deg`` and every element turns ``n`` revolutions. Then, per
element with ``z`` teeth (starts for a worm), kinematic error ``fi'`` and cumulative pitch error
``Fpr`` (um) and pitch diameter ``D`` (mm):

* odd teeth ``zk = frac(n) z``; ``F = fi'`` if ``zk = 0`` else ``F = fi' + zk Fpr / z`` (um);
* angle error ``dphi = 2 F / D`` (rad; tabulated in degrees);
* along one shaft, in the direction the power flows, angle errors accumulate: the gear that
  is driven onto the shaft carries its own ``dphi``, each following element adds its own; at
  the next mesh the accumulation restarts;
* a mesh's extreme (speed) ratios are ``(driven max) / (driver min)`` and
  ``(driven min) / (driver max)`` with ``max, min = 360 n +/- accumulated dphi`` (degrees);
* the chain's extreme ratios are the products over its meshes; the theoretical ratio is the
  product of ``z_driver / z_driven`` with the chosen change gears; the ratio error is
  ``max - min`` (absolute and in % of the theoretical ratio);
* the work's angle error is ``ratio error x input_angle_deg`` and the pitch error at the
  normal section is that angle (rad) times ``m_n z / (2 cos beta)``
  (:func:`normal_pitch_error_um`).

Everything is in micrometres (errors), millimetres (diameters) and degrees at the interface.
"""

from __future__ import annotations

import math
import os
import tomllib
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field, fields
from functools import cached_property
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np

from gearopt.errors import DesignError
from gearopt.validate import (
    check_integer,
    check_keys,
    check_number,
    read_table,
)

__all__ = [
    "ELEMENT_KINDS",
    "Shaft",
    "Element",
    "ChangeGearSlot",
    "Mesh",
    "Chain",
    "ToleranceBracket",
    "ChangeGearSet",
    "Machine",
    "WorkGear",
    "ElementRow",
    "MeshRow",
    "ChainResult",
    "ChangeGearChoice",
    "MACHINE_PATH_ENV",
    "machine_dirs",
    "machine_names",
    "load_machine",
    "loads_machine",
    "parse_machine",
    "chain_error",
    "chain_error_arrays",
    "normal_pitch_error_um",
    "required_ratio",
    "quadrant_ok",
    "check_quadrant",
    "select_change_gears",
    "choose_change_gears",
    "Quadrant",
    "MachineResult",
    "evaluate_machine",
]

ELEMENT_KINDS = ("spur", "bevel", "worm", "worm_wheel", "rack")
DIVISORS = ("work_teeth", "crown_teeth")
MACHINE_PATH_ENV = "GEAROPT_MACHINE_PATH"
# a revolution count within this (relative) distance of an integer is a whole number of turns
_WHOLE_TURN_TOLERANCE = 1e-9
_MAX_TEETH = 1000


def _name_ok(name: Any, where: str) -> str:
    if not isinstance(name, str) or not name or not name.replace("_", "").isalnum():
        raise DesignError(where, name, "must be a non-empty name of letters, digits and '_'")
    return name


def _optional_number(name: str, value: Any, **bounds: float) -> float | None:
    return None if value is None else check_number(name, value, **bounds)


# --- data model ----------------------------------------------------------------------------------


@dataclass(frozen=True, kw_only=True)
class Shaft:
    """A shaft of the machine (``[shafts]`` of a machine file: ``name = "description"``)."""

    name: str
    description: str = ""

    def __post_init__(self) -> None:
        _name_ok(self.name, "shafts")
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
        where = f"elements.{_name_ok(self.name, 'elements')}"
        set_ = object.__setattr__
        _name_ok(self.shaft, f"{where}.shaft")
        if self.kind not in ELEMENT_KINDS:
            raise DesignError(f"{where}.kind", self.kind, f"must be one of {list(ELEMENT_KINDS)}")
        check_integer(f"{where}.teeth", self.teeth, ge=1, le=_MAX_TEETH)
        set_(self, "module_mm", _optional_number(f"{where}.module_mm", self.module_mm, gt=0.0))
        set_(
            self,
            "pitch_diameter_mm",
            _optional_number(f"{where}.pitch_diameter_mm", self.pitch_diameter_mm, gt=0.0),
        )
        set_(
            self,
            "lead_angle_deg",
            _optional_number(f"{where}.lead_angle_deg", self.lead_angle_deg, gt=0.0, lt=90.0),
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
        where = f"slots.{_name_ok(self.name, 'slots')}"
        _name_ok(self.shaft, f"{where}.shaft")
        for key in ("fi_um", "fpr_um"):
            value = _optional_number(f"{where}.{key}", getattr(self, key), ge=0.0)
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
        where = f"chains.{_name_ok(self.name, 'chains')}"
        set_ = object.__setattr__
        _name_ok(self.input_shaft, f"{where}.input_shaft")
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
                check_integer(f"{where}.teeth[{i}]", t, ge=5, le=_MAX_TEETH)
                for i, t in enumerate(self.teeth)
            )
        )
        set_(self, "teeth", teeth)
        set_(self, "module_mm", check_number(f"{where}.module_mm", self.module_mm, gt=0.0))
        set_(
            self,
            "clearance_teeth",
            check_integer(f"{where}.clearance_teeth", self.clearance_teeth, ge=0, le=_MAX_TEETH),
        )
        set_(
            self,
            "shaft_distance_mm",
            _optional_number(f"{where}.shaft_distance_mm", self.shaft_distance_mm, gt=0.0),
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


@dataclass(frozen=True, kw_only=True)
class Machine:
    """A machine's kinematic chains, change-gear slots and change-gear set (a machine file)."""

    name: str
    shafts: tuple[Shaft, ...]
    elements: tuple[Element, ...]
    slots: tuple[ChangeGearSlot, ...]
    chains: tuple[Chain, ...]
    change_gears: ChangeGearSet
    description: str = ""
    source: str = ""
    notes: tuple[str, ...] = ()
    path: str | None = field(default=None, compare=False)

    def __post_init__(self) -> None:
        _name_ok(self.name, "machine.name")
        shafts = {s.name for s in self.shafts}
        if len(shafts) != len(self.shafts):
            raise DesignError("shafts", [s.name for s in self.shafts], "names must be unique")
        names: dict[str, str] = {}
        for kind, items in (("elements", self.elements), ("slots", self.slots)):
            for item in items:
                if item.name in names:
                    raise DesignError(
                        f"{kind}.{item.name}",
                        rule=f"name already used in [{names[item.name]}]: "
                        "elements and slots need unique names",
                    )
                names[item.name] = kind
                if item.shaft not in shafts:
                    raise DesignError(
                        f"{kind}.{item.name}.shaft",
                        item.shaft,
                        f"unknown shaft; the machine's shafts are {sorted(shafts)}",
                    )
        chain_names = [c.name for c in self.chains]
        if len(set(chain_names)) != len(chain_names) or not chain_names:
            raise DesignError("chains", chain_names, "need at least one chain, names unique")
        for chain in self.chains:
            self._check_chain(chain)

    @cached_property
    def parts(self) -> dict[str, Element | ChangeGearSlot]:
        """Elements and slots by name."""
        return {p.name: p for p in (*self.elements, *self.slots)}

    def chain(self, name: str) -> Chain:
        """The chain called ``name``; a :class:`DesignError` lists the known ones."""
        for chain in self.chains:
            if chain.name == name:
                return chain
        raise DesignError(
            "chain", name, f"unknown chain of machine {self.name!r}; it has {self.chain_names}"
        )

    @property
    def chain_names(self) -> list[str]:
        """Names of the machine's chains."""
        return [c.name for c in self.chains]

    def _check_chain(self, chain: Chain) -> None:
        where = f"chains.{chain.name}"
        parts = self.parts
        if chain.input_shaft not in {s.name for s in self.shafts}:
            raise DesignError(
                f"{where}.input_shaft",
                chain.input_shaft,
                f"unknown shaft; the machine's shafts are {sorted(s.name for s in self.shafts)}",
            )
        shaft = chain.input_shaft
        visited = [shaft]
        for i, mesh in enumerate(chain.meshes):
            for role in ("driver", "driven"):
                name = getattr(mesh, role)
                if name not in parts:
                    raise DesignError(
                        f"{where}.meshes[{i}].{role}",
                        name,
                        "no such element or change-gear slot (unknown slot or element name)",
                    )
                part = parts[name]
                if isinstance(part, Element) and part.kind == "rack":
                    raise DesignError(
                        f"{where}.meshes[{i}].{role}",
                        name,
                        "a rack drives its pinion's shaft: list it in extra_elements",
                    )
            driver, driven = parts[mesh.driver], parts[mesh.driven]
            if driver.shaft != shaft:
                raise DesignError(
                    f"{where}.meshes[{i}].driver",
                    mesh.driver,
                    f"sits on shaft {driver.shaft!r}, but the chain arrives on shaft {shaft!r} "
                    "(each mesh's driver must share a shaft with the previous mesh's driven gear)",
                )
            if driven.shaft == driver.shaft:
                raise DesignError(
                    f"{where}.meshes[{i}]",
                    [mesh.driver, mesh.driven],
                    f"driver and driven both sit on shaft {driver.shaft!r}: a mesh joins two "
                    "shafts",
                )
            if driven.shaft in visited:
                raise DesignError(
                    f"{where}.meshes[{i}].driven",
                    mesh.driven,
                    f"returns to shaft {driven.shaft!r}: a chain visits each shaft once",
                )
            shaft = driven.shaft
            visited.append(shaft)
        used = {m.driver for m in chain.meshes} | {m.driven for m in chain.meshes}
        for i, name in enumerate(chain.extra_elements):
            if name not in parts:
                raise DesignError(f"{where}.extra_elements[{i}]", name, "no such element")
            if name in used or chain.extra_elements.index(name) != i:
                raise DesignError(
                    f"{where}.extra_elements[{i}]", name, "is already counted in the chain"
                )
            if parts[name].shaft not in visited:
                raise DesignError(
                    f"{where}.extra_elements[{i}]",
                    name,
                    f"sits on shaft {parts[name].shaft!r}, which the chain does not pass",
                )
        if chain.change_gear_slots is not None:
            a, b, c, d = chain.change_gear_slots
            for name in chain.change_gear_slots:
                if not isinstance(parts.get(name), ChangeGearSlot):
                    raise DesignError(
                        f"{where}.change_gear_slots", name, "unknown slot (see [slots])"
                    )
            pairs = {frozenset((m.driver, m.driven)) for m in chain.meshes}
            for x, y in ((a, b), (c, d)):
                if frozenset((x, y)) not in pairs:
                    raise DesignError(
                        f"{where}.change_gear_slots",
                        list(chain.change_gear_slots),
                        f"slots {x!r} and {y!r} must mesh with each other in the chain",
                    )
            if parts[b].shaft != parts[c].shaft:
                raise DesignError(
                    f"{where}.change_gear_slots",
                    list(chain.change_gear_slots),
                    f"slots {b!r} and {c!r} must sit on one stud (shaft)",
                )

    def flow(self, chain: str) -> tuple[tuple[str, ...], ...]:
        """The chain's element and slot names per shaft, in the order the power flows."""
        spec = self.chain(chain)
        shafts = [spec.input_shaft] + [self.parts[m.driven].shaft for m in spec.meshes]
        groups: list[list[str]] = [[] for _ in shafts]
        for i, mesh in enumerate(spec.meshes):
            groups[i + 1].append(mesh.driven)
        for name in spec.extra_elements:
            groups[shafts.index(self.parts[name].shaft)].append(name)
        for i, mesh in enumerate(spec.meshes):
            if mesh.driver not in groups[i]:  # an idler is driven and driver at once
                groups[i].append(mesh.driver)
        return tuple(tuple(g) for g in groups)

    def slots_of(self, chain: str) -> tuple[str, ...]:
        """Change-gear slots the chain passes through (they need gears to evaluate it)."""
        names = [n for group in self.flow(chain) for n in group]
        return tuple(n for n in names if isinstance(self.parts[n], ChangeGearSlot))

    def quadrant_gears(self, chain: str, gears: Sequence[int]) -> dict[str, int]:
        """``{slot: teeth}`` of the chain's quadrant ``(a, b, c, d)``, checked by the set's rule."""
        spec = self.chain(chain)
        if spec.change_gear_slots is None:
            raise DesignError("chain", chain, "has no change-gear quadrant")
        label = f"{chain} change gears"
        quad = check_quadrant(self.change_gears, gears, where=label)
        return dict(zip(spec.change_gear_slots, quad, strict=True))


# --- machine files -------------------------------------------------------------------------------

_TOP_KEYS = ("machine", "change_gears", "shafts", "elements", "slots", "chains")
_MACHINE_KEYS = ("name", "description", "source", "notes")
_SET_KEYS = ("teeth", "module_mm", "clearance_teeth", "shaft_distance_mm", "tolerances")
_ELEMENT_KEYS = (
    "shaft",
    "kind",
    "teeth",
    "module_mm",
    "pitch_diameter_mm",
    "lead_angle_deg",
    "fi_um",
    "fpr_um",
    "note",
)
_SLOT_KEYS = ("shaft", "fi_um", "fpr_um", "note")
_CHAIN_KEYS = (
    "input_shaft",
    "meshes",
    "extra_elements",
    "input_angle_deg",
    "change_gear_slots",
    "change_gear_constant",
    "change_gear_divisor",
    "description",
)


def _required(table: Mapping[str, Any], keys: Iterable[str], where: str) -> None:
    for key in keys:
        if key not in table:
            raise DesignError(f"{where}.{key}", rule="required key is missing")


def parse_machine(data: Mapping[str, Any], *, path: str | None = None) -> Machine:
    """Build a :class:`Machine` from a parsed machine file (see ``plugins/data/*.toml``)."""
    check_keys(data, _TOP_KEYS, "")
    meta = read_table(data, "machine", "")
    check_keys(meta, _MACHINE_KEYS, "machine")
    _required(meta, ("name",), "machine")
    notes = meta.get("notes", [])
    if not isinstance(notes, list) or not all(isinstance(n, str) for n in notes):
        raise DesignError("machine.notes", notes, "must be a list of strings")
    for key in ("description", "source"):
        if not isinstance(meta.get(key, ""), str):
            raise DesignError(f"machine.{key}", meta[key], "must be a string")
    gear_set = read_table(data, "change_gears", "")
    check_keys(gear_set, _SET_KEYS, "change_gears")
    _required(gear_set, ("teeth", "module_mm", "tolerances"), "change_gears")
    shafts_table = read_table(data, "shafts", "")
    shafts = tuple(Shaft(name=k, description=v) for k, v in shafts_table.items())
    elements = []
    for name, table in read_table(data, "elements", "").items():
        where = f"elements.{name}"
        if not isinstance(table, Mapping):
            raise DesignError(where, table, "must be a table ([elements.NAME])")
        check_keys(table, _ELEMENT_KEYS, where)
        _required(table, ("shaft", "teeth", "fi_um", "fpr_um"), where)
        elements.append(Element(name=name, **table))
    slots = []
    for name, table in read_table(data, "slots", "").items():
        where = f"slots.{name}"
        if not isinstance(table, Mapping):
            raise DesignError(where, table, "must be a table ([slots.NAME])")
        check_keys(table, _SLOT_KEYS, where)
        _required(table, ("shaft",), where)
        slots.append(ChangeGearSlot(name=name, **table))
    chains = []
    for name, table in read_table(data, "chains", "").items():
        where = f"chains.{name}"
        if not isinstance(table, Mapping):
            raise DesignError(where, table, "must be a table ([chains.NAME])")
        check_keys(table, _CHAIN_KEYS, where)
        _required(table, ("input_shaft", "meshes"), where)
        if not isinstance(table["meshes"], list):
            raise DesignError(f"{where}.meshes", table["meshes"], "must be a list of pairs")
        chains.append(Chain(name=name, **{**table, "meshes": tuple(table["meshes"])}))
    return Machine(
        name=meta["name"],
        description=meta.get("description", ""),
        source=meta.get("source", ""),
        notes=tuple(notes),
        change_gears=ChangeGearSet(**gear_set),
        shafts=shafts,
        elements=tuple(elements),
        slots=tuple(slots),
        chains=tuple(chains),
        path=path,
    )


def loads_machine(text: str, *, path: str | None = None) -> Machine:
    """Parse a machine file's text."""
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise DesignError(path or "machine file", rule=f"is not valid TOML: {exc}") from None
    return parse_machine(data, path=path)


def machine_dirs() -> list[Path]:
    """Where machine files are looked up by name, in order.

    The directories of the environment variable ``GEAROPT_MACHINE_PATH`` (``os.pathsep``
    separated), then the data folder of the built-in plugins (``gearopt_plugins/data``).
    """
    dirs = [Path(p) for p in os.environ.get(MACHINE_PATH_ENV, "").split(os.pathsep) if p]
    try:
        builtin = resources.files("gearopt_plugins") / "data"
    except ModuleNotFoundError:  # gearopt without its built-in plugins
        return dirs
    return [*dirs, Path(str(builtin))]


def machine_names() -> list[str]:
    """Names of the machine files found in :func:`machine_dirs`."""
    names = set()
    for folder in machine_dirs():
        if folder.is_dir():
            names.update(p.stem for p in folder.glob("*.toml"))
    return sorted(names)


def load_machine(name_or_path: str | os.PathLike[str]) -> Machine:
    """Load a machine file by name (``"zftkk250x5"``, see :func:`machine_dirs`) or by path."""
    text = str(name_or_path)
    path = Path(text)
    if path.suffix == ".toml" or os.sep in text or "/" in text:
        if not path.is_file():
            raise DesignError("machine", text, "no such machine file")
        return loads_machine(path.read_text(), path=str(path))
    for folder in machine_dirs():
        candidate = folder / f"{text.lower()}.toml"
        if candidate.is_file():
            return loads_machine(candidate.read_text(), path=str(candidate))
    raise DesignError(
        "machine", text, f"unknown machine; known: {machine_names()} (or give a .toml path)"
    )


# --- change gears --------------------------------------------------------------------------------


def quadrant_ok(gear_set: ChangeGearSet, a: Any, b: Any, c: Any, d: Any) -> np.ndarray:
    """Whether quadrants ``a/b x c/d`` (integer arrays) mesh by the set's rule (not the counts)."""
    a, b, c, d = (np.asarray(x, dtype=np.int64) for x in (a, b, c, d))
    clearance = gear_set.clearance_teeth
    ok = (a + b >= c + clearance) & (c + d >= b + clearance)
    if gear_set.shaft_distance_mm is not None:
        half = 0.5 * gear_set.module_mm
        first, second = (a + b) * half, (c + d) * half
        distance = gear_set.shaft_distance_mm
        ok &= (np.abs(first - second) <= distance) & (first + second >= distance)
    return ok


def _available(gear_set: ChangeGearSet, reserved: Iterable[int], where: str) -> np.ndarray:
    avail = np.zeros(_MAX_TEETH + 1, dtype=np.int64)
    for teeth, count in gear_set.counts.items():
        avail[teeth] = count
    for teeth in reserved:
        teeth = check_integer(f"{where} reserved gear", teeth, ge=1, le=_MAX_TEETH)
        if avail[teeth] <= 0:
            raise DesignError(
                f"{where} reserved gear", teeth, "is not in the change-gear set (or used up)"
            )
        avail[teeth] -= 1
    return avail


def _counts_ok(avail: np.ndarray, a: Any, b: Any, c: Any, d: Any) -> np.ndarray:
    """Quadrants that use no tooth count more often than ``avail`` (per count) allows."""
    ab, ac, ad, bc, bd, cd = a == b, a == c, a == d, b == c, b == d, c == d
    return (
        (1 + ab + ac + ad <= avail[a])
        & (1 + ab + bc + bd <= avail[b])
        & (1 + ac + bc + cd <= avail[c])
        & (1 + ad + bd + cd <= avail[d])
    )


def check_quadrant(
    gear_set: ChangeGearSet,
    gears: Sequence[int],
    *,
    where: str = "change gears",
    reserved: Iterable[int] = (),
) -> tuple[int, int, int, int]:
    """Check that ``(a, b, c, d)`` comes from the set and meshes by its rule; return it."""
    if not isinstance(gears, list | tuple) or len(gears) != 4:
        raise DesignError(where, gears, "must be four tooth counts a, b, c, d (a/b x c/d)")
    quad = tuple(
        check_integer(f"{where}[{i}]", g, ge=1, le=_MAX_TEETH) for i, g in enumerate(gears)
    )
    avail = _available(gear_set, reserved, where)
    for teeth in set(quad):
        if quad.count(teeth) > avail[teeth]:
            have = int(avail[teeth])
            raise DesignError(
                where,
                list(quad),
                f"uses {quad.count(teeth)} gear(s) of {teeth} teeth; the set has {have}",
            )
    a, b, c, d = quad
    if not bool(quadrant_ok(gear_set, a, b, c, d)):
        rule = (
            f"cannot mesh in the quadrant: needs a + b >= c + {gear_set.clearance_teeth} and "
            f"c + d >= b + {gear_set.clearance_teeth} (teeth)"
        )
        if gear_set.shaft_distance_mm is not None:
            rule += (
                f" and |(a + b) - (c + d)| m / 2 <= {gear_set.shaft_distance_mm:g} mm <= "
                "(a + b + c + d) m / 2"
            )
        raise DesignError(where, list(quad), rule)
    return quad  # type: ignore[return-value]


@dataclass(frozen=True, kw_only=True)
class ChangeGearChoice:
    """A quadrant ``a/b x c/d`` for a required ratio: ``error = ratio - required_ratio``."""

    gears: tuple[int, int, int, int]
    ratio: float
    required_ratio: float
    error: float
    error_percent: float

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready dictionary."""
        return {
            "gears": list(self.gears),
            "ratio": self.ratio,
            "required_ratio": self.required_ratio,
            "error": self.error,
            "error_percent": self.error_percent,
        }


_CHUNK = 1 << 20  # candidates per block of the exact enumeration (bounds memory)
_WINDOWS = (1, 4, 16, 64)  # ratio-sorted neighbours on each side of every (a, b), first pass


def select_change_gears(
    ratio: float,
    gear_set: ChangeGearSet,
    *,
    top_k: int = 5,
    reserved: Iterable[int] = (),
) -> tuple[ChangeGearChoice, ...]:
    """The ``top_k`` quadrants ``a/b x c/d`` of the set nearest to ``ratio``, best first.

    Exact over the whole multiset (every ordered choice of four gears that the set holds and
    whose quadrant meshes by the set's rule), ranked by ``|a c / (b d) - ratio|``, ties by
    ``(a, b, c, d)``. Vectorised in two passes: all ordered pairs ``(a, b)`` and ``(c, d)``, the
    latter sorted by ratio; a first pass over a few ratio-neighbours per ``(a, b)`` bounds the
    k-th best error, a second enumerates every ``(c, d)`` within that bound (binary search) and
    keeps the best. ``reserved`` gears are taken out of the set first.

    Raises
    ------
    DesignError
        A ratio that is not a positive finite number, or a set with no quadrant that meshes.
    """
    ratio = check_number("ratio", ratio, gt=0.0)
    top_k = check_integer("top_k", top_k, ge=1, le=10_000)
    avail = _available(gear_set, reserved, "change gears")
    values = np.flatnonzero(avail)
    # every ordered pair the set holds: (x, y) with x != y, or x == y when there are two
    i, j = np.meshgrid(np.arange(values.size), np.arange(values.size), indexing="ij")
    keep = (i != j) | (avail[values][i] >= 2)
    first = values[i[keep]], values[j[keep]]
    pair_ratio = first[0] / first[1]
    order = np.argsort(pair_ratio, kind="stable")
    c_all, d_all, cd_ratio = first[0][order], first[1][order], pair_ratio[order]
    a_all, b_all, ab_ratio = first[0], first[1], pair_ratio
    target = ratio / ab_ratio

    def evaluate(ab: np.ndarray, cd: np.ndarray) -> tuple[np.ndarray, ...]:
        """The feasible quadrants among the candidates: a, b, c, d, ratio, |error|."""
        a, b, c, d = a_all[ab], b_all[ab], c_all[cd], d_all[cd]
        ok = quadrant_ok(gear_set, a, b, c, d) & _counts_ok(avail, a, b, c, d)
        a, b, c, d = a[ok], b[ok], c[ok], d[ok]
        value = (a * c) / (b * d)  # exact integer products: equal ratios are equal floats
        return a, b, c, d, value, np.abs(value - ratio)

    # pass 1: any k feasible quadrants bound the k-th best error; look for them among a few
    # ratio-neighbours of every (a, b) (more if too few mesh), the most accurate first
    pos = np.searchsorted(cd_ratio, target)
    bound = np.inf
    for window in _WINDOWS:
        cd = pos[:, None] + np.arange(-window, window)
        inside = (cd >= 0) & (cd < cd_ratio.size)
        ab = np.broadcast_to(np.arange(target.size)[:, None], cd.shape)[inside]
        cd = cd[inside]
        errors = np.abs(ab_ratio[ab] * cd_ratio[cd] - ratio)  # ranking only
        size = 64 * top_k
        near = np.argpartition(errors, size)[:size] if size < errors.size else slice(None)
        feasible = evaluate(ab[near], cd[near])[-1]
        if feasible.size < top_k and size < errors.size:
            feasible = evaluate(ab, cd)[-1]
        if feasible.size >= top_k:
            bound = np.partition(feasible, top_k - 1)[top_k - 1]
            break

    # pass 2: every (c, d) within the bound, in blocks
    if np.isfinite(bound):
        # widened by 1e-12 relative: pair ratios are rounded, the quadrants' errors are not
        low, high = (ratio - bound) / ab_ratio, (ratio + bound) / ab_ratio
        lo = np.searchsorted(cd_ratio, low * (1.0 - 1e-12), side="left")
        hi = np.searchsorted(cd_ratio, high * (1.0 + 1e-12), side="right")
    else:
        lo = np.zeros(target.size, dtype=np.int64)
        hi = np.full(target.size, cd_ratio.size, dtype=np.int64)
    counts = hi - lo
    best = (np.empty((0, 4), dtype=np.int64), np.empty(0), np.empty(0))
    start = 0
    cumulative = np.cumsum(counts)
    while start < target.size:
        base = cumulative[start - 1] if start else 0
        stop = max(int(np.searchsorted(cumulative, base + _CHUNK, side="right")), start + 1)
        rows = np.arange(start, stop)
        n = counts[rows]
        ab = np.repeat(rows, n)
        within = np.arange(ab.size) - np.repeat(np.cumsum(n) - n, n)
        cd = lo[ab] + within
        a, b, c, d, value, error = evaluate(ab, cd)
        quads = np.concatenate([best[0], np.stack([a, b, c, d], axis=1)])
        value = np.concatenate([best[1], value])
        error = np.concatenate([best[2], error])
        pick = np.lexsort((quads[:, 3], quads[:, 2], quads[:, 1], quads[:, 0], error))[:top_k]
        best = (quads[pick], value[pick], error[pick])
        start = stop
    if best[0].shape[0] == 0:
        raise DesignError(
            "change_gears.teeth",
            list(gear_set.teeth),
            f"no quadrant a/b x c/d of the set meshes (a + b >= c + {gear_set.clearance_teeth}, "
            f"c + d >= b + {gear_set.clearance_teeth}"
            + (", and the shaft distance" if gear_set.shaft_distance_mm is not None else "")
            + ")",
        )
    return tuple(
        ChangeGearChoice(
            gears=tuple(int(g) for g in quad),  # type: ignore[arg-type]
            ratio=float(value),
            required_ratio=ratio,
            error=float(value - ratio),
            error_percent=float(100.0 * (value - ratio) / ratio),
        )
        for quad, value in zip(best[0], best[1], strict=True)
    )


def required_ratio(
    machine: Machine,
    chain: str,
    *,
    work_teeth: int | None = None,
    crown_teeth: float | None = None,
) -> float:
    """The ratio ``a c / (b d)`` the chain's quadrant must give: constant / work or crown teeth."""
    spec = machine.chain(chain)
    if spec.change_gear_slots is None:
        raise DesignError("chain", chain, "has no change-gear quadrant")
    assert spec.change_gear_constant is not None
    if spec.change_gear_divisor == "work_teeth":
        if work_teeth is None:
            raise DesignError("work_teeth", rule=f"the {chain} ratio is constant / work teeth")
        divisor = float(check_integer("work_teeth", work_teeth, ge=1, le=_MAX_TEETH))
    else:
        if crown_teeth is None:
            raise DesignError("crown_teeth", rule=f"the {chain} ratio is constant / crown teeth")
        divisor = check_number("crown_teeth", crown_teeth, gt=0.0)
    return spec.change_gear_constant / divisor


# --- the chain-error method ----------------------------------------------------------------------


@dataclass(frozen=True, kw_only=True)
class WorkGear:
    """The gear being cut: what turns the work's angle error into a pitch error."""

    teeth: int
    normal_module_mm: float
    spiral_angle_deg: float

    def __post_init__(self) -> None:
        check_integer("work_teeth", self.teeth, ge=1, le=_MAX_TEETH)
        object.__setattr__(
            self, "normal_module_mm", check_number("normal_module_mm", self.normal_module_mm, gt=0)
        )
        object.__setattr__(
            self,
            "spiral_angle_deg",
            check_number("spiral_angle_deg", self.spiral_angle_deg, ge=0.0, lt=90.0),
        )


def normal_pitch_error_um(angle_error_deg: Any, work: WorkGear) -> Any:
    """Pitch error at the normal section: angle error (rad) x m_n z / (2 cos beta), um.

    Seed 000 section 3.1: 0.0369052 deg on z = 15, m_n = 3.5 mm, beta = 35 deg gives 20.64 um.
    """
    radius_mm = (
        work.normal_module_mm * work.teeth / (2.0 * math.cos(math.radians(work.spiral_angle_deg)))
    )
    return np.radians(angle_error_deg) * radius_mm * 1e3


def _resolve(
    machine: Machine, names: Iterable[str], gears: Mapping[str, Any], chain: str
) -> dict[str, tuple[Any, Any, Any, Any]]:
    """``name -> (teeth, D_mm, fi_um, fpr_um)``; slots take their teeth from ``gears``."""
    out = {}
    gear_set = machine.change_gears
    for name in names:
        part = machine.parts[name]
        if isinstance(part, Element):
            out[name] = (part.teeth, part.diameter_mm, part.fi_um, part.fpr_um)
            continue
        if name not in gears:
            raise DesignError(
                f"gears.{name}", rule=f"the {chain} chain passes slot {name!r}: give its gear"
            )
        teeth = np.asarray(gears[name])
        if teeth.dtype.kind not in "iu" or np.any(teeth < 1):
            raise DesignError(f"gears.{name}", gears[name], "must be a positive integer (teeth)")
        if part.fi_um is not None:
            fi, fpr = part.fi_um, part.fpr_um
        else:
            fi, fpr = gear_set.tolerance_um(teeth)
        out[name] = (teeth, teeth * gear_set.module_mm, fi, fpr)
    return out


def chain_error_arrays(
    machine: Machine,
    chain: str,
    gears: Mapping[str, Any],
    *,
    input_angle_deg: float | None = None,
) -> dict[str, Any]:
    """The chain-error method (module docstring), vectorised over change-gear candidates.

    ``gears`` maps slot names to teeth (integers, or integer arrays of one shape: one candidate
    per entry). Returns arrays of that shape: ``theoretical_ratio``, ``max_ratio``,
    ``min_ratio``, and per element (``elements``: name -> dict) and per mesh (``meshes``: list
    of dicts) the columns of seed 000 Tables 3/4 and 7/8.
    """
    spec = machine.chain(chain)
    unknown = sorted(set(gears) - {s.name for s in machine.slots})
    if unknown:
        raise DesignError(
            "gears",
            unknown,
            f"unknown slot(s); machine {machine.name!r} has slots "
            f"{[s.name for s in machine.slots]}",
        )
    angle = input_angle_deg if input_angle_deg is not None else spec.input_angle_deg
    if angle is None:
        raise DesignError(
            f"chains.{chain}.input_angle_deg", rule="give the input shaft's rotation per cycle"
        )
    angle = check_number(f"{chain} input_angle_deg", angle, gt=0.0)
    flow = machine.flow(chain)
    data = _resolve(machine, [n for group in flow for n in group], gears, chain)
    revolutions: Any = angle / 360.0
    elements: dict[str, dict[str, Any]] = {}
    own_first, accumulated_last, shaft_rev = [], [], []
    for index, group in enumerate(flow):
        if index:
            driver, driven = spec.meshes[index - 1].driver, spec.meshes[index - 1].driven
            revolutions = revolutions * data[driver][0] / data[driven][0]
        n = np.asarray(revolutions, dtype=float)
        whole = np.abs(n - np.rint(n)) <= _WHOLE_TURN_TOLERANCE * np.maximum(1.0, np.abs(n))
        fraction = np.where(whole, 0.0, n - np.floor(n))
        total: Any = 0.0
        for position, name in enumerate(group):
            teeth, diameter, fi, fpr = data[name]
            error = fi + fraction * fpr  # = fi' + zk Fpr / z with zk = frac(n) z
            dphi = np.degrees(2.0 * error * 1e-3 / diameter)
            total = total + dphi
            elements[name] = {
                "shaft": machine.parts[name].shaft,
                "teeth": teeth,
                "pitch_diameter_mm": diameter,
                "revolutions": n,
                "odd_teeth": fraction * teeth,
                "fi_um": fi,
                "fpr_um": fpr,
                "fp_um": fpr / teeth,
                "error_um": error,
                "angle_error_deg": dphi,
                "accumulated_angle_error_deg": total,
                "rotation_deg": 360.0 * n,
                "max_rotation_deg": 360.0 * n + total,
                "min_rotation_deg": 360.0 * n - total,
            }
            if position == 0:
                own_first.append(total)
        accumulated_last.append(total)
        shaft_rev.append(n)
    meshes = []
    max_ratio: Any = 1.0
    min_ratio: Any = 1.0
    theoretical: Any = 1.0
    for i, mesh in enumerate(spec.meshes):
        driver_deg, driven_deg = 360.0 * shaft_rev[i], 360.0 * shaft_rev[i + 1]
        a, b = accumulated_last[i], own_first[i + 1]
        if np.any(driver_deg <= a) or np.any(driven_deg <= b):
            raise DesignError(
                f"{chain} input_angle_deg",
                angle,
                f"too small: at mesh {mesh.driver}->{mesh.driven} the angle error exceeds the "
                "rotation (the method needs rotations much larger than their errors)",
            )
        mesh_max = (driven_deg + b) / (driver_deg - a)
        mesh_min = (driven_deg - b) / (driver_deg + a)
        mesh_theory = data[mesh.driver][0] / data[mesh.driven][0]
        meshes.append(
            {
                "driver": mesh.driver,
                "driven": mesh.driven,
                "theoretical_ratio": np.asarray(mesh_theory, dtype=float),
                "max_ratio": mesh_max,
                "min_ratio": mesh_min,
            }
        )
        max_ratio = max_ratio * mesh_max
        min_ratio = min_ratio * mesh_min
        theoretical = theoretical * mesh_theory
    theoretical = np.asarray(theoretical, dtype=float)
    return {
        "input_angle_deg": angle,
        "theoretical_ratio": theoretical,
        "max_ratio": max_ratio,
        "min_ratio": min_ratio,
        "ratio_error": max_ratio - min_ratio,
        "ratio_error_percent": 100.0 * (max_ratio - min_ratio) / theoretical,
        "angle_error_deg": (max_ratio - min_ratio) * angle,
        "elements": elements,
        "meshes": meshes,
    }


@dataclass(frozen=True, kw_only=True)
class ElementRow:
    """One row of the per-element table (seed 000 Tables 3 and 7)."""

    element: str
    shaft: str
    teeth: int
    pitch_diameter_mm: float
    revolutions: float
    odd_teeth: float
    fi_um: float
    fpr_um: float
    fp_um: float
    error_um: float
    angle_error_deg: float
    accumulated_angle_error_deg: float
    rotation_deg: float
    max_rotation_deg: float
    min_rotation_deg: float


@dataclass(frozen=True, kw_only=True)
class MeshRow:
    """One mesh's ratios (seed 000 Tables 4 and 8): speed of driven / speed of driver."""

    driver: str
    driven: str
    theoretical_ratio: float
    max_ratio: float
    min_ratio: float


@dataclass(frozen=True, kw_only=True)
class ChainResult:
    """The error of one chain for one cycle (seed 000 Tables 3-4, 7-8).

    ``ratio_error = max_ratio - min_ratio``; ``ratio_error_plus = max - theoretical`` and
    ``ratio_error_minus = min - theoretical``; ``angle_error_deg`` is the work's angle error per
    cycle (ratio error x input angle); ``pitch_error_um`` its pitch error at the normal section
    (None without a work gear).
    """

    machine: str
    chain: str
    gears: Mapping[str, int]
    input_angle_deg: float
    theoretical_ratio: float
    max_ratio: float
    min_ratio: float
    ratio_error: float
    ratio_error_plus: float
    ratio_error_minus: float
    ratio_error_percent: float
    angle_error_deg: float
    pitch_error_um: float | None
    elements: tuple[ElementRow, ...]
    meshes: tuple[MeshRow, ...]

    def table(self):
        """Per-element table (pandas DataFrame indexed by element), like Tables 3 and 7."""
        import pandas as pd

        rows = [vars(r) for r in self.elements]
        return pd.DataFrame(rows).set_index("element")

    def mesh_table(self):
        """Per-mesh ratios (pandas DataFrame), like Tables 4 and 8."""
        import pandas as pd

        return pd.DataFrame([vars(r) for r in self.meshes])

    def as_dict(self, *, elements: bool = True) -> dict[str, Any]:
        """JSON-ready dictionary (with the per-element and per-mesh rows unless told not to)."""
        out = {
            f.name: getattr(self, f.name)
            for f in fields(self)
            if f.name not in ("elements", "meshes")
        }
        out["gears"] = dict(self.gears)
        if elements:
            out["elements"] = [vars(r) for r in self.elements]
            out["meshes"] = [vars(r) for r in self.meshes]
        return out


def chain_error(
    machine: Machine,
    chain: str,
    *,
    gears: Mapping[str, int],
    input_angle_deg: float | None = None,
    work: WorkGear | None = None,
) -> ChainResult:
    """Error of one chain for one cycle with the given change gears (``{slot: teeth}``).

    Parameters
    ----------
    machine, chain
        The machine and the name of its chain (``"indexing"``, ``"envelope"``).
    gears
        Teeth of every slot the chain passes (:meth:`Machine.slots_of`); check quadrants first
        with :meth:`Machine.quadrant_gears`.
    input_angle_deg
        Rotation of the input shaft per cycle (the cradle swing); default the chain's own.
    work
        The gear being cut, for ``pitch_error_um``.
    """
    for name, teeth in gears.items():
        check_integer(f"gears.{name}", teeth, ge=1, le=_MAX_TEETH)
    out = chain_error_arrays(machine, chain, gears, input_angle_deg=input_angle_deg)
    rows = tuple(
        ElementRow(
            element=name,
            shaft=values["shaft"],
            teeth=int(values["teeth"]),
            **{k: float(v) for k, v in values.items() if k not in ("shaft", "teeth")},
        )
        for name, values in out["elements"].items()
    )
    meshes = tuple(
        MeshRow(**{k: v if isinstance(v, str) else float(v) for k, v in mesh.items()})
        for mesh in out["meshes"]
    )
    theory = float(out["theoretical_ratio"])
    angle_error = float(out["angle_error_deg"])
    used = set(machine.slots_of(chain))
    return ChainResult(
        machine=machine.name,
        chain=chain,
        gears={k: int(v) for k, v in gears.items() if k in used},
        input_angle_deg=float(out["input_angle_deg"]),
        theoretical_ratio=theory,
        max_ratio=float(out["max_ratio"]),
        min_ratio=float(out["min_ratio"]),
        ratio_error=float(out["ratio_error"]),
        ratio_error_plus=float(out["max_ratio"]) - theory,
        ratio_error_minus=float(out["min_ratio"]) - theory,
        ratio_error_percent=float(out["ratio_error_percent"]),
        angle_error_deg=angle_error,
        pitch_error_um=None if work is None else float(normal_pitch_error_um(angle_error, work)),
        elements=rows,
        meshes=meshes,
    )


def choose_change_gears(
    machine: Machine,
    chain: str,
    ratio: float,
    fixed: Mapping[str, int],
    *,
    candidates: int = 50,
    input_angle_deg: float | None = None,
) -> tuple[tuple[int, int, int, int], np.ndarray, np.ndarray]:
    """The chain's quadrant: the most accurate for ``ratio``, the least chain error among them.

    Takes the ``candidates`` quadrants nearest to ``ratio`` (:func:`select_change_gears`), keeps
    those as accurate as the best (equal ratios), evaluates the chain with each at once
    (:func:`chain_error_arrays`; ``fixed`` gives the teeth of the other slots the chain passes)
    and picks the smallest ratio error (ties: the lowest ``(a, b, c, d)``). Returns the chosen
    quadrant, the quadrants weighed (k, 4) and their chain ratio errors (k,).
    """
    spec = machine.chain(chain)
    if spec.change_gear_slots is None:
        raise DesignError("chain", chain, "has no change-gear quadrant")
    choices = select_change_gears(ratio, machine.change_gears, top_k=candidates)
    best = abs(choices[0].error)
    tied = [c for c in choices if abs(c.error) <= best + 1e-12 * ratio]
    quads = np.array([c.gears for c in tied], dtype=np.int64)
    gears = {**fixed, **{slot: quads[:, i] for i, slot in enumerate(spec.change_gear_slots)}}
    out = chain_error_arrays(machine, chain, gears, input_angle_deg=input_angle_deg)
    errors = np.broadcast_to(np.asarray(out["ratio_error"], dtype=float), (len(tied),))
    pick = int(np.argmin(errors))
    return tuple(int(g) for g in quads[pick]), quads, np.array(errors)  # type: ignore[return-value]


@dataclass(frozen=True, kw_only=True)
class Quadrant:
    """The change gears of one chain's quadrant and how well they give its required ratio.

    ``required_ratio`` and ``error`` (ratio minus required) are None when the divisor (work or
    crown teeth) was not given; ``candidates`` and ``candidate_ratio_errors`` are the quadrants
    weighed by :func:`choose_change_gears` when the gears were chosen, else None.
    """

    chain: str
    gears: tuple[int, int, int, int]
    ratio: float
    required_ratio: float | None
    error: float | None
    chosen: bool
    candidates: np.ndarray | None = field(default=None, compare=False, repr=False)
    candidate_ratio_errors: np.ndarray | None = field(default=None, compare=False, repr=False)

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready dictionary (without the candidates)."""
        return {
            "gears": list(self.gears),
            "ratio": self.ratio,
            "required_ratio": self.required_ratio,
            "error": self.error,
            "chosen": self.chosen,
        }


@dataclass(frozen=True, kw_only=True)
class MachineResult:
    """Every chain of a machine for one work gear: its quadrants and chain errors by name."""

    quadrants: Mapping[str, Quadrant]
    chains: Mapping[str, ChainResult]


def evaluate_machine(
    machine: Machine,
    *,
    work: WorkGear,
    crown_teeth: float | None = None,
    gears: Mapping[str, Sequence[int]] | None = None,
    input_angles_deg: Mapping[str, float] | None = None,
    candidates: int = 50,
) -> MachineResult:
    """Set up every quadrant and evaluate every chain of ``machine`` for the gear being cut.

    A quadrant given in ``gears`` (chain name -> ``(a, b, c, d)``) is checked by the set's rule;
    one not given is chosen by :func:`choose_change_gears` for its required ratio (``constant /
    work teeth``, or ``constant / crown_teeth``, which must then be given). Chains passing fewer
    slots are set up first, so the envelope chain sees the indexing quadrant it passes through.
    ``input_angles_deg`` overrides chains' input angles per cycle (the cradle swing).
    """
    gears = dict(gears or {})
    angles = dict(input_angles_deg or {})
    for name in (*gears, *angles):
        machine.chain(name)  # unknown chain names are errors
    with_slots = [c for c in machine.chains if c.change_gear_slots is not None]
    order = sorted(with_slots, key=lambda c: len(machine.slots_of(c.name)))
    teeth: dict[str, int] = {}
    quadrants: dict[str, Quadrant] = {}
    for spec in order:
        assert spec.change_gear_slots is not None
        divisor_known = spec.change_gear_divisor == "work_teeth" or crown_teeth is not None
        ratio = (
            required_ratio(machine, spec.name, work_teeth=work.teeth, crown_teeth=crown_teeth)
            if divisor_known
            else None
        )
        quads = errors = None
        if spec.name in gears:
            quad = tuple(machine.quadrant_gears(spec.name, gears[spec.name]).values())
        elif ratio is None:
            raise DesignError(
                "crown_teeth",
                rule=f"give the {spec.name} change gears a, b, c, d, or the crown gear's teeth "
                "to choose them from the machine's set",
            )
        else:
            fixed = {s: teeth[s] for s in machine.slots_of(spec.name) if s in teeth}
            quad, quads, errors = choose_change_gears(
                machine,
                spec.name,
                ratio,
                fixed,
                candidates=candidates,
                input_angle_deg=angles.get(spec.name),
            )
        teeth.update(zip(spec.change_gear_slots, quad, strict=True))
        value = quad[0] * quad[2] / (quad[1] * quad[3])
        quadrants[spec.name] = Quadrant(
            chain=spec.name,
            gears=quad,  # type: ignore[arg-type]
            ratio=value,
            required_ratio=ratio,
            error=None if ratio is None else value - ratio,
            chosen=spec.name not in gears,
            candidates=quads,
            candidate_ratio_errors=errors,
        )
    chains = {
        spec.name: chain_error(
            machine,
            spec.name,
            gears={s: teeth[s] for s in machine.slots_of(spec.name)},
            input_angle_deg=angles.get(spec.name),
            work=work,
        )
        for spec in machine.chains
    }
    return MachineResult(quadrants=quadrants, chains=chains)
