"""Clip a mesh by a plane and cap the cut: engaged (half-)columns are columns cut by a wall.

The clip is vectorised per triangle (Sutherland–Hodgman on every crossing triangle at once);
each cut edge gets one new vertex shared by both its triangles, so a closed input stays
closed. The cap fills the cut outline (several loops, possibly nested) with a constrained
Delaunay triangulation from shapely, which adds no vertices, so cap and clipped surface share
exactly the same boundary vertices.
"""

from __future__ import annotations

import numpy as np

from ionic_usd.errors import GeometryError
from ionic_usd.geometry import libm
from ionic_usd.geometry.caps import cap_outline
from ionic_usd.geometry.mesh import (
    CornerValues,
    Mesh,
    box_st,
    corner_normals,
    triangulate_fan,
    unique_rows,
)

__all__ = ["clip_mesh"]

# snapping tolerance relative to the bounding-box diagonal: far above float noise (a point at
# angle π on a ring has z ≈ 6e-17·r), far below any modelled feature
_REL_EPS = 1e-9


def _unit(v, what: str) -> np.ndarray:
    a = np.asarray(v, dtype=np.float64).reshape(-1)
    if a.shape != (3,) or not np.all(np.isfinite(a)):
        raise GeometryError(f"clip_mesh: {what} must be 3 finite numbers, got {v!r}")
    return a


def clip_mesh(
    mesh: Mesh,
    plane_point,
    plane_normal,
    *,
    cap: bool = True,
    eps: float | None = None,
    name: str | None = None,
) -> Mesh:
    """Keep the part of a mesh on the side of a plane its normal points to.

    Parameters
    ----------
    mesh : Mesh
        Any polygon mesh (faces are fan-triangulated first). For ``cap=True`` it should be
        closed (a union of closed shells), so the cut outline is a set of closed loops.
    plane_point : (3,) float
    plane_normal : (3,) float, non-zero (need not be unit length)
    cap : bool
        Close every cut with flat triangles in the plane facing ``−plane_normal``; a closed,
        consistently wound input then gives a closed, consistently wound output.
    eps : float, optional
        Vertices closer to the plane than this are moved onto it (default
        ``1e-9 × bounding-box diagonal``), so exact-on-plane vertices are robust to noise.
    name : str, optional
        Name of the result (default: the input's name).

    Returns
    -------
    Mesh
        Triangles, per-corner normals when the input has normals (interpolated along cut
        edges, ``−plane_normal`` on the cap); the input's ``st`` likewise, with planar
        (box-mapped, metric) ``st`` on the cap.
        When the plane does not cut the mesh (everything is kept), the input is returned
        unchanged apart from the name.

    Raises
    ------
    GeometryError
        Nothing is left on the kept side; the plane normal is zero; ``cap=True`` but the cut
        outline does not close (the input is not closed) or cannot be triangulated.

    Notes
    -----
    A face lying in the plane is kept when it faces ``−plane_normal`` (the solid behind it is
    on the kept side) and dropped otherwise.
    """
    name = mesh.name if name is None else name
    p0, n = _plane(plane_point, plane_normal)
    pts = mesh.points
    eps = _snap_eps(mesh, eps)
    raw = libm.dot(pts - p0, n)
    near = np.abs(raw) <= eps
    d = np.where(near, 0.0, raw)
    s = np.sign(d).astype(np.int8)
    tri = mesh.triangles.astype(np.int64)
    whole, split = _classify(pts, tri, s, n)
    if whole.all():
        return mesh if mesh.name == name else mesh.with_(name=name)
    if not whole.any() and not split.any():
        raise GeometryError(
            f"clip_mesh: mesh {mesh.name!r} lies entirely behind the plane "
            f"(point {p0.tolist()}, normal {n.tolist()}); nothing is left"
        )
    pts = np.where(near[:, None], pts - raw[:, None] * n, pts)  # snap onto the plane
    corner = triangulate_fan(
        mesh.face_vertex_counts, np.arange(mesh.face_vertex_indices.size)
    ).astype(np.int64)
    fv, sid = _corner_values(mesh, corner)
    cut = _Cut(pts, tri[split], s[tri[split]].astype(np.int64), d, p0, n)
    all_pts = np.concatenate([pts, cut.new_pts])
    faces = [np.concatenate([tri[whole], cut.poly_tri.astype(np.int64)])]
    ids = None if sid is None else [cut.kept_ids(sid, whole, split)]
    values = None if fv is None else [cut.kept_values(fv, corner, whole, split)]
    if cap:
        on_plane = np.concatenate([s == 0, np.ones(len(cut.new_pts), dtype=bool)])
        _add_cap(all_pts, faces, values, ids, on_plane, n, mesh.name)
    return _assemble(all_pts, faces, values, ids, mesh.normals is not None, n, name)


