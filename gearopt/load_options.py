"""The options of loaded contact: the ``[load]`` table of design and study files.

Keys (every one optional but ``torque_nm`` for an analysis under load):

- ``torque_nm``: output torque on the gear (N m), a number or a list for a sweep;
- ``youngs_modulus_mpa``, ``poisson_ratio``: the members' material, a number or
  ``[pinion, gear]`` (steel: 206000 MPa, 0.3);
- ``fe_mesh``: ``[n_face, n_profile, n_thickness]`` elements of each tooth's finite-element
  model (:mod:`gearopt.loaded.compliance`);
- ``patches``: ``[along, across]`` patches of each pair's potential contact zone
  (:mod:`gearopt.loaded.separations`), odd numbers;
- ``reach_um``: how far above the unloaded contact the potential contact zone reaches.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from gearopt.errors import GearoptError

__all__ = ["LOAD_KEYS", "LoadOptions"]

LOAD_KEYS = (
    "torque_nm",
    "youngs_modulus_mpa",
    "poisson_ratio",
    "fe_mesh",
    "patches",
    "reach_um",
)


def _number(value: Any) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool)


def _pair_of(name: str, value: Any) -> tuple[float, float]:
    if _number(value):
        return float(value), float(value)
    if isinstance(value, list | tuple) and len(value) == 2 and all(_number(v) for v in value):
        return float(value[0]), float(value[1])
    raise GearoptError(name, value, "must be a number or [pinion, gear]")


def _integers(name: str, value: Any, count: int, least: int) -> tuple[int, ...]:
    ok = isinstance(value, list | tuple) and len(value) == count
    ok = ok and all(isinstance(v, int) and not isinstance(v, bool) and v >= least for v in value)
    if not ok:
        raise GearoptError(name, value, f"must be {count} integers of at least {least}")
    return tuple(int(v) for v in value)


@dataclass(frozen=True, kw_only=True)
class LoadOptions:
    """Checked options of loaded contact (module docstring).

    Attributes
    ----------
    torque_nm
        Output torques on the gear (N m), each finite and >= 0.
    youngs_modulus_mpa, poisson_ratio
        ``(pinion, gear)``; E > 0, 0 < nu < 0.5.
    fe_mesh
        ``(n_face, n_profile, n_thickness)`` elements of each tooth model, or None for the
        default.
    patches
        ``(along, across)`` patches of each pair's potential contact zone.
    reach_um
        The potential contact zone: up to this separation above the unloaded contact.
    """

    torque_nm: tuple[float, ...] = ()
    youngs_modulus_mpa: tuple[float, float] = (206000.0, 206000.0)
    poisson_ratio: tuple[float, float] = (0.3, 0.3)
    fe_mesh: tuple[int, int, int] | None = None
    patches: tuple[int, int] = (41, 15)
    reach_um: float = 40.0

    def __post_init__(self) -> None:
        for t in self.torque_nm:
            if not (_number(t) and math.isfinite(t)):
                raise GearoptError("load.torque_nm", t, "must be a finite number of N m")
            if t < 0.0:
                raise GearoptError("load.torque_nm", t, "must not be negative (N m)")
        for e in self.youngs_modulus_mpa:
            if not (math.isfinite(e) and e > 0.0):
                raise GearoptError("load.youngs_modulus_mpa", e, "must be positive (MPa)")
        for nu in self.poisson_ratio:
            if not (math.isfinite(nu) and 0.0 < nu < 0.5):
                raise GearoptError("load.poisson_ratio", nu, "must lie in (0, 0.5)")
        along, across = self.patches
        if along % 2 == 0 or across % 2 == 0 or along < 5 or across < 3:
            raise GearoptError("load.patches", list(self.patches), "must be odd, at least [5, 3]")
        if not (_number(self.reach_um) and 1.0 <= self.reach_um <= 1000.0):
            raise GearoptError("load.reach_um", self.reach_um, "must be in [1, 1000] um")

    @classmethod
    def from_table(cls, table: Mapping[str, Any] | None, where: str = "load") -> LoadOptions:
        """Options from a ``[load]`` table (unknown keys refused)."""
        table = dict(table or {})
        unknown = sorted(set(table) - set(LOAD_KEYS))
        if unknown:
            raise GearoptError(f"{where}.{unknown[0]}", rule=f"unknown; known: {list(LOAD_KEYS)}")
        out: dict[str, Any] = {}
        if "torque_nm" in table:
            value = table["torque_nm"]
            values = value if isinstance(value, list | tuple) else [value]
            if not values:
                raise GearoptError(f"{where}.torque_nm", value, "must name at least one torque")
            out["torque_nm"] = tuple(values)
        for key in ("youngs_modulus_mpa", "poisson_ratio"):
            if key in table:
                out[key] = _pair_of(f"{where}.{key}", table[key])
        if "fe_mesh" in table:
            out["fe_mesh"] = _integers(f"{where}.fe_mesh", table["fe_mesh"], 3, 2)
        if "patches" in table:
            out["patches"] = _integers(f"{where}.patches", table["patches"], 2, 3)
        if "reach_um" in table:
            out["reach_um"] = table["reach_um"]
        try:
            return cls(**out)
        except GearoptError as exc:
            if exc.parameter.startswith(where):
                raise
            raise GearoptError(f"{where}.{exc.parameter}", exc.value, exc.rule) from None

    def with_torques(self, torque_nm) -> LoadOptions:
        """The same options at other torques."""
        values = torque_nm if isinstance(torque_nm, list | tuple) else [torque_nm]
        return LoadOptions(
            torque_nm=tuple(values),
            youngs_modulus_mpa=self.youngs_modulus_mpa,
            poisson_ratio=self.poisson_ratio,
            fe_mesh=self.fe_mesh,
            patches=self.patches,
            reach_um=self.reach_um,
        )

    def as_dict(self) -> dict:
        """JSON-ready form."""
        return {
            "torque_nm": list(self.torque_nm),
            "youngs_modulus_mpa": list(self.youngs_modulus_mpa),
            "poisson_ratio": list(self.poisson_ratio),
            "fe_mesh": None if self.fe_mesh is None else list(self.fe_mesh),
            "patches": list(self.patches),
            "reach_um": self.reach_um,
        }
