"""The Ionic capital (paper section VI, Tables 4–5, Figure 5; SPEC §3).

Frame: metres, Y up; the origin is the centre of the shaft's top circle (radius ``top_radius``,
given by the caller); the front faces +Z. Parts, each a set of closed, outward-wound shells:

* **echinus** — the round cushion (an ovolo: a convex quarter ellipse revolved about Y) from the
  shaft's top radius out by ``echinus_projection`` over ``echinus_height``;
* **volutes** — four (front/rear × right/left), see :mod:`ionic_usd.column.volute`: a backing
  disc (channel floor), the raised spiral band and the eye boss; the right-front one is built,
  the others are mirror images (``transform`` with a reflection reverses their winding);
* **canales** — the front and rear plates joining the two volutes of a face under the abacus;
  the band's straight continuation (the *spiral margin*) runs along their top;
* **bolsters** — the scroll bodies (pulvini) joining front and rear volutes along Z, lofted
  from the ring grammar (:mod:`ionic_usd.grammar.scroll`) and centred on the eye axis;
* **abacus** — the thin slab on top.

The paper's five general parameters, as read here (its Figure 5 is not in the text):

* ``capital_length`` — X extent of the volute group, outer edge of the left volute to the outer
  edge of the right one; it places the eyes: ``eye_x = length/2 − (volute's +X extent)``;
* ``capital_width`` — Z extent of the volute group, front band face to rear band face;
* ``spiral_margin`` — length of the straight band continuing each volute's top end towards the
  axis (the canalis' upper edge); cut at the centre plane so the two margins meet, never cross;
* ``scroll_position_y`` — height of the eye centres above the capital's bottom;
* ``capital_position_y`` — height of the capital's bottom above the shaft top.

Vertical layout: echinus ``[0, echinus_height]``; the abacus rests on the volutes' top (the band's
top end), ``y_abacus = max(scroll_position_y + volute top extent, echinus_height)``; everything is
lifted by ``capital_position_y``. :func:`capital_height` is the abacus' top.

Defaults (Vitruvius III.5.5–7 for the Temple of Portunus, D = 0.95 m, part = D/18): abacus
(D + D/18) square and 1½ parts thick; volutes 8 parts high with the eye ½ part above the shaft
top (so they hang 3 parts below it) and on the *cathetus* 1½ parts inside the abacus' ends;
echinus 2½ parts high projecting 1½ parts; capital width D.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, fields, replace

import numpy as np

from ionic_usd.errors import ParameterError
from ionic_usd.geometry.mesh import Mesh, merge, smooth_normals
from ionic_usd.grammar.scroll import ScrollGrammar, resolve_scroll

from .volute import (
    VoluteParams,
    volute_curve,
    volute_extent,
    volute_total_radius,
)
from .volute_solid import build_volute

__all__ = [
    "CapitalParams",
    "CapitalParts",
    "CapitalLayout",
    "CAPITAL_PARAMETER_DOCS",
    "capital_layout",
    "capital_height",
    "build_capital",
    "capital_mesh",
    "bolster_profile",
]

_D = 0.95
_PART = _D / 18.0

CAPITAL_PARAMETER_DOCS: dict[str, tuple[str, str, str]] = {
    "scroll": ("Table 5", "grammar", "scroll-body rings 'R<r> P<p>, …' or a preset name (S1, S2)"),
    "capital_length": ("capital length", "m", "X extent of the volutes (outer edge to edge)"),
    "capital_width": ("capital width", "m", "Z extent of the volutes (front to rear face)"),
    "spiral_margin": ("spiral margin length", "m", "straight band from a volute's top inward"),
    "scroll_position_y": ("vertical position of the scrolls", "m",
                          "eye centre height above the capital bottom"),
    "capital_position_y": ("vertical position of the capital", "m",
                           "capital bottom above the shaft top"),
    "abacus_length": ("", "m", "abacus X size"),
    "abacus_width": ("", "m", "abacus Z size"),
    "abacus_height": ("", "m", "abacus thickness"),
    "echinus_height": ("", "m", "height of the echinus (ovolo) cushion"),
    "echinus_projection": ("", "m", "how far the echinus reaches beyond the shaft top radius"),
    "relief_depth": ("", "m", "height of the band and eye above the channel floor"),
    "slab_depth": ("", "m", "thickness of the volute disc and canalis plate"),
    "spiral_samples": ("", "count", "samples along the spiral (LOD)"),
    "ring_segments": ("", "count", "segments around the echinus, bolsters and eyes (LOD)"),
    "bolster_rows": ("", "count", "rows along a bolster between front and rear (LOD)"),
}


@dataclass(frozen=True)
class CapitalParams:
    """Volute (Table 4), scroll grammar (Table 5), the five general parameters, abacus,
    echinus and level of detail. Defaults: Vitruvius for the Temple of Portunus (module
    docstring)."""

    volute: VoluteParams = field(default_factory=VoluteParams)
    scroll: str | ScrollGrammar = "S1"
    capital_length: float = 1.2656
    capital_width: float = _D
    spiral_margin: float = 0.4222
    scroll_position_y: float = 0.5 * _PART
    capital_position_y: float = 0.0
    abacus_length: float = _D * 19.0 / 18.0
    abacus_width: float = _D * 19.0 / 18.0
    abacus_height: float = 1.5 * _PART
    echinus_height: float = 2.5 * _PART
    echinus_projection: float = 1.5 * _PART
    relief_depth: float = 0.015
    slab_depth: float = 0.03
    spiral_samples: int = 192
    ring_segments: int = 48
    bolster_rows: int = 32
    _scroll: ScrollGrammar = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        ctx = "capital"
        if not isinstance(self.volute, VoluteParams):
            raise ParameterError("volute", self.volute, "a VoluteParams", context=ctx)
        if not isinstance(self.scroll, str | ScrollGrammar):
            raise ParameterError("scroll", self.scroll, "a grammar string or preset name",
                                 context=ctx)
        object.__setattr__(self, "_scroll", resolve_scroll(self.scroll))
        for f in fields(self):
            if f.name in ("volute", "scroll", "_scroll"):
                continue
            v = getattr(self, f.name)
            if isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(v):
                raise ParameterError(f.name, v, "a finite number", context=ctx)
        for name in ("spiral_samples", "ring_segments", "bolster_rows"):
            v = getattr(self, name)
            if int(v) != v:
                raise ParameterError(name, v, "an integer", context=ctx)
            object.__setattr__(self, name, int(v))
        positive = ("capital_length", "capital_width", "abacus_length", "abacus_width",
                    "abacus_height", "echinus_height", "relief_depth", "slab_depth")
        for name in positive:
            if getattr(self, name) <= 0:
                raise ParameterError(name, getattr(self, name), "a length > 0", context=ctx)
        for name in ("spiral_margin", "echinus_projection"):
            if getattr(self, name) < 0:
                raise ParameterError(name, getattr(self, name), "a length >= 0", context=ctx)
        for name, lo in (("spiral_samples", 8), ("ring_segments", 3), ("bolster_rows", 1)):
            if getattr(self, name) < lo:
                raise ParameterError(name, getattr(self, name), f"an integer >= {lo}",
                                     context=ctx)
        depth = 2 * (self.relief_depth + self.slab_depth)
        if self.capital_width <= depth:
            raise ParameterError(
                "capital_width", self.capital_width,
                f"> 2 × (relief_depth + slab_depth) = {depth:.4g} m (room for the bolsters)",
                context=ctx)
        ext = volute_extent(self.volute, self.spiral_samples, self.ring_segments)
        need = 2 * float(ext[1, 0] - ext[0, 0])
        if self.capital_length < need:
            raise ParameterError(
                "capital_length", self.capital_length,
                f">= {need:.4g} m: two volutes {need / 2:.4g} m wide must not overlap",
                context=ctx)
        top = capital_height(self)
        if top <= 0:
            raise ParameterError("capital_position_y", self.capital_position_y,
                                 f"a value that keeps the abacus top above the shaft top "
                                 f"(it is at {top:.4g} m)", context=ctx)

    @property
    def scroll_grammar(self) -> ScrollGrammar:
        """The parsed scroll rings."""
        return self._scroll

    def with_(self, **changes) -> CapitalParams:
        return replace(self, **changes)


@dataclass(frozen=True)
class CapitalLayout:
    """Derived placements (m, capital frame before ``capital_position_y``)."""

    eye_x: float
    eye_y: float
    abacus_y: float
    face_z: float
    back_z: float
    total_radius: float
    margin: float


def capital_layout(p: CapitalParams) -> CapitalLayout:
    """Eye position, abacus bottom and the Z planes of the volute faces."""
    ext = volute_extent(p.volute, p.spiral_samples, p.ring_segments)
    eye_x = p.capital_length / 2 - float(ext[1, 0])
    eye_y = p.scroll_position_y
    abacus_y = max(eye_y + float(ext[1, 1]), p.echinus_height)
    face_z = p.capital_width / 2
    back_z = face_z - p.relief_depth - p.slab_depth
    # the band's top end lies on the eye's vertical line only for zero offsets: measure it
    top_end_x = eye_x + _top_end_dx(p.volute)
    margin = min(p.spiral_margin, max(0.0, top_end_x))
    return CapitalLayout(eye_x, eye_y, abacus_y, face_z, back_z,
                         volute_total_radius(p.volute), margin)


def _top_end_dx(v: VoluteParams) -> float:
    """X of the band's top end relative to the eye centre."""
    return float(volute_curve(v, 2)[-1, 0]) - v.offset_x  # either volute model


