"""Procedural, tileable stone textures (base colour, roughness, normal) and user-texture checks.

Generation is numpy only (no pxr). Every map is built from *periodic* noise: band-limited
Gaussian noise synthesised directly in the Fourier domain and brought back with an inverse
real FFT, so each field lives on a torus and the tile wraps seamlessly in both directions.

Conventions
-----------
* Style colours (:attr:`StoneStyle.base_color`, :attr:`StoneStyle.vein_color`) are given
  **sRGB-encoded** in [0, 1] (what a colour picker shows). Mixing is done in linear light and
  the result is encoded back to sRGB.
* ``StoneMaps.base_color`` is sRGB-encoded; ``roughness``, ``height`` and ``normal`` are data.
* The normal map is tangent space, **OpenGL convention (+Y up, "Y+")**: image rows run
  downwards, the tangent +X points right (increasing column) and the bitangent +Y points up
  (decreasing row). Components are encoded as ``0.5 * n + 0.5``; z > 0 always.
* Feature sizes are defined in cycles per tile, not pixels, and the random Fourier
  coefficients up to :data:`ionic_usd.texture.noise.KMAX` cycles per tile do not depend on
  ``size``: one seed gives the same stone at every resolution (a 1024 map downsampled matches
  the 512 map), which keeps LOD texture sets consistent.

Noise synthesis lives in :mod:`ionic_usd.texture.noise`, the sRGB transfer functions in
:mod:`ionic_usd.texture.colour` and file writing / user textures in
:mod:`ionic_usd.texture.files`; their public names used here are importable from this module
too.
"""

from __future__ import annotations

import math
import os
import tomllib
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path

import numpy as np

from ionic_usd.errors import ParameterError
from ionic_usd.geometry import libm
from ionic_usd.texture.colour import encode_srgb_inplace, linear_to_srgb, srgb_to_linear
from ionic_usd.texture.files import (
    MAX_USER_TEXTURE_SIZE,
    USDZ_TEXTURE_FORMATS,
    TextureError,
    copy_user_textures,
    validate_user_texture,
    verify_image,
    write_maps,
)
from ionic_usd.texture.noise import NoiseSpec, Spectrum, gauss_quantile, smoothstep

__all__ = [
    "StoneStyle",
    "StoneMaps",
    "TextureError",
    "TRAVERTINE",
    "MARBLE",
    "STUCCO_PAINTED",
    "TERRACOTTA",
    "STONE_STYLES",
    "MIN_TEXTURE_SIZE",
    "MAX_TEXTURE_SIZE",
    "MAX_USER_TEXTURE_SIZE",
    "verify_image",
    "USDZ_TEXTURE_FORMATS",
    "get_stone_style",
    "generate_stone_maps",
    "height_to_normal",
    "srgb_to_linear",
    "linear_to_srgb",
    "write_stone_textures",
    "validate_user_texture",
    "copy_user_textures",
]

MIN_TEXTURE_SIZE = 16
MAX_TEXTURE_SIZE = 8192


def _check_unit(name: str, value: float, style: str) -> None:
    if not (math.isfinite(value) and 0.0 <= value <= 1.0):
        raise ParameterError(name, value, "a finite number in [0, 1]", context=f"style {style}")


