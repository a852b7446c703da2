"""Scans of several columns (a colonnade, issue 36): split, fit each, group the instances.

1. :func:`split_columns` — the common up axis is the direction ⊥ the normals of the
   vertical surfaces of every column at once (the columns stand parallel); the points
   projected on the ground plane fill a grid whose 8-connected occupied cells
   (``scipy.ndimage.label``) are the columns' footprints; clusters under
   :data:`MIN_SHARE` of the largest (or under 100 points) are dropped, and said so; a
   footprint holding several columns (touching plinths, a stylobate or an architrave joining
   them) is split by its mid-height band, where only the shafts stand (``_split_touching``);
2. each cluster is fitted by :func:`.fit_scan.fit_column_scan`, unchanged;
3. :func:`group_columns` — a column is an instance of another's description when their
   flute counts are equal and that description, placed at the column's own pose (axis, turn,
   flute phase, base bottom), leaves its points within :data:`SAME` × the rms deviation of
   its own fit (the noise): a criterion on every parameter the scan shows at once
   (diameter, taper, base profile and height, capital), in the units of the noise; else it
   describes a distinct column. The column's height along its axis is registered first
   (:func:`register_instance`): its zero is its lowest point along its fitted axis, a
   plinth's corner, which a fraction of a degree of the axis or the noise moves by
   millimetres, so two fits of equal columns stand up to ~1.5 cm apart along their axes
   (their plinths' heights absorb it) and their descriptions, compared at their own
   zeros, differ by twice the noise (the tests' seed 2: 2.8 mm apart, 1.64–1.72 mm rms).
   The per-instance deviation is that of its points from its group's description at that
   registered pose.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ionic_usd.errors import GeometryError, IonicError
from ionic_usd.evaluate.fit_scan import ScanFit, fit_column_scan
from ionic_usd.evaluate.scan_axis import VERTICAL, _prism_direction, normals
from ionic_usd.evaluate.scan_volute import circle_fit

__all__ = [
    "ColonnadeFit",
    "fit_colonnade",
    "group_columns",
    "instance_column",
    "register_instance",
    "split_columns",
    "up_axis",
]

#: a cluster smaller than this share of the largest is not a column (debris, a stray hit)
MIN_SHARE = 0.1
#: one description serves two columns when it leaves the second's points within this × their
#: rms deviation from their own fit (the noise the fit reached)
SAME = 1.5
#: a column's height along its axis as an instance is sought within this share of the
#: source's lower diameter either way (24 mm at D = 0.8 m; the tests' equal columns stand
#: 0–13 mm apart on seeds 0–7)
SHIFT = 0.03
#: grid cell: this × the median nearest-neighbour spacing of the points (3-D)
CELL_SPACINGS = 4.0


def up_axis(points: np.ndarray, *, max_points: int = 20_000, seed: int = 0) -> np.ndarray:
    """(3,) unit direction ⊥ the normals of the vertical surfaces of all the columns."""
    rng = np.random.default_rng(seed)
    p = points if len(points) <= max_points else points[rng.choice(len(points), max_points, False)]
    n = normals(p)
    # every surface of a colonnade is vertical (shafts, tori's equators, plinths' and a
    # stylobate's sides: normal ⊥ up) or horizontal (plinth and stylobate tops, a floor:
    # normal ∥ up). Candidates: normals (a horizontal surface's is up) and cross products of
    # two normals (two vertical surfaces' is up); the one most normals are ⊥ or ∥ to wins (a
    # large floor scanned with the columns outweighs them in Σ n nᵀ, so its least eigenvector
    # alone would not do), then it is refined on the vertical normals
    k = min(len(n), 256)
    cand = np.vstack([n[rng.choice(len(n), k, False)], np.linalg.eigh(n.T @ n)[1].T])
    pairs = rng.choice(len(n), (k, 2))
    cross = np.cross(n[pairs[:, 0]], n[pairs[:, 1]])
    size = np.linalg.norm(cross, axis=1)
    cand = np.vstack([cand, cross[size > 0.5] / size[size > 0.5, None]])
    sub = n if len(n) <= 5000 else n[rng.choice(len(n), 5000, False)]
    dots = np.abs(sub @ cand.T)
    score = ((dots < VERTICAL) | (dots > 1.0 - VERTICAL**2 / 2)).sum(axis=0)
    a = cand[int(np.argmax(score))]
    prism = _prism_direction(a, n)
    return a if prism is None else prism


def _cells(xy: np.ndarray, cell: float) -> tuple[np.ndarray, np.ndarray]:
    """Plan points (offset to >= 0) on a grid of ``cell``: each point's 8-connected group of
    occupied cells (``scipy.ndimage.label``) and each group's point count."""
    from scipy import ndimage

    ij = np.floor(xy / cell).astype(np.int64)
    grid = np.zeros(tuple(ij.max(axis=0) + 1), dtype=bool)
    grid[ij[:, 0], ij[:, 1]] = True
    labels, count = ndimage.label(grid, structure=np.ones((3, 3), dtype=int))
    lab = labels[ij[:, 0], ij[:, 1]] - 1
    return lab, np.bincount(lab, minlength=count)


