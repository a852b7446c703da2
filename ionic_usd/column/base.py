"""The column base from the two shape grammars (paper section V; SPEC §2).

Units. The grammar's r and h are in scene units — metres — exactly as the paper has it ("r is
an addition to the bottom radius of the shaft ($d)"): the base is ``d + r`` wide, not ``d·r``.
Checked against Vitruvius (III.5.1–3: the Attic base is half the lower diameter high): G2 is
0.446 high, which on the Portunus shaft (d = 0.475 m, diameter 0.95 m) is 0.47·diameter;
reading the numbers as fractions of d would make it 0.22·diameter, far too low. ``scale``
(metres per grammar unit, default 1) resizes a preset for another column.

Profile. Modules stack upward from y = 0; within a module:

* v1 floor from (r_b, 0) to (r_t, h) with curvature c: a quarter ellipse with axis-parallel
  semi-axes |r_t − r_b| and h. Of the two such arcs, the convex one (c = 1) lies outside the
  chord (away from the axis) and has its vertical tangent at the outermost end; the concave one
  (c = −1) lies inside the chord with its vertical tangent at the innermost end, so two convex
  floors R a H h C1 R b H h C1 R a make a smooth half-ellipse torus and two concave ones a smooth
  scotia. Equal radii give a straight cylinder and h = 0 a flat annulus (2 rows each); other
  floors get ``profile_slices`` segments, uniform in the ellipse angle.
* v2 floor: the Bézier curve of the control points (d + r, y₀ + h) sampled at
  ``profile_slices`` + 1 uniform parameters; a 2-point module is a straight segment with
  exactly 2 rows. The module's top (next module's bottom) is its last control point's h.

Joints and normals. Normals are indexed per corner from
:func:`~ionic_usd.geometry.smooth_normals` with one smoothing group per module (the floors of a
v1 module are welded, as in the paper), so every joint between modules is a crisp edge. A v2
module flagged C1 drops its first row and its second row joins the previous module's last row;
it shares that module's smoothing group, so the joint is smooth. Coincident rows are always
merged (a mesh with one set of points, not stacked shells), so where a module starts where the
last ended the flag changes only the normals. Zero-thickness "fins" — a flat run that goes out
and comes back at one height — are dropped: each run of rows at one height keeps only its first
and last row.

Solid. A bottom disc (at the first row's height, y = 0 for all presets), the revolved outside,
and a flat top disc from the last row to the axis. With ``cap_top=False`` a flat annulus joins
the last row to radius d (outward and facing down if the last row is inside d) and
the mesh ends exactly at ``ring(d, height, segments)`` (vertex 0 at +X, increasing angle), the
shaft's bottom ring: ``weld(merge([base, shaft]))`` is one watertight solid when ``segments``
equals the shaft's ``ring_segments``.

Square plinth. ``plinth_modules = k`` replaces the bottom k modules by a square slab of the
same height whose half-side is their largest radius ``d + r``: a closed box shell, with the
revolved rest (its own bottom disc resting on the box top) as a second closed shell. Two
shells keep both simple and edge-closed; coplanar touching faces are harmless for rendering.
"""

from __future__ import annotations

import functools
import tomllib
from dataclasses import dataclass, field, fields
from importlib import resources

import numpy as np

from ionic_usd.checks import check_fields
from ionic_usd.column.charts import revolved_st
from ionic_usd.errors import GeometryError, GrammarError, ParameterError
from ionic_usd.geometry.curves import bezier, revolve
from ionic_usd.geometry.mesh import CornerValues, Mesh, box_st, face_normals, smooth_normals
from ionic_usd.grammar.base import (
    BaseGrammar,
    BezierBase,
    BezierModule,
    TorusBase,
    TorusFloor,
    TorusModule,
    parse_base_grammar,
)

__all__ = [
    "BaseParams",
    "BASE_PARAMETER_DOCS",
    "build_base",
    "base_profile",
    "base_height",
    "base_triangle_estimate",
    "torus_arc",
    "load_base_preset",
    "base_preset_names",
]

