"""A member measured on its nominal grid: the nominal flanks, deviations of any design from
them, and the split of a deviation into what an engineer reads (pressure angle, spiral angle,
crowning, bias).

Split of a flank's deviation d (um) on the grid: with u the grid's face position scaled to
[-1, 1] toe to heel and v the profile position scaled to [-1, 1] root to top in each column, the
least-squares fit

    d ~ c0 + c_v v + c_u u + c_uu (u^2 - 1/3) + c_vv (v^2 - 1/3) + c_uv u v

over the valid points gives, in um: ``spacing_um`` c0 (the flank's mean offset: tooth
thickness or spacing); ``pressure_angle_um`` 2 c_v (top minus root: a pressure-angle error);
``spiral_angle_um`` 2 c_u (heel minus toe: a spiral-angle error); ``lengthwise_crowning_um``
-c_uu and ``profile_crowning_um`` -c_vv (the middle above the ends: positive crowning removes
material at the ends); ``bias_um`` 4 c_uv (the pressure-angle error at the heel minus that at
the toe: bias or twist); ``residual_rms_um`` what the six terms leave.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from gearopt.design import Design
from gearopt.design_files import parse_design, source_with_machine
from gearopt.errors import GearoptWarning
from gearopt.flank import FLANKS, FlankGrid
from gearopt.measurement.grid import (
    DEFAULT_POINTS,
    FlankPoints,
    MeasuringGrid,
    flank_points,
    measuring_grid,
    normal_deviation_um,
)
from gearopt.plugins import get_machine_model

__all__ = [
    "NominalMeasurement",
    "explicit_design",
    "nominal_measurement",
    "split_deviation",
    "SPLIT_KEYS",
]

SPLIT_KEYS = (
    "spacing_um",
    "pressure_angle_um",
    "spiral_angle_um",
    "lengthwise_crowning_um",
    "profile_crowning_um",
    "bias_um",
    "residual_rms_um",
)


@dataclass(frozen=True, kw_only=True)
class NominalMeasurement:
    """A member's nominal grid and flanks: what every measured deviation refers to.

    Attributes
    ----------
    design
        The nominal design.
    member
        ``"pinion"`` or ``"gear"``.
    grid
        The nominal measuring grid (from the blank).
    points
        ``{flank: FlankPoints}`` of the nominal flanks.
    flank_grid
        The FlankMap grid the flanks are generated on.
    """

    design: Design
    member: str
    grid: MeasuringGrid
    points: Mapping[str, FlankPoints]
    flank_grid: FlankGrid

    def deviations(self, design: Design) -> dict[str, tuple[NDArray, NDArray]]:
        """``{flank: (deviation_um, valid)}`` of ``design``'s flanks of this member on the
        nominal grid (:func:`gearopt.measurement.grid.normal_deviation_um`)."""
        model = get_machine_model(design.model)
        with warnings.catch_warnings():  # a root cut above its line is legal here
            warnings.simplefilter("ignore", GearoptWarning)
            flanks = model.generate_flanks(design, member=self.member, grid=self.flank_grid)
        return {f: normal_deviation_um(self.grid, self.points[f], flanks[f]) for f in self.points}

    def rotation_um_per_deg(self, flank: str) -> NDArray:
        """``(n_face, n_profile)`` deviation (um) of ``flank`` turned by +1 deg about the
        member axis (the tooth's angular position)."""
        return 1000.0 * math.radians(1.0) * self.grid.radius_mm * self.points[flank].circumferential


def explicit_design(design: Design) -> Design:
    """``design`` with its machine settings written out (the model's
    :meth:`~gearopt.machine.BaseMachineModel.machine_table`, no ``[synthesis]``): the same
    flanks, and every correction setting a key of its own."""
    table = get_machine_model(design.model).machine_table(design)
    return parse_design(source_with_machine(design, table), path=design.path)


def nominal_measurement(
    design: Design,
    member: str,
    *,
    points: tuple[int, int] = DEFAULT_POINTS,
    margin_mm: float | None = None,
    flank_grid: FlankGrid | None = None,
) -> NominalMeasurement:
    """Generate ``member``'s flanks of ``design`` and place the nominal grid on them (the
    measurement's design is :func:`explicit_design` of it)."""
    design = explicit_design(design)
    grid = measuring_grid(design.blank, member, points=points, margin_mm=margin_mm)
    flank_grid = flank_grid or FlankGrid()
    model = get_machine_model(design.model)
    flanks = model.generate_flanks(design, member=member, grid=flank_grid)
    return NominalMeasurement(
        design=design,
        member=member,
        grid=grid,
        points={f: flank_points(grid, flanks[f]) for f in FLANKS},
        flank_grid=flank_grid,
    )


def split_deviation(grid: MeasuringGrid, deviation_um: NDArray, valid: NDArray) -> dict:
    """The split of one flank's deviation (module docstring), ``{key: um}`` for
    :data:`SPLIT_KEYS`; NaN-free: terms the valid points cannot fit are 0."""
    n_face, n_profile = grid.shape
    u = np.broadcast_to(np.linspace(-1.0, 1.0, n_face)[:, None], grid.shape)
    v = np.broadcast_to(np.linspace(-1.0, 1.0, n_profile)[None, :], grid.shape)
    basis = np.stack(
        [np.ones(grid.shape), v, u, u * u - 1.0 / 3.0, v * v - 1.0 / 3.0, u * v], axis=-1
    )[valid]
    d = np.asarray(deviation_um)[valid]
    if d.size == 0:
        return dict.fromkeys(SPLIT_KEYS, 0.0)
    coef, *_ = np.linalg.lstsq(basis, d, rcond=1e-10)
    rest = d - basis @ coef
    c0, cv, cu, cuu, cvv, cuv = (float(c) for c in coef)
    return {
        "spacing_um": c0,
        "pressure_angle_um": 2.0 * cv,
        "spiral_angle_um": 2.0 * cu,
        "lengthwise_crowning_um": -cuu,
        "profile_crowning_um": -cvv,
        "bias_um": 4.0 * cuv,
        "residual_rms_um": float(np.sqrt(np.mean(rest * rest))),
    }
