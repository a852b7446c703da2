"""Charts that overlap themselves: find the triangle pairs, split the charts apart.

xatlas's flattening can fold a chart onto itself near its boundary: every triangle keeps its
counter-clockwise winding, but two of them (often sharing one vertex) cover the same sliver
of the atlas. Measured on the Portunus capital at the low LOD (32 px/m): 110 sub-texels of
an 8× raster in one chart of 157, invisible at pixel centres in xatlas's own packing but
overlapping texels once the chart is repacked at another sub-pixel offset
(:func:`ionic_usd.texture.atlas.analytic_atlas`). :func:`split_overlapping_charts` cuts such
a chart into pieces none of which overlaps itself, so a repacking places them apart.
"""

from __future__ import annotations

import numpy as np

from ionic_usd.geometry.mesh import chart_labels, unique_rows

__all__ = ["overlapping_triangles", "split_overlapping_charts"]


def _candidate_pairs(lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """(k, 2) int64 pairs i < j of boxes (t, 2) that intersect (closed boxes), by a query of
    GEOS's STR packed R-tree (shapely), in sorted order."""
    import shapely

    if not len(lo):
        return np.empty((0, 2), dtype=np.int64)
    boxes = shapely.box(lo[:, 0], lo[:, 1], hi[:, 0], hi[:, 1])
    i, j = shapely.STRtree(boxes).query(boxes, predicate="intersects")
    keep = i < j
    return unique_rows(np.stack([i[keep], j[keep]], axis=1).astype(np.int64))


def _min3(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """Elementwise minimum of three arrays (cheaper than a reduction over a length-3 axis)."""
    return np.minimum(np.minimum(a, b), c)


def _max3(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    return np.maximum(np.maximum(a, b), c)


def overlapping_triangles(
    st: np.ndarray, st_indices: np.ndarray, eps: float, *, same_chart: bool = True
) -> np.ndarray:
    """Pairs of triangles whose ``st`` images overlap by more than ``eps``.

    Parameters
    ----------
    st : (u, 2) float
    st_indices : (3 t,) int, one per triangle corner
    eps : float >= 0
        Overlaps thinner than this (in ``st`` units) do not count: neighbours that share an
        edge or a vertex touch exactly and are not reported.
    same_chart : only pairs within one chart (connected ``st`` values)

    Returns
    -------
    (k, 2) int64 triangle indices i < j, exact by the separating-axis test on the six edge
    normals (two triangles overlap iff no edge normal separates them by ``eps``).
    """
    t = np.asarray(st, dtype=np.float64)[np.asarray(st_indices, dtype=np.int64).reshape(-1, 3)]
    if not len(t):
        return np.empty((0, 2), dtype=np.int64)
    e1, e2 = t[:, 1] - t[:, 0], t[:, 2] - t[:, 0]
    area = 0.5 * np.abs(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])
    pairs = _candidate_pairs(_min3(*t.transpose(1, 0, 2)), _max3(*t.transpose(1, 0, 2)))
    if same_chart and len(pairs):
        chart = chart_labels(st_indices, len(st))
        pairs = pairs[chart[pairs[:, 0]] == chart[pairs[:, 1]]]
    # a triangle without area covers nothing
    pairs = pairs[(area[pairs[:, 0]] > eps * eps) & (area[pairs[:, 1]] > eps * eps)]
    out = []
    for chunk in np.array_split(pairs, max(1, len(pairs) // 200_000 + 1)):
        a, b = t[chunk[:, 0]], t[chunk[:, 1]]
        ca, cb = a.transpose(1, 0, 2), b.transpose(1, 0, 2)  # corners first
        lo_a, hi_a, lo_b, hi_b = _min3(*ca), _max3(*ca), _min3(*cb), _max3(*cb)
        boxes = np.all((hi_a > lo_b + eps) & (hi_b > lo_a + eps), axis=1)
        a, b, chunk = a[boxes], b[boxes], chunk[boxes]
        overlap = np.ones(len(chunk), dtype=bool)
        # the six edge normals (three of each triangle); projections as plain arithmetic on
        # the (m, 3) coordinate columns (einsum and reductions over a length-3 axis cost
        # several times more at these sizes)
        for tri in (a, b):
            for k in range(3):
                nx = tri[:, k, 1] - tri[:, (k + 1) % 3, 1]
                ny = tri[:, (k + 1) % 3, 0] - tri[:, k, 0]
                length = np.hypot(nx, ny)
                ok = length > 0
                nx, ny = nx / np.where(ok, length, 1.0), ny / np.where(ok, length, 1.0)
                pa = [nx * a[:, c, 0] + ny * a[:, c, 1] for c in range(3)]
                pb = [nx * b[:, c, 0] + ny * b[:, c, 1] for c in range(3)]
                ma, na, mb, nb = _max3(*pa), _min3(*pa), _max3(*pb), _min3(*pb)
                overlap &= ~(ok & ((ma <= nb + eps) | (mb <= na + eps)))
        out.append(chunk[overlap])
    return np.concatenate(out) if out else np.empty((0, 2), dtype=np.int64)


def split_overlapping_charts(
    st: np.ndarray, st_indices: np.ndarray, eps: float
) -> tuple[np.ndarray, np.ndarray, int]:
    """Cut every chart that overlaps itself into pieces that do not.

    Each such chart is regrown piece by piece across its shared ``st`` edges, a triangle
    joining the growing piece only if it overlaps none of the piece's triangles (see
    :func:`overlapping_triangles`); the triangles left start the next pieces. The fold's
    few triangles thus become small charts of their own and the rest stays whole.

    Parameters
    ----------
    st : (u, 2) float
    st_indices : (3 t,) int
    eps : as for :func:`overlapping_triangles`

    Returns
    -------
    (st (u', 2), st_indices (3 t,), the number of charts split). Charts that do not overlap
    keep their values; the values on a new cut are duplicated (one per piece). Unchanged
    input when nothing overlaps.
    """
    st = np.asarray(st)
    sti = np.asarray(st_indices, dtype=np.int64).reshape(-1)
    pairs = overlapping_triangles(st, sti, eps)
    if not len(pairs):
        return st, sti, 0
    tri = sti.reshape(-1, 3)
    chart = chart_labels(sti, len(st))
    conflict: dict[int, set[int]] = {}
    for i, j in pairs.tolist():
        conflict.setdefault(i, set()).add(j)
        conflict.setdefault(j, set()).add(i)
    bad = np.unique(chart[pairs[:, 0]])
    members = np.flatnonzero(np.isin(chart, bad))
    # triangles across each shared st edge (within the charts to split)
    e = np.sort(np.stack([tri[members], np.roll(tri[members], -1, axis=1)], axis=-1), axis=-1)
    key = e[..., 0] * len(st) + e[..., 1]
    owner = np.repeat(members, 3)
    order = np.argsort(key.reshape(-1), kind="stable")
    k, o = key.reshape(-1)[order], owner[order]
    same = np.flatnonzero(k[1:] == k[:-1])
    nbrs: dict[int, list[int]] = {}
    for x, y in zip(o[same].tolist(), o[same + 1].tolist(), strict=True):
        nbrs.setdefault(x, []).append(y)
        nbrs.setdefault(y, []).append(x)
    piece = np.full(len(tri), -1, dtype=np.int64)
    piece[np.isin(chart, bad, invert=True)] = chart[np.isin(chart, bad, invert=True)]
    label = int(chart.max()) + 1
    pc = piece.tolist()
    for seed in members.tolist():
        if pc[seed] >= 0:
            continue
        pc[seed] = label
        todo = [seed]
        while todo:
            f = todo.pop()
            for g in nbrs.get(f, ()):
                if pc[g] < 0 and not any(pc[c] == label for c in conflict.get(g, ())):
                    pc[g] = label
                    todo.append(g)
        label += 1
    piece = np.repeat(np.asarray(pc, dtype=np.int64), 3)
    _, first, inv = np.unique(
        np.stack([piece, sti], axis=1), axis=0, return_index=True, return_inverse=True
    )
    return st[sti[first]], inv.reshape(-1).astype(sti.dtype), len(bad)
