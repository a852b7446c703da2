"""A scanned base on a square plinth: the plinth as a box, the rest as a lathe (issue 36).

A lathe grammar rounds a square plinth's corners, so the plinth is measured as a box — its
half-side is the median distance of its side points along their face normals, its top the
median height of the points on its top face (outside the mouldings, inside the faces) — and
only the moulded rest is fitted as a Bézier lathe profile (:func:`.fit_base.fit_base`) to
the median radius of the scan per height bin (all round the axis: a lathe is the same at
every angle; the median, not an upper percentile, so the noise does not push it out). The
base grammar is the plinth module (a vertical side, ``plinth_modules = 1``: the generator
builds it as a square slab) followed by the fitted lathe modules.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ionic_usd.column.column import ColumnParams
from ionic_usd.evaluate.fit_core import FitResult

__all__ = ["plinth_box", "lathe_meridian", "fit_plinth_base"]


def plinth_box(col_pts: np.ndarray, top: float) -> tuple[float, float] | None:
    """(half-side, height) of a square plinth whose faces face ±x, ±z; None if unseen."""
    y = col_pts[:, 1]
    p = col_pts[(y >= 0.0) & (y <= top)]
    proj = np.maximum(np.abs(p[:, 0]), np.abs(p[:, 2]))
    hyp = np.hypot(p[:, 0], p[:, 2])
    low = p[:, 1] < 0.1 * top
    if np.count_nonzero(low) < 20:
        return None
    pl = proj[low]
    half = float(np.median(pl[pl > 0.9 * np.percentile(pl, 95)]))  # not a bottom face's
    # the corners: beyond the face distance only the plinth's sides and faces lie
    corner = hyp > 1.02 * half
    side = corner & (np.abs(proj - half) < 0.01 * half)
    if np.count_nonzero(side) < 10:
        return None
    half = float(np.median(proj[side]))
    rough_top = float(np.percentile(p[side, 1], 98))
    face_top = corner & (proj < 0.98 * half) & (p[:, 1] > 0.5 * rough_top)
    if np.count_nonzero(face_top) < 10:
        return None
    return half, float(np.median(p[face_top, 1]))


def lathe_meridian(
    col_pts: np.ndarray, y0: float, y1: float, width: float, r_max: float
) -> np.ndarray | None:
    """(r, y) median radius per height bin between y0 and y1 (points within r_max)."""
    y = col_pts[:, 1]
    r = np.hypot(col_pts[:, 0], col_pts[:, 2])
    sel = (y > y0) & (y < y1) & (r < r_max)
    y, r = y[sel], r[sel]
    edges = np.arange(y0, y1 + 0.5 * width, width)
    idx = np.digitize(y, edges) - 1
    out = []
    for k in range(len(edges) - 1):
        rk = r[idx == k]
        if len(rk) >= 5:
            out.append((float(np.median(rk)), float(np.median(y[idx == k]))))
    if len(out) < 12:
        return None
    return principal_curve(np.column_stack([r, y]), np.asarray(out), width)


def principal_curve(ry: np.ndarray, curve: np.ndarray, step: float, iters: int = 4) -> np.ndarray:
    """The meridian refined as a principal curve of the points (r, y): each node moved along
    its normal by the median offset of the points whose closest place on the curve is near
    it. A y-binned median cannot follow a horizontal run (a fillet's step, a torus's
    underside); the points' own closest places can."""
    from ionic_usd.evaluate.polyline import closest_on_polyline, resample

    for _ in range(iters):
        c = resample(curve, spacing=step)
        dist, seg, t = closest_on_polyline(ry, c)
        node = np.clip(np.rint(seg + t).astype(np.int64), 0, len(c) - 1)
        tang = np.gradient(c, axis=0)
        tang /= np.maximum(np.linalg.norm(tang, axis=1), 1e-15)[:, None]
        nrm = np.column_stack([tang[:, 1], -tang[:, 0]])
        off = np.einsum("ij,ij->i", ry - c[node], nrm[node])
        keep = dist < 8.0 * step
        new = c.copy()
        for k in np.unique(node[keep]):
            o = off[keep & (node == k)]
            if len(o) >= 3:
                new[k] = c[k] + float(np.median(o)) * nrm[k]
        # ends stay at their heights (the plinth's top, the joint)
        new[0, 1], new[-1, 1] = c[0, 1], c[-1, 1]
        curve = new
    return curve


def fit_plinth_base(
    col_pts: np.ndarray, col: ColumnParams, top: float, noise: float
) -> tuple[ColumnParams, FitResult, str] | None:
    """The base as plinth box + fitted lathe (module docstring); None when the plinth or the
    mouldings are too sparse. Returns the column, the lathe's fit and a note."""
    from ionic_usd.evaluate.fit_base import fit_base

    box = plinth_box(col_pts, top)
    if box is None:
        return None
    half, hp = box
    width = max(2.0 * noise, (top - hp) / 150.0)
    mer = lathe_meridian(col_pts, hp + 2.0 * noise, top, width, 0.995 * half)
    if mer is None:
        return None
    mer = np.vstack([[mer[0, 0], hp], mer, [mer[-1, 0], top]])
    fit = fit_base(mer, initial=col, axis_x=0.0, polish_evals=400)
    d = col.shaft.bottom_radius
    plinth = f"R{half - d:.9g} H0 R{half - d:.9g} H{hp:.9g}"
    grammar = f"{plinth}, {fit.params}"
    col = dataclasses.replace(col, base=grammar, base_height=None, base_plinth=1)
    note = (
        f"square plinth as a box: half-side {half:.4f} m, height {hp:.4f} m; lathe above it "
        f"fitted to the median radius of {len(mer)} height bins: "
        f"{fit.after.hausdorff_pct:.3f} % (paper's measure), "
        f"{fit.after.discrete_frechet_pct:.3f} % (discrete Fréchet)"
    )
    return col, fit, note
