"""Kinematic-chain error of the generating machine, seed 000: an evaluator plugin.

The ``chain-error`` evaluator computes, for the member being cut, the ratio, angle and pitch
errors of every chain of a machine file (by default ``zftkk250x5``: its indexing and envelope
chains) with the method of :mod:`gearopt.chains`. A study can weigh them, e.g. the indexing pitch
error against the choice of change gears.

Conditions (all optional)::

    machine = "zftkk250x5"        # a machine name or a machine-file path
    member = "pinion"             # or "gear": the member being cut
    work_teeth = 15               # default: that member's teeth
    normal_module_mm = 3.5        # default: the pair's mean normal module
    spiral_angle_deg = 35.0       # default: the pair's mean spiral angle
    crown_teeth = 33.541          # default: the pair's crown gear N / sin(pitch angle)
    indexing_gears = [48, 45, 60, 60]   # "<chain>_gears" for any chain with a quadrant
    envelope_gears = [40, 64, 62, 52]
    cradle_swing_deg = 55.0       # alias of envelope_input_angle_deg ("<chain>_input_angle_deg")
    candidates = 50               # quadrants considered when a chain's gears are not given

When a chain's gears are not given, the quadrants nearest to its required ratio (``constant /
work or crown teeth``) are taken from the machine's change-gear set, and among those that are as
accurate as the best (ties of the ratio) the one with the smallest chain ratio error is chosen:
the choice of change gears is weighed by the chain error. Chains that pass through another
chain's quadrant (the envelope chain passes a2..d2) are evaluated after it.

Metrics per chain ``<c>`` (finite floats): ``<c>_theoretical_ratio``, ``<c>_max_ratio``,
``<c>_min_ratio``, ``<c>_ratio_error``, ``<c>_ratio_error_percent``, ``<c>_angle_error_deg``,
``<c>_pitch_error_um``, ``<c>_change_gear_error`` (quadrant ratio minus required) and
``<c>_change_gear_error_percent``.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from gearopt import hookimpl
from gearopt.bench import time_call_ms
from gearopt.chains import WorkGear, evaluate_machine, load_machine, select_change_gears
from gearopt.declarations import Metric, Option
from gearopt.design import MEMBERS, Design
from gearopt.errors import DesignError
from gearopt.evaluation import BaseEvaluator, Evaluation
from gearopt.validate import check_integer, check_keys, check_number

__all__ = ["ChainErrorEvaluator", "bench_change_gears"]

DEFAULT_MACHINE = "zftkk250x5"
METRICS = (
    "theoretical_ratio",
    "max_ratio",
    "min_ratio",
    "ratio_error",
    "ratio_error_percent",
    "angle_error_deg",
    "pitch_error_um",
)
_UNITS = {"angle_error_deg": "deg", "pitch_error_um": "um", "ratio_error_percent": "%"}
_FIXED_KEYS = (
    "machine",
    "member",
    "work_teeth",
    "normal_module_mm",
    "spiral_angle_deg",
    "crown_teeth",
    "cradle_swing_deg",
    "candidates",
)


def _machine_keys(conditions: dict) -> tuple[Any, list[str], str]:
    """The conditions' machine, its change-gear quadrants and the member, every key checked."""
    name = conditions.get("machine", DEFAULT_MACHINE)
    if not isinstance(name, str):
        raise DesignError("conditions.machine", name, "must be a machine name or file path")
    machine = load_machine(name)
    quadrants = [c.name for c in machine.chains if c.change_gear_slots is not None]
    allowed = (
        *_FIXED_KEYS,
        *(f"{c}_gears" for c in quadrants),
        *(f"{c.name}_input_angle_deg" for c in machine.chains),
    )
    check_keys(conditions, allowed, "conditions")
    member = conditions.get("member", "pinion")
    if member not in MEMBERS:
        raise DesignError("conditions.member", member, f"must be one of {list(MEMBERS)}")
    return machine, quadrants, member


