"""Geometry kernel: Mesh, merge/transform/weld, normals, curves, revolve."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest
from numpy.testing import assert_allclose

from ionic_usd.errors import GeometryError, ParameterError
from ionic_usd.geometry import (
    CornerValues,
    Mesh,
    bezier,
    inspect_mesh,
    merge,
    polyline_length,
    resample_polyline,
    revolve,
    smooth_normals,
    transform,
    weld,
)


def test_kernel_imports_with_pxr_blocked():
    code = (
        "import sys\n"
        "class Block:\n"
        "    def find_spec(self, name, path=None, target=None):\n"
        "        if name == 'pxr' or name.startswith('pxr.'):\n"
        "            raise ImportError('pxr is blocked')\n"
        "sys.meta_path.insert(0, Block())\n"
        "import ionic_usd.geometry, ionic_usd.column.shaft\n"
        "ionic_usd.column.shaft.build_shaft()\n"
        "assert not any(m == 'pxr' or m.startswith('pxr.') for m in sys.modules)\n"
        "print('ok')\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "ok"


def cube() -> Mesh:
    p = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], float)
    quads = [[0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4], [1, 5, 7, 3]]
    return Mesh(p, [4] * 6, np.array(quads).reshape(-1), name="cube")


def test_mesh_is_immutable_and_validated():
    m = cube()
    with pytest.raises(ValueError):
        m.points[0, 0] = 5.0
    with pytest.raises(GeometryError, match="sum to"):
        Mesh(m.points, [4] * 5, m.face_vertex_indices)
    with pytest.raises(GeometryError, match="out of range"):
        Mesh(m.points, [3], [0, 1, 99])
    with pytest.raises(GeometryError, match="non-finite"):
        Mesh(np.full((3, 3), np.nan), [3], [0, 1, 2])


def test_cube_fan_triangulation_is_closed_with_unit_volume():
    r = inspect_mesh(cube())
    assert r.n_triangles == 12
    assert r.watertight
    assert r.signed_volume == pytest.approx(1.0)
    assert r.area == pytest.approx(6.0)


def test_transform_mirror_keeps_outward_winding():
    m = smooth_normals(Mesh(cube().points, [3] * 12, cube().triangles.reshape(-1)))
    mirror = np.diag([-1.0, 1.0, 1.0, 1.0])
    t = transform(m, mirror)
    assert inspect_mesh(t).signed_volume == pytest.approx(1.0)
    assert t.normals.by_point  # a point attribute stays one: the corners only permute
    assert_allclose(t.normals.values[:, 0], -m.normals.values[:, 0], atol=1e-6)
    scale = np.diag([2.0, 3.0, 4.0, 1.0])
    assert inspect_mesh(transform(m, scale)).signed_volume == pytest.approx(24.0)


def test_merge_and_weld():
    a = Mesh(cube().points, [3] * 12, cube().triangles.reshape(-1))
    b = transform(a, np.array([[1, 0, 0, 5], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1.0]]))
    m = merge([a, b])
    assert m.n_points == 16 and m.n_triangles == 24
    assert inspect_mesh(m).signed_volume == pytest.approx(2.0)
    # two copies on top of each other weld into 8 points with duplicate faces
    w = weld(merge([a, a]))
    assert w.n_points == 8
    assert inspect_mesh(w).duplicate_faces == 12


def test_smooth_normals_groups_crisp_and_smooth():
    tri = Mesh(cube().points, [3] * 12, cube().triangles.reshape(-1))
    smooth = smooth_normals(tri)
    # per-vertex normal of a cube corner points along the diagonal
    d = tri.points - 0.5
    assert smooth.normals.by_point
    unit = d / np.linalg.norm(d, axis=1, keepdims=True)
    assert_allclose(smooth.normals.values, unit, atol=1e-6)
    # one group per face side -> per-corner normals equal the face normals
    groups = np.repeat(np.arange(6), 2)
    crisp = smooth_normals(tri, groups)
    assert not crisp.normals.by_point and crisp.normals.one_per_corner
    p = tri.points[tri.triangles]
    fn = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    fn /= np.linalg.norm(fn, axis=1, keepdims=True)
    assert_allclose(crisp.normals.values, np.repeat(fn, 3, axis=0), atol=1e-6)


def test_resample_polyline_constant_spacing(rng):
    curve = np.cumsum(rng.normal(size=(50, 2)), axis=0)
    out = resample_polyline(curve, count=200)
    seg = np.linalg.norm(np.diff(out, axis=0), axis=1)
    assert_allclose(out[[0, -1]], curve[[0, -1]])
    # nodes are equally spaced along the original curve's arc length; chords are never longer
    assert seg.max() <= polyline_length(curve) / 199 + 1e-9
    sp = resample_polyline(curve, spacing=0.5)
    assert (len(sp) - 1) * 0.5 >= polyline_length(curve) - 1e-9
    with pytest.raises(ParameterError):
        resample_polyline(curve, spacing=-1)


def test_bezier_endpoints_and_line():
    ctrl = np.array([[0.0, 0.0], [1.0, 2.0], [3.0, 2.0], [4.0, 0.0]])
    t = np.linspace(0, 1, 11)
    pts = bezier(ctrl, t)
    assert_allclose(pts[[0, -1]], ctrl[[0, -1]])
    # a straight control polygon gives a straight line with the same parameter
    line = bezier(np.array([[0.0, 0.0], [1.0, 1.0], [2.0, 2.0]]), t)
    assert_allclose(line, np.stack([2 * t, 2 * t], axis=1))
    # de Casteljau at t = 0.5 for the cubic
    assert_allclose(bezier(ctrl, np.array([0.5]))[0], [2.0, 1.5])


@pytest.mark.parametrize("segments", [3, 8, 64])
def test_revolve_cylinder_volume(segments):
    prof = np.array([[0, 0], [1, 0], [1, 2], [0, 2]], float)
    m, rows = revolve(prof, segments)
    r = inspect_mesh(m)
    assert r.watertight
    expected = 0.5 * segments * np.sin(2 * np.pi / segments) * 2.0
    assert r.signed_volume == pytest.approx(expected)
    assert [len(x) for x in rows] == [1, segments, segments, 1]
    with pytest.raises(GeometryError):
        revolve(np.array([[-1.0, 0.0], [1.0, 1.0]]), 8)


def test_replace_never_keeps_stale_triangles():
    import dataclasses

    m = cube()
    before = m.triangles.copy()
    flipped = m.face_vertex_indices.reshape(-1, 4)[:, ::-1].reshape(-1)
    from ionic_usd.geometry.mesh import triangulate_fan

    expected = triangulate_fan(m.face_vertex_counts, flipped)
    for other in (
        dataclasses.replace(m, face_vertex_indices=flipped),
        m.with_(face_vertex_indices=flipped),
    ):
        np.testing.assert_array_equal(other.triangles, expected)
        assert not np.array_equal(other.triangles, before)


# -- indexed normals -------------------------------------------------------------------------


def _lathe_with_groups():
    from ionic_usd.geometry.curves import revolve

    prof = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.6, 1.4], [0.0, 1.4]])
    m, _ = revolve(prof, 24)
    groups = np.repeat(np.arange(4), [24, 48, 48, 24])  # one group per band: crisp joints
    return m, groups


def test_indexed_smooth_normals_expand_to_the_per_corner_ones():
    m, groups = _lathe_with_groups()
    flat = smooth_normals(m, groups)
    idx = smooth_normals(m, groups, indexed=True)
    assert flat.normals.one_per_corner and not idx.normals.one_per_corner
    assert idx.normals.indices is not None
    assert_allclose(idx.corner_normals(), flat.normals.values, atol=1e-6)
    # one value per point plus one per (point, group) pair of a point on a crease
    pairs = np.unique(m.triangles.reshape(-1) * 10 + np.repeat(groups, 3))
    per_point = np.bincount(pairs // 10, minlength=m.n_points)
    assert len(idx.normals.values) == m.n_points + per_point[per_point > 1].sum()
    # first-occurrence numbering of the crease values: they first appear in increasing order
    crease = idx.normals.indices[idx.normals.indices >= m.n_points]
    _, first = np.unique(crease, return_index=True)
    assert np.all(np.diff(crease[np.sort(first)]) == 1)


def test_indexed_normals_survive_merge_transform_weld():
    m, groups = _lathe_with_groups()
    a = smooth_normals(m, groups, indexed=True)
    b = transform(smooth_normals(m), np.diag([1.0, 1.0, 1.0, 1.0]) + np.eye(4, k=3) * 3)
    c = smooth_normals(m, groups)  # faceVarying, not indexed
    ab = merge([a, b, c])
    assert ab.normals.indices is not None and not ab.normals.one_per_corner
    assert_allclose(
        ab.corner_normals(),
        np.concatenate([a.corner_normals(), b.corner_normals(), c.corner_normals()]),
        atol=1e-6,
    )
    mirror = np.diag([-1.0, 1.0, 1.0, 1.0])
    t = transform(a, mirror)
    assert t.normals.indices is not None and not t.normals.one_per_corner
    expected = transform(c, mirror)  # the same mirror on per-corner storage
    assert_allclose(t.corner_normals(), expected.normals.values, atol=1e-6)
    w = weld(a)
    assert w.normals.indices is not None and not w.normals.one_per_corner
    assert_allclose(w.corner_normals(), a.corner_normals(), atol=0)


def test_indexed_normals_are_validated_and_extent_is_cached():
    m, groups = _lathe_with_groups()
    a = smooth_normals(m, groups, indexed=True)
    nrm = a.normals
    with pytest.raises(GeometryError, match="normals indices"):
        a.with_(normals=CornerValues(nrm.values, nrm.indices[:-3]))
    with pytest.raises(GeometryError, match="normals per point"):
        a.with_(normals=CornerValues(nrm.values))  # more values than points
    with pytest.raises(GeometryError, match="outside"):
        CornerValues(nrm.values[:3], nrm.indices)
    with pytest.raises(GeometryError, match="must be CornerValues"):
        a.with_(normals=nrm.values)
    with pytest.raises(GeometryError, match="must be CornerValues"):
        a.with_(st=nrm)  # st has two components
    assert_allclose(a.extent, [a.points.min(axis=0), a.points.max(axis=0)])
    assert a.extent is a.extent and not a.extent.flags.writeable


@pytest.mark.parametrize("dtype", [np.int64, np.float64, np.float32])
def test_unique_rows_is_numpys_unique_along_rows(dtype):
    from ionic_usd.geometry.mesh import unique_rows

    rng = np.random.default_rng(3)
    a = rng.integers(-3, 4, size=(5000, 3)).astype(dtype)
    if dtype != np.int64:
        a[::7, 1] = -0.0  # equal to 0.0, as numpy counts it
    want = np.unique(a, axis=0, return_index=True, return_inverse=True, return_counts=True)
    got = unique_rows(a, return_index=True, return_inverse=True, return_counts=True)
    for w, g in zip(want, got, strict=True):
        np.testing.assert_array_equal(g, w.reshape(g.shape))
    np.testing.assert_array_equal(unique_rows(a), want[0])
    empty = np.zeros((0, 2), dtype=dtype)
    assert unique_rows(empty).shape == (0, 2)


def test_pchip_is_scipys_pchip_interpolator():
    from scipy.interpolate import PchipInterpolator

    from ionic_usd.geometry.curves import pchip

    rng = np.random.default_rng(5)
    cases = [
        (np.array([0.0, 1.0]), np.array([2.0, 3.0])),
        (np.array([0.0, 0.2, 0.5, 1.0]), np.array([1.0, 1.0, 0.6, 0.8])),  # flat, turn
        (np.array([0.0, 0.1, 0.15, 0.6, 1.0]), np.array([0.9, 0.5, 0.55, 0.55, 1.0])),
    ]
    for _ in range(20):
        x = np.sort(rng.uniform(0, 3, 7))
        cases.append((x, rng.normal(size=7)))
    cases.append((np.array([0.0, 1.0, 2.0]), np.array([0.0, 1.0, -5.0])))  # end clamp to 3 m0
    for x, y in cases:
        t = np.linspace(x[0], x[-1], 301)
        want = PchipInterpolator(x, y)(t)
        np.testing.assert_allclose(pchip(x, y, t), want, rtol=0, atol=1e-12 * (1 + np.abs(y).max()))
        np.testing.assert_allclose(pchip(x, y, x), y, atol=1e-14 * (1 + np.abs(y).max()))


def test_corner_values_one_path_for_every_layout():
    """Point, per-corner and indexed values go through merge, mirror and weld alike: the
    expanded per-corner values are carried exactly, and the layout is the documented one."""
    m, groups = _lathe_with_groups()
    by_point = smooth_normals(m)
    per_corner = smooth_normals(m, groups)
    indexed = smooth_normals(m, groups, indexed=True)
    assert by_point.normals.by_point and per_corner.normals.one_per_corner
    assert indexed.normals.indices is not None and not indexed.normals.one_per_corner
    parts = [by_point, per_corner, indexed]
    expanded = np.concatenate([p.corner_normals() for p in parts])
    # all point values: still point values; point + per-corner: per corner; any indexed: indexed
    assert merge([by_point, by_point]).normals.by_point
    pc = merge([by_point, per_corner]).normals
    assert pc.one_per_corner and len(pc.values) == 2 * m.face_vertex_indices.size
    mixed = merge(parts)
    assert not mixed.normals.by_point and not mixed.normals.one_per_corner
    assert_allclose(mixed.corner_normals(), expanded, atol=0)
    mirror = np.diag([-1.0, 1.0, 1.0, 1.0])
    for p in parts:
        t = transform(p, mirror)
        assert t.normals.by_point == p.normals.by_point
        assert t.normals.one_per_corner == p.normals.one_per_corner
        # the mirror reverses each face and negates x: corner c of a face is old corner -c
        perm = np.arange(m.face_vertex_indices.size).reshape(-1, 3)[:, [0, 2, 1]].reshape(-1)
        assert_allclose(t.corner_normals(), p.corner_normals()[perm] * [-1, 1, 1], atol=1e-6)
        w = weld(p)  # a weld moves points: point values become per corner
        assert not w.normals.by_point
        assert_allclose(w.corner_normals(), p.corner_normals(), atol=0)
    # st rides through the same code: indexed st of the per-corner part survives the merge
    st = CornerValues(np.arange(2 * m.n_points, dtype=np.float32).reshape(-1, 2))
    with_st = [p.with_(st=st) for p in parts]
    got = merge(with_st).st
    assert got is not None and got.indices is None  # every part's st is per point
    assert_allclose(got.values, np.concatenate([st.values] * 3))
    assert merge([with_st[0], parts[1]]).st is None  # kept only when every part has it
