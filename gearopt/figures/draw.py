"""The figures a gear engineer reads in a design review (matplotlib, the ``plot`` extra).

Each function draws one figure into a new matplotlib figure and returns it; the data come from
:mod:`gearopt.figures.data` and :mod:`gearopt.figures.sweep`. Coordinates on a tooth: the true
projection (cone distance from the toe, height above the pitch cone).
"""

from __future__ import annotations

import numpy as np

from gearopt.errors import NotAvailableError

__all__ = [
    "MIN_TE_SPAN_ARCSEC",
    "backlash_figure",
    "ease_off_figure",
    "misalignment_figure",
    "pattern_figure",
    "pyplot",
    "te_figure",
]

#: the TE axes span at least this (a conjugate pair's numerical noise must not fill them)
MIN_TE_SPAN_ARCSEC = 2.0
SIDES = ("drive", "coast")


def pyplot():
    """matplotlib's pyplot on the Agg backend, or a NotAvailableError naming the extra."""
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:  # pragma: no cover - depends on the environment
        raise NotAvailableError(
            "--plot", "matplotlib", "needs matplotlib: pip install 'gearopt[plot]'"
        ) from None
    return plt


def _runs(mask):
    """``(start, stop)`` of the runs of True in a boolean array."""
    m = np.concatenate([[False], np.asarray(mask, bool), [False]])
    edges = np.flatnonzero(np.diff(m.astype(int)))
    return list(zip(edges[::2], edges[1::2], strict=True))


def te_figure(plt, curves: dict, title: str, target=None):
    """TE of both sides: every tooth pair over its whole contact (dashed where it does not
    carry), the envelope, the solved hand-overs; below, the envelope's spectrum in orders of
    the tooth-mesh frequency. ``curves``: ``{side: TeCurves}``; ``target``: the designed TE
    ``(phi1_deg, te_arcsec)`` of the drive side, if any."""
    fig, axes = plt.subplots(2, 2, figsize=(13, 7.5), gridspec_kw={"height_ratios": [2.2, 1]})
    for col, side in enumerate(SIDES):
        c = curves[side]
        ax = axes[0, col]
        for k in range(len(c.pair_t_deg)):
            t, te = c.pair_t_deg[k], c.pair_te_arcsec[k]
            color = f"C{k % 10}"
            ax.plot(t, np.where(c.pair_carrying[k], np.nan, te), "--", color=color, lw=0.9)
            ax.plot(t, np.where(c.pair_carrying[k], te, np.nan), "-", color=color, lw=1.6)
        ax.plot([], [], "-", color="0.4", lw=1.6, label="tooth pair, carrying")
        ax.plot([], [], "--", color="0.4", lw=0.9, label="tooth pair, not carrying")
        ax.plot(
            c.t_deg,
            c.envelope_arcsec,
            "-",
            color="0.6",
            alpha=0.6,
            lw=5,
            zorder=0,
            label=f"envelope (TE): peak-to-peak {c.peak_to_peak_arcsec:.3f} arcsec",
        )
        if abs(c.reported_peak_to_peak_arcsec - c.peak_to_peak_arcsec) > 0.01 * max(
            c.peak_to_peak_arcsec, 0.1
        ):  # the TCA's own hand-over solution disagrees with the curves': show both
            ax.plot(
                c.reported_handover_deg,
                np.interp(c.reported_handover_deg, c.t_deg, c.envelope_arcsec),
                "x",
                color="r",
                ms=7,
                label=f"TCA's hand-overs; its peak-to-peak {c.reported_peak_to_peak_arcsec:.3f}",
            )
        ax.plot(
            c.handover_deg,
            c.handover_arcsec,
            "o",
            mfc="none",
            mec="k",
            ms=7,
            label=f"hand-overs (solved); contact ratio {c.contact_ratio:.3f}",
        )
        if target is not None and side == "drive":
            ax.plot(*target, "m:", lw=1.2, label="designed TE")
        ax.axvspan(*c.analysed_deg, color="0.93", zorder=0, label="analysed positions")
        env = c.envelope_arcsec[np.isfinite(c.envelope_arcsec)]
        top, low = float(env.max()), float(env.min())
        span = max(top - low, MIN_TE_SPAN_ARCSEC)
        middle = 0.5 * (top + low)
        ax.set_ylim(middle - 1.1 * span, middle + 0.65 * span)
        ax.set_xlim(float(np.nanmin(c.t_deg)), float(np.nanmax(c.t_deg)))
        ax.set_xlabel("pinion rotation in the direction of motion (deg)")
        ax.set_ylabel("TE (arcsec of gear rotation)")
        ax.set_title(f"{side} side", fontsize=10)
        ax.grid(alpha=0.3)
        ax.legend(loc="lower center", fontsize=7, ncol=2)
        ax = axes[1, col]
        ax.bar(c.orders, c.amplitude_arcsec, width=0.6, color="C0")
        for x, a in zip(c.orders, c.amplitude_arcsec, strict=True):
            ax.annotate(f"{a:.3g}", (x, a), ha="center", va="bottom", fontsize=7)
        ax.set_xticks(c.orders)
        ax.set_ylim(0, max(1.2 * float(c.amplitude_arcsec.max()), 0.05 * MIN_TE_SPAN_ARCSEC))
        ax.set_xlabel("order of the tooth-mesh frequency")
        ax.set_ylabel("TE amplitude (arcsec)")
        ax.grid(alpha=0.3, axis="y")
    fig.suptitle(f"{title}: transmission error")
    fig.tight_layout()
    return fig


