"""Benchmark: exporting the Portunus temple (and optionally a city) as glTF, usdz and STL.

Run: ``python tools/bench_export.py [--temple PortunusTemple/Temple.usda] [--city City.usda]``
(without ``--temple`` a temple with 1024 px textures is built in a temporary folder first).

Per variant of the temple ``.glb`` — GPU instancing (default), plain nodes, Draco, low LOD —
prints the file size and how much of it is geometry and textures, the export time (best of
3, the scene read included), triangles stored and drawn, and draw calls. Where Node.js and
``tools/node`` (``npm ci``) are present, the Khronos glTF-Validator's own counts (errors,
warnings, draw calls, triangles) are printed beside ours.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def _validator(paths: list[Path]) -> dict:
    node = shutil.which("node")
    script = ROOT / "tools" / "node" / "validate.mjs"
    if node is None or not (ROOT / "tools" / "node" / "node_modules").is_dir():
        return {}
    out = Path(tempfile.mkdtemp()) / "reports.json"
    subprocess.run(
        [node, str(script), "--json", str(out), *map(str, paths)],
        capture_output=True,
        text=True,
        timeout=1200,
    )
    return json.loads(out.read_text()) if out.is_file() else {}


def _image_bytes(path: Path) -> int:
    import pygltflib

    g = pygltflib.GLTF2().load(str(path))
    return sum(g.bufferViews[i.bufferView].byteLength for i in g.images if i.bufferView is not None)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--temple", type=Path, help="an existing Temple.usda")
    ap.add_argument("--city", type=Path, help="an existing City.usda (also benchmarked)")
    ap.add_argument("--repeat", type=int, default=3)
    a = ap.parse_args()
    from ionic_usd.export import export_scene

    work = Path(tempfile.mkdtemp(prefix="ionic_bench_export_"))
    temple = a.temple
    if temple is None:
        os.environ.setdefault("IONIC_USD_CACHE", str(work / "cache"))
        from ionic_usd.pipeline.temple import compose_temple
        from ionic_usd.temple.layout import portunus_layout

        temple = compose_temple(work / "PortunusTemple", portunus_layout()).root
    cases = [
        ("temple.glb", temple, {}),
        ("temple_gpu.glb", temple, {"gpu_instancing": True}),
        ("temple_unmerged.glb", temple, {"merge": False}),
        ("temple_draco.glb", temple, {"compress": "draco"}),
        ("temple_low.glb", temple, {"lod": "low"}),
        ("temple_low_draco.glb", temple, {"lod": "low", "compress": "draco"}),
    ]
    if a.city is not None:
        cases += [("city.glb", a.city, {}), ("city_draco.glb", a.city, {"compress": "draco"})]
    rows = []
    for name, src, kw in cases:
        out = work / name
        best = float("inf")
        for _ in range(a.repeat):
            t0 = time.perf_counter()
            res = export_scene(src, out, force=True, **kw)
            best = min(best, time.perf_counter() - t0)
        rows.append((name, res.report, best, _image_bytes(out)))
    reports = _validator([work / r[0] for r in rows])
    print(
        f"{'file':<22}{'MB':>7}{'geom MB':>9}{'tex MB':>8}{'export s':>10}{'stored tri':>12}"
        f"{'drawn tri':>12}{'draws':>7}{'gpu inst':>9}   validator (err/warn, draws, tri)"
    )
    for name, r, secs, img in rows:
        v = reports.get(str(work / name))
        vtxt = ""
        if v:
            vtxt = (
                f"{v['issues']['numErrors']}/{v['issues']['numWarnings']}, "
                f"{v['info']['drawCallCount']}, {v['info']['totalTriangleCount']:,}"
            )
        print(
            f"{name:<22}{r.bytes / 1e6:>7.2f}{(r.bytes - img) / 1e6:>9.2f}{img / 1e6:>8.2f}"
            f"{secs:>10.2f}{r.triangles:>12,}{r.triangles_drawn:>12,}{r.draw_calls:>7}"
            f"{r.gpu_instanced_meshes:>9}   {vtxt}"
        )
    for name, kw in (("temple.usdz", {}), ("column.stl", None)):
        t0 = time.perf_counter()
        if kw is None:
            col = temple.parent / "IonicColumn" / "IonicColumn.usda"
            res = export_scene(col, work / name, scale=0.05, force=True)
            s = res.report.solids[0]
            print(
                f"{name}: {(work / name).stat().st_size / 1e6:.2f} MB at 1:20, volume "
                f"{s.volume * 1e9:,.0f} mm^3, closed {s.closed}, "
                f"{time.perf_counter() - t0:.2f} s"
            )
        else:
            res = export_scene(temple, work / name, force=True)
            print(
                f"{name}: {res.report.bytes / 1e6:.2f} MB, {res.report.files} files, "
                f"{time.perf_counter() - t0:.2f} s"
            )
    print(f"(outputs in {work})")


if __name__ == "__main__":
    import bench_md

    raise SystemExit(bench_md.run(main))
