"""A scan fit's report per part and the check that the scan is a column at all."""

from __future__ import annotations

from typing import Any

import numpy as np

from ionic_usd.column.column import ColumnParams
from ionic_usd.errors import GeometryError
from ionic_usd.evaluate.fit_core import FitResult
from ionic_usd.evaluate.scan_axis import ColumnFrame
from ionic_usd.evaluate.scan_capital import CapitalFit

__all__ = ["MAX_SHAFT_P95"]


#: Largest p95 deviation of the shaft's points from the fitted shaft, as a fraction of the
#: fitted diameter: past it the scan is refused as not a column (a scanned column's shaft
#: stays within a few noise widths; a sphere of points leaves 31 %).
MAX_SHAFT_P95 = 0.05


def _check_is_column(fits: dict[str, dict[str, Any]], diameter: float, flutes: int) -> None:
    """Refuse a fit whose shaft does not follow its points (:data:`MAX_SHAFT_P95`)."""
    dev = fits.get("shaft", {}).get("deviation", {})
    p95 = dev.get("p95")
    if p95 is not None and not p95 <= MAX_SHAFT_P95 * diameter:
        raise GeometryError(
            f"scan: not a column: the best fluted shaft (D {diameter:.3g} m, {flutes} flutes) "
            f"leaves its points {p95 * 1000:.3g} mm from it at p95 = "
            f"{100 * p95 / diameter:.3g} % of D (a column stays within "
            f"{100 * MAX_SHAFT_P95:g} %)"
        )


def _part_report(
    h: np.ndarray,
    dev: np.ndarray,
    frame: ColumnFrame,
    sec: dict[str, float],
    base_fit: FitResult | None,
    col: ColumnParams,
    cap_fit: CapitalFit | None = None,
) -> dict[str, dict[str, Any]]:
    """Per part found: what was fitted or only rebuilt, and the deviations of its points."""
    out: dict[str, dict[str, Any]] = {}
    for part, (a, b) in frame.parts.items():
        d = dev[(h >= a) & (h <= b)]
        rep: dict[str, Any] = {
            "points": int(len(d)),
            "deviation": {
                "rms": float(np.sqrt(np.mean(d**2))) if len(d) else None,
                "p95": float(np.percentile(d, 95)) if len(d) else None,
            },
        }
        if part == "shaft":
            rep.update(
                status="fitted",
                model="fluted section",
                fitted=["diameter", "flutes", "flute_angle", "flute_depth", "taper", "rotation"],
                values={k: sec[k] for k in ("radius", "flute_angle", "flute_depth") if k in sec},
            )
        elif part == "base" and base_fit is not None:
            plinth = col.base_plinth == 1 and col.base != base_fit.column.base
            rep.update(
                status="fitted"
                if col.base == base_fit.column.base or plinth
                else "fitted (reported; the column keeps the Vitruvian plinth base)",
                model="plinth box + bezier lathe" if plinth else "bezier meridian",
                height=base_fit.column.base_params().height,
                measures={
                    "hausdorff_pct": base_fit.after.hausdorff_pct,
                    "discrete_frechet_pct": base_fit.after.discrete_frechet_pct,
                },
            )
        elif part == "capital" and cap_fit is not None:
            rep.update(
                status="fitted",
                model=f"generator capital, volute {cap_fit.model}",
                fitted=cap_fit.fitted,
                kept=cap_fit.kept,
                values=cap_fit.values,
                models=cap_fit.models,
                bounds_hit=cap_fit.bounds_hit,
                rebuilt_rms=cap_fit.rms_start,
                seconds=cap_fit.seconds,
            )
        else:
            rep.update(status="rebuilt", model="Vitruvian proportions at the diameter")
        out[part] = rep
    return out
