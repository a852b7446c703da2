"""Benchmark the sliver clean-up of boolean results: the current
:func:`ionic_usd.geometry.boolean.remove_slivers` against the pure-Python-loop version it
replaced (kept here only, for the side-by-side), on every capital of the column asset.

Usage: python tools/bench_slivers.py [--repeat N]

Builds ``column_asset_meshes(ColumnAssetOptions(lods=("low", "medium", "high"),
bases=("G1",), flutes=("f24",)))`` once in a fresh cache, recording every
``remove_slivers`` input; then runs old and new on each input (best of N), prints the time
per family (mesh name) and the ratio, and asserts the outputs are equal bit for bit (points,
face indices, normals, st, st indices). Finally it builds the asset's CapitalBody meshes a
second time with the old version patched in and asserts they equal the current ones.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from collections import defaultdict

import numpy as np

from ionic_usd.geometry import boolean
from ionic_usd.geometry.mesh import Mesh, chart_labels, corner_normals


# -- the old implementation (before the fast paths), verbatim apart from the names and the
# st chart rules (chart channel, no flip on an st seam, st keyed by point) and the snap's
# corner copies both now follow
def _old_tri_angles(p: np.ndarray) -> np.ndarray:
    """(t, 3, 3) corner points → (t, 3) corner angles in degrees."""
    a = np.roll(p, -1, axis=1) - p
    b = np.roll(p, -2, axis=1) - p
    la, lb = np.linalg.norm(a, axis=2), np.linalg.norm(b, axis=2)
    c = np.einsum("tij,tij->ti", a, b) / np.maximum(la * lb, 1e-300)
    return np.degrees(np.arccos(np.clip(c, -1.0, 1.0)))


def _old_unit_normals(p: np.ndarray) -> np.ndarray:
    n = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    return n / np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)


def _old_tet_height(a, b, c, d) -> float:
    """Smallest height of the tetrahedron abcd: how far a flip of edge ab (triangles abc, abd
    → acd, bcd) moves the surface."""
    v = abs(float(np.dot(np.cross(b - a, c - a), d - a)))
    areas = [
        float(np.linalg.norm(np.cross(q - o, r - o)))
        for o, q, r in ((a, b, c), (a, b, d), (a, c, d), (b, c, d))
    ]
    return v / max(max(areas), 1e-300)


def _old_remove_slivers_loop(
    mesh: Mesh, tol: float, *, min_angle: float = 1.0, max_passes: int = 8
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
        chart = chart_labels(mesh.st_indices, len(mesh.st)).astype(np.float64)
        parts.append(np.repeat(chart, 3).reshape(-1, 3, 1))  # as the current version
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
        if _old_tet_height(pts[a], pts[b], pts[c], pts[d]) > tol:
            return False
        new = np.array([[c, a, d], [d, b, c]])
        old = pts[tri[[t, o]]]
        ref = np.cross(old[:, 1] - old[:, 0], old[:, 2] - old[:, 0]).sum(axis=0)  # vector area
        new_n = _old_unit_normals(pts[new])
        if np.any(new_n @ ref <= 0) or new_n[0] @ new_n[1] <= 0:
            return False
        before = _old_tri_angles(pts[tri[[t, o]]]).min()
        if _old_tri_angles(pts[new]).min() <= before:
            return False
        if cn is not None:
            cnl = cn

            def corner(f: int, v: int) -> np.ndarray:
                return cnl[f][int(np.flatnonzero(tri[f] == v)[0])]

            if cn.shape[2] > n_dim and not all(
                np.array_equal(corner(t, v)[n_dim:], corner(o, v)[n_dim:]) for v in (a, b)
            ):
                return False  # an st seam (as the current version)

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
        n_old = _old_unit_normals(pts[tri[around]])
        n_new = _old_unit_normals(moved[tri[around]])
        if np.any(np.einsum("ij,ij->i", n_old, n_new) < 0.5):
            return False
        halves = np.array([[b, c, d], [c, a, d]])
        before = min(
            _old_tri_angles(pts[tri[around]]).min(), _old_tri_angles(pts[tri[[t, o]]]).min()
        )
        after = min(_old_tri_angles(moved[tri[around]]).min(), _old_tri_angles(moved[halves]).min())
        if after <= before:
            return False
        pts[c] = foot
        if cn is not None:
            # copies: cn[o] is overwritten below (as the current version)
            n_a, n_b, n_d = (cn[o][int(np.flatnonzero(tri[o] == v)[0])].copy() for v in (a, b, d))
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
            n_old = _old_unit_normals(pts[tri[moved]])
            n_new = _old_unit_normals(pts[new])
            if np.any(np.einsum("ij,ij->i", n_old, n_new) < 0.5):
                continue
            if _old_tri_angles(pts[new]).min() < min(
                min_angle, _old_tri_angles(pts[tri[moved]]).min()
            ):
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
        worst = _old_tri_angles(pts[tri]).min(axis=1)
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
            a = _old_tri_angles(pts[tri[t]][None])[0]
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
        # re-index st per corner (point, chart and value as the current version)
        q = np.round(corners[:, n_dim:] * 1e7).astype(np.int64)
        q = np.concatenate([idx.reshape(-1, 1), q], axis=1)
        _, first, inv = np.unique(q, axis=0, return_index=True, return_inverse=True)
        order = np.argsort(first)
        rank = np.empty_like(order)
        rank[order] = np.arange(len(order))
        st = corners[first[order], n_dim : n_dim + 2].astype(np.float32)
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


# -- the comparison ---------------------------------------------------------------------------


def old_remove_slivers(mesh, tol, **kw):
    """The loop version, followed by the normal repair both versions now end with."""
    return boolean.normals_with_winding(_old_remove_slivers_loop(mesh, tol, **kw))


def _arrays(m: Mesh) -> list[np.ndarray | None]:
    return [m.points, m.face_vertex_counts, m.face_vertex_indices, m.normals, m.st, m.st_indices]


def _same(x: Mesh, y: Mesh) -> bool:
    for a, b in zip(_arrays(x), _arrays(y), strict=True):
        if (a is None) != (b is None):
            return False
        if a is not None and (
            a.shape != b.shape or a.dtype != b.dtype or a.tobytes() != b.tobytes()
        ):
            return False
    return x.name == y.name


def _best(fn, repeat: int) -> tuple[float, Mesh]:
    best, out = float("inf"), None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t0)
    return best, out


def _capitals(asset_meshes) -> list:
    return [m for m in asset_meshes if m.part == "CapitalBody"]


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args(argv)
    os.environ["IONIC_USD_CACHE"] = tempfile.mkdtemp(prefix="bench_slivers_")
    from ionic_usd.pipeline.asset import column_asset_meshes
    from ionic_usd.usd.column_asset import ColumnAssetOptions

    opts = ColumnAssetOptions(lods=("low", "medium", "high"), bases=("G1",), flutes=("f24",))
    new_fn = boolean.remove_slivers
    calls: list[tuple[Mesh, float]] = []

    def recording(mesh: Mesh, tol: float, **kw):
        calls.append((mesh, tol))
        return new_fn(mesh, tol, **kw)

    boolean.remove_slivers = recording
    try:
        new_caps = _capitals(column_asset_meshes(opts))
    finally:
        boolean.remove_slivers = new_fn
    print(f"{len(calls)} remove_slivers calls, {len(new_caps)} CapitalBody meshes")
    fam: dict[str, list[float]] = defaultdict(lambda: [0.0, 0.0, 0])
    for mesh, tol in calls:
        t_old, out_old = _best(lambda m=mesh, t=tol: old_remove_slivers(m, t), args.repeat)
        t_new, out_new = _best(lambda m=mesh, t=tol: new_fn(m, t), args.repeat)
        assert _same(out_old, out_new), f"remove_slivers differs on {mesh.name} (tol {tol})"
        f = fam[f"{mesh.name} ({len(mesh.face_vertex_counts)} tri)"]
        f[0] += t_old
        f[1] += t_new
        f[2] += 1
    print(f"{'family':44s} {'calls':>5s} {'old s':>8s} {'new s':>8s} {'ratio':>6s}")
    tot_old = tot_new = 0.0
    for name, (t_old, t_new, n) in fam.items():
        tot_old += t_old
        tot_new += t_new
        print(f"{name:44s} {n:5d} {t_old:8.3f} {t_new:8.3f} {t_old / t_new:6.1f}x")
    print(f"{'total':44s} {len(calls):5d} {tot_old:8.3f} {tot_new:8.3f} {tot_old / tot_new:6.1f}x")
    print("outputs identical (bit for bit) on every call")
    # the whole asset's capitals again with the old clean-up: equal arrays
    os.environ["IONIC_USD_CACHE"] = tempfile.mkdtemp(prefix="bench_slivers_")
    boolean.remove_slivers = old_remove_slivers
    try:
        old_caps = _capitals(column_asset_meshes(opts))
    finally:
        boolean.remove_slivers = new_fn
    assert [m.name for m in old_caps] == [m.name for m in new_caps]
    for a, b in zip(old_caps, new_caps, strict=True):
        assert _same(a.mesh, b.mesh), f"CapitalBody {a.name} differs"
    print(f"all {len(new_caps)} CapitalBody meshes identical (old vs new clean-up)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
