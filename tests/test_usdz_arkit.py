"""usdz for AR: point instancers expanded into meshes (ARKit has no PointInstancer), what is
drawn unchanged; the ARKit profile itself (usd-core 24.11's ComplianceChecker) when a Python
with it is given (IONIC_USD_ARKIT_PYTHON; tools/check_arkit.sh makes one)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from numpy.testing import assert_allclose
from pxr import Gf, Sdf, Usd, UsdGeom

from ionic_usd.export import export_scene
from ionic_usd.usd import validate_stage
from ionic_usd.usd.reader import read_scene

ROOT = Path(__file__).resolve().parent.parent
_PTS = [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 2), (1, 0, 2), (0, 1, 2)]
_IDX = [0, 2, 1, 3, 4, 5, 0, 1, 4, 3, 1, 2, 5, 4, 2, 0, 3, 5]


def _wedge_instancer(stage: Usd.Stage, path: str, primvar: bool = False) -> None:
    """A closed wedge placed three times: plain, mirrored (scale −1 in x) and stretched; its
    normals as the attribute, or as the indexed ``primvars:normals``."""
    pi = UsdGeom.PointInstancer.Define(stage, path)
    m = UsdGeom.Mesh.Define(stage, f"{path}/Protos/Wedge")
    m.CreatePointsAttr(_PTS)
    m.CreateFaceVertexCountsAttr([3, 3, 4, 4, 4])
    m.CreateFaceVertexIndicesAttr(_IDX)
    # flat normals per face corner, and a face-varying st
    pts = np.array(_PTS, float)
    counts, start, normals = [3, 3, 4, 4, 4], 0, []
    for c in counts:
        f = pts[_IDX[start : start + c]]
        n = np.cross(f[1] - f[0], f[2] - f[0])
        normals += [tuple(n / np.linalg.norm(n))] * c
        start += c
    if primvar:
        values = sorted(set(normals))
        pv = UsdGeom.PrimvarsAPI(m).CreatePrimvar(
            "normals", Sdf.ValueTypeNames.Normal3fArray, UsdGeom.Tokens.faceVarying
        )
        pv.Set(values)
        pv.SetIndices([values.index(n) for n in normals])
    else:
        m.CreateNormalsAttr(normals)
        m.SetNormalsInterpolation(UsdGeom.Tokens.faceVarying)
    st = UsdGeom.PrimvarsAPI(m).CreatePrimvar(
        "st", Sdf.ValueTypeNames.TexCoord2fArray, UsdGeom.Tokens.faceVarying
    )
    st.Set([(i / 18.0, 1 - i / 18.0) for i in range(18)])
    pi.CreatePrototypesRel().SetTargets([m.GetPath()])
    pi.CreateProtoIndicesAttr([0, 0, 0])
    pi.CreatePositionsAttr([(0, 0, 0), (3, 0, 0), (0, 4, 0)])
    q = [Gf.Quath(1, 0, 0, 0), Gf.Quath(0, 0, 1, 0), Gf.Quath(1, 0, 0, 0)]
    pi.CreateOrientationsAttr(q)
    pi.CreateScalesAttr([(1, 1, 1), (-1, 1, 1), (2, 0.5, 1)])


def _big_instancer(stage: Usd.Stage, path: str) -> None:
    """A prototype over the bake limit (a 2,048-triangle grid under a moved Xform), placed
    twice: kept once, the copies native instances of it."""
    pi = UsdGeom.PointInstancer.Define(stage, path)
    root = UsdGeom.Xform.Define(stage, f"{path}/Protos/Grid")
    root.AddTranslateOp().Set((0.0, 1.0, 0.0))  # the prototype root's own transform
    m = UsdGeom.Mesh.Define(stage, f"{path}/Protos/Grid/Plane")
    n = 33
    xs, zs = np.meshgrid(np.arange(n, dtype=float), np.arange(n, dtype=float))
    m.CreatePointsAttr([(x, 0.0, z) for x, z in zip(xs.ravel(), zs.ravel(), strict=True)])
    quads = [
        (r * n + c, (r + 1) * n + c, (r + 1) * n + c + 1, r * n + c + 1)
        for r in range(n - 1)
        for c in range(n - 1)
    ]
    m.CreateFaceVertexCountsAttr([4] * len(quads))
    m.CreateFaceVertexIndicesAttr([i for q in quads for i in q])
    pi.CreatePrototypesRel().SetTargets([root.GetPath()])
    pi.CreateProtoIndicesAttr([0, 0])
    pi.CreatePositionsAttr([(0, 0, 50), (0, 0, 100)])
    pi.CreateOrientationsAttr([Gf.Quath(1, 0, 0, 0), Gf.Quath(0.7071, 0, 0.7071, 0)])


def _scene(path: Path) -> None:
    """An instancer at the root, one inside a prototype two native instances share, and one
    of a prototype too big to bake."""
    stage = Usd.Stage.CreateNew(str(path))
    UsdGeom.SetStageUpAxis(stage, "Y")
    UsdGeom.SetStageMetersPerUnit(stage, 1.0)
    stage.SetDefaultPrim(UsdGeom.Xform.Define(stage, "/R").GetPrim())
    _wedge_instancer(stage, "/R/Loose")
    _big_instancer(stage, "/R/Big")
    proto = stage.CreateClassPrim("/_Proto")
    _wedge_instancer(stage, "/_Proto/Orn", primvar=True)
    del proto
    for k in range(2):
        x = UsdGeom.Xform.Define(stage, f"/R/Inst{k}")
        x.AddTranslateOp().Set((20.0 * (k + 1), 0, 0))
        x.GetPrim().GetInherits().AddInherit("/_Proto")
        x.GetPrim().SetInstanceable(True)
    stage.Save()


def _world(scene) -> tuple[np.ndarray, list[np.ndarray]]:
    """Every drawn point (sorted rows) and per drawn face (geometric normal, mean normal)."""
    pts, pairs = [], []
    for p in scene.placements:
        m = scene.meshes[p.mesh]
        w = (np.c_[m.points, np.ones(len(m.points))] @ p.matrix)[:, :3]
        pts.append(w)
        lin = p.matrix[:3, :3]
        nrm = m.normals if m.normals is not None else None
        start = 0
        for c in m.face_vertex_counts:
            f = w[m.face_vertex_indices[start : start + c]]
            geo = np.cross(f[1] - f[0], f[2] - f[0])
            if nrm is not None:
                src = (
                    nrm[start : start + c]
                    if m.normals_interpolation != "vertex"
                    else nrm[m.face_vertex_indices[start : start + c]]
                )
                n = (src @ np.linalg.inv(lin).T).mean(axis=0)
                pairs.append(np.array([geo, n]))
            start += c
    allp = np.concatenate(pts)
    return allp[np.lexsort(np.round(allp, 6).T[::-1])], pairs


def test_usdz_expands_point_instancers_and_draws_the_same(tmp_path):
    _scene(tmp_path / "s.usda")
    out = tmp_path / "s.usdz"
    res = export_scene(tmp_path / "s.usda", out)
    # 3 copies each: the root instancer, the one in the flattened prototype (edited once,
    # drawn by both instances) and the class's own (not drawn; ARKit checks every prim);
    # and the big grid's 2
    assert res.report.expanded_copies == 11
    assert validate_stage(out) == []
    stage = Usd.Stage.Open(str(out))
    every = list(Usd.PrimRange.Stage(stage, Usd.TraverseInstanceProxies(Usd.PrimAllPrimsPredicate)))
    assert not any(p.IsA(UsdGeom.PointInstancer) for p in every)
    # normals only as the attribute (Blender reads a primvars:normals twice)
    meshes = [p for p in every if p.IsA(UsdGeom.Mesh)]
    assert meshes and not any(p.HasAttribute("primvars:normals") for p in meshes)
    wedges = [p for p in meshes if p.GetName() != "Plane"]  # the grid has no normals
    assert all(UsdGeom.Mesh(p).GetNormalsAttr().HasAuthoredValue() for p in wedges)
    big = [p for p in stage.GetPrimAtPath("/R/Big").GetChildren()]
    assert len(big) == 2 and all(p.IsInstance() for p in big)
    a, b = read_scene(tmp_path / "s.usda"), read_scene(out)
    assert a.n_triangles == b.n_triangles == 9 * 8 + 2 * 2048
    pa, _ = _world(a)
    pb, faces = _world(b)
    assert_allclose(pa, pb, atol=1e-5)
    # every baked face winds counter-clockwise about its normals, the mirrored copies' too
    assert faces and all(float(np.dot(g, n)) > 0 for g, n in faces)


@pytest.mark.slow
def test_default_temple_usdz_passes_the_arkit_profile(tmp_path):
    py = os.environ.get("IONIC_USD_ARKIT_PYTHON")
    if not py:
        pytest.skip("IONIC_USD_ARKIT_PYTHON (a Python with usd-core 24.11) is not set")
    import pxr

    defs = Path(pxr.__file__).parent / "pluginfo/usdShaders/resources/shaders/shaderDefs.usda"
    subprocess.run(
        [sys.executable, "-m", "ionic_usd", "temple", "-o", str(tmp_path / "T"), "--force"],
        check=True,
        capture_output=True,
    )
    out = tmp_path / "temple.usdz"
    export_scene(tmp_path / "T" / "Temple.usda", out)
    r = subprocess.run(
        [py, str(ROOT / "tools/arkit_check.py"), str(out), "--shader-defs", str(defs)],
        capture_output=True,
        text=True,
    )
    assert r.returncode == 0, r.stdout[-3000:] + r.stderr[-2000:]
    assert "0 errors, 0 failed checks" in r.stdout
