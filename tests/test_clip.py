"""Plane clipping with caps (geometry.clip): watertightness, volumes, nested and touching cuts."""

from __future__ import annotations

import numpy as np
import pytest
from numpy.testing import assert_allclose
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from ionic_usd.errors import GeometryError
from ionic_usd.geometry import Mesh, boundary_edges, inspect_mesh, merge, revolve, weld
from ionic_usd.geometry.clip import clip_mesh
from ionic_usd.geometry.mesh import face_normals, smooth_normals

# -- fixtures -------------------------------------------------------------------------------
_CUBE_PTS = np.array([[x, y, z] for x in (0.0, 1.0) for y in (0.0, 1.0) for z in (0.0, 1.0)])
# quads wound counter-clockwise seen from outside; vertex index = 4x + 2y + z
_CUBE_QUADS = np.array(
    [
        [0, 1, 3, 2],
        [4, 6, 7, 5],  # x = 0, x = 1
        [0, 4, 5, 1],
        [2, 3, 7, 6],  # y = 0, y = 1
        [0, 2, 6, 4],
        [1, 5, 7, 3],  # z = 0, z = 1
    ]
)


def cube_quads(lo=(0.0, 0.0, 0.0), size=1.0) -> Mesh:
    return Mesh(
        _CUBE_PTS * size + np.asarray(lo), np.full(6, 4), _CUBE_QUADS.reshape(-1), name="cube"
    )


def cube_tris(lo=(0.0, 0.0, 0.0), size=1.0) -> Mesh:
    q = _CUBE_QUADS
    tri = np.concatenate([q[:, [0, 1, 2]], q[:, [0, 2, 3]]])
    return Mesh(_CUBE_PTS * size + np.asarray(lo), np.full(12, 3), tri.reshape(-1), name="cube")


def reversed_faces(m: Mesh) -> Mesh:
    return m.with_(face_vertex_indices=m.triangles[:, ::-1].reshape(-1))


def circle_profile(cx: float, cy: float, r: float, n: int) -> np.ndarray:
    """A closed (radius, height) circle traversed counter-clockwise, first node repeated."""
    a = np.linspace(0.0, 2 * np.pi, n + 1)
    return np.stack([cx + r * np.cos(a), cy + r * np.sin(a)], axis=1)


def revolve_closed(profile: np.ndarray, segments: int) -> Mesh:
    m, _ = revolve(profile, segments)
    return weld(m)  # the repeated first/last profile node leaves a seam


def sphere(radius: float, rows: int = 16, segments: int = 24) -> Mesh:
    a = np.linspace(-np.pi / 2, np.pi / 2, rows + 1)
    prof = np.stack([radius * np.cos(a), radius * np.sin(a)], axis=1)
    prof[[0, -1], 0] = 0.0
    return revolve(prof, segments)[0]


def polygon_area(n: int, r: float) -> float:
    return 0.5 * n * r * r * np.sin(2 * np.pi / n)


def check_closed(m: Mesh, *, watertight: bool = True) -> None:
    rep = inspect_mesh(m)
    assert rep.closed, rep
    assert rep.consistent, rep
    assert rep.unused_points == 0
    if watertight:
        assert rep.watertight, rep


def cap_area(m: Mesh, point, normal) -> float:
    """Area of the triangles lying in the plane and facing −normal."""
    n = np.asarray(normal, float) / np.linalg.norm(normal)
    fn, area = face_normals(m.points, m.triangles)
    d = np.abs((m.points[m.triangles] - np.asarray(point, float)) @ n).max(axis=1)
    sel = (d < 1e-9) & (fn @ n < -0.999)
    return float(area[sel].sum())


def border_loops(m: Mesh) -> int:
    """Number of connected components of the border edges (the cut loops if capping is off)."""
    e = boundary_edges(m)
    if len(e) == 0:
        return 0
    verts, inv = np.unique(e, return_inverse=True)
    inv = inv.reshape(-1, 2)
    g = coo_matrix((np.ones(len(inv)), (inv[:, 0], inv[:, 1])), shape=(len(verts),) * 2)
    return connected_components(g, directed=False)[0]


