"""A study's storage: the database URL (its default, its password kept out of every message),
the checks before a study opens it (not SQLite in memory, a sound SQLite file, no one else's
tables), Optuna's RDB
storage made safe for coordinators starting together, SQLite tuned for many commits, and a
worker's view of the storage that reads the study once per trial at most
(:class:`WorkerStorage`)."""

from __future__ import annotations

import contextlib
import copy
import datetime as dt
import functools
import hashlib
import json
import os
import re
import sqlite3
import time
from pathlib import Path

try:
    import fcntl
except ImportError:  # (Windows: no file locks of this kind; SQLite's own waits remain)
    fcntl = None

import optuna
import sqlalchemy as sa
import sqlalchemy.exc

from gearopt.errors import StudyError
from gearopt.results import SCHEMA_NAMES, ResultsStore
from gearopt.studyfile import StudySpec

__all__ = [
    "DRAFT_ID",
    "WorkerStorage",
    "check_integrity",
    "check_own_tables",
    "check_storage_url",
    "create_sqlite",
    "data_version",
    "default_storage_url",
    "fast_sqlite",
    "held_reads",
    "masked_url",
    "one_writer",
    "rdb_storage",
    "release",
    "storage_error",
    "storage_tag",
    "study_exists",
]


def masked_url(url: str) -> str:
    """A storage URL fit to print: its password replaced by ``***`` (never echoed, in errors,
    summaries or ``--json``)."""
    try:
        return sa.engine.make_url(url).render_as_string(hide_password=True)
    except Exception:  # not a URL SQLAlchemy reads: mask what looks like user:password@
        return re.sub(r"(://[^:/@]*:)[^@]*@", r"\1***@", str(url))


def _masked_text(text: str, url: str) -> str:
    """``text`` with the URL's password, wherever it stands, replaced by ``***``."""
    try:
        password = sa.engine.make_url(url).password
    except Exception:
        password = None
    text = text.replace(url, masked_url(url))
    return text.replace(str(password), "***") if password else text


def storage_error(url: str, what: str, exc: Exception) -> StudyError:
    """The error of a storage that fails (``what``: "cannot be opened"), the driver's message
    and the URL with its password masked."""
    why = _masked_text(f"{what} ({type(exc).__name__}: {exc})", url)
    return StudyError("storage", masked_url(url), why)


def check_storage_url(url: str) -> None:
    """Refuse a storage that cannot hold a study: SQLite in memory (it vanishes with the
    coordinator, and workers and later runs never see it)."""
    try:
        parsed = sa.engine.make_url(url)
    except Exception:
        return  # the driver's own error says more
    if parsed.get_backend_name() == "sqlite" and parsed.database in (None, "", ":memory:"):
        raise StudyError(
            "storage",
            masked_url(url),
            "must be a database file or server: an in-memory SQLite database vanishes with "
            "the coordinator, and its results with it",
        )


def check_integrity(url: str) -> None:
    """Refuse a SQLite file that is not a sound database (a damaged page, a file that is not
    SQLite at all) before anything reads or writes it: SQLite's ``quick_check``, on a
    read-only connection. An empty (0-byte) file is refused too: gearopt never leaves one
    (:func:`create_sqlite` makes a new database whole), so it is someone else's (a file
    truncated, a name taken by mistake). Other dialects keep their own consistency."""
    try:
        parsed = sa.engine.make_url(url)
    except Exception:
        return
    if parsed.get_backend_name() != "sqlite" or not Path(parsed.database or "").is_file():
        return
    path = Path(parsed.database).resolve()
    if path.stat().st_size == 0:
        raise StudyError(
            "storage",
            masked_url(url),
            "is an empty file (0 bytes), not a database gearopt made, left untouched: "
            "remove it to start a new study there, or give another --storage",
        )
    try:
        con = sqlite3.connect(f"{path.as_uri()}?mode=ro", uri=True, timeout=30.0)
    except sqlite3.Error as exc:
        raise storage_error(url, "cannot be opened", exc) from None
    try:
        rows = [" ".join(row[0].split()) for row in con.execute("PRAGMA quick_check")]
    except sqlite3.DatabaseError as exc:
        rows = [str(exc)]
    finally:
        con.close()
    if rows != ["ok"]:
        raise StudyError(
            "storage",
            masked_url(url),
            f"is a damaged SQLite database, left untouched (SQLite's check: {rows[0]}"
            f"{f'; {len(rows) - 1} more problems' if len(rows) > 1 else ''}): restore it from "
            "a copy, or give another --storage",
        )


