"""Setting up a machine's quadrants for the gear being cut, and evaluating all its chains.

:func:`required_ratio` is the ratio a chain's quadrant must give (``constant / work teeth`` or
``constant / crown teeth``); :func:`choose_change_gears` picks, among the quadrants of the set as
accurate as the best for that ratio (:func:`~gearopt.chains.change_gears.select_change_gears`),
the one with the smallest chain error (:func:`~gearopt.chains.method.chain_error_arrays`);
:func:`evaluate_machine` does both for every chain of a machine and evaluates every chain
(:func:`~gearopt.chains.method.chain_error`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from gearopt.chains.change_gears import select_change_gears
from gearopt.chains.machine import Machine
from gearopt.chains.method import ChainResult, WorkGear, chain_error, chain_error_arrays
from gearopt.chains.parsing import MAX_TEETH
from gearopt.errors import DesignError
from gearopt.validate import check_integer, check_number

__all__ = [
    "required_ratio",
    "choose_change_gears",
    "Quadrant",
    "MachineResult",
    "evaluate_machine",
]


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
        divisor = float(check_integer("work_teeth", work_teeth, ge=1, le=MAX_TEETH))
    else:
        if crown_teeth is None:
            raise DesignError("crown_teeth", rule=f"the {chain} ratio is constant / crown teeth")
        divisor = check_number("crown_teeth", crown_teeth, gt=0.0)
    return spec.change_gear_constant / divisor


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