BASE_PARAMETER_DOCS: dict[str, tuple[str, str]] = {
    "grammar": ("text", "base grammar, v1 `R H C R` or v2 `R H R H [C1]` (or `M(...)`)"),
    "version": ("1|2", "grammar version; empty = detect"),
    "shaft_radius": ("m", "the shaft's bottom radius $d, to which every r is added"),
    "segments": ("count", "vertices per ring (use the shaft's ring_segments so rings match)"),
    "profile_slices": ("count", "segments per curved floor (LOD)"),
    "plinth_modules": ("count", "bottom modules replaced by a square plinth (0 = none)"),
    "scale": ("m/unit", "metres per grammar unit (1 = the grammar is in metres)"),
}

_BOTTOM, _TOP = -1, -2  # smoothing-group ids of the caps (modules use 0, 1, …)


def _default_grammar() -> str | TorusBase | BezierBase:
    return load_base_preset("G2").grammar


@dataclass(frozen=True)
class BaseParams:
    """Everything that defines a column base. Lengths in metres.

    ``grammar`` may be text or an already parsed :class:`~ionic_usd.grammar.TorusBase` /
    :class:`~ionic_usd.grammar.BezierBase`. Parsing happens here, so an invalid grammar — or a
    radius with d + r ≤ 0 (it would reach the axis) — raises a pointed GrammarError.
    """

    grammar: str | TorusBase | BezierBase = field(default_factory=_default_grammar)
    version: int | None = None
    shaft_radius: float = 0.475
    segments: int = 120
    profile_slices: int = 8
    plinth_modules: int = 0
    scale: float = 1.0
    _parsed: BaseGrammar = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        ctx = "base"
        check_fields(
            self,
            context=ctx,
            skip=("grammar", "version"),
            integers={"segments": 3, "profile_slices": 1, "plinth_modules": 0},
            positive=("shaft_radius", "scale"),
        )
        if self.version not in (None, 1, 2):
            raise ParameterError("version", self.version, "1, 2 or None (detect)", context=ctx)
        g = self.grammar
        if isinstance(g, str):
            g = _parse_grammar(g, self.version)
        elif isinstance(g, TorusBase | BezierBase):
            if self.version is not None and g.version != self.version:
                raise ParameterError(
                    "version", self.version, f"{g.version} (the grammar's)", context=ctx
                )
            g = g.located()
        else:
            raise ParameterError("grammar", g, "grammar text or a parsed base grammar", context=ctx)
        if self.plinth_modules >= len(g.modules):
            raise ParameterError(
                "plinth_modules",
                self.plinth_modules,
                f"fewer than the grammar's {len(g.modules)} modules",
                context=ctx,
            )
        _check_axis(g, self.shaft_radius, self.scale)
        object.__setattr__(self, "_parsed", g)

    @property
    def parsed(self) -> BaseGrammar:
        """The parsed grammar (with token offsets)."""
        return self._parsed

    @property
    def height(self) -> float:
        """Base height in metres (where the shaft starts)."""
        return base_height(self)

    def to_dict(self) -> dict:
        out = {f.name: getattr(self, f.name) for f in fields(self) if f.init}
        if not isinstance(out["grammar"], str):
            out["grammar"] = out["grammar"].to_string()
        if out["version"] is None:
            del out["version"]
        return out


def _check_axis(g: BaseGrammar, d: float, scale: float) -> None:
    """Every radius must keep d + r > 0: the Bézier curve stays in its control points' hull and
    an elliptic arc between its end radii, so checking the tokens suffices."""
    modules: tuple[TorusModule | BezierModule, ...] = g.modules
    for k, m in enumerate(modules, 1):
        if isinstance(m, TorusModule):
            items = [(f.r_bottom, f.r_bottom_at) for f in m.floors]
            items.append((m.floors[-1].r_top, m.floors[-1].r_top_at))
        else:
            items = [(p.r, p.r_at) for p in m.points]
        for r, (off, ln) in items:
            if d + scale * r <= 0:
                raise GrammarError(
                    f"radius {r:g} reaches the column axis: d + r = {d:g} + {scale * r:g} "
                    f"<= 0 (r must be > {-d / scale:g})",
                    g.source,
                    off,
                    length=ln,
                    module=k,
                    grammar=g.grammar_name,
                )


