"""Export: glTF/GLB content (meshes, instancing, textures, paradata), usdz, STL/3MF solids, CLI."""

from __future__ import annotations

import json
import math
import zipfile
from xml.etree import ElementTree

import numpy as np
import pygltflib
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from numpy.testing import assert_allclose
from pxr import Gf, Sdf, Usd, UsdGeom

from ionic_usd.cli import main
from ionic_usd.export import export_scene
from ionic_usd.export.gltf import texture_transform, trs_decompose
from ionic_usd.export.solid import check_solid, read_stl
from ionic_usd.usd import validate_stage
from ionic_usd.usd.column_asset import TILE_METRES, UV_SPAN
from ionic_usd.usd.reader import TextureRef, read_scene


def usd_mesh_copies(stage: Usd.Stage) -> list[int]:
    """For every mesh of every native prototype: how many instances draw it."""
    out = []
    for proto in stage.GetPrototypes():
        n = len(proto.GetInstances())
        out += [n] * sum(1 for p in Usd.PrimRange(proto) if p.IsA(UsdGeom.Mesh))
    return out


def _accessor(g: pygltflib.GLTF2, i: int) -> np.ndarray:
    acc = g.accessors[i]
    bv = g.bufferViews[acc.bufferView]
    blob = g.binary_blob()
    dtype = {5126: np.float32, 5123: np.uint16, 5125: np.uint32}[acc.componentType]
    width = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4}[acc.type]
    a = np.frombuffer(blob, dtype, acc.count * width, bv.byteOffset + (acc.byteOffset or 0))
    return a.reshape(acc.count, width) if width > 1 else a


def _image_pixels(g: pygltflib.GLTF2, i: int, tmp_path) -> np.ndarray:
    import OpenImageIO as oiio

    img = g.images[i]
    bv = g.bufferViews[img.bufferView]
    data = g.binary_blob()[bv.byteOffset : bv.byteOffset + bv.byteLength]
    assert data[:8] == b"\x89PNG\r\n\x1a\n" and img.mimeType == "image/png"
    f = tmp_path / f"image{i}.png"
    f.write_bytes(data)
    return np.asarray(oiio.ImageBuf(str(f)).get_pixels(oiio.FLOAT))


@pytest.fixture(scope="module")
def temple_glb(tiny_temple, tmp_path_factory):
    out = tmp_path_factory.mktemp("glb") / "temple.glb"
    res = export_scene(tiny_temple.root, out)
    return res, pygltflib.GLTF2().load(str(out)), read_scene(tiny_temple.root)


@pytest.fixture(scope="module")
def temple_gpu_glb(tiny_temple, tmp_path_factory):
    out = tmp_path_factory.mktemp("glb") / "temple_gpu.glb"
    res = export_scene(tiny_temple.root, out, gpu_instancing=True)
    return res, pygltflib.GLTF2().load(str(out)), read_scene(tiny_temple.root)


def _drawn(g: pygltflib.GLTF2) -> tuple[int, int]:
    """(triangles, draw calls) a client without EXT_mesh_gpu_instancing draws: every node
    reachable from the scene draws its mesh once."""
    tris = calls = 0
    todo = list(g.scenes[g.scene].nodes)
    while todo:
        n = g.nodes[todo.pop()]
        todo += n.children or []
        if n.mesh is not None:
            for prim in g.meshes[n.mesh].primitives:
                tris += g.accessors[prim.indices].count // 3
                calls += 1
    return tris, calls


def test_glb_default_needs_no_extension_to_draw_every_copy(temple_glb, tiny_temple):
    """Core glTF only: a client that knows no extension draws every triangle of the temple."""
    res, g, scene = temple_glb
    assert "EXT_mesh_gpu_instancing" not in (g.extensionsUsed or [])
    assert not g.extensionsRequired
    tris, calls = _drawn(g)
    assert tris == res.report.triangles_drawn == tiny_temple.triangles
    assert calls == res.report.draw_calls
    # repeated column parts: one glTF mesh, one node per column that draws it
    stage = Usd.Stage.Open(str(tiny_temple.root))
    uses: dict[int, int] = {}
    for n in g.nodes:
        if n.mesh is not None:
            uses[n.mesh] = uses.get(n.mesh, 0) + 1
    want = sorted(n for n in usd_mesh_copies(stage) if n > 1)
    assert sorted(u for u in uses.values() if u > 1) == want


