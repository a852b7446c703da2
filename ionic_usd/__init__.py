"""ionic_usd: procedural Ionic-order columns and temples authored as OpenUSD scenes.

The curated API (imported on first use, so ``import ionic_usd`` stays light)::

    import ionic_usd as iu
    iu.portunus_column(lod="high").save("column.usda")     # one column, three closed parts
    iu.Temple.portunus().save("PortunusTemple")             # the default temple scene
    iu.hausdorff_distance(a, b), iu.frechet_distance(a, b)  # curve measures (m)

Everything else lives in the subpackages: ``geometry`` (numpy kernel), ``grammar``, ``column``,
``temple``, ``texture``, ``usd`` (the only one that imports ``pxr``), ``evaluate``, ``export``.
"""

from __future__ import annotations

from typing import Any

__version__ = "0.1.0"

_API = {
    "Column": "ionic_usd.api",
    "Temple": "ionic_usd.api",
    "column": "ionic_usd.api",
    "portunus_column": "ionic_usd.api",
    "ColumnParams": "ionic_usd.column.column",
    "portunus_column_params": "ionic_usd.column.column",
    "Mesh": "ionic_usd.geometry.mesh",
    "IonicError": "ionic_usd.errors",
    "hausdorff_distance": "ionic_usd.evaluate.metrics",
    "frechet_distance": "ionic_usd.evaluate.metrics",
    "discrete_frechet_distance": "ionic_usd.evaluate.metrics",
}

__all__ = ["__version__", *_API]


def __getattr__(name: str) -> Any:
    module = _API.get(name)
    if module is None:
        raise AttributeError(f"module 'ionic_usd' has no attribute {name!r}")
    import importlib

    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(__all__)
