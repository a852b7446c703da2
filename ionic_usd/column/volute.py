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

import numpy as np

from ionic_usd.errors import GeometryError, ParameterError
from ionic_usd.geometry.mesh import Mesh, merge
from ionic_usd.geometry.stitch import stitch

__all__ = [
    "VOLUTE_MODELS",
    "VoluteParams",
    "VOLUTE_PARAMETER_DOCS",
    "vitruvian_coefficients",
    "vitruvian_volute",
    "spiral_limit",
    "volute_theta",
    "volute_radius",
    "volute_thickness",
    "volute_curve",
    "volute_inner_curve",
    "volute_eye",
    "volute_extent",
    "volute_total_radius",
    "volute_band_outline",
    "build_volute_band",
    "build_volute_backing",
    "build_volute_eye",
    "build_volute",
    "prism",
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
    "volute_model": ("volute model", "", "log_spiral (paper, formula 3) or centred_arcs "
                     "(quarter circles about centres in the eye)"),
    "arc_square": ("arc square", "m", "centred_arcs: side of the outermost square of arc "
                   "centres (radius step between the last two arcs)"),
    "arc_ratio": ("arc ratio", "", "centred_arcs: innermost / outermost square side (steps "
                  "linear in between)"),
}

#: The volute curve constructions (``VoluteParams.volute_model``).
VOLUTE_MODELS = ("log_spiral", "centred_arcs")

#: θ samples per turn used by the validity checks (exact 2π pairing, see ``_check_band``)
_CHECK_PER_TURN = 720


