"""Write the reference curves in examples/ from constructions independent of the generator.

* ``volute_twelve_centres.csv`` — a volute drawn as the treatises draw it: a square of side
  equal to the eye's radius in the eye, its half-diagonals cut into three, the twelve points
  the centres of twelve quarter circles taken corner by corner (outer square first), each
  radius the previous one less the distance between the two centres (so the arcs join
  tangentially). Nothing here calls :mod:`ionic_usd.column.volute`.
* ``base_attic.csv`` — an Attic base half-profile by Vitruvius III.5.1–2 (D = 0.95 m): height
  D/2, plinth one third of it, the rest in four: upper torus one, lower torus and scotia
  with its fillets the rest; tori as half circles, the scotia as a quarter-ellipse pair.
* ``shaft_section_semicircles.csv`` — 24 flutes as semicircles centred *on* the shaft's circle
  (the generator centres its half-ellipses on the chord), fillets a quarter of a flute.

Run: ``python tools/make_examples.py`` (overwrites the files).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

OUT = Path(__file__).resolve().parent.parent / "examples"


def twelve_centre_volute(eye_radius: float = 0.95 / 36, samples_per_arc: int = 40) -> np.ndarray:
    """(n, 2) outer spiral from the eye outward (metres, eye centre at the origin)."""
    s = eye_radius  # the square's side
    # corners of three nested squares (sides s, 2s/3, s/3), rotated 45° (on the diagonals)
    corners = []
    for k in range(3):
        h = s * (3 - k) / 3 / 2
        corners.append([(h, h), (-h, h), (-h, -h), (h, -h)])
    centres = [np.array(c) for sq in corners for c in sq]  # outermost first
    # outermost arc: radius chosen so the volute is 8 parts high (a part = 2 eye radii)
    radius = 4.5 * 2 * eye_radius - s / 2
    pts = []
    ang = math.pi / 2  # the first arc starts at the top and turns counter-clockwise
    for i, c in enumerate(centres):
        t = np.linspace(ang, ang + math.pi / 2, samples_per_arc, endpoint=False)
        pts.append(c + radius * np.column_stack([np.cos(t), np.sin(t)]))
        ang += math.pi / 2
        if i + 1 < len(centres):
            radius -= float(np.linalg.norm(centres[i + 1] - c))
    pts.append(centres[-1] + radius * np.array([math.cos(ang), math.sin(ang)]))
    return np.vstack(pts)[::-1]


def attic_base(d: float = 0.95) -> np.ndarray:
    """(n, 2) half-profile (r, y) bottom to top, metres, axis at r = 0."""
    h = d / 2
    plinth = h / 3
    rest = h - plinth
    r0 = d / 2  # the shaft's radius
    w = 0.75 * d  # half the plinth's width (the base is 1½ D wide)
    up, low = rest / 4, rest * 0.35
    fil = rest * 0.05
    sco = rest - up - low - 2 * fil
    pts = [(w, 0.0), (w, plinth)]
    # lower torus: a half circle of diameter `low` bulging out to the plinth's edge
    t = np.linspace(-math.pi / 2, math.pi / 2, 40)
    cy = plinth + low / 2
    pts += list(zip(w - low / 2 + low / 2 * np.cos(t), cy + low / 2 * np.sin(t), strict=True))
    y = plinth + low
    inner = r0 + 0.3 * (w - r0)
    pts += [(inner + 0.6 * sco, y), (inner + 0.6 * sco, y + fil)]
    # scotia: a concave quarter ellipse pair between the fillets
    t = np.linspace(0, math.pi, 50)
    pts += list(
        zip(
            inner + 0.6 * sco - 0.6 * sco * np.sin(t),
            y + fil + sco * (1 - np.cos(t)) / 2,
            strict=True,
        )
    )
    y += fil + sco
    pts += [(inner + 0.3 * sco, y), (inner + 0.3 * sco, y + fil)]
    y += fil
    t = np.linspace(-math.pi / 2, math.pi / 2, 40)
    pts += list(
        zip(r0 + up / 2 * np.cos(t) + 0.02 * d, y + up / 2 + up / 2 * np.sin(t), strict=True)
    )
    pts.append((r0, h))
    return np.asarray(pts)


def semicircle_flutes(radius: float = 0.475 * 0.93, flutes: int = 24, per: int = 24) -> np.ndarray:
    """(n, 2) closed section, counter-clockwise, first node repeated."""
    period = 2 * math.pi / flutes
    rho = radius * math.sin(period * 0.8 / 2)  # flute half-width: fillets 1/4 of a flute
    pts = []
    for k in range(flutes):
        c = (k + 0.5) * period
        cx, cy = radius * math.cos(c), radius * math.sin(c)
        a_in = 2 * math.asin(rho / (2 * radius))  # the flute's ends: on both circles
        f = np.linspace(c - period / 2, c - a_in, per // 2)
        pts += list(zip(radius * np.cos(f), radius * np.sin(f), strict=True))
        # the flute: an arc of the circle of radius rho about (cx, cy), through the inside
        a0 = math.atan2(radius * math.sin(c - a_in) - cy, radius * math.cos(c - a_in) - cx)
        a1 = math.atan2(radius * math.sin(c + a_in) - cy, radius * math.cos(c + a_in) - cx)
        d = (a1 - a0) % (2 * math.pi)
        sweep = d if (c + math.pi - a0) % (2 * math.pi) < d else d - 2 * math.pi
        t = a0 + sweep * np.linspace(0.0, 1.0, per)[1:-1]
        pts += list(zip(cx + rho * np.cos(t), cy + rho * np.sin(t), strict=True))
        g = np.linspace(c + a_in, c + period / 2, per // 2, endpoint=False)
        pts += list(zip(radius * np.cos(g), radius * np.sin(g), strict=True))
    out = np.asarray(pts)
    return np.vstack([out, out[:1]])


def main() -> None:
    OUT.mkdir(exist_ok=True)
    for name, curve, head in (
        ("volute_twelve_centres.csv", twelve_centre_volute(), "x,y"),
        ("base_attic.csv", attic_base(), "r,y"),
        ("shaft_section_semicircles.csv", semicircle_flutes(), "x,y"),
    ):
        lines = [f"# {name}: see tools/make_examples.py; metres", head]
        lines += [f"{x:.7f},{y:.7f}" for x, y in curve]
        (OUT / name).write_text("\n".join(lines) + "\n", encoding="utf-8")
        print(f"wrote {OUT / name} ({len(curve)} nodes)")


if __name__ == "__main__":
    main()
