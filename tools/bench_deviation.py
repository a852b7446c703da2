"""Deviation map of a large scan against its fitted column: ionic_usd vs Open3D.

Usage: python tools/bench_deviation.py [--points 1000000] [--fit-points 6000]
[--markdown docs/bench/deviation.md]

Fits a column to a subset of a synthetic scan of a fragment (tests/synth_scan.py: a
square plinth, an Attic base and a fluted drum, 0.8 mm noise, mm units), then times the
distance of every point of the whole 1 M point scan from the fitted column:

* ionic_usd: :func:`ionic_usd.evaluate.fit_scan.scan_deviation` (exact to the shaft's
  section and the base's meridian and plinth; the capital, when present, by a kd-tree);
* Open3D: ``RaycastingScene.compute_distance`` on the fitted column's triangle mesh (the
  scene's build timed apart), with the same points (Open3D: ``pip install open3d``).

Prints both times, their ratio and how far the two distances differ (the mesh is the
generator's tessellation of the surfaces ionic_usd measures exactly).
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests"))


def main() -> None:
    from synth_scan import fragment_scan

    from ionic_usd.column.column import build_column
    from ionic_usd.evaluate.fit_scan import fit_column_scan, scan_deviation

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--points", type=int, default=1_000_000)
    ap.add_argument("--fit-points", type=int, default=6000)
    ap.add_argument("--repeat", type=int, default=3)
    a = ap.parse_args()
    big, _, _ = fragment_scan(a.points, seed=0)
    pts = big * 1e-3
    rng = np.random.default_rng(0)
    fit = fit_column_scan(pts[rng.choice(len(pts), a.fit_points, replace=False)])
    print(f"{len(pts):,} points; fitted column: parts {sorted(fit.frame.parts)}")

    def ours() -> np.ndarray:
        return scan_deviation(pts, fit.column, fit.matrix)

    scan_deviation(pts[:1000], fit.column, fit.matrix)  # compiled kernels loaded first
    d_ours, t_ours, c_ours = _best(ours, a.repeat)
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    print(f"load average {load:.1f} on {os.cpu_count()} CPUs")
    print(f"ionic_usd scan_deviation: {t_ours:.3f} s wall, {c_ours:.3f} s CPU (best of {a.repeat})")
    try:
        import open3d as o3d
    except ImportError:
        print("open3d not installed: pip install open3d (py3.11 wheels on PyPI) to compare")
        return
    parts = build_column(fit.column).parts()
    allp, allt, off = [], [], 0
    for mesh in parts.values():
        allp.append(np.asarray(mesh.points, dtype=np.float64))
        allt.append(np.asarray(mesh.triangles) + off)
        off += len(mesh.points)
    verts = np.concatenate(allp) @ fit.matrix[:3, :3] + fit.matrix[3, :3]
    tris = np.concatenate(allt)
    t0 = time.perf_counter()
    scene = o3d.t.geometry.RaycastingScene()
    scene.add_triangles(
        o3d.core.Tensor(verts.astype(np.float32)), o3d.core.Tensor(tris.astype(np.uint32))
    )
    query = o3d.core.Tensor(pts.astype(np.float32))
    scene.compute_distance(query[:10])  # the BVH is built on the first query
    t_build = time.perf_counter() - t0

    def theirs() -> np.ndarray:
        return scene.compute_distance(query).numpy().astype(np.float64)

    d_o3d, t_o3d, c_o3d = _best(theirs, a.repeat)
    diff = np.abs(d_ours - d_o3d) * 1000.0
    print(
        f"Open3D RaycastingScene.compute_distance: {t_o3d:.3f} s wall, {c_o3d:.3f} s CPU "
        f"(best of {a.repeat}; scene "
        f"of {len(tris):,} triangles built in {t_build:.3f} s)"
    )
    print(
        f"ratio ionic_usd / Open3D: {t_ours / t_o3d:.2f} wall (query), "
        f"{t_ours / (t_o3d + t_build):.2f} wall (query + scene build), {c_ours / c_o3d:.2f} CPU"
    )
    print(
        f"distances differ by {np.median(diff):.3f} mm median, {np.percentile(diff, 99):.3f} mm "
        f"p99 (the mesh's tessellation); rms ours {1000 * np.sqrt(np.mean(d_ours**2)):.3f} mm, "
        f"Open3D {1000 * np.sqrt(np.mean(d_o3d**2)):.3f} mm"
    )


def _best(fn, repeat: int) -> tuple[np.ndarray, float, float]:
    """The result, the best wall time and the best CPU time (all threads) of ``repeat``."""
    best, cpu, out = float("inf"), float("inf"), None
    for _ in range(repeat):
        t0, c0 = time.perf_counter(), time.process_time()
        out = fn()
        best = min(best, time.perf_counter() - t0)
        cpu = min(cpu, time.process_time() - c0)
    return out, best, cpu


if __name__ == "__main__":
    import bench_md

    raise SystemExit(bench_md.run(main))
