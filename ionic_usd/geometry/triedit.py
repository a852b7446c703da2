"""A closed triangle mesh open for local edits: the operations of the sliver clean-up.

:class:`TriangleEditor` keeps a triangle mesh as Python lists (points, triangles, per-corner
values: normals, st and the st chart) with exact vertex → triangle incidence, and offers the
three local operations :func:`ionic_usd.geometry.slivers.remove_slivers` mends slivers with
(COMPAS keeps the same operations on its half-edge mesh): :meth:`~TriangleEditor.flip` an
edge, :meth:`~TriangleEditor.snap` a vertex onto the opposite edge (splitting the neighbour)
and :meth:`~TriangleEditor.collapse` an edge. Each checks first that it moves the surface by
at most ``tol``, keeps the shell a closed 2-manifold, turns no triangle over and makes the
worst angle better, and does nothing (returns False) otherwise. Rows are made Python lists on
first read: an edit touches a few hundred of a mesh's rows, and plain float math on lists
(:mod:`ionic_usd.geometry.trimath`) is ~10x faster than numpy on 3-vectors. The triangles
and which are live are kept as arrays too (the clean-up's per-pass scans), and an edit clock
stamps the vertices round each edit (:meth:`~TriangleEditor.unchanged_since`: a failed
operation need not be tried again until one is stamped). :meth:`~TriangleEditor.to_mesh`
gives the result back.
"""

from __future__ import annotations

import math

import numpy as np

from ionic_usd.geometry.mesh import CornerValues, Mesh, chart_labels, corner_normals
from ionic_usd.geometry.trimath import (
    corner_angles,
    cross3,
    dot3,
    smallest_angle,
    tet_height,
    unit_normal,
)

__all__ = ["TriangleEditor"]


def _stable_argsort(key: np.ndarray) -> np.ndarray:
    """``np.argsort(key, kind="stable")`` of a 1-D array of non-negative ints, by numpy's fast
    sort of the distinct keys key × n + position (the position is the remainder): its stable
    argsort is ~10x slower (used where those keys fit 62 bits)."""
    n = len(key)
    if not n or int(key.max()) * n >= 2**62:
        return np.argsort(key, kind="stable")
    return np.sort(key.astype(np.int64) * n + np.arange(n)) % n