# -- the cube -------------------------------------------------------------------------------
@pytest.mark.parametrize("make", [cube_tris, cube_quads])
@pytest.mark.parametrize(
    ("point", "normal", "volume"),
    [
        ((0, 0, 0.5), (0, 0, 1), 0.5),
        ((0, 0, 0.25), (0, 0, -1), 0.25),
        ((0.3, 0, 0), (1, 0, 0), 0.7),
        ((0.5, 0.5, 0.5), (1, -1, 0), 0.5),  # through four cube vertices (on-plane vertices)
        ((0.5, 0.5, 0.5), (1, 1, 1), 0.5),  # a hexagonal section
        ((1, 0, 0), (1, 1, 0), 0.5),  # through the edges x + y = 1
        ((0.1, 0.1, 0.2), (1, 2, 3), 1 - 0.9**3 / 36),  # cuts off the corner at 0 (a tetrahedron)
    ],
)
def test_cube_cut_is_watertight_with_the_right_volume(make, point, normal, volume):
    out = clip_mesh(make(), point, normal)
    check_closed(out)
    assert_allclose(inspect_mesh(out).signed_volume, volume, rtol=1e-12, atol=1e-14)
    n = np.asarray(normal, float) / np.linalg.norm(normal)
    assert np.all((out.points - point) @ n >= -1e-12)
    assert np.all(out.face_vertex_counts == 3)
    assert out.st is None


def test_cube_half_has_a_unit_square_cap_and_only_new_edge_vertices():
    out = clip_mesh(cube_tris(), (0, 0, 0.5), (0, 0, 1), name="half")
    assert out.name == "half"
    assert_allclose(cap_area(out, (0, 0, 0.5), (0, 0, 1)), 1.0, rtol=1e-12)
    # 4 kept corners + one point on each of the 4 vertical cube edges and the 4 side diagonals
    assert out.n_points == 4 + 4 + 4
    on = np.isclose(out.points[:, 2], 0.5)
    assert on.sum() == 8


@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_both_halves_add_up_for_random_planes(rng, sign):
    ring, _ = revolve(np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 2.0], [0.0, 2.0]]), 40)
    total = inspect_mesh(ring).signed_volume
    for _ in range(10):
        p = rng.uniform([-0.5, 0.2, -0.5], [0.5, 1.8, 0.5])
        n = rng.normal(size=3) * sign
        a, b = clip_mesh(ring, p, n), clip_mesh(ring, p, -n)
        check_closed(a)
        check_closed(b)
        assert_allclose(
            inspect_mesh(a).signed_volume + inspect_mesh(b).signed_volume, total, rtol=1e-10
        )
        # both caps are the same section
        assert_allclose(cap_area(a, p, n), cap_area(b, p, -n), rtol=1e-10)


# -- plane misses, touches or removes everything -------------------------------------------
def test_plane_missing_the_mesh_returns_it_unchanged():
    cube = cube_quads()
    out = clip_mesh(cube, (0, 0, -5), (0, 0, 1), name="kept")
    assert out.name == "kept"
    np.testing.assert_array_equal(out.face_vertex_counts, cube.face_vertex_counts)
    np.testing.assert_array_equal(out.points, cube.points)
    # the plane of the bottom face: the face bounds the kept solid, so everything stays
    assert clip_mesh(cube, (0, 0, 0), (0, 0, 1)) is cube


@pytest.mark.parametrize(
    ("point", "normal"),
    [((0, 0, 5), (0, 0, 1)), ((0, 0, 1), (0, 0, 1)), ((0, 0, 0), (0, 0, -1))],
)
def test_nothing_left_raises(point, normal):
    # the last two leave only a face in the plane that faces the kept side: no solid
    with pytest.raises(GeometryError, match="nothing is left"):
        clip_mesh(cube_tris(), point, normal)


@pytest.mark.parametrize("normal", [(0, 0, 0), (np.nan, 0, 1)])
def test_bad_plane_raises(normal):
    with pytest.raises(GeometryError):
        clip_mesh(cube_tris(), (0, 0, 0.5), normal)


