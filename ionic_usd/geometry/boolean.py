"""Boolean union of closed meshes (manifold3d), keeping the authored normals.

Parts that are modelled as separate solids but overlap (the capital's volutes, canales, echinus,
bolsters and abacus) are joined into one closed, non-self-intersecting shell by manifold3d, a
robust boolean library (exact symbolic perturbation; imported here only). The authored corner
normals travel through the boolean as vertex properties, so smooth surfaces stay smooth and the
new intersection curves are crisp.
"""

from __future__ import annotations

import numpy as np

from ionic_usd.errors import GeometryError
from ionic_usd.geometry.mesh import Mesh, box_st, corner_normals, face_normals, triangulate_fan

__all__ = [
    "split_shells",
    "union",
    "difference",
    "remove_slivers",
    "SLIVER_ANGLE_DEG",
    "SLIVER_TOL",
]


def _as_triangles(mesh: Mesh) -> Mesh:
    """Fan-triangulate polygons, carrying faceVarying normals corner by corner."""
    if np.all(mesh.face_vertex_counts == 3):
        return mesh
    corners = triangulate_fan(
        mesh.face_vertex_counts, np.arange(len(mesh.face_vertex_indices))
    ).reshape(-1)
    nrm, interp = mesh.normals, mesh.normals_interpolation
    cn = corner_normals(mesh) if interp == "faceVarying" else None  # None without normals
    if cn is not None:
        nrm = cn[corners]
    return Mesh(
        mesh.points,
        np.full(len(corners) // 3, 3, np.int32),
        mesh.face_vertex_indices[corners],
        nrm,
        interp,
        name=mesh.name,
    )


def split_shells(mesh: Mesh) -> list[Mesh]:
    """The connected components of a mesh (triangles sharing vertex indices)."""
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
        nrm = None if fv is None else fv.reshape(-1, 3, 3)[sel].reshape(-1, 3)
        out.append(
            Mesh(
                mesh.points[used],
                np.full(len(sel), 3, np.int32),
                local.reshape(-1),
                nrm,
                "faceVarying",
                name=mesh.name,
            )
        )
    return out


def _corner_normals(mesh: Mesh) -> np.ndarray | None:
    """(3t, 3) float32 normals per triangle corner, or None."""
    if mesh.normals is None:
        return None
    if mesh.normals_interpolation == "vertex":
        return mesh.normals[mesh.triangles.reshape(-1)]
    if not np.all(mesh.face_vertex_counts == 3):
        raise GeometryError("union: faceVarying normals need a triangle mesh")
    return corner_normals(mesh)


def _to_manifold(mesh: Mesh, keep_faces: bool = False, st: np.ndarray | None = None):
    """A manifold3d.Manifold with the corner normals as properties 3..5 (and ``st``, per
    corner (3 t, 2), as properties 6..7).

    ``keep_faces``: one face id per triangle, so coplanar neighbours keep their edges (a flat
    top keeps the ring a shaft welds to); otherwise manifold3d merges coplanar triangles into
    faces and re-triangulates those it cuts (which also resolves touching coplanar parts).
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
    if st is not None:
        key = np.concatenate([key, np.round(st * 1e6).astype(np.int64)], axis=1)
    uk, first, inv = np.unique(key, axis=0, return_index=True, return_inverse=True)
    inv = inv.reshape(-1)
    pv = uk[:, 0]
    props = np.concatenate(
        [mesh.points[pv], cn[first].astype(np.float64)] + ([] if st is None else [st[first]]),
        axis=1,
    )
    # property vertices at one point are merged for topology
    order = np.argsort(pv, kind="stable")
    head = np.r_[True, pv[order][1:] != pv[order][:-1]]
    rep = order[np.maximum.accumulate(np.where(head, np.arange(len(order)), 0))]
    dup = order[~head]
    mm = manifold3d.Mesh64(
        vert_properties=np.ascontiguousarray(props, dtype=np.float64),
        tri_verts=np.ascontiguousarray(inv.reshape(-1, 3), dtype=np.uint64),
        merge_from_vert=np.ascontiguousarray(dup, dtype=np.uint64),
        merge_to_vert=np.ascontiguousarray(rep[~head], dtype=np.uint64),
        face_id=np.arange(len(tri), dtype=np.uint64) if keep_faces else None,
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
    Mesh : the union's surface, faceVarying normals carried from the inputs (interpolated at
        new vertices), no texture coordinates.

    Raises
    ------
    GeometryError : an input shell is not a closed manifold
    """
    import manifold3d

    ops = [_to_manifold(s) for m in meshes for s in split_shells(m)]
    if not ops:
        raise GeometryError("union needs at least one mesh")
    res = manifold3d.Manifold.batch_boolean(ops, manifold3d.OpType.Add)
    return _from_manifold(res, name)


def difference(
    mesh: Mesh, cutters: list[Mesh], name: str | None = None, *, simplify: bool = False
) -> Mesh:
    """Boolean difference ``mesh − cutters`` (closed meshes), normals carried as in :func:`union`.

    The faces left by a cutter get its normals reversed (they face into the cutter's void).
    The triangulation of faces the cutters do not touch is kept as it was (so a ring another
    part welds to survives).
    """
    import manifold3d

    if mesh.st is not None:
        # carry the mesh's own (analytic) st through the cut; the cap faces a cutter leaves
        # get planar st (box-mapped, wound like the caps, which face against the cutter)
        ops = [_to_manifold(mesh, keep_faces=True, st=mesh.st[mesh.st_indices].astype(np.float64))]
        cut = []
        for m in map(_as_triangles, cutters):
            fn, _ = face_normals(m.points, m.triangles)
            cst = box_st(m.points[m.triangles.reshape(-1)], -np.repeat(fn, 3, axis=0))
            cut.append(_to_manifold(m, keep_faces=True, st=cst))
        res = manifold3d.Manifold.batch_boolean([*ops, *cut], manifold3d.OpType.Subtract)
        if res.is_empty():
            raise GeometryError(f"difference: nothing of mesh {mesh.name!r} is left")
        return _from_manifold(res, mesh.name if name is None else name, simplify=simplify)
    ops = [_to_manifold(s, keep_faces=True) for s in split_shells(mesh)]
    base = manifold3d.Manifold.batch_boolean(ops, manifold3d.OpType.Add)
    cut = [_to_manifold(s, keep_faces=True) for m in cutters for s in split_shells(m)]
    res = manifold3d.Manifold.batch_boolean([base, *cut], manifold3d.OpType.Subtract)
    if res.is_empty():
        raise GeometryError(f"difference: nothing of mesh {mesh.name!r} is left")
    # no simplification by default: a cut must not depend on the mesh's size, so two parts
    # cut by the same plane keep the same vertices where they meet (base and shaft)
    return _from_manifold(res, mesh.name if name is None else name, simplify=simplify)


def _from_manifold(res, name: str, simplify: bool = True) -> Mesh:
    """A Mesh from a manifold3d result whose properties 3..5 are corner normals.

    ``simplify``: edges shorter than 1e-7 × the bounding box diagonal (slivers where faces
    met almost coplanar) are collapsed first (``Manifold.simplify``), then the remaining
    sliver triangles are flipped or collapsed away within :data:`SLIVER_TOL` × the diagonal
    (:func:`remove_slivers`; manifold3d's simplify keeps needles whose edges run along a
    crease of the authored normals).
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
    if props.shape[1] >= 8:
        # one st value per (point, st) pair: property vertices split by a normal crease only
        # share it, so a chart stays connected across creases
        q = np.round(props[:, 6:8] * 1e6).astype(np.int64)
        key = np.concatenate([pt_index[:, None], q], axis=1)
        _, first, inv = np.unique(key, axis=0, return_index=True, return_inverse=True)
        st = props[first, 6:8].astype(np.float32)
        sti = inv.reshape(-1)[tri.reshape(-1)]
    out_mesh = Mesh(
        points,
        np.full(len(idx), 3, np.int32),
        idx.reshape(-1),
        nrm.astype(np.float32),
        "faceVarying",
        st,
        sti,
        name=name,
    )
    return remove_slivers(out_mesh, SLIVER_TOL * diag) if simplify else out_mesh


# -- sliver clean-up ------------------------------------------------------------------------
#: triangles with an angle under this (degrees) are slivers :func:`remove_slivers` works on
SLIVER_ANGLE_DEG = 1.0
#: how far (× the bounding box diagonal) the sliver clean-up of a boolean result may move its
#: surface: 1.5e-4 m on a capital 1.5 m across
SLIVER_TOL = 1e-4


def _tri_angles(p: np.ndarray) -> np.ndarray:
    """(t, 3, 3) corner points → (t, 3) corner angles in degrees."""
    a = np.roll(p, -1, axis=1) - p
    b = np.roll(p, -2, axis=1) - p
    la, lb = np.linalg.norm(a, axis=2), np.linalg.norm(b, axis=2)
    c = np.einsum("tij,tij->ti", a, b) / np.maximum(la * lb, 1e-300)
    return np.degrees(np.arccos(np.clip(c, -1.0, 1.0)))


def _unit_normals(p: np.ndarray) -> np.ndarray:
    n = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    return n / np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)


def _tet_height(a, b, c, d) -> float:
    """Smallest height of the tetrahedron abcd: how far a flip of edge ab (triangles abc, abd
    → acd, bcd) moves the surface."""
    v = abs(float(np.dot(np.cross(b - a, c - a), d - a)))
    areas = [
        float(np.linalg.norm(np.cross(q - o, r - o)))
        for o, q, r in ((a, b, c), (a, b, d), (a, c, d), (b, c, d))
    ]
    return v / max(max(areas), 1e-300)


def remove_slivers(
    mesh: Mesh, tol: float, *, min_angle: float = SLIVER_ANGLE_DEG, max_passes: int = 8
) -> Mesh:
    """Remove sliver triangles of a closed triangle mesh without moving its surface by more
    than ``tol``.

    Each triangle with an angle under ``min_angle`` is mended, the worst first, by the first
    of these that is allowed: an **edge flip** of its longest edge (a cap: the opposite vertex
    lies near that edge), if the flip moves the surface by at most ``tol`` (the tetrahedron of
    the four vertices is that flat), raises the pair's smallest angle and turns no triangle
    over; an **edge collapse** of its shortest edge (a needle) if that edge is shorter than
    ``tol``, the two end points share exactly two neighbours (the link condition: the shell
    stays a closed 2-manifold) and no triangle round it turns over or becomes a new sliver.
    Slivers neither can mend within ``tol`` are left (they are real, thin features).

    Parameters
    ----------
    mesh : closed, consistently wound triangle mesh with faceVarying normals (or none)
    tol : largest allowed movement of the surface (m)
    min_angle : degrees

    Returns
    -------
    Mesh with the same name; unused points removed.
    """
    tri = mesh.triangles.astype(np.int64).copy()
    pts = np.array(mesh.points, dtype=np.float64)
    # per-corner attributes carried through every edit: the normals (3) and st (2)
    parts = []
    corner_n = corner_normals(mesh)
    if corner_n is not None:
        parts.append(np.asarray(corner_n, dtype=np.float64).reshape(-1, 3, 3))
    if mesh.st is not None and mesh.st_indices is not None:
        parts.append(np.asarray(mesh.st, dtype=np.float64)[mesh.st_indices].reshape(-1, 3, 2))
    cn: np.ndarray | None = np.concatenate(parts, axis=2) if parts else None
    n_dim = 3 if corner_n is not None else 0
    alive = np.ones(len(tri), dtype=bool)

    inc: dict[int, set[int]] = {}  # vertex → the live triangles using it
    for f, row in enumerate(tri.tolist()):
        for v in row:
            inc.setdefault(v, set()).add(f)

    def faces_with(*vs: int) -> np.ndarray:
        common = set.intersection(*(inc.get(int(v), set()) for v in vs))
        return np.array(sorted(common), dtype=np.int64)

    def set_tri(f: int, new) -> None:
        if f < len(tri):
            for v in tri[f].tolist():
                inc[v].discard(f)
        for v in np.asarray(new).tolist():
            inc.setdefault(v, set()).add(f)

    def kill(f: int) -> None:
        for v in tri[f].tolist():
            inc[v].discard(f)
        alive[f] = False

    def try_flip(t: int, k: int) -> bool:
        """Flip the edge opposite corner k of triangle t."""
        c = tri[t, k]
        a, b = tri[t, (k + 1) % 3], tri[t, (k + 2) % 3]
        other = [f for f in faces_with(a, b) if f != t]
        if len(other) != 1:
            return False
        o = other[0]
        d = int(tri[o][~np.isin(tri[o], (a, b))][0])
        if len(faces_with(c, d)):
            return False  # the new edge exists already
        if _tet_height(pts[a], pts[b], pts[c], pts[d]) > tol:
            return False
        new = np.array([[c, a, d], [d, b, c]])
        old = pts[tri[[t, o]]]
        ref = np.cross(old[:, 1] - old[:, 0], old[:, 2] - old[:, 0]).sum(axis=0)  # vector area
        new_n = _unit_normals(pts[new])
        if np.any(new_n @ ref <= 0) or new_n[0] @ new_n[1] <= 0:
            return False
        before = _tri_angles(pts[tri[[t, o]]]).min()
        if _tri_angles(pts[new]).min() <= before:
            return False
        if cn is not None:
            cnl = cn

            def corner(f: int, v: int) -> np.ndarray:
                return cnl[f][int(np.flatnonzero(tri[f] == v)[0])]

            n_new = np.array(
                [
                    [corner(t, c), corner(t, a), corner(o, d)],
                    [corner(o, d), corner(o, b), corner(t, c)],
                ]
            )
            cn[t], cn[o] = n_new
        set_tri(t, new[0])
        set_tri(o, new[1])
        tri[t], tri[o] = new
        return True

    def try_snap(t: int, k: int) -> bool:
        """Move the vertex at corner k of a cap t onto its opposite edge (at most ``tol``) and
        split the neighbour across that edge there; t vanishes."""
        nonlocal tri, cn, alive
        c = int(tri[t, k])
        a, b = int(tri[t, (k + 1) % 3]), int(tri[t, (k + 2) % 3])
        other = [f for f in faces_with(a, b) if f != t]
        if len(other) != 1:
            return False
        o = other[0]
        d = int(tri[o][~np.isin(tri[o], (a, b))][0])
        ab = pts[b] - pts[a]
        u = float(np.clip(np.dot(pts[c] - pts[a], ab) / max(float(ab @ ab), 1e-300), 0.0, 1.0))
        foot = pts[a] + u * ab
        if np.linalg.norm(foot - pts[c]) > tol or len(faces_with(c, d)):
            return False
        around = np.array([f for f in faces_with(c) if f != t])
        moved = pts.copy()
        moved[c] = foot
        n_old = _unit_normals(pts[tri[around]])
        n_new = _unit_normals(moved[tri[around]])
        if np.any(np.einsum("ij,ij->i", n_old, n_new) < 0.5):
            return False
        halves = np.array([[b, c, d], [c, a, d]])
        before = min(_tri_angles(pts[tri[around]]).min(), _tri_angles(pts[tri[[t, o]]]).min())
        after = min(_tri_angles(moved[tri[around]]).min(), _tri_angles(moved[halves]).min())
        if after <= before:
            return False
        pts[c] = foot
        if cn is not None:
            n_a, n_b, n_d = (cn[o][int(np.flatnonzero(tri[o] == v)[0])] for v in (a, b, d))
            nf = (1 - u) * n_a + u * n_b
            if n_dim:
                nf[:n_dim] /= max(float(np.linalg.norm(nf[:n_dim])), 1e-12)
            cn[o] = [n_b, nf, n_d]
            cn = np.concatenate([cn, [[nf, n_a, n_d]]])
        set_tri(o, halves[0])
        tri[o] = halves[0]
        set_tri(len(tri), halves[1])
        tri = np.vstack([tri, halves[1:]])
        alive = np.concatenate([alive, [True]])
        kill(t)
        return True

    def try_collapse(t: int, k: int) -> bool:
        """Collapse the edge opposite corner k of triangle t (one end onto the other)."""
        a, b = int(tri[t, (k + 1) % 3]), int(tri[t, (k + 2) % 3])
        if np.linalg.norm(pts[a] - pts[b]) > tol:
            return False
        shared = faces_with(a, b)
        if len(shared) != 2:
            return False
        ring_a = set(tri[faces_with(a)].ravel().tolist()) - {a}
        ring_b = set(tri[faces_with(b)].ravel().tolist()) - {b}
        opp = {int(v) for f in shared for v in tri[f] if v not in (a, b)}
        if ring_a & ring_b != opp:
            return False  # the link condition: a pinch or a fold would follow
        for keep, drop in ((a, b), (b, a)):
            moved = np.array([f for f in faces_with(drop) if f not in shared])
            new = tri[moved].copy()
            new[new == drop] = keep
            n_old = _unit_normals(pts[tri[moved]])
            n_new = _unit_normals(pts[new])
            if np.any(np.einsum("ij,ij->i", n_old, n_new) < 0.5):
                continue
            if _tri_angles(pts[new]).min() < min(min_angle, _tri_angles(pts[tri[moved]]).min()):
                continue
            for f, row in zip(moved.tolist(), new, strict=True):
                set_tri(f, row)
            tri[moved] = new
            for f in shared.tolist():
                kill(f)
            return True
        return False

    touched: set[int] | None = None  # vertices near a change in the last pass (None: all)
    for _ in range(max_passes):
        worst = _tri_angles(pts[tri]).min(axis=1)
        bad = np.flatnonzero(alive & (worst < min_angle))
        if touched is not None:  # a sliver nothing changed around failed before: skip it
            near = np.isin(tri[bad], np.fromiter(touched, np.int64, len(touched))).any(axis=1)
            bad = bad[near]
        if not len(bad):
            break
        touched = set()
        for t in bad[np.argsort(worst[bad])]:
            if not alive[t]:
                continue
            a = _tri_angles(pts[tri[t]][None])[0]
            if a.min() >= min_angle:
                continue
            ring = tri[t].tolist()
            if (
                try_flip(t, int(np.argmax(a)))
                or try_snap(t, int(np.argmax(a)))
                or try_collapse(t, int(np.argmin(a)))
            ):
                for v in ring:
                    for f in inc.get(v, ()):
                        touched.update(tri[f].tolist())
        if not touched:
            break
    tri = tri[alive]
    used, idx = np.unique(tri, return_inverse=True)
    corners = None if cn is None else cn[alive].reshape(-1, cn.shape[2])
    nrm = None if corners is None or not n_dim else corners[:, :3].astype(np.float32)
    st = sti = None
    if corners is not None and corners.shape[1] > n_dim:
        # re-index st per corner (equal values shared, first occurrence first)
        q = np.round(corners[:, n_dim:] * 1e7).astype(np.int64)
        _, first, inv = np.unique(q, axis=0, return_index=True, return_inverse=True)
        order = np.argsort(first)
        rank = np.empty_like(order)
        rank[order] = np.arange(len(order))
        st = corners[first[order], n_dim:].astype(np.float32)
        sti = rank[inv.reshape(-1)].astype(np.int32)
    return Mesh(
        pts[used],
        np.full(len(tri), 3, np.int32),
        idx.reshape(-1),
        nrm,
        "faceVarying",
        st,
        sti,
        name=mesh.name,
    )
