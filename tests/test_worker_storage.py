"""A supervised worker's view of the storage (:class:`gearopt.storage.WorkerStorage`): inside a
hold its reads of the study are served by one read of the database, with its own trials kept
in memory, and give what the database holds; the designs TPE suggests on it are the designs it
suggests on Optuna's own cached storage."""

from __future__ import annotations

import os

import optuna
import pytest
import sqlalchemy as sa
from optuna.trial import TrialState

from gearopt.storage import WorkerStorage, fast_sqlite, one_writer


def _sampler() -> optuna.samplers.TPESampler:
    return optuna.samplers.TPESampler(
        seed=3, multivariate=True, constant_liar=True, n_startup_trials=3
    )


def _seen(trials) -> list[tuple]:
    """What a sampler reads of each trial (the dates are the database's own clock)."""
    return [
        (t.number, t.state, t.values, t.params, t.distributions, t.user_attrs, t.system_attrs)
        for t in trials
    ]


def _run(storage, url: str, name: str, reads: list | None = None) -> list[tuple]:
    """Eight trials asked, suggested and told in holds (when ``storage`` has them), a given
    design popped from the queue first and another process's trial running from the fourth;
    inside each hold the trials read are compared with a fresh read of the database."""
    study = optuna.create_study(
        storage=storage, sampler=_sampler(), study_name=name, directions=["minimize"] * 2
    )
    study.enqueue_trial({"x": 0.25, "y": 2.0})
    other = optuna.load_study(
        study_name=name, storage=url, sampler=optuna.samplers.RandomSampler(seed=5)
    )
    database = optuna.storages.RDBStorage(url, skip_compatibility_check=True)
    study_id = database.get_study_id_from_name(name)
    hold = storage.hold if isinstance(storage, WorkerStorage) else None
    for i in range(8):
        if i == 4:  # another worker's trial, running while this one asks
            other.ask().suggest_float("x", 0.0, 1.0)
        with hold() if hold else _nothing():
            before = len(reads) if reads is not None else 0
            trial = study.ask()
            x = trial.suggest_float("x", 0.0, 1.0)
            y = trial.suggest_float("y", 1.0, 3.0, log=True)
            trial.set_user_attr("tag", ("worker", i))
            held = study.get_trials(deepcopy=False)
            assert _seen(held) == _seen(database.get_all_trials(study_id, deepcopy=False))
            if reads is not None:  # one read of the study's trials in the whole ask
                assert len(reads) - before == 1
        with hold() if hold else _nothing():
            trial_id = trial.storage.get_trial_id_from_study_id_trial_number(study_id, trial.number)
            trial.storage.set_trial_system_attr(trial_id, "constraints", [x - 0.5])
            study.tell(trial, [x * y, (x - 0.3) ** 2])
    database.engine.dispose()
    return _seen(study.get_trials(deepcopy=False))


class _nothing:
    def __enter__(self):
        return self

    def __exit__(self, *exc):
        return False


def test_a_workers_holds_read_the_study_once_and_see_what_the_database_holds(tmp_path):
    url = f"sqlite:///{tmp_path / 'worker.db'}"
    rdb = optuna.storages.RDBStorage(url)
    reads: list[str] = []

    @sa.event.listens_for(rdb.engine, "before_cursor_execute")
    def _count(conn, cursor, statement, *args):
        if "FROM trials " in statement and "ORDER BY trials.trial_id" in statement:
            reads.append(statement)

    held = _run(WorkerStorage(rdb), url, "held", reads)
    plain = _run(optuna.storages.RDBStorage(url), url, "plain")
    # the same trials, parameters and values as on Optuna's own cached storage
    assert [t[1:] for t in held] == [t[1:] for t in plain]
    assert sum(t[1] == TrialState.COMPLETE for t in held) == 8
    rdb.engine.dispose()


def _locked_elsewhere(path) -> bool:
    """Whether another open file (another process's, as the kernel sees it) holds ``path``'s
    exclusive ``flock``."""
    fcntl = pytest.importorskip("fcntl")
    fd = os.open(path, os.O_RDWR | os.O_CREAT)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        return True
    finally:
        os.close(fd)
    return False


def test_one_writer_holds_the_lock_from_the_first_write_to_the_connections_return(tmp_path):
    """A write transaction of an engine under :func:`gearopt.storage.one_writer` holds the run's
    lock file from its first INSERT, UPDATE or DELETE until its connection goes back to the
    pool (after the commit), so the workers of a run write in turn; reads take no lock."""
    pytest.importorskip("fcntl")
    url = f"sqlite:///{tmp_path / 'w.db'}"
    lock = tmp_path / "writes.lock"
    engine = sa.create_engine(url)
    fast_sqlite(engine)
    one_writer(engine, str(lock))
    with engine.begin() as con:
        con.execute(sa.text("CREATE TABLE t (x INTEGER)"))
    assert not _locked_elsewhere(lock)  # (no write statement: no lock)
    with engine.connect() as con:
        con.execute(sa.text("SELECT count(*) FROM t")).scalar()
        assert not _locked_elsewhere(lock)  # a read takes none
        con.execute(sa.text("INSERT INTO t VALUES (1)"))
        assert _locked_elsewhere(lock)
        con.execute(sa.text("UPDATE t SET x = 2"))
        con.commit()
        assert _locked_elsewhere(lock)  # until the connection is back in the pool
    assert not _locked_elsewhere(lock)
    with pytest.raises(sa.exc.IntegrityError), engine.begin() as con:
        con.execute(sa.text("CREATE UNIQUE INDEX u ON t (x)"))
        con.execute(sa.text("INSERT INTO t VALUES (2)"))  # a failed write gives it back too
    assert not _locked_elsewhere(lock)
    with engine.connect() as con:
        assert con.execute(sa.text("SELECT x FROM t")).scalars().all() == [2]
    engine.dispose()
