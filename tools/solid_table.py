"""Solid-check table of the column asset's meshes (and the temple's): python tools/solid_table.py.

One row per mesh family (part × variant at one LOD): shells, open/non-manifold edges, co-located
points, crossing triangle pairs, faces against their normals, smallest angle, volume.

``--capitals``: one row per capital family (normal/angle × full/engaged/corner × LOD) with the
sliver counts as well: triangles of area < 1e-12 m² (what a zero-area check flags) and
triangles with an angle under 0.5°.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from ionic_usd.geometry.check import manifold_status, solid_report
from ionic_usd.geometry.mesh import Mesh
from ionic_usd.pipeline.asset import column_asset_meshes
from ionic_usd.usd.column_asset import ColumnAssetOptions

#: a triangle with less area than this (m²) counts as zero-area
ZERO_AREA = 1e-12
#: a triangle with an angle under this (degrees) counts as a sliver
SLIVER_DEG = 0.5


def sliver_counts(mesh: Mesh) -> tuple[int, int]:
    """(zero-area triangles, sliver triangles) of a triangle mesh."""
    p = mesh.points[mesh.triangles]
    e = p[:, [1, 2, 0]] - p  # (t, 3, 3) edges
    area = 0.5 * np.linalg.norm(np.cross(e[:, 0], -e[:, 2]), axis=1)
    ln = np.linalg.norm(e, axis=2)
    cos = []
    for i in range(3):
        a, b = e[:, i], -e[:, (i + 2) % 3]
        cos.append(np.einsum("ij,ij->i", a, b) / np.maximum(ln[:, i] * ln[:, (i + 2) % 3], 1e-300))
    ang = np.degrees(np.arccos(np.clip(np.stack(cos, axis=1), -1.0, 1.0))).min(axis=1)
    return int((area < ZERO_AREA).sum()), int((ang < SLIVER_DEG).sum())


def capital_table(lods: tuple[str, ...]) -> None:
    print(
        f"{'capital family':28s} {'tris':>6s} {'shells':>6s} {'open':>5s} {'nonman':>6s} "
        f"{'coloc':>5s} {'cross':>5s} {'minang':>8s} {'zero':>5s} {'<0.5°':>5s} manifold3d"
    )
    opts = ColumnAssetOptions(
        lods=lods,
        bases=("attic_bezier_plinth",),
        flutes=("f24",),
        scrolls=("S1",),
        forms=("full", "engaged", "corner"),
    )
    for m in column_asset_meshes(opts):
        if m.part != "CapitalBody":
            continue
        r = solid_report(m.mesh)
        st, genus, _ = manifold_status(m.mesh)
        zero, sliver = sliver_counts(m.mesh)
        print(
            f"{m.tags['capital'] + '/' + m.tags.get('form', 'full') + '/' + m.tags['lod']:28s} "
            f"{r.triangles:6d} {r.shells:6d} {r.open_edges:5d} {r.nonmanifold_edges:6d} "
            f"{r.colocated_points:5d} {r.self_intersections:5d} {r.min_angle:8.4f} "
            f"{zero:5d} {sliver:5d} {st} g={genus}",
            flush=True,
        )


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--lod", default="high")
    ap.add_argument("--form", action="append")
    ap.add_argument(
        "--capitals",
        action="store_true",
        help="the capital families at every LOD (or --lod, repeated)",
    )
    args = ap.parse_args()
    if args.capitals:
        capital_table(("high", "medium", "low") if args.lod == "all" else (args.lod,))
        return
    kw = {"forms": tuple(args.form)} if args.form else {}
    opts = ColumnAssetOptions(lods=(args.lod,), **kw)
    print(
        f"{'mesh':34s} {'tris':>6s} {'shells':>6s} {'open':>5s} {'nonman':>6s} "
        f"{'coloc':>5s} {'cross':>6s} {'vs_n':>5s} {'minang':>7s} {'vol_l':>9s} manifold3d"
    )
    for m in column_asset_meshes(opts):
        t0 = time.perf_counter()
        r = solid_report(m.mesh)
        st, genus, _ = manifold_status(m.mesh)
        print(
            f"{m.part + '/' + m.name:34s} {r.triangles:6d} {r.shells:6d} {r.open_edges:5d} "
            f"{r.nonmanifold_edges:6d} {r.colocated_points:5d} {r.self_intersections:6d} "
            f"{r.against_normals:5d} {r.min_angle:7.3f} {r.volume * 1000:9.2f} {st} g={genus}"
            f"  ({time.perf_counter() - t0:.1f}s)",
            flush=True,
        )
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
            print(
                f"{'weld Base_' + b + '+Shaft_' + fname:34s} {r.triangles:6d} {r.shells:6d} "
                f"{r.open_edges:5d} {r.nonmanifold_edges:6d} {r.colocated_points:5d}",
                flush=True,
            )


if __name__ == "__main__":
    main()
