"""Lots → buildings, porticoes → columns: fitting, placement and LOD, as numpy arrays.

Frames: plan metres ``(e, n)`` (easting, northing) map to USD ``(x, z) = (e, −n)``, Y up. A
temple is authored in its own frame with the front towards ``+Z``; placing it is
``translate · rotateY(φ) · scale(s)`` with ``φ = 180° − azimuth`` (azimuth: the direction its
front faces, clockwise from north). Columns face the street they line.

Everything here is vectorised numpy (shapely for the lot polygons), so a million column
positions cost milliseconds and no per-instance Python object.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ionic_usd.city.plan import Lot, Porticus
from ionic_usd.errors import IonicError, ParameterError

__all__ = [
    "Footprint",
    "TempleFit",
    "fit_temple",
    "lot_azimuth",
    "lot_box",
    "porticus_columns",
    "extra_columns",
    "drop_inside",
    "lod_by_distance",
    "distance_from",
    "yaw_quaternions",
    "DEFAULT_INSTANCER_THRESHOLD",
]

# above this many temples the city uses a PointInstancer of temple prototypes instead of
# instanceable references. Measured (tools/bench_city.py): opening and counting a city of
# 2,500 temple references takes 2.9-3.8 s against 0.4-0.5 s as a PointInstancer, 10,000 take
# 12-18 s against 0.3-0.6 s (authoring 17 s against 0.8-2.5 s), on 2 busy cores: references
# grow ~1.5 ms each, so past a few hundred they cost more than the whole instancer; below,
# each temple stays a prim of its own
DEFAULT_INSTANCER_THRESHOLD = 500


@dataclass(frozen=True)
class Footprint:
    """A temple's plan box in its own frame (USD x, z; metres; front towards +z) and height."""

    x0: float
    x1: float
    z0: float
    z1: float
    height: float

    @property
    def width(self) -> float:
        return self.x1 - self.x0

    @property
    def length(self) -> float:
        return self.z1 - self.z0

    def corners(self) -> np.ndarray:
        """(4, 2) float — (x, z) corners, counter-clockwise seen from above."""
        return np.array(
            [[self.x0, self.z0], [self.x1, self.z0], [self.x1, self.z1], [self.x0, self.z1]]
        )


@dataclass(frozen=True)
class TempleFit:
    """Where a temple stands: USD translation (x, z), rotation about Y (degrees), scale."""

    x: float
    z: float
    yaw_deg: float
    scale: float

    def footprint_plan(self, fp: Footprint) -> np.ndarray:
        """(4, 2) float — the placed footprint's corners in plan metres (e, n)."""
        world = _rot(self.yaw_deg) @ (self.scale * fp.corners()).T
        return np.stack([world[0] + self.x, -(world[1] + self.z)], axis=1)


def _shapely():
    """shapely, or an error naming the extra that installs it."""
    try:
        import shapely
    except ImportError:
        raise IonicError("the city needs shapely: pip install 'ionic_usd[city]'") from None
    return shapely


def _rot(yaw_deg: float) -> np.ndarray:
    """(2, 2) rotation about +Y acting on (x, z) column vectors."""
    c, s = math.cos(math.radians(yaw_deg)), math.sin(math.radians(yaw_deg))
    return np.array([[c, s], [-s, c]])


def _azimuth(de: float, dn: float) -> float:
    return math.degrees(math.atan2(de, dn)) % 360.0


def fit_temple(
    lot: Lot,
    fp: Footprint,
    *,
    scale_range: tuple[float, float],
    toward: Sequence[float] | None = None,
) -> TempleFit:
    """Fit a temple's footprint inside a lot: rotated to the lot, uniformly scaled.

    The front faces ``lot.orientation`` or, when None, along the lot's long axis (of its
    minimum rotated rectangle) towards ``toward`` (plan point, e.g. the plan's centre). The
    scale is the largest in ``scale_range`` (or ``lot.scale``) whose footprint lies inside the
    lot (uniform: the description's proportions are kept); none → :class:`ParameterError`.

    Parameters
    ----------
    lot : the lot (its outline (n, 2) in plan metres)
    fp : the temple's footprint in its own frame
    scale_range : (min, max) uniform scale
    toward : (2,) plan point the front should face when the lot gives no orientation
    """
    shapely = _shapely()
    from shapely.ops import polylabel

    poly = shapely.Polygon(lot.outline)
    ctx = f"lot {lot.id}"
    if not poly.is_valid or poly.area <= 0:
        raise ParameterError(
            "outline", shapely.is_valid_reason(poly), "a simple polygon", context=ctx
        )
    smin, smax = lot.scale or scale_range
    az = lot_azimuth(lot, poly, toward)
    yaw = (180.0 - az) % 360.0
    R = _rot(yaw)
    world = np.stack([lot.outline[:, 0], -lot.outline[:, 1]])  # (2, n) USD x, z
    local = R.T @ world
    lo, hi = local.min(axis=1), local.max(axis=1)
    s = min(smax, (hi[0] - lo[0]) / fp.width, (hi[1] - lo[1]) / fp.length)
    fp_c = np.array([(fp.x0 + fp.x1) / 2, (fp.z0 + fp.z1) / 2])
    inside = _containment(poly, lot.outline)

    def centres():
        yield (lo + hi) / 2
        label = polylabel(poly, tolerance=0.05).coords[0]  # only when the box centre fails
        yield R.T @ np.array([label[0], -label[1]])

    def place(scale: float, c_local: np.ndarray) -> TempleFit | None:
        o = R @ (c_local - scale * fp_c)
        fit = TempleFit(float(o[0]), float(o[1]), yaw, float(scale))
        return fit if inside(fit.footprint_plan(fp)) else None

    if s >= smin:
        for c in centres():
            if (fit := place(s, c)) is not None:
                return fit
        lo_s, hi_s, best = smin, s, None
        for c in centres():
            if place(smin, c) is None:
                continue
            for _ in range(30):  # bisection on the scale: containment is monotone in s
                mid = (lo_s + hi_s) / 2
                if place(mid, c) is not None:
                    lo_s = mid
                else:
                    hi_s = mid
            best = place(lo_s, c)
            break
        if best is not None:
            return best
    raise ParameterError(
        "outline",
        f"{fp.width:.1f} × {fp.length:.1f} m temple",
        f"a lot that holds the temple at scale >= {smin:g} (facing "
        f"{az:.0f}°); enlarge the lot, lower its scale minimum or turn it",
        context=ctx,
    )


