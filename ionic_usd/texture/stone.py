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
  coefficients up to :data:`_KMAX` cycles per tile do not depend on ``size``: one seed gives the
  same stone at every resolution (a 1024 map downsampled matches the 512 map), which keeps
  LOD texture sets consistent.
"""

from __future__ import annotations

import functools
import math
import os
import shutil
from collections.abc import Mapping
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import IonicError, ParameterError

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
MAX_USER_TEXTURE_SIZE = 16384  # pixels per side of a user texture, checked before decoding

#: OpenImageIO format names allowed inside a USDZ package, with the file extensions that
#: must go with them (USD's image plugins choose the reader by extension).
USDZ_TEXTURE_FORMATS: dict[str, tuple[str, ...]] = {
    "png": (".png",),
    "jpeg": (".jpg", ".jpeg"),
}

# Highest frequency (cycles per tile) drawn from the size-independent random stream.
_KMAX = 512
# Edge of the independently seeded cells of the Fourier-coefficient grid.
_CELL = 64
# Offset of the stream ids that draw frequencies beyond _KMAX (tiles larger than 1024).
_HIGH_STREAM = 1000


class TextureError(IonicError, ValueError):
    """A texture file is missing, unreadable or in a format USDZ does not allow.

    Carries the offending ``path`` and a human-readable ``problem``.
    """

    def __init__(self, path: str | os.PathLike[str], problem: str) -> None:
        self.path = Path(path)
        self.problem = problem
        super().__init__(f"texture {str(self.path)!r}: {problem}")


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


# Temple of Portunus: travertine (columns, facing) and tufa: warm cream, horizontal layers with
# small elongated voids lying along them.
TRAVERTINE = StoneStyle(
    name="travertine",
    base_color=(0.84, 0.76, 0.62),
    vein_color=(0.72, 0.62, 0.47),
    vein_strength=0.15,
    pore_density=0.045,
    roughness_range=(0.55, 0.9),
    normal_strength=0.004,
    banding=0.8,
    mottling=0.35,
    pore_color=(0.5, 0.42, 0.3),
)
MARBLE = StoneStyle(
    name="marble",
    base_color=(0.91, 0.90, 0.88),
    vein_color=(0.45, 0.46, 0.48),
    vein_strength=0.75,
    pore_density=0.0,
    roughness_range=(0.12, 0.3),
    normal_strength=0.0008,
    banding=0.0,
    mottling=0.2,
    pore_color=(0.6, 0.6, 0.6),
)
# Reconstruction hypothesis: the travertine/tufa was coated with white painted stucco.
STUCCO_PAINTED = StoneStyle(
    name="stucco_painted",
    base_color=(0.90, 0.88, 0.83),
    vein_color=(0.80, 0.77, 0.70),
    vein_strength=0.0,
    pore_density=0.01,
    roughness_range=(0.6, 0.85),
    normal_strength=0.0015,
    banding=0.0,
    mottling=0.25,
    pore_color=(0.7, 0.67, 0.6),
)

# Roof tiles (tegulae, imbrices, antefixes): fired red-orange clay, matt, fine mottling and
# sparse pores (ionic_usd.temple.ornament).
TERRACOTTA = StoneStyle(
    name="terracotta",
    base_color=(0.70, 0.38, 0.24),
    vein_color=(0.58, 0.30, 0.19),
    vein_strength=0.1,
    pore_density=0.015,
    roughness_range=(0.65, 0.9),
    normal_strength=0.002,
    banding=0.0,
    mottling=0.45,
    pore_color=(0.45, 0.24, 0.16),
)
STONE_STYLES: dict[str, StoneStyle] = {
    s.name: s for s in (TRAVERTINE, MARBLE, STUCCO_PAINTED, TERRACOTTA)}


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


# ---------------------------------------------------------------------------------- colour


def srgb_to_linear(c: np.ndarray) -> np.ndarray:
    """IEC 61966-2-1 sRGB decoding of values in [0, 1] (any shape)."""
    c = np.asarray(c, dtype=np.float32)
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4).astype(np.float32)


def linear_to_srgb(c: np.ndarray) -> np.ndarray:
    """IEC 61966-2-1 sRGB encoding; input is clipped to [0, 1] first (any shape)."""
    c = np.clip(np.asarray(c, dtype=np.float32), 0.0, 1.0)
    out = np.where(c <= 0.0031308, c * 12.92, 1.055 * np.power(c, 1.0 / 2.4) - 0.055)
    return np.clip(out, 0.0, 1.0).astype(np.float32)


# ---------------------------------------------------------------------------- periodic noise


@dataclass(frozen=True)
class _NoiseSpec:
    """Spectrum of one periodic noise field (frequencies in cycles per tile).

    The amplitude at frequency ``f`` is ``f**-beta`` with a Gaussian high cut at ``f_hi`` and a
    low cut at ``f_lo``; ``stretch = (sx, sy)`` makes features ``sx / sy`` times longer along
    the x axis rotated by ``angle_deg``.
    """

    stream: int
    beta: float
    f_lo: float
    f_hi: float
    stretch: tuple[float, float] = (1.0, 1.0)
    angle_deg: float = 0.0

    @property
    def k_need(self) -> int:
        # Beyond 3 f_hi the Gaussian cut is below 1.3e-4: coefficients there are not drawn.
        return math.ceil(3.0 * self.f_hi / min(self.stretch))

    def amplitude(self, kx: np.ndarray, ky: np.ndarray) -> np.ndarray:
        a = math.radians(self.angle_deg)
        u = (kx * math.cos(a) + ky * math.sin(a)) * self.stretch[0]
        v = (ky * math.cos(a) - kx * math.sin(a)) * self.stretch[1]
        f = np.maximum(np.sqrt(u * u + v * v), 1e-6)
        amp = f ** (-self.beta) * np.exp(-((f / self.f_hi) ** 2))
        amp *= 1.0 - np.exp(-((f / self.f_lo) ** 2))
        return amp.astype(np.float32, copy=False)


@functools.lru_cache(maxsize=64)
def _sigma(spec: _NoiseSpec) -> float:
    """Standard deviation of the unnormalised field in the infinite-resolution limit (x n^2)."""
    k = spec.k_need
    amp = spec.amplitude(
        np.arange(0, k + 1, dtype=np.float32)[None, :],
        np.arange(-k, k + 1, dtype=np.float32)[:, None],
    )
    amp[k, 0] = 0.0
    # Columns kx > 0 of the half plane stand for two full-plane bins (Hermitian pairs);
    # E|c|^2 = 2 for a complex coefficient with unit-variance parts.
    var = 2.0 * (2.0 * float(np.sum(amp.astype(np.float64) ** 2)) - float(np.sum(amp[:, 0] ** 2)))
    return math.sqrt(var)


class _Spectrum:
    """Seeded periodic noise fields of one ``n x n`` tile, synthesised in rfft2 layout."""

    def __init__(self, size: int, seed: int) -> None:
        self.size = size
        self.seed = seed
        # Integer frequencies (cycles per tile) of the rfft2 rows and columns.
        self.iy = np.rint(np.fft.fftfreq(size) * size).astype(np.int64)
        self.ix = np.arange(size // 2 + 1, dtype=np.int64)

    def _draw_low(self, stream: int, k: int) -> np.ndarray:
        """Complex white noise for ky in [-k, k], kx in [0, k]: (2k+1, k+1) complex64.

        The grid |k| <= _KMAX is cut into fixed 64 x 64 cells, each with its own seed, so a
        coefficient has the same value whatever ``k`` (hence the tile size) is, and only the
        cells that are needed are drawn.
        """
        t = _CELL
        out = np.empty((2 * k + 1, k + 1), dtype=np.complex64)
        gy0, gy1 = _KMAX - k, _KMAX + k + 1  # global row range (row = ky + _KMAX)
        for cy in range(gy0 // t, (gy1 - 1) // t + 1):
            for cx in range(0, k // t + 1):
                rng = np.random.default_rng([self.seed, stream, cy, cx])
                cell = rng.standard_normal((t, t, 2), dtype=np.float32).view(np.complex64)[..., 0]
                y0, y1 = max(cy * t, gy0), min((cy + 1) * t, gy1)
                x0, x1 = cx * t, min((cx + 1) * t, k + 1)
                out[y0 - gy0 : y1 - gy0, x0:x1] = cell[y0 - cy * t : y1 - cy * t, : x1 - x0]
        return out

    def field(self, spec: _NoiseSpec) -> np.ndarray:
        """Periodic Gaussian noise, (n, n) float32, unit standard deviation in the
        infinite-resolution limit (so contrast does not depend on ``size``)."""
        n = self.size
        k = min(spec.k_need, _KMAX, n // 2)
        scale = np.float32(n * n / _sigma(spec))
        block = self._draw_low(spec.stream, k)
        block *= spec.amplitude(
            np.arange(0, k + 1, dtype=np.float32)[None, :],
            np.arange(-k, k + 1, dtype=np.float32)[:, None],
        )
        block *= scale
        if n // 2 <= k:
            coef = block[self.iy + k, : n // 2 + 1]
        else:
            coef = np.zeros((n, n // 2 + 1), dtype=np.complex64)
            if spec.k_need > _KMAX:
                # Frequencies past the size-independent block come from a second stream.
                rng = np.random.default_rng([self.seed, _HIGH_STREAM + spec.stream])
                hi = rng.standard_normal((n, n // 2 + 1, 2), dtype=np.float32)
                coef = hi.view(np.complex64)[..., 0]
                coef *= spec.amplitude(
                    self.ix[None, :].astype(np.float32), self.iy[:, None].astype(np.float32)
                )
                coef *= scale
            coef[: k + 1, : k + 1] = block[k:]
            coef[n - k :, : k + 1] = block[:k]
        return np.fft.irfft2(coef, s=(n, n)).astype(np.float32, copy=False)

    def fields(self, specs: Mapping[str, _NoiseSpec]) -> dict[str, np.ndarray]:
        """Several fields at once; threads overlap because numpy's FFT and RNG release the GIL
        (each field has its own streams, so the result does not depend on scheduling)."""
        workers = min(len(specs), os.cpu_count() or 1, 4)
        if workers <= 1 or self.size < 256:
            return {name: self.field(s) for name, s in specs.items()}
        with ThreadPoolExecutor(max_workers=workers) as pool:
            futures = {name: pool.submit(self.field, s) for name, s in specs.items()}
            return {name: f.result() for name, f in futures.items()}


def _gauss_quantile(p: float) -> float:
    """Inverse standard normal CDF by bisection (scalar; avoids a scipy dependency)."""
    lo, hi = -10.0, 10.0
    for _ in range(80):
        mid = 0.5 * (lo + hi)
        if 0.5 * (1.0 + math.erf(mid / math.sqrt(2.0))) < p:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


def _smoothstep(e0: float, e1: float, x: np.ndarray) -> np.ndarray:
    t = np.clip((x - e0) / (e1 - e0), 0.0, 1.0)
    return t * t * (3.0 - 2.0 * t)


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
    n = np.stack([-dh_du, -dh_dv, np.ones_like(h)], axis=-1)
    n /= np.linalg.norm(n, axis=-1, keepdims=True)
    return n.astype(np.float32)


def _encode_srgb_inplace(c: np.ndarray) -> None:
    """:func:`linear_to_srgb` without temporaries of the full shape beyond one mask."""
    np.clip(c, 0.0, 1.0, out=c)
    low = c <= 0.0031308
    lin = c[low] * 12.92
    np.power(c, np.float32(1.0 / 2.4), out=c)
    c *= 1.055
    c -= 0.055
    c[low] = lin
    np.clip(c, 0.0, 1.0, out=c)


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
    sp = _Spectrum(n, seed)

    # Each field has its own random streams, so skipping an unused one changes no other field.
    specs = {
        "cloud": _NoiseSpec(1, beta=1.6, f_lo=1.0, f_hi=24.0),
        "grain": _NoiseSpec(2, beta=0.3, f_lo=40.0, f_hi=260.0),
        "rough": _NoiseSpec(7, beta=0.8, f_lo=4.0, f_hi=120.0),
    }
    if st.banding > 0.0:
        # Sedimentary layers: features 16x longer horizontally than vertically, slightly wavy.
        specs["band"] = _NoiseSpec(3, 0.9, 2.0, 120.0, stretch=(16.0, 1.0), angle_deg=2.0)
    if st.vein_strength > 0.0:
        specs["vein_a"] = _NoiseSpec(4, 1.3, 1.0, 64.0, stretch=(2.5, 1.0), angle_deg=35.0)
        specs["vein_b"] = _NoiseSpec(5, 1.0, 3.0, 128.0, stretch=(1.5, 1.0), angle_deg=-20.0)
    if st.pore_density > 0.0:
        # Pores are elongated along the layers in banded stone.
        specs["pore"] = _NoiseSpec(6, 0.0, 20.0, 140.0, stretch=(1.0 + 5.0 * st.banding, 1.0))
    fld = sp.fields(specs)
    zeros = np.zeros((n, n), dtype=np.float32)
    cloud, grain, rough_f = fld["cloud"], fld["grain"], fld["rough"]
    band = fld.get("band", zeros)

    veins = zeros
    if st.vein_strength > 0.0:
        # Veins: thin neighbourhoods of the zero sets of smooth noise (meandering lines).
        vein_a, vein_b = fld["vein_a"], fld["vein_b"]
        # Widths and presence vary along each vein (large-scale cloud), so veins swell, thin
        # out and fade instead of looking like uniform contour lines.
        fade_a = _smoothstep(-0.8, 0.6, cloud)
        fade_b = _smoothstep(0.2, 1.4, -cloud + 0.5 * grain)
        width = np.float32(0.06) * (1.0 + 0.6 * cloud)
        primary = np.exp(-((vein_a / np.maximum(width, 0.015)) ** 2))
        halo = 0.25 * np.exp(-((vein_a / 0.3) ** 2))
        veins = np.maximum(primary, halo) * fade_a
        veins = np.maximum(veins, 0.45 * np.exp(-((vein_b / 0.035) ** 2)) * fade_b)
        veins *= np.float32(st.vein_strength)

    pores = zeros
    if st.pore_density > 0.0:
        # Pores cluster in the porous layers: the threshold drops where the band field is high;
        # the threshold is scaled by the std of the sum so the covered fraction stays as asked.
        coupling = 1.2 * st.banding
        t = _gauss_quantile(1.0 - st.pore_density) * math.sqrt(1.0 + coupling**2)
        pores = _smoothstep(t, t + 0.6, fld["pore"] + np.float32(coupling) * band)

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
    _encode_srgb_inplace(base_color)

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
    normal = height_to_normal(height, st.normal_strength)
    normal *= 0.5
    normal += 0.5
    np.clip(normal, 0.0, 1.0, out=normal)

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

    return StoneMaps(
        base_color=base_color,
        roughness=r,
        normal=normal,
        height=height,
        style=st.name,
        seed=seed,
    )


# ------------------------------------------------------------------------------------ writing


def _to_uint8(a: np.ndarray) -> np.ndarray:
    return np.round(np.clip(a, 0.0, 1.0) * 255.0).astype(np.uint8)


def _write_png(buf: object, path: Path) -> None:
    import OpenImageIO as oiio

    # zlib level 2 instead of libpng's 6: measured 0.62 s → 0.16 s for a 1024² basecolor,
    # files ≈ 12 % larger
    buf.specmod().attribute("png:compressionLevel", 2)
    # zlib level 3 with the "average" filter: ~4x faster than the defaults (level 6, adaptive
    # filters) and no larger on noisy images.
    buf.specmod().attribute("png:compressionLevel", 3)
    buf.specmod().attribute("png:filter", 64)
    from ionic_usd.io import atomic_path

    with atomic_path(path, verify=verify_image) as tmp:
        if not buf.write(str(tmp), oiio.UINT8, "png"):
            raise TextureError(path, f"OpenImageIO could not write it: {oiio.geterror()}")


def verify_image(path: Path) -> None:
    """Decode every pixel of an image file; raise :class:`TextureError` if it is incomplete.

    OpenImageIO's writers can report success on a full disk and leave a truncated file.
    """
    import OpenImageIO as oiio

    inp = oiio.ImageInput.open(str(path))
    if inp is None:
        raise TextureError(path, f"written image does not read back ({_one_line(oiio.geterror())})"
                           "; is the disk full?")
    try:
        spec = inp.spec()
        ok = inp.read_image(0, 0, 0, spec.nchannels, oiio.UINT8) is not None \
            and not inp.has_error
    finally:
        inp.close()
    if not ok:
        raise TextureError(path, "written image is incomplete; is the disk full?")


def _write_tx(buf: object, path: Path) -> None:
    import OpenImageIO as oiio

    config = oiio.ImageSpec()
    config.attribute("maketx:fileformatname", "tiff")
    # maketx's default 2x2 box reduction: exact for power-of-two sizes and 2.5x faster than
    # lanczos3, with no visible difference on noise-like stone.
    config.attribute("tile_width", 64)
    config.attribute("tile_height", 64)
    config.attribute("compression", "zip")
    # No maketx:incolorspace / outcolorspace: texels are copied unconverted (colour stays
    # sRGB-encoded and tagged so; roughness and normals stay raw data).
    from ionic_usd.io import atomic_path

    with atomic_path(path, verify=verify_image) as tmp:
        if not oiio.ImageBufAlgo.make_texture(oiio.MakeTxTexture, buf, str(tmp), config):
            raise TextureError(path, f"OpenImageIO make_texture failed: {oiio.geterror()}")


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
    import OpenImageIO as oiio

    maps = generate_stone_maps(style, size, seed)
    out = Path(folder)
    out.mkdir(parents=True, exist_ok=True)
    planes = {
        "basecolor": (maps.base_color, "sRGB"),
        "roughness": (maps.roughness, "Raw"),
        "normal": (maps.normal, "Raw"),
    }

    def write_one(key: str) -> dict[str, Path]:
        data, colorspace = planes[key]
        buf = oiio.ImageBuf(_to_uint8(data))
        # "Raw" makes the PNG writer omit sRGB/gAMA chunks, so viewers do not re-grade data.
        buf.specmod().attribute("oiio:ColorSpace", colorspace)
        done = {key: out / f"{maps.style}_{key}.png"}
        _write_png(buf, done[key])
        if make_tx:
            done[f"{key}_tx"] = out / f"{maps.style}_{key}.tx"
            _write_tx(buf, done[f"{key}_tx"])
        return done

    # zlib and maketx run outside the GIL: the three maps encode in parallel.
    with ThreadPoolExecutor(max_workers=min(3, os.cpu_count() or 1)) as pool:
        results = list(pool.map(write_one, planes))
    written: dict[str, Path] = {}
    for part in results:
        written.update(part)
    return written


# ------------------------------------------------------------------------- user textures


def _one_line(message: str) -> str:
    return "; ".join(part.strip() for part in message.splitlines() if part.strip())


def validate_user_texture(path: str | os.PathLike[str]) -> Path:
    """Check that a user-supplied texture can be packaged into a USDZ.

    The file must exist, be decodable by OpenImageIO, be PNG or JPEG by its *content*, and
    carry an extension matching that content (USD picks its image reader by extension).

    Returns
    -------
    Path
        The resolved path.

    Raises
    ------
    TextureError
        Naming the path and the problem.
    """
    import OpenImageIO as oiio

    p = Path(path)
    if not p.exists():
        raise TextureError(p, "file does not exist")
    if not p.is_file():
        raise TextureError(p, "not a regular file")
    if not os.access(p, os.R_OK):
        raise TextureError(p, "file is not readable (permission denied)")
    inp = oiio.ImageInput.open(str(p))
    if inp is None:
        msg = _one_line(oiio.geterror()) or "unknown format"
        raise TextureError(p, f"OpenImageIO cannot read it as an image ({msg})")
    try:
        fmt = inp.format_name()
        spec = inp.spec()
        if fmt not in USDZ_TEXTURE_FORMATS:
            allowed = ", ".join(sorted(USDZ_TEXTURE_FORMATS))
            raise TextureError(p, f"format is {fmt!r}; USDZ allows only {allowed}")
        if p.suffix.lower() not in USDZ_TEXTURE_FORMATS[fmt]:
            raise TextureError(
                p,
                f"content is {fmt} but the extension is {p.suffix!r}; "
                f"rename it to one of {list(USDZ_TEXTURE_FORMATS[fmt])}",
            )
        if spec.width <= 0 or spec.height <= 0:
            raise TextureError(p, "image has no pixels")
        # the header's dimensions, before any pixel is decoded (a small PNG can hold 20000²)
        if max(spec.width, spec.height) > MAX_USER_TEXTURE_SIZE or spec.depth > 1:
            raise TextureError(p, f"image is {spec.width}x{spec.height}x{spec.depth} pixels; "
                               f"the limit is {MAX_USER_TEXTURE_SIZE} per side, 2-D")
        # Opening only parses the header; decode the pixels to catch truncated files.
        pixels = inp.read_image(0, 0, 0, spec.nchannels, oiio.UINT8)
        if pixels is None:
            msg = _one_line(inp.geterror()) or "decode failed"
            raise TextureError(p, f"pixels cannot be decoded ({msg})")
    finally:
        inp.close()
    return p.resolve()


def copy_user_textures(
    mapping: Mapping[str, str | os.PathLike[str]], folder: str | os.PathLike[str]
) -> dict[str, Path]:
    """Validate every texture, then copy them all into ``folder`` under their own file names.

    Parameters
    ----------
    mapping : Mapping[str, path]
        Role (e.g. ``"basecolor"``) to source file.
    folder : path
        Destination, created if needed; existing files of the same name are replaced
        atomically.

    Returns
    -------
    dict[str, Path]
        Role to destination path.

    Raises
    ------
    TextureError
        If any source is invalid or two different sources share a file name; nothing is
        copied in that case.
    """
    sources = {role: validate_user_texture(src) for role, src in mapping.items()}
    by_name: dict[str, Path] = {}
    for role, src in sources.items():
        other = by_name.setdefault(src.name, src)
        if other != src:
            raise TextureError(src, f"file name clashes with {str(other)!r} (role {role!r})")
    out = Path(folder)
    out.mkdir(parents=True, exist_ok=True)
    copied: dict[str, Path] = {}
    for role, src in sources.items():
        dest = out / src.name
        if not (dest.exists() and dest.samefile(src)):
            from ionic_usd.io import atomic_path

            with atomic_path(dest) as tmp:
                shutil.copyfile(src, tmp)
        copied[role] = dest
    return copied
