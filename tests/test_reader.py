"""The one scene reader: primvars (indexed or not), instancing, variants, paradata."""

from __future__ import annotations

import numpy as np
import pytest
from numpy.testing import assert_allclose
from pxr import Gf, Sdf, Usd, UsdGeom, UsdShade, Vt

from ionic_usd.errors import ParameterError
from ionic_usd.usd.reader import parse_variant_args, read_scene

QUAD_PTS = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0)]
QUAD_ST = np.array([(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)])


def _quad_stage(path, st_mode: str, *, up="Y", mpu=1.0):
    stage = Usd.Stage.CreateNew(str(path))
    UsdGeom.SetStageUpAxis(stage, up)
    UsdGeom.SetStageMetersPerUnit(stage, mpu)
    root = UsdGeom.Xform.Define(stage, "/R")
    stage.SetDefaultPrim(root.GetPrim())
    root.GetPrim().SetCustomDataByKey("ionic_usd:note", "root paradata")
    m = UsdGeom.Mesh.Define(stage, "/R/Q")
    m.CreatePointsAttr(Vt.Vec3fArray([Gf.Vec3f(*p) for p in QUAD_PTS]))
    m.CreateFaceVertexCountsAttr([4])
    m.CreateFaceVertexIndicesAttr([0, 1, 2, 3])
    pv = UsdGeom.PrimvarsAPI(m).CreatePrimvar("st", Sdf.ValueTypeNames.TexCoord2fArray)
    if st_mode == "faceVarying":
        pv.SetInterpolation("faceVarying")
        pv.Set(Vt.Vec2fArray([Gf.Vec2f(*s) for s in QUAD_ST]))
    elif st_mode == "indexed":
        pv.SetInterpolation("faceVarying")
        pv.Set(Vt.Vec2fArray([Gf.Vec2f(*s) for s in QUAD_ST[::-1]]))
        pv.SetIndices(Vt.IntArray([3, 2, 1, 0]))
    else:  # vertex
        pv.SetInterpolation("vertex")
        pv.Set(Vt.Vec2fArray([Gf.Vec2f(*s) for s in QUAD_ST]))
    m.GetPrim().CreateAttribute("userProperties:source", Sdf.ValueTypeNames.String).Set("hand")
    stage.Save()
    return path


def usd_mesh_copies(stage: Usd.Stage) -> list[int]:
    """For every mesh of every native prototype: how many instances draw it."""
    out = []
    for proto in stage.GetPrototypes():
        n = len(proto.GetInstances())
        out += [n] * sum(1 for p in Usd.PrimRange(proto) if p.IsA(UsdGeom.Mesh))
    return out


@pytest.mark.parametrize("mode", ["faceVarying", "indexed", "vertex"])
def test_st_per_corner_whatever_the_primvar_layout(tmp_path, mode):
    scene = read_scene(_quad_stage(tmp_path / "q.usda", mode))
    (mesh,) = scene.meshes.values()
    assert_allclose(mesh.st, QUAD_ST)
    assert mesh.paradata == {} and scene.placements[0].paradata == {
        "userProperties": {"source": "hand"}
    }
    assert scene.paradata["ionic_usd"]["note"] == "root paradata"  # key path: nested


def test_z_up_centimetres_become_y_up_metres(tmp_path):
    scene = read_scene(_quad_stage(tmp_path / "q.usda", "vertex", up="Z", mpu=0.01))
    (p,) = scene.placements
    world = np.c_[scene.meshes[p.mesh].points, np.ones(4)] @ p.matrix
    # (x, y, z) cm, Z up -> (x, z, -y) m, Y up
    expect = np.array([(x, z, -y) for x, y, z in QUAD_PTS]) * 0.01
    assert_allclose(world[:, :3], expect, atol=1e-12)


def test_point_instancer_and_equal_prims_share_one_mesh(tmp_path):
    path = tmp_path / "pi.usda"
    stage = Usd.Stage.CreateNew(str(path))
    UsdGeom.SetStageUpAxis(stage, "Y")
    UsdGeom.SetStageMetersPerUnit(stage, 1.0)  # the fallback is centimetres
    stage.SetDefaultPrim(UsdGeom.Xform.Define(stage, "/W").GetPrim())
    pi = UsdGeom.PointInstancer.Define(stage, "/W/PI")
    proto = UsdGeom.Mesh.Define(stage, "/W/PI/Protos/Tri")
    proto.CreatePointsAttr([(0, 0, 0), (1, 0, 0), (0, 1, 0)])
    proto.CreateFaceVertexCountsAttr([3])
    proto.CreateFaceVertexIndicesAttr([0, 1, 2])
    UsdGeom.Xformable(proto).AddTranslateOp().Set((0, 0, 5))  # the prototype's own xform
    pi.CreatePrototypesRel().SetTargets([proto.GetPath()])
    pos = [(10, 0, 0), (20, 0, 0), (30, 0, 0)]
    pi.CreatePositionsAttr(pos)
    pi.CreateProtoIndicesAttr([0, 0, 0])
    copy = UsdGeom.Mesh.Define(stage, "/W/Copy")  # the same triangle authored again
    for name in ("points", "faceVertexCounts", "faceVertexIndices"):
        copy.GetPrim().CreateAttribute(name, proto.GetPrim().GetAttribute(name).GetTypeName()).Set(
            proto.GetPrim().GetAttribute(name).Get()
        )
    UsdGeom.Xformable(copy).AddTranslateOp().Set((-1, 0, 0))
    stage.Save()
    scene = read_scene(path)
    assert len(scene.meshes) == 1
    # the source is the prototype prim, so every placement (3 instances + the copy) is a reuse
    assert sum(p.instanced for p in scene.placements) == 4
    origins = sorted(tuple(p.matrix[3, :3]) for p in scene.placements)
    assert_allclose(origins, [(-1, 0, 0)] + [(x, 0, 5) for x, _, _ in pos])


