"""Curves and surfaces of revolution: arc-length resampling, Bézier, ellipse arcs, revolve."""

from __future__ import annotations

from math import comb

import numpy as np

from ionic_usd.errors import GeometryError, ParameterError
from ionic_usd.geometry import libm
from ionic_usd.geometry.mesh import Mesh
from ionic_usd.geometry.stitch import stitch

__all__ = [
    "pchip",
    "polyline_length",
    "cumulative_length",
    "resample_polyline",
    "bernstein",
    "bezier",
    "ring_angles",
    "ring",
    "revolve",
]


def cumulative_length(curve: np.ndarray) -> np.ndarray:
    """(n,) float: arc length from the first node to each node of a polyline (n, d)."""
    c = np.asarray(curve, dtype=np.float64)
    return np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(c, axis=0), axis=1))])


def polyline_length(curve: np.ndarray) -> float:
    """Total length of a polyline (n, d)."""
    return float(cumulative_length(curve)[-1])


def resample_polyline(
    curve: np.ndarray, *, count: int | None = None, spacing: float | None = None
) -> np.ndarray:
    """Resample a polyline at constant arc-length spacing, keeping both end points.

    Parameters
    ----------
    curve : (n, d) float, n ≥ 2
    count : int, optional
        Number of output nodes (≥ 2).
    spacing : float, optional
        Target node spacing; the node count is ``ceil(length / spacing) + 1`` so the actual
        spacing is ``length / (count - 1)`` ≤ ``spacing``.

    Returns
    -------
    (count, d) float
    """
    c = np.asarray(curve, dtype=np.float64)
    if c.ndim != 2 or len(c) < 2:
        raise GeometryError("resample_polyline needs an (n, d) array with n >= 2")
    s = cumulative_length(c)
    total = s[-1]
    if (count is None) == (spacing is None):
        raise ParameterError("count/spacing", (count, spacing), "exactly one of them")
    if spacing is not None:
        if not np.isfinite(spacing) or spacing <= 0:
            raise ParameterError("spacing", spacing, "a finite number > 0")
        count = int(np.ceil(total / spacing - 1e-9)) + 1
    assert count is not None  # exactly one of count and spacing, by the test above
    if count < 2:
        raise ParameterError("count", count, "an integer >= 2")
    if total == 0:
        return np.repeat(c[:1], count, axis=0)
    t = np.linspace(0.0, total, count)
    # drop zero-length segments so interpolation is well defined
    keep = np.concatenate([[True], np.diff(s) > 0])
    s, c = s[keep], c[keep]
    return np.stack([np.interp(t, s, c[:, k]) for k in range(c.shape[1])], axis=1)


def bernstein(n: int, t: np.ndarray) -> np.ndarray:
    """Bernstein basis B_i^n(t) (paper formula 1).

    Returns
    -------
    (len(t), n + 1) float
    """
    t = np.asarray(t, dtype=np.float64)[:, None]
    coef = np.array([comb(n, k) for k in range(n + 1)], dtype=np.float64)[None, :]
    # t^i and (1 - t)^(n - i) by repeated products, not numpy's power (whose AVX-512 loop
    # differs from the others in the last bits: see ionic_usd.geometry.libm)
    return coef * _powers(t, n) * _powers(1.0 - t, n)[:, ::-1]


def _powers(x: np.ndarray, n: int) -> np.ndarray:
    """(s, n + 1): x^0 .. x^n for a column x (s, 1), each the product of the one before."""
    out = np.empty((len(x), n + 1))
    out[:, :1] = 1.0
    out[:, 1:] = x
    return np.multiply.accumulate(out, axis=1)


