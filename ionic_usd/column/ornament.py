"""Ornament prototypes and instance arrays (pure numpy): small closed meshes repeated by rule.

Each prototype is one closed, outward-wound mesh of a few hundred triangles at most, built in
its own frame: **+Y up, +Z out of the surface it decorates (towards the viewer), +X along the
run** of the moulding, origin on the surface. :class:`Instances` holds where the copies go —
positions ``(n, 3)``, orientations as unit quaternions ``(n, 4)`` in ``(w, x, y, z)`` order,
scales ``(n, 3)`` and the prototype of each — so that a USD ``PointInstancer`` can take them
as they are (:mod:`ionic_usd.usd.detail`).

The capital's carved mouldings are placed here too: egg-and-dart on the echinus and
bead-and-reel on the astragal at the shaft's top (:func:`capital_ornament`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ionic_usd.errors import GeometryError, ParameterError
from ionic_usd.geometry.analysis import signed_volume
from ionic_usd.geometry.mesh import CornerValues, Mesh, smooth_normals
from ionic_usd.geometry.sweep import sweep

__all__ = [
    "Instances",
    "frames_to_quaternions",
    "quaternion_matrices",
    "lathe_closed",
    "box_prototype",
    "egg_prototype",
    "dart_prototype",
    "bead_prototype",
    "reel_prototype",
    "capital_ornament",
    "EGG_COUNT",
]

# Eggs round the echinus: one over each flute (24, Vitruvius III.5.14 for the flutes); the
# alignment of eggs with flutes is (!) an assumption — Vitruvius gives no egg count.
EGG_COUNT = 24


@dataclass(frozen=True, eq=False)
class Instances:
    """Copies of a few prototypes.

    Parameters
    ----------
    name : str
    prototypes : tuple[Mesh, ...]
    proto_indices : (n,) int32, index into ``prototypes``
    positions : (n, 3) float64
    orientations : (n, 4) float64 unit quaternions ``(w, x, y, z)``
    scales : (n, 3) float64
    """

    name: str
    prototypes: tuple[Mesh, ...]
    proto_indices: np.ndarray
    positions: np.ndarray
    orientations: np.ndarray
    scales: np.ndarray

    def __post_init__(self) -> None:
        n = len(self.proto_indices)
        idx = np.asarray(self.proto_indices, dtype=np.int32).reshape(-1)
        pos = np.asarray(self.positions, dtype=np.float64).reshape(-1, 3)
        rot = np.asarray(self.orientations, dtype=np.float64).reshape(-1, 4)
        sc = np.asarray(self.scales, dtype=np.float64).reshape(-1, 3)
        if not (len(pos) == len(rot) == len(sc) == n):
            raise GeometryError(f"instances {self.name!r}: arrays of different lengths")
        if n and (idx.min() < 0 or idx.max() >= len(self.prototypes)):
            raise GeometryError(f"instances {self.name!r}: a prototype index is out of range")
        if not all(np.all(np.isfinite(a)) for a in (pos, rot, sc)):
            raise GeometryError(f"instances {self.name!r}: non-finite values")
        object.__setattr__(self, "proto_indices", idx)
        object.__setattr__(self, "positions", pos)
        object.__setattr__(self, "orientations", rot)
        object.__setattr__(self, "scales", sc)
        object.__setattr__(self, "prototypes", tuple(self.prototypes))

    def __len__(self) -> int:
        return len(self.proto_indices)

    def counts(self) -> dict[str, int]:
        """Instances per prototype name."""
        c = np.bincount(self.proto_indices, minlength=len(self.prototypes))
        return {p.name: int(k) for p, k in zip(self.prototypes, c, strict=True)}

    @property
    def triangles(self) -> int:
        """Triangles drawn by all copies."""
        per = np.array([p.n_triangles for p in self.prototypes])
        return int(per[self.proto_indices].sum())

    def matrices(self) -> np.ndarray:
        """(n, 4, 4) column-vector transforms ``T · R · S`` of the copies."""
        m = np.zeros((len(self), 4, 4))
        m[:, :3, :3] = quaternion_matrices(self.orientations) * self.scales[:, None, :]
        m[:, :3, 3] = self.positions
        m[:, 3, 3] = 1.0
        return m

    @staticmethod
    def concat(name: str, parts: list[Instances]) -> Instances:
        """One set from several (prototypes concatenated, indices shifted)."""
        protos: list[Mesh] = []
        idx = []
        for p in parts:
            idx.append(p.proto_indices + len(protos))
            protos += list(p.prototypes)
        return Instances(
            name,
            tuple(protos),
            np.concatenate(idx),
            np.concatenate([p.positions for p in parts]),
            np.concatenate([p.orientations for p in parts]),
            np.concatenate([p.scales for p in parts]),
        )


def frames_to_quaternions(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Unit quaternions ``(w, x, y, z)`` of rotations taking local +X, +Y to ``x``, ``y``.

    Parameters
    ----------
    x, y : (n, 3) float, orthogonal directions (normalised here); local +Z goes to ``x × y``
    """
    x = np.asarray(x, dtype=np.float64).reshape(-1, 3)
    y = np.asarray(y, dtype=np.float64).reshape(-1, 3)
    x = x / np.linalg.norm(x, axis=1, keepdims=True)
    y = y - np.einsum("ij,ij->i", y, x)[:, None] * x
    y = y / np.linalg.norm(y, axis=1, keepdims=True)
    z = np.cross(x, y)
    m = np.stack([x, y, z], axis=2)  # columns
    # Shepperd's method, vectorised: pick the largest of 4w², 4x², 4y², 4z²
    tr = m[:, 0, 0] + m[:, 1, 1] + m[:, 2, 2]
    cand = np.stack([tr, m[:, 0, 0], m[:, 1, 1], m[:, 2, 2]], axis=1)
    k = np.argmax(cand, axis=1)
    q = np.empty((len(m), 4))
    for case in range(4):
        s = k == case
        if not s.any():
            continue
        r = m[s]
        if case == 0:
            t = np.sqrt(1.0 + tr[s]) * 2
            q[s] = np.stack(
                [
                    0.25 * t,
                    (r[:, 2, 1] - r[:, 1, 2]) / t,
                    (r[:, 0, 2] - r[:, 2, 0]) / t,
                    (r[:, 1, 0] - r[:, 0, 1]) / t,
                ],
                1,
            )
        elif case == 1:
            t = np.sqrt(1.0 + r[:, 0, 0] - r[:, 1, 1] - r[:, 2, 2]) * 2
            q[s] = np.stack(
                [
                    (r[:, 2, 1] - r[:, 1, 2]) / t,
                    0.25 * t,
                    (r[:, 0, 1] + r[:, 1, 0]) / t,
                    (r[:, 0, 2] + r[:, 2, 0]) / t,
                ],
                1,
            )
        elif case == 2:
            t = np.sqrt(1.0 + r[:, 1, 1] - r[:, 0, 0] - r[:, 2, 2]) * 2
            q[s] = np.stack(
                [
                    (r[:, 0, 2] - r[:, 2, 0]) / t,
                    (r[:, 0, 1] + r[:, 1, 0]) / t,
                    0.25 * t,
                    (r[:, 1, 2] + r[:, 2, 1]) / t,
                ],
                1,
            )
        else:
            t = np.sqrt(1.0 + r[:, 2, 2] - r[:, 0, 0] - r[:, 1, 1]) * 2
            q[s] = np.stack(
                [
                    (r[:, 1, 0] - r[:, 0, 1]) / t,
                    (r[:, 0, 2] + r[:, 2, 0]) / t,
                    (r[:, 1, 2] + r[:, 2, 1]) / t,
                    0.25 * t,
                ],
                1,
            )
    q *= np.where(q[:, :1] < 0, -1.0, 1.0)  # w ≥ 0: one representative
    return q / np.linalg.norm(q, axis=1, keepdims=True)