def spiral_limit(circuits: float) -> float:
    """Upper θ limit (radians) for ``circuits`` spiral circuits: ``2.5π + 2π(n − 1)``."""
    return 2.5 * math.pi + 2.0 * math.pi * (circuits - 1.0)


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
_D_PORTUNUS = 0.95


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

    def __post_init__(self) -> None:
        ctx = "volute"
        if self.volute_model not in VOLUTE_MODELS:
            raise ParameterError("volute_model", self.volute_model,
                                 f"one of {', '.join(VOLUTE_MODELS)}", context=ctx)
        for f in fields(self):
            if f.name == "volute_model":
                continue
            v = getattr(self, f.name)
            if isinstance(v, bool) or not isinstance(v, int | float):
                raise ParameterError(f.name, v, "a number", context=ctx)
            if not math.isfinite(v):
                raise ParameterError(f.name, v, "a finite number", context=ctx)
            object.__setattr__(self, f.name, float(v))
        if self.b == 0:
            raise ParameterError("b", self.b, "a number != 0 (r = a / (b e^{cθ}) - d)",
                                 context=ctx)
        if self.spiral_circuits < 1:
            raise ParameterError("spiral_circuits", self.spiral_circuits, "a number >= 1",
                                 context=ctx)
        if self.capital_spiral_radius <= 0:
            raise ParameterError("capital_spiral_radius", self.capital_spiral_radius,
                                 "a length > 0 (R)", context=ctx)
        if self.capital_circle_radius <= 0:
            raise ParameterError("capital_circle_radius", self.capital_circle_radius,
                                 "a length > 0 (the eye's radius)", context=ctx)
        if self.thickness <= 0:
            raise ParameterError("thickness", self.thickness, "a number > 0", context=ctx)
        if not 0 <= self.min_thickness <= self.thickness:
            raise ParameterError("min_thickness", self.min_thickness,
                                 f"0 <= min_thickness <= thickness ({self.thickness:g})",
                                 context=ctx)
        limit = math.degrees(self.theta_end)
        if self.start_angle >= limit:
            raise ParameterError(
                "start_angle", self.start_angle,
                f"an angle below the spiral limit 2.5π + 2π(n − 1) = {limit:g} deg "
                f"for spiral_circuits = {self.spiral_circuits:g}", context=ctx,
            )
        if self.volute_model == "centred_arcs":
            from ionic_usd.column.volute_arcs import check_arcs

            check_arcs(self)
            return
        self._check_shape()

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

    # -- validation ---------------------------------------------------------------------
    def _check_shape(self) -> None:
        span = self.theta_end - self.theta_start
        n = max(8, int(math.ceil(span / (2 * math.pi) * _CHECK_PER_TURN)) + 1)
        th = np.linspace(self.theta_start, self.theta_end, n)
        with np.errstate(over="ignore", invalid="ignore"):
            r = volute_radius(self, th)
        coeffs = "a, b, c, d"
        vals = (self.a, self.b, self.c, self.d)
        if not np.all(np.isfinite(r)):
            raise ParameterError(coeffs, vals, "a finite spiral radius over the θ range",
                                 context="volute")
        if r.min() <= 0:
            k = int(np.argmin(r))
            raise ParameterError(
                coeffs, vals,
                f"a spiral radius r > 0 for θ in [{self.start_angle:g}, "
                f"{math.degrees(self.theta_end):g}] deg (r = {r[k]:.4g} at "
                f"{math.degrees(th[k]):.1f} deg)", context="volute",
            )
        t = volute_thickness(self, th)
        bad = t >= r
        if bad.any():
            k = int(np.argmax(bad))
            raise ParameterError(
                "thickness/min_thickness", (self.thickness, self.min_thickness),
                f"a band thickness below the spiral radius (t = {t[k]:.4g} >= r = {r[k]:.4g} at "
                f"θ = {math.degrees(th[k]):.1f} deg)", context="volute",
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
        m = max(4, int(math.ceil((span - 2 * math.pi * k) / (2 * math.pi) * _CHECK_PER_TURN)))
        th1 = np.linspace(p.theta_start, p.theta_end - 2 * math.pi * k, m + 1)
        th2 = th1 + 2 * math.pi * k
        r1, r2 = volute_radius(p, th1), volute_radius(p, th2)
        t1, t2 = volute_thickness(p, th1), volute_thickness(p, th2)
        outer_inner = np.where(r2 > r1, r2 - t2, r1 - t1)  # inner edge of the outer turn
        inner_outer = np.minimum(r1, r2)  # outer edge of the inner turn
        gap = outer_inner - inner_outer
        if gap.min() <= 0:
            j = int(np.argmin(gap))
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
    if not (isinstance(lower_diameter, int | float) and math.isfinite(lower_diameter)
            and lower_diameter > 0):
        raise ParameterError("lower_diameter", lower_diameter, "a length > 0", context="volute")
    kw = dict(capital_spiral_radius=lower_diameter / 4.0,
              capital_circle_radius=lower_diameter / 36.0,
              arc_square=lower_diameter / 18.0 * 6.0 / 11.0)
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
    return p.a / (p.b * np.exp(p.c * th)) - p.d


def volute_thickness(p: VoluteParams, theta: np.ndarray | float) -> np.ndarray:
    """Band thickness at θ (spiral units): linear from ``min_thickness`` at the start angle to
    ``thickness`` at ``increasing_max``, constant after."""
    th = np.asarray(theta, dtype=np.float64)
    t0, t1 = p.theta_start, math.radians(p.increasing_max)
    if t1 <= t0:
        return np.full_like(th, p.thickness)
    u = np.clip((th - t0) / (t1 - t0), 0.0, 1.0)
    return p.min_thickness + (p.thickness - p.min_thickness) * u


def _polar(p: VoluteParams, radius: np.ndarray, th: np.ndarray) -> np.ndarray:
    return p.capital_spiral_radius * np.stack([radius * np.cos(th), radius * np.sin(th)], axis=1)


def volute_curve(p: VoluteParams, samples: int = 192) -> np.ndarray:
    """Outer edge of the spiral band.

    Returns
    -------
    (samples, 2) float: metres, relative to the spiral origin, at :func:`volute_theta`.
    """
    th = volute_theta(p, samples)
    if p.volute_model == "centred_arcs":
        from ionic_usd.column.volute_arcs import arc_points

        return arc_points(p, th, 0.0)
    return _polar(p, volute_radius(p, th), th)


def volute_inner_curve(p: VoluteParams, samples: int = 192) -> np.ndarray:
    """Inner edge: the outer radius reduced by the thickness, at the same θ.

    Returns
    -------
    (samples, 2) float, metres, relative to the spiral origin.
    """
    th = volute_theta(p, samples)
    if p.volute_model == "centred_arcs":
        from ionic_usd.column.volute_arcs import arc_points

        return arc_points(p, th, 1.0)
    return _polar(p, volute_radius(p, th) - volute_thickness(p, th), th)


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
    p: VoluteParams, samples: int = 192, margin: float = 0.0
) -> tuple[np.ndarray, np.ndarray]:
    """Outer and inner rows of the band, optionally continued straight past the last sample.

    The continuation (the canalis margin) leaves the end point along the curve's last
    direction — with the defaults horizontally towards −X — for ``margin`` metres.

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
        outer = np.vstack([outer, outer[-1] + step])
        inner = np.vstack([inner, inner[-1] + step])
    return outer, inner


# -- solids ------------------------------------------------------------------------------
def _boundary_loop(tris: np.ndarray) -> np.ndarray:
    """Ordered boundary vertex loop of a disc-like triangulation (edges used once)."""
    e = np.concatenate([tris[:, [0, 1]], tris[:, [1, 2]], tris[:, [2, 0]]])
    key = e[:, 0].astype(np.int64) * (1 << 32) + e[:, 1]
    rkey = e[:, 1].astype(np.int64) * (1 << 32) + e[:, 0]
    b = e[~np.isin(key, rkey)]
    nxt = dict(zip(b[:, 0].tolist(), b[:, 1].tolist(), strict=True))
    if len(nxt) != len(b):
        raise GeometryError("prism: the region boundary is not a simple loop")
    start = int(b[0, 0])
    loop = [start]
    v = nxt[start]
    while v != start:
        loop.append(v)
        if len(loop) > len(b):
            raise GeometryError("prism: the region boundary is not a single loop")
        v = nxt[v]
    if len(loop) != len(b):
        raise GeometryError("prism: the region has more than one boundary loop")
    return np.asarray(loop, dtype=np.int64)


def prism(
    points2d: np.ndarray,
    triangles: np.ndarray,
    z0: float,
    z1: float,
    *,
    loop: np.ndarray | None = None,
    crease_deg: float = 40.0,
    name: str = "prism",
) -> Mesh:
    """Extrude a triangulated planar region (one boundary loop) along Z into a closed solid.

    Parameters
    ----------
    points2d : (n, 2) float
    triangles : (t, 3) int, one orientation throughout (either; flipped to counter-clockwise)
    z0, z1 : back and front plane (z0 < z1)
    loop : (b,) int, optional
        The region's boundary, counter-clockwise; found from the triangles when omitted.
    crease_deg : boundary corners sharper than this give crisp vertical edges

    Returns
    -------
    Closed triangle Mesh with faceVarying normals: flat caps, walls smooth between creases.
    """
    pts = np.asarray(points2d, dtype=np.float64)
    tri = np.asarray(triangles, dtype=np.int64)
    if not z1 > z0:
        raise GeometryError(f"prism {name!r}: z1 must exceed z0")
    p = pts[tri]
    area2 = ((p[:, 1, 0] - p[:, 0, 0]) * (p[:, 2, 1] - p[:, 0, 1])
             - (p[:, 1, 1] - p[:, 0, 1]) * (p[:, 2, 0] - p[:, 0, 0]))
    if np.all(area2 < 0):
        tri, area2 = tri[:, ::-1], -area2
    if not np.all(area2 > 0):
        raise GeometryError(f"prism {name!r}: the region's triangles fold over or are degenerate")
    if loop is None:
        loop = _boundary_loop(tri)
    loop = np.asarray(loop, dtype=np.int64)
    lp = pts[loop]
    if np.dot(lp[:, 0], np.roll(lp[:, 1], -1)) - np.dot(np.roll(lp[:, 0], -1), lp[:, 1]) < 0:
        loop = loop[::-1]
    n = len(pts)
    # wall normals: outward edge normals of the counter-clockwise loop, averaged at smooth
    # vertices and kept per edge at creases (so a sharp corner stays crisp)
    d = pts[np.roll(loop, -1)] - pts[loop]
    en = np.stack([d[:, 1], -d[:, 0]], axis=1)
    en /= np.linalg.norm(en, axis=1, keepdims=True)
    prev_en = np.roll(en, 1, axis=0)
    crease = np.einsum("ij,ij->i", prev_en, en) < math.cos(math.radians(crease_deg))
    vn = prev_en + en
    vn /= np.linalg.norm(vn, axis=1, keepdims=True)
    n_start = np.where(crease[:, None], en, vn)  # normal at the edge's first vertex
    n_end = np.roll(np.where(crease[:, None], prev_en, vn), -1, axis=0)  # at its second vertex
    u, v = loop, np.roll(loop, -1)
    # wall quad (v_top, u_top, u_bot, v_bot): reverses the cap edge u→v on top, runs u→v below
    walls = np.concatenate([np.stack([v + n, u + n, u], axis=1), np.stack([v + n, u, v], axis=1)])
    wall_n = np.concatenate([np.stack([n_end, n_start, n_start], axis=1),
                             np.stack([n_end, n_start, n_end], axis=1)])
    faces = np.concatenate([tri + n, tri[:, ::-1], walls])
    t = len(tri)
    normals = np.zeros((len(faces), 3, 3), dtype=np.float32)
    normals[:t, :, 2] = 1.0
    normals[t:2 * t, :, 2] = -1.0
    normals[2 * t:, :, :2] = wall_n
    points = np.concatenate([np.column_stack([pts, np.full(n, z0)]),
                             np.column_stack([pts, np.full(n, z1)])])
    return Mesh(points, np.full(len(faces), 3, np.int32), faces.reshape(-1),
                normals.reshape(-1, 3), "faceVarying", name=name)


def _lift(p: VoluteParams, xy: np.ndarray) -> np.ndarray:
    """Spiral-origin coordinates → eye-centred coordinates."""
    return xy - p.eye_center


def build_volute_band(
    p: VoluteParams, *, samples: int = 192, margin: float = 0.0, z0: float, z1: float,
    name: str = "volute_band",
) -> Mesh:
    """The raised spiral band (the listel) as a closed prism between ``z0`` and ``z1``.

    Coordinates: the eye centre at the origin, the volute's face plane ⊥ Z.
    """
    outer, inner = volute_band_outline(p, samples, margin)
    n = len(outer)
    tris = stitch(np.arange(n), np.arange(n, 2 * n), is_closed=False)
    loop = np.concatenate([np.arange(n), np.arange(2 * n - 1, n - 1, -1)])
    return prism(_lift(p, np.concatenate([outer, inner])), tris, z0, z1, loop=loop, name=name)


def build_volute_backing(
    p: VoluteParams, *, samples: int = 192, z0: float, z1: float, name: str = "volute_backing",
) -> Mesh:
    """The volute's disc (the channel floor): the region inside the outermost turn.

    The region is fanned from the spiral origin (the curve is star-shaped about it since r is
    monotone); its closing edge is the radial segment between the two ends of the outer turn.
    """
    # the band's own θ samples (plus the turn's exact first angle), so the disc's rim lies
    # on the band's outer edge and adds nothing to the volute's extent
    band_th = volute_theta(p, samples)
    span = p.theta_end - p.theta_start
    turn = min(span, 2 * math.pi)
    if p.grows_outward:
        lo = p.theta_end - turn
        th = np.concatenate([[lo], band_th[band_th > lo + 1e-9]])
    else:
        hi = p.theta_start + turn
        th = np.concatenate([band_th[band_th < hi - 1e-9], [hi]])
    m = len(th)
    if p.volute_model == "centred_arcs":
        from ionic_usd.column.volute_arcs import arc_points

        ring = arc_points(p, th, 0.0)
    else:
        ring = _polar(p, volute_radius(p, th), th)
    pts = np.vstack([ring, [[0.0, 0.0]]])
    o = m
    i = np.arange(m - 1)
    fan = np.stack([np.full(m - 1, o), i, i + 1], axis=1)
    loop = np.arange(m)
    if turn >= 2 * math.pi - 1e-12:
        # the inner end of the turn lies on the segment from the origin to the outer end:
        # split the wedge holding it there so the triangulation is conforming (no T-junction)
        if p.grows_outward:
            fan = np.vstack([fan[:-1], [[o, m - 2, 0], [0, m - 2, m - 1]]])
        else:
            fan = np.vstack([[[o, m - 1, 1], [m - 1, 0, 1]], fan[1:]])
    else:
        loop = np.arange(m + 1)  # a pie: the origin is on the boundary
    return prism(_lift(p, pts), fan, z0, z1, loop=loop, name=name)


def build_volute_eye(
    p: VoluteParams, *, segments: int = 48, z0: float, z1: float, name: str = "volute_eye",
) -> Mesh:
    """The eye as a cylindrical boss (a closed prism over the eye's circle)."""
    circle = volute_eye(p, segments)
    pts = np.vstack([circle, p.eye_center[None, :]])
    i = np.arange(segments)
    fan = np.stack([np.full(segments, segments), i, (i + 1) % segments], axis=1)
    return prism(_lift(p, pts), fan, z0, z1, loop=np.arange(segments), crease_deg=90.0,
                  name=name)


def build_volute(
    p: VoluteParams | None = None,
    *,
    samples: int = 192,
    eye_segments: int = 48,
    relief_depth: float = 0.015,
    slab_depth: float = 0.03,
    margin: float = 0.0,
    name: str = "volute",
) -> Mesh:
    """One volute (three closed shells: backing disc, raised band, eye boss), merged.

    Frame: the eye centre at the origin, the face towards +Z; the band and the eye span
    ``z ∈ [−relief_depth, 0]``, the backing ``[−relief_depth − slab_depth, −relief_depth]``;
    the recess between the band's turns is the backing's front face (the channel floor).
    Mirror with :func:`ionic_usd.geometry.mesh.transform` for the other volutes.
    """
    p = p or VoluteParams()
    for nm, v in (("relief_depth", relief_depth), ("slab_depth", slab_depth)):
        if not (math.isfinite(v) and v > 0):
            raise ParameterError(nm, v, "a length > 0", context="volute")
    if margin < 0 or not math.isfinite(margin):
        raise ParameterError("margin", margin, "a length >= 0", context="volute")
    band = build_volute_band(p, samples=samples, margin=margin, z0=-relief_depth, z1=0.0)
    back = build_volute_backing(p, samples=samples, z0=-relief_depth - slab_depth,
                                z1=-relief_depth)
    eye = build_volute_eye(p, segments=eye_segments, z0=-relief_depth, z1=0.0)
    return merge([back, band, eye], name=name)
