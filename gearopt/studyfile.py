"""Study files: what a study searches, evaluates and minimises, read from TOML or built in Python.

A study file::

    [study]
    name = "cyclo_palloid_contact"      # the Optuna study name (default: the file's stem)
    design = "seed001_section5_3.toml"  # the base design, relative to the study file
    sampler = "tpe"                     # tpe | random | nsga2 | qmc
    seed = 7
    pick = "utopia"                     # multi-objective: utopia | "objective:<label>"
    artifacts = false                   # per-trial PNG plots as Optuna artifacts
    shared_storage = false              # true: a database holding others' tables too

    [search]                            # dotted design keys: [low, high] or {low, high, log}
    "machine.pinion.inner_cutter_radius_mm" = [73.0, 77.0]
    "machine.pinion.blade_parabola_coefficient_per_mm" = "model"   # the model's own bounds
    "machine.gear.inner_cutter_radius_mm" = "catalogue"  # the model's standard cutters that
                                                         # suit the design (categorical)

    [evaluations.tca]                   # a label; evaluator defaults to the label
    [evaluations.misaligned]
    evaluator = "tca"
    conditions = {misalignment = {offset_mm = 0.221}}

    [[objectives]]                      # objective plugins; label names the Optuna metric
    name = "worst_te"
    on = ["tca", "misaligned"]

    [[constraints]]
    name = "backlash_window"
    min_um = 150.0
    max_um = 260.0

    [[enqueue]]                         # given designs, evaluated first
    "machine.pinion.inner_cutter_radius_mm" = 75.0

    [grid]                              # a sweep: every combination is enqueued
    "machine.pinion.blade_parabola_coefficient_per_mm" = [0.0, 0.0015]

    [analysis]                          # contact-analysis options of every trial (they
    compound_um = 6.5                   # override the base design's [analysis] table)

    [fixed]                             # dotted design keys set for every trial
    "machine.gear.blade_parabola_coefficient_per_mm" = 0.0
"""

from __future__ import annotations

import itertools
import math
import re
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from gearopt.design import Design
from gearopt.design_files import load_design, with_overrides
from gearopt.errors import GearoptError, PluginError, StudyError, UnknownKeyError
from gearopt.machine import SearchDimension
from gearopt.plugins import evaluators, get_machine_model, objectives
from gearopt.validate import read_toml_file

__all__ = [
    "SAMPLERS",
    "Dimension",
    "EvaluationSpec",
    "ObjectiveSpec",
    "StudySpec",
    "load_study_spec",
    "parse_study_spec",
]

SAMPLERS = ("tpe", "random", "nsga2", "qmc")
_STUDY_KEYS = ("name", "design", "sampler", "seed", "pick", "artifacts", "shared_storage")
#: the most designs a ``[grid]`` may give (each a trial)
MAX_GRID_DESIGNS = 100_000
_TABLES = (
    "study",
    "search",
    "evaluations",
    "objectives",
    "constraints",
    "enqueue",
    "grid",
    "analysis",
    "fixed",
)


#: a searched design key is a machine model's kind of search dimension
Dimension = SearchDimension


def _check_value(dim: Dimension, value: Any, where: str) -> float:
    """``value`` as a float inside the dimension's bounds, or a :class:`StudyError`."""
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise StudyError(f"{where}.{dim.key}", value, "must be a number")
    if dim.choices and not dim.contains(value):
        raise StudyError(
            f"{where}.{dim.key}", value, f"must be one of the catalogue's {list(dim.choices)}"
        )
    if not dim.low <= value <= dim.high:
        raise StudyError(f"{where}.{dim.key}", value, f"must lie in [{dim.low}, {dim.high}]")
    return float(value)


@dataclass(frozen=True, kw_only=True)
class EvaluationSpec:
    """One evaluation of every trial: an evaluator under conditions, stored under ``label``."""

    label: str
    evaluator: str
    conditions: Mapping[str, Any] = field(default_factory=dict)


@dataclass(frozen=True, kw_only=True)
class ObjectiveSpec:
    """One objective or constraint: the plugin ``name``, the Optuna metric ``label``, its
    ``options`` and, from the plugin, ``kind`` and ``direction``."""

    name: str
    label: str
    kind: str
    direction: str
    options: Mapping[str, Any] = field(default_factory=dict)


