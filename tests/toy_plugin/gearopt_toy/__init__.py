"""A toy third-party plugin: a made-up straight-tooth planer, an evaluator and an objective.

It exists to show (and test) that a distribution installed next to gearopt is found through the
entry-point group ``gearopt`` and used exactly like the built-ins.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import gearopt
from gearopt.validate import check_keys, read_number


@dataclass(frozen=True, kw_only=True)
class ToyMachine:
    tool_tip_width_mm: float
    tool_pressure_angle_deg: float


@dataclass(frozen=True, kw_only=True)
class ToySettings:
    machine_root_angle_deg: float
    gear_to_cradle_roll: float
    tool_tip_width_mm: float
    tool_pressure_angle_deg: float


class ToyPlaner(gearopt.BaseMachineModel):
    name = "toy-planer"
    description = "Toy straight bevel planer (third-party plugin example)"

    def parse_machine(self, table, pair):
        check_keys(table, ("tool_tip_width_mm", "tool_pressure_angle_deg"), "machine")
        return ToyMachine(
            tool_tip_width_mm=read_number(table, "tool_tip_width_mm", "machine", gt=0.0),
            tool_pressure_angle_deg=read_number(
                table, "tool_pressure_angle_deg", "machine", pair.pressure_angle_deg, gt=0, lt=45
            ),
        )

    def basic_settings(self, design):
        if not design.compensation.is_zero:
            raise gearopt.NotAvailableError("compensation", rule="the toy planer cannot compensate")
        members = {}
        for index, member in enumerate(("pinion", "gear")):
            pitch = design.blank.pitch_angle_deg[index]
            members[member] = ToySettings(
                machine_root_angle_deg=pitch,
                gear_to_cradle_roll=1.0 / math.sin(math.radians(pitch)),
                tool_tip_width_mm=design.machine.tool_tip_width_mm,
                tool_pressure_angle_deg=design.machine.tool_pressure_angle_deg,
            )
        return gearopt.MachineSettings(model=self.name, **members)

    def search_space(self, design):
        width = design.machine.tool_tip_width_mm
        return (
            gearopt.SearchDimension(
                key="machine.tool_tip_width_mm", low=0.5 * width, high=1.5 * width
            ),
        )


class ToyBlankEvaluator(gearopt.BaseEvaluator):
    name = "toy-blank"
    description = "Crown gear teeth of the blank (toy evaluator)"

    def evaluate(self, design, conditions=None):
        return gearopt.Evaluation(
            evaluator=self.name,
            metrics={"crown_gear_teeth": design.blank.crown_gear_teeth},
            conditions=dict(conditions or {}),
        )


class ToyObjective(gearopt.BaseObjective):
    name = "toy-crown-teeth"
    description = "Crown gear teeth, to be minimised (toy objective)"
    requires = ("toy-blank",)

    def value(self, evaluations, **options):
        return evaluations["toy-blank"].metrics["crown_gear_teeth"]


@gearopt.hookimpl
def gearopt_machine_models():
    return [ToyPlaner()]


@gearopt.hookimpl
def gearopt_evaluators():
    return [ToyBlankEvaluator()]


@gearopt.hookimpl
def gearopt_objectives():
    return [ToyObjective()]
