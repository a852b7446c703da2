"""A temple's massing shared by every way of laying one out: the :class:`TempleLayout` value,
the podium, the roof over the cornice and the corner columns' quarter turn (frame of
:mod:`ionic_usd.temple.layout`). :mod:`ionic_usd.temple.layout` (a temple's own tables) and
:mod:`ionic_usd.temple.typed_layout` (a Vitruvian type) both build on it, so neither imports
the other's internals."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any

from ionic_usd.errors import ParameterError
from ionic_usd.temple.cuboid import Cuboid, Incline
from ionic_usd.temple.description import (
    ColumnKind,
    ColumnPlacement,
    Hypothesis,
    Layer,
    TempleParams,
    enum_value,
)

__all__ = ["TempleLayout", "ROOF_BED", "box", "podium_cuboids", "roof_cuboids", "outer_rotation"]


@dataclass(frozen=True, eq=False)
class TempleLayout:
    """A temple as values for the composer.

    Parameters
    ----------
    name : str
    cuboids : Mapping[Layer, tuple[Cuboid, ...]]
        Closed solids per layer (build meshes with :func:`~ionic_usd.temple.cuboid_mesh`).
    columns : tuple[ColumnPlacement, ...]
    params : TempleParams
        The dimensions used (after ``applied`` hypotheses).
    hypotheses : tuple[Hypothesis, ...]
        All alternatives recorded in the source TOML.
    applied : tuple[str, ...]
        Ids of the hypotheses whose temple keys were applied.
    """

    name: str
    cuboids: Mapping[Layer, tuple[Cuboid, ...]]
    columns: tuple[ColumnPlacement, ...]
    params: TempleParams
    hypotheses: tuple[Hypothesis, ...] = ()
    applied: tuple[str, ...] = ()
    # per-part evidence (ionic_usd.temple.paradata.Paradata); None: stated nowhere
    paradata: Any = None

    def __post_init__(self) -> None:
        groups = {
            enum_value(Layer, k, "layer", self.name): tuple(v) for k, v in self.cuboids.items()
        }
        object.__setattr__(self, "cuboids", MappingProxyType(groups))
        object.__setattr__(self, "columns", tuple(self.columns))
        object.__setattr__(self, "hypotheses", tuple(self.hypotheses))
        object.__setattr__(self, "applied", tuple(self.applied))

    def all_cuboids(self) -> tuple[Cuboid, ...]:
        return tuple(c for cs in self.cuboids.values() for c in cs)

    def columns_of(self, kind: ColumnKind | str) -> tuple[ColumnPlacement, ...]:
        k = ColumnKind(kind)
        return tuple(c for c in self.columns if c.kind is k)

    def cuboid(self, name: str) -> Cuboid:
        for c in self.all_cuboids():
            if c.name == name:
                return c
        raise ParameterError("name", name, "the name of one of the layout's cuboids")

    @property
    def stylobate_height(self) -> float:
        return self.params.podium_height

    @property
    def pitch_deg(self) -> float:
        return self.params.pitch_deg

    @property
    def axial_spacing(self) -> float:
        return self.params.axial_spacing


def box(name, x0, y0, z0, x1, y1, z1, rise=0.0, incline=Incline.SHEAR) -> Cuboid:
    """A named cuboid from its two corners (and its slab rise / incline)."""
    return Cuboid((x0, y0, z0), (x1, y1, z1), rise, incline, name=name)


def podium_cuboids(p: TempleParams) -> list[Cuboid]:
    """The podium: footing, die, cheek walls and steps (:mod:`ionic_usd.temple.layout`)."""
    w2, l2, pr = p.stylobate_width / 2, p.stylobate_length / 2, p.footing_projection
    fh, h, cw, run = (
        p.podium_footing_height,
        p.podium_height,
        p.podium_cheek_wall_width,
        p.stair_run,
    )
    front = l2 + run
    out = [
        box("footing", -w2 - pr, 0.0, -l2 - pr, w2 + pr, fh, l2),
        box("die", -w2, fh, -l2, w2, h, l2),
    ]
    for side, sgn in (("left", -1.0), ("right", 1.0)):
        xs = sorted((sgn * (w2 - cw), sgn * (w2 + pr)))
        out.append(box(f"cheek_footing_{side}", xs[0], 0.0, l2, xs[1], fh, front + pr))
        xs = sorted((sgn * (w2 - cw), sgn * w2))
        out.append(box(f"cheek_wall_{side}", xs[0], fh, l2, xs[1], h, front))
    n = p.steps_count
    riser, tread = h / n, run / n
    for i in range(n):
        out.append(
            box(
                f"step_{i + 1:02d}",
                -(w2 - cw),
                i * riser,
                l2,
                w2 - cw,
                (i + 1) * riser,
                l2 + (n - i) * tread,
            )
        )
    return out


# (!) assumption: the roof's bed on the cornice at the eaves (mortar and tile bedding), so the
# gable wedges have an outer face there; 5 cm.
ROOF_BED = 0.05


def roof_cuboids(p: TempleParams, y: float, xe: float, ze: float, proj: float) -> list[Cuboid]:
    """The two roof slabs and the gable wedges on a cornice topping at ``y``."""
    tan = 2.0 / p.roof_tympanum_ratio
    xc, zc = xe + proj, ze + proj
    h = xc * tan  # the slab soffit's rise from the eaves to the ridge = width / tympanum_ratio
    s = p.roof_slab_thickness
    yb = y + ROOF_BED
    return [
        box("roof_left", -xc, yb, -zc, 0.0, yb + s, zc, h),
        box("roof_right", 0.0, yb + h, -zc, xc, yb + h + s, zc, -h),
        box("pediment_left", -xc, y, -ze, 0.0, yb, ze, h, Incline.WEDGE),
        box("pediment_right", 0.0, y, -ze, xc, yb + h, ze, -h, Incline.WEDGE),
    ]


def outer_rotation(sx: float, sz: float) -> float:
    """The quarter-turn rotation taking local +Z and +X to the outer sides ``(sx, 0, 0)`` and
    ``(0, 0, sz)`` (signs ±1) of a corner, in one order or the other."""
    for deg in (0.0, 90.0, 180.0, -90.0):
        t = math.radians(deg)
        facing = (round(math.sin(t)), round(math.cos(t)))  # local +Z as (x, z)
        xaxis = (round(math.cos(t)), round(-math.sin(t)))  # local +X as (x, z)
        if {facing, xaxis} == {(int(sx), 0), (0, int(sz))}:
            return deg
    raise AssertionError("unreachable: two perpendicular sides have a quarter turn")