def test_glb_gpu_instancing_is_required(temple_gpu_glb, tiny_temple):
    res, g, scene = temple_gpu_glb
    assert len(g.meshes) == len(scene.meshes)
    # no fallback exists (a client without it would draw one copy): required, not just used
    assert "EXT_mesh_gpu_instancing" in g.extensionsUsed
    assert "EXT_mesh_gpu_instancing" in g.extensionsRequired
    inst_nodes = [n for n in g.nodes if n.extensions.get("EXT_mesh_gpu_instancing")]
    # one instanced node per mesh of each prototype that several columns share, with as many
    # copies as the prototype has instances (counted on the stage with Usd directly)
    stage = Usd.Stage.Open(str(tiny_temple.root))
    want = sorted(n for n in usd_mesh_copies(stage) if n > 1)
    assert sorted(len(n.extras["instances"]) for n in inst_nodes) == want
    # the instance translations are the columns' USD positions (read with UsdGeom directly)
    xfc = UsdGeom.XformCache()
    for n in inst_nodes:
        attrs = n.extensions["EXT_mesh_gpu_instancing"]["attributes"]
        tr = _accessor(g, attrs["TRANSLATION"])
        q = _accessor(g, attrs["ROTATION"])
        assert_allclose(np.linalg.norm(q, axis=1), 1.0, atol=1e-6)
        for row, inst in zip(tr, n.extras["instances"], strict=True):
            m = xfc.GetLocalToWorldTransform(stage.GetPrimAtPath(inst["path"]))
            assert_allclose(row, np.array(m.ExtractTranslation()), atol=1e-4)
    # triangles drawn: every copy counted, as the composer counts them
    assert res.report.triangles_drawn == tiny_temple.triangles
    assert res.report.draw_calls == len(g.meshes)


def test_glb_materials_textures_and_transform(temple_glb):
    _, g, scene = temple_glb
    assert len(g.images) >= 3
    column_mats = [
        m
        for m in g.materials
        if m.pbrMetallicRoughness.baseColorTexture
        and m.pbrMetallicRoughness.baseColorTexture.extensions
    ]
    assert column_mats, "the column material tiles its maps through KHR_texture_transform"
    for m in g.materials:
        pbr = m.pbrMetallicRoughness
        assert pbr.baseColorTexture is not None and pbr.metallicRoughnessTexture is not None
        assert m.normalTexture is not None
    xf = column_mats[0].pbrMetallicRoughness.baseColorTexture.extensions["KHR_texture_transform"]
    assert_allclose(xf["scale"], [UV_SPAN / TILE_METRES] * 2)
    # every textured primitive has normals, uvs and tangents with unit xyz and w = ±1
    for mesh in g.meshes:
        a = mesh.primitives[0].attributes
        nrm = _accessor(g, a.NORMAL)
        assert_allclose(np.linalg.norm(nrm, axis=1), 1.0, atol=1e-5)
        if mesh.primitives[0].material is not None:
            tan = _accessor(g, a.TANGENT)
            assert_allclose(np.linalg.norm(tan[:, :3], axis=1), 1.0, atol=1e-5)
            assert set(np.unique(tan[:, 3])) <= {-1.0, 1.0}
            assert a.TEXCOORD_0 is not None


