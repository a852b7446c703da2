"""The city's ground: streets and open areas paved, plazas, and the lots, as flat meshes.

The site is the plan's bounding box (lots, plazas, porticoes with their stoas) grown by a
margin; it is cut into three surfaces at ``y = 0`` (where the temples and columns stand):

* ``Lots`` — the temple lots' polygons (their own stone),
* ``Plazas`` — the plaza polygons less the lots,
* ``Paving`` — the rest: streets and open ground.

They share no area (each is the others' difference), so no two faces fight for a pixel.
Each is triangulated with shapely's constrained Delaunay triangulation (holes kept), faces
up (``+Y``), with ``st`` = plan metres / ``tile`` for a tileable stone map.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ionic_usd.geometry.mesh import CornerValues, Mesh

__all__ = ["ground_meshes", "GROUND_MARGIN"]

GROUND_MARGIN = 20.0  # m of paving beyond the plan's outermost feature


def _triangles(geom) -> np.ndarray:
    """(t, 3, 2) plan triangles of a (multi)polygon, constrained Delaunay."""
    import shapely

    if geom.is_empty:
        return np.zeros((0, 3, 2))
    tris = shapely.get_parts(shapely.constrained_delaunay_triangles(geom))
    coords = [np.asarray(shapely.get_coordinates(t))[:3] for t in tris if t.area > 1e-9]
    return np.array(coords).reshape(-1, 3, 2)


def _mesh(tris: np.ndarray, name: str, tile: float) -> Mesh:
    """A +Y-facing mesh of plan triangles (USD x = e, z = −n)."""
    pts = np.zeros((len(tris) * 3, 3))
    pts[:, 0] = tris[:, :, 0].ravel()
    pts[:, 2] = -tris[:, :, 1].ravel()
    idx = np.arange(len(pts), dtype=np.int32).reshape(-1, 3)
    a, b, c = pts[idx[:, 0]], pts[idx[:, 1]], pts[idx[:, 2]]
    up = np.cross(b - a, c - a)[:, 1]
    idx[up < 0] = idx[up < 0][:, ::-1]  # counter-clockwise seen from above: normal +Y
    st = (np.stack([pts[:, 0], -pts[:, 2]], axis=1) / tile).astype(np.float32)
    normals = np.tile(np.array([[0.0, 1.0, 0.0]], dtype=np.float32), (len(pts), 1))
    return Mesh(
        pts,
        np.full(len(idx), 3, dtype=np.int32),
        idx.ravel(),
        normals=CornerValues(normals),
        st=CornerValues(st, idx.ravel().copy()),
        name=name,
    )


def ground_meshes(
    lots: Sequence[np.ndarray],
    plazas: Sequence[np.ndarray],
    extent_points: np.ndarray,
    *,
    margin: float = GROUND_MARGIN,
    tile: float = 2.0,
) -> list[Mesh]:
    """Paving, plazas and lots (see the module docstring) over the box of ``extent_points``
    ((n, 2) plan metres, e.g. every lot corner, column and stoa back) grown by ``margin``."""
    import shapely

    pts = np.asarray(extent_points, dtype=float).reshape(-1, 2)
    lo, hi = pts.min(axis=0) - margin, pts.max(axis=0) + margin
    site = shapely.box(lo[0], lo[1], hi[0], hi[1])
    lot_geom = shapely.union_all([shapely.Polygon(p) for p in lots]) if len(lots) else None
    plaza_geom = shapely.union_all([shapely.Polygon(p) for p in plazas]) if len(plazas) else None
    empty = shapely.Polygon()
    lot_geom = lot_geom if lot_geom is not None else empty
    plaza_geom = shapely.difference(plaza_geom, lot_geom) if plaza_geom is not None else empty
    paving = shapely.difference(shapely.difference(site, lot_geom), plaza_geom)
    out = []
    for name, geom in (("Paving", paving), ("Plazas", plaza_geom), ("Lots", lot_geom)):
        tris = _triangles(geom)
        if len(tris):
            out.append(_mesh(tris, name, tile))
    return out
