"""Print the colonnade fit's per-column table (docs/colonnade.md): the independent synthetic
colonnade of tests/synth_scan.py (fragments on a line 2.8 m apart, small random poses, one of
radius 460 mm instead of 400), each column's fit, and every column's rms deviation from every
other column's description (at its pose registered along its axis, as the grouping does).

    python tools/colonnade_table.py [--columns 4] [--points 4000] [--seed 0]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))


def main(argv: list[str] | None = None) -> int:
    from synth_scan import Truth, colonnade_scan

    from ionic_usd.evaluate.scan_colonnade import fit_colonnade, register_instance
    from ionic_usd.evaluate.scan_deviation import other_parts_tree

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--columns", type=int, default=4)
    ap.add_argument("--points", type=int, default=4000)
    ap.add_argument("--seed", type=int, default=0)
    a = ap.parse_args(argv)
    t = Truth()
    truths = [t.scaled(460.0) if k == 2 else t for k in range(a.columns)]
    pts, lab = colonnade_scan(truths, a.points, seed=a.seed)
    pts = pts * 1e-3
    t0 = time.perf_counter()
    c = fit_colonnade(pts, seed=a.seed)
    secs = time.perf_counter() - t0
    trees = [other_parts_tree(f.column) for f in c.fits]
    head = " | ".join(f"from {j + 1}" for j in range(len(c.fits)))
    print(f"| column | true radius (mm) | group | D (m) | rms own (mm) | {head} |")
    print("|---" * (4 + len(c.fits) + 1) + "|")
    for i, f in enumerate(c.fits):
        src = int(np.bincount(lab[c.indices[i]]).argmax())
        row = []
        for j, g in enumerate(c.fits):
            d = f.deviation if i == j else register_instance(g, f, pts[c.indices[i]], trees[j])[1]
            row.append(f"{1000 * np.sqrt(np.mean(d**2)):.3g}")
        own = 1000 * np.sqrt(np.mean(f.deviation**2))
        print(
            f"| {i + 1} | {truths[src].radius:g} | {'ABCDEFGH'[c.group_of(i)]} | "
            f"{f.diameter:.4f} | {own:.3g} | {' | '.join(row)} |"
        )
    print(f"\n{len(pts):,} points, 0.8 mm noise; split, fits and grouping in {secs:.1f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
