"""Loaded tooth contact analysis: an evaluator plugin on the contact engine.

For each torque of the design's ``[load]`` table (or the ``torque_nm`` condition) and each side:
the loaded transmission error at the unloaded TCA's positions, its peak-to-peak (the LTE
fluctuation, seed 002 section 5), the load sharing of the tooth pairs, the largest contact
pressure and line load, the mesh stiffness and edge loading (:mod:`gearopt.loaded.ltca` defines
each).

Conditions: the ``tca`` evaluator's (:class:`gearopt.analysis.AnalysisOptions`) and the keys of
the ``[load]`` table (:class:`gearopt.load_options.LoadOptions`), which override the design's.

Metrics (the worst over the torques; ``coast_`` for the coast side):
``lte_peak_to_peak_arcsec``, ``max_contact_pressure_mpa``, ``max_line_load_n_per_mm``,
``mesh_stiffness_n_per_mm_um`` (the mean over the torques), ``edge_loading`` (0/1).
Arrays: ``torque_nm``, ``lte_peak_to_peak_arcsec`` (one per torque), ``lte_arcsec``
(torques x positions), ``phi1_deg``. Report: ``ltca`` and ``ltca_coast``, one entry per torque.

Objectives and constraints on it (options from the study file's entries):

``lte_fluctuation``
    The LTE peak-to-peak (arcsec) over a duty cycle: with ``weights`` (one per torque of the
    evaluation, in its order) their weighted mean, else the worst over the torques. ``on``
    (label, default ``"ltca"``), ``side`` (``"drive"``, ``"coast"`` or ``"both"``, the larger).
``max_contact_pressure`` (constraint)
    The largest contact pressure over the torques less ``limit_mpa`` (required): feasible when
    the pressure stays at or below the limit. ``on``, ``side``.
``edge_loading`` (constraint)
    +0.5 when a loaded patch lies on a flank's boundary at any torque, else -0.5. ``on``,
    ``side``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any, ClassVar

import numpy as np

from gearopt import hookimpl
from gearopt.analysis import (
    AnalysisOptions,
    contact_sides,
    meshed_pair,
    pair_loaded_contact,
)
from gearopt.errors import GearoptError, StudyError
from gearopt.evaluation import BaseEvaluator, BaseObjective, Evaluation
from gearopt.load_options import LOAD_KEYS, LoadOptions


def load_metrics(results, prefix: str = "") -> dict[str, float]:
    """The scalar metrics of one side's loaded TCA over its torques."""
    return {
        f"{prefix}lte_peak_to_peak_arcsec": max(r.lte_peak_to_peak_arcsec for r in results),
        f"{prefix}max_contact_pressure_mpa": max(r.max_contact_pressure_mpa for r in results),
        f"{prefix}max_line_load_n_per_mm": max(r.max_line_load_n_per_mm for r in results),
        f"{prefix}mesh_stiffness_n_per_mm_um": float(
            np.mean([r.mesh_stiffness_n_per_mm_um for r in results])
        ),
        f"{prefix}edge_loading": float(any(r.edge_loading for r in results)),
    }


def _load_and_options(design, conditions: Mapping[str, Any] | None):
    """The load (the design's ``[load]``, the conditions' load keys over it) and the
    contact analyses' options of an ``ltca`` evaluation."""
    given = dict(conditions or {})
    load_keys = {k: given.pop(k) for k in LOAD_KEYS if k in given}
    load = LoadOptions.from_table({**design.load, **load_keys})
    if not load.torque_nm:
        raise GearoptError(
            "load.torque_nm", rule="the ltca evaluator needs at least one torque (N m)"
        )
    return load, AnalysisOptions.from_conditions(given, design=design)


class LtcaEvaluator(BaseEvaluator):
    """Loaded TCA of both sides over the load's torques."""

    name = "ltca"
    description = (
        "loaded TCA of drive and coast: LTE and its fluctuation per torque, load sharing, "
        "contact pressure, mesh stiffness, edge loading"
    )

    def check_conditions(self, design, conditions: Mapping[str, Any]) -> None:
        """The load's keys and the contact analyses' options."""
        _load_and_options(design, conditions)

    def evaluate(self, design, conditions: Mapping[str, Any] | None = None) -> Evaluation:
        load, options = _load_and_options(design, conditions)
        pair = meshed_pair(design, options)
        sides = contact_sides(pair, options)
        loaded = pair_loaded_contact(design, pair, sides, load)
        drive, coast = loaded["drive"], loaded["coast"]
        arrays = {"torque_nm": np.array(load.torque_nm)}
        curves: dict[str, dict] = {}
        for side, results in (("drive", drive), ("coast", coast)):
            for r in results:
                curves.setdefault(f"lte_{r.torque_nm:g}nm", {})[side] = (r.phi1_deg, r.lte_arcsec)
            curves.setdefault("lte_fluctuation", {})[side] = (
                np.array([r.torque_nm for r in results]),
                np.array([r.lte_peak_to_peak_arcsec for r in results]),
            )
        for prefix, results in (("", drive), ("coast_", coast)):
            arrays[f"{prefix}phi1_deg"] = results[0].phi1_deg
            arrays[f"{prefix}lte_arcsec"] = np.stack([r.lte_arcsec for r in results])
            arrays[f"{prefix}lte_peak_to_peak_arcsec"] = np.array(
                [r.lte_peak_to_peak_arcsec for r in results]
            )
            top = max(results, key=lambda r: r.torque_nm)  # the pressure map at the largest
            arrays[f"{prefix}pressure_face_mm"] = top.pattern_face_mm
            arrays[f"{prefix}pressure_profile_mm"] = top.pattern_profile_mm
            arrays[f"{prefix}pressure_mpa"] = top.pattern_pressure_mpa
        return Evaluation(
            evaluator=self.name,
            metrics={**load_metrics(drive), **load_metrics(coast, "coast_")},
            arrays=arrays,
            conditions={**options.as_dict(), "load": load.as_dict()},
            report={
                "ltca": [r.as_dict() for r in drive],
                "ltca_coast": [r.as_dict() for r in coast],
            },
            curves=curves,
        )