@dataclass(frozen=True, kw_only=True)
class StudySpec:
    """A validated study: base design, search space, evaluations, objectives, constraints,
    sampler, seed, the pick rule of multi-objective studies and the given designs."""

    name: str
    design: Design
    search: tuple[Dimension, ...]
    evaluations: tuple[EvaluationSpec, ...]
    objectives: tuple[ObjectiveSpec, ...]
    constraints: tuple[ObjectiveSpec, ...] = ()
    sampler: str = "tpe"
    seed: int | None = None
    pick: str = "utopia"
    artifacts: bool = False
    shared_storage: bool = False
    enqueue: tuple[Mapping[str, float], ...] = ()
    path: str | None = None

    def __post_init__(self) -> None:
        if not re.fullmatch(r"[A-Za-z0-9_.-]+", self.name):
            raise StudyError("study.name", self.name, "use letters, digits, '_', '-' and '.'")
        if self.sampler not in SAMPLERS:
            raise StudyError("study.sampler", self.sampler, f"must be one of {SAMPLERS}")
        if not self.search:
            raise StudyError("search", rule="name at least one design key to search")
        if not self.objectives:
            raise StudyError("objectives", rule="name at least one objective")
        labels = [o.label for o in self.objectives + self.constraints]
        if len(set(labels)) != len(labels):
            raise StudyError("objectives", labels, "labels must be unique")
        if self.pick != "utopia":
            target = self.pick.removeprefix("objective:")
            named = labels[: len(self.objectives)]
            if not self.pick.startswith("objective:") or target not in named:
                raise StudyError(
                    "study.pick", self.pick, "must be 'utopia' or 'objective:<objective label>'"
                )

    @property
    def folder(self) -> Path:
        """The study file's folder (the working directory for a study built in a script
        without a path): the base design, the default storage and the outputs are there."""
        return _folder(self.path)

    @property
    def directions(self) -> list[str]:
        return [o.direction for o in self.objectives]

    @property
    def metric_names(self) -> list[str]:
        return [o.label for o in self.objectives]

    @property
    def dimensions(self) -> dict[str, Dimension]:
        return {d.key: d for d in self.search}

    def check_params(self, params: Mapping[str, Any], where: str) -> dict[str, float]:
        """Given design values as searched parameters: every key searched, every value inside
        its range (a given design outside the space would be resampled by Optuna)."""
        dims = self.dimensions
        unknown = set(params) - set(dims)
        if unknown:
            raise StudyError(where, sorted(unknown), f"not searched keys; searched: {sorted(dims)}")
        return {key: _check_value(dims[key], value, where) for key, value in params.items()}

    def design_for(self, params: Mapping[str, Any]) -> Design:
        """The base design with the searched keys set."""
        return with_overrides(self.design, params)


def _folder(path: str | Path | None) -> Path:
    return Path(path).resolve().parent if path else Path.cwd()


def _float(value: Any, where: str) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise StudyError(where, value, "must be a number")
    return float(value)


def _dimension(key: str, value: Any, design: Design) -> Dimension:
    where = f"search.{key}"
    if value == "model":
        model = get_machine_model(design.model)
        declared = {d.key: d for d in model.search_space(design)}
        if key not in declared:
            raise StudyError(
                where, value, f"the model has no bounds for it; it has {sorted(declared)}"
            )
        return declared[key]
    if value == "catalogue":
        model = get_machine_model(design.model)
        offered = {d.key: d for d in model.cutter_catalogue(design)}
        if key not in offered:
            rule = (
                f"the {design.model!r} model offers the catalogue for {sorted(offered)}"
                if offered
                else f"the {design.model!r} model has no cutter catalogue for this design"
            )
            raise StudyError(where, value, rule)
        return offered[key]
    if isinstance(value, list) and len(value) == 2:
        bounds = {"low": value[0], "high": value[1]}
    elif isinstance(value, Mapping) and {"low", "high"} <= set(value) <= {"low", "high", "log"}:
        bounds = dict(value)
    else:
        raise StudyError(
            where, value, 'must be [low, high], {low, high, log}, "model" or "catalogue"'
        )
    try:
        return Dimension(
            key=key,
            low=_float(bounds["low"], where),
            high=_float(bounds["high"], where),
            log=_boolean(bounds.get("log", False), f"{where}.log"),
        )
    except PluginError as exc:
        raise StudyError(where, value, exc.rule) from None


