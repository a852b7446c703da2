"""Cut a quadrant out of a closed mesh: the three-quarter column at a corner of two walls.

:func:`cut_quadrant` removes the solid's part in ``{x < x0, z < z0}`` and closes it with two
flat caps, one in each wall plane, without a boolean library. The mesh is split by the plane
``z = z0`` where it reaches ``x ≤ x0`` and then by ``x = x0`` where it reaches ``z ≤ z0``
(each crossing edge gets one new vertex, shared by both its triangles, so the surface stays
closed); the pieces inside the quadrant are dropped; the border left is one bent outline per
hole, a chain in each plane meeting the other on the corner line ``x = x0, z = z0``, and each
plane's chains are closed along that line and filled by a constrained Delaunay triangulation
(:mod:`ionic_usd.geometry.caps`), so both caps share the corner line's vertices.

Corner values travel with every split: normals and ``st`` interpolated along the cut edge,
``st`` identity (which corners share a value) by index, never by value, so two charts that
meet at a point stay apart; each cap outline is a planar (box-mapped, metric) chart.
"""

from __future__ import annotations

import numpy as np

from ionic_usd.errors import GeometryError
from ionic_usd.geometry import libm
from ionic_usd.geometry.caps import cap_loops, chain_loops, plane_frame
from ionic_usd.geometry.mesh import (
    CornerValues,
    Mesh,
    box_st,
    corner_normals,
    triangulate_fan,
    unique_rows,
)

__all__ = ["cut_quadrant"]

_REL_EPS = 1e-9  # as the plane clip: far above float noise, far below any modelled feature


class _Corners:
    """A triangle soup over shared points with per-corner values: points (n, 3), triangles
    (t, 3), values (t, 3, k) (normals, then st) or None, value ids (t, 3) (which corners
    share one st value) or None, and each triangle's side of the z plane (−1, 0 undecided,
    +1)."""

    def __init__(self, points, tri, values, ids, side):
        self.points, self.tri, self.values, self.ids, self.side = points, tri, values, ids, side


def _fan(mask: np.ndarray, edge_first: bool) -> tuple[np.ndarray, np.ndarray]:
    """Triangles over the slots of each row's polygon (``mask`` (m, 6): the slots v0, x01, v1,
    x12, v2, x20 it keeps, 3 or 4): (row, 3 slots) per triangle. ``edge_first``: fan from the
    polygon's edge point (a triangle with one point added on one edge: fanning from a vertex
    would give a triangle with no area)."""
    order = np.argsort(~mask, axis=1, kind="stable")[:, :4]  # kept slots first, in turn
    cnt = mask.sum(axis=1)
    if edge_first:
        p = np.argmax(order % 2 == 1, axis=1)
        order = np.take_along_axis(order, (p[:, None] + np.arange(4)) % 4, axis=1)
    rows = np.arange(len(mask))
    quad = cnt == 4
    tri_rows = np.concatenate([rows, rows[quad]])
    slots = np.concatenate([order[:, [0, 1, 2]], order[quad][:, [0, 2, 3]]])
    return tri_rows, slots


