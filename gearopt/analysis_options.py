"""The options of the contact analyses: the conditions the contact evaluators share.

:class:`AnalysisOptions` holds them (positions, tooth pairs and mesh cycles, marking compound,
separation, grid, misalignment); a design's ``[analysis]`` table gives their defaults and an
evaluator's conditions override them. Checked when made, before any flank is generated.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from gearopt.assembly import Misalignment
from gearopt.declarations import Option
from gearopt.errors import GearoptError
from gearopt.flank import FlankGrid

__all__ = ["ANALYSIS_OPTIONS", "SEPARATIONS", "TCA_GRID", "AnalysisOptions", "check_options"]

#: how the pattern's separations are measured: along the surface normal, or between two points
#: at equal radius (seed 003 section 5)
SEPARATIONS = ("normal", "circumferential")

#: The FlankMap grid of the contact analyses (n_face, n_profile): the profile is sampled more
#: finely than the flank default because the pinion's fold spoils interpolation in its lowest
#: cells (the engine replaces them by fine cells of the exact surface,
#: :mod:`gearopt.contact.boundary`, or, without one, keeps its refinement above them).
TCA_GRID = FlankGrid(n_face=25, n_profile=21)


def _misalignment(value: Any, where: str) -> None:
    """A ``misalignment`` condition: a table of the ``[misalignment]`` keys."""
    Misalignment.from_table(value, where)


def _positive(value: Any, where: str) -> None:
    if not value > 0.0:
        raise GearoptError(where, value, "must be > 0")


_FROM_DESIGN = "; default: the design's [analysis] table, else "

#: the contact evaluators' options (their conditions), as ``gearopt plugins --options`` lists
#: them; :meth:`AnalysisOptions.from_conditions` checks the rules that join two of them
ANALYSIS_OPTIONS = (
    Option(
        name="positions",
        default=21,
        kind="integer",
        lower=3,
        upper=401,
        description="contact positions over the mesh cycles, at least 2 cycles + 1"
        + _FROM_DESIGN
        + "21",
    ),
    Option(
        name="pairs",
        default=3,
        kind="integer",
        lower=2,
        upper=7,
        description="tooth pairs at each position" + _FROM_DESIGN + "3",
    ),
    Option(
        name="cycles",
        default=2.0,
        kind="number",
        lower=1.0,
        upper=5.0,
        description="mesh cycles analysed" + _FROM_DESIGN + "2",
    ),
    Option(
        name="compound_um",
        default=6.5,
        kind="number",
        lower=0.0,
        upper=100.0,
        description="marking-compound thickness of the pattern, > 0 (um)" + _FROM_DESIGN + "6.5",
        validate=_positive,
    ),
    Option(
        name="separation",
        default="normal",
        kind="string",
        choices=SEPARATIONS,
        description="how the pattern's separation is measured" + _FROM_DESIGN + "normal",
    ),
    Option(
        name="grid",
        default=[TCA_GRID.n_face, TCA_GRID.n_profile],
        kind="numbers",
        lower=2,
        description="FlankMap grid [n_face, n_profile] of both members",
    ),
    Option(
        name="misalignment",
        default=None,
        kind="table",
        description="the assembly, a table of [misalignment] keys; default: the design's",
        validate=_misalignment,
    ),
)


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
        check_options(self.positions, self.pairs, self.cycles, self.compound_um, self.separation)

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


def _is_number(value) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool)


def check_options(positions: int, pairs: int, cycles: float, compound_um: float, separation):
    """Check the mesh-cycle options (:class:`AnalysisOptions`), naming the first bad one."""
    if isinstance(positions, bool) or not isinstance(positions, int) or not 3 <= positions <= 401:
        raise GearoptError("positions", positions, "must be an integer from 3 to 401")
    if isinstance(pairs, bool) or not isinstance(pairs, int) or not 2 <= pairs <= 7:
        raise GearoptError("pairs", pairs, "must be an integer from 2 to 7")
    if not (_is_number(cycles) and 1.0 <= cycles <= 5.0):
        raise GearoptError("cycles", cycles, "must be a number from 1 to 5 mesh cycles")
    if positions < 2 * cycles + 1:
        raise GearoptError(
            "positions",
            positions,
            f"must be at least 2 cycles + 1 = {2 * cycles + 1:g} (a step "
            "below half a pitch, so that hand-overs are bracketed)",
        )
    if not (_is_number(compound_um) and 0.0 < compound_um <= 100.0):
        raise GearoptError("compound_um", compound_um, "must be in (0, 100] um")
    if separation not in SEPARATIONS:
        raise GearoptError("separation", separation, f"must be one of {SEPARATIONS}")