def test_open_mesh_with_cap_raises_but_clips_without():
    tri = cube_tris().triangles
    # drop the triangle (0,0,0), (0,1,1), (0,1,0) of the side x = 0, which the plane crosses
    assert_allclose(cube_tris().points[tri[6]][:, 2], [0.0, 1.0, 0.0])
    open_box = Mesh(_CUBE_PTS, np.full(11, 3), np.delete(tri, 6, axis=0).reshape(-1))
    with pytest.raises(GeometryError, match="not closed"):
        clip_mesh(open_box, (0, 0, 0.5), (0, 0, 1))
    out = clip_mesh(open_box, (0, 0, 0.5), (0, 0, 1), cap=False)
    assert inspect_mesh(out).consistent
    assert out.n_triangles > 0


# -- revolved solids ------------------------------------------------------------------------
@pytest.mark.parametrize("segments", [8, 32, 33])
def test_cylinder_cut_through_the_axis(segments):
    cyl, _ = revolve(np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 2.0], [0.0, 2.0]]), segments)
    out = clip_mesh(cyl, (0, 0, 0), (0, 0, 1))
    check_closed(out)
    full = polygon_area(segments, 1.0) * 2.0
    assert_allclose(inspect_mesh(cyl).signed_volume, full, rtol=1e-12)
    assert_allclose(inspect_mesh(out).signed_volume, full / 2, rtol=1e-12)
    # the cap is the 2 × 2 axial section (the polygon reaches radius 1 at angle 0 and π
    # when segments is even; for odd counts the far side is a chord)
    width = 1.0 + (1.0 if segments % 2 == 0 else np.cos(np.pi / segments))
    assert_allclose(cap_area(out, (0, 0, 0), (0, 0, 1)), 2.0 * width, rtol=1e-12)
    assert np.all(out.points[:, 2] >= 0.0)


def test_cut_through_vertices_adds_no_vertices():
    # the vertices at angle π have z = −sin(π)·r ≈ −1e-16: they must snap onto the plane,
    # not spawn slivers; no edge crosses the plane, so no new points either
    cyl, _ = revolve(np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 2.0], [0.0, 2.0]]), 32)
    out = clip_mesh(cyl, (0, 0, 0), (0, 0, 1))
    assert out.n_points == 2 * 17 + 2
    assert inspect_mesh(out).degenerate_faces == 0


def test_torus_cut_through_the_axis_gives_two_loops():
    torus = revolve_closed(circle_profile(2.0, 0.0, 0.5, 24), 48)
    check_closed(torus)
    open_half = clip_mesh(torus, (0, 0, 0), (0, 0, 1), cap=False)
    assert border_loops(open_half) == 2
    out = clip_mesh(torus, (0, 0, 0), (0, 0, 1))
    check_closed(out)
    assert_allclose(
        inspect_mesh(out).signed_volume, inspect_mesh(torus).signed_volume / 2, rtol=1e-12
    )
    assert_allclose(cap_area(out, (0, 0, 0), (0, 0, 1)), 2 * polygon_area(24, 0.5), rtol=1e-12)


def test_tube_cut_across_the_axis_gives_a_ring_shaped_cap():
    r0, r1, h, seg = 0.5, 1.0, 2.0, 36
    # (radius, height) section traversed counter-clockwise: outer side up, top inward, ...
    tube = revolve_closed(np.array([[r1, 0.0], [r1, h], [r0, h], [r0, 0.0], [r1, 0.0]]), seg)
    check_closed(tube)
    p, n = (0, 0.7, 0), (0, 1, 0)
    open_part = clip_mesh(tube, p, n, cap=False)
    assert border_loops(open_part) == 2
    out = clip_mesh(tube, p, n)
    check_closed(out)
    ring = polygon_area(seg, r1) - polygon_area(seg, r0)
    assert_allclose(cap_area(out, p, n), ring, rtol=1e-12)  # the hole is not filled
    assert_allclose(inspect_mesh(out).signed_volume, ring * (h - 0.7), rtol=1e-12)


