"""Transcendental functions and small matrix products that give the same bits on every CPU.

numpy picks its ``exp``, ``log``, ``power``, ``arctan2``, ``arccos`` … loops at import by what
the processor offers: with AVX-512 they are SIMD approximations accurate to a few units in
the last place, elsewhere other code, and the two disagree in the last bits on most inputs.
A last-bit difference in a volute's log spiral is enough for the capital's union to come out
with other triangles (the Portunus column had 40,894 triangles on an AVX-512 machine and
40,882 elsewhere), and one in a normal or a texel changes the bytes of every file it is in.

IEEE 754 requires ``+ − × ÷`` and ``sqrt`` to be correctly rounded, so they give the same
bits on every conforming CPU, scalar or SIMD (numpy's elementwise ufuncs never fuse a
multiply and an add). :func:`exp`, :func:`log`, :func:`power` and :func:`arctan2` are built
from those alone, plus the exact ``rint``, ``frexp`` and ``ldexp``: Cody–Waite argument
reduction and the rational approximations of Moshier's Cephes library (``exp.c``, ``log.c``,
``atan.c``: relative error at most 3.2e-16, 1.4 units in the last place, measured against
``math``; float32 input gets the single-precision ``expf.c``/``logf.c`` polynomials, 2e-7),
evaluated vectorised by numpy: 15 (exp), 35 (log) and 50 (atan2) ns a value in float64, 6
and 18 in float32, so the angle weights of a mesh's normals and the texels of a map can use
them too. (The C library is not enough: glibc picks its ``exp`` and ``log`` builds by CPU as
well, FMA ones on newer processors.)
``tests/test_libm.py`` checks them against ``math`` and builds the column, the asset and the
whole temple with numpy's SIMD loops switched off (``NPY_DISABLE_CPU_FEATURES``) and
OpenBLAS on its oldest x86 kernels (``OPENBLAS_CORETYPE=Nehalem``), comparing every array
and every file's bytes.

A matrix product of points (``points @ lin.T``) goes through BLAS, whose kernels are chosen
the same way: OpenBLAS's pre-AVX2 ones (no fused multiply-add) round differently from the
newer ones. :func:`linear` writes the 3 × 3 product as three scaled columns added in a fixed
order (elementwise ufuncs, which no CPU fuses): 24 ms against BLAS's 11 ms for a million
points, microseconds at a part's size.

Third, numpy's default (quick)sort is vectorised with AVX-512 too and leaves equal keys in
another order: where ties decide an order (the sliver clean-up visits its worst triangles
first, and a symmetric capital has many equal angles) the kernel sorts with
``kind="stable"``.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["exp", "log", "power", "arctan2", "by_blocks", "linear", "dot"]

_F = np.float64

# exp: e**x = 2**n · e**r, n = rint(x / ln 2), r = x − n·C1 − n·C2 (C1 + C2 = ln 2, C1 with
# 12 significant bits so n·C1 is exact), e**r = 1 + 2 r P(r²) / (Q(r²) − r P(r²))
_EXP_C1 = 6.93145751953125e-1
_EXP_C2 = 1.42860682030941723212e-6
_EXP_P = (1.26177193074810590878e-4, 3.02994407707441961300e-2, 9.99999999999999999910e-1)
_EXP_Q = (
    3.00198505138664455042e-6,
    2.52448340349684104192e-3,
    2.27265548208155028766e-1,
    2.00000000000000000009e0,
)
_EXP_MAX = 709.782712893384  # above: inf (the largest float64 whose exp is finite, rounded up)
_EXP_MIN = -745.2  # below: 0 (e**x under half the smallest subnormal)

# log: x = m · 2**e, m in [√½, √2); log(1 + z) = z − z²/2 + z³ P(z) / Q(z), z = m − 1
_LOG_P = (
    1.01875663804580931796e-4,
    4.97494994976747001425e-1,
    4.70579119878881725854e0,
    1.44989225341610930846e1,
    1.79368678507819816313e1,
    7.70838733755885391666e0,
)
_LOG_Q = (  # leading coefficient 1
    1.12873587189167450590e1,
    4.52279145837532221105e1,
    8.29875266912776603211e1,
    7.11544750618563894466e1,
    2.31251620126765340583e1,
)
_LN2_HI = 0.693359375  # ln 2 = _LN2_HI − _LN2_LO, _LN2_HI with 9 significant bits
_LN2_LO = 2.121944400546905827679e-4

# atan on [0, 1]: t ≤ 0.66 as it is, else π/4 + atan((t − 1)/(t + 1)), with
# atan(z) = z + z³ P(z²) / Q(z²) (|z| ≤ 0.66); _MOREBITS: π/2 − fl(π/2)
_ATAN_P = (
    -8.750608600031904122785e-1,
    -1.615753718733365076637e1,
    -7.500855792314704667340e1,
    -1.228866684490136173410e2,
    -6.485021904942025371773e1,
)
_ATAN_Q = (  # leading coefficient 1
    2.485846490142306297962e1,
    1.650270098316988542046e2,
    4.328810604912902668951e2,
    4.853903996359136964868e2,
    1.945506571482613964425e2,
)
_MOREBITS = 6.123233995736765886130e-17


def _horner(z: np.ndarray, coef: tuple[float, ...], monic: bool = False) -> np.ndarray:
    """Σ coef[i] z**(k−i) by Horner's rule (``monic``: a leading 1 before ``coef``)."""
    acc = z + coef[0] if monic else z * coef[0]
    if not monic:
        acc += coef[1]
    for c in coef[(1 if monic else 2) :]:
        acc *= z
        acc += c
    return acc