@dataclass(frozen=True)
class StoneStyle:
    """Appearance parameters of one stone.

    Parameters
    ----------
    name : str
        Identifier, also the file-name prefix of written textures (``[a-z0-9_]+``).
    base_color : (3,) float
        Mean stone colour, **sRGB-encoded**, each in [0, 1].
    vein_color : (3,) float
        Colour of veins, sRGB-encoded, each in [0, 1].
    vein_strength : float
        Opacity of the veins in [0, 1] (0: no veins).
    pore_density : float
        Fraction of the surface covered by pores / voids, in [0, 0.5].
    roughness_range : (2,) float
        ``(low, high)`` bounds of the roughness map, 0 <= low <= high <= 1.
    normal_strength : float
        Relief depth of the height field as a fraction of the tile width (the full [0, 1]
        height range spans this depth), in [0, 0.05]; 0 gives a flat normal map.
    banding : float
        Strength of horizontal sedimentary banding in [0, 1] (travertine layers).
    mottling : float
        Strength of large, soft colour clouds in [0, 1].
    pore_color : (3,) float
        sRGB-encoded colour at the bottom of pores.
    """

    name: str
    base_color: tuple[float, float, float]
    vein_color: tuple[float, float, float]
    vein_strength: float
    pore_density: float
    roughness_range: tuple[float, float]
    normal_strength: float
    banding: float = 0.0
    mottling: float = 0.3
    pore_color: tuple[float, float, float] = field(default=(0.35, 0.3, 0.24))

    def __post_init__(self) -> None:
        if not (self.name and self.name.replace("_", "").isalnum() and self.name.islower()):
            raise ParameterError("name", self.name, "a non-empty lower-case [a-z0-9_] identifier")
        for attr in ("base_color", "vein_color", "pore_color"):
            value = tuple(float(c) for c in getattr(self, attr))
            if len(value) != 3:
                raise ParameterError(attr, value, "three sRGB components", context=self.name)
            for c in value:
                _check_unit(attr, c, self.name)
            object.__setattr__(self, attr, value)
        for attr in ("vein_strength", "banding", "mottling"):
            _check_unit(attr, float(getattr(self, attr)), self.name)
        if not (math.isfinite(self.pore_density) and 0.0 <= self.pore_density <= 0.5):
            raise ParameterError(
                "pore_density", self.pore_density, "a number in [0, 0.5]", context=self.name
            )
        lo, hi = (float(v) for v in self.roughness_range)
        if not (math.isfinite(lo) and math.isfinite(hi) and 0.0 <= lo <= hi <= 1.0):
            raise ParameterError(
                "roughness_range", self.roughness_range, "0 <= low <= high <= 1", context=self.name
            )
        object.__setattr__(self, "roughness_range", (lo, hi))
        if not (math.isfinite(self.normal_strength) and 0.0 <= self.normal_strength <= 0.05):
            raise ParameterError(
                "normal_strength", self.normal_strength, "a number in [0, 0.05]", context=self.name
            )


def _load_presets() -> dict[str, StoneStyle]:
    """The preset styles of ``ionic_usd/data/stone_presets.toml``, one table each."""
    text = resources.files("ionic_usd").joinpath("data", "stone_presets.toml").read_text("utf-8")
    return {name: StoneStyle(name, **row) for name, row in tomllib.loads(text).items()}


STONE_STYLES: dict[str, StoneStyle] = _load_presets()
TRAVERTINE, MARBLE, STUCCO_PAINTED, TERRACOTTA = (
    STONE_STYLES[n] for n in ("travertine", "marble", "stucco_painted", "terracotta")
)


def get_stone_style(style: StoneStyle | str) -> StoneStyle:
    """Return ``style`` itself or the preset of that name.

    Raises
    ------
    ParameterError
        For an unknown name; the message lists the valid ones.
    """
    if isinstance(style, StoneStyle):
        return style
    if isinstance(style, str) and style in STONE_STYLES:
        return STONE_STYLES[style]
    raise ParameterError("style", style, f"one of {sorted(STONE_STYLES)} or a StoneStyle")


@dataclass(frozen=True)
class StoneMaps:
    """Texture maps of one stone tile (all float32, ``n = size``).

    Attributes
    ----------
    base_color : (n, n, 3) float32
        sRGB-encoded colour in [0, 1].
    roughness : (n, n) float32
        Data in [0, 1].
    normal : (n, n, 3) float32
        Tangent-space normal encoded as ``0.5 * n + 0.5`` (OpenGL, +Y up).
    height : (n, n) float32
        Height field in [0, 1] the normals are derived from.
    style : str
        Name of the style that made them.
    seed : int
    """

    base_color: np.ndarray
    roughness: np.ndarray
    normal: np.ndarray
    height: np.ndarray
    style: str
    seed: int

    @property
    def size(self) -> int:
        return int(self.roughness.shape[0])


