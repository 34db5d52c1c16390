"""The loaded TCA's figure (``ltca.png``): the LTE over the cycle per torque, the LTE
fluctuation versus torque, the load sharing of the pairs and the pressure map on the projected
tooth at the largest torque."""

from __future__ import annotations

import numpy as np

__all__ = ["ltca_figure"]


def ltca_figure(plt, ltca, title: str):
    """The loaded TCA: LTE over the cycle per torque, LTE fluctuation versus torque, load
    sharing and the pressure map at the largest torque."""
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
    return fig
