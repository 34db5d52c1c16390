"""The gearopt command: settings, plugins, bench, and one-line errors."""

from __future__ import annotations

import json
import subprocess
import sys
import time

import pytest

from gearopt.cli import main
from gearopt.commands import time_call_ms

from .conftest import STUDIES

CONTRACT_KEYS = (
    "slope_angle_deg",
    "additional_slope_angle_deg",
    "inner_machine_distance_mm",
    "inner_cradle_angle_deg",
    "outer_machine_distance_mm",
    "outer_cradle_angle_deg",
    "machine_root_angle_deg",
    "machine_center_to_back_mm",
    "blank_offset_mm",
    "sliding_base_mm",
    "gear_to_cradle_roll",
    "gear_to_blade_roll",
)


def test_settings_json_has_the_contract_keys(capsys, seed_cases):
    assert main(["settings", str(STUDIES / "seed001_table3.toml"), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    ref = seed_cases["cyclo_palloid_seed001"]["expected_table3"]
    for member in ("pinion", "gear"):
        for key in CONTRACT_KEYS:
            assert isinstance(out[member][key], float), (member, key)
        assert out[member]["inner_machine_distance_mm"] == pytest.approx(
            ref[member]["inner_machine_distance_mm"], abs=1e-4
        )
    assert out["model"] == "cyclo-palloid"
    assert out["blank"]["pitch_angle_deg"][0] == pytest.approx(21.318, abs=5e-4)


def test_settings_table_is_readable(capsys):
    assert main(["settings", str(STUDIES / "seed001_table3.toml")]) == 0
    text = capsys.readouterr().out
    assert "inner_machine_distance_mm" in text and "86.280827" in text and "pinion" in text


def test_plugins_lists_the_builtin(capsys):
    assert main(["plugins"]) == 0
    assert "cyclo-palloid" in capsys.readouterr().out
    assert main(["plugins", "--json"]) == 0
    entries = json.loads(capsys.readouterr().out)
    assert {"kind": "machine-model", "name": "cyclo-palloid"}.items() <= entries[0].items()


def test_bad_design_is_one_line_on_stderr_with_status_2(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text(
        (STUDIES / "seed001_table3.toml")
        .read_text()
        .replace("blade_groups = 5", "blade_groups = 0")
    )
    run = subprocess.run(
        [sys.executable, "-m", "gearopt.cli", "settings", str(bad)], capture_output=True, text=True
    )
    assert run.returncode == 2
    assert run.stdout == ""
    assert run.stderr.strip().splitlines() == [
        "gearopt: error: DesignError: machine.blade_groups = 0: must be >= 1 and <= 30"
    ]


def test_bench_json_reports_medians(capsys):
    assert main(["bench", "--json", "--repeats", "1", "basic_settings_ms"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["threads"] == 1 and out["basic_settings_ms"] > 0.0
    assert out["cpu_ms"]["basic_settings_ms"] > 0.0
    assert len(out["runs_cpu_ms"]["basic_settings_ms"]) == 1


def test_timed_calls_carry_cpu_time_apart_from_wall_time():
    # a call that waits (sleeps) takes wall time but next to no CPU time of the process
    timed = time_call_ms(lambda: time.sleep(0.02), number=2)
    assert timed >= 20.0 and timed.cpu_ms < 10.0
    # one that computes on one thread takes CPU time, never more than the wall time it spans
    busy = time_call_ms(lambda: sum(i * i for i in range(200_000)), number=2)
    assert 0.0 < busy.cpu_ms <= 1.01 * float(busy) + 0.1


def test_bench_reports_the_tca_with_its_kernels(capsys):
    assert main(["bench", "--json", "--repeats", "1", "tca_ms"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["tca_ms"] > 0.0 and out["tca_grid"] == [25, 21]
    assert out["tca_kernels"].startswith(("numba ", "plain Python"))


def test_settings_reports_the_solved_slope_angles(capsys):
    assert main(["settings", str(STUDIES / "seed001_section5_3.toml"), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    for member in ("pinion", "gear"):
        assert 0.0 < out[member]["additional_slope_angle_deg"] < 0.2
    assert any("eqs 39-48" in note for note in out["notes"])


def test_flanks_json_measures_the_generated_flanks(capsys):
    assert main(["flanks", str(STUDIES / "seed001_table3.toml"), "--json", "--grid", "13,9"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["grid"] == [13, 9]
    for member, thickness in (("pinion", 5.271), ("gear", 5.276)):
        assert out[member]["mean_normal_chordal_thickness_mm"] == pytest.approx(thickness, abs=2e-3)
        for flank in ("convex", "concave"):
            entry = out[member][flank]
            assert entry["max_residual"] < 1e-12
            assert entry["tool_penetration_mm"] < 1e-6
            assert 0.0 < entry["generated_depth_mm"] <= 3.397 + 4.076
    # the pinion's envelope folds before its dedendum: it is generated less deep than the gear
    assert (
        out["pinion"]["concave"]["generated_depth_mm"]
        < out["gear"]["concave"]["generated_depth_mm"]
    )


def test_flanks_bad_grid_is_one_line(capsys):
    assert main(["flanks", str(STUDIES / "seed001_table3.toml"), "--grid", "3,x"]) == 2
    err = capsys.readouterr().err
    assert "--grid" in err and "n_face,n_profile" in err and len(err.strip().splitlines()) == 1


def test_bench_json_reports_flank_timings_with_the_grid(capsys):
    names = ["flank_generation_ms", "thickness_solve_ms"]
    assert main(["bench", "--json", "--repeats", "1", *names]) == 0
    out = json.loads(capsys.readouterr().out)
    for name in names:
        assert out[name] > 0.0
    assert out["flank_grid"] == [25, 13]


def test_analyze_json_has_the_contract_keys(capsys):
    # the contract: tca / tca_coast with side, phi1_deg, te_arcsec, the peak-to-peak,
    # the pattern's width, bias, centre offset and edge flag; backlash with its statistics
    assert main(["analyze", str(STUDIES / "seed001_section5_3.toml"), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    for key, side in (("tca", "drive"), ("tca_coast", "coast")):
        tca = out[key]
        assert tca["side"] == side
        assert len(tca["phi1_deg"]) == len(tca["te_arcsec"]) == 21
        assert max(tca["te_arcsec"]) <= 1e-9  # shifted so that the maximum is 0
        assert tca["te_peak_to_peak_arcsec"] >= -min(tca["te_arcsec"])
        pattern = tca["pattern"]
        assert {"width_mm", "bias_mm", "center_offset_mm", "edge_contact"} <= set(pattern)
        assert len(pattern["center_offset_mm"]) == 2
        assert isinstance(pattern["edge_contact"], bool)
    backlash = out["backlash"]
    assert len(backlash["circumferential_um"]) == 21
    assert backlash["min_um"] <= backlash["mean_um"] <= backlash["max_um"]
    assert backlash["interference"] is False
    assert out["ease_off"]["drive"]["max_um"] > 0.0


def test_analyze_circumferential_separation_and_plots(capsys, tmp_path):
    pytest.importorskip("matplotlib")
    args = ["analyze", str(STUDIES / "seed001_section5_3.toml"), "--json"]
    args += ["--separation", "circumferential", "--compound-um", "10", "--plot", str(tmp_path)]
    assert main(args) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["tca"]["pattern"]["separation"] == "circumferential"
    assert out["tca"]["pattern"]["compound_um"] == 10.0
    for name in ("te.png", "pattern.png", "backlash.png", "ease_off.png"):
        path = tmp_path / name
        assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
        assert path.stat().st_size > 10_000


def test_analyze_bad_option_is_one_line(capsys):
    args = ["analyze", str(STUDIES / "seed001_section5_3.toml"), "--compound-um", "-3"]
    assert main(args) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "compound_um" in err[0]


def test_analysis_table_of_the_design_gives_defaults_the_options_override(capsys, tmp_path):
    text = (STUDIES / "seed001_section5_3.toml").read_text()
    design = tmp_path / "design.toml"
    design.write_text(text + '\n[analysis]\nseparation = "circumferential"\ncompound_um = 10.0\n')
    assert main(["analyze", str(design), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["conditions"]["separation"] == "circumferential"
    assert out["tca"]["pattern"]["compound_um"] == 10.0
    assert main(["analyze", str(design), "--json", "--compound-um", "6.5"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["tca"]["pattern"]["compound_um"] == 6.5
    assert out["tca"]["pattern"]["separation"] == "circumferential"
    design.write_text(text + "\n[analysis]\npositions = 2\n")
    assert main(["analyze", str(design)]) == 2
    err = capsys.readouterr().err
    assert "analysis.positions = 2" in err


def test_version():
    out = subprocess.run(
        [sys.executable, "-m", "gearopt.cli", "--version"], capture_output=True, text=True
    )
    assert out.returncode == 0
    assert out.stdout.strip().startswith("gearopt ")
    assert out.stdout.strip() != "gearopt unknown"  # the installed distribution's version


def test_a_reader_that_goes_away_gets_no_traceback():
    # ``gearopt settings X --json | head -0``: the pipe's reader closes before gearopt writes
    proc = subprocess.Popen(
        [sys.executable, "-m", "gearopt.cli", "settings", str(STUDIES / "seed001_table3.toml")]
        + ["--json"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
    )
    proc.stdout.close()
    err = proc.stderr.read().decode()
    proc.stderr.close()
    assert proc.wait() == 1
    assert "Traceback" not in err and "BrokenPipeError" not in err


def test_bench_thickness_solve_times_the_solve_not_the_memory(monkeypatch):
    # issue 19 item 5: thickness_solve_ms read 0.018 ms, the remembered settings answering;
    # every timed call (and the warm-up) must run the solve of seed 001 eqs 39-48
    from gearopt.bench import bench_thickness_solve
    from gearopt_plugins import cyclo_palloid

    solve = cyclo_palloid.solve_additional_slope_angle
    calls = []

    def counted(design, member, settings):
        calls.append(design.pair.mean_normal_chordal_thickness_mm[0])
        return solve(design, member, settings)

    monkeypatch.setattr(cyclo_palloid, "solve_additional_slope_angle", counted)
    bench_thickness_solve()
    assert len(calls) == 4 and len(set(calls)) == 4
