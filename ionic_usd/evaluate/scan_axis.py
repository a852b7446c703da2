"""A column's axis and parts in a scan (any pose, noise, holes, missing sectors).

Axis. Normals are estimated by local PCA (k nearest neighbours). Every normal line of a
surface of revolution meets its axis, and every normal of a prism (a fluted shaft) is
perpendicular to it; three candidate directions — the normals' least direction, the points'
principal direction and the axis of the normal lines' linear complex (Pottmann & Randrup 1998)
— are each refined by robust least squares (``soft_l1``) on the distance between the normal
lines and the axis line, over the points whose normals are not parallel to the candidate; the
candidate with the smallest robust residual wins.

Parts. Along the axis the scan is cut into bins; per bin the outer radius (the 95th
percentile of the distance from the axis) and the asymmetry (outer radius over eight angle
sectors, largest / smallest among sectors holding points). The shaft is the narrow band;
wider, symmetric bins at one end are the base, wider asymmetric ones (volutes) the capital.
The axis is turned so the base is at the bottom (else the capital at the top).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ionic_usd.errors import GeometryError

__all__ = ["ColumnFrame", "estimate_axis", "find_parts", "normals"]


def normals(points: np.ndarray, k: int = 12) -> np.ndarray:
    """(n, 3) unit normals (unsigned) by PCA of each point's k nearest neighbours."""
    from scipy.spatial import cKDTree

    _, idx = cKDTree(points).query(points, k=k)
    nb = points[idx] - points[idx].mean(axis=1, keepdims=True)
    cov = np.einsum("nki,nkj->nij", nb, nb)
    _, vec = np.linalg.eigh(cov)
    return vec[:, :, 0]


def _line_residuals(a: np.ndarray, c: np.ndarray, p: np.ndarray, n: np.ndarray) -> np.ndarray:
    """Distances between the normal lines (p, n) and the axis line (c, a)."""
    cr = np.cross(n, a)
    s = np.linalg.norm(cr, axis=1)
    return np.abs(np.einsum("ij,ij->i", p - c, cr)) / np.maximum(s, 1e-9)


