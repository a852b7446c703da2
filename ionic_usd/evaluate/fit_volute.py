"""Fitting the volute's outer spiral edge — every volute model, side by side.

Two constructions are fitted (:data:`~ionic_usd.column.volute.VOLUTE_MODELS`):

* ``log_spiral`` — the paper's ``R·(a e^{−cθ}/b − d)``. The curve depends on ``R·a/b`` and
  ``R·d`` only, so ``a`` and ``b`` keep their initial values; ``R``, ``c``, ``d``, the start
  angle and the circuits are fitted.
* ``centred_arcs`` — quarter circles about centres walking a square spiral in the eye (the
  Vitruvian construction of Alberti, Serlio, Vignola, Palladio); the eye radius (the first
  arc's radius), the outermost centres' square, the ratio innermost/outermost square, the
  start angle and the turns are fitted.

Scale-free: the start is the model's default *shape* scaled to the reference's size (its RMS
radius about its centroid) with as many turns as the reference winds (its total tangent
turning); every bound is derived from these (sizes within ×/÷ 1.6–2, turns ± 0.6, placement
within a quarter of the reference's diagonal). The pose (translation, rotation, mirror) joins
the parameters. Two more, ``free_arcs`` and ``free_joints``, refit the centred arcs by least
squares with every arc's radius free, then every joint too
(:mod:`~ionic_usd.evaluate.fit_volute_free`). The model with the lowest
BIC on the residuals is returned (a model wins by its residuals *and* its parameter count);
the others ride along in :attr:`~ionic_usd.evaluate.fit_core.FitResult.alternatives`. The
lower diameter is estimated from Vitruvius' proportion: the volute is 8/18 D high (upright).
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Sequence
from typing import Any

import numpy as np

from ionic_usd.column.column import ColumnParams, portunus_column_params
from ionic_usd.column.volute import VOLUTE_MODELS, VoluteParams, volute_curve
from ionic_usd.errors import GeometryError, IonicError, ParameterError
from ionic_usd.evaluate import fit_core as core
from ionic_usd.evaluate.fit_core import FitResult, compare_aligned, densify, orient_like
from ionic_usd.evaluate.metrics import compare, resample
from ionic_usd.evaluate.reference import Alignment, align

__all__ = ["FIT_VOLUTE_MODELS", "fit_volute", "reference_turns", "rms_radius"]

#: The models ``fit volute`` compares: the generator's constructions and the free-arc chain
#: (:mod:`~ionic_usd.evaluate.fit_volute_free`), chosen by BIC.
FIT_VOLUTE_MODELS = (*VOLUTE_MODELS, "free_arcs", "free_joints")


def reference_turns(curve: np.ndarray) -> float:
    """How many turns a traced spiral winds: its total tangent turning / 2π (signed).

    Parameters
    ----------
    curve : (n, 2) float

    Returns
    -------
    float, > 0 counter-clockwise along the curve's direction
    """
    p = resample(curve, count=max(64, min(len(curve), 1000)))
    d = np.diff(p, axis=0)
    ang = np.arctan2(d[:, 1], d[:, 0])
    turn = (np.diff(ang) + np.pi) % (2 * np.pi) - np.pi
    return float(turn.sum() / (2 * np.pi))


def rms_radius(curve: np.ndarray) -> float:
    """RMS distance of the arc-length-resampled curve from its centroid (rotation-free size)."""
    p = resample(curve, count=400)
    return float(np.sqrt(((p - p.mean(axis=0)) ** 2).sum(axis=1).mean()))


def _rotate(curve: np.ndarray, deg: float) -> np.ndarray:
    a = math.radians(deg)
    rot = np.array([[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]])
    return curve @ rot.T


class _ArcShape:
    """The attributes :func:`~ionic_usd.column.volute_arcs.arc_points` reads, unvalidated."""

    def __init__(self, x: np.ndarray, start: float, end: float, shape: VoluteParams) -> None:
        self.theta_start, self.theta_end = start, end
        self.capital_circle_radius, self.arc_square, self.arc_ratio = x[0], x[1], x[2]
        self.eye_center = shape.eye_center
        self.capital_spiral_radius = shape.capital_spiral_radius
        self.thickness, self.min_thickness = shape.thickness, shape.min_thickness
        self.increasing_max = shape.increasing_max
        self.start_angle = math.degrees(start)


class _Model:
    """One volute model's parameter vector (without the pose) and bounds."""

    def __init__(self, name: str, v0: VoluteParams, ref: np.ndarray) -> None:
        self.name = name
        base = v0.with_(volute_model=name)
        if name == "centred_arcs" and v0.volute_model != name:
            base = base.with_(
                capital_circle_radius=v0.capital_spiral_radius / 9.0,
                arc_square=v0.capital_spiral_radius * 4.0 / 33.0,
                arc_ratio=1.0 / 3.0,
            )
        turns = max(1.0, abs(reference_turns(ref)))
        # thin band while fitting: the outer edge does not depend on it, the validity checks do
        shape = base.with_(
            start_angle=90.0, spiral_circuits=turns, min_thickness=0.0, thickness=1e-4
        )
        k = rms_radius(ref) / rms_radius(volute_curve(shape, 256))
        self.k, self.turns, self.v0 = k, turns, base
        if name == "log_spiral":
            self.names = ("R", "c", "d", "start_angle", "spiral_circuits")
            self.shape = shape.with_(capital_spiral_radius=shape.capital_spiral_radius * k)
            c, d = shape.c, shape.d
            dc = 0.6 * abs(c) if c else 0.05
            dd = max(0.5 * abs(d), 0.1)
            x0 = [self.shape.capital_spiral_radius, c, d, 90.0, turns]
            lo = [x0[0] / 1.6, c - dc, d - dd, 0.0, max(1.0, turns - 0.6)]
            hi = [x0[0] * 1.6, c + dc, d + dd, 180.0, turns + 0.6]
        else:
            self.names = ("eye_radius", "arc_square", "arc_ratio", "start_angle", "spiral_circuits")
            self.shape = shape.with_(
                capital_circle_radius=shape.capital_circle_radius * k,
                arc_square=shape.arc_square * k,
                capital_spiral_radius=shape.capital_spiral_radius * k,
            )
            x0 = [
                self.shape.capital_circle_radius,
                self.shape.arc_square,
                shape.arc_ratio,
                90.0,
                turns,
            ]
            lo = [x0[0] / 3.0, x0[1] / 2.0, 0.02, 0.0, max(1.0, turns - 0.6)]
            hi = [x0[0] * 3.0, x0[1] * 2.0, 2.0, 180.0, turns + 0.6]
        self.x0, self.lo, self.hi = np.array(x0), np.array(lo), np.array(hi)

    def params(self, x: np.ndarray) -> VoluteParams:
        if self.name == "log_spiral":
            return self.shape.with_(
                capital_spiral_radius=float(x[0]),
                c=float(x[1]),
                d=float(x[2]),
                start_angle=float(x[3]),
                spiral_circuits=float(x[4]),
            )
        return self.shape.with_(
            capital_circle_radius=float(x[0]),
            arc_square=float(x[1]),
            arc_ratio=float(x[2]),
            start_angle=float(x[3]),
            spiral_circuits=float(x[4]),
        )

    def curve(self, x: np.ndarray, samples: int) -> np.ndarray | None:
        """The outer edge for parameters ``x`` without building (and validating) a
        VoluteParams — the fit's inner loop; None when the curve is not a volute (r <= 0 or
        not monotone). The result is validated once at the end (:meth:`finish`)."""
        start, circuits = math.radians(x[3]), x[4]
        end = 2.5 * math.pi + 2.0 * math.pi * (circuits - 1.0)
        if not (circuits >= 1.0 and end > start):
            return None
        th = np.linspace(start, end, samples)
        if self.name == "log_spiral":
            s = self.shape
            r = s.a / (s.b * np.exp(x[1] * th)) - x[2]
            dr = np.diff(r)
            if r.min() <= 0 or not (np.all(dr > 0) or np.all(dr < 0)):
                return None
            return x[0] * np.column_stack([r * np.cos(th), r * np.sin(th)])
        from ionic_usd.column.volute_arcs import arc_points

        if x[0] <= 0 or x[1] <= 0 or not 0 < x[2] <= 4:
            return None
        fast = _ArcShape(x, start, end, self.shape)
        return arc_points(fast, th, 0.0)

    def finish(self, fitted: VoluteParams) -> tuple[VoluteParams, str | None]:
        """The fitted outer edge with the initial band thickness, thinned until valid."""
        t, t_min = self.v0.thickness, self.v0.min_thickness
        if self.name == "log_spiral":
            scale = self.v0.capital_spiral_radius / fitted.capital_spiral_radius
            t, t_min = t * scale, t_min * scale  # the same band width in metres
        for _ in range(12):
            try:
                return fitted.with_(thickness=t, min_thickness=min(t_min, t)), (
                    None if t == self.v0.thickness else f"band thickness reduced to {t:.4g}"
                )
            except IonicError:
                t, t_min = 0.5 * t, 0.5 * t_min
        return fitted, "band thickness kept at 1e-4 spiral units (no wider band is valid)"


