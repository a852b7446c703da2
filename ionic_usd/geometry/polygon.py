"""Triangulating a planar polygon with holes, as indices into its own vertices.

The constrained Delaunay triangulation (shapely/GEOS) adds no vertex, so every triangle corner
is one of the rings' points: :func:`polygon_triangles` maps the corners back to the point
indices by exact coordinate lookup (GEOS copies the input coordinates), so the caller can
reuse the mesh vertices the rings came from. scipy's k-d tree is imported only for the rare
corner whose coordinates came back rounded.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ionic_usd.errors import GeometryError

__all__ = ["polygon_triangles"]


def polygon_triangles(
    outer: np.ndarray, holes: Sequence[np.ndarray] = (), *, what: str = "polygon"
) -> np.ndarray:
    """Constrained Delaunay triangles of a polygon with holes.

    Parameters
    ----------
    outer : (n, 2) float, the outline (either orientation, not closed by a repeated point)
    holes : (m_i, 2) float each, outlines of holes inside ``outer``
    what : names the polygon in the error

    Returns
    -------
    (t, 3) int64 indices into ``np.concatenate([outer, *holes])``; degenerate triangles (two
    corners on one point) dropped. The winding is shapely's; callers orient the triangles.

    Raises
    ------
    GeometryError
        If the triangulation would need a vertex that is not a ring point.
    """
    import shapely  # optional at import time: the kernel is numpy-only until a polygon is cut

    xy = np.concatenate(
        [np.asarray(outer, dtype=np.float64), *(np.asarray(h, dtype=np.float64) for h in holes)]
    )
    poly = shapely.Polygon(outer, list(holes))
    coords = shapely.get_coordinates(shapely.constrained_delaunay_triangles(poly))
    if coords.size == 0:
        return np.empty((0, 3), dtype=np.int64)
    corners = coords.reshape(-1, 4, 2)[:, :3].reshape(-1, 2)
    index: dict[tuple[float, float], int] = {}
    for i, p in enumerate(map(tuple, xy.tolist())):
        index.setdefault(p, i)
    j = np.fromiter(
        (index.get(c, -1) for c in map(tuple, corners.tolist())), dtype=np.int64, count=len(corners)
    )
    missing = j < 0
    if missing.any():
        from scipy.spatial import cKDTree

        dist, near = cKDTree(xy).query(corners[missing])
        if np.any(dist > 1e-9 * float(np.ptp(xy, axis=0).max())):
            raise GeometryError(f"{what}: the constrained triangulation added vertices")
        j[missing] = near
    tri = j.reshape(-1, 3)
    return tri[(tri[:, 0] != tri[:, 1]) & (tri[:, 1] != tri[:, 2]) & (tri[:, 0] != tri[:, 2])]
