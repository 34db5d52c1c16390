"""``gearopt chain`` and ``gearopt change-gears``: JSON keys, tables, one-line errors."""

from __future__ import annotations

import json

import pytest

from gearopt.chains import WorkGear, chain_error, load_machine, select_change_gears
from gearopt.cli import main

CHAIN_Z15 = [
    "chain",
    "zftkk250x5",
    "--work-teeth",
    "15",
    "--normal-module-mm",
    "3.5",
    "--spiral-angle-deg",
    "35",
    "--indexing-gears",
    "48,45,60,60",
    "--envelope-gears",
    "40,64,62,52",
    "--cradle-swing-deg",
    "55",
]
KEYS = (
    "theoretical_ratio",
    "max_ratio",
    "min_ratio",
    "ratio_error",
    "ratio_error_percent",
    "angle_error_deg",
    "pitch_error_um",
)


def _json(capsys, argv):
    assert main(argv) == 0
    return json.loads(capsys.readouterr().out)


def test_chain_json(capsys):
    out = _json(capsys, [*CHAIN_Z15, "--json"])
    assert set(out) == {"indexing", "envelope"}
    machine = load_machine("zftkk250x5")
    gears = {
        **machine.quadrant_gears("indexing", (48, 45, 60, 60)),
        **machine.quadrant_gears("envelope", (40, 64, 62, 52)),
    }
    work = WorkGear(teeth=15, normal_module_mm=3.5, spiral_angle_deg=35.0)
    for chain, result in out.items():
        for key in KEYS:
            assert isinstance(result[key], float), key
        want = chain_error(
            machine, chain, gears={s: gears[s] for s in machine.slots_of(chain)}, work=work
        )
        assert result["ratio_error"] == pytest.approx(want.ratio_error, rel=1e-12)
        assert result["pitch_error_um"] == pytest.approx(want.pitch_error_um, rel=1e-12)
        assert len(result["elements"]) == len(want.elements)
    assert out["envelope"]["theoretical_ratio"] == pytest.approx(2.23655914, rel=1e-8)
    assert out["indexing"]["input_angle_deg"] == 720.0
    # the check, within 10 % of the paper's 20.64 um (tests/test_chains.py says why)
    assert out["indexing"]["pitch_error_um"] == pytest.approx(20.64, rel=0.1)


def test_chain_text_tables(capsys):
    assert main(CHAIN_Z15) == 0
    text = capsys.readouterr().out
    assert "indexing chain of 'zftkk250x5'" in text and "envelope chain" in text
    for column in ("ratio_error_percent", "dphi_deg", "max_deg", "z96", "worm_cradle"):
        assert column in text


def test_chain_chooses_gears_from_the_crown_gear(capsys):
    argv = [a for a in CHAIN_Z15 if a not in ("--indexing-gears", "48,45,60,60")]
    argv = [a for a in argv if a not in ("--envelope-gears", "40,64,62,52")]
    out = _json(capsys, [*argv, "--crown-teeth", "33.54101966", "--json"])
    choice = out["envelope"]["change_gears"]
    assert abs(choice["error"]) < 1.6e-4  # better than the paper's 40/64 x 62/52
    quad = out["indexing"]["change_gears"]["gears"]
    assert quad[0] * quad[2] * 15 == 16 * quad[1] * quad[3]


def test_change_gears_json(capsys):
    out = _json(capsys, ["change-gears", "zftkk250x5", "--ratio", "0.745356", "--json"])
    best = select_change_gears(0.745356, load_machine("zftkk250x5").change_gears, top_k=5)
    assert out["gears"] == list(best[0].gears)
    assert out["ratio"] == pytest.approx(best[0].ratio, rel=1e-15)
    assert out["error"] == pytest.approx(best[0].ratio - 0.745356, abs=1e-15)
    assert abs(out["error"]) <= 1.6e-4
    assert len(out["candidates"]) == 5


def test_change_gears_text_and_machine_path(capsys):
    path = load_machine("zftkk250x5").path
    assert main(["change-gears", path, "--ratio", "1.0666667", "--top-k", "3"]) == 0
    text = capsys.readouterr().out
    assert "a/b/c/d" in text and len(text.strip().splitlines()) == 6


@pytest.mark.parametrize(
    ("argv", "fragment"),
    [
        (["--indexing-gears", "20,21,90,22"], "cannot mesh"),
        (["--indexing-gears", "48,45,60"], "four tooth counts"),
        (["--envelope-gears", "40,64,62,0"], ">= 1"),
        (["--cradle-swing-deg", "-5"], "must be > 0"),
    ],
)
def test_chain_errors_are_one_line(capsys, argv, fragment):
    base = list(CHAIN_Z15)
    for option, value in zip(argv[::2], argv[1::2], strict=True):
        base[base.index(option) + 1] = value
    assert main(base) == 2
    err = capsys.readouterr().err
    assert err.startswith("gearopt: error: DesignError") and fragment in err
    assert len(err.strip().splitlines()) == 1


def test_unknown_machine(capsys):
    assert main(["change-gears", "nosuch", "--ratio", "1.0"]) == 2
    assert "unknown machine" in capsys.readouterr().err


def test_chain_needs_envelope_gears_or_the_crown_gear(capsys):
    argv = [a for a in CHAIN_Z15 if a not in ("--envelope-gears", "40,64,62,52")]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert "crown_teeth" in err and "envelope change gears" in err
