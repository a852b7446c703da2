"""The volute as a solid: the backing disc (the channel floor), the raised spiral band and the
eye boss, each a closed prism over a triangulated region of the volute's face
(:func:`prism`); the curves come from :mod:`ionic_usd.column.volute`.
"""

from __future__ import annotations

import math

import numpy as np

from ionic_usd.column.volute import (
    VoluteParams,
    volute_band_outline,
    volute_eye,
    volute_points,
    volute_theta,
)
from ionic_usd.errors import GeometryError, ParameterError
from ionic_usd.geometry.mesh import CornerValues, Mesh, merge
from ionic_usd.geometry.stitch import stitch

__all__ = [
    "prism",
    "build_volute_band",
    "build_volute_backing",
    "build_volute_eye",
    "build_volute",
]


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
    Closed triangle Mesh with per-corner normals (flat caps, walls smooth between creases)
    and three exact metric ``st`` charts: the front cap (x, y), the back cap (−x, y) and the
    walls unrolled (arc length along the loop, z), each winding counter-clockwise like its
    faces seen from outside.
    """
    pts = np.asarray(points2d, dtype=np.float64)
    if not z1 > z0:
        raise GeometryError(f"prism {name!r}: z1 must exceed z0")
    tri = _ccw_triangles(pts, np.asarray(triangles, dtype=np.int64), name)
    if loop is None:
        loop = _boundary_loop(tri)
    loop = np.asarray(loop, dtype=np.int64)
    lp = pts[loop]
    if np.dot(lp[:, 0], np.roll(lp[:, 1], -1)) - np.dot(np.roll(lp[:, 0], -1), lp[:, 1]) < 0:
        loop = loop[::-1]
    n = len(pts)
    n_start, n_end = _wall_normals(pts, loop, crease_deg)
    u, v = loop, np.roll(loop, -1)
    # wall quad (v_top, u_top, u_bot, v_bot): reverses the cap edge u→v on top, runs u→v below
    walls = np.concatenate([np.stack([v + n, u + n, u], axis=1), np.stack([v + n, u, v], axis=1)])
    wall_n = np.concatenate(
        [np.stack([n_end, n_start, n_start], axis=1), np.stack([n_end, n_start, n_end], axis=1)]
    )
    faces = np.concatenate([tri + n, tri[:, ::-1], walls])
    t = len(tri)
    normals = np.zeros((len(faces), 3, 3), dtype=np.float32)
    normals[:t, :, 2] = 1.0
    normals[t : 2 * t, :, 2] = -1.0
    normals[2 * t :, :, :2] = wall_n
    points = np.concatenate(
        [np.column_stack([pts, np.full(n, z0)]), np.column_stack([pts, np.full(n, z1)])]
    )
    st, sti = _prism_st(pts, tri, loop, z0, z1)
    return Mesh(
        points,
        np.full(len(faces), 3, np.int32),
        faces.reshape(-1),
        CornerValues.per_corner(normals.reshape(-1, 3)),
        CornerValues(st.astype(np.float32), sti.reshape(-1)),
        name=name,
    )


def _ccw_triangles(pts: np.ndarray, tri: np.ndarray, name: str) -> np.ndarray:
    """The region's triangles turned counter-clockwise (all of one orientation, none
    degenerate, else GeometryError)."""
    p = pts[tri]
    area2 = (p[:, 1, 0] - p[:, 0, 0]) * (p[:, 2, 1] - p[:, 0, 1]) - (p[:, 1, 1] - p[:, 0, 1]) * (
        p[:, 2, 0] - p[:, 0, 0]
    )
    if np.all(area2 < 0):
        tri, area2 = tri[:, ::-1], -area2
    if not np.all(area2 > 0):
        raise GeometryError(f"prism {name!r}: the region's triangles fold over or are degenerate")
    return tri


def _wall_normals(pts: np.ndarray, loop: np.ndarray, crease_deg: float):
    """The walls' normals at each loop edge's first and second vertex: outward edge normals
    of the counter-clockwise loop, averaged at smooth vertices and kept per edge at creases
    (so a sharp corner stays crisp)."""
    d = pts[np.roll(loop, -1)] - pts[loop]
    en = np.stack([d[:, 1], -d[:, 0]], axis=1)
    en /= np.linalg.norm(en, axis=1, keepdims=True)
    prev_en = np.roll(en, 1, axis=0)
    crease = np.einsum("ij,ij->i", prev_en, en) < math.cos(math.radians(crease_deg))
    vn = prev_en + en
    vn /= np.linalg.norm(vn, axis=1, keepdims=True)
    n_start = np.where(crease[:, None], en, vn)
    n_end = np.roll(np.where(crease[:, None], prev_en, vn), -1, axis=0)
    return n_start, n_end


def _prism_st(pts: np.ndarray, tri: np.ndarray, loop: np.ndarray, z0: float, z1: float):
    """st values and per-corner indices: the front cap's n values, the back cap's n, then the
    walls' 2 (b + 1): loop vertex k at s = arc length to it (the last edge ends at the whole
    length: the strip's seam)."""
    n, b = len(pts), len(loop)
    d = pts[np.roll(loop, -1)] - pts[loop]
    arc = np.concatenate([[0.0], np.cumsum(np.linalg.norm(d, axis=1))])
    w0 = 2 * n
    k = np.arange(b)
    st = np.concatenate(
        [
            pts,
            pts * [-1.0, 1.0],
            np.column_stack([arc, np.full(b + 1, z1)]),
            np.column_stack([arc, np.full(b + 1, z0)]),
        ]
    )
    top, bot = w0 + k, w0 + b + 1 + k  # the edge's first vertex; + 1 is its second
    wall_st = np.concatenate(
        [np.stack([top + 1, top, bot], axis=1), np.stack([top + 1, bot, bot + 1], axis=1)]
    )
    return st, np.concatenate([tri, tri[:, ::-1] + n, wall_st])


