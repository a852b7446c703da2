"""The immutable :class:`Mesh` value and the operations on it (merge, transform, weld, normals).

Fields map 1:1 to ``UsdGeom.Mesh``: ``points`` → ``points``, ``face_vertex_counts`` →
``faceVertexCounts``, ``face_vertex_indices`` → ``faceVertexIndices``, ``normals`` → ``normals``
(with ``normals_interpolation``) or, with ``normals_indices``, the indexed primvar
``primvars:normals`` (the ``normals`` attribute cannot be indexed; a renderer reads the primvar
first), ``st`` / ``st_indices`` → the indexed primvar ``primvars:st`` (written as it is when
``st_distinct``, else de-duplicated at authoring).
Winding is counter-clockwise seen from outside (USD's default ``orientation = rightHanded``).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Any, Literal

import numpy as np

from ionic_usd.errors import GeometryError
from ionic_usd.geometry import libm

__all__ = [
    "Mesh",
    "merge",
    "transform",
    "weld",
    "face_normals",
    "smooth_normals",
    "triangulate_fan",
    "corner_normals",
    "frozen_array",
    "box_st",
    "chart_labels",
]

Interpolation = Literal["vertex", "faceVarying"]


def frozen_array(a: np.ndarray) -> np.ndarray:
    """A C-contiguous read-only view or copy of ``a`` (the fields of immutable values)."""
    a = np.ascontiguousarray(a)
    a.setflags(write=False)
    return a


_frozen = frozen_array


@dataclass(frozen=True, eq=False)
class Mesh:
    """A polygon mesh.

    Parameters
    ----------
    points : (n, 3) float64
    face_vertex_counts : (f,) int32
    face_vertex_indices : (k,) int32, ``k == face_vertex_counts.sum()``
    normals : (n, 3), (k, 3) or (w, 3) float32 or None
        Unit normals per vertex (``normals_interpolation == "vertex"``) or per face corner
        (``"faceVarying"``, which allows crisp edges on a watertight point set); with
        ``normals_indices`` the distinct values of faceVarying normals.
    st : (u, 2) float32 or None
        Texture coordinates, indexed per face corner by ``st_indices`` (faceVarying, indexed).
    st_indices : (k,) int32 or None
    name : str
        A prim name for authoring.
    normals_indices : (k,) int32 or None
        Indexed faceVarying normals: corner c has normal ``normals[normals_indices[c]]``
        (:meth:`corner_normals` expands them). A crisp-edged solid needs about one value per
        point instead of one per corner: a third of the data to author and store.
    st_distinct : bool
        The producer's promise that ``st`` is already indexed: every value is used by a corner
        and no two values of one chart (triangles joined through shared values) are equal, as
        a generator emits one value per seam-split chart vertex. Authoring then writes
        ``st`` / ``st_indices`` as they are instead of de-duplicating them (a sort of every
        value). Values of different charts may coincide (metric charts overlap until packed);
        they stay apart, which keeps the charts apart for a reader. A broken promise costs
        only a larger file: the expanded ``st[st_indices]`` is authored exactly either way.
        Replacing ``st`` or ``st_indices`` with :meth:`with_` drops the promise unless it is
        given again.
    """

    points: np.ndarray
    face_vertex_counts: np.ndarray
    face_vertex_indices: np.ndarray
    normals: np.ndarray | None = None
    normals_interpolation: Interpolation = "vertex"
    st: np.ndarray | None = None
    st_indices: np.ndarray | None = None
    name: str = "mesh"
    normals_indices: np.ndarray | None = None
    st_distinct: bool = False
    # derived data (the fan triangulation): not an init field, so dataclasses.replace() and
    # with_() always start a fresh cache and can never carry stale triangles over
    _cache: dict = field(default_factory=dict, init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        pts = np.asarray(self.points, dtype=np.float64).reshape(-1, 3)
        counts = np.asarray(self.face_vertex_counts, dtype=np.int32).reshape(-1)
        idx = np.asarray(self.face_vertex_indices, dtype=np.int32).reshape(-1)
        if counts.size and counts.min() < 3:
            raise GeometryError(f"mesh {self.name!r}: faces need at least 3 vertices")
        if int(counts.sum()) != idx.size:
            raise GeometryError(
                f"mesh {self.name!r}: face_vertex_counts sum to {int(counts.sum())} "
                f"but there are {idx.size} face_vertex_indices"
            )
        if idx.size and (idx.min() < 0 or idx.max() >= len(pts)):
            raise GeometryError(f"mesh {self.name!r}: a face vertex index is out of range")
        if not np.all(np.isfinite(pts)):
            raise GeometryError(f"mesh {self.name!r}: points contain non-finite values")
        object.__setattr__(self, "points", _frozen(pts))
        object.__setattr__(self, "face_vertex_counts", _frozen(counts))
        object.__setattr__(self, "face_vertex_indices", _frozen(idx))
        if self.normals_indices is not None:
            if self.normals is None or self.normals_interpolation != "faceVarying":
                raise GeometryError(f"mesh {self.name!r}: normals_indices need faceVarying normals")
            ni = np.asarray(self.normals_indices, dtype=np.int32).reshape(-1)
            nv = len(np.asarray(self.normals).reshape(-1, 3))
            if ni.size != idx.size or (ni.size and (ni.min() < 0 or ni.max() >= nv)):
                raise GeometryError(
                    f"mesh {self.name!r}: normals_indices do not match the faces and normals"
                )
            object.__setattr__(self, "normals_indices", _frozen(ni))
        if self.normals is not None:
            nrm = np.asarray(self.normals, dtype=np.float32).reshape(-1, 3)
            want = len(pts) if self.normals_interpolation == "vertex" else idx.size
            if self.normals_interpolation not in ("vertex", "faceVarying"):
                raise GeometryError(f"unknown normals interpolation {self.normals_interpolation!r}")
            if self.normals_indices is not None:
                want = len(nrm)
            if len(nrm) != want:
                raise GeometryError(
                    f"mesh {self.name!r}: {len(nrm)} normals for "
                    f"{self.normals_interpolation} interpolation, expected {want}"
                )
            object.__setattr__(self, "normals", _frozen(nrm))
        if (self.st is None) != (self.st_indices is None):
            raise GeometryError(f"mesh {self.name!r}: st and st_indices go together")
        if self.st_distinct and self.st is None:
            raise GeometryError(f"mesh {self.name!r}: st_distinct without st")
        object.__setattr__(self, "st_distinct", bool(self.st_distinct))
        if self.st is not None:
            st = np.asarray(self.st, dtype=np.float32).reshape(-1, 2)
            sti = np.asarray(self.st_indices, dtype=np.int32).reshape(-1)
            if sti.size != idx.size or (sti.size and (sti.min() < 0 or sti.max() >= len(st))):
                raise GeometryError(f"mesh {self.name!r}: st_indices do not match the faces")
            object.__setattr__(self, "st", _frozen(st))
            object.__setattr__(self, "st_indices", _frozen(sti))

    # -- derived views -------------------------------------------------------------------
    @property
    def n_points(self) -> int:
        return len(self.points)

    @property
    def n_faces(self) -> int:
        return len(self.face_vertex_counts)

    @property
    def n_triangles(self) -> int:
        """Triangles after fan triangulation of every face."""
        return int((self.face_vertex_counts - 2).sum())

    @property
    def triangles(self) -> np.ndarray:
        """(t, 3) int32 vertex indices of the fan-triangulated faces."""
        if "tri" not in self._cache:
            self._cache["tri"] = triangulate_fan(self.face_vertex_counts, self.face_vertex_indices)
        return self._cache["tri"]

    @property
    def extent(self) -> np.ndarray:
        """(2, 3) float64: min and max corner of the points (cached)."""
        if "extent" not in self._cache:
            if len(self.points) == 0:
                ext = np.zeros((2, 3))
            else:
                # one contiguous column at a time: numpy's min(axis=0) over an (n, 3) array
                # walks it with stride 3 and is ~15x slower (measured 33 ms vs 2 ms at 0.6 M)
                cols = [np.ascontiguousarray(self.points[:, k]) for k in range(3)]
                ext = np.array([[c.min() for c in cols], [c.max() for c in cols]])
            ext.setflags(write=False)
            self._cache["extent"] = ext
        return self._cache["extent"]

    def corner_normals(self) -> np.ndarray | None:
        """(k, 3) float32 normal of every face corner (expanding vertex or indexed normals)."""
        return corner_normals(self)

    def with_(self, **changes) -> Mesh:
        """A copy with some fields replaced (the cache is not carried over).

        New ``st`` or ``st_indices`` drop the ``st_distinct`` promise unless it is given again.
        """
        if "st" in changes or "st_indices" in changes:
            changes.setdefault("st_distinct", False)
        return replace(self, **changes)


def corner_normals(mesh: Mesh) -> np.ndarray | None:
    """(k, 3) float32 normal of every face corner, in ``face_vertex_indices`` order, or None.

    The one place that expands per-vertex and indexed faceVarying normals for consumers that
    need one normal per corner (clipping, booleans, checks, exporters).
    """
    if mesh.normals is None:
        return None
    if mesh.normals_interpolation == "vertex":
        return mesh.normals[mesh.face_vertex_indices]
    if mesh.normals_indices is not None:
        return mesh.normals[mesh.normals_indices]
    return mesh.normals


def triangulate_fan(counts: np.ndarray, indices: np.ndarray) -> np.ndarray:
    """Fan-triangulate polygon faces.

    Parameters
    ----------
    counts : (f,) int
    indices : (k,) int

    Returns
    -------
    (t, 3) int32
    """
    counts = np.asarray(counts, dtype=np.int64)
    indices = np.asarray(indices, dtype=np.int32)
    if counts.size and np.all(counts == 3):
        return indices.reshape(-1, 3)
    starts = np.concatenate([[0], np.cumsum(counts)[:-1]])
    ntri = counts - 2
    face_of_tri = np.repeat(np.arange(len(counts)), ntri)
    k = np.arange(ntri.sum()) - np.repeat(np.cumsum(ntri) - ntri, ntri)
    s = starts[face_of_tri]
    return np.stack([indices[s], indices[s + k + 1], indices[s + k + 2]], axis=1).astype(np.int32)


def face_normals(points: np.ndarray, triangles: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Unit normals and areas of triangles.

    Returns
    -------
    normals : (t, 3) float64 (zero for degenerate triangles)
    areas : (t,) float64
    """
    p = points[triangles]
    cr = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    ln = np.linalg.norm(cr, axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        n = np.where(ln[:, None] > 0, cr / ln[:, None], 0.0)
    return n, 0.5 * ln


# (s, t) axes with s × t = the outward normal -X, +X, -Y, +Y, -Z, +Z (t up on vertical faces)
_BOX_FRAMES = np.array(
    [
        [(0, 0, 1), (0, 1, 0)],
        [(0, 0, -1), (0, 1, 0)],
        [(1, 0, 0), (0, 0, 1)],
        [(1, 0, 0), (0, 0, -1)],
        [(-1, 0, 0), (0, 1, 0)],
        [(1, 0, 0), (0, 1, 0)],
    ],
    dtype=np.float64,
)


def box_st(points: np.ndarray, normals: np.ndarray) -> np.ndarray:
    """Planar texture coordinates (m) by the dominant axis of each normal ("box mapping").

    Exact (isometric) on faces perpendicular to an axis; the (s, t) axes are chosen so that
    s × t is the outward normal, i.e. a chart winds counter-clockwise like its faces seen from
    outside, and t points up on vertical faces.

    Parameters
    ----------
    points : (k, 3) float, the corners
    normals : (k, 3) float, their outward normals (need not be unit)

    Returns
    -------
    (k, 2) float64
    """
    n = np.asarray(normals, dtype=np.float64).reshape(-1, 3)
    axis = np.argmax(np.abs(n), axis=1)
    frame = _BOX_FRAMES[2 * axis + (n[np.arange(len(n)), axis] > 0)]
    p = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    return np.stack(
        [np.einsum("ij,ij->i", p, frame[:, 0]), np.einsum("ij,ij->i", p, frame[:, 1])], axis=1
    )


def smooth_normals(mesh: Mesh, groups: np.ndarray | None = None, *, indexed: bool = False) -> Mesh:
    """Angle-weighted normals, smooth within smoothing groups and crisp between them.

    Parameters
    ----------
    mesh : triangle mesh
    groups : (t,) int or None
        Smoothing group per triangle. ``None`` gives per-vertex normals smooth everywhere;
        otherwise faceVarying normals where a corner averages only the triangles of its own
        group around its vertex (so an edge between two groups is crisp).
    indexed : bool
        With ``groups``: return indexed faceVarying normals (``normals_indices``): the
        n per-vertex values first (a vertex inside one group uses its own), then one value
        per (vertex, group) pair on a crease, numbered by first occurrence.
    """
    if not np.all(mesh.face_vertex_counts == 3):
        raise GeometryError("smooth_normals expects a triangle mesh")
    tri = mesh.triangles
    npts = len(mesh.points)
    unit, angle = _face_units_and_angles(mesh.points, tri)
    corner_vertex = tri.reshape(-1)
    per_vertex = _normalise(
        np.stack(
            [_by_vertex(tri, [unit[:, k] * angle[c] for c in range(3)], npts) for k in range(3)],
            axis=1,
        )
    )
    if groups is None:
        return mesh.with_(
            normals=per_vertex.astype(np.float32),
            normals_interpolation="vertex",
            normals_indices=None,
        )
    groups = np.asarray(groups, dtype=np.int64).reshape(-1)
    if groups.size != len(tri):
        raise GeometryError("smooth_normals: one group per triangle expected")
    multi, crease, inv = _crease_normals(tri, groups, unit, angle, npts)
    if indexed:
        nidx = corner_vertex.astype(np.int64)
        nidx[multi] = npts + inv
        values = np.concatenate([per_vertex, crease]).astype(np.float32)
        return mesh.with_(
            normals=values,
            normals_interpolation="faceVarying",
            normals_indices=nidx.astype(np.int32),
        )
    out = per_vertex.astype(np.float32)[corner_vertex]
    if multi.size:
        out[multi] = crease[inv]
    return mesh.with_(normals=out, normals_interpolation="faceVarying", normals_indices=None)


def _face_units_and_angles(pts: np.ndarray, tri: np.ndarray) -> tuple[np.ndarray, list]:
    """Unit face normals (t, 3) and their weights, the three corner angles (each (t,)): unlike
    area weights, independent of how a flat region is triangulated."""
    p0, p1, p2 = pts[tri[:, 0]], pts[tri[:, 1]], pts[tri[:, 2]]
    e0, e1, e2 = p1 - p0, p2 - p1, p0 - p2
    cr = np.cross(e0, -e2)
    twice_area = np.linalg.norm(cr, axis=1)
    unit = cr / np.where(twice_area > 0, twice_area, 1.0)[:, None]
    dots = (
        -np.einsum("ij,ij->i", e0, e2),
        -np.einsum("ij,ij->i", e1, e0),
        -np.einsum("ij,ij->i", e2, e1),
    )
    return unit, [libm.arctan2(twice_area, d) for d in dots]


def _by_vertex(tri: np.ndarray, weights, npts: int) -> np.ndarray:
    """Per-vertex sums of per-corner weights (three (t,) columns, one bincount each)."""
    return np.sum(
        [np.bincount(tri[:, c], weights=weights[c], minlength=npts) for c in range(3)],
        axis=0,
    )


def _crease_normals(tri, groups, unit, angle, npts):
    """Corners at vertices of several smoothing groups (flat corner indices), a normal per
    (vertex, group) pair there, numbered by first occurrence (the crate writer compresses
    runs of nearby indices), and each such corner's pair number."""
    corner_vertex = tri.reshape(-1)
    # a vertex lies in a single group iff its corners' groups all equal one of them (any one)
    some = np.empty(npts, dtype=np.int64)
    for c in range(3):
        some[tri[:, c]] = groups
    spread = _by_vertex(tri, [np.abs(groups - some[tri[:, c]]) for c in range(3)], npts)
    multi = np.flatnonzero(spread[corner_vertex] != 0)
    if not multi.size:
        return multi, np.zeros((0, 3)), np.zeros(0, dtype=np.int64)
    face = multi // 3
    key = corner_vertex[multi].astype(np.int64) * (int(groups.max()) + 1) + groups[face]
    uniq, first, inv = np.unique(key, return_index=True, return_inverse=True)
    rank = np.empty(len(uniq), dtype=np.int64)
    rank[np.argsort(first, kind="stable")] = np.arange(len(uniq))
    inv = rank[inv.reshape(-1)]
    wcorner = np.stack(angle, axis=1).reshape(-1)[multi]
    acc = np.stack(
        [np.bincount(inv, weights=unit[face, k] * wcorner, minlength=len(uniq)) for k in range(3)],
        axis=1,
    )
    return multi, _normalise(acc), inv


def _normalise(v: np.ndarray) -> np.ndarray:
    ln = np.linalg.norm(v, axis=1, keepdims=True)
    return np.where(ln > 0, v / np.where(ln > 0, ln, 1.0), np.array([0.0, 1.0, 0.0]))


def merge(meshes: list[Mesh] | tuple[Mesh, ...], name: str = "mesh") -> Mesh:
    """Concatenate meshes into one (no welding; see :func:`weld`).

    Normals are kept when every mesh has them: per vertex if all are per vertex, indexed
    faceVarying if any is indexed (a per-vertex or per-corner part indexes its own values),
    else faceVarying. Texture coordinates are kept when every mesh has them.
    """
    meshes = list(meshes)
    if not meshes:
        raise GeometryError("merge needs at least one mesh")
    offsets = np.cumsum([0] + [m.n_points for m in meshes[:-1]])
    points = np.concatenate([m.points for m in meshes])
    counts = np.concatenate([m.face_vertex_counts for m in meshes])
    idx = np.concatenate([m.face_vertex_indices + o for m, o in zip(meshes, offsets, strict=True)])
    normals: np.ndarray | None = None
    nidx: np.ndarray | None = None
    interp: Interpolation = "vertex"
    if all(m.normals is not None for m in meshes):
        if all(m.normals_interpolation == "vertex" for m in meshes):
            normals = np.concatenate([m.normals for m in meshes])
        elif any(m.normals_indices is not None for m in meshes):
            parts = [_indexed_normals(m) for m in meshes]
            no = np.cumsum([0] + [len(v) for v, _ in parts[:-1]])
            normals = np.concatenate([v for v, _ in parts])
            nidx = np.concatenate([i + o for (_, i), o in zip(parts, no, strict=True)])
            interp = "faceVarying"
        else:
            normals = np.concatenate([m.corner_normals() for m in meshes])
            interp = "faceVarying"
    st = sti = None
    sts = [(m.st, m.st_indices) for m in meshes if m.st is not None and m.st_indices is not None]
    if len(sts) == len(meshes):
        so = np.cumsum([0] + [len(v) for v, _ in sts[:-1]])
        st = np.concatenate([v for v, _ in sts])
        sti = np.concatenate([i + o for (_, i), o in zip(sts, so, strict=True)])
    return Mesh(points, counts, idx, normals, interp, st, sti, name=name, normals_indices=nidx)


def _indexed_normals(m: Mesh) -> tuple[np.ndarray, np.ndarray]:
    """(values (w, 3), corner indices (k,)) of a mesh's normals, whatever their layout."""
    assert m.normals is not None
    if m.normals_indices is not None:
        return m.normals, m.normals_indices
    if m.normals_interpolation == "vertex":
        return m.normals, m.face_vertex_indices
    return m.normals, np.arange(len(m.normals), dtype=np.int32)


def transform(mesh: Mesh, matrix: np.ndarray) -> Mesh:
    """Apply a 4×4 affine transform (column-vector convention, ``p' = M @ p``).

    Normals use the inverse transpose; a mirroring transform (negative determinant) reverses
    the winding so faces stay outward.
    """
    m = np.asarray(matrix, dtype=np.float64)
    if m.shape != (4, 4):
        raise GeometryError(f"transform expects a 4x4 matrix, got shape {m.shape}")
    lin, t = m[:3, :3], m[:3, 3]
    pts = libm.linear(mesh.points, lin) + t
    det = np.linalg.det(lin)
    if abs(det) < 1e-15:
        raise GeometryError("transform matrix is singular")
    normals = mesh.normals
    if normals is not None:
        nm = np.linalg.inv(lin).T
        normals = _normalise(libm.linear(normals.astype(np.float64), nm)).astype(np.float32)
    counts, idx, sti = mesh.face_vertex_counts, mesh.face_vertex_indices, mesh.st_indices
    nidx = mesh.normals_indices
    if det < 0:
        perm = _reverse_faces_perm(counts)
        idx = idx[perm]
        if sti is not None:
            sti = sti[perm]
        if nidx is not None:
            nidx = nidx[perm]
        elif normals is not None and mesh.normals_interpolation == "faceVarying":
            normals = normals[perm]
    return mesh.with_(
        points=pts,
        face_vertex_indices=idx,
        normals=normals,
        st_indices=sti,
        normals_indices=nidx,
        st_distinct=mesh.st_distinct,  # a face's corners permuted: the same values, all used
    )


def _reverse_faces_perm(counts: np.ndarray) -> np.ndarray:
    """Corner permutation that reverses every face's vertex order (keeping its first vertex)."""
    counts = counts.astype(np.int64)
    starts = np.repeat(np.cumsum(counts) - counts, counts)
    local = np.arange(counts.sum()) - starts
    n = np.repeat(counts, counts)
    return (starts + np.where(local == 0, 0, n - local)).astype(np.int64)


def weld(mesh: Mesh, tol: float = 1e-9) -> Mesh:
    """Merge points closer than ``tol`` (by rounding to a grid) and drop collapsed faces.

    Normals become faceVarying (corner normals are preserved as they were; indexed ones stay
    indexed).
    """
    q = np.round(mesh.points / tol).astype(np.int64)
    _, first, inv = unique_rows(q, return_index=True, return_inverse=True)
    inv = inv.reshape(-1)
    pts = mesh.points[first]
    idx = inv[mesh.face_vertex_indices]
    normals, nidx = mesh.normals, mesh.normals_indices
    if normals is not None and nidx is None:
        normals = corner_normals(mesh)
    # faces that collapsed (two equal consecutive indices) are dropped: only for triangles
    counts = mesh.face_vertex_counts
    keep_corner = np.ones(idx.size, dtype=bool)
    keep_face = np.ones(len(counts), dtype=bool)
    if np.all(counts == 3):
        t = idx.reshape(-1, 3)
        bad = (t[:, 0] == t[:, 1]) | (t[:, 1] == t[:, 2]) | (t[:, 0] == t[:, 2])
        keep_face = ~bad
        keep_corner = np.repeat(keep_face, 3)
    if nidx is not None:
        nidx = nidx[keep_corner]
    elif normals is not None:
        normals = normals[keep_corner]
    return Mesh(
        pts,
        counts[keep_face],
        idx[keep_corner],
        normals,
        "faceVarying",
        mesh.st,
        None if mesh.st_indices is None else mesh.st_indices[keep_corner],
        name=mesh.name,
        normals_indices=nidx,
    )


def unique_rows(
    a: np.ndarray,
    *,
    return_index: bool = False,
    return_inverse: bool = False,
    return_counts: bool = False,
) -> Any:
    """``np.unique(a, axis=0, ...)`` for a 2-D array of numbers, by one ``lexsort`` of the
    columns (3-8x faster than ``unique(axis=0)``'s sort of rows as structured records).

    Same results, in the same order: the distinct rows in lexicographic order; with
    ``return_index`` the first occurrence of each (the sort is stable), ``return_inverse``
    (``(n,)``) and ``return_counts`` as numpy gives them. Rows holding NaN are each distinct.
    """
    a = np.asarray(a)
    if a.ndim != 2 or len(a) == 0:
        flags: dict[str, Any] = {
            "return_index": return_index,
            "return_inverse": return_inverse,
            "return_counts": return_counts,
        }
        return np.unique(a, axis=0, **flags)
    order = np.lexsort(a.T[::-1])
    srt = a[order]
    new = np.empty(len(srt), dtype=bool)
    new[0] = True
    np.any(srt[1:] != srt[:-1], axis=1, out=new[1:])
    out: list[np.ndarray] = [srt[new]]
    if return_index:
        out.append(order[new])
    if return_inverse:
        inverse = np.empty(len(srt), dtype=np.intp)
        inverse[order] = np.cumsum(new) - 1
        out.append(inverse)
    if return_counts:
        starts = np.flatnonzero(new)
        out.append(np.diff(np.append(starts, len(srt))))
    return out[0] if len(out) == 1 else tuple(out)


def chart_labels(st_indices: np.ndarray, n_values: int) -> np.ndarray:
    """Chart of every triangle: connected components of triangles sharing ``st`` values.

    Parameters
    ----------
    st_indices : (3 t,) int, one per triangle corner
    n_values : number of ``st`` values

    Returns
    -------
    (t,) int64 chart label, 0 .. charts - 1
    """
    from scipy.sparse import csr_matrix
    from scipy.sparse.csgraph import connected_components

    tri = np.asarray(st_indices, dtype=np.int64).reshape(-1, 3)
    rows, cols = tri[:, :2].T.reshape(-1), tri[:, 1:].T.reshape(-1)
    ptr = np.concatenate([[0], np.cumsum(np.bincount(rows, minlength=n_values))])
    # CSR made directly (from COO, scipy's conversions cost ~3x the search)
    graph = csr_matrix((np.ones(len(rows)), cols[np.argsort(rows)], ptr), shape=(n_values,) * 2)
    lab = connected_components(graph, directed=False)[1][tri[:, 0]]  # by smallest value
    return (np.cumsum(np.bincount(lab) > 0) - 1)[lab].astype(np.int64)  # the used ones