def test_glb_paradata_in_extras(temple_gpu_glb):
    _, g, _ = temple_gpu_glb
    extras = g.scenes[0].extras
    hyps = extras["ionic_usd"]["hypotheses"]
    assert "flutes_20" in hyps and hyps["flutes_20"]["certainty"]
    assert extras["variantSelections"]["hyp_flutes_20"] == "baseline"  # as composed
    assert not extras.get("requestedVariants")  # none asked (pygltflib drops empty dicts)
    node = next(n for n in g.nodes if n.extensions.get("EXT_mesh_gpu_instancing"))
    # the column asset's generator parameters are shared by every copy: stored once
    assert "parameters" in node.extras["ionic_usd"]
    # per copy: its path and what differs between columns (the part's unit, e.g. column.front_1)
    assert all(set(i) <= {"path", "paradata", "userProperties"} for i in node.extras["instances"])
    assert all(i["paradata"]["unit"].startswith("column.") for i in node.extras["instances"])
    assert node.extras["paradata"]["evidence"] == "US"  # shared by every column: stored once
    assert json.loads(g.to_json())["scenes"][0]["extras"] == extras  # plain JSON


def test_metallic_roughness_packs_roughness_in_green(temple_glb, tmp_path):
    import OpenImageIO as oiio

    _, g, scene = temple_glb
    mat = next(m for m in scene.materials.values() if m.roughness_texture is not None)
    src = np.asarray(oiio.ImageBuf(mat.roughness_texture.path).get_pixels(oiio.FLOAT))
    src = src[..., 0] if src.ndim == 3 else src
    # prototype paths differ between two openings of a stage: match by name
    gm = next(m for m in g.materials if m.name == mat.name)
    tex = g.textures[gm.pbrMetallicRoughness.metallicRoughnessTexture.index]
    px = _image_pixels(g, tex.source, tmp_path)
    assert_allclose(px[..., 1], src, atol=0.5 / 255)
    assert_allclose(px[..., 2], 1.0)  # metallic factor (0) multiplies a white channel
    assert gm.pbrMetallicRoughness.metallicFactor == 0.0


def test_texcoords_are_flipped_and_plain_nodes_fallback(tmp_path):
    stage = Usd.Stage.CreateNew(str(tmp_path / "q.usda"))
    UsdGeom.SetStageUpAxis(stage, "Y")
    UsdGeom.SetStageMetersPerUnit(stage, 1.0)
    stage.SetDefaultPrim(UsdGeom.Xform.Define(stage, "/R").GetPrim())
    st_in = np.array([(0.0, 0.0), (1.0, 0.0), (1.0, 0.25), (0.0, 0.25)])
    for i in range(3):
        m = UsdGeom.Mesh.Define(stage, f"/R/Q{i}")
        m.CreatePointsAttr([(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0)])
        m.CreateFaceVertexCountsAttr([4])
        m.CreateFaceVertexIndicesAttr([0, 1, 2, 3])
        pv = UsdGeom.PrimvarsAPI(m).CreatePrimvar(
            "st", Sdf.ValueTypeNames.TexCoord2fArray, UsdGeom.Tokens.vertex
        )
        pv.Set([Gf.Vec2f(*s) for s in st_in])
        UsdGeom.Xformable(m).AddTranslateOp().Set((3.0 * i, 0, 0))
    stage.Save()
    out = tmp_path / "q.glb"
    export_scene(tmp_path / "q.usda", out, gpu_instancing=False)
    g = pygltflib.GLTF2().load(str(out))
    assert len(g.meshes) == 1 and not g.extensionsUsed
    mesh_nodes = [n for n in g.nodes if n.mesh is not None]
    assert len(mesh_nodes) == 3 and {n.mesh for n in mesh_nodes} == {0}
    pos = _accessor(g, g.meshes[0].primitives[0].attributes.POSITION)
    uv = _accessor(g, g.meshes[0].primitives[0].attributes.TEXCOORD_0)
    for p, t in zip(pos, uv, strict=True):
        k = int(
            np.argmin(
                np.linalg.norm(np.array([(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0)]) - p, axis=1)
            )
        )
        assert_allclose(t, (st_in[k, 0], 1.0 - st_in[k, 1]))
    xs = sorted(np.array(n.matrix).reshape(4, 4)[3, 0] if n.matrix else 0.0 for n in mesh_nodes)
    assert_allclose(xs, [0.0, 3.0, 6.0])


