"""Benchmarks for ``gearopt bench``: medians over fresh processes on one thread.

Each benchmark is a :class:`gearopt.commands.Benchmark`: a name and a module-level function
``() -> (milliseconds, info)`` that times one run of its kernel (after any warm-up it needs)
and returns extra facts to print beside the time (grid size, set size). The core's benchmarks
(:data:`CORE_BENCHMARKS`) time the framework's kernels; plugins add theirs through the
``gearopt_benchmarks`` hook (:func:`all_benchmarks`). :func:`run_benchmarks` runs every repeat
in a fresh interpreter, which imports the benchmark's function by its module and name, with the
BLAS/OpenMP thread counts set to 1, and reports the median, so import caches, allocator state
and a second core do not flatter the numbers. Timings are never asserted in tests.
"""

from __future__ import annotations

import json
import os
import statistics
import subprocess
import sys
from collections.abc import Iterable
from importlib import import_module
from importlib.metadata import version as package_version
from pathlib import Path

import numpy as np
import pluggy

from gearopt.analysis import (
    AnalysisOptions,
    contact_sides,
    meshed_pair,
    pair_backlash,
    pair_loaded_contact,
)
from gearopt.commands import Benchmark, time_call_ms
from gearopt.contact import kernels as contact_kernels
from gearopt.design_files import loads_design, with_overrides
from gearopt.errors import GearoptError, NotAvailableError, PluginError
from gearopt.flank import FlankGrid
from gearopt.load_options import LoadOptions
from gearopt.loaded.compliance import DEFAULT_MESH, member_compliance
from gearopt.loaded.pair import member_flanks
from gearopt.newton_tca import newton_tca
from gearopt.plugins import get_machine_model, list_plugins
from gearopt.studyfile import load_study_spec
from gearopt.trial import evaluate_trial
from gearopt.warmup import warm_kernels

__all__ = ["CORE_BENCHMARKS", "all_benchmarks", "run_benchmarks", "time_call_ms"]

ONE_THREAD = {
    name: "1"
    for name in (
        "OMP_NUM_THREADS",
        "OPENBLAS_NUM_THREADS",
        "MKL_NUM_THREADS",
        "BLIS_NUM_THREADS",
        "NUMEXPR_NUM_THREADS",
        "VECLIB_MAXIMUM_THREADS",
    )
}


def bench_basic_settings() -> tuple[float, dict]:
    """Cyclo-palloid basic settings of the seed 001 Table 3 design (both members)."""

    text = _study_text("seed001_table3.toml")
    design = loads_design(text)
    model = get_machine_model(design.model)
    model.basic_settings(design)  # warm-up
    return time_call_ms(lambda: model.basic_settings(design), number=200), {
        "design": "seed001_table3"
    }


def bench_flank_generation() -> tuple[float, dict]:
    """Both flanks of the seed 001 Table 3 pinion (the member whose envelope folds) on the
    default FlankMap grid, settings included; one warm-up run first. Each timed call generates
    a design not generated before (its additional slope angle 1e-6 deg apart): a model may
    remember its last generations, and a repeated design would time the memory (it read
    0.2 ms)."""

    base = loads_design(_study_text("seed001_table3.toml"))
    key = "machine.pinion.additional_slope_angle_deg"
    slope = base.machine.pinion.additional_slope_angle_deg
    designs = iter([with_overrides(base, {key: slope + 1e-6 * k}) for k in range(1, 7)])
    model = get_machine_model(base.model)
    grid = FlankGrid()

    def run():
        model.generate_flanks(next(designs), member="pinion", grid=grid)

    run()
    return time_call_ms(run, number=5), {
        "flank_grid": list(grid.shape),
        "flank_member": "seed001_table3 pinion, both flanks",
    }


def bench_thickness_solve() -> tuple[float, dict]:
    """Additional slope angle of the seed 001 Table 3 pinion solved from its chordal thickness
    (eqs 39-48, "auto"), settings included. Each timed call solves a new thickness (0.1 um
    apart): the model remembers solved settings, and a repeated design would time the
    memory, not the solve (it read 0.018 ms)."""

    base = loads_design(_study_text("seed001_table3.toml"))
    base = with_overrides(base, {"machine.pinion.additional_slope_angle_deg": "auto"})
    thickness = base.pair.mean_normal_chordal_thickness_mm
    designs = [
        with_overrides(
            base,
            {"pair.mean_normal_chordal_thickness_mm": [thickness[0] + 1e-4 * k, thickness[1]]},
        )
        for k in range(1, 5)  # none the base's own thickness (checking it may solve it)
    ]
    model = get_machine_model(base.model)
    model.basic_settings(designs[0])  # warm-up
    todo = iter(designs[1:])
    return time_call_ms(lambda: model.basic_settings(next(todo)), number=3), {
        "thickness_member": "seed001_table3 pinion"
    }


