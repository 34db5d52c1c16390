"""Figures of a contact analysis and the design report (matplotlib, the ``plot`` extra).

:func:`analysis_figures` draws, from the ``tca``, ``backlash`` and ``ease-off`` evaluations of
a design (and ``ltca`` when present):

- ``te``: TE of both sides, every tooth pair over its whole contact (dashed where it does not
  carry), the envelope, the solved hand-overs, peak-to-peak and contact ratio, and the TE
  spectrum in orders of the tooth-mesh frequency (:func:`gearopt.figures.data.te_curves`);
- ``pattern``: the contact pattern of both sides on the pinion and on the gear, on the true
  projection of each member's tooth, with the instantaneous contact zones, the path, M and C
  (:func:`gearopt.figures.data.member_patterns`);
- ``ease_off``: the pinion's ease-off, both flanks on one colour scale;
- ``backlash``: with a window ``(min_um, max_um)`` when one is given;
- ``misalignment``: M under V, H, J and Sigma one at a time, the V-H chart and the TE
  peak-to-peak (:func:`gearopt.figures.sweep.misalignment_sweep`: 13 more TCAs of both sides,
  run here rather than by an evaluator);
- ``ltca``: the loaded TCA.

:func:`plot_analysis` writes them as PNG files (``gearopt analyze --plot DIR``);
:func:`plot_evaluations` a study trial's; :mod:`gearopt.figures.report` the HTML report.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import numpy as np

from gearopt.analysis import AnalysisOptions, meshed_pair
from gearopt.errors import GearoptError
from gearopt.figures.data import member_patterns, te_curves, tooth_outline
from gearopt.figures.draw import (
    backlash_figure,
    ease_off_figure,
    misalignment_figure,
    pattern_figure,
    pyplot,
    te_figure,
)
from gearopt.figures.ltca import ltca_figure
from gearopt.figures.sweep import misalignment_sweep

__all__ = ["analysis_figures", "figure_data", "plot_analysis", "plot_evaluations"]

SIDE_KEYS = {"drive": "tca", "coast": "tca_coast"}
#: the flanks (pinion, gear) of each side
SIDE_FLANKS = {"drive": ("convex", "concave"), "coast": ("concave", "convex")}


def figure_data(design, tca) -> dict:
    """The TE curves and patterns of both sides (:mod:`gearopt.figures.data`) of a ``tca``
    evaluation: ``{"te": {side: TeCurves}, "pattern": {side: (pinion, gear)}, "pair": ...}``."""
    options = AnalysisOptions.from_conditions(tca.conditions, design=design)
    pair = meshed_pair(design, options)
    fields = {"drive": pair.drive, "coast": pair.coast}
    te, patterns = {}, {}
    for side, field in fields.items():
        report = tca.report[SIDE_KEYS[side]]
        te[side] = te_curves(field, report, separation=report["pattern"]["separation"])
        patterns[side] = member_patterns(field, report, design.blank, flank_names=SIDE_FLANKS[side])
    return {"te": te, "pattern": patterns, "pair": pair, "options": options}


def _pattern_to_tooth(design, pair):
    """Pattern coordinates (face from the toe, profile from the root) to the pinion's true
    projection, per side."""
    frame = pair.frame
    pinions = {"drive": pair.drive.pinion, "coast": pair.coast.pinion}

    def convert(side, points):
        p = np.asarray(points, float)
        s, t = p[..., 0] + frame.toe_mm, p[..., 1] + frame.root_mm
        return np.stack([p[..., 0], pinions[side].height_at(s, t)], -1)

    return convert


def _ease_off(plt, design, pair, evaluation, title: str):
    """The ease-off figure of an ``ease-off`` evaluation on the pinion's true projection."""
    convert = _pattern_to_tooth(design, pair)
    report = evaluation.report["ease_off"]
    projections = {}
    for side in SIDE_KEYS:
        face = np.asarray(report[side]["face_mm"])
        profile = np.asarray(report[side]["profile_mm"])
        grid = np.stack(np.meshgrid(face, profile, indexing="ij"), -1)
        x, y = np.moveaxis(convert(side, grid), -1, 0)
        projections[side] = (x, y, tooth_outline(design.blank, "pinion"))
    return ease_off_figure(plt, report, projections, title)