@settings(max_examples=60, deadline=None)
@given(
    st.floats(0.1, 20),
    st.floats(0.1, 20),
    st.floats(-180, 180),
    st.floats(-3, 3),
    st.floats(-3, 3),
    st.floats(0, 1),
    st.floats(0, 1),
)
def test_texture_transform_samples_the_same_texel(sx, sy, rot, tx, ty, s, t):
    """USD: st' = T + R(θ)·S·st, image row from the top 1 − t'. glTF (KHR_texture_transform
    spec matrix, uv = (s, 1 − t)): uv' = offset + [[c, s], [−s, c]]·S·uv, row from the top v'."""
    tex = TextureRef(
        "x.png", "rgb", "sRGB", st_scale=(sx, sy), st_rotation=rot, st_translation=(tx, ty)
    )
    k = texture_transform(tex)
    th = math.radians(rot)
    usd = np.array([tx, ty]) + np.array(
        [[math.cos(th), -math.sin(th)], [math.sin(th), math.cos(th)]]
    ) @ (np.array([sx, sy]) * [s, t])
    r = k.get("rotation", 0.0)
    kr = np.array([[math.cos(r), math.sin(r)], [-math.sin(r), math.cos(r)]])
    gl = np.array(k.get("offset", [0.0, 0.0])) + kr @ (np.array(k["scale"]) * [s, 1.0 - t])
    assert_allclose(gl, [usd[0], 1.0 - usd[1]], atol=1e-9)


