"""The Ionic volute: the paper's logarithmic spiral (formula 3, Table 4; SPEC §3) and its solid.

Curve. ``r(θ) = a / (b·e^{cθ}) − d`` and ``(x, y) = R·r(θ)·(cos θ, sin θ)`` for θ from the start
angle to ``2.5π + 2π(n − 1)`` (``n`` spiral circuits). The inner edge of the band is the same
curve with the radius reduced by the thickness ``t(θ)``: ``R·(r(θ) − t(θ))``. The thickness grows
linearly from ``min_thickness`` at the start angle to ``thickness`` at ``increasing_max`` and is
constant after it (``increasing_max ≤ start_angle`` means a constant thickness). ``r``, ``d``,
``thickness`` and ``min_thickness`` are in *spiral units* (multiplied by R, metres); angles in
degrees. The eye (``capital_circle_radius``, metres) is centred at ``(offset_x, offset_y)``
(metres) from the spiral's origin.

Direction. The paper ends every spiral at θ ≡ π/2 (the top) and lets the band thickness *grow*
along θ. A real volute's listel is thinnest at the eye and its top end runs into the canalis
under the abacus, so the defaults take θ to run **from the eye outward**: ``c < 0`` (r grows with
θ), the start angle sits at the eye and the last point is the top of the outermost turn, where
the band continues horizontally towards the column axis. Read backwards (θ decreasing) the
spiral winds inward to the eye in three circuits. Both signs of ``c`` are accepted; the checks
below are direction-agnostic.

Defaults (Vitruvius, *De architectura* III.5.5–6, with the Temple of Portunus' lower diameter
D = 0.95 m): a *part* is D/18; the volute is 8 parts high, its eye centre 4½ parts below the
abacus and 3½ above the volute's lowest point; the eye is one part across (1/8 of the volute
height). With R = 4½ parts = D/4 (so r = 1 at the top end), the three conditions
``r(6.5π) = 1`` (top), ``r(5.5π) = 7/9`` (bottom, half a turn earlier) and ``r(π/2) = 1/9`` (the
eye's radius, three circuits earlier) fix ``a, c, d`` for ``b = 1`` (see
:func:`vitruvian_coefficients`): with ``q = e^{cπ}`` they reduce to ``1 + q + … + q⁵ = 4``.
The listel grows from 0.03 to 0.12 spiral units along the whole spiral, about 30 % of the gap
between turns everywhere.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields, replace
from typing import Any

import numpy as np

from ionic_usd.column.portunus import PORTUNUS_LOWER_DIAMETER
from ionic_usd.column.volute_arcs import arc_points, chain_arc_count, check_arcs
from ionic_usd.column.volute_band import (
    CHECK_PER_TURN,
    band_thickness,
    spiral_limit,
    turn_samples,
    worst_crossing,
)
from ionic_usd.errors import GeometryError, ParameterError
from ionic_usd.geometry import libm

__all__ = [
    "VOLUTE_MODELS",
    "VOLUTE_LENGTHS",
    "VoluteParams",
    "VOLUTE_PARAMETER_DOCS",
    "vitruvian_coefficients",
    "vitruvian_volute",
    "spiral_limit",
    "volute_theta",
    "volute_radius",
    "volute_thickness",
    "volute_points",
    "volute_curve",
    "volute_inner_curve",
    "volute_eye",
    "volute_extent",
    "volute_total_radius",
    "volute_band_outline",
]

VOLUTE_PARAMETER_DOCS: dict[str, tuple[str, str, str]] = {
    "start_angle": ("start angle", "deg", "lower limit of θ"),
    "thickness": ("thickness", "spiral units", "band thickness (radius reduction, inner edge)"),
    "min_thickness": ("min thickness", "spiral units", "band thickness at the start angle"),
    "increasing_max": ("increasing max", "deg", "θ at which the thickness reaches `thickness`"),
    "spiral_circuits": ("spiral circuits", "count", "θ limit: 2.5π + 2π(n − 1)"),
    "capital_circle_radius": ("capital circle radius", "m", "radius of the eye"),
    "capital_spiral_radius": ("capital spiral radius", "m", "R in formula 3"),
    "offset_x": ("offset X", "m", "horizontal distance from the spiral origin to the eye"),
    "offset_y": ("offset Y", "m", "vertical distance from the spiral origin to the eye"),
    "a": ("a", "", "r = a / (b e^{cθ}) − d"),
    "b": ("b", "", "r = a / (b e^{cθ}) − d, b ≠ 0"),
    "c": ("c", "1/rad", "r = a / (b e^{cθ}) − d; c < 0: r grows with θ"),
    "d": ("d", "spiral units", "r = a / (b e^{cθ}) − d"),
    "volute_model": (
        "volute model",
        "",
        "log_spiral (paper, formula 3) or centred_arcs (quarter circles about centres in the eye)",
    ),
    "arc_square": (
        "arc square",
        "m",
        "centred_arcs: side of the outermost square of arc "
        "centres (radius step between the last two arcs)",
    ),
    "arc_ratio": (
        "arc ratio",
        "",
        "centred_arcs: innermost / outermost square side (steps linear in between)",
    ),
    "arc_radii": (
        "arc radii",
        "m",
        "centred_arcs, a free chain: each arc's radius from the eye out (empty: the steps above)",
    ),
    "arc_sweeps": (
        "arc sweeps",
        "deg",
        "centred_arcs, a free chain: each joint's sweep (empty: quarter turns)",
    ),
}

#: The fields in metres (:meth:`VoluteParams.scaled`); the others are angles, counts, ratios or
#: spiral units (× R).
VOLUTE_LENGTHS = (
    "capital_circle_radius",
    "capital_spiral_radius",
    "offset_x",
    "offset_y",
    "arc_square",
)

#: The free chain of the centred-arc model: each arc's radius and each joint's sweep (lists).
ARC_CHAIN_FIELDS = ("arc_radii", "arc_sweeps")
#: At most this many arcs in a free chain (a volute of 24 turns).
MAX_CHAIN_ARCS = 96

#: The volute curve constructions (``VoluteParams.volute_model``).
VOLUTE_MODELS = ("log_spiral", "centred_arcs")


def vitruvian_coefficients() -> tuple[float, float, float, float]:
    """``(a, b, c, d)`` of the Vitruvian volute in spiral units (R = top radius, b = 1).

    Solves ``r(6.5π) = 1``, ``r(5.5π) = 7/9``, ``r(π/2) = 1/9`` (module docstring). With
    ``E = a·e^{−6.5πc}`` and ``q = e^{cπ}``: ``E − d = 1``, ``E·q − d = 7/9`` and
    ``E·q⁶ − d = 1/9``, so ``(1 − q⁶)/(1 − q) = 4``, solved by bisection on (0, 1).
    """
    lo, hi = 1e-9, 1.0 - 1e-12
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if sum(mid**k for k in range(6)) < 4.0:
            lo = mid
        else:
            hi = mid
    q = 0.5 * (lo + hi)
    e_top = (2.0 / 9.0) / (1.0 - q)
    d = e_top - 1.0
    c = math.log(q) / math.pi  # negative: r grows with θ
    a = e_top * math.exp(c * 6.5 * math.pi)
    return a, 1.0, c, d


_VA, _VB, _VC, _VD = vitruvian_coefficients()
_D_PORTUNUS = PORTUNUS_LOWER_DIAMETER


@dataclass(frozen=True)
class VoluteParams:
    """The nine volute parameters of the paper's Table 4 plus the spiral's a, b, c, d.

    Defaults: the Vitruvian volute for the Temple of Portunus (module docstring).
    Angles in degrees; ``capital_circle_radius``, ``capital_spiral_radius`` and the offsets in
    metres; ``thickness``, ``min_thickness`` and ``d`` in spiral units (× R).

    Raises
    ------
    ParameterError
        A value out of range (names the parameter).
    GeometryError
        The band crosses itself or the spiral radius does not stay monotone.
    """

    start_angle: float = 90.0
    thickness: float = 0.12
    min_thickness: float = 0.03
    increasing_max: float = 1170.0
    spiral_circuits: float = 3.0
    capital_circle_radius: float = _D_PORTUNUS / 36.0
    capital_spiral_radius: float = _D_PORTUNUS / 4.0
    offset_x: float = 0.0
    offset_y: float = 0.0
    a: float = _VA
    b: float = _VB
    c: float = _VC
    d: float = _VD
    volute_model: str = "log_spiral"
    arc_square: float = _D_PORTUNUS / 18.0 * 6.0 / 11.0
    arc_ratio: float = 1.0 / 3.0
    arc_radii: tuple[float, ...] = ()
    arc_sweeps: tuple[float, ...] = ()

    def __post_init__(self) -> None:
        ctx = "volute"
        if self.volute_model not in VOLUTE_MODELS:
            raise ParameterError(
                "volute_model", self.volute_model, f"one of {', '.join(VOLUTE_MODELS)}", context=ctx
            )
        for f in fields(self):
            if f.name in ("volute_model", *ARC_CHAIN_FIELDS):
                continue
            v = getattr(self, f.name)
            if isinstance(v, bool) or not isinstance(v, int | float):
                raise ParameterError(f.name, v, "a number", context=ctx)
            if not math.isfinite(v):
                raise ParameterError(f.name, v, "a finite number", context=ctx)
            object.__setattr__(self, f.name, float(v))
        if self.b == 0:
            raise ParameterError("b", self.b, "a number != 0 (r = a / (b e^{cθ}) - d)", context=ctx)
        if self.spiral_circuits < 1:
            raise ParameterError(
                "spiral_circuits", self.spiral_circuits, "a number >= 1", context=ctx
            )
        if self.capital_spiral_radius <= 0:
            raise ParameterError(
                "capital_spiral_radius", self.capital_spiral_radius, "a length > 0 (R)", context=ctx
            )
        if self.capital_circle_radius <= 0:
            raise ParameterError(
                "capital_circle_radius",
                self.capital_circle_radius,
                "a length > 0 (the eye's radius)",
                context=ctx,
            )
        if self.thickness <= 0:
            raise ParameterError("thickness", self.thickness, "a number > 0", context=ctx)
        if not 0 <= self.min_thickness <= self.thickness:
            raise ParameterError(
                "min_thickness",
                self.min_thickness,
                f"0 <= min_thickness <= thickness ({self.thickness:g})",
                context=ctx,
            )
        limit = math.degrees(self.theta_end)
        if self.start_angle >= limit:
            raise ParameterError(
                "start_angle",
                self.start_angle,
                f"an angle below the spiral limit 2.5π + 2π(n − 1) = {limit:g} deg "
                f"for spiral_circuits = {self.spiral_circuits:g}",
                context=ctx,
            )
        self._check_chain()
        if self.volute_model == "centred_arcs":
            check_arcs(self)
            return
        self._check_shape()

    def _check_chain(self) -> None:
        """``arc_radii`` / ``arc_sweeps`` (a free chain of the centred-arc model): tuples of
        finite numbers, radii > 0 (m), sweeps in (0, 360] deg, one radius per arc and one sweep
        per joint, the joints before the θ limit."""
        ctx = "volute"
        for name, unit in (("arc_radii", "lengths > 0 (m)"), ("arc_sweeps", "angles (deg)")):
            v = getattr(self, name)
            if isinstance(v, str) or not isinstance(v, tuple | list):
                raise ParameterError(name, v, f"a list of {unit}", context=ctx)
            if len(v) > MAX_CHAIN_ARCS or not all(
                isinstance(x, int | float) and not isinstance(x, bool) and math.isfinite(x)
                for x in v
            ):
                raise ParameterError(
                    name, v, f"a list of at most {MAX_CHAIN_ARCS} finite {unit}", context=ctx
                )
            object.__setattr__(self, name, tuple(float(x) for x in v))
        radii, sweeps = self.arc_radii, self.arc_sweeps
        if not radii and not sweeps:
            return
        if self.volute_model != "centred_arcs":
            raise ParameterError(
                "arc_radii", radii, "empty unless volute_model = centred_arcs", context=ctx
            )
        if not radii:
            raise ParameterError("arc_sweeps", sweeps, "given with arc_radii", context=ctx)
        if min(radii) <= 0:
            raise ParameterError("arc_radii", radii, "lengths > 0 (m)", context=ctx)
        if sweeps:
            if len(sweeps) != len(radii) - 1:
                raise ParameterError(
                    "arc_sweeps",
                    sweeps,
                    f"{len(radii) - 1} sweeps (one per joint of the {len(radii)} arcs)",
                    context=ctx,
                )
            if not all(0 < x <= 360 for x in sweeps):
                raise ParameterError("arc_sweeps", sweeps, "angles in (0, 360] deg", context=ctx)
            last = self.start_angle + sum(sweeps)
            limit = math.degrees(self.theta_end)
            if last >= limit:
                raise ParameterError(
                    "arc_sweeps",
                    sweeps,
                    f"joints before the θ limit {limit:g} deg (the last arc starts at "
                    f"{last:g} deg)",
                    context=ctx,
                )
        elif len(radii) != chain_arc_count(self):
            raise ParameterError(
                "arc_radii",
                radii,
                f"{chain_arc_count(self)} radii (one per quarter turn from start_angle to the θ "
                "limit), or arc_sweeps for other joints",
                context=ctx,
            )

    # -- derived ------------------------------------------------------------------------
    @property
    def theta_start(self) -> float:
        """Lower θ limit in radians."""
        return math.radians(self.start_angle)

    @property
    def theta_end(self) -> float:
        """Upper θ limit in radians: ``2.5π + 2π(n − 1)``."""
        return spiral_limit(self.spiral_circuits)

    @property
    def eye_center(self) -> np.ndarray:
        """(2,) float: the eye's centre relative to the spiral origin (m)."""
        return np.array([self.offset_x, self.offset_y])

    @property
    def grows_outward(self) -> bool:
        """True when r grows with θ (the start angle lies at the eye)."""
        if self.volute_model == "centred_arcs":
            return True
        return bool(volute_radius(self, self.theta_end) > volute_radius(self, self.theta_start))

    def with_(self, **changes) -> VoluteParams:
        return replace(self, **changes)

    def scaled(self, factor: float) -> VoluteParams:
        """The same volute ``factor`` times as large: every length in metres (R, the eye,
        the offsets, the arc square) scaled; angles and spiral units kept."""
        if isinstance(factor, bool) or not (isinstance(factor, int | float) and factor > 0):
            raise ParameterError("factor", factor, "a number > 0", context="volute")
        radii = tuple(r * factor for r in self.arc_radii)
        return replace(
            self, **{n: getattr(self, n) * factor for n in VOLUTE_LENGTHS}, arc_radii=radii
        )

    # -- validation ---------------------------------------------------------------------
    def _check_shape(self) -> None:
        span = self.theta_end - self.theta_start
        n = max(8, int(math.ceil(span / (2 * math.pi) * CHECK_PER_TURN)) + 1)
        th = np.linspace(self.theta_start, self.theta_end, n)
        with np.errstate(over="ignore", invalid="ignore"):
            r = volute_radius(self, th)
        coeffs = "a, b, c, d"
        vals = (self.a, self.b, self.c, self.d)
        if not np.all(np.isfinite(r)):
            raise ParameterError(
                coeffs, vals, "a finite spiral radius over the θ range", context="volute"
            )
        if r.min() <= 0:
            k = int(np.argmin(r))
            raise ParameterError(
                coeffs,
                vals,
                f"a spiral radius r > 0 for θ in [{self.start_angle:g}, "
                f"{math.degrees(self.theta_end):g}] deg (r = {r[k]:.4g} at "
                f"{math.degrees(th[k]):.1f} deg)",
                context="volute",
            )
        t = volute_thickness(self, th)
        bad = t >= r
        if bad.any():
            k = int(np.argmax(bad))
            raise ParameterError(
                "thickness/min_thickness",
                (self.thickness, self.min_thickness),
                f"a band thickness below the spiral radius (t = {t[k]:.4g} >= r = {r[k]:.4g} at "
                f"θ = {math.degrees(th[k]):.1f} deg)",
                context="volute",
            )
        dr = np.diff(r)
        if not (np.all(dr > 0) or np.all(dr < 0)):
            raise GeometryError(
                f"volute: the spiral radius must change monotonically along θ (c != 0); "
                f"a, b, c, d = {vals} give a radius that turns back"
            )
        _check_band(self)


