"""Contract test suites that plugin authors run against their own plugins (needs pytest).

As ``optuna.testing`` does for storages, gearopt ships the checks every machine model must pass;
a plugin proves itself with a few lines::

    # tests/test_my_machine.py
    import pytest
    from gearopt.testing import MachineModelContract
    from my_package.my_machine import MyMachine

    class TestMyMachine(MachineModelContract):
        @pytest.fixture
        def machine_model(self):
            return MyMachine()

        @pytest.fixture
        def design_text(self):
            return open("tests/my_design.toml").read()   # a valid design using the model

A model that generates flanks subclasses :class:`FlankContract` instead: the same fixtures, the
same checks, and those of its FlankMaps (residual, mask, normals, mirror, next tooth, tool
penetration)::

    class TestMyMachine(FlankContract): ...

An evaluator proves itself with :class:`EvaluatorContract` (fixtures ``evaluator``,
``design_text`` and, optionally, small ``conditions``): it evaluates what it declares (every
metric, curve and pattern), its metrics are the places of its report, it checks its declared
options and pickles. An objective with :class:`ObjectiveContract` (fixtures ``objective``,
``options`` and ``evaluations``, the labelled evaluations it reads)::

    class TestMyEvaluator(EvaluatorContract):
        @pytest.fixture
        def evaluator(self):
            return MyEvaluator()

        @pytest.fixture
        def design_text(self):
            return open("tests/my_design.toml").read()

The built-in machine models, evaluators and objectives run the same suites in gearopt's own
tests.
"""

from gearopt.testing.evaluators import EvaluatorContract, ObjectiveContract
from gearopt.testing.flanks import FlankContract
from gearopt.testing.machine_models import MachineModelContract

__all__ = ["EvaluatorContract", "FlankContract", "MachineModelContract", "ObjectiveContract"]