def _spacing(points: np.ndarray, rng) -> float:
    from scipy.spatial import cKDTree

    p = points if len(points) <= 20_000 else points[rng.choice(len(points), 20_000, False)]
    d, _ = cKDTree(p).query(p, k=2)
    return float(np.median(d[:, 1]))


def split_columns(
    points: np.ndarray, *, seed: int = 0
) -> tuple[np.ndarray, list[np.ndarray], list[str]]:
    """Split a scan into columns by their footprints on the ground plane.

    Returns
    -------
    up : (3,) the common axis
    clusters : index arrays into ``points``, largest first
    notes : what was dropped
    """

    rng = np.random.default_rng(seed)
    up = up_axis(points, seed=seed)
    u = np.cross(up, [1.0, 0.0, 0.0] if abs(up[0]) < 0.9 else [0.0, 1.0, 0.0])
    u /= np.linalg.norm(u)
    v = np.cross(up, u)
    xy = points @ np.column_stack([u, v])
    lo = xy.min(axis=0)
    ext = float(np.max(np.ptp(xy, axis=0)))
    cell = max(CELL_SPACINGS * _spacing(points, rng), ext / 2000.0, 1e-6)
    lab, sizes = _cells(xy - lo, cell)
    count = len(sizes)
    order = np.argsort(-sizes, kind="stable")
    keep = [k for k in order if sizes[k] >= max(100, MIN_SHARE * sizes[order[0]])]
    notes = []
    dropped = int(sizes.sum() - sizes[keep].sum())
    if dropped:
        notes.append(
            f"split: {count - len(keep)} cluster(s) of {dropped:,} points in all dropped "
            f"(under {MIN_SHARE:.0%} of the largest column's points or under 100)"
        )
    clusters: list[np.ndarray] = []
    for k in keep:
        idx = np.flatnonzero(lab == k)
        parts, shared = _split_touching(points[idx] @ up, xy[idx], cell)
        if len(parts) > 1:
            notes.append(
                f"split: {len(parts)} columns stood on one footprint (a shared plinth, "
                f"stylobate or architrave); its {shared:,} points off the columns dropped"
            )
        clusters += [idx[q] for q in parts]
    clusters.sort(key=len, reverse=True)
    return up, clusters, notes


#: the mid-height band (shares of a footprint's height) whose points are only the shafts
SHAFT_BAND = (0.35, 0.65)
#: a column's points lie within this × its shaft radius of its axis (an Ionic plinth's corner
#: is at 1.94 r for a base 1 3/8 D wide, 2.12 r for 1 1/2 D)
KEEP_RADII = 2.3


def _face(h: np.ndarray, xy: np.ndarray, tol: float, *, top: bool) -> tuple[np.ndarray, float]:
    """A horizontal face joining the columns (a stylobate's top, an architrave's soffit), as
    the plane through its points (``h`` over ``xy``: it need not be level in the scan's up,
    which comes from the columns' axes): fitted to the upper (``top``) or lower half of the
    points, then to those within ``tol`` of it, three times. Returns the plane's coefficients
    (h = c0 + c1 x + c2 y) and the margin just past it: 4.5× the robust scatter of its points
    (1.4826 × their median absolute deviation: the scan's noise there), + above, − below."""
    a = np.column_stack([np.ones(len(h)), xy])
    on = h >= np.median(h) if top else h <= np.median(h)
    for _ in range(3):
        coef = np.linalg.lstsq(a[on], h[on], rcond=None)[0]
        r = h - a @ coef
        on = np.abs(r) <= tol
        if on.sum() < 3:
            break
    sigma = 1.4826 * float(np.median(np.abs(r[on]))) if on.any() else tol
    return (coef, 4.5 * sigma if top else -4.5 * sigma)


