"""Sliver clean-up of boolean results: edge flips, snaps and collapses within a tolerance.

:func:`remove_slivers` mends the needle and cap triangles manifold3d leaves where faces met
almost coplanar (called by :func:`ionic_usd.geometry.boolean.difference` with ``simplify``);
:func:`normals_with_winding` makes authored corner normals agree with the face winding after
such edits.
"""

from __future__ import annotations

import math

import numpy as np

from ionic_usd.geometry.mesh import CornerValues, Mesh, corner_normals, face_normals
from ionic_usd.geometry.triedit import TriangleEditor

__all__ = ["SLIVER_ANGLE_DEG", "SLIVER_TOL", "normals_with_winding", "remove_slivers"]

#: triangles with an angle under this (degrees) are slivers :func:`remove_slivers` works on
SLIVER_ANGLE_DEG = 1.0
#: how far (× the bounding box diagonal) the sliver clean-up of a boolean result may move its
#: surface: 1.5e-4 m on a capital 1.5 m across
SLIVER_TOL = 1e-4


def _tri_cosines(p: np.ndarray) -> np.ndarray:
    """(t, 3, 3) corner points → (t, 3) cosines of the corner angles, in [-1, 1]."""
    a = p[:, [1, 2, 0]] - p  # np.roll(p, -1, axis=1) - p, without roll's overhead
    b = p[:, [2, 0, 1]] - p
    # the lengths as np.linalg.norm(axis=2) sums (x² + y²) + z², without its overhead
    aa, bb = a * a, b * b
    la = np.sqrt(aa[..., 0] + aa[..., 1] + aa[..., 2])
    lb = np.sqrt(bb[..., 0] + bb[..., 1] + bb[..., 2])
    return np.clip(np.einsum("tij,tij->ti", a, b) / np.maximum(la * lb, 1e-300), -1.0, 1.0)


def _maybe_slivers(pts: np.ndarray, tri: np.ndarray, cos_lo: float) -> np.ndarray:
    """(t,) bool over the triangles ``tri`` (rows into the (n, 3) ``pts``): a superset of
    those :func:`_tri_cosines` gives a corner cosine over ``cos_lo`` (> 0). A corner between
    edges u, v has u · v > cos_lo |u| |v| only if u · v > 0 and (u · v)² >= k |u|² |v|² with
    k = (cos_lo − 3e-12)²: no square roots or divisions, on (t,) coordinate arrays (~5x
    faster than the exact cosines, which are then computed for these few rows only)."""
    k = (cos_lo - 3e-12) ** 2
    x, y, z = pts[:, 0], pts[:, 1], pts[:, 2]
    i, j, m = tri[:, 0], tri[:, 1], tri[:, 2]
    xi, yi, zi = x[i], y[i], z[i]
    xj, yj, zj = x[j], y[j], z[j]
    xm, ym, zm = x[m], y[m], z[m]
    ax, ay, az = xj - xi, yj - yi, zj - zi  # i → j
    bx, by, bz = xm - xj, ym - yj, zm - zj  # j → m
    cx, cy, cz = xi - xm, yi - ym, zi - zm  # m → i
    la, lb, lc = (
        ax * ax + ay * ay + az * az,
        bx * bx + by * by + bz * bz,
        cx * cx + cy * cy + cz * cz,
    )
    # minus the cosine numerators at i, j, m (the edges into and out of each corner)
    di, dj, dm = (
        ax * cx + ay * cy + az * cz,
        bx * ax + by * ay + bz * az,
        cx * bx + cy * by + cz * bz,
    )
    return (
        ((di < 0) & (di * di >= k * (la * lc)))
        | ((dj < 0) & (dj * dj >= k * (lb * la)))
        | ((dm < 0) & (dm * dm >= k * (lc * lb)))
    )


def _tri_angles(p: np.ndarray) -> np.ndarray:
    """(t, 3, 3) corner points → (t, 3) corner angles in degrees (for reports: numpy's arccos
    differs in the last bits by CPU, so the clean-up itself orders by :func:`_tri_cosines`)."""
    return np.degrees(np.arccos(_tri_cosines(p)))  # noqa: TID251


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

    The edits are :class:`~ionic_usd.geometry.triedit.TriangleEditor`'s operations (Python
    lists and plain float math); only the per-pass sliver scan and the output are numpy. A
    sliver all three failed on is not tried again until an edit changes a triangle round one
    of its vertices (the operations read nothing else, so they would fail the same way).

    Parameters
    ----------
    mesh : closed, consistently wound triangle mesh with normals (or none)
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
    ed = TriangleEditor(mesh)
    cos_min = math.cos(math.radians(min_angle))
    failed: dict[int, int] = {}
    near: np.ndarray | None = None  # vertices near a change in the last pass (None: all)
    if changed is not None:
        near_new = np.any(np.asarray(changed, dtype=bool)[ed.tri0], axis=1)
        near = np.zeros(len(ed.pts), dtype=bool)
        near[ed.tri0[near_new]] = True
    for _ in range(max_passes):
        # the live triangles a pass looks at: all at first, then (a sliver nothing changed
        # around failed before) those with a vertex near the last pass's edits
        if near is None:
            cand, tri = np.arange(len(ed.T)), ed.tri0
        else:
            cand, tri = ed.live_near(near)
        touched = _mend_pass(ed, cand, tri, cos_min, min_angle, tol, failed)
        if not touched:
            break
        near = np.zeros(len(ed.pts), dtype=bool)
        near[list(touched)] = True
    return normals_with_winding(ed.to_mesh())