def _check_band(p: VoluteParams) -> None:
    """Refuse a band that overlaps itself.

    Two band points lie on the same ray only when their θ differ by 2πk; the band there
    covers the radial intervals ``[r − t, r]`` of both turns, and these must be disjoint
    (exact polar test on paired samples θ, θ + 2πk).
    """
    span = p.theta_end - p.theta_start
    k = 1
    while 2 * math.pi * k < span:
        th1 = turn_samples(p.theta_start, p.theta_end, k)
        th2 = th1 + 2 * math.pi * k
        r1, r2 = volute_radius(p, th1), volute_radius(p, th2)
        t1, t2 = volute_thickness(p, th1), volute_thickness(p, th2)
        outer_inner = np.where(r2 > r1, r2 - t2, r1 - t1)  # inner edge of the outer turn
        inner_outer = np.minimum(r1, r2)  # outer edge of the inner turn
        j = worst_crossing(outer_inner - inner_outer)
        if j is not None:
            raise GeometryError(
                "volute: the spiral band crosses itself: at θ = "
                f"{math.degrees(th1[j]):.1f} deg the inner edge of one turn "
                f"(r − t = {outer_inner[j]:.4g}) does not clear the outer edge of the next "
                f"turn (r = {inner_outer[j]:.4g}); reduce thickness / min_thickness / "
                "increasing_max or widen the spiral (a, b, c, d)"
            )
        k += 1