def _fit_one(
    ref: np.ndarray,
    model: _Model,
    *,
    measure: str,
    samples: int,
    seed: int,
    popsize: int,
    maxiter: int,
    polish_evals: int,
    allow_mirror: bool,
) -> tuple[
    VoluteParams, np.ndarray, tuple[str, ...], dict[str, float], Alignment, np.ndarray, int, int
]:
    first = volute_curve(model.params(model.x0), samples)
    # the pose of the scaled start: coarse copies are enough (the fit refines it)
    _, how = align(
        resample(ref, count=96),
        resample(first, count=96),
        allow_mirror=allow_mirror,
        allow_rotation=True,
    )
    sign = -1.0 if how.mirrored else 1.0
    # a rotation of the model is exactly a change of its start angle and circuits (the θ
    # range turns with it), so the pose's rotation moves into those and is not fitted
    turn = sign * how.rotation
    model.x0[3] += turn
    model.x0[4] += turn / 360.0
    model.lo[3], model.hi[3] = model.x0[3] - 90.0, model.x0[3] + 90.0
    model.lo[4] = max(1.0, model.lo[4] + turn / 360.0)
    model.hi[4] = model.hi[4] + turn / 360.0
    first = volute_curve(model.params(model.x0), samples)
    first[:, 0] *= sign
    _, how = align(resample(ref, count=200), resample(first, count=200))
    diag = float(np.linalg.norm(np.ptp(ref, axis=0)))
    t0 = np.asarray(how.translation)
    x0 = np.concatenate([model.x0, t0])
    box = core.Box(
        np.concatenate([model.lo, t0 - 0.25 * diag]), np.concatenate([model.hi, t0 + 0.25 * diag])
    )
    ref_o = orient_like(first + t0, ref)

    def make(u: np.ndarray) -> np.ndarray | None:
        x = box.x(u)
        curve = model.curve(x, samples)
        if curve is None:
            return None
        curve[:, 0] *= sign
        return curve + x[5:7]

    # the objective on at most 400 reference nodes (arc-length resampled); reports use all
    obj = core.Objective(ref_o if len(ref_o) <= 400 else resample(ref_o, count=400), measure)
    stages = core.Stages(make, obj, penalty=10.0 * diag)
    stages.run(
        box.u(x0),
        seed=seed,
        global_stage=True,
        popsize=popsize,
        maxiter=maxiter,
        polish_evals=polish_evals,
    )
    x = box.x(stages.best_u)
    names = (*model.names, "translation_x", "translation_y")
    hit = box.hit(stages.best_u, names)
    values = dict(zip(names, (float(v) for v in x), strict=True))
    pose = Alignment((float(x[5]), float(x[6])), sign < 0, 0.0, 0.0)
    start = make(box.u(x0))
    if start is None:  # x0 traced ``first`` above, so the start is a volute
        raise GeometryError(f"volute fit ({model.name}): the start parameters trace no volute")
    return (model.params(x), ref_o, hit, values, pose, start, stages.iterations, obj.calls)


