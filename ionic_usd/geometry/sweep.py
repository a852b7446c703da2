"""Sweep a closed 2D section along a planar polyline with mitred corners.

The section is given in ``(u, v)`` coordinates: ``u`` along the path's side normal (for a closed
path: outward, away from the enclosed area; for an open path: ``cross(tangent, axis)``, the
right-hand side when ``axis`` points at the viewer… see :func:`side_normals`) and ``v`` along
``axis``, the normal of the path's plane. A moulding swept round a building therefore has ``u``
= projection beyond the wall face and ``v`` = height.

At an interior path vertex the section is placed on the mitre plane: a point at offset ``u``
moves along the mitre vector ``m = (s₁ + s₂) / (1 + s₁·s₂)`` of the two segments' side
normals, so that it lies at distance ``u`` from *both* segments' lines (``m·s₁ = m·s₂ = 1``).
Every side face is then planar and the rows of consecutive segments share their corner points:
the sweep is closed (watertight) at the mitres by construction. Open paths end on planes
perpendicular to their end segments and are capped with the section polygon (a constrained
Delaunay triangulation from shapely, which adds no points).

The winding is chosen from the signed volume, so the result is outward-facing whatever the
orientation of the section and the path.
"""

from __future__ import annotations

import math

import numpy as np

from ionic_usd.errors import GeometryError
from ionic_usd.geometry import libm
from ionic_usd.geometry.mesh import CornerValues, Mesh

__all__ = ["sweep", "side_normals", "mitre_vectors", "polygon_area"]


def polygon_area(poly: np.ndarray) -> float:
    """Signed area of a closed 2D polygon (positive when counter-clockwise).

    Parameters
    ----------
    poly : (n, 2) float
    """
    p = np.asarray(poly, dtype=np.float64)
    q = np.roll(p, -1, axis=0)
    return 0.5 * float(np.sum(p[:, 0] * q[:, 1] - q[:, 0] * p[:, 1]))


def _signed_volume(points: np.ndarray, triangles: np.ndarray) -> float:
    """Signed volume of triangles (n, 3) indexing points (n, 3); see
    :func:`ionic_usd.geometry.analysis.signed_volume` (this one needs no Mesh yet)."""
    pts = np.asarray(points, dtype=np.float64)
    p = (pts - pts.mean(axis=0))[np.asarray(triangles)]
    return float(np.einsum("ij,ij->i", p[:, 0], np.cross(p[:, 1], p[:, 2])).sum() / 6.0)


def _unit(v: np.ndarray) -> np.ndarray:
    n = np.linalg.norm(v, axis=-1, keepdims=True)
    return v / np.where(n > 0, n, 1.0)


def side_normals(path: np.ndarray, axis: np.ndarray, closed: bool) -> np.ndarray:
    """Unit side normal ``cross(tangent, axis)`` of each segment.

    Returns
    -------
    (s, 3) float, s = m segments for a closed path of m points, m − 1 for an open one
    """
    nxt = np.roll(path, -1, axis=0) if closed else path[1:]
    cur = path if closed else path[:-1]
    return _unit(np.cross(nxt - cur, axis))


def mitre_vectors(sides: np.ndarray, closed: bool) -> np.ndarray:
    """Per path vertex, the vector a section point at offset ``u = 1`` moves along.

    Parameters
    ----------
    sides : (s, 3) unit side normals of the segments
    closed : whether the path wraps (vertex i joins segments i − 1 and i)

    Returns
    -------
    (m, 3) float: ``(s₁ + s₂) / (1 + s₁·s₂)`` at joints; the end segments' normals at the
    ends of an open path.
    """
    if closed:
        prev, nxt = np.roll(sides, 1, axis=0), sides
    else:
        prev = np.vstack([sides[:1], sides])
        nxt = np.vstack([sides, sides[-1:]])
    denom = 1.0 + np.einsum("ij,ij->i", prev, nxt)
    if np.any(denom < 1e-6):
        raise GeometryError("sweep: the path turns back on itself (a 180° corner)")
    return (prev + nxt) / denom[:, None]


