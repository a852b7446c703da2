"""The mesh cache's entry layout: every CornerValues layout read back as it was written."""

from __future__ import annotations

import numpy as np

from ionic_usd.blueprint.asset import AssetMesh
from ionic_usd.geometry.curves import revolve
from ionic_usd.geometry.mesh import CornerValues, Mesh, smooth_normals
from ionic_usd.pipeline import mesh_cache


def _parts() -> list[AssetMesh]:
    prof = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    m, _ = revolve(prof, 12)
    groups = np.repeat(np.arange(3), [12, 24, 12])
    k = m.face_vertex_indices.size
    st = CornerValues(np.arange(2 * k, dtype=np.float32).reshape(-1, 2)[::-1], np.arange(k)[::-1])
    meshes = [
        smooth_normals(m),  # point normals, no st
        smooth_normals(m, groups).with_(st=st),  # per-corner normals, indexed st
        smooth_normals(m, groups, indexed=True).with_(
            st=CornerValues(st.values, st.indices, distinct=True)
        ),
        Mesh(m.points, m.face_vertex_counts, m.face_vertex_indices, name="bare"),
    ]
    return [AssetMesh("part", f"p{i}", x, {"i": str(i)}) for i, x in enumerate(meshes)]


def test_every_layout_is_read_back_as_written(tmp_path):
    parts = _parts()
    mesh_cache._write(tmp_path, parts)
    back = mesh_cache._read(tmp_path)
    assert [(b.part, b.name, b.tags) for b in back] == [(a.part, a.name, a.tags) for a in parts]
    for a, b in zip(parts, back, strict=True):
        x, y = a.mesh, b.mesh
        assert y.name == x.name
        for f in ("points", "face_vertex_counts", "face_vertex_indices"):
            np.testing.assert_array_equal(getattr(y, f), getattr(x, f))
        for f in ("normals", "st"):
            u, v = getattr(x, f), getattr(y, f)
            assert (u is None) == (v is None), (a.name, f)
            if u is None:
                continue
            assert (v.by_point, v.one_per_corner, v.distinct) == (
                u.by_point,
                u.one_per_corner,
                u.distinct,
            ), (a.name, f)
            np.testing.assert_array_equal(v.values, u.values)
            if u.indices is None:
                assert v.indices is None
            else:
                np.testing.assert_array_equal(v.indices, u.indices)
    # the layouts the parts were made with, so the test covers each of them
    n0, n1, n2 = (p.mesh.normals for p in parts[:3])
    assert n0.by_point and n1.one_per_corner and not (n2.by_point or n2.one_per_corner)
    assert parts[2].mesh.st.distinct and not parts[1].mesh.st.distinct
