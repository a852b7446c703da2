"""Sliver clean-up of boolean results: edge flips, snaps and collapses within a tolerance.

:func:`remove_slivers` mends the needle and cap triangles manifold3d leaves where faces met
almost coplanar (called by :func:`ionic_usd.geometry.boolean.difference` with ``simplify``);
:func:`normals_with_winding` makes authored corner normals agree with the face winding after
such edits.
"""

from __future__ import annotations

import math

import numpy as np

from ionic_usd.geometry.mesh import (
    Mesh,
    chart_labels,
    corner_normals,
    face_normals,
    unique_rows,
)

__all__ = ["SLIVER_ANGLE_DEG", "SLIVER_TOL", "normals_with_winding", "remove_slivers"]

#: triangles with an angle under this (degrees) are slivers :func:`remove_slivers` works on
SLIVER_ANGLE_DEG = 1.0
#: how far (× the bounding box diagonal) the sliver clean-up of a boolean result may move its
#: surface: 1.5e-4 m on a capital 1.5 m across
SLIVER_TOL = 1e-4


def _tri_cosines(p: np.ndarray) -> np.ndarray:
    """(t, 3, 3) corner points → (t, 3) cosines of the corner angles, in [-1, 1]."""
    a = np.roll(p, -1, axis=1) - p
    b = np.roll(p, -2, axis=1) - p
    la, lb = np.linalg.norm(a, axis=2), np.linalg.norm(b, axis=2)
    return np.clip(np.einsum("tij,tij->ti", a, b) / np.maximum(la * lb, 1e-300), -1.0, 1.0)


def _tri_angles(p: np.ndarray) -> np.ndarray:
    """(t, 3, 3) corner points → (t, 3) corner angles in degrees (for reports: numpy's arccos
    differs in the last bits by CPU, so the clean-up itself orders by :func:`_tri_cosines`)."""
    return np.degrees(np.arccos(_tri_cosines(p)))  # noqa: TID251


def _angles(p: list[float], q: list[float], r: list[float]) -> tuple[float, float, float]:
    """The corner angles (degrees) of the triangle pqr (3 floats each): :func:`_tri_angles`
    for one triangle in plain float math (numpy costs ~1 µs a call on 3-vectors)."""
    out = []
    for o, u, w in ((p, q, r), (q, r, p), (r, p, q)):
        ax, ay, az = u[0] - o[0], u[1] - o[1], u[2] - o[2]
        bx, by, bz = w[0] - o[0], w[1] - o[1], w[2] - o[2]
        la = math.sqrt(ax * ax + ay * ay + az * az)
        lb = math.sqrt(bx * bx + by * by + bz * bz)
        c = (ax * bx + ay * by + az * bz) / max(la * lb, 1e-300)
        out.append(math.degrees(math.acos(min(max(c, -1.0), 1.0))))
    return out[0], out[1], out[2]


def _normal(p: list[float], q: list[float], r: list[float]) -> tuple[float, float, float]:
    """The unit normal of the triangle pqr (zero for a degenerate one)."""
    ux, uy, uz = q[0] - p[0], q[1] - p[1], q[2] - p[2]
    vx, vy, vz = r[0] - p[0], r[1] - p[1], r[2] - p[2]
    nx, ny, nz = uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx
    ln = max(math.sqrt(nx * nx + ny * ny + nz * nz), 1e-300)
    return nx / ln, ny / ln, nz / ln


def _cross(p: list[float], q: list[float], r: list[float]) -> tuple[float, float, float]:
    """(q − p) × (r − p): twice the vector area of the triangle pqr."""
    ux, uy, uz = q[0] - p[0], q[1] - p[1], q[2] - p[2]
    vx, vy, vz = r[0] - p[0], r[1] - p[1], r[2] - p[2]
    return uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx


def _dot(u, v) -> float:
    return u[0] * v[0] + u[1] * v[1] + u[2] * v[2]


def _tet_height(a: list[float], b: list[float], c: list[float], d: list[float]) -> float:
    """Smallest height of the tetrahedron abcd: how far a flip of edge ab (triangles abc, abd
    → acd, bcd) moves the surface."""
    n = _cross(a, b, c)
    v = abs(n[0] * (d[0] - a[0]) + n[1] * (d[1] - a[1]) + n[2] * (d[2] - a[2]))
    areas = [math.sqrt(_dot(x, x)) for x in (n, _cross(a, b, d), _cross(a, c, d), _cross(b, c, d))]
    return v / max(max(areas), 1e-300)


