"""``gearopt report DESIGN.toml --out DIR``: one self-contained HTML page per design.

The page holds the design's blank, its machine settings, every figure the analysis reports (with
its unit) and the figures of :func:`gearopt.figures.analysis_figures` as ``<img>`` elements with
base64-embedded PNG data: it opens offline, from the file, with no server and nothing fetched.
"""

from __future__ import annotations

import base64
import dataclasses
import html
import io
from pathlib import Path
from typing import Any

import numpy as np

from gearopt.analysis import AnalysisOptions, analysed_flanks
from gearopt.design import MEMBERS
from gearopt.errors import GearoptError
from gearopt.figures import analysis_figures
from gearopt.figures.draw import pyplot
from gearopt.plausibility import caught, contact_findings, flank_findings
from gearopt.plugins import evaluators

__all__ = ["FIGURE_CAPTIONS", "report_html", "write_report"]

#: the figures in the page's order, with their captions
FIGURE_CAPTIONS = {
    "te": "Transmission error (arcsec of gear rotation) of every tooth pair over its whole "
    "contact, the envelope, the solved hand-overs; below, its spectrum in orders of the "
    "tooth-mesh frequency.",
    "pattern": "Contact pattern on the pinion and on the gear (true projection of each tooth, "
    "mm): pattern, instantaneous contact zones, path, M and C.",
    "ease_off": "Pinion ease-off (um, normal to the flank) from the surfaces conjugate to the "
    "gear, both flanks on one colour scale.",
    "backlash": "Circumferential backlash (um) along the mesh.",
    "misalignment": "The pattern's movement under misalignment: M under V, H, J and Sigma "
    "alone, the V-H chart, and the TE peak-to-peak.",
    "ltca": "Loaded TCA.",
}

STYLE = """
body { font-family: sans-serif; margin: 2em auto; max-width: 1500px; color: #222; }
table { border-collapse: collapse; margin: 0.5em 0 1.5em; font-size: 0.9em; }
td, th { border: 1px solid #bbb; padding: 0.2em 0.6em; text-align: left; }
th { background: #eee; }
td.num { text-align: right; font-family: monospace; }
figure { margin: 1em 0 2em; }
figure img { max-width: 100%; border: 1px solid #ddd; }
.warn { color: #a40; }
"""


def _flat(value: Any, prefix: str = "") -> list[tuple[str, Any]]:
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        value = dataclasses.asdict(value)
    if isinstance(value, dict):
        rows = []
        for key, item in value.items():
            rows += _flat(item, f"{prefix}{key}.")
        return rows
    return [(prefix[:-1], value)]


def _cell(value: Any) -> str:
    if isinstance(value, float):
        return f'<td class="num">{value:.6g}</td>'
    if isinstance(value, (list, tuple)):
        return '<td class="num">' + ", ".join(_text(v) for v in value) + "</td>"
    return f'<td class="num">{html.escape(str(value))}</td>'


def _text(value: Any) -> str:
    return f"{value:.6g}" if isinstance(value, float) else html.escape(str(value))


def _table(rows, header=("quantity", "value")) -> str:
    head = "".join(f"<th>{html.escape(h)}</th>" for h in header)
    body = "".join(
        "<tr>"
        + f"<td>{html.escape(str(row[0]))}</td>"
        + "".join(_cell(v) for v in row[1:])
        + "</tr>"
        for row in rows
    )
    return f"<table><tr>{head}</tr>{body}</table>"


def _png(fig) -> str:
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=100)
    return base64.b64encode(buffer.getvalue()).decode("ascii")


def _results_rows(out: dict) -> list[tuple]:
    rows = []
    for key in ("tca", "tca_coast"):
        side = out[key]
        pat = side["pattern"]
        rows.append(
            (
                side["side"],
                side["te_peak_to_peak_arcsec"],
                side["contact_ratio"],
                pat["width_mm"],
                pat["bias_mm"],
                pat["center_offset_mm"],
                pat["ellipse_major_axis_mm"],
                pat["ellipse_minor_axis_mm"],
                pat["path_angle_deg"],
                "yes" if pat["edge_contact"] else "no",
            )
        )
    return rows


RESULT_HEADER = (
    "side",
    "te_peak_to_peak_arcsec",
    "contact_ratio",
    "pattern width_mm",
    "bias_mm",
    "center_offset_mm (face, profile)",
    "ellipse_major_axis_mm",
    "ellipse_minor_axis_mm",
    "path_angle_deg",
    "edge contact",
)


