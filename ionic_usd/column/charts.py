"""Analytic texture charts of the lathed and extruded parts (metric ``st``, seams split).

The base and the shaft are surfaces of revolution: they unroll without xatlas. Their ``st`` are
in metres of surface; :func:`ionic_usd.texture.atlas.analytic_atlas` scales and packs the charts
(connected pieces of ``st``) at a level of detail's texel density.

Charts of a revolved profile (:func:`revolved_st`), band by band (a band joins two profile
nodes):

* a band flatter than 35° (an annulus, a disc, a gentle slope) lies on a planar chart:
  (x, z) facing down, (x, −z) facing up, so every chart winds like its faces seen from
  outside; area scale cos(slope) ≥ 0.82;
* a steeper band lies on a side chart: t = arc length along the profile, s = θ·R with one
  radius R per chart. Consecutive side bands share a chart while their radii stay within a
  factor 1.3 (R their geometric mean, so the s-scale r/R stays within 1/1.14 … 1.14);
* the side charts' seam is at θ = 0 (+X): triangles across it use second ``st`` values.
"""

from __future__ import annotations

import numpy as np

from ionic_usd.geometry import libm

__all__ = ["revolved_st", "split_seam", "FLAT_SLOPE_DEG", "SIDE_RADIUS_SPREAD"]

FLAT_SLOPE_DEG = 35.0
# tan(35°) as a literal: numpy's tan differs in the last bit by CPU (tests/test_libm.py checks it)
_FLAT_SLOPE = 0.7002075382097097
SIDE_RADIUS_SPREAD = 1.3


def split_seam(st: np.ndarray, corners: np.ndarray, period: float) -> tuple[np.ndarray, np.ndarray]:
    """Cut a closed chart at s = 0: corners of wrapping triangles get a copy at s + period.

    Parameters
    ----------
    st : (w, 2) float, s in [0, period)
    corners : (t, 3) int indices into ``st``
    period : float

    Returns
    -------
    st : (w + d, 2) float with the d copies appended
    corners : (t, 3) int64
    """
    ss = st[corners, 0]
    wraps = (ss.max(axis=1) - ss.min(axis=1)) > 0.5 * period
    low = wraps[:, None] & (ss < 0.5 * period)
    dup = np.unique(corners[low])
    copy_of = np.zeros(len(st), dtype=np.int64)
    copy_of[dup] = len(st) + np.arange(len(dup))
    return (
        np.concatenate([st, st[dup] + [period, 0.0]]),
        np.where(low, copy_of[corners], corners).astype(np.int64),
    )


def _charts(nodes: np.ndarray) -> tuple[np.ndarray, list[tuple[str, float]]]:
    """Chart of every band, and each chart's kind ('up', 'down', 'side') and radius."""
    d = np.diff(nodes, axis=0)
    flat = np.abs(d[:, 1]) < _FLAT_SLOPE * np.abs(d[:, 0])
    chart = np.zeros(len(d), dtype=np.int64)
    kinds: list[tuple[str, float]] = []
    lo = hi = 0.0
    for k in range(len(d)):
        if flat[k]:
            kind = "up" if d[k, 0] < 0 else "down"  # outward normal's y is −Δr
        else:
            kind = "side"
        r0, r1 = sorted((float(nodes[k, 0]), float(nodes[k + 1, 0])))
        same = (
            bool(kinds)
            and kinds[-1][0] == kind
            and (kind != "side" or max(hi, r1) <= SIDE_RADIUS_SPREAD * min(lo, r0))
        )
        if same:
            lo, hi = min(lo, r0), max(hi, r1)
        else:
            lo, hi = r0, r1
            kinds.append((kind, 0.0))
        kinds[-1] = (kind, float(np.sqrt(max(lo, 1e-9) * max(hi, 1e-9))))
        chart[k] = len(kinds) - 1
    return chart, kinds


def revolved_st(
    nodes: np.ndarray,
    rows: list[np.ndarray],
    points: np.ndarray,
    triangles: np.ndarray,
    band_of_tri: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """Metric ``st`` of a revolved mesh (:func:`ionic_usd.geometry.curves.revolve`,
    :func:`ionic_usd.column.solids.lathe`).

    Parameters
    ----------
    nodes : (b + 1, 2) float, the revolved (r, y) profile
    rows : the b + 1 vertex rows ``revolve`` returned
    points : (n, 3) float
    triangles : (t, 3) int
    band_of_tri : (t,) int, the profile band (0 .. b − 1) of each triangle

    Returns
    -------
    st : (w, 2) float32 metres
    st_indices : (3 t,) int32
    """
    chart, kinds = _charts(nodes)
    arc = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(nodes, axis=0), axis=1))])
    theta = np.mod(libm.arctan2(-points[:, 2], points[:, 0]), 2 * np.pi)
    values: list[np.ndarray] = []
    corner = np.empty_like(triangles, dtype=np.int64)
    base = 0
    for c, (kind, radius) in enumerate(kinds):
        bands = np.flatnonzero(chart == c)
        verts = np.concatenate([rows[k] for k in range(bands[0], bands[-1] + 2)])
        p = points[verts]
        if kind == "side":
            node_of = np.concatenate(
                [np.full(len(rows[k]), k) for k in range(bands[0], bands[-1] + 2)]
            )
            s = np.where(np.hypot(p[:, 0], p[:, 2]) > 1e-12, theta[verts], np.pi) * radius
            st = np.stack([s, arc[node_of] - arc[bands[0]]], axis=1)
        else:
            st = np.stack([p[:, 0], p[:, 2] if kind == "down" else -p[:, 2]], axis=1)
        local = np.full(len(points), -1, dtype=np.int64)
        local[verts] = np.arange(len(verts))
        sel = np.isin(band_of_tri, bands)
        tri_local = local[triangles[sel]]
        if kind == "side":
            st, tri_local = split_seam(st, tri_local, 2 * np.pi * radius)
        values.append(st)
        corner[sel] = tri_local + base
        base += len(st)
    return (np.concatenate(values).astype(np.float32), corner.reshape(-1).astype(np.int32))
