"""Sections of the model: the generated curves that evaluation compares with references.

Every function returns a polyline ``(n, 2)`` in metres. Frames (column coordinates: Y up, the
column axis is +Y through the origin, y = 0 at the bottom of the base):

* **base** — the half-profile in the plane z = 0 through +X, as ``(r, y)``: from the outer
  corner at the bottom up to the first node at the base's top height (the bottom disc, the top
  disc and anything on the axis are left out). With a square plinth the plinth's side is part of
  the profile (the section plane z = 0 meets the plinth face at right angles).
* **shaft silhouette** — ``(r, y)`` in the same plane, the radius of the fillet surface (flutes
  are centred off angle 0, so the plane z = 0 runs along a fillet), from the axis at the shaft's
  bottom out to the bottom radius, up the outline and back in to the axis at the top (the
  "ends"); ``ends=False`` keeps only the outline.
* **shaft cross-section** — the closed polygon ``(x, −z)`` at a column height y (first node
  repeated at the end), as :func:`ionic_usd.column.shaft.shaft_cross_section`.
* **volute** — the outer edge of the front-right volute's spiral band, on the front face, as
  ``(x, y)`` in column coordinates (``frame="column"``), or relative to the spiral's origin
  (``frame="volute"``, exactly :func:`~ionic_usd.column.volute.volute_curve`). The curve runs
  from the start angle to the circuit limit (θ increasing; with the defaults from the eye
  outward) and leaves out the straight spiral margin.

The same curves are cut from USD files written by this project (``ionic-usd column`` or
``ionic-usd asset``) by :func:`section_from_usd`: the composed stage's active meshes of the
part are sliced with a plane (vectorised triangle/plane intersection), the segments chained
into loops through the mesh edges they cross (exact topology, no coordinate snapping), the
loops united (shapely) and the outer boundary kept.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from pathlib import Path

import numpy as np

from ionic_usd.column.base import base_profile
from ionic_usd.column.capital import capital_layout
from ionic_usd.column.column import ColumnParams
from ionic_usd.column.shaft import shaft_cross_section, shaft_radius_at
from ionic_usd.column.volute import volute_curve
from ionic_usd.errors import GeometryError, ParameterError
from ionic_usd.lod import LOD_NAMES

__all__ = [
    "PARTS",
    "base_section",
    "shaft_silhouette_section",
    "shaft_cross_section_at",
    "volute_section",
    "slice_mesh",
    "section_from_usd",
    "usd_part_triangles",
    "pick_band",
]

#: Part names accepted by :func:`section_from_usd` and the ``evaluate`` command.
PARTS = ("base", "shaft", "volute")

# Prim names of each part: ``ionic-usd column`` writes /Column/Geom/<Name>; the asset writes
# /IonicColumn/Geom/<Name>/<variant mesh>.
_PART_PRIMS = {"base": "Base", "shaft": "Shaft", "volute": "CapitalBody"}


# -- from parameters ---------------------------------------------------------------------------
def _strip_profile_ends(prof: np.ndarray, tol: float) -> np.ndarray:
    """Drop nodes on the axis and horizontal runs at the very bottom and top."""
    p = prof[prof[:, 0] > tol]
    y0, y1 = p[:, 1].min(), p[:, 1].max()
    start = 0
    while start < len(p) - 2 and abs(p[start + 1, 1] - y0) <= tol and abs(p[start, 1] - y0) <= tol:
        start += 1
    end = len(p)
    while end - start > 2 and abs(p[end - 1, 1] - y1) <= tol and abs(p[end - 2, 1] - y1) <= tol:
        end -= 1
    return p[start:end]


def base_section(params: ColumnParams, *, base: str | None = None) -> np.ndarray:
    """The base's half-profile ``(r, y)`` (module docstring), bottom to top.

    Parameters
    ----------
    params : ColumnParams
        Its LOD sets the profile sampling, as in the built column.
    base : str, optional
        Another base preset or grammar than ``params.base``.

    Returns
    -------
    (n, 2) float
        Metres; r from the axis, y from the base's bottom.
    """
    bp = params.base_params(base)
    prof = base_profile(bp, closed=True)
    return _strip_profile_ends(prof, 1e-9 * (1.0 + bp.height))


def shaft_silhouette_section(
    params: ColumnParams, *, samples: int = 401, ends: bool = True
) -> np.ndarray:
    """The shaft's outline ``(r, y)`` in column coordinates, bottom to top (module docstring).

    Parameters
    ----------
    params : ColumnParams
    samples : int
        Nodes along the outline (>= 2); the taper is linear, the entasis a sine.
    ends : bool
        Start and end on the axis (the bottom and top circles seen edge-on).

    Returns
    -------
    (samples [+ 2], 2) float
    """
    if not isinstance(samples, int) or samples < 2:
        raise ParameterError("samples", samples, "an integer >= 2", context="shaft section")
    sp = params.shaft_params()
    y0 = params.base_params().height
    ys = np.linspace(0.0, sp.length, samples)
    out = np.column_stack([shaft_radius_at(sp, ys), ys + y0])
    if ends:
        out = np.vstack([[0.0, y0], out, [0.0, y0 + sp.length]])
    return out


def shaft_cross_section_at(params: ColumnParams, y: float) -> np.ndarray:
    """Closed cross-section polygon ``(x, −z)`` of the shaft at column height ``y`` (m).

    Returns
    -------
    (n + 1, 2) float
        The first node repeated at the end.
    """
    sp = params.shaft_params()
    y0 = params.base_params().height
    if not (math.isfinite(y) and y0 <= y <= y0 + sp.length):
        raise ParameterError(
            "y",
            y,
            f"a height within the shaft [{y0:g}, {y0 + sp.length:g}] m",
            context="shaft section",
        )
    poly = shaft_cross_section(sp, y - y0)
    return np.vstack([poly, poly[:1]])


def _volute_origin(params: ColumnParams) -> np.ndarray:
    """Column (x, y) of the front-right volute's spiral origin."""
    cap = params.capital_params()
    lay = capital_layout(cap)
    y_cap = params.base_params().height + params.shaft.length + cap.capital_position_y
    return np.array([lay.eye_x, y_cap + lay.eye_y]) - cap.volute.eye_center


