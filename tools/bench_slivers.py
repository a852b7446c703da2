"""Benchmark the sliver clean-up (:func:`ionic_usd.geometry.slivers.remove_slivers`) side by
side with a baseline revision's, on every clean-up the column asset's capitals make.

Usage: python tools/bench_slivers.py --baseline DIR [--repeat N]

``DIR`` is another checkout of this project (``git worktree add /tmp/base <commit>``): its
``ionic_usd/geometry/slivers.py`` and the ``triedit.py`` beside it (the edit operations, if it
has one) are loaded as the baseline (against this checkout's ``geometry.mesh``; against its own
``mesh.py`` if that predates :class:`~ionic_usd.geometry.corners.CornerValues`, the inputs
converted to its ``Mesh`` before timing and its outputs back for the comparison). Builds
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
from ionic_usd.geometry.mesh import CornerValues, Mesh


def _exec(path: Path, name: str):
    spec = importlib.util.spec_from_file_location(name, path)
    assert spec is not None and spec.loader is not None
    mod = importlib.util.module_from_spec(spec)
    sys.modules[name] = mod  # dataclasses look their module up while they are made
    spec.loader.exec_module(mod)
    return mod


def _load_baseline(folder: Path):
    """(remove_slivers, input converter, output converter) of the baseline checkout."""
    geo = folder / "ionic_usd" / "geometry"
    if not (geo / "slivers.py").is_file():
        sys.exit(f"bench_slivers: {geo / 'slivers.py'} does not exist (--baseline is a checkout)")
    old_mesh = (
        "class CornerValues" not in (geo / "mesh.py").read_text()
        and not (geo / "corners.py").is_file()
    )
    # the baseline's slivers.py imports TriangleEditor from ionic_usd.geometry.triedit: give
    # it the baseline's own triedit.py (if it has one), and its own mesh.py if the Mesh
    # value changed since, while it loads
    keys = ["ionic_usd.geometry.triedit"] + ["ionic_usd.geometry.mesh"] * old_mesh
    saved = {k: sys.modules.get(k) for k in keys}
    try:
        base_mesh = None
        if old_mesh:
            base_mesh = sys.modules[keys[1]] = _exec(geo / "mesh.py", "baseline_mesh")
        if (geo / "triedit.py").is_file():
            sys.modules[keys[0]] = _exec(geo / "triedit.py", "baseline_triedit")
        fn = _exec(geo / "slivers.py", "baseline_slivers").remove_slivers
    finally:
        for k, v in saved.items():
            if v is None:
                sys.modules.pop(k, None)
            else:
                sys.modules[k] = v
    if base_mesh is None:
        return fn, lambda m: m, lambda m: m
    return fn, lambda m: _to_old(base_mesh, m), _from_old


def _to_old(mod, m: Mesh):
    """``m`` as the ``Mesh`` of a mesh.py with USD's encodings as fields."""
    n, kw = m.normals, {}
    if n is not None:
        kw["normals"] = n.values
        kw["normals_interpolation"] = "vertex" if n.by_point else "faceVarying"
        if not n.by_point and not n.one_per_corner:
            kw["normals_indices"] = n.indices
    if m.st is not None:
        kw.update(st=m.st.values, st_indices=m.st.corner_indices(m.face_vertex_indices))
        kw["st_distinct"] = m.st.distinct
    return mod.Mesh(m.points, m.face_vertex_counts, m.face_vertex_indices, name=m.name, **kw)


def _from_old(o) -> Mesh:
    normals = st = None
    if o.normals is not None:
        if o.normals_interpolation == "vertex":
            normals = CornerValues(o.normals)
        elif o.normals_indices is None:
            normals = CornerValues.per_corner(o.normals)
        else:
            normals = CornerValues(o.normals, o.normals_indices)
    if o.st is not None:
        st = CornerValues(o.st, o.st_indices, o.st_distinct)
    return Mesh(o.points, o.face_vertex_counts, o.face_vertex_indices, normals, st, name=o.name)


def _arrays(m: Mesh) -> list[np.ndarray | None]:
    out = [m.points, m.face_vertex_counts, m.face_vertex_indices]
    for a in (m.normals, m.st):
        flat = a is None or a.by_point or a.one_per_corner
        out += [None if a is None else a.values, None if flat else a.indices]  # type: ignore[union-attr]
    return out


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
    base_fn, to_base, from_base = _load_baseline(args.baseline)
    cache = tempfile.TemporaryDirectory(prefix="bench_slivers_")
    os.environ["IONIC_USD_CACHE"] = cache.name  # removed when the process ends
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
        inp = {"base": to_base(mesh), "new": mesh}
        for _ in range(args.repeat):  # taking turns: drifting load hits both alike
            for name, fn in (("base", base_fn), ("new", new_fn)):
                t0 = time.perf_counter()
                out[name] = fn(inp[name], tol, **kw)
                t[name] = min(t[name], time.perf_counter() - t0)
        out["base"] = from_base(out["base"])
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