def test_hollow_ball_hole_comes_from_another_shell():
    # the inner sphere is a separate, inward-facing shell: its loop is a hole in the outer one
    outer, inner = sphere(1.0), reversed_faces(sphere(0.6))
    ball = merge([outer, inner])
    out = clip_mesh(ball, (0, 0, 0), (0, 1, 0))
    check_closed(out)
    assert_allclose(
        inspect_mesh(out).signed_volume, inspect_mesh(ball).signed_volume / 2, rtol=1e-12
    )
    assert_allclose(
        cap_area(out, (0, 0, 0), (0, 1, 0)),
        polygon_area(24, 1.0) - polygon_area(24, 0.6),
        rtol=1e-12,
    )


def test_overlapping_shells_are_capped_each_on_its_own():
    # the two squares of the section cross each other; each shell must stay closed
    both = merge([cube_tris(), cube_tris((0.5, 0.5, 0.0))])
    out = clip_mesh(both, (0, 0, 0.5), (0, 0, 1))
    check_closed(out)
    assert_allclose(inspect_mesh(out).signed_volume, 1.0, rtol=1e-12)
    assert_allclose(cap_area(out, (0, 0, 0.5), (0, 0, 1)), 2.0, rtol=1e-12)


def test_sections_touching_at_a_vertex():
    # two cubes sharing the vertex 0 (welded); the plane x = y cuts both through that vertex,
    # so the section is two rectangles touching at a corner
    bow = weld(merge([cube_tris(), cube_tris((-1.0, -1.0, -1.0))]))
    assert bow.n_points == 15
    out = clip_mesh(bow, (0, 0, 0), (1, -1, 0))
    check_closed(out)
    assert_allclose(inspect_mesh(out).signed_volume, 1.0, rtol=1e-12)
    assert_allclose(cap_area(out, (0, 0, 0), (1, -1, 0)), 2 * np.sqrt(2), rtol=1e-12)


# -- normals --------------------------------------------------------------------------------
def test_normals_interpolate_on_the_surface_and_face_out_on_the_cap():
    ball = smooth_normals(sphere(1.0, rows=24, segments=48))
    p, n = (0.1, 0.2, 0.0), np.array([0.3, 1.0, -0.2]) / np.linalg.norm([0.3, 1.0, -0.2])
    out = clip_mesh(ball, p, n)
    check_closed(out)
    assert out.normals.one_per_corner
    out_n = out.corner_normals()
    assert_allclose(np.linalg.norm(out_n, axis=1), 1.0, atol=1e-6)
    corner_pts = out.points[out.face_vertex_indices]
    fn, _ = face_normals(out.points, out.triangles)
    on_cap = np.repeat(fn @ n < -0.999999, 3)
    assert on_cap.any()
    assert_allclose(out_n[on_cap], np.broadcast_to(-n, (on_cap.sum(), 3)), atol=1e-6)
    # a smooth sphere's normals stay close to radial, including the interpolated ones
    radial = corner_pts[~on_cap] / np.linalg.norm(corner_pts[~on_cap], axis=1, keepdims=True)
    assert np.min(np.einsum("ij,ij->i", out_n[~on_cap], radial)) > 0.995


def test_no_normals_in_gives_no_normals_out():
    out = clip_mesh(cube_tris(), (0, 0, 0.5), (0, 0, 1))
    assert out.normals is None


# -- column parts -----------------------------------------------------------------------------
@pytest.fixture(scope="module")
def shaft():
    from ionic_usd.column.shaft import ShaftParams, build_shaft

    return build_shaft(ShaftParams(flute_slices=4))


def test_half_shaft_is_watertight_and_half_the_volume(shaft):
    out = clip_mesh(shaft, (0, 0, 0), (0, 0, 1))
    check_closed(out)
    # the shaft's points are mirror-symmetric about z = 0 (a flute axis lies at angle 0) but
    # its quad diagonals are not, which shifts the halves' volumes by ~1e-9 of the whole
    assert_allclose(
        inspect_mesh(out).signed_volume, inspect_mesh(shaft).signed_volume / 2, rtol=1e-7
    )
    assert out.points[:, 2].min() >= 0.0