def _check_search_keys(design: Design, dims) -> None:
    """Every searched key is one the design knows: the base design with each key at its
    range's middle, checked for unknown keys only (a trial's design may be invalid for
    other reasons, which its trial reports)."""
    for d in dims:
        try:
            middle = d.choices[len(d.choices) // 2] if d.choices else 0.5 * (d.low + d.high)
            with_overrides(design, {d.key: middle})
        except UnknownKeyError as exc:
            raise StudyError(f"search.{d.key}", exc.value, exc.rule) from None
        except GearoptError:
            pass


def _boolean(value: Any, where: str) -> bool:
    """A TOML boolean (``"no"`` or ``0`` is not one: ``bool("false")`` is True)."""
    if not isinstance(value, bool):
        raise StudyError(where, value, "must be true or false (a TOML boolean, unquoted)")
    return value


def _objective(entry: Any, kind: str, where: str, known: Mapping[str, EvaluationSpec]):
    if not isinstance(entry, Mapping) or not isinstance(entry.get("name"), str):
        raise StudyError(where, entry, "must be a table with name = <objective plugin>")
    options = {k: v for k, v in entry.items() if k not in ("name", "label", "direction")}
    available = objectives()
    name = entry["name"]
    if name not in available:
        raise StudyError(f"{where}.name", name, f"unknown; installed: {sorted(available)}")
    plugin = available[name]
    if plugin.kind != kind:
        raise StudyError(f"{where}.name", name, f"is a {plugin.kind}, listed under {kind}s")
    try:
        reads = plugin.reads(**options)
    except GearoptError as exc:  # named as the file names it, with the plugin's parameter
        named = f"{where} ({exc.parameter})"
        if exc.value is None:
            raise StudyError(named, rule=exc.rule or str(exc)) from None
        raise StudyError(named, exc.value, exc.rule or str(exc)) from None
    for label, evaluator in reads.items():
        if label not in known:
            raise StudyError(where, label, f"is not in [evaluations]: {sorted(known)}")
        if known[label].evaluator != evaluator:
            raise StudyError(where, label, f"must be an evaluation of {evaluator!r}")
    direction = entry.get("direction", plugin.direction)
    if direction not in ("minimize", "maximize"):
        raise StudyError(f"{where}.direction", direction, "must be minimize or maximize")
    return ObjectiveSpec(
        name=name,
        label=str(entry.get("label", name)),
        kind=kind,
        direction=direction,
        options=options,
    )


def _evaluations(table: Mapping[str, Any], design: Design) -> tuple[EvaluationSpec, ...]:
    installed = evaluators()
    if not isinstance(table, Mapping):
        raise StudyError("evaluations", table, "must be tables [evaluations.<label>]")
    specs = []
    for label, entry in table.items():
        where = f"evaluations.{label}"
        if not isinstance(entry, Mapping) or not set(entry) <= {"evaluator", "conditions"}:
            raise StudyError(where, entry, "must be a table with evaluator and conditions")
        name = entry.get("evaluator", label)
        if not isinstance(name, str) or name not in installed:
            raise StudyError(f"{where}.evaluator", name, f"unknown; installed: {sorted(installed)}")
        conditions = entry.get("conditions", {})
        if not isinstance(conditions, Mapping):
            raise StudyError(f"{where}.conditions", conditions, "must be a table")
        try:  # before the database is touched: a typo must not fail every trial
            installed[name].check_conditions(design, conditions)
        except GearoptError as exc:
            raise StudyError(f"{where}.{exc.parameter}", exc.value, exc.rule) from None
        specs.append(EvaluationSpec(label=label, evaluator=name, conditions=dict(conditions)))
    return tuple(specs)


def _given(data: Mapping[str, Any]) -> list[dict]:
    """The given designs: the ``[[enqueue]]`` entries, then every combination of ``[grid]``."""
    given = []
    entries = data.get("enqueue", [])
    if not isinstance(entries, list):
        raise StudyError("enqueue", entries, "must be tables [[enqueue]] of design keys")
    for i, entry in enumerate(entries):
        if not isinstance(entry, Mapping):
            raise StudyError(f"enqueue[{i}]", entry, "must be a table of design keys")
        given.append(dict(entry))
    grid = data.get("grid", {})
    if not isinstance(grid, Mapping):
        raise StudyError("grid", grid, "must be a table of design keys and lists of values")
    if grid:
        keys = list(grid)
        for key in keys:
            if not isinstance(grid[key], list) or not grid[key]:
                raise StudyError(f"grid.{key}", grid[key], "must be a non-empty list of values")
        size = math.prod(len(grid[k]) for k in keys)
        if size > MAX_GRID_DESIGNS:
            raise StudyError(
                "grid",
                f"{size} designs",
                f"must give at most {MAX_GRID_DESIGNS} designs (the product of its lists' "
                "lengths), counted before they are built",
            )
        for combo in itertools.product(*(grid[k] for k in keys)):
            given.append(dict(zip(keys, combo, strict=True)))
    return given


def _entries(data: Mapping[str, Any], table: str) -> list:
    """The ``[[objectives]]`` or ``[[constraints]]`` entries (a list of tables)."""
    entries = data.get(table, [])
    if not isinstance(entries, list):
        raise StudyError(table, entries, f"must be tables [[{table}]]")
    return entries


def parse_study_spec(data: Mapping[str, Any], *, path: str | Path | None = None) -> StudySpec:
    """A :class:`StudySpec` from a parsed study file (``path`` resolves the base design)."""
    unknown = set(data) - set(_TABLES)
    if unknown:
        raise StudyError("study file", sorted(unknown), f"unknown tables; known: {_TABLES}")
    study = data.get("study", {})
    if not isinstance(study, Mapping):
        raise StudyError("study", study, "must be a table")
    if set(study) - set(_STUDY_KEYS):
        raise StudyError("study", sorted(set(study) - set(_STUDY_KEYS)), f"known: {_STUDY_KEYS}")
    if "design" not in study:
        raise StudyError("study.design", rule="name the base design file")
    if not isinstance(study["design"], str) or not study["design"].strip():
        raise StudyError("study.design", study["design"], "must be the base design's file name")
    design = load_design(_folder(path) / study["design"])
    fixed = data.get("fixed", {})
    if not isinstance(fixed, Mapping):
        raise StudyError("fixed", fixed, "must be a table of dotted design keys and values")
    if fixed:  # design keys every trial shares, set on the base design
        try:
            design = with_overrides(design, dict(fixed))
        except GearoptError as exc:
            raise StudyError(f"fixed.{exc.parameter}", exc.value, exc.rule) from None
    analysis = data.get("analysis", {})
    if not isinstance(analysis, Mapping):
        raise StudyError("analysis", analysis, "must be a table of contact-analysis options")
    if analysis:  # the study's [analysis] overrides the base design's
        try:
            design = with_overrides(design, {f"analysis.{k}": v for k, v in analysis.items()})
        except GearoptError as exc:
            raise StudyError(exc.parameter, exc.value, exc.rule) from None
    search = data.get("search", {})
    if not isinstance(search, Mapping):
        raise StudyError("search", search, "must be a table of design keys")
    dims = tuple(_dimension(key, value, design) for key, value in search.items())
    _check_search_keys(design, dims)
    evals = _evaluations(data.get("evaluations", {}), design)
    if not evals:
        raise StudyError("evaluations", rule="name at least one evaluation")
    known = {e.label: e for e in evals}
    objs = tuple(
        _objective(e, "objective", f"objectives[{i}]", known)
        for i, e in enumerate(_entries(data, "objectives"))
    )
    cons = tuple(
        _objective(e, "constraint", f"constraints[{i}]", known)
        for i, e in enumerate(_entries(data, "constraints"))
    )
    seed = study.get("seed")
    if seed is not None and (isinstance(seed, bool) or not isinstance(seed, int)):
        raise StudyError("study.seed", seed, "must be an integer")
    if seed is not None and not 0 <= seed < 2**32:
        raise StudyError("study.seed", seed, "must lie in [0, 2^32) (numpy's random seeds)")
    default_name = Path(path).stem if path else "study"
    spec = StudySpec(
        name=str(study.get("name", default_name)),
        design=design,
        search=dims,
        evaluations=evals,
        objectives=objs,
        constraints=cons,
        sampler=str(study.get("sampler", "tpe")),
        seed=seed,
        pick=str(study.get("pick", "utopia")),
        artifacts=_boolean(study.get("artifacts", False), "study.artifacts"),
        shared_storage=_boolean(study.get("shared_storage", False), "study.shared_storage"),
        path=str(path) if path else None,
    )
    given = tuple(spec.check_params(p, f"enqueue[{i}]") for i, p in enumerate(_given(data)))
    for i, params in enumerate(given):
        try:
            spec.design_for(params)
        except GearoptError as exc:
            raise StudyError(f"enqueue[{i}]", params, f"gives an invalid design: {exc}") from None
    return replace(spec, enqueue=given)


def load_study_spec(path: str | Path) -> StudySpec:
    """Read and validate a study file."""
    path = Path(path)
    data = read_toml_file(path, lambda rule: StudyError("study file", str(path), rule))
    return parse_study_spec(data, path=path)
