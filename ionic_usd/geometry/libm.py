"""Transcendental functions that give the same bits on every CPU.

numpy picks its ``exp``, ``log``, ``power``, ``arctan2``, ``arccos`` … loops at import by what
the processor offers: with AVX-512 they are SIMD approximations accurate to a few units in
the last place, elsewhere other code, and the two disagree in the last bits on most inputs
(``+ - * / sqrt``, ``sin`` and ``cos`` agree). A last-bit difference in a volute's log
spiral is enough for the capital's union to come out with other triangles: the Portunus
column had 40,894 triangles on an AVX-512 machine and 40,882 elsewhere. The generators take
these functions from here instead: the C library's, one value at a time (``math``; its
``exp`` and ``atan2`` are correctly rounded in nearly every case, so one CPU and the next
agree), which costs ~0.1 µs a value, nothing at the sizes they are used at (a curve's
samples, a row of a shaft, a chart's points). ``tests/test_libm.py`` builds the column with
numpy's SIMD loops switched off (``NPY_DISABLE_CPU_FEATURES``) and compares every array.

Normals stay on numpy's loops (their angle weights are per corner, millions on a shaft, and
a last-bit change in a normal changes no point, triangle or chart).
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["exp", "arctan2"]


_EXP_MAX = 709.782712893384  # the largest float64 whose exp is finite (rounded up)


def _exp_scalar(x: float) -> float:
    # numpy's exp gives inf above it; math's raises (and leaves the overflow flag set). A NaN
    # is returned before any comparison, which would raise the invalid flag
    if math.isnan(x):
        return x
    return math.inf if x > _EXP_MAX else math.exp(x)


_EXP = np.frompyfunc(_exp_scalar, 1, 1)
_ATAN2 = np.frompyfunc(math.atan2, 2, 1)


def exp(x: np.ndarray | float) -> np.ndarray:
    """``e**x`` elementwise as float64, the same bits on every CPU (numpy's ``exp``
    otherwise)."""
    return np.asarray(_EXP(np.asarray(x, dtype=np.float64)), dtype=np.float64)


def arctan2(y: np.ndarray | float, x: np.ndarray | float) -> np.ndarray:
    """The angle of ``(x, y)`` in radians, (−π, π], elementwise (broadcast) as float64, the
    same bits on every CPU (numpy's ``arctan2`` otherwise, signed zeros included)."""
    return np.asarray(
        _ATAN2(np.asarray(y, dtype=np.float64), np.asarray(x, dtype=np.float64)),
        dtype=np.float64,
    )
