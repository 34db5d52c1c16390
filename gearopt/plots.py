"""Figures of a contact analysis (matplotlib, the ``plot`` extra): what a gear engineer reads.

- ``te.png``: TE of both sides over two mesh cycles (the carrying pair at each position),
  hand-overs marked;
- ``pattern.png``: the contact pattern, path and mean point M on the projected pinion tooth
  (toe to heel, root to top) for the drive and the coast side;
- ``backlash.png``: circumferential backlash along the mesh;
- ``ease_off.png``: the pinion's ease-off maps (drive and coast flanks);
- ``ltca.png`` (with a loaded TCA): the LTE over the cycle per torque, the LTE fluctuation
  versus torque, the load sharing of the pairs and the pressure map on the projected tooth at
  the largest torque.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import numpy as np

from gearopt.errors import GearoptError, NotAvailableError

__all__ = ["DEDICATED_FIGURES", "plot_analysis"]

#: the evaluators :func:`plot_analysis` draws; any other evaluator's declared curves and pattern
#: are drawn by :func:`gearopt.plots_declared.plot_declared`
DEDICATED_FIGURES = frozenset({"tca", "backlash", "ease-off", "ltca"})


def _pyplot():
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:  # pragma: no cover - depends on the environment
        raise NotAvailableError(
            "--plot", "matplotlib", "needs matplotlib: pip install 'gearopt[plot]'"
        ) from None
    return plt


def _te(plt, tca: Mapping, title: str, path: Path) -> None:
    fig, axes = plt.subplots(1, 2, figsize=(11, 4), sharey=False)
    for ax, (key, name) in zip(axes, (("", "drive"), ("coast_", "coast")), strict=True):
        phi = np.asarray(tca.arrays[f"{key}phi1_deg"])
        te = np.asarray(tca.arrays[f"{key}te_arcsec"])
        report = tca.report["tca" if not key else "tca_coast"]
        ax.plot(phi, te, "o-", color="C0" if not key else "C1", label="TE (carrying pair)")
        if not key and "te_target_arcsec" in tca.arrays:
            fine = np.linspace(phi[0], phi[-1], 401)
            ax.plot(
                fine,
                np.interp(fine, phi, np.asarray(tca.arrays["te_target_arcsec"])),
                "k--",
                lw=1.0,
                label=f"designed TE (max deviation "
                f"{report['te_target_max_deviation_arcsec']:.3f} arcsec)",
            )
        for h in report["handover_phi1_deg"]:
            ax.axvline(h, color="0.7", lw=0.8, ls="--")
        ax.set_title(f"{name}: peak-to-peak {report['te_peak_to_peak_arcsec']:.3f} arcsec")
        ax.set_xlabel("pinion rotation in the direction of motion (deg)")
        ax.set_ylabel("TE (arcsec of gear rotation)")
        ax.grid(alpha=0.3)
        ax.legend(loc="lower right", fontsize=8)
    fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def _pattern(plt, tca, title: str, path: Path) -> None:
    fig, axes = plt.subplots(1, 2, figsize=(12, 3.6))
    face = np.asarray(tca.arrays["face_mm"])
    profile = np.asarray(tca.arrays["profile_mm"])
    for ax, (key, name) in zip(axes, (("", "drive"), ("coast_", "coast")), strict=True):
        report = tca.report["tca" if not key else "tca_coast"]
        pat = report["pattern"]
        mask = np.asarray(tca.arrays[f"{key}flank_mask"], float)
        ax.contourf(face, profile, mask.T, levels=[0.5, 1.5], colors=["0.88"])
        pattern = np.asarray(tca.arrays[f"{key}pattern_um"], float)
        pattern = np.where(np.isfinite(pattern), pattern, 1e9)
        ax.contourf(
            face, profile, pattern.T, levels=[-1e9, pat["compound_um"]], colors=["C3"], alpha=0.6
        )
        ax.plot(
            tca.arrays[f"{key}path_face_mm"],
            tca.arrays[f"{key}path_profile_mm"],
            "k.-",
            lw=1,
            ms=3,
            label="contact path",
        )
        ax.plot(*pat["mean_point_mm"], "k*", ms=10, label="M")
        ax.set_xlim(face[0], face[-1])
        ax.set_ylim(profile[0], profile[-1])
        ax.set_aspect("equal")
        ax.set_xlabel("face (mm): toe -> heel")
        ax.set_ylabel("profile (mm): root -> top")
        ax.set_title(
            f"pinion {'convex' if name == 'drive' else 'concave'} ({name}): width "
            f"{pat['width_mm']:.1f} mm, bias {pat['bias_mm']:.1f} mm"
            + (", EDGE" if pat["edge_contact"] else ""),
            fontsize=9,
        )
        ax.legend(loc="upper right", fontsize=8)
    fig.suptitle(
        f"{title}: contact pattern ({pat['separation']} separation {pat['compound_um']:g} um)"
    )
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def _backlash(plt, report: Mapping, title: str, path: Path) -> None:
    fig, ax = plt.subplots(figsize=(6, 4))
    ax.plot(report["phi1_deg"], report["circumferential_um"], "o-")
    ax.set_xlabel("pinion rotation (deg)")
    ax.set_ylabel("circumferential backlash (um)")
    ax.set_title(f"{title}: backlash, mean {report['mean_um']:.1f} um")
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def _ease_off(plt, report: Mapping, title: str, path: Path) -> None:
    fig, axes = plt.subplots(1, 2, figsize=(12, 3.6))
    for ax, name in zip(axes, ("drive", "coast"), strict=True):
        e = report[name]
        face, profile = np.asarray(e["face_mm"]), np.asarray(e["profile_mm"])
        values = np.where(np.asarray(e["mask"]), np.asarray(e["ease_off_um"]), np.nan)
        cs = ax.contourf(face, profile, values.T, levels=12, cmap="viridis")
        fig.colorbar(cs, ax=ax, label="ease-off (um)")
        ax.set_xlabel("face (mm): toe -> heel")
        ax.set_ylabel("profile (mm): root -> top")
        ax.set_title(f"pinion {'convex' if name == 'drive' else 'concave'} ({name})")
    fig.suptitle(f"{title}: ease-off")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def _ltca(plt, ltca, title: str, path: Path) -> None:
    fig, axes = plt.subplots(2, 2, figsize=(12, 8))
    torques = np.asarray(ltca.arrays["torque_nm"], float)
    drive = ltca.report["ltca"]
    ax = axes[0, 0]
    phi = np.asarray(ltca.arrays["phi1_deg"])
    for k, entry in enumerate(drive):
        ax.plot(
            phi,
            entry["lte_arcsec"],
            "-",
            color=plt.cm.viridis(k / max(len(drive) - 1, 1)),
            label=f"{entry['torque_nm']:g} N m",
        )
    ax.set_xlabel("pinion rotation in the direction of motion (deg)")
    ax.set_ylabel("loaded TE (arcsec of gear rotation)")
    ax.set_title("drive: loaded TE over the cycle")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)
    ax = axes[0, 1]
    for key, name in (("", "drive"), ("coast_", "coast")):
        ax.plot(torques, ltca.arrays[f"{key}lte_peak_to_peak_arcsec"], "o-", label=name)
    ax.set_xlabel("output torque (N m)")
    ax.set_ylabel("LTE fluctuation, peak-to-peak (arcsec)")
    ax.set_title("LTE fluctuation versus torque")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    ax = axes[1, 0]
    top = drive[int(np.argmax(torques))]
    share = np.asarray(top["load_share"], float)
    bottom = np.zeros(len(phi))
    for j in range(share.shape[1]):
        ax.bar(
            phi, share[:, j], bottom=bottom, width=0.8 * (phi[1] - phi[0]), label=f"pair {j + 1}"
        )
        bottom += share[:, j]
    ax.set_xlabel("pinion rotation in the direction of motion (deg)")
    ax.set_ylabel("share of the load")
    ax.set_title(f"drive: load sharing at {top['torque_nm']:g} N m")
    ax.legend(fontsize=7)
    ax = axes[1, 1]
    face = np.asarray(ltca.arrays["pressure_face_mm"])
    profile = np.asarray(ltca.arrays["pressure_profile_mm"])
    pressure = np.asarray(ltca.arrays["pressure_mpa"])
    if pressure.size:
        order = np.argsort(pressure)
        cs = ax.scatter(face[order], profile[order], c=pressure[order], s=4, cmap="inferno")
        fig.colorbar(cs, ax=ax, label="contact pressure (MPa)")
    outline = np.asarray(top["pattern_outline_mm"], float)
    if len(outline) > 2:
        ax.plot(*np.vstack([outline, outline[:1]]).T, "k-", lw=0.8, label="loaded pattern")
    ax.set_xlabel("face (mm): toe -> heel")
    ax.set_ylabel("profile (mm): root -> top")
    ax.set_title(f"drive: pressure on the pinion flank at {top['torque_nm']:g} N m")
    fig.suptitle(f"{title}: loaded TCA")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def plot_analysis(design, evaluations: Mapping, directory) -> list[Path]:
    """Write the figures of ``gearopt analyze`` into ``directory`` (created if missing) from
    the ``tca``, ``backlash`` and ``ease-off`` evaluations; returns the paths."""
    plt = _pyplot()
    out = Path(directory)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise GearoptError(
            "--plot", str(directory), f"cannot create the directory: {exc}"
        ) from None
    title = design.name or "design"
    tca = evaluations["tca"]
    paths = [out / "te.png", out / "pattern.png", out / "backlash.png", out / "ease_off.png"]
    try:
        _te(plt, tca, title, paths[0])
        _pattern(plt, tca, title, paths[1])
        _backlash(plt, evaluations["backlash"].report["backlash"], title, paths[2])
        _ease_off(plt, evaluations["ease-off"].report["ease_off"], title, paths[3])
        if "ltca" in evaluations:
            paths.append(out / "ltca.png")
            _ltca(plt, evaluations["ltca"], title, paths[-1])
    except OSError as exc:
        plt.close("all")
        raise GearoptError("--plot", str(directory), f"cannot write the figures: {exc}") from None
    return paths


def plot_evaluations(evaluations: Mapping, directory, title: str) -> list[Path]:
    """Figures of a study trial's evaluations (keyed by label) into ``directory``:
    ``<label>_te.png`` and ``<label>_pattern.png`` for each TCA, ``<label>_backlash.png``,
    ``<label>_ease_off.png``; evaluations of other evaluators are skipped."""
    plt = _pyplot()
    out = Path(directory)
    drawers = {
        "tca": (
            ("te", lambda e, p: _te(plt, e, title, p)),
            ("pattern", lambda e, p: _pattern(plt, e, title, p)),
        ),
        "backlash": (("backlash", lambda e, p: _backlash(plt, e.report["backlash"], title, p)),),
        "ease-off": (("ease_off", lambda e, p: _ease_off(plt, e.report["ease_off"], title, p)),),
        "ltca": (("ltca", lambda e, p: _ltca(plt, e, title, p)),),
    }
    paths = []
    for label, evaluation in evaluations.items():
        for name, draw in drawers.get(evaluation.evaluator, ()):
            path = out / f"{label}_{name}.png"
            draw(evaluation, path)
            paths.append(path)
    return paths