def _meshed_section53():
    """The seed 001 section 5.3 pair (crowned: the textbook cross-check's case) generated on
    the contact analyses' grid, with the default options."""

    design = loads_design(_study_text("seed001_section5_3.toml"))
    options = AnalysisOptions()
    return meshed_pair(design, options), options


def _tca_info(options) -> dict:

    kernels = (
        f"numba {package_version('numba')}"
        if contact_kernels.ENABLED
        else "plain Python (GEAROPT_JIT=0)"
    )
    return {
        "tca_grid": list(options.grid.shape),
        "tca_kernels": kernels,
        "tca_case": (
            f"seed001_section5_3, {options.positions} positions x {options.pairs} pairs, "
            "drive and coast, flanks generated beforehand"
        ),
    }


def bench_tca() -> tuple[float, dict]:
    """Unloaded TCA of both sides (TE with solved hand-overs, contact path, pattern, contact
    ratio) of the section 5.3 pair, flanks generated beforehand; one warm-up run first."""

    pair, options = _meshed_section53()
    contact_sides(pair, options)
    return time_call_ms(lambda: contact_sides(pair, options), number=10), _tca_info(options)


def bench_backlash() -> tuple[float, dict]:
    """Backlash at the 21 drive positions of the section 5.3 pair (drive contact, then the
    other flanks), flanks generated beforehand."""

    pair, options = _meshed_section53()
    pair_backlash(pair, options)
    return time_call_ms(lambda: pair_backlash(pair, options), number=10), _tca_info(options)


def bench_tca_newton() -> tuple[float, dict]:
    """The textbook point-by-point TCA (5 equations per position, scipy.optimize.root with the
    analytic Jacobian, continuation) on the same case as ``tca_ms``: every relative angle the
    21 positions x 3 pairs visit (41 distinct ones) on both sides, nothing else (no hand-over,
    no pattern)."""

    pair, options = _meshed_section53()
    p1 = pair.drive.pinion.pitch_rad
    t = np.linspace(-0.5 * options.cycles * p1, 0.5 * options.cycles * p1, options.positions)
    offsets = np.arange(options.pairs) - (options.pairs - 1) // 2
    u = t[:, None] + (np.round(-t / p1)[:, None] + offsets[None, :]) * p1
    u = np.unique(np.round(u.ravel() / p1 * 1e9)) * p1 / 1e9
    centre = int(np.argmin(np.abs(u)))
    # continuation outward from the mean position, where the engine's guess is best
    halves = (u[centre:], u[: centre + 1][::-1])

    def run():
        for field in (pair.drive, pair.coast):
            for part in halves:
                newton_tca(field, part)

    run()
    info = _tca_info(options)
    info["tca_newton_positions"] = 2 * (len(u) + 1)
    return time_call_ms(run, number=3), info


def bench_ltca_setup() -> tuple[float, dict]:
    """The finite-element influence numbers of both members of the section 5.3 pair (tooth
    models, factorisation, both flanks' tables) at the default FE mesh: the loaded TCA's
    set-up, once per design."""

    pair, _ = _meshed_section53()
    flanks = member_flanks(pair)
    blank = loads_design(_study_text("seed001_section5_3.toml")).blank

    def run():
        for member in ("pinion", "gear"):
            member_compliance(dict(flanks[member]), blank, mesh=DEFAULT_MESH)

    return time_call_ms(run, number=1), {"ltca_fe_mesh": list(DEFAULT_MESH)}


def bench_ltca() -> tuple[float, dict]:
    """Loaded TCA of the drive side of the section 5.3 pair at one torque (50 N m) over the
    21 positions, after the set-up (tooth models built, unloaded TCA done)."""
    return _bench_loaded((50.0,))


#: the torques of ``ltca_sweep_ms`` (N m): seed 002's range
SWEEP_NM = (5.0, 50.0, 100.0, 200.0, 300.0, 400.0, 500.0, 600.0, 800.0, 1000.0)


def bench_ltca_sweep() -> tuple[float, dict]:
    """As ``ltca_ms`` at the 10 torques of :data:`SWEEP_NM` in one call."""
    return _bench_loaded(SWEEP_NM)


def _bench_loaded(torques_nm) -> tuple[float, dict]:
    design = loads_design(_study_text("seed001_section5_3.toml"))
    pair, options = _meshed_section53()
    sides = contact_sides(pair, options)
    load = LoadOptions(torque_nm=tuple(torques_nm))

    def run():
        pair_loaded_contact(design, pair, sides, load, which=("drive",))

    run()
    return time_call_ms(run, number=3), {
        "ltca_case": f"seed001_section5_3 drive, {list(torques_nm)} N m, 21 positions",
        "ltca_patches": list(load.patches),
    }


