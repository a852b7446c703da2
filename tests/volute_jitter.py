"""A hand-carved volute for the tests: the twelve-centre treatise construction (Alberti,
Vignola: three nested squares of centres on the eye's diagonals) with every arc a little off.

Each arc's radius is scaled by up to ±``jitter`` and each centre moved by up to ``jitter`` of
the arc's radius; the arcs are then re-joined tangentially, as a carver redrawing from the
next centre would: arc ``j + 1`` keeps its (jittered) radius and its centre goes where tangency
with arc ``j`` allows nearest to the jittered centre (on the line through arc ``j``'s centre),
which moves the joint. The curve is sampled at a fixed spacing and digitised with Gaussian
noise. Independent of the package's own models (no import from ionic_usd).
"""

from __future__ import annotations

import math

import numpy as np


def _nominal(eye_radius: float) -> tuple[list[np.ndarray], list[float]]:
    s = eye_radius
    centres = []
    for k in range(3):
        h = s * (3 - k) / 6
        centres += [np.array(c) for c in ((h, h), (-h, h), (-h, -h), (h, -h))]
    radii = [9.0 * s - s / 2]
    for a, b in zip(centres[:-1], centres[1:], strict=True):
        radii.append(radii[-1] - float(np.linalg.norm(b - a)))
    return centres, radii


def carved_volute(
    diameter: float,
    *,
    jitter: float = 0.015,
    noise: float = 1.5e-4,
    spacing: float | None = None,
    seed: int = 0,
) -> np.ndarray:
    """(n, 2) outer spiral edge from the eye outward, metres, eye near the origin.

    Parameters
    ----------
    diameter : the column's lower diameter (the eye's radius is D/36)
    jitter : largest relative error of radii and centres (0: the exact construction)
    noise : standard deviation of the digitising noise (m)
    spacing : distance between samples (default: D/600)
    """
    rng = np.random.default_rng(seed)
    centres, radii = _nominal(diameter / 36.0)
    radii = [r * (1.0 + jitter * rng.uniform(-1, 1)) for r in radii]
    want = [
        c + jitter * r * _unit(rng.uniform(0, 2 * math.pi))
        for c, r in zip(centres, radii, strict=True)
    ]
    spacing = spacing or diameter / 600.0
    c, ang = want[0], math.pi / 2  # the outermost arc starts at the top, turning left
    pts = []
    for j, r in enumerate(radii):
        if j + 1 < len(radii):
            # tangent joint: the next centre at c + (r − r')·u(φ), φ towards the wanted centre
            d = want[j + 1] - c
            phi = math.atan2(d[1], d[0])
            end = ang + (phi - ang) % (2 * math.pi)
        else:
            end = ang + math.pi / 2
        n = max(2, int(math.ceil(r * (end - ang) / spacing)))
        t = np.linspace(ang, end, n, endpoint=False)
        pts.append(c + r * np.column_stack([np.cos(t), np.sin(t)]))
        if j + 1 < len(radii):
            c = c + (r - radii[j + 1]) * _unit(end)
        ang = end
    pts.append(c + radii[-1] * _unit(ang)[None, :])
    curve = np.vstack(pts)[::-1]
    return curve + rng.normal(0.0, noise, curve.shape)


def _unit(a: float) -> np.ndarray:
    return np.array([math.cos(a), math.sin(a)])
