"""Export a study for analysis elsewhere: Optuna's trials and the gearopt tables via pandas."""

from __future__ import annotations

from pathlib import Path

import pandas as pd
import sqlalchemy as sa

from gearopt.errors import NotAvailableError, StudyError
from gearopt.results import TABLES, VIEWS
from gearopt.storage import study_exists
from gearopt.study import open_study
from gearopt.studyfile import StudySpec

__all__ = ["export_study"]


def export_study(
    spec: StudySpec,
    out: Path,
    *,
    fmt: str = "csv",
    storage: str | None = None,
    force: bool = False,
) -> list[str]:
    """Write ``trials`` (Optuna's trials dataframe) and every gearopt table and view of the
    study, one file each, into ``out``; returns the paths written. Only new regular files
    are written (``force``: existing regular files are replaced), never through a symbolic
    link; a study that the storage does not hold is refused, and nothing is created for it."""
    if fmt not in ("csv", "parquet"):
        raise StudyError("--format", fmt, "must be csv or parquet")
    if fmt == "parquet":
        try:
            import pyarrow  # noqa: F401
        except ImportError:
            raise NotAvailableError(
                "--format", fmt, "needs pyarrow: pip install 'gearopt[parquet]'"
            ) from None
    names = ["trials"] + [t.name for t in TABLES] + list(VIEWS)
    targets = {name: out / f"{spec.name}_{name}.{fmt}" for name in names}
    _check_targets(out, targets.values(), force)
    if not study_exists(spec, storage):
        raise StudyError(
            "study", spec.name, "is not in the storage: run it first (export creates nothing)"
        )
    study, results = open_study(spec, storage)
    frames = {"trials": study.trials_dataframe()}
    with results.engine.connect() as con:
        for name in names[1:]:
            frames[name] = pd.read_sql(
                sa.text(f"SELECT * FROM {name} WHERE study = :s"), con, params={"s": spec.name}
            )
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise StudyError("--out", str(out), f"cannot be created ({exc})") from None
    written = []
    for name, frame in frames.items():
        path = targets[name]
        if path.exists() and force:
            path.unlink()
        try:  # exclusive creation: no file that appeared meanwhile, no link followed
            with open(path, "xb") as handle:
                if fmt == "csv":
                    frame.to_csv(handle, index=False)
                else:
                    frame.to_parquet(handle, index=False)
        except FileExistsError:
            raise StudyError("--out", str(path), "appeared while exporting: not replaced") from None
        written.append(str(path))
    return written


def _check_targets(out: Path, targets, force: bool) -> None:
    """The output folder and files: no symbolic link; existing files only with ``force``."""
    if out.is_symlink() or (out.exists() and not out.is_dir()):
        raise StudyError("--out", str(out), "must be a folder (not a link or a file)")
    for path in targets:
        if path.is_symlink():
            raise StudyError("--out", str(path), "is a symbolic link: never written through")
        if path.exists() and not (force and path.is_file()):
            rule = "is not a regular file" if force else "exists (--force replaces it)"
            raise StudyError("--out", str(path), rule)
