"""Fitting the shaft: its silhouette (r, y), or a closed fluted cross-section.

* silhouette — bottom and top radius, fluted height, entasis and the vertical placement;
  rings, flute-end ratio and flutes keep their initial values; r is the distance from the axis.
* section (:func:`fit_shaft_section`) — the closed cross-section of a fluted shaft: flutes
  (tried over a range, each fitted), radius, flute depth, flute angle (the share of the
  circumference the flutes take; the rest are fillets), rotation and centre.
"""

from __future__ import annotations

import dataclasses
import time

import numpy as np

from ionic_usd.column.column import ColumnParams, portunus_column_params
from ionic_usd.column.shaft import ShaftParams, shaft_radius_at
from ionic_usd.errors import IonicError, ReferenceCurveError
from ionic_usd.evaluate import fit_core as core
from ionic_usd.evaluate.fit_core import FitResult, compare_aligned

__all__ = ["closed_like", "fit_shaft", "fit_shaft_section", "fluted_section", "is_closed_curve"]


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
    t0 = time.perf_counter()
    ref = core.check_fit_inputs(reference, measure, seed)
    _check_closed(ref, closed=False)
    column = initial or portunus_column_params()
    if ref[0, 1] > ref[-1, 1]:
        ref = ref[::-1].copy()
    rmax = float(np.abs(ref[:, 0]).max())
    if ends is None:
        ends = bool(abs(ref[0, 0]) < 0.2 * rmax and abs(ref[-1, 0]) < 0.2 * rmax)
    sil = _Silhouette(ref, column, rmax, samples, ends)
    obj = core.Objective(ref, measure)
    stages = core.Stages(sil.make, obj, penalty=10.0 * (sil.span + rmax))
    stages.run(
        sil.box.u(sil.x0),
        seed=seed,
        global_stage=True,
        popsize=popsize,
        maxiter=maxiter,
        polish_evals=polish_evals,
    )
    x = sil.box.x(stages.best_u)
    fitted = sil.shaft_of(x)
    col = sil.column_with(column, fitted)
    names = ("bottom_radius", "top_radius", "height", "entasis", "y_bottom")
    hit = sil.box.hit(stages.best_u, names)
    notes = [
        "rings, flute-end ratio and flutes kept; r measured from the axis",
        f"ends {'included' if ends else 'left out'}; shaft bottom at y = {x[4]:.6g} m "
        "in the reference",
    ]
    if hit:
        notes.append("WARNING: ended on a search bound: " + ", ".join(hit))
    return _silhouette_result(
        ref,
        column,
        col,
        fitted,
        measure,
        (stages.iterations, obj.calls, t0),
        notes,
        hit,
        dict(zip(names, (float(v) for v in x), strict=True)),
        samples,
        ends,
    )


def _check_closed(ref: np.ndarray, *, closed: bool) -> None:
    """Refuse (ParameterError) a closed reference where a silhouette is fitted, an open one
    where a cross-section is."""
    from ionic_usd.errors import ParameterError

    if closed and not is_closed_curve(ref):
        raise ParameterError(
            "reference", "an open curve", "a closed cross-section (its last node on its first)"
        )
    if not closed and is_closed_curve(ref):
        raise ParameterError(
            "reference",
            "a closed curve",
            "a silhouette (r, y); fit a closed "
            "cross-section with fit_shaft_section (CLI: --section)",
        )


class _Silhouette:
    """The silhouette fit's vector (bottom and top radius, fluted height, entasis, the
    shaft's bottom y in the reference), its start, its box and the curve it makes."""

    def __init__(
        self, ref: np.ndarray, column: ColumnParams, rmax: float, samples: int, ends: bool
    ) -> None:
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
        self.box = core.Box(
            [0.3 * rmax, 0.3 * rmax, max(0.3 * x0[2], 1e-3), -0.2, x0[4] - 0.2 * span],
            [1.5 * rmax, 1.5 * rmax, 1.5 * x0[2] + 1e-3, 0.2, x0[4] + 0.2 * span],
        )
        self.s0, self.x0, self.span, self.ends = s0, x0, span, ends
        self.ys01 = np.linspace(0.0, 1.0, samples)

    def shaft_of(self, x: np.ndarray) -> ShaftParams:
        return dataclasses.replace(
            self.s0,
            bottom_radius=float(x[0]),
            top_radius=float(x[1]),
            height=float(x[2]),
            entasis=float(x[3]),
        )

    @staticmethod
    def column_with(column: ColumnParams, fitted: ShaftParams) -> ColumnParams:
        """``column`` whose shaft takes the fitted radii, fluted height and entasis."""
        shaft = dataclasses.replace(
            column.shaft,
            bottom_radius=fitted.bottom_radius,
            top_radius=fitted.top_radius,
            height=fitted.height,
            entasis=fitted.entasis,
        )
        return dataclasses.replace(column, shaft=shaft)

    def make(self, u: np.ndarray) -> np.ndarray | None:
        x = self.box.x(u)
        try:
            sp = self.shaft_of(x)
        except IonicError:
            return None
        ys = self.ys01 * sp.length
        out = np.column_stack([shaft_radius_at(sp, ys), ys + x[4]])
        if self.ends:
            out = np.vstack([[0.0, x[4]], out, [0.0, x[4] + sp.length]])
        return out


