"""Seed 003's figures from the sweeps: the maximum kinematic error and the bias against the
cutter edge radius R_b (Table 5, Figs. 12-13), against the cutter head radius R_h (Table 6), and
the maximum kinematic error over (R_h, R_b) (Fig. 14's surface, as a contour map).

Runs the sweeps through the task queue first where their studies are not complete (the grid
trials only), then reads the results back from the gearopt tables with SQL, as a dashboard
would, and writes ``table5.png``, ``table6.png`` and ``map.png`` into this folder (or the folder
given as the first argument). Needs matplotlib (``pip install -e ".[plot]"``).

    python studies/seed003/plots.py [OUT_DIR]
"""

from __future__ import annotations

import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import sqlalchemy as sa  # noqa: E402

from gearopt.study import default_storage_url, run_study  # noqa: E402
from gearopt.studyfile import load_study_spec  # noqa: E402

HERE = Path(__file__).resolve().parent
RB = "machine.pinion.convex.blade_profile_radius_mm"
RH = "machine.pinion.convex.cutter_head_radius_mm"

QUERY = sa.text(
    """
    SELECT p.trial_number, p.param, p.value AS param_value, m.metric, m.value
    FROM gearopt_trial_params p
    JOIN gearopt_trial_metrics m ON m.study = p.study AND m.trial_number = p.trial_number
    WHERE p.study = :study AND m.evaluation = 'tca'
      AND m.metric IN ('tca.te_peak_to_peak_arcsec', 'tca.pattern.bias_mm')
    """
)


def sweep(name: str) -> dict[int, dict[str, float]]:
    """Run the study's grid (if not done) and return ``{trial: {param or metric: value}}``."""
    spec = load_study_spec(HERE / f"{name}.toml")
    run_study(spec, trials=len(spec.enqueue), jobs=2, progress=False, save_best=False)
    engine = sa.create_engine(default_storage_url(spec))
    rows: dict[int, dict[str, float]] = {}
    with engine.connect() as con:
        for number, param, param_value, metric, value in con.execute(QUERY, {"study": spec.name}):
            rows.setdefault(number, {})[param] = param_value
            rows[number][metric] = value
    return rows


def _line(ax, rows, key, label):
    x = np.array([r[key] for r in rows.values()])
    order = np.argsort(x)
    te = -np.array([r["tca.te_peak_to_peak_arcsec"] for r in rows.values()])[order]
    bias = np.array([r["tca.pattern.bias_mm"] for r in rows.values()])[order]
    ax.plot(x[order], te, "o-", label="max. kinematic error (arcsec)")
    ax.plot(x[order], bias, "s--", label="bias (mm, the contact line's extension)")
    ax.set_xlabel(label)
    ax.grid(True, alpha=0.3)
    ax.legend()


def main(out: Path) -> list[Path]:
    out.mkdir(parents=True, exist_ok=True)
    paths = []
    for name, key, label, log in (
        ("table5", RB, "cutter edge radius R_b (mm), R_h = 135 mm", True),
        ("table6", RH, "cutter head radius R_h (mm), R_b = 500 mm", False),
    ):
        fig, ax = plt.subplots(figsize=(7, 4.5))
        _line(ax, sweep(name), key, label)
        if log:
            ax.set_xscale("log")
        ax.set_title(f"seed 003 {name.replace('table', 'Table ')}: pinion convex flank")
        fig.tight_layout()
        paths.append(out / f"{name}.png")
        fig.savefig(paths[-1], dpi=110)
        plt.close(fig)
    rows = sweep("map")
    rh = np.array(sorted({r[RH] for r in rows.values()}))
    rb = np.array(sorted({r[RB] for r in rows.values()}))
    te = np.full((len(rb), len(rh)), np.nan)
    for r in rows.values():
        te[np.searchsorted(rb, r[RB]), np.searchsorted(rh, r[RH])] = -r[
            "tca.te_peak_to_peak_arcsec"
        ]
    fig, ax = plt.subplots(figsize=(7, 5))
    contour = ax.contourf(rh, rb, te, levels=12, cmap="viridis")
    ax.contour(rh, rb, te, levels=[-10.0], colors="white", linewidths=2)
    fig.colorbar(contour, label="max. kinematic error (arcsec)")
    ax.set_yscale("log")
    ax.set_xlabel("cutter head radius R_h (mm)")
    ax.set_ylabel("cutter edge radius R_b (mm)")
    ax.set_title("seed 003: max. kinematic error over (R_h, R_b); white: -10 arcsec")
    fig.tight_layout()
    paths.append(out / "map.png")
    fig.savefig(paths[-1], dpi=110)
    plt.close(fig)
    return paths


if __name__ == "__main__":
    for path in main(Path(sys.argv[1]) if len(sys.argv) > 1 else HERE):
        print(path)
