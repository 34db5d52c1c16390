"""Point contact or line contact (:meth:`gearopt.mesh.zone.Zones.closed`): a flat lag (no TE)
is a line contact's, or a point contact's whose contact points stay on one conjugate line
(seed 003 section 7.1, case A). Told apart by the marking compound's zone at the middle of
the contact interval (seed 003 section 5): a point contact's closes on the flanks along its
valley, where the separation rises as half the least curvature times the distance squared; a
line contact's valley is its contact line, the separation on it the interpolants' error."""

from __future__ import annotations

import numpy as np
import pytest

import gearopt
from gearopt.analysis import AnalysisOptions, meshed_pair
from gearopt.mesh.cycle import MeshCycle

from .conftest import STUDIES

SEED003 = {"separation": "circumferential", "compound_um": 10.0}


def _cycle(name: str, conditions: dict, grid) -> MeshCycle:
    design = gearopt.load_design(STUDIES / name)
    extra = {"grid": list(grid)} if grid else {}
    options = AnalysisOptions.from_conditions({**conditions, **extra}, design=design)
    pair = meshed_pair(design, options)
    kinds = ("positions", "pairs", "cycles", "compound_um", "separation")
    cycle = MeshCycle(
        [pair.drive, pair.coast],
        ("drive", "coast"),
        frame=pair.frame,
        **{kind: getattr(options, kind) for kind in kinds},
    )
    cycle.main_sample(np.zeros(2))
    return cycle


def _valley(cycle: MeshCycle, side: int):
    zones, contact = cycle.centre_zones([cycle.sides[side]])
    return zones.valley([0], contact[:, 0], contact[:, 1])


@pytest.mark.parametrize("grid", [None, (81, 161)], ids=["default", "81x161"])
def test_case_a_is_a_point_contact_without_te(grid):
    # seed 003 case A (pinion convex R_h = 135 mm against the gear's 137.4 mm, drive): no TE,
    # one conjugate line of contact points, each an ellipse's centre
    cycle = _cycle("seed003_case_A.toml", SEED003, grid)
    drive = cycle.sides[0]
    assert drive.interval_flat and drive.point_contact
    distance, least, inside = _valley(cycle, 0)
    compound = cycle.compound_um * 1e-3
    for way in range(2):
        # the valley rises through the compound on the flanks, as kappa t^2 / 2 with one kappa
        # (the least curvature of the separation's quadratic form)
        zone = inside[way] & (least[way] <= compound)
        rising = np.flatnonzero(inside[way] & (least[way] > compound))
        assert rising.size and rising[0] == np.flatnonzero(zone).max() + 1
        t, y = distance[way][zone], least[way][zone]
        kappa = 2.0 * y[t > 2.0] / t[t > 2.0] ** 2
        assert np.ptp(kappa) < 0.05 * kappa.mean(), kappa
        # its zone: the contact ellipse's half major axis, 10 mm and more
        assert t.max() > 8.0


@pytest.mark.parametrize("grid", [None, (81, 161)], ids=["default", "81x161"])
def test_the_conjugate_face_milled_pair_is_a_line_contact(grid):
    # Litvin's conjugate face-milled pair: line contact on both sides, no TE
    cycle = _cycle("face_milling_conjugate.toml", {}, grid)
    compound = cycle.compound_um * 1e-3
    for k, side in enumerate(cycle.sides):
        assert side.interval_flat and not side.point_contact, side.index
        distance, least, inside = _valley(cycle, k)
        # the valley runs along the contact line to the flanks' edge, the separation on it
        # the interpolants' error: far below the compound however far it runs
        assert inside[:, 0].all()
        assert np.nanmax(np.abs(least[inside])) < 0.05 * compound
        # and runs some way on the flank: a line, not a point
        assert max(distance[way][inside[way]].max() for way in range(2)) > 10.0
