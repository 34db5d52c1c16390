"""Contact analysis of a design: the options the evaluators share, and the analyses themselves.

:func:`meshed_pair` generates a design's flanks and places them in the housing (with the
design's ``[misalignment]`` unless the options give another); :func:`contact_sides`,
:func:`pair_backlash` and :func:`pair_ease_off` run the unloaded TCA of both sides, the backlash
and the ease-off on it (:mod:`gearopt.mesh`). The evaluator plugins ``tca``, ``backlash`` and
``ease-off`` call them with options taken from their conditions.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from gearopt.design import Design, Misalignment
from gearopt.errors import GearoptError
from gearopt.flank import FlankGrid
from gearopt.mesh import (
    Backlash,
    EaseOff,
    MeshedPair,
    ToothContact,
    _check_options,
    backlash,
    ease_off,
    mesh_pair,
    tooth_contacts,
)

__all__ = [
    "AnalysisOptions",
    "TCA_GRID",
    "contact_sides",
    "meshed_pair",
    "pair_backlash",
    "pair_ease_off",
]

#: The FlankMap grid of the contact analyses (n_face, n_profile): the profile is sampled more
#: finely than the flank default because the pinion's fold spoils interpolation in its lowest
#: cells and the contact refinement must stay above them.
TCA_GRID = FlankGrid(n_face=25, n_profile=21)


@dataclass(frozen=True, kw_only=True)
class AnalysisOptions:
    """Options of the contact analyses (the evaluators' conditions, ``gearopt analyze``).

    Attributes
    ----------
    positions, pairs, cycles
        Contact positions over ``cycles`` mesh cycles, tooth pairs at each (21, 3, 2: seed 001).
    compound_um
        Marking-compound thickness of the pattern (6.5 um, seed 001; seed 003 uses 10).
    separation
        ``"normal"`` (along the surface normal) or ``"circumferential"`` (two points at equal
        radius, seed 003).
    grid
        FlankMap grid of both members.
    misalignment
        How the pair is assembled; ``None``: the design's ``[misalignment]``.
    """

    positions: int = 21
    pairs: int = 3
    cycles: float = 2.0
    compound_um: float = 6.5
    separation: str = "normal"
    grid: FlankGrid = field(default_factory=lambda: TCA_GRID)
    misalignment: Misalignment | None = None

    KEYS = ("positions", "pairs", "cycles", "compound_um", "separation", "grid", "misalignment")

    def __post_init__(self) -> None:
        _check_options(self.positions, self.pairs, self.cycles, self.compound_um, self.separation)

    @classmethod
    def from_conditions(
        cls, conditions: Mapping[str, Any] | None, *, design=None, where: str = "conditions"
    ) -> AnalysisOptions:
        """Options from an evaluator's conditions: the keys of this class; ``grid`` as
        ``[n_face, n_profile]``, ``misalignment`` as a table of the ``[misalignment]`` keys.
        A ``design``'s ``[analysis]`` table gives the defaults the conditions override."""
        conditions = {**(design.analysis if design is not None else {}), **(conditions or {})}
        unknown = sorted(set(conditions) - set(cls.KEYS))
        if unknown:
            raise GearoptError(where, unknown[0], f"unknown; known: {list(cls.KEYS)}")
        if "grid" in conditions and not isinstance(conditions["grid"], FlankGrid):
            grid = conditions["grid"]
            if not (isinstance(grid, list | tuple) and len(grid) == 2):
                raise GearoptError(f"{where}.grid", grid, "must be [n_face, n_profile]")
            conditions["grid"] = FlankGrid(n_face=grid[0], n_profile=grid[1])
        mis = conditions.get("misalignment")
        if mis is not None and not isinstance(mis, Misalignment):
            if not isinstance(mis, Mapping):
                raise GearoptError(f"{where}.misalignment", mis, "must be a table")
            conditions["misalignment"] = Misalignment.from_table(mis, "misalignment")
        try:
            return cls(**conditions)
        except TypeError as exc:
            raise GearoptError(where, conditions, f"invalid: {exc}") from None

    def as_dict(self) -> dict:
        """JSON-ready form (the ``conditions`` of an evaluation)."""
        mis = self.misalignment
        return {
            "positions": self.positions,
            "pairs": self.pairs,
            "cycles": self.cycles,
            "compound_um": self.compound_um,
            "separation": self.separation,
            "grid": list(self.grid.shape),
            "misalignment": None
            if mis is None
            else {
                "offset_mm": mis.offset_mm,
                "pinion_axial_mm": mis.pinion_axial_mm,
                "gear_axial_mm": mis.gear_axial_mm,
                "shaft_angle_deg": mis.shaft_angle_deg,
            },
        }


#: the last few designs' flanks and meshed pairs, so that the evaluators of one design
#: (``gearopt analyze`` runs tca, backlash and ease-off; a study evaluates several
#: misalignments) generate its flanks once; keyed by the design object's identity
_RECENT: list[tuple[Design, tuple, Any]] = []


def _recent(design: Design, key: tuple, make):
    for known, known_key, value in _RECENT:
        if known is design and known_key == key:
            return value
    value = make()
    _RECENT.insert(0, (design, key, value))
    del _RECENT[8:]
    return value


def meshed_pair(design: Design, options: AnalysisOptions, *, plugin_manager=None) -> MeshedPair:
    """The design's flanks generated on the options' grid and placed in the housing (the last
    few are kept: the same design object on the same grid is generated once, and placed once
    per misalignment)."""
    if plugin_manager is not None:
        return mesh_pair(
            design,
            grid=options.grid,
            misalignment=options.misalignment,
            plugin_manager=plugin_manager,
        )
    from gearopt import generate_flanks

    flanks = _recent(
        design,
        ("flanks", options.grid.shape),
        lambda: tuple(generate_flanks(design, m, grid=options.grid) for m in ("pinion", "gear")),
    )
    return _recent(
        design,
        ("pair", options.grid.shape, options.misalignment),
        lambda: mesh_pair(
            design, grid=options.grid, misalignment=options.misalignment, flanks=flanks
        ),
    )


def contact_sides(pair: MeshedPair, options: AnalysisOptions) -> dict[str, ToothContact]:
    """``{"drive": ..., "coast": ...}`` TCA of both sides."""
    common = dict(
        frame=pair.frame,
        positions=options.positions,
        pairs=options.pairs,
        cycles=options.cycles,
        compound_um=options.compound_um,
        separation=options.separation,
    )
    drive, coast = tooth_contacts([pair.drive, pair.coast], sides=("drive", "coast"), **common)
    return {"drive": drive, "coast": coast}


def pair_backlash(pair: MeshedPair, options: AnalysisOptions) -> Backlash:
    """Backlash at the drive side's positions."""
    return backlash(
        pair.drive,
        pair.coast,
        radius_mm=pair.backlash_radius_mm,
        positions=options.positions,
        pairs=options.pairs,
        cycles=options.cycles,
    )


def pair_ease_off(pair: MeshedPair) -> dict[str, EaseOff]:
    """Ease-off of the pinion's drive and coast flanks."""
    return {
        "drive": ease_off(pair.drive, frame=pair.frame, side="drive"),
        "coast": ease_off(pair.coast, frame=pair.frame, side="coast"),
    }