_PREFIXES = {"drive": ("",), "coast": ("coast_",), "both": ("", "coast_")}


class _LoadedObjective(BaseObjective):
    requires = ("ltca",)
    options: ClassVar[tuple[str, ...]] = ("on", "side")

    def reads(self, **options: Any) -> dict[str, str]:
        unknown = sorted(set(options) - set(self.options))
        if unknown:
            raise StudyError(
                f"{self.kind} {self.name}", unknown, f"unknown options; known: {self.options}"
            )
        if options.get("side", "drive") not in _PREFIXES:
            raise StudyError(
                f"{self.kind} {self.name}.side",
                options["side"],
                f"must be one of {list(_PREFIXES)}",
            )
        label = options.get("on", "ltca")
        if not isinstance(label, str):
            raise StudyError(f"{self.kind} {self.name}.on", label, "must be a label")
        return {label: "ltca"}

    @staticmethod
    def _prefixes(options) -> tuple[str, ...]:
        return _PREFIXES[options.get("side", "drive")]


class LteFluctuation(_LoadedObjective):
    name = "lte_fluctuation"
    description = "LTE peak-to-peak over a duty cycle (weighted mean over the torques, or worst)"
    options: ClassVar[tuple[str, ...]] = ("on", "side", "weights")

    def reads(self, **options: Any) -> dict[str, str]:
        weights = options.get("weights")
        if weights is not None:
            ok = isinstance(weights, list | tuple) and weights
            ok = ok and all(
                isinstance(w, int | float) and not isinstance(w, bool) and w >= 0 for w in weights
            )
            if not ok or not math.fsum(weights) > 0.0:
                raise StudyError(
                    f"objective {self.name}.weights", weights, "must be non-negative numbers"
                )
        return super().reads(**options)

    def value(self, evaluations, **options):
        evaluation = evaluations[options.get("on", "ltca")]
        weights = options.get("weights")
        worst = 0.0
        for prefix in self._prefixes(options):
            pp = np.asarray(evaluation.arrays[f"{prefix}lte_peak_to_peak_arcsec"], float)
            if weights is None:
                worst = max(worst, float(pp.max()))
                continue
            if len(weights) != len(pp):
                raise StudyError(
                    f"objective {self.name}.weights",
                    list(weights),
                    f"must give one weight per torque ({len(pp)})",
                )
            w = np.asarray(weights, float)
            worst = max(worst, float(w @ pp / w.sum()))
        return worst


class MaxContactPressure(_LoadedObjective):
    name = "max_contact_pressure"
    description = "largest contact pressure less limit_mpa (constraint)"
    kind = "constraint"
    options: ClassVar[tuple[str, ...]] = ("on", "side", "limit_mpa")

    def reads(self, **options: Any) -> dict[str, str]:
        limit = options.get("limit_mpa")
        if not (isinstance(limit, int | float) and not isinstance(limit, bool) and limit > 0):
            raise StudyError(f"constraint {self.name}.limit_mpa", limit, "is required (MPa > 0)")
        return super().reads(**options)

    def value(self, evaluations, **options):
        evaluation = evaluations[options.get("on", "ltca")]
        pressure = max(
            evaluation.metrics[f"{p}max_contact_pressure_mpa"] for p in self._prefixes(options)
        )
        return float(pressure - options["limit_mpa"])


class EdgeLoading(_LoadedObjective):
    name = "edge_loading"
    description = "no load on a flank's boundary at any torque (constraint: +0.5 with it)"
    kind = "constraint"

    def value(self, evaluations, **options):
        evaluation = evaluations[options.get("on", "ltca")]
        edge = max(evaluation.metrics[f"{p}edge_loading"] for p in self._prefixes(options))
        return float(edge) - 0.5


@hookimpl
def gearopt_evaluators() -> list[BaseEvaluator]:
    """The loaded TCA evaluator."""
    return [LtcaEvaluator()]


@hookimpl
def gearopt_objectives() -> list[BaseObjective]:
    """The loaded contact's objectives and constraints."""
    return [LteFluctuation(), MaxContactPressure(), EdgeLoading()]
