"""Fréchet distances between polylines: discrete (Eiter–Mannila) and continuous (Alt–Godau).

Compiled kernels (numba) over the free-space diagram; the measures and their mapping to the
paper are in :mod:`ionic_usd.evaluate.metrics`. For any two polylines
``discrete_frechet >= frechet >= hausdorff_distance``.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ionic_usd.errors import ParameterError
from ionic_usd.evaluate.polyline import as_curve_pair, densify_pair, two_way_distances

__all__ = ["discrete_frechet_distance", "frechet_bisect", "frechet_distance"]


# No fastmath: it lets LLVM contract a * b + c into a fused multiply-add and reassociate sums,
# which CPUs with and without FMA round differently, and assumes no infinities, which the
# diagonal borders are. Plain IEEE arithmetic gives the same distance on every CPU (5 % slower
# on 5,000-point walks than fastmath=True).


# --------------------------------------------------------------------------------------------
# Fréchet distances (numba kernels)
# --------------------------------------------------------------------------------------------
def _xyz(c: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    z = c[:, 2] if c.shape[1] == 3 else np.zeros(c.shape[0])
    return (np.ascontiguousarray(c[:, 0]), np.ascontiguousarray(c[:, 1]), np.ascontiguousarray(z))


@njit(cache=True)
def _dfd_diagonal_2d(xa, ya, xb, yb, p1, p1b, p2, out):  # pragma: no cover - compiled
    # One anti-diagonal; a separate function over contiguous slices so LLVM vectorises it.
    for t in range(out.size):
        dx = xa[t] - xb[t]
        dy = ya[t] - yb[t]
        out[t] = max(dx * dx + dy * dy, min(min(p1[t], p1b[t]), p2[t]))


@njit(cache=True)
def _dfd_diagonal_3d(xa, ya, za, xb, yb, zb, p1, p1b, p2, out):  # pragma: no cover - compiled
    for t in range(out.size):
        dx = xa[t] - xb[t]
        dy = ya[t] - yb[t]
        dz = za[t] - zb[t]
        out[t] = max(dx * dx + dy * dy + dz * dz, min(min(p1[t], p1b[t]), p2[t]))


@njit(cache=True)
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
    a, b = as_curve_pair(a, b)
    a, b = densify_pair(a, b, densify)
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


@njit(cache=True, inline="always")
def _first_column(px, py, pz, qx, qy, qz, eps2, llo, lhi, lstamp):  # pragma: no cover - compiled
    """Column x = 0: the left edges reachable upward from (0, 0) while the free space is
    unbroken, written into ``llo``, ``lhi``, ``lstamp``; returns their rows (jmin, jmax),
    -1 where none."""
    m = qx.size
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
    return jmin, jmax


@njit(cache=True, inline="always")
def _sweep_column(p, q, eps2, i, j, jmax, blo, bhi, left, right):  # pragma: no cover - compiled
    """One column of cells (i, j) from row ``j`` up: the reachable right edges written into
    ``right`` (lo, hi, stamp = i + 1) from the reachable left edges ``left`` and the bottom
    interval (blo, bhi). Returns (the row it stopped at, the last top edge's interval, the
    lowest and highest reachable right edge, -1 where none). ``p``, ``q``: the curves'
    coordinate arrays (x, y, z)."""
    px, py, pz = p
    qx, qy, qz = q
    llo, lhi, lstamp = left
    nlo, nhi, nstamp = right
    m = qx.size
    vx = px[i + 1] - px[i]
    vy = py[i + 1] - py[i]
    vz = pz[i + 1] - pz[i]
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
    return j, blo, bhi, new_min, new_max


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
    left, right = (llo, lhi, lstamp), (nlo, nhi, nstamp)
    jmin, jmax = _first_column(px, py, pz, qx, qy, qz, eps2, llo, lhi, lstamp)
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
        j, blo, bhi, new_min, new_max = _sweep_column(
            (px, py, pz), (qx, qy, qz), eps2, i, j, jmax, blo, bhi, left, right
        )
        if i == n - 2:
            # End corner (n-1, m-1): top of the last cell or right edge of the last cell.
            if j == m - 1 and blo <= bhi and bhi >= 1.0:
                return True
            return right[2][m - 2] == i + 1 and right[1][m - 2] >= 1.0
        left, right = right, left
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
    a, b = as_curve_pair(a, b)
    if not (math.isfinite(tol) and 0.0 < tol < 1.0):
        raise ParameterError("tol", tol, "a relative tolerance in (0, 1)")
    return frechet_bisect(a, b, discrete_frechet_distance(a, b), None, tol)


def frechet_bisect(
    a: np.ndarray, b: np.ndarray, hi: float, haus: float | None, tol: float
) -> float:
    if a.shape[0] == 1 or b.shape[0] == 1 or hi == 0.0:
        # A point against a curve: the farthest node decides (distance to a point is convex
        # along a segment), so discrete and continuous agree.
        return hi
    if haus is None:
        haus = float(max(d.max() for d in two_way_distances(a, b)))
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
