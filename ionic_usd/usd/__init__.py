"""USD authoring: the only subpackage that imports ``pxr``."""

from ionic_usd.usd.mesh import author_mesh, define_prim, mesh_extent, write_meshes
from ionic_usd.usd.stage import (
    USD_EXTENSIONS,
    check_output_path,
    create_stage,
    ensure_typed_ancestors,
    new_layer,
    save_layer,
    save_stage,
    validate_stage,
)

__all__ = [
    "USD_EXTENSIONS",
    "author_mesh",
    "check_output_path",
    "create_stage",
    "define_prim",
    "ensure_typed_ancestors",
    "mesh_extent",
    "new_layer",
    "save_layer",
    "save_stage",
    "validate_stage",
    "write_meshes",
]
