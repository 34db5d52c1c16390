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

The plugin also adds two commands, ``gearopt chain MACHINE ...`` (the errors of a machine's
chains, with per-element and per-mesh tables) and ``gearopt change-gears MACHINE --ratio R``
(the best change gears of its set), and the benchmark ``change_gears_ms`` of ``gearopt bench``.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
from collections.abc import Mapping
from typing import Any

import numpy as np

from gearopt import hookimpl
from gearopt.chains import WorkGear, evaluate_machine, load_machine, select_change_gears
from gearopt.commands import BaseCommand, Benchmark, text_table, time_call_ms
from gearopt.declarations import Metric, Option
from gearopt.design import MEMBERS, Design
from gearopt.errors import DesignError
from gearopt.evaluation import BaseEvaluator, Evaluation
from gearopt.validate import check_integer, check_keys, check_number

__all__ = ["ChainCommand", "ChainErrorEvaluator", "ChangeGearsCommand", "bench_change_gears"]

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


def _parse_teeth(text: str, option: str, *, count: int | None = None) -> list[int]:
    rule = "must be tooth counts separated by commas"
    if count == 4:
        rule = "must be four tooth counts a,b,c,d (a/b x c/d)"
    try:
        teeth = [int(part) for part in text.replace(" ", "").split(",") if part]
    except ValueError:
        raise DesignError(option, text, rule) from None
    if count is not None and len(teeth) != count:
        raise DesignError(option, text, rule)
    return teeth


def _chain_text(name: str, out: dict[str, Any]) -> str:

    summary = [
        (key, f"{out[key]:.8g}" if out[key] is not None else "-")
        for key in (
            "input_angle_deg",
            "theoretical_ratio",
            "max_ratio",
            "min_ratio",
            "ratio_error",
            "ratio_error_plus",
            "ratio_error_minus",
            "ratio_error_percent",
            "angle_error_deg",
            "pitch_error_um",
        )
    ]
    gears = ", ".join(f"{k}={v}" for k, v in out["gears"].items())
    lines = [f"{name} chain of {out['machine']!r} (change gears {gears or 'none'})"]
    if "change_gears" in out:
        choice = out["change_gears"]
        how = "chosen from the set" if choice["chosen"] else "given"
        line = f"quadrant {choice['gears']} ({how}): ratio {choice['ratio']:.8f}"
        if choice["required_ratio"] is not None:
            line += f" for {choice['required_ratio']:.8f} (error {choice['error']:+.3e})"
        lines.append(line)
    lines += ["", text_table(summary, ("result", "value")), ""]
    columns = {
        "revolutions": "n",
        "odd_teeth": "zk",
        "fi_um": "fi_um",
        "fpr_um": "Fpr_um",
        "error_um": "F_um",
        "pitch_diameter_mm": "D_mm",
        "angle_error_deg": "dphi_deg",
        "max_rotation_deg": "max_deg",
        "min_rotation_deg": "min_deg",
    }
    import pandas as pd  # (only here: the CLI loads every plugin at start-up)

    frame = pd.DataFrame(out["elements"]).set_index("element")[list(columns)]
    frame = frame.rename(columns=columns)
    lines.append(frame.to_string(float_format=lambda v: f"{v:.4f}"))
    lines.append("")
    meshes = pd.DataFrame(out["meshes"])
    lines.append(meshes.to_string(index=False, float_format=lambda v: f"{v:.6f}"))
    return "\n".join(lines)


