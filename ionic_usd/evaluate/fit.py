"""Automatic fitting of model parameters to reference curves — the step beyond the paper.

The paper tuned its parameters by hand; here scipy does it. Every fit minimises a chosen
measure (:data:`FIT_MEASURES`; default the paper's "weak Fréchet", i.e.
:func:`~ionic_usd.evaluate.metrics.hausdorff_distance`) between the generated section
(:mod:`ionic_usd.evaluate.sections`) and the reference, in three stages on parameters mapped to
the unit box:

1. **global** — ``differential_evolution`` (fixed seed, small population, few generations,
   ``polish=False``, the initial parameters as a member of the first population), or for the
   base the layout search and a linear least-squares Bézier fit of every module;
2. **local** — ``least_squares`` (trust region, bounded) on the node-to-curve residuals of
   both curves (smooth, so it converges fast and far);
3. **polish** — bounded Nelder–Mead on the chosen measure itself (it is not differentiable).

The best point seen by any stage wins, so a fit never ends worse than its start. Invalid
parameter sets (any :class:`~ionic_usd.errors.IonicError` from the parameter classes) cost a
large constant instead of stopping the fit. Reported comparisons (``before`` with the initial
parameters, ``after`` with the fitted ones) are :func:`~ionic_usd.evaluate.metrics.compare`
after :func:`~ionic_usd.evaluate.reference.align` (translation, mirror allowed), with the
generated curve oriented like the reference (the Fréchet measures care about direction) and
both curves :func:`densify`-d to segments of at most the reference's length / 500 (so the
discrete measures do not depend on how coarsely a curve happens to be sampled).

Degeneracies, and what is held fixed:

* volute — the outer spiral ``R·(a e^{−cθ}/b − d)`` depends on ``R·a/b`` and ``R·d`` only, so
  ``a`` and ``b`` keep their initial values and ``R`` (the capital spiral radius), ``c``, ``d``,
  the start angle, the spiral circuits and the placement (the spiral origin in the reference
  frame) are fitted. The eye offsets move the eye, not the curve: they are set from ``eye``
  (the eye centre traced in the reference frame) when given, else kept. A mirrored reference
  (a left volute) is handled by the alignment; rotation is not fitted.
* base — the reference is taken in column coordinates after a shift: its top end meets the
  shaft at radius ``d`` (the column's shaft bottom radius) and its first node is the base's
  bottom (override with ``axis_x``). Control points are free, so the shift changes the
  grammar's numbers, not the fit.
* shaft — r is the distance from the axis (a traced silhouette must be measured from the
  axis); the bottom and top radius, the fluted height $a, the entasis and the vertical
  placement are fitted; rings, flute-end ratio and flutes keep their initial values.
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from numba import njit
from scipy.optimize import differential_evolution, least_squares, minimize

from ionic_usd.column.column import ColumnParams, portunus_column_params
from ionic_usd.column.shaft import ShaftParams, shaft_radius_at
from ionic_usd.column.volute import VoluteParams, volute_curve
from ionic_usd.errors import IonicError, OutputExistsError, ParameterError
from ionic_usd.evaluate.metrics import (
    CurveComparison,
    _as_curve,
    _PolylineIndex,
    compare,
    curve_length,
    discrete_frechet_distance,
    frechet_distance,
    resample,
)
from ionic_usd.evaluate.reference import Alignment, align
from ionic_usd.geometry.curves import bezier

__all__ = [
    "FIT_MEASURES",
    "FitResult",
    "BaseLayout",
    "fit_volute",
    "fit_base",
    "fit_shaft",
    "suggest_base_layout",
    "base_grammar_string",
    "orient_like",
    "compare_aligned",
    "densify",
]

#: Measures a fit can minimise (names of :class:`CurveComparison` fields).
FIT_MEASURES = ("hausdorff", "average_error", "discrete_frechet", "frechet")


# -- shared machinery ----------------------------------------------------------------------------
def orient_like(reference: np.ndarray, curve: np.ndarray) -> np.ndarray:
    """``curve`` or its reverse, whichever runs the same way as ``reference`` (end points)."""
    same = np.linalg.norm(reference[0] - curve[0]) + np.linalg.norm(reference[-1] - curve[-1])
    flip = np.linalg.norm(reference[0] - curve[-1]) + np.linalg.norm(reference[-1] - curve[0])
    return curve[::-1].copy() if flip < same else curve


def densify(curve: np.ndarray, max_segment: float) -> np.ndarray:
    """Split every segment into the fewest equal parts no longer than ``max_segment``.

    Unlike :func:`~ionic_usd.evaluate.metrics.resample` it keeps every original node, so
    corners are not cut (which would add up to about half a spacing of error at each).

    Parameters
    ----------
    curve : (n, d) float
    max_segment : float > 0

    Returns
    -------
    (m, d) float, m >= n
    """
    c = _as_curve(curve, "curve", min_nodes=1)
    if not (math.isfinite(max_segment) and max_segment > 0):
        raise ParameterError("max_segment", max_segment, "a length > 0")
    if len(c) < 2:
        return c
    seg = np.linalg.norm(np.diff(c, axis=0), axis=1)
    k = np.maximum(1, np.ceil(seg / max_segment).astype(np.int64))
    idx = np.repeat(np.arange(len(seg)), k)
    t = (np.arange(k.sum()) - np.repeat(np.cumsum(k) - k, k)) / k[idx]
    pts = c[idx] + t[:, None] * (c[idx + 1] - c[idx])
    return np.vstack([pts, c[-1:]])


def compare_aligned(
    reference: np.ndarray, generated: np.ndarray, *, allow_mirror: bool = True,
    spacing: float | None = None, max_segment: float | None = None,
) -> tuple[CurveComparison, Alignment, np.ndarray]:
    """Align ``generated`` to ``reference``, orient it the same way, and compare.

    ``spacing`` resamples both curves (as the paper); ``max_segment`` instead
    :func:`densify`-s them (original nodes kept).

    Returns
    -------
    comparison : CurveComparison (a = reference, b = generated)
    alignment : Alignment
    aligned : (m, 2) float, the moved (and possibly reversed) generated curve
    """
    moved, how = align(reference, generated, allow_mirror=allow_mirror)
    moved = orient_like(reference, moved)
    if max_segment is not None:
        return (compare(densify(reference, max_segment), densify(moved, max_segment),
                        spacing=spacing), how, moved)
    return compare(reference, moved, spacing=spacing), how, moved


@njit(cache=True)
def _closest(points, poly):  # pragma: no cover - compiled
    # exact closest point on the polyline for each point (all segments; fit-sized curves):
    # distance, segment index and parameter t on that segment
    n, m = points.shape[0], poly.shape[0]
    dist = np.empty(n)
    seg = np.zeros(n, dtype=np.int64)
    par = np.zeros(n)
    for i in range(n):
        px, py = points[i, 0], points[i, 1]
        best = np.inf
        for j in range(max(m - 1, 1)):
            ox, oy = poly[j, 0], poly[j, 1]
            vx, vy = 0.0, 0.0
            if m > 1:
                vx, vy = poly[j + 1, 0] - ox, poly[j + 1, 1] - oy
            l2 = vx * vx + vy * vy
            t = ((px - ox) * vx + (py - oy) * vy) / l2 if l2 > 0.0 else 0.0
            t = min(max(t, 0.0), 1.0)
            dx, dy = px - ox - t * vx, py - oy - t * vy
            d2 = dx * dx + dy * dy
            if d2 < best:
                best = d2
                seg[i] = j
                par[i] = t
        dist[i] = math.sqrt(best)
    return dist, seg, par


def _report_spacing(reference: np.ndarray) -> float:
    """Longest segment of the reported comparisons: the reference's length / 500 (raw nodes
    would make the discrete measures depend on how coarsely each curve happens to be
    sampled; :func:`densify` keeps the corners that resampling would cut)."""
    return curve_length(reference) / 500.0


class _Objective:
    """The chosen measure and the least-squares residuals against one fixed reference."""

    def __init__(self, reference: np.ndarray, measure: str) -> None:
        if measure not in FIT_MEASURES:
            raise ParameterError("measure", measure, f"one of {', '.join(FIT_MEASURES)}")
        self.ref = np.ascontiguousarray(reference, dtype=np.float64)
        self.measure = measure
        self.calls = 0

    def both(self, gen: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        # brute force in numba: for fit-sized curves (hundreds of nodes) it beats the kd-tree
        # index, whose exactness loop re-queries many nodes of a badly placed candidate
        gen = np.ascontiguousarray(gen, dtype=np.float64)
        return _closest(gen, self.ref)[0], _closest(self.ref, gen)[0]

    def value(self, gen: np.ndarray) -> float:
        self.calls += 1
        if self.measure == "discrete_frechet":
            return discrete_frechet_distance(self.ref, gen)
        if self.measure == "frechet":
            return frechet_distance(self.ref, gen, tol=1e-4)
        da, db = self.both(gen)
        if self.measure == "hausdorff":
            return float(max(da.max(), db.max()))
        return float((da.sum() + db.sum()) / (da.size + db.size))

    def residuals(self, gen: np.ndarray) -> np.ndarray:
        self.calls += 1
        da, db = self.both(gen)
        # per-node weights so both curves count equally whatever their node counts
        return np.concatenate([da / math.sqrt(da.size), db / math.sqrt(db.size)])

    def jacobian(self, gen: np.ndarray, dgen: np.ndarray) -> np.ndarray:
        """d residuals / d params from the curve's derivative ``dgen`` (m, 2, k).

        A node-to-curve distance |p − q| changes along the unit vector (p − q)/|p − q| only
        (the foot point q slides along the segment to first order), so
        d|g_j − q| = n · dg_j for generated nodes and d|p − q| = −n · ((1 − t) dg_j +
        t dg_{j+1}) for reference nodes whose foot lies on generated segment j.
        """
        gen = np.ascontiguousarray(gen, dtype=np.float64)
        m, n = len(gen), len(self.ref)
        da, seg_a, t_a = _closest(gen, self.ref)  # generated nodes → reference
        db, seg_b, t_b = _closest(self.ref, gen)  # reference nodes → generated
        foot_a = (self.ref[seg_a] * (1 - t_a)[:, None]
                  + self.ref[np.minimum(seg_a + 1, n - 1)] * t_a[:, None])
        na = np.divide(gen - foot_a, da[:, None], out=np.zeros_like(gen), where=da[:, None] > 0)
        ja = np.einsum("ic,ick->ik", na, dgen)
        j1 = np.minimum(seg_b + 1, m - 1)
        dq = dgen[seg_b] * (1 - t_b)[:, None, None] + dgen[j1] * t_b[:, None, None]
        foot_b = gen[seg_b] * (1 - t_b)[:, None] + gen[j1] * t_b[:, None]
        nb = np.divide(self.ref - foot_b, db[:, None], out=np.zeros_like(self.ref),
                       where=db[:, None] > 0)
        jb = -np.einsum("ic,ick->ik", nb, dq)
        return np.vstack([ja / math.sqrt(m), jb / math.sqrt(n)])


@dataclass
class _Stages:
    """Runs the three stages on a curve generator over the unit box."""

    make: Callable[[np.ndarray], np.ndarray | None]  # unit-box params → curve, None if invalid
    objective: _Objective
    penalty: float
    best_u: np.ndarray = field(init=False)
    best_f: float = field(init=False, default=math.inf)
    iterations: int = field(init=False, default=0)
    n_res: int = field(init=False, default=0)
    ls_evals: int = 20
    dgen: np.ndarray | None = None  # constant curve derivative (m, 2, k), if linear

    def cost(self, u: np.ndarray) -> float:
        u = np.clip(u, 0.0, 1.0)
        gen = self.make(u)
        if gen is None:
            self.objective.calls += 1
            return self.penalty
        f = self.objective.value(gen)
        if f < self.best_f:
            self.best_f, self.best_u = f, u.copy()
        return f

    def residuals(self, u: np.ndarray) -> np.ndarray:
        gen = self.make(np.clip(u, 0.0, 1.0))
        if gen is None:
            self.objective.calls += 1
            return np.full(self.n_res, self.penalty)
        r = self.objective.residuals(gen)
        return r

    def jacobian(self, u: np.ndarray) -> np.ndarray:
        """Residual Jacobian: the curve's derivative by forward differences (cheap: curves
        only), the distances' derivative analytically (:meth:`_Objective.jacobian`)."""
        u = np.clip(u, 0.0, 1.0)
        gen = self.make(u)
        k = len(u)
        if gen is None:
            return np.zeros((self.n_res, k))
        if self.dgen is not None:  # a curve linear in its parameters
            return self.objective.jacobian(gen, self.dgen)
        dgen = np.zeros((*gen.shape, k))
        h = 1e-7
        for i in range(k):
            step = h if u[i] + h <= 1.0 else -h
            v = u.copy()
            v[i] += step
            g = self.make(v)
            if g is not None and g.shape == gen.shape:
                dgen[:, :, i] = (g - gen) / step
        return self.objective.jacobian(gen, dgen)

    def run(self, u0: np.ndarray, *, seed: int, global_stage: bool, popsize: int,
            maxiter: int, polish_evals: int) -> None:
        self.cost(u0)
        k = len(u0)
        if global_stage:
            res = differential_evolution(
                self.cost, [(0.0, 1.0)] * k, seed=seed, popsize=popsize, maxiter=maxiter,
                polish=False, tol=1e-10, init="latinhypercube", x0=u0, updating="immediate",
            )
            self.iterations += int(res.nit)
        gen = self.make(self.best_u)
        assert gen is not None
        self.n_res = len(self.objective.residuals(gen))
        ls = least_squares(self.residuals, self.best_u.copy(), jac=self.jacobian,
                           bounds=(0.0, 1.0), method="trf",
                           tr_solver="lsmr" if k > 24 else "exact", x_scale="jac",
                           xtol=1e-10, ftol=1e-10, gtol=1e-10,
                           max_nfev=self.ls_evals * (k + 1))
        self.iterations += int(ls.nfev)
        self.cost(ls.x)
        if polish_evals > 0:
            start = self.best_u.copy()
            step = 0.01 if global_stage else 0.002
            simplex = np.vstack([start, start + step * np.eye(k) * np.where(start > 0.5, -1, 1)])
            nm = minimize(self.cost, start, method="Nelder-Mead", bounds=[(0.0, 1.0)] * k,
                          options={"initial_simplex": simplex, "maxfev": polish_evals,
                                   "xatol": 1e-9, "fatol": 1e-12})
            self.iterations += int(nm.nit)