def analysis_figures(design, evaluations: Mapping, *, window_um=None, sweep: bool = True) -> dict:
    """``{name: matplotlib Figure}`` of a design's evaluations (module docstring): ``tca``,
    ``backlash``, ``ease-off`` and optionally ``ltca``; ``window_um`` the backlash window;
    ``sweep=False`` leaves the misalignment figure out."""
    plt = pyplot()
    title = design.name or "design"
    tca = evaluations["tca"]
    data = figure_data(design, tca)
    pair = data["pair"]
    target = None
    if "te_target_arcsec" in tca.arrays:
        target = (np.asarray(tca.arrays["phi1_deg"]), np.asarray(tca.arrays["te_target_arcsec"]))
    reports = {side: tca.report[key] for side, key in SIDE_KEYS.items()}
    figures = {
        "te": te_figure(plt, data["te"], title, target),
        "pattern": pattern_figure(plt, data["pattern"], reports, title),
    }
    if "backlash" in evaluations:
        figures["backlash"] = backlash_figure(
            plt, evaluations["backlash"].report["backlash"], title, window_um
        )
    convert = _pattern_to_tooth(design, pair)
    if "ease-off" in evaluations:
        figures["ease_off"] = _ease_off(plt, design, pair, evaluations["ease-off"], title)
    if sweep:
        result = misalignment_sweep(design, data["options"])
        outline = tooth_outline(design.blank, "pinion")
        figures["misalignment"] = misalignment_figure(
            plt, result, {"drive": outline, "coast": outline}, convert, title
        )
    if "ltca" in evaluations:
        figures["ltca"] = ltca_figure(plt, evaluations["ltca"], title)
    return figures


def _write(figures: dict, out: Path, prefix: str = "") -> list[Path]:
    plt = pyplot()
    paths = []
    try:
        for name, fig in figures.items():
            path = out / f"{prefix}{name}.png"
            fig.savefig(path, dpi=110)
            paths.append(path)
    except OSError as exc:
        raise GearoptError("--plot", str(out), f"cannot write the figures: {exc}") from None
    finally:
        for fig in figures.values():
            plt.close(fig)
    return paths


def plot_analysis(design, evaluations: Mapping, directory, *, window_um=None) -> list[Path]:
    """Write the figures of ``gearopt analyze`` (:func:`analysis_figures`) into ``directory``
    (created if missing) as ``<name>.png``; returns the paths."""
    out = Path(directory)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise GearoptError(
            "--plot", str(directory), f"cannot create the directory: {exc}"
        ) from None
    return _write(analysis_figures(design, evaluations, window_um=window_um), out)


def plot_evaluations(evaluations: Mapping, directory, title: str, *, design=None) -> list[Path]:
    """Figures of a study trial's evaluations (keyed by label) into ``directory``:
    ``<label>_te.png`` and ``<label>_pattern.png`` for each TCA (with the ``design``),
    ``<label>_backlash.png``, ``<label>_ease_off.png`` (with the ``design``),
    ``<label>_ltca.png``; evaluations of other evaluators are skipped. No misalignment sweep."""
    plt = pyplot()
    out = Path(directory)
    paths = []
    for label, evaluation in evaluations.items():
        kind = evaluation.evaluator
        figures = {}
        if kind == "tca" and design is not None:
            figures = analysis_figures(design, {"tca": evaluation}, sweep=False)
        elif kind == "backlash":
            figures = {"backlash": backlash_figure(plt, evaluation.report["backlash"], title)}
        elif kind == "ltca":
            figures = {"ltca": ltca_figure(plt, evaluation, title)}
        elif kind == "ease-off" and design is not None:
            options = AnalysisOptions.from_conditions(evaluation.conditions, design=design)
            pair = meshed_pair(design, options)
            figures = {"ease_off": _ease_off(plt, design, pair, evaluation, title)}
        paths += _write(figures, out, f"{label}_")
    return paths
