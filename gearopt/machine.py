"""The machine-model contract: what a plugin's machine model provides.

A machine model knows its settings dataclass (``parse_machine``), how to compute the basic
machine-tool settings of both members from the blank (``basic_settings``), which of its design keys
are tunable within which bounds (``search_space``) and, once its generator exists, how to generate a
member's tooth flank (``generate_flank``). Subclass :class:`BaseMachineModel`, return an instance
from a ``gearopt_machine_models`` hookimpl, and run :mod:`gearopt.testing` against it.
"""

from __future__ import annotations

import abc
import dataclasses
import json
import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, ClassVar

from gearopt.errors import NotAvailableError, PluginError, RexsError
from gearopt.rexs.attributes import RexsMachine, custom, read_string

if TYPE_CHECKING:
    from gearopt.design import Design, PairData

__all__ = [
    "BaseMachineModel",
    "CorrectionSetting",
    "MachineSettings",
    "SearchDimension",
    "design_value",
]


@dataclass(frozen=True, kw_only=True)
class SearchDimension:
    """One tunable design key and its bounds, as a study's search space uses it.

    Attributes
    ----------
    key
        Dotted design key, e.g. ``"machine.pinion.inner_cutter_radius_mm"``.
    low, high
        Inclusive bounds in the key's unit; every value between them gives a valid design.
        A categorical dimension's bounds are its smallest and largest choice.
    log
        Sample on a log scale.
    choices
        A categorical dimension's values (a catalogue's sizes, :meth:`categorical`): the study
        samples one of them, never a value between; empty for a continuous dimension.
    note
        One line saying where the choices come from (shown by ``gearopt study``).
    """

    key: str
    low: float
    high: float
    log: bool = False
    choices: tuple[float, ...] = ()
    note: str = ""

    @classmethod
    def categorical(cls, key: str, choices, note: str = "") -> SearchDimension:
        """A dimension whose values are ``choices`` only (sorted, duplicates removed)."""
        values = tuple(sorted({float(c) for c in choices}))
        if not values:
            raise PluginError(f"search dimension {key}", (), "needs at least one choice")
        return cls(key=key, low=values[0], high=values[-1], choices=values, note=note)

    def suggest(self, trial: Any) -> float:
        """The value an Optuna trial suggests for this dimension (categorical or float)."""
        if self.choices:
            return float(trial.suggest_categorical(self.key, list(self.choices)))
        return trial.suggest_float(self.key, self.low, self.high, log=self.log)

    def contains(self, value: float) -> bool:
        """Whether ``value`` is one of the choices, or inside the bounds."""
        if self.choices:
            return any(math.isclose(value, c, rel_tol=1e-12, abs_tol=1e-12) for c in self.choices)
        return self.low <= value <= self.high

    def describe(self) -> Any:
        """What a study's record keeps of the dimension: ``[low, high, log]`` or the choices."""
        return {"choices": list(self.choices)} if self.choices else [self.low, self.high, self.log]

    def __post_init__(self) -> None:
        if self.choices:
            if not all(math.isfinite(c) for c in self.choices) or (
                min(self.choices) != self.low or max(self.choices) != self.high
            ):
                raise PluginError(
                    f"search dimension {self.key}",
                    self.choices,
                    "needs finite choices whose smallest and largest are low and high",
                )
            return
        width = self.high - self.low
        if not (math.isfinite(self.low) and math.isfinite(width) and self.low < self.high):
            raise PluginError(
                f"search dimension {self.key}",
                (self.low, self.high),
                "needs finite low < high, high - low finite too",
            )
        if self.log and self.low <= 0.0:
            raise PluginError(f"search dimension {self.key}", self.low, "log scale needs low > 0")


