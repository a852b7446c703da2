"""Outputs of a scan fit: fitted column USD (scan frame), scan points USD with deviations,
a PNG (deviation histogram and section overlays), the column TOML and R.json (the
``ionic-usd fit column --scan`` command, :mod:`ionic_usd.cli.fit_scan`, fits and writes
them)."""

from __future__ import annotations

from pathlib import Path
from typing import IO, Any

import numpy as np

from ionic_usd.evaluate.fit_scan import ScanFit, ScanSummary, heat_colours

__all__ = ["plot_scan_fit", "write_outputs"]


def plot_scan_fit(fit: ScanFit, path: Path) -> Path:
    """PNG: deviation histogram (mm), the shaft slab over the fitted section, the base's
    outer profile over the fitted profile."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    from ionic_usd.evaluate.fit_shaft import fluted_section
    from ionic_usd.evaluate.report import write_atomically
    from ionic_usd.evaluate.sections import base_section

    fig = Figure(figsize=(15, 5), layout="constrained")
    FigureCanvasAgg(fig)
    ax1, ax2, ax3 = fig.subplots(1, 3)
    d = fit.deviation * 1000.0
    p95 = float(np.percentile(d, 95))
    ax1.hist(np.minimum(d, 3 * p95 + 1e-9), bins=80, color="#4477aa")
    ax1.axvline(p95, color="#cc3311", lw=1, label=f"p95 {p95:.3g} mm")
    ax1.axvline(
        float(np.sqrt(np.mean(d**2))),
        color="#228833",
        lw=1,
        label=f"rms {float(np.sqrt(np.mean(d**2))):.3g} mm",
    )
    ax1.set_xlabel("distance from the fitted column (mm; last bin: ≥ 3·p95)")
    ax1.set_ylabel("points")
    ax1.set_title(f"deviation of {len(d):,} scan points (max {d.max():.3g} mm)")
    ax1.legend(fontsize=8)
    s = fit.section
    if "radius" in s:
        sec = fluted_section(
            s["radius"],
            fit.flutes,
            s["flute_angle"],
            s["flute_depth"],
            s["rotation_deg"],
            (s["centre_u"], s["centre_v"]),
            slices=32,
        )
        ax2.plot(fit.slab[:, 0], fit.slab[:, 1], ".", ms=1.5, color="#d4a500", label="scan slab")
        ax2.plot(sec[:, 0], sec[:, 1], "-", lw=0.8, color="#d62728", label="fitted section")
        ax2.set_aspect("equal")
        ax2.set_xlabel("u (m)")
        ax2.set_ylabel("v (m)")
        ax2.set_title(f"shaft section: {fit.flutes} flutes, D = {fit.diameter:.4f} m")
        ax2.legend(fontsize=8, loc="upper right")
    else:
        ax2.set_axis_off()
        ax2.text(0.5, 0.5, "no shaft in the scan", ha="center", va="center")
    if fit.profile is not None and len(fit.profile):
        h0 = fit.frame.parts["base"][0]
        prof = base_section(fit.column)
        ax3.plot(
            fit.profile[:, 0],
            fit.profile[:, 1] - h0,
            ".",
            ms=3,
            color="#d4a500",
            label="scan: outer radius per bin",
        )
        ax3.plot(prof[:, 0], prof[:, 1], "-", lw=1, color="#d62728", label="fitted base")
        ax3.set_aspect("equal")
        ax3.set_xlabel("r (m)")
        ax3.set_ylabel("y above the base's bottom (m)")
        ax3.set_title("base profile")
        ax3.legend(fontsize=8)
    else:
        ax3.set_axis_off()
        ax3.text(0.5, 0.5, "no base in the scan", ha="center", va="center")

    def write(fh: IO[bytes]) -> None:
        fig.savefig(fh, format="png", dpi=110)

    return write_atomically(path, write)


def write_outputs(
    fit: ScanFit, points: np.ndarray, files: dict[str, Path], args: Any, summary: ScanSummary
) -> None:
    """Write every output of ``ionic-usd fit column`` (paths in ``files``; JSON at
    ``args.json``)."""
    from ionic_usd.column.column import COLUMN_DOCS, build_column, column_params_to_tables
    from ionic_usd.column.shaft import SHAFT_PARAMETER_DOCS
    from ionic_usd.evaluate.report import write_atomically, write_fit_json
    from ionic_usd.params import to_toml
    from ionic_usd.usd.scan import write_fitted_column, write_scan_points

    col = build_column(fit.column)
    write_fitted_column(
        files["column"],
        col.parts(),
        fit.matrix,
        force=True,
        comment=f"ionic_usd column fitted to {Path(args.scan).name}, placed in the scan's frame",
    )
    vmax = max(float(np.percentile(fit.deviation, 99)), 1e-4)
    width = 0.5 * float(np.linalg.norm(np.ptp(points, axis=0))) / max(len(points), 1) ** 0.5
    write_scan_points(
        files["scan"],
        points,
        fit.deviation,
        heat_colours(fit.deviation, vmax),
        width=max(width, 1e-4),
        force=True,
    )
    plot_scan_fit(fit, files["png"])
    text = to_toml(
        column_params_to_tables(fit.column),
        {"column": COLUMN_DOCS, "shaft": SHAFT_PARAMETER_DOCS},
        header=f"ionic_usd column fitted to the scan {Path(args.scan).name}",
    )
    write_atomically(files["toml"], lambda fh: fh.write(text.encode("utf-8")))
    if args.json is not None:
        fits = {"base": fit.base} if fit.base is not None else {}
        write_fit_json(
            args.json,
            fits,
            extra=summary,
            metadata={
                "scan": str(args.scan),
                "scale": args.scale,
                "units": getattr(args, "units", None) or "auto",
                "outputs": {k: str(v) for k, v in files.items()},
            },
        )