def fit_volute(
    reference: np.ndarray,
    *,
    initial: VoluteParams | None = None,
    measure: str = "hausdorff",
    eye: Sequence[float] | None = None,
    samples: int = 256,
    seed: int = 0,
    popsize: int = 8,
    maxiter: int = 15,
    polish_evals: int = 400,
    allow_mirror: bool = True,
    column: ColumnParams | None = None,
    models: Sequence[str] | str | None = None,
) -> FitResult:
    """Fit every volute model to a traced outer spiral edge; return the best.

    Parameters
    ----------
    reference : (n, 2) float
        The outer edge of the spiral band in metres, any origin, pose and direction.
    initial : VoluteParams, optional
        Its shape starts the fit of its own model (default: the column's volute).
    measure : one of :data:`~ionic_usd.evaluate.fit_core.FIT_MEASURES`
    eye : (2,) float, optional
        The eye centre in the reference's frame; sets ``offset_x``/``offset_y``.
    samples : nodes of the generated spiral while fitting
    seed, popsize, maxiter : differential evolution settings
    polish_evals : Nelder–Mead evaluations (0: no polish)
    allow_mirror : the reference may wind the other way (a left volute)
    column : ColumnParams the fitted volute is put into (default: Portunus)
    models : a model name or several (default: all of :data:`FIT_VOLUTE_MODELS`;
        ``free_arcs`` fits ``centred_arcs`` first, as its start)

    Returns
    -------
    FitResult with ``params`` a :class:`VoluteParams` of the best model; the others in
    ``alternatives``.
    """
    ref = core.check_fit_inputs(reference, measure, seed)
    column = column or portunus_column_params()
    v0 = initial or column.capital.volute
    if not isinstance(v0, VoluteParams):
        raise ParameterError("initial", v0, "a VoluteParams")
    names, chains, keep_centred = _models_to_fit(models)
    e = None
    if eye is not None:
        e = np.asarray(eye, dtype=float)
        if e.shape != (2,) or not np.all(np.isfinite(e)):
            raise ParameterError("eye", eye, "two finite numbers (x, y)")
    settings = {
        "measure": measure,
        "samples": samples,
        "seed": seed,
        "popsize": popsize,
        "maxiter": maxiter,
        "polish_evals": polish_evals,
        "allow_mirror": allow_mirror,
    }
    results = []
    from ionic_usd.progress import progress

    with progress(len(names), "fitting the volute", unit="model") as bar:
        for name in names:
            results.append(_fit_model(name, v0, ref, e, column, settings))
            bar.update(1)
    from ionic_usd.evaluate.fit_volute_free import add_free_arcs, choose_by_criterion

    results = choose_by_criterion(add_free_arcs(results, chains=chains, keep_centred=keep_centred))
    best = results[0]
    return dataclasses.replace(
        best, alternatives=tuple(results[1:]), seconds=sum(r.seconds for r in results)
    )


