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

from gearopt.load_options import PatchOptions
from gearopt.loaded.compliance import (
    DEFAULT_MESH,
    Factorised,
    Material,
    SolidModel,
    ToothCompliance,
    factorise,
    member_compliance,
    solid_model,
    tooth_compliance,
)
from gearopt.loaded.halfspace import (
    FAR_FIELD_RATIO,
    PatchGrid,
    composite_compliance_mm2_per_n,
    halfspace_columns_mm_per_n,
    halfspace_compliance_mm_per_n,
    patch_grid,
    rectangle_influence_mm_per_mpa,
)
from gearopt.loaded.lcp import (
    ColumnCache,
    ComplementarityResiduals,
    LoadDistribution,
    solve_load_columns,
    solve_load_distribution,
    solve_load_patches,
)
from gearopt.loaded.ltca import LoadedContact, PositionLoad, loaded_contact
from gearopt.loaded.pair import loaded_sides
from gearopt.loaded.patch_compliance import PatchCompliance
from gearopt.loaded.separations import PairPatches, contact_patches

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
