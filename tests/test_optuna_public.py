"""gearopt uses Optuna through its public API only (issue 21 item 5): no private attribute of
Optuna's objects (``study._storage``, ``study._study_id``, ``trial._trial_id``, ...) and no raw
SQL on Optuna's tables anywhere in ``gearopt/`` or ``plugins/``."""

from __future__ import annotations

import ast
import re
import warnings
from pathlib import Path

import optuna
import pytest
import sqlalchemy as sa

ROOT = Path(__file__).resolve().parents[1]
SOURCES = sorted([*ROOT.glob("gearopt/**/*.py"), *ROOT.glob("plugins/**/*.py")])
#: SQL that reads Optuna's tables for users, not for gearopt: the documented views
#: ``gearopt_trial_params`` and ``gearopt_trial_metrics`` (README, "Results for dashboards")
VIEWS_MODULE = ROOT / "gearopt" / "results.py"


def _optuna_private_names() -> set[str]:
    """The private attributes (one leading underscore) of Optuna's study, trial, frozen trial
    and storages, read off live objects and their classes."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        rdb = optuna.storages.RDBStorage("sqlite:///:memory:")
        study = optuna.create_study(storage=rdb)
        trial = study.ask()
        trial.suggest_float("x", 0.0, 1.0)
        study.tell(trial, 0.5)
        frozen = study.trials[0]
    objects = [study, trial, frozen, rdb, study.sampler]
    names = set()
    for obj in objects:
        names |= set(vars(obj)) | set(dir(type(obj)))
    rdb.engine.dispose()
    return {n for n in names if n.startswith("_") and not n.startswith("__")}


def _optuna_tables() -> set[str]:
    probe = optuna.storages.RDBStorage("sqlite:///:memory:")
    tables = set(sa.inspect(probe.engine).get_table_names())
    probe.engine.dispose()
    return tables


PRIVATE = _optuna_private_names()
TABLES = _optuna_tables()
SQL = re.compile(
    r"\b(?:FROM|JOIN|INTO|UPDATE|TABLE)\s+[\"`]?(" + "|".join(sorted(TABLES)) + r")\b",
    re.IGNORECASE,
)


def _own_private_names(tree: ast.AST) -> set[str]:
    """Private names a module defines itself (its functions, classes, assigned attributes)."""
    own = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef | ast.ClassDef):
            own.add(node.name)
        elif isinstance(node, ast.Attribute) and isinstance(node.ctx, ast.Store):
            own.add(node.attr)
        elif isinstance(node, ast.Name) and isinstance(node.ctx, ast.Store):
            own.add(node.id)
    return own


def private_reads(text: str) -> list[str]:
    """Reads of Optuna's private attributes in a module's source: ``x.name``, and the name as
    a string (``getattr(study, "_storage")``)."""
    tree = ast.parse(text)
    own = _own_private_names(tree)
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Attribute) and node.attr in PRIVATE and node.attr not in own:
            found.append(f"{node.lineno}: .{node.attr}")
        elif isinstance(node, ast.Constant) and isinstance(node.value, str):
            if node.value in PRIVATE and node.value not in own:
                found.append(f"{node.lineno}: {node.value!r}")
    return found


def raw_sql(text: str) -> list[str]:
    """String literals of a module that name one of Optuna's tables in SQL."""
    return [
        f"{node.lineno}: {node.value.strip()[:60]!r}"
        for node in ast.walk(ast.parse(text))
        if isinstance(node, ast.Constant) and isinstance(node.value, str) and SQL.search(node.value)
    ]


def test_the_scanners_find_what_they_look_for():
    # the grep below must be able to fail: the old coordinator's lines are found
    old = (
        'COUNTS = sa.text("SELECT state, COUNT(*) FROM trials WHERE study_id = :id")\n'
        "def f(study, trial):\n"
        "    study._storage.set_trial_user_attr(trial._trial_id, 'k', 1)\n"
        "    return study._study_id, getattr(study, '_storage')\n"
    )
    assert len(private_reads(old)) == 4
    assert len(raw_sql(old)) == 1
    assert {"_storage", "_study_id", "_trial_id"} <= PRIVATE
    assert {"trials", "studies", "trial_values", "trial_heartbeats"} <= TABLES
    # and gearopt's own tables and private names are not taken for Optuna's
    assert not raw_sql('q = "SELECT * FROM gearopt_trials JOIN gearopt_metrics USING (study)"')
    assert not private_reads("class A:\n    def _tell(self):\n        return self._tell\n")


@pytest.mark.parametrize("path", SOURCES, ids=lambda p: str(p.relative_to(ROOT)))
def test_no_private_attribute_of_optuna_is_read(path):
    assert private_reads(path.read_text(encoding="utf-8")) == []


@pytest.mark.parametrize(
    "path", [p for p in SOURCES if p != VIEWS_MODULE], ids=lambda p: str(p.relative_to(ROOT))
)
def test_no_raw_sql_on_optunas_tables(path):
    assert raw_sql(path.read_text(encoding="utf-8")) == []
