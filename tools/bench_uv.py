"""Benchmark: xatlas unwrapping of the shaft, cold and through the UV cache.

Run: ``python tools/bench_uv.py [--slices 2 4 8] [--texels-per-metre 256] [--repeat 3]``.
Per level of detail ($h = flute_slices) prints triangles, charts, atlas size, utilisation and
the common normalising size S, then wall times: cold (xatlas runs, best of ``--repeat`` with
a fresh cache folder each time), warm in memory (same ``UVCache``), warm from disk (a fresh
``UVCache`` on the same folder: what a rebuild in a new process pays) and the ratio
cold / disk.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from ionic_usd.column.shaft import ShaftParams, build_shaft  # noqa: E402
from ionic_usd.texture.uv import (  # noqa: E402
    DEFAULT_PADDING,
    DEFAULT_TEXELS_PER_METRE,
    XATLAS_VERSION,
    UVCache,
    common_atlas_size,
    unwrap,
)


def timed(fn, *args, **kwargs):
    t0 = time.perf_counter()
    out = fn(*args, **kwargs)
    return out, time.perf_counter() - t0


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--slices", type=int, nargs="*", default=[2, 4, 8])
    ap.add_argument("--texels-per-metre", type=float, default=DEFAULT_TEXELS_PER_METRE)
    ap.add_argument("--padding", type=int, default=DEFAULT_PADDING)
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args(argv)
    tpm, pad = args.texels_per_metre, args.padding
    print(f"xatlas {XATLAS_VERSION}, {tpm:g} px/m, padding {pad}")
    head = (
        f"{'h':>3} {'triangles':>9} {'charts':>6} {'atlas':>11} {'util':>5} {'S':>5} "
        f"{'cold ms':>8} {'mem ms':>7} {'disk ms':>8} {'cold/disk':>9}"
    )
    print(head)
    print("-" * len(head))
    with tempfile.TemporaryDirectory() as tmp:
        for h in args.slices:
            mesh = build_shaft(ShaftParams(flute_slices=h))
            cold = []
            for r in range(args.repeat):
                cache = UVCache(Path(tmp) / f"h{h}-{r}")
                atlas, dt = timed(unwrap, mesh, texels_per_metre=tpm, padding=pad, cache=cache)
                cold.append(dt)
            assert cache.misses == 1
            _, mem = timed(unwrap, mesh, texels_per_metre=tpm, padding=pad, cache=cache)
            fresh = UVCache(cache.folder)
            _, disk = timed(unwrap, mesh, texels_per_metre=tpm, padding=pad, cache=fresh)
            assert (cache.hits, fresh.disk_hits, fresh.misses) == (1, 1, 0)
            best = min(cold)
            print(
                f"{h:>3} {mesh.n_triangles:>9} {atlas.chart_count:>6} "
                f"{f'{atlas.width}x{atlas.height}':>11} {atlas.utilisation:>5.2f} "
                f"{common_atlas_size([atlas]):>5} {best * 1e3:>8.0f} {mem * 1e3:>7.2f} "
                f"{disk * 1e3:>8.2f} {best / disk:>8.0f}x"
            )
    return 0


if __name__ == "__main__":
    import bench_md

    raise SystemExit(bench_md.run(main))
