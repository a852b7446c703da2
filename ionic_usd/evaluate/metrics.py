"""Curve similarity measures for comparing reference and generated profiles (paper §VII).

All functions take polylines as ``(n, d)`` float arrays with ``d`` = 2 or 3 (both curves the
same ``d``) and are vectorised (numpy, scipy ``cKDTree``) or compiled with numba.

Naming follows shapely (``hausdorff_distance(a, b, *, densify=None)``,
``frechet_distance``). Each measure is documented as

* *discrete* (only the nodes count) or *continuous* (points on edges count too), and
* *symmetric* or *directed*.

Mapping to the paper (Konečný et al. 2016, Table 6) — the paper's names are not the standard
ones:

* paper's "weak Fréchet distance" = the largest node-to-curve distance in both directions,
  points on edges included: a Hausdorff distance, not a (weak) Fréchet distance (it ignores
  the order along the curves) → :func:`hausdorff_distance` (alias :data:`paper_weak_frechet`);
* paper's "Hausdorff distance" = the same, node to node only → :func:`node_hausdorff_distance`;
* paper's "average error" = the mean of all node-to-curve distances → :func:`average_error`.

The true Fréchet distances are offered too: :func:`discrete_frechet_distance` (Eiter–Mannila)
and :func:`frechet_distance` (continuous, Alt–Godau). For any two polylines
``discrete_frechet >= frechet >= hausdorff_distance``.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np
from numba import njit
from scipy.spatial import cKDTree

from ionic_usd.errors import GeometryError, ParameterError

__all__ = [
    "CurveComparison",
    "average_error",
    "compare",
    "curve_length",
    "densify_curve",
    "directed_hausdorff_distance",
    "discrete_frechet_distance",
    "frechet_distance",
    "hausdorff_distance",
    "node_hausdorff_distance",
    "paper_weak_frechet",
    "point_to_polyline_distances",
    "resample",
]

# Neighbours fetched per query point in the first kd-tree pass; enough for nearly all points
# of resampled curves, the rest are re-queried with more (see _PolylineIndex.distances).
_FIRST_K = 8


# --------------------------------------------------------------------------------------------
# validation and basic geometry
# --------------------------------------------------------------------------------------------
def _as_curve(curve: object, name: str, *, min_nodes: int = 1) -> np.ndarray:
    arr = np.asarray(curve, dtype=np.float64)
    if arr.ndim != 2 or arr.shape[1] not in (2, 3):
        raise ParameterError(name, f"array of shape {arr.shape}", "an (n, 2) or (n, 3) array")
    if arr.shape[0] < min_nodes:
        raise ParameterError(name, f"{arr.shape[0]} nodes", f"at least {min_nodes} nodes")
    if not np.all(np.isfinite(arr)):
        raise ParameterError(name, "non-finite coordinates", "finite coordinates")
    return arr


def _as_pair(a: object, b: object) -> tuple[np.ndarray, np.ndarray]:
    a = _as_curve(a, "a")
    b = _as_curve(b, "b")
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
    c = _as_curve(curve, "curve")
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
    c = _as_curve(curve, "curve", min_nodes=2)
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
    count = max(int(count), 2)
    targets = np.linspace(0.0, total, count)
    # Drop zero-length segments so the arc-length abscissa is strictly increasing.
    keep = np.concatenate(([True], seg > 0.0))
    s, c = s[keep], c[keep]
    out = np.empty((count, c.shape[1]))
    for k in range(c.shape[1]):
        out[:, k] = np.interp(targets, s, c[:, k])
    out[0], out[-1] = c[0], c[-1]
    return out


def densify_curve(curve: np.ndarray, fraction: float) -> np.ndarray:
    """Split every segment into ``round(1 / fraction)`` equal parts (GEOS' ``densify``).

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
    c = _as_curve(curve, "curve")
    if not (math.isfinite(fraction) and 0.0 < fraction <= 1.0):
        raise ParameterError("densify", fraction, "a fraction in (0, 1]")
    k = max(1, int(round(1.0 / fraction)))
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


class _PolylineIndex:
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


@njit(cache=True)
def _closest(points, poly):  # pragma: no cover - compiled
    # exact closest point on the polyline for each point (all segments; fit-sized curves):
    # distance, segment index and parameter t on that segment
    n, m = points.shape[0], poly.shape[0]
    dist = np.empty(n)
    seg = np.zeros(n, dtype=np.int64)
    par = np.zeros(n)
    for i in range(n):
        px, py = points[i, 0], points[i, 1]
        best = np.inf
        for j in range(max(m - 1, 1)):
            ox, oy = poly[j, 0], poly[j, 1]
            vx, vy = 0.0, 0.0
            if m > 1:
                vx, vy = poly[j + 1, 0] - ox, poly[j + 1, 1] - oy
            l2 = vx * vx + vy * vy
            t = ((px - ox) * vx + (py - oy) * vy) / l2 if l2 > 0.0 else 0.0
            t = min(max(t, 0.0), 1.0)
            dx, dy = px - ox - t * vx, py - oy - t * vy
            d2 = dx * dx + dy * dy
            if d2 < best:
                best = d2
                seg[i] = j
                par[i] = t
        dist[i] = math.sqrt(best)
    return dist, seg, par


def point_to_polyline_distances(points: np.ndarray, polyline: np.ndarray) -> np.ndarray:
    """Exact distance from each point to a polyline, points on its edges included.

    Continuous on the polyline's edges; one value per point. Uses a kd-tree over samples on
    the segments with an exact bound (see ``_PolylineIndex``), O((n + m) log m) for
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
    p, c = _as_pair(points, polyline)
    return _PolylineIndex(c).distances(p)


# --------------------------------------------------------------------------------------------
# Hausdorff-type measures
# --------------------------------------------------------------------------------------------
def _maybe_densify(a: np.ndarray, b: np.ndarray, densify: float | None):
    if densify is None:
        return a, b
    return densify_curve(a, densify), densify_curve(b, densify)


def directed_hausdorff_distance(
    a: np.ndarray, b: np.ndarray, *, densify: float | None = None
) -> float:
    """Largest distance from a node of ``a`` to the curve ``b`` (edges of ``b`` included).

    Directed; discrete on ``a`` (its nodes), continuous on ``b``. ``densify`` (a fraction in
    (0, 1], as in shapely/GEOS) first splits every segment of both curves into
    ``round(1 / densify)`` parts, which converges to the fully continuous directed Hausdorff
    distance.

    Parameters
    ----------
    a : (n, d) float
    b : (m, d) float

    Returns
    -------
    float
    """
    a, b = _as_pair(a, b)
    a, b = _maybe_densify(a, b, densify)
    return float(_PolylineIndex(b).distances(a).max())


def hausdorff_distance(a: np.ndarray, b: np.ndarray, *, densify: float | None = None) -> float:
    """Symmetric node-to-curve Hausdorff distance — the paper's "weak Fréchet distance".

    ``max(directed(a, b), directed(b, a))`` where each direction takes the nodes of one curve
    and the closest point of the other curve, points on its edges included (continuous on
    the target, discrete on the source nodes). This is what GEOS' ``hausdorff_distance``
    computes too. The paper calls it "weak Fréchet"; it ignores the order along the curves,
    so it is a Hausdorff distance (a lower bound of the Fréchet distances). ``densify``
    behaves as in :func:`directed_hausdorff_distance`.

    Parameters
    ----------
    a : (n, d) float
    b : (m, d) float

    Returns
    -------
    float
    """
    a, b = _as_pair(a, b)
    a, b = _maybe_densify(a, b, densify)
    da = _PolylineIndex(b).distances(a)
    db = _PolylineIndex(a).distances(b)
    return float(max(da.max(), db.max()))


#: The paper's "weak Fréchet distance" is :func:`hausdorff_distance` (the paper misnames it).
paper_weak_frechet = hausdorff_distance


def node_hausdorff_distance(a: np.ndarray, b: np.ndarray) -> float:
    """Symmetric node-to-node Hausdorff distance — the paper's "Hausdorff distance".

    Discrete on both curves: the largest distance from a node of either curve to the nearest
    *node* of the other (edges ignored). Always >= :func:`hausdorff_distance`.

    Parameters
    ----------
    a : (n, d) float
    b : (m, d) float

    Returns
    -------
    float
    """
    a, b = _as_pair(a, b)
    da, _ = cKDTree(b).query(a)
    db, _ = cKDTree(a).query(b)
    return float(max(da.max(), db.max()))


def average_error(a: np.ndarray, b: np.ndarray) -> float:
    """Mean of all node-to-curve distances — the paper's "average error".

    Symmetric; discrete on the source nodes, continuous on the target curve. The distances
    of the n nodes of ``a`` to curve ``b`` and of the m nodes of ``b`` to curve ``a`` are
    pooled: ``(sum_a + sum_b) / (n + m)``.

    Parameters
    ----------
    a : (n, d) float
    b : (m, d) float

    Returns
    -------
    float
    """
    a, b = _as_pair(a, b)
    da = _PolylineIndex(b).distances(a)
    db = _PolylineIndex(a).distances(b)
    return float((da.sum() + db.sum()) / (da.size + db.size))


# --------------------------------------------------------------------------------------------
# Fréchet distances (numba kernels)
# --------------------------------------------------------------------------------------------
def _xyz(c: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    z = c[:, 2] if c.shape[1] == 3 else np.zeros(c.shape[0])
    return (np.ascontiguousarray(c[:, 0]), np.ascontiguousarray(c[:, 1]), np.ascontiguousarray(z))


@njit(cache=True, fastmath=True)
def _dfd_diagonal_2d(xa, ya, xb, yb, p1, p1b, p2, out):  # pragma: no cover - compiled
    # One anti-diagonal; a separate function over contiguous slices so LLVM vectorises it.
    for t in range(out.size):
        dx = xa[t] - xb[t]
        dy = ya[t] - yb[t]
        out[t] = max(dx * dx + dy * dy, min(min(p1[t], p1b[t]), p2[t]))


@njit(cache=True, fastmath=True)
def _dfd_diagonal_3d(xa, ya, za, xb, yb, zb, p1, p1b, p2, out):  # pragma: no cover - compiled
    for t in range(out.size):
        dx = xa[t] - xb[t]
        dy = ya[t] - yb[t]
        dz = za[t] - zb[t]
        out[t] = max(dx * dx + dy * dy + dz * dz, min(min(p1[t], p1b[t]), p2[t]))


@njit(cache=True, fastmath=True)
def _dfd_squared(ax, ay, az, bx, by, bz, three_d):  # pragma: no cover - compiled
    # Eiter-Mannila DP swept by anti-diagonals k = i + j: the cells of one diagonal are
    # independent, so the inner loop vectorises (a row sweep has a serial min/max chain and
    # runs ~5x slower). Three diagonal buffers indexed by i + 1: slot 0 stays +inf as the
    # i = -1 border, and slots above a diagonal's end are still +inf when read (earlier
    # diagonals in the same buffer ended lower). b is reversed so that both curves are read
    # with increasing indices. Squared distances: max/min commute with the square root.
    n = ax.size
    m = bx.size
    bxr = bx[::-1].copy()
    byr = by[::-1].copy()
    bzr = bz[::-1].copy()
    prev2 = np.full(n + 1, np.inf)
    prev1 = np.full(n + 1, np.inf)
    cur = np.full(n + 1, np.inf)
    prev1[1] = (ax[0] - bx[0]) ** 2 + (ay[0] - by[0]) ** 2 + (az[0] - bz[0]) ** 2
    for k in range(1, n + m - 1):
        lo = max(0, k - m + 1)
        hi = min(k, n - 1) + 1
        jlo = m - 1 - k + lo
        jhi = jlo + hi - lo
        if three_d:
            _dfd_diagonal_3d(
                ax[lo:hi],
                ay[lo:hi],
                az[lo:hi],
                bxr[jlo:jhi],
                byr[jlo:jhi],
                bzr[jlo:jhi],
                prev1[lo:hi],
                prev1[lo + 1 : hi + 1],
                prev2[lo:hi],
                cur[lo + 1 : hi + 1],
            )
        else:
            _dfd_diagonal_2d(
                ax[lo:hi],
                ay[lo:hi],
                bxr[jlo:jhi],
                byr[jlo:jhi],
                prev1[lo:hi],
                prev1[lo + 1 : hi + 1],
                prev2[lo:hi],
                cur[lo + 1 : hi + 1],
            )
        tmp = prev2
        prev2 = prev1
        prev1 = cur
        cur = tmp
    return prev1[n]


def discrete_frechet_distance(
    a: np.ndarray, b: np.ndarray, *, densify: float | None = None
) -> float:
    """Discrete Fréchet distance (Eiter & Mannila 1994), exact.

    Discrete (couplings of nodes only), symmetric, order-aware: curves traversed in opposite
    directions are far apart even if they coincide as point sets. O(n m) time, O(n) memory
    (compiled with numba). ``densify`` as in shapely's ``frechet_distance``; the value
    converges from above to :func:`frechet_distance` as the curves are densified.

    Parameters
    ----------
    a : (n, d) float
    b : (m, d) float

    Returns
    -------
    float
    """
    a, b = _as_pair(a, b)
    a, b = _maybe_densify(a, b, densify)
    return float(math.sqrt(_dfd_squared(*_xyz(a), *_xyz(b), a.shape[1] == 3)))


@njit(cache=True, fastmath=False, inline="always")
def _free_interval(ox, oy, oz, vx, vy, vz, cx, cy, cz, eps2):  # pragma: no cover - compiled
    # Parameters t in [0, 1] with |o + t v - c| <= eps; empty as (1, 0).
    wx = ox - cx
    wy = oy - cy
    wz = oz - cz
    aa = vx * vx + vy * vy + vz * vz
    cc = wx * wx + wy * wy + wz * wz - eps2
    if aa == 0.0:
        if cc <= 0.0:
            return 0.0, 1.0
        return 1.0, 0.0
    t0 = -(vx * wx + vy * wy + vz * wz) / aa
    disc = t0 * t0 - cc / aa
    if disc < 0.0:
        return 1.0, 0.0
    r = math.sqrt(disc)
    lo = max(t0 - r, 0.0)
    hi = min(t0 + r, 1.0)
    if lo > hi:
        return 1.0, 0.0
    return lo, hi


@njit(cache=True, inline="always")
def _free_on_segment(x, y, z, j, cx, cy, cz, eps2):  # pragma: no cover - compiled
    # Free interval on segment j of the polyline (x, y, z) seen from point c.
    return _free_interval(
        x[j], y[j], z[j], x[j + 1] - x[j], y[j + 1] - y[j], z[j + 1] - z[j], cx, cy, cz, eps2
    )


@njit(cache=True)
def _frechet_decide(px, py, pz, qx, qy, qz, eps):  # pragma: no cover - compiled
    # Alt-Godau decision "Fréchet(P, Q) <= eps" on the free-space diagram, swept column by
    # column (column i = segment P_i). Only the rows between the lowest and highest reachable
    # left edge (plus what propagates upward from them) are visited, so near-identical curves
    # cost about O((n + m) * band) instead of O(n m).
    n = px.size
    m = qx.size
    eps2 = eps * eps
    d0 = (px[0] - qx[0]) ** 2 + (py[0] - qy[0]) ** 2 + (pz[0] - qz[0]) ** 2
    d1 = (px[n - 1] - qx[m - 1]) ** 2 + (py[n - 1] - qy[m - 1]) ** 2 + (pz[n - 1] - qz[m - 1]) ** 2
    if d0 > eps2 or d1 > eps2:
        return False
    # Reachable intervals on the left edges x = i of cells (i, j); valid when stamp == i.
    llo = np.empty(m - 1)
    lhi = np.empty(m - 1)
    lstamp = np.full(m - 1, -1)
    nlo = np.empty(m - 1)
    nhi = np.empty(m - 1)
    nstamp = np.full(m - 1, -1)
    # Column x = 0: reachable upward from (0, 0) while the free space is unbroken.
    jmin = -1
    jmax = -1
    for j in range(m - 1):
        lo, hi = _free_on_segment(qx, qy, qz, j, px[0], py[0], pz[0], eps2)
        if lo != 0.0 or lo > hi:
            break
        llo[j] = lo
        lhi[j] = hi
        lstamp[j] = 0
        if jmin < 0:
            jmin = j
        jmax = j
        if hi < 1.0:
            break
    bottom_ok = True  # corner (i, 0) reachable along y = 0
    for i in range(n - 1):
        vx = px[i + 1] - px[i]
        vy = py[i + 1] - py[i]
        vz = pz[i + 1] - pz[i]
        # Reachable part of the bottom edge of cell (i, 0).
        blo, bhi = 1.0, 0.0
        if bottom_ok:
            blo, bhi = _free_interval(px[i], py[i], pz[i], vx, vy, vz, qx[0], qy[0], qz[0], eps2)
            if blo != 0.0:
                blo, bhi = 1.0, 0.0
        bottom_ok = blo <= bhi and bhi >= 1.0
        if blo > bhi:
            if jmin < 0:
                return False
            j = jmin
        else:
            j = 0
        new_min = -1
        new_max = -1
        while j < m - 1:
            has_left = lstamp[j] == i
            has_bottom = blo <= bhi
            if not has_left and not has_bottom:
                if j >= jmax:
                    break
                j += 1
                continue
            # Right edge of cell (i, j): free interval on Q_j seen from p_{i+1}.
            rlo, rhi = _free_on_segment(qx, qy, qz, j, px[i + 1], py[i + 1], pz[i + 1], eps2)
            if not has_bottom:
                rlo = max(rlo, llo[j])
            if rlo <= rhi:
                nlo[j] = rlo
                nhi[j] = rhi
                nstamp[j] = i + 1
                if new_min < 0:
                    new_min = j
                new_max = j
            # Top edge of cell (i, j): free interval on P_i seen from q_{j+1}.
            tlo, thi = _free_interval(
                px[i], py[i], pz[i], vx, vy, vz, qx[j + 1], qy[j + 1], qz[j + 1], eps2
            )
            if not has_left:
                tlo = max(tlo, blo)
            if tlo <= thi:
                blo, bhi = tlo, thi
            else:
                blo, bhi = 1.0, 0.0
            j += 1
        if i == n - 2:
            # End corner (n-1, m-1): top of the last cell or right edge of the last cell.
            if j == m - 1 and blo <= bhi and bhi >= 1.0:
                return True
            return nstamp[m - 2] == i + 1 and nhi[m - 2] >= 1.0
        llo, nlo = nlo, llo
        lhi, nhi = nhi, lhi
        lstamp, nstamp = nstamp, lstamp
        jmin = new_min
        jmax = new_max
        if jmin < 0 and not bottom_ok:
            return False
    return False


def frechet_distance(a: np.ndarray, b: np.ndarray, *, tol: float = 1e-7) -> float:
    """Continuous Fréchet distance (Alt & Godau 1995) to a relative tolerance.

    Continuous (all points on the edges), symmetric, order-aware. The Alt–Godau free-space
    decision (numba, visiting only the reachable band of the diagram) is bisected on ε
    between the lower bound ``max(endpoint distances, hausdorff_distance(a, b))`` and the
    upper bound ``discrete_frechet_distance(a, b)``.

    Parameters
    ----------
    a : (n, d) float
    b : (m, d) float
    tol : float
        Relative tolerance: the result ``r`` satisfies ``F <= r <= F (1 + tol)`` (up to
        floating-point rounding in the decision), where ``F`` is the exact distance.

    Returns
    -------
    float
    """
    a, b = _as_pair(a, b)
    if not (math.isfinite(tol) and 0.0 < tol < 1.0):
        raise ParameterError("tol", tol, "a relative tolerance in (0, 1)")
    return _frechet_search(a, b, discrete_frechet_distance(a, b), None, tol)


def _frechet_search(
    a: np.ndarray, b: np.ndarray, hi: float, haus: float | None, tol: float
) -> float:
    if a.shape[0] == 1 or b.shape[0] == 1 or hi == 0.0:
        # A point against a curve: the farthest node decides (distance to a point is convex
        # along a segment), so discrete and continuous agree.
        return hi
    if haus is None:
        haus = hausdorff_distance(a, b)
    lo = max(
        haus,
        float(np.linalg.norm(a[0] - b[0])),
        float(np.linalg.norm(a[-1] - b[-1])),
    )
    pa, pb = _xyz(a), _xyz(b)
    if _frechet_decide(*pa, *pb, lo):
        return lo
    # Often the discrete bound is already exact (a node-node coupling is the bottleneck);
    # one decision just below it then settles the search.
    probe = hi / (1.0 + tol)
    if probe > lo and not _frechet_decide(*pa, *pb, probe):
        return hi
    while hi - lo > tol * hi:
        mid = 0.5 * (lo + hi)
        if _frechet_decide(*pa, *pb, mid):
            hi = mid
        else:
            lo = mid
    return hi


# --------------------------------------------------------------------------------------------
# the bundle (paper Table 6)
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class CurveComparison:
    """All measures between two curves, as in the paper's Table 6 plus true Fréchet.

    Distances are in the curves' units (metres in this package); ``*_pct`` properties are
    percentages of ``mean_length``, as in the paper.

    Attributes
    ----------
    nodes_a, nodes_b : int
    length_a, length_b, mean_length : float
    hausdorff : float
        Node-to-curve, symmetric — the paper's "weak Fréchet".
    node_hausdorff : float
        Node-to-node, symmetric — the paper's "Hausdorff".
    average_error : float
        Mean node-to-curve distance, both directions pooled.
    discrete_frechet, frechet : float
        Discrete and continuous Fréchet distances.
    """

    nodes_a: int
    nodes_b: int
    length_a: float
    length_b: float
    mean_length: float
    hausdorff: float
    node_hausdorff: float
    average_error: float
    discrete_frechet: float
    frechet: float

    _MEASURES = ("hausdorff", "node_hausdorff", "average_error", "discrete_frechet", "frechet")

    def __post_init__(self) -> None:
        for name in ("nodes_a", "nodes_b"):
            value = getattr(self, name)
            if int(value) != value or value < 1:
                raise ParameterError(name, value, "an integer >= 1")
        for name in ("length_a", "length_b", "mean_length", *self._MEASURES):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0.0):
                raise ParameterError(name, value, "a finite number >= 0")

    def percent(self, measure: str) -> float:
        """``measure`` as a percentage of the mean curve length (NaN if that is 0)."""
        if measure not in self._MEASURES:
            raise ParameterError("measure", measure, f"one of {', '.join(self._MEASURES)}")
        if self.mean_length == 0.0:
            return math.nan
        return 100.0 * getattr(self, measure) / self.mean_length

    @property
    def hausdorff_pct(self) -> float:
        return self.percent("hausdorff")

    @property
    def node_hausdorff_pct(self) -> float:
        return self.percent("node_hausdorff")

    @property
    def average_error_pct(self) -> float:
        return self.percent("average_error")

    @property
    def discrete_frechet_pct(self) -> float:
        return self.percent("discrete_frechet")

    @property
    def frechet_pct(self) -> float:
        return self.percent("frechet")

    def as_dict(self) -> dict[str, float | int]:
        """Plain JSON-ready dict: the fields plus ``<measure>_pct`` for each measure."""
        out: dict[str, float | int] = asdict(self)
        for name in self._MEASURES:
            pct = self.percent(name)
            out[f"{name}_pct"] = None if math.isnan(pct) else pct  # type: ignore[assignment]
        return out


def compare(
    a: np.ndarray, b: np.ndarray, *, spacing: float | None = None, tol: float = 1e-7
) -> CurveComparison:
    """Compute every measure between two curves.

    Parameters
    ----------
    a, b : (n, d), (m, d) float
        E.g. reference and generated curve.
    spacing : float, optional
        If given, both curves are first :func:`resample`-d to this node spacing (the paper
        uses the same constant spacing for all curves).
    tol : float
        Relative tolerance of the continuous Fréchet distance.

    Returns
    -------
    CurveComparison
    """
    a, b = _as_pair(a, b)
    if spacing is not None:
        a = resample(a, spacing=spacing)
        b = resample(b, spacing=spacing)
    ia, ib = _PolylineIndex(a), _PolylineIndex(b)
    da = ia.distances(b)  # nodes of b to curve a
    db = ib.distances(a)  # nodes of a to curve b
    haus = float(max(da.max(), db.max()))
    nd_a, _ = cKDTree(b).query(a)
    nd_b, _ = cKDTree(a).query(b)
    la, lb = curve_length(a), curve_length(b)
    if not (math.isfinite(tol) and 0.0 < tol < 1.0):
        raise ParameterError("tol", tol, "a relative tolerance in (0, 1)")
    dfd = discrete_frechet_distance(a, b)
    return CurveComparison(
        nodes_a=int(a.shape[0]),
        nodes_b=int(b.shape[0]),
        length_a=la,
        length_b=lb,
        mean_length=0.5 * (la + lb),
        hausdorff=haus,
        node_hausdorff=float(max(nd_a.max(), nd_b.max())),
        average_error=float((da.sum() + db.sum()) / (da.size + db.size)),
        discrete_frechet=dfd,
        frechet=_frechet_search(a, b, dfd, haus, tol),
    )
