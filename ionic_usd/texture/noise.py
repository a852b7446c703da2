"""Periodic band-limited Gaussian noise synthesised in the Fourier domain (tileable fields).

Each field lives on a torus: random Fourier coefficients with a power-law spectrum, brought back
with an inverse real FFT. The coefficients up to :data:`KMAX` cycles per tile are drawn per
fixed cell of the frequency grid, so they do not depend on the tile size: one seed gives the same
field at every resolution.
"""

from __future__ import annotations

import functools
import math
import os
from collections.abc import Mapping
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import numpy as np

from ionic_usd.geometry import libm

__all__ = [
    "KMAX",
    "CELL",
    "HIGH_STREAM",
    "NoiseSpec",
    "Spectrum",
    "noise_sigma",
    "gauss_quantile",
    "smoothstep",
]

# Highest frequency (cycles per tile) drawn from the size-independent random stream.
KMAX = 512
# Edge of the independently seeded cells of the Fourier-coefficient grid.
CELL = 64
# Offset of the stream ids that draw frequencies beyond KMAX (tiles larger than 1024).
HIGH_STREAM = 1000


@dataclass(frozen=True)
class NoiseSpec:
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
        # f**−β · exp(−(f/f_hi)²) as one exp, times the low cut, by ionic_usd.geometry.libm
        # (the same bits on every CPU), in float32 a block at a time

        def amp(b: np.ndarray) -> np.ndarray:
            e = libm.log(b)
            e *= np.float32(-self.beta)
            e -= np.square(b / np.float32(self.f_hi))
            out = libm.exp(e)
            out *= 1.0 - libm.exp(-np.square(b / np.float32(self.f_lo)))
            return out

        return libm.by_blocks(amp, f)


@functools.lru_cache(maxsize=16)
def _amplitude_grid(spec: NoiseSpec) -> np.ndarray:
    """The amplitude for ky in [−K, K] (rows), kx in [0, K] (columns), K = ``spec.k_need``:
    every frequency a tile draws below KMAX, so a field slices it (read-only, shared). An
    unrotated spectrum is even in ky (u = kx·sx, v = ky·sy exactly): its rows ky ≥ 0 are
    computed and mirrored, the same values at half the cost."""
    k = spec.k_need
    kx = np.arange(0, k + 1, dtype=np.float32)[None, :]
    if spec.angle_deg == 0.0:
        top = spec.amplitude(kx, np.arange(0, k + 1, dtype=np.float32)[:, None])
        grid = np.concatenate([top[:0:-1], top])
    else:
        grid = spec.amplitude(kx, np.arange(-k, k + 1, dtype=np.float32)[:, None])
    grid.flags.writeable = False
    return grid


@functools.lru_cache(maxsize=64)
def noise_sigma(spec: NoiseSpec) -> float:
    """Standard deviation of the unnormalised field in the infinite-resolution limit (x n^2)."""
    k = spec.k_need
    amp = _amplitude_grid(spec).copy()
    amp[k, 0] = 0.0
    # Columns kx > 0 of the half plane stand for two full-plane bins (Hermitian pairs);
    # E|c|^2 = 2 for a complex coefficient with unit-variance parts.
    var = 2.0 * (2.0 * float(np.sum(amp.astype(np.float64) ** 2)) - float(np.sum(amp[:, 0] ** 2)))
    return math.sqrt(var)


class Spectrum:
    """Seeded periodic noise fields of one ``n x n`` tile, synthesised in rfft2 layout."""

    def __init__(self, size: int, seed: int) -> None:
        self.size = size
        self.seed = seed
        # Integer frequencies (cycles per tile) of the rfft2 rows and columns.
        self.iy = np.rint(np.fft.fftfreq(size) * size).astype(np.int64)
        self.ix = np.arange(size // 2 + 1, dtype=np.int64)

    def _draw_low(self, stream: int, k: int) -> np.ndarray:
        """Complex white noise for ky in [-k, k], kx in [0, k]: (2k+1, k+1) complex64.

        The grid |k| <= KMAX is cut into fixed 64 x 64 cells, each with its own seed, so a
        coefficient has the same value whatever ``k`` (hence the tile size) is, and only the
        cells that are needed are drawn.
        """
        t = CELL
        out = np.empty((2 * k + 1, k + 1), dtype=np.complex64)
        gy0, gy1 = KMAX - k, KMAX + k + 1  # global row range (row = ky + KMAX)
        for cy in range(gy0 // t, (gy1 - 1) // t + 1):
            for cx in range(0, k // t + 1):
                rng = np.random.default_rng([self.seed, stream, cy, cx])
                cell = rng.standard_normal((t, t, 2), dtype=np.float32).view(np.complex64)[..., 0]
                y0, y1 = max(cy * t, gy0), min((cy + 1) * t, gy1)
                x0, x1 = cx * t, min((cx + 1) * t, k + 1)
                out[y0 - gy0 : y1 - gy0, x0:x1] = cell[y0 - cy * t : y1 - cy * t, : x1 - x0]
        return out

    def field(self, spec: NoiseSpec) -> np.ndarray:
        """Periodic Gaussian noise, (n, n) float32, unit standard deviation in the
        infinite-resolution limit (so contrast does not depend on ``size``)."""
        n = self.size
        k = min(spec.k_need, KMAX, n // 2)
        scale = np.float32(n * n / noise_sigma(spec))
        block = self._draw_low(spec.stream, k)
        big = spec.k_need
        block *= _amplitude_grid(spec)[big - k : big + k + 1, : k + 1]  # the same values
        block *= scale
        if n // 2 <= k:
            coef = block[self.iy + k, : n // 2 + 1]
        else:
            coef = np.zeros((n, n // 2 + 1), dtype=np.complex64)
            if spec.k_need > KMAX:
                # Frequencies past the size-independent block come from a second stream.
                rng = np.random.default_rng([self.seed, HIGH_STREAM + spec.stream])
                hi = rng.standard_normal((n, n // 2 + 1, 2), dtype=np.float32)
                coef = hi.view(np.complex64)[..., 0]
                coef *= spec.amplitude(
                    self.ix[None, :].astype(np.float32), self.iy[:, None].astype(np.float32)
                )
                coef *= scale
            coef[: k + 1, : k + 1] = block[k:]
            coef[n - k :, : k + 1] = block[:k]
        return np.fft.irfft2(coef, s=(n, n)).astype(np.float32, copy=False)

    def fields(self, specs: Mapping[str, NoiseSpec]) -> dict[str, np.ndarray]:
        """Several fields at once; threads overlap because numpy's FFT and RNG release the GIL
        (each field has its own streams, so the result does not depend on scheduling)."""
        workers = min(len(specs), os.cpu_count() or 1, 4)
        if workers <= 1 or self.size < 256:
            return {name: self.field(s) for name, s in specs.items()}
        with ThreadPoolExecutor(max_workers=workers) as pool:
            futures = {name: pool.submit(self.field, s) for name, s in specs.items()}
            return {name: f.result() for name, f in futures.items()}


def gauss_quantile(p: float) -> float:
    """Inverse standard normal CDF by bisection (scalar; avoids a scipy dependency)."""
    lo, hi = -10.0, 10.0
    for _ in range(80):
        mid = 0.5 * (lo + hi)
        if 0.5 * (1.0 + math.erf(mid / math.sqrt(2.0))) < p:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


def smoothstep(e0: float, e1: float, x: np.ndarray) -> np.ndarray:
    t = np.clip((x - e0) / (e1 - e0), 0.0, 1.0)
    return t * t * (3.0 - 2.0 * t)
