"""Loaded tooth contact analysis: tooth compliance by finite elements."""

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

__all__ = [
    "DEFAULT_MESH",
    "Factorised",
    "Material",
    "SolidModel",
    "ToothCompliance",
    "factorise",
    "member_compliance",
    "solid_model",
    "tooth_compliance",
]