def _check(profile, path, axis, closed) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    prof = np.asarray(profile, dtype=np.float64)
    pts = np.asarray(path, dtype=np.float64)
    ax = np.asarray(axis, dtype=np.float64).reshape(-1)
    if prof.ndim != 2 or prof.shape[1] != 2 or len(prof) < 3:
        raise GeometryError("sweep: the section must be (n ≥ 3, 2) points (u, v)")
    if pts.ndim != 2 or pts.shape[1] != 3 or len(pts) < (3 if closed else 2):
        raise GeometryError("sweep: the path must be (m, 3) points (≥ 3 closed, ≥ 2 open)")
    if ax.size != 3 or not np.all(np.isfinite(ax)) or np.linalg.norm(ax) == 0:
        raise GeometryError("sweep: axis must be a non-zero 3-vector")
    if not (np.all(np.isfinite(prof)) and np.all(np.isfinite(pts))):
        raise GeometryError("sweep: section and path must be finite")
    ax = ax / np.linalg.norm(ax)
    seg = (np.roll(pts, -1, axis=0) - pts) if closed else np.diff(pts, axis=0)
    scale = max(1.0, float(np.abs(pts).max()))
    if np.any(np.linalg.norm(seg, axis=1) <= 1e-12 * scale):
        raise GeometryError("sweep: the path has coincident consecutive points")
    if np.abs(libm.dot(pts - pts[0], ax)).max() > 1e-9 * scale:
        raise GeometryError("sweep: the path must lie in a plane perpendicular to axis")
    if abs(polygon_area(prof)) <= 1e-15:
        raise GeometryError("sweep: the section encloses no area")
    return prof, pts, ax


def _check_offsets(
    pts: np.ndarray, mit: np.ndarray, us: tuple[float, float], ax: np.ndarray, closed: bool
) -> None:
    """Refuse sections that reach so far that the sweep would cut through itself.

    The sweep is the union of the offset copies of the path for ``u`` in the section's range;
    it is free of self-intersections when no offset copy at the extreme ``u`` reverses a
    segment (a mitre overtaking its neighbour) or crosses itself.
    """
    import shapely

    seg = (np.roll(pts, -1, axis=0) - pts) if closed else np.diff(pts, axis=0)
    e1 = seg[0] / np.linalg.norm(seg[0])
    e2 = np.cross(ax, e1)
    for u in us:
        off = pts + u * mit
        oseg = (np.roll(off, -1, axis=0) - off) if closed else np.diff(off, axis=0)
        if np.any(np.einsum("ij,ij->i", oseg, seg) <= 0):
            raise GeometryError(
                f"sweep: the section reaches u = {u:g}, past where a mitre "
                "overtakes its neighbour (it would cut through itself)"
            )
        flat = libm.linear(off, np.stack([e1, e2]))
        line = shapely.LinearRing(flat) if closed else shapely.LineString(flat)
        if not line.is_simple:
            raise GeometryError(f"sweep: at u = {u:g} the offset path crosses itself")


def _cap_triangles(prof: np.ndarray) -> np.ndarray:
    """(t, 3) indices into ``prof`` triangulating the (simple) section polygon."""
    import shapely

    poly = shapely.Polygon(prof)
    if not poly.is_valid:
        raise GeometryError("sweep: the section polygon intersects itself")
    tris = shapely.get_parts(shapely.constrained_delaunay_triangles(poly))
    coords = shapely.get_coordinates(tris).reshape(-1, 4, 2)[:, :3]
    key = {(float(x), float(y)): i for i, (x, y) in enumerate(prof)}
    try:
        return np.array([[key[(float(x), float(y))] for x, y in t] for t in coords], dtype=np.int32)
    except KeyError:  # pragma: no cover - CDT of a polygon adds no points
        raise GeometryError("sweep: could not triangulate the section") from None