def vitruvian_volute(lower_diameter: float = _D_PORTUNUS, **overrides) -> VoluteParams:
    """The Vitruvian volute for a column of lower diameter ``lower_diameter`` (m).

    R = D/4 (4½ parts of D/18), eye radius D/36 (one part across); ``a, b, c, d`` from
    :func:`vitruvian_coefficients` (dimensionless, so independent of D).
    """
    if not (
        isinstance(lower_diameter, int | float)
        and math.isfinite(lower_diameter)
        and lower_diameter > 0
    ):
        raise ParameterError("lower_diameter", lower_diameter, "a length > 0", context="volute")
    kw: dict[str, Any] = dict(
        capital_spiral_radius=lower_diameter / 4.0,
        capital_circle_radius=lower_diameter / 36.0,
        arc_square=lower_diameter / 18.0 * 6.0 / 11.0,
    )
    kw.update(overrides)
    return VoluteParams(**kw)


# -- the curve ---------------------------------------------------------------------------
def volute_theta(p: VoluteParams, samples: int) -> np.ndarray:
    """(samples,) float: θ (radians) evenly from the start angle to the circuit limit."""
    if not isinstance(samples, int | np.integer) or samples < 2:
        raise ParameterError("samples", samples, "an integer >= 2", context="volute")
    return np.linspace(p.theta_start, p.theta_end, int(samples))