def test_temple_placements_and_triangles_match_the_composer(tiny_temple):
    scene = read_scene(tiny_temple.root)
    # the composer counts triangles on the composed stage its own way
    assert scene.n_triangles == tiny_temple.triangles
    counts = {}
    for p in scene.placements:
        counts[p.mesh] = counts.get(p.mesh, 0) + 1
    colonnade = {p.mesh for p in scene.placements if p.path.startswith("/Temple/Colonnade/")}
    column_meshes = [k for k, n in counts.items() if n > 1 and k in colonnade]
    # 3 parts of the corner column (4 copies), the free one (6) and the engaged one (8); the
    # other repeated meshes are the detail's PointInstancer prototypes (dentils, tiles)
    assert sorted(counts[k] for k in column_meshes) == [4] * 3 + [6] * 3 + [8] * 3
    assert scene.paradata["ionic_usd"]["temple"] == "Temple of Portunus"
    instance_paths = {p.path for p in scene.placements if p.instanced}
    assert "/Temple/Colonnade/Free/front_1" in instance_paths


def test_variant_selection_reaches_nested_instances(tiny_city):
    base = read_scene(tiny_city)
    engaged = read_scene(tiny_city, variants={"form": "engaged"})

    # the column parts keep their names (stable prim paths); the engaged selection swaps
    # their content: cut by the wall plane 5 cm behind the axis (z >= -0.05 in the part's
    # frame), where the full column reaches -r
    def column_parts(scene):
        parts = [m for m in scene.meshes.values() if m.name in ("Shaft", "Base", "CapitalBody")]
        assert {m.name for m in parts} == {"Shaft", "Base", "CapitalBody"}
        return parts

    assert all(m.points[:, 2].min() >= -0.05 - 1e-6 for m in column_parts(engaged))
    assert any(m.points[:, 2].min() < -0.3 for m in column_parts(base))


@pytest.mark.parametrize(
    "sel,needle",
    [({"nope": "x"}, "variant set of the scene"), ({"form": "sideways"}, "one of .*engaged, full")],
)
def test_bad_variant_selection_names_the_valid_ones(tiny_temple, sel, needle):
    with pytest.raises(ParameterError, match=needle):
        read_scene(tiny_temple.root, variants=sel)


def test_parse_variant_args():
    assert parse_variant_args(["lod=low", " form = engaged "]) == {"lod": "low", "form": "engaged"}
    for bad in (["lod"], ["=x"], ["lod="]):
        with pytest.raises(ParameterError):
            parse_variant_args(bad)


def test_city_placements_name_nested_instances_and_instancer_entries(tiny_city):
    scene = read_scene(tiny_city)
    paths = {p.path for p in scene.placements}
    assert "/City/Temples/Temple_a/Colonnade/Free/front_1" in paths  # an instance proxy path
    assert "/City/Porticus[0]" in paths
    stage = Usd.Stage.Open(str(tiny_city))
    prim = stage.GetPrimAtPath("/City/Temples/Temple_d/Colonnade/Engaged/rear_2")
    assert prim and prim.IsInstanceProxy()
    want = np.array(UsdGeom.XformCache().GetLocalToWorldTransform(prim))
    got = [p.matrix for p in scene.placements if p.path == str(prim.GetPath())]
    parts = [p for p in Usd.PrimRange(prim, Usd.TraverseInstanceProxies()) if p.IsA(UsdGeom.Mesh)]
    assert len(got) == len(parts) >= 2  # the column's parts carry no local transforms
    for m in got:
        assert_allclose(m, want, atol=1e-9)


@pytest.mark.parametrize("which", ["temple", "city"])
def test_mesh_sources_are_paths_of_the_scene_not_of_usd_prototypes(tiny_temple, tiny_city, which):
    """A mesh's ``source`` and a material's ``path`` (glTF's ``extras.usdPath``, the solid
    export's messages) name prims of the scene: inside native instances the first instance's
    proxy, never USD's ``/__Prototype_N``, whose numbering changes from one opening of the
    stage to the next (the same temple exported twice gave two GLBs)."""
    path = tiny_temple.root if which == "temple" else tiny_city
    scene = read_scene(path)
    stage = Usd.Stage.Open(str(path))
    sources = [m.source for m in scene.meshes.values()]
    assert not [s for s in sources if "__Prototype" in s]
    for s in sources:
        prim = stage.GetPrimAtPath(s)
        assert prim and prim.IsA(UsdGeom.Mesh), s
    # nested: the city's temples are instances holding column instances and instancers
    proxies = [s for s in sources if stage.GetPrimAtPath(s).IsInstanceProxy()]
    assert proxies
    # materials too (the city's are inside its temple instances)
    materials = [m.path for m in scene.materials.values()]
    assert materials and not [p for p in materials if "__Prototype" in p]
    for p in materials:
        assert stage.GetPrimAtPath(p).IsA(UsdShade.Material), p
    # and the scene read again names every mesh the same way
    again = read_scene(path)
    assert sorted(sources) == sorted(m.source for m in again.meshes.values())