class ChainCommand(BaseCommand):
    """``gearopt chain MACHINE ...``: the errors of a machine's indexing and envelope chains."""

    name = "chain"
    help = "errors of a machine's indexing and envelope chains (seed 000)"

    def add_arguments(self, parser: argparse.ArgumentParser) -> None:
        p = parser
        p.add_argument("machine", help="machine name (e.g. zftkk250x5) or machine TOML file")
        p.add_argument("--work-teeth", type=int, required=True, help="teeth of the gear being cut")
        p.add_argument("--normal-module-mm", type=float, required=True, help="mean normal module")
        p.add_argument("--spiral-angle-deg", type=float, required=True, help="mean spiral angle")
        p.add_argument("--indexing-gears", help="a,b,c,d of the indexing quadrant (default: best)")
        p.add_argument("--envelope-gears", help="a,b,c,d of the envelope quadrant")
        p.add_argument(
            "--crown-teeth", type=float, help="crown gear teeth, to choose the envelope gears"
        )
        p.add_argument(
            "--cradle-swing-deg", type=float, help="cradle swing per cycle (default: the machine's)"
        )
        p.add_argument("--json", action="store_true", help="print JSON")

    def run(self, args: argparse.Namespace) -> int:
        machine = load_machine(args.machine)
        work = WorkGear(
            teeth=args.work_teeth,
            normal_module_mm=args.normal_module_mm,
            spiral_angle_deg=args.spiral_angle_deg,
        )
        gears = {
            chain: _parse_teeth(text, f"--{chain}-gears", count=4)
            for chain, text in (
                ("indexing", args.indexing_gears),
                ("envelope", args.envelope_gears),
            )
            if text is not None
        }
        swing = {} if args.cradle_swing_deg is None else {"envelope": args.cradle_swing_deg}
        result = evaluate_machine(
            machine, work=work, crown_teeth=args.crown_teeth, gears=gears, input_angles_deg=swing
        )
        out: dict[str, Any] = {}
        for name, chain in result.chains.items():
            out[name] = chain.as_dict()
            out[name]["work"] = dataclasses.asdict(work)
            if name in result.quadrants:
                out[name]["change_gears"] = result.quadrants[name].as_dict()
        if args.json:
            print(json.dumps(out, indent=2))
            return 0
        print(
            f"work gear: z = {work.teeth}, m_n = {work.normal_module_mm:g} mm, "
            f"beta = {work.spiral_angle_deg:g} deg"
        )
        for name, chain_out in out.items():
            print()
            print(_chain_text(name, chain_out))
        return 0


class ChangeGearsCommand(BaseCommand):
    """``gearopt change-gears MACHINE --ratio R``: the best change gears of a machine's set."""

    name = "change-gears"
    help = "best change gears a/b x c/d for a ratio"

    def add_arguments(self, parser: argparse.ArgumentParser) -> None:
        p = parser
        p.add_argument("machine", help="machine name (e.g. zftkk250x5) or machine TOML file")
        p.add_argument("--ratio", type=float, required=True, help="required ratio a c / (b d)")
        p.add_argument("--top-k", type=int, default=5, help="how many quadrants to list")
        p.add_argument("--reserve", help="gears already in use, e.g. 48,45,60,60")
        p.add_argument("--json", action="store_true", help="print JSON")

    def run(self, args: argparse.Namespace) -> int:
        machine = load_machine(args.machine)
        reserved = [] if args.reserve is None else _parse_teeth(args.reserve, "--reserve")
        choices = select_change_gears(
            args.ratio, machine.change_gears, top_k=args.top_k, reserved=reserved
        )
        best = choices[0].as_dict()
        gear_set = machine.change_gears
        clearance = gear_set.clearance_teeth
        out = {
            "machine": machine.name,
            **best,
            "candidates": [c.as_dict() for c in choices],
            "set_size": len(gear_set.teeth),
            "rule": f"a + b >= c + {clearance}, c + d >= b + {clearance}",
        }
        if args.json:
            print(json.dumps(out, indent=2))
            return 0
        print(
            f"change gears a/b x c/d of {machine.name!r} for ratio {args.ratio:g} "
            f"({len(gear_set.teeth)} gears; {out['rule']})"
        )
        rows = [
            (
                "/".join(str(g) for g in c.gears),
                f"{c.ratio:.8f}",
                f"{c.error:+.3e}",
                f"{c.error_percent:+.5f}",
            )
            for c in choices
        ]
        print(text_table(rows, ("a/b/c/d", "ratio", "error", "error %")))
        return 0


@hookimpl
def gearopt_commands() -> list[BaseCommand]:
    """``gearopt chain`` and ``gearopt change-gears``."""
    return [ChainCommand(), ChangeGearsCommand()]


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


@hookimpl
def gearopt_benchmarks() -> list[Benchmark]:
    """``change_gears_ms``: the change-gear selection."""
    return [
        Benchmark(
            name="change_gears_ms",
            function=bench_change_gears,
            description="top-5 change gears for a ratio from the zftkk250x5 set",
        )
    ]