def _lift(p: VoluteParams, xy: np.ndarray) -> np.ndarray:
    """Spiral-origin coordinates → eye-centred coordinates."""
    return xy - p.eye_center


def build_volute_band(
    p: VoluteParams,
    *,
    samples: int = 192,
    margin: float = 0.0,
    rise: float = 0.0,
    z0: float,
    z1: float,
    name: str = "volute_band",
) -> Mesh:
    """The raised spiral band (the listel) as a closed prism between ``z0`` and ``z1``; the
    margin's upper edge rises by ``rise`` (:func:`~ionic_usd.column.volute.volute_band_outline`).

    Coordinates: the eye centre at the origin, the volute's face plane ⊥ Z.
    """
    outer, inner = volute_band_outline(p, samples, margin, rise)
    n = len(outer)
    tris = stitch(np.arange(n), np.arange(n, 2 * n), is_closed=False)
    loop = np.concatenate([np.arange(n), np.arange(2 * n - 1, n - 1, -1)])
    return prism(_lift(p, np.concatenate([outer, inner])), tris, z0, z1, loop=loop, name=name)


def build_volute_backing(
    p: VoluteParams,
    *,
    samples: int = 192,
    z0: float,
    z1: float,
    name: str = "volute_backing",
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
    ring = volute_points(p, th)
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
    p: VoluteParams,
    *,
    segments: int = 48,
    z0: float,
    z1: float,
    name: str = "volute_eye",
) -> Mesh:
    """The eye as a cylindrical boss (a closed prism over the eye's circle)."""
    return _disc(
        _lift(p, np.vstack([volute_eye(p, segments), p.eye_center[None, :]])), z0, z1, name
    )


def _disc(pts: np.ndarray, z0: float, z1: float, name: str) -> Mesh:
    """A closed prism over a polygon (``pts``: its points, then its centre) fanned from the
    centre, with crisp vertical edges."""
    n = len(pts) - 1
    i = np.arange(n)
    fan = np.stack([np.full(n, n), i, (i + 1) % n], axis=1)
    return prism(pts, fan, z0, z1, loop=i, crease_deg=90.0, name=name)


def build_volute(
    p: VoluteParams | None = None,
    *,
    samples: int = 192,
    eye_segments: int = 48,
    relief_depth: float = 0.015,
    slab_depth: float = 0.03,
    margin: float = 0.0,
    seat: float = 0.0,
    rim: float = 0.0,
    rim_segments: int = 48,
    name: str = "volute",
) -> Mesh:
    """One volute (closed shells: backing disc, raised band, eye boss and, for ``rim`` > 0,
    the bolster's end: a disc of that radius about the eye, level with the channel floor),
    merged.

    Frame: the eye centre at the origin, the face towards +Z; the band and the eye span ``z ∈
    [−relief_depth − seat, 0]`` (``seat`` sinks them into the backing, and raises the margin's
    far end as much, so a union meets an overlap, not touching faces), the backing
    ``[−relief_depth − slab_depth, −relief_depth]``; the recess between the band's turns is the
    backing's front face (the channel floor). Mirror with
    :func:`ionic_usd.geometry.mesh.transform` for the other volutes.
    """
    p = p or VoluteParams()
    for nm, v in (("relief_depth", relief_depth), ("slab_depth", slab_depth)):
        if not (math.isfinite(v) and v > 0):
            raise ParameterError(nm, v, "a length > 0", context="volute")
    if margin < 0 or not math.isfinite(margin):
        raise ParameterError("margin", margin, "a length >= 0", context="volute")
    if not (math.isfinite(seat) and 0 <= seat < slab_depth):
        raise ParameterError("seat", seat, "a length in [0, slab_depth)", context="volute")
    band = build_volute_band(
        p, samples=samples, margin=margin, rise=seat, z0=-relief_depth - seat, z1=0.0
    )
    back = build_volute_backing(p, samples=samples, z0=-relief_depth - slab_depth, z1=-relief_depth)
    eye = build_volute_eye(p, segments=eye_segments, z0=-relief_depth - seat, z1=0.0)
    shells = [back, band, eye]
    if rim > 0:
        shells.append(_rim_disc(rim, rim_segments, z0=-relief_depth - slab_depth, z1=-relief_depth))
    return merge(shells, name=name)


def _rim_disc(radius: float, segments: int, *, z0: float, z1: float) -> Mesh:
    """The roll's end as a disc about the eye, level with the channel floor: where the roll
    (the bolster, a lathe about the eye's axis) is wider than the spiral's outer turn, its end
    is the volute's face, not a step back to the bolster's end."""
    a = 2 * np.pi * (np.arange(segments) + 0.5) / segments  # between the bolster's vertices
    ring = radius * np.stack([np.cos(a), np.sin(a)], axis=1)
    return _disc(np.vstack([ring, [[0.0, 0.0]]]), z0, z1, "volute_rim")
