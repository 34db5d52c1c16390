"""A machine (its chains, change-gear slots and change-gear set) and its machine files.

:class:`Machine` joins the parts of :mod:`gearopt.chains.model` and checks that every chain runs
from its input shaft through its meshes, shaft by shaft, to the work spindle. A machine file is a
TOML description of one machine (see ``plugins/chain_error/data/zftkk250x5.toml``):
:func:`parse_machine` builds a :class:`Machine` from its parsed tables, :func:`loads_machine`
from its text and :func:`load_machine` by name (looked up in :func:`machine_dirs`: the folders of
``GEAROPT_MACHINE_PATH``, then those the installed distributions name in the entry-point group
``gearopt.machine_files``) or by path.
"""

from __future__ import annotations

import os
import tomllib
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from functools import cached_property
from importlib import metadata, resources
from pathlib import Path
from typing import Any

from gearopt.chains.change_gears import check_quadrant
from gearopt.chains.model import Chain, ChangeGearSet, ChangeGearSlot, Element, Shaft
from gearopt.chains.parsing import name_ok
from gearopt.errors import DesignError, PluginError
from gearopt.validate import check_keys, read_table

__all__ = [
    "MACHINE_PATH_ENV",
    "MACHINE_FILES_GROUP",
    "Machine",
    "parse_machine",
    "loads_machine",
    "machine_dirs",
    "machine_names",
    "load_machine",
]

MACHINE_PATH_ENV = "GEAROPT_MACHINE_PATH"
#: the entry-point group through which a distribution ships machine files
MACHINE_FILES_GROUP = "gearopt.machine_files"


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
        name_ok(self.name, "machine.name")
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
    """Build a :class:`Machine` from a parsed machine file (see
    ``plugins/chain_error/data/*.toml``)."""
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
    separated), then the folders that installed distributions ship through the entry-point
    group ``gearopt.machine_files``, in the order of the entries' names. An entry's value
    ``package:folder`` names a folder of package data inside an importable package (dots
    separate nested folders; ``package`` alone is the package's own folder)::

        [project.entry-points."gearopt.machine_files"]
        my-machines = "my_package:machines"    # my_package/machines/*.toml

    A :class:`PluginError` names an entry whose package cannot be imported.
    """
    dirs = [Path(p) for p in os.environ.get(MACHINE_PATH_ENV, "").split(os.pathsep) if p]
    for entry in sorted(metadata.entry_points(group=MACHINE_FILES_GROUP), key=lambda e: e.name):
        try:
            folder = resources.files(entry.module)
        except ModuleNotFoundError as exc:
            raise PluginError(
                f"entry point {entry.name!r} of group {MACHINE_FILES_GROUP!r}",
                entry.value,
                f"names a package that cannot be imported: {exc}",
            ) from None
        for part in (entry.attr or "").split("."):
            folder = folder.joinpath(part) if part else folder
        path = Path(str(folder))
        if path not in dirs:
            dirs.append(path)
    return dirs


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