# -- curves ---------------------------------------------------------------------------------
def torus_arc(floor: TorusFloor, slices: int) -> np.ndarray:
    """Edge curve of a v1 floor, relative to its bottom: (r, h) from (r_b, 0) to (r_t, h).

    Returns
    -------
    (slices + 1, 2) float, or (2, 2) for a straight floor (equal radii or h = 0)
    """
    rb, rt, h = floor.r_bottom, floor.r_top, floor.height
    if h == 0 or rb == rt:
        return np.array([[rb, 0.0], [rt, h]])
    phi = 0.5 * np.pi * np.arange(slices + 1) / slices
    s, c = np.sin(phi), np.cos(phi)
    s[-1], c[-1] = 1.0, 0.0  # exact end points: the floors must hit their control values
    dr = rt - rb
    if floor.curvature * dr > 0:
        # centre (r_b, h): horizontal tangent at the bottom, vertical at the top
        return np.stack([rb + dr * s, h * (1.0 - c)], axis=1)
    # centre (r_t, 0): vertical tangent at the bottom, horizontal at the top
    return np.stack([rt - dr * c, h * s], axis=1)


def _module_curves(g: BaseGrammar, slices: int) -> list[tuple[np.ndarray, bool]]:
    """(nodes (n, 2) as (r, h) relative to d and the module bottom, joins_previous) each."""
    out = []
    modules: tuple[TorusModule | BezierModule, ...] = g.modules
    for k, m in enumerate(modules):
        if isinstance(m, TorusModule):
            arcs = [torus_arc(f, slices) for f in m.floors]
            nodes = np.concatenate(
                [arcs[0]]
                + [
                    a[1:] + [0.0, sum(f.height for f in m.floors[: i + 1])]
                    for i, a in enumerate(arcs[1:])
                ]
            )
            out.append((nodes, False))
        else:
            ctrl = np.array([[p.r, p.h] for p in m.points])
            n = 2 if len(ctrl) == 2 else slices + 1
            out.append((bezier(ctrl, np.linspace(0.0, 1.0, n)), m.continuous and k > 0))
    return out


@dataclass
class _Profile:
    nodes: list  # (r, y) tuples
    groups: list  # group of the segment ending at nodes[i], i ≥ 1 (groups[0] unused)


def _append(pr: _Profile, r: float, y: float, group: int, tol: float) -> None:
    """Add a node, merging coincident ones and collapsing flat runs to their two ends."""
    if pr.nodes:
        r0, y0 = pr.nodes[-1]
        if abs(y - y0) <= tol:
            y = y0  # snap: a flat run must be exactly flat for the collapse and the rings
            if len(pr.nodes) >= 2 and pr.nodes[-2][1] == y0:
                pr.nodes[-1] = (r, y)  # keep the group of the run's first segment
                r0, y0 = pr.nodes[-2]
                if abs(r - r0) <= tol:
                    pr.nodes.pop()
                    pr.groups.pop()
                return
        if abs(r - r0) <= tol and abs(y - y0) <= tol:
            return
    pr.nodes.append((r, y))
    pr.groups.append(group)


def _layout(p: BaseParams) -> tuple[np.ndarray, np.ndarray, float, float, float]:
    """The grammar's outside curve in metres and where the plinth ends.

    Returns
    -------
    outer : (n, 2) float (R, y) with R = d + scale·r, bottom to top (fins collapsed)
    seg_group : (n - 1,) int smoothing group of each segment
    plinth_half : half-side of the square plinth (0 without one)
    plinth_top : y of the plinth top (0 without one)
    tol : coincidence tolerance (m)
    """
    g, d, sc = p.parsed, p.shaft_radius, p.scale
    curves = _module_curves(g, p.profile_slices)
    tol = 1e-12 * (d + sc * max(1.0, g.height))
    pr = _Profile([], [])
    y0 = 0.0
    plinth_half = 0.0
    group = -1
    for k, (nodes, joins) in enumerate(curves):
        pts = np.column_stack([d + sc * nodes[:, 0], y0 + sc * nodes[:, 1]])
        top = y0 + sc * g.modules[k].height
        if k < p.plinth_modules:
            plinth_half = max(plinth_half, float(pts[:, 0].max()))
            y0 = top
            continue
        if joins and k > p.plinth_modules:
            pts = pts[1:]  # the C1 flag: the first row goes, the second joins the last one
        else:
            group += 1
            if pr.nodes:
                # the first segment of a crisp module is a joint (only non-empty when the
                # module does not start where the previous one ended): it is the module's
                _append(pr, float(pts[0, 0]), float(pts[0, 1]), group, tol)
                pts = pts[1:]
        for r, y in pts:
            _append(pr, float(r), float(y), group, tol)
        y0 = top
    outer = np.array(pr.nodes, dtype=np.float64).reshape(-1, 2)
    seg = np.array(pr.groups[1:], dtype=np.int64)
    plinth_top = sc * sum(m.height for m in g.modules[: p.plinth_modules])
    return outer, seg, plinth_half, plinth_top, tol


