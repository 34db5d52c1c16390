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

        def compliance(positions, pinion=pinion, gear=gear) -> list:
            picked = [pair for pairs in positions for pair in pairs]
            sizes = np.array([k.size for _, k in picked], dtype=np.intp)

            def flat(name):
                return np.concatenate([getattr(p, name).ravel()[k] for p, k in picked])

            # all positions' patches in one array each, the stencils in one call each
            # (numpy's overhead paid once); each position's compliance a slice of them
            x, y = flat("x_mm"), flat("y_mm")
            a, b = 0.5 * flat("length_mm"), 0.5 * flat("width_mm")
            k1, w1 = pinion.stencil(flat("face_mm"), flat("profile_mm"))
            k2, w2 = gear.stencil(flat("gear_face_mm"), flat("gear_profile_mm"))
            ends = np.cumsum([len(pairs) for pairs in positions])
            pair_ends = np.concatenate([[0], np.cumsum(sizes)])
            out, first = [], 0
            for last in ends:
                lo, hi = pair_ends[first], pair_ends[last]
                out.append(
                    PatchCompliance(
                        starts=pair_ends[first : last + 1] - lo,
                        x_mm=x[lo:hi],
                        y_mm=y[lo:hi],
                        a_mm=a[lo:hi],
                        b_mm=b[lo:hi],
                        composite_mm2_per_n=composite,
                        members=(
                            (pinion.table_mm_per_n, k1[lo:hi], w1[lo:hi]),
                            (gear.table_mm_per_n, k2[lo:hi], w2[lo:hi]),
                        ),
                    )
                )
                first = last
            return out

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
