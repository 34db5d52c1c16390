"""Export a study for analysis elsewhere: Optuna's trials and the gearopt tables via pandas."""

from __future__ import annotations

from pathlib import Path

import pandas as pd
import sqlalchemy as sa

from gearopt.errors import NotAvailableError, StudyError
from gearopt.results import TABLES, VIEWS
from gearopt.study import open_study
from gearopt.studyfile import StudySpec

__all__ = ["export_study"]


def export_study(
    spec: StudySpec, out: Path, *, fmt: str = "csv", storage: str | None = None
) -> list[str]:
    """Write ``trials`` (Optuna's trials dataframe) and every gearopt table and view of the
    study, one file each, into ``out``; returns the paths written."""
    if fmt not in ("csv", "parquet"):
        raise StudyError("--format", fmt, "must be csv or parquet")
    if fmt == "parquet":
        try:
            import pyarrow  # noqa: F401
        except ImportError:
            raise NotAvailableError(
                "--format", fmt, "needs pyarrow: pip install 'gearopt[parquet]'"
            ) from None
    study, results = open_study(spec, storage)
    frames = {"trials": study.trials_dataframe()}
    with results.engine.connect() as con:
        for name in [t.name for t in TABLES] + list(VIEWS):
            frames[name] = pd.read_sql(
                sa.text(f"SELECT * FROM {name} WHERE study = :s"), con, params={"s": spec.name}
            )
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise StudyError("--out", str(out), f"cannot be created ({exc})") from None
    written = []
    for name, frame in frames.items():
        path = out / f"{spec.name}_{name}.{fmt}"
        if fmt == "csv":
            frame.to_csv(path, index=False)
        else:
            frame.to_parquet(path, index=False)
        written.append(str(path))
    return written
