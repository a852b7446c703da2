"""``ionic-usd fit column --scan``: fit a column to a scan (one fit per column of a colonnade)
and write the fitted column, the scan with its deviations, a picture, TOML and R.json."""

from __future__ import annotations

import numpy as np

from ionic_usd.evaluate.fit_scan import fit_column_scan
from ionic_usd.evaluate.scan_io import check_scan_extent
from ionic_usd.evaluate.scan_report import write_outputs

__all__ = ["cmd_fit_column"]


def cmd_fit_column(args) -> int:
    """``ionic-usd fit column --scan FILE -o OUTDIR [--json R.json]``."""
    from pathlib import Path

    from ionic_usd.errors import ParameterError

    if args.scan is None:
        raise ParameterError("--scan", None, "a scan file for `fit column`")
    if args.output is None:
        raise ParameterError("-o", None, "an output folder for `fit column`")
    out = Path(args.output)
    files = _output_files(out, args)
    pts, unit_note = _scan_points(args)
    from ionic_usd.evaluate.scan_colonnade import split_columns

    split = None
    if len(pts) >= 200 and np.all(np.isfinite(pts)):
        check_scan_extent(pts, "scan")  # as the fit would: no split of a line or a plane
        split = split_columns(pts, seed=args.seed)
    if split is not None and len(split[1]) > 1:  # several columns: one fit each
        from ionic_usd.evaluate.scan_colonnade_report import run_colonnade

        return run_colonnade(pts, split, out, args, unit_note)
    fit = fit_column_scan(pts, seed=args.seed)
    summary = fit.summary()
    out.mkdir(parents=True, exist_ok=True)
    write_outputs(fit, pts, files, args, summary)
    _print_scan_fit(args, fit, summary, pts, unit_note)
    for p in files.values():
        print(f"wrote {p}")
    if args.json is not None:
        print(f"wrote {args.json}")
    return 0


def _output_files(out, args) -> dict:
    """The files ``fit column`` writes in the folder ``out``; refuses (before any work) a
    folder that is a file, files that exist without ``--force`` and a bad ``--json``."""
    from ionic_usd.errors import OutputExistsError, ParameterError

    if out.exists() and not out.is_dir():
        raise ParameterError("-o", str(out), "a folder (created if missing)")
    files = {
        k: out / n
        for k, n in (
            ("column", "fitted_column.usda"),
            ("scan", "scan_deviation.usdc"),
            ("png", "scan_fit.png"),
            ("toml", "fitted_column.toml"),
        )
    }
    clash = [str(p) for p in files.values() if p.exists()]
    if clash and not args.force:
        raise OutputExistsError(f"{clash[0]} exists; pass --force to overwrite it")
    if args.json is not None:
        if args.json.suffix.lower() != ".json":
            raise ParameterError("--json", str(args.json), "a file ending in .json")
        if args.json.exists() and not args.force:
            raise OutputExistsError(f"{args.json} exists; pass --force to overwrite it")
    return files


def _scan_points(args) -> tuple[np.ndarray, str]:
    """The scan's points in metres and a note on their units: detected from the scan's
    least extent unless ``--units`` or ``--scale`` set them."""
    from ionic_usd.evaluate.scan_io import UNITS, detect_units, read_scan

    units = getattr(args, "units", None) or "auto"
    if units == "auto" and args.scale == 1.0:
        pts = read_scan(args.scan)
        factor, units = detect_units(pts, str(args.scan))
        pts = pts * factor
        check_scan_extent(pts, str(args.scan))
        return pts, f"units: {units} (detected from the scan's least extent; --units sets them)"
    factor = UNITS.get(units, 1.0)
    return read_scan(args.scan, scale=args.scale * factor), f"units: {units}, scale {args.scale:g}"


def _print_scan_fit(args, fit, summary, pts: np.ndarray, unit_note: str) -> None:
    """The fit's report on stdout: the axis, the deviation, each part and the notes."""
    dev = summary["deviation"]
    print(f"scan {args.scan}: {len(pts):,} points; parts {', '.join(summary['parts_found'])}")
    print(f"  {unit_note}")
    print(
        f"  diameter {fit.diameter:.4f} m, {fit.flutes} flutes; axis "
        f"{np.round(fit.frame.direction, 5).tolist()} through "
        f"{np.round(fit.frame.origin, 4).tolist()}"
    )
    print(
        f"  deviation rms {dev['rms'] * 1000:.3g} mm, p95 {dev['p95'] * 1000:.3g} mm, max "
        f"{dev['max'] * 1000:.3g} mm; {fit.seconds:.1f} s"
    )
    for part, rep in sorted(fit.fits.items()):
        d = rep["deviation"]
        dev_txt = (
            "no points"
            if d["rms"] is None
            else f"rms {d['rms'] * 1000:.3g} mm, p95 {d['p95'] * 1000:.3g} mm"
        )
        extra = ""
        if "measures" in rep:
            m = rep["measures"]
            extra = (
                f"; meridian {m['hausdorff_pct']:.3f} % (paper's measure), "
                f"{m['discrete_frechet_pct']:.3f} % (discrete Fréchet)"
            )
        print(
            f"  {part}: {rep['status']} ({rep['model']}); {rep['points']:,} points, "
            f"{dev_txt}{extra}"
        )
    if summary["not_fitted"]:
        print(
            f"  not fitted (kept from the column description): {', '.join(summary['not_fitted'])}"
        )
    for note in fit.notes:
        print(f"  {note}")