def _basis(a: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """u, v with (u, v, a) right-handed and orthonormal."""
    t = np.array([1.0, 0.0, 0.0]) if abs(a[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    u = t - a * (t @ a)
    u /= np.linalg.norm(u)
    return u, np.cross(a, u)


def _refine(
    a0: np.ndarray, p: np.ndarray, n: np.ndarray, size: float, *, direction_fixed: bool = False
) -> tuple[np.ndarray, np.ndarray, float]:
    from scipy.optimize import least_squares

    u, v = _basis(a0)
    keep = np.linalg.norm(np.cross(n, a0), axis=1) > 0.5  # normals not along the axis
    if keep.sum() < 20:
        return a0, p.mean(axis=0), math.inf
    pk, nk = p[keep], n[keep]
    # start: the point nearest all projected normal lines, in the plane ⊥ a0
    q = np.column_stack([(pk - pk.mean(0)) @ u, (pk - pk.mean(0)) @ v])
    m = np.column_stack([nk @ u, nk @ v])
    m /= np.maximum(np.linalg.norm(m, axis=1, keepdims=True), 1e-12)
    perp = np.column_stack([-m[:, 1], m[:, 0]])
    c2, *_ = np.linalg.lstsq(perp, np.einsum("ij,ij->i", perp, q), rcond=None)
    origin = pk.mean(0)

    def unpack(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        if direction_fixed:  # only the axis point moves
            return a0, origin + x[0] * u + x[1] * v
        a = a0 + x[0] * u + x[1] * v
        a /= np.linalg.norm(a)
        return a, origin + x[2] * u + x[3] * v

    def res(x: np.ndarray) -> np.ndarray:
        a, c = unpack(x)
        return _line_residuals(a, c, pk, nk)

    x0 = np.array([c2[0], c2[1]] if direction_fixed else [0.0, 0.0, c2[0], c2[1]])
    sol = least_squares(res, x0, loss="soft_l1", f_scale=0.01 * size, max_nfev=200)
    a, c = unpack(sol.x)
    return a, c, float(np.median(res(sol.x)))


def estimate_axis(
    points: np.ndarray, *, max_points: int = 30_000, seed: int = 0
) -> tuple[np.ndarray, np.ndarray, float]:
    """The axis of a (fragment of a) column in a scan.

    Parameters
    ----------
    points : (n, 3) float

    Returns
    -------
    direction : (3,) unit vector (sign arbitrary here; see :func:`find_parts`)
    point : (3,) a point of the axis
    residual : median distance (m) between the normal lines used and the axis
    """
    rng = np.random.default_rng(seed)
    p = (
        points
        if len(points) <= max_points
        else points[rng.choice(len(points), max_points, replace=False)]
    )
    size = float(np.linalg.norm(np.ptp(p, axis=0)))
    n = normals(p)
    cands = [np.linalg.eigh(n.T @ n)[1][:, 0]]  # ⊥ most normals: a prism's direction
    centred = p - p.mean(0)
    cands.append(np.linalg.eigh(centred.T @ centred)[1][:, -1])  # the long direction
    # linear complex of the normal lines: (n, p × n) · (ā, a) = 0 with |a| = 1
    big = np.column_stack([n, np.cross(p - p.mean(0), n)])
    w, vec = np.linalg.eigh(big.T @ big)
    for k in range(2):
        a = vec[3:, k]
        if np.linalg.norm(a) > 1e-6:
            cands.append(a / np.linalg.norm(a))
    best = None
    for a0 in cands:
        a, c, r = _refine(a0 / np.linalg.norm(a0), p, n, size)
        if best is None or r < best[2]:
            best = (a, c, r)
    assert best is not None
    prism = _prism_direction(best[0], n)
    return best if prism is None else _refine(prism, p, n, size, direction_fixed=True)


#: normals within this |n·a| of the plane ⊥ the axis are the surface's vertical parts
VERTICAL = 0.15


def _prism_direction(a: np.ndarray, n: np.ndarray, rounds: int = 8) -> np.ndarray | None:
    """The direction ⊥ the normals of the surface's vertical parts, started from ``a``.

    Wherever a surface of revolution's profile is vertical (the shaft, a torus' equator) and
    everywhere on a fluted shaft, the normal is ⊥ the axis; a flute's normal line, though,
    passes the axis by up to the shaft radius × the flute's half angle, so the normal lines'
    least-squares axis above is tilted by the flutes (1–4° on a 1.6 m drum). Iterated: the
    least eigenvector of Σ n nᵀ over the normals within :data:`VERTICAL` of ⊥ ``a``. None
    when too few normals are vertical (no such part).
    """
    cur = a
    for _ in range(rounds):
        vert = np.abs(n @ cur) < VERTICAL
        if vert.sum() < 50:
            return None
        nv = n[vert]
        new = np.linalg.eigh(nv.T @ nv)[1][:, 0]
        new = new if new @ cur >= 0 else -new
        done = np.linalg.norm(new - cur) < 1e-7
        cur = new
        if done:
            break
    return cur


@dataclass(frozen=True)
class ColumnFrame:
    """The column's frame in the scan and the parts found along its axis.

    Attributes
    ----------
    direction : (3,) unit, the axis pointing up (base → capital)
    origin : (3,) the axis point at height 0 (the lowest scan point's height)
    u, v : (3,) with (u, v, direction) right-handed: the section plane's axes
    parts : dict part → (h0, h1) heights along the axis (m)
    shaft_radius : outer radius of the narrow band (m), the median over its bins
    """

    direction: np.ndarray
    origin: np.ndarray
    u: np.ndarray
    v: np.ndarray
    parts: dict[str, tuple[float, float]]
    shaft_radius: float

    def local(self, points: np.ndarray) -> np.ndarray:
        """(n, 3): (x along u, y along v, h along the axis) of scan points."""
        d = points - self.origin
        return np.column_stack([d @ self.u, d @ self.v, d @ self.direction])


def _bins(loc: np.ndarray, width: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    h = loc[:, 2]
    r = np.hypot(loc[:, 0], loc[:, 1])
    edges = np.arange(h.min(), h.max() + width, width)
    idx = np.clip(np.digitize(h, edges) - 1, 0, len(edges) - 2)
    sector = ((np.arctan2(loc[:, 1], loc[:, 0]) + np.pi) / (2 * np.pi) * 8).astype(int) % 8
    nb = len(edges) - 1
    r95 = np.full(nb, np.nan)
    asym = np.full(nb, np.nan)
    order = np.argsort(idx, kind="stable")
    splits = np.searchsorted(idx[order], np.arange(nb + 1))
    for b in range(nb):
        sel = order[splits[b] : splits[b + 1]]
        if len(sel) < 20:
            continue
        r95[b] = np.percentile(r[sel], 95)
        sec = [
            np.percentile(r[sel][sector[sel] == s], 95)
            for s in range(8)
            if np.count_nonzero(sector[sel] == s) >= 5
        ]
        if len(sec) >= 3:
            asym[b] = max(sec) / max(min(sec), 1e-12)
    return edges, r95, asym, r


def find_parts(points: np.ndarray, direction: np.ndarray, point: np.ndarray) -> ColumnFrame:
    """Orient the axis and find the base, shaft and capital along it (module docstring)."""
    a = direction / np.linalg.norm(direction)
    for _ in range(2):
        u, v = _basis(a)
        h = (points - point) @ a
        origin = point + a * h.min()
        frame = ColumnFrame(a, origin, u, v, {}, 0.0)
        loc = frame.local(points)
        r_all = np.hypot(loc[:, 0], loc[:, 1])
        width = max(float(np.ptp(loc[:, 2])) / 200.0, 0.02 * float(np.percentile(r_all, 50)))
        edges, r95, asym, _ = _bins(loc, width)
        ok = np.isfinite(r95)
        if ok.sum() < 3:
            raise GeometryError("the scan is too small or too sparse along its axis")
        r_shaft = float(np.nanpercentile(r95, 25))
        narrow = ok & (r95 < 1.1 * r_shaft)
        wide = ok & (r95 > 1.15 * r_shaft)
        lo_end = _end_run(wide, ok, from_start=True)
        hi_end = _end_run(wide, ok, from_start=False)
        parts: dict[str, tuple[float, float]] = {}
        kinds: dict[str, tuple[str, tuple[float, float], float]] = {}
        for name, run in (("low", lo_end), ("high", hi_end)):
            if run is None:
                continue
            i, j = run
            asy = np.nanmedian(asym[i : j + 1]) if np.isfinite(asym[i : j + 1]).any() else 1.0
            grow = float(np.nanmax(r95[i : j + 1])) / r_shaft
            tall = float(edges[j + 1] - edges[i]) / r_shaft
            # a capital's volutes reach ≥ 1.4 shaft radii over ≥ 0.7 of one (the echinus
            # to the abacus); a cut drum's top seen from a tilted first axis flares less
            if asy > 1.25 and grow > 1.3 and tall > 0.6:
                kinds[name] = ("capital", (edges[i], edges[j + 1]), grow)
            elif grow > 1.2:  # a plinth: ≥ 1.27 shaft radii (a square's corners more)
                kinds[name] = ("base", (edges[i], edges[j + 1]), grow)
        if kinds.get("low", ("",))[0] == kinds.get("high", ("",))[0] == "base":
            del kinds[min(kinds, key=lambda k: kinds[k][2])]  # one base: the wider end
        # a base belongs at the bottom, a capital at the top: flip once if they disagree
        flip = (kinds.get("high", ("",))[0] == "base" and kinds.get("low", ("",))[0] != "base") or (
            kinds.get("low", ("",))[0] == "capital" and kinds.get("high", ("",))[0] != "capital"
        )
        if flip:
            a = -a
            continue
        for kind, span, _ in kinds.values():
            parts[kind] = (float(span[0]), float(span[1]))
        nidx = np.flatnonzero(narrow)
        if len(nidx) >= 3:
            parts["shaft"] = (float(edges[nidx[0]]), float(edges[nidx[-1] + 1]))
        return ColumnFrame(
            a, origin, u, v, parts, float(np.nanmedian(r95[narrow])) if narrow.any() else r_shaft
        )
    raise GeometryError("cannot orient the column: base and capital both at one end")


def _end_run(mask: np.ndarray, ok: np.ndarray, *, from_start: bool) -> tuple[int, int] | None:
    """The run of True at one end of ``mask`` (a few False bins tolerated, empty bins —
    not ``ok`` — skipped), at least 2 long."""
    idx = np.arange(len(mask)) if from_start else np.arange(len(mask))[::-1]
    run, gap = [], 0
    for i in idx:
        if not ok[i]:
            continue
        if mask[i]:
            run.append(i)
            gap = 0
        else:
            gap += 1
            if gap > 2:
                break
    if len(run) < 2:
        return None
    return (min(run), max(run))
