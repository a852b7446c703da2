"""Cap a planar cut: chain the cut's border edges into loops and fill them.

The loops of a cut outline (several, possibly nested or touching) are filled with a
constrained Delaunay triangulation from shapely, which adds no vertices, so a cap and the
surface it closes share exactly the same boundary vertices. Used by the plane clip
(:mod:`ionic_usd.geometry.clip`) and the corner notch (:mod:`ionic_usd.geometry.notch`).
"""

from __future__ import annotations

import math

import numpy as np

from ionic_usd.errors import GeometryError
from ionic_usd.geometry import libm
from ionic_usd.geometry.polygon import polygon_triangles

__all__ = ["cap_loops", "cap_outline", "chain_loops", "plane_frame", "plane_loops"]


def plane_frame(normal: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Unit vectors (u, w) in the plane with u × w = −normal (the cap's outward side)."""
    helper = np.eye(3)[int(np.argmin(np.abs(normal)))]
    u = np.cross(helper, normal)
    u /= np.linalg.norm(u)
    w = np.cross(-normal, u)
    return u, w


def chain_loops(
    src: np.ndarray, dst: np.ndarray, xy: dict[int, np.ndarray], mesh_name: str
) -> list[np.ndarray]:
    """Chain directed edges into closed loops (vertex index arrays, not repeating the start).

    Where loops touch at a vertex (several outgoing edges), the walk takes the outgoing edge
    first met turning clockwise from the way back, which keeps the region on the left of
    every loop a single piece (no figure-eight loops).
    """
    order = np.argsort(src, kind="stable")
    src, dst = src[order], dst[order]
    uniq, first, cnt = np.unique(src, return_index=True, return_counts=True)
    out_of = {int(v): (int(f), int(c)) for v, f, c in zip(uniq, first, cnt, strict=True)}
    used = np.zeros(len(src), dtype=bool)
    loops = []
    for e0 in range(len(src)):
        if used[e0]:
            continue
        used[e0] = True
        loop = [int(src[e0])]
        e = e0
        while True:
            v = int(dst[e])
            f, c = out_of.get(v, (0, 0))
            cands = [k for k in range(f, f + c) if not used[k] or k == e0]
            if not cands:
                raise GeometryError(
                    f"the cut outline of mesh {mesh_name!r} is not closed "
                    "(is the mesh closed? use cap=False for open meshes)"
                )
            if len(cands) > 1:
                back = xy[int(src[e])] - xy[v]
                ab = math.atan2(back[1], back[0])
                ang = [
                    (ab - math.atan2(*(xy[int(dst[k])] - xy[v])[::-1])) % (2 * math.pi)
                    for k in cands
                ]
                nxt = cands[int(np.argmin(ang))]
            else:
                nxt = cands[0]
            if nxt == e0:
                break
            used[nxt] = True
            loop.append(v)
            e = nxt
        loops.append(np.array(loop, dtype=np.int64))
    return loops


def _signed_area(p: np.ndarray) -> float:
    x, y = p[:, 0], p[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y))


def plane_loops(
    points: np.ndarray,
    triangles: np.ndarray,
    on_plane: np.ndarray,
    normal: np.ndarray,
    *,
    mesh_name: str = "mesh",
) -> list[np.ndarray]:
    """Closed loops of a clipped mesh's border edges that lie in the cutting plane.

    Parameters
    ----------
    points : (n, 3) float
    triangles : (t, 3) int, the kept side of a clip (consistently wound)
    on_plane : (n,) bool, which points lie in the plane
    normal : (3,) float, unit normal pointing to the kept side

    Returns
    -------
    list of (k,) int64 arrays, vertex indices of each loop, ordered counter-clockwise seen
    from the ``−normal`` side for outer outlines and clockwise for holes (the winding a cap
    facing ``−normal`` needs).
    """
    tri = np.asarray(triangles, dtype=np.int64)
    directed = np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]])
    npts = len(points)
    und = np.minimum(directed[:, 0], directed[:, 1]) * npts + np.maximum(
        directed[:, 0], directed[:, 1]
    )
    _, inv, cnt = np.unique(und, return_inverse=True, return_counts=True)
    border = (cnt[inv.reshape(-1)] == 1) & on_plane[directed[:, 0]] & on_plane[directed[:, 1]]
    if not border.any():
        return []
    # the cap runs along each border edge the other way round
    src, dst = directed[border, 1], directed[border, 0]
    u, w = plane_frame(np.asarray(normal, dtype=np.float64))
    verts = np.unique(np.concatenate([src, dst]))
    p2 = libm.linear(points[verts], np.stack([u, w]))
    xy = dict(zip(verts.tolist(), p2, strict=True))
    return chain_loops(src, dst, xy, mesh_name)


