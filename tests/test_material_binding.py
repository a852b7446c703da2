"""One material library per temple, bound once: UsdShade resolves every mesh of a composed
temple (its columns' meshes, read through their instances, and read in their prototypes alone)
to ``/Temple/Materials``, a column's ``finish`` still switches its material, and Blender, which
reads a column's material in its prototype only, makes each material of the library once."""

from __future__ import annotations

import json
import os
import subprocess
from collections import defaultdict

import pytest
from pxr import Sdf, Usd, UsdGeom, UsdShade

from ionic_usd.usd import validate_stage

PROXIES = Usd.TraverseInstanceProxies(Usd.PrimAllPrimsPredicate)
BPY = os.environ.get("IONIC_USD_BPY_PYTHON")


def _bound(root: Usd.Prim) -> dict[Sdf.Path, Sdf.Path]:
    """Every Mesh and PointInstancer under ``root`` (through instances) → its bound material."""
    out = {}
    for p in Usd.PrimRange(root, PROXIES):
        if p.IsActive() and (p.IsA(UsdGeom.Mesh) or p.IsA(UsdGeom.PointInstancer)):
            mat, _ = UsdShade.MaterialBindingAPI(p).ComputeBoundMaterial()
            assert mat, f"{p.GetPath()}: no bound material"
            out[p.GetPath()] = mat.GetPath()
    return out


def _prototype_bound(stage: Usd.Stage) -> dict[Sdf.Path, set[Sdf.Path]]:
    """Per prototype, the materials its meshes bind read in the prototype alone (what a client
    that ignores an instance root's binding, such as Blender's importer, sees)."""
    out = {proto.GetPath(): set(_bound(proto).values()) for proto in stage.GetPrototypes()}
    return {p: used for p, used in out.items() if used}


def _check_one_library(root: Usd.Prim, library: Sdf.Path) -> dict[Sdf.Path, Sdf.Path]:
    bound = _bound(root)
    assert bound
    outside = {m: p for m, p in bound.items() if not p.HasPrefix(library)}
    assert not outside, f"bound outside {library}: {sorted(set(outside.values()))[:4]}"
    # one prim per material: no two bound materials share a name (a client that makes a
    # material per bound prim makes each once)
    used = set(bound.values())
    assert len(used) == len({p.name for p in used}), sorted(used)
    return bound


def test_every_mesh_of_the_temple_binds_into_its_one_library(portunus_temple):
    stage = Usd.Stage.Open(str(portunus_temple.root))
    bound = _check_one_library(stage.GetPseudoRoot(), Sdf.Path("/Temple/Materials"))
    columns = {m: p for m, p in bound.items() if m.HasPrefix("/Temple/Colonnade")}
    assert len({m.GetPrefixes()[3] for m in columns}) == 18  # every column's meshes
    assert set(columns.values()) == {Sdf.Path("/Temple/Materials/PaintedStucco")}
    assert {p.name for p in bound.values()} == {"PaintedStucco", "Travertine", "Terracotta"}
    # every Material of the composed stage is the temple library's, or one of the column
    # asset's own (inside an instance: what a reader of the prototype alone binds), which
    # UsdShade resolves nothing to
    for p in Usd.PrimRange(stage.GetPseudoRoot(), PROXIES):
        if p.IsA(UsdShade.Material) and not p.GetPath().HasPrefix("/Temple/Materials"):
            assert p.IsInstanceProxy() and p.GetPath().HasPrefix("/Temple/Colonnade"), p
            assert p.GetPath() not in bound.values()
    assert len(stage.GetPrototypes()) == 3  # the bindings left the columns' sharing alone
    # read alone, each column prototype binds the library too (the class's opinions on the
    # asset's Geom and Proxy are part of it), not the asset's copy inside the instance
    protos = _prototype_bound(stage)
    assert len(protos) == 3
    assert set().union(*protos.values()) == {Sdf.Path("/Temple/Materials/PaintedStucco")}
    assert validate_stage(stage) == []


def test_the_finish_switches_the_columns_material_in_the_library(portunus_temple):
    stage = Usd.Stage.Open(str(portunus_temple.root))
    stage.SetEditTarget(stage.GetSessionLayer())
    temple = stage.GetDefaultPrim()
    # the finish hypothesis: every column (and part) travertine
    temple.GetVariantSet("hyp_finish_bare_stone").SetVariantSelection("alternative")
    bound = _check_one_library(stage.GetPseudoRoot(), Sdf.Path("/Temple/Materials"))
    assert {p.name for m, p in bound.items() if m.HasPrefix("/Temple/Colonnade")} == {"Travertine"}
    protos = _prototype_bound(stage)  # the prototypes, read alone, switch too
    assert len(protos) == 3
    assert set().union(*protos.values()) == {Sdf.Path("/Temple/Materials/Travertine")}
    stage.GetSessionLayer().Clear()
    # a user's selection on one column: that column only
    one = stage.GetPrimAtPath("/Temple/Colonnade/Free/front_1")
    one.GetVariantSet("finish").SetVariantSelection("travertine")
    per_column = defaultdict(set)
    for m, p in _check_one_library(stage.GetPseudoRoot(), Sdf.Path("/Temple/Materials")).items():
        if m.HasPrefix("/Temple/Colonnade"):
            per_column[m.GetPrefixes()[3].name].add(p.name)
    assert per_column.pop("front_1") == {"Travertine"}
    assert set().union(*per_column.values()) == {"PaintedStucco"}
    # its own prototype (a selection is an arc: a fourth one) binds Travertine in itself
    others = {p.GetPrototype() for p in stage.Traverse() if p.IsInstance() and p != one}
    assert len(others) == 3 and one.GetPrototype() not in others
    protos = _prototype_bound(stage)
    assert len(protos) == 4
    assert protos[one.GetPrototype().GetPath()] == {Sdf.Path("/Temple/Materials/Travertine")}


