"""Axis-aligned cuboids and inclined roof pieces (paper §VII; SPEC §4) and their meshes.

The paper builds a temple from cuboids "which edges [are] parallel to the scene axes. For each
cuboid, the user only needs to define two vertices: the first with the minimum x, y and z
values and the second with the maximum x, y and z co-ordinates. [...] One exception has been
included for the roof creation, where it is possible to define one extra parameter: the height
difference. The third parameter is optional, but if defined, the four vertices with maximum z
coordinate are shifted by the specified difference towards the direction of y axis, so inclined
cuboids can be created. For example, two inclined cuboids have been used in the roof of the
temple of Portunus."

Frame (ours): metres, Y up, the temple's long axis and its roof ridge along Z, the front (+Z)
being the entrance. The paper's slope runs along its z; ours runs *across* the ridge, along X.
So the paper's rule becomes:

``Incline.SHEAR`` (the paper's rule)
    the four vertices with maximum **x** (the whole ``x = x1`` face, its two bottom and two
    top corners) are shifted by ``rise`` along +y. The section across the ridge is a
    parallelogram of constant vertical thickness: an inclined roof slab. Shearing keeps the
    volume: ``V = Δx·Δy·Δz``.
``Incline.WEDGE`` (an extension, for the pediment/tympanum)
    only the two **top** vertices at maximum x are raised by ``rise``; the bottom stays flat.
    The section is a right trapezoid of heights ``Δy`` (at x0) and ``Δy + rise`` (at x1):
    ``V = Δx·Δz·(Δy + rise/2)``, i.e. the box volume plus ``rise·Δx/2·Δz``.

A negative ``rise`` lowers the max-x side instead (the right-hand half of a gable, whose
ridge is at its min x). Two SHEAR pieces mirrored about the ridge make the paper's gabled roof;
two WEDGE pieces make the solid gable under it (its front face is the pediment).
"""

from __future__ import annotations

import math

import numpy as np

from ionic_usd.errors import ParameterError
from ionic_usd.geometry.mesh import CornerValues, Mesh

# the value types sit below their users (the cuboid grammar parses them); re-exported here
from ionic_usd.grammar.cuboid import Cuboid, Incline

__all__ = [
    "Incline",
    "Cuboid",
    "cuboid_points",
    "cuboid_mesh",
    "cuboid_volume",
    "DEFAULT_UV_SCALE",
]

DEFAULT_UV_SCALE = 0.25
"""Texture coordinates per metre: a texture repeat spans 4 m (a 1024 px map at 4 mm/px)."""

# corner k of the box has (x, y, z) = (x0|x1, y0|y1, z0|z1) by the bits (k & 1, k & 2, k & 4)
# six faces, counter-clockwise seen from outside: -x, +x, -y, +y, -z, +z
_FACES = np.array(
    [
        [0, 4, 6, 2],  # x = x0
        [1, 3, 7, 5],  # x = x1
        [0, 1, 5, 4],  # y = y0
        [2, 6, 7, 3],  # y = y1
        [0, 2, 3, 1],  # z = z0
        [4, 5, 7, 6],  # z = z1
    ],
    dtype=np.int32,
)


def cuboid_points(c: Cuboid) -> np.ndarray:
    """The 8 corners.

    Returns
    -------
    (8, 3) float64
        Corner ``k`` has x from bit 0, y from bit 1, z from bit 2 of ``k`` (0 → min, 1 → max),
        after the incline: corners with x = x1 get ``+rise`` on y (all four for SHEAR, the two
        with y = y1 for WEDGE).
    """
    k = np.arange(8)
    lo, hi = np.array(c.min), np.array(c.max)
    bits = np.stack([k & 1, (k >> 1) & 1, (k >> 2) & 1], axis=1).astype(bool)
    pts = np.where(bits, hi, lo).astype(np.float64)
    moved = bits[:, 0] if c.incline is Incline.SHEAR else bits[:, 0] & bits[:, 1]
    pts[moved, 1] += c.rise
    return pts


def cuboid_volume(c: Cuboid) -> float:
    """Analytic volume (see the module docstring for the derivation)."""
    dx, dy, dz = c.size
    if c.incline is Incline.SHEAR:
        return dx * dy * dz
    return dx * dz * (dy + 0.5 * c.rise)


def _face_frames(normals: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Orthonormal in-plane axes (u, v) per face with ``u × v = n`` (never mirrored).

    Mostly-horizontal faces take u from world +X, the others take v from world +Y (so walls
    read upright); both are projected into the face plane, which keeps UVs isometric to metres
    on sloped faces too.
    """
    us, vs = [], []
    for n in normals:
        if abs(n[1]) >= max(abs(n[0]), abs(n[2])):
            u = np.array([1.0, 0.0, 0.0]) - n[0] * n
            u /= np.linalg.norm(u)
            v = np.cross(n, u)
        else:
            v = np.array([0.0, 1.0, 0.0]) - n[1] * n
            v /= np.linalg.norm(v)
            u = np.cross(v, n)
        us.append(u)
        vs.append(v)
    return np.array(us), np.array(vs)


def cuboid_mesh(c: Cuboid, *, uv_scale: float = DEFAULT_UV_SCALE, name: str | None = None) -> Mesh:
    """A closed 8-point, 6-quad mesh of the cuboid with crisp normals and metric UVs.

    Parameters
    ----------
    c : Cuboid
    uv_scale : float
        Texture coordinates per metre (> 0). Each face is projected onto its own plane with
        world-anchored axes (``st = uv_scale · (p·u, p·v)``), so UV distances are metres ×
        ``uv_scale`` on every face, sloped ones included, and coplanar neighbours tile
        seamlessly.
    name : str, optional
        Mesh name (default: the cuboid's name).

    Returns
    -------
    Mesh
        ``points (8, 3)``, 6 quads wound counter-clockwise from outside, ``normals (24, 3)``
        per corner (one flat normal per face), ``st (24, 2)`` indexed by ``arange(24)``.
    """
    if not (isinstance(uv_scale, int | float) and math.isfinite(uv_scale) and uv_scale > 0):
        raise ParameterError("uv_scale", uv_scale, "a finite number > 0 (uv per metre)")
    pts = cuboid_points(c)
    quad = pts[_FACES]  # (6, 4, 3)
    # Newell's normal of each (planar) quad: exact for the sheared and wedged faces too
    nxt = np.roll(quad, -1, axis=1)
    nrm = np.stack(
        [
            ((quad[..., 1] - nxt[..., 1]) * (quad[..., 2] + nxt[..., 2])).sum(axis=1),
            ((quad[..., 2] - nxt[..., 2]) * (quad[..., 0] + nxt[..., 0])).sum(axis=1),
            ((quad[..., 0] - nxt[..., 0]) * (quad[..., 1] + nxt[..., 1])).sum(axis=1),
        ],
        axis=1,
    )
    nrm /= np.linalg.norm(nrm, axis=1, keepdims=True)
    u, v = _face_frames(nrm)
    st = uv_scale * np.stack(
        [np.einsum("fkj,fj->fk", quad, u), np.einsum("fkj,fj->fk", quad, v)], axis=2
    ).reshape(-1, 2)
    return Mesh(
        points=pts,
        face_vertex_counts=np.full(6, 4, dtype=np.int32),
        face_vertex_indices=_FACES.reshape(-1),
        normals=CornerValues.per_corner(np.repeat(nrm, 4, axis=0).astype(np.float32)),
        st=CornerValues(st.astype(np.float32), np.arange(24, dtype=np.int32)),
        name=name if name is not None else c.name,
    )
