"""Loaded tooth contact analysis (LTCA).

- :mod:`gearopt.loaded.halfspace`: the local contact compliance of two elastic bodies, Love's
  uniformly loaded rectangle on Boussinesq half-spaces (influence coefficients of a patch grid);
- :mod:`gearopt.loaded.lcp`: the load distribution at one mesh position, the linear
  complementarity problem of the patch forces and the rotation lag solved exactly by an
  active-set method.
"""

from gearopt.loaded.halfspace import (
    PatchGrid,
    composite_compliance_mm2_per_n,
    halfspace_compliance_mm_per_n,
    patch_grid,
    rectangle_influence_mm_per_mpa,
)
from gearopt.loaded.lcp import ComplementarityResiduals, LoadDistribution, solve_load_distribution

__all__ = [
    "ComplementarityResiduals",
    "LoadDistribution",
    "PatchGrid",
    "composite_compliance_mm2_per_n",
    "halfspace_compliance_mm_per_n",
    "patch_grid",
    "rectangle_influence_mm_per_mpa",
    "solve_load_distribution",
]