def test_the_reliability_view_still_wins_over_the_columns_binding(portunus_temple):
    stage = Usd.Stage.Open(str(portunus_temple.root))
    stage.GetDefaultPrim().GetVariantSet("view").SetVariantSelection("reliability")
    bound = _bound(stage.GetPseudoRoot())
    cols = {p for m, p in bound.items() if m.HasPrefix("/Temple/Colonnade")}
    assert cols and all(p.HasPrefix("/Temple/Materials/EM") for p in cols), cols


def test_the_column_asset_alone_keeps_its_own_library(portunus_temple):
    asset = portunus_temple.root.parent / "IonicColumn" / "IonicColumn.usda"
    stage = Usd.Stage.Open(str(asset))
    root = stage.GetDefaultPrim()
    for finish, name in (("stucco", "PaintedStucco"), ("travertine", "Travertine")):
        root.GetVariantSet("finish").SetVariantSelection(finish)
        bound = _check_one_library(root, Sdf.Path("/IonicColumn/Materials"))
        assert {p.name for p in bound.values()} == {name}


@pytest.mark.parametrize("temple", ["Temple_a", "Temple_b", "Temple_c", "Temple_d"])
def test_every_temple_of_a_city_binds_into_its_own_library(tiny_city, temple):
    stage = Usd.Stage.Open(str(tiny_city))
    roots = [p for p in stage.Traverse() if p.GetName() == temple]
    assert len(roots) == 1
    bound = _check_one_library(roots[0], roots[0].GetPath().AppendChild("Materials"))
    colonnade = roots[0].GetPath().AppendChild("Colonnade")
    columns = {p for m, p in bound.items() if m.HasPrefix(colonnade)}
    assert columns == {roots[0].GetPath().AppendPath(Sdf.Path("Materials/PaintedStucco"))}


def test_a_citys_column_prototypes_bind_a_temples_library(tiny_city):
    # the temples of one build share their column prototypes: read alone, a prototype binds
    # the library of the temple it was composed from, one temple's of this build (not the
    # asset's copy in the prototype)
    stage = Usd.Stage.Open(str(tiny_city))
    temples = [p for p in stage.Traverse() if p.GetName().startswith("Temple_")]
    libraries = {p.GetPath().AppendChild("Materials") for p in temples}
    assert len(libraries) == 4
    columns = [
        proto
        for proto in stage.GetPrototypes()
        if proto.GetChild("Geom")
        and any("/Colonnade/" in str(i.GetPath()) for i in proto.GetInstances())
    ]
    assert columns
    for proto in columns:
        used = set(_bound(proto).values())
        assert len({m.GetParentPath() for m in used}) == 1, (proto, used)
        assert used.pop().GetParentPath() in libraries, proto


BLENDER_MATERIALS = r"""
import json, sys
import bpy
bpy.ops.wm.read_factory_settings(use_empty=True)
bpy.ops.wm.usd_import(filepath=sys.argv[-1], support_scene_instancing=True,
                      import_usd_preview=True)
used = sorted({s.material.name for o in bpy.data.objects if o.type == "MESH"
               for s in o.material_slots if s.material})
print("RESULT" + json.dumps({"materials": sorted(m.name for m in bpy.data.materials),
                             "used": used}))
"""


@pytest.mark.slow
@pytest.mark.skipif(not BPY, reason="IONIC_USD_BPY_PYTHON is not set (a venv with bpy==5.0.1)")
def test_blender_makes_the_temples_library_once(portunus_temple, tmp_path):
    script = tmp_path / "materials.py"
    script.write_text(BLENDER_MATERIALS)
    proc = subprocess.run(
        [BPY, str(script), str(portunus_temple.root)], capture_output=True, text=True, timeout=600
    )
    assert proc.returncode == 0, proc.stderr[-2000:]
    line = next(x for x in proc.stdout.splitlines() if x.startswith("RESULT"))
    rep = json.loads(line[len("RESULT") :])
    # before the columns' prototypes bound the library: 6 (PaintedStucco .001-.003, one per
    # column prototype, from the asset's copy)
    assert rep["materials"] == ["PaintedStucco", "Terracotta", "Travertine"]
    assert rep["used"] == rep["materials"]
