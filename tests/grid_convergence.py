"""What the grid-convergence tests share (``test_pattern_convergence``, ``test_te_convergence``):
a design's TCA of both sides at a grid, computed once per module run, and the parameters of one
test per (case, side, figure) with the known gaps as strict xfails."""

from __future__ import annotations

import pytest

import gearopt
from gearopt.analysis import AnalysisOptions, contact_sides, meshed_pair

from .conftest import STUDIES

#: the fine grid every default-grid figure is held to (n_face, n_profile)
FINE = [81, 161]

_RESULTS: dict = {}


def analysed_sides(name: str, grid=None, overrides=None, conditions=None) -> dict:
    """:func:`gearopt.analysis.contact_sides` of ``studies/<name>`` with ``overrides`` under
    ``conditions`` at ``grid`` (None: the default), remembered for the session."""
    overrides, conditions = overrides or {}, conditions or {}
    key = (name, tuple(grid) if grid else None, repr(sorted(overrides.items())), repr(conditions))
    if key not in _RESULTS:
        design = gearopt.with_overrides(gearopt.load_design(STUDIES / name), overrides)
        extra = {"grid": list(grid)} if grid else {}
        options = AnalysisOptions.from_conditions({**conditions, **extra}, design=design)
        _RESULTS[key] = contact_sides(meshed_pair(design, options), options)
    return _RESULTS[key]


def figure_params(sides, figures, gaps):
    """``pytest.param(case, side, figure)`` for every (case, side) of ``sides`` and figure,
    a strict xfail where ``(case, side, figure)`` is in ``gaps``."""
    for case, side in sides:
        for figure in figures:
            marks = ()
            if (case, side, figure) in gaps:
                marks = pytest.mark.xfail(strict=True, reason="known gap: see GAPS")
            yield pytest.param(case, side, figure, marks=marks, id=f"{case}-{side}-{figure}")
