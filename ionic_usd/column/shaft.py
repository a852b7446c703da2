"""The fluted column shaft (paper section IV, Table 1; SPEC §1).

Geometry, from the bottom (y = 0) up; the axis is +Y::

    plain ring      y ∈ [0, ring_bottom]                 (a plain cylinder band, M vertices/row)
    flute ends      y ∈ [ring_bottom, + arc_bottom]       ($h rows, rounded "channel arcs")
    fluted body     y ∈ [..., + height]                   ($a: the shaft without the arcs)
    flute ends      arc_top                              ($h rows)
    plain ring      ring_top                              (M vertices/row)

Radius: linear taper from ``bottom_radius`` ($d) to ``top_radius`` ($c) over the whole length
plus an optional entasis ``E·d·sin(π t)`` (t = y / length): a convex swelling that vanishes at
both ends and is largest at mid-height — the simplest smooth curve with Vitruvius' property
that the swelling adds to, and never reverses, the taper for small E.

Cross-section: ``flutes`` ($e) flutes, centred at angles (k + ½)·360°/e so a fillet straddles
angle 0. Each flute is half an ellipse cut into the circle: its diameter parallel to the
tangent is the chord spanning the central angle ``flute_angle`` ($f), the perpendicular
semi-axis is ``flute_depth`` ($g) times the parallel one (g = 1: Vitruvius' semicircular flute).
Between flutes the fillet is an arc of the circle. The flute ends are rounded in elevation: over
the arc height ``arc_ratio``·ρ ($b, ρ = the flute's half-chord) the flute shrinks as
``sqrt(1 - s²)`` in width and depth (an ellipsoidal spoon end), and the last, narrowed row is
joined to the plain ring — which has a different vertex count — by ring stitching.

Level of detail: ``flute_slices`` ($h) slices across a flute and rows in each arc;
``flute_slices_per_fillet_slice`` ($i): the fillet is cut into ``round(w / (i·f/h))`` slices
(w = fillet angle), at least one; the plain rings use the fillet's angular step. Above the $i
that gives one fillet slice (:meth:`ShaftParams.fillet_ratio_saturation`) $i changes nothing,
so the ``shaft`` command refuses a larger one given by the user.

The shaft is a closed solid (bottom and top caps) unless ``cap_bottom`` / ``cap_top`` is off: then
it is open exactly at its bottom / top ring (``ring_segments`` vertices, vertex 0 at +X,
increasing angle), where the base and capital join.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from ionic_usd.checks import check_fields
from ionic_usd.errors import BudgetError, ParameterError
from ionic_usd.geometry import libm
from ionic_usd.geometry.mesh import CornerValues, Mesh, smooth_normals
from ionic_usd.geometry.stitch import auto_sequence, stitch

from .shaft_surface import grid_normals, shaft_st

__all__ = [
    "ShaftParams",
    "SHAFT_PARAMETER_DOCS",
    "build_shaft",
    "shaft_triangle_estimate",
    "shaft_radius_at",
    "shaft_silhouette",
    "shaft_cross_section",
    "DEFAULT_TRIANGLE_BUDGET",
]

DEFAULT_TRIANGLE_BUDGET = 20_000_000

# name -> (paper letter, unit, description); drives --help and TOML comments
SHAFT_PARAMETER_DOCS: dict[str, tuple[str, str, str]] = {
    "height": ("$a", "m", "shaft height without the channel arcs (fluted body)"),
    "arc_ratio": ("$b", "ratio", "channel-arc height as a ratio to the flute's half-chord"),
    "top_radius": ("$c", "m", "radius of the shaft's top circle"),
    "bottom_radius": ("$d", "m", "radius of the shaft's bottom circle"),
    "flutes": ("$e", "count", "number of flutes (Ionic: 24)"),
    "flute_angle": ("$f", "deg", "central angle of one flute; 360/e - f is the fillet"),
    "flute_depth": ("$g", "ratio", "flute ellipse depth: perpendicular/parallel diameter"),
    "flute_slices": ("$h", "count", "slices across one flute and rows per flute end (LOD)"),
    "flute_slices_per_fillet_slice": ("$i", "count", "flute slices per fillet slice (LOD)"),
    "ring_bottom": ("", "m", "height of the plain ring below the flutes"),
    "ring_top": ("", "m", "height of the plain ring above the flutes"),
    "entasis": ("", "ratio", "entasis amplitude as a fraction of the bottom radius (0 = none)"),
    "entasis_rows": ("", "count", "rows along the fluted body when entasis > 0"),
    "body_rows": ("", "count", "rows along the fluted body (at least; entasis_rows with entasis)"),
    "ring_vertices": (
        "",
        "count",
        "vertices of the bottom/top rings (0: from the fillet step); "
        "the column sets one count for every flute variant so bases fit all",
    ),
    "flute_phase": (
        "",
        "deg",
        "turn of the flutes about the axis (0: a fillet faces +x, as the plinth's face)",
    ),
}


@dataclass(frozen=True)
class ShaftParams:
    """The nine shaft parameters of the paper's Table 1 plus plain rings and entasis.

    Defaults: the Temple of Portunus (lower diameter 0.95 m, top diameter 6/7 of it after
    Vitruvius III.3.12 for columns of 20-30 ft; 24 flutes, fillet = ¼ flute width and
    semicircular flutes after Vitruvius III.5.14). Lengths in metres, angles in degrees.
    """

    height: float = 7.02
    arc_ratio: float = 1.0
    top_radius: float = 0.475 * 6.0 / 7.0
    bottom_radius: float = 0.475
    flutes: int = 24
    flute_angle: float = 12.0
    flute_depth: float = 1.0
    flute_slices: int = 8
    flute_slices_per_fillet_slice: int = 4
    ring_bottom: float = 0.06
    ring_top: float = 0.06
    entasis: float = 0.0
    entasis_rows: int = 16
    body_rows: int = 1
    ring_vertices: int = 0
    flute_phase: float = 0.0

    def __post_init__(self) -> None:
        ctx = "shaft"
        check_fields(
            self,
            context=ctx,
            integers=(
                "flutes",
                "flute_slices",
                "entasis_rows",
                "flute_slices_per_fillet_slice",
                "body_rows",
                "ring_vertices",
            ),
        )
        _pos = "a finite number > 0"
        if self.height <= 0:
            raise ParameterError("height ($a)", self.height, _pos, context=ctx)
        if self.top_radius <= 0:
            raise ParameterError("top_radius ($c)", self.top_radius, _pos, context=ctx)
        if self.bottom_radius <= 0:
            raise ParameterError("bottom_radius ($d)", self.bottom_radius, _pos, context=ctx)
        if self.flutes < 3:
            raise ParameterError("flutes ($e)", self.flutes, "an integer >= 3", context=ctx)
        period = 360.0 / self.flutes
        if not 0 < self.flute_angle < period:
            raise ParameterError(
                "flute_angle ($f)",
                self.flute_angle,
                f"0 < f < 360/e = {period:g} deg (the rest of 360/e is the fillet)",
                context=ctx,
            )
        if not 0 < self.flute_depth <= 4:
            raise ParameterError("flute_depth ($g)", self.flute_depth, "0 < g <= 4", context=ctx)
        if self.arc_ratio < 0:
            raise ParameterError("arc_ratio ($b)", self.arc_ratio, "a number >= 0", context=ctx)
        if self.flute_slices < 1:
            raise ParameterError(
                "flute_slices ($h)", self.flute_slices, "an integer >= 1", context=ctx
            )
        if self.flute_slices_per_fillet_slice < 1:
            raise ParameterError(
                "flute_slices_per_fillet_slice ($i)",
                self.flute_slices_per_fillet_slice,
                "an integer >= 1",
                context=ctx,
            )
        if not -180.0 <= self.flute_phase <= 180.0:
            raise ParameterError(
                "flute_phase", self.flute_phase, "-180 <= phase <= 180 deg", context=ctx
            )
        for name in ("ring_bottom", "ring_top"):
            if getattr(self, name) < 0:
                raise ParameterError(name, getattr(self, name), "a number >= 0", context=ctx)
        if not -0.2 <= self.entasis <= 0.2:
            raise ParameterError("entasis", self.entasis, "-0.2 <= entasis <= 0.2", context=ctx)
        if self.entasis_rows < 1:
            raise ParameterError("entasis_rows", self.entasis_rows, "an integer >= 1", context=ctx)
        if self.body_rows < 1:
            raise ParameterError("body_rows", self.body_rows, "an integer >= 1", context=ctx)
        if self.ring_vertices != 0 and self.ring_vertices < 3:
            raise ParameterError(
                "ring_vertices", self.ring_vertices, "0 (automatic) or an integer >= 3", context=ctx
            )
        # the flutes must not cut through the axis: chord distance minus depth stays > 0
        for name, r in (
            ("bottom_radius ($d)", self.bottom_radius),
            ("top_radius ($c)", self.top_radius),
        ):
            a = math.radians(self.flute_angle) / 2
            if r * math.cos(a) - self.flute_depth * r * math.sin(a) <= 0.05 * r:
                raise ParameterError(
                    "flute_depth ($g)",
                    self.flute_depth,
                    f"flutes shallower than the radius at {name}",
                    context=ctx,
                )

    # -- derived quantities --------------------------------------------------------------
    @property
    def fillet_angle(self) -> float:
        """Fillet width in degrees (360/e − f)."""
        return 360.0 / self.flutes - self.flute_angle

    @property
    def fillet_slices(self) -> int:
        step = self.flute_slices_per_fillet_slice * self.flute_angle / self.flute_slices
        return max(1, round(self.fillet_angle / step))

    def fillet_ratio_saturation(self) -> int:
        """The smallest $i giving the fillet a single slice: every larger $i builds the same
        shaft (``round(w·h / (i·f))`` is below one half; the fillet is at least one slice)."""
        # round() of Python rounds half to even: search rather than solve
        i = 1
        while max(1, round(self.fillet_angle * self.flute_slices / (i * self.flute_angle))) > 1:
            i += 1
        return i

    @property
    def ring_segments(self) -> int:
        """Vertices in a plain-ring row (the bottom/top rings the base and capital meet)."""
        if self.ring_vertices:
            return self.ring_vertices
        step = self.fillet_angle / self.fillet_slices
        per = max(1, round((360.0 / self.flutes) / step))
        return self.flutes * max(per, 2 if self.flutes < 8 else 1)

    @property
    def fluted_segments(self) -> int:
        """Vertices in a fluted row."""
        return self.flutes * (self.flute_slices + self.fillet_slices)

    def arc_height(self, radius: float) -> float:
        """Height of a flute end at a shaft radius: $b × the flute's half-chord."""
        return self.arc_ratio * radius * math.sin(math.radians(self.flute_angle) / 2)

    @property
    def length(self) -> float:
        """Total shaft length: rings + arcs + $a."""
        return (
            self.ring_bottom
            + self.arc_height(self.bottom_radius)
            + self.height
            + self.arc_height(self.top_radius)
            + self.ring_top
        )

    def to_dict(self) -> dict:
        return asdict(self)


