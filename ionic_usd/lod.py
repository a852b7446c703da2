"""The levels of detail: the one registry every part of the package reads a LOD from.

A level of detail is named by a string (``"high"``, ``"medium"``, ``"low"``: the ``lod``
variant set's values, the ``--lod`` flag's, a city lot's by distance). Everything a name
decides is a field of its :class:`LevelOfDetail` here:

- ``rank``: its order, finest first (0 = high); a city stores a lot's LOD as this index into
  :data:`LOD_NAMES`, and the column asset builds its units in this order;
- ``sampling``: the :class:`LodSampling` of every part of a column;
- two texel densities (px per metre of surface), for two different purposes:

  - ``atlas_texels_per_metre`` (256 / 128 / 64): the texture API's density
    (:func:`ionic_usd.texture.uv.unwrap` and friends default to the high one): 256 px/m puts
    about 4 px on a 16 mm fillet of the Portunus shaft and gives it a 4096² atlas;
  - ``asset_texels_per_metre`` (128 / 64 / 32): the column asset's atlases. Its materials tile
    2 m stone maps, so the atlas density only sets the chart gutters (4 texels = 3 cm at
    128 px/m) and the resolution available to a later bake; packing time grows with the atlas
    area (measured when xatlas still unwrapped every part: the four parts of the high-LOD
    column took 4.3 s at 256 px/m, 2.4 s at 64 px/m), hence half the texture API's density.

Nothing here imports more than the standard library and :mod:`ionic_usd.errors`: no numpy, no
``pxr`` (the command line's flags and the city's layout read it cheaply).
"""

from __future__ import annotations

from dataclasses import dataclass

from ionic_usd.errors import ParameterError

__all__ = [
    "LEVELS",
    "LOD_NAMES",
    "LevelOfDetail",
    "LodSampling",
    "lod_rank",
    "lod_sampling",
    "level",
]


@dataclass(frozen=True)
class LodSampling:
    """Sampling of every part for one level of detail.

    ``flute_slices``/``fillet_ratio`` are the shaft's $h/$i; ``base_slices`` the rows per curved
    base floor; ``spiral_samples``, ``ring_segments``, ``bolster_rows`` the capital's;
    ``shaft_rows`` the rows along the fluted body (one row of 7 m long, 2 cm wide triangles is
    fine for a renderer but poor for displacement, booleans and LOD tools).
    """

    flute_slices: int
    fillet_ratio: int
    base_slices: int
    spiral_samples: int
    ring_segments: int
    bolster_rows: int
    shaft_rows: int = 1


@dataclass(frozen=True)
class LevelOfDetail:
    """One level of detail: its name, rank (0 = finest), sampling and texel densities (see
    the module's docstring for what each density is for)."""

    name: str
    rank: int
    sampling: LodSampling
    atlas_texels_per_metre: float
    asset_texels_per_metre: float


# Triangles of the default Portunus column (three parts): high 40,862, medium 16,054, low 7,996
# (the LOD table of docs/specification/column.md, checked by tests/test_shaft.py).
#: the levels, finest first (their rank is their index)
LEVELS: tuple[LevelOfDetail, ...] = (
    # shaft rows ≈ 0.29 m apart
    LevelOfDetail("high", 0, LodSampling(8, 4, 8, 192, 48, 32, 24), 256.0, 128.0),
    # ≈ 0.88 m
    LevelOfDetail("medium", 1, LodSampling(4, 2, 4, 96, 24, 16, 8), 128.0, 64.0),
    # ≈ 2.3 m
    LevelOfDetail("low", 2, LodSampling(2, 1, 2, 48, 16, 8, 3), 64.0, 32.0),
)

#: the names, finest first: the ``lod`` variant set's values in order
LOD_NAMES: tuple[str, ...] = tuple(lv.name for lv in LEVELS)

_BY_NAME = {lv.name: lv for lv in LEVELS}


def level(name: str) -> LevelOfDetail:
    """The level named ``name``; any other name is refused (:class:`ParameterError`)."""
    try:
        return _BY_NAME[name]
    except (KeyError, TypeError):
        raise ParameterError("lod", name, f"one of {', '.join(LOD_NAMES)}") from None


def lod_sampling(name: str) -> LodSampling | None:
    """The named level's sampling; ``custom`` (None) keeps the parts' own sampling
    parameters."""
    if name == "custom":
        return None
    if name not in _BY_NAME:
        raise ParameterError("lod", name, f"one of {', '.join(LOD_NAMES)}, custom")
    return _BY_NAME[name].sampling


def lod_rank(name: str) -> int:
    """The level's rank (0 = finest); a name that is no level ranks after them all."""
    lv = _BY_NAME.get(name)
    return len(LEVELS) if lv is None else lv.rank