# float32 (Cephes expf.c, logf.c): the same reductions, polynomials of single precision
_EXPF_C1 = 0.693359375
_EXPF_C2 = -2.12194440e-4
_EXPF_P = (
    1.9875691500e-4,
    1.3981999507e-3,
    8.3334519073e-3,
    4.1665795894e-2,
    1.6666665459e-1,
    5.0000001201e-1,
)
_EXPF_MAX = 88.72283  # above: inf
_EXPF_MIN = -103.97208  # below: 0
_LOGF_P = (
    7.0376836292e-2,
    -1.1514610310e-1,
    1.1676998740e-1,
    -1.2420140846e-1,
    1.4249322787e-1,
    -1.6668057665e-1,
    2.0000714765e-1,
    -2.4999993993e-1,
    3.3333331174e-1,
)


def _flat(x) -> tuple[np.ndarray, tuple[int, ...]]:
    """``x`` as a 1-d float array (float32 stays float32, anything else becomes float64; in-
    place updates need arrays, not numpy scalars) and its shape."""
    a = np.asarray(x)
    a = a.astype(np.float32 if a.dtype == np.float32 else _F, copy=False)
    return a.reshape(-1), a.shape


def _result(out: np.ndarray, shape: tuple[int, ...]) -> np.ndarray:
    """``out`` in ``shape``; a 0-d result as a numpy scalar."""
    return out.reshape(shape) if shape else out[0]