def _split_touching(h: np.ndarray, xy: np.ndarray, cell: float) -> tuple[list[np.ndarray], int]:
    """One footprint holding several columns (their plinths touch, or a stylobate or an
    architrave joins them): the shafts stand apart in the footprint's mid-height band, so
    that band's connected cells are the columns. Each column keeps the points within
    :data:`KEEP_RADII` × its shaft radius of its axis (the band's points' circle), nearest
    axis first; below the top of what joins them at the bottom (a stylobate) and above the
    bottom of what joins them on top (an architrave) nothing is kept. Returns index arrays
    into the footprint's points (one, all of them, when it is one column) and the count of
    points dropped."""

    lo_h, span = float(h.min()), float(np.ptp(h))
    band = np.flatnonzero((h > lo_h + SHAFT_BAND[0] * span) & (h < lo_h + SHAFT_BAND[1] * span))
    if len(band) < 200:
        return [np.arange(len(h))], 0
    q = xy[band]
    lab, sizes = _cells(q - q.min(axis=0), cell)
    count = len(sizes)
    shafts = [k for k in range(count) if sizes[k] >= max(100, MIN_SHARE * sizes.max())]
    if len(shafts) < 2:
        return [np.arange(len(h))], 0
    circles = np.array([circle_fit(q[lab == k]) for k in shafts])
    centres, radii = circles[:, :2], circles[:, 2]
    d = np.linalg.norm(xy[:, None, :] - centres[None, :, :], axis=2)
    near = np.argmin(d, axis=1)
    on = d[np.arange(len(h)), near] <= KEEP_RADII * radii[near]
    keep = on.copy()
    tol = 0.01 * float(radii.min())
    a = np.column_stack([np.ones(len(h)), xy])
    for top in (True, False):  # a stylobate's top and all below; an architrave's soffit, above
        side = ~on & ((h < lo_h + 0.5 * span) if top else (h >= lo_h + 0.5 * span))
        if side.sum() >= 3:
            coef, margin = _face(h[side], xy[side], tol, top=top)
            level = a @ coef + margin
            keep &= (h > level) if top else (h < level)
    parts = [np.flatnonzero(keep & (near == k)) for k in range(len(shafts))]
    return parts, int(len(h) - keep.sum())


@dataclass(eq=False)
class ColonnadeFit:
    """Outcome of :func:`fit_colonnade` (metres, the scan's frame).

    fits : one ScanFit per column found (largest cluster first)
    indices : each column's point indices in the scan
    groups : per distinct column description, the indices into ``fits`` of its instances
        (the first is the description's source: the instance of least rms deviation)
    instance_deviation : per column, its points' distances to its group's description
    instance_matrix : per column, its pose as an instance of its group (4, 4): its own
        ``matrix`` moved along its axis so the description fits its points best
        (:func:`register_instance`); a source's is its own
    """

    up: np.ndarray
    fits: list[ScanFit]
    indices: list[np.ndarray]
    groups: list[list[int]]
    instance_deviation: list[np.ndarray]
    instance_matrix: list[np.ndarray]
    notes: list[str] = field(default_factory=list)

    def group_of(self, i: int) -> int:
        return next(g for g, m in enumerate(self.groups) if i in m)

    def summary(self) -> dict[str, Any]:
        """The R.json keys of a colonnade: ``columns`` (one per column found) and
        ``distinct_columns`` (one per description)."""
        cols = []
        for i, f in enumerate(self.fits):
            s = f.summary()
            d = self.instance_deviation[i]
            cols.append(
                {
                    "position": f.matrix[3, :3].tolist(),  # the column's y = 0 on its axis
                    "axis": s["axis"],
                    "diameter": s["diameter"],
                    "flutes": s["flutes"],
                    "base_height": _base_height(f),
                    "points": s["points"],
                    "deviation": s["deviation"],
                    "group": self.group_of(i),
                    "deviation_from_group": _stats(d),
                    "shift_from_own_pose": _shift(f.matrix, self.instance_matrix[i]),
                    "parts": s["parts"],
                    "not_fitted": s["not_fitted"],
                }
            )
        return {
            "up": self.up.tolist(),
            "columns": cols,
            "distinct_columns": [
                {"instances": g, "source": g[0], "diameter": self.fits[g[0]].diameter}
                for g in self.groups
            ],
            "notes": self.notes,
        }


def _stats(d: np.ndarray) -> dict[str, float]:
    return {
        "rms": float(np.sqrt(np.mean(d**2))),
        "p95": float(np.percentile(d, 95)),
        "max": float(d.max()),
    }


def _shift(own: np.ndarray, inst: np.ndarray) -> float:
    """How far the instance pose stands along the column's axis from its own (metres)."""
    return float((inst[3, :3] - own[3, :3]) @ own[1, :3])


def _rms(d: np.ndarray) -> float:
    return float(np.sqrt(np.mean(d**2)))


def _base_height(f: ScanFit) -> float | None:
    return f.column.base_params().height if "base" in f.frame.parts else None


def instance_column(src: ScanFit, inst: ScanFit):
    """The source's column description with the instance's flute phase (its pose)."""
    return dataclasses.replace(
        src.column,
        shaft=dataclasses.replace(src.column.shaft, flute_phase=inst.column.shaft.flute_phase),
    )