def volute_section(
    params: ColumnParams, *, frame: str = "column", samples: int | None = None
) -> np.ndarray:
    """Outer edge of the front-right volute's spiral on the front face (module docstring).

    Parameters
    ----------
    params : ColumnParams
    frame : ``"column"`` (x, y in column coordinates) or ``"volute"`` (relative to the
        spiral's origin, as :func:`~ionic_usd.column.volute.volute_curve`)
    samples : int, optional
        Nodes along θ; default the LOD's spiral samples (as in the built capital).

    Returns
    -------
    (samples, 2) float
    """
    if frame not in ("column", "volute"):
        raise ParameterError("frame", frame, "column or volute", context="volute section")
    cap = params.capital_params()
    curve = volute_curve(cap.volute, samples or cap.spiral_samples)
    if frame == "volute":
        return curve
    return curve + _volute_origin(params)


# -- slicing meshes ------------------------------------------------------------------------------
def slice_mesh(
    points: np.ndarray, triangles: np.ndarray, origin: np.ndarray, normal: np.ndarray
) -> list[np.ndarray]:
    """Cut a triangle mesh with a plane; chain the cut into polylines.

    A vertex exactly on the plane counts as lying on its positive side (a symbolic shift of
    the plane), so every crossing triangle has exactly two crossing edges and shared edges give
    identical points: the chains follow the mesh's edges, and a closed manifold gives closed
    loops.

    Parameters
    ----------
    points : (n, 3) float
    triangles : (t, 3) int
    origin, normal : (3,) float
        A point of the plane and its normal (any length > 0).

    Returns
    -------
    list of (k, 3) float
        One polyline per connected chain; a closed loop repeats its first node at the end.
        Consecutive duplicate nodes are removed.
    """
    pts = np.asarray(points, dtype=np.float64)
    tri = np.asarray(triangles, dtype=np.int64).reshape(-1, 3)
    nrm = np.asarray(normal, dtype=np.float64)
    if not np.linalg.norm(nrm) > 0:
        raise ParameterError("normal", normal, "a non-zero vector", context="slice")
    dist = (pts - np.asarray(origin, dtype=np.float64)) @ nrm
    pos = dist >= 0.0
    side = pos[tri]
    crossing = side.any(axis=1) & ~side.all(axis=1)
    tri = tri[crossing]
    if len(tri) == 0:
        return []
    # the two crossing edges of each triangle (each edge as a sorted vertex pair)
    e = np.stack([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]], axis=1)  # (t, 3, 2)
    cut = pos[e[..., 0]] != pos[e[..., 1]]  # (t, 3), two True per row
    pairs = e[cut].reshape(-1, 2, 2)  # (t, 2 edges, 2 vertices)
    pairs = np.sort(pairs, axis=2)
    flat = pairs.reshape(-1, 2)
    keys, inv = np.unique(flat[:, 0] * (len(pts) + 1) + flat[:, 1], return_inverse=True)
    inv = inv.reshape(-1, 2)
    a, b = keys // (len(pts) + 1), keys % (len(pts) + 1)
    t = dist[a] / (dist[a] - dist[b])
    cross_pts = pts[a] + t[:, None] * (pts[b] - pts[a])
    # chain: every cut edge joins the (usually two) triangles that cross it
    nbrs: dict[int, list[int]] = {}
    for u, v in inv.tolist():
        if u == v:
            continue
        nbrs.setdefault(u, []).append(v)
        nbrs.setdefault(v, []).append(u)
    seen_edges: set[tuple[int, int]] = set()
    chains: list[list[int]] = []
    # open chains start at nodes of odd degree, then the remaining loops
    starts = [n for n, lst in nbrs.items() if len(lst) % 2 == 1] + list(nbrs)
    for s in starts:
        while True:
            nxt = next((w for w in nbrs[s] if (min(s, w), max(s, w)) not in seen_edges), None)
            if nxt is None:
                break
            chain = [s]
            cur = s
            while nxt is not None:
                seen_edges.add((min(cur, nxt), max(cur, nxt)))
                chain.append(nxt)
                cur = nxt
                nxt = next(
                    (w for w in nbrs[cur] if (min(cur, w), max(cur, w)) not in seen_edges), None
                )
            chains.append(chain)
    out = []
    for chain in chains:
        c = cross_pts[np.asarray(chain)]
        keep = np.concatenate([[True], np.any(np.diff(c, axis=0) != 0.0, axis=1)])
        c = c[keep]
        if len(c) >= 2:
            out.append(c)
    return out


