"""Small solids the capital is assembled from: an axis-aligned box, a lathe (a profile revolved
about +Y with analytic normals) and orthogonal placements (rotations, mirrors) that keep the
winding outward. Frame: metres, Y up.

Each solid carries its own metric texture charts (``st`` in metres of surface, see
:mod:`ionic_usd.column.charts`): the box one exact planar chart per face, the lathe the
revolved charts of :func:`~ionic_usd.column.charts.revolved_st`. A placement carries them
along (a mirror flips ``s``, so every chart still winds counter-clockwise like its faces seen
from outside), and the capital's union keeps them (:func:`ionic_usd.geometry.boolean.union`):
the capital needs no xatlas unwrap.
"""

from __future__ import annotations

import math

import numpy as np

from ionic_usd.column.charts import revolved_st
from ionic_usd.geometry import libm
from ionic_usd.geometry.mesh import CornerValues, Mesh, box_st, smooth_normals

__all__ = ["box_mesh", "lathe", "rigid", "rot_y", "MIRROR_X", "MIRROR_Z", "SWAP_XZ"]


def box_mesh(lo, hi, name: str) -> Mesh:
    """Axis-aligned box, outward-wound, crisp per-corner normals, one exact planar ``st``
    chart per face (:func:`~ionic_usd.geometry.mesh.box_st`)."""
    (x0, y0, z0), (x1, y1, z1) = lo, hi
    pts = np.array(
        [
            [x0, y0, z0],
            [x1, y0, z0],
            [x1, y1, z0],
            [x0, y1, z0],
            [x0, y0, z1],
            [x1, y0, z1],
            [x1, y1, z1],
            [x0, y1, z1],
        ]
    )
    quads = np.array(
        [[0, 3, 2, 1], [4, 5, 6, 7], [0, 1, 5, 4], [3, 7, 6, 2], [0, 4, 7, 3], [1, 2, 6, 5]]
    )
    tri = np.concatenate([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]])
    groups = np.tile(np.arange(6), 2)
    m = Mesh(pts, np.full(12, 3, np.int32), tri.reshape(-1), name=name)
    # four st values per face, in its quad's corner order
    face_n = np.array([[0, 0, -1], [0, 0, 1], [0, -1, 0], [0, 1, 0], [-1, 0, 0], [1, 0, 0]])
    st = box_st(pts[quads.reshape(-1)], np.repeat(face_n, 4, axis=0))
    local = np.concatenate([np.tile([0, 1, 2], (6, 1)), np.tile([0, 2, 3], (6, 1))])
    sti = (4 * groups[:, None] + local).reshape(-1)
    return smooth_normals(m, groups).with_(st=CornerValues(st.astype(np.float32), sti))


def lathe(profile: np.ndarray, segments: int, name: str, crease_deg: float = 40.0) -> Mesh:
    """Revolve a (radius, height) half-profile about +Y, vectorised, with analytic normals.

    Same vertex rings and triangle orientation as :func:`ionic_usd.geometry.curves.revolve`
    (nodes on the axis become single vertices), but the whole grid is built at once and the
    normals come from the profile: smooth across profile nodes turning less than
    ``crease_deg``, crisp at sharper ones. The ``st`` charts are
    :func:`~ionic_usd.column.charts.revolved_st`'s (flat bands planar, steep ones unrolled).
    """
    prof = np.asarray(profile, dtype=np.float64)
    s = int(segments)
    on_axis = prof[:, 0] <= 1e-12
    sizes = np.where(on_axis, 1, s)
    first = np.concatenate([[0], np.cumsum(sizes)[:-1]])
    ang = np.arange(s) * (2 * np.pi / s)
    cos, sin = np.cos(ang), np.sin(ang)
    pts: list[np.ndarray] = []
    for (r, y), ax in zip(prof, on_axis, strict=True):
        if ax:
            pts.append(np.array([[0.0, y, 0.0]]))
        else:
            pts.append(np.stack([r * cos, np.full(s, y), -r * sin], axis=1))
    points = np.concatenate(pts)
    seg_len, n_start, n_end = _profile_normals(prof, crease_deg)
    live = (seg_len > 0) & ~(on_axis[:-1] & on_axis[1:])
    tri, normals, band = _lathe_triangles(s, first, on_axis, live, n_start, n_end)
    rows = [first[k] + np.arange(sizes[k]) for k in range(len(prof))]
    st, sti = revolved_st(prof, rows, points, tri, band)
    return Mesh(
        points,
        np.full(len(tri), 3, np.int32),
        tri.reshape(-1),
        CornerValues.per_corner(normals),
        CornerValues(st, sti),
        name=name,
    )


