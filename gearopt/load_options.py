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

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from gearopt.errors import DesignError
from gearopt.validate import check_integer, check_keys, check_number, read_member_pair

__all__ = ["LOAD_KEYS", "LoadOptions", "PatchOptions", "check_torques"]

LOAD_KEYS = (
    "torque_nm",
    "youngs_modulus_mpa",
    "poisson_ratio",
    "fe_mesh",
    "patches",
    "reach_um",
)


def check_torques(torque_nm, name: str = "load.torque_nm") -> tuple[float, ...]:
    """Output torques (N m on the gear): a number or a non-empty list, each finite and >= 0."""
    values = list(torque_nm) if isinstance(torque_nm, list | tuple) else [torque_nm]
    if not values:
        raise DesignError(name, torque_nm, "must name at least one torque (N m)")
    return tuple(check_number(name, t, ge=0.0, unit="N m") for t in values)


def _integers(name: str, value: Any, count: int, least: int) -> tuple[int, ...]:
    if not (isinstance(value, list | tuple) and len(value) == count):
        raise DesignError(name, value, f"must be a list of {count} integers")
    return tuple(check_integer(f"{name}[{k}]", v, ge=least) for k, v in enumerate(value))


@dataclass(frozen=True, kw_only=True)
class PatchOptions:
    """The patch grid of a pair's potential contact zone (:mod:`gearopt.loaded.separations`):
    ``along`` the contact line (strips) and ``across`` it, both odd (a patch on the contact
    point), and how far it reaches: up to a separation of ``reach_um`` above the contact (the
    approach the largest load may bring), and at most ``max_half_width_mm`` across."""

    along: int = 41
    across: int = 15
    reach_um: float = 40.0
    max_half_width_mm: float = 4.0

    def __post_init__(self) -> None:
        along = check_integer("load.patches[along]", self.along, ge=5)
        across = check_integer("load.patches[across]", self.across, ge=3)
        if along % 2 == 0 or across % 2 == 0:
            raise DesignError(
                "load.patches", [along, across], "must be odd (a patch on the contact point)"
            )
        check_number("load.reach_um", self.reach_um, ge=1.0, le=1000.0, unit="um")
        check_number("max_half_width_mm", self.max_half_width_mm, gt=0.0, unit="mm")


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
        if self.torque_nm:
            object.__setattr__(self, "torque_nm", check_torques(self.torque_nm))
        for e in self.youngs_modulus_mpa:
            check_number("load.youngs_modulus_mpa", e, gt=0.0, unit="MPa")
        for nu in self.poisson_ratio:
            check_number("load.poisson_ratio", nu, gt=0.0, lt=0.5)
        _integers("load.patches", self.patches, 2, 3)
        self.patch_options()

    def patch_options(self) -> PatchOptions:
        """The patch grid these options ask for (checked)."""
        along, across = self.patches
        return PatchOptions(along=along, across=across, reach_um=self.reach_um)

    @classmethod
    def from_table(cls, table: Mapping[str, Any] | None, where: str = "load") -> LoadOptions:
        """Options from a ``[load]`` table (unknown keys refused)."""
        table = dict(table or {})
        check_keys(table, LOAD_KEYS, where)
        out: dict[str, Any] = {}
        if "torque_nm" in table:
            out["torque_nm"] = check_torques(table["torque_nm"], f"{where}.torque_nm")
        for key, bounds in (
            ("youngs_modulus_mpa", {"gt": 0.0}),
            ("poisson_ratio", {"gt": 0.0, "lt": 0.5}),
        ):
            if key in table:
                out[key] = read_member_pair(table, key, where, **bounds)
        if "fe_mesh" in table:
            out["fe_mesh"] = _integers(f"{where}.fe_mesh", table["fe_mesh"], 3, 2)
        if "patches" in table:
            out["patches"] = _integers(f"{where}.patches", table["patches"], 2, 3)
        if "reach_um" in table:
            out["reach_um"] = table["reach_um"]
        return cls(**out)

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
