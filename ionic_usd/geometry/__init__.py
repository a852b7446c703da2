"""Pure-numpy geometry kernel (no pxr): Mesh, ring stitching, curves, revolve, checks."""

from ionic_usd.geometry.analysis import MeshReport, boundary_edges, inspect_mesh, signed_volume
from ionic_usd.geometry.clip import clip_mesh
from ionic_usd.geometry.curves import (
    bernstein,
    bezier,
    cumulative_length,
    polyline_length,
    resample_polyline,
    revolve,
    ring,
    ring_angles,
)
from ionic_usd.geometry.mesh import (
    CornerValues,
    Mesh,
    face_normals,
    merge,
    smooth_normals,
    transform,
    triangulate_fan,
    weld,
)
from ionic_usd.geometry.polygon import polygon_triangles
from ionic_usd.geometry.stitch import auto_sequence, row_parameters, stitch
from ionic_usd.geometry.sweep import sweep

__all__ = [
    "polygon_triangles",
    "CornerValues",
    "Mesh",
    "MeshReport",
    "auto_sequence",
    "bernstein",
    "bezier",
    "clip_mesh",
    "boundary_edges",
    "cumulative_length",
    "face_normals",
    "inspect_mesh",
    "merge",
    "polyline_length",
    "resample_polyline",
    "revolve",
    "ring",
    "ring_angles",
    "row_parameters",
    "signed_volume",
    "smooth_normals",
    "stitch",
    "sweep",
    "transform",
    "triangulate_fan",
    "weld",
]