@dataclass(frozen=True, eq=False)
class FitResult:
    """A fit's outcome.

    Attributes
    ----------
    part : ``"volute"``, ``"base"`` or ``"shaft"``
    params : VoluteParams, the base grammar string, or ShaftParams
    column : ColumnParams with the fitted part (what ``ionic-usd column --config`` rebuilds)
    before, after : CurveComparison
        Reference (a) against the section with the initial / fitted parameters, aligned.
    measure : the minimised measure
    iterations : DE generations + least-squares evaluations + Nelder–Mead iterations
    evaluations : curve evaluations
    seconds : wall time
    reference : (n, 2) float, the reference as compared
    fitted, initial : (m, 2) float, the fitted / initial sections aligned to the reference
    alignment : Alignment of the fitted section
    notes : what was held fixed or inferred
    """

    part: str
    params: object
    column: ColumnParams
    before: CurveComparison
    after: CurveComparison
    measure: str
    iterations: int
    evaluations: int
    seconds: float
    reference: np.ndarray
    fitted: np.ndarray
    initial: np.ndarray
    alignment: Alignment
    notes: tuple[str, ...] = ()

    def tables(self) -> dict[str, dict]:
        """TOML tables for ``ionic-usd column --config``: only what the fit changed."""
        from ionic_usd.column.column import column_params_to_tables

        t = column_params_to_tables(self.column)
        if self.part == "volute":
            return {"volute": t["volute"]}
        if self.part == "shaft":
            return {"shaft": t["shaft"]}
        return {"column": {"base": t["column"]["base"],
                           "base_height": t["column"]["base_height"]}}

    def to_toml(self) -> str:
        from ionic_usd.column.column import COLUMN_DOCS
        from ionic_usd.column.shaft import SHAFT_PARAMETER_DOCS
        from ionic_usd.column.volute import VOLUTE_PARAMETER_DOCS
        from ionic_usd.params import to_toml

        docs = {"column": COLUMN_DOCS, "shaft": SHAFT_PARAMETER_DOCS,
                "volute": VOLUTE_PARAMETER_DOCS}
        a, b = self.before, self.after
        header = (
            f"ionic_usd fit of the {self.part} ({self.measure}); pass to "
            "`ionic-usd column --config`\n"
            f"before: {getattr(a, self.measure):.6g} m ({a.percent(self.measure):.3f} %), "
            f"after: {getattr(b, self.measure):.6g} m ({b.percent(self.measure):.3f} %)"
        )
        return to_toml(self.tables(), docs, header=header)

    def write_toml(self, path: str | Path, *, force: bool = False) -> Path:
        """Write :meth:`to_toml` atomically; refuse to overwrite without ``force``."""
        from ionic_usd.evaluate.report import _atomic_write

        path = Path(path)
        if path.exists() and not force:
            raise OutputExistsError(f"{path} exists; pass --force (force=True) to overwrite it")
        text = self.to_toml().encode("utf-8")
        return _atomic_write(path, lambda fh: fh.write(text))


