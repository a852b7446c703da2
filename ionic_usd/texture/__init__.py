"""Texturing: UVs (xatlas; analytic charts where exact) and procedural stone maps (OpenImageIO).

Modules, by what a reader looks for:

* :mod:`~ionic_usd.texture.uv` — xatlas unwrapping, one texel density across parts;
* :mod:`~ionic_usd.texture.atlas` — atlas values, the common normalising size, packing of the
  analytic charts the base and shaft generators emit;
* :mod:`~ionic_usd.texture.uv_cache` — atlases by content key, in memory and on disk;
* :mod:`~ionic_usd.texture.stone` — stone styles and maps; :mod:`~ionic_usd.texture.noise` the
  periodic noise they are made of; :mod:`~ionic_usd.texture.colour` the sRGB transfer
  functions; :mod:`~ionic_usd.texture.files` PNG/``.tx`` writing and user textures.

Names are imported on first use (PEP 562), so ``import ionic_usd.texture`` loads neither
xatlas nor OpenImageIO.
"""

from __future__ import annotations

import importlib
from typing import Any

_WHERE = {
    "DEFAULT_PADDING": "atlas",
    "DEFAULT_RESOLUTION_CAP": "atlas",
    "DEFAULT_TEXELS_PER_METRE": "atlas",
    "UVAtlas": "atlas",
    "analytic_atlas": "atlas",
    "attach_uvs": "atlas",
    "common_atlas_size": "atlas",
    "UVCache": "uv_cache",
    "default_cache": "uv_cache",
    "default_cache_folder": "uv_cache",
    "uv_cache_key": "uv_cache",
    "apply_uvs": "uv",
    "prefetch": "uv",
    "unwrap": "uv",
    "unwrap_parts": "uv",
    "MARBLE": "stone",
    "MAX_TEXTURE_SIZE": "stone",
    "MIN_TEXTURE_SIZE": "stone",
    "STONE_STYLES": "stone",
    "STUCCO_PAINTED": "stone",
    "TRAVERTINE": "stone",
    "StoneMaps": "stone",
    "StoneStyle": "stone",
    "generate_stone_maps": "stone",
    "get_stone_style": "stone",
    "height_to_normal": "stone",
    "write_stone_textures": "stone",
    "linear_to_srgb": "colour",
    "srgb_to_linear": "colour",
    "USDZ_TEXTURE_FORMATS": "files",
    "TextureError": "files",
    "copy_user_textures": "files",
    "validate_user_texture": "files",
}

__all__ = sorted(_WHERE)


def __getattr__(name: str) -> Any:
    if name not in _WHERE:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(f"{__name__}.{_WHERE[name]}"), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_WHERE))
