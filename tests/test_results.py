"""The gearopt tables (:mod:`gearopt.results`): a trial's rows, inserted through the driver's
``executemany`` in the driver's own parameter style, read back as written, whether the driver
takes positional parameters (SQLite's ``?``) or named ones (as psycopg does; SQLite's
``:name`` here, where no PostgreSQL server runs)."""

from __future__ import annotations

import pytest
import sqlalchemy as sa

from gearopt.results import TABLES, ResultsStore
from gearopt.trial import TrialOutcome


@pytest.mark.parametrize("paramstyle", ["qmark", "named"])
def test_a_trials_rows_read_back_as_written(tmp_path, paramstyle):
    url = f"sqlite:///{tmp_path / 'results.db'}"
    engine = sa.create_engine(url, paramstyle=paramstyle)
    store = ResultsStore(url, engine=engine)
    outcome = TrialOutcome(
        number=7,
        values=(1.5, 0.25),
        constraints={"window_um": -3.0},
        metrics=[("tca", "te_arcsec", 12.5), ("tca", "ratio", 1.75)],
        curves=[("tca", "te", "drive", i, 0.1 * i, (0.1 * i) ** 2) for i in range(5)],
        patterns=[("tca", "drive", i, float(i), -float(i)) for i in range(4)],
        settings=[("pinion", "radius_mm", 75.0)],
        seconds=0.5,
        pid=123,
    )
    labels = {"te": "objective", "movement": "objective", "window_um": "constraint"}
    store.write("s", outcome, attempt=2, coordinator="c", labels=labels)
    store.write("s", outcome, attempt=3, coordinator="c", labels=labels)  # replaced, not added
    with engine.connect() as con:
        rows = {t.name: con.execute(sa.select(t).order_by(*t.primary_key)).all() for t in TABLES}
    assert [tuple(r) for r in rows["gearopt_trials"]] == [("s", 7, 3, 0.5, 123, "c")]
    assert [tuple(r)[2:] for r in rows["gearopt_curves"]] == sorted(outcome.curves)
    assert [tuple(r)[2:] for r in rows["gearopt_patterns"]] == sorted(outcome.patterns)
    assert [tuple(r)[2:] for r in rows["gearopt_metrics"]] == sorted(outcome.metrics)
    assert [tuple(r)[2:] for r in rows["gearopt_settings"]] == outcome.settings
    assert sorted(tuple(r)[2:] for r in rows["gearopt_objectives"]) == [
        ("movement", "objective", 0.25),
        ("te", "objective", 1.5),
        ("window_um", "constraint", -3.0),
    ]
    engine.dispose()
