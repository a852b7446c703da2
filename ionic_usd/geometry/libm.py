"""Transcendental functions and small matrix products that give the same bits on every CPU.

numpy picks its ``exp``, ``log``, ``power``, ``arctan2``, ``arccos`` … loops at import by what
the processor offers: with AVX-512 they are SIMD approximations accurate to a few units in
the last place, elsewhere other code, and the two disagree in the last bits on most inputs
(``+ - * / sqrt``, ``sin`` and ``cos`` agree). A last-bit difference in a volute's log
spiral is enough for the capital's union to come out with other triangles: the Portunus
column had 40,894 triangles on an AVX-512 machine and 40,882 elsewhere. The generators take
these functions from here instead: the C library's, one value at a time (``math``; its
``exp`` and ``atan2`` are correctly rounded in nearly every case, so one CPU and the next
agree), which costs ~0.1 µs a value, nothing at the sizes they are used at (a curve's
samples, a row of a shaft, a chart's points). ``tests/test_libm.py`` builds the column and
the asset with numpy's SIMD loops switched off (``NPY_DISABLE_CPU_FEATURES``) and OpenBLAS on
its oldest x86 kernels (``OPENBLAS_CORETYPE=Nehalem``) and compares every array.

A matrix product of points (``points @ lin.T``) goes through BLAS, whose kernels are chosen
the same way: OpenBLAS's pre-AVX2 ones (no fused multiply-add) round differently from the
newer ones. :func:`linear` writes the 3 × 3 product as three scaled columns added in a fixed
order (elementwise ufuncs, which no CPU fuses): 24 ms against BLAS's 11 ms for a million
points, microseconds at a part's size.

Third, numpy's default (quick)sort is vectorised with AVX-512 too and leaves equal keys in
another order: where ties decide an order (the sliver clean-up visits its worst triangles
first, and a symmetric capital has many equal angles) the kernel sorts with
``kind="stable"``.

Normals stay on numpy's loops (their angle weights are per corner, millions on a shaft, and
a last-bit change in a normal changes no point, triangle or chart).
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["exp", "arctan2", "linear", "dot"]


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


def linear(points: np.ndarray, lin: np.ndarray) -> np.ndarray:
    """``points @ lin.T`` for (n, k) points and a (m, k) matrix (k small: 3-vectors, a
    Bézier's control points), the same bits on every CPU: ``Σ_j points[:, j] · lin[:, j]``,
    summed in the order of j (float64 unless both are float32, as numpy's product)."""
    p = np.asarray(points)
    a = np.asarray(lin)
    dtype = np.result_type(p, a)
    cols = np.ascontiguousarray(p.T, dtype=dtype)  # contiguous columns: 1-D products
    a = a.astype(dtype, copy=False)
    out = np.empty((p.shape[0], a.shape[0]), dtype=dtype)
    for i in range(a.shape[0]):
        row = cols[0] * a[i, 0]
        for j in range(1, a.shape[1]):
            row += cols[j] * a[i, j]
        out[:, i] = row
    return out


def dot(points: np.ndarray, v: np.ndarray) -> np.ndarray:
    """``points @ v`` for (n, k) points and a k-vector, the same bits on every CPU."""
    return linear(points, np.asarray(v)[None, :])[:, 0]