def _models_to_fit(
    models: Sequence[str] | str | None,
) -> tuple[list[str], tuple[str, ...], bool]:
    """(the models fitted one by one, in order; the free chains fitted from the centred arcs
    afterwards; whether the centred arcs were asked for themselves)."""
    if models is None:
        models = FIT_VOLUTE_MODELS
    elif isinstance(models, str):
        models = (models,)
    for m in models:
        if m not in FIT_VOLUTE_MODELS:
            raise ParameterError("models", m, f"one of {', '.join(FIT_VOLUTE_MODELS)}")
    chains = tuple(m for m in models if m in ("free_arcs", "free_joints"))
    keep_centred = "centred_arcs" in models
    names = [m for m in dict.fromkeys(models) if m not in chains]
    if chains and not keep_centred:
        names.append("centred_arcs")  # the free arcs start from the centred-arc fit
    return list(dict.fromkeys(names)), chains, keep_centred


def _fit_model(
    name: str,
    v0: VoluteParams,
    ref: np.ndarray,
    e: np.ndarray | None,
    column: ColumnParams,
    settings: dict[str, Any],
) -> FitResult:
    """One volute model fitted (:func:`_fit_one` with ``settings``), offset to the eye ``e``
    when given, put into ``column`` and measured against the reference."""
    t0 = time.perf_counter()
    model = _Model(name, v0, ref)
    fitted, ref_o, hit, values, pose, start, iters, calls = _fit_one(ref, model, **settings)
    fitted, notes = _finished(model, fitted, e, pose)
    if hit:
        notes.append("WARNING: ended on a search bound: " + ", ".join(hit))
    # Vitruvius: the volute is 8/18 D high — measured upright, turned so the spiral ends
    # at the top (θ ≡ 90°), as carved (the eye's size varies more between constructions)
    own = _rotate(volute_curve(fitted, 2048), 90.0 - math.degrees(fitted.theta_end))
    diameter = 18.0 / 8.0 * float(np.ptp(own[:, 1]))
    notes.append(f"diameter estimate {diameter:.4g} m (Vitruvius: the volute is 8/18 D high)")
    col = dataclasses.replace(column, capital=column.capital.with_(volute=fitted))
    h = core.report_spacing(ref_o)
    init_al = orient_like(ref_o, start)
    before = compare(densify(ref_o, h), densify(init_al, h))
    after, al, fit_al = compare_aligned(
        ref_o,
        pose.apply(volute_curve(fitted, settings["samples"])),
        allow_mirror=False,
        max_segment=h,
    )
    al = Alignment(
        tuple(np.add(al.translation, pose.translation)),
        pose.mirrored,
        al.hausdorff_before,
        al.hausdorff_after,
        pose.rotation,
    )
    values.update(mirrored=float(pose.mirrored))
    return FitResult(
        "volute",
        fitted,
        col,
        before,
        after,
        settings["measure"],
        iters,
        calls,
        time.perf_counter() - t0,
        ref_o,
        fit_al,
        init_al,
        al,
        tuple(notes),
        model=name,
        bounds_hit=hit,
        diameter=diameter,
        values=values,
        spacing=h,
    )


