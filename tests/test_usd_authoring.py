"""USD authoring: stage metadata, mesh attributes, atomic writes, validation."""

from __future__ import annotations

import numpy as np
import pytest
from numpy.testing import assert_allclose
from pxr import Sdf, Usd, UsdGeom

from ionic_usd.column.shaft import ShaftParams, build_shaft
from ionic_usd.errors import OutputExistsError, ParameterError
from ionic_usd.usd import new_layer, save_layer, validate_stage, write_meshes


@pytest.mark.parametrize("ext", [".usda", ".usdc", ".usd"])
def test_shaft_roundtrip_and_validates(tmp_path, ext):
    mesh = build_shaft(ShaftParams(flute_slices=4))
    path = write_meshes(tmp_path / f"shaft{ext}", {"Shaft": mesh}, root="Shaft")
    stage = Usd.Stage.Open(str(path))
    assert stage.GetDefaultPrim().GetPath() == Sdf.Path("/Shaft")
    assert UsdGeom.GetStageUpAxis(stage) == UsdGeom.Tokens.y
    assert UsdGeom.GetStageMetersPerUnit(stage) == 1.0
    assert Usd.ModelAPI(stage.GetDefaultPrim()).GetKind() == "component"
    prim = stage.GetPrimAtPath("/Shaft/Geom/Shaft")
    geom = UsdGeom.Mesh(prim)
    assert_allclose(np.array(geom.GetPointsAttr().Get()), mesh.points, atol=1e-6)
    assert list(geom.GetFaceVertexIndicesAttr().Get()) == mesh.face_vertex_indices.tolist()
    assert geom.GetSubdivisionSchemeAttr().Get() == "none"
    # indexed normals are the indexed primvar primvars:normals, and only it (the normals
    # attribute cannot be indexed; the primvar takes precedence for every reader)
    assert not geom.GetNormalsAttr().HasAuthoredValue()
    pv = UsdGeom.PrimvarsAPI(prim).GetPrimvar("normals")
    assert pv.IsIndexed() and pv.GetInterpolation() == UsdGeom.Tokens.faceVarying
    assert len(pv.Get()) == len(mesh.normals) < mesh.face_vertex_indices.size / 2
    flat = np.array(pv.ComputeFlattened())
    assert flat.shape == (mesh.face_vertex_indices.size, 3)
    assert_allclose(flat, mesh.corner_normals(), atol=1e-6)
    extent = np.array(geom.GetExtentAttr().Get())
    assert_allclose(extent, mesh.extent, atol=1e-6)
    # every ancestor is typed: the model an Xform, the organising Geom a Scope
    assert stage.GetPrimAtPath("/Shaft").GetTypeName() == "Xform"
    assert stage.GetPrimAtPath("/Shaft/Geom").GetTypeName() == "Scope"
    # file format follows the extension
    head = path.read_bytes()[:8]
    assert head == (b"#usda 1." if ext == ".usda" else b"PXR-USDC")
    assert validate_stage(stage) == []


def test_st_is_an_indexed_primvar_of_distinct_values(tmp_path):
    from ionic_usd.temple import Cuboid, cuboid_mesh

    # a cuboid: 24 corners, coplanar faces sharing st values along their common edges
    mesh = cuboid_mesh(Cuboid((0, 0, 0), (2, 1, 3)), uv_scale=0.5)
    assert mesh.st is not None and len(mesh.st) == 24
    path = write_meshes(tmp_path / "box.usda", {"Box": mesh}, root="Box")
    stage = Usd.Stage.Open(str(path))
    prim = stage.GetPrimAtPath("/Box/Geom/Box")
    st = UsdGeom.PrimvarsAPI(prim).GetPrimvar("st")
    assert st.IsIndexed() and st.GetInterpolation() == UsdGeom.Tokens.faceVarying
    values = np.array(st.Get())
    assert len(np.unique(values, axis=0)) == len(values) < len(st.GetIndices()) == 24
    assert_allclose(np.array(st.ComputeFlattened()), mesh.st[mesh.st_indices], atol=1e-6)


def test_validator_catches_missing_metadata(tmp_path):
    layer = Sdf.Layer.CreateAnonymous(".usda")
    Sdf.CreatePrimInLayer(layer, "/A").specifier = Sdf.SpecifierDef
    errors = validate_stage(Usd.Stage.Open(layer))
    assert any("defaultPrim" in e for e in errors)
    assert any("upAxis" in e for e in errors)


def test_atomic_write_and_force(tmp_path):
    path = tmp_path / "a.usda"
    save_layer(new_layer("A"), path)
    before = path.read_bytes()
    with pytest.raises(OutputExistsError):
        save_layer(new_layer("B"), path)
    assert path.read_bytes() == before
    save_layer(new_layer("B"), path, force=True)
    assert b'defaultPrim = "B"' in path.read_bytes()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.usda"]  # no temp leftovers
    with pytest.raises(ParameterError, match="usda"):
        save_layer(new_layer("C"), tmp_path / "c.obj")