def _tooth(ax, m, *, first: bool) -> None:
    """The outline, pitch line, non-generated region and the end names of a member's tooth."""
    corners = m.outline.corners_mm
    ring = np.vstack([corners, corners[:1]])
    ax.plot(*ring.T, "k-", lw=1.2, label="blank: toe, heel, root and face lines" if first else None)
    ax.plot(
        [0, m.outline.face_width_mm],
        [0, 0],
        ":",
        color="0.5",
        lw=0.8,
        label="pitch cone" if first else None,
    )
    missing = (~m.generated).astype(float)
    if missing.any():
        ax.contourf(
            m.grid_x_mm, m.grid_y_mm, missing, levels=[0.5, 1.5], colors="none", hatches=["////"]
        )
        ax.contour(m.grid_x_mm, m.grid_y_mm, missing, levels=[0.5], colors="0.55", linewidths=0.6)
        ax.fill(
            [],
            [],
            facecolor="white",
            edgecolor="0.55",
            hatch="////",
            label="not generated (fillet / below the form limit)" if first else None,
        )
    lo, hi = corners[:, 1].min(), corners[:, 1].max()
    pad = 0.08 * (hi - lo)
    ax.text(0.0, lo - pad, "toe", ha="center", va="top", fontsize=8)
    ax.text(m.outline.face_width_mm, lo - pad, "heel", ha="center", va="top", fontsize=8)
    x_mid = 0.5 * m.outline.face_width_mm
    ax.text(
        x_mid,
        0.5 * (corners[0, 1] + corners[1, 1]) - pad,
        "root",
        ha="center",
        va="top",
        fontsize=8,
    )
    ax.text(
        x_mid,
        0.5 * (corners[2, 1] + corners[3, 1]) + pad,
        "top",
        ha="center",
        va="bottom",
        fontsize=8,
    )
    ax.set_xlim(-0.06 * m.outline.face_width_mm, 1.06 * m.outline.face_width_mm)
    ax.set_ylim(lo - 4 * pad, hi + 3 * pad)
    ax.set_aspect("equal")


def pattern_figure(plt, patterns: dict, reports: dict, title: str):
    """The contact pattern of both sides on the pinion and on the gear (as a roll tester shows):
    pattern, instantaneous contact zones, path, M and C on the tooth's true projection.
    ``patterns``: ``{side: (pinion MemberPattern, gear MemberPattern)}``; ``reports``:
    ``{side: reported TCA}``."""
    from matplotlib.patches import PathPatch
    from matplotlib.path import Path

    m0 = patterns["drive"][0].outline
    aspect = np.ptp(m0.corners_mm[:, 1]) * 1.6 / m0.face_width_mm
    height = max(1.6, 6.4 * aspect) + 1.0
    fig, axes = plt.subplots(2, 2, figsize=(14, 2 * height + 1.2))
    first = True
    for row, side in enumerate(SIDES):
        pat = reports[side]["pattern"]
        for col, m in enumerate(patterns[side]):
            ax = axes[row, col]
            _tooth(ax, m, first=first)
            if m.pattern:
                area = Path.make_compound_path(*[Path(r, closed=True) for r in m.pattern])
                label = f"pattern ({pat['compound_um']:g} um compound)" if first else None
                ax.add_patch(PathPatch(area, facecolor="C3", alpha=0.45, lw=0, label=label))
            for k, zone in enumerate(m.zones):
                ax.plot(
                    *np.vstack([zone, zone[:1]]).T,
                    "-",
                    color="darkred",
                    lw=0.7,
                    label="instantaneous contact zones" if first and k == 0 else None,
                )
            path = m.path_mm
            for a, b in _runs(m.path_carrying & np.isfinite(path[:, 0])):
                ax.plot(*path[a:b].T, "k-", lw=1.4)
            ax.plot(*path.T, "k--", lw=0.7)
            ax.plot([], [], "k-", lw=1.4, label="path, carrying pair" if first else None)
            ax.plot(
                [], [], "k--", lw=0.7, label="path, one tooth's whole contact" if first else None
            )
            ax.plot(
                *m.mean_point_mm, "k*", ms=11, label="M (mean contact point)" if first else None
            )
            ax.plot(
                *m.centre_mm, "P", color="C0", ms=8, label="C (flank centre)" if first else None
            )
            first = False
            ax.set_xlabel("cone distance from the toe (mm)")
            ax.set_ylabel("height above pitch cone (mm)")
            extra = ", EDGE CONTACT" if pat["edge_contact"] else ""
            ax.set_title(
                f"{m.member} {m.flank} ({side}): width {pat['width_mm']:.1f} mm, bias "
                f"{pat['bias_mm']:.1f} mm, M - C ({pat['center_offset_mm'][0]:.1f}, "
                f"{pat['center_offset_mm'][1]:.1f}) mm{extra}",
                fontsize=9,
            )
    fig.suptitle(f"{title}: contact pattern ({pat['separation']} separation)")
    fig.legend(loc="lower center", ncol=5, fontsize=8, frameon=False)
    fig.tight_layout(rect=(0, 0.06, 1, 1))
    return fig


