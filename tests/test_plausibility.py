"""Results that are not a gear mesh are errors, the unusual ones warnings (issues 19 and 27).

Every ``--json`` output of ``settings``, ``flanks``, ``flank`` and ``analyze`` carries a
``warnings`` list (strings naming their rule), printed on stderr in text mode.
"""

from __future__ import annotations

import json
import re

import pytest

from gearopt.cli import main
from gearopt.design_files import load_design
from gearopt.errors import DesignError
from gearopt.plausibility import contact_findings, flank_findings

from .conftest import STUDIES

TABLE3 = STUDIES / "seed001_table3.toml"


def _with_pinion_teeth(tmp_path, teeth: int):
    # seed 001 Table 3 with fewer pinion teeth (the module kept, the cone distance derived)
    text = TABLE3.read_text().replace("pinion_teeth = 16", f"pinion_teeth = {teeth}")
    text = re.sub(r"^mean_cone_distance_mm = .*$", "", text, flags=re.M)
    path = tmp_path / f"pinion_{teeth}.toml"
    path.write_text(text)
    return path


def _json(capsys, argv) -> dict:
    assert main(argv) == 0
    return json.loads(capsys.readouterr().out)


@pytest.mark.parametrize("teeth", [5, 7])
def test_a_pinion_generated_short_of_the_working_depth_is_a_warning(tmp_path, capsys, teeth):
    # issue 19 item 5: a 7 (or 5) tooth pinion was reported generated down to h = -0.5 mm
    # against a 5 mm dedendum without a word; the gear's tip reaches h = -3.397 mm
    out = _json(capsys, ["flanks", str(_with_pinion_teeth(tmp_path, teeth)), "--json"])
    depth = [w for w in out["warnings"] if w.startswith("working depth")]
    assert depth and all("pinion" in w and "-3.397" in w for w in depth)
    assert out["pinion"]["convex"]["lowest_generated_height_mm"]["middle"] > -0.5 * 3.397
    # the published pair (its pinion generated to 0.85 of the working depth) has none
    assert _json(capsys, ["flanks", str(TABLE3), "--json"])["warnings"] == []


def test_analyze_of_a_seven_tooth_pinion_reports_its_warnings(tmp_path, capsys):
    # issue 19 item 5: IndexError in contact.py's _refined; now a result with its warnings,
    # on stderr in text mode
    design = str(_with_pinion_teeth(tmp_path, 7))
    out = _json(capsys, ["analyze", design, "--json", "--grid", "13,21", "--positions", "11"])
    assert any(w.startswith("working depth: the pinion") for w in out["warnings"])
    assert any(w.startswith("edge contact") for w in out["warnings"])
    assert main(["analyze", design, "--grid", "13,21", "--positions", "11"]) == 0
    err = capsys.readouterr().err.splitlines()
    assert err and all(line.startswith("gearopt: warning: ") for line in err)


@pytest.mark.parametrize(
    ("member", "at", "generated"),
    [
        # h = -3.81 mm on the pinion, past its envelope's fold (-3.2 mm at the middle)
        ("pinion", "86.40,29.63", False),
        ("pinion", "85.38,32.24", True),  # h = -1.0 mm
        # h = -4.0 mm on the gear, below where its blades' tips pass (-3.75 to -3.94 mm)
        ("gear", "36.90,83.56", False),
        ("gear", "34.12,84.18", True),  # h = -1.2 mm
    ],
)
def test_flank_at_says_whether_the_tool_generates_the_point(capsys, member, at, generated):
    # issue 19 item 5: points on envelope the blade never cuts were returned without a word
    argv = ["flank", str(TABLE3), "--member", member, "--flank", "convex", "--at", at, "--json"]
    out = _json(capsys, argv)
    assert out["inside_blank"] is True
    assert out["generated"] is generated
    assert bool(out["warnings"]) is not generated


def test_settings_json_carries_a_warnings_list(capsys):
    assert _json(capsys, ["settings", str(TABLE3), "--json"])["warnings"] == []


def _side(side, te=10.0, ratio=1.5, edge=False):
    pattern = {"edge_contact": edge}
    return {"side": side, "te_peak_to_peak_arcsec": te, "contact_ratio": ratio, "pattern": pattern}


def test_results_that_are_not_a_gear_mesh_are_errors():
    ok = {"tca": _side("drive"), "tca_coast": _side("coast"), "backlash": {"min_um": 100.0}}
    assert contact_findings(ok) == []
    # issue 27: 4006 arcsec of TE and 7.8 mm of interference were reported with exit 0
    with pytest.raises(DesignError, match="one degree"):
        contact_findings({**ok, "tca": _side("drive", te=4006.0)})
    with pytest.raises(DesignError, match="interference"):
        contact_findings({**ok, "backlash": {"min_um": -7800.0}})
    warned = contact_findings({**ok, "tca_coast": _side("coast", ratio=0.7, edge=True)})
    assert [w.split(":")[0] for w in warned] == ["contact ratio", "edge contact"]
    design = load_design(TABLE3)
    summary = {"lowest_generated_height_mm": {"middle": -3.0}, "tool_penetration_mm": 3.03}
    with pytest.raises(DesignError, match="tool penetration"):
        flank_findings(design, "pinion", "convex", summary, row_mm=0.5)
    summary["tool_penetration_mm"] = 1e-12
    assert flank_findings(design, "pinion", "convex", summary, row_mm=0.5) == []
