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

* **base top** — the base's last fillet and the shaft's plain ring are one cylinder, so the
  joint cannot be seen in the outer radius. The flutes' start can: per thin height bin, the
  mean depth of the points below the bin's outer radius (a fraction of it) is ~0 on the
  ring and the mouldings' bins near the shaft, and the flutes' level above; the start is
  where it first reaches half that level, walking down from the flutes
  (:func:`flute_onset`). The same measure on the fitted shaft's own mesh gives the start's
  height above the shaft's bottom (the ring and the spoon ends' half depth), so the
  joint is the scan's start less that (:func:`base_top`).
"""

from __future__ import annotations

import numpy as np

__all__ = ["base_meridian", "base_top", "flute_onset", "has_square_plinth", "to_column"]


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


def flute_onset(r: np.ndarray, h: np.ndarray, h0: float, h1: float) -> float | None:
    """Height where the flutes start (module docstring), between ``h0`` and ``h1``.

    Parameters
    ----------
    r, h : (n,) float, distance from the axis and height along it
    h0, h1 : the search range: the base's mouldings at the bottom, flutes at the top

    Returns
    -------
    float, or None when the range holds too few points or no fluted level
    """
    sel = (h >= h0) & (h <= h1)
    r, h = r[sel], h[sel]
    if len(r) < 200:
        return None
    width = max((h1 - h0) * 30.0 / len(r), (h1 - h0) / 400.0)  # ~30 points a bin
    edges = np.arange(h0, h1 + 0.5 * width, width)
    idx = np.clip(np.digitize(h, edges) - 1, 0, len(edges) - 2)
    nb = len(edges) - 1
    depth = np.full(nb, np.nan)
    for k in range(nb):
        rk = r[idx == k]
        if len(rk) >= 8:
            depth[k] = float(np.mean(1.0 - rk / np.percentile(rk, 95)))
    ok = np.flatnonzero(np.isfinite(depth))
    if len(ok) < 12:
        return None
    d = np.interp(np.arange(nb), ok, depth[ok])
    d = np.array([np.median(d[max(0, k - 1) : k + 2]) for k in range(nb)])  # 3-bin median
    level = float(np.median(d[int(0.75 * nb) :]))  # the top quarter: flutes
    if not level > 4.0 * float(np.median(np.abs(np.diff(d)))) + 1e-4:
        return None
    half = 0.5 * level
    k = int(0.75 * nb)
    while k > 0 and d[k - 1] >= half:
        k -= 1
    if k == 0:
        return None
    # d[k - 1] < half <= d[k]: linear between the bins' centres
    f = (half - d[k - 1]) / max(d[k] - d[k - 1], 1e-12)
    return float(edges[k - 1] + (0.5 + f) * width)


def base_top(
    r: np.ndarray, h: np.ndarray, guess: float, diameter: float, shaft_mesh
) -> tuple[float, float] | None:
    """The base/shaft joint's height (module docstring) and the flutes' start above it.

    Parameters
    ----------
    r, h : (n,) float, the scan's distance from the axis and height along it
    guess : the base's top from the parts' bins (short: the joint is often unassigned)
    diameter : the fitted lower diameter (m)
    shaft_mesh : the fitted shaft's Mesh, y = 0 at its bottom

    Returns
    -------
    (joint height, onset above the joint), or None
    """
    from ionic_usd.evaluate.scan_io import sample_surface

    h0, h1 = guess - 0.1 * diameter, guess + 0.8 * diameter
    onset = flute_onset(r, h, h0, h1)
    if onset is None:
        return None
    # the same measure on the model: its own onset above the shaft's bottom
    tri = np.asarray(shaft_mesh.triangles)
    pts = np.asarray(shaft_mesh.points)
    low = pts[tri][:, :, 1].max(axis=1) < 0.7 * diameter
    s, _ = sample_surface(pts, tri[low], 60_000, seed=3)
    below = np.linspace(-0.1 * diameter, 0.0, 2000)  # the base below the joint: no flutes
    rm = np.concatenate([np.hypot(s[:, 0], s[:, 2]), np.full(2000, float(pts[:, 0].max()))])
    hm = np.concatenate([s[:, 1], below])
    model = flute_onset(rm, hm, -0.1 * diameter, 0.6 * diameter)
    if model is None:
        return None
    return onset - model, model