def capital_height(p: CapitalParams) -> float:
    """Top of the abacus above the shaft top (m): where the next element stacks."""
    ext = volute_extent(p.volute, p.spiral_samples, p.ring_segments)
    abacus_y = max(p.scroll_position_y + float(ext[1, 1]), p.echinus_height)
    return p.capital_position_y + abacus_y + p.abacus_height


# -- parts -----------------------------------------------------------------------------------
def _box(lo, hi, name: str) -> Mesh:
    """Axis-aligned box, outward-wound, crisp faceVarying normals."""
    (x0, y0, z0), (x1, y1, z1) = lo, hi
    pts = np.array([[x0, y0, z0], [x1, y0, z0], [x1, y1, z0], [x0, y1, z0],
                    [x0, y0, z1], [x1, y0, z1], [x1, y1, z1], [x0, y1, z1]])
    quads = np.array([[0, 3, 2, 1], [4, 5, 6, 7], [0, 1, 5, 4],
                      [3, 7, 6, 2], [0, 4, 7, 3], [1, 2, 6, 5]])
    tri = np.concatenate([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]])
    groups = np.tile(np.arange(6), 2)
    m = Mesh(pts, np.full(12, 3, np.int32), tri.reshape(-1), name=name)
    return smooth_normals(m, groups)


