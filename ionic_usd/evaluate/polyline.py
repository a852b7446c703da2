"""Polylines: validation, arc length, resampling and exact node-to-curve distances.

The kernels every curve measure and fit shares (:mod:`ionic_usd.evaluate.metrics`,
:mod:`ionic_usd.evaluate.frechet`, the fits). Curves are ``(n, d)`` float arrays with ``d`` = 2
or 3; distances are exact (points on edges count), kd-tree accelerated (scipy) for the
measures and grid accelerated for the fits' closest points, compiled (numba).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit
from scipy.spatial import cKDTree

from ionic_usd.errors import GeometryError, ParameterError
from ionic_usd.geometry.curves import resample_polyline

__all__ = [
    "PolylineIndex",
    "as_curve",
    "as_curve_pair",
    "closest_on_polyline",
    "curve_length",
    "densify_curve",
    "densify_pair",
    "point_to_polyline_distances",
    "resample",
    "two_way_distances",
]

# Neighbours fetched per query point in the first kd-tree pass; enough for nearly all points
# of resampled curves, the rest are re-queried with more (see PolylineIndex.distances).
_FIRST_K = 8


# --------------------------------------------------------------------------------------------
# validation and basic geometry
# --------------------------------------------------------------------------------------------
def as_curve(curve: object, name: str, *, min_nodes: int = 1) -> np.ndarray:
    arr = np.asarray(curve, dtype=np.float64)
    if arr.ndim != 2 or arr.shape[1] not in (2, 3):
        raise ParameterError(name, f"array of shape {arr.shape}", "an (n, 2) or (n, 3) array")
    if arr.shape[0] < min_nodes:
        raise ParameterError(name, f"{arr.shape[0]} nodes", f"at least {min_nodes} nodes")
    if not np.all(np.isfinite(arr)):
        raise ParameterError(name, "non-finite coordinates", "finite coordinates")
    return arr


def as_curve_pair(a: object, b: object) -> tuple[np.ndarray, np.ndarray]:
    a = as_curve(a, "a")
    b = as_curve(b, "b")
    if a.shape[1] != b.shape[1]:
        raise ParameterError("b", f"dimension {b.shape[1]}", f"the dimension of a ({a.shape[1]})")
    return a, b


def curve_length(curve: np.ndarray) -> float:
    """Arc length of a polyline.

    Parameters
    ----------
    curve : (n, d) float

    Returns
    -------
    float
        Sum of the segment lengths (0 for a single node).
    """
    c = as_curve(curve, "curve")
    return float(np.linalg.norm(np.diff(c, axis=0), axis=1).sum())


def resample(
    curve: np.ndarray, *, spacing: float | None = None, count: int | None = None
) -> np.ndarray:
    """Resample a polyline to nodes at constant spacing along its arc length.

    Give exactly one of ``spacing`` and ``count``. With ``spacing`` the node count is the
    smallest one whose spacing does not exceed it, ``ceil(L / spacing) + 1``; the actual
    spacing is then ``L / (count - 1)``. Both endpoints are kept. Spacing is measured along
    the input polyline (arc length), so chords across corners are slightly shorter.

    Parameters
    ----------
    curve : (n, d) float
        At least two nodes and non-zero length.
    spacing : float, optional
        Wanted arc length between adjacent nodes, > 0.
    count : int, optional
        Number of output nodes, >= 2.

    Returns
    -------
    (m, d) float
    """
    c = as_curve(curve, "curve", min_nodes=2)
    if (spacing is None) == (count is None):
        raise ParameterError("spacing/count", (spacing, count), "exactly one of them given")
    seg = np.linalg.norm(np.diff(c, axis=0), axis=1)
    s = np.concatenate(([0.0], np.cumsum(seg)))
    total = s[-1]
    if not total > 0.0:
        raise GeometryError("cannot resample a curve of zero length")
    if spacing is not None:
        if not (math.isfinite(spacing) and spacing > 0.0):
            raise ParameterError("spacing", spacing, "a finite number > 0")
        # The tiny slack keeps L = k * spacing exactly at k segments despite rounding.
        count = int(math.ceil(total / spacing * (1.0 - 1e-12))) + 1
    assert count is not None
    if int(count) != count or count < 2:
        raise ParameterError("count", count, "an integer >= 2")
    # the interpolation itself is the geometry kernel's one resampler
    return resample_polyline(c, count=int(count))


def densify_curve(curve: np.ndarray, fraction: float) -> np.ndarray:
    """Split every segment into ``1 / fraction`` equal parts rounded as GEOS rounds (a half
    up: ``floor(1 / fraction + 0.5)``), so node counts equal GEOS' ``densify`` at ties.

    Parameters
    ----------
    curve : (n, d) float
    fraction : float
        In (0, 1].

    Returns
    -------
    (k (n - 1) + 1, d) float
        Same geometry, more nodes.
    """
    c = as_curve(curve, "curve")
    if not (math.isfinite(fraction) and 0.0 < fraction <= 1.0):
        raise ParameterError("densify", fraction, "a fraction in (0, 1]")
    # GEOS' util::round (JTS: Math.round): a half rounds up, where
    # Python's round() goes to even — 1 / 0.4 = 2.5 is 3 parts in GEOS, 2 in round()
    k = max(1, int(math.floor(1.0 / fraction + 0.5)))
    if k == 1 or c.shape[0] < 2:
        return c
    t = np.arange(k) / k
    seg = c[:-1, None, :] + t[None, :, None] * (c[1:] - c[:-1])[:, None, :]
    return np.concatenate((seg.reshape(-1, c.shape[1]), c[-1:]))


# --------------------------------------------------------------------------------------------
# node-to-curve distances (exact, kd-tree accelerated)
# --------------------------------------------------------------------------------------------
@njit(cache=True)
def _min_segment_distance(points, segs, origin, vec, len2):  # pragma: no cover - compiled
    # For each point i, the exact distance to the nearest of the segments segs[i, :].
    n, k = segs.shape
    d = points.shape[1]
    out = np.empty(n)
    for i in range(n):
        best = np.inf
        for c in range(k):
            s = segs[i, c]
            dot = 0.0
            for e in range(d):
                dot += (points[i, e] - origin[s, e]) * vec[s, e]
            t = dot / len2[s] if len2[s] > 0.0 else 0.0
            t = min(max(t, 0.0), 1.0)
            acc = 0.0
            for e in range(d):
                w = points[i, e] - origin[s, e] - t * vec[s, e]
                acc += w * w
            best = min(best, acc)
        out[i] = math.sqrt(best)
    return out


class PolylineIndex:
    """Exact nearest-point-on-polyline queries.

    The index holds sample points on the segments: segment ``j`` of length ``L_j`` gets
    ``k_j = ceil(L_j / h)`` samples at the midpoints of ``k_j`` equal pieces, so every point of
    the segment is within ``r = max_j L_j / (2 k_j) <= h / 2`` of a sample *tagged with that
    segment*. If ``D`` is the exact distance from a query ``p`` to some examined segments,
    the closest polyline point ``q*`` (distance ``d* <= D``) has a sample within
    ``d* + r <= D + r`` of ``p``. So when the k-th nearest sample is farther than ``D + r``,
    the segment of ``q*`` was among the examined ones and ``D = d*`` exactly; otherwise
    the query is repeated with a larger k.
    """

    def __init__(self, polyline: np.ndarray) -> None:
        self.nodes = polyline
        m = polyline.shape[0]
        if m == 1:
            self.origin = polyline
            self.vec = np.zeros_like(polyline)
            self.len2 = np.zeros(1)
            self.seg_id = np.zeros(1, dtype=np.intp)
            self.slack = 0.0
            self.tree = cKDTree(polyline)
            return
        self.origin = polyline[:-1]
        self.vec = polyline[1:] - polyline[:-1]
        self.len2 = np.einsum("ij,ij->i", self.vec, self.vec)
        length = np.sqrt(self.len2)
        positive = length[length > 0.0]
        h = float(positive.mean()) if positive.size else 1.0
        per_seg = np.maximum(1, np.ceil(length / h).astype(np.intp))
        self.seg_id = np.repeat(np.arange(m - 1), per_seg)
        start = np.repeat(np.cumsum(per_seg) - per_seg, per_seg)
        t = (np.arange(self.seg_id.size) - start + 0.5) / per_seg[self.seg_id]
        samples = self.origin[self.seg_id] + t[:, None] * self.vec[self.seg_id]
        self.slack = float((length / per_seg).max()) * 0.5
        self.tree = cKDTree(samples)

    def distances(self, points: np.ndarray) -> np.ndarray:
        n_samples = self.tree.n
        out = np.empty(points.shape[0])
        todo = np.arange(points.shape[0])
        k = min(_FIRST_K, n_samples)
        while todo.size:
            dist, idx = self.tree.query(points[todo], k=k)
            if k == 1:
                dist, idx = dist[:, None], idx[:, None]
            best = _min_segment_distance(
                points[todo], self.seg_id[idx], self.origin, self.vec, self.len2
            )
            if k >= n_samples:
                done = np.ones(todo.size, dtype=bool)
            else:
                done = dist[:, -1] > best + self.slack
            out[todo[done]] = best[done]
            todo = todo[~done]
            k = min(4 * k, n_samples)
        return out


@njit(cache=True, inline="always")
def _segment_d2(px, py, poly, j, m):  # pragma: no cover - compiled
    """(squared distance, parameter t) from (px, py) to segment j of ``poly`` (m nodes; a
    single node when m == 1): the one formula both kernels use, so their values agree bit
    for bit."""
    ox, oy = poly[j, 0], poly[j, 1]
    vx, vy = 0.0, 0.0
    if m > 1:
        vx, vy = poly[j + 1, 0] - ox, poly[j + 1, 1] - oy
    l2 = vx * vx + vy * vy
    t = ((px - ox) * vx + (py - oy) * vy) / l2 if l2 > 0.0 else 0.0
    t = min(max(t, 0.0), 1.0)
    dx, dy = px - ox - t * vx, py - oy - t * vy
    return dx * dx + dy * dy, t


@njit(cache=True)
def _closest_brute(points, poly):  # pragma: no cover - compiled
    """:func:`closest_on_polyline` by trying every segment for every point (the reference the
    grid kernel is tested against, and its path for small or degenerate inputs)."""
    n, m = points.shape[0], poly.shape[0]
    dist = np.empty(n)
    seg = np.zeros(n, dtype=np.int64)
    par = np.zeros(n)
    for i in range(n):
        best = np.inf
        for j in range(max(m - 1, 1)):
            d2, t = _segment_d2(points[i, 0], points[i, 1], poly, j, m)
            if d2 < best:
                best = d2
                seg[i] = j
                par[i] = t
        dist[i] = math.sqrt(best)
    return dist, seg, par


@njit(cache=True)
def _segment_grid(poly, cs, nx, ny, x0, y0):  # pragma: no cover - compiled
    """Segments binned by their bounding boxes into an nx × ny grid of cells of side cs
    (CSR: the segments of cell c are items[start[c]:start[c + 1]])."""
    ns = poly.shape[0] - 1
    lo = np.empty((ns, 2), dtype=np.int64)
    hi = np.empty((ns, 2), dtype=np.int64)
    count = np.zeros(nx * ny + 1, dtype=np.int64)
    for j in range(ns):
        for e in range(2):
            o, nn = (x0, nx) if e == 0 else (y0, ny)
            a = (min(poly[j, e], poly[j + 1, e]) - o) / cs
            b = (max(poly[j, e], poly[j + 1, e]) - o) / cs
            lo[j, e] = min(max(int(math.floor(a)), 0), nn - 1)
            hi[j, e] = min(max(int(math.floor(b)), 0), nn - 1)
        for cj in range(lo[j, 1], hi[j, 1] + 1):
            for ci in range(lo[j, 0], hi[j, 0] + 1):
                count[cj * nx + ci + 1] += 1
    start = np.cumsum(count)
    fill = start[:-1].copy()
    items = np.empty(start[-1], dtype=np.int64)
    for j in range(ns):
        for cj in range(lo[j, 1], hi[j, 1] + 1):
            for ci in range(lo[j, 0], hi[j, 0] + 1):
                items[fill[cj * nx + ci]] = j
                fill[cj * nx + ci] += 1
    return start, items


@njit(cache=True, inline="always")
def _grid_box(points, poly):  # pragma: no cover - compiled
    """(use the grid, cell size, x0, y0, x1, y1) for :func:`closest_on_polyline`: the
    polyline's box and cells about four segments long; False where every segment is tried
    instead (small, degenerate or non-finite inputs, long segments listed in too many
    cells)."""
    n, m = points.shape[0], poly.shape[0]
    ns = m - 1
    finite = True
    for i in range(n):
        finite = finite and math.isfinite(points[i, 0]) and math.isfinite(points[i, 1])
    x0, y0, x1, y1, total = np.inf, np.inf, -np.inf, -np.inf, 0.0
    for j in range(m):
        finite = finite and math.isfinite(poly[j, 0]) and math.isfinite(poly[j, 1])
        x0, x1 = min(x0, poly[j, 0]), max(x1, poly[j, 0])
        y0, y1 = min(y0, poly[j, 1]), max(y1, poly[j, 1])
        if j:
            total += math.hypot(poly[j, 0] - poly[j - 1, 0], poly[j, 1] - poly[j - 1, 1])
    if not finite or ns < 32 or n * ns < 20_000 or total <= 0.0:
        return False, 0.0, x0, y0, x1, y1
    cs = max(4.0 * total / ns, 1e-9 * max(x1 - x0, y1 - y0))
    cells = (math.floor((x1 - x0) / cs) + 1) * (math.floor((y1 - y0) / cs) + 1)
    if cells > 4 * ns:  # a sparse curve in a large box: coarser cells
        cs *= math.sqrt(cells / (4.0 * ns))
    # listings per segment: its bounding box's cells (long diagonal segments list many)
    listed = 0.0
    for j in range(ns):
        listed += (math.floor(abs(poly[j + 1, 0] - poly[j, 0]) / cs) + 2) * (
            math.floor(abs(poly[j + 1, 1] - poly[j, 1]) / cs) + 2
        )
    return listed <= 64.0 * ns, cs, x0, y0, x1, y1


@njit(cache=True, inline="always")
def _ring_search(i, px, py, fx, fy, poly, grid, stamp, scale):  # pragma: no cover - compiled
    """(squared distance, segment, t) of point ``i`` at (px, py), cell coordinates (fx, fy):
    the rings of cells round its own, nearest first, until the closest segment found is
    nearer than any cell not yet searched (the searched block's edge, less a rounding
    margin). ``grid``: (start, items, nx, ny, cs), the cells' segments
    (:func:`_segment_grid`); ``stamp`` marks the segments tried for this point."""
    start, items, nx, ny, cs = grid
    m = poly.shape[0]
    ci, cj = int(math.floor(fx)), int(math.floor(fy))
    k = max(0, ci - (nx - 1), -ci, cj - (ny - 1), -cj)  # the first ring on the grid
    best, bj, bt = np.inf, m - 1, 0.0
    while True:
        for gj in range(max(cj - k, 0), min(cj + k, ny - 1) + 1):
            edge_row = gj == cj - k or gj == cj + k
            gi = max(ci - k, 0)
            last = min(ci + k, nx - 1)
            while gi <= last:
                if edge_row or gi == ci - k or gi == ci + k:
                    c = gj * nx + gi
                    for q in range(start[c], start[c + 1]):
                        j = items[q]
                        if stamp[j] == i:
                            continue
                        stamp[j] = i
                        d2, t = _segment_d2(px, py, poly, j, m)
                        if d2 < best or (d2 == best and j < bj):
                            best, bj, bt = d2, j, t
                if edge_row or gi >= ci + k:
                    gi += 1
                else:
                    gi = max(gi + 1, ci + k)  # inner rows: the ring's two ends only
        if ci - k <= 0 and ci + k >= nx - 1 and cj - k <= 0 and cj + k >= ny - 1:
            break  # every cell searched
        # any segment not yet tried lies outside the block of rings 0..k round the point
        lb = min(fx - (ci - k), ci + k + 1 - fx, fy - (cj - k), cj + k + 1 - fy) * cs
        lb -= 1e-9 * cs + 1e-13 * (scale + abs(px) + abs(py))
        if lb > 0.0 and best < lb * lb:
            break
        k += 1
    return best, bj, bt


@njit(cache=True)
def closest_on_polyline(points, poly):  # pragma: no cover - compiled
    """Exact closest point of a 2-D polyline ``poly`` (m, 2) for each of ``points`` (n, 2):
    distances (n,), segment indices (n,) int and parameters t (n,) on those segments — the
    values of trying every segment (of equally close segments, the first), found through a
    grid of cells about four segments long.

    Each point searches the rings of cells round its own, nearest first, and stops once the
    closest segment found is nearer than any cell not yet searched (the distance to the
    searched block's edge, less a rounding margin): exact, and for points near the curve a
    few dozen segments instead of all m. Small, degenerate or non-finite inputs, grids that
    would list long segments in too many cells, and points very far out use every segment.
    """
    n, m = points.shape[0], poly.shape[0]
    ns = m - 1
    ok, cs, x0, y0, x1, y1 = _grid_box(points, poly)
    if not ok:
        return _closest_brute(points, poly)
    nx = int(math.floor((x1 - x0) / cs)) + 1
    ny = int(math.floor((y1 - y0) / cs)) + 1
    start, items = _segment_grid(poly, cs, nx, ny, x0, y0)
    grid = (start, items, nx, ny, cs)
    stamp = np.full(ns, -1, dtype=np.int64)
    dist = np.empty(n)
    seg = np.zeros(n, dtype=np.int64)
    par = np.zeros(n)
    reach = 1e6 + nx + ny  # points farther out (in cells) try every segment
    # the rounding of a distance is a few ulps of the coordinates: far less than this margin
    scale = max(abs(x0), abs(x1), abs(y0), abs(y1))
    for i in range(n):
        px, py = points[i, 0], points[i, 1]
        fx, fy = (px - x0) / cs, (py - y0) / cs
        if abs(fx) > reach or abs(fy) > reach:
            d, s, t = _closest_brute(points[i : i + 1], poly)
            dist[i], seg[i], par[i] = d[0], s[0], t[0]
            continue
        best, bj, bt = _ring_search(i, px, py, fx, fy, poly, grid, stamp, scale)
        dist[i], seg[i], par[i] = math.sqrt(best), bj, bt
    return dist, seg, par


def point_to_polyline_distances(points: np.ndarray, polyline: np.ndarray) -> np.ndarray:
    """Exact distance from each point to a polyline, points on its edges included.

    Continuous on the polyline's edges; one value per point. Uses a kd-tree over samples on
    the segments with an exact bound (see ``PolylineIndex``), O((n + m) log m) for
    resampled curves instead of the dense n x m segment matrix.

    Parameters
    ----------
    points : (n, d) float
    polyline : (m, d) float
        m >= 1 (a single node is a point).

    Returns
    -------
    (n,) float
    """
    p, c = as_curve_pair(points, polyline)
    return PolylineIndex(c).distances(p)


def densify_pair(
    a: np.ndarray, b: np.ndarray, densify: float | None
) -> tuple[np.ndarray, np.ndarray]:
    """Both curves through :func:`densify_curve` (unchanged when ``densify`` is None)."""
    if densify is None:
        return a, b
    return densify_curve(a, densify), densify_curve(b, densify)


def two_way_distances(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Node-to-curve distances both ways: ``(nodes of a to curve b, nodes of b to curve a)``.

    Parameters
    ----------
    a, b : (n, d), (m, d) float

    Returns
    -------
    (n,) float, (m,) float
    """
    a, b = as_curve_pair(a, b)
    return PolylineIndex(b).distances(a), PolylineIndex(a).distances(b)