def _snap_eps(mesh: Mesh, eps: float | None) -> float:
    """The snapping tolerance: ``eps``, or 1e-9 × the bounding-box diagonal; refuses no faces."""
    if mesh.n_faces == 0:
        raise GeometryError(f"clip_mesh: mesh {mesh.name!r} is empty, nothing is left")
    if eps is not None:
        return eps
    return _REL_EPS * max(float(np.linalg.norm(np.ptp(mesh.points, axis=0))), 1e-300)


def _plane(plane_point, plane_normal) -> tuple[np.ndarray, np.ndarray]:
    """The plane's point and unit normal, refusing non-finite values and a zero normal."""
    p0 = _unit(plane_point, "plane_point")
    n = _unit(plane_normal, "plane_normal")
    ln = float(np.linalg.norm(n))
    if ln == 0.0:
        raise GeometryError("clip_mesh: plane_normal is zero")
    return p0, n / ln


def _add_cap(
    all_pts: np.ndarray,
    faces: list[np.ndarray],
    values: list[np.ndarray] | None,
    ids: list[np.ndarray] | None,
    on_plane: np.ndarray,
    n: np.ndarray,
    mesh_name: str,
) -> None:
    """Append the cut's cap triangles, and their chart ids and corner values, in place."""
    cap_tri, outline = cap_outline(all_pts, faces[0], on_plane, n, mesh_name)
    if not len(cap_tri):
        return
    faces.append(cap_tri)
    if ids is not None:  # every outline's cap is a chart of its own: ids below -1
        ids.append(np.stack([np.repeat(-2 - outline, 3), np.full(3 * len(outline), -1)], 1))
    if values is not None:
        values.append(_cap_values(all_pts, cap_tri, n, values[0].shape[-1]))


