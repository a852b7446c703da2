"""Benchmark the sliver clean-up (:func:`ionic_usd.geometry.slivers.remove_slivers`) side by
side with a baseline revision's, on every clean-up the column asset's capitals make.

Usage: python tools/bench_slivers.py --baseline DIR [--repeat N]

``DIR`` is another checkout of this project (``git worktree add /tmp/base <commit>``): its
``ionic_usd/geometry/slivers.py`` and the ``triedit.py`` beside it (the edit operations, if it
has one) are loaded as the baseline (against this checkout's ``geometry.mesh``). Builds
``column_asset_meshes(ColumnAssetOptions(lods=("low", "medium", "high"), bases=("G1",),
flutes=("f24",)), workers=1)`` once in a fresh cache, recording every ``remove_slivers``
input (the unions' and the form cuts'); then runs baseline and current on each input (best of
N, taking turns), prints the time per kind of call and the ratio, and counts the calls whose
outputs differ bit for bit (points, face indices, normals, st, st indices): 0 when the change
is a pure speed-up.
"""

from __future__ import annotations

import argparse
import importlib.util
import os
import sys
import tempfile
import time
from collections import defaultdict
from pathlib import Path

import numpy as np

from ionic_usd.geometry import boolean, slivers
from ionic_usd.geometry.mesh import Mesh


def _exec(path: Path, name: str):
    spec = importlib.util.spec_from_file_location(name, path)
    assert spec is not None and spec.loader is not None
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def _load_baseline(folder: Path):
    geo = folder / "ionic_usd" / "geometry"
    if not (geo / "slivers.py").is_file():
        sys.exit(f"bench_slivers: {geo / 'slivers.py'} does not exist (--baseline is a checkout)")
    # the baseline's slivers.py imports TriangleEditor from ionic_usd.geometry.triedit: give
    # it the baseline's own triedit.py (if it has one) while it loads
    key = "ionic_usd.geometry.triedit"
    saved = sys.modules.get(key)
    try:
        if (geo / "triedit.py").is_file():
            sys.modules[key] = _exec(geo / "triedit.py", "baseline_triedit")
        return _exec(geo / "slivers.py", "baseline_slivers").remove_slivers
    finally:
        if saved is None:
            sys.modules.pop(key, None)
        else:
            sys.modules[key] = saved


def _arrays(m: Mesh) -> list[np.ndarray | None]:
    return [m.points, m.face_vertex_counts, m.face_vertex_indices, m.normals, m.st, m.st_indices]


def _same(x: Mesh, y: Mesh) -> bool:
    for a, b in zip(_arrays(x), _arrays(y), strict=True):
        if (a is None) != (b is None):
            return False
        if a is not None and (
            a.shape != b.shape or a.dtype != b.dtype or a.tobytes() != b.tobytes()
        ):
            return False
    return x.name == y.name


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--baseline", type=Path, required=True, help="another checkout")
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args(argv)
    base_fn = _load_baseline(args.baseline)
    os.environ["IONIC_USD_CACHE"] = tempfile.mkdtemp(prefix="bench_slivers_")
    from ionic_usd.pipeline import forms
    from ionic_usd.pipeline.asset import column_asset_meshes
    from ionic_usd.usd.column_asset import ColumnAssetOptions

    opts = ColumnAssetOptions(lods=("low", "medium", "high"), bases=("G1",), flutes=("f24",))
    new_fn = slivers.remove_slivers
    calls: list[tuple[Mesh, float, dict]] = []

    def recording(mesh: Mesh, tol: float, **kw):
        calls.append((mesh, tol, kw))
        return new_fn(mesh, tol, **kw)

    # in this process (workers=1), so the recording sees every call: the unions' (through
    # geometry.boolean) and the form cuts' (through pipeline.forms)
    boolean.remove_slivers = forms.remove_slivers = recording  # type: ignore[assignment]
    try:
        column_asset_meshes(opts, workers=1)
    finally:
        boolean.remove_slivers = forms.remove_slivers = new_fn  # type: ignore[assignment]
    print(f"{len(calls)} remove_slivers calls")
    kinds: dict[str, list[float]] = defaultdict(lambda: [0.0, 0.0, 0, 0])
    for mesh, tol, kw in calls:
        t = {"base": float("inf"), "new": float("inf")}
        out = {}
        for _ in range(args.repeat):  # taking turns: drifting load hits both alike
            for name, fn in (("base", base_fn), ("new", new_fn)):
                t0 = time.perf_counter()
                out[name] = fn(mesh, tol, **kw)
                t[name] = min(t[name], time.perf_counter() - t0)
        k = kinds["form cut (round the cut)" if kw.get("changed") is not None else "union"]
        k[0] += t["base"]
        k[1] += t["new"]
        k[2] += 1
        k[3] += not _same(out["base"], out["new"])
    print(f"{'kind':28s} {'calls':>5s} {'base s':>8s} {'new s':>8s} {'ratio':>6s} {'differ':>6s}")
    tb = tn = 0.0
    nd = 0
    for name, (t_b, t_n, n, d) in kinds.items():
        tb, tn, nd = tb + t_b, tn + t_n, nd + d
        print(f"{name:28s} {n:5d} {t_b:8.3f} {t_n:8.3f} {t_b / t_n:5.2f}x {d:6d}")
    print(f"{'total':28s} {len(calls):5d} {tb:8.3f} {tn:8.3f} {tb / tn:5.2f}x {nd:6d}")
    print("outputs identical (bit for bit) on every call" if not nd else f"{nd} outputs differ")
    return 0


if __name__ == "__main__":
    import bench_md

    raise SystemExit(bench_md.run(main))