def _lathe(profile: np.ndarray, segments: int, name: str, crease_deg: float = 40.0) -> Mesh:
    """Revolve a (radius, height) half-profile about +Y, vectorised, with analytic normals.

    Same vertex rings and triangle orientation as :func:`ionic_usd.geometry.curves.revolve`
    (nodes on the axis become single vertices), but the whole grid is built at once and the
    normals come from the profile: smooth across profile nodes turning less than
    ``crease_deg``, crisp at sharper ones.
    """
    prof = np.asarray(profile, dtype=np.float64)
    s = int(segments)
    on_axis = prof[:, 0] <= 1e-12
    sizes = np.where(on_axis, 1, s)
    first = np.concatenate([[0], np.cumsum(sizes)[:-1]])
    ang = np.arange(s) * (2 * np.pi / s)
    cos, sin = np.cos(ang), np.sin(ang)
    pts = []
    for (r, y), ax in zip(prof, on_axis, strict=True):
        if ax:
            pts.append([[0.0, y, 0.0]])
        else:
            pts.append(np.stack([r * cos, np.full(s, y), -r * sin], axis=1))
    points = np.concatenate(pts)
    d = np.diff(prof, axis=0)
    seg_len = np.linalg.norm(d, axis=1)
    en = np.stack([d[:, 1], -d[:, 0]], axis=1) / np.where(seg_len > 0, seg_len, 1.0)[:, None]
    cos_turn = np.einsum("ij,ij->i", en[:-1], en[1:])
    smooth = np.concatenate([[False], cos_turn > math.cos(math.radians(crease_deg)), [False]])
    avg = en[:-1] + en[1:]
    avg = avg / np.maximum(np.linalg.norm(avg, axis=1, keepdims=True), 1e-300)
    n_start = en.copy()
    n_end = en.copy()
    n_start[1:][smooth[1:-1]] = avg[smooth[1:-1]]
    n_end[:-1][smooth[1:-1]] = avg[smooth[1:-1]]
    j = np.arange(s)
    j1 = (j + 1) % s
    mid = ang + np.pi / s  # the angle used for corners on the axis
    cmid, smid = np.cos(mid), np.sin(mid)

    def nvec(n2: np.ndarray, c: np.ndarray, sn: np.ndarray) -> np.ndarray:
        """(..., 2) profile normals × (s,) angles → (..., s, 3) normals."""
        n2 = np.asarray(n2)[..., None, :]
        return np.stack([n2[..., 0] * c, n2[..., 1] * np.ones_like(c), -n2[..., 0] * sn],
                        axis=-1)

    live = (seg_len > 0) & ~(on_axis[:-1] & on_axis[1:])
    grid = np.flatnonzero(live & ~on_axis[:-1] & ~on_axis[1:])
    tris, corner_n = [], []
    if grid.size:  # ring-to-ring bands, all at once
        a0, b0 = first[grid][:, None], first[grid + 1][:, None]
        na, nb = n_start[grid], n_end[grid]
        t1 = np.stack([a0 + j, b0 + j1, b0 + j], axis=-1)
        t2 = np.stack([a0 + j, a0 + j1, b0 + j1], axis=-1)
        na_j, na_j1 = nvec(na, cos, sin), nvec(na, cos[j1], sin[j1])
        nb_j, nb_j1 = nvec(nb, cos, sin), nvec(nb, cos[j1], sin[j1])
        tris += [t1.reshape(-1, 3), t2.reshape(-1, 3)]
        corner_n += [np.stack([na_j, nb_j1, nb_j], axis=-2).reshape(-1, 3, 3),
                     np.stack([na_j, na_j1, nb_j1], axis=-2).reshape(-1, 3, 3)]
    for k in np.flatnonzero(live & (on_axis[:-1] | on_axis[1:])):  # cap fans and cone tips
        a0, b0 = first[k], first[k + 1]
        na, nb = n_start[k], n_end[k]
        if on_axis[k]:
            tris.append(np.stack([np.full(s, a0), b0 + j1, b0 + j], axis=1))
            corner_n.append(np.stack([nvec(na, cmid, smid), nvec(nb, cos[j1], sin[j1]),
                                      nvec(nb, cos, sin)], axis=1))
        else:
            tris.append(np.stack([a0 + j, a0 + j1, np.full(s, b0)], axis=1))
            corner_n.append(np.stack([nvec(na, cos, sin), nvec(na, cos[j1], sin[j1]),
                                      nvec(nb, cmid, smid)], axis=1))
    tri = np.concatenate(tris)
    normals = np.concatenate(corner_n).reshape(-1, 3)
    return Mesh(points, np.full(len(tri), 3, np.int32), tri.reshape(-1), normals,
                "faceVarying", name=name)


