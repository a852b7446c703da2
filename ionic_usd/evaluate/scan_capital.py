"""The capital fitted to a scan: the generator's own capital against the scanned points.

A scanned volute's outline is hard to extract (an edge search near the volute face sat a
median 8 mm off even on clean synthetic scans), but its surface is easy to compare: every
scan point of the capital has a distance to the model capital's surface, and a few of the
model's parameters are chosen to make those distances small (robust least squares,
``soft_l1``, bounded). The distance is to dense area-uniform samples of the model's meshes
(a kd-tree), corrected to the plane of the sample's triangle (so the objective does not
step from sample to sample), with the fitted shaft's exact distance taken where nearer.

Stages, in column coordinates (y up the axis, the capital's front facing ±z):

1. **placement** — the capital's scale ``s`` about the shaft's top centre and its height
   ``ty`` along the axis (a 1-D scan of ``ty`` first, then both): moving the points, not
   the model, so one kd-tree serves every step;
2. **proportions**, for each volute model (``log_spiral``, ``centred_arcs``): the volute's
   size (``capital_spiral_radius``, the eye and the model's lengths with it), the eyes'
   height (``scroll_position_y``) and their spacing (``capital_length``), each evaluation
   building the model again (about 0.1 s);
3. placement again at the fitted proportions. The model with the smaller robust cost wins;
   both are reported.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ionic_usd.column.capital import CapitalParams, build_capital
from ionic_usd.errors import GeometryError, ParameterError

__all__ = ["CapitalFit", "CapitalSurface", "capital_surface", "fit_scanned_capital"]

#: Stage 2's parameters: volute size factor, eye height and eye half-spacing offsets (parts).
PROPORTIONS = ("volute_scale", "eye_dy_parts", "eye_dx_parts")
_LO = np.array([0.8, -2.0, -2.0])
_HI = np.array([1.25, 2.0, 2.0])


@dataclass(frozen=True)
class CapitalSurface:
    """Dense samples of a capital's surface (capital frame: origin at the shaft's top
    centre), their triangles' unit normals, the sample spacing (m) and the lowest point's
    height (the volutes' hang below the shaft top is ``-low``)."""

    tree: Any
    samples: np.ndarray
    normals: np.ndarray
    spacing: float
    low: float

    def distance(self, q: np.ndarray) -> np.ndarray:
        """(n,) distance of points (n, 3) from the surface: to the nearest sample's
        triangle plane, plus what lies beyond a sample spacing along the plane."""
        d, idx = self.tree.query(q, eps=0.5)  # approximate: the plane corrects it
        v = q - self.samples[idx]
        dp = np.abs(np.einsum("ij,ij->i", v, self.normals[idx]))
        lateral = np.sqrt(np.maximum(d**2 - dp**2, 0.0))
        return np.sqrt(dp**2 + np.maximum(lateral - self.spacing, 0.0) ** 2)


def capital_surface(cap: CapitalParams, top_radius: float, count: int = 120_000) -> CapitalSurface:
    """:class:`CapitalSurface` of ``build_capital(cap, top_radius=top_radius)``."""
    from scipy.spatial import cKDTree

    from ionic_usd.evaluate.scan_io import sample_surface

    parts = build_capital(cap, top_radius=top_radius).as_dict()
    allp, allt, off = [], [], 0
    for mesh in parts.values():
        allp.append(mesh.points)
        allt.append(mesh.triangles + off)
        off += len(mesh.points)
    P, T = np.concatenate(allp), np.concatenate(allt)
    pp = P[T]
    cr = np.cross(pp[:, 1] - pp[:, 0], pp[:, 2] - pp[:, 0])
    norm = np.linalg.norm(cr, axis=1)
    nrm = cr / np.maximum(norm, 1e-300)[:, None]
    samples, tri = sample_surface(P, T, count, seed=1)
    spacing = float(np.sqrt(0.5 * norm.sum() / count))
    tree = cKDTree(samples, balanced_tree=False, compact_nodes=False)
    return CapitalSurface(tree, samples, nrm[tri], spacing, float(P[:, 1].min()))


@dataclass(eq=False)
class CapitalFit:
    """Outcome of :func:`fit_scanned_capital`.

    Attributes
    ----------
    capital : the fitted CapitalParams (at the scan's scale)
    ty : the capital's height shift along the axis (m) against the column it was fitted in
    model : the winning volute model
    values : the fitted capital's parameters (m, and the placement scale)
    models : per volute model, its robust cost, rms (m) and proportions
    rms_start, rms : rms (m) of the capital points against the starting (Vitruvian, rebuilt)
        and the fitted capital
    """

    capital: CapitalParams
    ty: float
    model: str
    values: dict[str, float]
    models: dict[str, dict[str, Any]]
    rms_start: float
    rms: float
    bounds_hit: list[str]
    seconds: float
    points: int
    notes: list[str] = field(default_factory=list)


def _proportioned(cap: CapitalParams, model: str, x: np.ndarray) -> CapitalParams:
    """``cap`` with the volute model and stage 2's values ``x`` (:data:`PROPORTIONS`)."""
    part = cap.capital_width / 18.0  # the capital's width is D: a part is D/18
    vol = cap.volute.scaled(float(x[0])).with_(volute_model=model)
    return cap.with_(
        volute=vol,
        scroll_position_y=cap.scroll_position_y + float(x[1]) * part,
        capital_length=cap.capital_length + 2.0 * float(x[2]) * part,
    )


def fit_scanned_capital(
    col_pts: np.ndarray,
    cap: CapitalParams,
    top_radius: float,
    y_top: float,
    other: np.ndarray | None = None,
    *,
    max_points: int = 2000,
    seed: int = 0,
) -> CapitalFit:
    """Fit the capital to scan points (module docstring).

    Parameters
    ----------
    col_pts : (n, 3) float, the capital's scan points in column coordinates (y up)
    cap : the starting capital (the Vitruvian one at the fitted diameter)
    top_radius : the shaft's top radius (m), where the echinus starts
    y_top : height (column y) of the shaft's top, the capital's origin
    other : (n,) float, each point's distance from the rest of the column (the shaft), or
        None; the nearer surface counts

    Returns
    -------
    CapitalFit
    """
    from scipy.optimize import least_squares

    t0 = time.perf_counter()
    rng = np.random.default_rng(seed)
    keep = rng.permutation(len(col_pts))[:max_points]
    q = np.asarray(col_pts, dtype=np.float64)[keep]
    far = np.full(len(q), np.inf) if other is None else np.asarray(other)[keep]
    if len(q) < 100:
        raise GeometryError(f"too few capital points ({len(q)}) to fit the capital")
    size = cap.capital_width
    f_scale = 0.002 * size / 0.95  # 2 mm at the Portunus size

    few = slice(0, min(len(q), 600))  # the coarse scans' points

    def dist(surf: CapitalSurface, s: float, ty: float, sel: slice = slice(None)) -> np.ndarray:
        qm = (q[sel] - np.array([0.0, y_top + ty, 0.0])) / s
        return np.minimum(surf.distance(qm) * s, far[sel])

    def robust(d: np.ndarray) -> float:
        z = (d / f_scale) ** 2
        return float(np.sum(2.0 * (np.sqrt(1.0 + z) - 1.0)))

    def place(
        surf: CapitalSurface, s0: float, ty0: float, span: float, sel: slice = slice(None)
    ) -> tuple[float, float, float]:
        """(s, ty, cost): a scan of ty over ±span at s0 (a few points), then both polished."""
        grid = ty0 + np.linspace(-span, span, 25)
        ty1 = float(grid[int(np.argmin([robust(dist(surf, s0, t, few)) for t in grid]))])
        lim = 0.25 * size
        sol = least_squares(
            lambda x: dist(surf, x[0], x[1], sel),
            np.array([s0, ty1]),
            bounds=([0.85, ty1 - lim], [1.15, ty1 + lim]),
            loss="soft_l1",
            f_scale=f_scale,
            x_scale=[0.05, 0.02 * size],
            diff_step=1e-4,
            max_nfev=25,
        )
        return float(sol.x[0]), float(sol.x[1]), float(sol.cost)

    def build(model: str, x: np.ndarray, count: int = 60_000) -> CapitalSurface | None:
        try:
            return capital_surface(_proportioned(cap, model, x), top_radius, count=count)
        except (ParameterError, GeometryError):
            return None

    start = capital_surface(cap, top_radius)
    rms_start = float(np.sqrt(np.mean(dist(start, 1.0, 0.0) ** 2)))
    s0, ty0, _ = place(start, 1.0, 0.0, 0.15 * size)
    models: dict[str, dict[str, Any]] = {}
    for model in ("log_spiral", "centred_arcs"):
        # the volute's size moves the abacus (it rests on the volutes' top): a coarse scan
        # of the size, each placed, keeps a wrong size from being traded for a wrong height
        best_c = None
        for vs in (0.85, 0.92, 1.0, 1.08, 1.16):
            x0 = np.array([vs, 0.0, 0.0])
            surf0 = build(model, x0)
            if surf0 is None:
                continue
            s_i, ty_i, c_i = place(surf0, s0, ty0, 0.06 * size, few)
            if best_c is None or c_i < best_c[0]:
                best_c = (c_i, x0, s_i, ty_i)
        if best_c is None:
            continue
        _, x, s, ty = best_c

        def res(x: np.ndarray, model: str = model, s: float = s, ty: float = ty) -> np.ndarray:
            surf = build(model, x)
            return np.full(len(q), 10.0 * size) if surf is None else dist(surf, s, ty)

        sol = least_squares(
            res,
            x,
            bounds=(_LO, _HI),
            loss="soft_l1",
            f_scale=f_scale,
            x_scale=[0.05, 0.5, 0.5],
            diff_step=3e-2,
            max_nfev=8,
        )
        c = _proportioned(cap, model, sol.x)
        surf = capital_surface(c, top_radius)
        s_m, ty_m, cost = place(surf, s, ty, 0.02 * size)
        d = dist(surf, s_m, ty_m)
        u = (sol.x - _LO) / (_HI - _LO)
        models[model] = {
            "cost": cost,
            "rms": float(np.sqrt(np.mean(d**2))),
            "p95": float(np.percentile(d, 95)),
            "proportions": dict(zip(PROPORTIONS, (float(v) for v in sol.x), strict=True)),
            "scale": s_m,
            "ty": ty_m,
            "bounds_hit": [
                n for n, ui in zip(PROPORTIONS, u, strict=True) if min(ui, 1 - ui) < 1e-3
            ],
            "_capital": c.scaled(s_m),
        }
    best = min(models, key=lambda k: models[k]["cost"])
    win = models[best]
    fitted: CapitalParams = win["_capital"]
    for m in models.values():
        del m["_capital"]
    values = {
        "scale": win["scale"],
        "capital_spiral_radius": fitted.volute.capital_spiral_radius,
        "capital_circle_radius": fitted.volute.capital_circle_radius,
        "scroll_position_y": fitted.scroll_position_y,
        "capital_length": fitted.capital_length,
        "capital_width": fitted.capital_width,
    }
    return CapitalFit(
        fitted,
        win["ty"],
        best,
        values,
        models,
        rms_start,
        win["rms"],
        list(win["bounds_hit"]),
        time.perf_counter() - t0,
        len(q),
    )
