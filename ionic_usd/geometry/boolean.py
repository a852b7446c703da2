"""Boolean union of closed meshes (manifold3d), keeping the authored normals.

Parts that are modelled as separate solids but overlap (the capital's volutes, canales, echinus,
bolsters and abacus) are joined into one closed, non-self-intersecting shell by manifold3d, a
robust boolean library (exact symbolic perturbation; imported here only). The authored corner
normals travel through the boolean as vertex properties, so smooth surfaces stay smooth and the
new intersection curves are crisp; so do the parts' metric ``st`` charts (with the chart of
every corner, and the charts as manifold3d's face ids, so no re-triangulation mixes two of them):
the united capital keeps its parts' analytic parametrisation, and needs no xatlas unwrap.
"""

from __future__ import annotations

import numpy as np

from ionic_usd.errors import GeometryError
from ionic_usd.geometry.mesh import (
    CornerValues,
    Mesh,
    box_st,
    chart_labels,
    corner_normals,
    face_normals,
    triangulate_fan,
    unique_rows,
)
from ionic_usd.geometry.slivers import (
    SLIVER_ANGLE_DEG,
    SLIVER_TOL,
    normals_with_winding,
    remove_slivers,
)

__all__ = [
    "split_shells",
    "union",
    "difference",
    "differences",
    "new_points",
    "remove_slivers",
    "normals_with_winding",
    "SLIVER_ANGLE_DEG",
    "SLIVER_TOL",
]


