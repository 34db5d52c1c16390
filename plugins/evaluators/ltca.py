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
from typing import Any

import numpy as np

from gearopt import hookimpl
from gearopt.analysis import (
    AnalysisOptions,
    contact_sides,
    meshed_pair,
    pair_loaded_contact,
)
from gearopt.analysis_options import ANALYSIS_OPTIONS
from gearopt.declarations import SIDES, Curve, Metric, Option
from gearopt.errors import GearoptError, StudyError
from gearopt.evaluation import BaseEvaluator, BaseObjective, Evaluation
from gearopt.load_options import LOAD_KEYS, LoadOptions

#: the keys of the ``[load]`` table an ``ltca`` evaluation's conditions may override
LOAD_OPTIONS = (
    Option(
        name="torque_nm",
        description="output torque or torques (N m on the gear); default: the design's [load]",
    ),
    Option(name="youngs_modulus_mpa", description="Young's modulus (MPa), or per member"),
    Option(name="poisson_ratio", description="Poisson's ratio, or per member"),
    Option(name="fe_mesh", description="the compliance's finite-element mesh"),
    Option(name="patches", description="the contact patches' options"),
    Option(name="reach_um", description="separations counted as the potential contact (um)"),
)


#: the report section of each side (``gearopt analyze --json``'s keys), before each metric
SECTIONS = {"drive": "ltca", "coast": "ltca_coast"}
#: the metrics of one side, each the worst over the torques (the mean for the stiffness)
LTCA_METRICS = (
    Metric(
        name="lte_peak_to_peak_arcsec",
        unit="arcsec",
        description="LTE peak-to-peak, the largest over the torques",
        per_side=True,
    ),
    Metric(
        name="max_contact_pressure_mpa",
        unit="MPa",
        description="largest contact pressure over the torques",
        per_side=True,
    ),
    Metric(
        name="max_line_load_n_per_mm",
        unit="N/mm",
        description="largest line load over the torques",
        per_side=True,
    ),
    Metric(
        name="mesh_stiffness_n_per_mm_um",
        unit="N/(mm um)",
        description="mesh stiffness, the mean over the torques",
        per_side=True,
    ),
    Metric(
        name="edge_loading",
        description="a loaded patch on a flank's boundary at some torque (0/1)",
        per_side=True,
    ),
)


def load_metrics(results, section: str) -> dict[str, float]:
    """The scalar metrics of one side's loaded TCA over its torques (names after
    ``section``: the worst over the report's list of torques)."""
    return {
        f"{section}.lte_peak_to_peak_arcsec": max(r.lte_peak_to_peak_arcsec for r in results),
        f"{section}.max_contact_pressure_mpa": max(r.max_contact_pressure_mpa for r in results),
        f"{section}.max_line_load_n_per_mm": max(r.max_line_load_n_per_mm for r in results),
        f"{section}.mesh_stiffness_n_per_mm_um": float(
            np.mean([r.mesh_stiffness_n_per_mm_um for r in results])
        ),
        f"{section}.edge_loading": float(any(r.edge_loading for r in results)),
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
    section = "ltca"
    sections = SECTIONS
    metrics = LTCA_METRICS
    curves = (
        Curve(
            name="lte_*nm",
            x="phi1_deg",
            y="lte_arcsec",
            x_unit="deg",
            y_unit="arcsec",
            description="loaded TE over the positions at one torque (lte_100nm: 100 N m)",
            sides=SIDES,
        ),
        Curve(
            name="lte_fluctuation",
            x="torque_nm",
            y="lte_peak_to_peak_arcsec",
            x_unit="N m",
            y_unit="arcsec",
            description="LTE peak-to-peak over the torques",
            sides=SIDES,
        ),
    )
    options = (*ANALYSIS_OPTIONS, *LOAD_OPTIONS)
    analysis = True

    def in_analysis(self, design) -> bool:
        """With a torque: the design's ``[load]`` gives one (or ``--torque-nm``)."""
        return design.load.get("torque_nm") is not None

    def check_conditions(self, design, conditions: Mapping[str, Any]) -> None:
        """The declared options, then the load's keys over the design's ``[load]``."""
        super().check_conditions(design, conditions)
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
            metrics={
                **load_metrics(drive, SECTIONS["drive"]),
                **load_metrics(coast, SECTIONS["coast"]),
            },
            arrays=arrays,
            conditions={**options.as_dict(), "load": load.as_dict()},
            report={
                SECTIONS["drive"]: [r.as_dict() for r in drive],
                SECTIONS["coast"]: [r.as_dict() for r in coast],
            },
            curves=curves,
        )


_PREFIXES = {"drive": ("ltca.",), "coast": ("ltca_coast.",), "both": ("ltca.", "ltca_coast.")}
_ON = Option(name="on", default="ltca", kind="label", description="label of the ltca evaluation")
_SIDE = Option(
    name="side",
    default="drive",
    kind="string",
    choices=tuple(_PREFIXES),
    description="the flank side read; both: the larger",
)


class _LoadedObjective(BaseObjective):
    requires = ("ltca",)
    options = (_ON, _SIDE)

    @staticmethod
    def _prefixes(options) -> tuple[str, ...]:
        return _PREFIXES[options.get("side", "drive")]


class LteFluctuation(_LoadedObjective):
    name = "lte_fluctuation"
    description = "LTE peak-to-peak over a duty cycle (weighted mean over the torques, or worst)"
    options = (
        _ON,
        _SIDE,
        Option(
            name="weights",
            kind="numbers",
            lower=0.0,
            description="one weight per torque of the evaluation (a duty cycle); default: worst",
        ),
    )

    def reads(self, **options: Any) -> dict[str, str]:
        labels = super().reads(**options)
        weights = options.get("weights")
        if weights is not None and not math.fsum(weights) > 0.0:
            raise StudyError(
                f"objective {self.name}.weights", weights, "must be non-negative numbers"
            )
        return labels

    def value(self, evaluations, **options):
        evaluation = evaluations[options.get("on", "ltca")]
        weights = options.get("weights")
        worst = 0.0
        for prefix in self._prefixes(options):
            array = "" if prefix == "ltca." else "coast_"
            pp = np.asarray(evaluation.arrays[f"{array}lte_peak_to_peak_arcsec"], float)
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
    options = (
        _ON,
        _SIDE,
        Option(
            name="limit_mpa",
            kind="number",
            lower=1e-9,
            required=True,
            description="the largest contact pressure allowed (MPa > 0)",
        ),
    )

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