def bench_study_trial() -> tuple[float, dict]:
    """One trial of the example study as a worker evaluates it (the design with the trial's
    keys, both members generated, TCA aligned and misaligned, backlash, objectives, table rows),
    a different pinion each time (the unchanged gear's solved slope angle is remembered, as in
    a study's worker); every kernel warmed first, as a study's coordinator does before its
    workers start (a kernel a trial needs only now and then, as the recall of a re-centred
    window's node fields, would otherwise be loaded from the cache inside a timed trial), then
    one warm-up trial."""

    warm_kernels(announce=False)
    spec = load_study_spec(_study_path("cyclo_palloid_contact.toml"))
    params = dict(spec.enqueue[0])
    key = "machine.pinion.inner_cutter_radius_mm"
    radii = iter([74.5, 74.6, 74.7, 74.8, 74.9, 75.1])

    def run():
        outcome = evaluate_trial(spec, 0, {**params, key: next(radii)})
        if outcome.failed:
            raise RuntimeError(outcome.error)

    run()
    return time_call_ms(run, number=5), {
        "study_trial_case": "studies/cyclo_palloid_contact.toml, grid 25 x 21, 3 evaluations"
    }


def _study_path(name: str):
    """``studies/<name>`` of the source checkout, or a NotAvailableError."""

    path = Path(__file__).resolve().parents[1] / "studies" / name
    if not path.exists():
        raise NotAvailableError("benchmark design", str(path), "needs a source checkout (studies/)")
    return path


def _study_text(name: str) -> str:
    return _study_path(name).read_text()


#: the framework's own benchmarks, in the order ``gearopt bench`` runs them (then the plugins')
CORE_BENCHMARKS: tuple[Benchmark, ...] = tuple(
    Benchmark(name=name, function=function, description=(function.__doc__ or "").split("\n")[0])
    for name, function in (
        ("basic_settings_ms", bench_basic_settings),
        ("flank_generation_ms", bench_flank_generation),
        ("thickness_solve_ms", bench_thickness_solve),
        ("tca_ms", bench_tca),
        ("backlash_ms", bench_backlash),
        ("tca_newton_ms", bench_tca_newton),
        ("study_trial_ms", bench_study_trial),
        ("ltca_setup_ms", bench_ltca_setup),
        ("ltca_ms", bench_ltca),
        ("ltca_sweep_ms", bench_ltca_sweep),
    )
)


def all_benchmarks(plugin_manager: pluggy.PluginManager | None = None) -> dict[str, Benchmark]:
    """The core's benchmarks, then every plugin's (``gearopt_benchmarks``), by name.

    Raises :class:`PluginError` when a plugin's benchmark takes a core benchmark's name (two
    plugins' are refused by the registry).
    """
    found = {b.name: b for b in CORE_BENCHMARKS}
    entries = {e.name: e for e in list_plugins(plugin_manager, "benchmark")}
    for name, entry in sorted(entries.items()):
        if name in found:
            raise PluginError(
                f"benchmark name {name!r}",
                rule=f"provided by both the core (gearopt.bench) and plugin {entry.plugin!r}",
            )
        found[name] = entry.obj
    return found


def _run_one(target: str) -> None:
    """Run a benchmark once, given as ``module:qualified.name`` of its function (or by its
    name); print its JSON record."""
    if ":" not in target:
        target = all_benchmarks()[target].target
    module, qualname = target.split(":")
    function = import_module(module)
    for part in qualname.split("."):
        function = getattr(function, part)
    ms, info = function()
    print(json.dumps({"ms": float(ms), "cpu_ms": getattr(ms, "cpu_ms", None), "info": info}))


def run_benchmarks(names: Iterable[str] | None = None, *, repeats: int = 5) -> dict[str, dict]:
    """Run benchmarks, each ``repeats`` times in fresh one-thread processes; report medians.

    Returns ``{name: {"median_ms", "runs_ms", "median_cpu_ms", "runs_cpu_ms", "info"}}``: the
    wall times and the process CPU times of the timed calls (:class:`gearopt.commands.CallTime`;
    the CPU ones None for a benchmark that times itself without
    :func:`gearopt.commands.time_call_ms`).
    """
    known = all_benchmarks()
    names = list(names or known)
    env = {**os.environ, **ONE_THREAD}
    results = {}
    for name in names:
        if name not in known:
            raise GearoptError("benchmark", name, f"unknown; known: {sorted(known)}")
        runs, cpu, info = [], [], {}
        for _ in range(repeats):
            out = subprocess.run(
                [sys.executable, "-m", "gearopt.bench", known[name].target],
                env=env,
                capture_output=True,
                text=True,
                check=True,
            )
            record = json.loads(out.stdout.strip().splitlines()[-1])
            runs.append(record["ms"])
            cpu.append(record.get("cpu_ms"))
            info = record["info"]
        timed = None not in cpu
        results[name] = {
            "median_ms": statistics.median(runs),
            "runs_ms": runs,
            "median_cpu_ms": statistics.median(cpu) if timed else None,
            "runs_cpu_ms": cpu if timed else None,
            "info": info,
        }
    return results


if __name__ == "__main__":
    _run_one(sys.argv[1])
