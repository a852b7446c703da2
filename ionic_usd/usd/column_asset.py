"""The Ionic column as a USD component asset: :func:`author_column_asset` writes the layers of
the asset that :func:`ionic_usd.blueprint.column_asset.column_asset_spec` describes.

The variant sets, build options and texture conventions are described (and defined, without
``pxr``) in :mod:`ionic_usd.blueprint.column_asset`, whose names this module hands on; the
pipeline that makes the meshes (generate → clip → UV → texture) is
:mod:`ionic_usd.pipeline.asset`, whose :func:`~ionic_usd.pipeline.asset.build_column_asset` is
the entry point.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Sequence
from pathlib import Path

from ionic_usd.blueprint.asset import AssetInstancer, AssetMesh
from ionic_usd.blueprint.column_asset import (
    ASSET_NAME,
    BASE_CHART_BOUNDARY,
    BASE_VARIANTS,
    CAPITAL_VARIANTS,
    ENGAGED_INSET,
    FINISHES,
    FLUTE_VARIANTS,
    FORM_VARIANTS,
    SCROLL_VARIANTS,
    TILE_METRES,
    UV_SPAN,
    VOLUTE_VARIANTS,
    ColumnAssetOptions,
    column_asset_spec,
    volute_variant_params,
)
from ionic_usd.usd.asset import write_asset

__all__ = [
    "ColumnAssetOptions",
    "author_column_asset",
    "column_asset_spec",
    "volute_variant_params",
    "ASSET_NAME",
    "BASE_CHART_BOUNDARY",
    "BASE_VARIANTS",
    "SCROLL_VARIANTS",
    "FLUTE_VARIANTS",
    "FORM_VARIANTS",
    "CAPITAL_VARIANTS",
    "VOLUTE_VARIANTS",
    "FINISHES",
    "ENGAGED_INSET",
    "UV_SPAN",
    "TILE_METRES",
]


def author_column_asset(
    folder: str | os.PathLike,
    opts: ColumnAssetOptions,
    meshes: Sequence[AssetMesh],
    instancers: Sequence[AssetInstancer] = (),
    *,
    populate: Callable[[Path], None] | None = None,
    force: bool = False,
    key: str | None = None,
    record: dict | None = None,
) -> Path:
    """Author the asset folder from kernel values (see :func:`column_asset_spec`);
    ``populate(tmp)`` puts the textures in after the layers; ``key`` and ``record`` go to the
    folder's manifest (:func:`ionic_usd.io.replace_folder`). Returns the interface layer's
    path."""
    return write_asset(
        column_asset_spec(opts, meshes, instancers),
        folder,
        populate=populate,
        force=force,
        key=key,
        record=record,
    )