# -- USD ----------------------------------------------------------------------------------------
def usd_part_triangles(
    path: str | Path, part: str, *, variants: Mapping[str, str] | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """World-space triangles (metres) of a part's active meshes in a composed USD stage.

    See :func:`ionic_usd.usd.sections_reader.part_triangles` (pxr lives under ``usd/``).

    Returns
    -------
    points : (n, 3) float
    triangles : (t, 3) int
    """
    from ionic_usd.usd.sections_reader import part_triangles

    if part not in PARTS:
        raise ParameterError("part", part, f"one of {', '.join(PARTS)}")
    return part_triangles(path, _PART_PRIMS[part], variants=variants)


def _outline(loops2d: list[np.ndarray]):
    """Union of the closed loops as one shapely (Multi)Polygon."""
    from shapely import Polygon, make_valid
    from shapely.ops import unary_union

    polys = []
    for c in loops2d:
        if len(c) >= 4 and np.allclose(c[0], c[-1]):
            p = Polygon(c)
            if not p.is_valid:
                p = make_valid(p)
            if p.area > 0:
                polys.append(p)
    if not polys:
        raise GeometryError("the section has no closed outline")
    return unary_union(polys)


def _half_outline(loops2d: list[np.ndarray]) -> np.ndarray:
    """Outer boundary of the section with x >= 0, from the axis at the bottom to the top."""
    from shapely import LineString, box
    from shapely.ops import linemerge

    shape = _outline(loops2d)
    geoms = getattr(shape, "geoms", [shape])
    poly = max(geoms, key=lambda g: g.area)
    ring = np.asarray(poly.exterior.coords)
    lo, hi = ring.min(axis=0), ring.max(axis=0)
    pad = 1.0 + float(np.abs(ring).max())
    half = LineString(ring).intersection(box(0.0, lo[1] - pad, hi[0] + pad, hi[1] + pad))
    if half.geom_type == "MultiLineString":
        half = linemerge(half)
    if half.geom_type == "MultiLineString":  # the ring's seam splits it: join the longest parts
        parts = sorted(half.geoms, key=lambda g: g.length, reverse=True)
        half = linemerge(parts)
        if half.geom_type == "MultiLineString":
            half = parts[0]
    out = np.asarray(half.coords)
    if out[0, 1] > out[-1, 1]:
        out = out[::-1]
    return out


def _radial_envelope(points: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """Side outline ``(r, y)`` of a solid of (near) revolution: the largest vertex radius at
    every vertex height, bottom to top, closed to the axis at both ends.

    Used for the shaft instead of the plane cut: the ring-stitching triangles between a plain
    ring and the first fluted row dip a few millimetres below the fillet at angle 0, which a
    cut would see but the silhouette (the outline of the side view) does not.
    """
    used = points[np.unique(triangles)]
    r = np.hypot(used[:, 0], used[:, 2])
    scale = 1.0 + float(np.abs(used).max())
    ykey = np.round(used[:, 1] / (1e-7 * scale)).astype(np.int64)
    levels, inv = np.unique(ykey, return_inverse=True)
    rmax = np.zeros(len(levels))
    np.maximum.at(rmax, inv, r)
    ys = np.zeros(len(levels))
    np.add.at(ys, inv, used[:, 1])
    ys /= np.bincount(inv)
    out = np.column_stack([rmax, ys])
    out = out[out[:, 0] > 1e-7 * scale]
    return np.vstack([[0.0, ys[0]], out, [0.0, ys[-1]]])


def _outer_chain(loop: np.ndarray) -> np.ndarray:
    """Outer edge of a spiral band's closed outline (see :func:`section_from_usd`)."""
    c = loop[:-1] if np.allclose(loop[0], loop[-1]) else loop
    d = np.diff(np.vstack([c[-1:], c, c[:1]]), axis=0)
    ang_in, ang_out = np.arctan2(d[:-1, 1], d[:-1, 0]), np.arctan2(d[1:, 1], d[1:, 0])
    turn = np.abs((ang_out - ang_in + np.pi) % (2 * np.pi) - np.pi)
    corners = np.sort(np.argsort(turn)[-4:])
    # the four band corners cut the loop into two long edges and two short end walls
    pieces = []
    for k in range(4):
        i, j = corners[k], corners[(k + 1) % 4]
        idx = (
            np.arange(i, j + 1)
            if j > i
            else np.concatenate([np.arange(i, len(c)), np.arange(0, j + 1)])
        )
        seg = c[idx]
        pieces.append((float(np.linalg.norm(np.diff(seg, axis=0), axis=1).sum()), seg))
    outer = max(pieces, key=lambda p: p[0])[1]
    centre = outer.mean(axis=0)
    if np.linalg.norm(outer[0] - centre) > np.linalg.norm(outer[-1] - centre):
        outer = outer[::-1]  # start at the eye end, as θ runs
    # drop the straight spiral margin: the trailing straight run, if much longer than a sample
    seg = np.diff(outer, axis=0)
    length = np.linalg.norm(seg, axis=1)
    unit = seg / np.maximum(length, 1e-300)[:, None]
    k = len(seg) - 1
    run = length[k]
    while k > 0 and float(unit[k - 1] @ unit[-1]) > 1.0 - 1e-8:
        k -= 1
        run += length[k]
    if len(seg) > 4 and run > 3.0 * float(np.median(length[:k])):
        outer = outer[: k + 1]
    return outer


def _volute_plane_z(points: np.ndarray, params: ColumnParams | None) -> float:
    """z of the plane through the middle of the front-right volute's band."""
    if params is not None:
        cap = params.capital_params()
        return capital_layout(cap).face_z - 0.5 * cap.relief_depth
    # the band and eye prisms put most vertices on the two planes of the relief; take the two
    # most populated z levels on the front-right quarter and cut between them
    z = np.round(points[(points[:, 0] > 0) & (points[:, 2] > 0), 2], 6)
    levels, counts = np.unique(z, return_counts=True)
    if len(levels) < 2:
        raise GeometryError("cannot find the volute's front face in the capital mesh")
    top2 = levels[np.argsort(counts)[-2:]]
    return float(top2.mean())


def _params_from_stage(path: Path) -> ColumnParams | None:
    """ColumnParams from an asset's root customData (``ionic-usd asset`` stores them)."""
    from ionic_usd.column.column import column_params_from_mapping
    from ionic_usd.usd.sections_reader import stored_tables

    tables = stored_tables(path, ("column", "shaft", "capital", "volute"))
    if not tables:
        return None
    try:
        return column_params_from_mapping(tables, context=f"{path} customData")
    except Exception:  # noqa: BLE001 - metadata from another version: fall back to geometry
        return None


def section_from_usd(
    path: str | Path,
    part: str = "base",
    *,
    y: float | None = None,
    variants: Mapping[str, str] | None = None,
    params: ColumnParams | None = None,
    plane_z: float | None = None,
) -> np.ndarray:
    """Cut a part's section from a USD file written by this project.

    Frames as in the module docstring; the stage is composed (variant selections, payloads)
    and only active meshes count.

    * ``base`` — plane z = 0; the outer boundary of the section with x >= 0, bottom to top,
      without the caps' horizontal runs (as :func:`base_section`).
    * ``shaft`` — with ``y`` None: the side outline ``(r, y)``, the largest vertex radius at
      each row height, from the axis at the bottom to the axis at the top (as
      :func:`shaft_silhouette_section`; a plane cut would also see the stitching triangles
      at the flute ends dip ~3 mm under the fillet); with ``y``:
      the cross-section ``(x, −z)`` at that height, closed (the longest loop).
    * ``volute`` — plane z through the middle of the front-right band's relief (from
      ``params``, else from the asset's stored parameters, else from the mesh: the two most
      populated z levels at x, z > 0; ``plane_z`` overrides); of the loops with x > 0 the one
      with the most nodes is the band's outline, whose four sharpest corners split it into the
      outer and inner edges and the two end walls; the longer edge is the outer one. The
      trailing straight run (the spiral margin) is dropped when it is longer than three median
      segments. Oriented from the eye end.

    Returns
    -------
    (n, 2) float
        Metres.
    """
    path = Path(path)
    pts, tris = usd_part_triangles(path, part, variants=variants)
    if part == "shaft" and y is None:
        return _radial_envelope(pts, tris)
    if part == "base":
        loops = slice_mesh(pts, tris, np.zeros(3), np.array([0.0, 0.0, 1.0]))
        half = _half_outline([c[:, :2] for c in loops])
        scale = 1.0 + float(np.abs(half).max())
        return _strip_profile_ends(half, 1e-7 * scale)
    if part == "shaft" and y is not None:  # (y is None returned above)
        loops = slice_mesh(pts, tris, np.array([0.0, float(y), 0.0]), np.array([0.0, 1.0, 0.0]))
        closed = [c for c in loops if np.allclose(c[0], c[-1])]
        if not closed:
            raise GeometryError(f"{path}: the shaft has no closed cross-section at y = {y:g} m")
        best = max(closed, key=lambda c: float(np.linalg.norm(np.diff(c, axis=0), axis=1).sum()))
        return np.column_stack([best[:, 0], -best[:, 2]])
    if plane_z is None:
        if params is None:
            params = _params_from_stage(path)
            if params is not None and variants and variants.get("lod") in LOD_NAMES:
                params = params.with_lod(variants["lod"])  # the selected LOD's sampling
        plane_z = _volute_plane_z(pts, params)
    loops = slice_mesh(pts, tris, np.array([0.0, 0.0, plane_z]), np.array([0.0, 0.0, 1.0]))
    # a band on its own (it may touch x = 0 exactly: picked by length and side, not by a sign
    # test on its nodes); in a capital united into one solid the band joins its neighbours
    band = pick_band([c[:, :2] for c in loops if c[:, 0].min() >= -1e-9])
    eye = None
    if band is None:
        cands, eye = _united_band(loops, pts, params)
        band = max(cands, key=len) if cands else None
    if band is None:
        raise GeometryError(f"{path}: no volute band in the capital's section at z = {plane_z:g}")
    chain = _outer_chain(band)
    if eye is not None:  # start where the outer edge leaves the eye boss
        import shapely

        on_eye = shapely.distance(shapely.points(chain), shapely.LinearRing(eye)) < 1e-6
        k = 0
        while k + 1 < len(chain) and on_eye[k + 1]:
            k += 1
        chain = chain[k:]
    return chain


def _united_band(
    loops: list[np.ndarray], pts: np.ndarray, params: ColumnParams | None
) -> tuple[list[np.ndarray], np.ndarray | None]:
    """The front-right band's outline out of the section of a united capital.

    There the band's cut joins the abacus above it, the left volute's band (their margins
    meet at x = 0) and its eye boss: keep the part right of x = 0 below the abacus (found from
    the mesh: the top slab's corner edges), and take the eye's disc away when the parameters
    are known (without them the outline keeps a piece of the eye's arc).
    """
    import shapely

    top = pts[:, 1].max()
    on = pts[np.abs(pts[:, 1] - top) < 1e-6]
    hx, hz = np.abs(on[:, 0]).max(), np.abs(on[:, 2]).max()
    edge = pts[(np.abs(np.abs(pts[:, 0]) - hx) < 1e-6) & (np.abs(np.abs(pts[:, 2]) - hz) < 1e-6)]
    abacus = float(edge[:, 1].min()) if len(edge) else float(top)
    polys = [shapely.Polygon(c[:, :2]) for c in loops if np.allclose(c[0], c[-1]) and len(c) >= 4]
    if not polys:
        return [], None
    part = shapely.union_all(polys).intersection(shapely.box(0.0, -1e30, 1e30, abacus))
    eye = None
    if params is not None:
        cap = params.capital_params()
        from ionic_usd.column.volute import volute_eye

        # the eye boss as modelled: the eye's circle at the capital's ring segments
        eye = volute_eye(cap.volute, cap.ring_segments) + _volute_origin(params)
        part = part.difference(shapely.Polygon(eye))
    # float32 points: drop the µm jitter the clipping leaves on straight runs
    part = shapely.simplify(part, 1e-6)
    geoms = [g for g in getattr(part, "geoms", [part]) if g.geom_type == "Polygon"]
    if not geoms:
        return [], eye
    return [np.asarray(max(geoms, key=lambda g: g.area).exterior.coords)], eye


def pick_band(loops: list[np.ndarray]) -> np.ndarray | None:
    """The front-right volute band's outline among the section's loops.

    The band is the longest closed loop on the +x side (by its length-weighted centroid, not
    by a sign test on its nodes: a band may touch x = 0 exactly), with at least 8 nodes; the
    eye's circle and the canalis are shorter.

    Parameters
    ----------
    loops : list of (k, 2) float

    Returns
    -------
    (k, 2) float, or None when no loop qualifies
    """

    def length(c: np.ndarray) -> float:
        return float(np.linalg.norm(np.diff(c, axis=0), axis=1).sum())

    def centre_x(c: np.ndarray) -> float:
        seg = np.linalg.norm(np.diff(c, axis=0), axis=1)
        mid = 0.5 * (c[1:, 0] + c[:-1, 0])
        return float((mid * seg).sum() / max(seg.sum(), 1e-300))

    cands = [c for c in loops if len(c) >= 8 and np.allclose(c[0], c[-1]) and centre_x(c) > 0]
    return max(cands, key=length) if cands else None