def volute_radius(p: VoluteParams, theta: np.ndarray | float) -> np.ndarray:
    """Spiral radius ``r(θ) = a / (b·e^{cθ}) − d`` in spiral units (paper formula 3)."""
    th = np.asarray(theta, dtype=np.float64)
    return p.a / (p.b * libm.exp(p.c * th)) - p.d


def volute_thickness(p: VoluteParams, theta: np.ndarray | float) -> np.ndarray:
    """Band thickness at θ (spiral units): linear from ``min_thickness`` at the start angle to
    ``thickness`` at ``increasing_max``, constant after."""
    return band_thickness(p, theta)


def volute_points(p: VoluteParams, theta: np.ndarray, inner: bool = False) -> np.ndarray:
    """Points of the band's outer (or, ``inner``, inner) edge at θ, for either volute model.

    Returns
    -------
    (len(theta), 2) float: metres, relative to the spiral origin.
    """
    th = np.asarray(theta, dtype=np.float64)
    if p.volute_model == "centred_arcs":
        return arc_points(p, th, 1.0 if inner else 0.0)
    r = volute_radius(p, th) - (volute_thickness(p, th) if inner else 0.0)
    return p.capital_spiral_radius * np.stack([r * np.cos(th), r * np.sin(th)], axis=1)


