"""Build every built-in temple and render them side by side at one scale into docs/temples.png.

Run: ``python tools/render_temples.py [--work DIR]`` (needs the preview extra). Each preset is
composed (``Temple.from_toml``, 64 px textures, the default detail) into DIR/<name>/, the
folders are referenced side by side along +X (front to the camera, their bounds 6 m apart) by one
DIR/temples.usda, and that scene is rendered with the headless preview at LOD ``low`` through a
narrow field of view (``--fov``, 8°: the camera stands far off, so the fronts, all on one line,
show at nearly one scale and the flanks hardly at all).
Prints the build time per preset (wall and CPU seconds, the asset's worker processes
included once they have finished).
"""

from __future__ import annotations

import argparse
import resource
import tempfile
import time
from pathlib import Path

from pxr import Gf, Usd, UsdGeom

from ionic_usd.api import Temple
from ionic_usd.preview import camera, render_preview
from ionic_usd.temple.presets import PRESETS, preset_path
from ionic_usd.usd.city_prototypes import prototype_stats

DOCS = Path(__file__).resolve().parent.parent / "docs"
GAP = 6.0


def _cpu() -> float:
    """CPU seconds of this process and its finished children (the asset's process pool)."""
    own, kids = (
        resource.getrusage(resource.RUSAGE_SELF),
        resource.getrusage(resource.RUSAGE_CHILDREN),
    )
    return own.ru_utime + own.ru_stime + kids.ru_utime + kids.ru_stime


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--work", type=Path, default=None)
    ap.add_argument("--out", type=Path, default=DOCS / "temples.png")
    ap.add_argument(
        "--fov", type=float, default=8.0, help="field of view, degrees (narrow: near one scale)"
    )
    args = ap.parse_args()
    work = args.work or Path(tempfile.mkdtemp(prefix="temples_"))
    stage = Usd.Stage.CreateNew(str(work / "temples.usda"))
    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.y)
    UsdGeom.SetStageMetersPerUnit(stage, 1.0)
    world = UsdGeom.Xform.Define(stage, "/World")
    stage.SetDefaultPrim(world.GetPrim())
    x = 0.0
    for name in PRESETS:
        temple = Temple.from_toml(preset_path(name))
        t0, c0 = time.perf_counter(), _cpu()
        temple.save(work / name, force=True, texture_size=64)
        dt, cpu = time.perf_counter() - t0, _cpu() - c0
        p = temple.layout.params
        # the built temple's own bound (steps, podium and cornices included), so that
        # neighbours stand GAP apart however far their parts reach
        lo, hi, _ = prototype_stats(
            Usd.Stage.Open(str(work / name / "Temple.usda")), "/Temple", {"lod": "low"}
        )
        x -= lo[0]
        xf = UsdGeom.Xform.Define(stage, f"/World/{name}")
        xf.AddTranslateOp().Set(Gf.Vec3d(x, 0.0, -p.stylobate_length / 2))
        half = hi[0]
        xf.GetPrim().GetReferences().AddReference(f"./{name}/Temple.usda")
        x += half + GAP
        print(f"{name}: {temple.layout.name}, built in {dt:.1f} s wall, {cpu:.1f} CPU-s")
    stage.GetRootLayer().Save()
    camera.FOV_DEG = args.fov  # a far, narrow camera: every front at nearly one scale
    s = render_preview(
        work / "temples.usda", args.out, width=2400, height=700, camera="front", lod="low",
        force=True,
    )  # fmt: skip
    print(f"wrote {args.out}: {s}")


if __name__ == "__main__":
    main()
