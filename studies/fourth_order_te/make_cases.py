"""Write seed 002's five fourth-order TE designs (Table 2) from base.toml.

Each case keeps the base pair and asks, in ``[te_target]``, for the paper's pitch-point TE with
the same mesh-in TE and contact ratio (tests/data/seed_cases.json: the cases share them; its
caveat reads the table's a as the quadratic and b as the quartic coefficient).

1. ``--adjust`` (slow, about a minute a case): as seed 002 does, the reference point M is moved
   along the tooth height and the drive side's path direction turned until the contact of the
   designed pair -- followed on the exact surfaces by the inverse TCA -- stays on both flanks
   (inside both blanks, and above the fold of the pinion flank the fitted roll generates, as
   the envelope solver trims it) over the design contact ratio, symmetrically about M (entry
   and exit equal). The two numbers
   of each case go to ``adjusted.json``.
2. Then each case: the base's local synthesis with that M and path, ``realise_te_target`` (the
   inverse TCA) fits the pinion's drive-side roll, and the design is written out with plain
   settings (no ``[synthesis]``), so a study can search the roll terms themselves.

    python studies/fourth_order_te/make_cases.py [--adjust]
"""

from __future__ import annotations

import copy
import json
import math
import sys
from pathlib import Path

import numpy as np
import tomli_w
from scipy.optimize import least_squares

import gearopt
from gearopt.analysis import AnalysisOptions
from gearopt.design_files import parse_design
from gearopt.plugins import get_machine_model
from gearopt_plugins.face_milling import FaceMilling

HERE = Path(__file__).resolve().parent
#: seed 002 Table 2, pitch-point TE (arcsec); mesh-in TE and contact ratio shared by the cases
PITCH_POINT_TE_ARCSEC = {1: -6.156, 2: -12.312, 3: -15.39, 4: -18.468, 5: -23.085}
MESH_IN_TE_ARCSEC = -80.0
CONTACT_RATIO = 2.3
ADJUSTED = HERE / "adjusted.json"


def _source(number: int, adjusted: dict | None = None) -> dict:
    """The base document with case ``number``'s target and (when given) its M and path."""
    data = copy.deepcopy(dict(gearopt.load_design(HERE / "base.toml").source))
    data["te_target"] = {
        "pitch_point_te_arcsec": PITCH_POINT_TE_ARCSEC[number],
        "mesh_in_te_arcsec": MESH_IN_TE_ARCSEC,
        "contact_ratio": CONTACT_RATIO,
    }
    if adjusted is not None:
        data["synthesis"]["drive"]["mean_point_profile_mm"] = adjusted["mean_point_profile_mm"]
        data["synthesis"]["drive"]["path_angle_deg"] = adjusted["path_angle_deg"]
    return data


def adjust(number: int) -> dict:
    """M's height and the drive path direction that centre the contact interval of case
    ``number`` on M with the design contact ratio (exact surfaces, inverse TCA)."""
    from gearopt_plugins.face_milling.inverse import inverse_tca

    data = _source(number)
    design = parse_design(data)
    pitch = 2.0 * math.pi / design.pair.pinion_teeth
    profile0 = design.machine.synthesis[0].targets.mean_point_profile_mm
    face = design.machine.synthesis[0].targets.mean_point_face_mm
    path0 = data["synthesis"]["drive"]["path_angle_deg"]

    def residual(z):
        trial = copy.deepcopy(data)
        trial["synthesis"]["drive"]["mean_point_profile_mm"] = profile0 + z[0]
        trial["synthesis"]["drive"]["path_angle_deg"] = path0 + z[1]
        d = parse_design(trial)
        mean = (face, profile0 + z[0])
        # the pinion flank the fitted roll generates ends above its fold: the contact must too
        fitted = parse_design(_realised(trial, d))
        options = AnalysisOptions.from_conditions({}, design=fitted)
        fm = FaceMilling().generate_flank(
            fitted, member="pinion", flank="convex", grid=options.grid
        )
        result = inverse_tca(d, d.te_target, mean_point_mm=mean, pinion_region=fm.inside)
        start, end = result.interval_rad
        return np.array([(start + end) / pitch, (end - start) / pitch - CONTACT_RATIO])

    start = [0.0, 0.0]
    if ADJUSTED.exists():  # from the last adjustment
        last = json.loads(ADJUSTED.read_text()).get(str(number))
        if last:
            start = [last["mean_point_profile_mm"] - profile0, last["path_angle_deg"] - path0]
    sol = least_squares(
        residual, start, bounds=([-1.5, -5.0], [1.5, 5.0]), diff_step=1e-3, xtol=1e-10
    )
    return {
        "mean_point_profile_mm": float(profile0 + sol.x[0]),
        "path_angle_deg": float(path0 + sol.x[1]),
        "residual": [float(v) for v in sol.fun],
    }


