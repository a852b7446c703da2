"""``ionic-usd web``: a static site presenting a temple scene and its paradata.

The site (``index.html``, ``app.js``, ``style.css``, ``data.json``, ``scene.glb``,
``hyp/<id>.glb``, ``vendor/three/``) loads nothing from the internet: three.js (its one
JavaScript dependency, installed from npm: ``npm install three`` — CI runs ``npm ci`` in
``tools/node``) is copied in, and it works from ``python -m http.server``.

* ``scene.glb``: the scene as built (the project's glTF exporter; paradata in ``extras``);
* ``hyp/<id>.glb``: for each hypothesis, only the parts its ``alternative`` changes (found by
  :func:`ionic_usd.usd.web_scene.hypothesis_changes`), exported with it selected; a toggle
  hides the baseline's copies of those parts (per node, or per instance of a GPU-instanced
  mesh) and shows these;
* ``data.json``: hypotheses grouped by the question they answer (the description's
  ``question``: ``frieze-plain`` and ``frieze-garlands`` are alternatives for the frieze, one
  variant set: the panel lets one of them be on at a time; an independent hypothesis is a
  question of its own), with
  description, certainty, sources, evidence class and the parts they change; the part records
  and the EM colour chart. The reliability view recolours each part by its evidence class, read
  from its glTF ``extras``.

Another scene (a city of temples) gets the scene, the reliability view, picking and the
permalink, with no hypothesis toggles; its ``scene.glb`` draws each repeated mesh as one
``EXT_mesh_gpu_instancing`` node (picks map ``instanceId`` to the per-instance ``extras``).

Level of detail (``static/lod.js``): ``data.json``'s ``lodGroups`` names the units the view
switches by (:func:`ionic_usd.usd.web_scene.lod_groups`: a city's temples, else the temple; a
point instancer's instances, such as street columns, are units of their own). The page makes a
far level of each detailed mesh at load (vertex clustering) and, each time the camera moves,
draws in full the units whose far level would be off by more than a pixel, the one the camera
orbits (or walks nearest) first, within a triangle budget (lower on software GL); the rest at
their far level, and nothing outside the view.
"""

from __future__ import annotations

import json
import os
import shutil
import tempfile
from importlib import resources
from pathlib import Path

from ionic_usd.errors import ParameterError

__all__ = ["write_site", "find_three", "question_of"]

THREE_FILES = (
    "build/three.module.js",
    "examples/jsm/loaders/GLTFLoader.js",
    "examples/jsm/utils/BufferGeometryUtils.js",
    "examples/jsm/controls/OrbitControls.js",
    "LICENSE",
)
STATIC = ("index.html", "app.js", "lod.js", "style.css")


def find_three(given: str | os.PathLike | None = None) -> Path:
    """The npm package folder of three.js: ``given``, ``$IONIC_USD_THREE``, ``./node_modules/
    three`` or the project's ``tools/node/node_modules/three``; refused if none holds it."""
    here = Path(__file__).resolve().parents[2] / "tools" / "node" / "node_modules" / "three"
    cands = [given, os.environ.get("IONIC_USD_THREE"), Path("node_modules/three"), here]
    for c in cands:
        if c and all((Path(c) / f).is_file() for f in THREE_FILES):
            return Path(c)
    raise ParameterError(
        "--three",
        str(given or "(not found)"),
        "the folder of the npm package three (npm install three; or set IONIC_USD_THREE)",
    )


def question_of(hid: str, entry: dict | None = None) -> str:
    """The question a hypothesis answers: its listing's ``question`` (the description's;
    ``frieze`` for ``frieze-plain`` and ``frieze-garlands``), else its id (independent)."""
    return str((entry or {}).get("question") or hid)


def _record(rec) -> dict:
    return {
        "evidence": str(rec.evidence),
        "certainty": str(rec.certainty),
        "sources": list(rec.sources),
        "description": rec.description,
    }