def create_sqlite(url: str) -> bool:
    """Make a new SQLite database whole: Optuna's schema and gearopt's tables are created in
    a temporary file beside it, which is then linked under the database's name (``os.link``,
    which fails when the name exists: another coordinator made it first, and that one is
    used). No coordinator ever sees a half-made file, so two starting together never race on
    the schema, and a 0-byte file is never gearopt's. True when this call made it; nothing to
    do for other dialects or an existing file."""
    try:
        parsed = sa.engine.make_url(url)
    except Exception:
        return False
    if parsed.get_backend_name() != "sqlite" or not parsed.database:
        return False
    path = Path(parsed.database)
    if path.exists() or not path.parent.is_dir():
        return False  # an existing file is checked; a missing folder, the driver says so
    temporary = path.with_name(f".{path.name}.{os.getpid()}.{time.monotonic_ns()}.new")
    temp_url = f"sqlite:///{temporary}"
    try:
        storage = optuna.storages.RDBStorage(
            temp_url, engine_kwargs=_engine_kwargs(temp_url), skip_compatibility_check=True
        )  # (its schema is this Optuna's, made now: no version check)
        ResultsStore(temp_url, engine=storage.engine)
        storage.engine.dispose()
        try:
            os.link(temporary, path)
        except FileExistsError:
            return False
        except OSError:  # no hard links here: the first rename wins the name all the same
            if path.exists():
                return False
            os.replace(temporary, path)
        return True
    finally:
        for leftover in (temporary, *temporary.parent.glob(f"{temporary.name}-*")):
            Path(leftover).unlink(missing_ok=True)


def check_own_tables(url: str) -> None:
    """Refuse a database that holds tables neither Optuna's nor gearopt's (a user's own
    SQLite file given as ``--storage``: gearopt would add its tables and views to it), unless
    the study file says ``shared_storage = true``."""
    try:
        parsed = sa.engine.make_url(url)
    except Exception:
        return
    if parsed.get_backend_name() == "sqlite" and not Path(parsed.database or "").is_file():
        return
    try:
        engine = sa.create_engine(url)
    except Exception:
        return  # opening it says more (an unknown dialect, a missing driver)
    try:
        inspector = sa.inspect(engine)
        present = set(inspector.get_table_names()) | set(inspector.get_view_names())
    except Exception:
        return  # opening it says more
    finally:
        engine.dispose()
    foreign = sorted(present - _own_tables())
    if foreign:
        raise StudyError(
            "storage",
            masked_url(url),
            f"holds tables that are not Optuna's or gearopt's ({', '.join(foreign[:5])}"
            f"{', ...' if len(foreign) > 5 else ''}): give a database of its own, or set "
            "shared_storage = true in the study file's [study] table",
        )


@functools.cache
def _own_tables() -> frozenset[str]:
    """The names of Optuna's tables (as this Optuna makes them) and gearopt's."""
    probe = optuna.storages.RDBStorage("sqlite:///:memory:")
    optuna_tables = frozenset(sa.inspect(probe.engine).get_table_names())
    probe.engine.dispose()
    return optuna_tables | SCHEMA_NAMES | {"sqlite_sequence"}


def default_storage_url(spec: StudySpec) -> str:
    """``sqlite:///<study name>.db`` beside the study file (the name sanitised)."""
    name = re.sub(r"[^A-Za-z0-9_.-]", "_", spec.name)
    return f"sqlite:///{spec.folder / (name + '.db')}"