@settings(max_examples=60, deadline=None)
@given(
    st.lists(st.floats(-1, 1), min_size=4, max_size=4).filter(lambda q: np.linalg.norm(q) > 0.1),
    st.lists(st.floats(0.1, 5), min_size=3, max_size=3),
    st.lists(st.floats(-100, 100), min_size=3, max_size=3),
    st.booleans(),
)
def test_trs_decompose_recomposes(q, scale, t, mirror):
    from scipy.spatial.transform import Rotation

    lin = Rotation.from_quat(q).as_matrix() @ np.diag(scale) @ np.diag([-1 if mirror else 1, 1, 1])
    m = np.eye(4)
    m[:3, :3] = lin.T
    m[3, :3] = t
    tr, quat, sc = trs_decompose(m)
    back = np.eye(4)
    back[:3, :3] = (Rotation.from_quat(quat).as_matrix() @ np.diag(sc)).T
    back[3, :3] = tr
    assert_allclose(back, m, atol=1e-9)
    shear = m.copy()  # a sheared frame: its axes are no longer orthogonal
    shear[:3, :3] = (lin @ np.array([[1.0, 0.5, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])).T
    assert trs_decompose(shear) is None


def test_usdz_is_flat_valid_and_self_contained(tiny_temple, tmp_path):
    out = tmp_path / "t.usdz"
    res = export_scene(tiny_temple.root, out, variants={"form": "engaged"})
    assert res.report.variant_sets_left == 0
    assert validate_stage(out) == []
    with zipfile.ZipFile(out) as z:
        names = z.namelist()
    assert names[0].endswith(".usdc")
    assert sum(n.endswith(".png") for n in names) >= 3
    stage = Usd.Stage.Open(str(out))
    assert not any(p.HasVariantSets() for p in stage.Traverse())
    # the shafts (stable name) hold the engaged form: cut 5 cm behind the axis
    shafts = [
        np.array(UsdGeom.Mesh(p).GetPointsAttr().Get())
        for p in Usd.PrimRange.Stage(stage, Usd.TraverseInstanceProxies())
        if p.IsA(UsdGeom.Mesh) and p.GetName() == "Shaft"
    ]
    assert shafts and all(pts[:, 2].min() >= -0.05 - 1e-6 for pts in shafts)
    for prim in Usd.PrimRange.Stage(stage, Usd.TraverseInstanceProxies()):
        f = prim.GetAttribute("inputs:file")
        if f and f.Get() is not None:
            assert "t.usdz[" in f.Get().resolvedPath  # textures resolve inside the package


def _renamed_prototypes(layer: Sdf.Layer, mapping: dict[str, str]) -> None:
    """Root prims renamed (copied: targets inside follow) and internal references re-aimed."""
    for src, dst in mapping.items():
        assert Sdf.CopySpec(layer, Sdf.Path(src), layer, Sdf.Path(dst))
    paths: list[Sdf.Path] = []
    layer.Traverse(Sdf.Path.absoluteRootPath, lambda p: paths.append(p) if p.IsPrimPath() else None)
    for path in paths:
        spec = layer.GetPrimAtPath(path)
        if spec is None or not spec.hasReferences:
            continue
        refs = spec.referenceList
        for kind in ("explicitItems", "prependedItems", "appendedItems"):
            setattr(
                refs,
                kind,
                [
                    Sdf.Reference(
                        r.assetPath, Sdf.Path(mapping.get(str(r.primPath), str(r.primPath)))
                    )
                    for r in getattr(refs, kind)
                ],
            )
    for src in mapping:
        del layer.rootPrims[Sdf.Path(src).name]


@pytest.mark.parametrize("which", ["temple", "city"])
def test_stable_prototypes_do_not_depend_on_usds_numbering(tiny_temple, tiny_city, which):
    """Flatten numbers the prototypes as USD happened to (it changes from one opening to the
    next); renumbered by their first instance, any numbering gives the same layer (the
    city's temples are prototypes holding the columns' prototypes: nested)."""
    from ionic_usd.usd.package import stable_prototypes

    scene = tiny_temple.root if which == "temple" else tiny_city
    flat = Usd.Stage.Open(str(scene)).Flatten()
    names = [f"/{p.name}" for p in flat.rootPrims if p.name.startswith("Flattened_Prototype_")]
    # the temple: the free, engaged and corner columns; the city: its temples' too
    assert len(names) == 3 if which == "temple" else len(names) > 3
    other = Sdf.Layer.CreateAnonymous(".usda")
    other.TransferContent(flat)
    # another numbering: the names rotated, through temporary ones
    n = len(names)
    _renamed_prototypes(other, {p: f"/Tmp{i}" for i, p in enumerate(names)})
    _renamed_prototypes(other, {f"/Tmp{i}": names[(i + 1) % n] for i in range(n)})
    assert other.ExportToString() != flat.ExportToString()
    stable_prototypes(flat)
    stable_prototypes(other)
    assert other.ExportToString() == flat.ExportToString()
    assert validate_stage(Usd.Stage.Open(other)) == []  # every instance finds its prototype


def test_the_packaged_crate_does_not_depend_on_the_order_fields_were_authored(tmp_path):
    """The crate writer keeps each spec's fields in the order they were authored (Flatten
    authors them in an order that changed from one process to another): two layers with the
    same content authored in two orders are different crate bytes, and the same bytes once
    read back through their text."""
    from ionic_usd.usd.package import _canonical

    def layer(first_default: bool) -> Sdf.Layer:
        lay = Sdf.Layer.CreateAnonymous(".usda")
        prim = Sdf.CreatePrimInLayer(lay, "/Column")
        prim.specifier = Sdf.SpecifierDef
        attr = Sdf.AttributeSpec(prim, "primvars:st", Sdf.ValueTypeNames.TexCoord2fArray)
        steps = [
            lambda: setattr(attr, "default", [(0.0, 0.5), (1.0, 0.25)]),
            lambda: attr.SetInfo("interpolation", "vertex"),
        ]
        for step in steps if first_default else steps[::-1]:
            step()
        prim.typeName = "Mesh"
        return lay

    def crate(lay: Sdf.Layer, name: str) -> bytes:
        assert lay.Export(str(tmp_path / name))
        return (tmp_path / name).read_bytes()

    a, b = layer(True), layer(False)
    assert a.ExportToString() == b.ExportToString()
    assert crate(a, "a.usdc") != crate(b, "b.usdc")
    assert crate(_canonical(a), "ca.usdc") == crate(_canonical(b), "cb.usdc")
    assert _canonical(a).ExportToString() == a.ExportToString()


def test_exports_are_the_same_bytes_run_after_run(tiny_temple, tiny_city, tmp_path):
    """glb, usdz and 3mf of one scene, the glb of a city (its materials inside nested
    instances) and the usdz of a copy of the scene in another folder: the same bytes in two
    processes (other time zones), every zip entry stamped with the zip epoch."""
    import os
    import shutil
    import subprocess
    import sys

    moved = tmp_path / "elsewhere" / tiny_temple.root.parent.name
    shutil.copytree(tiny_temple.root.parent, moved, symlinks=True)
    jobs = [(f"t.{ext}", tiny_temple.root) for ext in ("glb", "usdz", "3mf")]
    jobs += [("city.glb", tiny_city), ("moved/t.usdz", moved / tiny_temple.root.name)]
    outs: dict[str, list[bytes]] = {}
    for run, tz in enumerate(("UTC", "Asia/Tokyo")):
        for name, scene in jobs:
            out = tmp_path / f"run{run}" / name
            out.parent.mkdir(parents=True, exist_ok=True)
            cmd = [sys.executable, "-m", "ionic_usd", "export", str(scene), "-o", str(out), "-q"]
            r = subprocess.run(cmd, env={**os.environ, "TZ": tz}, capture_output=True, text=True)
            assert r.returncode == 0, r.stderr
            outs.setdefault(name, []).append(out.read_bytes())
    for name, (a, b) in outs.items():
        assert a == b, name
    # where the scene lies on disk is not in the package
    assert outs["moved/t.usdz"][0] == outs["t.usdz"][0]
    for name in ("t.usdz", "t.3mf"):
        with zipfile.ZipFile(tmp_path / "run1" / name) as z:
            assert {i.date_time for i in z.infolist()} == {(1980, 1, 1, 0, 0, 0)}, name


def _cubes_stage(path, boxes):
    stage = Usd.Stage.CreateNew(str(path))
    UsdGeom.SetStageUpAxis(stage, "Y")
    UsdGeom.SetStageMetersPerUnit(stage, 1.0)
    stage.SetDefaultPrim(UsdGeom.Xform.Define(stage, "/Col").GetPrim())
    for i, (lo, hi) in enumerate(boxes):
        x0, y0, z0 = lo
        x1, y1, z1 = hi
        pts = [
            (x0, y0, z0),
            (x1, y0, z0),
            (x1, y1, z0),
            (x0, y1, z0),
            (x0, y0, z1),
            (x1, y0, z1),
            (x1, y1, z1),
            (x0, y1, z1),
        ]
        m = UsdGeom.Mesh.Define(stage, f"/Col/Part{i}")
        m.CreatePointsAttr(pts)
        m.CreateFaceVertexCountsAttr([4] * 6)
        m.CreateFaceVertexIndicesAttr(
            [0, 3, 2, 1, 4, 5, 6, 7, 0, 1, 5, 4, 2, 3, 7, 6, 1, 2, 6, 5, 0, 4, 7, 3]
        )
    stage.Save()
    return path


@pytest.mark.parametrize("ext", [".stl", ".3mf"])
def test_parts_union_into_one_closed_solid_with_hand_computed_volume(tmp_path, ext):
    # a 1 m cube and a 1 x 2 x 1 m box overlapping it by half: union 0.5 + 2 = 2.5 m^3... by hand:
    # [0,1]^3 ∪ [0.5,1.5]x[0,2]x[0,1] = 1 + (1.5-0.5)*2*1 - (1-0.5)*1*1 = 2.5 m^3
    src = _cubes_stage(tmp_path / "c.usda", [((0, 0, 0), (1, 1, 1)), ((0.5, 0, 0), (1.5, 2, 1))])
    out = tmp_path / f"c{ext}"
    res = export_scene(src, out, scale=0.05)
    (solid,) = res.report.solids
    assert solid.closed and solid.parts == 2 and solid.non_manifold_edges == 0
    assert_allclose(solid.volume, 2.5 * 0.05**3, rtol=1e-6)
    assert_allclose(solid.size, (1.5 * 0.05, 1.0 * 0.05, 2.0 * 0.05), rtol=1e-6)  # Z up
    if ext == ".stl":
        tri = read_stl(out)
    else:
        with zipfile.ZipFile(out) as z:
            root = ElementTree.fromstring(z.read("3D/3dmodel.model"))
        ns = {"m": "http://schemas.microsoft.com/3dmanufacturing/core/2015/02"}
        assert root.get("unit") == "millimeter"
        v = np.array([[float(e.get(k)) for k in "xyz"] for e in root.iterfind(".//m:vertex", ns)])
        t = np.array(
            [
                [int(e.get(k)) for k in ("v1", "v2", "v3")]
                for e in root.iterfind(".//m:triangle", ns)
            ]
        )
        tri = v[t].astype(np.float32)
    # re-check the file's own numbers, welded by position as a slicer does
    uniq, inv = np.unique(tri.reshape(-1, 3), axis=0, return_inverse=True)
    closed, pinched, vol = check_solid(uniq, inv.reshape(-1, 3))
    assert closed and pinched == 0
    assert_allclose(vol, 2.5 * 50.0**3, rtol=1e-5)  # mm^3 at 1:20


def test_temple_stl_one_closed_solid_per_column(tiny_temple, tmp_path):
    out = tmp_path / "t.stl"
    rep = export_scene(tiny_temple.root, out, scale=0.01).report
    assert len(rep.solids) == 18 + 1  # every column, and the building
    assert rep.all_closed
    cols = [s for s in rep.solids if s.name != "Temple"]  # "Temple": what is not instanced
    assert len(cols) == 18 and all(s.parts >= 2 for s in cols)  # parts unioned
    free = [s for s in cols if s.name.startswith("front")]
    # a free column at 1:100 stands its height (8.22 m -> 82.2 mm) tall, Z up
    assert_allclose([s.size[2] for s in free], 0.0822, rtol=1e-3)
    assert len(read_stl(out)) == sum(s.triangles for s in rep.solids)


def test_cli_export_formats(tiny_temple, tmp_path, capsys):
    for ext in (".glb", ".gltf"):
        out = tmp_path / f"t{ext}"
        assert (
            main(
                ["export", str(tiny_temple.root), "-o", str(out), "--variant", "finish=travertine"]
            )
            == 0
        )
        g = pygltflib.GLTF2().load(str(out))
        assert g.scenes[0].extras["requestedVariants"] == {"finish": "travertine"}
        # columns switch to travertine; the building keeps its (stucco) binding
        assert {m.name for m in g.materials} == {"Travertine", "PaintedStucco"}
    assert "draw calls" in capsys.readouterr().out


@pytest.mark.parametrize(
    "args,needle",
    [
        (["-o", "{tmp}/x.obj"], "one of .glb"),
        (["-o", "{tmp}/x.glb", "--variant", "lod"], "SET=VALUE"),
        (["-o", "{tmp}/x.glb", "--variant", "form=sideways"], "engaged, full"),
        (["-o", "{tmp}/x.glb", "--lod", "ultra"], "--variant lod"),
        (["-o", "{tmp}/x.stl", "--scale", "0"], "--scale"),
        (["-o", "{tmp}/x.stl", "--scale", "1:0"], "--scale"),
        (["-o", "{tmp}/x.glb", "--scale", "1:20"], "--scale"),
        (["-o", "{tmp}/nodir/x.glb"], "does not exist"),
        (["-o", "{tmp}/x.stl", "--compress", "draco"], "--compress"),
        (["-o", "{tmp}/x.glb", "--compress", "zip"], "invalid choice"),
        (["-o", "{tmp}/x.usdz", "--gpu-instancing"], "--gpu-instancing"),
        (["-o", "{tmp}/x.stl", "--no-merge"], "--no-merge"),
    ],
)
def test_cli_errors_are_one_line_and_write_nothing(tiny_temple, tmp_path, capsys, args, needle):
    args = [a.replace("{tmp}", str(tmp_path)) for a in args]
    try:
        status = main(["export", str(tiny_temple.root), *args])
    except SystemExit as exc:  # argparse's own errors: same one line, same status
        status = exc.code
    assert status == 2
    err = capsys.readouterr().err.strip()
    assert needle in err and len(err.splitlines()) == 1 and "Traceback" not in err
    assert sorted(p.name for p in tmp_path.iterdir()) == []


def test_cli_refuses_to_overwrite_and_bad_scene(tiny_temple, tmp_path, capsys):
    out = tmp_path / "x.glb"
    out.write_bytes(b"mine")
    assert main(["export", str(tiny_temple.root), "-o", str(out)]) == 2
    assert out.read_bytes() == b"mine"
    bad = tmp_path / "bad.usda"
    bad.write_text("#usda 1.0\n(\n garbage")
    assert main(["export", str(bad), "-o", str(tmp_path / "y.glb")]) == 2
    assert main(["export", str(tmp_path / "none.usda"), "-o", str(tmp_path / "y.glb")]) == 2
    err = capsys.readouterr().err
    assert "exists" in err and "cannot open" in err and "Traceback" not in err
    assert not (tmp_path / "y.glb").exists()
    assert main(["export", str(out), "-o", str(out), "--force"]) == 2  # never over its input
    assert out.read_bytes() == b"mine"


def test_draco_compressed_glb_decodes_to_the_same_geometry(tmp_path):
    import DracoPy

    src = _cubes_stage(tmp_path / "c.usda", [((0, 0, 0), (1, 1, 1)), ((2, 0, 0), (3, 2, 1))])
    plain, packed = tmp_path / "p.glb", tmp_path / "d.glb"
    export_scene(src, plain)
    export_scene(src, packed, compress="draco")
    gp, gd = pygltflib.GLTF2().load(str(plain)), pygltflib.GLTF2().load(str(packed))
    assert gd.extensionsRequired == ["KHR_draco_mesh_compression"]
    for mp, md in zip(gp.meshes, gd.meshes, strict=True):
        ext = md.primitives[0].extensions["KHR_draco_mesh_compression"]
        bv = gd.bufferViews[ext["bufferView"]]
        dec = DracoPy.decode(gd.binary_blob()[bv.byteOffset : bv.byteOffset + bv.byteLength])
        want = _accessor(gp, mp.primitives[0].attributes.POSITION)
        tri_p = _canonical(want[_accessor(gp, mp.primitives[0].indices).reshape(-1, 3)])
        tri_d = _canonical(np.asarray(dec.points)[np.asarray(dec.faces)])
        assert_allclose(tri_d, tri_p, atol=2e-3)  # 16-bit positions over a 2 m box
        acc = gd.accessors[md.primitives[0].attributes.POSITION]
        assert acc.bufferView is None and acc.count == len(dec.points)


def _canonical(tris: np.ndarray) -> np.ndarray:
    """(t, 3, 3) triangles → rows sorted, each rotated (winding kept) to start at its
    lexicographically smallest corner, rounded to the millimetre."""
    r = np.round(tris, 3)
    out = []
    for t in r:
        k = min(range(3), key=lambda i: tuple(t[i]))
        out.append(np.roll(t, -k, axis=0).reshape(-1))
    out = np.array(out)
    return out[np.lexsort(out.T[::-1])]


def test_shared_paradata_is_stored_once():
    from ionic_usd.export.gltf import split_common

    a = {"path": "/a", "ionic_usd": {"temple": "T", "hypothesis": {"id": "h1"}}, "x": 1}
    b = {"path": "/b", "ionic_usd": {"temple": "T"}, "x": 1}
    common, rest = split_common([a, b])
    assert common == {"ionic_usd": {"temple": "T"}, "x": 1}
    assert rest == [{"path": "/a", "ionic_usd": {"hypothesis": {"id": "h1"}}}, {"path": "/b"}]
