"""Write seed 002's five fourth-order TE designs (Table 2) from base.toml.

Each case keeps the base pair and asks, in ``[te_target]``, for the paper's pitch-point TE with
the same mesh-in TE and contact ratio (seed_cases.json: the cases share them; its caveat reads
the table's a as the quadratic and b as the quartic coefficient). ``gearopt realise-te`` -- the
inverse TCA -- fits the pinion's drive-side roll, and the design is written out with plain
settings (no ``[synthesis]``), so a study can search the roll terms themselves.

    python studies/fourth_order_te/make_cases.py
"""

from __future__ import annotations

import copy
import json
from pathlib import Path

import tomli_w

import gearopt
from gearopt.design import parse_design
from gearopt.plugins import get_machine_model

HERE = Path(__file__).resolve().parent
#: seed 002 Table 2, pitch-point TE (arcsec); mesh-in TE and contact ratio shared by the cases
PITCH_POINT_TE_ARCSEC = {1: -6.156, 2: -12.312, 3: -15.39, 4: -18.468, 5: -23.085}
MESH_IN_TE_ARCSEC = -80.0
CONTACT_RATIO = 2.3


def case_design(number: int) -> tuple[dict, dict]:
    """The TOML document of case ``number`` and the inverse TCA's report."""
    base = gearopt.load_design(HERE / "base.toml")
    data = copy.deepcopy(dict(base.source))
    data["te_target"] = {
        "pitch_point_te_arcsec": PITCH_POINT_TE_ARCSEC[number],
        "mesh_in_te_arcsec": MESH_IN_TE_ARCSEC,
        "contact_ratio": CONTACT_RATIO,
    }
    design = parse_design(data)
    table, report = get_machine_model(design.model).realise_te_target(design)
    data.pop("synthesis")
    data["machine"] = {"model": design.model, **table}
    data["meta"] = {
        "name": f"fourth_order_te_case{number}",
        "description": f"Seed 002 Table 2 case {number}: designed fourth-order TE by modified roll",
        "source": "base.toml, pinion drive roll by inverse TCA (make_cases.py)",
    }
    return data, report


def main() -> None:
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


if __name__ == "__main__":
    main()
