"""Loaded contact of a meshed pair: both sides, at the options' torques.

The compliance between two patches of one tooth pair is the sum of the pinion tooth's and the
gear tooth's finite-element influence numbers (:func:`gearopt.loaded.compliance.member_compliance`,
each at the patch's own grid coordinates on that member's flank) and the two half-spaces' local
contact compliance (:mod:`gearopt.loaded.halfspace`, Love's rectangles at the patches'
coordinates along and across the contact line). The tooth models are built once per member,
material and mesh and kept for the next analyses of the same flanks.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from gearopt.load_options import LoadOptions
from gearopt.loaded import kernels
from gearopt.loaded.compliance import DEFAULT_MESH, Material, member_compliance
from gearopt.loaded.halfspace import composite_compliance_mm2_per_n, halfspace_columns_mm_per_n
from gearopt.loaded.ltca import LoadedContact, loaded_contact
from gearopt.loaded.separations import PairPatches

__all__ = ["loaded_sides", "member_flanks"]

#: the last few members' tooth models: ``((flank ids, material, mesh), compliance by flank)``
_MODELS: list[tuple[tuple, dict]] = []


def member_flanks(pair) -> dict[str, dict]:
    """``{"pinion": {"convex", "concave"}, "gear": {...}}``: the FlankMaps of a meshed pair."""
    return {
        "pinion": {"convex": pair.drive.pinion, "concave": pair.coast.pinion},
        "gear": {"concave": pair.drive.gear, "convex": pair.coast.gear},
    }


def _compliance_of(flanks: Mapping, blank, material: Material, mesh) -> dict:
    key = (tuple(id(f) for f in flanks.values()), material, mesh)
    for known, value in _MODELS:
        if known == key:
            return value
    value = member_compliance(dict(flanks), blank, material=material, mesh=mesh)
    _MODELS.insert(0, (key, value))
    del _MODELS[4:]
    return value


class _PairColumns:
    """The compliance of one pair's candidate patches, by columns: Love's rectangles between
    the patches plus both teeth's influence numbers (each member's table with its stencils at
    the patches, :func:`kernels.influence_columns`)."""

    def __init__(self, x, y, a, b, members, composite) -> None:
        self.x, self.y, self.a, self.b = x, y, a, b
        self.members = members  # ((table, points, weights), ...)
        self.composite = composite

    def __call__(self, cols: np.ndarray) -> np.ndarray:
        out = halfspace_columns_mm_per_n(self.x, self.y, self.a, self.b, cols, self.composite)
        rows = out.T  # C-ordered (len(cols), m)
        for table, points, weights in self.members:
            kernels.influence_columns(points, weights, cols, table, rows)
        return out

    def subset(self, rows: np.ndarray) -> _PairColumns:
        """The same for the patches ``rows`` only."""
        return _PairColumns(
            self.x[rows],
            self.y[rows],
            self.a[rows],
            self.b[rows],
            tuple((table, k[rows], w[rows]) for table, k, w in self.members),
            self.composite,
        )

    def bending_mm(self, forces_n: np.ndarray) -> np.ndarray:
        """The teeth's part of ``C F`` at every patch (mm): all of it but the half-spaces'
        local part, which is positive; one table product per member."""
        out = np.zeros(self.x.size)
        for table, points, weights in self.members:
            nodal = np.bincount(
                points.ravel(), (weights * forces_n[:, None]).ravel(), minlength=table.shape[0]
            )
            out += (weights * (table @ nodal)[points]).sum(axis=1)
        return out


def _pair_columns(p: PairPatches, keep, pinion, gear, composite) -> _PairColumns:
    """:class:`_PairColumns` of one pair's candidate patches ``keep`` (``(model, (points,
    weights))`` of each member: its tooth model and its stencils at the patches)."""
    return _PairColumns(
        p.x_mm.ravel()[keep],
        p.y_mm.ravel()[keep],
        0.5 * p.length_mm.ravel()[keep],
        0.5 * p.width_mm.ravel()[keep],
        tuple((model.table_mm_per_n, k, w) for model, (k, w) in (pinion, gear)),
        composite,
    )


def loaded_sides(
    pair, sides: Mapping, blank, load: LoadOptions, *, which=("drive", "coast")
) -> dict[str, list[LoadedContact]]:
    """Loaded TCA of both sides of a meshed pair (:class:`gearopt.mesh.MeshedPair`) at the
    options' torques: ``{"drive": [one per torque], "coast": [...]}``, on the positions of the
    unloaded TCA ``sides`` (:func:`gearopt.analysis.contact_sides`); ``which`` sides."""
    flanks = member_flanks(pair)
    mesh = load.fe_mesh or DEFAULT_MESH
    materials = [
        Material(youngs_modulus_mpa=e, poisson_ratio=nu)
        for e, nu in zip(load.youngs_modulus_mpa, load.poisson_ratio, strict=True)
    ]
    models = {
        member: _compliance_of(flanks[member], blank, material, mesh)
        for member, material in zip(("pinion", "gear"), materials, strict=True)
    }
    composite = composite_compliance_mm2_per_n(
        load.youngs_modulus_mpa[0],
        load.poisson_ratio[0],
        load.youngs_modulus_mpa[1],
        load.poisson_ratio[1],
    )
    grid = load.patch_options()
    out = {}
    for side, field in (("drive", pair.drive), ("coast", pair.coast)):
        if side not in which:
            continue
        pinion = models["pinion"][field.pinion.flank]
        gear = models["gear"][field.gear.flank]

        def compliance(pairs, pinion=pinion, gear=gear) -> list:
            picked = list(pairs)
            sizes = np.cumsum([k.size for _, k in picked])[:-1]

            def flat(name):
                return np.concatenate([getattr(p, name).ravel()[k] for p, k in picked])

            # the stencils of all pairs in one call each (numpy's overhead paid once)
            k1, w1 = pinion.stencil(flat("face_mm"), flat("profile_mm"))
            k2, w2 = gear.stencil(flat("gear_face_mm"), flat("gear_profile_mm"))
            return [
                _pair_columns(p, k, (pinion, (a, b)), (gear, (c, d)), composite)
                for (p, k), a, b, c, d in zip(
                    picked,
                    np.split(k1, sizes),
                    np.split(w1, sizes),
                    np.split(k2, sizes),
                    np.split(w2, sizes),
                    strict=True,
                )
            ]

        out[side] = loaded_contact(
            field,
            sides[side],
            load.torque_nm,
            compliance=compliance,
            frame=pair.frame,
            grid=grid,
            side=side,
        )
    return out