def storage_tag(spec: StudySpec, url: str | None) -> str:
    """``""`` for the study's default storage, else ``_<tag>`` naming the other one: its
    SQLite file's stem, or the first 8 hex digits of the SHA-256 of its password-masked URL."""
    if url is None or url == default_storage_url(spec):
        return ""
    try:
        parsed = sa.engine.make_url(url)
    except Exception:
        parsed = None
    if parsed is not None and parsed.get_backend_name() == "sqlite" and parsed.database:
        return "_" + re.sub(r"[^A-Za-z0-9_.-]", "_", Path(parsed.database).stem)
    return "_" + hashlib.sha256(masked_url(url).encode()).hexdigest()[:8]


def study_exists(spec: StudySpec, storage: str | None = None) -> bool:
    """Whether the storage holds the study ``spec.name``, found without creating anything
    (no database file, schema or study where there was none)."""
    url = storage or default_storage_url(spec)
    check_storage_url(url)
    parsed = sa.engine.make_url(url)
    if parsed.get_backend_name() == "sqlite" and not Path(parsed.database).is_file():
        return False
    check_integrity(url)
    try:
        engine = sa.create_engine(url)
    except Exception as exc:  # an unknown dialect, a missing driver
        raise storage_error(url, "cannot be opened", exc) from None
    try:
        if "studies" not in sa.inspect(engine).get_table_names():
            return False
    except sqlalchemy.exc.SQLAlchemyError as exc:
        raise storage_error(url, "cannot be read", exc) from None
    finally:
        engine.dispose()
    try:  # Optuna's schema is there: its public API reads it (and creates nothing)
        rdb = optuna.storages.RDBStorage(
            url, engine_kwargs=_engine_kwargs(url), skip_table_creation=True
        )
    except Exception as exc:
        raise storage_error(url, "cannot be read", exc) from None
    try:
        return spec.name in optuna.get_all_study_names(storage=rdb)
    finally:
        rdb.engine.dispose()


def rdb_storage(url: str, attempts: int = 5, **heartbeat) -> optuna.storages.RDBStorage:
    """Optuna's RDB storage; a new database's schema is created by whichever coordinator comes
    first, and one that meets another creating it at the same moment tries again.
    ``heartbeat``: RDBStorage's ``heartbeat_interval``, ``grace_period`` and
    ``heartbeat_stale_trial_callback`` (:mod:`gearopt.recovery`), and its other keywords
    (``skip_table_creation``, ``skip_compatibility_check``)."""

    def make() -> optuna.storages.RDBStorage:
        return optuna.storages.RDBStorage(url, engine_kwargs=_engine_kwargs(url), **heartbeat)

    for attempt in range(attempts - 1):
        try:
            return make()
        except (sqlalchemy.exc.IntegrityError, sqlalchemy.exc.ProgrammingError):
            time.sleep(0.3 * (attempt + 1))
        except sqlalchemy.exc.OperationalError as exc:  # SQLite's "table ... already exists"
            if not _schema_race(exc):
                raise
            time.sleep(0.3 * (attempt + 1))
    return make()


def _schema_race(exc: Exception) -> bool:
    """Whether a database error is another coordinator creating the same schema at the same
    moment (SQLite says so with an OperationalError, other dialects with integrity or
    programming errors)."""
    text = str(exc).lower()
    return "already exists" in text or "database is locked" in text


def _engine_kwargs(url: str) -> dict:
    """SQLite: wait for a lock rather than fail at once (a second reader, a dashboard); a
    file's pool hands out the connection returned last, so that a process that uses one at a
    time does so on one connection (and :func:`data_version` sees only others' writes)."""
    if not url.startswith("sqlite"):
        return {}
    memory = sa.engine.make_url(url).database in (None, "", ":memory:")
    return {"connect_args": {"timeout": 30.0}, **({} if memory else {"pool_use_lifo": True})}


