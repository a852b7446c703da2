"""Benchmark: the capital's texture charts, analytic (carried through the union) vs. xatlas.

Run: ``python tools/bench_capital_charts.py [--lods high medium low] [--repeat 3]``.
For every capital variant (volute model × scroll × normal/angle) of each LOD, side by side:

* **analytic** — the parts carry their generators' charts and the union keeps them
  (:func:`ionic_usd.geometry.boolean.union`): the union's time is the whole cost;
* **xatlas** — the same parts without ``st``, united, then charted by
  :func:`ionic_usd.texture.uv.metric_charts` (xatlas and the chart-overlap split), which is
  what the column asset did before.

Prints CPU seconds (best of ``--repeat``) and their ratio, and the charts' quality on the
surface: the 99th percentile and the maximum of the per-triangle anisotropy (singular-value
ratio of the surface → st map; 1 is conformal), the st area over the surface area, and the
triangles whose st area is not positive (folded or collapsed).
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from ionic_usd.blueprint.column_asset import (  # noqa: E402
    ColumnAssetOptions,
    volute_variant_params,
)
from ionic_usd.column.capital import build_capital  # noqa: E402
from ionic_usd.geometry.boolean import union  # noqa: E402
from ionic_usd.geometry.mesh import Mesh  # noqa: E402
from ionic_usd.lod import level  # noqa: E402
from ionic_usd.texture.atlas import st_distortion  # noqa: E402
from ionic_usd.texture.uv import UVCache, metric_charts  # noqa: E402


def quality(m: Mesh) -> tuple[float, float, float, int]:
    """(p99 anisotropy, max anisotropy, st area / surface area, st triangles with area ≤ 0)
    (:func:`ionic_usd.texture.atlas.st_distortion`)."""
    ratio, st_area, area = st_distortion(m)  # inf: a triangle collapsed to a line in st
    return (
        float(np.percentile(ratio[np.isfinite(ratio)], 99)),
        float(ratio.max()),
        float(st_area.sum() / area.sum()),
        int((st_area <= 0).sum()),
    )


def _best(fn, repeat: int):
    best, out = float("inf"), None
    for _ in range(repeat):
        t = time.process_time()
        out = fn()
        best = min(best, time.process_time() - t)
    return best, out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--lods", nargs="+", default=["high", "medium", "low"])
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    opts = ColumnAssetOptions()
    cache_dir = tempfile.mkdtemp(prefix="bench_capital_charts_")
    print(
        f"{'lod':7} {'variant':28} {'analytic s':>10} {'xatlas s':>9} {'ratio':>6}   "
        f"{'p99 an/xa':>11} {'max an/xa':>13} {'area an/xa':>11} {'folded an/xa':>12}"
    )
    tot_a = tot_x = 0.0
    # warm-up, not counted: the first union imports manifold3d, scipy's graph code, xatlas
    warm = build_capital(opts.params.capital_params(), top_radius=opts.params.shaft.top_radius)
    union(list(warm.as_dict().values()))
    for lod in args.lods:
        p = opts.params.with_lod(lod)
        tpm = level(lod).asset_texels_per_metre
        for vm in opts.volutes:
            for scroll in opts.scrolls:
                for cap in opts.capitals:
                    vp = volute_variant_params(p, vm)
                    parts = list(
                        build_capital(
                            vp.capital_params(scroll),
                            top_radius=vp.shaft.top_radius,
                            angle=cap == "angle",
                        )
                        .as_dict()
                        .values()
                    )
                    bare = [m.with_(st=None) for m in parts]
                    ta, ma = _best(lambda parts=parts: union(parts, "capital"), args.repeat)

                    def charted(bare=bare, tpm=tpm):
                        # a fresh cache every run: xatlas runs each time (the cold cost)
                        cache = UVCache(tempfile.mkdtemp(dir=cache_dir))
                        (m,) = metric_charts([union(bare, "capital")], tpm, cache=cache)
                        return m

                    tx, mx = _best(charted, args.repeat)
                    qa, qx = quality(ma), quality(mx)
                    tot_a += ta
                    tot_x += tx
                    print(
                        f"{lod:7} {vm + ' ' + scroll + ' ' + cap:28} {ta:10.3f} {tx:9.3f} "
                        f"{ta / tx:6.2f}   {qa[0]:5.2f}/{qx[0]:<5.2f} {qa[1]:6.2f}/{qx[1]:<6.1f} "
                        f"{qa[2]:5.3f}/{qx[2]:<5.3f} {qa[3]:5d}/{qx[3]:<6d}"
                    )
    print(f"total CPU s: analytic {tot_a:.2f}, xatlas {tot_x:.2f}, ratio {tot_a / tot_x:.2f}")


if __name__ == "__main__":
    import bench_md

    raise SystemExit(bench_md.run(main))
