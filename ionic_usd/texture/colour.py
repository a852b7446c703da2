"""sRGB transfer functions (IEC 61966-2-1), the package's one implementation."""

from __future__ import annotations

import numpy as np

__all__ = ["srgb_to_linear", "linear_to_srgb", "encode_srgb_inplace"]


def srgb_to_linear(c: np.ndarray) -> np.ndarray:
    """IEC 61966-2-1 sRGB decoding of values in [0, 1] (any shape)."""
    c = np.asarray(c, dtype=np.float32)
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4).astype(np.float32)


def linear_to_srgb(c: np.ndarray) -> np.ndarray:
    """IEC 61966-2-1 sRGB encoding; input is clipped to [0, 1] first (any shape)."""
    c = np.clip(np.asarray(c, dtype=np.float32), 0.0, 1.0)
    out = np.where(c <= 0.0031308, c * 12.92, 1.055 * np.power(c, 1.0 / 2.4) - 0.055)
    return np.clip(out, 0.0, 1.0).astype(np.float32)


def encode_srgb_inplace(c: np.ndarray) -> None:
    """:func:`linear_to_srgb` without temporaries of the full shape beyond one mask."""
    np.clip(c, 0.0, 1.0, out=c)
    low = c <= 0.0031308
    lin = c[low] * 12.92
    np.power(c, np.float32(1.0 / 2.4), out=c)
    c *= 1.055
    c -= 0.055
    c[low] = lin
    np.clip(c, 0.0, 1.0, out=c)
