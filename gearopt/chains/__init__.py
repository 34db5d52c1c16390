"""Kinematic chains of a generating machine: their errors and the choice of change gears.

A machine's indexing and envelope (generating) chains are gear trains: shafts joined by meshes
(gear pairs, worm drives), driven at one end (the rack of the indexing clutch, the cradle) and
ending at the work spindle, with change gears in quadrant slots (``a b c d``: ratio
``a c / (b d)``, ``a`` meshing ``b``, ``b`` and ``c`` on one stud, ``c`` meshing ``d``). This
package holds the machine-independent data model (frozen dataclasses, validated on
construction), the loader of machine files (TOML, see
``plugins/chain_error/data/zftkk250x5.toml``), the chain-error method of seed 000 and the
change-gear selection. Every public name is importable from ``gearopt.chains``; the modules are:

:mod:`gearopt.chains.model`
    The parts of a chain: :class:`Shaft`, :class:`Element`, :class:`ChangeGearSlot`,
    :class:`Mesh`, :class:`Chain`, :class:`ToleranceBracket`, :class:`ChangeGearSet`.
:mod:`gearopt.chains.machine`
    :class:`Machine`, which joins them, and the machine files: :func:`parse_machine`,
    :func:`loads_machine`, :func:`load_machine`, :func:`machine_dirs`, :func:`machine_names`.
:mod:`gearopt.chains.change_gears`
    The quadrant's meshing rule (:func:`quadrant_ok`, :func:`check_quadrant`) and the quadrants
    nearest to a ratio (:func:`select_change_gears`, :class:`ChangeGearChoice`).
:mod:`gearopt.chains.method`
    The chain-error method of seed 000 (Step 3, Tables 3, 4, 7, 8; stated in that module's
    docstring): :func:`chain_error_arrays`, :func:`chain_error`, :class:`ChainResult`,
    :class:`WorkGear`, :func:`normal_pitch_error_um`.
:mod:`gearopt.chains.evaluate`
    A machine's quadrants for the gear being cut and all its chains' errors:
    :func:`required_ratio`, :func:`choose_change_gears`, :func:`evaluate_machine`.
:mod:`gearopt.chains.parsing`
    Checks the modules share (names, optional numbers, the largest tooth count).

Everything is in micrometres (errors), millimetres (diameters) and degrees at the interface.
"""

from __future__ import annotations

from gearopt.chains.change_gears import (
    ChangeGearChoice,
    check_quadrant,
    quadrant_ok,
    select_change_gears,
)
from gearopt.chains.evaluate import (
    MachineResult,
    Quadrant,
    choose_change_gears,
    evaluate_machine,
    required_ratio,
)
from gearopt.chains.machine import (
    MACHINE_PATH_ENV,
    Machine,
    load_machine,
    loads_machine,
    machine_dirs,
    machine_names,
    parse_machine,
)
from gearopt.chains.method import (
    ChainResult,
    ElementRow,
    MeshRow,
    WorkGear,
    chain_error,
    chain_error_arrays,
    normal_pitch_error_um,
)
from gearopt.chains.model import (
    DIVISORS,
    ELEMENT_KINDS,
    Chain,
    ChangeGearSet,
    ChangeGearSlot,
    Element,
    Mesh,
    Shaft,
    ToleranceBracket,
)

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
