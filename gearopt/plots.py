"""The figures of ``gearopt analyze --plot`` and of a study trial: :mod:`gearopt.figures`
(kept under this name for its importers)."""

from gearopt.figures import plot_analysis, plot_evaluations

__all__ = ["plot_analysis", "plot_evaluations"]