def _exp_kernel(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(e**r, n) with e**x = e**r · 2**n, r = x − n ln 2, n = rint(x / ln 2), in x's dtype."""
    n = x * (1.0 / math.log(2.0))
    np.rint(n, out=n)
    single = x.dtype == np.float32
    r = n * -(_EXPF_C1 if single else _EXP_C1)
    r += x
    r -= n * (_EXPF_C2 if single else _EXP_C2)
    rr = r * r
    if single:  # 1 + r + r² P(r)
        e = _horner(r, _EXPF_P)
        e *= rr
        e += r
        e += 1.0
        return e, n
    px = _horner(rr, _EXP_P)  # 1 + 2 r P(r²) / (Q(r²) − r P(r²))
    px *= r
    q = _horner(rr, _EXP_Q)
    q -= px
    px /= q
    px *= 2.0
    px += 1.0
    return px, n


def exp(x: np.ndarray | float) -> np.ndarray:
    """``e**x`` elementwise, the same bits on every CPU (numpy's ``exp`` otherwise: float32
    stays float32, anything else is float64; inf above the largest finite result, 0 far
    below, NaN kept, no floating-point warning)."""
    x, shape = _flat(x)
    single = x.dtype == np.float32
    top, bottom = (_EXPF_MAX, _EXPF_MIN) if single else (_EXP_MAX, _EXP_MIN)
    with np.errstate(all="ignore"):
        lo, hi = (float(x.min()), float(x.max())) if x.size else (0.0, 0.0)
        inside = bottom <= lo and hi <= top  # False with a NaN too
        e, n = _exp_kernel(x if inside else np.clip(x, bottom, top))
        # ldexp scales exactly and rounds once, so e · 2**n needs no 2**n (which would
        # overflow at the top and underflow at the bottom); a NaN's n casts to anything
        out = np.ldexp(e, n.astype(np.int32))
        if not inside:
            out[x > top] = np.inf
            out[x < bottom] = 0.0
    return _result(out, shape)


def log(x: np.ndarray | float) -> np.ndarray:
    """Natural logarithm elementwise, the same bits on every CPU (numpy's ``log`` otherwise:
    float32 stays float32, anything else is float64; −inf at 0, NaN below, inf at inf, no
    floating-point warning)."""
    x, shape = _flat(x)
    with np.errstate(all="ignore"):
        ok = np.isfinite(x) & (x > 0.0)
        every = bool(ok.all())
        m, e = np.frexp(x if every else np.where(ok, x, 1.0))  # m in [½, 1)
        e = e.astype(x.dtype)
        low = m < math.sqrt(0.5)
        e -= low
        m[low] *= 2.0
        m -= 1.0  # z: exact, as m − 1 and 2m − 1 are
        z = m
        zz = z * z
        if x.dtype == np.float32:
            y = _horner(z, _LOGF_P)  # log(1 + z) = z − z²/2 + z³ P(z)
        else:
            y = _horner(z, _LOG_P)
            y /= _horner(z, _LOG_Q, monic=True)
        y *= zz
        y *= z
        y -= e * _LN2_LO
        y -= 0.5 * zz
        y += z
        y += e * _LN2_HI
        if not every:
            y[x == 0.0] = -np.inf
            y[x == np.inf] = np.inf
            y[~ok & (x != 0.0) & (x != np.inf)] = np.nan
    return _result(y, shape)


def power(x: np.ndarray | float, p: float) -> np.ndarray:
    """``x**p`` elementwise for ``x ≥ 0`` (``exp(p · log x)``; 0**p is 0 for p > 0), the
    same bits on every CPU, in the dtype :func:`exp` gives; relative error below 1e-15 in
    float64 (1e-6 in float32) for |p · log x| < 30."""
    x, shape = _flat(x)
    if p == 0.0:
        return _result(np.ones_like(x), shape)
    lx = log(x)
    lx *= p
    return _result(exp(lx), shape)


def arctan2(y: np.ndarray | float, x: np.ndarray | float) -> np.ndarray:
    """The angle of ``(x, y)`` in radians, [−π, π], elementwise (broadcast) as float64, the
    same bits on every CPU (numpy's ``arctan2`` otherwise, signed zeros and infinities
    included).

    With a = |y|, b = |x|: r = atan(min/max) on [0, 1] (above 0.66 as π/4 + atan((t − 1)/
    (t + 1))), then one turn per octant, π/2 − r (a > b, x ≥ 0), π/2 + r (a > b, x < 0 or
    −0), π − r (a ≤ b, x < 0 or −0), signed as y.
    """
    y, x = np.broadcast_arrays(np.asarray(y, dtype=_F), np.asarray(x, dtype=_F))
    shape = y.shape
    y, x = y.reshape(-1), x.reshape(-1)
    ay, ax = np.abs(y), np.abs(x)
    with np.errstate(all="ignore"):
        steep = ay > ax
        lo = np.minimum(ay, ax)
        hi = np.maximum(ay, ax)
        t = lo / hi  # 0/0 and inf/inf: NaN, set below
        special = ~np.isfinite(t)
        if special.any():
            # both zero: 0; both infinite: 1 (π/4 before the turns); a NaN input: NaN
            both_zero = np.where(hi[special] == 0, 0.0, np.nan)
            t[special] = np.where(np.isinf(lo[special]), 1.0, both_zero)
        mid = t > 0.66
        z = np.where(mid, (t - 1.0) / (t + 1.0), t)
        zz = z * z
        r = _horner(zz, _ATAN_P)
        r /= _horner(zz, _ATAN_Q, monic=True)
        r *= zz
        r *= z
        r += z
        # each turn adds the part of its multiple of π/4 that fl(π/4) leaves out (_MOREBITS
        # is π/2 − fl(π/2)) before the rounded constant, and each octant takes one turn (two
        # in a row would round twice): steep on the left is π/2 + a, not π − (π/2 − a)
        a = np.where(mid, (r + 0.5 * _MOREBITS) + math.pi / 4, r)
        left = np.signbit(x)
        a = np.where(
            steep,
            np.where(left, (a + _MOREBITS) + math.pi / 2, (_MOREBITS - a) + math.pi / 2),
            np.where(left, (2.0 * _MOREBITS - a) + math.pi, a),
        )
        out = np.copysign(a, y)
    return _result(out, shape)


def by_blocks(
    fn, x: np.ndarray, dtype=np.float32, *, out: np.ndarray | None = None, block: int = 1 << 18
) -> np.ndarray:
    """``fn(values)`` over ``x`` (any shape) ``block`` values at a time, as ``dtype``: the
    float64 temporaries of the functions above are those of a block (2 MB), not of a whole
    map (a 8192² texture would need gigabytes). ``out``: a 1-d array of ``x.size`` values to
    write into (it may be ``x`` itself, flattened: each block is read before it is written)."""
    flat = np.ascontiguousarray(x).reshape(-1)
    res = np.empty(flat.shape, dtype=dtype) if out is None else out
    for i in range(0, flat.size, block):
        res[i : i + block] = fn(flat[i : i + block])
    return res.reshape(np.shape(x))


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