def _check_common(reference: object, measure: str, seed: object) -> np.ndarray:
    ref = _as_curve(reference, "reference", min_nodes=2)
    if ref.shape[1] != 2:
        raise ParameterError("reference", f"shape {ref.shape}", "an (n, 2) curve")
    if curve_length(ref) <= 0:
        raise ParameterError("reference", "a zero-length curve", "a curve of positive length")
    if measure not in FIT_MEASURES:
        raise ParameterError("measure", measure, f"one of {', '.join(FIT_MEASURES)}")
    if isinstance(seed, bool) or not isinstance(seed, int):
        raise ParameterError("seed", seed, "an integer")
    return ref


class _Box:
    """Parameter bounds; optimisers work on u ∈ [0, 1]^k."""

    def __init__(self, lo: Sequence[float], hi: Sequence[float]) -> None:
        self.lo, self.hi = np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)

    def x(self, u: np.ndarray) -> np.ndarray:
        return self.lo + np.asarray(u) * (self.hi - self.lo)

    def u(self, x: np.ndarray) -> np.ndarray:
        return np.clip((np.asarray(x) - self.lo) / (self.hi - self.lo), 0.0, 1.0)


# -- volute ---------------------------------------------------------------------------------------
def fit_volute(
    reference: np.ndarray,
    *,
    initial: VoluteParams | None = None,
    measure: str = "hausdorff",
    eye: Sequence[float] | None = None,
    samples: int = 256,
    seed: int = 0,
    popsize: int = 8,
    maxiter: int = 30,
    polish_evals: int = 600,
    allow_mirror: bool = True,
    column: ColumnParams | None = None,
) -> FitResult:
    """Fit the volute's spiral to a traced outer spiral edge.

    Parameters
    ----------
    reference : (n, 2) float
        The outer edge of the spiral band in metres, any origin, either direction.
    initial : VoluteParams, optional
        Start (default: the column's volute, i.e. Vitruvius for Portunus).
    measure : one of :data:`FIT_MEASURES`
    eye : (2,) float, optional
        The eye centre in the reference's frame; sets ``offset_x``/``offset_y``.
    samples : nodes of the generated spiral while fitting
    seed, popsize, maxiter : differential evolution settings
    polish_evals : Nelder–Mead evaluations (0: no polish)
    allow_mirror : the reference may wind the other way (a left volute)
    column : ColumnParams the fitted volute is put into (default: Portunus)

    Returns
    -------
    FitResult with ``params`` a :class:`VoluteParams`.
    """
    t0 = time.perf_counter()
    ref = _check_common(reference, measure, seed)
    column = column or portunus_column_params()
    v0 = initial or column.capital.volute
    if not isinstance(v0, VoluteParams):
        raise ParameterError("initial", v0, "a VoluteParams")
    first = volute_curve(v0, samples)
    moved, how = align(ref, first, allow_mirror=allow_mirror)
    ref_o = orient_like(moved, ref)  # run the reference the way θ runs (Fréchet measures)
    sign = -1.0 if how.mirrored else 1.0
    t_init = np.asarray(how.translation)
    diag = float(np.linalg.norm(np.ptp(ref, axis=0)))
    n_max = v0.spiral_circuits + 0.5
    x0 = np.array([math.log(v0.capital_spiral_radius), v0.c, v0.d, v0.start_angle,
                   v0.spiral_circuits, *t_init])
    dc = 0.6 * abs(v0.c) if v0.c else 0.05
    box = _Box(
        [x0[0] - math.log(1.6), v0.c - dc, v0.d - max(0.5 * abs(v0.d), 0.1), v0.start_angle - 60,
         max(1.0, v0.spiral_circuits - 0.5), t_init[0] - 0.25 * diag, t_init[1] - 0.25 * diag],
        [x0[0] + math.log(1.6), v0.c + dc, v0.d + max(0.5 * abs(v0.d), 0.1), v0.start_angle + 60,
         n_max, t_init[0] + 0.25 * diag, t_init[1] + 0.25 * diag],
    )

    def params_of(x: np.ndarray) -> VoluteParams:
        return v0.with_(capital_spiral_radius=float(math.exp(x[0])), c=float(x[1]),
                        d=float(x[2]), start_angle=float(x[3]), spiral_circuits=float(x[4]))

    def make(u: np.ndarray) -> np.ndarray | None:
        x = box.x(u)
        try:
            curve = volute_curve(params_of(x), samples)
        except IonicError:
            return None
        curve[:, 0] *= sign
        curve += x[5:7]
        return curve

    obj = _Objective(ref_o, measure)
    stages = _Stages(make, obj, penalty=10.0 * diag)
    stages.run(box.u(x0), seed=seed, global_stage=True, popsize=popsize, maxiter=maxiter,
               polish_evals=polish_evals)
    x = box.x(stages.best_u)
    fitted = params_of(x)
    notes = ["a, b held (the curve depends on R·a/b and R·d); R, c, d, start angle, circuits "
             "and the spiral origin fitted"]
    if eye is not None:
        e = np.asarray(eye, dtype=float)
        if e.shape != (2,) or not np.all(np.isfinite(e)):
            raise ParameterError("eye", eye, "two finite numbers (x, y)")
        off = (e - x[5:7]) * np.array([sign, 1.0])
        fitted = fitted.with_(offset_x=float(off[0]), offset_y=float(off[1]))
        notes.append("offsets from the given eye centre")
    else:
        notes.append("offsets kept (they move the eye, not the spiral)")
    col = dataclasses.replace(column, capital=column.capital.with_(volute=fitted))
    init_al = orient_like(ref_o, moved)  # the start's alignment, computed above
    h = _report_spacing(ref_o)
    before = compare(densify(ref_o, h), densify(init_al, h))
    after, al, fit_al = compare_aligned(ref_o, volute_curve(fitted, samples),
                                        allow_mirror=allow_mirror,
                                        max_segment=_report_spacing(ref_o))
    return FitResult("volute", fitted, col, before, after, measure, stages.iterations,
                     obj.calls, time.perf_counter() - t0, ref_o, fit_al, init_al, al,
                     tuple(notes))