def quaternion_matrices(q: np.ndarray) -> np.ndarray:
    """(n, 3, 3) rotation matrices of unit quaternions ``(w, x, y, z)`` (n, 4)."""
    w, x, y, z = np.asarray(q, dtype=np.float64).reshape(-1, 4).T
    return np.stack(
        [
            np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], 1),
            np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], 1),
            np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], 1),
        ],
        axis=1,
    )


# -- prototypes ---------------------------------------------------------------------------------
def lathe_closed(
    profile: np.ndarray, segments: int, *, axis: str = "y", name: str = "lathe"
) -> Mesh:
    """Revolve a half-profile whose two ends lie on the axis into a closed solid.

    Parameters
    ----------
    profile : (k, 2) float (r, t): ``r`` ≥ 0 the distance from the axis, ``t`` along it; the
        first and last points have ``r = 0`` (the poles), the others ``r > 0``
    segments : points per ring (≥ 3)
    axis : "y" or "x", the axis of revolution

    Returns
    -------
    Mesh: triangles, smooth vertex normals, cylindrical ``st`` (angle / 2π, t)
    """
    prof = np.asarray(profile, dtype=np.float64)
    if (
        prof.ndim != 2
        or len(prof) < 3
        or prof[0, 0] != 0
        or prof[-1, 0] != 0
        or np.any(prof[1:-1, 0] <= 0)
        or segments < 3
    ):
        raise GeometryError("lathe_closed: (k ≥ 3, 2) profile from pole to pole, r > 0 between")
    rings = prof[1:-1]
    nr, n = len(rings), segments
    a = 2 * np.pi * np.arange(n) / n
    ring_pts = np.stack(
        [
            rings[:, None, 0] * np.cos(a)[None],
            np.broadcast_to(rings[:, None, 1], (nr, n)),
            rings[:, None, 0] * np.sin(a)[None],
        ],
        axis=2,
    ).reshape(-1, 3)
    pts = np.vstack([[0.0, prof[0, 1], 0.0], ring_pts, [0.0, prof[-1, 1], 0.0]])
    top = len(pts) - 1
    j = np.arange(n)
    j1 = (j + 1) % n
    tris = [np.stack([np.zeros(n, int), 1 + j1, 1 + j], 1)]
    for r in range(nr - 1):
        b0, b1 = 1 + r * n, 1 + (r + 1) * n
        tris += [np.stack([b0 + j, b0 + j1, b1 + j1], 1), np.stack([b0 + j, b1 + j1, b1 + j], 1)]
    last = 1 + (nr - 1) * n
    tris.append(np.stack([np.full(n, top), last + j, last + j1], 1))
    tri = np.concatenate(tris)
    if signed_volume(Mesh(pts, np.full(len(tri), 3), tri.reshape(-1))) < 0:
        tri = tri[:, ::-1]
    if axis == "x":
        pts = pts[:, [1, 0, 2]]
        pts[:, 2] *= -1  # swap x/y and flip z: a proper rotation keeps the winding
    elif axis != "y":
        raise ParameterError("axis", axis, "'x' or 'y'")
    # cylindrical st with its own seam column (u = 1 on the wrap-around corners)
    ang = np.zeros(len(pts))
    ang[1:top] = np.tile(np.arange(n) / n, nr)
    t = np.concatenate([[prof[0, 1]], np.repeat(rings[:, 1], n), [prof[-1, 1]]])
    u = ang[tri]
    wrap = u.max(axis=1, keepdims=True) - u > 0.5
    u = np.where(wrap, u + 1.0, u)
    st = np.stack([u.reshape(-1), t[tri].reshape(-1)], axis=1)
    m = Mesh(
        pts,
        np.full(len(tri), 3, np.int32),
        tri.reshape(-1),
        name=name,
        st=CornerValues(st.astype(np.float32), np.arange(len(st), dtype=np.int32)),
    )
    return smooth_normals(m)


