"""A material's textures as values (no ``pxr``): what :mod:`ionic_usd.usd.materials` authors."""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["TILE_METRES", "MaterialTextures"]

TILE_METRES = 2.0  # m of stone per repeat of the tileable maps


@dataclass(frozen=True)
class MaterialTextures:
    """Anchored relative asset paths (``./Textures/…``) of one material's texture maps.

    ``basecolor`` is sRGB-encoded; ``roughness`` and ``normal`` are data (``raw``). The normal
    map is tangent space, OpenGL convention (+Y up), 8-bit: decoded with scale 2, bias −1.
    """

    basecolor: str
    roughness: str
    normal: str