def _first_ranks(key: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Groups of equal ``key`` (1-D, non-negative ints) numbered by first
    occurrence: the position of each group's first element, in group order, and the (n,)
    group number of every element."""
    order = _stable_argsort(key)
    srt = key[order]
    new = np.empty(len(srt), dtype=bool)
    new[:1] = True
    np.not_equal(srt[1:], srt[:-1], out=new[1:])
    first = order[new]  # first occurrence of each group, the groups in key order
    group = np.empty(len(srt), dtype=np.int64)
    group[order] = np.cumsum(new) - 1
    by_first = _stable_argsort(first)
    rank = np.empty_like(by_first)
    rank[by_first] = np.arange(len(by_first))
    return first[by_first], rank[group]


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


class TriangleEditor:
    """A closed, consistently wound triangle mesh under local edits (see the module).

    Parameters
    ----------
    mesh : triangle mesh with normals (or none) and st (or none), any layout
    """

    def __init__(self, mesh: Mesh) -> None:
        self.name = mesh.name
        self.pts = np.array(mesh.points, dtype=np.float64)
        self.P = _Rows(self.pts)  # the points as floats (kept equal to pts)
        self.tri0 = mesh.triangles.astype(np.int64).reshape(-1, 3)
        self.T = _Rows(self.tri0)
        # T and the live triangles as arrays too (kept equal by _set_tri and _kill; room for
        # the triangles snaps add), for the vectorised sliver scans and the result
        self.tri = np.concatenate([self.tri0, np.zeros((len(self.tri0) // 8 + 8, 3), np.int64)])
        self.alive = np.zeros(len(self.tri), dtype=bool)
        self.alive[: len(self.tri0)] = True
        self._corner_values(mesh)
        self.cn: dict[int, np.ndarray] = {}  # the (3, n_ch) corners of each edited or new face
        # vertex → the live triangles using it, made on first use from the input's incidence
        # (every edit goes through faces_of for each vertex it touches, so it stays exact)
        flat = self.tri0.reshape(-1)
        counts = np.bincount(flat, minlength=len(self.pts))
        self._first_use = np.concatenate([[0], np.cumsum(counts)])
        self._by_vertex = _stable_argsort(flat) // 3
        self._inc: dict[int, set[int]] = {}
        # edit clock: each edit ticks it and stamps every vertex whose star (its triangles,
        # their rows, corners and points) it changes; an operation on a triangle reads only
        # the stars of its three vertices, so one that failed fails again until one is stamped
        self.clock = 0
        self.stamp = [0] * len(self.pts)

    def _corner_values(self, mesh: Mesh) -> None:
        """The per-corner values carried through every edit: the normals (3), st (2) and the
        st chart (1: an edit never joins two charts, whose values may meet at a point)."""
        corner_n = corner_normals(mesh)
        has_st = mesh.st is not None
        self.n_dim = n_dim = 3 if corner_n is not None else 0
        self.n_ch = n_dim + (3 if has_st else 0)
        self.nrm32 = None if corner_n is None else np.asarray(corner_n, dtype=np.float32)
        self.st_idx = None
        self.cn0 = None
        if not self.n_ch:
            return
        cn0 = np.empty((len(self.tri0), 3, self.n_ch))  # float64, filled in place
        if self.nrm32 is not None:
            cn0[:, :, :3] = self.nrm32.reshape(-1, 3, 3)
        if has_st:
            assert mesh.st is not None
            self.st32 = mesh.st.values
            self.st_idx = mesh.st.corner_indices(mesh.face_vertex_indices).astype(np.int64)
            chart = chart_labels(self.st_idx, len(self.st32)).astype(np.float64)
            self.chart_of_st = np.zeros(len(self.st32))  # one chart per st value
            self.chart_of_st[self.st_idx] = np.repeat(chart, 3)
            cn0[:, :, n_dim : n_dim + 2] = self.st32[self.st_idx].reshape(-1, 3, 2)
            cn0[:, :, n_dim + 2] = chart[:, None]
        self.cn0 = cn0

    # ---- queries ----------------------------------------------------------------------------
    def corners_of(self, f: int) -> np.ndarray:
        """The (3, n_ch) per-corner values of triangle ``f``."""
        got = self.cn.get(f)
        return self.cn0[f] if got is None else got  # type: ignore[index]

    def faces_of(self, v: int) -> set[int]:
        """The live triangles using vertex ``v`` (the set itself: edits keep it exact)."""
        got = self._inc.get(v)
        if got is None:
            lo, hi = self._first_use[v], self._first_use[v + 1]
            got = self._inc[v] = set(self._by_vertex[lo:hi].tolist())
        return got

    def edge_faces(self, a: int, b: int) -> set[int]:
        return self.faces_of(a) & self.faces_of(b)

    def unchanged_since(self, t: int, when: int) -> bool:
        """No edit after clock ``when`` changed the stars of triangle ``t``'s vertices."""
        stamp, r = self.stamp, self.T[t]
        return stamp[r[0]] <= when and stamp[r[1]] <= when and stamp[r[2]] <= when

    def angles_of(self, t: int) -> tuple[float, float, float]:
        """Corner angles (degrees) of triangle ``t``, in its corners' order."""
        P, r = self.P, self.T[t]
        return corner_angles(P[r[0]], P[r[1]], P[r[2]])

    def min_angle_of(
        self, rows: list[list[int]], at: dict[int, list[float]] | _Rows | None = None
    ) -> float:
        """Smallest angle of the triangles ``rows`` (vertex triples), at the points ``at``."""
        at = self.P if at is None else at
        r = rows[0]
        lo = smallest_angle(at[r[0]], at[r[1]], at[r[2]])
        for r in rows[1:]:  # min()'s order: the first, then each smaller one
            a = smallest_angle(at[r[0]], at[r[1]], at[r[2]])
            if a < lo:
                lo = a
        return lo

    def shares_edge(self, a: int, b: int) -> bool:
        """Some live triangle has the edge ab (``bool(edge_faces(a, b))``, no new set)."""
        return not self.faces_of(a).isdisjoint(self.faces_of(b))

    def across(self, t: int, a: int, b: int) -> tuple[int, int] | None:
        """The one other triangle on edge ab and its vertex off that edge."""
        fb = self.faces_of(b)
        o = -1
        for f in self.faces_of(a):  # edge_faces(a, b) - {t}, which must be one triangle
            if f != t and f in fb:
                if o >= 0:
                    return None
                o = f
        if o < 0:
            return None
        r = self.T[o]  # its first vertex off ab
        d = r[0] if r[0] != a and r[0] != b else (r[1] if r[1] != a and r[1] != b else r[2])
        return o, d

    def flat_fan(self, v: int) -> bool:
        """Every triangle round ``v`` lies in one plane with one set of corner values at
        ``v`` (same normal, st and chart: no crease or seam through it): ``v`` is inside a
        flat face, and removing it leaves the surface where it is."""
        P, T = self.P, self.T
        fs = sorted(self.faces_of(v))
        if self.cn0 is not None:  # the cheap test first: one property vertex at v
            ref = self.corners_of(fs[0])[T[fs[0]].index(v)].tolist()
            for f in fs[1:]:
                if self.corners_of(f)[T[f].index(v)].tolist() != ref:
                    return False
        vec = [cross3(*(P[i] for i in T[f])) for f in fs]
        big = max(range(len(fs)), key=lambda i: dot3(vec[i], vec[i]))
        n0 = unit_normal(*(P[i] for i in T[fs[big]]))
        p0 = P[v]
        for f, w in zip(fs, vec, strict=True):
            if dot3(w, n0) < 0:
                return False  # a fold
            for i in T[f]:
                q = P[i]
                if abs(dot3(n0, (q[0] - p0[0], q[1] - p0[1], q[2] - p0[2]))) > 1e-12:
                    return False  # off the plane by more than rounding (1e-12 m)
        return True

    # ---- edits ------------------------------------------------------------------------------
    def _set_tri(self, f: int, new: list[int]) -> None:
        """Triangle ``f`` (an existing one, or the next new one) becomes ``new`` in the
        incidence and the arrays (the caller sets or appends the row of T)."""
        stamp, now = self.stamp, self.clock
        if f < len(self.T):
            for v in self.T[f]:
                self.faces_of(v).discard(f)
                stamp[v] = now
        else:
            if f >= len(self.tri):
                self.tri = np.concatenate([self.tri, np.zeros_like(self.tri)])
                self.alive = np.concatenate([self.alive, np.zeros_like(self.alive)])
            self.alive[f] = True
        self.tri[f] = new
        for v in new:
            self.faces_of(v).add(f)
            stamp[v] = now

    def _kill(self, f: int) -> None:
        for v in self.T[f]:
            self.faces_of(v).discard(f)
            self.stamp[v] = self.clock
        self.alive[f] = False

    def flip(self, t: int, k: int, tol: float) -> bool:
        """Flip the edge opposite corner k of triangle t, if the flip moves the surface by at
        most ``tol`` (the tetrahedron of the four vertices is that flat), raises the pair's
        smallest angle, turns no triangle over and crosses no st seam."""
        P, T = self.P, self.T
        row = T[t]
        c, a, b = row[k], row[(k + 1) % 3], row[(k + 2) % 3]
        od = self.across(t, a, b)
        if od is None:
            return False
        o, d = od
        if self.shares_edge(c, d):
            return False  # the new edge exists already
        pa, pb, pc, pd = P[a], P[b], P[c], P[d]
        if tet_height(pa, pb, pc, pd) > tol:
            return False
        ro = T[o]
        r1, r2 = cross3(P[row[0]], P[row[1]], P[row[2]]), cross3(P[ro[0]], P[ro[1]], P[ro[2]])
        ref = (r1[0] + r2[0], r1[1] + r2[1], r1[2] + r2[2])  # vector area
        n0, n1 = unit_normal(pc, pa, pd), unit_normal(pd, pb, pc)
        if dot3(n0, ref) <= 0 or dot3(n1, ref) <= 0 or dot3(n0, n1) <= 0:
            return False
        before = smallest_angle(P[row[0]], P[row[1]], P[row[2]])  # min_angle_of([row, ro])
        lo = smallest_angle(P[ro[0]], P[ro[1]], P[ro[2]])
        before = lo if lo < before else before
        if min(smallest_angle(pc, pa, pd), smallest_angle(pd, pb, pc)) <= before:
            return False
        if self.cn0 is not None:
            n_dim = self.n_dim
            ct, co = self.corners_of(t), self.corners_of(o)
            ic, ia, id_, ib = row.index(c), row.index(a), ro.index(d), ro.index(b)
            if self.n_ch > n_dim and not (
                ct[ia, n_dim:].tolist() == co[ro.index(a), n_dim:].tolist()
                and ct[row.index(b), n_dim:].tolist() == co[ib, n_dim:].tolist()
            ):
                return False  # ab is an st seam: the new triangles would span two charts
            self.cn[t] = np.array([ct[ic], ct[ia], co[id_]])
            self.cn[o] = np.array([co[id_], co[ib], ct[ic]])
        self.clock += 1
        self._set_tri(t, [c, a, d])
        self._set_tri(o, [d, b, c])
        T[t], T[o] = [c, a, d], [d, b, c]
        return True

    def snap(self, t: int, k: int, tol: float) -> bool:
        """Move the vertex at corner k of a cap t onto its opposite edge (at most ``tol``) and
        split the neighbour across that edge there; t vanishes."""
        P, T = self.P, self.T
        row = T[t]
        c, a, b = row[k], row[(k + 1) % 3], row[(k + 2) % 3]
        pa, pb, pc = P[a], P[b], P[c]
        ab = (pb[0] - pa[0], pb[1] - pa[1], pb[2] - pa[2])
        ac = (pc[0] - pa[0], pc[1] - pa[1], pc[2] - pa[2])
        u = min(max(dot3(ac, ab) / max(dot3(ab, ab), 1e-300), 0.0), 1.0)
        fl = [pa[0] + u * ab[0], pa[1] + u * ab[1], pa[2] + u * ab[2]]  # the foot on ab
        off = (fl[0] - pc[0], fl[1] - pc[1], fl[2] - pc[2])
        if math.sqrt(dot3(off, off)) > tol:
            return False  # first: the cheapest test, and most snaps fail it
        od = self.across(t, a, b)
        if od is None:
            return False
        o, d = od
        if self.shares_edge(c, d):
            return False
        around = [T[f] for f in sorted(self.faces_of(c)) if f != t]
        moved = {v: P[v] for r in around for v in r}
        moved[c] = fl
        for r in around:
            n_old = unit_normal(P[r[0]], P[r[1]], P[r[2]])
            n_new = unit_normal(moved[r[0]], moved[r[1]], moved[r[2]])
            if dot3(n_old, n_new) < 0.5:
                return False
        halves = [[b, c, d], [c, a, d]]
        moved.update({a: P[a], b: P[b], d: P[d]})
        before = min(self.min_angle_of(around), self.min_angle_of([row, T[o]]))
        after = min(self.min_angle_of(around, moved), self.min_angle_of(halves, moved))
        if after <= before:
            return False
        self.clock += 1
        self.pts[c] = fl
        P[c] = fl
        for r in around:  # c moved: the stars of its neighbours changed
            for v in r:
                self.stamp[v] = self.clock
        if self.cn0 is not None:
            ro, co = T[o], self.corners_of(o)
            ia, ib, id_ = ro.index(a), ro.index(b), ro.index(d)
            n_a, n_b, n_d = co[ia], co[ib], co[id_]
            nf = (1 - u) * n_a + u * n_b
            if self.n_dim:
                nf[: self.n_dim] /= max(float(np.linalg.norm(nf[: self.n_dim])), 1e-12)
            self.cn[o] = np.array([n_b, nf, n_d])  # halves[0] = b, c, d
            # halves[1] = c, a, d takes o's old corners at a and d (the loop version read
            # them back after overwriting o's, giving this half o's new corners: wrong st
            # and normals, an st fold on the cut capitals)
            self.cn[len(T)] = np.array([nf, n_a, n_d])
        self._set_tri(o, halves[0])
        T[o] = halves[0]
        self._set_tri(len(T), halves[1])
        T.append(halves[1])
        self._kill(t)
        return True

    def collapse(self, t: int, k: int, tol: float, min_angle: float) -> bool:
        """Collapse the edge opposite corner k of triangle t (one end onto the other), if that
        edge is shorter than ``tol`` or one of its ends lies inside a flat face, the link
        condition holds and no triangle round it turns over or gets an angle under
        ``min_angle`` (or its old worst)."""
        T = self.T
        row = T[t]
        a, b = row[(k + 1) % 3], row[(k + 2) % 3]
        pa, pb = self.P[a], self.P[b]
        ab = (pb[0] - pa[0], pb[1] - pa[1], pb[2] - pa[2])
        short = math.sqrt(dot3(ab, ab)) <= tol
        flat = {} if short else {a: self.flat_fan(a), b: self.flat_fan(b)}
        if not short and not (flat[a] or flat[b]):
            return False
        shared = self.edge_faces(a, b)
        if len(shared) != 2 or not self._link_condition(a, b, shared):
            return False
        for keep, drop in ((a, b), (b, a)):
            if not short and not flat[drop]:
                continue
            moved = [f for f in sorted(self.faces_of(drop)) if f not in shared]
            if not moved:
                continue  # drop is on the two shared triangles only (a flap): leave it
            new = [[keep if v == drop else v for v in T[f]] for f in moved]
            if not self._collapse_keeps_shape(moved, new, min_angle):
                continue
            self.clock += 1
            if self.cn0 is not None and (self.n_ch > self.n_dim or not short):
                self._move_corners(keep, drop, shared, moved, short)
            for f, nr in zip(moved, new, strict=True):
                self._set_tri(f, nr)
                T[f] = nr
            for f in sorted(shared):
                self._kill(f)
            return True
        return False

    def _link_condition(self, a: int, b: int, shared: set[int]) -> bool:
        """The ends of edge ab share exactly its two opposite vertices as neighbours (else a
        pinch or a fold would follow the collapse)."""
        T = self.T
        ring_a = {v for f in self.faces_of(a) for v in T[f]} - {a}
        ring_b = {v for f in self.faces_of(b) for v in T[f]} - {b}
        opp = {v for f in shared for v in T[f] if v != a and v != b}
        return ring_a & ring_b == opp

    def _collapse_keeps_shape(self, moved: list[int], new: list[list[int]], min_angle: float):
        """No moved triangle turns by more than 60 degrees, and none gets an angle under
        ``min_angle`` (or under the old triangles' worst)."""
        P, T = self.P, self.T
        old = [T[f] for f in moved]
        if any(
            dot3(unit_normal(P[r[0]], P[r[1]], P[r[2]]), unit_normal(P[s[0]], P[s[1]], P[s[2]]))
            < 0.5
            for r, s in zip(old, new, strict=True)
        ):
            return False
        return self.min_angle_of(new) >= min(min_angle, self.min_angle_of(old))

    def _move_corners(
        self, keep: int, drop: int, shared: set[int], moved: list[int], short: bool
    ) -> None:
        """The moved corners take keep's own values where keep has them in the same chart (st
        is a function of the position on a chart: drop's values would stretch the triangles
        round keep, by up to tol on a short edge); inside a flat fan of one chart (a long
        edge: the surface does not move) every value."""
        T, n_dim = self.T, self.n_dim
        at: dict[float, np.ndarray] = {}
        for f0 in sorted(shared):
            row0 = self.corners_of(f0)[T[f0].index(keep)]
            at.setdefault(float(row0[-1]), row0)
        for f in moved:
            c = self.corners_of(f).copy()
            k = T[f].index(drop)
            if not short:
                c[k] = next(iter(at.values()))
            elif float(c[k, -1]) in at:
                c[k, n_dim:] = at[float(c[k, -1])][n_dim:]
            else:
                continue
            self.cn[f] = c

    # ---- result -----------------------------------------------------------------------------
    def live_near(self, near: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The live triangles with a vertex where the (n,) bool ``near`` is set, ascending,
        and their (t, 3) vertex rows."""
        n = len(self.T)
        faces = np.flatnonzero(self.alive[:n] & near[self.tri[:n]].any(axis=1))
        return faces, self.tri[faces]

    def to_mesh(self) -> Mesh:
        """The live triangles as a mesh (unused points removed; st re-indexed per corner,
        equal values of one point and chart shared, first occurrence first)."""
        n = len(self.T)
        alive = self.alive[:n]
        live: slice | np.ndarray = slice(None) if alive.all() else alive  # no copy: all live
        tri = self.tri[:n][live]
        # the used points in order and each corner's new point index (np.unique's, by counts)
        used_mask = np.bincount(tri.reshape(-1), minlength=len(self.pts)) > 0
        used = np.flatnonzero(used_mask)
        new_index = np.cumsum(used_mask) - 1
        idx = new_index[tri.reshape(-1)]
        nrm = st = sti = None
        # the edited faces and their corner values, stacked once: (m, 3, n_ch)
        edited = sorted(self.cn)
        corners = np.array([self.cn[f] for f in edited]).reshape(len(edited), 3, self.n_ch)
        if self.nrm32 is not None:
            nrm3 = np.empty((n, 3, 3), np.float32)
            nrm3[: len(self.tri0)] = self.nrm32.reshape(-1, 3, 3)
            nrm3[edited] = corners[:, :, :3]
            nrm = nrm3[live].reshape(-1, 3)
        if self.st_idx is not None:
            st, sti = self._st_of_corners(n, live, idx, edited, corners)
        return Mesh(
            self.pts[used],
            np.full(len(tri), 3, np.int32),
            idx,
            None if nrm is None else CornerValues.per_corner(nrm),
            None if st is None or sti is None else CornerValues(st, sti),
            name=self.name,
        )

    def _st_of_corners(
        self,
        n: int,
        live: slice | np.ndarray,
        idx: np.ndarray,
        edited: list[int],
        corners: np.ndarray,
    ) -> tuple[np.ndarray, np.ndarray]:
        """st values and indices of the corners of the live triangles ``live`` of the first
        ``n`` (point indices ``idx``): one value per point, st rounded to 1e-7 and chart,
        first occurrence first. ``corners``: the (m, 3, n_ch) values of the ``edited`` faces."""
        n_dim, n_st, st_idx = self.n_dim, len(self.st32), self.st_idx
        assert st_idx is not None
        # the classes of equal (rounded st, chart): of the input's st values and the edits'
        new = corners[:, :, n_dim:].reshape(-1, 3)
        vals = np.concatenate([np.column_stack([self.st32, self.chart_of_st]), new])
        q = np.round(vals * 1e7).astype(np.int64)  # st to 1e-7; the chart (an int) as it is
        q[:, 2] = vals[:, 2]
        cls = _row_classes(q)
        corner_cls = np.empty((n, 3), np.int64)
        k = len(self.tri0)
        corner_cls[:k] = cls[st_idx].reshape(-1, 3)
        if edited:
            corner_cls[edited] = cls[n_st:].reshape(-1, 3)
        first, rank = _first_ranks(idx * (int(cls.max()) + 1) + corner_cls[live].reshape(-1))
        # the st of each first occurrence only: its face and corner, from the input's st or
        # the edits' values (float64 cast to float32, as a float32 array of them would be)
        face = first // 3 if isinstance(live, slice) else np.flatnonzero(live)[first // 3]
        corner = first % 3
        st = np.empty((len(first), 2), np.float32)
        inp = face < k
        st[inp] = self.st32[st_idx[face[inp] * 3 + corner[inp]]]
        if edited:
            row = np.full(n, -1)
            row[edited] = np.arange(len(edited))
            er = row[face]
            at = er >= 0
            st[at] = new[er[at] * 3 + corner[at], :2]
        return st, rank.astype(np.int32)


def _row_classes(a: np.ndarray) -> np.ndarray:
    """(n,) class of every row of the (n, k) int array ``a``: equal rows, equal classes
    (0 .. classes - 1); one int key per row where the columns' spans allow."""
    if not len(a):
        return np.zeros(0, dtype=np.int64)
    lo, hi = a.min(axis=0).tolist(), a.max(axis=0).tolist()
    span = [h - c + 1 for c, h in zip(lo, hi, strict=True)]  # Python ints: no overflow
    if math.prod(span) < 2**62:
        key = np.zeros(len(a), dtype=np.int64)
        for col, c0, n in zip(a.T, lo, span, strict=True):
            key = key * n + (col - c0)
        return np.unique(key, return_inverse=True)[1].reshape(-1)
    cls = np.zeros(len(a), dtype=np.int64)
    for col in a.T:
        _, r = np.unique(col, return_inverse=True)
        _, cls = np.unique(cls * (int(r.max(initial=0)) + 1) + r.reshape(-1), return_inverse=True)
    return cls.reshape(-1)