def height_to_normal(height: np.ndarray, depth: float) -> np.ndarray:
    """Tangent-space unit normals of a periodic height field (OpenGL, +Y up).

    Parameters
    ----------
    height : (n, m) float
        Heights in tile-depth units: ``depth`` times ``height`` is the relief as a fraction of
        the tile width.
    depth : float
        Relief scale (fraction of the tile width per unit of height).

    Returns
    -------
    (n, m, 3) float32
        Unit normals, z > 0, *not* encoded. Gradients are periodic central differences
        (``np.roll``), so the normal map tiles like the height field.
    """
    h = np.asarray(height, dtype=np.float32)
    n_rows, n_cols = h.shape
    # Per-pixel differences rescaled to per-tile-width units: u = col / n_cols, v = -row / n_rows.
    dh_du = (np.roll(h, -1, axis=1) - np.roll(h, 1, axis=1)) * (0.5 * n_cols * depth)
    dh_dv = -(np.roll(h, -1, axis=0) - np.roll(h, 1, axis=0)) * (0.5 * n_rows * depth)
    np.negative(dh_du, out=dh_du)
    np.negative(dh_dv, out=dh_dv)
    # |(x, y, 1)| as np.linalg.norm sums the squares along the axis, (x² + y²) + 1, on planes
    # (the same float32 operations in the same order: the same bits, without the (n, m, 3)
    # temporaries and the reduction along a 3-wide axis)
    norm = np.square(dh_du)
    norm += np.square(dh_dv)
    norm += np.float32(1.0)
    np.sqrt(norm, out=norm)
    n = np.empty((n_rows, n_cols, 3), dtype=np.float32)
    np.divide(dh_du, norm, out=n[..., 0])
    np.divide(dh_dv, norm, out=n[..., 1])
    np.divide(np.float32(1.0), norm, out=n[..., 2])
    return n


def _check_size(size: object) -> int:
    if isinstance(size, bool) or not isinstance(size, (int, np.integer)):
        raise ParameterError("size", size, "an int power of two in [16, 8192]")
    s = int(size)
    if not (MIN_TEXTURE_SIZE <= s <= MAX_TEXTURE_SIZE and s & (s - 1) == 0):
        raise ParameterError("size", size, "a power of two in [16, 8192]")
    return s


def _check_seed(seed: object) -> int:
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or int(seed) < 0:
        raise ParameterError("seed", seed, "a non-negative int")
    return int(seed)


def _gauss(u: np.ndarray) -> np.ndarray:
    """exp(−u²) of float32 ``u`` by :func:`ionic_usd.geometry.libm.exp`, block by block."""
    return libm.by_blocks(lambda b: libm.exp(-np.square(b)), u.astype(np.float32, copy=False))


