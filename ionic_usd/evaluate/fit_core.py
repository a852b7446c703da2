"""Shared machinery of the fits: objective, three-stage optimiser, bounds, result.

Every fit minimises a chosen measure (:data:`FIT_MEASURES`; default the paper's "weak Fréchet",
i.e. :func:`~ionic_usd.evaluate.metrics.hausdorff_distance`) between a generated curve and the
reference, in three stages on parameters mapped to the unit box:

1. **global** — ``differential_evolution`` (fixed seed, small population, few generations,
   ``polish=False``, the initial parameters as a member of the first population);
2. **local** — ``least_squares`` (trust region, bounded) on the node-to-curve residuals of
   both curves (smooth, so it converges fast and far);
3. **polish** — bounded Nelder–Mead on the chosen measure itself (it is not differentiable).

The best point seen by any stage wins, so a fit never ends worse than its start. Invalid
parameter sets (any :class:`~ionic_usd.errors.IonicError` from the parameter classes) cost a
large constant instead of stopping the fit. Bounds are derived from the reference itself (its
size, its turns) by each part's module; a fitted parameter that ends within 0.1 % of the box
edge is reported in :attr:`FitResult.bounds_hit` (the optimum may lie outside).

Reported comparisons are :func:`~ionic_usd.evaluate.metrics.compare` after alignment, with
both curves :func:`densify`-d to segments of at most the reference's length / 2000 (so the
discrete measures do not depend on how coarsely a curve happens to be sampled).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike
from scipy.optimize import differential_evolution, least_squares, minimize

from ionic_usd.column.column import ColumnParams
from ionic_usd.errors import OutputExistsError, ParameterError
from ionic_usd.evaluate import FIT_MEASURES  # the package's light vocabulary
from ionic_usd.evaluate.metrics import (
    CurveComparison,
    compare,
    curve_length,
    discrete_frechet_distance,
    frechet_distance,
)
from ionic_usd.evaluate.polyline import as_curve, closest_on_polyline
from ionic_usd.evaluate.reference import Alignment, align

__all__ = [
    "FIT_MEASURES",
    "Box",
    "FitResult",
    "Objective",
    "Stages",
    "check_fit_inputs",
    "report_spacing",
    "orient_like",
    "compare_aligned",
    "densify",
]


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
    c = as_curve(curve, "curve", min_nodes=1)
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
    reference: np.ndarray,
    generated: np.ndarray,
    *,
    allow_mirror: bool = True,
    spacing: float | None = None,
    max_segment: float | None = None,
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
        return (
            compare(densify(reference, max_segment), densify(moved, max_segment), spacing=spacing),
            how,
            moved,
        )
    return compare(reference, moved, spacing=spacing), how, moved


def report_spacing(reference: np.ndarray) -> float:
    """Longest segment of the reported comparisons: the reference's length / 2000 (raw nodes
    would make the discrete measures depend on how coarsely each curve happens to be
    sampled; :func:`densify` keeps the corners that resampling would cut)."""
    return curve_length(reference) / 2000.0


class Objective:
    """The chosen measure and the least-squares residuals against one fixed reference."""

    def __init__(self, reference: np.ndarray, measure: str) -> None:
        if measure not in FIT_MEASURES:
            raise ParameterError("measure", measure, f"one of {', '.join(FIT_MEASURES)}")
        self.ref = np.ascontiguousarray(reference, dtype=np.float64)
        self.measure = measure
        self.calls = 0

    def both(self, gen: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        # the compiled grid kernel: for fit-sized curves (hundreds of nodes) it beats the
        # kd-tree index, whose exactness loop re-queries many nodes of a badly placed candidate
        gen = np.ascontiguousarray(gen, dtype=np.float64)
        return closest_on_polyline(gen, self.ref)[0], closest_on_polyline(self.ref, gen)[0]

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
        da, seg_a, t_a = closest_on_polyline(gen, self.ref)  # generated nodes → reference
        db, seg_b, t_b = closest_on_polyline(self.ref, gen)  # reference nodes → generated
        foot_a = (
            self.ref[seg_a] * (1 - t_a)[:, None]
            + self.ref[np.minimum(seg_a + 1, n - 1)] * t_a[:, None]
        )
        na = np.divide(gen - foot_a, da[:, None], out=np.zeros_like(gen), where=da[:, None] > 0)
        ja = np.einsum("ic,ick->ik", na, dgen)
        j1 = np.minimum(seg_b + 1, m - 1)
        dq = dgen[seg_b] * (1 - t_b)[:, None, None] + dgen[j1] * t_b[:, None, None]
        foot_b = gen[seg_b] * (1 - t_b)[:, None] + gen[j1] * t_b[:, None]
        nb = np.divide(
            self.ref - foot_b, db[:, None], out=np.zeros_like(self.ref), where=db[:, None] > 0
        )
        jb = -np.einsum("ic,ick->ik", nb, dq)
        return np.vstack([ja / math.sqrt(m), jb / math.sqrt(n)])


@dataclass
class Stages:
    """Runs the three stages on a curve generator over the unit box."""

    make: Callable[[np.ndarray], np.ndarray | None]  # unit-box params → curve, None if invalid
    objective: Objective
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
        only), the distances' derivative analytically (:meth:`Objective.jacobian`)."""
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

    def run(
        self,
        u0: np.ndarray,
        *,
        seed: int,
        global_stage: bool,
        popsize: int,
        maxiter: int,
        polish_evals: int,
    ) -> None:
        self.cost(u0)
        k = len(u0)
        if global_stage:
            res = differential_evolution(
                self.cost,
                [(0.0, 1.0)] * k,
                seed=seed,
                popsize=popsize,
                maxiter=maxiter,
                polish=False,
                tol=1e-10,
                init="latinhypercube",
                x0=u0,
                updating="immediate",
            )
            self.iterations += int(res.nit)
        gen = self.make(self.best_u)
        assert gen is not None
        self.n_res = len(self.objective.residuals(gen))
        ls = least_squares(
            self.residuals,
            self.best_u.copy(),
            jac=self.jacobian,
            bounds=(0.0, 1.0),
            method="trf",
            tr_solver="lsmr" if k > 24 else "exact",
            x_scale="jac",
            xtol=1e-10,
            ftol=1e-10,
            gtol=1e-10,
            max_nfev=self.ls_evals * (k + 1),
        )
        self.iterations += int(ls.nfev)
        self.cost(ls.x)
        if polish_evals > 0:
            start = self.best_u.copy()
            step = 0.01 if global_stage else 0.002
            simplex = np.vstack([start, start + step * np.eye(k) * np.where(start > 0.5, -1, 1)])
            nm = minimize(
                self.cost,
                start,
                method="Nelder-Mead",
                bounds=[(0.0, 1.0)] * k,
                options={
                    "initial_simplex": simplex,
                    "maxfev": polish_evals,
                    "xatol": 1e-9,
                    "fatol": 1e-12,
                },
            )
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
    model : the model fitted (``log_spiral``, ``centred_arcs``, ``bezier``, ``silhouette``,
        ``section``)
    bounds_hit : fitted parameters that ended on their search bound (the optimum may lie
        outside the box: a warning, not a failure)
    diameter : the column's lower diameter implied by the fit (m), when the part tells it
    values : the fitted parameters by name (numbers)
    spacing : the longest segment (m) of both curves in the reported comparisons
    alternatives : the other models' fits (volute), best first
    criterion : volute: ``aic``, ``bic``, ``rss``, ``points``, ``parameters`` (the model is
        chosen by the lowest BIC; :mod:`~ionic_usd.evaluate.fit_volute_free`)
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
    model: str = ""
    bounds_hit: tuple[str, ...] = ()
    diameter: float | None = None
    values: dict[str, float] = field(default_factory=dict)
    spacing: float = 0.0
    alternatives: tuple[FitResult, ...] = ()
    criterion: dict[str, float] = field(default_factory=dict)

    def as_dict(self) -> dict[str, object]:
        """The ``ionic_usd.evaluate/1`` entry of this part (see :mod:`.report`).

        With alternatives (a volute fitted with several models), ``models`` holds every model's
        entry, this one included, each without a ``models`` table of its own.
        """
        out = self._entry()
        if self.alternatives:
            out["models"] = {a.model: a._entry() for a in (self, *self.alternatives)}
        return out

    def _entry(self) -> dict[str, object]:
        """This fit's figures alone (no ``models`` table)."""
        out: dict[str, object] = dict(self.after.as_dict())
        out.update(
            model=self.model or self.part,
            measure=self.measure,
            before=self.before.as_dict(),
            alignment=self.alignment.as_dict(),
            parameters={k: float(v) for k, v in self.values.items()},
            bounds_hit=list(self.bounds_hit),
            diameter_estimate=self.diameter,
            resample_spacing=self.spacing,
            seconds=self.seconds,
            evaluations=self.evaluations,
            notes=list(self.notes),
        )
        if self.criterion:
            out["criterion"] = {k: float(v) for k, v in self.criterion.items()}
        return out

    def tables(self) -> dict[str, dict]:
        """TOML tables for ``ionic-usd column --config``: only what the fit changed."""
        from ionic_usd.column.column import column_params_to_tables

        t = column_params_to_tables(self.column)
        if self.part == "volute":
            return {"volute": t["volute"]}
        if self.part == "shaft":
            return {"shaft": t["shaft"]}
        return {"column": {"base": t["column"]["base"], "base_height": t["column"]["base_height"]}}

    def to_toml(self) -> str:
        from ionic_usd.column.column import COLUMN_DOCS
        from ionic_usd.column.shaft import SHAFT_PARAMETER_DOCS
        from ionic_usd.column.volute import VOLUTE_PARAMETER_DOCS
        from ionic_usd.params import to_toml

        docs = {
            "column": COLUMN_DOCS,
            "shaft": SHAFT_PARAMETER_DOCS,
            "volute": VOLUTE_PARAMETER_DOCS,
        }
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
        from ionic_usd.evaluate.report import write_atomically

        path = Path(path)
        if path.exists() and not force:
            raise OutputExistsError(f"{path} exists; pass --force to overwrite it")
        text = self.to_toml().encode("utf-8")
        return write_atomically(path, lambda fh: fh.write(text))


