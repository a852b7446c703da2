"""Benchmark: whole column per LOD, the column asset and the Portunus temple, cold and warm.

Run: ``python tools/bench_pipeline.py``. "Cold" uses an empty cache folder (every UV unwrap and
texture is computed: what a first run on a new machine costs); "warm" rebuilds the same output
with the cache filled (what an edit-and-rebuild loop costs). Targets: full column ≤ 50 ms at
high LOD on one core (issue 4); default temple cold ≤ 5 s on the 2-core machine (issue 6).
"""

from __future__ import annotations

import os
import tempfile
import time
from pathlib import Path


def main() -> None:
    os.environ["IONIC_USD_CACHE"] = tempfile.mkdtemp(prefix="ionic_bench_cache_")
    from ionic_usd.column.column import LODS, build_column, portunus_column_params
    from ionic_usd.temple.layout import portunus_layout
    from ionic_usd.usd.column_asset import ColumnAssetOptions, build_column_asset
    from ionic_usd.usd.temple import compose_temple

    print("whole column (base + shaft + capital body + scrolls), best of 5:")
    print(f"{'lod':>8} {'triangles':>10} {'ms':>8} {'Mtri/s':>8}")
    for lod in LODS:
        p = portunus_column_params(lod=lod)
        build_column(p)
        best = min(_timed(lambda p=p: build_column(p)) for _ in range(5))
        n = build_column(p).n_triangles
        print(f"{lod:>8} {n:>10,} {1e3 * best:>8.1f} {n / best / 1e6:>8.2f}")
    print("target: high LOD <= 50 ms\n")

    out = Path(tempfile.mkdtemp())
    cold = build_column_asset(out / "a" / "IonicColumn", ColumnAssetOptions())
    warm = build_column_asset(out / "a" / "IonicColumn", ColumnAssetOptions(), force=True)
    print(f"column asset: {cold.meshes} meshes, triangles per LOD {cold.triangles_per_lod}, "
          f"{cold.bytes_on_disk / 1e6:.1f} MB")
    print(f"  cold {cold.seconds:.2f} s ({cold.uv_unwraps} unwraps), warm {warm.seconds:.2f} s "
          f"({warm.uv_unwraps} unwraps), ratio {cold.seconds / warm.seconds:.1f}x\n")

    os.environ["IONIC_USD_CACHE"] = tempfile.mkdtemp(prefix="ionic_bench_cache_")
    t = compose_temple(out / "t", portunus_layout())
    w = compose_temple(out / "t", portunus_layout(), force=True)
    print(f"Portunus temple: {t.files} files, {t.prims} prims, {t.instances} instances of "
          f"{t.prototypes} prototypes, {t.triangles:,} triangles")
    print(f"  cold {t.seconds:.2f} s, warm {w.seconds:.2f} s, ratio {t.seconds / w.seconds:.1f}x"
          f"  (target: cold <= 5 s on 2 cores)")


def _timed(fn) -> float:
    t0 = time.perf_counter()
    fn()
    return time.perf_counter() - t0


if __name__ == "__main__":
    main()
