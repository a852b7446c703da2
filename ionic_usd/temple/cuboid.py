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
from dataclasses import dataclass
from enum import StrEnum

import numpy as np

from ionic_usd.errors import ParameterError
from ionic_usd.geometry.mesh import Mesh

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

_AXES = ("x", "y", "z")

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


class Incline(StrEnum):
    """How ``rise`` deforms a cuboid (see the module docstring)."""

    SHEAR = "shear"
    WEDGE = "wedge"

    @classmethod
    def parse(cls, value: object, *, context: str = "") -> Incline:
        try:
            return cls(value)
        except ValueError:
            valid = " or ".join(repr(m.value) for m in cls)
            raise ParameterError("incline", value, valid, context=context) from None


def _vec3(name: str, value: object, context: str) -> tuple[float, float, float]:
    try:
        arr = np.asarray(value, dtype=np.float64).reshape(-1)
    except (TypeError, ValueError):
        raise ParameterError(name, value, "three numbers (x, y, z)", context=context) from None
    if arr.size != 3:
        raise ParameterError(name, value, "three numbers (x, y, z)", context=context)
    if not np.all(np.isfinite(arr)):
        raise ParameterError(name, value, "finite numbers", context=context)
    return (float(arr[0]), float(arr[1]), float(arr[2]))


@dataclass(frozen=True)
class Cuboid:
    """An axis-aligned box, optionally inclined across X (a roof piece).

    Parameters
    ----------
    min, max : (3,) float
        Corners with the smallest and largest x, y, z, in metres; ``min < max`` on every axis.
    rise : float
        Height difference (metres, along +y) applied to the vertices at max x; 0 for a box.
    incline : Incline or str
        ``"shear"`` (the paper's rule: the whole max-x face moves) or ``"wedge"`` (only its
        top edge moves). A wedge must keep its max-x face upright: ``max.y + rise > min.y``.
    name : str
        Prim name for authoring.
    """

    min: tuple[float, float, float]
    max: tuple[float, float, float]
    rise: float = 0.0
    incline: Incline = Incline.SHEAR
    name: str = "cuboid"

    def __post_init__(self) -> None:
        ctx = f"cuboid {self.name!r}"
        lo = _vec3("min", self.min, ctx)
        hi = _vec3("max", self.max, ctx)
        for k, axis in enumerate(_AXES):
            if not lo[k] < hi[k]:
                raise ParameterError(
                    f"max.{axis}", hi[k], f"> min.{axis} = {lo[k]!r}", context=ctx
                )
        try:
            rise = float(self.rise)
        except (TypeError, ValueError):
            raise ParameterError("rise", self.rise, "a number (metres)", context=ctx) from None
        if not math.isfinite(rise):
            raise ParameterError("rise", self.rise, "a finite number (metres)", context=ctx)
        incline = Incline.parse(self.incline, context=ctx)
        if incline is Incline.WEDGE and not hi[1] + rise > lo[1]:
            raise ParameterError(
                "rise", rise, f"> {lo[1] - hi[1]!r} (a wedge's top edge must stay above its "
                "bottom: max.y + rise > min.y)", context=ctx,
            )
        if not isinstance(self.name, str) or not self.name:
            raise ParameterError("name", self.name, "a non-empty string", context=ctx)
        object.__setattr__(self, "min", lo)
        object.__setattr__(self, "max", hi)
        object.__setattr__(self, "rise", rise)
        object.__setattr__(self, "incline", incline)

    @property
    def size(self) -> tuple[float, float, float]:
        """(Δx, Δy, Δz) of the undeformed box."""
        return tuple(b - a for a, b in zip(self.min, self.max, strict=True))  # type: ignore[return-value]

    @property
    def inclined(self) -> bool:
        return self.rise != 0.0

    @property
    def pitch_deg(self) -> float:
        """Slope of the inclined faces, ``atan(rise / Δx)`` in degrees (signed)."""
        return math.degrees(math.atan2(self.rise, self.size[0]))

    def top_at(self, x: float | np.ndarray) -> float | np.ndarray:
        """Height of the top face at ``x`` (linear across the slope)."""
        t = (np.asarray(x, dtype=np.float64) - self.min[0]) / self.size[0]
        return self.max[1] + self.rise * t

    def bottom_at(self, x: float | np.ndarray) -> float | np.ndarray:
        """Height of the bottom face at ``x``."""
        t = (np.asarray(x, dtype=np.float64) - self.min[0]) / self.size[0]
        return self.min[1] + (self.rise * t if self.incline is Incline.SHEAR else 0.0 * t)

    def contains(self, p, *, strict: bool = True, tol: float = 1e-9) -> bool:
        """Whether point ``p`` (3,) is inside the (deformed) solid; ``strict`` excludes the
        boundary within ``tol``."""
        x, y, z = (float(v) for v in p)
        e = tol if strict else -tol
        if not (self.min[0] + e < x < self.max[0] - e and self.min[2] + e < z < self.max[2] - e):
            return False
        return float(self.bottom_at(x)) + e < y < float(self.top_at(x)) - e

    def translated(self, offset) -> Cuboid:
        d = _vec3("offset", offset, f"cuboid {self.name!r}")
        return Cuboid(
            tuple(a + b for a, b in zip(self.min, d, strict=True)),
            tuple(a + b for a, b in zip(self.max, d, strict=True)),
            self.rise, self.incline, self.name,
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
        faceVarying (one flat normal per face), ``st (24, 2)`` with ``st_indices = arange(24)``.
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
        normals=np.repeat(nrm, 4, axis=0).astype(np.float32),
        normals_interpolation="faceVarying",
        st=st.astype(np.float32),
        st_indices=np.arange(24, dtype=np.int32),
        name=name if name is not None else c.name,
    )