def check_fit_inputs(reference: object, measure: str, seed: object) -> np.ndarray:
    ref = as_curve(reference, "reference", min_nodes=2)
    if ref.shape[1] != 2:
        raise ParameterError("reference", f"shape {ref.shape}", "an (n, 2) curve")
    if curve_length(ref) <= 0:
        raise ParameterError("reference", "a zero-length curve", "a curve of positive length")
    if measure not in FIT_MEASURES:
        raise ParameterError("measure", measure, f"one of {', '.join(FIT_MEASURES)}")
    if isinstance(seed, bool) or not isinstance(seed, int):
        raise ParameterError("seed", seed, "an integer")
    return ref


class Box:
    """Parameter bounds; optimisers work on u ∈ [0, 1]^k."""

    def __init__(self, lo: ArrayLike, hi: ArrayLike) -> None:
        self.lo, self.hi = np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)

    def x(self, u: ArrayLike) -> np.ndarray:
        return self.lo + np.asarray(u) * (self.hi - self.lo)

    def u(self, x: ArrayLike) -> np.ndarray:
        return np.clip((np.asarray(x) - self.lo) / (self.hi - self.lo), 0.0, 1.0)

    def hit(self, u: np.ndarray, names: Sequence[str], *, tol: float = 1e-3) -> tuple[str, ...]:
        """Names of the parameters within ``tol`` (a fraction of the box) of a bound."""
        u = np.asarray(u, dtype=float)
        near = (u <= tol) | (u >= 1.0 - tol)
        return tuple(n for n, b in zip(names, near, strict=True) if b)