class _Rows(dict):
    """Rows of a numpy array as Python lists, made on first read (an edit touches a few
    hundred of a mesh's rows: converting them all costs more than the edits); rows set or
    appended are kept here. ``len`` is the number of rows, appended ones included."""

    def __init__(self, src: np.ndarray) -> None:
        super().__init__()
        self.src = src
        self.n = len(src)

    def __missing__(self, k: int) -> list:
        row = self[k] = self.src[k].tolist()
        return row

    def __len__(self) -> int:
        return self.n

    def append(self, row: list) -> None:
        self[self.n] = row
        self.n += 1

    def array(self) -> np.ndarray:
        """All rows (appended included) as one array."""
        out = np.empty((self.n, *self.src.shape[1:]), dtype=self.src.dtype)
        out[: len(self.src)] = self.src
        for k, row in self.items():
            out[k] = row
        return out


def remove_slivers(
    mesh: Mesh,
    tol: float,
    *,
    min_angle: float = SLIVER_ANGLE_DEG,
    max_passes: int = 8,
    changed: np.ndarray | None = None,
) -> Mesh:
    """Remove sliver triangles of a closed triangle mesh without moving its surface by more
    than ``tol``.

    Each triangle with an angle under ``min_angle`` is mended, the worst first, by the first
    of these that is allowed: an **edge flip** of its longest edge (a cap: the opposite vertex
    lies near that edge), if the flip moves the surface by at most ``tol`` (the tetrahedron of
    the four vertices is that flat), raises the pair's smallest angle and turns no triangle
    over; an **edge collapse** of its shortest edge (a needle) if that edge is shorter than
    ``tol`` or one of its ends lies inside a flat face (its triangles coplanar, with one
    normal, st and chart there: removing it does not move the surface, and the moved corners
    take the kept end's values), the two end points share exactly two neighbours (the link
    condition: the shell stays a closed 2-manifold) and no triangle round it turns over or
    becomes a new sliver.
    Slivers neither can mend within ``tol`` are left (they are real, thin features).

    The edits run on Python lists (points, triangles, per-corner attributes) with plain float
    math; only the per-pass sliver scan and the output are numpy.

    Parameters
    ----------
    mesh : closed, consistently wound triangle mesh with faceVarying normals (or none)
    tol : largest allowed movement of the surface (m)
    min_angle : degrees
    changed : (n,) bool over the points, or None (all). Only the slivers with a vertex on a
        triangle round a changed point are worked on (then, as always, those round the
        edits): the rest of the mesh is as an earlier clean-up with at least this ``tol``
        left it, whose slivers failed then and would fail again (a cut of a cleaned union
        re-mends only along the cut)

    Returns
    -------
    Mesh with the same name; unused points removed.
    """
    pts = np.array(mesh.points, dtype=np.float64)
    P = _Rows(pts)  # the points as floats (kept equal to pts)
    tri0 = mesh.triangles.astype(np.int64).reshape(-1, 3)
    T = _Rows(tri0)
    # per-corner attributes carried through every edit: the normals (3), st (2) and the
    # st chart (1: an edit never joins two charts, whose values may meet at a point)
    parts = []
    corner_n = corner_normals(mesh)
    if corner_n is not None:
        parts.append(np.asarray(corner_n, dtype=np.float64).reshape(-1, 3, 3))
    if mesh.st is not None and mesh.st_indices is not None:
        parts.append(np.asarray(mesh.st, dtype=np.float64)[mesh.st_indices].reshape(-1, 3, 2))
        chart = chart_labels(mesh.st_indices, len(mesh.st)).astype(np.float64)
        parts.append(np.repeat(chart, 3).reshape(-1, 3, 1))
    cn0 = np.concatenate(parts, axis=2) if parts else None
    n_ch = 0 if cn0 is None else cn0.shape[2]
    cn: dict[int, np.ndarray] = {}  # the (3, n_ch) corners of each edited or new face
    n_dim = 3 if corner_n is not None else 0
    alive = [True] * len(T)
    cos_min = math.cos(math.radians(min_angle))

    def corners_of(f: int) -> np.ndarray:
        got = cn.get(f)
        return cn0[f] if got is None else got  # type: ignore[index]

    # vertex → the live triangles using it, made on first use from the input's incidence
    # (every edit goes through faces_of for each vertex it touches, so it stays exact)
    flat = tri0.reshape(-1)
    first_use = np.concatenate([[0], np.cumsum(np.bincount(flat, minlength=len(pts)))]).tolist()
    by_vertex = (np.argsort(flat, kind="stable") // 3).tolist()
    inc: dict[int, set[int]] = {}

    def faces_of(v: int) -> set[int]:
        got = inc.get(v)
        if got is None:
            got = inc[v] = set(by_vertex[first_use[v] : first_use[v + 1]])
        return got

    def edge_faces(a: int, b: int) -> set[int]:
        return faces_of(a) & faces_of(b)

    def set_tri(f: int, new: list[int]) -> None:
        if f < len(T):
            for v in T[f]:
                faces_of(v).discard(f)
        for v in new:
            faces_of(v).add(f)

    def kill(f: int) -> None:
        for v in T[f]:
            faces_of(v).discard(f)
        alive[f] = False

    def min_angle_of(
        rows: list[list[int]], at: dict[int, list[float]] | list[list[float]] = P
    ) -> float:
        return min(min(_angles(at[r[0]], at[r[1]], at[r[2]])) for r in rows)

    def across(t: int, a: int, b: int) -> tuple[int, int] | None:
        """The one other triangle on edge ab and its vertex off that edge."""
        other = edge_faces(a, b) - {t}
        if len(other) != 1:
            return None
        (o,) = other
        d = next(v for v in T[o] if v != a and v != b)
        return o, d

    def try_flip(t: int, k: int) -> bool:
        """Flip the edge opposite corner k of triangle t."""
        row = T[t]
        c, a, b = row[k], row[(k + 1) % 3], row[(k + 2) % 3]
        od = across(t, a, b)
        if od is None:
            return False
        o, d = od
        if edge_faces(c, d):
            return False  # the new edge exists already
        pa, pb, pc, pd = P[a], P[b], P[c], P[d]
        if _tet_height(pa, pb, pc, pd) > tol:
            return False
        ro = T[o]
        r1, r2 = _cross(P[row[0]], P[row[1]], P[row[2]]), _cross(P[ro[0]], P[ro[1]], P[ro[2]])
        ref = (r1[0] + r2[0], r1[1] + r2[1], r1[2] + r2[2])  # vector area
        n0, n1 = _normal(pc, pa, pd), _normal(pd, pb, pc)
        if _dot(n0, ref) <= 0 or _dot(n1, ref) <= 0 or _dot(n0, n1) <= 0:
            return False
        before = min_angle_of([row, ro])
        if min(min(_angles(pc, pa, pd)), min(_angles(pd, pb, pc))) <= before:
            return False
        if cn0 is not None:
            ct, co = corners_of(t), corners_of(o)
            ic, ia, id_, ib = row.index(c), row.index(a), ro.index(d), ro.index(b)
            if n_ch > n_dim and not (
                np.array_equal(ct[ia, n_dim:], co[ro.index(a), n_dim:])
                and np.array_equal(ct[row.index(b), n_dim:], co[ib, n_dim:])
            ):
                return False  # ab is an st seam: the new triangles would span two charts
            cn[t] = np.array([ct[ic], ct[ia], co[id_]])
            cn[o] = np.array([co[id_], co[ib], ct[ic]])
        set_tri(t, [c, a, d])
        set_tri(o, [d, b, c])
        T[t], T[o] = [c, a, d], [d, b, c]
        return True

    def try_snap(t: int, k: int) -> bool:
        """Move the vertex at corner k of a cap t onto its opposite edge (at most ``tol``) and
        split the neighbour across that edge there; t vanishes."""
        row = T[t]
        c, a, b = row[k], row[(k + 1) % 3], row[(k + 2) % 3]
        od = across(t, a, b)
        if od is None:
            return False
        o, d = od
        pa, pb, pc = P[a], P[b], P[c]
        ab = (pb[0] - pa[0], pb[1] - pa[1], pb[2] - pa[2])
        ac = (pc[0] - pa[0], pc[1] - pa[1], pc[2] - pa[2])
        u = min(max(_dot(ac, ab) / max(_dot(ab, ab), 1e-300), 0.0), 1.0)
        fl = [pa[0] + u * ab[0], pa[1] + u * ab[1], pa[2] + u * ab[2]]  # the foot on ab
        off = (fl[0] - pc[0], fl[1] - pc[1], fl[2] - pc[2])
        if math.sqrt(_dot(off, off)) > tol or edge_faces(c, d):
            return False
        around = [T[f] for f in sorted(faces_of(c)) if f != t]
        moved = {v: P[v] for r in around for v in r}
        moved[c] = fl
        for r in around:
            n_old = _normal(P[r[0]], P[r[1]], P[r[2]])
            n_new = _normal(moved[r[0]], moved[r[1]], moved[r[2]])
            if _dot(n_old, n_new) < 0.5:
                return False
        halves = [[b, c, d], [c, a, d]]
        moved.update({a: P[a], b: P[b], d: P[d]})
        before = min(min_angle_of(around), min_angle_of([row, T[o]]))
        after = min(min_angle_of(around, moved), min_angle_of(halves, moved))
        if after <= before:
            return False
        pts[c] = fl
        P[c] = fl
        if cn0 is not None:
            ro, co = T[o], corners_of(o)
            ia, ib, id_ = ro.index(a), ro.index(b), ro.index(d)
            n_a, n_b, n_d = co[ia], co[ib], co[id_]
            nf = (1 - u) * n_a + u * n_b
            if n_dim:
                nf[:n_dim] /= max(float(np.linalg.norm(nf[:n_dim])), 1e-12)
            cn[o] = np.array([n_b, nf, n_d])  # halves[0] = b, c, d
            # halves[1] = c, a, d takes o's old corners at a and d (the loop version read
            # them back after overwriting o's, giving this half o's new corners: wrong st
            # and normals, an st fold on the cut capitals)
            cn[len(T)] = np.array([nf, n_a, n_d])
        set_tri(o, halves[0])
        T[o] = halves[0]
        set_tri(len(T), halves[1])
        T.append(halves[1])
        alive.append(True)
        kill(t)
        return True

    def try_collapse(t: int, k: int) -> bool:
        """Collapse the edge opposite corner k of triangle t (one end onto the other)."""
        row = T[t]
        a, b = row[(k + 1) % 3], row[(k + 2) % 3]
        pa, pb = P[a], P[b]
        ab = (pb[0] - pa[0], pb[1] - pa[1], pb[2] - pa[2])
        short = math.sqrt(_dot(ab, ab)) <= tol
        flat = {} if short else {a: flat_fan(a), b: flat_fan(b)}
        if not short and not (flat[a] or flat[b]):
            return False
        shared = edge_faces(a, b)
        if len(shared) != 2:
            return False
        ring_a = {v for f in faces_of(a) for v in T[f]} - {a}
        ring_b = {v for f in faces_of(b) for v in T[f]} - {b}
        opp = {v for f in shared for v in T[f] if v != a and v != b}
        if ring_a & ring_b != opp:
            return False  # the link condition: a pinch or a fold would follow
        for keep, drop in ((a, b), (b, a)):
            if not short and not flat[drop]:
                continue
            moved = [f for f in sorted(faces_of(drop)) if f not in shared]
            if not moved:
                continue  # drop is on the two shared triangles only (a flap): leave it
            new = [[keep if v == drop else v for v in T[f]] for f in moved]
            old = [T[f] for f in moved]
            if any(
                _dot(_normal(P[r[0]], P[r[1]], P[r[2]]), _normal(P[s[0]], P[s[1]], P[s[2]])) < 0.5
                for r, s in zip(old, new, strict=True)
            ):
                continue
            if min_angle_of(new) < min(min_angle, min_angle_of(old)):
                continue
            if cn0 is not None and (n_ch > n_dim or not short):
                # the moved corners take keep's own values where keep has them in the same
                # chart (st is a function of the position on a chart: drop's values would
                # stretch the triangles round keep, by up to tol on a short edge); inside a
                # flat fan of one chart (a long edge: the surface does not move) every value
                at: dict[float, np.ndarray] = {}
                for f0 in sorted(shared):
                    row0 = corners_of(f0)[T[f0].index(keep)]
                    at.setdefault(float(row0[-1]), row0)
                for f in moved:
                    c = corners_of(f).copy()
                    k = T[f].index(drop)
                    if not short:
                        c[k] = next(iter(at.values()))
                    elif float(c[k, -1]) in at:
                        c[k, n_dim:] = at[float(c[k, -1])][n_dim:]
                    else:
                        continue
                    cn[f] = c
            for f, nr in zip(moved, new, strict=True):
                set_tri(f, nr)
                T[f] = nr
            for f in sorted(shared):
                kill(f)
            return True
        return False

    def flat_fan(v: int) -> bool:
        """Every triangle round ``v`` lies in one plane with one set of corner values at
        ``v`` (same normal, st and chart: no crease or seam through it): ``v`` is inside a
        flat face, and removing it leaves the surface where it is."""
        fs = sorted(faces_of(v))
        if cn0 is not None:  # the cheap test first: one property vertex at v
            ref = corners_of(fs[0])[T[fs[0]].index(v)].tolist()
            for f in fs[1:]:
                if corners_of(f)[T[f].index(v)].tolist() != ref:
                    return False
        vec = [_cross(*(P[i] for i in T[f])) for f in fs]
        big = max(range(len(fs)), key=lambda i: _dot(vec[i], vec[i]))
        n0 = _normal(*(P[i] for i in T[fs[big]]))
        p0 = P[v]
        for f, w in zip(fs, vec, strict=True):
            if _dot(w, n0) < 0:
                return False  # a fold
            for i in T[f]:
                q = P[i]
                if abs(_dot(n0, (q[0] - p0[0], q[1] - p0[1], q[2] - p0[2]))) > 1e-12:
                    return False  # off the plane by more than rounding (1e-12 m)
        return True

    touched: set[int] | None = None  # vertices near a change in the last pass (None: all)
    if changed is not None:
        near_new = np.any(np.asarray(changed, dtype=bool)[tri0], axis=1)
        touched = set(np.unique(tri0[near_new]).tolist())
    for _ in range(max_passes):
        # the live triangles a pass looks at: all at first, then (a sliver nothing changed
        # around failed before) those with a vertex near the last pass's edits
        if touched is None:
            cand = np.arange(len(T))
            tri = tri0
        else:
            cand = np.array(sorted({f for v in touched for f in faces_of(v)}), dtype=np.int64)
            tri = np.array([T[f] for f in cand.tolist()], dtype=np.int64).reshape(-1, 3)
        # the smallest angle is the largest cosine: candidates and their order from + - * / and
        # sqrt only (arccos is CPU-dependent); a margin of 1e-12 keeps every triangle under
        # min_angle a candidate, and _angles decides each exactly as before
        worst = _tri_cosines(pts[tri]).max(axis=1)
        low = worst > cos_min - 1e-12
        bad, worst = cand[low], worst[low]
        if not len(bad):
            break
        touched = set()
        for t in bad[np.argsort(-worst, kind="stable")].tolist():
            if not alive[t]:
                continue
            r = T[t]
            a = _angles(P[r[0]], P[r[1]], P[r[2]])
            lo = min(a)
            if lo >= min_angle:
                continue
            kmax, kmin = a.index(max(a)), a.index(lo)
            ring = list(r)
            if try_flip(t, kmax) or try_snap(t, kmax) or try_collapse(t, kmin):
                for v in ring:
                    for f in faces_of(v):
                        touched.update(T[f])
        if not touched:
            break
    tri = T.array()[np.array(alive, dtype=bool)]
    used, idx = np.unique(tri, return_inverse=True)
    corners = None
    if cn0 is not None:
        full = np.empty((len(T), 3, n_ch))
        full[: len(cn0)] = cn0
        for f, rows in cn.items():
            full[f] = rows
        corners = full[np.array(alive, dtype=bool)].reshape(-1, n_ch)
    nrm = None if corners is None or not n_dim else corners[:, :3].astype(np.float32)
    st = sti = None
    if corners is not None and corners.shape[1] > n_dim:
        # re-index st per corner (equal values of one point and chart shared, first
        # occurrence first)
        q = np.round(corners[:, n_dim:] * 1e7).astype(np.int64)
        q = np.concatenate([idx.reshape(-1, 1), q], axis=1)
        _, first, inv = unique_rows(q, return_index=True, return_inverse=True)
        order = np.argsort(first, kind="stable")
        rank = np.empty_like(order)
        rank[order] = np.arange(len(order))
        st = corners[first[order], n_dim : n_dim + 2].astype(np.float32)
        sti = rank[inv.reshape(-1)].astype(np.int32)
    out = Mesh(
        pts[used],
        np.full(len(tri), 3, np.int32),
        idx.reshape(-1),
        nrm,
        "faceVarying",
        st,
        sti,
        name=mesh.name,
    )
    return normals_with_winding(out)


def normals_with_winding(mesh: Mesh) -> Mesh:
    """``mesh`` with every faceVarying corner normal that points against its face's winding
    (dot < 0: a flip or snap of the sliver clean-up across a crease) replaced by the face
    normal, so authored normals agree with the winding on every face. Triangles only."""
    if mesh.normals is None or mesh.normals_interpolation != "faceVarying" or not mesh.n_faces:
        return mesh
    corner = corner_normals(mesh)
    assert corner is not None
    fn, _ = face_normals(mesh.points, mesh.triangles)
    cn3 = np.array(corner, dtype=np.float32).reshape(-1, 3, 3)
    against = np.einsum("ikj,ij->ik", cn3, fn) < 0
    if not against.any():
        return mesh
    cn3[against] = np.broadcast_to(fn[:, None, :], cn3.shape)[against]
    return mesh.with_(normals=cn3.reshape(-1, 3), normals_indices=None)
