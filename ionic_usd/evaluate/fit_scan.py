"""Whole columns (or fragments) from scans: axis, parts, sections, fits, deviations.

:func:`fit_column_scan` runs the chain on an ``(n, 3)`` point set:

1. the axis and the parts along it (:mod:`.scan_axis`);
2. the shaft: a slab of points a third of the way up the narrow band gives the cross-section;
   the flute count is the strongest harmonic of the outer radius round the axis, then radius,
   flute angle, depth, rotation and centre are fitted by robust least squares (``soft_l1``) on
   the distances from the slab's points to the model section (:func:`.fit_shaft.fluted_section`)
   — points against the model, so missing sectors cost nothing; the outer radius of every bin
   gives the taper (robust line), hence the lower diameter at the shaft's bottom;
3. the base: once the turn about the axis is fixed, its meridian at the plinth's face normals
   (:func:`.scan_parts.base_meridian`, its top at the joint found from the flutes' start,
   :func:`.scan_parts.base_top`) is fitted with :func:`.fit_base.fit_base`; the column
   takes the fitted base unless the base has a square plinth (a lathe grammar cannot rebuild
   its corners; ``fit_base_grammar`` takes it anyway);
4. the capital: the generator's capital fitted to its points — placement, volute size, eye
   height and spacing, for both volute models (:mod:`.scan_capital`);
5. deviations: every scan point's distance to the fitted surfaces — exact to the fitted
   shaft section (scaled by the taper at the point's height), and to the base and capital
   by the nearest of dense surface samples (about 1 mm apart).
"""

from __future__ import annotations

import dataclasses
import math
import time
from dataclasses import dataclass, field
from typing import Any, TypedDict

import numpy as np

from ionic_usd.column.column import ColumnParams, build_column, portunus_column_params
from ionic_usd.errors import GeometryError
from ionic_usd.evaluate.fit_core import FitResult
from ionic_usd.evaluate.scan_axis import ColumnFrame, estimate_axis, find_parts
from ionic_usd.evaluate.scan_capital import CapitalFit
from ionic_usd.evaluate.scan_checks import _check_is_column, _part_report
from ionic_usd.evaluate.scan_deviation import (
    heat_colours,
    other_parts_tree,
    scan_deviation,
    shaft_deviation,
)
from ionic_usd.evaluate.scan_flutes import (
    plinth_turn,
    section_noise,
    shaft_details,
    shaft_taper,
    shaft_top,
)
from ionic_usd.evaluate.scan_parts import base_meridian, base_top, has_square_plinth, to_column
from ionic_usd.evaluate.scan_section import outer_profile, shaft_axis_section

__all__ = ["ScanFit", "ScanSummary", "fit_column_scan", "heat_colours", "scan_deviation"]


class ScanSummary(TypedDict):
    """:meth:`ScanFit.summary`: the R.json keys (lengths in metres, seconds)."""

    diameter: float
    flutes: int
    axis: dict[str, list[float]]  # "point", "direction": (3,) each
    parts_found: list[str]
    part_heights: dict[str, list[float]]  # part -> [h0, h1]
    deviation: dict[str, float]  # "rms", "p95", "max"
    points: int
    section: dict[str, float]
    seconds: float
    parts: dict[str, dict[str, Any]]
    not_fitted: list[str]
    notes: list[str]


