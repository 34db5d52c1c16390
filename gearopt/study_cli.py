"""``gearopt study run | enqueue | export``: the study commands of the ``gearopt`` CLI."""

from __future__ import annotations

import argparse
import json
import signal
import sys
import tomllib
from pathlib import Path

from gearopt.errors import StudyError
from gearopt.studyfile import load_study_spec

__all__ = ["add_study_parser"]


def _parse_assignment(text: str) -> tuple[str, float]:
    key, sep, value = text.partition("=")
    if not sep or not key.strip():
        example = "machine.pinion.inner_cutter_radius_mm=75"
        raise StudyError("enqueue", text, f"write KEY=VALUE, e.g. {example}")
    try:
        parsed = tomllib.loads(f"v = {value.strip()}")["v"]
    except tomllib.TOMLDecodeError:
        raise StudyError(f"enqueue.{key.strip()}", value, "is not a number") from None
    return key.strip(), parsed


def _interrupt(signum, frame) -> None:
    raise KeyboardInterrupt


def _cmd_run(args: argparse.Namespace) -> int:
    from gearopt.study import constraint_values, run_study

    spec = load_study_spec(args.study)
    for dim in spec.search:  # what a catalogue search kept of the catalogue, and why
        if dim.note:
            print(f"gearopt: search {dim.key}: {dim.note}", file=sys.stderr)
    # a polite stop (a scheduler's SIGTERM) is a Ctrl-C: the trials in hand go back to the queue
    signal.signal(signal.SIGTERM, _interrupt)
    try:
        summary = run_study(
            spec,
            trials=args.trials,
            jobs=args.jobs,
            storage=args.storage,
            deterministic=args.deterministic,
            progress=not args.no_progress,
            backend=args.backend,
            scheduler=args.scheduler,
        )
    except KeyboardInterrupt:
        print("gearopt: stopped; the trials in hand are back in the queue", file=sys.stderr)
        return 130
    best = summary.best
    report = {
        "study": summary.study,
        "storage": summary.storage,
        "complete": summary.complete,
        "evaluated_this_run": summary.evaluated_this_run,
        "failed_this_run": summary.failed_this_run,
        "recovered": summary.recovered,
        "wall_s": round(summary.wall_s, 3),
        "kernels_s": round(summary.kernels_s, 3),
        "trials_per_s": round(summary.trials_per_s, 4),
        "worker_efficiency": round(summary.worker_efficiency, 4),
        "coordinator_ms_per_trial": round(summary.coordinator_ms_per_trial, 2),
        "coordinator_cpu_ms_per_trial": round(summary.coordinator_cpu_ms_per_trial, 2),
        "ask_tell_cpu_ms_per_trial": round(summary.ask_tell_cpu_ms_per_trial, 2),
        "best": None
        if best is None
        else {
            "trial": best.number,
            "values": dict(zip(spec.metric_names, best.values, strict=True)),
            "constraints": constraint_values(spec, best),
            "params": best.params,
            "design": summary.best_design_path,
        },
    }
    if args.json:
        print(json.dumps(report, indent=2))
        return 0
    print(
        f"study {summary.study}: {summary.complete} complete trials in {summary.storage}\n"
        f"this run: {summary.evaluated_this_run} evaluated ({summary.failed_this_run} failed) "
        f"in {summary.wall_s:.1f} s ({summary.kernels_s:.1f} s of it the compiled kernels), "
        f"{summary.trials_per_s:.2f} trials/s on {summary.jobs} "
        f"jobs, worker efficiency {summary.worker_efficiency:.0%}, coordinator "
        f"{summary.coordinator_ms_per_trial:.0f} ms/trial"
    )
    if best is None:
        print("no feasible trial yet")
        return 0
    print(f"best trial {best.number} (feasible, rule {spec.pick!r}):")
    for name, value in zip(spec.metric_names, best.values, strict=True):
        print(f"  {name} = {value:.6g}")
    for name, value in constraint_values(spec, best).items():
        print(f"  {name} = {value:.6g} (constraint, feasible <= 0)")
    for key, value in best.params.items():
        print(f"  {key} = {value:.6g}")
    print(f"design saved as {summary.best_design_path}")
    return 0


def _cmd_enqueue(args: argparse.Namespace) -> int:
    from gearopt.study import enqueue

    spec = load_study_spec(args.study)
    params = dict(_parse_assignment(a) for a in args.assignments)
    if not params:
        raise StudyError("enqueue", args.assignments, "give at least one KEY=VALUE")
    enqueue(spec, params, args.storage)
    print(f"enqueued {params} in study {spec.name}")
    return 0


def _cmd_export(args: argparse.Namespace) -> int:
    from gearopt.export import export_study

    spec = load_study_spec(args.study)
    written = export_study(
        spec, Path(args.out), fmt=args.format, storage=args.storage, force=args.force
    )
    for path in written:
        print(path)
    return 0


def add_study_parser(sub) -> None:
    """Add ``gearopt study ...`` to the CLI's subparsers."""
    study = sub.add_parser("study", help="Optuna studies: run, enqueue given designs, export")
    commands = study.add_subparsers(dest="study_command", required=True)
    storage_help = "SQLAlchemy storage URL (default sqlite:///<study name>.db beside the file)"

    p = commands.add_parser("run", help="run a study until it holds N COMPLETE trials")
    p.add_argument("study", help="study TOML file")
    p.add_argument("--trials", type=int, default=48, help="COMPLETE trials at the end (48)")
    p.add_argument("--jobs", type=int, default=2, help="worker processes (2)")
    p.add_argument("--storage", help=storage_help)
    p.add_argument(
        "--deterministic",
        action="store_true",
        help="synchronous batches of JOBS trials told in order (reproducible with a seed)",
    )
    p.add_argument(
        "--backend",
        choices=("loky", "dask"),
        default="loky",
        help="worker pool: local processes (loky) or a Dask cluster through joblib's dask backend",
    )
    p.add_argument("--scheduler", help="Dask scheduler address (default: a local cluster)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.add_argument("--json", action="store_true", help="print the summary as JSON")
    p.set_defaults(func=_cmd_run)

    p = commands.add_parser("enqueue", help="put a given design at the head of the queue")
    p.add_argument("study", help="study TOML file")
    p.add_argument("assignments", nargs="*", metavar="KEY=VALUE", help="searched design keys")
    p.add_argument("--storage", help=storage_help)
    p.set_defaults(func=_cmd_enqueue)

    p = commands.add_parser("export", help="write the study's tables as CSV or Parquet")
    p.add_argument("study", help="study TOML file")
    p.add_argument("--format", choices=("csv", "parquet"), default="csv")
    p.add_argument("--out", required=True, help="output folder")
    p.add_argument("--force", action="store_true", help="replace existing files")
    p.add_argument("--storage", help=storage_help)
    p.set_defaults(func=_cmd_export)
