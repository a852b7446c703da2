"""The sliver clean-up's editor: its sorts and st re-indexing give what the lexsort versions
they replace gave (the temple's files stay byte-identical)."""

from __future__ import annotations

import numpy as np
import pytest

from ionic_usd.geometry.mesh import CornerValues, Mesh, unique_rows
from ionic_usd.geometry.triedit import (
    TriangleEditor,
    _first_ranks,
    _row_classes,
    _stable_argsort,
)


@pytest.mark.parametrize("top", [50, 2**61])  # many ties; keys too big to pack (numpy's own)
def test_stable_argsort_is_numpys_stable_argsort(top):
    key = np.random.default_rng(0).integers(0, 50, 5000) * (top // 50)
    np.testing.assert_array_equal(_stable_argsort(key), np.argsort(key, kind="stable"))


@pytest.mark.parametrize("scale", [1, 2**61])  # one packed key; the column-by-column fallback
def test_row_classes_are_the_classes_of_equal_rows(scale):
    rng = np.random.default_rng(1)
    a = rng.integers(-3, 3, (4000, 3)) * scale
    cls = _row_classes(a)
    _, ref = unique_rows(a, return_inverse=True)
    # the same partition: each class is one distinct row and back
    pairs = set(zip(cls.tolist(), ref.reshape(-1).tolist(), strict=True))
    assert len(pairs) == len(set(cls.tolist())) == len(set(ref.reshape(-1).tolist())) > 100


def test_first_ranks_number_groups_by_first_occurrence():
    key = np.random.default_rng(2).integers(0, 300, 3000)
    first, rank = _first_ranks(key)
    _, ref_first, inv = np.unique(key, return_index=True, return_inverse=True)
    order = np.argsort(ref_first, kind="stable")
    ref_rank = np.empty_like(order)
    ref_rank[order] = np.arange(len(order))
    np.testing.assert_array_equal(first, ref_first[order])
    np.testing.assert_array_equal(rank, ref_rank[inv.reshape(-1)])


def _old_st(corners: np.ndarray, idx: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The st re-indexing to_mesh had before: one lexsort of (point, st to 1e-7, chart) rows."""
    q = np.concatenate([idx.reshape(-1, 1), np.round(corners * 1e7).astype(np.int64)], axis=1)
    _, first, inv = unique_rows(q, return_index=True, return_inverse=True)
    order = np.argsort(first, kind="stable")
    rank = np.empty_like(order)
    rank[order] = np.arange(len(order))
    return corners[first[order], :2].astype(np.float32), rank[inv.reshape(-1)].astype(np.int32)


def test_to_mesh_st_as_the_lexsort_gave_it():
    # a strip of quads in two charts meeting along a seam where their st values coincide (two
    # values per seam point: one per chart), a value repeated within a chart (shared in the
    # output) and one edited face with a new value at one corner
    n = 6
    pts = np.array([(x, y, 0.0) for y in (0, 1) for x in range(n)], dtype=np.float64)
    tri = []
    for x in range(n - 1):
        a, b, c, d = x, x + 1, n + x + 1, n + x
        tri += [(a, b, c), (a, c, d)]
    tri = np.array(tri)
    half = len(tri) // 2 + 1  # the seam runs along x = 3
    sti = np.where(np.arange(len(tri))[:, None] < half, tri, tri + len(pts)).reshape(-1)
    st_vals = np.concatenate([pts[:, :2], pts[:, :2]]).astype(np.float32)
    st_vals = np.vstack([st_vals, st_vals[tri[0, 0]]])  # a duplicate of one value, chart 1
    sti[0] = len(st_vals) - 1
    mesh = Mesh(pts, np.full(len(tri), 3), tri.reshape(-1), None, CornerValues(st_vals, sti))
    ed = TriangleEditor(mesh)
    assert ed.cn0 is not None
    edited = ed.cn0[4].copy()
    edited[0, 0] += 0.25  # a second st value at point 2 (on face 2 too), same chart
    ed.cn[4] = edited
    out = ed.to_mesh()
    corners = ed.cn0.copy()
    corners[4] = edited
    ref_st, ref_sti = _old_st(corners.reshape(-1, ed.n_ch), out.face_vertex_indices)
    np.testing.assert_array_equal(out.st.values, ref_st)
    np.testing.assert_array_equal(out.st.indices, ref_sti)
    # one value per point and chart, plus the edited corner's
    assert len(out.st.values) == len(pts) + 2 + 1