def shaft_radius_at(p: ShaftParams, y: np.ndarray) -> np.ndarray:
    """Radius of the shaft's circle (fillet surface) at heights ``y`` (m): taper + entasis."""
    t = np.clip(np.asarray(y, dtype=np.float64) / p.length, 0.0, 1.0)
    r = p.bottom_radius + (p.top_radius - p.bottom_radius) * t
    return r + p.entasis * p.bottom_radius * np.sin(np.pi * t)


def _row_layout(p: ShaftParams) -> tuple[np.ndarray, np.ndarray]:
    """Heights and flute scale factors (0..1] of the fluted rows, bottom to top.

    A flute end is a quarter ellipse in elevation (scale k = cos φ at height fraction
    s = sin φ); rows sample φ in equal steps, which puts more rows where the end curves most.
    The tip itself (k = 0) is the plain ring row. A zero-height end is a single full row.
    """
    h = p.flute_slices
    y0 = p.ring_bottom
    ab = p.arc_height(p.bottom_radius)
    at = p.arc_height(p.top_radius)
    phi = 0.5 * np.pi * np.arange(h - 1, -1, -1) / h  # from the tip side to the full flute
    s, k_end = np.sin(phi), np.cos(phi)

    def end(height: float) -> tuple[np.ndarray, np.ndarray]:
        return (s, k_end) if height > 0 else (np.zeros(1), np.ones(1))

    sb, kb = end(ab)
    st, kt = end(at)
    body_rows = max(p.body_rows, p.entasis_rows if p.entasis != 0 else 1)
    y_body = y0 + ab + p.height * np.arange(1, body_rows) / body_rows
    ys = np.concatenate([y0 + ab * (1.0 - sb), y_body, y0 + ab + p.height + at * st[::-1]])
    ks = np.concatenate([kb, np.ones(len(y_body)), kt[::-1]])
    return ys, ks


