"""The evaluator and objective contract suites (:class:`EvaluatorContract`,
:class:`ObjectiveContract`)."""

from __future__ import annotations

import fnmatch
import json
import math
import pickle

import pytest

from gearopt.declarations import Curve, Metric, Option, Pattern, declared, metric_names
from gearopt.design_files import loads_design
from gearopt.errors import GearoptError
from gearopt.evaluation import BaseEvaluator, BaseObjective, Evaluation

__all__ = ["EvaluatorContract", "ObjectiveContract"]

#: one evaluation per (evaluator, design text, conditions): the checks share it
_EVALUATIONS: dict[tuple, Evaluation] = {}


def _identifier(name: str) -> bool:
    return isinstance(name, str) and bool(name) and name == name.strip()


class EvaluatorContract:
    """Checks every evaluator must pass. Subclass it and provide the fixtures:

    ``evaluator``
        An instance of the evaluator under test.
    ``design_text``
        The TOML text of a design it can evaluate.
    ``conditions``
        Conditions to evaluate it under (default ``{}``); keep them small, the suite runs
        ``evaluate`` once per test class.
    """

    @pytest.fixture
    def conditions(self):
        return {}

    @pytest.fixture
    def design(self, design_text):
        return loads_design(design_text)

    @pytest.fixture
    def evaluation(self, evaluator, design, design_text, conditions) -> Evaluation:
        key = (type(evaluator), evaluator.name, design_text, repr(sorted(conditions.items())))
        if key not in _EVALUATIONS:
            _EVALUATIONS[key] = evaluator.evaluate(design, dict(conditions))
        return _EVALUATIONS[key]

    def test_is_an_evaluator_with_a_name(self, evaluator):
        assert isinstance(evaluator, BaseEvaluator)
        assert _identifier(evaluator.name)
        assert isinstance(evaluator.description, str) and evaluator.description

    def test_is_picklable(self, evaluator):
        # evaluators run in worker processes
        clone = pickle.loads(pickle.dumps(evaluator))
        assert type(clone) is type(evaluator) and clone.name == evaluator.name

    def test_declarations_are_well_formed(self, evaluator):
        assert all(isinstance(m, Metric) for m in evaluator.metrics)
        assert all(isinstance(c, Curve) for c in evaluator.curves)
        assert evaluator.pattern is None or isinstance(evaluator.pattern, Pattern)
        names = [n for m in evaluator.metrics for n in metric_names(evaluator, m)]
        assert len(names) == len(set(names)), "a metric is declared twice"
        curves = [c.name for c in evaluator.curves]
        assert len(curves) == len(set(curves)), "a curve is declared twice"
        if any(m.per_side for m in evaluator.metrics):
            assert evaluator.sections, "a metric per side needs the sides' sections"
        for curve in evaluator.curves:
            assert curve.sides and all(_identifier(s) for s in curve.sides), curve
            assert _identifier(curve.x) and _identifier(curve.y), curve
        if evaluator.options is not None:
            assert all(isinstance(o, Option) for o in evaluator.options)
            options = [o.name for o in evaluator.options]
            assert len(options) == len(set(options)), "an option is declared twice"

    def test_evaluates_what_it_declares(self, evaluator, evaluation):
        assert isinstance(evaluation, Evaluation)
        assert evaluation.evaluator == evaluator.name
        for name, value in evaluation.metrics.items():
            assert declared(evaluator, name) is not None, f"metric {name!r} is not declared"
            assert math.isfinite(value), name
        for metric in evaluator.metrics:
            if metric.always and "*" not in metric.name:
                for name in metric_names(evaluator, metric):
                    assert name in evaluation.metrics, f"declared metric {name!r} missing"
        for name, by_side in evaluation.curves.items():
            matches = [c for c in evaluator.curves if fnmatch.fnmatchcase(name, c.name)]
            assert matches, f"curve {name!r} is not declared"
            assert set(by_side) <= set(matches[0].sides), (name, sorted(by_side))
        if evaluation.patterns:
            assert evaluator.pattern is not None, "patterns given but none declared"
            assert set(evaluation.patterns) <= set(evaluator.pattern.sides)
        json.dumps(evaluation.report)  # JSON-ready: what `gearopt analyze --json` prints
        json.dumps(evaluation.conditions)

    def test_metrics_are_the_places_of_its_report(self, evaluator, evaluation):
        # one vocabulary: a metric found in the report is the same number there
        for name, value in evaluation.metrics.items():
            found = evaluation.report
            for part in name.split("."):
                if isinstance(found, dict) and part in found:
                    found = found[part]
                elif isinstance(found, list) and part.isdigit() and int(part) < len(found):
                    found = found[int(part)]
                else:
                    found = None
                    break
            if isinstance(found, bool | int | float):
                assert float(found) == pytest.approx(value, rel=1e-12, abs=1e-12), name

    def test_checks_its_declared_options(self, evaluator, design, conditions):
        evaluator.check_conditions(design, dict(conditions))
        if evaluator.options is None:
            pytest.skip("the evaluator declares no options")
        with pytest.raises(GearoptError, match="no_such_option_xyz"):
            evaluator.check_conditions(design, {**conditions, "no_such_option_xyz": 1})
        for option in evaluator.options:
            if option.kind in ("integer", "number") and option.lower is not None:
                bad = option.lower - 1
                with pytest.raises(GearoptError, match=option.name):
                    evaluator.check_conditions(design, {**conditions, option.name: bad})


class ObjectiveContract:
    """Checks every objective and constraint must pass. Subclass it and provide the fixtures:

    ``objective``
        An instance of the objective under test.
    ``options``
        Valid options of its study-file entry (``{}`` when it needs none).
    ``evaluations``
        ``{label: Evaluation}`` holding every label the options make it read.
    """

    def test_is_an_objective_with_a_name(self, objective):
        assert isinstance(objective, BaseObjective)
        assert _identifier(objective.name)
        assert isinstance(objective.description, str) and objective.description
        assert objective.kind in ("objective", "constraint")
        assert objective.direction in ("minimize", "maximize")
        assert all(isinstance(r, str) for r in objective.requires)

    def test_is_picklable(self, objective):
        clone = pickle.loads(pickle.dumps(objective))
        assert type(clone) is type(objective) and clone.name == objective.name

    def test_declares_its_options(self, objective):
        assert all(isinstance(o, Option) for o in objective.options)
        names = [o.name for o in objective.options]
        assert len(names) == len(set(names))
        for option in objective.options:
            if option.default is not None and "*" not in option.name:
                option.check(option.default, objective.name)

    def test_reads_labelled_evaluations_of_what_it_requires(self, objective, options, evaluations):
        reads = objective.reads(**options)
        assert reads, "an objective reads at least one evaluation"
        for label, evaluator in reads.items():
            assert evaluator in objective.requires, (label, evaluator)
            assert label in evaluations, label
            assert evaluations[label].evaluator == evaluator

    def test_refuses_an_unknown_option(self, objective, options):
        with pytest.raises(GearoptError, match="no_such_option_xyz"):
            objective.reads(**options, no_such_option_xyz=1)

    def test_refuses_a_missing_required_option(self, objective, options):
        for option in objective.options:
            if option.required:
                with pytest.raises(GearoptError, match=option.name):
                    objective.reads(**{k: v for k, v in options.items() if k != option.name})

    def test_value_is_a_finite_number(self, objective, options, evaluations):
        value = objective.value(evaluations, **options)
        assert isinstance(value, int | float) and not isinstance(value, bool)
        assert math.isfinite(value)
