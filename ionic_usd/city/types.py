"""A temple type chosen for a city lot (``temple = "auto"``): seeded, fitted to the lot.

The lot's minimum rotated rectangle gives its width and depth; a seeded draw picks an
arrangement, a front column count (:data:`~ionic_usd.temple.vitruvius.FRONTS`) and an
intercolumniation (Vitruvius III.2–3), and the lower diameter follows from the front's
division (III.3.7) so that the temple's plan (steps and stairs included) takes :data:`FILL` of
the lot's width — or less, when its length would not fit :data:`FILL` of its depth. The
result is a typed temple description (TOML text) the city builds like any other; the city
still fits it into the lot (within its scale limits). Pure Python + numpy (shapely for the
rectangle).
"""

from __future__ import annotations

import numpy as np

from ionic_usd.temple.vitruvius import (
    FRONTS,
    Arrangement,
    Intercolumniation,
    TempleType,
)

__all__ = ["FILL", "lot_size", "choose_type"]

FILL = 0.8  # share of the lot the stylobate may take (the rest: steps, footing, the street)


def lot_size(outline: np.ndarray) -> tuple[float, float]:
    """(width, depth) of the lot's minimum rotated rectangle, width ≤ depth, metres."""
    import shapely

    rect = np.asarray(shapely.minimum_rotated_rectangle(shapely.Polygon(outline)).exterior.coords)
    a = float(np.hypot(*(rect[1] - rect[0])))
    b = float(np.hypot(*(rect[2] - rect[1])))
    return min(a, b), max(a, b)


def _footprint(t: TempleType) -> tuple[float, float]:
    """(width, length) of a type's plan: every cuboid's x and z extent."""
    from ionic_usd.temple.typed_layout import type_layout

    cs = type_layout(t).all_cuboids()
    x = max(max(abs(c.min[0]), abs(c.max[0])) for c in cs)
    z0, z1 = min(c.min[2] for c in cs), max(c.max[2] for c in cs)
    return 2 * x, z1 - z0


def choose_type(
    width: float,
    depth: float,
    rng: np.random.Generator,
    *,
    arrangement: str | None = None,
    front: int | None = None,
    intercolumniation: str | None = None,
    lower_diameter: float | None = None,
) -> tuple[str, str]:
    """A seeded type fitted to a ``width`` × ``depth`` lot: (slug, TOML text). What the lot
    names (``arrangement``, ``front``, ``intercolumniation``, ``lower_diameter``) is kept; the
    draws are made all the same, so a named key does not shift the others."""
    arrangements = list(Arrangement)
    arr = arrangements[int(rng.integers(len(arrangements)))]
    if arrangement is not None:
        arr = Arrangement(arrangement)
    drawn_front = int(FRONTS[arr][int(rng.integers(len(FRONTS[arr])))])
    front = drawn_front if front is None else int(front)
    ics = list(Intercolumniation)
    ic = ics[int(rng.integers(len(ics)))]
    if intercolumniation is not None:
        ic = Intercolumniation(intercolumniation)
    d = 1.0
    for _ in range(3):  # the footprint (steps, stairs) is nearly proportional to D
        t = TempleType(
            arrangement=arr.value, front=front, intercolumniation=ic.value, lower_diameter=d
        )
        fw, fl = _footprint(t)
        d = round(float(d * min(FILL * width / fw, FILL * depth / fl)), 3)
    if lower_diameter is not None:
        d = float(lower_diameter)
    slug = f"{arr.value}-{front}-{ic.value}"
    text = (
        f'[temple]\nname = "{slug} (chosen for the lot)"\n\n[type]\n'
        f'arrangement = "{arr.value}"\nfront = {front}\nintercolumniation = "{ic.value}"\n'
        f"lower_diameter = {d!r}\n"
    )
    return slug, text
