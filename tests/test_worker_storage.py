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

from gearopt.drafts import ask_drafted
from gearopt.storage import DRAFT_ID, WorkerStorage, fast_sqlite, one_writer, rdb_storage


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


def _run(storage, url: str, name: str, reads: list | None = None, fresh=None) -> list[tuple]:
    """Eight trials asked, suggested and told in holds (when ``storage`` has them), a given
    design popped from the queue first and another process's trial running from the fourth;
    inside each hold the trials read are compared with a fresh read of the database.
    ``fresh``: the asks that must read the study from the database (the others read nothing);
    None: each reads it once at most."""
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
            if reads is not None:  # one read of the study's trials in the whole ask at most
                if fresh is None:
                    assert len(reads) - before <= 1
                else:
                    assert len(reads) - before == (i in fresh), i
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


@pytest.mark.parametrize("pool", ["gearopt", "optuna"])
def test_a_workers_holds_read_the_study_once_and_see_what_the_database_holds(tmp_path, pool):
    """On gearopt's storage (its pool hands out one connection to a process using one at a
    time) a hold reads the study only when another connection has written since the last
    read: the first ask, and the ask after another process's trial; on a pool that hands out
    its connections in turn, every hold's own writes look like another's, and it reads."""
    url = f"sqlite:///{tmp_path / 'worker.db'}"
    rdb = rdb_storage(url) if pool == "gearopt" else optuna.storages.RDBStorage(url)
    reads: list[str] = []

    @sa.event.listens_for(rdb.engine, "before_cursor_execute")
    def _count(conn, cursor, statement, *args):
        if "FROM trials " in statement and "ORDER BY trials.trial_id" in statement:
            reads.append(statement)

    held = _run(WorkerStorage(rdb), url, "held", reads, {0, 4} if pool == "gearopt" else None)
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


#: the study file's parameters in its order (a single-valued one draws nothing)
SPACE = [
    ("x", optuna.distributions.FloatDistribution(0.0, 1.0)),
    ("y", optuna.distributions.FloatDistribution(1.0, 3.0, log=True)),
    ("z", optuna.distributions.FloatDistribution(2.0, 2.0)),
]


def _asked(url: str, name: str, *, drafted: bool, sampler=None) -> tuple[list[tuple], list[int]]:
    """Eight trials asked (Optuna's ``Study.ask`` and a ``suggest`` per parameter, or
    :func:`gearopt.drafts.ask_drafted` on a worker's view), tagged and told, as the database
    holds them; and the write transactions of each drafted ask."""
    rdb = optuna.storages.RDBStorage(url)
    writes: list[int] = []
    wrote: list[bool] = []

    @sa.event.listens_for(rdb.engine, "before_cursor_execute")
    def _write(conn, cursor, statement, *args):
        if statement.lstrip()[:6].upper() in ("INSERT", "UPDATE"):
            wrote.append(True)

    @sa.event.listens_for(rdb.engine, "commit")
    def _commit(conn):
        if wrote:
            writes.append(1)
            wrote.clear()

    view = WorkerStorage(rdb)
    study = optuna.create_study(
        storage=view if drafted else rdb,
        sampler=sampler or _sampler(),
        study_name=name,
        directions=["minimize"] * 2,
    )
    study_id = rdb.get_study_id_from_name(name)
    asks = []
    for i in range(8):
        if drafted:
            with view.hold():
                before = len(writes)
                trial_id, number = ask_drafted(study, view, study_id, SPACE, {"tag": ["w", i]})
                view.write_params(trial_id)
                asks.append(len(writes) - before)
                trial = optuna.Trial(study, trial_id)
                assert trial.number == number
                assert trial_id == view.get_trial_id_from_study_id_trial_number(study_id, number)
            x, y = trial.params["x"], trial.params["y"]
        else:
            trial = study.ask()
            x, y, _ = (trial.suggest_float(n, d.low, d.high, log=d.log) for n, d in SPACE)
            trial.set_user_attr("tag", ["w", i])
        study.tell(trial, [x * y, (x - 0.3) ** 2])
    trials = rdb.get_all_trials(study_id, deepcopy=False)
    rdb.engine.dispose()
    return _seen(trials), asks