def _classify(
    pts: np.ndarray, tri: np.ndarray, s: np.ndarray, n: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """(triangles kept whole, triangles the plane splits), by the side ``s`` (-1, 0, 1) of
    their corners; a face in the plane bounds kept solid iff it faces away from the kept side."""
    ts = s[tri]
    has_pos = (ts > 0).any(axis=1)
    has_neg = (ts < 0).any(axis=1)
    flat = ~has_pos & ~has_neg
    keep_flat = np.zeros(len(tri), dtype=bool)
    if flat.any():
        fp = pts[tri[flat]]
        keep_flat[flat] = libm.dot(np.cross(fp[:, 1] - fp[:, 0], fp[:, 2] - fp[:, 0]), n) < 0
    return (has_pos & ~has_neg) | keep_flat, has_pos & has_neg


def _corner_values(mesh: Mesh, corner: np.ndarray) -> tuple[np.ndarray | None, np.ndarray | None]:
    """The per-corner values carried through the cut (normals, then st: (c, 3) or (c, 5), or
    None) and which st value each corner is ((triangles, 3) input st indices, or None)."""
    fv = None
    cn0 = corner_normals(mesh)  # None iff the mesh has no normals
    if cn0 is not None:
        fv = cn0.astype(np.float64)
    sid = None
    if mesh.st is not None:
        # st rides along with the normals (3 more columns, interpolated the same way)
        st_ids = mesh.st.corner_indices(mesh.face_vertex_indices)
        cst = mesh.st.values[st_ids].astype(np.float64)
        fv = np.concatenate([fv if fv is not None else np.zeros((len(cst), 3)), cst], axis=1)
        # which st value each corner is: (input st index, -1) for a kept corner, the pair of
        # its edge's end indices for a cut corner; never the value itself, so two charts
        # whose values meet at a shared point (mirrored planar maps on an axis) stay apart
        sid = np.asarray(st_ids, dtype=np.int64)[corner]
    return fv, sid


class _Cut:
    """The crossing triangles ``st_`` (sides ``ss``) split by the plane: one new vertex per
    crossing undirected edge, shared by both its triangles, and each triangle's kept polygon
    (3 or 4 corners, Sutherland–Hodgman order v0, x01, v1, x12, v2, x20) fanned."""

    def __init__(self, pts, st_, ss, d, p0, n) -> None:
        self.ss, self.d, self.st_ = ss, d, st_
        a, b = st_, np.roll(st_, -1, axis=1)  # edge k runs from corner k to corner k+1
        self.cross = cross = ss * np.roll(ss, -1, axis=1) < 0
        lo, hi = np.minimum(a, b)[cross], np.maximum(a, b)[cross]
        ukey, inv = np.unique(lo * len(pts) + hi, return_inverse=True)
        elo, ehi = ukey // len(pts), ukey % len(pts)
        # interpolate from the lower index so both triangles of an edge compute the same point
        t = d[elo] / (d[elo] - d[ehi])
        new_pts = pts[elo] + t[:, None] * (pts[ehi] - pts[elo])
        self.new_pts = new_pts - libm.dot(new_pts - p0, n)[:, None] * n
        edge_vertex = np.full(a.shape, -1, dtype=np.int64)
        edge_vertex[cross] = len(pts) + inv.reshape(-1)
        cand = np.empty((len(st_), 6), dtype=np.int64)
        cand[:, 0::2], cand[:, 1::2] = st_, edge_vertex
        self.mask = mask = np.empty((len(st_), 6), dtype=bool)
        mask[:, 0::2], mask[:, 1::2] = ss >= 0, cross
        self.counts = mask.sum(axis=1)  # 3 or 4: a clipped triangle is a triangle or a quad
        self.poly_tri = triangulate_fan(self.counts, cand[mask])
        self.poly_i = triangulate_fan(self.counts, np.arange(int(self.counts.sum())))

    def kept_ids(self, sid: np.ndarray, whole: np.ndarray, split: np.ndarray) -> np.ndarray:
        """(corners, 2) st identities of the kept triangles' corners, whole ones first."""
        cs, ns = sid[split], np.roll(sid[split], -1, axis=1)
        cand_id = np.empty((len(self.st_), 6, 2), dtype=np.int64)
        cand_id[:, 0::2, 0], cand_id[:, 0::2, 1] = cs, -1
        cand_id[:, 1::2, 0], cand_id[:, 1::2, 1] = np.minimum(cs, ns), np.maximum(cs, ns)
        whole_id = np.stack([sid[whole], np.full(sid[whole].shape, -1)], axis=-1)
        return np.concatenate(
            [whole_id.reshape(-1, 2), cand_id[self.mask][self.poly_i].reshape(-1, 2)]
        )

    def kept_values(
        self, fv: np.ndarray, corner: np.ndarray, whole: np.ndarray, split: np.ndarray
    ) -> np.ndarray:
        """The kept triangles' corner values, cut corners interpolated along their edges."""
        cross, sd = self.cross, self.d[self.st_]
        cn = fv[corner[split]]  # (m, 3 corners, channels)
        w = sd / np.where(cross, sd - np.roll(sd, -1, axis=1), 1.0)  # share of the next corner
        en = cn + w[..., None] * (np.roll(cn, -1, axis=1) - cn)
        cand_n = np.empty((len(self.st_), 6, fv.shape[1]))
        cand_n[:, 0::2], cand_n[:, 1::2] = cn, en
        return np.concatenate([fv[corner[whole]], cand_n[self.mask][self.poly_i]])


def _cap_values(all_pts: np.ndarray, cap_tri: np.ndarray, n: np.ndarray, channels: int):
    """The cap's corner values: -n, and planar (box-mapped, metric) st when carried."""
    cap_v = np.broadcast_to(-n, (3 * len(cap_tri), 3))
    if channels == 5:
        cap_v = np.concatenate([cap_v, box_st(all_pts[cap_tri.reshape(-1)], cap_v)], axis=1)
    return cap_v


def _assemble(all_pts, faces, values, ids, has_normals: bool, n, name) -> Mesh:
    """The result: unused points dropped, st re-indexed by (point, st identity), normals
    unit length (-n where a cut interpolated them to zero)."""
    faces_all = np.concatenate(faces)
    used, remap = np.unique(faces_all, return_inverse=True)
    out_nrm = st = sti = None
    if values is not None:
        channels = values[0].shape[-1]
        out_nrm = np.concatenate([np.reshape(x, (-1, channels)) for x in values])
        if out_nrm.shape[1] == 5 and ids is not None:
            key = np.concatenate([faces_all.reshape(-1, 1), np.concatenate(ids)], axis=1)
            _, first, sti = unique_rows(key, return_index=True, return_inverse=True)
            st, sti = out_nrm[first, 3:], sti.reshape(-1)
            out_nrm = out_nrm[:, :3] if has_normals else None
    if out_nrm is not None:
        ln_ = np.linalg.norm(out_nrm, axis=1, keepdims=True)
        out_nrm = np.where(ln_ > 0, out_nrm / np.where(ln_ > 0, ln_, 1.0), -n)
    return Mesh(
        all_pts[used],
        np.full(len(faces_all), 3, dtype=np.int32),
        remap.reshape(-1).astype(np.int32),
        None if out_nrm is None else CornerValues.per_corner(out_nrm),
        None if st is None else CornerValues(st, sti),
        name=name,
    )
