"""sRGB transfer functions (IEC 61966-2-1), the package's one implementation.

Both are computed so that a map encodes to the same bytes on every CPU (numpy's ``power`` is a
SIMD approximation on some processors and not on others):

* decoding with :func:`ionic_usd.geometry.libm.power` (float32, relative error below 1e-6);
* encoding, which runs on every texel of a base colour map, by a table of the encoded value at
  every 2**13-th float32 above 2**-9 (the exponent and the top 10 mantissa bits of the
  argument: 9.2 k entries, made once with float64 ``libm.power``) interpolated linearly in the
  low 13 bits, the linear segment exactly: within 1.5e-7 relative of the float64 formula
  (7e-7 at the knee itself, where the standard's two segments differ by that), about 8 ns a
  value.
"""

from __future__ import annotations

import functools

import numpy as np

from ionic_usd.geometry import libm

__all__ = ["srgb_to_linear", "linear_to_srgb", "encode_srgb_inplace"]

_KNEE = 0.0031308  # below: the linear segment, 12.92 c
_LOW_BITS = 13  # mantissa bits interpolated within a table cell
_FIRST = np.float32(2.0**-9)  # the table starts here (below the knee: linear from 0)


def srgb_to_linear(c: np.ndarray) -> np.ndarray:
    """IEC 61966-2-1 sRGB decoding of values in [0, 1] (any shape)."""
    c = np.asarray(c, dtype=np.float32)
    high = libm.power((c + np.float32(0.055)) / np.float32(1.055), 2.4)
    return np.where(c <= 0.04045, c / np.float32(12.92), high).astype(np.float32)


@functools.cache
def _table() -> tuple[np.ndarray, np.ndarray]:
    """(value at each knot, difference to the next): float32, knots at the float32 values
    whose low 13 bits are zero, from 2**-9 up to 1 and one past it (9.2 k entries)."""
    first = int(_FIRST.view(np.int32)) >> _LOW_BITS
    last = int(np.float32(1.0).view(np.int32)) >> _LOW_BITS
    knots = (np.arange(first, last + 2, dtype=np.int32) << _LOW_BITS).view(np.float32)
    # the power branch at every knot, below the knee too: the cell holding the knee then
    # interpolates the curve (values up to the knee take the linear segment exactly)
    values = 1.055 * libm.power(knots.astype(np.float64), 1.0 / 2.4) - 0.055
    return values[:-1].astype(np.float32), np.diff(values).astype(np.float32)


def _encode(c: np.ndarray) -> np.ndarray:
    """Encoded float32 values of float32 ``c`` clipped to [0, 1] (1-d; NaN stays NaN)."""
    c = np.clip(c, np.float32(0.0), np.float32(1.0))
    values, steps = _table()
    bits = c.view(np.int32)
    cell = (bits >> _LOW_BITS) - (int(_FIRST.view(np.int32)) >> _LOW_BITS)
    low = c <= np.float32(_KNEE)  # on the linear segment (cells below 2**-9 too)
    nan = np.isnan(c)  # either sign: its bits index no cell
    cell[low | nan] = 0
    frac = (bits & ((1 << _LOW_BITS) - 1)).astype(np.float32)
    frac *= np.float32(1.0 / (1 << _LOW_BITS))
    out = steps[cell]
    out *= frac
    out += values[cell]
    out[low] = c[low] * np.float32(12.92)
    out[nan] = np.nan
    return np.clip(out, np.float32(0.0), np.float32(1.0))


def linear_to_srgb(c: np.ndarray) -> np.ndarray:
    """IEC 61966-2-1 sRGB encoding; input is clipped to [0, 1] first (any shape)."""
    c = np.asarray(c, dtype=np.float32)
    return libm.by_blocks(_encode, c)


def encode_srgb_inplace(c: np.ndarray) -> None:
    """:func:`linear_to_srgb` of a float32 array in place, block by block (no temporary of
    the full shape); a float64 array is encoded through float32 values, in place too."""
    if c.dtype != np.float32:
        c[...] = linear_to_srgb(c)
        return
    flat = c.reshape(-1)  # a view of a contiguous map (else a copy, written back below)
    libm.by_blocks(_encode, flat, c.dtype, out=flat)
    if not np.shares_memory(flat, c):
        c[...] = flat.reshape(c.shape)