def lot_azimuth(lot: Lot, poly, toward: Sequence[float] | None) -> float:
    """The azimuth a temple on ``lot`` faces: ``lot.orientation``, or along the long axis of
    the lot's minimum rotated rectangle towards ``toward`` (plan point)."""
    shapely = _shapely()
    if lot.orientation is not None:
        return lot.orientation
    cen = np.array(poly.centroid.coords[0])
    rect = np.asarray(shapely.minimum_rotated_rectangle(poly).exterior.coords)[:4]
    e1, e2 = rect[1] - rect[0], rect[2] - rect[1]
    axis = e1 if np.hypot(*e1) >= np.hypot(*e2) else e2
    tgt = np.asarray(toward, dtype=float) if toward is not None else cen + axis
    if np.dot(axis, tgt - cen) < 0:
        axis = -axis
    return _azimuth(*axis)


def lot_box(lot: Lot, toward: Sequence[float] | None = None) -> tuple[float, float]:
    """(width, depth) in metres of the lot's box in the frame of the temple it holds (across
    and along the direction :func:`lot_azimuth` gives)."""
    shapely = _shapely()
    poly = shapely.Polygon(lot.outline)
    if not poly.is_valid or poly.area <= 0:
        raise ParameterError(
            "outline", shapely.is_valid_reason(poly), "a simple polygon", context=f"lot {lot.id}"
        )
    yaw = (180.0 - lot_azimuth(lot, poly, toward)) % 360.0
    local = _rot(yaw).T @ np.stack([lot.outline[:, 0], -lot.outline[:, 1]])
    span = local.max(axis=1) - local.min(axis=1)
    return float(span[0]), float(span[1])


def _containment(poly, ring: np.ndarray):
    """A test ``(4, 2) corners → bool``: is the quadrilateral inside the lot (1 mm slack)?
    Convex lots (the usual case) use half-planes in numpy; others shapely."""
    shapely = _shapely()
    if poly.convex_hull.area - poly.area <= 1e-9 * poly.area:
        pts = ring if shapely.is_ccw(shapely.LinearRing(ring)) else ring[::-1]
        edge = np.roll(pts, -1, axis=0) - pts
        length = np.hypot(edge[:, 0], edge[:, 1])
        keep = length > 1e-12
        pts, edge, length = pts[keep], edge[keep], length[keep]

        def convex(corners: np.ndarray) -> bool:
            rel = corners[:, None, :] - pts[None, :, :]
            cross = edge[None, :, 0] * rel[..., 1] - edge[None, :, 1] * rel[..., 0]
            return bool((cross / length >= -1e-3).all())

        return convex
    grown = poly.buffer(1e-3)

    def general(corners: np.ndarray) -> bool:
        return bool(grown.contains(shapely.Polygon(corners)))

    return general