def fast_sqlite(engine: sa.Engine) -> None:
    """SQLite in WAL mode with ``synchronous = NORMAL``: a commit no longer waits for the disk
    (a transaction is safe against a killed process; only a power cut may lose the last
    ones), which takes the coordinator's time per trial from about 100 ms to a few ms."""
    if engine.dialect.name != "sqlite":
        return

    @sa.event.listens_for(engine, "connect")
    def _pragmas(connection, _record):
        cursor = connection.cursor()
        cursor.execute("PRAGMA journal_mode=WAL")
        cursor.execute("PRAGMA synchronous=NORMAL")
        cursor.close()

    engine.dispose()  # connections made before the listener get the pragmas when remade


#: the trial id of a supervised worker's trial while it is sampled, before it is written
#: (:meth:`WorkerStorage.draft`): no database's (their ids count from 1)
DRAFT_ID = -1

#: the statements that make a SQLite transaction a write transaction
_WRITES = ("INSERT", "UPDATE", "DELETE", "REPLAC")


def one_writer(engine: sa.Engine, lock_path: str) -> None:
    """SQLite: the engine's write transactions in this process hold an exclusive lock on the
    file ``lock_path`` (``flock``) from their first write until their connection goes back to
    the pool. The supervised workers of a run share one such file, so a worker that wants to
    write while another writes waits on the lock and wakes when the other has committed, rather
    than in SQLite's busy handler, which sleeps 1, 2, 5, 10, ... ms between its tries: about a
    tenth of each worker's time in a 2-job run of the example study went to those sleeps. The
    lock goes with a process that dies. Nothing for other dialects, nor where there is no
    ``fcntl`` (Windows)."""
    if engine.dialect.name != "sqlite" or fcntl is None:
        return
    lock = os.open(lock_path, os.O_RDWR | os.O_CREAT, 0o600)
    holders: set[int] = set()  # the pool records (their ids) in a write transaction

    @sa.event.listens_for(engine, "before_cursor_execute")
    def _take(connection, cursor, statement, parameters, context, executemany):
        record = id(connection.info)
        if record not in holders and statement.lstrip()[:6].upper() in _WRITES:
            if not holders:
                fcntl.flock(lock, fcntl.LOCK_EX)
            holders.add(record)

    def _drop(dbapi_connection, record, *_) -> None:
        if id(record.info) in holders:
            holders.discard(id(record.info))
            if not holders:
                fcntl.flock(lock, fcntl.LOCK_UN)

    for event in ("checkin", "invalidate", "close"):
        sa.event.listen(engine, event, _drop)


def release(rdb: optuna.storages.RDBStorage) -> None:
    """Close the storage's database connections (it opens new ones when used again): a run's
    end, so that SQLite folds its write-ahead log into the database file there and then rather
    than whenever the interpreter collects the engine."""
    rdb.remove_session()
    rdb.engine.dispose()


def data_version(engine: sa.Engine) -> tuple | None:
    """SQLite: a pooled connection of ``engine`` and its ``PRAGMA data_version``, which changes
    when another connection (another process's, or another of the pool's) has committed to
    the database since the connection last looked, and not for the connection's own commits.
    Two equal versions say that nothing was written but through that connection between
    them. None for other dialects."""
    if engine.dialect.name != "sqlite":
        return None
    with engine.connect() as con:
        return con.connection.dbapi_connection, con.exec_driver_sql("PRAGMA data_version").scalar()


def held_reads(view: WorkerStorage | None):
    """``view``'s :meth:`WorkerStorage.hold`, or nothing (None: not a supervised worker)."""
    return view.hold() if view is not None else contextlib.nullcontext()


