"""The shaft's surface attributes: analytic ``st`` charts and the fluted grid's normals.

Split from :mod:`ionic_usd.column.shaft` (which lays out the rows and stitches the bands);
both functions work on the layout :func:`ionic_usd.column.shaft.build_shaft` makes: four plain
rows, then the fluted rows (``N`` vertices each), then the two cap centres, and triangles with
the fluted grid's quads first (two per quad, row by row), then the bands, then the caps.
"""

from __future__ import annotations

import numpy as np

from ionic_usd.geometry import libm

__all__ = ["shaft_st", "grid_normals"]


def _norm3(a: np.ndarray) -> np.ndarray:
    """``|a|`` over the last axis of ``(..., 3)``, summed x² + y² + z² in that order.

    The same sums in the same order as ``np.linalg.norm(a, axis=-1)`` (bit for bit), without
    its strided reduction.
    """
    x, y, z = a[..., 0], a[..., 1], a[..., 2]
    return np.sqrt(x * x + y * y + z * z)


def shaft_st(
    points: np.ndarray,
    tri: np.ndarray,
    n_lateral: int,
    n_grid: int,
    flutes: int,
    flute_slices: int,
    perimeter: float,
    starts: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """Analytic texture coordinates in metres: the unrolled side and two planar caps.

    Side (triangles ``[:n_lateral]``): t = y (the taper's slope changes arc length by
    < 0.01 %), s = arc length around the full-flute cross-section at the mean radius
    (``perimeter``, that cross-section's length), the same s for a column of vertices on every
    row, so flute edges run straight up the chart. Plain-ring vertices (at other angles) take s
    from their angle through the same arc-length function. The seam (s = 0 and s = perimeter)
    lies on a fillet at angle 0; triangles across it use a second value of their low-s
    corners. Caps: (x, z) below and (x, −z) above, exact and wound like their faces (so is the
    side: s grows with the angle about +Y). Distortion: the side's s-scale is the reference
    row's, so a ring at radius r is stretched by (reference arc length)/(2π r) and a flute end
    is compressed where its flute narrows.

    Parameters
    ----------
    points : (n, 3) float, the last two the cap centres
    tri : (t, 3) int32, the ``n_grid`` grid triangles first, lateral ones before ``n_lateral``
    starts : (5,) int, where the four plain rows start and the fluted rows begin

    Returns
    -------
    st : (w, 2) float32 metres, one value per chart vertex: every value is used (or belongs
        to a point no triangle uses) and no two of one chart are equal
        (:attr:`ionic_usd.geometry.corners.CornerValues.distinct`)
    st_indices : (3 t,) int32
    """
    n_side = len(points) - 2  # the cap centres are on no side triangle: no side value
    s = _side_s(points, flutes, flute_slices, perimeter, starts)
    half = 0.5 * perimeter
    n = int(starts[2] - starts[1])
    wraps = _seam_triangles(s, int(starts[4]), tri, n_grid, n_lateral, n, half)
    sub = tri[wraps]
    low_c = s[sub] < half
    dup_v = np.unique(sub[low_c])
    dup_of = np.zeros(n_side, dtype=np.int32)
    dup_of[dup_v] = n_side + np.arange(len(dup_v), dtype=np.int32)
    st_idx = tri.astype(np.int32, copy=True)  # side corners: their point's value
    st_idx[wraps] = np.where(low_c, dup_of[sub], sub)
    side = np.empty((n_side, 2), dtype=np.float32)
    side[:, 0] = s
    side[:, 1] = points[:n_side, 1]
    values = [side, (np.stack([s[dup_v] + perimeter, points[dup_v, 1]], axis=1))]
    base = n_side + len(dup_v)
    caps = tri[n_lateral:]
    for k, sign in ((0, 1.0), (3, -1.0)):  # caps: bottom ring row 0, top ring row 3
        sel = np.all(np.abs(points[caps, 1] - points[starts[k], 1]) < 1e-12, axis=1)
        if not sel.any():
            continue
        v = np.unique(caps[sel])
        values.append(np.stack([points[v, 0], sign * points[v, 2]], axis=1))
        st_idx[n_lateral + np.flatnonzero(sel)] = base + np.searchsorted(v, caps[sel])
        base += len(v)
    out = np.concatenate([a.astype(np.float32, copy=False) for a in values])
    return out, st_idx.reshape(-1)


def _side_s(points: np.ndarray, e: int, h: int, perimeter: float, starts: np.ndarray) -> np.ndarray:
    """s (metres, in [0, perimeter)) of every side point (the cap centres excluded)."""
    n = int(starts[2] - starts[1])  # a fluted row's width (the plain rows at its angles)
    k_per = n // e  # vertices per flute period in a fluted row
    n_side = len(points) - 2
    base_fl = int(starts[4])
    s = np.empty(n_side)
    # plain rings (other angles): s proportional to the angle
    for k in (0, 3):
        ring = points[starts[k] : starts[k + 1]]
        theta = np.mod(libm.arctan2(-ring[:, 2], ring[:, 0]), 2 * np.pi)
        s[starts[k] : starts[k + 1]] = theta / (2 * np.pi) * perimeter
    # rows with the flute columns (the two plain rows at the flute angles and the fluted
    # grid): s = the flute centre's s + arc length along this row from the flute centre, so
    # every flute centre runs straight up the chart and a narrowing flute end stays narrow
    q = np.concatenate([points[starts[1] : starts[3]], points[base_fl:n_side]]).reshape(-1, n, 3)
    d = np.empty_like(q)
    np.subtract(q[:, 1:], q[:, :-1], out=d[:, :-1])
    np.subtract(q[:, 0], q[:, -1], out=d[:, -1])
    seg = _norm3(d)
    cum = (np.cumsum(seg, axis=1) - seg).reshape(len(q), e, k_per)
    # the flute centre lies half-way (in arc length) between the flute's two corners
    centre = cum[:, :, 0] + 0.5 * seg.reshape(len(q), e, k_per)[:, :, :h].sum(axis=2)
    # scaled so the row's perimeter maps to the reference one: the taper and a flute end's
    # narrowing spread over the whole row instead of squeezing the fillets
    local = (cum - centre[:, :, None]) * (perimeter / seg.sum(axis=1))[:, None, None]
    s_rows = ((np.arange(e) + 0.5)[None, :, None] * (perimeter / e) + local).reshape(-1)
    s[starts[1] : starts[3]] = s_rows[: 2 * n]
    s[base_fl:] = s_rows[2 * n :]
    return np.mod(s, perimeter)


def _seam_triangles(
    s: np.ndarray, base_fl: int, tri: np.ndarray, n_grid: int, n_lateral: int, n: int, half: float
) -> np.ndarray:
    """The side triangles that wrap round s = 0 (span more than ``half`` the perimeter). A
    grid triangle can only if its quad has corners on both sides of s = half, so the span is
    measured on those quads (two columns) and on the bands, not on every one."""
    cand = [np.arange(n_grid, n_lateral)]
    if n_grid:
        low = (s[base_fl:] < half).reshape(-1, n)
        low_next = np.roll(low, -1, axis=1)
        q00, q01, q10, q11 = low[:-1], low_next[:-1], low[1:], low_next[1:]
        mixed = np.flatnonzero((q00 != q01) | (q00 != q10) | (q00 != q11))
        cand.insert(0, (2 * mixed[:, None] + np.arange(2)).reshape(-1))
    cand_t = np.concatenate(cand)
    sc = s[tri[cand_t]]
    span = sc.max(axis=1) - sc.min(axis=1)
    return cand_t[span > half]


def grid_normals(pts: np.ndarray, col: np.ndarray, h: int) -> tuple[np.ndarray, np.ndarray]:
    """Indexed corner normals of the fluted grid's triangles, crisp at the flute corners.

    ``pts`` (R, N, 3) rows of the fluted grid; quads (r, j) are split into (a0, a1, b0) and
    (a1, b1, b0). A vertex's normal on each side of a crease column is the mean of the unit
    normals of the quads on that side (a regular grid: equal weights are the angle weights).
    Every vertex has one value (its right side: the quads of column j); a vertex on a crease
    column (a flute edge) has a second one for its left side.

    Returns
    -------
    values : (R (N + c), 3) float32, row by row: each vertex's right-side value, followed on
        the c crease columns by its left-side value
    indices : (2 (R-1) N · 3,) int32, one per triangle corner
    """
    pts = pts.astype(np.float32)  # normals need no more precision; halves the memory traffic
    R, N = pts.shape[:2]
    a0 = pts[:-1]
    b0 = pts[1:]
    q = np.cross(np.roll(b0, -1, axis=1) - a0, b0 - np.roll(a0, -1, axis=1))  # quad normals
    q /= np.maximum(_norm3(q), np.float32(1e-30))[..., None]
    v = np.empty((R, N, 3), dtype=np.float32)  # the quads above + below a vertex
    v[0] = q[0]
    v[-1] = q[-1]
    np.add(q[:-1], q[1:], out=v[1:-1])
    is_crease = (col == 0) | (col == h)
    creases = np.flatnonzero(is_crease)
    smooth = np.flatnonzero(~is_crease)
    # values row by row, each crease vertex's left value right after its right one: corner
    # indices then follow the grid as closely as the vertex indices do, which the crate
    # writer's integer compression turns into a smaller file in less time (measured at 1.25 M
    # triangles: 31 → 17 ms to save the indices, 0.42 → 0.19 MB, against the left values
    # stored after all right ones)
    width = N + len(creases)
    slot = (np.arange(N) + np.cumsum(is_crease) - is_crease).astype(np.int32)  # right value
    values = np.empty((R, width, 3), dtype=np.float32)
    # the right value: the quads of column j, plus those of column j - 1 off the creases;
    # the left value of a crease vertex: column j - 1's
    values[:, slot[creases]] = v[:, creases]
    values[:, slot[smooth]] = v[:, smooth] + v[:, (smooth - 1) % N]
    values[:, slot[creases] + 1] = v[:, (creases - 1) % N]
    values = values.reshape(-1, 3)
    values /= np.maximum(_norm3(values), np.float32(1e-30))[:, None]
    right_idx = (np.arange(R, dtype=np.int32) * np.int32(width))[:, None] + slot
    left_next = np.roll(right_idx + is_crease.astype(np.int32), -1, axis=1)  # of vertex j + 1
    corners = np.empty((R - 1, N, 6), dtype=np.int32)
    corners[..., 0] = right_idx[:-1]
    corners[..., 1] = left_next[:-1]
    corners[..., 2] = right_idx[1:]
    corners[..., 3] = left_next[:-1]
    corners[..., 4] = left_next[1:]
    corners[..., 5] = right_idx[1:]
    return values, corners.reshape(-1)