def _silhouette_result(
    ref: np.ndarray,
    column: ColumnParams,
    col: ColumnParams,
    fitted: ShaftParams,
    measure: str,
    counts: tuple[int, int, float],
    notes: list[str],
    hit: tuple[str, ...],
    values: dict[str, float],
    samples: int,
    ends: bool,
) -> FitResult:
    """The silhouette fit's report: the starting ``column`` and the fitted ``col`` measured
    against ``ref``; ``counts``: (iterations, measure calls, the fit's start time)."""
    from ionic_usd.evaluate.sections import shaft_silhouette_section

    def section(c: ColumnParams) -> np.ndarray:
        return shaft_silhouette_section(c, samples=samples, ends=ends)

    before, _, init_al = compare_aligned(
        ref, section(column), allow_mirror=False, max_segment=core.report_spacing(ref)
    )
    after, al, fit_al = compare_aligned(
        ref, section(col), allow_mirror=False, max_segment=core.report_spacing(ref)
    )
    iterations, calls, t0 = counts
    return FitResult(
        "shaft",
        fitted,
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
        model="silhouette",
        bounds_hit=hit,
        diameter=2.0 * fitted.bottom_radius,
        values=values,
        spacing=core.report_spacing(ref),
    )


def is_closed_curve(curve: np.ndarray, *, rel_tol: float = 1e-3) -> bool:
    """Whether a traced curve closes on itself (end within ``rel_tol`` of its size of the start).

    Parameters
    ----------
    curve : (n, 2) float
    """
    c = np.asarray(curve, dtype=float)
    size = float(np.linalg.norm(np.ptp(c, axis=0)))
    return len(c) >= 4 and float(np.linalg.norm(c[0] - c[-1])) <= rel_tol * size


def fluted_section(
    radius: float,
    flutes: int,
    flute_angle: float,
    flute_depth: float,
    rotation: float = 0.0,
    centre=(0.0, 0.0),
    *,
    slices: int = 24,
) -> np.ndarray:
    """Closed fluted cross-section, as :func:`ionic_usd.column.shaft.shaft_cross_section`.

    Each flute is half an ellipse whose chord spans ``flute_angle`` degrees; depth ratio
    ``flute_depth``; fillets are arcs of the circle; flutes centred at (k + ½)·360°/flutes +
    ``rotation``.

    Returns
    -------
    (flutes · (2 slices) + 1, 2) float, counter-clockwise, the first node repeated at the end
    """
    period = 2 * np.pi / flutes
    alpha = np.radians(flute_angle) / 2
    phi = np.pi * np.arange(slices) / slices
    rho = radius * np.sin(alpha)
    x_r = radius * np.cos(alpha) - flute_depth * rho * np.sin(phi)
    x_t = -rho * np.cos(phi)
    fil = alpha + (period - 2 * alpha) * (np.arange(slices) / slices)
    rc = np.concatenate([x_r, radius * np.cos(fil)])
    rs = np.concatenate([x_t, radius * np.sin(fil)])
    centres = (np.arange(flutes) + 0.5) * period + np.radians(rotation)
    cc, sc = np.cos(centres)[:, None], np.sin(centres)[:, None]
    x = (cc * rc - sc * rs).ravel()
    y = (sc * rc + cc * rs).ravel()
    pts = np.column_stack([x, y]) + np.asarray(centre, dtype=float)
    return np.vstack([pts, pts[:1]])