def test_engaged_shaft_keeps_more_than_half(shaft):
    r = 0.475
    p, n = (0, 0, -0.2 * r), (0, 0, 1)
    front, back = clip_mesh(shaft, p, n), clip_mesh(shaft, p, (0, 0, -1))
    check_closed(front)
    check_closed(back)
    v, vf, vb = (inspect_mesh(m).signed_volume for m in (shaft, front, back))
    assert vf > v / 2
    assert_allclose(vf + vb, v, rtol=1e-10)


@pytest.mark.parametrize(
    ("point", "normal"),
    [((0, 0, 0), (0, 0, 1)), ((0, 0.1, 0), (0, 1, 0)), ((0.05, 0, 0), (1, 0, 0.3))],
)
def test_base_and_capital_stay_closed(point, normal):
    from ionic_usd.column.base import build_base
    from ionic_usd.column.capital import CapitalParams, capital_mesh

    for m in (build_base(), capital_mesh(CapitalParams(), top_radius=0.407)):
        out = clip_mesh(m, point, normal)
        rep = inspect_mesh(out)
        assert rep.closed and rep.consistent, (m.name, rep)
        assert rep.signed_volume > 0


def test_polygon_triangles_index_the_rings_and_need_no_scipy():
    """A square with a square hole: 8 triangles (n + 2h - 2), every corner a ring point,
    area outer - hole; the exact coordinate lookup needs no k-d tree."""
    import subprocess
    import sys

    code = """
import sys
class Block:
    def find_spec(self, name, path=None, target=None):
        if name.split('.')[0] == 'scipy':
            raise ImportError('blocked')
sys.meta_path.insert(0, Block())
import numpy as np
from ionic_usd.geometry.polygon import polygon_triangles
outer = np.array([[0, 0], [4, 0], [4, 4], [0, 4]], float)
hole = np.array([[1, 1], [1, 3], [3, 3], [3, 1]], float)
t = polygon_triangles(outer, [hole])
xy = np.concatenate([outer, hole])
p = xy[t]
area = np.abs(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])).sum() / 2
assert t.shape == (8, 3) and t.min() >= 0 and t.max() < 8, t
assert abs(area - 12.0) < 1e-12, area
assert len({tuple(sorted(r)) for r in t.tolist()}) == 8
print('ok')
"""
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert out.returncode == 0 and out.stdout.strip() == "ok", out.stderr[-2000:]


# -- the corner notch (geometry.notch) ---------------------------------------------------------
def _boolean_notch_volume(m: Mesh, x0: float, z0: float) -> float:
    """Reference: manifold3d's volume of ``m`` minus the quadrant block x < x0, z < z0."""
    from ionic_usd.geometry.boolean import difference
    from ionic_usd.geometry.check import solid_report

    big = 10.0
    block = cube_tris((-big, -big, -big), 1.0)
    block = block.with_(
        points=np.array([[x, y, z] for x in (-big, x0) for y in (-big, big) for z in (-big, z0)])
    )
    return solid_report(difference(m, [block]), intersections=False).volume


def _notch_checks(m: Mesh) -> None:
    from ionic_usd.geometry.check import solid_report

    check_closed(m)
    r = solid_report(m)
    assert r.shells == 1 and r.self_intersections == 0, r


@pytest.mark.parametrize("make", [cube_tris, cube_quads])
def test_notch_of_a_cube_keeps_the_rest_and_caps_both_walls(make):
    from ionic_usd.geometry.check import solid_report
    from ionic_usd.geometry.notch import cut_quadrant

    m = make()
    out = cut_quadrant(smooth_normals(m) if make is cube_tris else m, 0.4, 0.7)
    _notch_checks(out)
    assert solid_report(out).volume == pytest.approx(1.0 - 0.4 * 0.7, abs=1e-12)
    # the two caps: z = 0.7 over x < 0.4 (facing -z), x = 0.4 under z = 0.7 (facing -x)
    assert cap_area(out, (0, 0, 0.7), (0, 0, 1)) == pytest.approx(0.4, abs=1e-12)
    assert cap_area(out, (0.4, 0, 0), (1, 0, 0)) == pytest.approx(0.7, abs=1e-12)
    # the caps' authored normals are their face normals
    q = out.points[out.triangles]
    cap = np.all(q[:, :, 2] == 0.7, axis=1) | np.all(q[:, :, 0] == 0.4, axis=1)
    assert cap.sum() >= 4
    if make is cube_tris:
        fn, _ = face_normals(out.points, out.triangles)
        cn = out.corner_normals().reshape(-1, 3, 3)
        assert np.all(np.einsum("tkj,tj->tk", cn[cap], fn[cap]) > 1 - 1e-9)


