"""sRGB transfer functions (IEC 61966-2-1), the package's one implementation.

The powers are :func:`ionic_usd.geometry.libm.power` (float32, relative error below 5e-7),
so a map encodes to the same bytes on every CPU.
"""

from __future__ import annotations

import numpy as np

from ionic_usd.geometry import libm

__all__ = ["srgb_to_linear", "linear_to_srgb", "encode_srgb_inplace"]


def srgb_to_linear(c: np.ndarray) -> np.ndarray:
    """IEC 61966-2-1 sRGB decoding of values in [0, 1] (any shape)."""
    c = np.asarray(c, dtype=np.float32)
    high = libm.power((c + np.float32(0.055)) / np.float32(1.055), 2.4)
    return np.where(c <= 0.04045, c / 12.92, high).astype(np.float32)


def linear_to_srgb(c: np.ndarray) -> np.ndarray:
    """IEC 61966-2-1 sRGB encoding; input is clipped to [0, 1] first (any shape)."""
    c = np.clip(np.asarray(c, dtype=np.float32), 0.0, 1.0)
    high = np.float32(1.055) * libm.power(c, 1.0 / 2.4) - np.float32(0.055)
    out = np.where(c <= 0.0031308, c * np.float32(12.92), high)
    return np.clip(out, 0.0, 1.0).astype(np.float32)


def encode_srgb_inplace(c: np.ndarray) -> None:
    """:func:`linear_to_srgb` of a float32 array in place, block by block (no temporary of
    the full shape)."""
    flat = c.reshape(-1)  # a view of a contiguous map (else a copy, written back below)

    def encode(b: np.ndarray) -> np.ndarray:
        b = np.clip(b, 0.0, 1.0)
        out = libm.power(b, 1.0 / 2.4)  # float32, as b
        out *= np.float32(1.055)
        out -= np.float32(0.055)
        low = b <= 0.0031308
        out[low] = b[low] * np.float32(12.92)
        return np.clip(out, 0.0, 1.0)

    libm.by_blocks(encode, flat, c.dtype, out=flat)
    if not np.shares_memory(flat, c):
        c[...] = flat.reshape(c.shape)
