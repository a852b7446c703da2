"""Import a USD file written by ionic_usd into Blender (headless) and report what came across.

Blender as a Python module (``bpy==5.0.1``, Python 3.11) pins its own numpy, so it lives in a
separate virtual environment. Run from the project's environment::

    python tools/blender_check.py IonicColumn/IonicColumn.usda          # the column asset
    python tools/blender_check.py PortunusTemple/Temple.usda --instances 18 --prototypes 3

The driver reads the composed stage with pxr (variant selections, expected meshes), then runs
this same file inside the Blender environment (``--blender-python``, ``$IONIC_USD_BPY_PYTHON``,
or ``.venv-bpy`` made with ``--setup``), which imports the file with ``bpy.ops.wm.usd_import``
and reports objects, UV layers, materials and images as JSON. The check fails (exit 1) when a
mesh arrives without its ``st`` UV layer or a material, when a material has no texture image,
when the number of imported meshes differs from the active meshes of the stage (untyped parents
would drop them), or when instancing did not survive (more mesh datablocks than prototypes'
meshes, or a different instance count than ``--instances``).
"""

from __future__ import annotations

import argparse
import json
import os
import re
import subprocess
import sys
import venv
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
DEFAULT_VENV = ROOT / ".venv-bpy"


def inside_blender(path: str) -> dict:
    import bpy

    bpy.ops.wm.read_factory_settings(use_empty=True)
    result = bpy.ops.wm.usd_import(
        filepath=path, support_scene_instancing=True, import_usd_preview=True
    )
    objects = []
    for o in bpy.data.objects:
        entry = {"name": o.name, "type": o.type, "parent": o.parent.name if o.parent else None}
        if o.type == "MESH":
            entry["uv_layers"] = [u.name for u in o.data.uv_layers]
            entry["materials"] = [s.material.name for s in o.material_slots if s.material]
            entry["mesh"] = o.data.name
            entry["polygons"] = len(o.data.polygons)
        if o.instance_type == "COLLECTION" and o.instance_collection:
            entry["instance_of"] = o.instance_collection.name
        objects.append(entry)
    materials = {}
    for m in bpy.data.materials:
        images = []
        if m.node_tree:
            images = [
                n.image.name
                for n in m.node_tree.nodes
                if n.type == "TEX_IMAGE" and n.image is not None
            ]
        materials[m.name] = images
    return {
        "result": sorted(result),
        "blender": bpy.app.version_string,
        "objects": objects,
        "materials": materials,
        "meshes": len(bpy.data.meshes),
        "images": [i.name for i in bpy.data.images],
        # Blender reads every array primvar as a generic attribute: a primvars:normals
        # arrives both as the custom normals and as a 'normals' attribute
        "normals_attribute": sorted(
            me.name for me in bpy.data.meshes if "normals" in me.attributes
        ),
    }


def stage_facts(path: str) -> dict:
    from pxr import Usd, UsdGeom

    stage = Usd.Stage.Open(path)
    root = stage.GetDefaultPrim()
    selections = dict(root.GetVariantSets().GetAllVariantSelections())

    def drawn(p) -> bool:
        # Blender imports render and default purpose (not proxy, guide), and not what a detail
        # or hypothesis hides (visibility invisible: the prim keeps its path)
        img = UsdGeom.Imageable(p)
        return (
            p.IsA(UsdGeom.Mesh)
            and img.ComputePurpose() in (UsdGeom.Tokens.default_, UsdGeom.Tokens.render)
            and img.ComputeVisibility() != UsdGeom.Tokens.invisible
        )

    active = [p for p in stage.Traverse() if drawn(p)]
    proto_meshes = sum(1 for pr in stage.GetPrototypes() for p in Usd.PrimRange(pr) if drawn(p))
    # Blender makes one collection-instance object per instance, nested ones included (an
    # instance inside a prototype — a column of an instanced temple — is an object of that
    # prototype's collection), so count the instances inside every prototype too
    instances = sum(1 for p in stage.Traverse() if p.IsInstance())
    instances += sum(
        1 for pr in stage.GetPrototypes() for p in Usd.PrimRange(pr) if p != pr and p.IsInstance()
    )
    return {
        "variant_selections": selections,
        "active_meshes": len(active),
        "prototype_meshes": proto_meshes,
        "instances": instances,
        "prototypes": len(stage.GetPrototypes()),
    }