def _closed_profile(
    p: BaseParams, *, cap_bottom: bool, cap_top: bool
) -> tuple[np.ndarray, np.ndarray, float, float]:
    """The profile to revolve (axis → outside → top) and its segment groups."""
    outer, seg, half, ptop, tol = _layout(p)
    d = p.shaft_radius
    if p.plinth_modules:
        # a flat run on the plinth's top is the slab's own top face: start after it
        k = 0
        while k + 1 < len(outer) and outer[k + 1, 1] == outer[0, 1]:
            k += 1
        outer, seg = outer[k:], seg[k:]
    pr = _Profile([], [])
    if cap_bottom and not p.plinth_modules:
        pr.nodes.append((0.0, float(outer[0, 1])))
        pr.groups.append(_BOTTOM)
        _append(pr, float(outer[0, 0]), float(outer[0, 1]), _BOTTOM, tol)
    else:
        pr.nodes.append((float(outer[0, 0]), float(outer[0, 1])))
        pr.groups.append(_BOTTOM)
    for (r, y), gid in zip(outer[1:], seg, strict=True):
        _append(pr, float(r), float(y), int(gid), tol)
    h = float(outer[-1, 1])
    _append(pr, d, h, _TOP, tol)
    # the ring of radius d is kept even inside a flat top: it is the shaft's bottom ring, and
    # the disc inside it is exactly the shaft's bottom cap (remove both and they weld)
    last = len(pr.nodes) - 1
    if cap_top:
        pr.nodes.append((0.0, h))
        pr.groups.append(_TOP)
    nodes = np.array(pr.nodes, dtype=np.float64)
    nodes[last] = (d, h)
    return nodes, np.array(pr.groups[1:], dtype=np.int64), half, ptop


def base_height(p: BaseParams) -> float:
    """Height of the base (m): the y of the ring where the shaft starts."""
    return p.scale * p.parsed.height


def base_profile(p: BaseParams | None = None, *, closed: bool = False) -> np.ndarray:
    """The base's half-profile in the section plane through +X.

    Parameters
    ----------
    p : BaseParams (defaults to G2 on the Portunus shaft)
    closed : False → the grammar's outside curve from the bottom outer corner to the last
        row (with a plinth: its side and top, then the revolved rest); True → the whole
        section outline from the axis at the bottom to the axis at the top, as revolved.

    Returns
    -------
    (n, 2) float (r, y) in metres
    """
    p = p or BaseParams()
    if closed:
        nodes, _, half, ptop = _closed_profile(p, cap_bottom=True, cap_top=True)
        if p.plinth_modules:  # the slab's outline, then the revolved rest from its ring
            nodes = np.vstack([[[0.0, 0.0], [half, 0.0], [half, ptop]], nodes])
        return nodes
    outer, _, half, ptop, tol = _layout(p)
    if p.plinth_modules:
        side = np.array([[half, 0.0], [half, ptop]])
        if np.abs(outer[0] - side[1]).max() <= tol:
            side = side[:1]
        outer = np.vstack([side, outer])
    return outer


def base_triangle_estimate(p: BaseParams, *, cap_bottom: bool = True, cap_top: bool = True) -> int:
    """Triangles :func:`build_base` emits (the profile is built, not the mesh)."""
    nodes, _, _, _ = _closed_profile(p, cap_bottom=cap_bottom, cap_top=cap_top)
    on_axis = nodes[:, 0] <= 1e-12
    n = p.segments
    band = np.where(on_axis[:-1] | on_axis[1:], n, 2 * n)
    band[on_axis[:-1] & on_axis[1:]] = 0
    box = 8 + (2 if cap_bottom else 0) + n + 4 if p.plinth_modules else 0
    return int(band.sum()) + box


