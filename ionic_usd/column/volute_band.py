"""What both volute models share: the θ range, the band's thickness and the sampling of the
band-crossing checks. :mod:`ionic_usd.column.volute` (the parameters and the log spiral) and
:mod:`ionic_usd.column.volute_arcs` (the centred arcs) both build on this module, so neither
imports the other's internals.
"""

from __future__ import annotations

import math
from typing import Protocol

import numpy as np

__all__ = [
    "VoluteShape",
    "CHECK_PER_TURN",
    "spiral_limit",
    "band_thickness",
    "turn_samples",
    "worst_crossing",
]

#: θ samples per turn used by the validity checks (exact 2π pairing)
CHECK_PER_TURN = 720


class VoluteShape(Protocol):
    """The attributes the curve functions read (a ``VoluteParams`` or a fitter's stand-in)."""

    @property
    def theta_start(self) -> float: ...

    @property
    def theta_end(self) -> float: ...

    @property
    def start_angle(self) -> float: ...

    @property
    def increasing_max(self) -> float: ...

    @property
    def thickness(self) -> float: ...

    @property
    def min_thickness(self) -> float: ...

    @property
    def capital_circle_radius(self) -> float: ...

    @property
    def capital_spiral_radius(self) -> float: ...

    @property
    def arc_square(self) -> float: ...

    @property
    def arc_ratio(self) -> float: ...

    @property
    def eye_center(self) -> np.ndarray: ...


def spiral_limit(circuits: float) -> float:
    """Upper θ limit (radians) for ``circuits`` spiral circuits: ``2.5π + 2π(n − 1)``."""
    return 2.5 * math.pi + 2.0 * math.pi * (circuits - 1.0)


def band_thickness(p: VoluteShape, theta: np.ndarray | float) -> np.ndarray:
    """Band thickness at θ (spiral units): linear from ``min_thickness`` at the start angle to
    ``thickness`` at ``increasing_max``, constant after."""
    th = np.asarray(theta, dtype=np.float64)
    t0, t1 = p.theta_start, math.radians(p.increasing_max)
    if t1 <= t0:
        return np.full_like(th, p.thickness)
    u = np.clip((th - t0) / (t1 - t0), 0.0, 1.0)
    return p.min_thickness + (p.thickness - p.min_thickness) * u


def turn_samples(theta_start: float, theta_end: float, turns: int = 1) -> np.ndarray:
    """θ samples (radians) whose partners ``θ + 2π·turns`` still lie in the range.

    Two points of the band lie on one ray from the centre only when their θ differ by a whole
    number of turns, so a crossing check compares the band at these samples with the band
    ``turns`` turns later (:data:`CHECK_PER_TURN` samples per turn, at least 5 in all).

    Returns
    -------
    (m,) float, from ``theta_start`` to ``theta_end − 2π·turns``.
    """
    span = theta_end - theta_start - 2 * math.pi * turns
    m = max(4, int(math.ceil(span / (2 * math.pi) * CHECK_PER_TURN)))
    return np.linspace(theta_start, theta_end - 2 * math.pi * turns, m + 1)


def worst_crossing(gap: np.ndarray) -> int | None:
    """Index of the smallest gap between two turns of the band if it is not positive (the band
    crosses itself there), else None."""
    j = int(np.argmin(gap))
    return j if gap[j] <= 0 else None
