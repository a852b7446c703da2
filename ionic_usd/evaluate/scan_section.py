"""The shaft's cross-section in a scan: flute count, fluted section fit, taper.

Moved out of :mod:`.fit_scan` (the shaft's stage of :func:`.fit_scan.fit_column_scan`):
the flute count is the strongest harmonic of the outer radius round the axis; radius, flute
angle, depth, rotation and centre are fitted by robust least squares (``soft_l1``) on the
distances from a slab's points to the model section; the outer radius of thin bins gives the
taper (a robust line).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from ionic_usd.errors import GeometryError
from ionic_usd.evaluate.polyline import closest_on_polyline
from ionic_usd.evaluate.scan_alone import is_fluted
from ionic_usd.evaluate.scan_axis import ColumnFrame, find_parts

__all__ = ["outer_profile", "section_at", "shaft_axis_section", "taper"]


def _flutes_from_points(xy: np.ndarray) -> tuple[int, float]:
    """Flute count and a flute centre's angle (deg) from the outer radius round the centre."""
    ang = np.arctan2(xy[:, 1], xy[:, 0])
    rad = np.hypot(xy[:, 0], xy[:, 1])
    nb = 720
    idx = ((ang + np.pi) / (2 * np.pi) * nb).astype(int) % nb
    prof = np.full(nb, np.nan)
    np.fmax.at(prof, idx, rad)
    ok = np.isfinite(prof)
    prof = np.interp(np.arange(nb), np.flatnonzero(ok), prof[ok], period=nb)
    spec = np.fft.rfft(prof - prof.mean())
    k = int(np.argmax(np.abs(spec[6:65]))) + 6
    phase = float(np.angle(spec[k]))
    # prof ≈ A cos(kθ' + phase) with θ' = θ + π: lowest (a flute centre) at kθ' + phase = π
    centre = (np.pi - phase) / k - np.pi
    return k, math.degrees(centre)


def _fit_section_e(
    xy: np.ndarray, r0: float, e: int, centre_deg: float
) -> tuple[int, float, np.ndarray, np.ndarray, np.ndarray]:
    """Fluted section with ``e`` flutes through scattered points (points → model, robust)."""
    from scipy.optimize import least_squares

    from ionic_usd.evaluate.fit_shaft import fluted_section

    period = 360.0 / e
    rot0 = (centre_deg - 0.5 * period) % period  # fluted_section centres flutes at (k+½)p
    pts = np.ascontiguousarray(xy)
    lo = np.array([0.8 * r0, 0.2 * period, 0.05, rot0 - 0.5 * period, -0.1 * r0, -0.1 * r0])
    hi = np.array([1.2 * r0, 0.98 * period, 1.6, rot0 + 0.5 * period, 0.1 * r0, 0.1 * r0])

    def res(x: np.ndarray) -> np.ndarray:
        poly = fluted_section(x[0], e, x[1], x[2], x[3], x[4:6], slices=12)
        return closest_on_polyline(pts, np.ascontiguousarray(poly))[0]

    sols = [
        least_squares(
            res,
            np.array([r0, f0 * period, 1.0, rot0, 0.0, 0.0]),
            bounds=(lo, hi),
            loss="soft_l1",
            f_scale=0.002 * r0,
            x_scale=hi - lo,
            max_nfev=300,
        )
        for f0 in (0.6, 0.8)
    ]
    best = min(sols, key=lambda sol: sol.cost)  # the first of equal costs, as before
    x = best.x
    return e, best.cost, x, lo, hi


def _fit_section(
    xy: np.ndarray, r0: float, flutes: int | None = None
) -> tuple[int, dict[str, float]]:
    """Fluted section through scattered points: the harmonic's flute count and its two
    neighbours are each fitted (a missing sector blurs the spectrum); the lowest cost wins."""
    e0, centre_deg = _flutes_from_points(xy)
    counts = (e0 - 1, e0, e0 + 1) if flutes is None else (flutes,)
    fits = [_fit_section_e(xy, r0, e, centre_deg) for e in counts if e >= 4]
    e, _, x, lo, hi = min(fits, key=lambda f: f[1])
    names = ("radius", "flute_angle", "flute_depth", "rotation_deg", "centre_u", "centre_v")
    vals = dict(zip(names, (float(v) for v in x), strict=True))
    vals["flutes"] = float(e)
    span = hi - lo
    vals["bounds_hit"] = [
        n for n, u in zip(names, (x - lo) / span, strict=True) if u < 1e-3 or u > 1 - 1e-3
    ]  # type: ignore[assignment]
    return e, vals


def taper(loc: np.ndarray, s0: float, s1: float) -> tuple[float, float]:
    """Outer radius along the shaft band (ends trimmed) as a robust line r = a + b h."""
    prof = outer_profile(
        loc, s0 + 0.05 * (s1 - s0), s1 - 0.05 * (s1 - s0), max((s1 - s0) / 40, 0.004)
    )
    if len(prof) < 3:
        raise GeometryError("too few points along the shaft to measure its taper")
    return _robust_line(prof[:, 1], prof[:, 0])


