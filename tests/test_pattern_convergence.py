"""Contact-pattern figures that converge with the grid (issue 19, item 2): every figure at the
default grid (25 x 21) against the same design at 81 x 161, on seed 001 section 5.3 (both
sides, normal separation, 6.5 um) and seed 003 cases A, B, C (drive, circumferential, 10 um:
seed 003 sections 5-6).

Tolerance: the issue's, 1 % of the fine grid's value or 0.05 mm, whichever is larger (the
contact ratio, a ratio: 1 %). Before the zones were measured on the refined field
(``gearopt.mesh.zone``) the default grid read the section 5.3 drive side's ellipse major axis
as 10.50 mm against 12.95 mm at 81 x 161, case C's as 13.23 against 16.68 mm.
"""

from __future__ import annotations

import pytest

import gearopt
from gearopt.analysis import AnalysisOptions, contact_sides, meshed_pair

from .conftest import STUDIES

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
FINE = [81, 161]
FIGURES = (
    "width_mm",
    "ellipse_major_axis_mm",
    "ellipse_minor_axis_mm",
    "mean_point_face_mm",
    "mean_point_profile_mm",
    "bias_mm",
    "contact_ratio",
)
#: known gaps (none: the six of section 5.3's widths and drive contact ratio, case A's M, bias
#: and contact ratio were closed by the generated boundary solved per column and a flat TE's
#: contact interval solved on its tangency point; see the module docstring)
GAPS: set = set()

_RESULTS: dict = {}


def _sides(case: str, grid):
    key = (case, tuple(grid) if grid else None)
    if key not in _RESULTS:
        name, overrides, conditions = CASES[case]
        design = gearopt.with_overrides(gearopt.load_design(STUDIES / name), overrides)
        extra = {"grid": list(grid)} if grid else {}
        options = AnalysisOptions.from_conditions({**conditions, **extra}, design=design)
        _RESULTS[key] = contact_sides(meshed_pair(design, options), options)
    return _RESULTS[key]


def _figure(contact, figure: str) -> float:
    if figure == "mean_point_face_mm":
        return contact.mean_point_mm[0]
    if figure == "mean_point_profile_mm":
        return contact.mean_point_mm[1]
    return getattr(contact, figure)


def _params():
    for case in CASES:
        for side in ("drive", "coast") if case == "section 5.3" else ("drive",):
            for figure in FIGURES:
                marks = ()
                if (case, side, figure) in GAPS:
                    marks = pytest.mark.xfail(strict=True, reason="known gap: see GAPS")
                yield pytest.param(case, side, figure, marks=marks, id=f"{case}-{side}-{figure}")


@pytest.mark.parametrize(("case", "side", "figure"), list(_params()))
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
