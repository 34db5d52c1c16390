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
"""

from __future__ import annotations

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
from gearopt.errors import GearoptError
from gearopt.evaluation import BaseEvaluator, Evaluation
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


class LtcaEvaluator(BaseEvaluator):
    """Loaded TCA of both sides over the load's torques."""

    name = "ltca"
    description = (
        "loaded TCA of drive and coast: LTE and its fluctuation per torque, load sharing, "
        "contact pressure, mesh stiffness, edge loading"
    )

    def evaluate(self, design, conditions: Mapping[str, Any] | None = None) -> Evaluation:
        given = dict(conditions or {})
        load_keys = {k: given.pop(k) for k in LOAD_KEYS if k in given}
        load = LoadOptions.from_table({**design.load, **load_keys})
        if not load.torque_nm:
            raise GearoptError(
                "load.torque_nm", rule="the ltca evaluator needs at least one torque (N m)"
            )
        options = AnalysisOptions.from_conditions(given, design=design)
        pair = meshed_pair(design, options)
        sides = contact_sides(pair, options)
        loaded = pair_loaded_contact(design, pair, sides, load)
        drive, coast = loaded["drive"], loaded["coast"]
        arrays = {"torque_nm": np.array(load.torque_nm)}
        for prefix, results in (("", drive), ("coast_", coast)):
            arrays[f"{prefix}phi1_deg"] = results[0].phi1_deg
            arrays[f"{prefix}lte_arcsec"] = np.stack([r.lte_arcsec for r in results])
            arrays[f"{prefix}lte_peak_to_peak_arcsec"] = np.array(
                [r.lte_peak_to_peak_arcsec for r in results]
            )
        return Evaluation(
            evaluator=self.name,
            metrics={**load_metrics(drive), **load_metrics(coast, "coast_")},
            arrays=arrays,
            conditions={**options.as_dict(), "load": load.as_dict()},
            report={
                "ltca": [r.as_dict() for r in drive],
                "ltca_coast": [r.as_dict() for r in coast],
            },
        )


@hookimpl
def gearopt_evaluators() -> list[BaseEvaluator]:
    """The loaded TCA evaluator."""
    return [LtcaEvaluator()]