def _split(c: _Corners, axis: int, at: float, near_q: np.ndarray, eps: float, tiny: float):
    """Split the triangles of ``c`` that cross the plane ``points[:, axis] = at`` and reach
    the quadrant (``near_q``: per triangle), and, on the one edge, their neighbours across a
    split edge. Points within ``eps`` of the plane (``tiny`` where they are on no triangle
    reaching the quadrant) are moved onto it first. Returns the new soup and each triangle's
    side of this plane (−1, +1; 0: not separated by it, away from the quadrant)."""
    pts, d, ts, side = _sides(c, axis, at, near_q, eps, tiny)
    tri = c.tri
    n = len(pts)
    nxt = np.roll(tri, -1, axis=1)  # edge k runs from corner k to corner k+1
    crossing = ts * np.roll(ts, -1, axis=1) < 0
    key = np.minimum(tri, nxt) * n + np.maximum(tri, nxt)
    cut_keys = np.unique(key[crossing & near_q[:, None]])
    is_cut = crossing & np.isin(key, cut_keys)
    work = is_cut.any(axis=1)
    if not work.any():
        return _Corners(pts, tri, c.values, c.ids, c.side), side
    elo, ehi = cut_keys // n, cut_keys % n
    t_e = d[elo] / (d[elo] - d[ehi])  # from the lower index: both triangles get one point
    new_pts = pts[elo] + t_e[:, None] * (pts[ehi] - pts[elo])
    new_pts[:, axis] = at
    w_tri, w_cut = tri[work], is_cut[work]
    m = len(w_tri)
    full = w_cut.sum(axis=1) == crossing[work].sum(axis=1)  # pieces on either side
    cand = np.empty((m, 6), dtype=np.int64)
    cand[:, 0::2] = w_tri
    cand[:, 1::2] = np.where(w_cut, n + np.searchsorted(cut_keys, key[work]), -1)
    cands = _slot_values(c, work, w_cut, d, key)
    rows, slots, piece_side = _pieces(ts[work], w_cut, full)
    keep = ~work
    tri2 = np.concatenate([tri[keep], cand[rows[:, None], slots]])
    out: list[np.ndarray | None] = [None, None]
    k = 0
    for j, arr in enumerate((c.values, c.ids)):
        if arr is not None:
            out[j] = np.concatenate([arr[keep], cands[k][rows[:, None], slots]])
            k += 1
    zside = np.concatenate([c.side[keep], c.side[work][rows]])
    side2 = np.concatenate([side[keep], piece_side])
    return _Corners(np.concatenate([pts, new_pts]), tri2, out[0], out[1], zside), side2


def _sides(c: _Corners, axis: int, at: float, near_q: np.ndarray, eps: float, tiny: float):
    """The points snapped onto the plane (within ``eps`` near the quadrant, ``tiny``
    elsewhere), their signed distances, each corner's side (t, 3) and each triangle's side
    (a face in the plane belongs to the side its solid is on)."""
    pts = c.points.copy()
    tri = c.tri
    d = pts[:, axis] - at
    reach = np.zeros(len(pts), dtype=bool)
    reach[tri[near_q].reshape(-1)] = True
    on = np.abs(d) <= np.where(reach, eps, tiny)
    pts[on, axis] = at
    d[on] = 0.0
    ts = np.sign(d).astype(np.int64)[tri]
    pos, neg = (ts > 0).any(axis=1), (ts < 0).any(axis=1)
    side = np.where(pos & ~neg, 1, np.where(neg & ~pos, -1, 0))
    flat = ~pos & ~neg
    if flat.any():
        q = pts[tri[flat]]
        facing = np.cross(q[:, 1] - q[:, 0], q[:, 2] - q[:, 0])[:, axis]
        side[flat] = np.where(facing < 0, 1, -1)
    return pts, d, ts, side


