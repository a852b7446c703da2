"""An independent synthetic scan of a whole Ionic column, capital included (issue 36).

Not the project's model: the base and the fluted shaft are those of :mod:`synth_scan` (a
square plinth, an Attic profile with a sine scotia, ray–ellipse flutes), here over the
whole shaft with quarter-ellipse flute ends and a plain ring at both ends; the capital is
built here from simple analytic surfaces — an echinus (a quarter-ellipse lathe) showing
in front of and behind the volutes, a cushion whose two faces carry Archimedean volutes (3
turns: a flat fillet and a sine channel between the turns, a flat eye) joined by a sine
canalis, the volutes' rolls (circles swept between the faces) and a square abacus (a box)
— then Gaussian noise, a hidden sector, holes and a random rigid pose, in mm.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from synth_scan import Truth, _lathe, _plinth, attic_profile, joint_height, section_radius


@dataclass(frozen=True)
class CapitalTruth:
    """The capital's dimensions (mm at a 400 mm shaft radius; scaled with it)."""

    echinus_top: float = 120.0  # height of the echinus (and of the volutes' eyes)
    echinus_radius: float = 410.0  # its radius at the top
    eye_x: float = 390.0  # the volutes' eyes, either side of the axis
    volute_radius: float = 110.0
    face: float = 340.0  # the cushion's faces at z = ±face
    channel: float = 9.0  # depth of the volute's channel and of the canalis
    turns: float = 3.0
    eye_radius: float = 14.0
    fillet: float = 0.2  # share of a turn's pitch that is flat fillet
    abacus_half: float = 480.0
    abacus_height: float = 60.0


def _ring_scale(y: np.ndarray, ring: float, half: np.ndarray) -> np.ndarray:
    """Flute scale k (0 on the plain ring, 1 in the body) with quarter-ellipse ends."""
    z = y - ring
    return np.where(
        z <= 0, 0.0, np.sqrt(np.clip(1 - ((half - np.minimum(z, half)) / half) ** 2, 0, 1))
    )


def _whole_shaft(t: Truth, n: int, rng, y0: float) -> np.ndarray:
    """Points on the whole shaft (length ``t.shaft_length``) above the joint at ``y0``."""
    from synth_scan import shaft_radius

    L = t.shaft_length
    y = rng.uniform(0.0, L, n)
    th = rng.random(n) * 2 * math.pi
    r = shaft_radius(t, y)
    period = 2.0 * math.pi / t.flutes
    half = r * math.sin(0.5 * (period - math.radians(t.fillet_deg)))
    k = np.minimum(_ring_scale(y, t.ring, half), _ring_scale(L - y, t.ring, half))
    rr = section_radius(t, th, r, k)
    return np.c_[rr * np.cos(th), y0 + y, rr * np.sin(th)]


def _volute_depth(c: CapitalTruth, dx: np.ndarray, dy: np.ndarray) -> np.ndarray:
    """Depth (mm, ≥ 0) of the volute's face at (dx, dy) from its eye: 0 on the fillet and
    the eye, a sine channel between the turns of the Archimedean spiral
    rho = R - (R - eye) theta / (2 pi turns) (theta from the top, turning outwards-down)."""
    rho = np.hypot(dx, dy)
    pitch = (c.volute_radius - c.eye_radius) / c.turns
    phi = np.arctan2(dx, dy) % (2 * math.pi)  # 0 at the top, growing towards +x
    # the spiral's radius at this angle on the turn just outside: R - pitch (phi/2pi + m)
    u = ((c.volute_radius - rho) / pitch - phi / (2 * math.pi)) % 1.0
    groove = np.clip((u - c.fillet) / (1.0 - c.fillet), 0.0, 1.0)
    d = c.channel * np.sin(math.pi * groove)
    return np.where(rho <= c.eye_radius, 0.0, d)


