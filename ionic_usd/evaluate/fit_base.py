"""Fitting a Bézier base grammar (v2) to a traced base half-profile.

The global stage is the layout search (:func:`suggest_base_layout`: cuts at tangent breaks and
at extrema of r) and a linear least-squares Bézier fit of every module; then least squares and
Nelder–Mead as every fit (:mod:`.fit_core`). Scale-free: the reference is put into column
coordinates by a shift, and the column's lower diameter is estimated from the reference's top
end (it meets the shaft) unless the axis is given; the starting column is *scaled* to that
diameter, so ``column --config`` rebuilds the fitted base on a shaft of the right radius.
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ionic_usd.column.column import ColumnParams, portunus_column_params
from ionic_usd.errors import ParameterError
from ionic_usd.evaluate import fit_core as core
from ionic_usd.evaluate.fit_core import FitResult, compare_aligned
from ionic_usd.evaluate.polyline import PolylineIndex, as_curve, curve_length, resample
from ionic_usd.geometry.curves import bezier

__all__ = ["BaseLayout", "fit_base", "suggest_base_layout", "base_grammar_string"]


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
        return ctrl, float(PolylineIndex(np.vstack([p0, p1])).distances(piece).max())
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
    err = float(PolylineIndex(bezier(ctrl, np.linspace(0, 1, 129))).distances(piece).max())
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
    prof = as_curve(profile, "profile", min_nodes=2)
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
            cand.add(int(k + np.argmax(turn[k : j + 1])))
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
        seg = p[i : j + 1]
        chord_err = float(PolylineIndex(seg[[0, -1]]).distances(seg).max())
        if chord_err <= tol:
            out.append((i, j, 2))
            continue
        ctrl, err = _fit_bezier_piece(seg, 4)
        if err > tol and j - i >= 8 and len(out) + len(pieces) + 2 <= max_modules:
            d = PolylineIndex(bezier(ctrl, np.linspace(0, 1, 129))).distances(seg)
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
    t0 = time.perf_counter()
    ref = core.check_fit_inputs(reference, measure, seed)
    if ref[0, 1] > ref[-1, 1]:
        ref = ref[::-1].copy()
    column, diameter = _starting_column(ref, initial)
    d = column.shaft.bottom_radius
    ax = float(ref[-1, 0] - d) if axis_x is None else float(axis_x)
    shift = np.array([ax, ref[0, 1]])
    ref_c = ref - shift
    p = resample(ref_c, count=400)
    layout = _modules_layout(ref_c, modules, tolerance)
    ctrls = [
        _fit_bezier_piece(p[i : j + 1], m)[0]
        for i, j, m in zip(layout.breaks[:-1], layout.breaks[1:], layout.points, strict=True)
    ]
    chain = _Chain(layout.points, column.base_params().profile_slices)
    size = float(np.ptp(ref_c, axis=0).max())
    x0, box = chain.start(ctrls, size)
    best_u, iterations, calls = chain.optimise(
        x0, box, core.Objective(ref_c, measure), 10.0 * size, seed, polish_evals
    )
    grammar = base_grammar_string(chain.controls(box.x(best_u)), d)
    hit = _bound_hits(box, best_u)
    notes = [
        f"{len(layout.points)} modules, points {list(layout.points)}",
        f"reference shifted by ({-shift[0]:+.6g}, {-shift[1]:+.6g}) m into column "
        f"coordinates (shaft radius d = {d:g} m)",
        f"diameter estimate {diameter:.4g} m (Vitruvius: the base is D/2 high)"
        + ("; the starting column scaled to it" if initial is None else ""),
    ]
    if hit:
        notes.append(f"WARNING: {len(hit)} control-point coordinates ended on a search bound")
    return _base_result(
        ref,
        column,
        grammar,
        measure,
        iterations,
        calls,
        t0,
        notes,
        hit,
        diameter,
        len(layout.points),
    )


class _Chain:
    """The base's modules as one parameter vector: the first point's R, then per module its
    points after the first as (R, h above the module bottom); ``counts`` points per module,
    each sampled at ``slices`` + 1 parameters (two for a straight module)."""

    def __init__(self, counts: Sequence[int], slices: int) -> None:
        self.counts = counts
        self.ts = {m: np.linspace(0.0, 1.0, 2 if m == 2 else slices + 1) for m in set(counts)}

    def start(self, ctrls: list[np.ndarray], size: float) -> tuple[np.ndarray, core.Box]:
        """The vector of the control points ``ctrls`` and its search box: bounds keep R > 0
        and h >= 0 (the grammar's rules)."""
        xs = [ctrls[0][0, 0]]
        y_bottom = 0.0
        for c in ctrls:
            for r, y in c[1:]:
                xs += [r, max(y - y_bottom, 0.0)]
            y_bottom = max(float(c[-1, 1]), y_bottom)
        x0 = np.asarray(xs)
        lo = np.where(np.arange(len(x0)) % 2 == 0, 1e-4 * size, 0.0)  # R (even), h (odd)
        lo = np.minimum(lo, x0)
        return x0, core.Box(lo, np.maximum(x0 + 0.5 * size, lo + 1e-6))

    def controls(self, x: np.ndarray) -> list[np.ndarray]:
        """Each module's control points (r, y) from the vector ``x``."""
        out, k, y0 = [], 1, 0.0
        start = np.array([x[0], 0.0])
        for m in self.counts:
            pts = [start]
            for _ in range(m - 1):
                pts.append(np.array([x[k], y0 + x[k + 1]]))
                k += 2
            c = np.array(pts)
            out.append(c)
            y0 = float(c[-1, 1])
            start = c[-1]
        return out

    def optimise(
        self,
        x0: np.ndarray,
        box: core.Box,
        obj: core.Objective,
        penalty: float,
        seed: int,
        polish_evals: int,
    ) -> tuple[np.ndarray, int, int]:
        """(the best point in the box's unit coordinates, iterations, measure calls) of the
        local stages from ``x0``. The curve is linear in x (Bézier points are linear in the
        control points, which are linear in x while h >= 0): it is tabulated once, then
        every evaluation is one matrix product."""
        g0 = self.curve_of(np.zeros_like(x0))
        lin = np.stack([self.curve_of(np.eye(len(x0))[i]) - g0 for i in range(len(x0))], axis=-1)
        dgen = lin * (box.hi - box.lo)

        def make(u: np.ndarray) -> np.ndarray | None:
            return g0 + lin @ box.x(u)

        stages = core.Stages(make, obj, penalty=penalty, ls_evals=4, dgen=dgen)
        stages.run(
            box.u(x0),
            seed=seed,
            global_stage=False,
            popsize=0,
            maxiter=0,
            polish_evals=polish_evals,
        )
        return stages.best_u, stages.iterations, obj.calls

    def curve_of(self, x: np.ndarray) -> np.ndarray:
        """The sampled profile of the vector ``x``."""
        cs = self.controls(x)
        return np.vstack([cs[0][:1]] + [bezier(c, self.ts[len(c)])[1:] for c in cs])


def _base_result(
    ref: np.ndarray,
    column: ColumnParams,
    grammar: str,
    measure: str,
    iterations: int,
    calls: int,
    t0: float,
    notes: list[str],
    hit: tuple[str, ...],
    diameter: float,
    n_modules: int,
) -> FitResult:
    """The fit's report: ``column`` with the fitted ``grammar`` (of ``n_modules`` modules),
    both measured against the reference ``ref``."""
    from ionic_usd.evaluate.sections import base_section
    from ionic_usd.grammar.base import parse_base_grammar

    height = parse_base_grammar(grammar, 2).height
    col = dataclasses.replace(column, base=grammar, base_height=height)
    before, _, init_al = compare_aligned(
        ref, base_section(column), allow_mirror=False, max_segment=core.report_spacing(ref)
    )
    after, al, fit_al = compare_aligned(
        ref, base_section(col), allow_mirror=False, max_segment=core.report_spacing(ref)
    )
    d = column.shaft.bottom_radius
    values = {"modules": float(n_modules), "base_height": float(height), "shaft_radius": float(d)}
    return FitResult(
        "base",
        grammar,
        col,
        before,
        after,
        measure,
        iterations,
        calls,
        time.perf_counter() - t0,
        ref,
        fit_al,
        init_al,
        al,
        tuple(notes),
        model="bezier",
        bounds_hit=hit,
        diameter=diameter,
        values=values,
        spacing=core.report_spacing(ref),
    )


def _starting_column(ref: np.ndarray, initial: ColumnParams | None) -> tuple[ColumnParams, float]:
    """(the column the base is fitted into, the diameter the reference's height gives):
    ``initial``, or the Portunus column scaled to the reference (not shifted to the Portunus
    radius). Vitruvius (III.5.1–2): the base is half the lower diameter high."""
    diameter = 2.0 * float(np.ptp(ref[:, 1]))
    if initial is not None:
        return initial, diameter
    column = portunus_column_params(lower_diameter=diameter)
    if column.lod != portunus_column_params().lod:  # pragma: no cover - defaults agree
        column = dataclasses.replace(column, lod=portunus_column_params().lod)
    return column, diameter


def _modules_layout(
    ref_c: np.ndarray, modules: Sequence[int] | None, tolerance: float | None
) -> BaseLayout:
    """The given control points per module laid on ``ref_c``, or the suggested layout."""
    if modules is None:
        return suggest_base_layout(ref_c, tolerance=tolerance)
    mods = list(modules)
    if not mods or any(isinstance(m, bool) or int(m) != m or m < 2 for m in mods):
        raise ParameterError("modules", modules, "control points per module, each >= 2")
    return _layout_for_modules(ref_c, mods)


def _bound_hits(box: core.Box, best_u: np.ndarray) -> tuple[str, ...]:
    """The coordinates (``x<i>``) that ended on their upper bound: the lower bounds are the
    grammar's R > 0 and h >= 0."""
    names = tuple(f"x{i}" for i in range(len(best_u)))
    return tuple(
        n
        for n in box.hit(best_u, names)
        if box.hi[int(n[1:])] - box.lo[int(n[1:])] > 0 and best_u[int(n[1:])] >= 1.0 - 1e-3
    )