def bezier(control: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Points of a Bézier curve of any degree (paper formula 2).

    Parameters
    ----------
    control : (k, d) float, k ≥ 2
    t : (s,) float in [0, 1]

    Returns
    -------
    (s, d) float
    """
    p = np.asarray(control, dtype=np.float64)
    return libm.linear(bernstein(len(p) - 1, t), p.T)  # Σ_i B_i(t) P_i, in the order of i


def pchip(x: np.ndarray, y: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Monotone piecewise cubic Hermite interpolation (PCHIP; Fritsch & Carlson 1980, the
    derivatives of Fritsch & Butland 1984) of the knots (``x`` strictly increasing, ``y``) at
    ``t`` in [x[0], x[-1]]: smooth, and never overshooting the knots' values.

    The slopes are those of ``scipy.interpolate.PchipInterpolator`` (interior: the weighted
    harmonic mean of the neighbouring secants, 0 where they change sign or one is 0; ends: the
    shape-preserving three-point formula), evaluated as the cubic Hermite form; two knots give
    the straight line. (Tested against scipy; written here because importing
    ``scipy.interpolate`` costs half a second of every capital build for five knots.)
    """
    x = np.asarray(x, dtype=np.float64)
    y = np.asarray(y, dtype=np.float64)
    t = np.asarray(t, dtype=np.float64)
    h = np.diff(x)
    m = np.diff(y) / h
    d = np.empty_like(y)
    if len(x) == 2:
        d[:] = m[0]
    else:
        w1 = 2.0 * h[1:] + h[:-1]
        w2 = h[1:] + 2.0 * h[:-1]
        flat = (np.sign(m[1:]) != np.sign(m[:-1])) | (m[1:] == 0.0) | (m[:-1] == 0.0)
        with np.errstate(divide="ignore", invalid="ignore"):
            whmean = (w1 / m[:-1] + w2 / m[1:]) / (w1 + w2)
            d[1:-1] = np.where(flat, 0.0, 1.0 / whmean)
        d[0] = _pchip_end(h[0], h[1], m[0], m[1])
        d[-1] = _pchip_end(h[-1], h[-2], m[-1], m[-2])
    k = np.clip(np.searchsorted(x, t, side="right") - 1, 0, len(x) - 2)
    s = (t - x[k]) / h[k]
    s2, s3 = s * s, s * s * s
    return (
        (2 * s3 - 3 * s2 + 1) * y[k]
        + (s3 - 2 * s2 + s) * h[k] * d[k]
        + (-2 * s3 + 3 * s2) * y[k + 1]
        + (s3 - s2) * h[k] * d[k + 1]
    )


def _pchip_end(h0: float, h1: float, m0: float, m1: float) -> float:
    """PCHIP's end slope: the three-point estimate, kept shape-preserving."""
    d = ((2 * h0 + h1) * m0 - h0 * m1) / (h0 + h1)
    if np.sign(d) != np.sign(m0):
        return 0.0
    if np.sign(m0) != np.sign(m1) and abs(d) > abs(3 * m0):
        return 3 * m0
    return float(d)


def ring_angles(segments: int) -> np.ndarray:
    """(segments,) float: angles of a ring's vertices, starting at 0, increasing."""
    return np.arange(segments) * (2.0 * np.pi / segments)


def ring(radius: float | np.ndarray, y: float, segments: int) -> np.ndarray:
    """(segments, 3) float: a horizontal circle about the +Y axis, vertex 0 at +X."""
    th = ring_angles(segments)
    r = np.broadcast_to(np.asarray(radius, dtype=np.float64), th.shape)
    return np.stack([r * np.cos(th), np.full_like(th, y), -r * np.sin(th)], axis=1)


def revolve(
    profile: np.ndarray,
    segments: int,
    *,
    name: str = "revolved",
    axis_tol: float = 1e-12,
) -> tuple[Mesh, list[np.ndarray]]:
    """Revolve a half-profile about the +Y axis into a triangle mesh (a lathe).

    Parameters
    ----------
    profile : (n, 2) float
        (radius, height) nodes. Traverse the solid's section counter-clockwise (outer side
        going up, a top face going inward, a bottom face going outward) so faces point out.
        A node on the axis (radius ≤ ``axis_tol``) becomes a single vertex (a cap centre).
    segments : int ≥ 3

    Returns
    -------
    mesh : Mesh without normals
    rows : list of (segments,) or (1,) int arrays, the vertex indices of each profile node
    """
    prof = np.asarray(profile, dtype=np.float64)
    if prof.ndim != 2 or prof.shape[1] != 2 or len(prof) < 2:
        raise GeometryError("revolve needs an (n, 2) profile with n >= 2")
    if segments < 3:
        raise ParameterError("segments", segments, "an integer >= 3", context="revolve")
    if np.any(prof[:, 0] < -axis_tol):
        raise GeometryError("revolve: profile radius below zero crosses the axis")
    pts, rows, start = [], [], 0
    for r, y in prof:
        if r <= axis_tol:
            pts.append(np.array([[0.0, y, 0.0]]))
            rows.append(np.array([start]))
            start += 1
        else:
            pts.append(ring(r, y, segments))
            rows.append(np.arange(start, start + segments))
            start += segments
    tris = [
        stitch(rows[k], rows[k + 1], is_closed=True)
        for k in range(len(rows) - 1)
        if not (len(rows[k]) == 1 and len(rows[k + 1]) == 1)
    ]
    mesh = Mesh(
        np.concatenate(pts),
        np.full(sum(len(t) for t in tris), 3, dtype=np.int32),
        np.concatenate(tris).reshape(-1),
        name=name,
    )
    return mesh, rows
