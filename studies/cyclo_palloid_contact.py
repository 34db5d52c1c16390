"""Search the cyclo-palloid settings of the seed 001 pair for a low TE and a contact pattern
that stays centred and on the flanks under the section 5.4 misalignment, with backlash inside
a window: the Python twin of ``cyclo_palloid_contact.toml``.

Run it with ``python studies/cyclo_palloid_contact.py [TRIALS]``. It runs on two worker processes
and keeps its study in ``cyclo_palloid_contact_script.db`` beside this file, so running it again
continues the study. For a single-process ``study.optimize`` (a notebook), use
``gearopt.study.trial_objective(SPEC)`` as the objective function.
"""

from __future__ import annotations

import sys
from pathlib import Path

from gearopt.study import run_study
from gearopt.studyfile import parse_study_spec

HERE = Path(__file__).resolve().parent

# seed 001 section 5.4: the four assembly errors together (housing frame and signs:
# docs/architecture.md, Frames and signs)
SECTION_5_4 = {
    "offset_mm": 0.221,
    "pinion_axial_mm": -0.005,
    "gear_axial_mm": 0.188,
    "shaft_angle_deg": -0.062,
}
PINION = "machine.pinion."

SPEC = parse_study_spec(
    {
        "study": {
            "name": "cyclo_palloid_contact_script",
            "design": "seed001_section5_3.toml",
            "sampler": "tpe",
            "seed": 20261123,
        },
        "search": {
            PINION + "inner_cutter_radius_mm": [74.0, 76.0],
            PINION + "outer_cutter_radius_mm": [74.5, 77.0],
            PINION + "additional_slope_angle_deg": [-0.2, 0.15],
            PINION + "blade_parabola_coefficient_per_mm": [0.0005, 0.003],
        },
        "evaluations": {
            "tca": {},
            "misaligned": {"evaluator": "tca", "conditions": {"misalignment": SECTION_5_4}},
            "backlash": {},
        },
        "objectives": [
            {
                "name": "worst_te",
                "label": "worst_te_arcsec",
                "on": ["tca", "misaligned"],
                "side": "both",
            },
            {
                "name": "pattern_movement",
                "label": "pattern_movement_mm",
                "misaligned": "misaligned",
            },
        ],
        "constraints": [
            {
                "name": "backlash_window",
                "label": "backlash_window_um",
                "min_um": 150.0,
                "max_um": 260.0,
            },
            {"name": "edge_contact", "on": ["tca", "misaligned"], "side": "both"},
        ],
        "enqueue": [
            {
                PINION + "inner_cutter_radius_mm": 75.0,
                PINION + "outer_cutter_radius_mm": 75.5,
                PINION + "additional_slope_angle_deg": 0.0523,
                PINION + "blade_parabola_coefficient_per_mm": 0.0015,
            },
            {  # a feasible start (the study file says why)
                PINION + "inner_cutter_radius_mm": 74.11,
                PINION + "outer_cutter_radius_mm": 75.77,
                PINION + "additional_slope_angle_deg": -0.0746,
                PINION + "blade_parabola_coefficient_per_mm": 0.00101,
            },
        ],
    },
    path=HERE / "cyclo_palloid_contact.py",
)


def main(trials: int = 48) -> None:
    summary = run_study(SPEC, trials=trials, jobs=2)
    best = summary.best
    print(f"{summary.complete} complete trials; {summary.trials_per_s:.2f} trials/s")
    if best is not None:
        print(f"best trial {best.number}: {dict(zip(SPEC.metric_names, best.values, strict=True))}")
        print(f"design saved as {summary.best_design_path}")


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 48)
