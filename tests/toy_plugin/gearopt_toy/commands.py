"""The toy distribution's command and benchmark: how a third party extends ``gearopt``.

``gearopt toy-roll DESIGN.toml [--member pinion|gear] [--json]`` prints the toy planer's
cradle roll of a member (1 / sin of its pitch angle, the crown gear's teeth per work tooth) and
the benchmark ``toy_roll_ms`` of ``gearopt bench`` times it. A separate module registered under
its own entry point (``toy-commands`` in the toy's ``pyproject.toml``): a plugin may be any
number of modules.
"""

from __future__ import annotations

import json
from importlib import resources

import gearopt
from gearopt.commands import time_call_ms


class ToyRollCommand(gearopt.BaseCommand):
    name = "toy-roll"
    help = "the toy planer's cradle roll of a member (toy command)"

    def __init__(self, *, plugin_manager=None):
        self.plugin_manager = plugin_manager

    def add_arguments(self, parser):
        parser.add_argument("design", help="design TOML file of the toy planer")
        parser.add_argument("--member", default="pinion", choices=("pinion", "gear"))
        parser.add_argument("--json", action="store_true", help="print JSON")

    def run(self, args):
        design = gearopt.load_design(args.design, plugin_manager=self.plugin_manager)
        if design.model != "toy-planer":
            raise gearopt.DesignError("machine.model", design.model, "must be 'toy-planer'")
        settings = gearopt.basic_settings(design, plugin_manager=self.plugin_manager)
        roll = getattr(settings, args.member).gear_to_cradle_roll
        out = {"design": design.name, "member": args.member, "gear_to_cradle_roll": roll}
        print(json.dumps(out) if args.json else f"{args.member} cradle roll {roll:.6f}")
        return 0


def bench_toy_roll():
    """The toy planer's basic settings of the toy design."""
    text = resources.files(__package__).joinpath("toy_design.toml").read_text()
    design = gearopt.loads_design(text)
    model = gearopt.get_machine_model(design.model)
    model.basic_settings(design)  # warm-up
    ms = time_call_ms(lambda: model.basic_settings(design), number=20)
    return ms, {"toy_design": design.name}


@gearopt.hookimpl
def gearopt_commands(plugin_manager):
    return [ToyRollCommand(plugin_manager=plugin_manager)]


@gearopt.hookimpl
def gearopt_benchmarks():
    return [gearopt.Benchmark(name="toy_roll_ms", function=bench_toy_roll)]
