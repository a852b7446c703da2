"""Tangent-continuous chains of circular arcs — the carved volute's free-arc model.

A chain is a first centre ``C_0``, the start direction ``φ_0`` (the angle of the first point
seen from ``C_0``), a turning sense ``s`` (+1 counter-clockwise), the radii ``ρ_j`` and the
sweeps ``Δ_j`` (radians). Arc ``j`` runs from ``φ_j`` to ``φ_{j+1} = φ_j + s·Δ_j`` about
``C_j``; tangent continuity fixes the next centre: ``C_{j+1} = C_j + (ρ_j − ρ_{j+1})·u(φ_{j+1})``
(the joint lies on the line through both centres). The centred-arc construction
(:func:`~ionic_usd.column.volute_arcs.arc_centres`) is the chain whose radii step linearly and
whose sweeps are quarter turns; ``free_arcs`` frees every radius.

The fit is least squares on the signed distances of the reference's nodes to the chain, and
the models are compared by an information criterion on those residuals (:func:`criterion`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from ionic_usd.column.volute import VoluteParams
from ionic_usd.column.volute_arcs import arc_centres

__all__ = [
    "ArcChain",
    "chain_from_centred",
    "volute_from_chain",
    "chain_residuals",
    "criterion",
    "fit_chain",
    "free_parameters",
]


@dataclass(frozen=True)
class ArcChain:
    """A tangent-continuous arc chain (module docstring); lengths in metres, angles radians."""

    c0: tuple[float, float]
    phi0: float
    sense: float
    radii: np.ndarray
    sweeps: np.ndarray

    def frame(self) -> tuple[np.ndarray, np.ndarray]:
        """Centres (k, 2) and start angles (k,) of the arcs."""
        phi = self.phi0 + self.sense * np.concatenate([[0.0], np.cumsum(self.sweeps[:-1])])
        u = np.stack([np.cos(phi[1:]), np.sin(phi[1:])], axis=1)
        steps = (self.radii[:-1] - self.radii[1:])[:, None] * u
        centres = np.vstack([[0.0, 0.0], np.cumsum(steps, axis=0)]) + np.asarray(self.c0)
        return centres, phi

    def points(self, per_arc: int = 64) -> np.ndarray:
        """(k·per_arc + 1, 2) points along the chain, in order."""
        centres, phi = self.frame()
        out = []
        for c, r, a, d in zip(centres, self.radii, phi, self.sweeps, strict=True):
            t = a + self.sense * np.linspace(0.0, d, per_arc, endpoint=False)
            out.append(c + r * np.stack([np.cos(t), np.sin(t)], axis=1))
        end = phi[-1] + self.sense * self.sweeps[-1]
        out.append(centres[-1] + self.radii[-1] * np.array([[math.cos(end), math.sin(end)]]))
        return np.vstack(out)


def chain_from_centred(
    p: VoluteParams, mirrored: bool, translation: tuple[float, float]
) -> ArcChain:
    """The chain of a fitted ``centred_arcs`` volute placed by its pose (mirror, translation)."""
    centres, radii, th0 = arc_centres(p)
    sweeps = np.full(len(radii), 0.5 * math.pi)
    if p.arc_sweeps:  # a free chain's own joints
        sweeps[:-1] = np.radians(p.arc_sweeps)
    sweeps[-1] = p.theta_end - th0[-1]
    sign = -1.0 if mirrored else 1.0
    c0 = (sign * centres[0, 0] + translation[0], centres[0, 1] + translation[1])
    phi0 = float(th0[0]) if not mirrored else math.pi - float(th0[0])
    return ArcChain(c0, phi0, sign, np.asarray(radii, dtype=float), sweeps)


def volute_from_chain(
    chain: ArcChain, base: VoluteParams, mirrored: bool, translation: tuple[float, float]
) -> VoluteParams:
    """The :class:`VoluteParams` that draw ``chain`` (placed by the pose a centred-arc fit gave
    ``base``: mirror, then translation): the free chain of the centred-arc model, its radii
    and sweeps as fitted, its start and eye (the centres' centroid) in the model's frame, the
    θ limit at the chain's end; ``base``'s band (thickness) and spiral radius kept.

    The inverse of :func:`chain_from_centred` for any chain: ``chain_from_centred(
    volute_from_chain(c, base, m, t), m, t)`` is ``c``. Raises what :class:`VoluteParams`
    raises when the chain makes no valid volute (a band crossing itself)."""
    sign = -1.0 if mirrored else 1.0
    if chain.sense != sign:
        raise ValueError("volute_from_chain: the chain turns against the pose's mirror")
    centres, _ = chain.frame()
    model = np.column_stack(
        [sign * (centres[:, 0] - translation[0]), centres[:, 1] - translation[1]]
    )
    phi0 = chain.phi0 if not mirrored else math.pi - chain.phi0
    theta_end = phi0 + float(np.sum(chain.sweeps))
    eye = model.mean(axis=0)
    return replace(
        base,
        volute_model="centred_arcs",
        start_angle=math.degrees(phi0),
        spiral_circuits=(theta_end - 2.5 * math.pi) / (2.0 * math.pi) + 1.0,
        capital_circle_radius=float(chain.radii[0]),
        offset_x=float(eye[0]),
        offset_y=float(eye[1]),
        arc_radii=tuple(float(r) for r in chain.radii),
        arc_sweeps=tuple(float(np.degrees(d)) for d in chain.sweeps[:-1]),
    )


def chain_residuals(chain: ArcChain, pts: np.ndarray) -> np.ndarray:
    """Signed distance of each point to the chain (to its nearest arc; outside an arc's span
    the distance to the arc's nearer end, unsigned)."""
    centres, phi = chain.frame()
    d = pts[:, None, :] - centres[None, :, :]
    dist = np.hypot(d[..., 0], d[..., 1])
    ang = np.arctan2(d[..., 1], d[..., 0])
    t = np.mod(chain.sense * (ang - phi[None, :]), 2.0 * math.pi)
    radial = dist - chain.radii[None, :]
    ends = []
    for a in (phi, phi + chain.sense * chain.sweeps):
        e = centres + chain.radii[:, None] * np.stack([np.cos(a), np.sin(a)], axis=1)
        ends.append(np.linalg.norm(pts[:, None, :] - e[None, :, :], axis=2))
    inside = t <= chain.sweeps[None, :]
    cand = np.where(inside, radial, np.minimum(ends[0], ends[1]))
    j = np.argmin(np.abs(cand), axis=1)
    return cand[np.arange(len(pts)), j]


def _unpack(x: np.ndarray, base: ArcChain, model: str) -> ArcChain:
    k = len(base.radii)
    sweeps = base.sweeps.copy()
    sweeps[-1] = x[3]
    if model == "free_joints":  # every radius and every joint (sweep) free
        sweeps[:-1] = x[4 + k :]
    if model in ("free_arcs", "free_joints"):
        radii = np.asarray(x[4 : 4 + k])
    else:  # centred: ρ_0 (outer or inner end as the chain runs) plus linear steps
        r0, s_first, s_last = x[4], x[5], x[6]
        steps = np.linspace(s_first, s_last, k - 1) if k > 1 else np.zeros(0)
        radii = r0 + np.concatenate([[0.0], np.cumsum(steps)])
    return replace(
        base, c0=(float(x[0]), float(x[1])), phi0=float(x[2]), radii=radii, sweeps=sweeps
    )


def free_parameters(chain: ArcChain, model: str) -> int:
    """How many parameters :func:`fit_chain` frees for ``model`` on this chain."""
    return len(_pack(chain, model))


def _pack(chain: ArcChain, model: str) -> np.ndarray:
    head = [chain.c0[0], chain.c0[1], chain.phi0, chain.sweeps[-1]]
    if model == "free_arcs":
        return np.array(head + list(chain.radii))
    if model == "free_joints":
        return np.array(head + list(chain.radii) + list(chain.sweeps[:-1]))
    steps = np.diff(chain.radii)
    first, last = (steps[0], steps[-1]) if len(steps) else (0.0, 0.0)
    return np.array([*head, chain.radii[0], first, last])


def fit_chain(chain: ArcChain, pts: np.ndarray, model: str) -> tuple[ArcChain, float, int]:
    """Least-squares fit of a chain (``centred_arcs``: radius steps linear; ``free_arcs``:
    every radius free) to points; the pose is the first centre and start direction, the end
    the last sweep.

    Returns
    -------
    the fitted chain, its residual sum of squares, the number of free parameters
    """
    from scipy.optimize import least_squares

    x0 = _pack(chain, model)

    def fun(x: np.ndarray) -> np.ndarray:
        c = _unpack(x, chain, model)
        if np.any(c.radii <= 0) or np.any(c.sweeps <= 0):
            return np.full(len(pts) + 4, 1e3 * float(np.ptp(pts)))
        return _residuals(c, pts)

    scale = float(np.mean(chain.radii))
    x_scale = np.full(len(x0), scale)
    x_scale[2:4] = 1.0
    if model == "free_joints":
        x_scale[4 + len(chain.radii) :] = 1.0
    sol = least_squares(fun, x0, x_scale=x_scale, method="lm", max_nfev=200 * len(x0))
    best = _unpack(sol.x, chain, model)
    rss = float(np.sum(chain_residuals(best, pts) ** 2))  # the nodes' residuals only
    return best, rss, len(x0)


def _residuals(chain: ArcChain, pts: np.ndarray) -> np.ndarray:
    """The nodes' distances to the chain, then the chain's ends against the first and last
    node (a chain running past the traced ends would otherwise cost nothing)."""
    centres, phi = chain.frame()
    end = phi[-1] + chain.sense * chain.sweeps[-1]
    first = centres[0] + chain.radii[0] * np.array([math.cos(phi[0]), math.sin(phi[0])])
    last = centres[-1] + chain.radii[-1] * np.array([math.cos(end), math.sin(end)])
    return np.concatenate([chain_residuals(chain, pts), first - pts[0], last - pts[-1]])


def criterion(rss: float, n: int, k: int, size: float) -> dict[str, float]:
    """AIC and BIC of a least-squares fit (Gaussian residuals, unknown variance):
    ``n·ln(RSS/n) + 2k`` and ``n·ln(RSS/n) + k·ln n``; lower is better.

    The residuals' rms is floored at 1e-5 of ``size`` (the reference's diagonal): a drawing
    exact to the last digit would otherwise let rounding choose the model; at the floor the
    parameter count alone decides (the simpler model)."""
    floor = n * (1e-5 * size) ** 2
    ll = n * math.log(max(rss, floor) / n)
    return {
        "aic": ll + 2.0 * k,
        "bic": ll + k * math.log(n),
        "rss": rss,
        "points": float(n),
        "parameters": float(k),
    }
