"""The coordinator: prototype specs, the content-addressed prototype cache, the Dask build,
and the city build that ties them together.

The names below are imported on first use, so the ``city`` subcommand's flags
(:mod:`ionic_usd.cli.city`) load without the builders behind them.
"""

from __future__ import annotations

from ionic_usd.lazy import lazy_attributes

_NAMES = {
    "CityOptions": "ionic_usd.pipeline.city",
    "build_city": "ionic_usd.pipeline.city",
    "PrototypeCache": "ionic_usd.pipeline.build",
    "build_prototypes": "ionic_usd.pipeline.build",
    "TempleSpec": "ionic_usd.pipeline.spec",
    "temple_spec": "ionic_usd.pipeline.spec",
}

__all__ = [
    "CityOptions",
    "PrototypeCache",
    "TempleSpec",
    "build_city",
    "build_prototypes",
    "temple_spec",
]


__getattr__, __dir__ = lazy_attributes(__name__, _NAMES, globals())