def blender_python(args) -> str:
    if args.blender_python:
        return args.blender_python
    if os.environ.get("IONIC_USD_BPY_PYTHON"):
        return os.environ["IONIC_USD_BPY_PYTHON"]
    py = DEFAULT_VENV / "bin" / "python"
    if not py.exists():
        if not args.setup:
            sys.exit(
                f"no Blender Python: run with --setup to create {DEFAULT_VENV} "
                "(pip install bpy==5.0.1), or pass --blender-python"
            )
        venv.create(DEFAULT_VENV, with_pip=True)
        subprocess.run([str(py), "-m", "pip", "install", "-q", "bpy==5.0.1"], check=True)
    return str(py)


def main() -> int:
    ap = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    ap.add_argument("usd")
    ap.add_argument("--inside", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--blender-python", help="python of a venv with bpy==5.0.1")
    ap.add_argument("--setup", action="store_true", help="create .venv-bpy if missing")
    ap.add_argument("--instances", type=int, help="expected collection instances")
    ap.add_argument("--prototypes", type=int, help="expected instanced prototypes")
    ap.add_argument("--json", help="write the full report here")
    ap.add_argument(
        "--no-duplicate-normals",
        action="store_true",
        help="fail when a mesh arrives with a 'normals' attribute beside its custom normals",
    )
    args = ap.parse_args()
    path = str(Path(args.usd).resolve())
    if args.inside:
        print(json.dumps(inside_blender(path)))
        return 0

    facts = stage_facts(path)
    out = subprocess.run(
        [blender_python(args), __file__, path, "--inside"], capture_output=True, text=True
    )
    line = next((x for x in reversed(out.stdout.splitlines()) if x.startswith("{")), None)
    if out.returncode != 0 or line is None:
        print(out.stdout[-2000:], out.stderr[-2000:], sep="\n")
        print("FAIL: Blender could not import the file")
        return 1
    rep = json.loads(line)
    meshes = [o for o in rep["objects"] if o["type"] == "MESH"]
    inst = [o for o in rep["objects"] if "instance_of" in o]
    problems = []
    if "FINISHED" not in rep["result"]:
        problems.append(f"import result {rep['result']}")
    for m in meshes:
        if "st" not in m["uv_layers"]:
            problems.append(f"{m['name']}: no 'st' UV layer")
        if not m["materials"]:
            problems.append(f"{m['name']}: no material")
    for name, images in rep["materials"].items():
        if not images:
            problems.append(f"material {name}: no texture image")
    dup = [i for i in rep["images"] if re.search(r"\.\d{3}$", i)]
    if dup:
        problems.append(f"texture maps loaded more than once: {', '.join(dup)}")
    expected_meshes = facts["active_meshes"] + facts["prototype_meshes"]
    if len(meshes) != expected_meshes:
        problems.append(f"{len(meshes)} mesh objects, the stage has {expected_meshes} active")
    if facts["instances"]:
        protos = len({o["instance_of"] for o in inst})
        if len(inst) != facts["instances"]:
            problems.append(f"{len(inst)} instances arrived, the stage has {facts['instances']}")
        if rep["meshes"] > expected_meshes:
            problems.append("instanced meshes were copied, not shared")
        if args.prototypes is not None and protos != args.prototypes:
            problems.append(f"{protos} prototypes, expected {args.prototypes}")
    dn = rep["normals_attribute"]
    if args.no_duplicate_normals and dn:
        problems.append(f"{len(dn)} meshes with a 'normals' attribute beside custom_normal")
    if args.instances is not None and len(inst) != args.instances:
        problems.append(f"{len(inst)} instances, expected {args.instances}")

    print(f"Blender {rep['blender']} imported {Path(path).name}")
    print(f"  variant selections: {facts['variant_selections']}")
    print(
        f"  objects: {len(rep['objects'])} ({len(meshes)} meshes, {len(inst)} collection "
        f"instances of {len({o['instance_of'] for o in inst})} prototypes); mesh datablocks: "
        f"{rep['meshes']}"
    )
    for m in meshes:
        print(
            f"    {m['name']:<40} polygons {m['polygons']:>6}  uv {m['uv_layers']}  "
            f"materials {m['materials']}"
        )
    mats = ", ".join(f"{k} ({len(v)} images)" for k, v in rep["materials"].items())
    print(f"  materials: {mats}")
    print(
        f"  mesh datablocks with a 'normals' attribute beside custom_normal (primvars:normals "
        f"read twice): {len(dn)} of {rep['meshes']}"
    )
    if args.json:
        Path(args.json).write_text(json.dumps({"stage": facts, "blender": rep}, indent=1))
    if problems:
        print("FAIL:")
        for p in problems:
            print(f"  - {p}")
        return 1
    print("OK: every mesh has its st UV layer, a material with textures; instancing kept")
    return 0


if __name__ == "__main__":
    sys.exit(main())
