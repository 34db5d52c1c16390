"""The face-milling machine's correction settings for the closed loop (``gearopt correct``).

A member whose two flanks share every machine setting is cut in one set-up (spread blade,
completing: Gleason's gear) and one key of each setting serves both flanks; otherwise each flank
is cut in its own set-up (fixed setting, the pinion) and has its own keys. The blade angle is
always per blade, hence per flank.
"""

from __future__ import annotations

from gearopt.design import Design
from gearopt.flank import FLANKS
from gearopt.machine import CorrectionSetting

#: the settings a machine operator corrects, with finite-difference steps in their units
MACHINE_STEPS = {
    "radial_setting_mm": 1e-3,
    "cradle_angle_deg": 1e-3,
    "machine_root_angle_deg": 1e-3,
    "sliding_base_mm": 1e-3,
    "blank_offset_mm": 1e-3,
    "ratio_of_roll": 1e-5,
    "roll_c2": 1e-5,
}
BLADE_STEPS = {"blade_pressure_angle_deg": 1e-3}
#: settings whose values must agree on both flanks for one set-up
SET_UP = (*MACHINE_STEPS, "machine_center_to_back_mm", *(f"roll_c{k}" for k in range(3, 7)))


def correction_settings(design: Design, member: str) -> tuple[CorrectionSetting, ...]:
    """The face-milling correction settings of ``member`` (module docstring)."""
    spec = design.machine.member(member)
    flanks = {f: spec.flank(f) for f in FLANKS}
    one_set_up = all(getattr(flanks["convex"], k) == getattr(flanks["concave"], k) for k in SET_UP)
    tables = design.source.get("machine", {}).get(member, {})
    out = []
    for key, step in MACHINE_STEPS.items():
        if one_set_up:
            own = tuple(f"machine.{member}.{f}.{key}" for f in FLANKS if key in tables.get(f, {}))
            main = f"machine.{member}.{key}"
            out.append(
                CorrectionSetting(
                    key=main, value=float(getattr(flanks["convex"], key)), step=step, also=own
                )
            )
        else:
            out += [
                CorrectionSetting(
                    key=f"machine.{member}.{f}.{key}",
                    value=float(getattr(flanks[f], key)),
                    step=step,
                )
                for f in FLANKS
            ]
    for key, step in BLADE_STEPS.items():
        out += [
            CorrectionSetting(
                key=f"machine.{member}.{f}.{key}",
                value=float(getattr(flanks[f], key)),
                step=step,
                correctable=False,
            )
            for f in FLANKS
        ]
    return tuple(out)