def _slot_values(
    c: _Corners, work: np.ndarray, w_cut: np.ndarray, d: np.ndarray, key: np.ndarray
) -> list[np.ndarray]:
    """Per-slot (v0, x01, v1, x12, v2, x20) corner data of the split triangles: values
    interpolated along each cut edge from its lower-index end (both triangles of an edge get
    the same), and ids, a new one per cut edge and pair of end ids."""
    w_tri = c.tri[work]
    m = len(w_tri)
    lo_first = w_tri < np.roll(w_tri, -1, axis=1)  # the edge's lower-index end is corner k
    cands = []
    if c.values is not None:
        v0 = c.values[work]
        v1 = np.roll(v0, -1, axis=1)
        sd = d[w_tri]
        sd1 = np.roll(sd, -1, axis=1)
        da, db = np.where(lo_first, sd, sd1), np.where(lo_first, sd1, sd)
        va = np.where(lo_first[..., None], v0, v1)
        vb = np.where(lo_first[..., None], v1, v0)
        tt = da / np.where(w_cut, da - db, 1.0)
        cv = np.empty((m, 6, v0.shape[2]))
        cv[:, 0::2], cv[:, 1::2] = v0, va + tt[..., None] * (vb - va)
        cands.append(cv)
    if c.ids is not None:
        i0 = c.ids[work]
        i1 = np.roll(i0, -1, axis=1)
        ia, ib = np.where(lo_first, i0, i1), np.where(lo_first, i1, i0)
        _, fresh = unique_rows(
            np.stack([key[work][w_cut], ia[w_cut], ib[w_cut]], axis=1), return_inverse=True
        )
        new_id = np.full((m, 3), -1, dtype=np.int64)
        new_id[w_cut] = int(c.ids.max(initial=-1)) + 1 + fresh.reshape(-1)
        ci = np.empty((m, 6), dtype=np.int64)
        ci[:, 0::2], ci[:, 1::2] = i0, new_id
        cands.append(ci)
    return cands


def _pieces(w_s: np.ndarray, w_cut: np.ndarray, full: np.ndarray):
    """The split triangles' pieces: (row into them, (3,) slots, side) per new triangle. A
    triangle cut on two edges gives a piece on either side; one cut on one edge (beside a
    split neighbour) gives one polygon of its three corners and the edge point."""
    m = len(w_s)
    polys = []
    for sign in (1, -1):
        mask = np.zeros((m, 6), dtype=bool)
        mask[:, 0::2], mask[:, 1::2] = w_s * sign >= 0, w_cut
        r, sl = _fan(mask[full], edge_first=False)
        polys.append((np.flatnonzero(full)[r], sl, sign))
    part = np.flatnonzero(~full)
    if len(part):
        mask = np.zeros((len(part), 6), dtype=bool)
        mask[:, 0::2], mask[:, 1::2] = True, w_cut[part]
        r, sl = _fan(mask, edge_first=True)
        polys.append((part[r], sl, 0))
    rows = np.concatenate([p[0] for p in polys])
    slots = np.concatenate([p[1] for p in polys])
    piece_side = np.concatenate([np.full(len(p[0]), p[2]) for p in polys])
    return rows, slots, piece_side


def cut_quadrant(
    mesh: Mesh, x0: float, z0: float, *, eps: float | None = None, name: str | None = None
) -> Mesh:
    """``mesh`` (closed, consistently wound) without its part in ``{x < x0, z < z0}``, capped.

    Parameters
    ----------
    mesh : a closed triangle or polygon mesh
    x0, z0 : the wall planes (the quadrant removed lies below both)
    eps : points of the triangles reaching the quadrant closer to a wall plane than this are
        moved onto it first (default ``1e-9 ×`` the bounding-box diagonal); elsewhere ``1e-9
        ×`` the diagonal
    name : of the result (default the input's)

    Returns
    -------
    Mesh : triangles; per-corner normals carried (``+x``/``+z`` against the caps' solid: the
    caps face ``−x`` and ``−z``), the input's ``st`` likewise with planar ``st`` on each cap
    (one chart per cap outline). The input itself when the quadrant holds none of it.

    Raises
    ------
    GeometryError : nothing is left; the cut outline does not close or meets the corner line
        in a way the caps cannot follow (a face or edge along the corner line itself)
    """
    name = mesh.name if name is None else name
    if mesh.n_faces == 0:
        raise GeometryError(f"cut_quadrant: mesh {mesh.name!r} is empty")
    pts = np.asarray(mesh.points, dtype=np.float64)
    diag = max(float(np.linalg.norm(np.ptp(pts, axis=0))), 1e-300)
    tiny = _REL_EPS * diag
    eps = tiny if eps is None else max(float(eps), tiny)
    if not np.any((pts[:, 0] < x0 - tiny) & (pts[:, 2] < z0 - tiny)):
        return mesh if mesh.name == name else mesh.with_(name=name)
    soup = _soup(mesh, pts)
    values, has_normals = soup.values, mesh.normals is not None

    p = soup.points[soup.tri]
    near_z = p[:, :, 0].min(axis=1) <= x0 + eps
    soup, zside = _split(soup, 2, z0, near_z, eps, tiny)
    soup.side = zside
    p = soup.points[soup.tri]
    near_x = p[:, :, 2].min(axis=1) <= z0 + eps
    soup, xside = _split(soup, 0, x0, near_x, eps, tiny)
    inside = (soup.side < 0) & (xside < 0)
    if inside.all():
        raise GeometryError(f"cut_quadrant: nothing of mesh {mesh.name!r} is left")
    kept = soup.tri[~inside]
    P = soup.points
    cap_tri, cap_plane, cap_id = _caps(P, kept, x0, z0, mesh.name)

    return _assemble(soup, inside, cap_tri, cap_plane, cap_id, values, has_normals, name)