def generate_stone_maps(style: StoneStyle | str, size: int = 1024, seed: int = 0) -> StoneMaps:
    """Generate tileable base colour, roughness, normal and height maps.

    Parameters
    ----------
    style : StoneStyle or str
        A style or the name of a preset in :data:`STONE_STYLES`.
    size : int
        Edge length in pixels, a power of two in [16, 8192].
    seed : int
        Non-negative seed; equal seeds give identical arrays.

    Returns
    -------
    StoneMaps
        See :class:`StoneMaps` for shapes and encodings.
    """
    st = get_stone_style(style)
    n = _check_size(size)
    seed = _check_seed(seed)
    fld = Spectrum(n, seed).fields(_noise_specs(st))
    zeros = np.zeros((n, n), dtype=np.float32)
    cloud, grain = fld["cloud"], fld["grain"]
    band = fld.get("band", zeros)
    veins = _veins(st, fld) if st.vein_strength > 0.0 else zeros
    pores = zeros
    if st.pore_density > 0.0:
        # Pores cluster in the porous layers: the threshold drops where the band field is high;
        # the threshold is scaled by the std of the sum so the covered fraction stays as asked.
        coupling = 1.2 * st.banding
        t = gauss_quantile(1.0 - st.pore_density) * math.sqrt(1.0 + coupling**2)
        pores = smoothstep(t, t + 0.6, fld["pore"] + np.float32(coupling) * band)
    height = _height(st, cloud, grain, band, veins, pores)
    normal = height_to_normal(height, st.normal_strength)
    normal *= 0.5
    normal += 0.5
    np.clip(normal, 0.0, 1.0, out=normal)
    return StoneMaps(
        base_color=_base_color(st, cloud, grain, band, veins, pores),
        roughness=_roughness(st, fld["rough"], grain, veins, pores),
        normal=normal,
        height=height,
        style=st.name,
        seed=seed,
    )


def _noise_specs(st: StoneStyle) -> dict[str, NoiseSpec]:
    """The noise fields a style needs. Each field has its own random streams, so skipping an
    unused one changes no other field."""
    specs = {
        "cloud": NoiseSpec(1, beta=1.6, f_lo=1.0, f_hi=24.0),
        "grain": NoiseSpec(2, beta=0.3, f_lo=40.0, f_hi=260.0),
        "rough": NoiseSpec(7, beta=0.8, f_lo=4.0, f_hi=120.0),
    }
    if st.banding > 0.0:
        # Sedimentary layers: features 16x longer horizontally than vertically, slightly wavy.
        specs["band"] = NoiseSpec(3, 0.9, 2.0, 120.0, stretch=(16.0, 1.0), angle_deg=2.0)
    if st.vein_strength > 0.0:
        specs["vein_a"] = NoiseSpec(4, 1.3, 1.0, 64.0, stretch=(2.5, 1.0), angle_deg=35.0)
        specs["vein_b"] = NoiseSpec(5, 1.0, 3.0, 128.0, stretch=(1.5, 1.0), angle_deg=-20.0)
    if st.pore_density > 0.0:
        # Pores are elongated along the layers in banded stone.
        specs["pore"] = NoiseSpec(6, 0.0, 20.0, 140.0, stretch=(1.0 + 5.0 * st.banding, 1.0))
    return specs


def _veins(st: StoneStyle, fld: dict[str, np.ndarray]) -> np.ndarray:
    """Veins: thin neighbourhoods of the zero sets of smooth noise (meandering lines)."""
    cloud, grain, vein_a, vein_b = fld["cloud"], fld["grain"], fld["vein_a"], fld["vein_b"]
    # Widths and presence vary along each vein (large-scale cloud), so veins swell, thin out
    # and fade instead of looking like uniform contour lines.
    fade_a = smoothstep(-0.8, 0.6, cloud)
    fade_b = smoothstep(0.2, 1.4, -cloud + 0.5 * grain)
    width = np.float32(0.06) * (1.0 + 0.6 * cloud)
    # Gaussians through libm.exp (float32): the same texels on every CPU
    primary = _gauss(vein_a / np.maximum(width, 0.015))
    halo = 0.25 * _gauss(vein_a / np.float32(0.3))
    veins = np.maximum(primary, halo) * fade_a
    veins = np.maximum(veins, 0.45 * _gauss(vein_b / np.float32(0.035)) * fade_b)
    veins *= np.float32(st.vein_strength)
    return veins


