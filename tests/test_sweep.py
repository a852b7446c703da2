"""Sweeps: closed at the mitres, outward, exact volumes, UVs in metres."""

from __future__ import annotations

import numpy as np
import pytest
from numpy.testing import assert_allclose

from ionic_usd.errors import GeometryError
from ionic_usd.geometry.analysis import signed_volume
from ionic_usd.geometry.sweep import polygon_area, sweep


def _manifold(mesh):
    import manifold3d as m3

    return m3.Manifold(
        m3.Mesh(
            vert_properties=mesh.points.astype(np.float32),
            tri_verts=mesh.triangles.astype(np.uint32),
        )
    )


def _directed_edges_unique(mesh) -> bool:
    t = mesh.triangles
    d = np.concatenate([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]])
    return len(np.unique(d, axis=0)) == len(d)


RECT = np.array([[-2.0, 0.0, -3.0], [2.0, 0.0, -3.0], [2.0, 0.0, 3.0], [-2.0, 0.0, 3.0]])


@pytest.mark.parametrize("reverse", [False, True])
@pytest.mark.parametrize("flip_section", [False, True])
def test_closed_box_section_volume_and_shell(reverse, flip_section):
    u0, u1, h = -0.3, 0.2, 0.5
    sec = np.array([[u0, 0.0], [u1, 0.0], [u1, h], [u0, h]])
    if flip_section:
        sec = sec[::-1]
    path = RECT[::-1] if reverse else RECT
    m = sweep(sec, path)
    # hand: outer rectangle (4 + 2u1)(6 + 2u1) minus inner (4 + 2u0)(6 + 2u0), times h
    want = h * ((4 + 2 * u1) * (6 + 2 * u1) - (4 + 2 * u0) * (6 + 2 * u0))
    man = _manifold(m)
    assert str(man.status()) == "Error.NoError"
    assert man.genus() == 1
    assert_allclose(man.volume(), want, rtol=1e-5)
    assert_allclose(signed_volume(m), want, rtol=1e-12)
    assert _directed_edges_unique(m)
    # outward: the extent reaches +u1 beyond the path, never +|u0|
    assert_allclose(m.extent[1, 0], 2 + u1)
    assert_allclose(m.extent[0, 2], -3 - u1)


def test_open_l_path_centred_band_is_width_times_length():
    # a band symmetric about the centre line: area = width × centre-line length, mitre or not
    sec = np.array([[-0.1, 0.0], [0.1, 0.0], [0.1, 1.0], [-0.1, 1.0]])
    path = np.array([[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [2.0, 0.0, 3.0]])
    m = sweep(sec, path, closed=False)
    man = _manifold(m)
    assert str(man.status()) == "Error.NoError" and man.genus() == 0
    assert_allclose(man.volume(), 0.2 * 5.0 * 1.0, rtol=1e-5)
    assert _directed_edges_unique(m)


def test_sloped_open_path_with_concave_section_is_closed():
    # an L-shaped (non-convex) section along a gable: caps need a real triangulation
    sec = np.array([[0, 0], [0.4, 0], [0.4, 0.1], [0.1, 0.1], [0.1, 0.5], [0, 0.5]], float)
    path = np.array([[-3.0, 0.0, 1.0], [0.0, 0.7, 1.0], [3.0, 0.0, 1.0]])
    m = sweep(sec, path, axis=(0, 0, 1), closed=False)
    man = _manifold(m)
    assert str(man.status()) == "Error.NoError"
    assert man.volume() > 0 and signed_volume(m) > 0


def test_uvs_are_metres_along_rows_and_section():
    sec = np.array([[0.0, 0.0], [0.2, 0.0], [0.2, 0.3], [0.0, 0.3]])
    m = sweep(sec, RECT, uv_scale=2.0)
    # the row at u = 0.2 runs round the rectangle grown by 0.2: perimeter 2·(4.4 + 6.4)
    assert_allclose(m.st.values[:, 0].max(), 2.0 * 2 * (4.4 + 6.4), rtol=1e-6)
    assert_allclose(m.st.values[:, 1].max(), 2.0 * 1.0, rtol=1e-6)  # section perimeter 1.0 m
    assert_allclose(np.linalg.norm(m.corner_normals(), axis=1), 1.0, atol=1e-6)


def test_box_normals_are_crisp_and_outward():
    sec = np.array([[0.0, 0.0], [0.2, 0.0], [0.2, 0.3], [0.0, 0.3]])
    m = sweep(sec, RECT)
    tri = m.triangles
    p = m.points[tri]
    fn = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    fn /= np.linalg.norm(fn, axis=1, keepdims=True)
    # each quad's corner normals equal its face normal (all section corners are 90°)
    corner = m.corner_normals().reshape(-1, 4, 3)
    quad_n = fn[0::2][: len(corner)]  # fan: two triangles per quad, the first one
    assert np.all(np.einsum("qkj,qj->qk", corner, quad_n) > 0.999)


def test_curved_section_is_smooth():
    t = np.linspace(0, np.pi / 2, 9)
    arc = np.stack([0.2 * np.sin(t), 0.2 - 0.2 * np.cos(t)], axis=1)
    sec = np.vstack([[[-0.1, 0.0]], arc, [[-0.1, 0.2]]])
    m = sweep(sec, RECT)
    # at an interior arc vertex the two quads share one normal: fewer distinct normals
    # than corners
    cn = m.corner_normals()
    assert len(np.unique(cn.round(5), axis=0)) < len(cn) / 3


@pytest.mark.parametrize(
    "path, err",
    [
        (np.array([[0, 0, 0], [1, 0, 0], [0, 0, 0.0]]), "turns back"),
        (np.array([[0, 0, 0], [1, 0.5, 0], [1, 0, 1.0]]), "plane"),
        (np.array([[0, 0, 0], [0, 0, 0], [1, 0, 1.0]]), "coincident"),
    ],
)
def test_bad_paths_raise(path, err):
    sec = np.array([[0.0, 0.0], [0.2, 0.0], [0.2, 0.3]])
    with pytest.raises(GeometryError, match=err):
        sweep(sec, path, closed=False)


def test_polygon_area_sign():
    sq = np.array([[0, 0], [1, 0], [1, 1], [0, 1.0]])
    assert polygon_area(sq) == 1.0 and polygon_area(sq[::-1]) == -1.0


@pytest.mark.parametrize("closed, bad, good", [(True, 2.5, 1.9), (False, 3.2, 2.5)])
def test_section_deeper_than_the_outline_is_refused(closed, bad, good):
    # closed 4 × 6 m rectangle: the 4 m sides vanish at 2 m inside; open U round the same
    # rectangle (u > 0 = cross(tangent, +Y) = outward): its 6 m middle vanishes at 3 m
    def sec(depth):
        return np.array([[-depth, 0.0], [0.1, 0.0], [0.1, 0.3], [-depth, 0.3]])

    path = RECT if closed else RECT[::-1]
    with pytest.raises(GeometryError, match="cut through itself|crosses itself"):
        sweep(sec(bad), path, closed=closed)
    ok = sweep(sec(good), path, closed=closed)
    assert signed_volume(ok) > 0
