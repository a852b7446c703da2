"""The centred-arc volute (``volute_model = "centred_arcs"``): quarter circles about centres
walking a square spiral in the eye — the Vitruvian construction as Alberti, Serlio, Vignola and
Palladio draw it. :mod:`ionic_usd.column.volute` dispatches here; the shared θ range, band
thickness and crossing-check sampling are in :mod:`ionic_usd.column.volute_band`. The parameters
live in :class:`~ionic_usd.column.volute.VoluteParams` (``capital_circle_radius`` is the first arc's
radius, ``arc_square`` and ``arc_ratio`` the centres' squares, ``start_angle`` and
``spiral_circuits`` the θ range, ``thickness``/``min_thickness`` the band as for the spiral).
"""

from __future__ import annotations

import math

import numpy as np

from ionic_usd.column.volute_band import VoluteShape, band_thickness, turn_samples, worst_crossing
from ionic_usd.errors import GeometryError, ParameterError

__all__ = ["arc_centres", "arc_points", "chain_arc_count", "check_arcs"]


def check_arcs(p: VoluteShape) -> None:
    """Refuse centred-arc parameters that give no volute or a band crossing itself.

    Turns are compared along rays from the eye centre, as for the spiral: the band's inner
    edge one turn out must clear the outer edge of the turn inside it.
    """
    ctx = "volute (centred_arcs)"
    if p.arc_square <= 0:
        raise ParameterError("arc_square", p.arc_square, "a length > 0", context=ctx)
    if not 0 < p.arc_ratio <= 4:
        raise ParameterError("arc_ratio", p.arc_ratio, "a ratio in (0, 4]", context=ctx)
    span = p.theta_end - p.theta_start
    if span <= 2 * math.pi:
        return
    th = turn_samples(p.theta_start, p.theta_end)
    o = np.linalg.norm(arc_points(p, th, 0.0) - p.eye_center, axis=1)
    i2 = np.linalg.norm(arc_points(p, th + 2 * math.pi, 1.0) - p.eye_center, axis=1)
    j = worst_crossing(i2 - o)
    if j is not None:
        raise GeometryError(
            "volute (centred_arcs): the band crosses itself at θ = "
            f"{math.degrees(th[j]):.1f} deg (inner edge {i2[j]:.4g} m from the eye centre, "
            f"the turn inside it {o[j]:.4g} m); reduce thickness or widen arc_square"
        )


def arc_centres(p: VoluteShape) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Centres, radii and start angles of the quarter-circle arcs (``centred_arcs``).

    Arc ``j`` turns from θ_j = start + j·90° to θ_{j+1} (the last one may be shorter) about
    centre ``C_j`` with radius ``ρ_j``. ``ρ_0`` is the eye's radius; the radius grows by a step
    ``e_j`` from arc to arc, the steps linear from ``arc_ratio·arc_square`` (innermost) to
    ``arc_square`` (outermost). Tangent continuity puts ``C_{j+1} = C_j − e_j·u(θ_{j+1})``:
    the centres walk a square spiral, shrinking towards the eye — the Vitruvian construction
    as Alberti, Serlio, Vignola and Palladio draw it (three turns, twelve centres on the eye's
    square). The centres' centroid is the eye centre.

    Returns
    -------
    centres : (k, 2) float, metres from the spiral origin
    radii : (k,) float, metres
    theta0 : (k,) float, radians where each arc starts

    With ``arc_radii`` (a free chain, :class:`~ionic_usd.column.volute.VoluteParams`) the
    radii are those, and the arcs turn by ``arc_sweeps`` (degrees; quarter turns without), the
    last one to the θ limit; the centres follow by the same tangency, centroid on the eye.
    """
    given = tuple(getattr(p, "arc_radii", ()))
    if given:  # a free chain (a carved volute fitted arc by arc): radii and joints as given
        radii = np.asarray(given, dtype=np.float64)
        steps = np.diff(radii)
        th0 = _chain_starts(p, len(radii))
    else:
        k = chain_arc_count(p)
        th0 = p.theta_start + 0.5 * math.pi * np.arange(k)
        steps = p.arc_square * np.linspace(p.arc_ratio, 1.0, k - 1) if k > 1 else np.zeros(0)
        radii = p.capital_circle_radius + np.concatenate([[0.0], np.cumsum(steps)])
    u = np.stack([np.cos(th0[1:]), np.sin(th0[1:])], axis=1)
    centres = np.vstack([[0.0, 0.0], -np.cumsum(steps[:, None] * u, axis=0)])
    centres += p.eye_center - centres.mean(axis=0)
    return centres, radii, th0


def arc_points(p: VoluteShape, theta: np.ndarray, inner: float) -> np.ndarray:
    """Points of the centred-arc curve at θ; ``inner`` = 1 gives the band's inner edge."""
    th = np.asarray(theta, dtype=np.float64)
    centres, radii, th0 = arc_centres(p)
    if getattr(p, "arc_sweeps", ()):  # free joints: the arc whose span holds θ
        j = np.clip(np.searchsorted(th0, th + 1e-12, side="right") - 1, 0, len(radii) - 1)
    else:
        j = np.clip(
            np.floor((th - p.theta_start) / (0.5 * math.pi) + 1e-12).astype(np.int64),
            0,
            len(radii) - 1,
        )
    rho = radii[j] - inner * p.capital_spiral_radius * band_thickness(p, th)
    return centres[j] + rho[:, None] * np.stack([np.cos(th), np.sin(th)], axis=1)


def chain_arc_count(p: VoluteShape) -> int:
    """How many arcs the θ range holds as quarter turns (the last one may be shorter)."""
    return max(1, int(math.ceil((p.theta_end - p.theta_start) / (0.5 * math.pi) - 1e-9)))


def _chain_starts(p: VoluteShape, k: int) -> np.ndarray:
    """Where each of ``k`` arcs starts (radians): after ``arc_sweeps`` (degrees), or every
    quarter turn."""
    sweeps = tuple(getattr(p, "arc_sweeps", ()))
    if sweeps:
        return p.theta_start + np.concatenate([[0.0], np.cumsum(np.radians(sweeps))])
    return p.theta_start + 0.5 * math.pi * np.arange(k)
