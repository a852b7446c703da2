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
2. **shape**, for each volute model (``log_spiral``, ``centred_arcs``): a coarse scan of
   the volute's size (the eyes raised or lowered to keep the abacus, which rests on the
   volutes' top, where it was), each placed; then the least squares over
   :data:`PROPORTIONS` — the volute's size (``capital_spiral_radius``, the eye and the
   model's lengths with it), the eyes' height (``scroll_position_y``) and spacing
   (``capital_length``), the volute faces' distance (``capital_width``), the bolster rings'
   radii (one factor: the description's ring positions and relative radii kept), the
   echinus' height and projection, the abacus' side (one factor on length and width) and
   thickness, the log spiral's growth (its radius ratio over half a turn, the top and the
   eye kept: :func:`with_growth`), the bolsters' belt (the middle rings' swell over the
   end rings'), the eye's offset from the spiral's origin (the eye and the bolsters on its
   axis move, the spiral stays), the band's relief, the spiral's turns and the band's
   width (one factor) and its start's share of it — each evaluation building the
   model again (about 0.04 s); the width is scanned over its range first and the abacus'
   side after (:data:`GRIDDED_BEFORE`, :data:`GRIDDED_AFTER`: their costs have flats and
   several minima; the side then again on a finer step), then polished. Before the least
   squares the volute is moved onto the rolls' circle
   (:func:`~ionic_usd.evaluate.scan_volute.roll_circle`: the points between the faces seen
   from the side, a trimmed robust circle fit) — its eye on the
   circle's centre, its top radius and the bolsters' radius the circle's — when that is
   nearer the points: the faces' spirals alone held the eye 20 mm off the rolls' axis
   (a local minimum the least squares did not leave); then, and again before the last
   polish, the bolsters are put on that circle (the eye's offset from the spiral, the
   bolsters' radius, the volutes' height and the abacus' thickness solved for, the abacus'
   seat on the rolls' top and its top kept: :meth:`_Problem.bolster_on_rolls`) when that is
   nearer the points (the spirals pulled the bolsters 11 mm off the rolls' axis); last,
   the volute's growth, turns, band and relief and its size are swept one at a time
   (:data:`SWEPT`), the bolsters put back on the rolls after each;
3. placement again at the fitted shape. The model with the smaller robust cost wins; both
   are reported, with what was fitted and what kept from the description (:data:`KEPT`).

On the tests' independent whole column (tests/synth_column.py: Archimedean volutes on a
cushion, a quarter-ellipse echinus, a square abacus; 0.8 mm noise) the capital's rms went
from 38.8-41.9 mm (size, eyes and placement only) to the figures in
tests/test_scan_whole_column.py; tools/capital_surfaces.py prints them surface by surface.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ionic_usd.column.capital import CapitalParams
from ionic_usd.errors import GeometryError, ParameterError
from ionic_usd.evaluate.capital_shape import (
    ACTIVE,
    HI,
    KEPT,
    LO,
    PROPORTIONS,
    X0,
    XSCALE,
    fitted_values,
    proportioned,
)
from ionic_usd.evaluate.capital_surface import CapitalSurface, capital_surface
from ionic_usd.evaluate.scan_volute import bolster_circle, roll_circle, solve_for, spiral_growth

__all__ = ["CapitalFit", "CapitalSurface", "capital_surface", "fit_scanned_capital"]

#: parameters whose cost has flats or several minima (indices into :data:`PROPORTIONS`),
#: scanned over their whole range: the capital's width before the least squares (the
#: faces' points lie between the model's band, channel floor and disc back, each a
#: minimum), the abacus' side after it (a box's side seen from inside is still near its
#: top and bottom: past the scanned side the cost is flat)
GRIDDED_BEFORE = (3,)
GRIDDED_AFTER = (7,)
#: swept one at a time, last (:meth:`_Problem.sweep`): the volute's growth, turns, band
#: width and start, relief and size
SWEPT = (
    "volute_growth",
    "volute_turns",
    "band_width",
    "band_start",
    "relief_depth",
    "volute_scale",
)
#: moved to put the bolsters on the rolls' circle (:meth:`_Problem.bolster_on_rolls`)
_ON_ROLLS = (
    "eye_offset_x",
    "eye_offset_y",
    "bolster_radius",
    "eye_dy_parts",
    "abacus_height",
)
_BELT = PROPORTIONS.index("bolster_belt")


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
    fitted, kept : the capital's parameters fitted (placement, :data:`PROPORTIONS`) and kept
        from the description (:data:`KEPT`)
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
    fitted: list[str] = field(default_factory=lambda: ["scale", "height", *PROPORTIONS])
    kept: list[str] = field(default_factory=lambda: list(KEPT))


def _eye_on_rolls(
    cap: CapitalParams, model: str, x: np.ndarray, qm: np.ndarray, f_scale: float
) -> np.ndarray:
    """``x`` with the volute's eye on the rolls' axis
    (:func:`~ionic_usd.evaluate.scan_volute.roll_circle`), its top radius and the bolsters'
    radius the rolls' (the volute's outer turn and the bolster
    roll together); ``x`` when the rolls are not seen or the move leaves the bounds."""
    from ionic_usd.column.capital_body import capital_layout
    from ionic_usd.column.volute import volute_extent, volute_total_radius

    try:
        c = proportioned(cap, model, x)
    except (ParameterError, GeometryError):
        return x
    got = roll_circle(qm, c, f_scale)
    if got is None:
        return x
    part = cap.capital_width / 18.0
    y = x.copy()
    y[0] *= got[2] / c.volute.capital_spiral_radius
    y[11:13] = 0.0
    try:
        c = proportioned(cap, model, y)
        ext = volute_extent(c.volute, c.spiral_samples, c.ring_segments)
    except (ParameterError, GeometryError):
        return x
    y[2] += (got[0] + float(ext[1, 0]) - 0.5 * c.capital_length) / part
    y[1] += (got[1] - c.scroll_position_y - c.capital_position_y) / part
    if not np.all((y > LO) & (y < HI)):
        return x
    try:
        moved = proportioned(cap, model, y)
        capital_layout(moved)  # raises when the moved capital cannot be laid out
    except (ParameterError, GeometryError):
        return x
    ring = max(g.radius for g in moved.scroll_grammar.rings)
    y[4] *= got[2] / (ring * volute_total_radius(moved.volute))
    return np.clip(y, LO, HI)


def _level_eye(cap: CapitalParams, model: str, vs: float) -> float:
    """The eye offset (parts) that keeps the abacus where it is at volute size ``vs``: the
    abacus rests on the volutes' top, so a smaller volute alone would drop it."""
    from ionic_usd.column.volute import volute_extent

    part = cap.capital_width / 18.0
    top = float(volute_extent(cap.volute, cap.spiral_samples, cap.ring_segments)[1, 1])
    vol = cap.volute.scaled(vs).with_(volute_model=model)
    top_vs = float(volute_extent(vol, cap.spiral_samples, cap.ring_segments)[1, 1])
    return (top - top_vs) / part


@dataclass
class _Problem:
    """What every stage of the capital's fit shares: the points (column coordinates), their
    distance to the rest of the column, the starting capital and the robust cost's scale."""

    q: np.ndarray
    far: np.ndarray
    cap: CapitalParams
    top_radius: float
    y_top: float

    def __post_init__(self) -> None:
        self.size = self.cap.capital_width
        self.f_scale = 0.002 * self.size / 0.95  # 2 mm at the Portunus size
        self.few = slice(0, min(len(self.q), 600))  # the coarse scans' points

    def dist(
        self, surf: CapitalSurface, s: float, ty: float, sel: slice = slice(None)
    ) -> np.ndarray:
        """The points' distances to ``surf`` scaled by ``s`` and raised by ``ty``."""
        qm = (self.q[sel] - np.array([0.0, self.y_top + ty, 0.0])) / s
        return np.minimum(surf.distance(qm) * s, self.far[sel])

    def robust(self, d: np.ndarray) -> float:
        """The ``soft_l1`` cost of distances ``d`` (as least_squares sums it, halved)."""
        z = (d / self.f_scale) ** 2
        return float(np.sum(2.0 * (np.sqrt(1.0 + z) - 1.0)))

    def place(
        self, surf: CapitalSurface, s0: float, ty0: float, span: float, sel: slice = slice(None)
    ) -> tuple[float, float, float]:
        """(s, ty, cost): a scan of ty over ±span at s0 (a few points), then both polished."""
        from scipy.optimize import least_squares

        grid = ty0 + np.linspace(-span, span, 25)
        ty1 = float(
            grid[int(np.argmin([self.robust(self.dist(surf, s0, t, self.few)) for t in grid]))]
        )
        lim = 0.25 * self.size
        sol = least_squares(
            lambda x: self.dist(surf, x[0], x[1], sel),
            np.array([s0, ty1]),
            bounds=([0.85, ty1 - lim], [1.15, ty1 + lim]),
            loss="soft_l1",
            f_scale=self.f_scale,
            x_scale=[0.05, 0.02 * self.size],
            diff_step=1e-4,
            max_nfev=25,
        )
        return float(sol.x[0]), float(sol.x[1]), float(sol.cost)

    def build(self, model: str, x: np.ndarray, count: int = 60_000) -> CapitalSurface | None:
        """The surface of the capital with proportions ``x``, or None where it cannot be."""
        try:
            return capital_surface(
                proportioned(self.cap, model, x), self.top_radius, count=count, outer=True
            )
        except (ParameterError, GeometryError):
            return None

    def grid(
        self,
        model: str,
        x: np.ndarray,
        s: float,
        ty: float,
        which: tuple[int, ...],
        n: int,
        span: float | None = None,
    ) -> np.ndarray:
        """``x`` with each parameter of ``which`` in turn set to the best of ``n`` values
        over its range, or over ``x ± span`` within it (the others and the placement held)."""
        x = x.copy()
        for k in which:
            lo, hi = (LO[k], HI[k]) if span is None else (x[k] - span, x[k] + span)
            vals = np.linspace(max(lo, LO[k]), min(hi, HI[k]), n)
            costs = []
            for v in vals:
                xk = x.copy()
                xk[k] = v
                surf_k = self.build(model, xk)
                costs.append(np.inf if surf_k is None else self.robust(self.dist(surf_k, s, ty)))
            x[k] = vals[int(np.argmin(costs))]
        return x

    def residuals(
        self, xa: np.ndarray, x: np.ndarray, model: str, s: float, ty: float
    ) -> np.ndarray:
        """The distances with the model's active parameters set to ``xa`` (the rest ``x``)."""
        xf = x.copy()
        xf[ACTIVE[model]] = xa
        surf = self.build(model, xf)
        return np.full(len(self.q), 10.0 * self.size) if surf is None else self.dist(surf, s, ty)

    def solve(self, model: str, x: np.ndarray, s: float, ty: float, nfev: int) -> np.ndarray:
        """``x`` with the model's active parameters polished by bounded robust least squares."""
        from scipy.optimize import least_squares

        act = ACTIVE[model]
        sol = least_squares(
            self.residuals,
            np.clip(x[act], LO[act], HI[act]),
            bounds=(LO[act], HI[act]),
            loss="soft_l1",
            f_scale=self.f_scale,
            x_scale=XSCALE[act],
            diff_step=3e-2,
            max_nfev=nfev,
            args=(x, model, s, ty),
        )
        out = x.copy()
        out[act] = sol.x
        return out

    def sized(self, model: str, s0: float, ty0: float) -> tuple[np.ndarray, float, float] | None:
        """The best of a coarse scan of the volute's size, each placed: (x, s, ty), or None.

        The volute's size moves the abacus (it rests on the volutes' top): scanning it first
        keeps a wrong size from being traded for a wrong height."""
        cap, best = self.cap, None
        for vs in (0.5, 0.6, 0.72, 0.86, 1.0, 1.16):
            x0 = X0.copy()
            x0[0], x0[1] = vs, _level_eye(cap, model, vs)
            x0[9] = spiral_growth(cap.volute)
            x0[14] = cap.volute.spiral_circuits
            x0[16] = cap.volute.min_thickness / cap.volute.thickness
            surf0 = self.build(model, x0)
            if surf0 is None:
                continue
            s_i, ty_i, c_i = self.place(surf0, s0, ty0, 0.06 * self.size, self.few)
            if best is None or c_i < best[0]:
                best = (c_i, x0, s_i, ty_i)
        return None if best is None else best[1:]

    def on_rolls(self, model: str, x: np.ndarray, s: float, ty: float) -> np.ndarray:
        """``x``, or the volute moved onto the rolls' circle where that is nearer the points
        (the faces' spirals and the rolls pull the eye apart when the volute's outline is
        not the rolls' circle)."""
        qm = (self.q - np.array([0.0, self.y_top + ty, 0.0])) / s
        xr = _eye_on_rolls(self.cap, model, x, qm, self.f_scale)
        if xr is x:
            return x
        surfs = [self.build(model, xi) for xi in (x, xr)]
        if surfs[1] is not None and (
            surfs[0] is None
            or self.robust(self.dist(surfs[1], s, ty)) < self.robust(self.dist(surfs[0], s, ty))
        ):
            return xr
        return x

    def bolster_on_rolls(self, model: str, x: np.ndarray, s: float, ty: float) -> np.ndarray:
        """``x``, or the bolsters' axis and radius on the rolls' circle (the eye's offset
        from the spiral and the rings' radius moved; the belt kept, or flattened), whichever
        is nearest the points: the faces' spirals pull the eye, and the bolsters on its axis,
        off the rolls (12 mm out and 7 mm down on the whole-column scan) when the model's
        spiral is not the scan's. The volutes' height and the abacus' thickness move with
        them so that the abacus rests on the rolls (it rests on the volutes' top) and its
        top stays where it was."""
        from ionic_usd.column.capital_body import capital_layout

        qm = (self.q - np.array([0.0, self.y_top + ty, 0.0])) / s
        got = roll_circle(qm, proportioned(self.cap, model, x), self.f_scale)
        if got is None:
            return x

        def circle(xx: np.ndarray) -> np.ndarray | None:  # bolsters, abacus seat and top
            try:
                c = proportioned(self.cap, model, xx)
                b = bolster_circle(c, self.top_radius)
                seat = capital_layout(c).abacus_y + c.capital_position_y
            except (ParameterError, GeometryError):
                return None
            return None if b is None else np.append(b, [seat, seat + c.abacus_height])

        now = circle(x)
        if now is None:
            return x
        # the abacus rests on the rolls (their top its seat), its top where it was
        target = np.array([*got, got[1] + got[2], now[4]])
        which = tuple(PROPORTIONS.index(n) for n in _ON_ROLLS)
        cands = [x]
        for belt in dict.fromkeys((float(x[_BELT]), 0.0)):  # the belt kept, and flattened
            xb = x.copy()
            xb[_BELT] = belt
            moved = solve_for(circle, xb, which, target, 1e-4 * self.size)
            if moved is not None and np.all((moved >= LO) & (moved <= HI)):
                cands.append(moved)
        if len(cands) == 1:
            return x
        surfs = [self.build(model, xc) for xc in cands]
        costs = [np.inf if sf is None else self.robust(self.dist(sf, s, ty)) for sf in surfs]
        return cands[int(np.argmin(costs))]

    def sweep(self, model: str, x: np.ndarray, s: float, ty: float) -> np.ndarray:
        """``x`` with each of :data:`SWEPT` in turn set to the best of 9 values over ±15 % of
        its range, the bolsters put back on the rolls after each: the volute's shape once the
        rolls hold its eye (3.41 to 2.86 mm rms on the whole column's seed 0, where the
        least squares' last polish had stopped)."""
        for name in SWEPT:
            k = PROPORTIONS.index(name)
            if k in ACTIVE[model]:
                x = self.grid(model, x, s, ty, (k,), 9, span=0.15 * (HI[k] - LO[k]))
                x = self.bolster_on_rolls(model, x, s, ty)
        return x

    def fit_model(self, model: str, s0: float, ty0: float) -> dict[str, Any] | None:
        """Stages 2 and 3 of the module docstring for one volute model: its report entry
        (with the fitted capital under ``_capital``), or None if no size could be built."""
        start = self.sized(model, s0, ty0)
        if start is None:
            return None
        x, s, ty = start
        x = self.grid(model, np.clip(x, LO, HI), s, ty, GRIDDED_BEFORE, 29)
        x = self.bolster_on_rolls(model, self.on_rolls(model, x, s, ty), s, ty)
        x = self.grid(model, self.solve(model, x, s, ty, 12), s, ty, GRIDDED_AFTER, 13)
        x = self.grid(model, x, s, ty, GRIDDED_AFTER, 9, span=0.5 * (HI[7] - LO[7]) / 12)
        x = self.sweep(model, self.bolster_on_rolls(model, x, s, ty), s, ty)
        xs = self.solve(model, x, s, ty, 4)
        c = proportioned(self.cap, model, xs)
        surf = capital_surface(c, self.top_radius, outer=True)
        s_m, ty_m, cost = self.place(surf, s, ty, 0.02 * self.size)
        d = self.dist(surf, s_m, ty_m)
        u = (xs - LO) / (HI - LO)
        return {
            "cost": cost,
            "rms": float(np.sqrt(np.mean(d**2))),
            "p95": float(np.percentile(d, 95)),
            "proportions": dict(zip(PROPORTIONS, (float(v) for v in xs), strict=True)),
            "scale": s_m,
            "ty": ty_m,
            "bounds_hit": [
                n for n, ui in zip(PROPORTIONS, u, strict=True) if min(ui, 1 - ui) < 1e-3
            ],
            "_capital": c.scaled(s_m),
        }


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
    t0 = time.perf_counter()
    rng = np.random.default_rng(seed)
    keep = rng.permutation(len(col_pts))[:max_points]
    q = np.asarray(col_pts, dtype=np.float64)[keep]
    far = np.full(len(q), np.inf) if other is None else np.asarray(other)[keep]
    if len(q) < 100:
        raise GeometryError(f"too few capital points ({len(q)}) to fit the capital")
    pb = _Problem(q, far, cap, top_radius, y_top)
    start = capital_surface(cap, top_radius, outer=True)
    rms_start = float(np.sqrt(np.mean(pb.dist(start, 1.0, 0.0) ** 2)))
    s0, ty0, _ = pb.place(start, 1.0, 0.0, 0.15 * pb.size)
    models: dict[str, dict[str, Any]] = {}
    for model in ("log_spiral", "centred_arcs"):
        entry = pb.fit_model(model, s0, ty0)
        if entry is not None:
            models[model] = entry
    best = min(models, key=lambda k: models[k]["cost"])
    win = models[best]
    fitted: CapitalParams = win["_capital"]
    for m in models.values():
        del m["_capital"]
    return CapitalFit(
        fitted,
        win["ty"],
        best,
        fitted_values(fitted, win["scale"]),
        models,
        rms_start,
        win["rms"],
        list(win["bounds_hit"]),
        time.perf_counter() - t0,
        len(q),
    )
