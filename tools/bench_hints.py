"""Benchmark: the extentsHint computation of a temple build, the previous code beside the current.

Run: ``python tools/bench_hints.py [--repeat N]``. Builds ``ionic-usd temple -o X --force`` (warm
mesh cache, so the hints are a visible share of the build) alternately with the previous hint
code and the current one, times the hint calls of the column asset (``write_asset_layers``) and
of the temple (``bound_changing_sets`` + ``variant_extents_hints`` in ``compose_temple``), best of
N, and compares every authored ``extentsHint`` (every layer of both outputs, every variant
spec) value for value. The previous code composed the asset once per combination of its
variant sets (576 for the default column): it is kept here as the ``old`` mode, which makes
the asset fall back to :func:`ionic_usd.usd.bounds.variant_extents_hints`.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np


def _timed(fn: Callable[..., Any], acc: list[float]) -> Callable[..., Any]:
    def wrapper(*a: Any, **k: Any) -> Any:
        t = time.perf_counter()
        try:
            return fn(*a, **k)
        finally:
            acc[0] += time.perf_counter() - t

    return wrapper


def _no_memo(fn: Callable[..., Any]) -> Callable[..., Any]:
    def wrapper(*a: Any, memo: Any = None, **k: Any) -> Any:
        return fn(*a, **k)

    return wrapper


def build(out: Path, mode: str) -> tuple[float, float, float]:
    """One temple build in ``mode`` ('old' or 'new'): (asset hints s, temple hints s, build s)."""
    import ionic_usd.usd.asset as asset
    import ionic_usd.usd.bounds as bounds
    import ionic_usd.usd.temple as temple
    from ionic_usd.cli import main

    saved = {
        (asset, "toggled_extents_hints"): asset.toggled_extents_hints,
        (asset, "variant_extents_hints"): asset.variant_extents_hints,
        (temple, "bound_changing_sets"): temple.bound_changing_sets,
        (temple, "variant_extents_hints"): temple.variant_extents_hints,
    }
    a, t = [0.0], [0.0]
    try:
        if mode == "old":
            asset.toggled_extents_hints = lambda *args, **kw: None  # the per-combination path
        else:
            asset.toggled_extents_hints = _timed(bounds.toggled_extents_hints, a)
        asset.variant_extents_hints = _timed(bounds.variant_extents_hints, a)
        tb, tv = saved[(temple, "bound_changing_sets")], saved[(temple, "variant_extents_hints")]
        if mode == "old":  # no memo: every pass and the product compose all their combinations
            tb = _no_memo(tb)
            tv = _no_memo(tv)
        temple.bound_changing_sets = _timed(tb, t)
        temple.variant_extents_hints = _timed(tv, t)
        t0 = time.perf_counter()
        rc = main(["-q", "temple", "-o", str(out), "--force"])
        total = time.perf_counter() - t0
        if rc not in (0, None):
            sys.exit(f"build failed ({mode}): {rc}")
    finally:
        for (mod, name), fn in saved.items():
            setattr(mod, name, fn)
    return a[0], t[0], total


def authored_hints(folder: Path) -> dict[tuple[str, str], np.ndarray]:
    """(layer relative path, attribute spec path) → authored extentsHint, over every layer."""
    from pxr import Sdf

    out: dict[tuple[str, str], np.ndarray] = {}
    for f in sorted(folder.rglob("*.usd*")):
        layer = Sdf.Layer.FindOrOpen(str(f))
        rel = str(f.relative_to(folder))

        def visit(path: Sdf.Path, layer: Sdf.Layer = layer, rel: str = rel) -> None:
            if path.IsPropertyPath() and path.name == "extentsHint":
                v = layer.GetAttributeAtPath(path).default
                out[(rel, str(path))] = np.array(v, dtype=np.float32)

        layer.Traverse(Sdf.Path.absoluteRootPath, visit)
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    os.environ.setdefault("IONIC_USD_CACHE", tempfile.mkdtemp(prefix="ionic_bench_cache_"))
    tmp = Path(tempfile.mkdtemp(prefix="ionic_bench_hints_"))
    build(tmp / "warmup", "new")  # fills the mesh cache
    best: dict[str, tuple[float, float, float]] = {}
    for _ in range(args.repeat):
        for mode in ("old", "new"):
            r = build(tmp / mode, mode)
            prev = best.get(mode, r)
            best[mode] = (min(prev[0], r[0]), min(prev[1], r[1]), min(prev[2], r[2]))
    print(f"best of {args.repeat} warm temple builds (s):")
    print(f"{'':>6} {'asset hints':>12} {'temple hints':>13} {'all hints':>10} {'build':>8}")
    for mode in ("old", "new"):
        a, t, total = best[mode]
        print(f"{mode:>6} {a:>12.3f} {t:>13.3f} {a + t:>10.3f} {total:>8.2f}")
    old, new = sum(best["old"][:2]), sum(best["new"][:2])
    print(f"hints speed-up: {old / new:.2f}x (asset {best['old'][0] / best['new'][0]:.1f}x)")
    h_old, h_new = authored_hints(tmp / "old"), authored_hints(tmp / "new")
    same_keys = h_old.keys() == h_new.keys()
    differ = [k for k in h_old if k in h_new and not np.array_equal(h_old[k], h_new[k])]
    print(
        f"extentsHint values: {len(h_old)} old, {len(h_new)} new; same specs: {same_keys}; "
        f"differing: {len(differ)}"
    )
    for k in differ[:10]:
        print("  differs:", k, h_old[k].tolist(), h_new[k].tolist())
    print("every hint identical:", same_keys and not differ and bool(h_old))


if __name__ == "__main__":
    import bench_md

    raise SystemExit(bench_md.run(main))