@dataclass(eq=False)
class ScanFit:
    """Outcome of :func:`fit_column_scan` (lengths in metres, in the scan's frame).

    Attributes
    ----------
    column : the fitted ColumnParams
    frame : the axis, section basis and parts' heights
    matrix : (4, 4) column coordinates → scan (row vectors, as USD)
    diameter : lower shaft diameter
    flutes : flute count
    section : fitted section values (radius, flute_angle, flute_depth, rotation_deg, …)
    base : the base's FitResult (its meridian), or None
    deviation : (n,) per point
    notes : what was inferred, assumed or skipped
    fits : per part found, what was fitted (model, measures) or only rebuilt, and the
        deviations (rms, p95) of its points
    """

    column: ColumnParams
    frame: ColumnFrame
    matrix: np.ndarray
    diameter: float
    flutes: int
    section: dict[str, float]
    base: FitResult | None
    deviation: np.ndarray
    seconds: float
    slab: np.ndarray = field(repr=False)
    profile: np.ndarray | None = field(default=None, repr=False)
    notes: list[str] = field(default_factory=list)
    fits: dict[str, dict[str, Any]] = field(default_factory=dict)

    def not_fitted(self) -> list[str]:
        """What the scan does not show, kept from the column description."""
        found = self.frame.parts
        out = [p for p in ("base", "shaft", "capital") if p not in found]
        if "shaft" in found and not ("base" in found and "capital" in found):
            out.append("shaft length and top ring")
        return out

    def summary(self) -> ScanSummary:
        """The R.json keys: diameter, flutes, axis, parts_found, deviation, …"""
        d = self.deviation
        return {
            "diameter": self.diameter,
            "flutes": self.flutes,
            "axis": {
                "point": self.frame.origin.tolist(),
                "direction": self.frame.direction.tolist(),
            },
            "parts_found": sorted(self.frame.parts),
            "part_heights": {k: list(v) for k, v in self.frame.parts.items()},
            "deviation": {
                "rms": float(np.sqrt(np.mean(d**2))),
                "p95": float(np.percentile(d, 95)),
                "max": float(d.max()),
            },
            "points": int(len(d)),
            "section": self.section,
            "seconds": self.seconds,
            "parts": self.fits,
            "not_fitted": self.not_fitted(),
            "notes": self.notes,
        }


def fit_column_scan(
    points: np.ndarray,
    *,
    seed: int = 0,
    max_fit_points: int = 60_000,
    fit_base_grammar: bool = False,
) -> ScanFit:
    """Fit a column to a scan (module docstring).

    Parameters
    ----------
    points : (n, 3) float, metres, any pose
    max_fit_points : the axis and the fits use a random subset of at most this many points;
        the deviations cover every point
    fit_base_grammar : the column takes the fitted (lathe) base even on a square plinth

    Returns
    -------
    ScanFit
    """

    t0 = time.perf_counter()
    pts = np.asarray(points, dtype=np.float64)
    if pts.ndim != 2 or pts.shape[1] != 3 or len(pts) < 100 or not np.all(np.isfinite(pts)):
        raise GeometryError("scan: at least 100 finite points (x, y, z) needed")
    from ionic_usd.evaluate.scan_io import check_scan_extent

    check_scan_extent(pts, "scan")
    rng = np.random.default_rng(seed)
    sub = (
        pts
        if len(pts) <= max_fit_points
        else pts[rng.choice(len(pts), max_fit_points, replace=False)]
    )
    a, c, resid = estimate_axis(sub, seed=seed)
    frame = find_parts(sub, a, c)
    notes = [f"axis: normal lines meet it within {resid * 1000:.3g} mm (median)"]
    found = shaft_axis_section(sub, frame, notes)
    if found is None:
        return _capital_alone(pts, sub, seed, notes, t0)
    frame, e, sec, slab, s0 = found
    loc = frame.local(sub)
    noise = section_noise(slab, sec, e)
    notes.append(f"noise {noise * 1000:.3g} mm (1.4826 × the section's median residual)")
    det = shaft_details(loc, frame.parts, sec, e, noise)
    frame, ring_bottom = _plain_ring(frame, loc, det, sec, e, notes)
    r_bottom = det["a"] + det["b"] * frame.parts["shaft"][0]
    diameter = 2.0 * r_bottom
    col = portunus_column_params(lower_diameter=diameter, flutes=e)
    if "base" in frame.parts and ring_bottom is None:
        frame = _joint(frame, loc, col, r_bottom, sec, notes)
    col = _scanned_shaft(col, frame, loc, det, sec, e, ring_bottom, notes)
    has_base, has_cap = "base" in frame.parts, "capital" in frame.parts
    bprof = _base_profile(frame, loc, notes)
    tree = other_parts_tree(col)
    m, col = _turn_about_axis(sub, rng, frame, col, sec, e, s0, tree, notes)
    base_fit = None
    if has_base:  # the turn about the axis is known now: the plinth's faces face ±x, ±z
        col, base_fit = _fit_scanned_base(
            to_column(sub, m), col, frame, notes, fit_base_grammar, noise
        )
        if base_fit is not None:
            tree = other_parts_tree(col)
    cap_fit = None
    if has_cap:
        col, m, cap_fit = _fit_capital(sub, col, m, has_base, notes)
        if has_base:  # its length set by the capital: the taper again, the top ring seen
            col = shaft_top(
                to_column(sub, m), frame.local(sub), frame.parts["shaft"], sec, col, noise, notes
            )
        tree = other_parts_tree(col)
    dev = scan_deviation(pts, col, m, tree=tree)
    fits = _part_report(frame.local(pts)[:, 2], dev, frame, sec, base_fit, col, cap_fit)
    _check_is_column(fits, diameter, e)
    secs = time.perf_counter() - t0
    return ScanFit(col, frame, m, diameter, e, sec, base_fit, dev, secs, slab, bprof, notes, fits)


