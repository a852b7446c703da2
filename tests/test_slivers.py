"""The sliver clean-up's vectorised checks give exactly what the plain numpy versions they
replace gave (the temple's files stay byte-identical)."""

from __future__ import annotations

import numpy as np

from ionic_usd.geometry.mesh import CornerValues, Mesh, chart_labels, face_normals
from ionic_usd.geometry.slivers import _against, _maybe_slivers, _tri_cosines, normals_with_winding


def _hard_mesh(seed: int, n: int = 3000) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Random triangles of every size and shape (degenerate, 1e-60 and 1e60 across) with
    corner normals nearly in their face's plane (dot products within rounding of 0), zero,
    random or opposite."""
    rng = np.random.default_rng(seed)
    pts = rng.normal(size=(n, 3)) * 10.0 ** rng.integers(-4, 2, (n, 1))
    pts[:10] *= 1e-60
    pts[10:20] *= 1e60
    tri = rng.integers(0, n, (2 * n, 3))
    tri[:30, 1] = tri[:30, 0]  # degenerate: two corners on one point
    tri[:10] = rng.integers(0, 10, (10, 3))
    tri[10:20] = rng.integers(10, 20, (10, 3))
    fn, _ = face_normals(pts, tri)
    inplane = np.cross(fn, rng.normal(size=fn.shape))
    inplane /= np.maximum(np.linalg.norm(inplane, axis=1, keepdims=True), 1e-300)
    eps = rng.choice([0.0, 1e-17, -1e-17, 1e-9, -1e-9, 0.3, -0.3], size=(len(tri), 3, 1))
    cn3 = (inplane[:, None, :] + eps * fn[:, None, :]).astype(np.float32)
    cn3[::7, 1] = 0.0
    cn3[::11, 2] = rng.normal(size=(len(cn3[::11]), 3))
    # and faces with an edge along their corner normal: the dot product is 0 to rounding,
    # whose sign the two ways of summing it often disagree on
    m = n // 2
    along = rng.normal(size=(m, 3)).astype(np.float32)
    p0 = rng.normal(size=(m, 3))
    p1 = p0 + along * rng.uniform(0.1, 3.0, (m, 1))
    ring = len(pts) + np.arange(m)
    pts = np.concatenate([pts, p0, p1, rng.normal(size=(m, 3))])
    tri = np.concatenate([tri, np.stack([ring, ring + m, ring + 2 * m], 1)])
    cn3 = np.concatenate([cn3, np.repeat(along[:, None, :], 3, axis=1)])
    return pts, tri, cn3


def test_against_is_the_einsum_sign_exactly():
    for seed in range(4):
        pts, tri, cn3 = _hard_mesh(seed)
        fn, _ = face_normals(pts, tri)
        ref = np.einsum("ikj,ij->ik", cn3, fn) < 0
        got = _against(pts, tri, cn3)
        assert 100 < ref.sum() < ref.size - 100  # both kinds, many near 0
        np.testing.assert_array_equal(got, ref)


def test_normals_with_winding_replaces_the_corners_against_the_winding():
    pts, tri, cn3 = _hard_mesh(5, 400)
    mesh = Mesh(
        pts, np.full(len(tri), 3), tri.reshape(-1), CornerValues.per_corner(cn3.reshape(-1, 3))
    )
    fn, _ = face_normals(pts, tri)
    ref = cn3.copy()  # the plain version: every face normal broadcast, the corners against it
    against = np.einsum("ikj,ij->ik", cn3, fn) < 0
    ref[against] = np.broadcast_to(fn[:, None, :], ref.shape)[against]
    out = normals_with_winding(mesh)
    assert out.normals is not None and out.normals.values.dtype == np.float32
    assert against.sum() > 100
    np.testing.assert_array_equal(out.corner_normals(), ref.reshape(-1, 3))


def test_maybe_slivers_holds_every_sliver_corner():
    cos_lo = np.cos(np.radians(1.0)) - 1e-12
    for seed in range(4):
        pts, tri, _ = _hard_mesh(seed)
        # and triangles with an angle within rounding of the threshold, in random frames
        rng = np.random.default_rng(seed)
        m = 20000
        a = np.arccos(cos_lo) * (1 + rng.uniform(-3e-13, 3e-13, m))
        rot, _ = np.linalg.qr(rng.normal(size=(m, 3, 3)))
        ends = np.stack([np.ones(m), np.zeros(m), np.zeros(m)], 1) * rng.uniform(0.5, 2, (m, 1))
        far = np.stack([np.cos(a), np.sin(a), np.zeros(m)], 1) * rng.uniform(0.5, 2, (m, 1))
        at = rng.normal(size=(m, 3))
        ring = len(pts) + np.arange(m)
        ends, far = np.einsum("tij,tj->ti", rot, ends) + at, np.einsum("tij,tj->ti", rot, far) + at
        pts = np.concatenate([pts, at, ends, far])
        tri = np.concatenate([tri, np.stack([ring, ring + m, ring + 2 * m], 1)])
        exact = _tri_cosines(pts[tri]).max(axis=1) > cos_lo
        maybe = _maybe_slivers(pts, tri, cos_lo)
        assert exact.sum() > 5000
        assert not (exact & ~maybe).any()  # a superset
        clear = _tri_cosines(pts[tri]).max(axis=1) < cos_lo - 1e-10
        assert clear.sum() > 3000 and not (maybe & clear).any()  # none clearly not one


def _coo_chart_labels(st_indices: np.ndarray, n_values: int) -> np.ndarray:
    """chart_labels as it was: the graph as a COO matrix, the used components by np.unique."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    tri = np.asarray(st_indices, dtype=np.int64).reshape(-1, 3)
    rows = np.concatenate([tri[:, 0], tri[:, 1]])
    cols = np.concatenate([tri[:, 1], tri[:, 2]])
    graph = coo_matrix((np.ones(len(rows), np.int8), (rows, cols)), shape=(n_values, n_values))
    _, label = connected_components(graph, directed=False)
    return np.unique(label[tri[:, 0]], return_inverse=True)[1].reshape(-1).astype(np.int64)


def test_chart_labels_are_the_coo_versions():
    rng = np.random.default_rng(7)
    for _ in range(30):
        n = int(rng.integers(3, 3000))
        # sparse draws: many charts, values no triangle uses, repeated edges
        idx = rng.integers(0, n, 3 * int(rng.integers(1, n // 2 + 2)))
        ref = _coo_chart_labels(idx, n + 3)
        got = chart_labels(idx.astype(np.int32), n + 3)
        assert got.dtype == ref.dtype == np.int64
        np.testing.assert_array_equal(got, ref)
    assert ref.max() > 10  # many charts