def closed_like(reference: np.ndarray, curve: np.ndarray) -> np.ndarray:
    """A closed curve run the reference's way round, starting at the node nearest its start
    (the Fréchet measures of closed curves depend on both)."""

    def area(c: np.ndarray) -> float:
        return float(np.dot(c[:-1, 0], c[1:, 1]) - np.dot(c[1:, 0], c[:-1, 1]))

    c = curve[:-1]
    if np.sign(area(curve)) != np.sign(area(reference)):
        c = c[::-1]
    k = int(np.argmin(np.linalg.norm(c - reference[0], axis=1)))
    c = np.roll(c, -k, axis=0)
    return np.vstack([c, c[:1]])


def _flute_estimate(ref: np.ndarray, centre: np.ndarray) -> tuple[int, float, float]:
    """Flute count, a flute centre's angle (deg) and the outer radius from the polar profile."""
    from ionic_usd.evaluate.metrics import resample

    p = resample(ref, count=4096) - centre
    ang = np.arctan2(p[:, 1], p[:, 0])
    rad = np.hypot(p[:, 0], p[:, 1])
    bins = np.linspace(-np.pi, np.pi, 1025)
    idx = np.clip(np.digitize(ang, bins) - 1, 0, 1023)
    prof = np.full(1024, np.nan)
    np.fmax.at(prof, idx, rad)  # the outer surface at every angle (fmax skips the nans)
    ok = np.isfinite(prof)
    prof = np.interp(np.arange(1024), np.flatnonzero(ok), prof[ok], period=1024)
    spec = np.fft.rfft(prof - prof.mean())
    k = int(np.argmax(np.abs(spec[6:65]))) + 6
    # flutes are the minima of the radius: centre angle where the k-th harmonic is lowest
    phase = float(np.angle(spec[k]))
    centre_ang = (np.pi - phase) / k  # argmin of cos(kθ + phase)
    return k, float(np.degrees(centre_ang - np.pi / k + np.pi)) % (360.0 / k), float(rad.max())


#: Largest residual (node-to-curve Hausdorff, % of the mean curve length) of a fitted
#: section: past it the reference is refused as not a fluted section (hand-drawn and scanned
#: sections fit within 0.1 %; a triangle leaves 4.7 %, a figure-eight is refused before).
SECTION_MAX_PCT = 2.0


def check_simple_section(ref: np.ndarray) -> None:
    """Refuse a closed section that crosses itself (a figure-eight), naming where."""
    from shapely import Polygon
    from shapely.validation import explain_validity

    poly = Polygon(ref)
    if not poly.is_valid:
        raise ReferenceCurveError(
            f"reference: a shaft section must not cross itself ({explain_validity(poly)})"
        )


def fit_shaft_section(
    reference: np.ndarray,
    *,
    initial: ColumnParams | None = None,
    measure: str = "hausdorff",
    flutes: int | None = None,
    seed: int = 0,
    popsize: int = 6,
    maxiter: int = 15,
    polish_evals: int = 300,
) -> FitResult:
    """Fit a closed fluted shaft cross-section: radius, flutes, flute angle, depth, rotation.

    Parameters
    ----------
    reference : (n, 2) float
        A closed section (metres, any centre and rotation, either direction).
    initial : ColumnParams whose shaft receives the fitted values (default: Portunus); the
        top radius keeps its ratio to the bottom radius.
    flutes : int, optional
        Fix the flute count; default: the strongest harmonic (6 to 64) of the radius
        round the centre.

    Returns
    -------
    FitResult (model ``section``) with ``params`` a :class:`ShaftParams`; the section is
    taken as the shaft's lower section (``diameter`` = twice the fitted radius).
    """
    t0 = time.perf_counter()
    ref = core.check_fit_inputs(reference, measure, seed)
    _check_closed(ref, closed=True)
    check_simple_section(ref)
    column = initial or portunus_column_params()
    e, x0, box = _section_start(ref, flutes)
    names = ("radius", "flute_angle", "flute_depth", "rotation_deg", "centre_x", "centre_y")

    obj = core.Objective(ref, measure)
    stages = core.Stages(_section_maker(box, e), obj, penalty=10.0 * x0[0])
    stages.run(
        box.u(x0),
        seed=seed,
        global_stage=True,
        popsize=popsize,
        maxiter=maxiter,
        polish_evals=polish_evals,
    )
    x = box.x(stages.best_u)
    hit = box.hit(stages.best_u, names)
    notes = [
        f"{e} flutes ({'given' if flutes is not None else 'strongest harmonic'}); "
        "radius, flute angle, depth, rotation and centre fitted"
    ]
    col, params = _section_column(column, x, e, notes)
    if hit:
        notes.append("WARNING: ended on a search bound: " + ", ".join(hit))
    h = core.report_spacing(ref)
    fitted, start, before, after, al = _section_measures(ref, x, x0, e, h)
    values = {**dict(zip(names, (float(v) for v in x), strict=True)), "flutes": float(e)}
    return FitResult(
        "shaft",
        params,
        col,
        before,
        after,
        measure,
        stages.iterations,
        obj.calls,
        time.perf_counter() - t0,
        ref,
        fitted,
        start,
        al,
        tuple(notes),
        model="section",
        bounds_hit=hit,
        diameter=2.0 * float(x[0]),
        values=values,
        spacing=h,
    )


