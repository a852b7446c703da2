"""A city's instances as arrays, what :func:`ionic_usd.usd.city.compose_city` authors: the
temples (:class:`TempleInstances`) and the street columns (:class:`ColumnInstances`)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

__all__ = ["ColumnInstances", "TempleInstances"]


@dataclass(frozen=True)
class TempleInstances:
    """Temples of a city as arrays (n temples, b builds).

    Attributes
    ----------
    folders : (b,) build folders relative to the city (``Temples/<name>-<key>``)
    build : (n,) int — build of each temple
    names : (n,) lot ids
    xz : (n, 2) float — USD x, z translation; yaw : (n,) degrees about +Y; scale : (n,)
    selections : (n,) hypothesis id → "baseline" | "alternative" per temple (ids the build
        does not realise are ignored)
    lod : (n,) int8 index into LOD_NAMES, or None (no lod selection)
    cards : (n,) bool — drawn as cards (far field), or None (none); a card temple's prototype
        carries ``UsdGeomModelAPI`` draw mode cards with the images of ``card_dirs``
    """

    folders: Sequence[str]
    build: np.ndarray
    names: Sequence[str]
    xz: np.ndarray
    yaw: np.ndarray
    scale: np.ndarray
    selections: Sequence[Mapping[str, str]]
    lod: np.ndarray | None = None
    cards: np.ndarray | None = None

    def __len__(self) -> int:
        return len(self.build)


@dataclass(frozen=True)
class ColumnInstances:
    """Street columns as arrays: ``asset`` (city-relative path of the column asset folder's
    root layer), ``xz`` (m, 2), ``yaw`` (m,) degrees, ``lod`` (m,) int8 (None: all low),
    ``cards`` (m,) bool — drawn by the card prototype (far field), or None (none)."""

    asset: str
    xz: np.ndarray
    yaw: np.ndarray
    lod: np.ndarray | None = None
    cards: np.ndarray | None = None

    def __len__(self) -> int:
        return len(self.xz)