def ease_off_figure(plt, report: dict, projections: dict, title: str):
    """The pinion's ease-off of both flanks as filled contours on the tooth (true projection),
    one colour scale for both. ``projections``: ``{side: (x, y, outline)}`` of the
    ease-off's nodes."""
    m0 = projections["drive"][2]
    aspect = np.ptp(m0.corners_mm[:, 1]) * 1.3 / m0.face_width_mm
    fig, axes = plt.subplots(1, 2, figsize=(14, max(1.6, 6.0 * aspect) + 1.6), layout="constrained")
    values = {}
    for side in SIDES:
        e = report[side]
        values[side] = np.where(np.asarray(e["mask"]), np.asarray(e["ease_off_um"], float), np.nan)
    top = max(float(np.nanmax(v)) for v in values.values() if np.isfinite(v).any())
    from matplotlib.ticker import MaxNLocator

    levels = MaxNLocator(15).tick_values(0.0, max(top, 1e-3))
    cs = None
    for ax, side in zip(axes, SIDES, strict=True):
        x, y, outline = projections[side]
        cs = ax.contourf(x, y, values[side], levels=levels, cmap="viridis", extend="min")
        ax.contour(x, y, values[side], levels=levels[::3], colors="k", linewidths=0.4)
        undefined = (~np.isfinite(values[side])).astype(float)
        if undefined.any():
            ax.contourf(x, y, undefined, levels=[0.5, 1.5], colors="none", hatches=["////"])
            ax.fill(
                [],
                [],
                facecolor="white",
                edgecolor="0.4",
                hatch="////",
                label="not generated / no conjugate gear point" if side == "drive" else None,
            )
        ring = np.vstack([outline.corners_mm, outline.corners_mm[:1]])
        ax.plot(*ring.T, "k-", lw=1.0)
        ax.set_aspect("equal")
        ax.set_xlabel("cone distance from the toe (mm): toe -> heel")
        ax.set_ylabel("height (mm): root -> top")
        flank = "convex" if side == "drive" else "concave"
        ax.set_title(f"pinion {flank} ({side}): max {report[side]['max_um']:.1f} um", fontsize=9)
    fig.colorbar(cs, ax=list(axes), label="ease-off (um, normal to the flank)")
    fig.legend(loc="outside lower center", fontsize=8, frameon=False)
    fig.suptitle(f"{title}: ease-off (from the surface conjugate to the gear)")
    return fig


def backlash_figure(plt, report: dict, title: str, window_um=None):
    """Circumferential backlash along the mesh, with the window ``(min_um, max_um)`` if given."""
    fig, ax = plt.subplots(figsize=(7, 4))
    phi = np.asarray(report["phi1_deg"])
    b = np.asarray(report["circumferential_um"])
    ax.plot(phi, b, "o-", ms=3, label=f"backlash, mean {report['mean_um']:.1f} um")
    if window_um is not None:
        lo, hi = window_um
        ax.axhspan(lo, hi, color="C2", alpha=0.15, label=f"window {lo:g} to {hi:g} um")
        out = (b < lo) | (b > hi)
        if out.any():
            ax.plot(phi[out], b[out], "rx", ms=8, label="outside the window")
        span = hi - lo
        ax.set_ylim(min(lo, b.min()) - 0.2 * span, max(hi, b.max()) + 0.2 * span)
    if report["interference"]:
        ax.axhline(0.0, color="r", lw=1.0, label="interference below 0")
    ax.set_xlabel("pinion rotation (deg)")
    ax.set_ylabel(f"circumferential backlash (um) at r = {report['radius_mm']:.2f} mm")
    ax.set_title(f"{title}: backlash", fontsize=10)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    return fig


