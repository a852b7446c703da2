"""The immutable :class:`Mesh` value and the operations on it (merge, transform, weld, normals).

A mesh is geometry and per-corner values: ``points``, faces (``face_vertex_counts``,
``face_vertex_indices``, the names ``UsdGeom.Mesh`` uses) and two optional attributes,
``normals`` and ``st``, each a :class:`~ionic_usd.geometry.corners.CornerValues` (values per
point, or values with an index per corner). Every operation here treats both alike. How they
are encoded in a file is chosen when writing, not here: :mod:`ionic_usd.usd.mesh` writes
point normals as the ``normals`` attribute (vertex interpolation) and other normals and all
st as indexed faceVarying primvars (``primvars:normals``, ``primvars:st``; de-duplicated
unless ``st.distinct`` promises they need not be); :mod:`ionic_usd.pipeline.mesh_cache`
stores them in a layout of its own.
Winding is counter-clockwise seen from outside (USD's default ``orientation = rightHanded``).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from ionic_usd.errors import GeometryError
from ionic_usd.geometry import libm
from ionic_usd.geometry.corners import CornerValues, concat_corner_values

__all__ = [
    "CornerValues",
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
    normals : CornerValues (d = 3) or None
        Unit normals per point (shared by the corners there: smooth) or per corner (which
        allows crisp edges on a watertight point set; indexed, a crisp-edged solid needs
        about one value per point instead of one per corner).
    st : CornerValues (d = 2) or None
        Texture coordinates, usually per corner (seams split charts); ``st.distinct`` is the
        generator's promise that they need no de-duplication.
    name : str
        A prim name for authoring.
    """

    points: np.ndarray
    face_vertex_counts: np.ndarray
    face_vertex_indices: np.ndarray
    normals: CornerValues | None = None
    st: CornerValues | None = None
    name: str = "mesh"
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
        for what in ("normals", "st"):
            cv = getattr(self, what)
            if cv is None:
                continue
            if not isinstance(cv, CornerValues) or cv.dim != (3 if what == "normals" else 2):
                raise GeometryError(f"mesh {self.name!r}: {what} must be CornerValues")
            cv.check(len(pts), idx.size, what, self.name)

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
        """A copy with some fields replaced (the cache is not carried over)."""
        return replace(self, **changes)


def corner_normals(mesh: Mesh) -> np.ndarray | None:
    """(k, 3) float32 normal of every face corner, in ``face_vertex_indices`` order, or None.

    The one place that expands normals for consumers that need one normal per corner
    (clipping, booleans, checks, exporters).
    """
    if mesh.normals is None:
        return None
    return mesh.normals.at_corners(mesh.face_vertex_indices)


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
        otherwise per-corner normals where a corner averages only the triangles of its own
        group around its vertex (so an edge between two groups is crisp).
    indexed : bool
        With ``groups``: return indexed normals (``normals.indices``): the
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
        return mesh.with_(normals=CornerValues(per_vertex.astype(np.float32)))
    groups = np.asarray(groups, dtype=np.int64).reshape(-1)
    if groups.size != len(tri):
        raise GeometryError("smooth_normals: one group per triangle expected")
    multi, crease, inv = _crease_normals(tri, groups, unit, angle, npts)
    if indexed:
        nidx = corner_vertex.astype(np.int64)
        nidx[multi] = npts + inv
        values = np.concatenate([per_vertex, crease]).astype(np.float32)
        return mesh.with_(normals=CornerValues(values, nidx.astype(np.int32)))
    out = per_vertex.astype(np.float32)[corner_vertex]
    if multi.size:
        out[multi] = crease[inv]
    return mesh.with_(normals=CornerValues.per_corner(out))


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

    Normals (and st) are kept when every mesh has them (see
    :func:`~ionic_usd.geometry.corners.concat_corner_values`).
    """
    meshes = list(meshes)
    if not meshes:
        raise GeometryError("merge needs at least one mesh")
    offsets = np.cumsum([0] + [m.n_points for m in meshes[:-1]])
    points = np.concatenate([m.points for m in meshes])
    counts = np.concatenate([m.face_vertex_counts for m in meshes])
    idx = np.concatenate([m.face_vertex_indices + o for m, o in zip(meshes, offsets, strict=True)])
    fvis = [m.face_vertex_indices for m in meshes]
    attrs: dict[str, CornerValues | None] = {}
    for what in ("normals", "st"):
        parts = [getattr(m, what) for m in meshes]
        kept = [p for p in parts if p is not None]
        attrs[what] = concat_corner_values(kept, fvis) if len(kept) == len(parts) else None
    return Mesh(points, counts, idx, attrs["normals"], attrs["st"], name=name)


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
        v = _normalise(libm.linear(normals.values.astype(np.float64), nm)).astype(np.float32)
        normals = normals.with_values(v)
    idx, st = mesh.face_vertex_indices, mesh.st
    if det < 0:
        perm = _reverse_faces_perm(mesh.face_vertex_counts)
        idx = idx[perm]
        normals = None if normals is None else normals.reorder(perm)
        st = None if st is None else st.reorder(perm)
    return mesh.with_(points=pts, face_vertex_indices=idx, normals=normals, st=st)


def _reverse_faces_perm(counts: np.ndarray) -> np.ndarray:
    """Corner permutation that reverses every face's vertex order (keeping its first vertex)."""
    counts = counts.astype(np.int64)
    starts = np.repeat(np.cumsum(counts) - counts, counts)
    local = np.arange(counts.sum()) - starts
    n = np.repeat(counts, counts)
    return (starts + np.where(local == 0, 0, n - local)).astype(np.int64)


def weld(mesh: Mesh, tol: float = 1e-9) -> Mesh:
    """Merge points closer than ``tol`` (by rounding to a grid) and drop collapsed faces.

    Point normals become per corner (the corner values are preserved as they were; indexed
    ones stay indexed).
    """
    q = np.round(mesh.points / tol).astype(np.int64)
    _, first, inv = unique_rows(q, return_index=True, return_inverse=True)
    inv = inv.reshape(-1)
    pts = mesh.points[first]
    idx = inv[mesh.face_vertex_indices]
    # faces that collapsed (two equal consecutive indices) are dropped: only for triangles
    counts = mesh.face_vertex_counts
    keep_corner = np.arange(idx.size)
    keep_face = np.ones(len(counts), dtype=bool)
    if np.all(counts == 3):
        t = idx.reshape(-1, 3)
        bad = (t[:, 0] == t[:, 1]) | (t[:, 1] == t[:, 2]) | (t[:, 0] == t[:, 2])
        keep_face = ~bad
        keep_corner = np.flatnonzero(np.repeat(keep_face, 3))
    fvi = mesh.face_vertex_indices
    nrm, st = (None if a is None else a.take(keep_corner, fvi) for a in (mesh.normals, mesh.st))
    return Mesh(pts, counts[keep_face], idx[keep_corner], nrm, st, name=mesh.name)


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
