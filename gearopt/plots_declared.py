"""A figure of any evaluator's declared curves and pattern (matplotlib, the ``plot`` extra).

``gearopt analyze --plot`` and a study's artifacts draw the built-in evaluators with their
dedicated figures (:mod:`gearopt.plots`); every other evaluator gets ``<name>.png`` from its
declarations (:mod:`gearopt.declarations`): one panel per declared curve, each side a line, the
axes named with the declared quantities and units, and one panel with the contact pattern's
outline per side on the projected tooth (face toe -> heel, profile root -> top).
"""

from __future__ import annotations

import fnmatch
from collections.abc import Mapping
from pathlib import Path

import numpy as np

from gearopt.errors import GearoptError
from gearopt.figures.draw import pyplot

__all__ = ["plot_declared"]


def _panels(evaluator, evaluation) -> list[tuple[str, object]]:
    """``(curve name, declaration)`` of every declared curve the evaluation carries."""
    out = []
    for curve in evaluator.curves:
        names = sorted(n for n in evaluation.curves if fnmatch.fnmatchcase(n, curve.name))
        out += [(n, curve) for n in names]
    return out


def _axis(quantity: str, unit: str) -> str:
    return f"{quantity} ({unit})" if unit else quantity


def plot_declared(
    evaluations: Mapping, registry: Mapping, directory, *, title: str = ""
) -> list[Path]:
    """Write ``<label>.png`` for each evaluation (keyed by label) whose evaluator (in
    ``registry``, by :attr:`Evaluation.evaluator`) declares curves or a pattern it carries;
    returns the paths written."""
    todo = []
    for label, evaluation in evaluations.items():
        evaluator = registry[evaluation.evaluator]
        panels = _panels(evaluator, evaluation)
        pattern = evaluator.pattern is not None and bool(evaluation.patterns)
        if panels or pattern:
            todo.append((label, evaluator, evaluation, panels, pattern))
    if not todo:
        return []
    plt = pyplot()
    out = Path(directory)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise GearoptError(
            "--plot", str(directory), f"cannot create the directory: {exc}"
        ) from None
    paths = []
    for label, evaluator, evaluation, panels, pattern in todo:
        count = len(panels) + int(pattern)
        fig, axes = plt.subplots(1, count, figsize=(5.0 * count, 4.0), squeeze=False)
        for ax, (name, curve) in zip(axes[0], panels, strict=False):
            for side, (x, y) in evaluation.curves[name].items():
                ax.plot(np.ravel(x), np.ravel(y), "o-", ms=3, label=side)
            ax.set_xlabel(_axis(curve.x, curve.x_unit))
            ax.set_ylabel(_axis(curve.y, curve.y_unit))
            ax.set_title(f"{name}: {curve.description}" if curve.description else name)
            ax.grid(True, lw=0.3)
            ax.legend(fontsize=8)
        if pattern:
            ax = axes[0][-1]
            for side, outline in evaluation.patterns.items():
                ring = np.asarray(outline, float)
                if len(ring):
                    ring = np.vstack([ring, ring[:1]])
                    ax.fill(*ring.T, alpha=0.3, label=side)
                    ax.plot(*ring.T, "k-", lw=0.6)
            ax.set_xlabel("face (mm): toe -> heel")
            ax.set_ylabel("profile (mm): root -> top")
            ax.set_title(evaluator.pattern.description or "contact pattern")
            ax.set_aspect("equal", adjustable="datalim")
            ax.legend(fontsize=8)
        name = label if label == evaluator.name else f"{label} ({evaluator.name})"
        fig.suptitle(f"{title}: {name}" if title else name)
        fig.tight_layout()
        path = out / f"{label}.png"
        try:
            fig.savefig(path, dpi=110)
        except OSError as exc:
            raise GearoptError(
                "--plot", str(directory), f"cannot write {path.name}: {exc}"
            ) from None
        finally:
            plt.close(fig)
        paths.append(path)
    return paths