def _base_profile(frame: ColumnFrame, loc: np.ndarray, notes: list[str]) -> np.ndarray | None:
    """The scanned base's outer profile (thin height bins), or None (with a note)."""
    if "base" not in frame.parts:
        notes.append("no base in the scan: the column's base is the Vitruvian one")
        return None
    b0, b1 = frame.parts["base"]
    return outer_profile(loc, b0, b1, max((b1 - b0) / 80, 0.002))


def _plain_ring(
    frame: ColumnFrame, loc: np.ndarray, det: dict, sec: dict, e: int, notes: list[str]
) -> tuple[ColumnFrame, float | None]:
    """Where a base is scanned and the flutes' lower tip found: the frame with the base
    ending where its mouldings do, and the plain ring's height between them and the tip;
    else the frame as it is and None."""
    if "base" not in frame.parts or not math.isfinite(det["tip"]):
        return frame, None
    b0 = frame.parts["base"][0]
    joint, tip = det["joint"], det["tip"]
    # no step between the mouldings and the ring: the base may end in a fillet at the
    # ring's radius; the joint the flutes' start gives (the model's ring below them)
    # then splits the plain part
    r0 = det["a"] + det["b"] * joint
    col0 = portunus_column_params(lower_diameter=2.0 * r0, flutes=e)
    onset = _joint(frame, loc, col0, r0, sec, []).parts["base"][1]
    if joint < onset < tip:
        joint = onset
    notes.append(
        f"flutes end {tip - b0:.4f} m up (the tip whose flute ends fit best); the base's "
        f"mouldings end at {joint - b0:.4f} m: plain ring {(tip - joint) * 1000:.3g} mm"
    )
    parts = dict(frame.parts, base=(b0, joint), shaft=(joint, frame.parts["shaft"][1]))
    return dataclasses.replace(frame, parts=parts), tip - joint


def _scanned_shaft(
    col: ColumnParams,
    frame: ColumnFrame,
    loc: np.ndarray,
    det: dict,
    sec: dict,
    e: int,
    ring_bottom: float | None,
    notes: list[str],
) -> ColumnParams:
    """``col`` with the scanned shaft: its plain ring, its length and top radius on a whole
    column (the capital's volutes hang below the shaft's top: the hang measured on the
    model), the taper and entasis where the points allow, the flutes' count, angle, depth."""
    r_bottom = det["a"] + det["b"] * frame.parts["shaft"][0]
    sh = col.shaft
    if ring_bottom is not None:
        sh = dataclasses.replace(sh, ring_bottom=max(ring_bottom, 0.0))
    top_ratio = (r_bottom + det["b"] * sh.length) / r_bottom
    if "base" in frame.parts and "capital" in frame.parts:
        built = build_column(col)
        low = min(m.points[:, 1].min() for k, m in built.parts().items() if k.startswith("Capital"))
        hang = built.base_height + built.shaft_length - float(low)
        length = frame.parts["capital"][0] + hang - frame.parts["base"][1]
        r_top = det["a"] + det["b"] * frame.parts["capital"][0]
        top_ratio = r_top / r_bottom
        notes.append("whole column: shaft length and top radius measured")
        sh = dataclasses.replace(sh, height=max(length - sh.length + sh.height, 0.1))
    else:
        notes.append(
            "fragment: shaft length kept from the Vitruvian column, its top radius from the "
            "measured taper"
        )
    r_top, entasis = r_bottom * top_ratio, 0.0
    tap = shaft_taper(loc, frame.parts["shaft"], sec, e, sh.length)
    if tap is not None:
        r_bottom, r_top, entasis = tap
        notes.append(f"taper and entasis fitted: entasis {entasis:.4f} of the radius")
    sh = dataclasses.replace(
        sh,
        bottom_radius=r_bottom,
        top_radius=r_top,
        entasis=entasis,
        flutes=e,
        flute_angle=sec["flute_angle"],
        flute_depth=sec["flute_depth"],
    )
    return dataclasses.replace(col, shaft=sh)