def _profile_normals(
    prof: np.ndarray, crease_deg: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per profile segment: its length and its 2-D outward normal at its start and end
    (averaged with the neighbour's across nodes turning less than ``crease_deg``)."""
    d = np.diff(prof, axis=0)
    seg_len = np.linalg.norm(d, axis=1)
    en = np.stack([d[:, 1], -d[:, 0]], axis=1) / np.where(seg_len > 0, seg_len, 1.0)[:, None]
    cos_turn = np.einsum("ij,ij->i", en[:-1], en[1:])
    smooth = np.concatenate([[False], cos_turn > math.cos(math.radians(crease_deg)), [False]])
    avg = en[:-1] + en[1:]
    avg = avg / np.maximum(np.linalg.norm(avg, axis=1, keepdims=True), 1e-300)
    n_start = en.copy()
    n_end = en.copy()
    n_start[1:][smooth[1:-1]] = avg[smooth[1:-1]]
    n_end[:-1][smooth[1:-1]] = avg[smooth[1:-1]]
    return seg_len, n_start, n_end


def _nvec(n2: np.ndarray, c: np.ndarray, sn: np.ndarray) -> np.ndarray:
    """(..., 2) profile normals × (s,) angles → (..., s, 3) normals."""
    n2 = np.asarray(n2)[..., None, :]
    return np.stack([n2[..., 0] * c, n2[..., 1] * np.ones_like(c), -n2[..., 0] * sn], axis=-1)


def _lathe_triangles(
    s: int,
    first: np.ndarray,
    on_axis: np.ndarray,
    live: np.ndarray,
    n_start: np.ndarray,
    n_end: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The revolved triangles (t, 3), their corner normals (3 t, 3) and each triangle's
    profile segment: ring-to-ring bands all at once, then cap fans and cone tips."""
    ang = np.arange(s) * (2 * np.pi / s)
    cos, sin = np.cos(ang), np.sin(ang)
    j = np.arange(s)
    j1 = (j + 1) % s
    mid = ang + np.pi / s  # the angle used for corners on the axis
    cmid, smid = np.cos(mid), np.sin(mid)
    grid = np.flatnonzero(live & ~on_axis[:-1] & ~on_axis[1:])
    tris, corner_n, band = [], [], []
    if grid.size:  # ring-to-ring bands, all at once
        a0, b0 = first[grid][:, None], first[grid + 1][:, None]
        na, nb = n_start[grid], n_end[grid]
        t1 = np.stack([a0 + j, b0 + j1, b0 + j], axis=-1)
        t2 = np.stack([a0 + j, a0 + j1, b0 + j1], axis=-1)
        na_j, na_j1 = _nvec(na, cos, sin), _nvec(na, cos[j1], sin[j1])
        nb_j, nb_j1 = _nvec(nb, cos, sin), _nvec(nb, cos[j1], sin[j1])
        tris += [t1.reshape(-1, 3), t2.reshape(-1, 3)]
        band += [np.repeat(grid, s)] * 2
        corner_n += [
            np.stack([na_j, nb_j1, nb_j], axis=-2).reshape(-1, 3, 3),
            np.stack([na_j, na_j1, nb_j1], axis=-2).reshape(-1, 3, 3),
        ]
    for k in np.flatnonzero(live & (on_axis[:-1] | on_axis[1:])):  # cap fans and cone tips
        a0, b0 = first[k], first[k + 1]
        na, nb = n_start[k], n_end[k]
        band.append(np.full(s, k))
        if on_axis[k]:
            tris.append(np.stack([np.full(s, a0), b0 + j1, b0 + j], axis=1))
            corner_n.append(
                np.stack(
                    [_nvec(na, cmid, smid), _nvec(nb, cos[j1], sin[j1]), _nvec(nb, cos, sin)],
                    axis=1,
                )
            )
        else:
            tris.append(np.stack([a0 + j, a0 + j1, np.full(s, b0)], axis=1))
            corner_n.append(
                np.stack(
                    [_nvec(na, cos, sin), _nvec(na, cos[j1], sin[j1]), _nvec(nb, cmid, smid)],
                    axis=1,
                )
            )
    return np.concatenate(tris), np.concatenate(corner_n).reshape(-1, 3), np.concatenate(band)


def rigid(mesh: Mesh, lin: np.ndarray, t=(0.0, 0.0, 0.0), name: str | None = None) -> Mesh:
    """``transform`` for an orthogonal ``lin`` (rotations, axis mirrors) on a triangle mesh.

    Orthogonal maps carry unit normals to unit normals, so this skips the inverse transpose
    and renormalisation of :func:`~ionic_usd.geometry.mesh.transform` (the capital's largest
    cost at high LOD); a mirror reverses each triangle's winding (corners 1 and 2 swap) and
    flips ``s`` of the mesh's metric charts, so they wind counter-clockwise as before.
    """
    lin = np.asarray(lin, dtype=np.float64)
    pts = libm.linear(mesh.points, lin) + np.asarray(t, dtype=np.float64)
    normals = mesh.normals
    if normals is not None:
        normals = normals.with_values(libm.linear(normals.values, lin.astype(np.float32)))
    idx, st = mesh.face_vertex_indices, mesh.st
    if np.linalg.det(lin) < 0:
        perm = np.arange(idx.size).reshape(-1, 3)[:, [0, 2, 1]].reshape(-1)
        idx = idx[perm]
        normals = None if normals is None else normals.reorder(perm)
        if st is not None:
            st = st.with_values(st.values * np.array([-1.0, 1.0], dtype=np.float32)).reorder(perm)
    return Mesh(pts, mesh.face_vertex_counts, idx, normals, st, name=name or mesh.name)


MIRROR_X = np.diag([-1.0, 1.0, 1.0])
MIRROR_Z = np.diag([1.0, 1.0, -1.0])
#: the mirror in the diagonal plane x = z (it swaps the X and Z axes)
SWAP_XZ = np.array([[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]])


def rot_y(deg: float) -> np.ndarray:
    """Rotation about +Y taking +Z to (sin θ, 0, cos θ)."""
    t = math.radians(deg)
    # exact for quarter turns, so faces coplanar before the turn stay exactly coplanar
    c, s = (round(math.cos(t)), round(math.sin(t))) if deg % 90 == 0 else (math.cos(t), math.sin(t))
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])