def sweep(
    profile: np.ndarray,
    path: np.ndarray,
    *,
    axis=(0.0, 1.0, 0.0),
    closed: bool = True,
    crease_deg: float = 35.0,
    uv_scale: float = 1.0,
    name: str = "sweep",
) -> Mesh:
    """Sweep a closed section along a planar polyline into one closed, outward mesh.

    Parameters
    ----------
    profile : (k, 2) float
        The section polygon in ``(u, v)``: ``u`` along the side normal, ``v`` along ``axis``
        (either winding; not self-intersecting).
    path : (m, 3) float
        The polyline; all points in one plane perpendicular to ``axis``.
    axis : (3,) float
        The plane normal (the section's ``v`` direction), default +Y.
    closed : True: the path wraps round (``m`` segments) and ``u > 0`` points away from the
        area it encloses; False: an open path of ``m − 1`` segments, ``u`` along
        ``cross(tangent, axis)``, both ends capped.
    crease_deg : section corners sharper than this get crisp normals; gentler ones (curved
        mouldings) are smoothed.
    uv_scale : texture units per metre.

    Returns
    -------
    Mesh
        Points ``(m·k, 3)`` shared by all faces (watertight); ``m_s·k`` quads (+ cap triangles
        for open paths); per-corner normals; ``st = uv_scale · (arc length along the row,
        length along the section)``.
    """
    prof, pts, ax = _check(profile, path, axis, closed)
    if closed:
        pts = _outward_loop(pts, ax)
    k, m = len(prof), len(pts)
    mit = mitre_vectors(side_normals(pts, ax, closed), closed)
    if len(pts) > 2:
        _check_offsets(pts, mit, (float(prof[:, 0].min()), float(prof[:, 0].max())), ax, closed)
    verts = (
        pts[:, None, :]
        + prof[None, :, 0, None] * mit[:, None, :]
        + prof[None, :, 1, None] * ax[None, None, :]
    )  # (m, k, 3)
    points = verts.reshape(-1, 3)
    quads, caps = _faces(prof, points, m, closed)
    normals = _quad_corner_normals(points, quads, crease_deg).reshape(-1, 3)
    st = _side_st(verts, prof, quads, closed)
    counts = [np.full(quads.shape[0] * k, 4, dtype=np.int32)]
    indices = [quads.reshape(-1)]
    if len(caps):
        cap_pts = points[caps]
        cn = _unit(np.cross(cap_pts[:, 1] - cap_pts[:, 0], cap_pts[:, 2] - cap_pts[:, 0]))
        counts.append(np.full(len(caps), 3, dtype=np.int32))
        indices.append(caps.reshape(-1))
        normals = np.vstack([normals, np.repeat(cn, 3, axis=0)])
        # caps: planar projection of the section itself
        st = np.vstack([st, prof[caps.reshape(-1) % k]])
    st = (st * uv_scale).astype(np.float32)
    return Mesh(
        points,
        np.concatenate(counts),
        np.concatenate(indices),
        CornerValues.per_corner(normals.astype(np.float32)),
        CornerValues(st, np.arange(len(st), dtype=np.int32)),
        name=name,
    )


def _outward_loop(pts: np.ndarray, ax: np.ndarray) -> np.ndarray:
    """A closed path ordered so that its side normal points out of the enclosed area."""
    e1 = _unit(pts[1] - pts[0])
    e2 = np.cross(ax, e1)
    loop2 = libm.linear(pts - pts[0], np.stack([e1, e2]))
    return pts[::-1].copy() if polygon_area(loop2) < 0 else pts


