"""Property-based fuzzing of design and study files (issue 27): whatever a careless or hostile
user feeds gearopt, a command ends with exit 0 and finite output (with its ``warnings`` list) or
with exit 2 and one line naming the problem; never a traceback, NaN, or a flood of lines.

Hypothesis draws mutations of the shipped designs (values of every type, huge, tiny and
non-finite numbers, missing and unknown keys, deep nesting) and of their raw text (truncated,
binary, with a byte-order mark); seeded (``derandomize``) and bounded in examples so that the
suite stays reproducible and under a minute here. ``GEAROPT_FUZZ_EXAMPLES`` scales the number of
examples for a longer hunt.
"""

from __future__ import annotations

import contextlib
import io
import json
import math
import os
import tempfile
import tomllib
from pathlib import Path

import pytest
import tomli_w

from gearopt.cli import main
from gearopt.errors import GearoptError
from gearopt.studyfile import StudySpec, load_study_spec

from .conftest import STUDIES

hypothesis = pytest.importorskip("hypothesis")
st = hypothesis.strategies

SCALE = float(os.environ.get("GEAROPT_FUZZ_EXAMPLES", "1"))
BASES = ("seed001_table3.toml", "face_milling_conjugate.toml", "seed003_case_A.toml")
STUDY = "cyclo_palloid_contact.toml"
#: the longest error line accepted (a value is cut to 120 characters in a message)
LONGEST_LINE = 2000


def _settings(examples: int):
    return hypothesis.settings(
        max_examples=max(1, int(examples * SCALE)),
        derandomize=True,
        database=None,
        deadline=None,
        suppress_health_check=list(hypothesis.HealthCheck),
    )


NUMBERS = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True),
    st.integers(min_value=-(2**63), max_value=2**63 - 1),
    st.sampled_from([0, 0.0, -1.0, 1e-308, 1e308, 1e18, 0.001, 8.5, 89.999, 90.0, 180.0]),
)
VALUES = st.one_of(
    NUMBERS,
    st.booleans(),
    st.text(max_size=12),
    st.sampled_from(["auto", "inf", "left", "right", "", "nan"]),
    st.lists(NUMBERS, max_size=3),
    st.recursive(st.integers(0, 3), lambda inner: st.lists(inner, max_size=2), max_leaves=6),
    st.dictionaries(st.sampled_from(["a", "offset_mm", "model"]), NUMBERS, max_size=2),
)


def _paths(data: dict, prefix=()):
    for key, value in data.items():
        yield (*prefix, key), value
        if isinstance(value, dict):
            yield from _paths(value, (*prefix, key))


def _number(value) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool)


@st.composite
def mild_tables(draw, base: str) -> dict:
    """A shipped design with one or two of its numbers scaled: mostly valid designs, whose
    flanks and contact the machine models and the engine must handle or refuse."""
    data = tomllib.loads((STUDIES / base).read_text())
    for _ in range(draw(st.integers(1, 2))):
        paths = sorted(((p, v) for p, v in _paths(data) if _number(v)), key=str)
        path, value = draw(st.sampled_from(paths))
        parent = data
        for key in path[:-1]:
            parent = parent[key]
        factor = draw(st.sampled_from([0.5, 0.8, 0.95, 0.99, 1.01, 1.05, 1.25, 1.6, 2.0, 4.0]))
        parent[path[-1]] = type(value)(value * factor) if isinstance(value, float) else value
        if isinstance(value, int):
            parent[path[-1]] = max(1, round(value * factor))
    return data


@st.composite
def mild_texts(draw) -> bytes:
    return tomli_w.dumps(draw(mild_tables(draw(st.sampled_from(BASES))))).encode()


@st.composite
def mutated_tables(draw, base: str) -> dict:
    data = tomllib.loads((STUDIES / base).read_text())
    for _ in range(draw(st.integers(1, 3))):
        paths = sorted(_paths(data), key=str)
        path, value = draw(st.sampled_from(paths))
        parent = data
        for key in path[:-1]:
            parent = parent[key]
        op = draw(st.sampled_from(["set", "scale", "scale", "delete", "unknown"]))
        if op == "delete":
            del parent[path[-1]]
        elif op == "unknown":
            parent[draw(st.sampled_from([path[-1] + "_x", "zz", "Face_Width_mm"]))] = draw(VALUES)
        elif op == "scale" and isinstance(value, int | float) and not isinstance(value, bool):
            factor = draw(st.sampled_from([-1.0, 0.0, 1e-6, 0.5, 0.999, 1.001, 2.0, 1e3, 1e12]))
            parent[path[-1]] = value * factor
        else:
            parent[path[-1]] = draw(VALUES)
    return data


