"""The base's meridian section from a scan in column coordinates.

Once the shaft has fixed the column's frame (:func:`ionic_usd.evaluate.fit_scan.fit_column_scan`:
axis, diameter, turn about the axis), the scan's points are taken into the column's own
coordinates (y up the axis, x and z the plinth's and the capital's face normals):

* **base meridian** — the points within ``±half_angle`` of the four half-planes through the
  axis at the plinth's face normals (±x, ±z: four copies of one section, so a missing sector
  or a hole costs at most one of them); their distance along the face normal per thin height
  bin (the 95th percentile: the outer surface under noise) is the profile (r, y). Per bin,
  the distance along the face normal (a square plinth's flat face: its half-side) or the
  radius (a round moulding), whichever spreads less across the half-angle.

It is None when the scan does not cover enough of the base.
"""

from __future__ import annotations

import numpy as np

__all__ = ["base_meridian", "has_square_plinth", "to_column"]


def to_column(points: np.ndarray, matrix: np.ndarray) -> np.ndarray:
    """Scan points (n, 3) in column coordinates, for ``matrix`` (4, 4) column → scan (row
    vectors, as USD)."""
    return (np.asarray(points) - matrix[3, :3]) @ np.linalg.inv(matrix[:3, :3])


def base_meridian(
    col_pts: np.ndarray,
    y0: float,
    y1: float,
    *,
    half_angle: float = 6.0,
    width: float | None = None,
    min_points: int = 4,
) -> np.ndarray | None:
    """The base's meridian (r, y) at the plinth's face normals (module docstring).

    Parameters
    ----------
    col_pts : (n, 3) float, column coordinates (y up)
    y0, y1 : the base's height range (m)
    half_angle : degrees either side of each half-plane
    width : height bin (default (y1 − y0) / 60, at least 2 mm)

    Returns
    -------
    (k + 2, 2) float (r, y) bottom to top, the first and last bins' radii repeated at y0 and
    y1; or None with fewer than 12 filled bins
    """
    y = col_pts[:, 1]
    sel = (y >= y0) & (y <= y1)
    p = col_pts[sel]
    ang = np.degrees(np.arctan2(p[:, 2], p[:, 0]))
    near = np.abs((ang + 45.0) % 90.0 - 45.0) <= half_angle  # 0°, 90°, 180°, 270°
    p = p[near]
    if len(p) < 12 * min_points:
        return None
    proj = np.maximum(np.abs(p[:, 0]), np.abs(p[:, 2]))  # along the nearest face normal
    hyp = np.hypot(p[:, 0], p[:, 2])
    width = width or max((y1 - y0) / 60.0, 0.002)
    edges = np.arange(y0, y1 + 0.5 * width, width)
    idx = np.digitize(p[:, 1], edges) - 1
    out = []
    for k in range(len(edges) - 1):
        sel = idx == k
        if np.count_nonzero(sel) < min_points:
            continue
        # a flat face (the plinth) keeps its distance along the normal, a round moulding its
        # radius: whichever spreads less across the half-angle is the surface's
        a, b = proj[sel], hyp[sel]
        spread = [float(np.subtract(*np.percentile(v, [90, 10]))) for v in (a, b)]
        rk = a if spread[0] <= spread[1] else b
        out.append((float(np.percentile(rk, 95)), 0.5 * (edges[k] + edges[k + 1])))
    if len(out) < 12:
        return None
    # the end bins' radii carried to the ends of the range (the base's bottom and top)
    return np.asarray([(out[0][0], y0), *out, (out[-1][0], y1)])


def has_square_plinth(col_pts: np.ndarray, y0: float, y1: float) -> bool:
    """True when the bottom fifth of the base is square about the axis: its points on the
    diagonals stand >= 20 % farther out than those on the face normals (a round plinth: 0 %,
    a square one: 41 %)."""
    y = col_pts[:, 1]
    p = col_pts[(y >= y0) & (y <= y0 + 0.2 * (y1 - y0))]
    if len(p) < 40:
        return False
    ang = np.degrees(np.arctan2(p[:, 2], p[:, 0])) % 90.0
    r = np.hypot(p[:, 0], p[:, 2])
    face = r[(ang < 10.0) | (ang > 80.0)]
    diag = r[np.abs(ang - 45.0) < 10.0]
    if len(face) < 8 or len(diag) < 8:
        return False
    return bool(np.percentile(diag, 95) > 1.2 * np.percentile(face, 95))
