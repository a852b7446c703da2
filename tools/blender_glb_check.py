"""Import a .glb written by ``ionic-usd export`` into Blender (headless) and check what arrived.

Blender as a Python module (``bpy==5.0.1``) lives in its own environment; this driver re-runs
itself there (``--blender-python``, ``$IONIC_USD_BPY_PYTHON``, else ``/work/venv-bpy`` or
``.venv-bpy``)::

    python tools/blender_glb_check.py temple.glb [--triangles 472236]

Inside Blender it runs ``bpy.ops.import_scene.gltf`` and reports, as one JSON line: mesh
objects, mesh datablocks (shared meshes stay shared: fewer datablocks than objects means the
instancing survived), triangles over all objects, materials and the images their node trees
use, and the scene's custom properties (the glTF ``extras`` paradata). It fails (exit 1) when
the import does not finish, nothing arrives, a material has no image texture, the scene's
paradata is missing, or ``--triangles`` differs from the triangles Blender holds.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def inside_blender(path: str) -> dict:
    import bpy

    bpy.ops.wm.read_factory_settings(use_empty=True)
    result = bpy.ops.import_scene.gltf(filepath=path)
    dg = bpy.context.evaluated_depsgraph_get()
    tris = 0
    objects = 0
    for inst in dg.object_instances:  # GPU instances arrive as instances of shared meshes
        ob = inst.object
        if ob.type != "MESH":
            continue
        objects += 1
        tris += sum(len(p.vertices) - 2 for p in ob.data.polygons)
    materials = {}
    for m in bpy.data.materials:
        if m.users == 0 or not m.node_tree:
            continue
        materials[m.name] = sorted(
            n.image.name for n in m.node_tree.nodes if n.type == "TEX_IMAGE" and n.image is not None
        )
    scene_props = {k: str(type(bpy.context.scene[k]).__name__) for k in bpy.context.scene.keys()}
    return {
        "result": sorted(result),
        "blender": bpy.app.version_string,
        "mesh_objects": sum(1 for o in bpy.data.objects if o.type == "MESH"),
        "drawn_objects": objects,
        "mesh_datablocks": len(bpy.data.meshes),
        "triangles": tris,
        "materials": materials,
        "scene_properties": scene_props,
    }


def _bpy_python(given: str | None) -> str:
    for c in (
        given,
        os.environ.get("IONIC_USD_BPY_PYTHON"),
        "/work/venv-bpy/bin/python",
        str(ROOT / ".venv-bpy" / "bin" / "python"),
    ):
        if c and Path(c).is_file():
            return c
    sys.exit(
        "blender_glb_check: no Python with bpy (give --blender-python or set IONIC_USD_BPY_PYTHON)"
    )


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("glb", type=Path)
    ap.add_argument("--triangles", type=int, help="triangles the scene must hold")
    ap.add_argument("--blender-python")
    ap.add_argument("--inside", action="store_true", help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.inside:
        print("RESULT " + json.dumps(inside_blender(str(a.glb.resolve()))))
        return 0
    run = subprocess.run(
        [_bpy_python(a.blender_python), __file__, "--inside", str(a.glb)],
        capture_output=True,
        text=True,
        timeout=900,
    )
    line = next((x for x in run.stdout.splitlines() if x.startswith("RESULT ")), None)
    if run.returncode != 0 or line is None:
        print(f"Blender: import of {a.glb} FAILED\n{run.stdout[-2000:]}\n{run.stderr[-2000:]}")
        return 1
    r = json.loads(line[7:])
    problems = []
    if r["result"] != ["FINISHED"]:
        problems.append(f"import returned {r['result']}")
    if r["drawn_objects"] == 0:
        problems.append("no mesh arrived")
    problems += [
        f"material {m} has no image texture" for m, imgs in r["materials"].items() if not imgs
    ]
    if not r["scene_properties"]:
        problems.append("the scene's paradata (glTF extras) did not arrive")
    if a.triangles is not None and r["triangles"] != a.triangles:
        problems.append(f"{r['triangles']} triangles, expected {a.triangles}")
    print(
        f"Blender {r['blender']} import_scene.gltf: {a.glb}: {r['drawn_objects']} mesh "
        f"objects drawn from {r['mesh_datablocks']} meshes, {r['triangles']} triangles, "
        f"{len(r['materials'])} materials with "
        f"{sum(len(v) for v in r['materials'].values())} image textures, scene properties "
        f"{sorted(r['scene_properties'])}: {'OK' if not problems else 'FAILED'}"
    )
    for p in problems:
        print(f"  {p}")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
