"""Benchmark column-base generation: triangles per second at several levels of detail.

Usage: python tools/bench_base.py [--repeat N]
Prints, for each preset and LOD (segments × profile slices), the triangle count, the best
time of N runs and the throughput, plus the ratio to the lowest LOD's throughput.
"""

from __future__ import annotations

import argparse
import time

from ionic_usd.column.base import build_base, load_base_preset

LODS = [(24, 2), (48, 4), (120, 8), (240, 16), (480, 32)]
PRESETS = ("G1", "G2", "attic_bezier", "attic_bezier_plinth")


def _best(fn, repeat: int) -> float:
    best = float("inf")
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args(argv)
    print(
        f"{'preset':22s} {'segments':>8s} {'slices':>6s} {'triangles':>10s} "
        f"{'ms':>8s} {'Mtri/s':>8s} {'vs LOD0':>8s}"
    )
    for name in PRESETS:
        base_rate = None
        for segments, slices in LODS:
            p = load_base_preset(name, segments=segments, profile_slices=slices)
            mesh = build_base(p)
            t = _best(lambda p=p: build_base(p), args.repeat)
            rate = mesh.n_triangles / t
            base_rate = base_rate or rate
            print(
                f"{name:22s} {segments:8d} {slices:6d} {mesh.n_triangles:10d} "
                f"{t * 1e3:8.2f} {rate / 1e6:8.2f} {rate / base_rate:8.2f}x"
            )
    t_parse = _best(lambda: load_base_preset("G2"), 50)
    print(f"\nparse + validate G2 preset (incl. TOML read): {t_parse * 1e6:.0f} µs")
    return 0


if __name__ == "__main__":
    import bench_md

    raise SystemExit(bench_md.run(main))
