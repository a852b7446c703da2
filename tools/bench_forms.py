"""Benchmark the form cuts (engaged, corner) side by side with manifold3d's boolean difference.

Usage: python tools/bench_forms.py [--repeat N] [--lods high medium low]

For every capital of the temple's column asset (both volute models, both scrolls, normal and
angle capitals) and every base and shaft, per LOD: the package's cut
(:func:`ionic_usd.pipeline.forms.form_cut`: a plane clip for ``engaged``, the two-plane notch
of :mod:`ionic_usd.geometry.notch` for ``corner``, each capital's with its sliver clean-up
round the cut) against the same part minus the wall block by manifold3d
(:func:`ionic_usd.geometry.boolean.difference`, with the same sliver clean-up for capitals),
best of N each, taking turns. Prints the CPU time per (part, form), the ratio, and the
quality of both results: triangles, smallest angle, triangles under 0.1°, and the largest
relative volume difference between the two (the same solid: ~1e-9).
"""

from __future__ import annotations

import argparse
import time
from collections import defaultdict

import numpy as np


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--lods", nargs="*", default=["high", "medium", "low"])
    args = ap.parse_args()

    from ionic_usd.column.column import build_base_part, build_capital_part, build_shaft_part
    from ionic_usd.geometry.check import min_angle_deg, solid_report
    from ionic_usd.geometry.slivers import _tri_angles
    from ionic_usd.pipeline import forms
    from ionic_usd.usd.column_asset import (
        ENGAGED_INSET,
        FLUTE_VARIANTS,
        ColumnAssetOptions,
        volute_variant_params,
    )

    opts = ColumnAssetOptions()
    parts = []  # (kind, mesh)
    for lod in args.lods:
        p = opts.params.with_lod(lod)
        base_h = p.base_params().height
        for b in opts.bases[:1]:
            parts.append(("Base", build_base_part(p, b)))
        fp = p.with_flutes(FLUTE_VARIANTS[opts.flutes[0]])
        parts.append(("Shaft", build_shaft_part(fp, base_h)))
        for vm in opts.volutes:
            vp = volute_variant_params(p, vm)
            for s in opts.scrolls:
                for c in opts.capitals:
                    body = build_capital_part(
                        vp, base_h + p.shaft.length, scroll=s, angle=c == "angle"
                    )
                    parts.append(("CapitalBody", body))

    def boolean_cut(mesh, form, part):
        x_max = None if form == "engaged" else -ENGAGED_INSET
        return forms._wall_cut(mesh, x_max, simplify=part == "CapitalBody")

    rows: dict[tuple[str, str], list] = defaultdict(lambda: [0.0, 0.0, 0, 0, 1e9, 1e9, 0, 0, 0.0])
    for part, mesh in parts:
        for form in ("engaged", "corner"):
            best = {"ours": float("inf"), "manifold3d": float("inf")}
            out = {}
            for _ in range(args.repeat):
                for name, fn in (("ours", forms.form_cut), ("manifold3d", boolean_cut)):
                    t0 = time.process_time()
                    out[name] = fn(mesh, form, part)
                    best[name] = min(best[name], time.process_time() - t0)
            r = rows[(part, form)]
            r[0] += best["ours"]
            r[1] += best["manifold3d"]
            a, b = out["ours"], out["manifold3d"]
            r[2] += a.n_triangles
            r[3] += b.n_triangles
            r[4] = min(r[4], min_angle_deg(a))
            r[5] = min(r[5], min_angle_deg(b))
            r[6] += int((_tri_angles(a.points[a.triangles]).min(axis=1) < 0.1).sum())
            r[7] += int((_tri_angles(b.points[b.triangles]).min(axis=1) < 0.1).sum())
            va = solid_report(a, intersections=False).volume
            vb = solid_report(b, intersections=False).volume
            r[8] = max(r[8], abs(va - vb) / vb)
    head = (
        f"{'part, form':22s} {'ours s':>7s} {'m3d s':>7s} {'ratio':>6s} {'tris':>8s} "
        f"{'m3d tris':>8s} {'min°':>7s} {'m3d min°':>8s} {'<0.1°':>6s} {'m3d':>5s} {'dV rel':>8s}"
    )
    lods = ", ".join(args.lods)
    print(f"{len(parts)} parts over LODs {lods}; CPU seconds, best of {args.repeat}")
    print(head)
    tot = np.zeros(2)
    for (part, form), r in rows.items():
        tot += r[:2]
        print(
            f"{part + ', ' + form:22s} {r[0]:7.3f} {r[1]:7.3f} {r[1] / r[0]:5.2f}x {r[2]:8d} "
            f"{r[3]:8d} {r[4]:7.4f} {r[5]:8.4f} {r[6]:6d} {r[7]:5d} {r[8]:8.1e}"
        )
    print(f"{'total':22s} {tot[0]:7.3f} {tot[1]:7.3f} {tot[1] / tot[0]:5.2f}x")
    return 0


if __name__ == "__main__":
    import bench_md

    raise SystemExit(bench_md.run(main))