def test_non_finite_transform_is_refused(tmp_path):
    path = _quad_stage(tmp_path / "q.usda", "vertex")
    stage = Usd.Stage.Open(str(path))
    UsdGeom.Xformable(stage.GetPrimAtPath("/R")).AddTranslateOp().Set((float("nan"), 0, 0))
    stage.Save()
    from ionic_usd.errors import GeometryError

    with pytest.raises(GeometryError, match="/R/Q: its transform is not finite"):
        read_scene(path)


@pytest.mark.parametrize(
    "apply, kind, geometry",
    [
        (True, "component", "box"),
        (True, "component", "cross"),
        (False, "component", "box"),
        (True, "", "box"),
    ],
    ids=["box", "cross", "not-applied", "not-a-model"],
)
def test_card_draw_mode_replaces_a_model_by_its_cards(tmp_path, apply, kind, geometry):
    from ionic_usd.usd.draw_mode import author_cards

    path = tmp_path / "c.usda"
    stage = Usd.Stage.CreateNew(str(path))
    UsdGeom.SetStageUpAxis(stage, "Y")
    UsdGeom.SetStageMetersPerUnit(stage, 1.0)
    root = UsdGeom.Xform.Define(stage, "/W")
    stage.SetDefaultPrim(root.GetPrim())
    Usd.ModelAPI(root).SetKind("assembly")
    model = UsdGeom.Xform.Define(stage, "/W/M")
    model.AddTranslateOp().Set((10, 0, 0))
    if kind:
        Usd.ModelAPI(model).SetKind(kind)
    m = UsdGeom.Mesh.Define(stage, "/W/M/Box")  # a 2 x 3 x 4 box of 6 quads
    m.CreatePointsAttr([(x, y, z) for x in (-1, 1) for y in (0, 3) for z in (-2, 2)])
    m.CreateFaceVertexCountsAttr([4] * 6)
    m.CreateFaceVertexIndicesAttr(
        [0, 1, 3, 2, 4, 6, 7, 5, 0, 4, 5, 1, 2, 3, 7, 6, 0, 2, 6, 4, 1, 5, 7, 3]
    )
    (tmp_path / "x.png").write_bytes(b"")  # only XPos: a box's XNeg takes it too
    author_cards(stage.GetRootLayer().GetPrimAtPath("/W/M"), {"XPos": "./x.png"}, geometry=geometry)
    if not apply:
        model.GetPrim().GetAttribute("model:applyDrawMode").Set(False)
    stage.Save()
    scene = read_scene(path, draw_modes=True)
    assert read_scene(path).n_triangles == 12  # exporters read the geometry
    cards = {m.card_face: m for m in scene.meshes.values() if m.card_face}
    if not (apply and kind):
        assert not cards and scene.n_triangles == 12
        return
    # as Hydra: only the axis with a texture is drawn, both its faces (box and cross alike)
    assert sorted(cards) == ["XNeg", "XPos"]
    assert scene.n_triangles == 4 and all(p.path == "/W/M" for p in scene.placements)
    assert_allclose(scene.placements[0].matrix[3, :3], (10, 0, 0))
    xpos = cards["XPos"].points
    assert_allclose(xpos[:, 0], 1.0 if geometry == "box" else 0.0)  # on the bound / centre
    assert_allclose(xpos.min(axis=0)[1:], (0, -2))
    assert_allclose(xpos.max(axis=0)[1:], (3, 2))
    tex = {f: scene.materials[m.material].diffuse_texture for f, m in cards.items()}
    assert tex["XPos"].path.endswith("x.png")
    # XPos: s along +Y (Hydra's convention, see test_preview); XNeg borrows XPos's image with
    # XPos's mapping (seen through; Hydra's flipped s), so s runs along +Y on XNeg too
    assert tex["XNeg"].path == tex["XPos"].path
    for face in ("XPos", "XNeg"):
        assert_allclose(cards[face].st[:, 0], cards[face].points[:, 1] / 3)
        assert_allclose(cards[face].st[:, 1], (cards[face].points[:, 2] + 2) / 4)
    # every quad is counter-clockwise seen from the side it shows
    for face, mesh in cards.items():
        p = mesh.points
        normal = np.cross(p[1] - p[0], p[2] - p[0])
        axis = {"X": 0, "Y": 1, "Z": 2}[face[0]]
        assert np.sign(normal[axis]) == (1 if face.endswith("Pos") else -1)
