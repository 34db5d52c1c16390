"""The figures of ``gearopt analyze --plot`` and of a study trial: :mod:`gearopt.figures`
(kept under this name for its importers)."""

from gearopt.figures import plot_analysis, plot_evaluations

__all__ = ["DEDICATED_FIGURES", "plot_analysis", "plot_evaluations"]

#: the evaluators :func:`plot_analysis` draws; any other evaluator's declared curves and pattern
#: are drawn by :func:`gearopt.plots_declared.plot_declared`
DEDICATED_FIGURES = frozenset({"tca", "backlash", "ease-off", "ltca"})