def _as_triangles(mesh: Mesh) -> Mesh:
    """Fan-triangulate polygons, carrying per-corner normals corner by corner."""
    if np.all(mesh.face_vertex_counts == 3):
        return mesh
    corners = triangulate_fan(
        mesh.face_vertex_counts, np.arange(len(mesh.face_vertex_indices))
    ).reshape(-1)
    nrm = mesh.normals
    if nrm is not None and not nrm.by_point:
        nrm = CornerValues.per_corner(nrm.at_corners(mesh.face_vertex_indices)[corners])
    return Mesh(
        mesh.points,
        np.full(len(corners) // 3, 3, np.int32),
        mesh.face_vertex_indices[corners],
        nrm,
        name=mesh.name,
    )


def split_shells(mesh: Mesh) -> list[Mesh]:
    """The connected components of a mesh (triangles sharing vertex indices), each with its
    share of the mesh's ``st`` (if any)."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    mesh = _as_triangles(mesh)
    tri = mesh.triangles
    n = mesh.n_points
    rows = np.concatenate([tri[:, 0], tri[:, 1]])
    cols = np.concatenate([tri[:, 1], tri[:, 2]])
    ncomp, lab = connected_components(
        coo_matrix((np.ones(len(rows)), (rows, cols)), shape=(n, n)), directed=False
    )
    face_lab = lab[tri[:, 0]]
    fv = _corner_normals(mesh)
    out = []
    for c in np.unique(face_lab):
        sel = np.flatnonzero(face_lab == c)
        used, local = np.unique(tri[sel], return_inverse=True)
        nrm = None
        if fv is not None:
            nrm = CornerValues.per_corner(fv.reshape(-1, 3, 3)[sel].reshape(-1, 3))
        st = None
        if mesh.st is not None:
            ids = mesh.st.corner_indices(mesh.face_vertex_indices).reshape(-1, 3)[sel]
            st_used, sti = np.unique(ids, return_inverse=True)
            st = CornerValues(mesh.st.values[st_used], sti.reshape(-1))
        out.append(
            Mesh(
                mesh.points[used],
                np.full(len(sel), 3, np.int32),
                local.reshape(-1),
                nrm,
                st,
                name=mesh.name,
            )
        )
    return out


def _corner_normals(mesh: Mesh) -> np.ndarray | None:
    """(3t, 3) float32 normals per triangle corner, or None."""
    if mesh.normals is None:
        return None
    if mesh.normals.by_point:
        return mesh.normals.values[mesh.triangles.reshape(-1)]
    if not np.all(mesh.face_vertex_counts == 3):
        raise GeometryError("union: per-corner normals need a triangle mesh")
    return corner_normals(mesh)


def _to_manifold(
    mesh: Mesh,
    keep_faces: bool = False,
    st: np.ndarray | None = None,
    chart: np.ndarray | None = None,
    faces: np.ndarray | None = None,
):
    """A manifold3d.Manifold with the corner normals as properties 3..5 (and ``st``, per
    corner (3 t, 2), as properties 6..7, with its chart number per corner (3 t,) as 8).

    ``keep_faces``: one face id per triangle, so coplanar neighbours keep their edges (a flat
    top keeps the ring a shaft welds to); otherwise manifold3d merges coplanar triangles into
    faces and re-triangulates those it cuts (which also resolves touching coplanar parts).
    ``faces``: (t,) face ids to use instead (the union's charts: edges between two ids are
    kept, triangles of one id may be merged).
    """
    import manifold3d

    tri = mesh.triangles.astype(np.int64)
    cn = _corner_normals(mesh)
    if cn is None:
        fn, _ = face_normals(mesh.points, tri)
        cn = np.repeat(fn, 3, axis=0)
    corner_pt = tri.reshape(-1)
    q = np.round(cn.astype(np.float64) * 1e6).astype(np.int64)
    key = np.concatenate([corner_pt[:, None], q], axis=1)
    extra = []
    if st is not None and chart is not None:
        extra = [st, np.asarray(chart, dtype=np.float64).reshape(-1, 1)]
        key = np.concatenate([key, np.round(extra[1]).astype(np.int64)], axis=1)
        key = np.concatenate([key, np.round(st * 1e6).astype(np.int64)], axis=1)
    uk, first, inv = unique_rows(key, return_index=True, return_inverse=True)
    inv = inv.reshape(-1)
    pv = uk[:, 0]
    props = np.concatenate(
        [mesh.points[pv], cn[first].astype(np.float64)] + [e[first] for e in extra], axis=1
    )
    # property vertices at one point are merged for topology
    order = np.argsort(pv, kind="stable")
    head = np.r_[True, pv[order][1:] != pv[order][:-1]]
    rep = order[np.maximum.accumulate(np.where(head, np.arange(len(order)), 0))]
    dup = order[~head]
    if keep_faces:
        faces = np.arange(len(tri))
    mm = manifold3d.Mesh64(
        vert_properties=np.ascontiguousarray(props, dtype=np.float64),
        tri_verts=np.ascontiguousarray(inv.reshape(-1, 3), dtype=np.uint64),
        merge_from_vert=np.ascontiguousarray(dup, dtype=np.uint64),
        merge_to_vert=np.ascontiguousarray(rep[~head], dtype=np.uint64),
        face_id=None if faces is None else np.ascontiguousarray(faces, dtype=np.uint64),
    )
    man = manifold3d.Manifold(mm)
    if man.status() != manifold3d.Error.NoError:
        raise GeometryError(
            f"union: mesh {mesh.name!r} is not a closed manifold ({man.status().name})"
        )
    return man


def union(meshes: list[Mesh], name: str = "mesh") -> Mesh:
    """Boolean union of closed meshes; each connected shell of each input is one operand.

    Parameters
    ----------
    meshes : closed, outward-wound triangle meshes (shells may overlap one another)
    name : name of the result

    Returns
    -------
    Mesh : the union's surface, per-corner normals carried from the inputs (interpolated at
        new vertices); when every input has ``st`` (metric charts) so has the union, each
        input chart's visible part a chart of its own (the values carried through the boolean
        like the normals, so a cut through a chart keeps its parametrisation exactly).

    Raises
    ------
    GeometryError : an input shell is not a closed manifold
    """
    import manifold3d

    shells = [s for m in meshes for s in split_shells(m)]
    if all(s.st is not None for s in shells):
        ops = [
            _to_manifold(s, st=st, chart=np.repeat(chart, 3), faces=chart)
            for s, (st, chart) in zip(shells, _union_charts(shells), strict=True)
        ]
    else:
        ops = [_to_manifold(s) for s in shells]
    if not ops:
        raise GeometryError("union needs at least one mesh")
    res = manifold3d.Manifold.batch_boolean(ops, manifold3d.OpType.Add)
    return _from_manifold(res, name)


def _union_charts(shells: list[Mesh]) -> list[tuple[np.ndarray, np.ndarray]]:
    """Per shell: (st per corner (3 t, 2), chart per triangle (t,)) for the union.

    Every chart of every shell gets a number of its own, except the flat faces (a triangle
    whose corner normals are its face normal: caps, box faces): they are charted by their
    plane, st = :func:`_plane_st` of the position, one chart per plane across all shells.
    The charts are manifold3d's face ids, so the union never re-triangulates across two
    charts (which would mix their st), while coplanar flat faces of different parts (the two
    margins meeting on the centre plane, a cap seated in a slab) are one face it may merge.
    """
    planes: dict[tuple[int, ...], int] = {}
    out = []
    offset = 0
    for s in shells:
        assert s.st is not None
        tri = s.triangles
        chart = chart_labels(s.st.corner_indices(s.face_vertex_indices), len(s.st.values))
        chart += offset
        offset = int(chart.max()) + 1
        cst = s.st.at_corners(s.face_vertex_indices).astype(np.float64)
        fn, _ = face_normals(s.points, tri)
        cn = _corner_normals(s)
        if cn is not None:
            cn3 = cn.reshape(-1, 3, 3).astype(np.float64)
            flat = np.all(np.einsum("tkj,tj->tk", cn3, fn) > 1.0 - 1e-9, axis=1)
            if flat.any():
                nq = np.round(fn[flat] * 1e6).astype(np.int64)
                d = np.round(np.einsum("ij,ij->i", fn[flat], s.points[tri[flat, 0]]) * 1e8)
                keys = np.concatenate([nq, d.astype(np.int64)[:, None]], axis=1)
                uk, inv = unique_rows(keys, return_inverse=True)
                ids = np.array([planes.setdefault(tuple(k), len(planes)) for k in uk.tolist()])
                chart[flat] = -1 - ids[inv.reshape(-1)]  # negative: renumbered below
                nrm = uk[:, :3] / 1e6
                nrm /= np.linalg.norm(nrm, axis=1, keepdims=True)
                corner_n = np.repeat(nrm[inv.reshape(-1)], 3, axis=0)
                pts = s.points[tri[flat].reshape(-1)]
                cst.reshape(-1, 3, 2)[flat] = _plane_st(pts, corner_n).reshape(-1, 3, 2)
        out.append((cst, chart))
    # plane charts after the shells' own
    return [(st, np.where(c < 0, offset - 1 - c, c)) for st, c in out]


def _plane_st(points: np.ndarray, normals: np.ndarray) -> np.ndarray:
    """(k, 2) st (m) of points on planes with unit ``normals`` (k, 3): a function of the
    position and the plane only (coplanar faces agree), isometric, s × t = n (counter-
    clockwise seen from outside); t up the plane on steep planes, s along +X on flat ones
    (the frames of :func:`~ionic_usd.geometry.mesh.box_st` on axis planes)."""
    n = np.asarray(normals, dtype=np.float64)
    steep = np.abs(n[:, 1]) < 0.9
    ref = np.where(steep[:, None], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0])
    a = ref - np.einsum("ij,ij->i", ref, n)[:, None] * n
    a /= np.linalg.norm(a, axis=1, keepdims=True)
    s_axis = np.where(steep[:, None], np.cross(a, n), a)
    t_axis = np.where(steep[:, None], a, np.cross(n, a))
    p = np.asarray(points, dtype=np.float64)
    return np.stack([np.einsum("ij,ij->i", p, s_axis), np.einsum("ij,ij->i", p, t_axis)], axis=1)


def difference(
    mesh: Mesh, cutters: list[Mesh], name: str | None = None, *, simplify: bool = False
) -> Mesh:
    """Boolean difference ``mesh − cutters`` (closed meshes), normals carried as in :func:`union`.

    The faces left by a cutter get its normals reversed (they face into the cutter's void).
    The triangulation of faces the cutters do not touch is kept as it was (so a ring another
    part welds to survives).
    """
    (out,) = differences(mesh, [cutters], name, simplify=simplify)
    return out


def differences(
    mesh: Mesh,
    cutter_sets: list[list[Mesh]],
    name: str | None = None,
    *,
    simplify: bool = False,
) -> list[Mesh]:
    """:func:`difference` of ``mesh`` and each set of cutters in turn: ``mesh`` is handed to
    manifold3d once for all of them (the forms of a capital are cuts of one solid)."""
    import manifold3d

    name = mesh.name if name is None else name
    if mesh.st is not None:
        # carry the mesh's own (analytic) st through the cut; the cap faces a cutter leaves
        # get planar st (box-mapped, wound like the caps, which face against the cutter).
        # Every corner carries its chart too (the mesh's charts 0.., each cutter plane's
        # below 0), so charts whose values meet at a point are not joined by the cut
        sti = mesh.st.corner_indices(mesh.face_vertex_indices)
        chart = np.repeat(chart_labels(sti, len(mesh.st.values)), 3)
        cst = mesh.st.values[sti].astype(np.float64)
        base = _to_manifold(mesh, keep_faces=True, st=cst, chart=chart)
    else:
        ops = [_to_manifold(s, keep_faces=True) for s in split_shells(mesh)]
        base = manifold3d.Manifold.batch_boolean(ops, manifold3d.OpType.Add)
    out = []
    for cutters in cutter_sets:
        if mesh.st is not None:
            cut = []
            for k, m in enumerate(map(_as_triangles, cutters)):
                fn, _ = face_normals(m.points, m.triangles)
                cst = box_st(m.points[m.triangles.reshape(-1)], -np.repeat(fn, 3, axis=0))
                axis = np.argmax(np.abs(fn), axis=1)
                plane = 2 * axis + (fn[np.arange(len(fn)), axis] > 0)  # one chart per plane
                ids = -1.0 - 6 * k - np.repeat(plane, 3)
                cut.append(_to_manifold(m, keep_faces=True, st=cst, chart=ids))
        else:
            cut = [_to_manifold(s, keep_faces=True) for m in cutters for s in split_shells(m)]
        res = manifold3d.Manifold.batch_boolean([base, *cut], manifold3d.OpType.Subtract)
        if res.is_empty():
            raise GeometryError(f"difference: nothing of mesh {mesh.name!r} is left")
        # no simplification by default: a cut must not depend on the mesh's size, so two
        # parts cut by the same plane keep the same vertices where they meet (base and shaft)
        out.append(_from_manifold(res, name, simplify=simplify, before=mesh.points))
    return out


def new_points(points: np.ndarray, before: np.ndarray) -> np.ndarray:
    """(n,) bool: the ``points`` (n, 3) that are not, bit for bit, among ``before``."""

    def rows(a: np.ndarray) -> np.ndarray:
        a = np.ascontiguousarray(a, dtype=np.float64) + 0.0  # + 0.0: -0.0 becomes 0.0
        return a.view(np.dtype((np.void, a.dtype.itemsize * 3))).reshape(-1)

    return ~np.isin(rows(points), rows(before))


def _from_manifold(res, name: str, simplify: bool = True, before: np.ndarray | None = None) -> Mesh:
    """A Mesh from a manifold3d result whose properties 3..5 are corner normals.

    ``simplify``: edges shorter than 1e-7 × the bounding box diagonal (slivers where faces
    met almost coplanar) are collapsed first (``Manifold.simplify``), then the remaining
    sliver triangles are flipped or collapsed away within :data:`SLIVER_TOL` × the diagonal
    (:func:`remove_slivers`; manifold3d's simplify keeps needles whose edges run along a
    crease of the authored normals). ``before``: the points of the operand a difference
    cut (its surface already clean): only the slivers round the points the cut made are
    mended.
    """
    diag = 0.0
    if simplify:
        box = np.asarray(res.bounding_box(), dtype=np.float64).reshape(2, 3)
        diag = float(np.linalg.norm(box[1] - box[0]))
        res = res.simplify(1e-7 * diag)
    out = res.to_mesh64()
    props = np.asarray(out.vert_properties, dtype=np.float64)
    tri = np.asarray(out.tri_verts, dtype=np.int64)
    # property vertices → positions: follow the merge vectors
    target = np.arange(len(props))
    mf = np.asarray(out.merge_from_vert, dtype=np.int64)
    mt = np.asarray(out.merge_to_vert, dtype=np.int64)
    target[mf] = mt
    used, pt_index = np.unique(target, return_inverse=True)
    pt_index = pt_index.reshape(-1)
    points = props[used, :3]
    idx = pt_index[tri]
    nrm = props[tri.reshape(-1), 3:6]
    ln = np.linalg.norm(nrm, axis=1, keepdims=True)
    fn, _ = face_normals(points, idx)
    fn3 = np.repeat(fn, 3, axis=0)
    nrm = np.where(ln > 1e-6, nrm / np.where(ln > 1e-6, ln, 1.0), fn3)
    # a subtracted solid's faces come with its outward normals: they now face the other way
    against = np.einsum("ij,ij->i", nrm, fn3) < 0
    nrm[against] = -nrm[against]
    st = sti = None
    if props.shape[1] >= 9:
        # one st value per (point, chart, st): property vertices split by a normal crease
        # only share it, so a chart stays connected across creases (and only within itself)
        q = np.round(props[:, 6:8] * 1e6).astype(np.int64)
        key = np.concatenate([pt_index[:, None], np.round(props[:, 8:9]).astype(np.int64), q], 1)
        _, first, inv = unique_rows(key, return_index=True, return_inverse=True)
        st = props[first, 6:8].astype(np.float32)
        sti = inv.reshape(-1)[tri.reshape(-1)]
    out_mesh = Mesh(
        points,
        np.full(len(idx), 3, np.int32),
        idx.reshape(-1),
        CornerValues.per_corner(nrm.astype(np.float32)),
        None if st is None else CornerValues(st, sti),
        name=name,
    )
    if not simplify:
        return out_mesh
    changed = None if before is None else new_points(points, before)
    return remove_slivers(out_mesh, SLIVER_TOL * diag, changed=changed)
