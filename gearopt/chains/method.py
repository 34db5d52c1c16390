"""The chain-error method of seed 000: a chain's ratio, angle and pitch errors for one cycle.

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
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, fields
from typing import Any

import numpy as np

from gearopt.chains.machine import Machine
from gearopt.chains.model import Element
from gearopt.chains.parsing import MAX_TEETH
from gearopt.errors import DesignError
from gearopt.validate import check_integer, check_number

__all__ = [
    "WorkGear",
    "normal_pitch_error_um",
    "chain_error_arrays",
    "ElementRow",
    "MeshRow",
    "ChainResult",
    "chain_error",
]

# a revolution count within this (relative) distance of an integer is a whole number of turns
_WHOLE_TURN_TOLERANCE = 1e-9


@dataclass(frozen=True, kw_only=True)
class WorkGear:
    """The gear being cut: what turns the work's angle error into a pitch error."""

    teeth: int
    normal_module_mm: float
    spiral_angle_deg: float

    def __post_init__(self) -> None:
        check_integer("work_teeth", self.teeth, ge=1, le=MAX_TEETH)
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
        import pandas as pd  # (loaded when a table is asked for: the CLI starts without it)

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
        check_integer(f"gears.{name}", teeth, ge=1, le=MAX_TEETH)
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
