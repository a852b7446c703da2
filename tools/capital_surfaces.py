"""The whole-column scan's capital, surface by surface: rms (mm) of the fitted column's
deviation on each of the capital's surfaces, per seed (issue 36).

Usage: python tools/capital_surfaces.py [--seeds 0,1,2,3,4] [--dump DIR]

The scans are tests/synth_column.py's (0.8 mm noise, mm). Each capital point is labelled by
the generator's own surfaces, from its noisy position in the generator's column frame
(known: the scan's pose is returned with it): the abacus, the echinus (below the eyes and
clear of the rolls), the volutes' eyes, the volutes' spiral (channel and fillet), the
canalis, the rolls between the faces and the joint with the shaft (the echinus' lowest 30
mm). Also prints the base's, the shaft's and the capital's rms and the fit's time.
``--dump DIR`` pickles the capital fit's inputs (points, starting capital, shaft top) per
seed, to work on :func:`ionic_usd.evaluate.scan_capital.fit_scanned_capital` alone.
"""

from __future__ import annotations

import argparse
import math
import pickle
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

SURFACES = ("abacus", "echinus", "joint", "eye", "spiral", "canalis", "roll")


def capital_labels(local: np.ndarray, sc: float = 1.0) -> np.ndarray:
    """(n,) index into :data:`SURFACES` of capital points in the generator's capital frame
    (mm, origin at the echinus' foot on the axis, y up, the faces at z = ±face)."""
    from synth_column import CapitalTruth

    c = CapitalTruth()
    x, y, z = (local / sc).T
    ye, R, xe, C = c.echinus_top, c.volute_radius, c.eye_x, c.face
    ya = ye + R
    dx, dy = np.abs(x) - xe, y - ye
    rho = np.hypot(dx, dy)
    lab = np.full(len(local), SURFACES.index("echinus"))
    face = np.abs(z) > C - c.channel - 3.0
    lab[face & (np.abs(x) <= xe) & (y >= ye)] = SURFACES.index("canalis")
    lab[face & (rho <= R + 3.0)] = SURFACES.index("spiral")
    lab[face & (rho <= c.eye_radius + 2.0)] = SURFACES.index("eye")
    lab[~face & (np.abs(rho - R) < 4.0)] = SURFACES.index("roll")
    lab[y >= ya - 2.0] = SURFACES.index("abacus")
    lab[(lab == SURFACES.index("echinus")) & (y < 30.0)] = SURFACES.index("joint")
    return lab


def run(seed: int, dump: Path | None) -> dict[str, float]:
    from synth_column import column_scan
    from synth_scan import Truth, joint_height

    import ionic_usd.evaluate.scan_capital as sc_mod
    from ionic_usd.evaluate.fit_scan import fit_column_scan

    pts, part, rot, tr = column_scan(noise=0.8, seed=seed)
    orig = sc_mod.fit_scanned_capital
    box: dict[str, float] = {}

    def spy(*a, **k):
        if dump is not None:
            dump.mkdir(parents=True, exist_ok=True)
            with open(dump / f"capital_{seed}.pkl", "wb") as f:
                pickle.dump((a, k), f)
        t = time.perf_counter()
        out = orig(*a, **k)
        box["capital_s"] = time.perf_counter() - t
        return out

    sc_mod.fit_scanned_capital = spy
    try:
        t0 = time.perf_counter()
        fit = fit_column_scan(pts * 1e-3)
        box["fit_s"] = time.perf_counter() - t0
    finally:
        sc_mod.fit_scanned_capital = orig
    dev = 1000.0 * fit.deviation
    out = dict(box)
    for k, name in enumerate(("base", "shaft", "capital")):
        out[name] = float(np.sqrt(np.mean(dev[part == k] ** 2)))
    t = Truth()
    col = (pts - tr) @ rot  # the generator's column frame
    local = col[part == 2] - np.array([0.0, joint_height(t) + t.shaft_length, 0.0])
    lab = capital_labels(local, t.radius / 400.0)
    dc = dev[part == 2]
    for i, s in enumerate(SURFACES):
        sel = lab == i
        out[s] = float(np.sqrt(np.mean(dc[sel] ** 2))) if sel.any() else math.nan
        out[s + "_n"] = int(sel.sum())
    # each surface's share of the capital's sum of squares
    tot = float(np.sum(dc**2))
    for i, s in enumerate(SURFACES):
        out[s + "_share"] = float(np.sum(dc[lab == i] ** 2)) / tot
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seeds", default="0,1,2,3,4")
    ap.add_argument("--dump", type=Path, default=None)
    a = ap.parse_args()
    rows = [(int(s), run(int(s), a.dump)) for s in a.seeds.split(",")]
    head = ["seed", "base", "shaft", "capital", *SURFACES, "fit s", "cap s"]
    print(" | ".join(f"{h:>7}" for h in head))
    for seed, r in rows:
        vals = [r["base"], r["shaft"], r["capital"], *(r[s] for s in SURFACES)]
        cells = [f"{seed:>7}", *(f"{v:7.2f}" for v in vals)]
        cells += [f"{r['fit_s']:7.1f}", f"{r['capital_s']:7.1f}"]
        print(" | ".join(cells))
    print("points per surface (seed 0):", {s: rows[0][1][s + "_n"] for s in SURFACES})
    print(
        "share of the capital's squared deviation (seed 0):",
        {s: round(rows[0][1][s + "_share"], 3) for s in SURFACES},
    )


if __name__ == "__main__":
    import bench_md

    raise SystemExit(bench_md.run(main))