def _fluted_rows(p: ShaftParams, ys: np.ndarray, ks: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Points (R, N, 3) of fluted rows, and angles (2, N) about +Y of the first and last row.

    One period (flute + fillet) is computed in the flute's local polar frame (R × (h + nf)
    values), then rotated to every flute by the angle-addition formulas: products instead
    of trigonometry over the whole grid.
    """
    e, h, nf = p.flutes, p.flute_slices, p.fillet_slices
    period = 2 * np.pi / e
    r = shaft_radius_at(p, ys)[:, None]  # (R,1)
    alpha = (np.radians(p.flute_angle) / 2 * ks)[:, None]  # flute half-angle per row
    phi = np.pi * np.arange(h) / h  # corner1 + interior flute vertices
    rho = r * np.sin(alpha)
    x_r = r * np.cos(alpha) - p.flute_depth * rho * np.sin(phi)  # (R,h)
    x_t = -rho * np.cos(phi)
    # fillet: corner2 and interior vertices on the circle up to the next flute
    fil_delta = alpha + (period - 2 * alpha) * (np.arange(nf) / nf)  # (R,nf)
    delta = np.concatenate([libm.arctan2(x_t, x_r), fil_delta], axis=1)  # (R,K) local angle
    rc = np.concatenate([x_r, r * np.cos(fil_delta)], axis=1)  # rad·cos(delta)
    rs = np.concatenate([x_t, r * np.sin(fil_delta)], axis=1)  # rad·sin(delta)
    centre = (np.arange(e) + 0.5) * period + np.radians(p.flute_phase)
    cc, sc = np.cos(centre)[None, :, None], np.sin(centre)[None, :, None]
    rc, rs = rc[:, None, :], rs[:, None, :]
    R, K = len(ys), h + nf
    pts = np.empty((R, e, K, 3))
    pts[..., 0] = cc * rc - sc * rs
    pts[..., 1] = ys[:, None, None]
    pts[..., 2] = -(sc * rc + cc * rs)
    # angles only of the first and last rows: the ones stitched to the plain rings
    ang = (centre[None, :, None] + delta[[0, -1], None, :]).reshape(2, -1)
    return pts.reshape(R, e * K, 3), ang


def shaft_triangle_estimate(p: ShaftParams, *, caps: int = 2) -> int:
    """Triangles :func:`build_shaft` will emit (computed without building)."""
    ys, _ = _row_layout(p)
    n, m = p.fluted_segments, p.ring_segments
    rings = 2 * n * ((p.ring_bottom > 0) + (p.ring_top > 0))
    return 2 * n * (len(ys) - 1) + 2 * (n + m) + rings + caps * m


def build_shaft(
    p: ShaftParams | None = None,
    *,
    cap_bottom: bool = True,
    cap_top: bool = True,
    y_offset: float = 0.0,
    max_triangles: int = DEFAULT_TRIANGLE_BUDGET,
    name: str = "shaft",
) -> Mesh:
    """Build the fluted shaft as a triangle mesh with crisp fillet edges.

    Parameters
    ----------
    p : ShaftParams (defaults to the Portunus shaft)
    cap_bottom, cap_top : close the shaft with flat caps (off where base/capital join)
    y_offset : lift the shaft (m), e.g. by the base height
    max_triangles : refuse a level of detail above this many triangles (BudgetError)

    Returns
    -------
    Mesh with indexed normals (``normals.indices``): smooth inside each flute
    and over fillets and rings, crisp at every flute/fillet edge and at the caps; and analytic
    ``st`` in metres of surface (the unrolled side, seam on the fillet at +X, and two flat
    caps; see :func:`ionic_usd.column.shaft_surface.shaft_st`), indexed by the generator
    itself (``st.distinct``: authoring writes it without de-duplicating), which
    :func:`ionic_usd.texture.uv.unwrap` packs without xatlas.
    """
    p = p or ShaftParams()
    _check_budget(p, int(cap_bottom) + int(cap_top), max_triangles)
    e, n = p.flutes, p.fluted_segments
    ys, ks = _row_layout(p)
    fl_pts, fl_ang = _fluted_rows(p, ys, ks)
    nrows = len(ys)
    ring_rows = _plain_rows(p, fl_ang)
    starts = np.concatenate([[0], np.cumsum([len(x) for x in ring_rows])])
    base_fl = int(starts[-1])
    points = np.concatenate(
        ring_rows + [fl_pts.reshape(-1, 3), np.array([[0.0, 0.0, 0.0], [0.0, p.length, 0.0]])]
    )
    c_bot, c_top = base_fl + nrows * n, base_fl + nrows * n + 1
    plain = [np.arange(starts[k], starts[k + 1]) for k in range(4)]
    grid_tri, grid_nrm, grid_nidx = _fluted_grid(p, fl_pts, base_fl, nrows)
    # groups: 0 = fillets and plain rings (one smooth cylinder), 1..e = flutes, e+1/e+2 caps
    tris, groups = _band_triangles(p, fl_ang, plain, starts, base_fl, nrows)
    n_lateral = len(grid_tri) + sum(len(t) for t in tris)
    _add_caps(tris, groups, plain, (c_bot, c_top), e, cap_bottom, cap_top)
    rest = np.concatenate(tris)
    # the bands and caps touch few points: compute their normals on a compact copy
    used, local = np.unique(rest, return_inverse=True)
    rest_mesh = Mesh(points[used], np.full(len(rest), 3, np.int32), local.reshape(-1))
    rest_mesh = smooth_normals(rest_mesh, np.concatenate(groups), indexed=True)
    tri = np.concatenate([grid_tri, rest.astype(np.int32)])
    st, st_idx = shaft_st(
        points, tri, n_lateral, len(grid_tri), e, p.flute_slices, _reference_perimeter(p), starts
    )
    assert rest_mesh.normals is not None and rest_mesh.normals.indices is not None
    normals = np.concatenate([grid_nrm, rest_mesh.normals.values])
    nidx = np.concatenate([grid_nidx, rest_mesh.normals.indices + len(grid_nrm)])
    # drop points no triangle uses (cap centres of an open shaft, collapsed ring rows)
    keep = _used_points(len(points), p, plain, (c_bot, c_top), cap_bottom, cap_top)
    if not keep.all():
        points, tri, st, st_idx = _drop_unused(points, tri, st, st_idx, keep, c_bot, n_lateral)
    if y_offset:
        points = points + np.array([0.0, y_offset, 0.0])
    return Mesh(
        points,
        np.full(len(tri), 3, np.int32),
        tri.reshape(-1),
        CornerValues(normals, nidx),
        CornerValues(st, st_idx, distinct=True),
        name=name,
    )


def _check_budget(p: ShaftParams, caps: int, max_triangles: int) -> None:
    """Refuse (BudgetError) a level of detail whose estimated triangles exceed the budget."""
    est = shaft_triangle_estimate(p, caps=caps)
    if est > max_triangles:
        raise BudgetError(
            f"shaft: this level of detail needs about {est:,} triangles, above the budget of "
            f"{max_triangles:,} (lower flute_slices $h or raise max_triangles)"
        )


def _add_caps(
    tris: list[np.ndarray],
    groups: list[np.ndarray],
    plain: list[np.ndarray],
    centres: tuple[int, int],
    e: int,
    cap_bottom: bool,
    cap_top: bool,
) -> None:
    """Append the flat caps (fans from the centre points; smoothing groups e+1 and e+2)."""
    if cap_bottom:
        t = stitch(plain[0], np.array([centres[0]]), is_closed=True, direction=-1)
        tris.append(t)
        groups.append(np.full(len(t), e + 1))
    if cap_top:
        t = stitch(plain[3], np.array([centres[1]]), is_closed=True)
        tris.append(t)
        groups.append(np.full(len(t), e + 2))


def _used_points(
    n_points: int,
    p: ShaftParams,
    plain: list[np.ndarray],
    centres: tuple[int, int],
    cap_bottom: bool,
    cap_top: bool,
) -> np.ndarray:
    """Mask of the points a triangle uses (no cap centre of an open end, no collapsed ring)."""
    keep = np.ones(n_points, dtype=bool)
    keep[list(centres)] = [cap_bottom, cap_top]
    if p.ring_bottom == 0:
        keep[plain[1]] = False
    if p.ring_top == 0:
        keep[plain[2]] = False
    return keep


def _plain_rows(p: ShaftParams, fl_ang: np.ndarray) -> list[np.ndarray]:
    """The four plain rows: the bottom and top rings (``ring_segments`` vertices, vertex 0
    at +X) and, where a plain ring has a height, its other row on the circle at the angles of
    the adjacent fluted row, so the flute ends meet the ring in regular quads (a stitched fan
    from the coarse ring into a narrow flute tip folds against the spoon's normals) and the
    stitch between different vertex counts lies on the plain cylinder."""
    ring_ang = np.arange(p.ring_segments) * (2 * np.pi / p.ring_segments)
    rows_ang = [ring_ang, fl_ang[0], fl_ang[-1], ring_ang]
    ring_ys = [0.0, p.ring_bottom, p.length - p.ring_top, p.length]
    rows = []
    for yv, ang in zip(ring_ys, rows_ang, strict=True):
        r = float(shaft_radius_at(p, np.array([yv]))[0])
        rows.append(np.stack([r * np.cos(ang), np.full(len(ang), yv), -r * np.sin(ang)], axis=1))
    return rows


def _fluted_grid(
    p: ShaftParams, fl_pts: np.ndarray, base_fl: int, nrows: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The fluted bands: regular quads split along the rising diagonal, and their normals
    from the grid directly (dense arrays, no scatter; the rest of the mesh uses
    smooth_normals): triangles (t, 3), normal values and their faceVarying indices."""
    n, h, nf = p.fluted_segments, p.flute_slices, p.fillet_slices
    if nrows <= 1:
        return (
            np.zeros((0, 3), dtype=np.int64),
            np.zeros((0, 3), dtype=np.float32),
            np.zeros(0, dtype=np.int32),
        )
    r0 = (base_fl + np.arange(nrows - 1)[:, None] * n).astype(np.int32)
    j = np.arange(n, dtype=np.int32)[None, :]
    a0, a1 = r0 + j, r0 + (j + 1) % n
    b0, b1 = a0 + n, a1 + n
    grid_tri = np.stack([a0, a1, b0, a1, b1, b0], axis=-1).reshape(-1, 3)
    col = np.arange(n) % (h + nf)
    grid_nrm, grid_nidx = grid_normals(fl_pts.reshape(nrows, n, 3), col, h)
    return grid_tri, grid_nrm, grid_nidx


def _band_triangles(
    p: ShaftParams,
    fl_ang: np.ndarray,
    plain: list[np.ndarray],
    starts: np.ndarray,
    base_fl: int,
    nrows: int,
) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """The bands between the plain rows and the fluted grid (stitched where the vertex
    counts differ) and each triangle's smoothing group: 0 (the plain cylinder) or 1 + the
    flute whose spoon end it continues (a triangle touching a flute's interior vertex)."""
    n, h, nf = p.fluted_segments, p.flute_slices, p.fillet_slices
    col = np.arange(n) % (h + nf)
    flute_of_col = np.arange(n) // (h + nf)
    ring_ang = np.arange(p.ring_segments) * (2 * np.pi / p.ring_segments)
    u_ring = ring_ang / (2 * np.pi)
    u_bot, u_top = fl_ang[0] / (2 * np.pi), fl_ang[-1] / (2 * np.pi)
    first_fl = base_fl + np.arange(n)
    last_fl = base_fl + (nrows - 1) * n + np.arange(n)
    quads = np.full(n, 2, dtype=np.int64)  # equal rows: one quad per column
    bands = []
    if p.ring_bottom > 0:
        bands += [
            (plain[0], plain[1], auto_sequence(u_ring, u_bot, True)),
            (plain[1], first_fl, quads),
        ]
    else:
        bands.append((plain[0], first_fl, auto_sequence(u_ring, u_bot, True)))
    if p.ring_top > 0:
        bands += [
            (last_fl, plain[2], quads),
            (plain[2], plain[3], auto_sequence(u_top, u_ring, True)),
        ]
    else:
        bands.append((last_fl, plain[3], auto_sequence(u_top, u_ring, True)))
    interior = (col > 0) & (col < h)
    tris, groups = [], []
    for lo, hi, seq in bands:
        t = stitch(lo, hi, is_closed=True, sequence=seq)
        fl_col = np.where(t >= base_fl, (t - base_fl) % n, -1)
        for k in (1, 2):  # the plain rows at the flute angles carry the flute columns too
            on = (t >= starts[k]) & (t < starts[k + 1])
            fl_col = np.where(on, t - starts[k], fl_col)
        touch = np.where(fl_col >= 0, interior[np.maximum(fl_col, 0)], False)
        g = np.zeros(len(t), dtype=np.int64)
        hit = touch.any(axis=1)
        which = np.argmax(touch, axis=1)
        g[hit] = 1 + flute_of_col[fl_col[hit, which[hit]]]
        tris.append(t)
        groups.append(g)
    return tris, groups


def _drop_unused(points, tri, st, st_idx, keep, c_bot: int, n_lateral: int):
    """Drop the points ``keep`` leaves out (cap centres of an open shaft, collapsed ring
    rows), renumbering the triangles and, for dropped side rows, the ``st`` values too."""
    remap = (np.cumsum(keep) - 1).astype(np.int32)
    if keep[:c_bot].all():  # only cap centres (the last points): renumber the caps only
        tri[n_lateral:] = remap[tri[n_lateral:]]
    else:
        tri = remap[tri]
        # the side values of the dropped rows are unused: drop them too (st.distinct)
        keep_st = np.ones(len(st), dtype=bool)
        keep_st[:c_bot] = keep[:c_bot]
        st_idx = (np.cumsum(keep_st, dtype=np.int32) - 1)[st_idx]
        st = st[keep_st]
    return points[keep], tri, st, st_idx


def _reference_perimeter(p: ShaftParams) -> float:
    """Length of the full-flute cross-section at the mean radius (the side chart's width)."""
    r_mid = 0.5 * (p.bottom_radius + p.top_radius)
    ref, _ = _fluted_rows(
        ShaftParams(**{**p.to_dict(), "entasis": 0.0, "bottom_radius": r_mid, "top_radius": r_mid}),
        np.array([0.5 * p.length]),
        np.ones(1),
    )
    return float(np.linalg.norm(np.diff(np.vstack([ref[0], ref[0, :1]]), axis=0), axis=1).sum())


def shaft_silhouette(p: ShaftParams, samples: int = 200) -> np.ndarray:
    """(samples, 2) float: the shaft's outline (radius of the fillet surface, y) bottom to top."""
    ys = np.linspace(0.0, p.length, samples)
    return np.stack([shaft_radius_at(p, ys), ys], axis=1)


def shaft_cross_section(p: ShaftParams, y: float) -> np.ndarray:
    """(N, 2) float: the closed cross-section polygon (x, −z) at height ``y`` (m).

    At heights inside the fluted body or the flute ends the flutes are included (scaled as in
    the mesh); in the plain rings it is the circle at the plain-ring resolution.
    """
    ys, ks = _row_layout(p)
    y = float(y)
    if y < ys[0] or y > ys[-1]:
        r = float(shaft_radius_at(p, np.array([y]))[0])
        ang = np.arange(p.ring_segments) * (2 * np.pi / p.ring_segments)
        return np.stack([r * np.cos(ang), r * np.sin(ang)], axis=1)
    k = float(np.interp(y, ys, ks))
    pts, _ = _fluted_rows(p, np.array([y]), np.array([k]))
    return np.stack([pts[0, :, 0], -pts[0, :, 2]], axis=1)
