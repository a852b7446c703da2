"""glTF: copies of small meshes merged per point instancer (ionic_usd.export.gltf_merge)."""

from __future__ import annotations

import numpy as np
import pygltflib
from numpy.testing import assert_allclose
from pxr import Gf, Usd, UsdGeom

from ionic_usd.export import export_scene
from ionic_usd.usd.reader import read_scene


def _accessor(g: pygltflib.GLTF2, i: int) -> np.ndarray:
    acc = g.accessors[i]
    bv = g.bufferViews[acc.bufferView]
    dtype = {5126: np.float32, 5123: np.uint16, 5125: np.uint32}[acc.componentType]
    width = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4}[acc.type]
    a = np.frombuffer(
        g.binary_blob(), dtype, acc.count * width, bv.byteOffset + (acc.byteOffset or 0)
    )
    return a.reshape(acc.count, width) if width > 1 else a


def _drawn(g: pygltflib.GLTF2) -> tuple[int, int]:
    """(triangles, draw calls) of every node reachable from the scene, each drawn once."""
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


def _instancer_stage(path) -> None:
    """Two point instancers laid out alike (one moved) of a closed wedge; a mirrored and a
    non-uniformly scaled copy among the three."""
    stage = Usd.Stage.CreateNew(str(path))
    UsdGeom.SetStageUpAxis(stage, "Y")
    UsdGeom.SetStageMetersPerUnit(stage, 1.0)
    stage.SetDefaultPrim(UsdGeom.Xform.Define(stage, "/R").GetPrim())
    pts = [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 2), (1, 0, 2), (0, 1, 2)]
    for k, dx in ((0, 0.0), (1, 10.0)):
        pi = UsdGeom.PointInstancer.Define(stage, f"/R/I{k}")
        UsdGeom.Xformable(pi).AddTranslateOp().Set((dx, 0, 0))
        m = UsdGeom.Mesh.Define(stage, f"/R/I{k}/Protos/Wedge")
        m.CreatePointsAttr(pts)
        m.CreateFaceVertexCountsAttr([3, 3, 4, 4, 4])
        m.CreateFaceVertexIndicesAttr([0, 2, 1, 3, 4, 5, 0, 1, 4, 3, 1, 2, 5, 4, 2, 0, 3, 5])
        pi.CreatePrototypesRel().SetTargets([m.GetPath()])
        pi.CreateProtoIndicesAttr([0, 0, 0])
        pi.CreatePositionsAttr([(0, 0, 0), (3, 0, 0), (0, 4, 0)])
        q = [Gf.Quath(1, 0, 0, 0), Gf.Quath(0, 0, 1, 0), Gf.Quath(1, 0, 0, 0)]
        pi.CreateOrientationsAttr(q)
        pi.CreateScalesAttr([(1, 1, 1), (-1, 1, 1), (2, 0.5, 1)])
    stage.Save()


def test_glb_merges_instancer_copies_exactly(tmp_path):
    _instancer_stage(tmp_path / "w.usda")
    scene = read_scene(tmp_path / "w.usda")
    out = tmp_path / "w.glb"
    res = export_scene(tmp_path / "w.usda", out)
    g = pygltflib.GLTF2().load(str(out))
    # the two instancers share one merged mesh; each is one node, one draw call
    mesh_nodes = [n for n in g.nodes if n.mesh is not None]
    assert len(g.meshes) == 1 and len(mesh_nodes) == 2
    assert res.report.draw_calls == 2 and res.report.merged == 6
    assert _drawn(g) == (res.report.triangles_drawn, 2) and res.report.triangles_drawn == 6 * 8
    prim = g.meshes[0].primitives[0]
    pos = _accessor(g, prim.attributes.POSITION).astype(np.float64)
    nrm = _accessor(g, prim.attributes.NORMAL).astype(np.float64)
    tri = _accessor(g, prim.indices).reshape(-1, 3)
    world = []
    for n in mesh_nodes:
        m = np.array(n.matrix).reshape(4, 4) if n.matrix else np.eye(4)
        world.append(np.c_[pos, np.ones(len(pos))] @ m)
    got = np.unique(np.round(np.concatenate(world)[:, :3], 5), axis=0)
    key = next(iter(scene.meshes))
    src = scene.meshes[key].points
    want = np.concatenate(
        [(np.c_[src, np.ones(len(src))] @ p.matrix)[:, :3] for p in scene.placements]
    )
    assert_allclose(got, np.unique(np.round(want, 5), axis=0), atol=1e-5)
    # every triangle winds counter-clockwise about its normals, the mirrored copy's included
    geo = np.cross(pos[tri[:, 1]] - pos[tri[:, 0]], pos[tri[:, 2]] - pos[tri[:, 0]])
    assert np.all(np.einsum("ij,ij->i", geo, nrm[tri].mean(axis=1)) > 0)
    assert_allclose(np.linalg.norm(nrm, axis=1), 1.0, atol=1e-6)
    # without merging: one node per copy, the same triangles
    res2 = export_scene(tmp_path / "w.usda", tmp_path / "n.glb", merge=False)
    g2 = pygltflib.GLTF2().load(str(tmp_path / "n.glb"))
    assert _drawn(g2) == (res.report.triangles_drawn, 6) and res2.report.merged == 0