def _soup(mesh: Mesh, pts: np.ndarray) -> _Corners:
    """The mesh as a triangle soup with its corner values (normals, then st; zero normals
    when it has st but none) and st ids, every triangle undecided."""
    corner = triangulate_fan(mesh.face_vertex_counts, np.arange(mesh.face_vertex_indices.size))
    corner = corner.reshape(-1, 3).astype(np.int64)
    tri = mesh.face_vertex_indices.astype(np.int64)[corner]
    parts = []
    cn = corner_normals(mesh)
    if cn is not None:
        parts.append(np.asarray(cn, dtype=np.float64)[corner])
    ids = None
    if mesh.st is not None:
        sti = np.asarray(mesh.st.corner_indices(mesh.face_vertex_indices), dtype=np.int64)[corner]
        if cn is None:
            parts.append(np.zeros((len(tri), 3, 3)))
        parts.append(np.asarray(mesh.st.values, dtype=np.float64)[sti])
        ids = sti
    values = np.concatenate(parts, axis=2) if parts else None
    return _Corners(pts, tri, values, ids, np.zeros(len(tri), dtype=np.int64))


def _assemble(soup, inside, cap_tri, cap_plane, cap_id, values, has_normals, name) -> Mesh:
    """The kept triangles and the caps as one mesh: normals carried (unit; the cap's where
    a cut interpolated one to zero), st re-indexed by (point, st id), planar st on the caps."""
    P = soup.points
    faces = np.concatenate([soup.tri[~inside], cap_tri])
    used, remap = np.unique(faces, return_inverse=True)
    nrm = st = st_idx = None
    has_st = soup.ids is not None
    if values is not None:
        plane_n = np.array([[0.0, 0.0, -1.0], [-1.0, 0.0, 0.0]])[cap_plane]
        cap_n = np.repeat(plane_n, 3, axis=0)
        cv = cap_n
        if has_st:
            cv = np.concatenate([cap_n, box_st(P[cap_tri.reshape(-1)], cap_n)], axis=1)
        assert soup.values is not None
        allv = np.concatenate([soup.values[~inside].reshape(-1, values.shape[2]), cv])
        if has_normals:
            nrm = allv[:, :3]
            ln = np.linalg.norm(nrm, axis=1, keepdims=True)
            nrm = np.where(ln > 0, nrm / np.where(ln > 0, ln, 1.0), cap_n[:1]).astype(np.float32)
        if has_st:
            cid = np.concatenate([soup.ids[~inside].reshape(-1), np.repeat(cap_id, 3)])
            key = np.stack([faces.reshape(-1), cid], axis=1)
            _, first, inv = unique_rows(key, return_index=True, return_inverse=True)
            st, st_idx = allv[first, 3:5].astype(np.float32), inv.reshape(-1)
    return Mesh(
        P[used],
        np.full(len(faces), 3, dtype=np.int32),
        remap.reshape(-1).astype(np.int32),
        None if nrm is None else CornerValues.per_corner(nrm),
        None if st is None else CornerValues(st, st_idx),
        name=name,
    )


