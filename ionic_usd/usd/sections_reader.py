"""Reading the meshes of a part from a composed USD stage, for evaluation's sections.

The only place evaluation touches pxr: :mod:`ionic_usd.evaluate.sections` does the math.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from pathlib import Path

import numpy as np

from ionic_usd.errors import GeometryError, ParameterError

__all__ = ["part_triangles", "stored_tables"]


def part_triangles(
    path: str | Path, prim_name: str, *, variants: Mapping[str, str] | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """World-space triangles (metres) of a part's active meshes in a composed USD stage.

    Parameters
    ----------
    path : USD file written by ``ionic-usd column`` or ``ionic-usd asset``
    prim_name : the part's prim name (a mesh counts when its path holds it, e.g. ``Base``)
    variants : variant selections to set on every prim that has the set (e.g.
        ``{"lod": "high", "base": "G2"}``); default: the file's own selections

    Returns
    -------
    points : (n, 3) float
    triangles : (t, 3) int
    """
    from pxr import Usd, UsdGeom

    path = Path(path)
    if not path.is_file():
        raise ParameterError("usd", str(path), "an existing USD file")
    stage = Usd.Stage.Open(str(path))
    if stage is None:
        raise GeometryError(f"{path}: cannot open as a USD stage")
    if variants:
        for prim in stage.Traverse():
            vsets = prim.GetVariantSets()
            for name, value in variants.items():
                if vsets.HasVariantSet(name):
                    vs = vsets.GetVariantSet(name)
                    if value not in vs.GetVariantNames():
                        raise ParameterError(f"variant {name}", value,
                                             f"one of {', '.join(vs.GetVariantNames())}")
                    vs.SetVariantSelection(value)
    mpu = UsdGeom.GetStageMetersPerUnit(stage) or 1.0
    cache = UsdGeom.XformCache(Usd.TimeCode.Default())
    all_pts, all_tris, offset = [], [], 0
    for prim in stage.Traverse():
        if not prim.IsA(UsdGeom.Mesh) or prim_name not in prim.GetPath().pathString.split("/"):
            continue
        mesh = UsdGeom.Mesh(prim)
        pts = np.asarray(mesh.GetPointsAttr().Get(), dtype=np.float64).reshape(-1, 3)
        counts = np.asarray(mesh.GetFaceVertexCountsAttr().Get(), dtype=np.int64)
        idx = np.asarray(mesh.GetFaceVertexIndicesAttr().Get(), dtype=np.int64)
        if pts.size == 0 or counts.size == 0:
            continue
        m = np.asarray(cache.GetLocalToWorldTransform(prim), dtype=np.float64)
        pts = (np.column_stack([pts, np.ones(len(pts))]) @ m)[:, :3] * mpu
        all_pts.append(pts)
        all_tris.append(_fan(counts, idx) + offset)
        offset += len(pts)
    if not all_pts:
        raise GeometryError(f"{path}: no active mesh of the part (a prim named {prim_name!r})")
    return np.concatenate(all_pts), np.concatenate(all_tris)


def _fan(counts: np.ndarray, idx: np.ndarray) -> np.ndarray:
    """Triangles of polygons given as USD face counts/indices (fan triangulation)."""
    if np.all(counts == 3):
        return idx.reshape(-1, 3)
    starts = np.concatenate([[0], np.cumsum(counts)[:-1]])
    n_tri = np.maximum(counts - 2, 0)
    face = np.repeat(np.arange(len(counts)), n_tri)
    k = np.arange(n_tri.sum()) - np.repeat(np.cumsum(n_tri) - n_tri, n_tri)
    s = starts[face]
    return np.stack([idx[s], idx[s + k + 1], idx[s + k + 2]], axis=1)


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
    return {k: dict(v) for k, v in data.items() if k in wanted and hasattr(v, "items")}