def _turn_about_axis(
    sub: np.ndarray,
    rng: np.random.Generator,
    frame: ColumnFrame,
    col: ColumnParams,
    sec: dict,
    e: int,
    s0: float,
    tree,
    notes: list[str],
) -> tuple[np.ndarray, ColumnParams]:
    """The column → scan matrix (y along the axis, x at the flutes' angle 0) and the column
    with its flutes' phase. The flutes fix the turn about the axis up to a flute period; the
    plinth and the volutes (180° symmetric) choose among the periods: the one nearest the
    scan wins."""
    has_base, has_cap = "base" in frame.parts, "capital" in frame.parts
    h_col0 = _column_zero(frame, col, s0)
    probe = sub[rng.choice(len(sub), min(len(sub), 5000), replace=False)]
    plinth = None
    if has_base:
        b0, b1 = frame.parts["base"]
        lsub = frame.local(sub)
        low = lsub[(lsub[:, 2] > b0 + 0.02 * (b1 - b0)) & (lsub[:, 2] < b0 + 0.12 * (b1 - b0))]
        plinth = plinth_turn(low[:, :2])
    period = 360.0 / e
    if plinth is not None:  # the plinth's faces set the turn, the flutes their own phase
        cands = [plinth + 90.0 * j for j in range(4 if has_cap else 1)]
        notes.append(f"square plinth turned {plinth:.3f}° about the axis; flutes phased apart")
    else:  # the flutes fix the turn up to a period; the volutes choose among the periods
        cands = [sec["rotation_deg"] + j * period for j in range(e // 2 if has_cap else 1)]
    turns = []
    for rot in cands:
        phase = (sec["rotation_deg"] - rot + 0.5 * period) % period - 0.5 * period
        c_j = dataclasses.replace(col, shaft=dataclasses.replace(col.shaft, flute_phase=phase))
        m = _matrix(frame, rot, h_col0)
        d = scan_deviation(probe, c_j, m, tree=tree)
        turns.append((float(np.sqrt(np.mean(d**2))), m, c_j))
    best = min(turns, key=lambda t: t[0])  # the first of equal scores
    return best[1], best[2]


def _capital_alone(
    pts: np.ndarray, sub: np.ndarray, seed: int, notes: list[str], t0: float
) -> ScanFit:
    """A capital scanned alone: its pose and size from the capital itself
    (:func:`.scan_alone.capital_pose`), then its proportions (:func:`_fit_capital`); the
    column is the Vitruvian one at the capital's diameter."""
    from ionic_usd.evaluate.scan_alone import capital_pose

    pose = capital_pose(sub, seed=seed)
    if not pose.rms < 0.02 * pose.scale:
        raise GeometryError(
            f"neither a fluted shaft nor a capital fits the scan (the best capital pose "
            f"leaves {pose.rms * 1000:.3g} mm rms at D = {pose.scale:.3f} m)"
        )
    notes.append(
        f"capital alone: its pose and size from the capital ({pose.candidates} frames from "
        f"the points' principal directions, the best placed at {pose.rms * 1000:.3g} mm rms)"
    )
    col = portunus_column_params(lower_diameter=pose.scale)
    up = pose.rotation[:, 1]
    y_top = _shaft_top(col)
    m = np.eye(4)
    m[:3, :3] = pose.rotation.T
    m[3, :3] = pose.origin - y_top * up
    col, m, cap_fit = _fit_capital(sub, col, m, False, notes)
    top = m[3, :3] + y_top * up  # the shaft's top centre in the scan
    diameter = float(cap_fit.capital.capital_width)  # the capital's width is the diameter
    col = dataclasses.replace(
        portunus_column_params(lower_diameter=diameter, flutes=col.shaft.flutes),
        capital=cap_fit.capital,
    )
    m[3, :3] = top - _shaft_top(col) * up
    notes.append(
        f"diameter {diameter:.4f} m from the capital's fitted size; shaft, flutes "
        f"({col.shaft.flutes}) and base not seen: the Vitruvian ones"
    )
    h = (pts - top) @ up
    frame = ColumnFrame(
        up,
        top + h.min() * up,
        m[0, :3],
        np.cross(up, m[0, :3]),
        {"capital": (0.0, float(np.ptp(h)))},
        col.shaft.top_radius,
    )
    dev = scan_deviation(pts, col, m, tree=other_parts_tree(col))
    fits = _part_report(frame.local(pts)[:, 2], dev, frame, {}, None, col, cap_fit)
    return ScanFit(
        col,
        frame,
        m,
        diameter,
        col.shaft.flutes,
        {},
        None,
        dev,
        time.perf_counter() - t0,
        np.empty((0, 2)),
        None,
        notes,
        fits,
    )


def _shaft_top(col: ColumnParams) -> float:
    """Column y of the shaft's top (the capital's origin)."""
    built = build_column(col)
    return built.base_height + built.shaft_length


def _fit_capital(
    sub: np.ndarray, col: ColumnParams, m: np.ndarray, has_base: bool, notes: list[str]
) -> tuple[ColumnParams, np.ndarray, CapitalFit]:
    """The capital fitted to its points (:func:`.scan_capital.fit_scanned_capital`), the
    column taking it: its height shift lengthens the shaft (a whole column) or moves the
    column along the axis (no base to hold it)."""
    from ionic_usd.evaluate.scan_capital import fit_scanned_capital

    built = build_column(col)
    y_top = built.base_height + built.shaft_length
    low = float(built.capital_body.points[:, 1].min())
    d = 2.0 * col.shaft.bottom_radius
    q = to_column(sub, m)
    q = q[q[:, 1] > low - 0.05 * d]
    other = shaft_deviation(q, col)
    keep = (q[:, 1] > y_top) | (other > 0.003 * d)  # not on the shaft's top
    fit = fit_scanned_capital(q[keep], col.capital, col.shaft.top_radius, y_top, other[keep])
    if has_base:
        col = dataclasses.replace(
            col, shaft=dataclasses.replace(col.shaft, height=col.shaft.height + fit.ty)
        )
    else:
        m = m.copy()
        m[3, :3] += fit.ty * m[1, :3]
    col = dataclasses.replace(col, capital=fit.capital)
    notes.append(
        f"capital fitted to {fit.points} points ({fit.seconds:.1f} s): volute model "
        f"{fit.model}, R = {fit.values['capital_spiral_radius']:.4f} m, height shift "
        f"{fit.ty * 1000:+.3g} mm; rms {fit.rms_start * 1000:.2f} mm (Vitruvian, rebuilt) → "
        f"{fit.rms * 1000:.2f} mm"
    )
    return col, m, fit


def _joint(
    frame: ColumnFrame,
    loc: np.ndarray,
    col: ColumnParams,
    r_bottom: float,
    sec: dict[str, float],
    notes: list[str],
) -> ColumnFrame:
    """The base's top moved to the base/shaft joint found from the flutes' start
    (:func:`.scan_parts.base_top`); the frame unchanged when the flutes' start is not seen."""
    from ionic_usd.column.shaft import build_shaft

    b0, b1 = frame.parts["base"]
    sp = dataclasses.replace(
        col.shaft,
        bottom_radius=r_bottom,
        top_radius=r_bottom * col.shaft.top_radius / col.shaft.bottom_radius,
        flute_angle=sec["flute_angle"],
        flute_depth=sec["flute_depth"],
    )
    found = base_top(np.hypot(loc[:, 0], loc[:, 1]), loc[:, 2], b1, 2 * r_bottom, build_shaft(sp))
    if found is None or not b0 < found[0] < b1 + 1.2 * r_bottom:
        notes.append("base top: the flutes' start not seen; the parts' bins kept")
        return frame
    top = found[0]
    notes.append(
        f"base top at the joint {top - b0:.4f} m up: the flutes start {found[1] * 1000:.3g} mm "
        f"above it on the fitted shaft (the parts' bins gave {b1 - b0:.4f} m)"
    )
    parts = dict(frame.parts, base=(b0, top))
    if "shaft" in parts:
        parts["shaft"] = (max(top, parts["shaft"][0]), parts["shaft"][1])
    return dataclasses.replace(frame, parts=parts)


def _fit_scanned_base(
    col_pts: np.ndarray,
    col: ColumnParams,
    frame: ColumnFrame,
    notes: list[str],
    use_on_plinth: bool,
    noise: float = 0.001,
) -> tuple[ColumnParams, FitResult | None]:
    """The base's meridian (:func:`.scan_parts.base_meridian`) fitted with
    :func:`.fit_base.fit_base`; the column takes the fitted base unless the scanned base has
    a square plinth (a lathe grammar cannot rebuild its corners) and ``use_on_plinth`` is
    False. Returns the column and the fit (None when the scan covers too little)."""
    from ionic_usd.evaluate.fit_base import fit_base

    b0, b1 = frame.parts["base"]
    top = b1 - b0  # the parts' bins: the joint with the shaft may fall short of the top
    if has_square_plinth(col_pts, 0.0, top) and not use_on_plinth:
        from ionic_usd.evaluate.scan_plinth import fit_plinth_base

        got = fit_plinth_base(col_pts, col, top, noise)
        if got is not None:
            from ionic_usd.evaluate.scan_deviation import base_deviation

            near = col_pts[col_pts[:, 1] < top]
            rms = [float(np.sqrt(np.mean(base_deviation(near, c) ** 2))) for c in (got[0], col)]
            if rms[0] <= rms[1]:
                notes.append(got[2] + "; the column takes the plinth and the fitted lathe")
                return got[0], got[1]
            notes.append(
                f"{got[2]}; kept the Vitruvian base, nearer its points ({rms[1] * 1000:.3g} "
                f"against {rms[0] * 1000:.3g} mm rms)"
            )
    mer = base_meridian(col_pts, 0.0, top)
    if mer is None:
        notes.append("base found but its meridian is too sparse to fit: the Vitruvian base")
        return col, None
    fit = fit_base(mer, initial=col, axis_x=0.0, polish_evals=300)
    what = (
        f"base fitted to its meridian ({len(mer)} bins at the plinth's face normals): "
        f"{fit.after.hausdorff_pct:.3f} % (paper's measure), "
        f"{fit.after.discrete_frechet_pct:.3f} % (discrete Fréchet)"
    )
    if has_square_plinth(col_pts, 0.0, top) and not use_on_plinth:
        notes.append(
            f"{what}; square plinth: the column keeps the Vitruvian base (a lathe "
            "grammar would round its corners)"
        )
        return col, fit
    notes.append(f"{what}; the column takes the fitted base")
    return fit.column, fit


def _matrix(frame: ColumnFrame, rotation_deg: float, h0: float) -> np.ndarray:
    """(4, 4) column → scan: y along the axis, x at the flutes' angle 0, y = 0 at h0."""
    rot = math.radians(rotation_deg)
    x_ax = math.cos(rot) * frame.u + math.sin(rot) * frame.v
    m = np.eye(4)
    m[0, :3], m[1, :3], m[2, :3] = x_ax, frame.direction, np.cross(x_ax, frame.direction)
    m[3, :3] = frame.origin + h0 * frame.direction
    return m


def _column_zero(frame: ColumnFrame, col: ColumnParams, shaft_start: float) -> float:
    """Height along the axis (frame heights) of the column's y = 0 (the base's bottom)."""
    if "base" in frame.parts:
        return frame.parts["base"][0]
    bh = col.base_params().height
    if "capital" in frame.parts:
        built = build_column(col)
        low = float(
            np.min(
                [m.points[:, 1].min() for k, m in built.parts().items() if k.startswith("Capital")]
            )
        )
        return frame.parts["capital"][0] - low
    return shaft_start - bh