def _plinth_box(
    half: float, top: float, ring: np.ndarray, ring_pts: np.ndarray, cap_bottom: bool, first: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The square plinth around the revolved part's open bottom ring, as one shell with it.

    Its top face is the square minus the ring's disc (constrained Delaunay, shapely).

    Parameters
    ----------
    half, top : half-side and height of the slab (m)
    ring : (s,) int vertex indices of the revolved part's bottom ring (counter-clockwise
        about +Y, vertex 0 at +X), at y = ``top``
    ring_pts : (s, 3) float their positions
    first : index the slab's 8 corners start at

    Returns
    -------
    points (8, 3), triangles (t, 3) int, corner normals (t, 3, 3) float32
    """
    h = half
    # corners by angle θ = atan2(−z, x): 45°, 135°, 225°, 315°; bottom ones first
    cxz = np.array([[h, -h], [-h, -h], [-h, h], [h, h]])
    pts = np.array([[x, y, z] for y in (0.0, top) for x, z in cxz])
    bot = first + np.arange(4)
    tp = first + 4 + np.arange(4)
    tris = []
    # the top face: a constrained Delaunay triangulation of the square with the ring as a
    # hole adds no vertex, so it shares exactly the ring's edges
    import shapely
    from scipy.spatial import cKDTree

    xy = np.concatenate([cxz, ring_pts[:, [0, 2]]])
    poly = shapely.Polygon(cxz, [ring_pts[:, [0, 2]]])
    coords = shapely.get_coordinates(shapely.constrained_delaunay_triangles(poly))
    dist, jj = cKDTree(xy).query(coords.reshape(-1, 4, 2)[:, :3].reshape(-1, 2))
    if np.any(dist > 1e-9 * h):
        raise GeometryError("build_base: the plinth's top triangulation added vertices")
    ids = np.concatenate([tp, ring])
    tris = [tuple(t) for t in ids[jj].reshape(-1, 3)]
    for k in range(4):  # sides: corners k → k+1 go clockwise seen from above
        k1 = (k + 1) % 4
        tris += [(bot[k], bot[k1], tp[k1]), (bot[k], tp[k1], tp[k])]
    if cap_bottom:
        tris += [(bot[0], bot[3], bot[2]), (bot[0], bot[2], bot[1])]
    tri = np.array(tris, dtype=np.int64)
    return pts, tri, np.zeros((len(tri), 3, 3), dtype=np.float32)


def build_base(
    p: BaseParams | None = None,
    *,
    cap_bottom: bool = True,
    cap_top: bool = True,
    y_offset: float = 0.0,
    name: str = "base",
) -> Mesh:
    """Build the column base as a triangle mesh.

    Parameters
    ----------
    p : BaseParams (defaults to G2 on the Portunus shaft)
    cap_bottom : close the bottom (disc, or the plinth's bottom face)
    cap_top : close the top with a disc; without it the mesh ends exactly at the ring of
        radius d at y = height (``segments`` vertices, vertex 0 at +X), the shaft's bottom ring
    y_offset : lift the base (m)

    Returns
    -------
    Mesh with indexed normals (``normals.indices``): smooth within a module (and
    across C1 joints), crisp between modules and at the caps; and analytic ``st`` in metres
    of surface (:func:`ionic_usd.column.charts.revolved_st`; the plinth box-mapped).
    """
    p = p or BaseParams()
    nodes, seg, half, ptop = _closed_profile(p, cap_bottom=cap_bottom, cap_top=cap_top)
    mesh, rows = revolve(nodes, p.segments, name=name)
    sizes = np.array([len(r) for r in rows])
    per_band = np.where((sizes[:-1] == 1) | (sizes[1:] == 1), p.segments, 2 * p.segments)
    per_band[(sizes[:-1] == 1) & (sizes[1:] == 1)] = 0
    groups = np.repeat(seg, per_band)
    if len(groups) != mesh.n_triangles:  # revolve emits bands in profile order
        raise GeometryError("build_base: revolve's band layout changed")
    mesh = smooth_normals(mesh, groups - groups.min(), indexed=True)
    st, st_idx = revolved_st(
        nodes, rows, mesh.points, mesh.triangles, np.repeat(np.arange(len(per_band)), per_band)
    )
    mesh = mesh.with_(st=CornerValues(st, st_idx))
    if p.plinth_modules:
        mesh = _with_plinth(mesh, rows[0], half, ptop, cap_bottom, name)
    if y_offset:
        mesh = mesh.with_(points=mesh.points + np.array([0.0, y_offset, 0.0]))
    return mesh


def _with_plinth(
    mesh: Mesh, ring: np.ndarray, half: float, top: float, cap_bottom: bool, name: str
) -> Mesh:
    """Close the revolved part's bottom ring with the square plinth (one shell, flat normals)."""
    if len(ring) == 1 or half <= float(np.linalg.norm(mesh.points[ring[0]][[0, 2]])):
        raise GeometryError("build_base: the plinth must be wider than the moulding on it")
    pts, tri, _ = _plinth_box(half, top, ring, mesh.points[ring], cap_bottom, mesh.n_points)
    points = np.concatenate([mesh.points, pts])
    fn, _ = face_normals(points, tri)
    # orient every slab triangle outward by construction check: flip any facing inward
    centre = np.array([0.0, top / 2, 0.0])
    cen = points[tri].mean(axis=1)
    out = np.einsum("ij,ij->i", fn, cen - centre)
    flat_top = np.abs(points[tri][:, :, 1] - top).max(axis=1) < 1e-12
    out = np.where(flat_top, fn[:, 1], out)
    flip = out < 0
    tri[flip] = tri[flip][:, [0, 2, 1]]
    fn[flip] = -fn[flip]
    assert mesh.normals is not None and mesh.normals.indices is not None
    normals = CornerValues(
        np.concatenate([mesh.normals.values, fn.astype(np.float32)]),
        np.concatenate(
            [mesh.normals.indices, len(mesh.normals.values) + np.repeat(np.arange(len(tri)), 3)]
        ),
    )
    idx = np.concatenate([mesh.face_vertex_indices, tri.reshape(-1)])
    st_cv = mesh.st
    if st_cv is not None:
        st, sti = st_cv.values, st_cv.corner_indices(mesh.face_vertex_indices)
        # the slab's faces are planar: one chart per face plane (by outward normal), box-mapped
        corners = tri.reshape(-1)
        axis = np.argmax(np.abs(fn), axis=1)
        key = np.repeat(axis * 2 + (fn[np.arange(len(fn)), axis] > 0), 3)
        uniq, first, inv = np.unique(
            key * len(points) + corners, return_index=True, return_inverse=True
        )
        slab = box_st(points[uniq % len(points)], np.repeat(fn, 3, axis=0)[first])
        sti = np.concatenate([sti, len(st) + inv.reshape(-1)])
        st_cv = CornerValues(np.concatenate([st, slab.astype(np.float32)]), sti)
    return Mesh(points, np.full(len(idx) // 3, 3, np.int32), idx, normals, st_cv, name=name)


# the parsed grammars are frozen values: a text parsed once serves every BaseParams of it
# (the column asset makes ~70, one per part variant × LOD)
_parse_grammar = functools.lru_cache(maxsize=256)(parse_base_grammar)


# -- presets --------------------------------------------------------------------------------
_PRESET_KEYS = {"description", "version", "grammar", "plinth_modules"}


@functools.cache
def _preset_text() -> str:
    return resources.files("ionic_usd").joinpath("data/base_presets.toml").read_text("utf-8")


@functools.cache
def _parsed_presets() -> dict[str, dict]:
    return tomllib.loads(_preset_text())


def _presets() -> dict[str, dict]:
    # fresh dicts each call (their values are numbers and strings): callers may not mutate ours
    return {name: dict(entry) for name, entry in _parsed_presets().items()}


def base_preset_names() -> tuple[str, ...]:
    """Names of the shipped base presets."""
    return tuple(_presets())


def load_base_preset(name: str, **overrides) -> BaseParams:
    """A shipped base preset as :class:`BaseParams`.

    Parameters
    ----------
    name : preset name (see :func:`base_preset_names`; ``G1``, ``G2`` are the paper's)
    overrides : BaseParams fields to change (``shaft_radius``, ``segments``, …)

    Raises
    ------
    ParameterError
        For an unknown name (the message lists the valid ones).
    """
    presets = _presets()
    if name not in presets:
        raise ParameterError("base preset", name, f"one of {', '.join(presets)}")
    entry = presets[name]
    extra = set(entry) - _PRESET_KEYS
    if extra:
        raise ParameterError(
            f"base preset {name!r} key",
            sorted(extra)[0],
            f"one of {', '.join(sorted(_PRESET_KEYS))}",
        )
    kw = {k: v for k, v in entry.items() if k != "description"}
    kw.update(overrides)
    return BaseParams(**kw)