def _sample_polyline(
    line: np.ndarray, spacing: float, closed: bool
) -> tuple[np.ndarray, np.ndarray]:
    """Points every ``spacing`` along a polyline (centred on an open line; evenly round a
    closed one) and the unit tangent there. Returns ((n, 2), (n, 2))."""
    pts = np.vstack([line, line[:1]]) if closed else line
    seg = np.diff(pts, axis=0)
    seglen = np.hypot(seg[:, 0], seg[:, 1])
    keep = seglen > 1e-12
    pts = np.vstack([pts[:1], pts[1:][keep]])
    seg, seglen = seg[keep], seglen[keep]
    cum = np.concatenate([[0.0], np.cumsum(seglen)])
    total = cum[-1]
    if total <= 0:
        return np.zeros((0, 2)), np.zeros((0, 2))
    if closed:
        n = max(1, int(total // spacing))
        d = np.arange(n) * (total / n)
    else:
        n = int(total / spacing + 1e-9) + 1
        d = np.arange(n) * spacing + (total - (n - 1) * spacing) / 2
    k = np.clip(np.searchsorted(cum, d, side="right") - 1, 0, len(seg) - 1)
    t = ((d - cum[k]) / seglen[k])[:, None]
    tangent = seg[k] / seglen[k][:, None]
    return pts[k] + t * seg[k], tangent


def porticus_columns(p: Porticus, spacing: float) -> tuple[np.ndarray, np.ndarray]:
    """Column axes of a colonnade: a column on every vertex of its line(s), each straight run
    divided into equal bays of about ``spacing`` (:func:`ionic_usd.city.stoa.porticus_stoa`).

    Returns
    -------
    xz : (n, 2) float — USD (x, z) of each column
    yaw : (n,) float — rotation about Y (degrees): each column faces the line it lines
    """
    from ionic_usd.city.stoa import porticus_stoa

    _shapely()
    lay = porticus_stoa(p, spacing)
    return lay.column_xz, lay.column_yaw


def extra_columns(
    count: int, bounds: tuple[float, float, float, float], spacing: float, pitch: float = 6.0
) -> tuple[np.ndarray, np.ndarray]:
    """``count`` more columns in colonnade rows south of the city (USD ``+z``), each row as
    wide as the city (at least 300 m), ``pitch`` m apart; the columns face south.

    bounds : (xmin, zmin, xmax, zmax) of the city in USD x, z. Returns ((count, 2), (count,)).
    """
    xmin, _, xmax, zmax = bounds
    width = max(xmax - xmin, 300.0)
    per_row = int(width // spacing) + 1
    i = np.arange(count, dtype=np.int64)
    xz = np.empty((count, 2))
    xz[:, 0] = xmin + (i % per_row) * spacing
    xz[:, 1] = zmax + pitch * (1 + i // per_row)
    return xz, np.zeros(count)


def drop_inside(
    xz: np.ndarray, footprints: Sequence[np.ndarray], margin: float = 1.0
) -> np.ndarray:
    """(n,) bool — which columns stand clear of every temple footprint (plan (m, 2) corner
    arrays, grown by ``margin`` m)."""
    if not footprints or len(xz) == 0:
        return np.ones(len(xz), dtype=bool)
    shapely = _shapely()
    tree = shapely.STRtree(
        [shapely.Polygon(f).buffer(margin, join_style="mitre") for f in footprints]
    )
    pts = shapely.points(xz[:, 0], -xz[:, 1])
    hit = tree.query(pts, predicate="intersects")[0]
    keep = np.ones(len(xz), dtype=bool)
    keep[hit] = False
    return keep


def lod_by_distance(
    xz: np.ndarray, focus: Sequence[float] | None, distances: tuple[float, float]
) -> np.ndarray:
    """(n,) int8 index into :data:`ionic_usd.lod.LOD_NAMES` (a level's rank): high within
    ``distances[0]`` m of the focus (plan (e, n)), medium within ``distances[1]``, low beyond;
    all high without a focus."""
    if focus is None:
        return np.zeros(len(xz), dtype=np.int8)
    d = distance_from(xz, focus)
    return (d > distances[0]).astype(np.int8) + (d > distances[1]).astype(np.int8)


def distance_from(xz: np.ndarray, focus: Sequence[float]) -> np.ndarray:
    """(n,) horizontal distances (m) of USD positions ``xz`` (n, 2) from a plan point
    ``focus`` (e, n) (USD z = −n)."""
    return np.hypot(xz[:, 0] - focus[0], xz[:, 1] + focus[1])


def yaw_quaternions(yaw_deg: np.ndarray) -> np.ndarray:
    """(n, 4) float16 — unit quaternions (i, j, k, real: Gf.Quath's memory order) of
    rotations about +Y."""
    half = np.radians(np.asarray(yaw_deg, dtype=np.float64)) / 2
    q = np.zeros((len(half), 4), dtype=np.float16)
    q[:, 1] = np.sin(half)
    q[:, 3] = np.cos(half)
    return q


def check_lots_apart(lots: Sequence[Lot], source: str) -> None:
    """Refuse two temple lots that overlap (their temples would interpenetrate).

    Lots that only touch (a shared edge, an overlap below 1e-6 of the smaller lot's area) are
    fine. An STRtree finds the candidate pairs, so a 10⁵-lot plan is checked in seconds.
    """
    shapely = _shapely()
    polys = [shapely.Polygon(lot.outline).buffer(0) for lot in lots]
    if len(polys) < 2:
        return
    tree = shapely.STRtree(polys)
    left, right = tree.query(polys, predicate="intersects")
    for i, j in zip(left.tolist(), right.tolist(), strict=True):
        if i >= j:
            continue
        shared = polys[i].intersection(polys[j]).area
        if shared > 1e-6 * min(polys[i].area, polys[j].area):
            raise ParameterError(
                "temple lots",
                f"{lots[i].id} and {lots[j].id}",
                f"lots that do not overlap (they share {shared:.3g} m²; their temples "
                "would interpenetrate: move or shrink one)",
                context=source,
            )