# -- base -----------------------------------------------------------------------------------------
@dataclass(frozen=True)
class BaseLayout:
    """Module layout of a Bézier base fit.

    Attributes
    ----------
    breaks : (k + 1,) int — indices into the resampled reference where modules start/end
    points : (k,) int — control points per module (2: a straight segment, 4: a cubic)
    """

    breaks: tuple[int, ...]
    points: tuple[int, ...]

    def __post_init__(self) -> None:
        if len(self.breaks) != len(self.points) + 1 or not self.points:
            raise ParameterError("layout", self, "k + 1 breaks for k modules, k >= 1")
        if any(b1 <= b0 for b0, b1 in zip(self.breaks, self.breaks[1:], strict=False)):
            raise ParameterError("breaks", self.breaks, "strictly increasing indices")
        if any(p < 2 for p in self.points):
            raise ParameterError("points", self.points, "at least 2 control points per module")


def _turning(p: np.ndarray, w: int) -> np.ndarray:
    """Turning angle (rad) at every node between the chords to ±w nodes away."""
    n = len(p)
    i = np.arange(n)
    a, b = p[np.clip(i - w, 0, n - 1)], p[np.clip(i + w, 0, n - 1)]
    d1, d2 = p - a, b - p
    ang = np.arctan2(d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0], (d1 * d2).sum(axis=1))
    ang[(np.linalg.norm(d1, axis=1) == 0) | (np.linalg.norm(d2, axis=1) == 0)] = 0.0
    return np.abs(ang)