def box_prototype(size=(1.0, 1.0, 1.0), *, back: float = 0.0, name: str = "box") -> Mesh:
    """A box ``x ∈ [−sx/2, sx/2]``, ``y ∈ [0, sy]``, ``z ∈ [−back, sz]`` (a dentil)."""
    sx, sy, sz = (float(v) for v in size)
    sec = np.array([[-sx / 2, 0.0], [sx / 2, 0.0], [sx / 2, sy], [-sx / 2, sy]])
    path = np.array([[0.0, 0.0, -back], [0.0, 0.0, sz]])
    # sweep along +Z with axis +Y: u runs along cross(+Z, +Y) = −X, v along +Y
    return sweep(sec, path, axis=(0.0, 1.0, 0.0), closed=False, name=name)


def egg_prototype(
    height: float,
    width: float,
    depth: float,
    *,
    segments: int = 12,
    rows: int = 8,
    name: str = "Egg",
) -> Mesh:
    """An egg (ovum) with its long axis along Y, centred at the origin, depth along Z.

    The meridian is a Hügelschäffer-like egg curve, fuller at the top (the eggs of an echinus
    hang with their narrow end down)."""
    t = np.linspace(-np.pi / 2, np.pi / 2, rows + 1)
    y = 0.5 * height * np.sin(t)
    r = 0.5 * width * np.cos(t) * (1.0 + 0.18 * np.sin(t))
    r[0] = r[-1] = 0.0
    m = lathe_closed(np.stack([r, y], 1), segments, name=name)
    s = np.diag([1.0, 1.0, depth / width, 1.0])
    from ionic_usd.geometry.mesh import transform

    return transform(m, s)


