"""The coordinator: prototype specs, the content-addressed prototype cache, the Dask build,
and the city build that ties them together.

The names below are imported on first use, so the ``city`` subcommand's flags
(:mod:`ionic_usd.pipeline.commands`) load without the builders behind them.
"""

from __future__ import annotations

import importlib
from typing import Any

_NAMES = {
    "CityOptions": "ionic_usd.pipeline.city",
    "build_city": "ionic_usd.pipeline.city",
    "PrototypeCache": "ionic_usd.pipeline.build",
    "build_prototypes": "ionic_usd.pipeline.build",
    "TempleSpec": "ionic_usd.pipeline.spec",
    "temple_spec": "ionic_usd.pipeline.spec",
}

__all__ = ["CityOptions", "PrototypeCache", "TempleSpec", "build_city", "build_prototypes",
           "temple_spec"]


def __getattr__(name: str) -> Any:
    module = _NAMES.get(name)
    if module is None:
        raise AttributeError(f"module 'ionic_usd.pipeline' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(__all__)
