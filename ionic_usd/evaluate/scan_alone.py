"""A capital scanned alone: no fluted shaft to set the axis, so the capital sets it.

The capital has two mirror planes (through the axis, one facing the volutes, one the
bolsters), so the principal directions of its points lie close to its frame's axes, whichever
pose it was scanned in (a missing sector or holes tilt them a few degrees). Each of the
frames they allow (which direction is up, which sign, which of the other two runs through the
volutes: 12, the capital's 180° turn about its axis halving the 24 of a cube) is placed by
robust least squares (``soft_l1``) of the scan points' distances to the generator's own
capital (:class:`.capital_surface.CapitalSurface`, at unit lower diameter), over a rotation, a
translation and a scale; the frame with the smallest robust cost wins and is polished on more
points. The scale is the lower diameter (the Vitruvian capital scales with it), the
rotation's y column the axis.

:func:`is_fluted` tells whether a shaft's slab carries flutes: the fitted fluted section
through it must follow its points to a small fraction of the radius (a capital's section,
cut across its volutes by a wrong axis, does not).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ionic_usd.errors import GeometryError

__all__ = ["CapitalPose", "capital_pose", "is_fluted"]


def is_fluted(xy: np.ndarray, sec: dict[str, float], *, tol: float = 0.02) -> bool:
    """True when the fitted fluted section ``sec`` (:func:`.scan_section.section_at`) follows
    the slab's points ``xy`` (n, 2): their median distance below ``tol`` × radius (a drum
    seen from a 4° first axis: 0.85 %; a capital's cross-cut: 4.6 %)."""
    from ionic_usd.evaluate.fit_shaft import fluted_section
    from ionic_usd.evaluate.polyline import closest_on_polyline

    poly = fluted_section(
        sec["radius"],
        int(sec["flutes"]),
        sec["flute_angle"],
        sec["flute_depth"],
        sec["rotation_deg"],
        np.array([sec["centre_u"], sec["centre_v"]]),
        slices=12,
    )
    d = closest_on_polyline(np.ascontiguousarray(xy), np.ascontiguousarray(poly))[0]
    return bool(np.median(d) < tol * sec["radius"])


@dataclass(frozen=True)
class CapitalPose:
    """The capital's pose in the scan: ``scan = origin + scale * rotation @ c`` for a point
    ``c`` of the unit-diameter capital's frame (origin at the shaft's top centre, y up).

    Attributes
    ----------
    rotation : (3, 3) float, columns the capital's x (through the volutes), y (up), z
    origin : (3,) float, the shaft's top centre in the scan
    scale : the lower diameter (m)
    rms : rms (m) of the polished points' distances
    cost : the robust cost per point of the winning frame
    candidates : frames tried
    """

    rotation: np.ndarray
    origin: np.ndarray
    scale: float
    rms: float
    cost: float
    candidates: int


#: Bounds of the placement: rotation vector (rad), translation (units of the size), log scale.
_BOUND = np.array([0.6, 0.6, 0.6, 0.5, 0.5, 0.5, 0.35])


def _frames(axes: np.ndarray) -> list[np.ndarray]:
    """Right-handed frames (columns x, y, z) from three principal directions (columns)."""
    out = []
    for iy in range(3):
        for sy in (1.0, -1.0):
            y = sy * axes[:, iy]
            for ix in (i for i in range(3) if i != iy):
                x = axes[:, ix]
                out.append(np.column_stack([x, y, np.cross(x, y)]))
    return out


def capital_pose(points: np.ndarray, *, seed: int = 0, max_points: int = 2000) -> CapitalPose:
    """The pose and scale of a capital scanned alone (module docstring).

    Parameters
    ----------
    points : (n, 3) float, the scan (metres, any pose)

    Returns
    -------
    CapitalPose
    """
    from scipy.optimize import least_squares
    from scipy.spatial.transform import Rotation

    from ionic_usd.column.column import portunus_column_params
    from ionic_usd.evaluate.capital_surface import capital_surface

    pts = np.asarray(points, dtype=np.float64)
    if len(pts) < 200:
        raise GeometryError(f"too few points ({len(pts)}) to place a capital")
    rng = np.random.default_rng(seed)
    q = pts[rng.permutation(len(pts))[:max_points]]
    unit = portunus_column_params(lower_diameter=1.0)
    surf = capital_surface(unit.capital, unit.shaft.top_radius, count=60_000)
    m_c = surf.samples.mean(axis=0)
    m_r = float(np.sqrt(np.mean(np.sum((surf.samples - m_c) ** 2, axis=1))))
    c_s = q.mean(axis=0)
    cen = q - c_s
    s0 = float(np.sqrt(np.mean(np.sum(cen**2, axis=1)))) / m_r  # size: rms radius
    axes = np.linalg.eigh(cen.T @ cen)[1]
    f_scale = 0.002  # 2 mm at unit diameter (residuals in units of the scan's size s0)

    def residuals(x: np.ndarray, r0: np.ndarray, sel: np.ndarray) -> np.ndarray:
        rot = Rotation.from_rotvec(x[:3]).as_matrix() @ r0
        s = s0 * float(np.exp(x[6]))
        t = c_s + x[3:6] * s0 - s * rot @ m_c  # the model's centroid near the scan's
        c = ((sel - t) @ rot) / s
        return surf.distance(c) * (s / s0)  # the scan's lengths: a larger model gains nothing

    def fit(r0: np.ndarray, x0: np.ndarray, sel: np.ndarray, nfev: int):
        return least_squares(
            residuals,
            x0,
            args=(r0, sel),
            bounds=(-_BOUND, _BOUND),
            loss="soft_l1",
            f_scale=f_scale,
            x_scale=np.array([0.05, 0.05, 0.05, 0.02, 0.02, 0.02, 0.02]),
            diff_step=1e-3,
            max_nfev=nfev,
        )

    few = q[:400]
    tried = []
    for r0 in _frames(axes):
        sol = fit(r0, np.zeros(7), few, 40)
        tried.append((float(sol.cost), r0, sol.x))
    cost, r0, x = min(tried, key=lambda t: t[0])
    sol = fit(r0, x, q, 80)
    rot = Rotation.from_rotvec(sol.x[:3]).as_matrix() @ r0
    s = s0 * float(np.exp(sol.x[6]))
    t = c_s + sol.x[3:6] * s0 - s * rot @ m_c
    d = residuals(sol.x, r0, q) * s0
    return CapitalPose(
        rot, t, s, float(np.sqrt(np.mean(d**2))), float(sol.cost) / len(q), len(tried)
    )