@dataclass(frozen=True, kw_only=True)
class CorrectionSetting:
    """One design key the closed loop (:mod:`gearopt.measurement`) may identify and correct.

    Attributes
    ----------
    key
        Dotted design key, e.g. ``"machine.pinion.concave.radial_setting_mm"``; the design with
        this key replaced (:func:`gearopt.design_files.with_overrides`) is cut with the changed
        setting.
    value
        The key's value in the design.
    step
        Finite-difference step for the sensitivities, in the key's unit (small against the
        errors to find, large against the generator's accuracy).
    low, high
        Bounds of an identified or corrected value.
    also
        Further dotted keys that hold the same setting and take the same value (one machine
        setting that the design file writes in more than one table).
    correctable
        Whether the next cut may change it (a machine setting); False for what is identified
        but corrected through other settings (a blade angle ground into the cutter).
    """

    key: str
    value: float
    step: float
    low: float = -math.inf
    high: float = math.inf
    also: tuple[str, ...] = ()
    correctable: bool = True

    def overrides(self, value: float) -> dict[str, float]:
        """``{dotted key: value}`` for :func:`gearopt.design_files.with_overrides`."""
        return {k: float(value) for k in (self.key, *self.also)}

    def __post_init__(self) -> None:
        if not (math.isfinite(self.value) and math.isfinite(self.step) and self.step > 0.0):
            raise PluginError(
                f"correction setting {self.key}",
                (self.value, self.step),
                "needs a finite value and a finite step > 0",
            )
        if not self.low <= self.value <= self.high:
            raise PluginError(
                f"correction setting {self.key}",
                (self.low, self.value, self.high),
                "needs low <= value <= high",
            )


def design_value(source: Mapping[str, Any], key: str) -> Any:
    """The value a dotted design key has in a design's source tables, the nearest enclosing
    table giving it (``machine.pinion.convex.k`` falls back to ``machine.pinion.k``, then
    ``machine.k``, the inheritance every built-in model uses); None when no table gives it."""
    parts = key.split(".")
    for depth in range(len(parts) - 1, 0, -1):
        node: Any = source
        for part in parts[:depth]:
            node = node.get(part) if isinstance(node, Mapping) else None
        if isinstance(node, Mapping) and parts[-1] in node:
            return node[parts[-1]]
    return None


