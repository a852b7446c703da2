"""What ``ionic-usd city`` can set, checked at the boundary (:class:`CityOptions`): the city
build (:mod:`ionic_usd.pipeline.city`) and its far-field cards
(:mod:`ionic_usd.pipeline.city_cards`) read it."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ionic_usd.errors import ParameterError

__all__ = ["CityOptions"]


@dataclass(frozen=True)
class CityOptions:
    """What ``ionic-usd city`` can set (defaults = the CLI's)."""

    plan: str | None = None
    rows: int = 5
    cols: int = 5
    block: float = 60.0
    columns: int | None = None
    column_spacing: float = 3.0
    variety: bool = True
    column_variety: int = 1
    temple: str | None = None  # lots that name no temple, preset or type: None = choose
    seed: int = 0
    focus: tuple[float, float] | None = None
    lod_distances: tuple[float, float] = (150.0, 400.0)
    cards_beyond: float | None = None  # None: the far LOD distance, when a focus is given
    cards: bool = True
    card_size: int = 256
    scale_range: tuple[float, float] = (0.6, 1.4)
    texture_size: int = 1024
    instancer_threshold: int | None = None
    scheduler: str | None = None
    workers: int | None = None
    memory_limit_gb: float = 4.0  # ionic_usd.resources.DEFAULT_MAX_MEMORY_GB
    force: bool = False
    prototype_cache: str | None = None  # default: $IONIC_USD_CACHE/prototypes

    def __post_init__(self) -> None:
        if self.columns is not None and (
            isinstance(self.columns, bool) or not isinstance(self.columns, int) or self.columns < 0
        ):
            raise ParameterError("--columns", self.columns, "an integer >= 0")
        if not (isinstance(self.column_variety, int) and 1 <= self.column_variety <= 16):
            raise ParameterError("--column-variety", self.column_variety, "an integer 1-16")
        near, far = self.lod_distances
        if not (np.isfinite([near, far]).all() and 0 < near <= far):
            raise ParameterError(
                "--lod-distances", self.lod_distances, "NEAR,FAR with 0 < NEAR <= FAR (m)"
            )
        if self.cards_beyond is not None and not (
            np.isfinite(self.cards_beyond) and self.cards_beyond >= 0
        ):
            raise ParameterError("--cards-beyond", self.cards_beyond, "a distance >= 0 (m)")
        cs = self.card_size
        if isinstance(cs, bool) or not isinstance(cs, int) or not 16 <= cs <= 4096:
            raise ParameterError("--card-size", cs, "an integer from 16 to 4096 pixels")
        lo, hi = self.scale_range
        if not (np.isfinite([lo, hi]).all() and 0 < lo <= hi):
            raise ParameterError("--scale-range", self.scale_range, "MIN,MAX with 0 < MIN <= MAX")
        if self.focus is not None and not np.isfinite(self.focus).all():
            raise ParameterError("--focus", self.focus, "finite X,Y (plan metres)")
        if not (np.isfinite(self.memory_limit_gb) and self.memory_limit_gb > 0):
            raise ParameterError("--max-memory", self.memory_limit_gb, "GB > 0")
        ts = self.texture_size
        if isinstance(ts, bool) or not isinstance(ts, int) or not 16 <= ts <= 8192 or ts & (ts - 1):
            raise ParameterError("--texture-size", ts, "a power of two in [16, 8192]")
        if self.scheduler is not None:
            from ionic_usd.city.address import check_scheduler_address

            check_scheduler_address(self.scheduler)
        it = self.instancer_threshold
        if it is not None and (isinstance(it, bool) or not isinstance(it, int) or it < 0):
            raise ParameterError("--instancer-threshold", it, "an integer >= 0")
        if self.temple is not None and (not isinstance(self.temple, str) or not self.temple):
            raise ParameterError("--temple", self.temple, "a description name or TOML path")
        if self.workers is not None and (not isinstance(self.workers, int) or self.workers < 1):
            raise ParameterError("--workers", self.workers, "an integer >= 1")
