"""TE near the pinion's generated boundary converges with the grid (issue 19, item 2): TE
peak-to-peak, the edge-contact flag and the contact ratio at the default grid (25 x 21)
against the same design at 81 x 161, on the designs whose contact runs to the pinion's
generated boundary (docs/figures.md, "TE near the generated boundary").

Tolerances: TE within 0.05 arcsec (the noise floor a conjugate pair's TE is held to,
tests/test_te_target.py) or 1 % of the fine grid's, whichever is larger; the contact ratio within
1 %; the edge flag the same. Before the pinion's fine cells at its generated boundary
(:mod:`gearopt.contact.boundary`) the refinement stayed two cells above the lowest generated
nodes: the 14 x 39 coast side read 7.483 arcsec with edge contact at the default grid against
6.176 at 81 x 161 (now 6.176 / 6.176), section 5.2's coast side 1.160 (edge contact) against
0.806, the margin's lag at both grids (now 0.003 / 0.000, 0.000 at 161 x 321: a line contact).
"""

from __future__ import annotations

import pytest

from .grid_convergence import FINE, analysed_sides, figure_params

CASES = {
    "face_milling_14x39": "iso23509/face_milling_14x39.toml",
    "section 5.2": "seed001_section5_2.toml",
    "cyclo_palloid_17x43": "iso23509/cyclo_palloid_17x43.toml",
    "table 3": "seed001_table3.toml",
}
SIDES = (
    ("face_milling_14x39", "coast"),
    ("face_milling_14x39", "drive"),
    ("section 5.2", "coast"),
    ("cyclo_palloid_17x43", "coast"),
    ("table 3", "drive"),
)
FIGURES = ("te_peak_to_peak_arcsec", "edge_contact", "contact_ratio")
#: known gaps, measured (default / 81 x 161):
#: - the 14 x 39 drive side's TE 8.341 / 8.130 arcsec: the samples agree to 0.001 arcsec, but
#:   at the hand-over (-12.15 / -12.00 deg) the incoming pair touches the pinion's tip edge
#:   (lag 8.147 / 7.574 arcsec at -12.214 deg): the top edge, not the generated boundary
#:   (25 x 81 reads 8.130, 81 x 21 8.238);
#: - the 17 x 43 coast side: 0.291 (edge contact, contact ratio 0.30) / 0.147 (1.30); 0.215
#:   (edge, 0.20) at 41 x 81, 0.150 (2.62) at 161 x 321: a lag flat within 0.15 arcsec, whose
#:   edge flag and contact interval move with every grid (case A's gap,
#:   tests/test_pattern_convergence.py);
#: - section 5.2's coast side and Table 3's drive side are conjugate (TE 0.003 / 0.000 and
#:   0.018 / 0.000): a line contact has no unique tangency point, so the contact ratio (0.74 /
#:   1.25, 1.61 / 2.91) is the edge flag's bracket in noise (the same gap).
GAPS = {
    ("face_milling_14x39", "drive", "te_peak_to_peak_arcsec"),
    ("cyclo_palloid_17x43", "coast", "te_peak_to_peak_arcsec"),
    ("cyclo_palloid_17x43", "coast", "edge_contact"),
    ("cyclo_palloid_17x43", "coast", "contact_ratio"),
    ("section 5.2", "coast", "contact_ratio"),
    ("table 3", "drive", "contact_ratio"),
}


def _sides(case: str, grid):
    return analysed_sides(CASES[case], grid)


@pytest.mark.parametrize(("case", "side", "figure"), list(figure_params(SIDES, FIGURES, GAPS)))
def test_te_figure_at_the_default_grid_is_the_fine_grids(case, side, figure):
    coarse = getattr(_sides(case, None)[side], figure)
    fine = getattr(_sides(case, FINE)[side], figure)
    if figure == "edge_contact":
        assert coarse == fine
        return
    tolerance = 0.01 * abs(fine)
    if figure == "te_peak_to_peak_arcsec":
        tolerance = max(tolerance, 0.05)
    assert abs(coarse - fine) <= tolerance, (coarse, fine)


def test_a_conjugate_pairs_te_stays_in_noise_up_to_the_generated_boundary():
    # the refinement reaches the generated boundary on the fine cells without raising a
    # conjugate pair's noise floor (fitting the boundary cell's one cubic instead read 0.12;
    # 0.050 / 0.000 with the two-cell margin, 0.018 / 0.000 now)
    for grid in (None, FINE):
        assert _sides("table 3", grid)["drive"].te_peak_to_peak_arcsec <= 0.05