def _fit_bezier_piece(piece: np.ndarray, n_points: int) -> tuple[np.ndarray, float]:
    """Least-squares Bézier with fixed end points (chord-length parameters, refined twice).

    Returns
    -------
    control : (n_points, 2) float
    error : largest node-to-curve distance of the piece
    """
    p0, p1 = piece[0], piece[-1]
    if n_points == 2 or len(piece) <= n_points:
        ctrl = np.linspace(p0, p1, n_points)
        return ctrl, float(_PolylineIndex(np.vstack([p0, p1])).distances(piece).max())
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(piece, axis=0), axis=1))])
    t = s / s[-1]
    n = n_points - 1
    from math import comb

    ctrl = np.linspace(p0, p1, n_points)
    for _ in range(3):
        basis = np.stack([comb(n, i) * t**i * (1 - t) ** (n - i) for i in range(n + 1)], axis=1)
        rhs = piece - np.outer(basis[:, 0], p0) - np.outer(basis[:, -1], p1)
        inner, *_ = np.linalg.lstsq(basis[:, 1:-1], rhs, rcond=None)
        ctrl = np.vstack([p0, inner, p1])
        dense = bezier(ctrl, np.linspace(0, 1, 257))
        # re-parameterise: each node at the parameter of its nearest dense sample
        from scipy.spatial import cKDTree

        _, j = cKDTree(dense).query(piece)
        t = np.maximum.accumulate(j / 256.0)
        t[0], t[-1] = 0.0, 1.0
    err = float(_PolylineIndex(bezier(ctrl, np.linspace(0, 1, 129))).distances(piece).max())
    return ctrl, err


