"""The contact pattern's movement under misalignment: sweeps of each assembly error and a V-H
grid, run on the analyses' public interface (:func:`gearopt.analysis.analysed_flanks`,
:func:`gearopt.mesh.mesh_pair`, :func:`gearopt.analysis.contact_sides`) for the figures of
``gearopt analyze --plot`` and ``gearopt report``.

The errors are the housing's ``[misalignment]`` keys (docs/architecture.md, "Housing frame and
misalignment"), added to the design's own: V = ``offset_mm`` (dE, pinion along +y_f),
H = ``pinion_axial_mm`` (dA1, out of mesh positive), J = ``gear_axial_mm`` (dA2, out of mesh
positive), Sigma = ``shaft_angle_deg`` (dGamma).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import NDArray

from gearopt.analysis import AnalysisOptions, analysed_flanks, contact_sides
from gearopt.assembly import Misalignment
from gearopt.mesh import mesh_pair

__all__ = ["ERRORS", "MisalignmentSweep", "misalignment_sweep"]

#: the swept errors: (letter, misalignment key, unit, default amplitude)
ERRORS = (
    ("V", "offset_mm", "mm", 0.1),
    ("H", "pinion_axial_mm", "mm", 0.1),
    ("J", "gear_axial_mm", "mm", 0.1),
    ("Sigma", "shaft_angle_deg", "deg", 0.05),
)


@dataclass(frozen=True, kw_only=True)
class MisalignmentSweep:
    """The sweeps' results, per side (``"drive"``, ``"coast"``).

    Attributes
    ----------
    steps
        ``(n,)`` the sweep's steps in units of each error's amplitude (-1 ... 1).
    amplitudes
        ``{letter: amplitude}`` (mm, or deg for Sigma).
    mean_point_mm
        ``{side: {letter: (n, 2)}}`` M in pattern coordinates (face from the toe, profile
        from the root) at each step.
    te_peak_to_peak_arcsec, edge_contact
        ``{side: {letter: (n,)}}``.
    vh_mean_point_mm
        ``{side: (n, n, 2)}``: M at V = steps[i] * V amplitude, H = steps[j] * H amplitude.
    vh_edge_contact
        ``{side: (n, n)}``.
    """

    steps: NDArray
    amplitudes: dict
    mean_point_mm: dict
    te_peak_to_peak_arcsec: dict
    edge_contact: dict
    vh_mean_point_mm: dict
    vh_edge_contact: dict


def _run(design, options: AnalysisOptions, base: Misalignment, changes: dict) -> dict:
    values = {key: getattr(base, key) + value for key, value in changes.items()}
    mis = replace(base, **values)
    # the flanks generated once (the analyses' own), placed anew at each misalignment
    flanks = analysed_flanks(design, options)
    sides = contact_sides(mesh_pair(design, flanks, misalignment=mis), options)
    return {
        name: (np.array(tc.mean_point_mm), tc.te_peak_to_peak_arcsec, tc.edge_contact)
        for name, tc in sides.items()
    }


def misalignment_sweep(
    design, options: AnalysisOptions, *, steps: int = 3, amplitudes: dict | None = None
) -> MisalignmentSweep:
    """Sweep V, H, J and Sigma one at a time over ``steps`` values from -1 to +1 times their
    amplitude (default :data:`ERRORS`), and the V-H grid, each a TCA of both sides.

    Parameters
    ----------
    design
        The design.
    options
        The analyses' options (the grid, positions, compound...); its ``misalignment`` (or the
        design's) is the sweep's centre.
    steps
        Values per error (odd, at least 3).
    amplitudes
        ``{letter: amplitude}`` overriding the defaults.
    """
    amp = {letter: default for letter, _, _, default in ERRORS}
    amp.update(amplitudes or {})
    base = options.misalignment or design.misalignment
    grid = np.linspace(-1.0, 1.0, steps)
    key = {letter: name for letter, name, _, _ in ERRORS}
    centre = _run(design, options, base, {})
    runs = {}
    for letter in key:
        runs[letter] = [
            centre if x == 0.0 else _run(design, options, base, {key[letter]: x * amp[letter]})
            for x in grid
        ]
    vh = [
        [
            runs["H"][j]
            if x == 0.0
            else runs["V"][i]
            if y == 0.0
            else _run(
                design, options, base, {"offset_mm": x * amp["V"], "pinion_axial_mm": y * amp["H"]}
            )
            for j, y in enumerate(grid)
        ]
        for i, x in enumerate(grid)
    ]
    sides = ("drive", "coast")
    return MisalignmentSweep(
        steps=grid,
        amplitudes=amp,
        mean_point_mm={
            s: {k: np.array([r[s][0] for r in v]) for k, v in runs.items()} for s in sides
        },
        te_peak_to_peak_arcsec={
            s: {k: np.array([r[s][1] for r in v]) for k, v in runs.items()} for s in sides
        },
        edge_contact={
            s: {k: np.array([r[s][2] for r in v]) for k, v in runs.items()} for s in sides
        },
        vh_mean_point_mm={s: np.array([[c[s][0] for c in row] for row in vh]) for s in sides},
        vh_edge_contact={s: np.array([[c[s][2] for c in row] for row in vh]) for s in sides},
    )