def dart_prototype(height: float, width: float, depth: float, *, name: str = "Dart") -> Mesh:
    """A dart (arrow-head leaf between two eggs): a flattened double cone along Y, tip down."""
    prof = np.array(
        [
            [0.0, -0.5 * height],
            [0.5 * width, 0.15 * height],
            [0.15 * width, 0.5 * height],
            [0.0, 0.5 * height],
        ]
    )
    m = lathe_closed(prof, 6, name=name)
    from ionic_usd.geometry.mesh import transform

    return transform(m, np.diag([1.0, 1.0, depth / width, 1.0]))


def bead_prototype(
    length: float, diameter: float, *, segments: int = 10, name: str = "Bead"
) -> Mesh:
    """An elongated bead along X, centred at the origin."""
    t = np.linspace(-np.pi / 2, np.pi / 2, 7)
    prof = np.stack([0.5 * diameter * np.cos(t), 0.5 * length * np.sin(t)], 1)
    prof[0, 0] = prof[-1, 0] = 0.0
    return lathe_closed(prof, segments, axis="x", name=name)


def reel_prototype(
    length: float, diameter: float, *, segments: int = 10, name: str = "Reel"
) -> Mesh:
    """A reel (a pair of discs, waisted) along X, centred at the origin."""
    h, r = 0.5 * length, 0.5 * diameter
    prof = np.array(
        [[0.0, -h], [r, -h], [r, -0.3 * h], [0.45 * r, 0.0], [r, 0.3 * h], [r, h], [0.0, h]]
    )
    return lathe_closed(prof, segments, axis="x", name=name)


