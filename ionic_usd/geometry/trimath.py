"""Plain float math on triangles given as Python lists of 3 floats: corner cosines and angles,
normals, cross and dot products, a tetrahedron's height. The sliver clean-up's edits
(:mod:`ionic_usd.geometry.triedit`) read a few hundred rows of a mesh each: on 3-vectors, plain
float math is ~10x faster than numpy (~1 µs a call), and gives the same bits on every CPU.
"""

from __future__ import annotations

import math

__all__ = [
    "corner_angles",
    "corner_cosines",
    "cross3",
    "dot3",
    "smallest_angle",
    "tet_height",
    "unit_normal",
]

_DEG = 180.0 / math.pi  # x * _DEG is math.degrees(x), bit for bit


def corner_cosines(p: list[float], q: list[float], r: list[float]) -> tuple[float, float, float]:
    """The corner cosines of the triangle pqr (3 floats each), clamped to [-1, 1], in plain
    float math (numpy costs ~1 µs a call on 3-vectors). Each corner's cosine is (edge · edge) /
    (length × length) of its two edges from it; an edge reversed only flips signs, exactly, so
    the three edges and lengths are computed once. The clamps are written out as the
    comparisons ``max(x, 1e-300)`` and ``min(max(c, -1.0), 1.0)`` make (the same results, NaN
    included, without the builtins' call overhead)."""
    px, py, pz = p
    qx, qy, qz = q
    rx, ry, rz = r
    ux, uy, uz = qx - px, qy - py, qz - pz  # p → q
    vx, vy, vz = rx - px, ry - py, rz - pz  # p → r
    wx, wy, wz = rx - qx, ry - qy, rz - qz  # q → r
    lu = math.sqrt(ux * ux + uy * uy + uz * uz)
    lv = math.sqrt(vx * vx + vy * vy + vz * vz)
    lw = math.sqrt(wx * wx + wy * wy + wz * wz)
    d = lu * lv
    cp = (ux * vx + uy * vy + uz * vz) / (1e-300 if 1e-300 > d else d)
    d = lw * lu
    cq = -(wx * ux + wy * uy + wz * uz) / (1e-300 if 1e-300 > d else d)
    d = lv * lw
    cr = (vx * wx + vy * wy + vz * wz) / (1e-300 if 1e-300 > d else d)
    cp = -1.0 if -1.0 > cp else cp
    cq = -1.0 if -1.0 > cq else cq
    cr = -1.0 if -1.0 > cr else cr
    return (1.0 if 1.0 < cp else cp), (1.0 if 1.0 < cq else cq), (1.0 if 1.0 < cr else cr)


def corner_angles(p: list[float], q: list[float], r: list[float]) -> tuple[float, float, float]:
    """The corner angles (degrees) of the triangle pqr (3 floats each): see
    :func:`corner_cosines`."""
    cp, cq, cr = corner_cosines(p, q, r)
    acos = math.acos
    return acos(cp) * _DEG, acos(cq) * _DEG, acos(cr) * _DEG


def smallest_angle(p: list[float], q: list[float], r: list[float]) -> float:
    """``min(corner_angles(p, q, r))``, without the tuple and the builtin."""
    cp, cq, cr = corner_cosines(p, q, r)
    acos = math.acos
    a, b, c = acos(cp) * _DEG, acos(cq) * _DEG, acos(cr) * _DEG
    a = b if b < a else a
    return c if c < a else a


def unit_normal(p: list[float], q: list[float], r: list[float]) -> tuple[float, float, float]:
    """The unit normal of the triangle pqr (zero for a degenerate one)."""
    ux, uy, uz = q[0] - p[0], q[1] - p[1], q[2] - p[2]
    vx, vy, vz = r[0] - p[0], r[1] - p[1], r[2] - p[2]
    nx, ny, nz = uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx
    ln = math.sqrt(nx * nx + ny * ny + nz * nz)
    ln = 1e-300 if 1e-300 > ln else ln  # max(ln, 1e-300)
    return nx / ln, ny / ln, nz / ln


def cross3(p: list[float], q: list[float], r: list[float]) -> tuple[float, float, float]:
    """(q − p) × (r − p): twice the vector area of the triangle pqr."""
    ux, uy, uz = q[0] - p[0], q[1] - p[1], q[2] - p[2]
    vx, vy, vz = r[0] - p[0], r[1] - p[1], r[2] - p[2]
    return uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx


def dot3(u, v) -> float:
    return u[0] * v[0] + u[1] * v[1] + u[2] * v[2]


def tet_height(a: list[float], b: list[float], c: list[float], d: list[float]) -> float:
    """Smallest height of the tetrahedron abcd: how far a flip of edge ab (triangles abc, abd
    → acd, bcd) moves the surface."""
    n = cross3(a, b, c)
    v = abs(n[0] * (d[0] - a[0]) + n[1] * (d[1] - a[1]) + n[2] * (d[2] - a[2]))
    big = math.sqrt(dot3(n, n))  # the largest face area (x 2), as max() takes it
    for x in (cross3(a, b, d), cross3(a, c, d), cross3(b, c, d)):
        ar = math.sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2])
        if ar > big:
            big = ar
    return v / (1e-300 if 1e-300 > big else big)
