"""An independent synthetic scan of a column fragment, for the scan-fit tests (issue 36).

Not the project's model: the points are drawn on analytic surfaces built here — a square
plinth (a box), an Attic lathe profile of a lower torus (circle arc), fillets, a scotia (a
sine hollow, not an arc) and an upper torus, and a tapered shaft whose fluted section is
found by intersecting rays with the flutes' half ellipses (polar form), its flutes ending in
quarter-ellipse channel ends above a plain ring — then Gaussian noise, a broken side (points
beyond an oblique plane gone), a hidden sector, holes and a random rigid pose. Units: mm by
default (``unit`` = metres per unit).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Truth:
    """The fragment's true dimensions (mm)."""

    radius: float = 400.0  # shaft radius (fillets) at the joint
    top_ratio: float = 0.86  # radius at the shaft's top / at its bottom (whole shaft)
    shaft_length: float = 7000.0  # whole shaft (the fragment shows drum_height of it)
    entasis: float = 0.012  # bulge, fraction of the radius, sin(pi t)
    flutes: int = 24
    fillet_deg: float = 3.4  # fillet width (degrees); the flute spans 360/e - this
    depth: float = 0.85  # flute ellipse depth / half-chord
    ring: float = 35.0  # plain ring below the flutes
    drum_height: float = 2000.0
    plinth_half: float = 590.0
    plinth_height: float = 130.0
    rotation_deg: float = 4.0  # flute phase

    def scaled(self, radius: float) -> Truth:
        """The same column at another shaft radius (mm)."""
        k = radius / self.radius
        return dataclasses.replace(
            self,
            radius=radius,
            shaft_length=k * self.shaft_length,
            ring=k * self.ring,
            drum_height=k * self.drum_height,
            plinth_half=k * self.plinth_half,
            plinth_height=k * self.plinth_height,
        )


