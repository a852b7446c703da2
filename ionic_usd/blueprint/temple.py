"""A temple's column, as values (no ``pxr``): the column its layout calls for and the column
asset it instances, shared by the API (:class:`ionic_usd.api.Temple`) and the temple's plan
(:func:`ionic_usd.blueprint.temple_plan.plan_temple`)."""

from __future__ import annotations

import dataclasses
from typing import TYPE_CHECKING

from ionic_usd.blueprint.column_asset import ColumnAssetOptions

if TYPE_CHECKING:
    from ionic_usd.column.column import ColumnParams
    from ionic_usd.temple.layout import TempleLayout

__all__ = ["temple_asset_options", "temple_column_params"]


def temple_column_params(layout: TempleLayout) -> ColumnParams:
    """The Portunus column at the layout's column height and lower diameter, on the base a
    typed temple names (``column_base``; else the Attic base with plinth)."""
    from ionic_usd.column.column import portunus_column_params

    p = layout.params
    return portunus_column_params(
        height=p.columns_height,
        lower_diameter=p.columns_lower_diameter,
        base=getattr(p, "column_base", "attic_bezier_plinth"),  # a typed temple names its base
    )


def temple_asset_options(
    column: ColumnParams,
    *,
    texture_size: int = 1024,
    seed: int = 7,
    asset_options: ColumnAssetOptions | None = None,
) -> ColumnAssetOptions:
    """The column asset a temple instances: ``asset_options`` (default: every variant, at
    ``texture_size`` and ``seed``) for ``column``, whose base is the asset's default base, with
    the carved capital (it goes with the temple's detail)."""
    opts = asset_options or ColumnAssetOptions(params=column, texture_size=texture_size, seed=seed)
    if opts.params != column:
        opts = dataclasses.replace(opts, params=column)
    if opts.bases[0] != column.base:  # the asset's default base is the column's
        opts = dataclasses.replace(
            opts, bases=(column.base, *(b for b in opts.bases if b != column.base))
        )
    if not opts.carved:
        opts = dataclasses.replace(opts, carved=True)
    return opts