def _realised(data: dict, design) -> dict:
    """``data`` with the roll the inverse TCA fits and plain settings."""
    table, _ = get_machine_model(design.model).realise_te_target(design)
    out = copy.deepcopy(data)
    out.pop("synthesis")
    out["machine"] = {"model": design.model, **table}
    return out


def case_design(number: int) -> tuple[dict, dict]:
    """The TOML document of case ``number`` and the inverse TCA's report."""
    adjusted = json.loads(ADJUSTED.read_text())[str(number)]
    data = _source(number, adjusted)
    design = parse_design(data)
    table, report = get_machine_model(design.model).realise_te_target(design)
    data.pop("synthesis")
    data["machine"] = {"model": design.model, **table}
    data["meta"] = {
        "name": f"fourth_order_te_case{number}",
        "description": f"Seed 002 Table 2 case {number}: designed fourth-order TE by modified roll",
        "source": "base.toml, pinion drive roll by inverse TCA (make_cases.py)",
    }
    report["adjusted"] = adjusted
    return data, report


def main() -> None:
    if "--adjust" in sys.argv:
        out = {str(n): adjust(n) for n in PITCH_POINT_TE_ARCSEC}
        ADJUSTED.write_text(json.dumps(out, indent=2) + "\n", encoding="utf-8")
    for number in PITCH_POINT_TE_ARCSEC:
        data, report = case_design(number)
        header = "".join(
            f"# {line}\n"
            for line in (
                f"Seed 002 Table 2, case {number}: written by make_cases.py from base.toml.",
                "The pinion's convex (drive) roll fitted by inverse TCA to [te_target]:",
                *json.dumps(report, indent=1).splitlines(),
            )
        )
        path = HERE / f"case{number}.toml"
        path.write_text(header + "\n" + tomli_w.dumps(data), encoding="utf-8")
        print(f"{path.name}: " + ", ".join(f"{k} {v:.6g}" for k, v in report["after"].items()))
        if number == 5:
            write_study(data)


STUDY = """\
# An Optuna study whose search space is the drive roll terms themselves: can a search find
# case 5's designed TE without the inverse TCA? Bounds: three times the magnitude of the
# inverse TCA's answer, symmetric about zero (the study is not told the answer's sign); c5
# and c6 are fixed at 0. Written by make_cases.py.
#
#   gearopt study run studies/fourth_order_te/roll_study.toml --trials 64 --jobs 2

[study]
name = "fourth_order_te_roll"
design = "case5.toml"
sampler = "tpe"
seed = 20261123

[search]
{search}
[fixed]
"machine.pinion.convex.roll_c5" = 0.0
"machine.pinion.convex.roll_c6" = 0.0

[evaluations.tca]
conditions = {{ grid = [31, 21] }}

[[objectives]]
name = "te_target"
label = "te_target_rms_arcsec"
"""


def write_study(case5: dict) -> None:
    """roll_study.toml from case 5's fitted roll."""
    roll = case5["machine"]["pinion"]["convex"]
    search = "".join(
        f'"machine.pinion.convex.{key}" = [{-3.0 * abs(roll[key])!r}, {3.0 * abs(roll[key])!r}]\n'
        for key in ("roll_c2", "roll_c3", "roll_c4")
    )
    (HERE / "roll_study.toml").write_text(STUDY.format(search=search), encoding="utf-8")


if __name__ == "__main__":
    main()
