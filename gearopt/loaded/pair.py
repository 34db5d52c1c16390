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
from gearopt.loaded.compliance import DEFAULT_MESH, Material, member_compliance
from gearopt.loaded.halfspace import composite_compliance_mm2_per_n
from gearopt.loaded.ltca import LoadedContact, loaded_contact
from gearopt.loaded.patch_compliance import PatchCompliance
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


def _pair_compliance(p: PairPatches, keep, pinion, gear, composite) -> PatchCompliance:
    """The compliance of one pair's candidate patches ``keep``: Love's rectangles between the
    patches plus both teeth's influence numbers (``(model, (points, weights))`` of each
    member: its tooth model and its stencils at the patches)."""
    return PatchCompliance(
        starts=[0, keep.size],
        x_mm=p.x_mm.ravel()[keep],
        y_mm=p.y_mm.ravel()[keep],
        a_mm=0.5 * p.length_mm.ravel()[keep],
        b_mm=0.5 * p.width_mm.ravel()[keep],
        composite_mm2_per_n=composite,
        members=tuple((model.table_mm_per_n, k, w) for model, (k, w) in (pinion, gear)),
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
                _pair_compliance(p, k, (pinion, (a, b)), (gear, (c, d)), composite)
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