class ChainErrorEvaluator(BaseEvaluator):
    """Ratio, angle and pitch errors of a machine's kinematic chains (seed 000)."""

    name = "chain-error"
    description = "kinematic-chain (indexing, envelope) ratio and pitch errors, seed 000"
    metrics = (
        *(
            Metric(name=f"*_{key}", unit=_UNITS.get(key, ""), description=f"each chain's {key}")
            for key in METRICS
        ),
        Metric(name="*_change_gear_error", description="quadrant ratio minus required"),
        Metric(
            name="*_change_gear_error_percent",
            unit="%",
            description="quadrant ratio minus required, of the required ratio",
        ),
    )
    options = (
        Option(name="machine", default=DEFAULT_MACHINE, kind="string", description="machine"),
        Option(
            name="member",
            default="pinion",
            kind="string",
            choices=MEMBERS,
            description="the member being cut",
        ),
        Option(name="work_teeth", kind="integer", lower=1, description="default: the member's"),
        Option(name="normal_module_mm", kind="number", description="default: the pair's mean"),
        Option(name="spiral_angle_deg", kind="number", description="default: the pair's mean"),
        Option(name="crown_teeth", kind="number", description="default: the pair's"),
        Option(name="cradle_swing_deg", kind="number", description="envelope input angle"),
        Option(name="candidates", default=50, kind="integer", lower=1, upper=10_000),
        Option(name="*_gears", kind="numbers", description="a chain's change-gear quadrant"),
        Option(name="*_input_angle_deg", kind="number", description="a chain's input angle"),
    )

    def check_conditions(self, design: Design, conditions: Mapping[str, Any]) -> None:
        """The declared options, then the keys the machine knows (its chains')."""
        super().check_conditions(design, conditions)
        _machine_keys(dict(conditions))

    def evaluate(self, design: Design, conditions: Mapping[str, Any] | None = None) -> Evaluation:
        conditions = dict(conditions or {})
        machine, quadrants, member = _machine_keys(conditions)
        pair = design.pair
        default_teeth = pair.pinion_teeth if member == "pinion" else pair.gear_teeth
        work = WorkGear(
            teeth=check_integer(
                "conditions.work_teeth", conditions.get("work_teeth", default_teeth), ge=1
            ),
            normal_module_mm=check_number(
                "conditions.normal_module_mm",
                conditions.get("normal_module_mm", pair.mean_normal_module_mm),
                gt=0.0,
            ),
            spiral_angle_deg=check_number(
                "conditions.spiral_angle_deg",
                conditions.get("spiral_angle_deg", pair.mean_spiral_angle_deg),
                ge=0.0,
                lt=90.0,
            ),
        )
        crown = check_number(
            "conditions.crown_teeth",
            conditions.get("crown_teeth", design.blank.crown_gear_teeth),
            gt=0.0,
        )
        angles = {
            c.name: conditions[f"{c.name}_input_angle_deg"]
            for c in machine.chains
            if f"{c.name}_input_angle_deg" in conditions
        }
        if "cradle_swing_deg" in conditions:
            angles["envelope"] = conditions["cradle_swing_deg"]
        given = {c: conditions[f"{c}_gears"] for c in quadrants if f"{c}_gears" in conditions}
        result = evaluate_machine(
            machine,
            work=work,
            crown_teeth=crown,
            gears=given,
            input_angles_deg=angles,
            candidates=check_integer(
                "conditions.candidates", conditions.get("candidates", 50), ge=1, le=10_000
            ),
        )
        metrics: dict[str, float] = {}
        arrays: dict[str, np.ndarray] = {}
        for chain, quadrant in result.quadrants.items():
            assert quadrant.error is not None and quadrant.required_ratio is not None
            metrics[f"{chain}_change_gear_error"] = quadrant.error
            metrics[f"{chain}_change_gear_error_percent"] = (
                100.0 * quadrant.error / quadrant.required_ratio
            )
            if quadrant.candidates is not None:
                arrays[f"{chain}_candidate_gears"] = quadrant.candidates
                arrays[f"{chain}_candidate_ratio_error"] = quadrant.candidate_ratio_errors
        for chain, chain_result in result.chains.items():
            for key in METRICS:
                metrics[f"{chain}_{key}"] = float(getattr(chain_result, key))
        return Evaluation(
            evaluator=self.name,
            metrics=metrics,
            arrays=arrays,
            conditions={
                "machine": machine.name,
                "member": member,
                "work_teeth": work.teeth,
                "normal_module_mm": work.normal_module_mm,
                "spiral_angle_deg": work.spiral_angle_deg,
                "crown_teeth": crown,
                "input_angles_deg": {c: r.input_angle_deg for c, r in result.chains.items()},
                **{f"{c}_gears": list(q.gears) for c, q in result.quadrants.items()},
            },
        )


@hookimpl
def gearopt_evaluators() -> list[BaseEvaluator]:
    """The chain-error evaluator."""
    return [ChainErrorEvaluator()]


def bench_change_gears() -> tuple[float, dict]:
    """Top-5 change gears for seed 000's envelope ratio 0.745356 from the shipped set."""

    machine = load_machine(DEFAULT_MACHINE)
    ratio = 0.745356
    select_change_gears(ratio, machine.change_gears, top_k=5)  # warm-up
    ms = time_call_ms(lambda: select_change_gears(ratio, machine.change_gears, top_k=5), number=50)
    return ms, {
        "change_gears_machine": machine.name,
        "change_gears_set_size": len(machine.change_gears.teeth),
        "change_gears_ratio": ratio,
        "change_gears_top_k": 5,
    }