@pytest.mark.parametrize("seed", range(6))
def test_notch_of_a_sphere_is_the_boolean_difference(seed):
    """A faceted sphere at a random place, cut by random walls: the notch's volume is
    manifold3d's difference's, the result one closed shell without self-intersections."""
    from ionic_usd.geometry.check import solid_report
    from ionic_usd.geometry.notch import cut_quadrant

    rng = np.random.default_rng(seed)
    s = sphere(1.0, rows=12 + seed, segments=20 + 3 * seed)
    s = s.with_(points=s.points + rng.uniform(-0.3, 0.3, 3))
    x0, z0 = rng.uniform(-0.5, 0.5, 2)
    out = cut_quadrant(s, x0, z0)
    _notch_checks(out)
    assert solid_report(out).volume == pytest.approx(_boolean_notch_volume(s, x0, z0), rel=1e-9)
    assert np.all(np.isfinite(out.points))


def test_notch_carries_st_by_chart_and_charts_the_caps():
    """An analytic-st base cut at the corner: every split triangle keeps its input's st map
    (its stretch), the caps are isometric (stretch 1), no chart is joined to another."""
    from ionic_usd.column.base import build_base
    from ionic_usd.column.column import portunus_column_params
    from ionic_usd.geometry.mesh import chart_labels
    from ionic_usd.geometry.notch import cut_quadrant
    from ionic_usd.texture.atlas import st_distortion

    b = build_base(portunus_column_params(lod="low").base_params())
    assert b.st is not None
    out = cut_quadrant(b, -0.05, -0.05)
    _notch_checks(out)
    smax_in = st_distortion(b)[0].max()
    s_out = st_distortion(out)[0]
    assert s_out.max() <= smax_in * (1 + 1e-6)
    caps = np.abs(out.points[out.triangles][:, :, [0, 2]] + 0.05).max(axis=1).min(axis=1) < 1e-12
    assert caps.any()
    assert_allclose(s_out[caps], 1.0, atol=1e-3)  # st is float32: thin triangles round
    n_in = chart_labels(b.st.indices, len(b.st.values)).max() + 1
    n_out = chart_labels(out.st.indices, len(out.st.values)).max() + 1
    assert n_out >= n_in  # cuts may split charts and add cap charts, never join two


def test_notch_outside_the_quadrant_and_of_everything():
    from ionic_usd.geometry.notch import cut_quadrant

    m = cube_tris((0.0, 0.0, 0.0))
    assert cut_quadrant(m, 0.0, 0.5) is m  # x >= 0 everywhere: nothing in the quadrant
    with pytest.raises(GeometryError, match="nothing"):
        cut_quadrant(m, 2.0, 2.0)


def test_corner_form_falls_back_to_the_boolean_on_the_corner_line():
    """A box whose top face lies in the wall plane z = -0.05: the notch's outline would run
    along the corner line (refused), and the corner form is cut by the boolean instead."""
    from ionic_usd.geometry.check import solid_report
    from ionic_usd.geometry.notch import cut_quadrant
    from ionic_usd.pipeline.forms import form_cut

    box = cube_tris().with_(
        points=np.array([[x, y, z] for x in (-1.0, 1.0) for y in (0.0, 1.0) for z in (-1.0, -0.05)])
    )
    with pytest.raises(GeometryError, match="corner line"):
        cut_quadrant(box, -0.05, -0.05)
    out = form_cut(box, "corner", "Shaft")
    _notch_checks(out)
    assert solid_report(out).volume == pytest.approx(1.05 * 0.95, abs=1e-9)
