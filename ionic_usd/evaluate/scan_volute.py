"""The scanned capital's volute (:mod:`ionic_usd.evaluate.scan_capital`): the log spiral's
growth as one number to fit, and the circle the volutes' rolls lie on, where the fit starts
the volute's eye."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from ionic_usd.column.capital import CapitalParams
from ionic_usd.column.volute import VoluteParams

__all__ = [
    "bolster_circle",
    "circle_fit",
    "solve_for",
    "roll_circle",
    "spiral_growth",
    "with_growth",
]


def spiral_growth(v: VoluteParams) -> float:
    """The log spiral's radius ratio over half a turn, ``q = e^{cπ}`` (< 1: r grows
    outwards; the Vitruvian volute's 0.70)."""
    return float(np.exp(v.c * np.pi))


def with_growth(v: VoluteParams, q: float, turns: float | None = None) -> VoluteParams:
    """``v``'s log spiral with the half-turn ratio ``q``, its top end (r = 1) and its eye's
    radius ratio (``capital_circle_radius / capital_spiral_radius``) kept: with ``n`` half
    turns from the eye to the top, ``E(1 - q^n) = 1 - e`` and ``r = E q^j - d`` (b = 1), the
    Vitruvian construction (:func:`~ionic_usd.column.volute.vitruvian_coefficients`) with
    another ratio between its turns. ``q`` towards 1 is the Archimedean limit (turns evenly
    spaced). ``turns``: the spiral's circuits instead of ``v``'s."""
    from ionic_usd.column.volute import spiral_limit

    turns = v.spiral_circuits if turns is None else turns
    end = spiral_limit(turns)
    e = v.capital_circle_radius / v.capital_spiral_radius
    n = (end - v.theta_start) / np.pi
    big = (1.0 - e) / (1.0 - q**n)
    c = float(np.log(q) / np.pi)
    a = big * float(np.exp(c * end))
    return v.with_(a=a, b=1.0, c=c, d=big - 1.0, spiral_circuits=turns)


def roll_circle(
    qm: np.ndarray, cap: CapitalParams, f_scale: float
) -> tuple[float, float, float] | None:
    """(x, y, radius) of the circle the rolls' points lie on, seen from the side (``|x|``,
    ``y``; capital frame): the points between the volute faces within half to one and a half
    volute radii of ``cap``'s eye, a robust circle fit. None when too few."""
    from scipy.optimize import least_squares

    from ionic_usd.column.capital_body import capital_layout

    lay = capital_layout(cap)
    ey = lay.eye_y + cap.capital_position_y
    big = lay.total_radius
    u, y = np.abs(qm[:, 0]), qm[:, 1]
    rho = np.hypot(u - lay.eye_x, y - ey)
    sel = (np.abs(qm[:, 2]) < 0.85 * lay.back_z) & (rho > 0.5 * big) & (rho < 1.5 * big)
    sel &= y < lay.abacus_y + cap.capital_position_y - 0.05 * big
    if sel.sum() < 30:
        return None
    uv = np.c_[u[sel], y[sel]]
    c = np.array([lay.eye_x, ey, big])
    for trim in (np.inf, 8.0, 4.0, 3.0):  # robust, then the points near the circle only
        res = np.abs(np.hypot(uv[:, 0] - c[0], uv[:, 1] - c[1]) - c[2])
        near = uv[res < trim * f_scale]
        if len(near) < 30:
            return None
        c = least_squares(
            lambda c, p=near: np.hypot(p[:, 0] - c[0], p[:, 1] - c[1]) - c[2],
            c,
            loss="soft_l1",
            f_scale=f_scale,
        ).x
    return float(c[0]), float(c[1]), float(abs(c[2]))


def bolster_circle(cap: CapitalParams, top_radius: float) -> np.ndarray | None:
    """(x, y, radius) of the circle the model's right bolster lies on, seen from the side
    (capital frame, as :func:`roll_circle`): a circle fitted to its points between a tenth and
    three tenths of its half-length from the middle (clear of the belt and of the ends' seat
    in the volute discs). None when the capital has no such bolster (the angle capital)."""
    from ionic_usd.column.capital import build_capital

    parts = build_capital(cap, top_radius=top_radius).as_dict()
    if "bolster_right" not in parts:
        return None
    p = parts["bolster_right"].points
    z = np.abs(p[:, 2])
    sel = (z > 0.1 * z.max()) & (z < 0.3 * z.max())
    return circle_fit(np.c_[np.abs(p[sel, 0]), p[sel, 1] + cap.capital_position_y])


def circle_fit(xy: np.ndarray) -> np.ndarray:
    """(x, y, radius) of the least-squares (Kåsa) circle through points (n, 2)."""
    u, y = xy[:, 0], xy[:, 1]
    a = np.c_[2.0 * u, 2.0 * y, np.ones_like(u)]
    cx, cy, k = np.linalg.lstsq(a, u * u + y * y, rcond=None)[0]
    return np.array([cx, cy, np.sqrt(max(k + cx * cx + cy * cy, 0.0))])


def solve_for(
    measure: Callable[[np.ndarray], np.ndarray | None],
    x: np.ndarray,
    which: tuple[int, ...],
    target: np.ndarray,
    tol: float,
) -> np.ndarray | None:
    """``x`` with its entries ``which`` moved (Newton steps, a finite-difference Jacobian) so
    that the vector ``measure(x)`` (as long as ``which``) is ``target`` within ``tol``; None
    when that takes more than 4 steps or ``measure`` fails."""
    y = np.array(x, dtype=np.float64)
    idx = list(which)
    for _ in range(5):
        b = measure(y)
        if b is None:
            return None
        r = b - target
        if np.abs(r).max() < tol:
            return y
        jac = np.empty((len(idx), len(idx)))
        for j, k in enumerate(idx):
            yk = y.copy()
            yk[k] += 1e-3
            bk = measure(yk)
            if bk is None:
                return None
            jac[:, j] = (bk - b) / 1e-3
        try:
            y[idx] -= np.linalg.solve(jac, r)
        except np.linalg.LinAlgError:
            return None
    return None