def _caps(
    P: np.ndarray, kept: np.ndarray, x0: float, z0: float, mesh_name: str
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The caps over the border of ``kept``: (c, 3) triangles, (c,) plane (0: z = z0, 1:
    x = x0) and (c,) st value id (negative, one per cap outline)."""
    directed = np.concatenate([kept[:, [0, 1]], kept[:, [1, 2]], kept[:, [2, 0]]])
    n = len(P)
    und = np.minimum(directed[:, 0], directed[:, 1]) * n + np.maximum(
        directed[:, 0], directed[:, 1]
    )
    _, inv, cnt = np.unique(und, return_inverse=True, return_counts=True)
    border = directed[cnt[inv.reshape(-1)] == 1]
    if not len(border):
        raise GeometryError(f"cut_quadrant: the cut of mesh {mesh_name!r} left no outline")
    on_z = P[:, 2] == z0
    on_x = P[:, 0] == x0
    src, dst = border[:, 1], border[:, 0]  # a cap runs along each border edge the other way
    in_z, in_x = on_z[src] & on_z[dst], on_x[src] & on_x[dst]
    if np.any(in_z & in_x) or not np.all(in_z | in_x):
        raise GeometryError(
            f"cut_quadrant: the cut outline of mesh {mesh_name!r} runs along the corner line "
            "or off the wall planes"
        )
    line = np.flatnonzero(on_z & on_x)
    out_tri, out_plane, out_id = [], [], []
    next_id = -1
    for plane, sel, normal in ((0, in_z, np.array([0.0, 0.0, 1.0])), (1, in_x, np.eye(3)[0])):
        s, t = src[sel], dst[sel]
        ends = np.setdiff1d(t, s)  # on the corner line: a chain ends here, or starts
        starts = np.setdiff1d(s, t)
        on_line = np.union1d(ends, starts)
        if not np.all(np.isin(on_line, line)):
            raise GeometryError(
                f"cut_quadrant: the cut outline of mesh {mesh_name!r} is not closed"
            )
        # along the line (y), the solid's inside runs between consecutive crossings: close
        # each chain end to the chain start across its interval
        order = on_line[np.argsort(P[on_line, 1], kind="stable")]
        if len(order) % 2:
            raise GeometryError(
                f"cut_quadrant: the corner line crosses mesh {mesh_name!r} an odd number of times"
            )
        extra_s, extra_t = [], []
        is_end = np.isin(order, ends)
        for i in range(0, len(order), 2):
            a, b = order[i], order[i + 1]
            if is_end[i] == is_end[i + 1]:
                raise GeometryError(
                    f"cut_quadrant: the cut outline of mesh {mesh_name!r} meets the corner "
                    "line out of turn"
                )
            e, f = (a, b) if is_end[i] else (b, a)
            extra_s.append(e)
            extra_t.append(f)
        s = np.concatenate([s, np.array(extra_s, dtype=np.int64)])
        t = np.concatenate([t, np.array(extra_t, dtype=np.int64)])
        u, w = plane_frame(normal)
        verts = np.unique(np.concatenate([s, t]))
        xy = dict(
            zip(
                verts.tolist(),
                libm.linear(P[verts], np.stack([u, w])),
                strict=True,
            )
        )
        loops = chain_loops(s, t, xy, mesh_name)
        ct, which = cap_loops(P, loops, normal, mesh_name)
        out_tri.append(ct)
        out_plane.append(np.full(len(ct), plane, dtype=np.int64))
        out_id.append(next_id - which)
        next_id -= int(which.max(initial=-1)) + 1
    return np.concatenate(out_tri), np.concatenate(out_plane), np.concatenate(out_id)
