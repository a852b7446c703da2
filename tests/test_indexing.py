"""Indexed primvar values (ionic_usd.geometry.indexing.distinct_values) against a brute-force
dictionary, and every indexed primvar of an authored asset: each value once, every value used
(NVIDIA's IndexedPrimvarChecker and UnusedPrimvarChecker), the same corners as the mesh."""

from __future__ import annotations

import numpy as np
import pytest

from ionic_usd.errors import GeometryError
from ionic_usd.geometry import indexing
from ionic_usd.geometry.indexing import distinct_values


def _brute(values: np.ndarray, indices: np.ndarray | None):
    v = np.asarray(values, dtype=np.float32) + np.float32(0.0)  # -0.0 is 0.0
    idx = range(len(v)) if indices is None else indices
    used = sorted(set(int(i) for i in idx))
    ids: dict[bytes, int] = {}
    for i in used:  # first row of each distinct value among the used rows, in row order
        ids.setdefault(v[i].tobytes(), len(ids))
    out = np.array([np.frombuffer(k, np.float32) for k in ids]).reshape(-1, v.shape[1])
    return out, np.array([ids[v[int(i)].tobytes()] for i in idx], dtype=np.int32)


@pytest.mark.parametrize("columns", [1, 2, 3])
@pytest.mark.parametrize("with_indices", [True, False])
def test_distinct_values_is_the_brute_force_dictionary(columns, with_indices):
    rng = np.random.default_rng(columns)
    pool = rng.normal(size=(40, columns))
    values = pool[rng.integers(0, 40, 600)]  # many repeats
    values[::7] = -0.0  # equal to 0.0 though other bits: one value, written as 0.0
    values[::11] = 0.0
    indices = rng.integers(0, 500, 2000) if with_indices else None  # rows 500.. unused
    got_v, got_i = distinct_values(values, indices)
    want_v, want_i = _brute(values, indices)
    assert got_v.dtype == np.float32 and got_i.dtype == np.int32
    assert got_v.tobytes() == want_v.tobytes() and np.array_equal(got_i, want_i)
    ref = values if indices is None else values[indices]
    assert np.array_equal(got_v[got_i], ref.astype(np.float32))
    assert len(np.unique(got_v, axis=0)) == len(got_v)  # distinct by value, not only by bits
    assert not np.signbit(got_v[got_v == 0]).any()


def test_a_key_collision_falls_back_to_comparing_the_rows(monkeypatch):
    rows = np.array([[1, 2, 3], [4, 5, 6], [1, 2, 3], [0, 0, 0], [4, 5, 6]], np.float32)
    idx = np.array([4, 3, 0, 2, 1, 4])
    want = _brute(rows, idx)
    # every row gets the same key: the rows themselves must tell them apart
    monkeypatch.setattr(indexing, "_keys", lambda r: np.zeros(len(r), np.uint64))
    got_v, got_i = distinct_values(rows, idx)
    assert got_v.tobytes() == want[0].tobytes() and np.array_equal(got_i, want[1])
    assert len(got_v) == 3


@pytest.mark.parametrize("columns", [1, 2, 3])
def test_keys_colliding_in_some_runs_are_told_apart_there(monkeypatch, columns):
    # three keys for many values: some runs hold several values (sorted out by the rows'
    # values), the rest one; the result is the brute force's all the same
    rng = np.random.default_rng(7)
    values = rng.normal(size=(30, columns))[rng.integers(0, 30, 500)]
    idx = rng.integers(0, 450, 1500)
    want = _brute(values, idx)
    monkeypatch.setattr(
        indexing,
        "_keys",
        lambda r: (r.view(np.uint32)[:, 0] % np.uint32(3)).astype(np.uint64) << np.uint64(50),
    )
    got_v, got_i = distinct_values(values, idx)
    assert got_v.tobytes() == want[0].tobytes() and np.array_equal(got_i, want[1])


def test_distinct_values_refuses_what_is_not_a_primvar():
    with pytest.raises(GeometryError, match="shape"):
        distinct_values(np.zeros((4, 5)), None)
    with pytest.raises(GeometryError, match="index outside"):
        distinct_values(np.zeros((4, 3)), np.array([0, 4]))
    v, i = distinct_values(np.zeros((0, 3)), None)
    assert v.shape == (0, 3) and i.size == 0


def test_every_indexed_primvar_of_the_asset_is_distinct_and_used(tmp_path):
    from pxr import Usd, UsdGeom

    from ionic_usd.pipeline.asset import ColumnAssetOptions, column_asset_meshes
    from ionic_usd.usd.mesh import write_meshes

    meshes = column_asset_meshes(ColumnAssetOptions(lods=("low",)), workers=1)
    path = write_meshes(tmp_path / "asset.usdc", {m.name: m.mesh for m in meshes}, root="Asset")
    stage = Usd.Stage.Open(str(path))
    seen = 0
    by_name = {m.name: m.mesh for m in meshes}
    for prim in stage.Traverse():
        if not prim.IsA(UsdGeom.Mesh):
            continue
        mesh = by_name[prim.GetName()]
        for name in ("normals", "st"):
            pv = UsdGeom.PrimvarsAPI(prim).GetPrimvar(name)
            assert pv.IsIndexed(), (prim.GetPath(), name)
            values, idx = np.array(pv.Get()), np.array(pv.GetIndices())
            assert np.unique(idx).size == len(values), (prim.GetPath(), name)
            # st may repeat a value in two charts (a generator's own indexing keeps its
            # charts apart, e.g. a cap centre on the side's seam); normals never repeat
            if name == "normals":
                assert len(np.unique(values, axis=0)) == len(values), prim.GetPath()
        flat = np.array(UsdGeom.PrimvarsAPI(prim).GetPrimvar("normals").ComputeFlattened())
        np.testing.assert_array_equal(flat, mesh.corner_normals().astype(np.float32))
        seen += 1
    # both forms cut (engaged, corner) and full: the cuts' per-corner normals are indexed too
    assert seen == len(meshes) and any(m.name.endswith("_corner") for m in meshes)