def misalignment_figure(plt, sweep, outlines: dict, to_tooth, title: str):
    """The pattern's movement under misalignment: M under each error alone, the V-H chart and
    the TE peak-to-peak, both sides. ``outlines``: ``{side: ToothOutline}`` of the pinion;
    ``to_tooth(side, points)``: pattern coordinates to the true projection."""
    fig, axes = plt.subplots(2, 3, figsize=(16, 7.5), gridspec_kw={"width_ratios": [3, 3, 2]})
    amp = sweep.amplitudes
    colors = {"V": "C0", "H": "C1", "J": "C2", "Sigma": "C4"}
    units = {"V": "mm", "H": "mm", "J": "mm", "Sigma": "deg"}
    for row, side in enumerate(SIDES):
        outline = outlines[side]
        ring = np.vstack([outline.corners_mm, outline.corners_mm[:1]])
        ax = axes[row, 0]
        ax.plot(*ring.T, "k-", lw=1.0)
        for letter, points in sweep.mean_point_mm[side].items():
            xy = to_tooth(side, points)
            ax.plot(*xy.T, "-", color=colors[letter], lw=1.2)
            ax.annotate(
                "",
                xy=xy[-1],
                xytext=xy[-2],
                arrowprops={"arrowstyle": "->", "color": colors[letter]},
            )
            edge = sweep.edge_contact[side][letter]
            ax.plot(*xy[edge].T, "rx", ms=7)
            ax.plot(
                [],
                [],
                "-",
                color=colors[letter],
                label=f"{letter} {-amp[letter]:+g} -> {amp[letter]:+g} {units[letter]}",
            )
        ax.plot(
            *to_tooth(side, sweep.mean_point_mm[side]["V"][len(sweep.steps) // 2]),
            "k*",
            ms=10,
            label="M, as assembled",
        )
        ax.plot([], [], "rx", label="edge contact")
        ax.set_aspect("equal")
        ax.set_title(f"pinion, {side}: M under each error alone", fontsize=9)
        ax.set_xlabel("cone distance from the toe (mm)")
        ax.set_ylabel("height (mm)")
        ax.legend(
            fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.45), ncol=3, frameon=False
        )
        ax = axes[row, 1]
        ax.plot(*ring.T, "k-", lw=1.0)
        vh = to_tooth(side, sweep.vh_mean_point_mm[side].reshape(-1, 2)).reshape(
            sweep.vh_mean_point_mm[side].shape
        )
        n = len(sweep.steps)
        for i in range(n):
            ax.plot(*vh[i].T, "-", color="C0", lw=0.8)  # V = steps[i], H varying
            ax.plot(*vh[:, i].T, "-", color="C1", lw=0.8)  # H = steps[i]
        for i in range(n):
            for j in range(n):
                v, h = sweep.steps[i] * amp["V"], sweep.steps[j] * amp["H"]
                edge = sweep.vh_edge_contact[side][i, j]
                ax.plot(*vh[i, j], "x" if edge else "o", color="r" if edge else "k", ms=4)
                if i in (0, n - 1) and j in (0, n - 1):  # the corners named
                    ax.annotate(
                        f"V{v:+.2g} H{h:+.2g}",
                        vh[i, j],
                        fontsize=6,
                        xytext=(2, 2),
                        textcoords="offset points",
                    )
        ax.set_aspect("equal")
        ax.set_title(
            f"pinion, {side}: V-H chart (M; lines of constant V blue, H orange)", fontsize=9
        )
        ax.set_xlabel("cone distance from the toe (mm)")
        ax = axes[row, 2]
        for letter, values in sweep.te_peak_to_peak_arcsec[side].items():
            ax.plot(sweep.steps, values, "o-", color=colors[letter], ms=3, label=letter)
        ax.set_xlabel("error / amplitude")
        ax.set_ylabel("TE peak-to-peak (arcsec)")
        ax.set_title(f"{side}: TE under each error", fontsize=9)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    fig.suptitle(
        f"{title}: pattern movement under misalignment (V offset, H pinion axial, J gear axial, "
        "Sigma shaft angle; + out of mesh for H and J)"
    )
    fig.tight_layout()
    return fig