def _instance_deviation(
    src: ScanFit, inst: ScanFit, pts: np.ndarray, tree, matrix: np.ndarray | None = None
) -> np.ndarray:
    """The instance's points against the source's description at the instance's pose
    (its own turn, flute phase and height of the base's bottom; or ``matrix``)."""
    from ionic_usd.evaluate.scan_deviation import scan_deviation

    m = inst.matrix if matrix is None else matrix
    return scan_deviation(pts, instance_column(src, inst), m, tree=tree)


def _along(matrix: np.ndarray, dy: float) -> np.ndarray:
    m = matrix.copy()
    m[3, :3] = m[3, :3] + dy * m[1, :3]  # row vectors: the column's y axis is row 1
    return m


def register_instance(
    src: ScanFit, inst: ScanFit, pts: np.ndarray, tree
) -> tuple[np.ndarray, np.ndarray]:
    """The instance's pose moved along its own axis (within :data:`SHIFT` × the source's
    diameter either way) to where the source's description leaves its points the least rms:
    a grid of 25 steps, then Brent's method in the best step's neighbourhood. A column's
    zero is its lowest point along its fitted axis (a plinth's corner, moved by the axis'
    error and the noise), so its height along its axis is a pose to fit, not a shape to
    compare.

    Returns
    -------
    matrix : (4, 4) the registered pose (row vectors, as ``inst.matrix``)
    deviation : (n,) the points' distances to the description there
    """
    from scipy.optimize import minimize_scalar

    def rms(dy: float) -> float:
        return _rms(_instance_deviation(src, inst, pts, tree, _along(inst.matrix, dy)))

    reach = SHIFT * src.diameter
    grid = np.linspace(-reach, reach, 25)
    best = int(np.argmin([rms(float(dy)) for dy in grid]))
    step = grid[1] - grid[0]
    lo, hi = grid[max(best - 1, 0)], grid[min(best + 1, len(grid) - 1)]
    res = minimize_scalar(rms, bounds=(lo, hi), method="bounded", options={"xatol": 1e-3 * step})
    dy = float(res.x) if res.fun < rms(float(grid[best])) else float(grid[best])
    m = _along(inst.matrix, dy)
    return m, _instance_deviation(src, inst, pts, tree, m)


def group_columns(
    fits: list[ScanFit], points: list[np.ndarray]
) -> tuple[list[list[int]], list[np.ndarray], list[np.ndarray]]:
    """Group the fits: a fit joins the group whose source describes its points within
    :data:`SAME` × its own rms deviation, at its pose registered along its axis
    (:func:`register_instance`; the fits taken by increasing rms; each compared with the
    groups' sources only, so no chaining); else it is the source of a new group.

    Returns
    -------
    groups : fit indices per group, the source first
    deviation : per fit, its points' distances to its group's source
    matrices : per fit, its pose as an instance of its group (a source's own ``matrix``)
    """
    from ionic_usd.evaluate.scan_deviation import other_parts_tree

    order = sorted(range(len(fits)), key=lambda i: _rms(fits[i].deviation))
    groups: list[list[int]] = []
    trees: list[Any] = []
    dev: list[np.ndarray] = [f.deviation for f in fits]
    mats: list[np.ndarray] = [f.matrix for f in fits]
    for i in order:
        own = _rms(fits[i].deviation)
        for g, tree in zip(groups, trees, strict=True):
            if fits[g[0]].flutes != fits[i].flutes:
                continue
            m, d = register_instance(fits[g[0]], fits[i], points[i], tree)
            if _rms(d) <= SAME * own:
                g.append(i)
                dev[i], mats[i] = d, m
                break
        else:
            groups.append([i])
            trees.append(other_parts_tree(fits[i].column))
    return sorted(groups, key=min), dev, mats


def fit_colonnade(
    points: np.ndarray,
    *,
    seed: int = 0,
    split: tuple[np.ndarray, list[np.ndarray], list[str]] | None = None,
) -> ColonnadeFit:
    """Split, fit each column, group the instances (module docstring); ``split``: the
    output of :func:`split_columns` when already computed."""
    pts = np.asarray(points, dtype=np.float64)
    up, clusters, notes = split if split is not None else split_columns(pts, seed=seed)
    if not clusters:
        raise GeometryError("scan: no cluster of points large enough for a column")
    fits = []
    for k, idx in enumerate(clusters):
        try:
            fits.append(fit_column_scan(pts[idx], seed=seed))
        except IonicError as exc:  # which column could not be fitted, and why
            raise GeometryError(f"column {k + 1} of {len(clusters)}: {exc}") from exc
    groups, inst, mats = group_columns(fits, [pts[c] for c in clusters])
    return ColonnadeFit(up, fits, clusters, groups, inst, mats, notes)
