"""A part's triangles and the stored parameter tables of a column file, for evaluation.

A thin layer over the one scene reader (:mod:`ionic_usd.usd.reader`): no traversal or variant
selection of its own. :mod:`ionic_usd.evaluate.sections` does the math.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from pathlib import Path

import numpy as np

from ionic_usd.errors import GeometryError, ParameterError
from ionic_usd.geometry.mesh import triangulate_fan
from ionic_usd.usd.reader import read_scene

__all__ = ["part_triangles", "stored_tables"]


def part_triangles(
    path: str | Path, prim_name: str, *, variants: Mapping[str, str] | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """World-space triangles (metres, Y up) of a part's drawn meshes in a composed USD stage.

    Read by the one scene reader (:func:`ionic_usd.usd.reader.read_scene`): the same variant
    selection, visibility, purposes and instancing as preview and export.

    Parameters
    ----------
    path : USD file written by ``ionic-usd column`` or ``ionic-usd asset``
    prim_name : the part's prim name (a mesh counts when its placed path holds it, e.g.
        ``Base``)
    variants : variant selections to set on every prim that has the set (e.g.
        ``{"lod": "high", "base": "G2"}``; a set no prim has, or a value a set does not offer,
        is refused, as export refuses it); default:
        the file's own selections

    Returns
    -------
    points : (n, 3) float
    triangles : (t, 3) int
    """
    path = Path(path)
    if not path.is_file():
        raise ParameterError("usd", str(path), "an existing USD file")
    scene = read_scene(path, variants=variants)
    all_pts, all_tris, offset = [], [], 0
    for p in scene.placements:
        if prim_name not in p.path.split("/"):
            continue
        mesh = scene.meshes[p.mesh]
        pts = mesh.points @ p.matrix[:3, :3] + p.matrix[3, :3]
        all_pts.append(pts)
        all_tris.append(triangulate_fan(mesh.face_vertex_counts, mesh.face_vertex_indices) + offset)
        offset += len(pts)
    if not all_pts:
        raise GeometryError(f"{path}: no active mesh of the part (a prim named {prim_name!r})")
    return np.concatenate(all_pts), np.concatenate(all_tris)


def stored_tables(path: str | Path, keys: Iterable[str]) -> dict[str, dict]:
    """Tables stored in the default prim's customData (``ionic-usd asset`` stores the column
    parameters there), only those named in ``keys``; {} when there are none."""
    from pxr import Usd

    stage = Usd.Stage.Open(str(path), Usd.Stage.LoadNone)
    prim = stage.GetDefaultPrim() if stage else None
    data = dict(prim.GetCustomData()) if prim else {}
    nested = data.get("ionic_usd", {})
    if hasattr(nested, "get") and hasattr(nested.get("parameters"), "items"):
        data = dict(nested["parameters"])  # where ``ionic-usd asset`` keeps them
    wanted = set(keys)
    return {
        k: {n: _plain(x) for n, x in v.items()}
        for k, v in data.items()
        if k in wanted and hasattr(v, "items")
    }


def _plain(value: object) -> object:
    """A customData value as the TOML tables hold it (a ``double[]`` as a list of floats)."""
    if isinstance(value, str | bytes) or not hasattr(value, "__len__"):
        return value
    return [float(x) for x in value]  # type: ignore[attr-defined]
