"""Scan fits on synthetic scans: part × case → fitted values vs truth, deviations, times.

Usage: python tools/scan_table.py [--points N] [--cases whole,capital,base_drum]
[--diameters 0.6,0.95,1.2]

Every case samples the generator's own column (noise 0.5 mm, four 5 cm holes, a 60° missing
sector, the joints and the ground hidden, a random rigid pose) and fits it with
:func:`ionic_usd.evaluate.fit_scan.fit_column_scan`. Prints one row per part found.

``--fragments`` instead prints the per-part deviation table of the independent fragment
scans of tests/synth_scan.py (a square plinth, an Attic base and a fluted drum with a broken
side, 0.8 mm noise, random pose; mm or inches): rms and p95 per part against the noise.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from ionic_usd.column.column import build_column, portunus_column_params
from ionic_usd.evaluate.scan_io import synthetic_scan


def make_scan(diameter: float, n: int, seed: int, case: str, params=None):
    p = params or portunus_column_params(lower_diameter=diameter)
    bh, length = p.base_params().height, p.shaft_params().length
    hidden = ((0.0, 99.0), (bh, 9.0), (bh + length, 9.0))
    y_range = {"whole": None, "base_drum": (0.0, bh + 1.6 * diameter / 1.2)}.get(case)
    parts = build_column(p).parts()
    if case == "capital":
        parts = {k: m for k, m in parts.items() if k.startswith("Capital")}
    pts, rot, t = synthetic_scan(
        parts,
        n=n,
        noise=5e-4,
        holes=4,
        missing_sector=(40.0, 100.0),
        hidden=hidden,
        seed=seed,
        y_range=y_range,
        hole_radius=0.05,
    )
    return p, pts, rot, t


#: (shaft radius mm, metres per scan unit, seed) of the ``--fragments`` table
FRAGMENTS = ((400.0, 1e-3, 0), (250.0, 0.0254, 1), (700.0, 1e-3, 2), (400.0, 1e-3, 3))


def fragments(points: int) -> None:
    """The per-part deviation table of the independent fragment scans."""
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
    from synth_scan import Truth, fragment_scan

    from ionic_usd.evaluate.fit_scan import fit_column_scan

    print(
        f"{'R mm':>5} {'unit':>6} {'seed':>4} {'points':>6} {'D fit/true':>14} {'part':6} "
        f"{'rms mm':>7} {'p95 mm':>7} {'rms/noise':>9}"
    )
    for radius, unit, seed in FRAGMENTS:
        truth = Truth().scaled(radius)
        pts, _, _ = fragment_scan(points, truth=truth, noise=0.8, seed=seed, unit=unit)
        name = {1e-3: "mm", 0.0254: "in"}[unit]
        try:
            s = fit_column_scan(pts * unit).summary()
        except Exception as exc:  # a table row, not a crash
            print(f"{radius:5.0f} {name:>6} {seed:4d} FAILED {type(exc).__name__}: {exc}")
            continue
        dd = f"{s['diameter']:.4f}/{2e-3 * radius:.4f}"
        for part in ("all", *sorted(s["parts"])):
            dv = s["deviation"] if part == "all" else s["parts"][part]["deviation"]
            rms, p95 = 1000 * dv["rms"], 1000 * dv["p95"]
            print(
                f"{radius:5.0f} {name:>6} {seed:4d} {len(pts):6d} {dd:>14} {part:6} "
                f"{rms:7.2f} {p95:7.2f} {rms / 0.8:9.2f}"
            )


def main() -> None:
    from ionic_usd.evaluate.fit_scan import fit_column_scan

    ap = argparse.ArgumentParser()
    ap.add_argument("--points", type=int, default=60_000)
    ap.add_argument("--cases", default="whole,capital,base_drum")
    ap.add_argument("--diameters", default="0.6,0.95,1.2")
    ap.add_argument("--seed", type=int, default=2)
    ap.add_argument("--fragments", action="store_true", help="the independent fragment table")
    a = ap.parse_args()
    if a.fragments:
        fragments(a.points)
        return
    print(f"{'case':10} {'D':>5} {'part':8} {'status':9} {'fitted vs truth':52} rms/p95 mm")
    for case in a.cases.split(","):
        for d in (float(x) for x in a.diameters.split(",")):
            p, pts, rot, _ = make_scan(d, a.points, a.seed, case)
            t0 = time.perf_counter()
            try:
                fit = fit_column_scan(pts)
            except Exception as exc:  # a table row, not a crash
                print(f"{case:10} {d:5.2f} {'-':8} FAILED    {type(exc).__name__}: {exc}")
                continue
            sec = time.perf_counter() - t0
            s = fit.summary()
            ang = np.degrees(np.arccos(min(1.0, abs(fit.frame.direction @ rot[:, 1]))))
            print(
                f"{case:10} {d:5.2f} {'all':8} {'':9} parts {s['parts_found']} "
                f"D {s['diameter']:.4f} ({100 * (s['diameter'] / d - 1):+.2f} %) "
                f"flutes {s['flutes']} axis {ang:.3f}°  {sec:.1f} s, {len(pts)} pts "
                f"rms/p95 {1000 * s['deviation']['rms']:.1f}/{1000 * s['deviation']['p95']:.1f}"
            )
            for part, rep in s["parts"].items():
                dv = rep["deviation"]
                txt = ""
                if part == "base" and "height" in rep:
                    bh = p.base_params().height
                    dh = 100 * (rep["height"] / bh - 1)
                    txt = f"height {rep['height']:.4f} vs {bh:.4f} ({dh:+.2f} %)"
                if part == "capital" and "values" in rep:
                    v, c = rep["values"], p.capital
                    tr = c.volute.capital_spiral_radius
                    txt = (
                        f"{rep['model'][-12:]} R {v['capital_spiral_radius']:.4f} vs {tr:.4f} "
                        f"({100 * (v['capital_spiral_radius'] / tr - 1):+.1f} %) "
                        f"rebuilt {1000 * rep['rebuilt_rms']:.1f} mm {rep['seconds']:.1f} s"
                    )
                rms = 1000 * dv["rms"] if dv["rms"] is not None else float("nan")
                p95 = 1000 * dv["p95"] if dv["p95"] is not None else float("nan")
                print(
                    f"{case:10} {d:5.2f} {part:8} {rep['status'][:9]:9} {txt:52} "
                    f"{rms:.1f}/{p95:.1f}"
                )


if __name__ == "__main__":
    main()