def attic_profile(t: Truth, n: int = 400) -> np.ndarray:
    """(m, 2) (r, y) lathe profile above the plinth, bottom to top, ending at the joint
    (drawn for a 400 mm shaft radius, scaled to ``t.radius``)."""
    sc = t.radius / 400.0
    hp = t.plinth_height / sc
    phi = np.linspace(-0.5 * np.pi, 0.5 * np.pi, n // 4)
    lower = np.c_[500.0 + 62.0 * np.cos(phi), hp + 62.0 + 62.0 * np.sin(phi)]
    y1 = hp + 124.0
    fil1 = np.array([[480.0, y1], [480.0, y1 + 12.0]])
    s = np.linspace(0.0, 1.0, n // 4)
    scotia = np.c_[480.0 - 38.0 * np.sin(np.pi * s) ** 1.5, y1 + 12.0 + 76.0 * s]
    y2 = y1 + 88.0
    fil2 = np.array([[480.0, y2 + 10.0], [462.0, y2 + 10.0]])
    up = np.c_[424.0 + 38.0 * np.cos(phi), y2 + 48.0 + 38.0 * np.sin(phi)]
    top = up[-1, 1]
    joint = np.array([[406.0, top], [406.0, top + 8.0], [400.0, top + 8.0]])
    return sc * np.vstack([lower, fil1, scotia, fil2, up, joint])


def joint_height(t: Truth) -> float:
    return float(attic_profile(t)[-1, 1])


def shaft_radius(t: Truth, y: np.ndarray) -> np.ndarray:
    """Fillet radius at height y above the joint (taper and entasis over the whole shaft)."""
    s = np.clip(y / t.shaft_length, 0.0, 1.0)
    return t.radius * (1.0 + (t.top_ratio - 1.0) * s + t.entasis * np.sin(np.pi * s))


def section_radius(t: Truth, theta: np.ndarray, r: np.ndarray, k: np.ndarray) -> np.ndarray:
    """Radius of the fluted section along rays ``theta`` for fillet radius r, flute scale k
    (1 in the body, → 0 at the flute's end): the flute ellipse's inner half
    within the flute's span, else the circle."""
    period = 2.0 * math.pi / t.flutes
    alpha = 0.5 * (period - math.radians(t.fillet_deg))
    c0 = math.radians(t.rotation_deg) + 0.5 * period
    d = (theta - c0 + 0.5 * period) % period - 0.5 * period  # angle from the flute's centre
    ak = alpha * np.clip(k, 0.0, 1.0)
    rho = r * np.sin(ak)  # half-chord of a flute narrowed to k at its end
    xc = r * np.cos(ak)  # the chord's distance from the axis: on the circle
    a, b = np.maximum(rho, 1e-9), np.maximum(t.depth * rho, 1e-9)
    # the ray (cos d, sin d)·s meets the ellipse ((x - xc)/b)² + (y/a)² = 1 nearest inside
    cx, sy = np.cos(d), np.sin(d)
    qa = (cx / b) ** 2 + (sy / a) ** 2
    qb = -2.0 * xc * cx / b**2
    qc = (xc / b) ** 2 - 1.0
    disc = qb * qb - 4.0 * qa * qc
    s_near = (-qb - np.sqrt(np.maximum(disc, 0.0))) / (2.0 * qa)  # the inner half
    inside = (np.abs(d) < ak) & (disc > 0)
    return np.where(inside, np.minimum(s_near, r), r)


def _lathe(profile: np.ndarray, n: int, rng) -> np.ndarray:
    seg = np.diff(profile, axis=0)
    w = np.hypot(seg[:, 0], seg[:, 1]) * 0.5 * (profile[1:, 0] + profile[:-1, 0])
    i = rng.choice(len(seg), n, p=w / w.sum())
    u = rng.random(n)
    p = profile[i] + u[:, None] * seg[i]
    th = rng.random(n) * 2 * math.pi
    return np.c_[p[:, 0] * np.cos(th), p[:, 1], p[:, 0] * np.sin(th)]


def _plinth(t: Truth, n: int, rng, inner: float) -> np.ndarray:
    a, h = t.plinth_half, t.plinth_height
    side = 8 * a * h
    top = 4 * a * a - math.pi * inner**2
    ns = int(n * side / (side + top))
    u, v = rng.uniform(-a, a, ns), rng.uniform(0, h, ns)
    face = rng.integers(4, size=ns)
    x = np.where(face < 2, np.where(face == 0, a, -a), u)
    z = np.where(face < 2, u, np.where(face == 2, a, -a))
    sides = np.c_[x, v, z]
    q = rng.uniform(-a, a, (3 * (n - ns), 2))
    q = q[np.hypot(q[:, 0], q[:, 1]) > inner][: n - ns]
    return np.vstack([sides, np.c_[q[:, 0], np.full(len(q), h), q[:, 1]]])


def _shaft(t: Truth, n: int, rng, y0: float) -> np.ndarray:
    y = rng.uniform(0.0, t.drum_height, n)
    th = rng.random(n) * 2 * math.pi
    r = shaft_radius(t, y)
    period = 2.0 * math.pi / t.flutes
    half = r * math.sin(0.5 * (period - math.radians(t.fillet_deg)))
    z = y - t.ring  # quarter-ellipse flute end of height = the half-chord
    k = np.where(
        z <= 0, 0.0, np.sqrt(np.clip(1 - ((half - np.minimum(z, half)) / half) ** 2, 0, 1))
    )
    rr = section_radius(t, th, r, k)
    return np.c_[rr * np.cos(th), y0 + y, rr * np.sin(th)]


def fragment_scan(
    n: int = 6000,
    *,
    truth: Truth = Truth(),
    noise: float = 0.8,
    seed: int = 0,
    unit: float = 1e-3,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A scan of a base on a square plinth carrying a fluted drum with a broken side.

    Returns
    -------
    points : (m, 3) in the scan's units (mm by default), posed
    rotation, translation : scan = column @ rotation.T + translation (column: y up, mm)
    """
    from scipy.spatial.transform import Rotation

    rng = np.random.default_rng(seed)
    prof = attic_profile(truth)
    y0 = joint_height(truth)
    areas = np.array([0.9, 1.6, 3.3])  # plinth, lathe, shaft shares (about their areas)
    k = np.round(3 * n * areas / areas.sum()).astype(int)
    pts = np.vstack(
        [
            _plinth(truth, k[0], rng, prof[0, 0]),
            _lathe(prof, k[1], rng),
            _shaft(truth, k[2], rng, y0),
        ]
    )
    # the broken side: an oblique break through the drum's upper half
    nrm = np.array([0.5, 0.6, 0.3]) / np.linalg.norm([0.5, 0.6, 0.3])
    pts = pts[(pts - [0, y0 + 0.7 * truth.drum_height, 0]) @ nrm < 0]
    ang = np.degrees(np.arctan2(pts[:, 2], pts[:, 0])) % 360  # a side against a wall
    pts = pts[~((ang > 200) & (ang < 250))]
    for _ in range(4):
        c = pts[rng.integers(len(pts))]
        pts = pts[np.linalg.norm(pts - c, axis=1) > 60.0]
    pts = pts[rng.choice(len(pts), min(n, len(pts)), replace=False)]
    pts = pts + rng.normal(0.0, noise, pts.shape)
    rot = Rotation.random(random_state=seed + 7).as_matrix()
    tr = rng.normal(0.0, 2000.0, 3)
    scale = 1e-3 / unit
    return (pts @ rot.T + tr) * scale, rot, tr * scale


def colonnade_scan(
    truths: list[Truth],
    n: int = 3000,
    *,
    spacing: float = 2800.0,
    noise: float = 0.8,
    seed: int = 0,
    tilt_deg: float = 0.3,
    stylobate: int = 0,
) -> tuple[np.ndarray, np.ndarray]:
    """Fragments from :func:`fragment_scan` (one per truth) stood upright on a line ``spacing``
    mm apart, each with a small random pose (tilt ≤ ``tilt_deg``, any turn about its axis,
    ±30 mm off the line), then one random rigid pose for the whole scan (mm). With
    ``stylobate`` (a point count) they stand on a stylobate scanned with them: its top (at the
    plinths' bottom, 1.2 m beyond the end columns' axes and 1 m either side of the line; none
    under the plinths) and its front, 300 mm high, which join all the footprints into one.

    Returns
    -------
    points : (m, 3) mm, posed
    labels : (m,) the column each point came from (-1: the stylobate)
    """
    from scipy.spatial.transform import Rotation

    rng = np.random.default_rng(seed + 100)
    parts, labels = [], []
    for i, t in enumerate(truths):
        pts, rot, tr = fragment_scan(n, truth=t, noise=noise, seed=seed + i)
        col = (pts - tr) @ rot  # back to the column's own frame: y up
        tilt = Rotation.from_rotvec(
            np.radians(tilt_deg) * rng.uniform(-1, 1) * np.array([1.0, 0.0, 0.0])
        ) * Rotation.from_rotvec(np.radians(tilt_deg) * rng.uniform(-1, 1) * np.array([0, 0, 1.0]))
        turn = Rotation.from_rotvec([0.0, rng.uniform(0, 2 * math.pi), 0.0])
        off = np.array([i * spacing, 0.0, rng.uniform(-30.0, 30.0)])
        parts.append((tilt * turn).apply(col) + off)
        labels.append(np.full(len(col), i))
    if stylobate:
        x0, x1 = -1200.0, (len(truths) - 1) * spacing + 1200.0
        m = 4 * stylobate
        top = np.c_[rng.uniform(x0, x1, m), np.zeros(m), rng.uniform(-1000.0, 1000.0, m)]
        clear = np.ones(len(top), dtype=bool)
        for i, t in enumerate(truths):  # nothing under a plinth (its turn: the corner circle)
            clear &= np.hypot(top[:, 0] - i * spacing, top[:, 2]) > t.plinth_half * math.sqrt(2)
        top = top[clear][: stylobate * 3 // 4]
        k = stylobate - len(top)
        front = np.c_[rng.uniform(x0, x1, k), rng.uniform(-300.0, 0.0, k), np.full(k, 1000.0)]
        slab = np.vstack([top, front]) + rng.normal(0.0, noise, (len(top) + k, 3))
        parts.append(slab)
        labels.append(np.full(len(slab), -1))
    pts = np.vstack(parts)
    rot = Rotation.random(random_state=seed + 11).as_matrix()
    return pts @ rot.T + rng.normal(0.0, 2000.0, 3), np.concatenate(labels)