@dataclass(frozen=True, kw_only=True)
class MachineSettings:
    """Basic machine-tool settings of a pair: one settings dataclass per member.

    ``pinion`` and ``gear`` are the model's own frozen dataclasses whose fields are scalars named
    with their units (``inner_machine_distance_mm``, ``machine_root_angle_deg``); dimensionless
    ratios are named for what they are (``gear_to_cradle_roll``).
    """

    model: str
    pinion: Any
    gear: Any
    notes: tuple[str, ...] = ()

    def member(self, name: str) -> Any:
        """Settings of ``"pinion"`` or ``"gear"``."""
        if name not in ("pinion", "gear"):
            raise ValueError(f"member must be 'pinion' or 'gear', got {name!r}")
        return getattr(self, name)

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready ``{"model": ..., "pinion": {...}, "gear": {...}, "notes": [...]}``."""
        return {
            "model": self.model,
            "pinion": dataclasses.asdict(self.pinion),
            "gear": dataclasses.asdict(self.gear),
            "notes": list(self.notes),
        }


class BaseMachineModel(abc.ABC):
    """A cutting machine and process that generates spiral bevel tooth flanks.

    Instances are stateless and picklable (joblib workers rebuild or receive them). Every method
    validates what it is given and raises a :class:`~gearopt.errors.GearoptError` subclass that
    names the parameter, its value and the rule; none returns NaN.

    Class attributes
    ----------------
    name
        Unique model name used in design files (``[machine] model = "cyclo-palloid"``); lower case
        words joined by hyphens.
    description
        One line for ``gearopt plugins``.
    """

    name: ClassVar[str]
    description: ClassVar[str] = ""

    @abc.abstractmethod
    def parse_machine(self, table: Mapping[str, Any], pair: PairData) -> Any:
        """Validate the ``[machine]`` table (without ``model``) and return a frozen dataclass.

        Unknown keys are refused (:func:`gearopt.validate.check_keys`), with error names of the form
        ``machine.<member>.<key>``.
        """

    def synthesize(
        self, table: Mapping[str, Any], synthesis: Mapping[str, Any], pair: PairData
    ) -> Any:
        """Derive the settings the ``[machine]`` table leaves out from the blank and the
        design's ``[synthesis]`` table (what the contact should be), and return the same frozen
        dataclass as :meth:`parse_machine`.

        Called instead of :meth:`parse_machine` when the design has a ``[synthesis]`` table.
        The default raises :class:`~gearopt.errors.NotAvailableError` naming ``synthesis``:
        a model without a synthesis refuses the table rather than ignoring it.
        """
        raise NotAvailableError(
            "synthesis", rule=f"the {self.name!r} machine model has no settings synthesis"
        )

    def realise_te_target(self, design: Design, *, side: str = "drive") -> tuple[dict, dict]:
        """Settings that make ``side`` of the pair run with the design's ``[te_target]`` (an
        inverse TCA): ``(machine table without "model", report)``. The table parses back with
        :meth:`parse_machine`; the report says what was fitted and how it converged.

        The default raises :class:`~gearopt.errors.NotAvailableError` naming ``te_target``.
        """
        raise NotAvailableError(
            "te_target", rule=f"the {self.name!r} machine model cannot realise a designed TE"
        )

    @abc.abstractmethod
    def basic_settings(self, design: Design) -> MachineSettings:
        """Compute the basic machine-tool settings of both members from the blank and the
        machine table, including the compensation of ``design.compensation`` if the model
        supports it (and an error naming ``compensation`` if it does not but it is non-zero)."""

    @abc.abstractmethod
    def search_space(self, design: Design) -> tuple[SearchDimension, ...]:
        """The design keys a study may tune, with bounds inside which every design is valid."""

    def cutter_catalogue(self, design: Design) -> tuple[SearchDimension, ...]:
        """The design keys a study may search over the standard cutters one can buy
        (``[search] "<key>" = "catalogue"``): categorical dimensions
        (:meth:`SearchDimension.categorical`) whose choices are the catalogue's sizes that
        suit ``design`` under the model's own rules (blade groups, module range, the slope
        angle's limit), each ``note`` saying which catalogue, how many sizes remain of how
        many and where the sizes come from.

        The catalogue is the plugin's data; the core never names one. The default is ``()``:
        a model without a catalogue refuses the search value ``"catalogue"``.
        """
        return ()

    def machine_table(self, design: Design) -> dict[str, Any]:
        """The ``[machine]`` table (without ``model``) that states ``design``'s settings
        explicitly and parses back to the same machine (:meth:`parse_machine`) without any
        ``[synthesis]``: what the closed loop changes one key at a time.

        The default is the design's own table; a model that derives settings (a synthesis, a
        gear from the blank) writes them out.
        """
        table = dict(design.source.get("machine", {}))
        table.pop("model", None)
        return table

    def rexs_export(self, design: Design) -> RexsMachine:
        """``design``'s settings as REXS attributes (:mod:`gearopt.rexs`): the tool and the
        machine settings of the step that cuts each flank (``bevel_gear_tool``,
        ``bevel_gear_manufacturing_settings``) and the pair's (``bevel_stage``), so that
        :meth:`rexs_import` reads back a ``[machine]`` table with identical flanks.

        Use the REXS attributes (:func:`gearopt.rexs.attributes.standard`) where they mean the
        setting, custom ones (:func:`gearopt.rexs.attributes.custom`) for what REXS has no
        attribute for, and document the mapping and its sign conventions for users.
        The default writes :meth:`machine_table` as one custom attribute of the stage
        (``custom_gearopt_machine_table``, a JSON string): a round trip through gearopt, which no
        other tool reads.
        """
        name, value = custom("machine_table", json.dumps(self.machine_table(design)), "none")
        return RexsMachine(stage={name: value})

    def rexs_import(self, machine: RexsMachine, pair: PairData) -> dict[str, Any]:
        """The ``[machine]`` table (without ``model``) of a REXS file's settings, read from
        ``machine`` (what :meth:`rexs_export` writes, or another tool's file): parsed next by
        :meth:`parse_machine` with the file's ``pair``.

        Raise :class:`~gearopt.errors.RexsError` naming the attribute that is missing, in
        another unit, or a setting the model does not model
        (:func:`gearopt.rexs.attributes.refuse_unmodelled`). The default reads the custom
        attribute the default :meth:`rexs_export` writes.
        """
        text = read_string(machine.stage, "custom_gearopt_machine_table", "bevel_stage")
        try:
            table = json.loads(text)
        except json.JSONDecodeError as exc:
            raise RexsError(
                "bevel_stage.custom_gearopt_machine_table", text, f"is not JSON: {exc}"
            ) from None
        if not isinstance(table, dict):
            raise RexsError(
                "bevel_stage.custom_gearopt_machine_table", text, "must hold a JSON object"
            )
        return table

    def correction_settings(self, design: Design, member: str) -> tuple[CorrectionSetting, ...]:
        """The settings of ``member`` that the closed loop identifies from a measured flank
        topography and corrects (``gearopt correct``), with their values in ``design``.

        Return the settings a machine operator corrects on this machine (for face milling the
        radial setting, cradle angle, machine root angle, sliding base, blank offset, ratio of
        roll, modified roll and blade angle), as keys of ``design`` so that
        :func:`gearopt.design_files.with_overrides` cuts the changed gear. A member whose two
        flanks are cut in one set-up shares its keys between them. The closed loop finds
        which of them the grid cannot tell apart and identifies a well-posed subset.

        The default offers the numeric keys of :meth:`search_space` that belong to ``member``
        (steps a thousandth of their range); override it to offer the machine's settings.
        """
        out = []
        for dim in self.search_space(design):
            if f".{member}." not in f".{dim.key}":
                continue
            value = design_value(design.source, dim.key)
            if isinstance(value, bool) or not isinstance(value, int | float):
                continue
            if not (math.isfinite(value) and dim.low <= value <= dim.high):
                continue
            step = 1e-3 * (dim.high - dim.low)
            out.append(
                CorrectionSetting(
                    key=dim.key, value=float(value), step=step, low=dim.low, high=dim.high
                )
            )
        return tuple(out)

    def generate_flank(
        self, design: Design, *, member: str, flank: str, grid: Any = None, tool_pass: int = 0
    ) -> Any:
        """Generate ``member``'s ``flank`` ("concave" or "convex") as a :class:`FlankMap`.

        Parameters
        ----------
        design
            A design that selects this model.
        member, flank
            ``"pinion"``/``"gear"`` and ``"convex"``/``"concave"``.
        grid
            A :class:`gearopt.flank.FlankGrid` (default: the default grid).
        tool_pass
            0 for tooth 0; k for the flank cut by the tool's k-th pass (the k-th blade group
            of a face-hobbing cutter, the k-th indexing of single indexing), which is tooth k
            turned by k pitches when the machine indexes exactly. The flank contract checks it.

        Returns
        -------
        FlankMap
            Right- or left-hand as the pair says, its normals out of the tooth material, with
            a ``surface`` for exact points and the tool's positions when the model can.

        The default asks :meth:`generate_flanks` for the one flank when the model overrides
        that; models without a generator raise :class:`~gearopt.errors.NotAvailableError`.
        """
        if type(self).generate_flanks is not BaseMachineModel.generate_flanks:
            return self.generate_flanks(
                design, member=member, grid=grid, flanks=(flank,), tool_pass=tool_pass
            )[flank]
        raise NotAvailableError(
            f"machine model {self.name!r}",
            rule="does not generate tooth flanks (no generate_flank implementation)",
        )

    def generate_flanks(
        self,
        design: Design,
        *,
        member: str,
        grid: Any = None,
        flanks: tuple[str, ...] = ("convex", "concave"),
        tool_pass: int = 0,
    ) -> dict[str, Any]:
        """``{flank: FlankMap}`` for the member's ``flanks`` (arguments as :meth:`generate_flank`).

        The default calls :meth:`generate_flank` once per flank; override it when the model can
        solve several flanks in one batch (then :meth:`generate_flank` needs no override).
        """
        return {
            f: self.generate_flank(design, member=member, flank=f, grid=grid, tool_pass=tool_pass)
            for f in flanks
        }

    def warm_kernels(self) -> None:
        """Compile the model's own numerical kernels (numba), or load them from the disk cache,
        in this process: :func:`gearopt.warmup.warm_kernels` calls it for every installed model
        before a study's workers start, so that they load the cache rather than compile it side
        by side. The default does nothing (a model without compiled kernels)."""
        return None

    def __repr__(self) -> str:
        return f"<{type(self).__name__} {self.name!r}>"