def suggest_base_layout(
    profile: np.ndarray, *, tolerance: float | None = None, max_modules: int = 24
) -> BaseLayout:
    """Split a base profile into Bézier modules.

    The profile (bottom to top) is resampled to 400 nodes; it is cut at tangent breaks
    (turning angle over ±1 % of its length above 35°, one cut per run) and at local extrema of
    r with a prominence above 0.5 % of its length (the outermost point of a torus, the
    innermost of a scotia). Each piece becomes a straight 2-point module when it deviates less
    than ``tolerance`` from its chord, else a cubic (4 points); a cubic that misses the piece
    by more than ``tolerance`` is split at its worst node, until ``max_modules``.

    Parameters
    ----------
    profile : (n, 2) float
    tolerance : float, optional
        Metres; default 0.05 % of the profile's length.

    Returns
    -------
    BaseLayout (indices refer to ``resample(profile, count=400)``)
    """
    prof = _as_curve(profile, "profile", min_nodes=2)
    length = curve_length(prof)
    tol = 5e-4 * length if tolerance is None else float(tolerance)
    if not (math.isfinite(tol) and tol > 0):
        raise ParameterError("tolerance", tolerance, "a length > 0")
    p = resample(prof, count=400)
    n = len(p)
    turn = _turning(p, 4)
    cand: set[int] = {0, n - 1}
    hot = turn > math.radians(35)
    k = 0
    while k < n:
        if hot[k]:
            j = k
            while j + 1 < n and hot[j + 1]:
                j += 1
            cand.add(int(k + np.argmax(turn[k:j + 1])))
            k = j + 1
        else:
            k += 1
    from scipy.signal import find_peaks

    for sgn in (1.0, -1.0):
        peaks, _ = find_peaks(sgn * p[:, 0], prominence=5e-3 * length)
        cand.update(int(i) for i in peaks)
    breaks = sorted(c for c in cand)
    breaks = [b for i, b in enumerate(breaks) if i == 0 or b - breaks[i - 1] >= 2]
    if breaks[-1] != n - 1:
        breaks[-1] = n - 1
    pieces: list[tuple[int, int]] = list(zip(breaks[:-1], breaks[1:], strict=True))
    out: list[tuple[int, int, int]] = []
    while pieces:
        i, j = pieces.pop(0)
        seg = p[i:j + 1]
        chord_err = float(_PolylineIndex(seg[[0, -1]]).distances(seg).max())
        if chord_err <= tol:
            out.append((i, j, 2))
            continue
        ctrl, err = _fit_bezier_piece(seg, 4)
        if err > tol and j - i >= 8 and len(out) + len(pieces) + 2 <= max_modules:
            d = _PolylineIndex(bezier(ctrl, np.linspace(0, 1, 129))).distances(seg)
            m = i + int(np.clip(np.argmax(d), 3, j - i - 3))
            pieces[:0] = [(i, m), (m, j)]
            continue
        out.append((i, j, 4))
    out.sort()
    return BaseLayout(tuple([o[0] for o in out] + [out[-1][1]]), tuple(o[2] for o in out))


