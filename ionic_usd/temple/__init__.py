"""Temple geometry: cuboids and inclined roof pieces, colonnade layouts, the Portunus preset.

No pxr here: the USD composer consumes these values (:class:`TempleLayout`, :class:`Cuboid`,
:func:`cuboid_mesh`). The compact text form of cuboids is parsed by
:mod:`ionic_usd.grammar.cuboid`.
"""

from ionic_usd.temple.cuboid import (
    DEFAULT_UV_SCALE,
    Cuboid,
    Incline,
    cuboid_mesh,
    cuboid_points,
    cuboid_volume,
)
from ionic_usd.temple.layout import (
    Certainty,
    ColumnKind,
    ColumnPlacement,
    Hypothesis,
    Layer,
    TempleLayout,
    TempleParams,
    build_layout,
    colonnade_positions,
    cuboids_from_tables,
    cuboids_to_toml,
    layout_from_toml,
    load_cuboids_toml,
    params_from_tables,
    portunus_layout,
)

__all__ = [
    "DEFAULT_UV_SCALE",
    "Certainty",
    "ColumnKind",
    "ColumnPlacement",
    "Cuboid",
    "Hypothesis",
    "Incline",
    "Layer",
    "TempleLayout",
    "TempleParams",
    "build_layout",
    "colonnade_positions",
    "cuboid_mesh",
    "cuboid_points",
    "cuboid_volume",
    "cuboids_from_tables",
    "cuboids_to_toml",
    "layout_from_toml",
    "load_cuboids_toml",
    "params_from_tables",
    "portunus_layout",
]
