"""USD authoring: stage metadata, mesh attributes, atomic writes, validation."""

from __future__ import annotations

import numpy as np
import pytest
from numpy.testing import assert_allclose
from pxr import Sdf, Usd, UsdGeom

from ionic_usd.column.shaft import ShaftParams, build_shaft
from ionic_usd.errors import OutputExistsError, ParameterError
from ionic_usd.geometry.corners import CornerValues
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
    values, indices = np.array(pv.Get()), np.array(pv.GetIndices())
    assert len(values) <= len(mesh.normals.values) < mesh.face_vertex_indices.size / 2
    # each value once and every value used (NVIDIA's IndexedPrimvar and UnusedPrimvar rules)
    assert len(np.unique(values, axis=0)) == len(values) == np.unique(indices).size
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
    assert mesh.st is not None and len(mesh.st.values) == 24
    path = write_meshes(tmp_path / "box.usda", {"Box": mesh}, root="Box")
    stage = Usd.Stage.Open(str(path))
    prim = stage.GetPrimAtPath("/Box/Geom/Box")
    st = UsdGeom.PrimvarsAPI(prim).GetPrimvar("st")
    assert st.IsIndexed() and st.GetInterpolation() == UsdGeom.Tokens.faceVarying
    values = np.array(st.Get())
    assert len(np.unique(values, axis=0)) == len(values) < len(st.GetIndices()) == 24
    corner_st = mesh.st.at_corners(mesh.face_vertex_indices)
    assert_allclose(np.array(st.ComputeFlattened()), corner_st, atol=1e-6)


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


def _primvar_arrays(path, prim_path: str, name: str) -> tuple[np.ndarray, np.ndarray]:
    stage = Usd.Stage.Open(str(path))
    pv = UsdGeom.PrimvarsAPI(stage.GetPrimAtPath(prim_path)).GetPrimvar(name)
    assert pv.IsIndexed() and pv.GetInterpolation() == UsdGeom.Tokens.faceVarying
    return np.array(pv.Get()), np.array(pv.GetIndices())


@pytest.mark.parametrize(
    ("params", "kw"),
    [
        (ShaftParams(), {}),
        (ShaftParams(flute_slices=5, entasis=0.01), {"cap_bottom": False, "cap_top": False}),
        (ShaftParams(flute_slices=4, ring_bottom=0.0, ring_top=0.0), {"cap_top": False}),
    ],
)
def test_authored_shaft_st_is_the_generators_indexing(tmp_path, params, kw):
    from ionic_usd.texture.atlas import chart_labels

    m = build_shaft(params, **kw)
    assert m.st is not None and m.st.distinct  # the generator indexed st itself: no sort
    fast = write_meshes(tmp_path / "fast.usdc", {"Shaft": m}, root="Shaft")
    # the same mesh without the promise: de-duplicated at authoring, as before
    plain = CornerValues(m.st.values, m.st.indices)
    slow = write_meshes(tmp_path / "slow.usdc", {"Shaft": m.with_(st=plain)}, root="Shaft")
    values, idx = _primvar_arrays(fast, "/Shaft/Geom/Shaft", "st")
    # expanded, exactly the generator's per-corner st, and exactly the de-duplicated file's
    corner_st = m.st.at_corners(m.face_vertex_indices)
    np.testing.assert_array_equal(values[idx], corner_st)
    np.testing.assert_array_equal(values, m.st.values)  # written as the generator indexed it
    v_slow, i_slow = _primvar_arrays(slow, "/Shaft/Geom/Shaft", "st")
    np.testing.assert_array_equal(v_slow[i_slow], corner_st)
    # every value is used, and within a chart no two values are equal
    assert np.unique(idx).size == len(values)
    chart = chart_labels(idx, len(values))
    value_chart = np.empty(len(values))
    value_chart[idx.reshape(-1, 3)] = chart[:, None]
    keyed = np.column_stack([values, value_chart])
    assert len(np.unique(keyed, axis=0)) == len(values)
    # the charts of the two files are the same (the sort may merge values of two charts
    # that coincide, e.g. a cap centre with the side's seam corner, never more)
    assert len(v_slow) <= len(values) <= len(v_slow) + 2
    # the normals are untouched by the choice
    for path in (fast, slow):
        nv, ni = _primvar_arrays(path, "/Shaft/Geom/Shaft", "normals")
        np.testing.assert_array_equal(nv[ni], m.corner_normals())


def test_st_distinct_promise_follows_the_values():
    from ionic_usd.errors import GeometryError
    from ionic_usd.geometry.mesh import Mesh, merge, transform
    from ionic_usd.texture.atlas import analytic_atlas, attach_uvs

    m = build_shaft(ShaftParams(flute_slices=3))
    st, fvi = m.st, m.face_vertex_indices
    assert st is not None and st.distinct
    # new values or indices drop the promise unless it is given again
    assert not st.with_values(st.values * 2).distinct
    assert not st.take(np.arange(fvi.size)[::-1], fvi).distinct
    assert CornerValues(st.values * 2, st.indices, distinct=True).distinct
    assert m.with_(points=m.points * 2).st.distinct
    # a mirror permutes each face's corners: the same values, still all used
    mirrored = transform(m, np.diag([-1.0, 1.0, 1.0, 1.0]))
    assert mirrored.st.distinct and not np.array_equal(mirrored.st.indices, st.indices)
    assert not merge([m, m]).st.distinct  # two parts' charts may coincide
    # the promise lives on the values: they must fit the mesh's corners
    with pytest.raises(GeometryError, match="st indices"):
        Mesh(m.points, m.face_vertex_counts, fvi, st=CornerValues(st.values, st.indices[:-3], True))
    # packing moves whole charts apart: the atlas keeps the promise, and after packing all
    # values are distinct (the charts no longer overlap)
    atlas = analytic_atlas(m, texels_per_metre=64)
    packed = attach_uvs(m, atlas)
    assert atlas.st_distinct and packed.st.distinct
    assert len(np.unique(packed.st.values, axis=0)) == len(packed.st.values)
