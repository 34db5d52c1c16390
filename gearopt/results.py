"""The gearopt tables: trial results for dashboards, in the study's own database.

Optuna's tables hold the trials, parameters and objective values (``optuna-dashboard`` reads
them). Beside them, in the same database, gearopt writes with SQLAlchemy what a dashboard needs
to draw a gear engineer's plots, keyed by study name and Optuna trial number:

``gearopt_trials``       one row per evaluated trial: attempt, seconds, worker pid, coordinator
``gearopt_metrics``      every metric the evaluators declare, long format (evaluation, metric,
                         value), named by its place in ``gearopt analyze --json``
                         (``tca_coast.te_peak_to_peak_arcsec``; :mod:`gearopt.declarations`)
``gearopt_objectives``   objective and constraint values by label (kind: objective/constraint)
``gearopt_settings``     the machine settings of each member (member, key, value)
``gearopt_curves``       the evaluators' declared curves: TE, contact path, backlash, ...
                         (evaluation, curve, side, idx, x, y)
``gearopt_patterns``     the declared contact-pattern outlines, closed polygons
                         (evaluation, side, idx, face_mm, profile_mm)
``gearopt_studies``      one row per study (the study file's search space as JSON)
``gearopt_coordinators`` the coordinators that ran a study, with their last heartbeat (UTC)

Views join them with Optuna's tables, COMPLETE trials only: ``gearopt_trial_params``
(study, trial_number, param, value) and ``gearopt_trial_metrics`` (study, trial_number,
evaluation, metric, value). Rows are written before the trial is told, and removed when a trial
is failed, so the views hold one row set per COMPLETE trial.
"""

from __future__ import annotations

import datetime as dt
import functools
import json
import tempfile
import time
from collections.abc import Iterable
from pathlib import Path

import sqlalchemy as sa
from optuna.artifacts import FileSystemArtifactStore, upload_artifact

from gearopt.studyfile import StudySpec
from gearopt.trial import TrialOutcome

__all__ = ["ResultsStore", "SCHEMA_NAMES", "TABLES", "VIEWS", "artifact_dir", "upload_figures"]

_meta = sa.MetaData()


def _keyed(name: str, *columns: sa.Column) -> sa.Table:
    return sa.Table(
        name,
        _meta,
        sa.Column("study", sa.String(256), primary_key=True),
        sa.Column("trial_number", sa.Integer, primary_key=True),
        *columns,
    )


_S = sa.String(128)
trials_t = _keyed(
    "gearopt_trials",
    sa.Column("attempt", sa.Integer, nullable=False),
    sa.Column("seconds", sa.Float, nullable=False),
    sa.Column("worker_pid", sa.Integer, nullable=False),
    sa.Column("coordinator", sa.String(64), nullable=False),
)
metrics_t = _keyed(
    "gearopt_metrics",
    sa.Column("evaluation", _S, primary_key=True),
    sa.Column("metric", _S, primary_key=True),
    sa.Column("value", sa.Float, nullable=False),
)
objectives_t = _keyed(
    "gearopt_objectives",
    sa.Column("label", _S, primary_key=True),
    sa.Column("kind", sa.String(16), nullable=False),
    sa.Column("value", sa.Float, nullable=False),
)
settings_t = _keyed(
    "gearopt_settings",
    sa.Column("member", sa.String(16), primary_key=True),
    sa.Column("key", _S, primary_key=True),
    sa.Column("value", sa.Float, nullable=False),
)
curves_t = _keyed(
    "gearopt_curves",
    sa.Column("evaluation", _S, primary_key=True),
    sa.Column("curve", sa.String(32), primary_key=True),
    sa.Column("side", sa.String(16), primary_key=True),
    sa.Column("idx", sa.Integer, primary_key=True),
    sa.Column("x", sa.Float, nullable=False),
    sa.Column("y", sa.Float, nullable=False),
)
patterns_t = _keyed(
    "gearopt_patterns",
    sa.Column("evaluation", _S, primary_key=True),
    sa.Column("side", sa.String(16), primary_key=True),
    sa.Column("idx", sa.Integer, primary_key=True),
    sa.Column("face_mm", sa.Float, nullable=False),
    sa.Column("profile_mm", sa.Float, nullable=False),
)
studies_t = sa.Table(
    "gearopt_studies",
    _meta,
    sa.Column("study", sa.String(256), primary_key=True),
    sa.Column("search", sa.Text, nullable=False),
    sa.Column("created_utc", sa.DateTime, nullable=False),
)
coordinators_t = sa.Table(
    "gearopt_coordinators",
    _meta,
    sa.Column("id", sa.String(64), primary_key=True),
    sa.Column("study", sa.String(256), nullable=False),
    sa.Column("host", sa.String(256), nullable=False),
    sa.Column("pid", sa.Integer, nullable=False),
    sa.Column("heartbeat_utc", sa.DateTime, nullable=False),
)