def volute_curve(p: VoluteParams, samples: int = 192) -> np.ndarray:
    """Outer edge of the spiral band.

    Returns
    -------
    (samples, 2) float: metres, relative to the spiral origin, at :func:`volute_theta`.
    """
    return volute_points(p, volute_theta(p, samples))


def volute_inner_curve(p: VoluteParams, samples: int = 192) -> np.ndarray:
    """Inner edge: the outer radius reduced by the thickness, at the same θ.

    Returns
    -------
    (samples, 2) float, metres, relative to the spiral origin.
    """
    return volute_points(p, volute_theta(p, samples), inner=True)


def volute_eye(p: VoluteParams, segments: int = 48) -> np.ndarray:
    """The eye's circle, counter-clockwise from angle 0.

    Returns
    -------
    (segments, 2) float, metres, relative to the spiral origin.
    """
    if segments < 3:
        raise ParameterError("segments", segments, "an integer >= 3", context="volute eye")
    a = np.arange(segments) * (2 * np.pi / segments)
    return p.eye_center + p.capital_circle_radius * np.stack([np.cos(a), np.sin(a)], axis=1)


def volute_extent(p: VoluteParams, samples: int = 2048, eye_segments: int = 64) -> np.ndarray:
    """Bounding box of the sampled outer curve and eye relative to the **eye centre**.

    With the samples of :func:`build_volute` this is exactly the solid's XY extent (the
    backing reuses the band's samples).

    Returns
    -------
    (2, 2) float: ``[[xmin, ymin], [xmax, ymax]]`` in metres.
    """
    pts = np.concatenate([volute_curve(p, samples), volute_eye(p, eye_segments)])
    pts = pts - p.eye_center
    return np.stack([pts.min(axis=0), pts.max(axis=0)])


