"""ionic_usd: procedural Ionic-order columns and temples authored as OpenUSD scenes.

The curated API (each name is imported on first use, so ``import ionic_usd`` stays light)::

    import ionic_usd as iu
    iu.portunus_column(lod="high").save("column.usda")     # one column, three closed parts
    iu.Temple.portunus().save("PortunusTemple")             # the default temple scene
    iu.hausdorff_distance(a, b), iu.frechet_distance(a, b)  # curve measures (m)

Build and save
    :func:`portunus_column` (the Temple of Portunus column), :func:`column` (from any
    :class:`ColumnParams`), :class:`Column` (its parts; ``.save(path)``), :class:`Temple`
    (``Temple.portunus()``, ``Temple.from_toml(path)``; ``.save(folder)``),
    :func:`portunus_column_params`, :class:`Mesh` (the kernel's immutable mesh) with
    :class:`CornerValues` (its normals and ``st``: per point or indexed per corner),
    :func:`build_city` with :class:`CityOptions` (a city of temples), :func:`export_scene`
    (glTF/GLB, usdz, STL, 3MF from any scene written here).
Compare with references (paper §VII)
    :func:`read_reference` (CSV or SVG curve), :func:`hausdorff_distance`,
    :func:`frechet_distance`, :func:`discrete_frechet_distance`, :func:`compare` (all
    measures at once), :func:`fit_volute`, :func:`fit_base`, :func:`fit_shaft` (parameters
    fitted to a reference curve).
Errors
    :class:`IonicError` (the root of every error raised here), :class:`ParameterError`,
    :class:`GrammarError`.

Everything else lives in the subpackages: ``geometry`` (numpy kernel), ``grammar``, ``column``,
``temple``, ``city``, ``texture``, ``blueprint`` (what to write, no ``pxr``), ``pipeline``,
``usd`` (the only one that imports ``pxr``), ``evaluate``, ``export``, ``cli`` (the command
line, which no other module imports); the levels of detail are ``lod``.
"""

from __future__ import annotations

from ionic_usd.lazy import lazy_attributes

__version__ = "0.1.0"

#: public name → the module that defines it
_API = {
    "Column": "ionic_usd.api",
    "Temple": "ionic_usd.api",
    "column": "ionic_usd.api",
    "portunus_column": "ionic_usd.api",
    "ColumnParams": "ionic_usd.column.column",
    "portunus_column_params": "ionic_usd.column.column",
    "Mesh": "ionic_usd.geometry.mesh",
    "CornerValues": "ionic_usd.geometry.corners",
    "CityOptions": "ionic_usd.pipeline.city",
    "build_city": "ionic_usd.pipeline.city",
    "export_scene": "ionic_usd.export",
    "read_reference": "ionic_usd.evaluate.reference",
    "hausdorff_distance": "ionic_usd.evaluate.metrics",
    "frechet_distance": "ionic_usd.evaluate.metrics",
    "discrete_frechet_distance": "ionic_usd.evaluate.metrics",
    "compare": "ionic_usd.evaluate.metrics",
    "fit_volute": "ionic_usd.evaluate.fit",
    "fit_base": "ionic_usd.evaluate.fit",
    "fit_shaft": "ionic_usd.evaluate.fit",
    "IonicError": "ionic_usd.errors",
    "ParameterError": "ionic_usd.errors",
    "GrammarError": "ionic_usd.errors",
}

__all__ = ["__version__", *_API]


__getattr__, __dir__ = lazy_attributes(__name__, _API, globals())
