"""Benchmark the closest-point kernel the fits call on every residual evaluation.

Run: ``python tools/bench_closest.py [--repeat 20]``. One core (thread pools pinned to 1).

:func:`ionic_usd.evaluate.polyline.closest_on_polyline` (the grid kernel) beside the same
values by every segment (``_closest_brute``, the kernel before the grid: the reference it is
tested against bit for bit), the kd-tree index (:class:`PolylineIndex`, distances only) and
GEOS (``shapely.distance`` of points to the LineString, vectorised). Cases: the section fit of
a scanned drum (4,000 slab points round a 24-flute section of 577 nodes, as
:mod:`ionic_usd.evaluate.scan_section` fits it), a profile fit (300 generated nodes to a
300-node reference and back, :mod:`ionic_usd.evaluate.fit_core`) and points scattered far
from a curve (the grid's worst case). Prints milliseconds per call, ratios (baseline / grid)
and the largest disagreement with the brute force.
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))


def _cases(rng: np.random.Generator) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    from ionic_usd.evaluate.fit_shaft import fluted_section

    sec = fluted_section(0.6, 24, 10.0, 1.0, 3.0, np.array([0.001, -0.002]), slices=12)
    ang = rng.uniform(0.0, 2.0 * np.pi, 4000)
    r = 0.6 + rng.normal(0.0, 0.004, ang.size)
    slab = np.stack([r * np.cos(ang), r * np.sin(ang)], axis=1)
    ref = np.cumsum(rng.normal(size=(300, 2)), axis=0) * 0.01
    gen = ref + rng.normal(scale=0.002, size=ref.shape)
    far = ref.mean(axis=0) + rng.normal(size=(2000, 2))
    return {
        "section fit (4000 x 577)": (slab, sec),
        "profile fit (300 x 300)": (gen, ref),
        "far points (2000 x 300)": (far, ref),
    }


def _best(fn, repeat: int) -> float:
    fn()
    best = float("inf")
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=20)
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args(argv)
    import shapely

    from ionic_usd.evaluate.polyline import PolylineIndex, _closest_brute, closest_on_polyline

    print(
        f"{'case':<26} {'grid ms':>8} {'brute ms':>9} {'ratio':>6} {'kd-tree ms':>10} "
        f"{'ratio':>6} {'GEOS ms':>8} {'ratio':>6} {'max |diff|':>10}"
    )
    for name, (pts, poly) in _cases(np.random.default_rng(args.seed)).items():
        pts, poly = np.ascontiguousarray(pts), np.ascontiguousarray(poly)
        line = shapely.LineString(poly)
        geo = shapely.points(pts)
        t_grid = _best(lambda p=pts, c=poly: closest_on_polyline(p, c), args.repeat)
        t_brute = _best(lambda p=pts, c=poly: _closest_brute(p, c), args.repeat)
        t_kd = _best(lambda p=pts, c=poly: PolylineIndex(c).distances(p), args.repeat)
        t_geos = _best(lambda g=geo, ln=line: shapely.distance(g, ln), args.repeat)
        diff = np.abs(closest_on_polyline(pts, poly)[0] - _closest_brute(pts, poly)[0]).max()
        print(
            f"{name:<26} {1e3 * t_grid:>8.3f} {1e3 * t_brute:>9.3f} {t_brute / t_grid:>5.1f}x "
            f"{1e3 * t_kd:>10.3f} {t_kd / t_grid:>5.1f}x {1e3 * t_geos:>8.3f} "
            f"{t_geos / t_grid:>5.1f}x {diff:>10.1e}"
        )
    return 0


if __name__ == "__main__":
    import bench_md

    raise SystemExit(bench_md.run(main))