#: the per-trial tables, in the order rows are written
TABLES = (trials_t, metrics_t, objectives_t, settings_t, curves_t, patterns_t)

VIEWS = {
    "gearopt_trial_params": """
        SELECT s.study_name AS study, t.number AS trial_number, p.param_name AS param,
               p.param_value AS value
        FROM trials t JOIN studies s ON s.study_id = t.study_id
        JOIN trial_params p ON p.trial_id = t.trial_id
        WHERE t.state = 'COMPLETE'""",
    "gearopt_trial_metrics": """
        SELECT m.study, m.trial_number, m.evaluation, m.metric, m.value
        FROM gearopt_metrics m
        JOIN studies s ON s.study_name = m.study
        JOIN trials t ON t.study_id = s.study_id AND t.number = m.trial_number
        WHERE t.state = 'COMPLETE'""",
}

#: every table and view gearopt makes (its schema's names)
SCHEMA_NAMES = frozenset(_meta.tables) | frozenset(VIEWS)


def _rows(table: sa.Table, key: tuple, tuples) -> list[dict]:
    """Rows of a per-trial table as dicts from ``key`` (study, trial number) and tuples of its
    columns after ``study, trial_number``."""
    names = [c.name for c in table.columns]
    return [dict(zip(names, (*key, *row), strict=True)) for row in tuples]


@functools.cache
def _insert_sql(table: sa.Table, dialect: sa.engine.Dialect) -> tuple[str, bool]:
    """The insert of every column of ``table`` in ``dialect``, and whether its parameters are
    positional in the table's column order (False for a named paramstyle)."""
    compiled = table.insert().compile(dialect=dialect)
    order = compiled.positiontup
    return str(compiled), bool(order) and list(order) == [c.name for c in table.columns]


def _insert_params(dialect: sa.engine.Dialect, table: sa.Table, key: tuple, tuples: list):
    """The insert of a trial's rows of ``table`` (``key``: study and trial number, then
    ``tuples`` of the other columns in the table's order) and its parameters for the driver's
    ``executemany``: SQLAlchemy's per-row parameter handling cost more than SQLite's inserts
    (a trial's few hundred curve points). Positional drivers (SQLite's ``?``) are given the
    tuples as they are, named ones (psycopg's ``%(name)s``) dicts."""
    sql, positional = _insert_sql(table, dialect)
    if positional:
        return sql, [(*key, *row) for row in tuples]
    return sql, _rows(table, key, tuples)


def _utcnow() -> dt.datetime:
    return dt.datetime.now(dt.UTC).replace(tzinfo=None)