def _layout_for_modules(p: np.ndarray, modules: Sequence[int]) -> BaseLayout:
    """Breaks for a given number of modules: the strongest suggested cuts, else arc length."""
    k = len(modules)
    sug = suggest_base_layout(p, max_modules=max(k, 2))
    p = resample(p, count=400)  # the suggestion's indices refer to this resampling
    inner = list(sug.breaks[1:-1])
    n = len(p)
    if len(inner) > k - 1:
        # keep the cuts with the sharpest turn
        turn = _turning(p, 4)
        inner = sorted(sorted(inner, key=lambda b: -turn[b])[: k - 1])
    while len(inner) < k - 1:
        edges = [0, *inner, n - 1]
        gaps = np.diff(edges)
        g = int(np.argmax(gaps))
        inner.append(int(edges[g] + gaps[g] // 2))
        inner.sort()
    return BaseLayout(tuple([0, *inner, n - 1]), tuple(int(m) for m in modules))


def base_grammar_string(modules: Sequence[np.ndarray], shaft_radius: float) -> str:
    """Bézier grammar v2 text for modules of absolute control points ``(R, y)``.

    Each module's ``r = R − d`` and ``h = y − (module bottom)``; the bottom of module k is the
    last control point's y of module k − 1 (the first module's bottom is y = 0).
    """
    def num(v: float) -> str:
        v = 0.0 if abs(v) < 5e-10 else float(v)
        return f"{v:.9g}"

    parts = []
    y0 = 0.0
    for ctrl in modules:
        toks = []
        for r, y in ctrl:
            toks.append(f"R{num(r - shaft_radius)} H{num(max(y - y0, 0.0))}")
        parts.append(" ".join(toks))
        y0 = max(float(ctrl[-1, 1]), y0)
    return ", ".join(parts)


def fit_base(
    reference: np.ndarray,
    *,
    modules: Sequence[int] | None = None,
    initial: ColumnParams | None = None,
    measure: str = "hausdorff",
    axis_x: float | None = None,
    seed: int = 0,
    polish_evals: int = 1500,
    tolerance: float | None = None,
) -> FitResult:
    """Fit a Bézier base grammar (v2) to a traced base half-profile.

    Parameters
    ----------
    reference : (n, 2) float
        The profile (r, y) in metres, bottom to top or top to bottom.
    modules : sequence of int, optional
        Control points per module, bottom to top (e.g. ``[2, 4, 4, 2]``); default:
        :func:`suggest_base_layout`.
    initial : ColumnParams
        The column to put the base into (default: Portunus); its shaft bottom radius is the
        grammar's d and its LOD's base slices sample the modules.
    measure : one of :data:`FIT_MEASURES`
    axis_x : float, optional
        x of the column axis in the reference; default: the top end lies at radius d.
    seed : unused by the base's deterministic global stage; accepted for a uniform API
    polish_evals : Nelder–Mead evaluations on the measure (0: none)
    tolerance : layout tolerance (m), see :func:`suggest_base_layout`

    Returns
    -------
    FitResult with ``params`` the grammar string; ``column.base`` is that string and
    ``column.base_height`` its height, so the column rebuilds the fitted base at scale 1.
    """
    from ionic_usd.evaluate.sections import base_section

    t0 = time.perf_counter()
    ref = _check_common(reference, measure, seed)
    column = initial or portunus_column_params()
    if ref[0, 1] > ref[-1, 1]:
        ref = ref[::-1].copy()
    d = column.shaft.bottom_radius
    ax = float(ref[-1, 0] - d) if axis_x is None else float(axis_x)
    shift = np.array([ax, ref[0, 1]])
    ref_c = ref - shift
    p = resample(ref_c, count=400)
    if modules is None:
        layout = suggest_base_layout(ref_c, tolerance=tolerance)
    else:
        mods = list(modules)
        if not mods or any(isinstance(m, bool) or int(m) != m or m < 2 for m in mods):
            raise ParameterError("modules", modules, "control points per module, each >= 2")
        layout = _layout_for_modules(ref_c, mods)
    slices = column.base_params().profile_slices
    ctrls = [_fit_bezier_piece(p[i:j + 1], m)[0] for i, j, m in
             zip(layout.breaks[:-1], layout.breaks[1:], layout.points, strict=True)]

    # parameter vector: the first point's R, then per module its points after the first as
    # (R, h above the module bottom); bounds keep R > 0 and h >= 0 (the grammar's rules)
    size = float(np.ptp(ref_c, axis=0).max())
    x0 = [ctrls[0][0, 0]]
    y_bottom = 0.0
    for c in ctrls:
        for r, y in c[1:]:
            x0 += [r, max(y - y_bottom, 0.0)]
        y_bottom = max(float(c[-1, 1]), y_bottom)
    x0 = np.asarray(x0)
    lo = np.where(np.arange(len(x0)) % 2 == 0, 1e-4 * size, 0.0)  # R (even), h (odd)
    lo = np.minimum(lo, x0)
    box = _Box(lo, np.maximum(x0 + 0.5 * size, lo + 1e-6))
    counts = layout.points
    ts = {m: np.linspace(0.0, 1.0, 2 if m == 2 else slices + 1) for m in set(counts)}

    def controls(x: np.ndarray) -> list[np.ndarray]:
        out, k, y0 = [], 1, 0.0
        start = np.array([x[0], 0.0])
        for m in counts:
            pts = [start]
            for _ in range(m - 1):
                pts.append(np.array([x[k], y0 + x[k + 1]]))
                k += 2
            c = np.array(pts)
            out.append(c)
            y0 = float(c[-1, 1])
            start = c[-1]
        return out

    def curve_of(x: np.ndarray) -> np.ndarray:
        cs = controls(x)
        return np.vstack([cs[0][:1]] + [bezier(c, ts[len(c)])[1:] for c in cs])

    # the curve is linear in x (Bézier points are linear in the control points, which are
    # linear in x while h >= 0): tabulate it once, then every evaluation is one matrix product
    g0 = curve_of(np.zeros_like(x0))
    lin = np.stack([curve_of(np.eye(len(x0))[i]) - g0 for i in range(len(x0))], axis=-1)
    dgen = lin * (box.hi - box.lo)

    def make(u: np.ndarray) -> np.ndarray | None:
        return g0 + lin @ box.x(u)

    obj = _Objective(ref_c, measure)
    stages = _Stages(make, obj, penalty=10.0 * size, ls_evals=4, dgen=dgen)
    stages.run(box.u(x0), seed=seed, global_stage=False, popsize=0, maxiter=0,
               polish_evals=polish_evals)
    grammar = base_grammar_string(controls(box.x(stages.best_u)), d)
    from ionic_usd.grammar.base import parse_base_grammar

    height = parse_base_grammar(grammar, 2).height
    col = dataclasses.replace(column, base=grammar, base_height=height)
    before, _, init_al = compare_aligned(ref, base_section(column), allow_mirror=False,
                                           max_segment=_report_spacing(ref))
    after, al, fit_al = compare_aligned(ref, base_section(col), allow_mirror=False,
                                           max_segment=_report_spacing(ref))
    notes = (f"{len(counts)} modules, points {list(counts)}",
             f"reference shifted by ({-shift[0]:+.6g}, {-shift[1]:+.6g}) m into column "
             f"coordinates (shaft radius d = {d:g} m)")
    return FitResult("base", grammar, col, before, after, measure, stages.iterations,
                     obj.calls, time.perf_counter() - t0, ref, fit_al, init_al, al, notes)


# -- shaft ----------------------------------------------------------------------------------------
def fit_shaft(
    reference: np.ndarray,
    *,
    initial: ColumnParams | None = None,
    measure: str = "hausdorff",
    ends: bool | None = None,
    samples: int = 201,
    seed: int = 0,
    popsize: int = 8,
    maxiter: int = 20,
    polish_evals: int = 400,
) -> FitResult:
    """Fit the shaft's bottom and top radius, fluted height, entasis and vertical placement.

    Parameters
    ----------
    reference : (n, 2) float
        The silhouette (r, y) in metres, r from the column axis, either direction.
    initial : ColumnParams (default: Portunus)
    measure : one of :data:`FIT_MEASURES`
    ends : bool, optional
        Whether the reference runs in to the axis at both ends (as
        :func:`~ionic_usd.evaluate.sections.shaft_silhouette_section`); default: detected
        (both end nodes closer to the axis than 20 % of the largest r).

    Returns
    -------
    FitResult with ``params`` a :class:`ShaftParams`.
    """
    from ionic_usd.evaluate.sections import shaft_silhouette_section

    t0 = time.perf_counter()
    ref = _check_common(reference, measure, seed)
    column = initial or portunus_column_params()
    if ref[0, 1] > ref[-1, 1]:
        ref = ref[::-1].copy()
    rmax = float(np.abs(ref[:, 0]).max())
    if ends is None:
        ends = bool(abs(ref[0, 0]) < 0.2 * rmax and abs(ref[-1, 0]) < 0.2 * rmax)
    s0 = column.shaft_params()
    span = float(np.ptp(ref[:, 1]))
    y_base = column.base_params().height
    x0 = np.array([s0.bottom_radius, s0.top_radius, s0.height, s0.entasis, y_base])
    # start from the reference's own extent when the initial shaft is far from it
    fixed = s0.length - s0.height
    body = span - fixed
    if body > 0:
        x0[2] = body
    x0[4] = float(ref[:, 1].min())
    x0[0] = float(np.clip(x0[0], 0.3 * rmax, 1.5 * rmax))
    x0[1] = float(np.clip(x0[1], 0.3 * rmax, 1.5 * rmax))
    box = _Box([0.3 * rmax, 0.3 * rmax, max(0.3 * x0[2], 1e-3), -0.2, x0[4] - 0.2 * span],
               [1.5 * rmax, 1.5 * rmax, 1.5 * x0[2] + 1e-3, 0.2, x0[4] + 0.2 * span])
    ys01 = np.linspace(0.0, 1.0, samples)

    def shaft_of(x: np.ndarray) -> ShaftParams:
        return dataclasses.replace(s0, bottom_radius=float(x[0]), top_radius=float(x[1]),
                                   height=float(x[2]), entasis=float(x[3]))

    def make(u: np.ndarray) -> np.ndarray | None:
        x = box.x(u)
        try:
            sp = shaft_of(x)
        except IonicError:
            return None
        ys = ys01 * sp.length
        out = np.column_stack([shaft_radius_at(sp, ys), ys + x[4]])
        if ends:
            out = np.vstack([[0.0, x[4]], out, [0.0, x[4] + sp.length]])
        return out

    obj = _Objective(ref, measure)
    stages = _Stages(make, obj, penalty=10.0 * (span + rmax))
    stages.run(box.u(x0), seed=seed, global_stage=True, popsize=popsize, maxiter=maxiter,
               polish_evals=polish_evals)
    x = box.x(stages.best_u)
    fitted = shaft_of(x)
    col = dataclasses.replace(column, shaft=dataclasses.replace(
        column.shaft, bottom_radius=fitted.bottom_radius, top_radius=fitted.top_radius,
        height=fitted.height, entasis=fitted.entasis))

    def section(c: ColumnParams) -> np.ndarray:
        return shaft_silhouette_section(c, samples=samples, ends=ends)

    before, _, init_al = compare_aligned(ref, section(column), allow_mirror=False,
                                           max_segment=_report_spacing(ref))
    after, al, fit_al = compare_aligned(ref, section(col), allow_mirror=False,
                                           max_segment=_report_spacing(ref))
    notes = ("rings, flute-end ratio and flutes kept; r measured from the axis",
             f"ends {'included' if ends else 'left out'}; shaft bottom at y = {x[4]:.6g} m "
             "in the reference")
    return FitResult("shaft", fitted, col, before, after, measure, stages.iterations,
                     obj.calls, time.perf_counter() - t0, ref, fit_al, init_al, al, notes)
