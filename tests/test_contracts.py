"""Every built-in evaluator and objective passes its contract suite (gearopt.testing), as every
machine model passes its own; the toy third-party evaluator and objective too."""

from __future__ import annotations

import sys

import pytest

import gearopt
from gearopt.testing import EvaluatorContract, ObjectiveContract

from .conftest import STUDIES
from .test_declarations import toy_evaluator_site  # noqa: F401  (a fixture)

#: a small analysis: enough positions to bracket the hand-overs, a coarse grid (fast)
SMALL = {"grid": [13, 9], "positions": 9}
SECTION53 = STUDIES / "seed001_section5_3.toml"
TE_TARGET = STUDIES / "fourth_order_te" / "case1.toml"
FACE_MILLING = STUDIES / "face_milling_conjugate.toml"
#: the closed loop's measured gear (absolute paths: the contract reads the design from text)
TOPOGRAPHY = {
    "member": "gear",
    "reference": str(FACE_MILLING),
    "target": str(STUDIES / "closed_loop" / "face_milling_gear_measured.csv"),
}

#: evaluator -> (design file, conditions)
EVALUATORS = {
    "tca": (SECTION53, SMALL),
    "backlash": (SECTION53, SMALL),
    "ease-off": (SECTION53, SMALL),
    "ltca": (SECTION53, {**SMALL, "torque_nm": [50.0]}),
    "chain-error": (STUDIES / "seed001_table3.toml", {}),
    "topography": (FACE_MILLING, TOPOGRAPHY),
}


def test_every_built_in_evaluator_is_tested():
    entries = gearopt.list_plugins(kind="evaluator")
    assert set(EVALUATORS) == {e.name for e in entries if e.distribution == "gearopt"}


@pytest.mark.parametrize("name", sorted(EVALUATORS))
class TestBuiltInEvaluator(EvaluatorContract):
    @pytest.fixture
    def evaluator(self, name):
        return gearopt.evaluators()[name]

    @pytest.fixture
    def design_text(self, name):
        return EVALUATORS[name][0].read_text()

    @pytest.fixture
    def conditions(self, name):
        return dict(EVALUATORS[name][1])


_CACHE: dict[str, object] = {}


def _evaluate(label: str, evaluator: str, design, conditions):
    if label not in _CACHE:
        design = gearopt.load_design(design)
        _CACHE[label] = gearopt.evaluators()[evaluator].evaluate(design, conditions)
    return _CACHE[label]


def _tca():
    return _evaluate("tca", "tca", SECTION53, SMALL)


def _misaligned():
    shifted = {**SMALL, "misalignment": {"offset_mm": 0.221, "gear_axial_mm": 0.188}}
    return _evaluate("mis", "tca", SECTION53, shifted)


#: objective -> (options, the labelled evaluations it reads)
OBJECTIVES = {
    "te_peak_to_peak": (lambda: {}, lambda: {"tca": _tca()}),
    "worst_te": (
        lambda: {"on": ["tca", "mis"], "side": "both"},
        lambda: {"tca": _tca(), "mis": _misaligned()},
    ),
    "te_level": (lambda: {"level_arcsec": 5.0}, lambda: {"tca": _tca()}),
    "te_target": (
        lambda: {"measure": "max"},
        lambda: {"tca": _evaluate("target", "tca", TE_TARGET, {"grid": [25, 13]})},
    ),
    "pattern_center_offset": (lambda: {"component": "face"}, lambda: {"tca": _tca()}),
    "pattern_bias": (lambda: {"side": "coast"}, lambda: {"tca": _tca()}),
    "pattern_movement": (
        lambda: {"misaligned": "mis"},
        lambda: {"tca": _tca(), "mis": _misaligned()},
    ),
    "backlash_window": (
        lambda: {"min_um": 150.0, "max_um": 260.0},
        lambda: {"backlash": _evaluate("backlash", "backlash", SECTION53, SMALL)},
    ),
    "edge_contact": (lambda: {"on": ["tca", "mis"]}, lambda: {"tca": _tca(), "mis": _misaligned()}),
    "lte_fluctuation": (
        lambda: {"weights": [1.0, 3.0]},
        lambda: {"ltca": _evaluate("ltca", "ltca", SECTION53, {**SMALL, "torque_nm": [20, 50]})},
    ),
    "max_contact_pressure": (
        lambda: {"limit_mpa": 1500.0, "side": "both"},
        lambda: {"ltca": _evaluate("ltca", "ltca", SECTION53, {**SMALL, "torque_nm": [20, 50]})},
    ),
    "topography": (
        lambda: {"flank": "convex"},
        lambda: {"topography": _evaluate("topography", "topography", FACE_MILLING, TOPOGRAPHY)},
    ),
    "edge_loading": (
        lambda: {},
        lambda: {"ltca": _evaluate("ltca", "ltca", SECTION53, {**SMALL, "torque_nm": [20, 50]})},
    ),
}


def test_every_built_in_objective_is_tested():
    entries = gearopt.list_plugins(kind="objective")
    assert set(OBJECTIVES) == {e.name for e in entries if e.distribution == "gearopt"}


@pytest.mark.parametrize("name", sorted(OBJECTIVES))
class TestBuiltInObjective(ObjectiveContract):
    @pytest.fixture
    def objective(self, name):
        return gearopt.objectives()[name]

    @pytest.fixture
    def options(self, name):
        return OBJECTIVES[name][0]()

    @pytest.fixture
    def evaluations(self, name):
        return OBJECTIVES[name][1]()


@pytest.fixture
def toy_evaluator(toy_evaluator_site, monkeypatch):  # noqa: F811
    monkeypatch.syspath_prepend(str(toy_evaluator_site))
    yield __import__("gearopt_toy_evaluator")
    sys.modules.pop("gearopt_toy_evaluator", None)


class TestToyEvaluatorPassesTheContract(EvaluatorContract):
    @pytest.fixture
    def evaluator(self, toy_evaluator):
        return toy_evaluator.ToyDepthEvaluator()

    @pytest.fixture
    def design_text(self):
        return SECTION53.read_text()

    @pytest.fixture
    def conditions(self):
        return {"margin": 0.1}


class TestToyObjectivePassesTheContract(ObjectiveContract):
    @pytest.fixture
    def objective(self, toy_evaluator):
        return toy_evaluator.ToyBoxArea()

    @pytest.fixture
    def options(self):
        return {}

    @pytest.fixture
    def evaluations(self, toy_evaluator):
        design = gearopt.load_design(SECTION53)
        return {"toy-depth": toy_evaluator.ToyDepthEvaluator().evaluate(design)}