def _data(pd, changes: dict, base: list[str]) -> dict:
    from ionic_usd.temple.paradata import EM_CHART
    from ionic_usd.usd.paradata_scene import SceneParadata

    pd = pd or SceneParadata()
    hyps = []
    for hid, entry in pd.listing.items():
        vset = entry.get("variantSet") or ""
        value = entry.get("variant") or "alternative"
        key = f"{vset}={value}"
        rec = pd.hypotheses.get(hid, (None, ()))[0]
        hyps.append(
            {
                "id": hid,
                "set": vset,
                "variant": value,
                "question": question_of(hid, entry),
                "description": entry.get("description", ""),
                "certainty": entry.get("certainty", ""),
                "sources": list(entry.get("sources", [])),
                "evidence": str(rec.evidence) if rec else "",
                "changes": changes.get(key, []),
                "glb": f"hyp/{hid}.glb" if changes.get(key) else "",
            }
        )
    return {
        "scene": "scene.glb",
        "hypotheses": hyps,
        "parts": {k: _record(r) for k, r in sorted(pd.parts.items())},
        "prims": dict(sorted(pd.prims.items())),
        "baseParts": base,
        "chart": {str(ev): {"label": e.label, "colour": e.border} for ev, e in EM_CHART.items()},
    }


def write_site(
    scene: str | os.PathLike,
    out: str | os.PathLike,
    *,
    force: bool = False,
    three: str | os.PathLike | None = None,
    lod: str = "low",
) -> str:
    """Write the site into ``out``; returns a one-line report."""
    from ionic_usd.export import export_scene
    from ionic_usd.io import check_output_folder
    from ionic_usd.usd.paradata_scene import read_scene_paradata
    from ionic_usd.usd.web_scene import (
        hypothesis_changes,
        lod_groups,
        part_centres,
        subset_layer,
    )

    src = Path(scene)
    if not src.is_file():
        raise ParameterError("SCENE", str(scene), "an existing USD file")
    three_dir = find_three(three)
    dest = check_output_folder(out, force=force)
    try:
        pd = read_scene_paradata(src)
    except ParameterError:  # not a temple (a city of temples): its parts' extras only
        pd = None
    changes, base = hypothesis_changes(src, {"lod": lod})
    dest.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=".site-", dir=dest.parent))
    tmp.chmod(0o755)  # served as it is
    try:
        # a city: its repeated meshes drawn as EXT_mesh_gpu_instancing nodes (three.js
        # InstancedMesh): 168 draw calls instead of 2,467, and no stalls (docs/paradata.md)
        export_scene(src, tmp / "scene.glb", variants={"lod": lod}, gpu_instancing=pd is None)
        (tmp / "hyp").mkdir()
        data = _data(pd, changes, base)
        data["centres"] = part_centres(src, {"lod": lod})
        data["lodGroups"] = lod_groups(src)
        for h in data["hypotheses"]:
            if not h["glb"]:
                continue
            layer = subset_layer(
                src, tmp / "subset.usda", {"lod": lod, h["set"]: h["variant"]}, h["changes"]
            )
            export_scene(layer, tmp / h["glb"])
            layer.unlink()
        (tmp / "data.json").write_text(json.dumps(data, indent=1, sort_keys=True))
        for f in THREE_FILES:
            (tmp / "vendor" / "three" / f).parent.mkdir(parents=True, exist_ok=True)
            shutil.copyfile(three_dir / f, tmp / "vendor" / "three" / f)
        static = resources.files("ionic_usd") / "web" / "static"
        for name in STATIC:
            (tmp / name).write_bytes((static / name).read_bytes())
        if dest.exists():
            shutil.rmtree(dest)
        tmp.rename(dest)
    finally:
        if tmp.exists():
            shutil.rmtree(tmp)
    size = sum(p.stat().st_size for p in dest.rglob("*") if p.is_file())
    n = sum(1 for h in data["hypotheses"] if h["glb"])
    return (
        f"wrote {dest}/index.html: the scene, {n} hypothesis toggles, {len(data['parts'])} "
        f"parts ({size / 1e6:.1f} MB); serve it with: python -m http.server -d {dest}"
    )