def _echinus(p: CapitalParams, top_radius: float, segments: int) -> Mesh:
    c, h, w = top_radius, p.echinus_height, p.echinus_projection
    n = max(4, segments // 4)
    phi = np.linspace(0.0, np.pi / 2, n + 1)
    # convex ovolo: quarter ellipse centred at (c, h), bulging outward and down
    arc = np.stack([c + w * np.sin(phi), h - h * np.cos(phi)], axis=1)
    if w == 0:
        arc = np.array([[c, 0.0], [c, h]])
    prof = np.vstack([[[0.0, 0.0]], arc, [[0.0, h]]])
    return _lathe(prof, segments, "echinus")


def bolster_profile(p: CapitalParams, length: float, radius: float) -> np.ndarray:
    """Bolster half-profile along its axis from the ring grammar.

    Rings at ``p·length`` with radius ``r·radius``; the first and last rings are held to p = 0
    and p = 1 (where the bolster meets the volute discs). Between rings the radius is a
    monotone cubic (PCHIP: smooth, no overshoot, so it never dips below the smaller
    neighbour); rings sharing a position make a flat step.

    Returns
    -------
    (n, 2) float: (radius, distance along the axis) from the axis at 0 to the axis at
    ``length``, the counter-clockwise order :func:`~ionic_usd.geometry.curves.revolve` wants.
    """
    rings = p.scroll_grammar.rings
    knots = [(r.position, r.radius) for r in rings]
    if knots[0][0] > 0:
        knots.insert(0, (0.0, knots[0][1]))
    if knots[-1][0] < 1:
        knots.append((1.0, knots[-1][1]))
    runs: list[list[tuple[float, float]]] = [[knots[0]]]
    for k in knots[1:]:
        if k[0] == runs[-1][-1][0]:
            runs.append([k])
        else:
            runs[-1].append(k)
    from scipy.interpolate import PchipInterpolator

    grid = np.linspace(0.0, 1.0, p.bolster_rows + 1)
    nodes: list[tuple[float, float]] = []
    for run in runs:
        ps = np.array([k[0] for k in run])
        rs = np.array([k[1] for k in run])
        if len(run) == 1:
            nodes.append((ps[0], rs[0]))
            continue
        inside = grid[(grid > ps[0]) & (grid < ps[-1])]
        t = np.union1d(ps, inside)
        nodes.extend(zip(t.tolist(), PchipInterpolator(ps, rs)(t).tolist(), strict=True))
    prof = [(0.0, 0.0)]
    for pos, r in nodes:
        node = (max(r, 0.0) * radius, pos * length)
        if node != prof[-1]:
            prof.append(node)
    prof.append((0.0, length))
    return np.asarray(prof)


def _bolster(p: CapitalParams, lay: CapitalLayout) -> Mesh:
    length = 2 * lay.back_z
    prof = bolster_profile(p, length, lay.total_radius)
    m = _lathe(prof, p.ring_segments, "bolster")
    # +Y (the lathe axis, p from 0 to 1) → −Z (front to rear), then onto the eye axis
    rot = np.array([[1.0, 0, 0], [0, 0, 1], [0, -1, 0]])
    return _rigid(m, rot, (lay.eye_x, lay.eye_y, lay.back_z), "bolster_right")


@dataclass(frozen=True)
class CapitalParts:
    """The capital's meshes (capital frame, lifted by ``capital_position_y``).

    ``volutes``: front-right, front-left, rear-right, rear-left; ``canales``: front, rear;
    ``bolsters``: right, left.
    """

    abacus: Mesh
    echinus: Mesh
    volutes: tuple[Mesh, ...]
    canales: tuple[Mesh, ...]
    bolsters: tuple[Mesh, ...]

    def as_dict(self) -> dict[str, Mesh]:
        """Name → mesh, in a stable order (names are valid USD prim names)."""
        out = {"abacus": self.abacus, "echinus": self.echinus}
        for m in (*self.volutes, *self.canales, *self.bolsters):
            out[m.name] = m
        return out

    def merged(self, name: str = "capital") -> Mesh:
        return merge(list(self.as_dict().values()), name=name)


def _rigid(mesh: Mesh, lin: np.ndarray, t=(0.0, 0.0, 0.0), name: str | None = None) -> Mesh:
    """``transform`` for an orthogonal ``lin`` (rotations, axis mirrors) on a triangle mesh.

    Orthogonal maps carry unit normals to unit normals, so this skips the inverse transpose
    and renormalisation of :func:`~ionic_usd.geometry.mesh.transform` (the capital's largest
    cost at high LOD); a mirror reverses each triangle's winding (corners 1 and 2 swap).
    """
    lin = np.asarray(lin, dtype=np.float64)
    pts = mesh.points @ lin.T + np.asarray(t, dtype=np.float64)
    normals = None if mesh.normals is None else (mesh.normals @ lin.T.astype(np.float32))
    idx = mesh.face_vertex_indices
    if np.linalg.det(lin) < 0:
        idx = idx.reshape(-1, 3)[:, [0, 2, 1]].reshape(-1)
        if normals is not None and mesh.normals_interpolation == "faceVarying":
            normals = normals.reshape(-1, 3, 3)[:, [0, 2, 1]].reshape(-1, 3)
    return Mesh(pts, mesh.face_vertex_counts, idx, normals, mesh.normals_interpolation,
                name=name or mesh.name)


_MIRROR_X = np.diag([-1.0, 1.0, 1.0])
_MIRROR_Z = np.diag([1.0, 1.0, -1.0])


def build_capital(p: CapitalParams | None = None, *, top_radius: float,
                  angle: bool = False) -> CapitalParts:
    """Build the Ionic capital's parts.

    Parameters
    ----------
    p : CapitalParams (defaults: Vitruvius / Portunus)
    top_radius : radius of the shaft's top circle $c (m), where the echinus starts
    angle : an angle (corner) capital whose two outer faces, +Z and +X, both show volutes:
        the corner volute is turned 45° outward onto the diagonal, the +X face gets its own
        canalis and rear volute (the front-right volute turned 90°), and only the left bolster
        is kept (the inner faces −X and −Z). ``volutes``: front-left, corner, side-rear,
        rear-left; ``canales``: front, rear, side; ``bolsters``: left only.

    Returns
    -------
    CapitalParts, every mesh a union of closed, outward-wound triangle shells with normals.
    """
    p = p or CapitalParams()
    if (isinstance(top_radius, bool) or not isinstance(top_radius, int | float)
            or not math.isfinite(top_radius) or top_radius <= 0):
        raise ParameterError("top_radius", top_radius, "a length > 0 (the shaft's $c)",
                             context="capital")
    lay = capital_layout(p)
    segs = p.ring_segments
    vol = build_volute(p.volute, samples=p.spiral_samples, eye_segments=segs,
                       relief_depth=p.relief_depth, slab_depth=p.slab_depth,
                       margin=lay.margin)
    eye3 = np.eye(3)
    fr = _rigid(vol, eye3, (lay.eye_x, lay.eye_y, lay.face_z), "volute_front_right")
    fl = _rigid(fr, _MIRROR_X, name="volute_front_left")
    rr = _rigid(fr, _MIRROR_Z, name="volute_rear_right")
    rl = _rigid(fl, _MIRROR_Z, name="volute_rear_left")
    slab_front = lay.face_z - p.relief_depth
    # the canalis hangs between the volutes down to the echinus' top, so the echinus runs
    # under it as a moulding (from the eye down it would cut the ovolo's top off flat)
    canalis_lo = min(max(lay.eye_y, p.echinus_height), lay.abacus_y - 1e-3)
    front = _box((-lay.eye_x, canalis_lo, lay.back_z), (lay.eye_x, lay.abacus_y, slab_front),
                 "canalis_front")
    rear = _rigid(front, _MIRROR_Z, name="canalis_rear")
    br = _bolster(p, lay)
    bl = _rigid(br, _MIRROR_X, name="bolster_left")
    ab = _box((-p.abacus_length / 2, lay.abacus_y, -p.abacus_width / 2),
              (p.abacus_length / 2, lay.abacus_y + p.abacus_height, p.abacus_width / 2),
              "abacus")
    ech = _echinus(p, float(top_radius), segs)
    if angle:
        return _angle_capital(p, lay, ab, ech, fr, fl, rl, canalis_lo, rear, bl)
    parts = [ab, ech, fr, fl, rr, rl, front, rear, br, bl]
    if p.capital_position_y != 0:
        parts = [_rigid(m, eye3, (0.0, p.capital_position_y, 0.0)) for m in parts]
    ab, ech, fr, fl, rr, rl, front, rear, br, bl = parts
    return CapitalParts(ab, ech, (fr, fl, rr, rl), (front, rear), (br, bl))


CANALIS_BURY = 0.5  # how deep (fraction of the disc) the angle capital's canales end in it


def _rot_y(deg: float) -> np.ndarray:
    """Rotation about +Y taking +Z to (sin θ, 0, cos θ)."""
    t = math.radians(deg)
    # exact for quarter turns, so faces coplanar before the turn stay exactly coplanar
    c, s = (round(math.cos(t)), round(math.sin(t))) if deg % 90 == 0 else \
        (math.cos(t), math.sin(t))
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def _angle_capital(p: CapitalParams, lay: CapitalLayout, ab: Mesh, ech: Mesh, fr: Mesh,
                   fl: Mesh, rl: Mesh, canalis_lo: float, rear: Mesh, bl: Mesh
                   ) -> CapitalParts:
    """The angle capital (see :func:`build_capital`): outer faces +Z and +X."""
    from ionic_usd.geometry.boolean import union
    from ionic_usd.geometry.clip import clip_mesh

    eye = np.array([lay.eye_x, lay.eye_y, lay.face_z])
    # the corner volute: turned 45° about its eye's vertical, its eye moved onto the diagonal;
    # its band, eye and disc are united first, where their touching faces are exactly coplanar
    e = 0.5 * (lay.eye_x + lay.face_z)
    # it is lifted 1 mm into the abacus: an overlap, not a tangent touch of its disc's top
    # with the abacus and canales (which leaves a pinch vertex in the union)
    diag = _rigid(union([_rigid(fr, np.eye(3), -eye)]), _rot_y(45.0), (e, lay.eye_y + 1e-3, e),
                  "volute_corner")
    quarter = _rot_y(90.0)  # +Z → +X: the front face's right half becomes the +X face
    side = _rigid(fr, quarter, name="volute_side_rear")
    # the two outer canales run from their face's other volute into the corner volute's disc
    slab_front = lay.face_z - p.relief_depth
    reach = e + lay.total_radius
    front = _box((-lay.eye_x, canalis_lo, lay.back_z), (reach, lay.abacus_y, slab_front),
                 "canalis_front")
    # (into the side volute's disc by 1 cm: an overlap, not an edge touching its band's end)
    side_canalis = _rigid(_box((-reach, canalis_lo, lay.back_z),
                               (lay.eye_x + 0.01, lay.abacus_y, slab_front), "canalis_side"),
                          quarter)
    # keep the side behind the disc's mid-plane: the ends are buried in the disc (an end flush
    # with the disc's face would leave coplanar slivers in the union)
    diag_n = np.array([-1.0, 0.0, -1.0]) / math.sqrt(2.0)
    on_face = np.array([e, 0.0, e]) + diag_n * (p.relief_depth + CANALIS_BURY * p.slab_depth)
    front = clip_mesh(front, on_face, diag_n, name="canalis_front")
    side_canalis = clip_mesh(side_canalis, on_face, diag_n, name="canalis_side")
    parts = [ab, ech, fl, diag, side, rl, front, rear, side_canalis, bl]
    if p.capital_position_y != 0:
        parts = [_rigid(m, np.eye(3), (0.0, p.capital_position_y, 0.0)) for m in parts]
    ab, ech, fl, diag, side, rl, front, rear, side_canalis, bl = parts
    return CapitalParts(ab, ech, (fl, diag, side, rl), (front, rear, side_canalis), (bl,))


def capital_mesh(p: CapitalParams | None = None, *, top_radius: float,
                 name: str = "capital", angle: bool = False) -> Mesh:
    """All capital parts united into one closed solid (manifold3d boolean union)."""
    from ionic_usd.geometry.boolean import union

    parts = build_capital(p, top_radius=top_radius, angle=angle)
    return union(list(parts.as_dict().values()), name=name)
