"""The names of the files and prims the package writes, shared by the writers (``usd/``) and
the coordinators (``pipeline/``: the up-to-date check reads them without loading ``pxr``).

Standard library only.
"""

from __future__ import annotations

__all__ = [
    "ASSET_NAME",
    "CITY_INSTANCES_LAYER",
    "CITY_ROOT_LAYER",
    "COLONNADE_LAYER",
    "GENERATED_LAYER",
    "MATERIALS_LAYER",
    "OVERRIDES_LAYER",
    "ROOT_LAYER",
    "TEMPLE_CLASS",
]

#: the column asset's folder, interface layer stem and default prim (``IonicColumn/``)
ASSET_NAME = "IonicColumn"

# a temple folder
#: the temple's root layer (what a user opens)
ROOT_LAYER = "Temple.usda"
#: the generated layers' hub, sublayered by the root
GENERATED_LAYER = "generated.usda"
#: the user's layer: the strongest, created empty once and never rewritten
OVERRIDES_LAYER = "overrides.usda"
MATERIALS_LAYER = "materials.usda"
COLONNADE_LAYER = "colonnade.usda"
TEMPLE_CLASS = "/_class_Temple"

# a city folder
CITY_ROOT_LAYER = "City.usda"
CITY_INSTANCES_LAYER = "Instances.usdc"