def _faces(
    prof: np.ndarray, points: np.ndarray, m: int, closed: bool
) -> tuple[np.ndarray, np.ndarray]:
    """The side quads (nseg, k, 4) and, for an open path, the end caps' triangles, wound so
    that the solid is outward (positive volume)."""
    k = len(prof)
    nseg = m if closed else m - 1
    i = np.arange(nseg)[:, None]
    j = np.arange(k)[None, :]
    i1, j1 = (i + 1) % m, (j + 1) % k
    quads = np.stack(
        np.broadcast_arrays(i * k + j, i1 * k + j, i1 * k + j1, i * k + j1), axis=-1
    )  # (nseg, k, 4)
    caps = np.zeros((0, 3), dtype=np.int64)
    if not closed:
        # the side quads of the first row hold the edges j+1 → j: the start cap runs the
        # section the other way (j → j+1), i.e. with the section polygon's own orientation
        ct = _cap_triangles(prof)
        a, b, c = prof[ct[:, 0]], prof[ct[:, 1]], prof[ct[:, 2]]
        ab, ac = b - a, c - a
        tri_sign = ab[:, 0] * ac[:, 1] - ab[:, 1] * ac[:, 0]
        ct = np.where((tri_sign * polygon_area(prof) > 0)[:, None], ct, ct[:, ::-1])
        caps = np.vstack([ct, ct[:, ::-1] + (m - 1) * k])
    tris = np.concatenate(
        [quads[..., [0, 1, 2]].reshape(-1, 3), quads[..., [0, 2, 3]].reshape(-1, 3), caps]
    )
    if _signed_volume(points, tris) < 0:
        quads = quads[..., ::-1]
        caps = caps[:, ::-1]
    return quads, caps


def _quad_corner_normals(points: np.ndarray, quads: np.ndarray, crease_deg: float) -> np.ndarray:
    """(nseg, k, 4, 3) corner normals of the side quads: flat per quad, smoothed across
    section corners gentler than ``crease_deg``."""
    k = quads.shape[1]
    j = np.arange(k)[None, :]
    q = points[quads]  # (nseg, k, 4, 3)
    qn = _unit(np.cross(q[..., 2, :] - q[..., 0, :], q[..., 3, :] - q[..., 1, :]))
    prev = np.roll(qn, 1, axis=1)  # quad of section edge j − 1 (wraps: the section is closed)
    smooth = np.einsum("ij,ij->i", prev[0], qn[0]) > math.cos(math.radians(crease_deg))
    shared = _unit(prev + qn)  # normal at section vertex j shared by edges j − 1 and j
    # corners of quad (i, j) in quad order: vertices j, j, j + 1, j + 1 of the section — but the
    # order was reversed when the winding flipped, so pick by which section vertex each is
    nstart = np.where(smooth[None, :, None], shared, qn)
    nend = np.where(np.roll(smooth, -1)[None, :, None], np.roll(shared, -1, axis=1), qn)
    at_start = quads % k == j[..., None]
    return np.where(at_start[..., None], nstart[:, :, None, :], nend[:, :, None, :])


def _side_st(verts: np.ndarray, prof: np.ndarray, quads: np.ndarray, closed: bool) -> np.ndarray:
    """(nseg·k·4, 2) st of the side quads' corners: (arc length along the row, length along
    the section), unscaled."""
    k = len(prof)
    i = np.arange(quads.shape[0])[:, None]
    j = np.arange(k)[None, :]
    rows = verts if not closed else np.concatenate([verts, verts[:1]], axis=0)
    seglen = np.linalg.norm(np.diff(rows, axis=0), axis=2)  # (nseg, k)
    arc = np.vstack([np.zeros((1, k)), np.cumsum(seglen, axis=0)])  # (nseg + 1, k)
    plen = np.linalg.norm(np.roll(prof, -1, axis=0) - prof, axis=1)
    vlen = np.concatenate([[0.0], np.cumsum(plen)])  # (k + 1,)
    corner_j = quads % k  # section vertex of each corner
    at_start = corner_j == j[..., None]
    ci = np.where(quads // k == i[..., None], i[..., None], i[..., None] + 1)
    cj_v = np.where(at_start, j[..., None], j[..., None] + 1)
    return np.stack([arc[ci, corner_j], vlen[cj_v]], axis=-1).reshape(-1, 2)