def section_at(
    loc: np.ndarray, h: float, s0: float, s1: float, ra: float, rb: float, flutes: int | None
) -> tuple[int, dict[str, float], np.ndarray, float]:
    """Fit the section through a slab at height ``h``, thick enough for ~1500 points, each
    point scaled radially to the slab's middle by the taper."""
    in_band = int(np.count_nonzero((loc[:, 2] >= s0) & (loc[:, 2] <= s1)))
    half = min(max(0.004, 0.5 * (s1 - s0) * 1500.0 / max(in_band, 1)), 0.15 * (s1 - s0))
    sel = np.abs(loc[:, 2] - h) < half
    if np.count_nonzero(sel) < 200:
        raise GeometryError(
            f"too few points ({np.count_nonzero(sel)}) at the shaft section {h:.3f} m up the axis"
        )
    sl = loc[sel]
    k = (ra + rb * h) / (ra + rb * sl[:, 2])
    slab = (sl[:, :2] * k[:, None])[:4000]
    e, sec = _fit_section(slab, ra + rb * h, flutes)
    return e, sec, slab, half


def _robust_line(h: np.ndarray, r: np.ndarray) -> tuple[float, float]:
    """r ≈ a + b h, Huber-weighted (outer radius per bin; noisy bins and holes)."""
    w = np.ones_like(r)
    a, b = float(np.median(r)), 0.0
    for _ in range(8):
        A = np.column_stack([np.ones_like(h), h]) * w[:, None]
        (a, b), *_ = np.linalg.lstsq(A, r * w, rcond=None)
        res = np.abs(r - a - b * h)
        s = 1.4826 * np.median(res) + 1e-9
        w = np.minimum(1.0, 2.0 * s / np.maximum(res, 1e-12))
    return float(a), float(b)


def outer_profile(loc: np.ndarray, h0: float, h1: float, width: float) -> np.ndarray:
    """(r, h) polyline: the 95th percentile radius of thin bins between h0 and h1."""
    r = np.hypot(loc[:, 0], loc[:, 1])
    edges = np.arange(h0, h1 + 0.5 * width, width)
    out = []
    for a, b in zip(edges[:-1], edges[1:], strict=True):
        sel = (loc[:, 2] >= a) & (loc[:, 2] < b)
        if np.count_nonzero(sel) >= 8:
            out.append((float(np.percentile(r[sel], 95)), 0.5 * (a + b)))
    return np.asarray(out)


def shaft_axis_section(
    sub: np.ndarray, frame: ColumnFrame, notes: list[str]
) -> tuple[ColumnFrame, int, dict, np.ndarray, float] | None:
    """The axis through the centres of two shaft sections and the section fitted a third of
    the way up the shaft in that frame, the axis recentred on it: (frame, flute count,
    section, its slab of points, the shaft band's bottom), or None (with a note) where the
    scan has no fluted shaft.

    Two sections, a quarter and three quarters up the shaft band: their centres set the axis
    far better than the normals (a 1 mm error over 4 m is 0.015°)."""
    if "shaft" not in frame.parts:
        notes.append("no narrow band along the axis: no shaft")
        return None
    e = None
    fracs = (0.25, 0.75)
    for stage in range(3):  # refine twice: a tilted first axis blurs the first slabs
        loc = frame.local(sub)
        s0, s1 = frame.parts["shaft"]
        ra, rb = taper(loc, s0, s1)
        if stage == 0:
            try:
                found = _lowest_fluted(loc, s0, s1, ra, rb)
            except GeometryError:
                notes.append("too few points for a shaft section: no shaft")
                return None
            if isinstance(found, str):
                notes.append(f"no fluted section fits the narrow band ({found}): no shaft")
                return None
            first, e = found  # the count its search chose: the loop fits that count only
            fracs = (first, 0.75 if first < 0.5 else 0.9)
        if stage < 2:
            cs = []
            for frac in fracs:
                h = s0 + frac * (s1 - s0)
                e, sec1, slab1, _ = section_at(loc, h, s0, s1, ra, rb, e)
                cs.append(
                    frame.origin
                    + sec1["centre_u"] * frame.u
                    + sec1["centre_v"] * frame.v
                    + h * frame.direction
                )
            a_new = cs[1] - cs[0]
            frame = find_parts(sub, a_new / np.linalg.norm(a_new), cs[0])
            if "shaft" not in frame.parts:
                raise GeometryError("the shaft band was lost after refining the axis")
    hs = s0 + (s1 - s0) / 3.0
    # the flute count is chosen again in the refined frame (a tilted slab blurs flutes)
    e, sec, slab, half = section_at(loc, hs, s0, s1, ra, rb, None)
    notes.append(
        f"axis through the centres of sections {s0 + 0.25 * (s1 - s0):.3f} and "
        f"{s0 + 0.75 * (s1 - s0):.3f} m up; section from {len(slab)} points within "
        f"±{half * 1000:.3g} mm of {hs:.3f} m"
    )
    # recentre the axis on the fitted section centre
    shift = sec["centre_u"] * frame.u + sec["centre_v"] * frame.v
    return dataclasses.replace(frame, origin=frame.origin + shift), e, sec, slab, s0


#: where the first fluted section is sought, as fractions of the narrow band: its lower part
#: can still be the base's top (a short fragment's band starts at the upper torus)
FIRST_SECTIONS = (0.25, 0.4, 0.55)


def _lowest_fluted(
    loc: np.ndarray, s0: float, s1: float, ra: float, rb: float
) -> tuple[float, int] | str:
    """The lowest of :data:`FIRST_SECTIONS` whose section is fluted and its flute count, or
    what was tried."""
    tried = []
    for frac in FIRST_SECTIONS:
        h = s0 + frac * (s1 - s0)
        e, sec, slab, _ = section_at(loc, h, s0, s1, ra, rb, None)
        if is_fluted(slab, sec):
            return frac, e
        tried.append(f"{e} flutes at {h:.3f} m")
    return ", ".join(tried) + " tried"
