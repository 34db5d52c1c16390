"""A toy third-party plugin: a made-up straight-tooth planer, an evaluator and an objective.

It exists to show (and test) that a distribution installed next to gearopt is found through the
entry-point group ``gearopt`` and used exactly like the built-ins, and that a new machine gets
its flanks from gearopt's shared envelope solver by describing its generating family only.

The planer: a crown rack in the cradle plane whose straight tool flanks run through the cone
apex at the pressure angle; the cradle turns by psi and the work by psi / sin(gamma), so the
tool flank's envelope is a straight (zero-spiral) bevel tooth flank, conjugate to the crown rack.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

import gearopt
from gearopt.envelope import flank_map, solve_envelope
from gearopt.flank import FlankGrid, check_member_and_flank
from gearopt.validate import check_keys, read_number

FLANK_SIDE = {"convex": 1.0, "concave": -1.0}


@dataclass(frozen=True, kw_only=True)
class CrownRackFamily:
    """The planer's tool flanks as a generating family, q = (u along the tool profile,
    v along the tool line, psi the cradle angle); flank k has side ``sides[k]``."""

    sides: tuple[float, ...]
    slot_half_angle_rad: float  # beta: the tool flank line's angle from the slot's middle
    tool_pass_rad: float  # the rack tooth's angle on the cradle (k crown pitches)
    pressure_angle_rad: float
    root_angle_rad: float
    scale_mm: float
    tip_depth_mm: float
    max_step: tuple[float, float, float] = (1.0, 1.0, 0.05)

    @property
    def n_flanks(self):
        return len(self.sides)

    def _machine(self, q, flank):
        sigma = np.asarray(self.sides)[flank]
        b, a = self.slot_half_angle_rad, self.pressure_angle_rad
        u, v, psi = q[..., 0], q[..., 1], q[..., 2] + self.tool_pass_rad
        c, s = np.cos(sigma * b + psi), np.sin(sigma * b + psi)
        d = (c, s, 0.0 * c)  # the tool line, turned by the cradle
        out = (-s * sigma, c * sigma, 0.0 * c)  # away from the slot's middle
        t = (math.sin(a) * out[0], math.sin(a) * out[1], -math.cos(a) + 0.0 * c)
        point = tuple(v * d[i] + u * t[i] for i in range(3))
        return point, t, d, sigma

    def axial_radial_meshing(self, q, flank):
        (x, y, z), t, d, _ = self._machine(q, flank)
        g = self.root_angle_rad
        ca, sa, roll = math.cos(g), math.sin(g), 1.0 / math.sin(g)
        # relative velocity per unit psi: cradle about z, work about (ca, 0, sa) by psi / sin g
        w = (-y - roll * (-sa * y), x - roll * (sa * x - ca * z), -roll * (ca * y))
        n = (t[1] * d[2] - t[2] * d[1], t[2] * d[0] - t[0] * d[2], t[0] * d[1] - t[1] * d[0])
        axial = ca * x + sa * z
        radius = np.sqrt(x * x + y * y + z * z - axial * axial)
        meshing = n[0] * w[0] + n[1] * w[1] + n[2] * w[2]
        size = np.sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2])
        return axial, radius, meshing / (size * self.scale_mm)

    def pitch_row(self, cone_distance_mm):
        s = np.asarray(cone_distance_mm, float)
        rows = [
            np.stack([0 * s, s, 0 * s - side * self.slot_half_angle_rad], axis=-1)
            for side in self.sides
        ]
        return np.stack(rows) - np.array([0.0, 0.0, self.tool_pass_rad])

    def geometry(self, q, flank):
        point, t, d, sigma = self._machine(q, flank)
        n = np.cross(np.stack(np.broadcast_arrays(*t), -1), np.stack(np.broadcast_arrays(*d), -1))
        g = self.root_angle_rad
        work = q[..., 2] / math.sin(g)
        cw, sw = np.cos(work), np.sin(work)

        def to_work(x, y, z):
            xq, zq = math.sin(g) * x - math.cos(g) * z, math.cos(g) * x + math.sin(g) * z
            return np.stack([cw * xq + sw * y, -sw * xq + cw * y, zq], axis=-1)

        normal = to_work(n[..., 0], n[..., 1], n[..., 2])
        normal *= (sigma / np.linalg.norm(normal, axis=-1))[..., None]
        return {"point": to_work(*point), "normal": normal}

    def within_tool(self, q, flank):
        return q[..., 0] * math.cos(self.pressure_angle_rad) <= self.tip_depth_mm + 1e-9


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

    def generate_flank(self, design, *, member, flank, grid=None, tool_pass=0):
        return self.generate_flanks(
            design, member=member, grid=grid, flanks=(flank,), tool_pass=tool_pass
        )[flank]

    def generate_flanks(
        self, design, *, member, grid=None, flanks=("convex", "concave"), tool_pass=0
    ):
        for flank in flanks:
            check_member_and_flank(member, flank)
        index = ("pinion", "gear").index(member)
        blank = design.blank
        teeth = (blank.pinion_teeth, blank.gear_teeth)[index]
        gamma = math.radians(blank.pitch_angle_deg[index])
        family = CrownRackFamily(
            sides=tuple(FLANK_SIDE[f] for f in flanks),
            slot_half_angle_rad=0.5 * math.pi / blank.crown_gear_teeth,
            tool_pass_rad=2.0 * math.pi * tool_pass / blank.crown_gear_teeth,
            pressure_angle_rad=math.radians(design.machine.tool_pressure_angle_deg),
            root_angle_rad=gamma,
            scale_mm=blank.mean_cone_distance_mm,
            tip_depth_mm=blank.mean_dedendum_mm[index],
        )
        solution = solve_envelope(
            family,
            cone_distances_mm=(blank.inner_cone_distance_mm, blank.outer_cone_distance_mm),
            heights_mm=(-blank.mean_dedendum_mm[index], blank.mean_addendum_mm[index]),
            pitch_angle_rad=gamma,
            grid=grid or FlankGrid(),
        )
        hand = blank.hand[index]
        out = {}
        for k, flank in enumerate(flanks):
            fm = flank_map(
                family,
                solution,
                index=k,
                member=member,
                flank=flank,
                hand=hand,
                teeth=teeth,
                # tooth 0: the convex flank at +pi/(2N) and its concave flank a pitch further
                turn_rad=0.0 if flank == "convex" else 2.0 * math.pi / teeth,
                notes=("toy crown-rack planer",),
            )
            out[flank] = fm.rotated(0.0, teeth=tool_pass if hand == "right" else -tool_pass)
        return out

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


class ToyProbeEvaluator(gearopt.BaseEvaluator):
    """A cheap stand-in for a real evaluation, for tests of the study machinery.

    Metric ``probe`` = (tool_tip_width_mm - 1.1)^2. Conditions: ``sleep_s`` (pretend to work),
    ``exit_at_mm`` (the worker process dies, ``os._exit``, when the tool tip width is exactly
    that), ``refuse_above_mm`` (a DesignError when the width exceeds it).
    """

    name = "toy-probe"
    description = "Tool tip width's distance from 1.1 mm (toy evaluator for study tests)"

    def evaluate(self, design, conditions=None):
        import os
        import time

        conditions = dict(conditions or {})
        width = design.machine.tool_tip_width_mm
        time.sleep(conditions.get("sleep_s", 0.0))
        if width == conditions.get("exit_at_mm"):
            os._exit(3)
        if width > conditions.get("refuse_above_mm", math.inf):
            raise gearopt.DesignError("machine.tool_tip_width_mm", width, "refused by the probe")
        return gearopt.Evaluation(
            evaluator=self.name,
            metrics={"probe": (width - 1.1) ** 2},
            conditions=conditions,
        )


class ToyProbeObjective(gearopt.BaseObjective):
    name = "toy-probe"
    description = "The toy probe metric (toy objective for study tests)"
    requires = ("toy-probe",)

    def value(self, evaluations, **options):
        return evaluations["toy-probe"].metrics["probe"]


@gearopt.hookimpl
def gearopt_machine_models():
    return [ToyPlaner()]


@gearopt.hookimpl
def gearopt_evaluators():
    return [ToyBlankEvaluator(), ToyProbeEvaluator()]


@gearopt.hookimpl
def gearopt_objectives():
    return [ToyObjective(), ToyProbeObjective()]
