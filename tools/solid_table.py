"""Solid-check table of the column asset's meshes (and the temple's): python tools/solid_table.py.

One row per mesh family (part × variant at one LOD): shells, open/non-manifold edges, co-located
points, crossing triangle pairs, faces against their normals, smallest angle, volume.
"""

from __future__ import annotations

import argparse
import time

from ionic_usd.geometry.check import manifold_status, solid_report
from ionic_usd.pipeline.asset import column_asset_meshes
from ionic_usd.usd.column_asset import ColumnAssetOptions


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--lod", default="high")
    ap.add_argument("--form", action="append")
    args = ap.parse_args()
    kw = {"forms": tuple(args.form)} if args.form else {}
    opts = ColumnAssetOptions(lods=(args.lod,), **kw)
    print(f"{'mesh':34s} {'tris':>6s} {'shells':>6s} {'open':>5s} {'nonman':>6s} "
          f"{'coloc':>5s} {'cross':>6s} {'vs_n':>5s} {'minang':>7s} {'vol_l':>9s} manifold3d")
    for m in column_asset_meshes(opts):
        t0 = time.perf_counter()
        r = solid_report(m.mesh)
        st, genus, _ = manifold_status(m.mesh)
        print(f"{m.part + '/' + m.name:34s} {r.triangles:6d} {r.shells:6d} {r.open_edges:5d} "
              f"{r.nonmanifold_edges:6d} {r.colocated_points:5d} {r.self_intersections:6d} "
              f"{r.against_normals:5d} {r.min_angle:7.3f} {r.volume * 1000:9.2f} {st} g={genus}"
              f"  ({time.perf_counter() - t0:.1f}s)", flush=True)
    # base + shaft welded (caps between them removed): one watertight solid?
    from ionic_usd.column.base import build_base
    from ionic_usd.column.shaft import build_shaft
    from ionic_usd.geometry.mesh import merge, weld
    from ionic_usd.usd.column_asset import FLUTE_VARIANTS

    p = opts.params.with_lod(args.lod)
    for b in opts.bases:
        bp = p.base_params(b)
        base = build_base(bp, cap_top=False)
        for fname in opts.flutes:
            fp = p.with_flutes(FLUTE_VARIANTS[fname]).shaft_params()
            shaft = build_shaft(fp, cap_bottom=False, y_offset=bp.height)
            w = weld(merge([base, shaft]), 1e-6)
            r = solid_report(w, intersections=False)
            print(f"{'weld Base_' + b + '+Shaft_' + fname:34s} {r.triangles:6d} {r.shells:6d} "
                  f"{r.open_edges:5d} {r.nonmanifold_edges:6d} {r.colocated_points:5d}", flush=True)


if __name__ == "__main__":
    main()
