"""The flank contract suite (:class:`FlankContract`): what every generated FlankMap must satisfy.

Each check measures the generated flanks themselves, not what the solver was told: the meshing
residual at every generated node, normals that point out of the tooth, the mirror image for the
opposite hand, the next tool pass cutting the next tooth, and no tool position penetrating the
flank (which needs the FlankMap's ``surface``).
"""

from __future__ import annotations

import math
import tomllib

import numpy as np
import pytest

from gearopt.design import Design
from gearopt.design_files import loads_design, parse_design
from gearopt.errors import GearoptError
from gearopt.flank import FLANKS, MEMBERS, FlankGrid, FlankMap
from gearopt.testing.machine_models import MachineModelContract

__all__ = ["FlankContract"]

RESIDUAL_LIMIT = 1e-12  # meshing residual normalised by |N| A_m
PENETRATION_LIMIT_MM = 1e-6
SAME_POINT_MM = 1e-9


def _wrap(angle):
    return (angle + math.pi) % (2.0 * math.pi) - math.pi


class FlankContract(MachineModelContract):
    """The machine-model checks plus those every flank generator must pass. Subclass it with
    the fixtures of :class:`gearopt.testing.MachineModelContract` (``machine_model``,
    ``design_text``) and, optionally:

    ``exact_indexing_design_text``
        A design whose machine indexes exactly (the next tool pass cuts the next tooth);
        default ``design_text``.
    ``flank_grid``
        The grid to generate on; default ``FlankGrid()``.
    """

    @pytest.fixture
    def flank_grid(self) -> FlankGrid:
        return FlankGrid()

    @pytest.fixture
    def exact_indexing_design_text(self, design_text) -> str:
        return design_text

    @pytest.fixture
    def flanks(self, machine_model, design, flank_grid) -> dict[tuple[str, str], FlankMap]:
        out = {}
        for member in MEMBERS:
            maps = machine_model.generate_flanks(design, member=member, grid=flank_grid)
            for flank in FLANKS:
                out[member, flank] = maps[flank]
        return out

    def test_flanks_are_labelled_flankmaps_on_the_grid(self, flanks, design, flank_grid):
        for (member, flank), fm in flanks.items():
            assert isinstance(fm, FlankMap)
            assert (fm.member, fm.flank, fm.tooth) == (member, flank, 0)
            assert fm.hand == design.blank.hand[MEMBERS.index(member)]
            assert fm.shape == flank_grid.shape
            assert fm.mask.mean() >= 0.5, f"{member} {flank}: less than half the grid generated"
            normals = fm.normals[fm.mask]
            assert np.allclose(np.linalg.norm(normals, axis=-1), 1.0, atol=1e-12)

    def test_generated_nodes_satisfy_the_meshing_equation(self, flanks):
        for key, fm in flanks.items():
            worst = float(fm.residual[fm.mask].max())
            assert worst <= RESIDUAL_LIMIT, f"{key}: meshing residual {worst:.2e}"

    def test_generated_region_is_one_band_per_face_column(self, flanks):
        for key, fm in flanks.items():
            for column in fm.mask:
                on = np.flatnonzero(column)
                assert on.size, f"{key}: a face column with no generated node"
                assert np.all(np.diff(on) == 1), f"{key}: a column's generated nodes have a gap"
                assert on[-1] == len(column) - 1, f"{key}: the top of a column is not generated"

    def test_normals_point_out_of_the_tooth(self, flanks, design):
        # tooth 0's material lies between its convex and concave flank: each normal's
        # circumferential component points away from the other flank, across the tooth space
        s = design.blank.mean_cone_distance_mm
        for member in MEMBERS:
            convex, concave = flanks[member, "convex"], flanks[member, "concave"]
            i = int(np.argmin(np.abs(convex.face_mm - s)))
            j = int(np.argmin(np.abs(convex.profile_mm)))
            toward = _wrap(concave.polar_angle_rad[i, j] - convex.polar_angle_rad[i, j])
            assert 0.0 < abs(toward) < convex.pitch_rad, f"{member}: flanks of different teeth"
            for fm, sign in ((convex, 1.0), (concave, -1.0)):
                theta = fm.polar_angle_rad[i, j]
                n = fm.normals[i, j]
                around = -math.sin(theta) * n[0] + math.cos(theta) * n[1]
                assert sign * around * toward < 0.0, f"{member} {fm.flank}: normal into the tooth"

    def test_opposite_hand_gives_the_mirror_image(
        self, flanks, machine_model, design_text, plugin_manager, flank_grid
    ):
        data = tomllib.loads(design_text)
        hand = data["pair"].get("pinion_hand", "left")
        data["pair"]["pinion_hand"] = "right" if hand == "left" else "left"
        other = parse_design(data, plugin_manager=plugin_manager)
        for member in MEMBERS:
            maps = machine_model.generate_flanks(other, member=member, grid=flank_grid)
            for flank in FLANKS:
                mine, theirs = flanks[member, flank].mirrored(), maps[flank]
                assert theirs.hand == mine.hand
                assert np.array_equal(theirs.mask, mine.mask)
                on = mine.mask
                gap = np.abs(theirs.points_mm - mine.points_mm)[on].max()
                assert gap <= SAME_POINT_MM, f"{member} {flank}: mirror off by {gap:.2e} mm"
                assert np.abs(theirs.normals - mine.normals)[on].max() <= 1e-9

    def test_next_tool_pass_cuts_the_next_tooth(
        self, machine_model, exact_indexing_design_text, plugin_manager, flank_grid
    ):
        design: Design = loads_design(exact_indexing_design_text, plugin_manager=plugin_manager)
        for member in MEMBERS:
            first = machine_model.generate_flanks(design, member=member, grid=flank_grid)
            second = machine_model.generate_flanks(
                design, member=member, grid=flank_grid, tool_pass=1
            )
            for flank in FLANKS:
                nxt = second[flank]
                assert abs(nxt.tooth) == 1
                turned = first[flank].tooth_turned(nxt.tooth)
                assert np.array_equal(turned.mask, nxt.mask)
                gap = np.abs(turned.points_mm - nxt.points_mm)[nxt.mask].max()
                assert gap <= SAME_POINT_MM, f"{member} {flank}: next tooth off by {gap:.2e} mm"

    def test_no_tool_position_penetrates_the_flank(self, flanks):
        for key, fm in flanks.items():
            if fm.surface is None:
                pytest.skip("the model's FlankMaps carry no surface (tool positions unknown)")
            depth = fm.tool_penetration_mm()
            assert depth <= PENETRATION_LIMIT_MM, f"{key}: the tool penetrates {depth:.2e} mm"

    def test_exact_surface_agrees_with_the_grid(self, flanks):
        for key, fm in flanks.items():
            if fm.surface is None:
                pytest.skip("the model's FlankMaps carry no surface")
            s, h = np.meshgrid(fm.face_mm, fm.profile_mm, indexing="ij")
            exact = fm.polar_angle_exact(s[fm.mask], h[fm.mask])
            assert np.abs(exact - fm.polar_angle_rad[fm.mask]).max() <= 1e-12, key

    def test_unknown_member_or_flank_is_refused(self, machine_model, design):
        with pytest.raises(GearoptError, match="member"):
            machine_model.generate_flank(design, member="wheel", flank="convex")
        with pytest.raises(GearoptError, match="flank"):
            machine_model.generate_flank(design, member="gear", flank="drive")