class WorkerStorage(optuna.storages.BaseStorage):
    """Optuna's cached RDB storage (:func:`optuna.storages.get_storage`) as a supervised
    worker uses it: the study's trials read once per :meth:`hold` rather than at every read,
    and the trials this process asked kept in memory with its own writes applied.

    Inside :meth:`hold` (a worker's ask and suggest, or its tell) the first read of the
    study's trials is the only one: later reads (TPE reads them twice more per ask, Optuna's
    ask and tell read the trial in hand three times) are served from it, with this process's
    trials (created or popped from the queue here) replaced by their copies in memory. A
    trial is read from the database once, when first read after this process took it; every
    write through this storage is made in the database first, then applied to the copy as
    the database would store it (attributes through JSON, a finished trial's completion
    time the moment it is told). With no other process writing meanwhile (``--jobs 1``), every
    read gives what a read of the database would (the same designs); another
    worker's writes are seen at the next hold, as Optuna's cached storage sees them at its
    next read. Outside a hold every read goes to Optuna's cached storage as before.

    On SQLite a hold whose database no other connection has written to since the last read
    (:func:`data_version`: one pragma) reads nothing: the last read with this process's trials
    is what the database holds (its finished trials are kept in memory until a read of the
    database holds them). One worker alone, that is most asks: Optuna's read of the trials
    finished since its last look cost about as much as the trial's creation.

    Not thread-safe: one coordinator's thread uses it. It has no heartbeat of its own (the
    coordinator records them on the RDB storage): a worker does not fail other coordinators'
    stale trials, its supervisor does.
    """

    def __init__(self, rdb: optuna.storages.RDBStorage) -> None:
        self.inner = optuna.storages.get_storage(rdb)
        self.engine = rdb.engine
        #: this process's trials by id (a copy, or None until first read): its unfinished
        #: ones, and its finished ones until a read of the database holds them
        self.own: dict[int, optuna.trial.FrozenTrial | None] = {}
        self.read: dict[int, list] = {}  # the hold's read of each study's trials
        #: each study's last read of the database and the data version it was read at
        #: (:func:`data_version`; SQLite only)
        self.synced: dict[int, tuple[tuple, list]] = {}
        self.holding = 0
        #: a trial being sampled before it is written (:meth:`draft`), under :data:`DRAFT_ID`
        self.drafted: optuna.trial.FrozenTrial | None = None
        #: drafts written without their parameters yet, by trial id (:meth:`write_params`)
        self.unwritten: dict[int, optuna.trial.FrozenTrial] = {}

    @contextlib.contextmanager
    def hold(self):
        """Reads of the study's trials served by one read of the database (the class text)."""
        self.holding += 1
        try:
            yield self
        finally:
            self.holding -= 1
            if not self.holding:
                self.read.clear()
                self.unwritten.clear()  # (a trial given back without its parameters)
                if not self.synced:  # (no read is served again: the next one holds them)
                    self.own = {
                        k: t for k, t in self.own.items() if t is None or not t.state.is_finished()
                    }

    def draft(self, draft: optuna.trial.FrozenTrial) -> None:
        """Hold ``draft`` (a RUNNING trial made with ``trial_id`` :data:`DRAFT_ID`) in memory
        until :meth:`write_draft`: a sampler's writes to it (TPE's relative parameters, kept
        in a system attribute for the other workers' constant liar) and reads of it are the
        draft's."""
        self.drafted = draft

    def write_draft(self, study_id: int) -> tuple[int, int]:
        """Write the draft as a new trial of the study with its attributes, in one transaction
        (Optuna's ``create_new_trial`` from a template trial), its parameters kept for
        :meth:`write_params`; kept as this process's trial. Returns its trial id and number."""
        draft, self.drafted = self.drafted, None
        template = copy.copy(draft)
        template.params, template.distributions = {}, {}
        trial_id = self.inner.create_new_trial(study_id, template_trial=template)
        number = self._number_of(study_id, trial_id, draft.number)
        self.own[trial_id] = optuna.trial.FrozenTrial(
            number=number,
            state=draft.state,
            value=None,
            values=None,
            datetime_start=draft.datetime_start,
            datetime_complete=None,
            params={},
            distributions={},
            user_attrs=json.loads(json.dumps(draft.user_attrs)),
            system_attrs=json.loads(json.dumps(draft.system_attrs)),
            intermediate_values={},
            trial_id=trial_id,
        )
        self.unwritten[trial_id] = draft
        return trial_id, number

    def _number_of(self, study_id: int, trial_id: int, guess: int) -> int:
        """The number of a trial just created: the number it was sampled with, unless other
        processes created trials meanwhile (then one of the next few; the cached storage
        knows the new trial's number, a look at another's costs a query)."""
        for number in range(guess, guess + 4):
            try:
                if self.inner.get_trial_id_from_study_id_trial_number(study_id, number) == trial_id:
                    return number
            except KeyError:
                break
        return self.inner.get_trial(trial_id).number

    def write_params(self, trial_id: int) -> None:
        """Write the parameters of a trial written by :meth:`write_draft` (through the cached
        storage, which knows their distributions: in the template each would cost two more
        queries, its trial's and the study's distribution of the name; measured again, the
        example study's trial written whole took a worker 17.3 ms of CPU, against 9.5 + 6.5
        for the trial and then its four parameters, each in a transaction of its own)."""
        draft = self.unwritten.pop(trial_id)
        for name, value in draft.params.items():
            distribution = draft.distributions[name]
            internal = distribution.to_internal_repr(value)
            self.inner.set_trial_param(trial_id, name, internal, distribution)
        mine = self._mine(trial_id)
        mine.params, mine.distributions = dict(draft.params), dict(draft.distributions)

    def refresh(self) -> None:
        """The hold's next read of the study goes to the database again: for a read that must
        count the trials other processes created since the hold's first one (served by the
        last read only when nothing was written since, as :meth:`get_all_trials` says)."""
        self.read.clear()

    def _read(self, study_id: int) -> bool:
        """The hold's read of the study's trials: Optuna's cached storage's, or on SQLite the
        last read again when no other connection has committed to the database since it
        (:func:`data_version`: then only this process wrote, and its trials are in memory).
        True when read from the database."""
        version = data_version(self.engine)
        last = self.synced.get(study_id)
        if last is not None and version is not None and last[0] == version:
            self.read[study_id] = last[1]
            return False
        self.read[study_id] = self.inner.get_all_trials(study_id, deepcopy=False)
        if version is not None:
            self.synced[study_id] = (version, self.read[study_id])
        return True

    def _mine(self, trial_id: int) -> optuna.trial.FrozenTrial:
        trial = self.own[trial_id]
        if trial is None:
            trial = self.own[trial_id] = copy.deepcopy(self.inner.get_trial(trial_id))
        return trial

    # --- reads ----------------------------------------------------------------------------

    def get_trial(self, trial_id: int) -> optuna.trial.FrozenTrial:
        if trial_id == DRAFT_ID and self.drafted is not None:
            return copy.deepcopy(self.drafted)
        if self.holding and trial_id in self.own:
            return _copied(self._mine(trial_id))
        trial = self.inner.get_trial(trial_id)
        if trial_id in self.own and self.own[trial_id] is not None:
            self.own[trial_id] = copy.deepcopy(trial)
        return trial

    def get_all_trials(self, study_id, deepcopy=True, states=None) -> list:
        if not self.holding:
            return self.inner.get_all_trials(study_id, deepcopy=deepcopy, states=states)
        fresh = study_id not in self.read and self._read(study_id)
        trials = {t.number: t for t in self.read[study_id]}
        for trial_id in list(self.own):
            number = self._mine(trial_id).number
            if self.inner.get_trial_id_from_study_id_trial_number(study_id, number) != trial_id:
                continue  # another study's
            if fresh and number in trials and trials[number].state.is_finished():
                del self.own[trial_id]  # the database's (finished here, or by another process)
            else:
                trials[number] = self.own[trial_id]
        found = [trials[n] for n in sorted(trials) if states is None or trials[n].state in states]
        return copy.deepcopy(found) if deepcopy else found

    def get_trial_id_from_study_id_trial_number(self, study_id: int, trial_number: int) -> int:
        return self.inner.get_trial_id_from_study_id_trial_number(study_id, trial_number)

    # --- trials: writes -------------------------------------------------------------------

    def create_new_trial(self, study_id: int, template_trial=None) -> int:
        trial_id = self.inner.create_new_trial(study_id, template_trial)
        self.own[trial_id] = None
        return trial_id

    def set_trial_state_values(self, trial_id: int, state, values=None) -> bool:
        done = self.inner.set_trial_state_values(trial_id, state, values)
        if done and trial_id not in self.own and state == optuna.trial.TrialState.RUNNING:
            self.own[trial_id] = None  # popped from the queue here
        elif done and self.own.get(trial_id) is not None:
            trial = self.own[trial_id]
            if values is not None:
                trial.values = [float(v) for v in values]
            trial.state = state
            if state.is_finished():
                trial.datetime_complete = dt.datetime.now()
        return done

    def set_trial_param(self, trial_id: int, param_name: str, param_value_internal, distribution):
        if trial_id == DRAFT_ID and self.drafted is not None:
            self.drafted.params[param_name] = distribution.to_external_repr(param_value_internal)
            self.drafted.distributions[param_name] = distribution
            return
        self.inner.set_trial_param(trial_id, param_name, param_value_internal, distribution)
        if self.own.get(trial_id) is not None:
            trial = self.own[trial_id]
            trial.params[param_name] = distribution.to_external_repr(param_value_internal)
            trial.distributions[param_name] = distribution

    def set_trial_user_attr(self, trial_id: int, key: str, value) -> None:
        if trial_id == DRAFT_ID and self.drafted is not None:
            self.drafted.user_attrs[key] = value
            return
        self.inner.set_trial_user_attr(trial_id, key, value)
        if self.own.get(trial_id) is not None:
            self.own[trial_id].user_attrs[key] = json.loads(json.dumps(value))

    def set_trial_system_attr(self, trial_id: int, key: str, value) -> None:
        if trial_id == DRAFT_ID and self.drafted is not None:
            self.drafted.system_attrs[key] = value
            return
        self.inner.set_trial_system_attr(trial_id, key, value)
        if self.own.get(trial_id) is not None:
            self.own[trial_id].system_attrs[key] = json.loads(json.dumps(value))

    def set_trial_intermediate_value(self, trial_id: int, step: int, intermediate_value) -> None:
        self.inner.set_trial_intermediate_value(trial_id, step, intermediate_value)
        if self.own.get(trial_id) is not None:
            self.own[trial_id] = None  # read again (not a study gearopt runs)

    # --- studies: Optuna's cached storage as it is -----------------------------------------

    def create_new_study(self, directions, study_name=None) -> int:
        return self.inner.create_new_study(directions, study_name)

    def delete_study(self, study_id: int) -> None:
        self.inner.delete_study(study_id)

    def set_study_user_attr(self, study_id: int, key: str, value) -> None:
        self.inner.set_study_user_attr(study_id, key, value)

    def set_study_system_attr(self, study_id: int, key: str, value) -> None:
        self.inner.set_study_system_attr(study_id, key, value)

    def get_study_id_from_name(self, study_name: str) -> int:
        return self.inner.get_study_id_from_name(study_name)

    def get_study_name_from_id(self, study_id: int) -> str:
        return self.inner.get_study_name_from_id(study_id)

    def get_study_directions(self, study_id: int) -> list:
        return self.inner.get_study_directions(study_id)

    def get_study_user_attrs(self, study_id: int) -> dict:
        return self.inner.get_study_user_attrs(study_id)

    def get_study_system_attrs(self, study_id: int) -> dict:
        return self.inner.get_study_system_attrs(study_id)

    def get_all_studies(self) -> list:
        return self.inner.get_all_studies()

    def remove_session(self) -> None:
        self.inner.remove_session()


def _copied(trial: optuna.trial.FrozenTrial) -> optuna.trial.FrozenTrial:
    """A copy of ``trial`` whose parameters, distributions and attributes can be set without
    touching the original (as Optuna's ``Trial`` sets those of the trial it is given): the
    dictionaries copied, their values shared (a deep copy of every value cost about a
    millisecond a trial)."""
    twin = copy.copy(trial)
    twin.params, twin.distributions = dict(trial.params), dict(trial.distributions)
    twin.user_attrs, twin.system_attrs = dict(trial.user_attrs), dict(trial.system_attrs)
    twin.intermediate_values = dict(trial.intermediate_values)
    if trial.values is not None:
        twin.values = list(trial.values)
    return twin