def cap_outline(
    points: np.ndarray, tri: np.ndarray, on_plane: np.ndarray, normal: np.ndarray, mesh_name: str
) -> tuple[np.ndarray, np.ndarray]:
    """(c, 3) int64 cap triangles over the cut outline (the border edges of ``tri`` in the
    plane), wound to face ``−normal``, and the (c,) int64 number of the outer outline each
    one fills: :func:`cap_loops` of :func:`plane_loops`."""
    loops = plane_loops(points, tri, on_plane, normal, mesh_name=mesh_name)
    return cap_loops(points, loops, normal, mesh_name)


def cap_loops(
    points: np.ndarray, loops: list[np.ndarray], normal: np.ndarray, mesh_name: str
) -> tuple[np.ndarray, np.ndarray]:
    """(c, 3) int64 triangles filling closed planar ``loops`` (vertex index arrays into
    ``points``, counter-clockwise seen from ``−normal`` for outer outlines, clockwise for
    holes), wound to face ``−normal``, and the (c,) int64 number of the outer outline each
    one fills."""
    import shapely  # optional at import time: the kernel is numpy-only until a cut is made

    if not loops:
        return np.empty((0, 3), dtype=np.int64), np.empty(0, dtype=np.int64)
    u, w = plane_frame(normal)
    rings = [libm.linear(points[lp], np.stack([u, w])) for lp in loops]
    areas = np.array([_signed_area(r) for r in rings])
    keep = [i for i in range(len(loops)) if len(loops[i]) >= 3 and areas[i] != 0.0]
    outer = [i for i in keep if areas[i] > 0]
    holes = [i for i in keep if areas[i] < 0]
    # a hole belongs to the smallest outer outline around it (outlines of overlapping
    # shells may cross each other; each outer outline is capped on its own)
    outer_polys = [shapely.Polygon(rings[i]) for i in outer]
    owned: dict[int, list[int]] = {i: [] for i in range(len(outer))}
    for h in holes:
        probe = shapely.Point(rings[h][0])
        inside = [k for k, pg in enumerate(outer_polys) if pg.covers(probe) and pg.area > -areas[h]]
        if not inside:
            raise GeometryError(
                f"a hole in the cut of mesh {mesh_name!r} lies in no outline "
                "(is the mesh consistently wound?)"
            )
        owned[min(inside, key=lambda k: outer_polys[k].area)].append(h)
    caps, which = [], []
    for k, i in enumerate(outer):
        lp = np.concatenate([loops[i]] + [loops[h] for h in owned[k]])
        ct = lp[
            polygon_triangles(
                rings[i],
                [rings[h] for h in owned[k]],
                what=f"the cap of mesh {mesh_name!r}",
            )
        ]
        if len(ct) == 0:
            continue
        ct = ct[(ct[:, 0] != ct[:, 1]) & (ct[:, 1] != ct[:, 2]) & (ct[:, 0] != ct[:, 2])]
        # wind every cap triangle counter-clockwise in (u, w), i.e. facing −normal
        q = points[ct]
        flip = libm.dot(np.cross(q[:, 1] - q[:, 0], q[:, 2] - q[:, 0]), normal) > 0
        ct[flip] = ct[flip][:, ::-1]
        caps.append(ct)
        which.append(np.full(len(ct), k, dtype=np.int64))
    if not caps:
        return np.empty((0, 3), dtype=np.int64), np.empty(0, dtype=np.int64)
    return np.concatenate(caps), np.concatenate(which)
