"""Loaded tooth contact analysis (LTCA).

- :mod:`gearopt.loaded.compliance`: the bending and shear compliance of a member's tooth,
  finite-element influence numbers of a model built from its two FlankMaps;
- :mod:`gearopt.loaded.halfspace`: the local contact compliance of two elastic bodies, Love's
  uniformly loaded rectangle on Boussinesq half-spaces (influence coefficients of a patch grid,
  or columns of them on demand, compiled in :mod:`gearopt.loaded.kernels`);
- :mod:`gearopt.loaded.lcp`: the load distribution at one mesh position, the linear
  complementarity problem of the patch forces and the rotation lag solved exactly by an
  active-set method, on a dense compliance or on its columns requested as needed, or compiled
  (:mod:`gearopt.loaded.lcp_kernels`) on the compliance of contact patches
  (:mod:`gearopt.loaded.patch_compliance`, computed by columns and kept);
- :mod:`gearopt.loaded.separations`: the initial separations, patches around each tooth pair's
  unloaded contact on the flanks' interpolants;
- :mod:`gearopt.loaded.ltca`: one side's loaded TCA over the mesh cycle (LTE, load sharing,
  pressure, mesh stiffness, edge loading); :mod:`gearopt.loaded.pair`: both sides of a pair.
"""

from __future__ import annotations

import importlib

__all__ = [
    "ColumnCache",
    "DEFAULT_MESH",
    "FAR_FIELD_RATIO",
    "ComplementarityResiduals",
    "Factorised",
    "LoadDistribution",
    "LoadedContact",
    "Material",
    "PairPatches",
    "PatchCompliance",
    "PatchGrid",
    "PatchOptions",
    "PositionLoad",
    "SolidModel",
    "ToothCompliance",
    "composite_compliance_mm2_per_n",
    "contact_patches",
    "factorise",
    "halfspace_columns_mm_per_n",
    "halfspace_compliance_mm_per_n",
    "loaded_contact",
    "loaded_sides",
    "member_compliance",
    "patch_grid",
    "rectangle_influence_mm_per_mpa",
    "solid_model",
    "solve_load_columns",
    "solve_load_distribution",
    "solve_load_patches",
    "tooth_compliance",
]

#: where each public name lives: imported at its first use (PEP 562), so that importing one
#: submodule (the warm-up's kernels) does not import scikit-fem's and SciPy's parts
_WHERE = {
    "PatchOptions": "gearopt.load_options",
    "DEFAULT_MESH": "gearopt.loaded.compliance",
    "Factorised": "gearopt.loaded.compliance",
    "Material": "gearopt.loaded.compliance",
    "SolidModel": "gearopt.loaded.compliance",
    "ToothCompliance": "gearopt.loaded.compliance",
    "factorise": "gearopt.loaded.compliance",
    "member_compliance": "gearopt.loaded.compliance",
    "solid_model": "gearopt.loaded.compliance",
    "tooth_compliance": "gearopt.loaded.compliance",
    "FAR_FIELD_RATIO": "gearopt.loaded.halfspace",
    "PatchGrid": "gearopt.loaded.halfspace",
    "composite_compliance_mm2_per_n": "gearopt.loaded.halfspace",
    "halfspace_columns_mm_per_n": "gearopt.loaded.halfspace",
    "halfspace_compliance_mm_per_n": "gearopt.loaded.halfspace",
    "patch_grid": "gearopt.loaded.halfspace",
    "rectangle_influence_mm_per_mpa": "gearopt.loaded.halfspace",
    "ColumnCache": "gearopt.loaded.lcp",
    "ComplementarityResiduals": "gearopt.loaded.lcp",
    "LoadDistribution": "gearopt.loaded.lcp",
    "solve_load_columns": "gearopt.loaded.lcp",
    "solve_load_distribution": "gearopt.loaded.lcp",
    "solve_load_patches": "gearopt.loaded.lcp",
    "LoadedContact": "gearopt.loaded.ltca",
    "PositionLoad": "gearopt.loaded.ltca",
    "loaded_contact": "gearopt.loaded.ltca",
    "loaded_sides": "gearopt.loaded.pair",
    "PatchCompliance": "gearopt.loaded.patch_compliance",
    "PairPatches": "gearopt.loaded.separations",
    "contact_patches": "gearopt.loaded.separations",
}


def __getattr__(name: str):
    if name in _WHERE:
        value = getattr(importlib.import_module(_WHERE[name]), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
