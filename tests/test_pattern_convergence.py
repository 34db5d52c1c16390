"""Contact-pattern figures that converge with the grid (issue 19, item 2): every figure at the
default grid (25 x 21) against the same design at 81 x 161, on seed 001 section 5.3 (both
sides, normal separation, 6.5 um) and seed 003 cases A, B, C (drive, circumferential, 10 um:
seed 003 sections 5-6).

Tolerance: the issue's, 1 % of the fine grid's value or 0.05 mm, whichever is larger (the
contact ratio, a ratio: 1 %). Before the zones were measured on the refined field
(``gearopt.mesh.zone``) the default grid read the section 5.3 drive side's ellipse major axis
as 10.50 mm against 12.95 mm at 81 x 161, case C's as 13.23 against 16.68 mm. The outline
polygon (``ToothContact.outline_mm``) is checked the same way: Hausdorff distance and area.
"""

from __future__ import annotations

import numpy as np
import pytest

import gearopt
from gearopt.analysis import AnalysisOptions

from .conftest import STUDIES
from .grid_convergence import FINE, analysed_sides, figure_params

SEED003 = {"separation": "circumferential", "compound_um": 10.0}
PINION = "machine.pinion.convex."
CASES = {
    "section 5.3": ("seed001_section5_3.toml", {}, {}),
    "case A": ("seed003_case_A.toml", {}, SEED003),
    "case B": (
        "seed003_case_A.toml",
        {PINION + "cutter_head_radius_mm": 137.4, PINION + "blade_profile_radius_mm": 509.634},
        SEED003,
    ),
    "case C": ("seed003_case_A.toml", {PINION + "blade_profile_radius_mm": 509.634}, SEED003),
}
FIGURES = (
    "width_mm",
    "ellipse_major_axis_mm",
    "ellipse_minor_axis_mm",
    "mean_point_face_mm",
    "mean_point_profile_mm",
    "bias_mm",
    "contact_ratio",
)
#: known gaps: none left. How they closed (default / 81 x 161): section 5.3's drive contact
#: interval starts at the toe-root corner, where the tangency point crosses the gear's toe edge:
#: the point lies along a 13 mm ellipse's major axis, where a 0.04 um error of the pinion's
#: interpolant in the cell through the generated boundary (the envelope's fold 0.3 mm below: Theta
#: is not cubic there) moved it by tenths of a mm (contact ratio 2.752 / 2.705 on the flank's own
#: cells); on the fine cells of the exact surface there (gearopt.contact.boundary) it reads 2.7045
#: / 2.7049. Case A's lag is flat (no TE) but its contact is a point's
#: (gearopt.mesh.zone.Zones.closed, tests/test_point_contact.py): its interval's ends are solved on
#: the tangency point and M is centred on the interval, M (26.387, 7.639) / (26.385, 7.639), bias
#: -2.042 / -2.045, contact ratio 1.3209 / 1.3207 (read as a line contact: 7.39 / 6.85, -1.49 /
#: -0.25, 1.275 / 1.375).
GAPS: set = set()


def _sides(case: str, grid):
    name, overrides, conditions = CASES[case]
    return analysed_sides(name, grid, overrides, conditions)


def _figure(contact, figure: str) -> float:
    if figure == "mean_point_face_mm":
        return contact.mean_point_mm[0]
    if figure == "mean_point_profile_mm":
        return contact.mean_point_mm[1]
    return getattr(contact, figure)


#: section 5.3 on both sides, the seed 003 cases on the drive side
SIDES = [
    (case, side)
    for case in CASES
    for side in (("drive", "coast") if case == "section 5.3" else ("drive",))
]


@pytest.mark.parametrize(("case", "side", "figure"), list(figure_params(SIDES, FIGURES, GAPS)))
def test_pattern_figure_at_the_default_grid_is_the_fine_grids(case, side, figure):
    coarse = _figure(_sides(case, None)[side], figure)
    fine = _figure(_sides(case, FINE)[side], figure)
    tolerance = 0.01 * abs(fine)
    if figure != "contact_ratio":
        tolerance = max(tolerance, 0.05)
    assert abs(coarse - fine) <= tolerance, (coarse, fine)


def test_the_default_grid_is_the_analysis_default():
    # the convergence above is of the grid every analysis uses unless told otherwise
    design = gearopt.load_design(STUDIES / "seed001_section5_3.toml")
    options = AnalysisOptions.from_conditions({}, design=design)
    assert list(options.grid.shape) == [25, 21]


#: the outline's known gaps (Hausdorff distance default / 81 x 161): none. Case A's read 1.77 mm,
#: its interval's ends solved or not: its first station's sampled minimum is held at the
#: engine's refinement margin at the default grid, which turned the path's direction there by
#: some 40 degrees; 0.009 mm (areas 189.125 / 189.134 mm^2) with a point contact's stations on
#: its tangency points (gearopt.mesh.zone.Zones.tangency_points)
OUTLINE_GAPS: set = set()


def _to_segments(points, polygon):
    """Distances from ``points`` ``(m, 2)`` to the closed polygon's edges."""
    a = polygon
    b = np.roll(polygon, -1, axis=0)
    ab = b - a
    t = np.einsum("mkd,kd->mk", points[:, None, :] - a[None], ab) / np.maximum(
        np.einsum("kd,kd->k", ab, ab), 1e-300
    )
    near = a[None] + np.clip(t, 0.0, 1.0)[..., None] * ab[None]
    return np.min(np.linalg.norm(points[:, None, :] - near, axis=-1), axis=1)


def _ring(polygon, step_mm=0.02):
    edges = zip(polygon, np.roll(polygon, -1, axis=0), strict=True)
    return np.concatenate(
        [
            a
            + np.linspace(0.0, 1.0, max(int(np.hypot(*(b - a)) / step_mm), 1), endpoint=False)[
                :, None
            ]
            * (b - a)
            for a, b in edges
        ]
    )


def _area(polygon):
    x, y = polygon[:, 0], polygon[:, 1]
    return 0.5 * abs(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))


def _outline_params():
    for case in CASES:
        for side in ("drive", "coast") if case == "section 5.3" else ("drive",):
            marks = ()
            if (case, side) in OUTLINE_GAPS:
                marks = pytest.mark.xfail(strict=True, reason="known gap: see OUTLINE_GAPS")
            yield pytest.param(case, side, marks=marks, id=f"{case}-{side}")


@pytest.mark.parametrize(("case", "side"), list(_outline_params()))
def test_pattern_outline_at_the_default_grid_is_the_fine_grids(case, side):
    # the outline polygon (ToothContact.outline_mm, what the tca evaluator stores as its
    # pattern): the Hausdorff distance between the default grid's and 81 x 161's within
    # 0.05 mm, their areas within 1 % (the node outline, lowest and highest marked node per
    # column, read 0.85-1.8 mm and 12-16 % less area)
    coarse = _sides(case, None)[side].outline_mm
    fine = _sides(case, FINE)[side].outline_mm
    assert len(coarse) > 4 and len(fine) > 4
    distance = max(_to_segments(_ring(coarse), fine).max(), _to_segments(_ring(fine), coarse).max())
    assert distance <= 0.05, distance
    assert abs(_area(coarse) - _area(fine)) <= 0.01 * _area(fine)