def report_html(design, evaluations: dict, figures: dict, warnings=(), window_um=None) -> str:
    """The page of a design's evaluations (``tca``, ``backlash``, ``ease-off``) and figures
    (``{name: matplotlib Figure}``, embedded as base64 PNG)."""
    out: dict[str, Any] = {}
    for evaluation in evaluations.values():
        out.update(evaluation.report)
    name = html.escape(design.name)
    parts = [
        "<!DOCTYPE html>",
        '<html lang="en"><head><meta charset="utf-8">',
        f"<title>gearopt report: {name}</title><style>{STYLE}</style></head><body>",
        f"<h1>{name}</h1>",
        f"<p>{html.escape(design.meta.description or '')}<br>source: "
        f"{html.escape(design.meta.source or '')}<br>machine model: "
        f"<b>{html.escape(design.model)}</b></p>",
    ]
    if warnings:
        parts.append("<h2>Warnings</h2><ul>")
        parts += [f'<li class="warn">{html.escape(w)}</li>' for w in warnings]
        parts.append("</ul>")
    parts.append("<h2>Blank (pinion, gear)</h2>")
    parts.append(_table(_flat(design.blank.as_dict())))
    parts.append("<h2>Machine settings</h2>")
    parts.append(_table(_flat(design.machine)))
    mis = dataclasses.asdict(design.misalignment)
    parts.append("<h2>Assembly (misalignment)</h2>")
    parts.append(_table(list(mis.items())))
    parts.append("<h2>Analysis conditions</h2>")
    parts.append(_table(_flat(evaluations["tca"].conditions)))
    parts.append("<h2>Tooth contact analysis</h2>")
    parts.append(_table(_results_rows(out), RESULT_HEADER))
    b, e = out["backlash"], out["ease_off"]
    rows = [
        ("backlash min_um", b["min_um"]),
        ("backlash mean_um", b["mean_um"]),
        ("backlash max_um", b["max_um"]),
        ("backlash radius_mm", b["radius_mm"]),
        ("interference", "yes" if b["interference"] else "no"),
        ("ease-off drive max_um", e["drive"]["max_um"]),
        ("ease-off coast max_um", e["coast"]["max_um"]),
    ]
    if window_um is not None:
        rows.insert(3, ("backlash window_um", list(window_um)))
    parts.append("<h2>Backlash and ease-off</h2>")
    parts.append(_table(rows))
    parts.append("<h2>Figures</h2>")
    for key, caption in FIGURE_CAPTIONS.items():
        if key in figures:
            parts.append(
                f'<figure id="fig-{key}"><img alt="{key}" src="data:image/png;base64,'
                f'{_png(figures[key])}"><figcaption>{html.escape(caption)}</figcaption></figure>'
            )
    parts.append("<p><small>Written by gearopt report.</small></p></body></html>")
    return "\n".join(parts)


def write_report(design, directory, *, window_um=None, conditions=None, sweep=True) -> Path:
    """Analyse ``design`` (``tca``, ``backlash``, ``ease-off`` with ``conditions``, default its
    ``[analysis]``), draw its figures and write ``<directory>/<name>.html``; returns the path.
    ``window_um``: the backlash window ``(min_um, max_um)`` to draw."""
    out = Path(directory)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise GearoptError("--out", str(directory), f"cannot create the directory: {exc}") from None
    conditions = dict(conditions or {})
    registry = evaluators()
    with caught() as numerical:
        results = {
            n: registry[n].evaluate(design, conditions) for n in ("tca", "backlash", "ease-off")
        }
        options = AnalysisOptions.from_conditions(conditions, design=design)
        found = [
            text
            for member, maps in zip(MEMBERS, analysed_flanks(design, options), strict=True)
            for flank, fm in maps.items()
            for text in flank_findings(
                design, member, flank, fm.summary(), row_mm=float(np.ptp(fm.profile_mm[:2]))
            )
        ]
        merged: dict[str, Any] = {}
        for evaluation in results.values():
            merged.update(evaluation.report)
        found += contact_findings(merged)
        figures = analysis_figures(design, results, window_um=window_um, sweep=sweep)
    plt = pyplot()
    try:
        text = report_html(design, results, figures, found + numerical, window_um)
    finally:
        for fig in figures.values():
            plt.close(fig)
    path = out / f"{design.name}.html"
    try:
        path.write_text(text, encoding="utf-8")
    except OSError as exc:
        raise GearoptError("--out", str(directory), f"cannot write the report: {exc}") from None
    return path