def _capital(c: CapitalTruth, t: Truth, n: int, rng, y0: float) -> np.ndarray:
    """Points on the capital whose bottom (the echinus' foot) is at ``y0``."""
    sc = t.radius / 400.0
    top_r = t.radius * t.top_ratio / sc  # the shaft's top radius, in the 400 mm drawing
    ye, R, xe, C = c.echinus_top, c.volute_radius, c.eye_x, c.face
    ya = ye + R  # the cushion's top, under the abacus
    A, H = c.abacus_half, c.abacus_height
    out = []
    # the echinus: a quarter ellipse from the shaft's top radius out to its top radius
    s = np.linspace(0.0, 0.5 * math.pi, 200)
    prof = np.c_[top_r + (c.echinus_radius - top_r) * np.sin(s), ye * (1 - np.cos(s))]
    prof = np.vstack([prof, [[0.0, ye]]])  # and its flat top
    e = _lathe(prof, 4 * n, rng)
    in_roll = (np.hypot(np.abs(e[:, 0]) - xe, e[:, 1] - ye) < R) & (np.abs(e[:, 2]) <= C)
    under = (np.abs(e[:, 2]) <= C) & (np.abs(e[:, 0]) <= xe) & (e[:, 1] >= ye - 1e-9)
    out.append(e[~in_roll & ~under][: n // 5])
    # the cushion's faces at z = ±C: the volutes' disks and the canalis between them
    m = 6 * n
    x, y = rng.uniform(-(xe + R), xe + R, m), rng.uniform(ye - R, ya, m)
    side = rng.choice([-1.0, 1.0], m)
    dx = np.abs(x) - xe
    disk = np.hypot(dx, y - ye) <= R
    band = (np.abs(x) <= xe) & (y >= ye)
    keep = disk | band
    # the volute turns outwards-down on either side: mirror x on the left
    depth = np.where(disk, _volute_depth(c, dx, y - ye), 0.0)
    canalis = band & ~disk
    depth = np.where(canalis, c.channel * np.sin(math.pi * (ya - y) / R), depth)
    z = side * (C - depth)
    out.append(np.c_[x, y, z][keep][: 2 * n // 5])
    # the rolls: the volutes' outer circles swept between the faces (outside the cushion)
    m = 2 * n
    a = rng.uniform(0.0, 2 * math.pi, m)
    sgn = rng.choice([-1.0, 1.0], m)
    rx, ry = xe + R * np.cos(a), ye + R * np.sin(a)
    roll = np.c_[sgn * rx, ry, rng.uniform(-C, C, m)]
    r_e = np.interp(roll[:, 1], prof[:-1, 1], prof[:-1, 0], right=-1.0)
    hid = ((rx <= xe) & (ry >= ye)) | (np.hypot(roll[:, 0], roll[:, 2]) < r_e)
    out.append(roll[~hid][: n // 5])
    # the abacus: a square box on the cushion; its underside where nothing is under it
    m = n
    f = rng.integers(6, size=m)
    u, v, w = rng.uniform(-A, A, m), rng.uniform(-A, A, m), rng.uniform(ya, ya + H, m)
    box = np.where(
        (f < 4)[:, None],
        np.c_[
            np.where(f < 2, np.where(f == 0, A, -A), u),
            w,
            np.where(f < 2, u, np.where(f == 2, A, -A)),
        ],
        np.c_[u, np.where(f == 4, ya + H, ya), v],
    )
    below = (f == 5) & (np.abs(box[:, 2]) <= C) & (np.abs(box[:, 0]) <= xe)
    out.append(box[~below][: n // 5])
    pts = np.vstack(out)
    return np.c_[sc * pts[:, 0], y0 + sc * pts[:, 1], sc * pts[:, 2]]


def capital_height(c: CapitalTruth, t: Truth) -> float:
    return t.radius / 400.0 * (c.echinus_top + c.volute_radius + c.abacus_height)


def column_scan(
    counts: tuple[int, int, int] = (3000, 6000, 4000),
    *,
    truth: Truth | None = None,
    capital: CapitalTruth = CapitalTruth(),
    noise: float = 0.8,
    seed: int = 0,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """A scan of a whole column: base, shaft and capital (``counts`` points each, before the
    hidden sector and the holes), mm.

    Returns
    -------
    points : (m, 3) mm, posed
    part : (m,) 0 base, 1 shaft, 2 capital
    rotation, translation : scan = column @ rotation.T + translation (column: y up, mm)
    """
    from scipy.spatial.transform import Rotation

    truth = Truth() if truth is None else truth
    rng = np.random.default_rng(seed)
    prof = attic_profile(truth)
    y0 = joint_height(truth)
    nb = counts[0]
    base = np.vstack([_plinth(truth, nb // 3, rng, prof[0, 0]), _lathe(prof, nb - nb // 3, rng)])
    shaft = _whole_shaft(truth, counts[1], rng, y0)
    cap = _capital(capital, truth, counts[2], rng, y0 + truth.shaft_length)
    pts = np.vstack([base, shaft, cap])
    part = np.repeat([0, 1, 2], [len(base), len(shaft), len(cap)])
    ang = np.degrees(np.arctan2(pts[:, 2], pts[:, 0])) % 360  # a side against a wall
    keep = ~((ang > 200) & (ang < 250))
    for _ in range(5):
        c = pts[rng.integers(len(pts))]
        keep &= np.linalg.norm(pts - c, axis=1) > 60.0
    pts, part = pts[keep], part[keep]
    pts = pts + rng.normal(0.0, noise, pts.shape)
    rot = Rotation.random(random_state=seed + 13).as_matrix()
    tr = rng.normal(0.0, 2000.0, 3)
    return pts @ rot.T + tr, part, rot, tr