def _section_start(ref: np.ndarray, flutes: int | None) -> tuple[int, np.ndarray, core.Box]:
    """(flute count, start, box) of the section fit: the vector (radius, flute angle, depth,
    rotation, centre x, y) from the arc centroid and the radius' strongest harmonic (or the
    given count), within a fifth of the radius, half a flute period of turn and a tenth of
    the radius of the centre."""
    from ionic_usd.evaluate.reference import arc_centroid

    c0 = arc_centroid(ref)
    e, rot0, r0 = _flute_estimate(ref, c0)
    if flutes is not None:
        e = int(flutes)
    period = 360.0 / e
    size = r0
    x0 = np.array([r0, 0.8 * period, 1.0, rot0, *c0])
    box = core.Box(
        [0.8 * r0, 0.2 * period, 0.05, rot0 - 0.5 * period, c0[0] - 0.1 * size, c0[1] - 0.1 * size],
        [1.2 * r0, 0.98 * period, 1.6, rot0 + 0.5 * period, c0[0] + 0.1 * size, c0[1] + 0.1 * size],
    )
    return e, x0, box


def _section_maker(box: core.Box, e: int):
    """The coarse section (12 slices per flute) of a point ``u`` of the box: what the fit
    compares with the reference."""

    def make(u: np.ndarray) -> np.ndarray | None:
        x = box.x(u)
        return fluted_section(x[0], e, x[1], x[2], x[3], x[4:6], slices=12)

    return make


def _section_column(
    column: ColumnParams, x: np.ndarray, e: int, notes: list[str]
) -> tuple[ColumnParams, ShaftParams]:
    """``column`` with the fitted section as its shaft's lower section (the top radius keeps
    its ratio), and that shaft; the column as it was (with a note) where the values do not
    make a shaft."""
    s0 = column.shaft
    try:
        shaft = dataclasses.replace(
            s0,
            bottom_radius=float(x[0]),
            top_radius=float(x[0]) * s0.top_radius / s0.bottom_radius,
            flutes=e,
            flute_angle=float(x[1]),
            flute_depth=float(x[2]),
        )
        col = dataclasses.replace(column, shaft=shaft)
        return col, col.shaft_params()
    except IonicError as exc:
        notes.append(f"not put into the column: {exc}")
        return column, column.shaft_params()


def _section_measures(ref: np.ndarray, x: np.ndarray, x0: np.ndarray, e: int, h: float):
    """(fitted and starting sections, fine, closed like ``ref``; the measures before and
    after; the alignment). Refuses (ReferenceCurveError) a curve no fluted section fits
    within :data:`SECTION_MAX_PCT`."""
    from ionic_usd.evaluate.fit_core import densify
    from ionic_usd.evaluate.metrics import compare
    from ionic_usd.evaluate.reference import Alignment

    fine = fluted_section(x[0], e, x[1], x[2], x[3], x[4:6], slices=48)
    fitted = closed_like(ref, fine)
    after = compare(densify(ref, h), densify(fitted, h))
    start = closed_like(ref, fluted_section(x0[0], e, x0[1], x0[2], x0[3], x0[4:6], slices=48))
    before = compare(densify(ref, h), densify(start, h))
    al = Alignment(
        (float(x[4]), float(x[5])), False, before.hausdorff, after.hausdorff, float(x[3])
    )
    if not after.hausdorff_pct <= SECTION_MAX_PCT:
        raise ReferenceCurveError(
            f"reference: not a fluted shaft section: the best {e}-flute section stays "
            f"{after.hausdorff_pct:.3g} % of the curve's length from it (node-to-curve "
            f"Hausdorff; a fluted section fits within {SECTION_MAX_PCT:g} %)"
        )
    return fitted, start, before, after, al
