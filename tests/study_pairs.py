"""Pairs of coordinators starting together on fresh SQLite files (issue 27), cheaply.

``python tests/study_pairs.py FOLDER PAIRS TRIALS``, with the toy plugin importable: imports
gearopt once, then for each pair forks two processes that meet at a barrier and run the toy
study's coordinator (:class:`gearopt.study.Coordinator`, evaluating in its own process, as a
supervised worker does) on ``FOLDER/pairK/toy_probe.db``, a file neither has seen. Prints one
JSON line per pair: the coordinators' exit codes and their last error lines.
"""

from __future__ import annotations

import json
import multiprocessing as mp
import os
import shutil
import sys
import traceback
from pathlib import Path

from gearopt.storage import check_own_tables, create_sqlite
from gearopt.study import Coordinator
from gearopt.studyfile import load_study_spec

STUDY = """
[study]
name = "toy_probe"
design = "toy_design.toml"
sampler = "tpe"
seed = 11

[search]
"machine.tool_tip_width_mm" = [0.8, 1.6]

[evaluations.toy-probe]

[[objectives]]
name = "toy-probe"
label = "probe"
"""


def _coordinator(study: Path, trials: int, barrier, errors) -> None:
    try:
        spec = load_study_spec(study)
        barrier.wait(timeout=60)
        coordinator = Coordinator(
            spec,
            trials=trials,
            jobs=1,
            storage=None,
            deterministic=False,
            progress=False,
            max_failures=None,
            backend="inline",
            scheduler=None,
        )
        coordinator.run(save_best=False)
    except BaseException:  # noqa: BLE001 - reported to the test
        errors.put(traceback.format_exc()[-2000:])
        os._exit(1)
    os._exit(0)


def main(folder: Path, pairs: int, trials: int) -> None:
    import gearopt_toy
    from gearopt.warmup import warm_kernels

    warm_kernels(announce=False)  # loaded once here, not in every coordinator
    warm = f"sqlite:///{folder / 'warm.db'}"
    create_sqlite(warm)
    check_own_tables(warm)  # Optuna's table names, read once here likewise
    design = Path(gearopt_toy.__file__).with_name("toy_design.toml")
    context = mp.get_context("fork")
    for k in range(pairs):
        pair = folder / f"pair{k}"
        pair.mkdir(parents=True)
        shutil.copy(design, pair / "toy_design.toml")
        study = pair / "toy_probe.toml"
        study.write_text(STUDY)
        barrier, errors = context.Barrier(2), context.Queue()
        procs = [
            context.Process(target=_coordinator, args=(study, trials, barrier, errors))
            for _ in range(2)
        ]
        for proc in procs:
            proc.start()
        for proc in procs:
            proc.join(120)
        said = []
        while not errors.empty():
            said.append(errors.get())
        codes = [proc.exitcode for proc in procs]
        db = str(pair / "toy_probe.db")
        print(json.dumps({"pair": k, "db": db, "codes": codes, "errors": said}))
        sys.stdout.flush()


if __name__ == "__main__":
    main(Path(sys.argv[1]), int(sys.argv[2]), int(sys.argv[3]))