class ResultsStore:
    """The gearopt tables of one database (created on first use, next to Optuna's; ``create``
    False: known to be there, as for a study's supervised workers)."""

    def __init__(self, url: str, *, engine: sa.Engine | None = None, create: bool = True) -> None:
        self.engine = engine or sa.create_engine(url)
        if not create:
            return
        for attempt in range(5):  # another coordinator may be creating the same tables
            try:
                _meta.create_all(self.engine)
                break
            except sa.exc.DBAPIError:
                if attempt == 4:
                    raise
                time.sleep(0.3 * (attempt + 1))
        with self.engine.begin() as con:
            existing = set(sa.inspect(con).get_view_names())
            for name, body in VIEWS.items():
                if name not in existing:
                    try:
                        with con.begin_nested():
                            con.execute(sa.text(f"CREATE VIEW {name} AS {body}"))
                    except sa.exc.DBAPIError:  # another coordinator created it meanwhile
                        pass

    def register_study(self, study: str, search: dict) -> bool:
        """Record the study; True for the first coordinator ever to do so (it enqueues the
        study file's given designs), False when the study was known."""
        try:
            with self.engine.begin() as con:
                con.execute(
                    studies_t.insert().values(
                        study=study, search=json.dumps(search), created_utc=_utcnow()
                    )
                )
            return True
        except sa.exc.IntegrityError:
            return False

    def heartbeat(self, coordinator: str, study: str, host: str, pid: int) -> None:
        """Record that ``coordinator`` is alive now."""
        with self.engine.begin() as con:
            done = con.execute(
                coordinators_t.update()
                .where(coordinators_t.c.id == coordinator)
                .values(heartbeat_utc=_utcnow())
            ).rowcount
            if not done:
                con.execute(
                    coordinators_t.insert().values(
                        id=coordinator, study=study, host=host, pid=pid, heartbeat_utc=_utcnow()
                    )
                )

    def coordinators(self) -> dict[str, tuple[str, int, dt.datetime]]:
        """``{id: (host, pid, last heartbeat UTC)}``."""
        with self.engine.connect() as con:
            rows = con.execute(sa.select(coordinators_t)).all()
        return {r.id: (r.host, r.pid, r.heartbeat_utc) for r in rows}

    def write(
        self, study: str, outcome: TrialOutcome, *, attempt: int, coordinator: str, labels
    ) -> None:
        """Write a trial's rows in one transaction (``labels``: objective label -> kind)."""
        key = (study, outcome.number)
        # each table's rows as tuples of its columns after the key (the outcome's are so)
        rows = {
            trials_t: [(attempt, outcome.seconds, outcome.pid, coordinator)],
            objectives_t: [
                (label, kind, value)
                for (label, kind), value in zip(
                    labels.items(), [*outcome.values, *outcome.constraints.values()], strict=True
                )
            ],
            metrics_t: outcome.metrics,
            settings_t: outcome.settings,
            curves_t: outcome.curves,
            patterns_t: outcome.patterns,
        }
        # (made before the transaction, which holds the database's write lock from its first
        # insert: a worker of the run waiting to write waits the inserts alone)
        inserts = [_insert_params(self.engine.dialect, t, key, v) for t, v in rows.items() if v]
        try:
            with self.engine.begin() as con:
                for sql, params in inserts:  # (the trial's row first: it is there or not)
                    con.exec_driver_sql(sql, params)
        except sa.exc.IntegrityError:
            # rows of this trial written before (a tell that failed after them) are replaced;
            # the common case, none, costs no look
            with self.engine.begin() as con:
                self._delete(con, study, [outcome.number])
                for sql, params in inserts:
                    con.exec_driver_sql(sql, params)

    def forget(self, study: str, numbers: Iterable[int]) -> None:
        """Remove the rows of trials that were failed."""
        numbers = list(numbers)
        if numbers:
            with self.engine.begin() as con:
                self._delete(con, study, numbers)

    @staticmethod
    def _delete(con, study: str, numbers: list[int]) -> None:
        for table in TABLES:
            con.execute(
                table.delete().where(table.c.study == study, table.c.trial_number.in_(numbers))
            )


def artifact_dir(spec: StudySpec) -> Path:
    """Where a study's artifacts go: ``<study name>_artifacts`` beside the study file (give
    it to ``optuna-dashboard --artifact-dir``)."""
    return spec.folder / f"{spec.name}_artifacts"


def upload_figures(base: Path, trial, figures) -> None:
    """A trial's figures (``(name, PNG bytes)`` pairs) as Optuna artifacts in ``base``."""
    base.mkdir(parents=True, exist_ok=True)
    store = FileSystemArtifactStore(str(base))
    with tempfile.TemporaryDirectory() as folder:
        for name, data in figures:
            path = Path(folder, f"trial{trial.number}_{name}")
            path.write_bytes(data)
            upload_artifact(
                artifact_store=store,
                file_path=str(path),
                study_or_trial=trial,
                mimetype="image/png",
            )