def _base_color(st: StoneStyle, cloud, grain, band, veins, pores) -> np.ndarray:
    """(n, n, 3) sRGB-encoded base colour: mottled, banded, veined and pored."""
    n = cloud.shape[0]
    base = srgb_to_linear(np.array(st.base_color, dtype=np.float32))
    vein_c = srgb_to_linear(np.array(st.vein_color, dtype=np.float32))
    pore_c = srgb_to_linear(np.array(st.pore_color, dtype=np.float32))
    shade = 0.18 * st.mottling * cloud
    shade += 0.035 * grain
    shade += 1.0
    if st.banding > 0.0:
        shade += (0.16 * st.banding) * band
        shade += (0.04 * st.banding) * np.abs(band) * cloud
    # Mottling also shifts hue a little (warmer/cooler patches) so the stone is not greyscale.
    hue = np.array([1.0, 0.2, -0.8], dtype=np.float32) * np.float32(0.04 * st.mottling)
    pore_mix = 0.85 * pores
    # Per channel on 2-D planes with in-place updates: (n, n, 3) temporaries cost more in
    # page faults than in arithmetic.
    base_color = np.empty((n, n, 3), dtype=np.float32)
    for c in range(3):
        ch = hue[c] * cloud
        ch += 1.0
        ch *= shade
        ch *= base[c]
        if st.vein_strength > 0.0:
            ch += (vein_c[c] - ch) * veins
        if st.pore_density > 0.0:
            ch += (pore_c[c] - ch) * pore_mix
        base_color[..., c] = ch
    encode_srgb_inplace(base_color)
    return base_color


def _height(st: StoneStyle, cloud, grain, band, veins, pores) -> np.ndarray:
    """(n, n) height in [0, 1]."""
    height = 0.25 * grain
    height += (0.35 * st.mottling) * cloud
    if st.banding > 0.0:
        height += (0.6 * st.banding) * band
    if st.pore_density > 0.0:
        height -= 2.5 * pores
    if st.vein_strength > 0.0:
        height -= 0.1 * veins
    h_min, h_max = float(height.min()), float(height.max())
    height -= h_min
    height *= np.float32(1.0 / max(h_max - h_min, 1e-12))
    np.clip(height, 0.0, 1.0, out=height)  # float rounding can leave 1 + 1 ulp
    return height


def _roughness(st: StoneStyle, rough_f, grain, veins, pores) -> np.ndarray:
    """(n, n) roughness in the style's range."""
    lo, hi = st.roughness_range
    r = 0.2 * rough_f
    r += 0.08 * grain
    r += 0.5
    if st.pore_density > 0.0:
        r += 0.6 * pores
    if st.vein_strength > 0.0:
        r -= 0.25 * veins
    np.clip(r, 0.0, 1.0, out=r)
    r *= np.float32(hi - lo)
    r += np.float32(lo)
    return r


def write_stone_textures(
    folder: str | os.PathLike[str],
    style: StoneStyle | str,
    size: int = 1024,
    seed: int = 0,
    *,
    make_tx: bool = False,
) -> dict[str, Path]:
    """Generate a stone and write its maps as 8-bit PNGs (and optionally mipmapped ``.tx``).

    Files ``<style>_basecolor.png`` (RGB, sRGB), ``<style>_roughness.png`` (one channel, raw)
    and ``<style>_normal.png`` (RGB, raw, OpenGL +Y up) are written atomically (temporary file
    in ``folder`` then ``os.replace``); existing files are replaced. ``folder`` is created if
    needed. With ``make_tx`` also ``<style>_<map>.tx`` (tiled TIFF with a full mip chain, no
    colour conversion).

    Returns
    -------
    dict[str, Path]
        Keys ``basecolor``, ``roughness``, ``normal`` and, with ``make_tx``, ``basecolor_tx``,
        ``roughness_tx``, ``normal_tx``.
    """
    maps = generate_stone_maps(style, size, seed)
    out = Path(folder)
    out.mkdir(parents=True, exist_ok=True)
    planes = {
        "basecolor": (maps.base_color, "sRGB"),
        "roughness": (maps.roughness, "Raw"),
        "normal": (maps.normal, "Raw"),
    }
    return write_maps(out, maps.style, planes, make_tx=make_tx)