# -- the capital -------------------------------------------------------------------------------
def _ring_instances(
    proto: Mesh,
    n: int,
    phase: float,
    radius: float,
    y: float,
    tilt: np.ndarray | tuple[float, float] = (0.0, 1.0),
) -> Instances:
    """``n`` copies of ``proto`` evenly round the Y axis at ``radius`` and height ``y``, the
    first at angle ``phase``: local +X along the ring, local +Y ``tilt[0]`` × the outward radial
    + ``tilt[1]`` × world +Y (``tilt`` a unit vector in the meridian plane)."""
    a = phase + 2 * np.pi * np.arange(n) / n
    radial = np.stack([np.sin(a), np.zeros(n), np.cos(a)], 1)
    y_dir = tilt[0] * radial + tilt[1] * np.array([0.0, 1.0, 0.0])
    x_dir = np.stack([np.cos(a), np.zeros(n), -np.sin(a)], 1)
    pos = np.stack([radius * np.sin(a), np.full(n, y), radius * np.cos(a)], 1)
    return Instances(
        proto.name,
        (proto,),
        np.zeros(n, np.int32),
        pos,
        frames_to_quaternions(x_dir, y_dir),
        np.ones((n, 3)),
    )


def capital_ornament(
    *,
    y_capital: float,
    top_radius: float,
    echinus_height: float,
    echinus_projection: float,
    ring_top: float,
    capital_lift: float = 0.0,
    eggs: int = EGG_COUNT,
) -> tuple[Instances, Instances]:
    """Egg-and-dart on the echinus and bead-and-reel on the astragal, in column coordinates.

    Parameters
    ----------
    y_capital : height of the shaft's top (the capital's bottom), m
    top_radius : the shaft's top radius c, m (the echinus starts there)
    echinus_height, echinus_projection : the ovolo's height and reach beyond c (capital.py)
    ring_top : height of the plain ring at the shaft's top, where the astragal runs
    capital_lift : the capital's ``capital_position_y`` (its bottom above the shaft's top)
    eggs : eggs round the echinus (one dart between two eggs)

    Returns
    -------
    (egg_and_dart, bead_and_reel) : Instances
        Eggs sit on the ovolo at 60° of its quarter (where it faces out and down) with their
        axis along the ovolo's tangent; beads and reels alternate round the astragal, the
        number of pairs the circumference holds at a bead length of 1.6 × its diameter.
    """
    if eggs < 4:
        raise ParameterError("eggs", eggs, "an integer ≥ 4")
    c, h, w = top_radius, echinus_height, echinus_projection
    # the ovolo (capital._echinus): (c + w sin φ, h − h cos φ), φ ∈ [0, π/2]
    phi = math.radians(55.0)
    r0, y0 = c + w * math.sin(phi), y_capital + capital_lift + h * (1 - math.cos(phi))
    tang = np.array([w * math.cos(phi), h * math.sin(phi)])
    tang /= np.linalg.norm(tang)
    spacing = 2 * math.pi * r0 / eggs
    egg_h = 0.9 * h
    egg = egg_prototype(egg_h, 0.62 * spacing, 0.8 * min(w, 0.62 * spacing))
    dart = dart_prototype(0.75 * egg_h, 0.22 * spacing, 0.35 * min(w, 0.62 * spacing))
    # eggs and darts with their axis along the ovolo's tangent (up and out)
    out_parts = [
        _ring_instances(proto, eggs, phase, r0, y0, tilt=tang)
        for proto, phase in ((egg, 0.0), (dart, math.pi / eggs))
    ]
    egg_dart = Instances.concat("EggAndDart", out_parts)
    # bead-and-reel round the astragal (the shaft's plain top ring)
    d = 0.8 * ring_top
    lb, lr = 1.6 * d, 0.7 * d
    pairs = max(4, int(2 * math.pi * c // (lb + lr + 0.2 * d)))
    bead, reel = bead_prototype(lb, d), reel_prototype(lr, 0.85 * d)
    yb = y_capital - 0.5 * ring_top
    parts = [
        _ring_instances(proto, pairs, phase, c, yb)
        for proto, phase in ((bead, 0.0), (reel, math.pi / pairs))
    ]
    return egg_dart, Instances.concat("BeadAndReel", parts)