def test_a_drafted_ask_writes_the_trial_optuna_asks(tmp_path):
    """The same seed gives the same trials (parameters, TPE's relative parameters shared for
    the constant liar, user attributes, values) whether asked through Optuna's ``Study.ask``
    and ``suggest`` or drafted and then written, and a drafted ask writes its trial with its
    attributes at once."""
    plain, _ = _asked(f"sqlite:///{tmp_path / 'plain.db'}", "s", drafted=False)
    drafted, asks = _asked(f"sqlite:///{tmp_path / 'drafted.db'}", "s", drafted=True)
    assert drafted == plain
    assert len(plain) == 8 and all(t[1] == TrialState.COMPLETE for t in plain)
    # past TPE's start-up trials the sampler's relative parameters went with the trial
    assert any(k.startswith("tpe:relative_params") for k in plain[-1][-1])
    # the trial with its attributes, then a write per parameter (Optuna's ask also writes
    # each attribute on its own: the coordinator's tag, and TPE's relative parameters)
    assert asks == [1 + len(SPACE)] * 8


#: the study file's other samplers (gearopt.samplers): NSGA-II with a population of four, so
#: that its second generation (parents, crossover) is drawn within the eight trials
OTHER_SAMPLERS = {
    "random": lambda: optuna.samplers.RandomSampler(seed=3),
    "nsga2": lambda: optuna.samplers.NSGAIISampler(seed=3, population_size=4),
    "qmc": lambda: optuna.samplers.QMCSampler(seed=3),
}


@pytest.mark.filterwarnings("ignore::optuna.exceptions.ExperimentalWarning")
@pytest.mark.parametrize("name", sorted(OTHER_SAMPLERS))
def test_a_drafted_ask_gives_the_other_samplers_trials(tmp_path, name):
    """Drafted, the study file's other samplers suggest what Optuna's ask gives them on one
    seed (their ``before_trial`` and study attributes included)."""
    make = OTHER_SAMPLERS[name]
    plain, _ = _asked(f"sqlite:///{tmp_path / 'p.db'}", "s", drafted=False, sampler=make())
    drafted, _ = _asked(f"sqlite:///{tmp_path / 'd.db'}", "s", drafted=True, sampler=make())
    assert len(plain) == 8 and drafted == plain


def test_a_draft_written_after_another_processs_trial_gets_its_own_number(tmp_path):
    """A draft carries the number its trial would have; when another process created a trial
    meanwhile the trial written gets the next number, and the worker's copy says so."""
    url = f"sqlite:///{tmp_path / 'd.db'}"
    rdb = optuna.storages.RDBStorage(url)
    view = WorkerStorage(rdb)
    study = optuna.create_study(storage=view, study_name="d")
    study_id = rdb.get_study_id_from_name("d")
    other = optuna.load_study(study_name="d", storage=url)
    with view.hold():
        draft = optuna.trial.FrozenTrial(
            number=len(study.get_trials(deepcopy=False)),
            state=TrialState.RUNNING,
            value=None,
            values=None,
            datetime_start=None,
            datetime_complete=None,
            params={"x": 0.5},
            distributions={"x": SPACE[0][1]},
            user_attrs={"tag": ("w", 0)},
            system_attrs={},
            intermediate_values={},
            trial_id=DRAFT_ID,
        )
        view.draft(draft)
        view.set_trial_system_attr(DRAFT_ID, "k", [1])  # a sampler's write: the draft's
        other.ask()  # another process's trial takes number 0
        trial_id, number = view.write_draft(study_id)
        assert view.get_trial(trial_id).params == {}  # (written next, unless given back)
        view.write_params(trial_id)
        mine = view.get_trial(trial_id)
    assert number == 1 == mine.number
    stored = rdb.get_trial(trial_id)
    assert _seen([stored]) == _seen([mine])
    assert stored.user_attrs == {"tag": ["w", 0]} and stored.system_attrs == {"k": [1]}
    rdb.engine.dispose()