def volute_total_radius(p: VoluteParams, samples: int = 2048) -> float:
    """The spiral's total radius: the largest distance of the outer edge from the eye (m)."""
    return float(np.linalg.norm(volute_curve(p, samples) - p.eye_center, axis=1).max())


def volute_band_outline(
    p: VoluteParams, samples: int = 192, margin: float = 0.0, rise: float = 0.0
) -> tuple[np.ndarray, np.ndarray]:
    """Outer and inner rows of the band, optionally continued straight past the last sample.

    The continuation (the canalis margin) leaves the end point along the curve's last
    direction — with the defaults horizontally towards −X — for ``margin`` metres; its outer
    (upper) edge rises by ``rise`` on the way, up into the abacus it runs under (so the two
    do not meet as coincident faces; the lower edge, the one seen, stays straight).

    Returns
    -------
    outer, inner : (samples [+1], 2) float, metres relative to the spiral origin.
    """
    outer, inner = volute_curve(p, samples), volute_inner_curve(p, samples)
    if margin > 0:
        # the top end lies at θ ≡ π/2: the tangent is close to horizontal, and a horizontal
        # margin keeps the canalis parallel to the abacus
        direction = np.sign(outer[-1, 0] - outer[-2, 0]) or -1.0
        step = np.array([direction * margin, 0.0])
        outer = np.vstack([outer, outer[-1] + step + [0.0, rise]])
        inner = np.vstack([inner, inner[-1] + step])
    return outer, inner