@st.composite
def design_texts(draw) -> bytes:
    base = draw(st.sampled_from(BASES))
    data = draw(mutated_tables(base))
    try:
        text = tomli_w.dumps(data).encode()
    except (TypeError, ValueError):
        text = (STUDIES / base).read_bytes()
    raw = draw(st.sampled_from(["as is"] * 6 + ["truncate", "garbage", "bom", "nest"]))
    if raw == "truncate":
        text = text[: draw(st.integers(0, len(text)))]
    elif raw == "garbage":
        at = draw(st.integers(0, len(text)))
        text = text[:at] + draw(st.binary(min_size=1, max_size=16)) + text[at:]
    elif raw == "bom":
        text = b"\xef\xbb\xbf" + text
    elif raw == "nest":
        depth = draw(st.integers(50, 800))
        text += b"\n[fuzz]\nx = " + b"[" * depth + b"]" * depth + b"\n"
    return text


def _finite(value) -> bool:
    if isinstance(value, float):
        return math.isfinite(value)
    if isinstance(value, dict):
        return all(_finite(v) for v in value.values())
    if isinstance(value, list):
        return all(_finite(v) for v in value)
    return True


OUTCOMES: dict[str, int] = {}


def _check_command(argv: list[str]) -> None:
    """Exit 0 with finite JSON and a warnings list of strings and nothing on stderr, or exit 2
    with one short line on stderr; anything else (an exception escapes) fails."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        status = main(argv)
    lines = err.getvalue().splitlines()
    OUTCOMES[f"{argv[0]} exit {status}"] = OUTCOMES.get(f"{argv[0]} exit {status}", 0) + 1
    if status == 2:
        assert len(lines) == 1, err.getvalue()[-3000:]
        assert lines[0].startswith("gearopt: error: ") and len(lines[0]) < LONGEST_LINE
        return
    assert status == 0, (status, err.getvalue()[-3000:])
    assert lines == [], err.getvalue()[-3000:]
    result = json.loads(out.getvalue())
    assert _finite(result), out.getvalue()[:3000]
    assert all(isinstance(w, str) for w in result["warnings"])


def _fuzz_design(text: bytes, commands) -> None:
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "design.toml"
        path.write_bytes(text)
        for command in commands:
            _check_command([*command[:1], str(path), *command[1:], "--json"])


@_settings(60)
@hypothesis.given(design_texts())
def test_fuzzed_designs_give_settings_or_one_line(text):
    _fuzz_design(text, [["settings"]])


@_settings(20)
@hypothesis.given(st.one_of(mild_texts(), design_texts()))
def test_fuzzed_designs_give_flanks_or_one_line(text):
    _fuzz_design(text, [["flanks", "--grid", "7,7"]])


@_settings(6)
@hypothesis.given(mild_texts())
def test_fuzzed_designs_give_an_analysis_or_one_line(text):
    _fuzz_design(text, [["analyze", "--grid", "9,9", "--positions", "7"]])


@st.composite
def study_texts(draw) -> bytes:
    data = draw(mutated_tables(STUDY))
    try:
        return tomli_w.dumps(data).encode()
    except (TypeError, ValueError):
        return (STUDIES / STUDY).read_bytes()


@_settings(60)
@hypothesis.given(study_texts())
def test_fuzzed_study_files_are_read_or_refused_with_a_gearopt_error(text):
    # the whole study file is validated before any database is made: reading it either gives
    # a study or a GearoptError (one line at the command line), nothing else
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "study.toml"
        path.write_bytes(text)
        (Path(folder) / "seed001_section5_3.toml").write_bytes(
            (STUDIES / "seed001_section5_3.toml").read_bytes()
        )
        try:
            spec = load_study_spec(path)
        except GearoptError as exc:
            OUTCOMES["study refused"] = OUTCOMES.get("study refused", 0) + 1
            assert "\n" not in str(exc) and len(str(exc)) < LONGEST_LINE
        else:
            OUTCOMES["study read"] = OUTCOMES.get("study read", 0) + 1
            assert isinstance(spec, StudySpec)
        assert sorted(p.name for p in Path(folder).iterdir()) == [
            "seed001_section5_3.toml",
            "study.toml",
        ]