def _finished(
    model: _Model, fitted: VoluteParams, e: np.ndarray | None, pose
) -> tuple[VoluteParams, list[str]]:
    """The fitted volute made whole (:meth:`_Model.finish`) and offset to the eye ``e`` (in
    the reference's frame) when given, with the notes that say what was fitted."""
    if model.name == "log_spiral":
        notes = [
            "a, b held (the curve depends on R·a/b and R·d); R, c, d, start "
            "angle, circuits and the pose fitted"
        ]
    else:
        notes = ["eye radius, centres' square and ratio, start angle, turns and the pose fitted"]
    notes.append(
        f"start scaled ×{model.k:.4g} to the reference's size; "
        f"{model.turns:.3g} turns traced; rotation is the start angle and "
        "circuits (an exact equivalence)"
    )
    fitted, thin = model.finish(fitted)
    if thin:
        notes.append(thin)
    if e is not None:
        local = _rotate((e - np.asarray(pose.translation))[None, :], -pose.rotation)[0]
        local[0] *= -1.0 if pose.mirrored else 1.0
        fitted = fitted.with_(offset_x=float(local[0]), offset_y=float(local[1]))
        notes.append("offsets from the given eye centre")
    else:
        notes.append("offsets kept (they move the eye, not the spiral)")
    return fitted, notes
