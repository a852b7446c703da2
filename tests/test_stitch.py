"""Ring stitching (paper section IV): counts, validity and orientation."""

from __future__ import annotations

import numpy as np
import pytest

from ionic_usd.errors import ParameterError
from ionic_usd.geometry import Mesh, inspect_mesh, ring, stitch


def band_edges(tri):
    e = np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]])
    return e


def check_band(tri, a, b, closed):
    n, m = len(a), len(b)
    expected = (n + m - (m == 1) - (n == 1) * 0) if closed else n + m - 2
    if closed and n == 1:
        expected = m
    assert len(tri) == expected
    # every triangle uses both rows
    ina = np.isin(tri, a).sum(axis=1)
    assert np.all((ina >= 1) & (ina <= 2))
    # directed edges unique (consistent winding), each row edge used exactly once
    e = band_edges(tri)
    assert len(np.unique(e, axis=0)) == len(e)
    und = np.sort(e, axis=1)
    u, c = np.unique(und, axis=0, return_counts=True)
    row_edges = {tuple(sorted((a[i], a[(i + 1) % n]))) for i in range(n if closed else n - 1)}
    row_edges |= {tuple(sorted((b[i], b[(i + 1) % m]))) for i in range(m if closed else m - 1)}
    if not closed:  # the two end rungs bound an open band
        row_edges |= {tuple(sorted((a[0], b[0]))), tuple(sorted((a[-1], b[-1])))}
    row_edges = {x for x in row_edges if x[0] != x[1]}
    for edge, count in zip(map(tuple, u), c, strict=True):
        assert count == (1 if edge in row_edges else 2), edge


@pytest.mark.parametrize("n,m", [(5, 3), (3, 5), (1, 4), (4, 1), (7, 7), (24, 96)])
@pytest.mark.parametrize("closed", [False, True])
def test_auto_sequence_valid(n, m, closed):
    a, b = np.arange(n), np.arange(n, n + m)
    tri = stitch(a, b, is_closed=closed)
    check_band(tri, a, b, closed)


def test_explicit_sequence_matches_paper_semantics():
    a, b = np.arange(3), np.arange(3, 8)
    # a0 connects to b0,b1,b2; a1 to b2,b3; a2 to b3,b4  -> sum 7 = 3 + 5 - 1
    tri = stitch(a, b, sequence=[3, 2, 2])
    check_band(tri, a, b, False)
    fan = {tuple(t) for t in tri.tolist()}
    assert (0, 4, 3) in fan and (0, 5, 4) in fan  # a0's fan over b0-b1, b1-b2
    assert (0, 1, 5) in fan  # a0-a1 edge joins at a0's last connection b2
    with pytest.raises(ParameterError, match="sum"):
        stitch(a, b, sequence=[3, 2, 3])
    with pytest.raises(ParameterError, match=">= 1"):
        stitch(a, b, sequence=[0, 4, 4])
    with pytest.raises(ParameterError, match="one number per node"):
        stitch(a, b, sequence=[7])
    with pytest.raises(ParameterError, match="shared"):
        stitch(a, np.array([2, 9]))


def test_closed_stitch_of_rings_forms_outward_band():
    n, m = 12, 30
    pts = np.concatenate([ring(1.0, 0.0, n), ring(1.0, 1.0, m)])
    tri = stitch(
        np.arange(n), np.arange(n, n + m), is_closed=True, a_points=pts[:n], b_points=pts[n:]
    )
    p = pts[tri]
    normal = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    centre = p.mean(axis=1)
    radial = centre * np.array([1, 0, 1])
    assert np.all(np.einsum("ij,ij->i", normal, radial) > 0)
    flipped = stitch(np.arange(n), np.arange(n, n + m), is_closed=True, direction=-1)
    assert np.array_equal(flipped, tri[:, ::-1]) or len(flipped) == len(tri)


def test_stitched_cylinder_of_unequal_rings_is_watertight():
    n, m = 9, 23
    pts = np.concatenate([ring(1.0, 0.0, n), ring(1.0, 1.0, m), [[0, 0, 0], [0, 1, 0]]])
    a, b = np.arange(n), np.arange(n, n + m)
    tri = np.concatenate(
        [
            stitch(a, b, is_closed=True),
            stitch(a, np.array([n + m]), is_closed=True, direction=-1),
            stitch(b, np.array([n + m + 1]), is_closed=True),
        ]
    )
    r = inspect_mesh(Mesh(pts, [3] * len(tri), tri.reshape(-1)))
    assert r.watertight, r