def _mend_pass(
    ed: TriangleEditor,
    cand: np.ndarray,
    tri: np.ndarray,
    cos_min: float,
    min_angle: float,
    tol: float,
    failed: dict[int, int],
) -> set[int]:
    """One pass over the candidate triangles ``cand`` (vertex rows ``tri``): each sliver,
    the worst first, mended by a flip, a snap or a collapse. Returns the vertices round the
    edits (empty: nothing changed, or no sliver). ``failed``: triangle → the edit clock
    when mending it last failed (kept up to date)."""
    # the smallest angle is the largest cosine: candidates and their order from + - * / and
    # sqrt only (arccos is CPU-dependent); a margin of 1e-12 keeps every triangle under
    # min_angle a candidate, and angles_of decides each exactly
    maybe = _maybe_slivers(ed.pts, tri, cos_min - 1e-12)
    worst = _tri_cosines(ed.pts[tri[maybe]]).max(axis=1)
    low = worst > cos_min - 1e-12
    bad, worst = cand[maybe][low], worst[low]
    touched: set[int] = set()
    for t in bad[np.argsort(-worst, kind="stable")].tolist():
        if not ed.alive[t] or (t in failed and ed.unchanged_since(t, failed[t])):
            continue  # gone, or failed before and nothing round it changed since
        a = ed.angles_of(t)
        lo = min(a)
        if lo >= min_angle:
            continue
        kmax, kmin = a.index(max(a)), a.index(lo)
        ring = list(ed.T[t])
        if ed.flip(t, kmax, tol) or ed.snap(t, kmax, tol) or ed.collapse(t, kmin, tol, min_angle):
            for v in ring:
                for f in ed.faces_of(v):
                    touched.update(ed.T[f])
        else:
            failed[t] = ed.clock
    return touched


def normals_with_winding(mesh: Mesh) -> Mesh:
    """``mesh`` with every per-corner normal that points against its face's winding
    (dot < 0: a flip or snap of the sliver clean-up across a crease) replaced by the face
    normal, so authored normals agree with the winding on every face. Triangles only."""
    if mesh.normals is None or mesh.normals.by_point or not mesh.n_faces:
        return mesh
    corner = corner_normals(mesh)
    assert corner is not None
    tri = mesh.triangles
    cn3 = np.asarray(corner, dtype=np.float32).reshape(-1, 3, 3)
    against = _against(mesh.points, tri, cn3)
    rows = np.flatnonzero(against.any(axis=1))
    if not len(rows):
        return mesh
    fn, _ = face_normals(mesh.points, tri[rows])
    cn3 = cn3.copy()
    sub = cn3[rows]
    sub[against[rows]] = np.broadcast_to(fn[:, None, :], sub.shape)[against[rows]]
    cn3[rows] = sub
    return mesh.with_(normals=CornerValues.per_corner(cn3.reshape(-1, 3)))


def _against(points: np.ndarray, tri: np.ndarray, cn3: np.ndarray) -> np.ndarray:
    """(t, 3) bool: ``einsum("ikj,ij->ik", cn3, face_normals(points, tri)[0]) < 0``, the
    corners whose (t, 3, 3) normals point against their face's winding, exactly, ~3x faster:
    the signs of the corner normals' dot products with the unnormalised face normal (the same
    cross products as ``face_normals``') on (t,) coordinate arrays, where they are clear (over
    1e-13 of a bound on the sum of the terms' magnitudes: rounding moves either sum by ~4e-16
    of it), and by the exact computation on the few faces where they are not (and faces too
    small or large for that bound: lengths under 1e-50 or over 1e50)."""
    x, y, z = points[:, 0], points[:, 1], points[:, 2]
    i, j, k = tri[:, 0], tri[:, 1], tri[:, 2]
    xi, yi, zi = x[i], y[i], z[i]
    ux, uy, uz = x[j] - xi, y[j] - yi, z[j] - zi
    vx, vy, vz = x[k] - xi, y[k] - yi, z[k] - zi
    cx, cy, cz = uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx
    size = np.abs(cx) + np.abs(cy) + np.abs(cz)
    bound = size * (1e-13 * float(np.abs(cn3).max(initial=0.0)))
    s = np.empty(cn3.shape[:2])
    for c in range(3):
        s[:, c] = cn3[:, c, 0] * cx + cn3[:, c, 1] * cy + cn3[:, c, 2] * cz
    neg = s < 0
    odd = ~((size > 1e-100) & (size < 1e100))  # also NaN
    unsure = np.flatnonzero((np.abs(s) <= bound[:, None]).any(axis=1) | odd)
    if len(unsure):
        fn, _ = face_normals(points, tri[unsure])
        neg[unsure] = np.einsum("ikj,ij->ik", cn3[unsure], fn) < 0
    return neg
