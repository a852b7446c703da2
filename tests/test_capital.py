"""Tests for the Ionic capital: parts, extents, layout, scroll bodies, validation."""

from __future__ import annotations

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose

from ionic_usd.column.capital import (
    CapitalParams,
    bolster_profile,
    build_capital,
    capital_height,
    capital_layout,
    capital_mesh,
)
from ionic_usd.column.capital_body import seat_depth
from ionic_usd.column.volute import VoluteParams, volute_extent
from ionic_usd.errors import GrammarError, ParameterError
from ionic_usd.geometry.analysis import inspect_mesh
from ionic_usd.geometry.mesh import face_normals

C = 0.475 * 6 / 7  # the default shaft's top radius
D = 0.95
PART = D / 18


@pytest.fixture(scope="module")
def parts():
    return build_capital(CapitalParams(), top_radius=C)


def _split_shells(m):
    """Connected components of a triangle mesh (by shared vertices)."""
    tri = m.triangles
    parent = np.arange(m.n_points)

    def find(i):
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    for a, b, c in tri:
        for u, v in ((a, b), (b, c)):
            ru, rv = find(u), find(v)
            if ru != rv:
                parent[ru] = rv
    roots = np.array([find(i) for i in tri[:, 0]])
    return [tri[roots == r] for r in np.unique(roots)]


@pytest.mark.parametrize(
    "name",
    [
        "abacus",
        "echinus",
        "volute_front_right",
        "volute_front_left",
        "volute_rear_right",
        "volute_rear_left",
        "canalis_front",
        "canalis_rear",
        "bolster_right",
        "bolster_left",
    ],
)
def test_every_part_is_watertight(parts, name):
    m = parts.as_dict()[name]
    r = inspect_mesh(m)
    assert r.closed and r.consistent and r.watertight, r
    assert r.degenerate_faces == 0 and r.unused_points == 0
    # every shell on its own encloses positive volume (no inside-out shell hidden in a sum)
    for shell in _split_shells(m):
        p = m.points[shell]
        c = p.reshape(-1, 3).mean(axis=0)
        vol = np.einsum("ij,ij->i", p[:, 0] - c, np.cross(p[:, 1] - c, p[:, 2] - c)).sum() / 6
        assert vol > 0
    # corner normals: unit length and on the outer side of their face
    fn, _ = face_normals(m.points, m.triangles)
    cn = m.corner_normals().reshape(-1, 3, 3)
    assert_allclose(np.linalg.norm(cn, axis=2), 1.0, atol=1e-5)
    assert np.all(np.einsum("ij,ikj->ik", fn, cn) > 0.2)


def test_abacus_box_equals_its_parameters(parts):
    p = CapitalParams()
    ext = parts.abacus.extent
    top = capital_height(p)
    assert_allclose(
        ext,
        [
            [-p.abacus_length / 2, top - p.abacus_height, -p.abacus_width / 2],
            [p.abacus_length / 2, top, p.abacus_width / 2],
        ],
        atol=1e-12,
    )
    assert inspect_mesh(parts.abacus).signed_volume == pytest.approx(
        p.abacus_length * p.abacus_width * p.abacus_height
    )


@pytest.mark.parametrize("length, width", [(1.2656, 0.95), (1.0, 0.8), (1.6, 1.3)])
def test_capital_length_and_width_are_the_volute_extents(length, width):
    p = CapitalParams(capital_length=length, capital_width=width, spiral_margin=0.1)
    parts = build_capital(p, top_radius=C)
    pts = np.concatenate([m.points for m in parts.volutes])
    assert pts[:, 0].min() == pytest.approx(-length / 2, abs=1e-9)
    assert pts[:, 0].max() == pytest.approx(length / 2, abs=1e-9)
    assert pts[:, 2].min() == pytest.approx(-width / 2, abs=1e-12)
    assert pts[:, 2].max() == pytest.approx(width / 2, abs=1e-12)
    # nothing but the abacus and echinus reaches beyond the volutes along Z
    body = np.concatenate([m.points for m in (*parts.canales, *parts.bolsters)])
    assert np.abs(body[:, 2]).max() <= width / 2


def test_vitruvian_layout(parts):
    """Eye ½ part above the shaft top, volutes hanging 3 parts below it, abacus 1½ parts
    thick on top of the 8-part volute, eyes on the cathetus 1½ parts inside the abacus."""
    p = CapitalParams()
    lay = capital_layout(p)
    assert lay.eye_y == pytest.approx(0.5 * PART)
    vol = parts.volutes[0]
    assert vol.extent[0, 1] == pytest.approx(-3 * PART, rel=1e-2)
    assert lay.abacus_y == pytest.approx(5 * PART)
    assert capital_height(p) == pytest.approx(6.5 * PART)
    assert lay.eye_x == pytest.approx(p.abacus_length / 2 - 1.5 * PART, abs=1e-4)
    # the volutes' top is the abacus bottom: the spiral band reaches it, only the margin's far
    # end (inside the abacus) rises a seat above it
    assert vol.extent[1, 1] == pytest.approx(lay.abacus_y + seat_depth(p))
    above = vol.points[vol.points[:, 1] > lay.abacus_y + 1e-9]
    assert len(above) and np.all(above[:, 0] < lay.eye_x - lay.margin + 1e-9)


def test_left_right_front_rear_are_mirrors(parts):
    fr, fl, rr, rl = parts.volutes
    assert_allclose(fl.points * [-1, 1, 1], fr.points)
    assert_allclose(rr.points * [1, 1, -1], fr.points)
    assert_allclose(rl.points * [-1, 1, -1], fr.points)
    for m in parts.volutes:
        assert inspect_mesh(m).signed_volume == pytest.approx(inspect_mesh(fr).signed_volume)


def test_echinus_radii(parts):
    p = CapitalParams()
    pts = parts.echinus.points
    r = np.hypot(pts[:, 0], pts[:, 2])
    bottom = np.isclose(pts[:, 1], 0.0)
    top = np.isclose(pts[:, 1], p.echinus_height)
    assert r[bottom].max() == pytest.approx(C)
    assert r[top].max() == pytest.approx(C + p.echinus_projection)
    assert pts[:, 1].min() == 0 and pts[:, 1].max() == pytest.approx(p.echinus_height)
    # convex ovolo: every profile point lies outside the straight chord
    side = r > 1e-9
    t = pts[side, 1] / p.echinus_height
    assert np.all(r[side] >= C + p.echinus_projection * t - 1e-12)


@pytest.mark.parametrize(
    "scroll", ["S1", "S2", "R0.5 P0, R1 P0.5, R0.5 P1", "R0.7 P0.2, R0.9 P0.2, R0.7 P0.8"]
)
def test_bolster_rings_follow_the_grammar(scroll):
    p = CapitalParams(scroll=scroll)
    lay = capital_layout(p)
    parts = build_capital(p, top_radius=C)
    br = parts.bolsters[0]
    assert inspect_mesh(br).watertight
    pts = br.points
    # axis along Z through the eye; front (p = 0) at the back of the front volute disc, each
    # end carried a seat on into its disc (a cylinder of the end ring's radius)
    seat = seat_depth(p)
    assert pts[:, 2].max() == pytest.approx(lay.back_z + seat)
    assert pts[:, 2].min() == pytest.approx(-lay.back_z - seat)
    for end in (1.0, -1.0):
        tip = np.abs(pts[:, 2] - end * (lay.back_z + seat)) < 1e-12
        ring = np.abs(pts[:, 2] - end * lay.back_z) < 1e-12
        r_tip = np.hypot(pts[tip, 0] - lay.eye_x, pts[tip, 1] - lay.eye_y).max()
        r_ring = np.hypot(pts[ring, 0] - lay.eye_x, pts[ring, 1] - lay.eye_y).max()
        assert r_tip == pytest.approx(r_ring, abs=1e-12)
    pts = pts[np.abs(pts[:, 2]) <= lay.back_z + 1e-12]
    dist = np.hypot(pts[:, 0] - lay.eye_x, pts[:, 1] - lay.eye_y)
    pos = (lay.back_z - pts[:, 2]) / (2 * lay.back_z)
    for ring in p.scroll_grammar.rings:
        at = np.isclose(pos, ring.position)
        want = ring.radius * lay.total_radius
        assert np.any(np.isclose(dist[at], want, atol=1e-9)), (ring, dist[at].max())
    # the loft never leaves the range of the ring radii (monotone interpolation)
    radii = np.array(p.scroll_grammar.radii) * lay.total_radius
    assert dist.max() <= radii.max() + 1e-9
    side = dist > 1e-9
    inner = (pos > 1e-9) & (pos < 1 - 1e-9) & side
    assert dist[inner].min() >= radii.min() - 1e-9


def test_bolster_profile_is_held_to_the_volutes():
    p = CapitalParams(scroll="S1")
    prof = bolster_profile(p, 2.0, 1.0)
    assert tuple(prof[0]) == (0.0, 0.0) and tuple(prof[-1]) == (0.0, 2.0)
    assert tuple(prof[1]) == (0.7, 0.0)  # the first ring's radius held to p = 0
    assert tuple(prof[-2]) == (0.7, 2.0)
    assert np.all(np.diff(prof[:, 1]) >= 0)


def test_lod_changes_triangle_count():
    lo = capital_mesh(
        CapitalParams(spiral_samples=64, ring_segments=16, bolster_rows=8), top_radius=C
    )
    hi = capital_mesh(
        CapitalParams(spiral_samples=384, ring_segments=96, bolster_rows=64), top_radius=C
    )
    assert hi.n_triangles > 4 * lo.n_triangles
    assert inspect_mesh(hi).closed and inspect_mesh(hi).consistent


@pytest.mark.parametrize("dy", [-0.05, 0.0, 0.1])
def test_capital_position_lifts_everything(dy):
    base = build_capital(CapitalParams(), top_radius=C).merged()
    moved = build_capital(CapitalParams(capital_position_y=dy), top_radius=C).merged()
    assert_allclose(moved.points, base.points + [0, dy, 0], atol=1e-12)
    assert capital_height(CapitalParams(capital_position_y=dy)) == pytest.approx(moved.extent[1, 1])


def test_scroll_position_moves_scrolls_and_abacus():
    p = CapitalParams(scroll_position_y=0.1)
    lay = capital_layout(p)
    ext = volute_extent(p.volute)
    assert lay.abacus_y == pytest.approx(0.1 + ext[1, 1])
    parts = build_capital(p, top_radius=C)
    assert parts.abacus.extent[0, 1] == pytest.approx(lay.abacus_y)
    assert parts.echinus.extent[1, 1] == pytest.approx(p.echinus_height)


def test_spiral_margin_is_cut_at_the_centre():
    near = build_capital(CapitalParams(spiral_margin=0.05), top_radius=C).volutes[0]
    far = build_capital(CapitalParams(spiral_margin=5.0), top_radius=C).volutes[0]
    lay = capital_layout(CapitalParams())
    assert near.extent[0, 0] > 0.2
    # meets its mirror image at x = 0, and overlaps it by a seat (no touching end faces)
    assert far.extent[0, 0] == pytest.approx(-seat_depth(CapitalParams()), abs=1e-9)
    top = near.points[:, 1] > lay.abacus_y - 1e-3
    assert near.points[top, 0].min() == pytest.approx(lay.eye_x - 0.05, abs=1e-9)


@pytest.mark.parametrize(
    "kwargs, name",
    [
        (dict(capital_length=0.5), "capital_length"),
        (dict(capital_width=0.08), "capital_width"),
        (dict(abacus_height=0.0), "abacus_height"),
        (dict(echinus_projection=-0.1), "echinus_projection"),
        (dict(spiral_margin=-1.0), "spiral_margin"),
        (dict(spiral_samples=4), "spiral_samples"),
        (dict(ring_segments=2.5), "ring_segments"),
        (dict(capital_position_y=-2.0), "capital_position_y"),
        (dict(relief_depth=float("inf")), "relief_depth"),
        (dict(volute="S1"), "volute"),
    ],
)
def test_parameter_errors(kwargs, name):
    with pytest.raises(ParameterError) as exc:
        CapitalParams(**kwargs)
    assert exc.value.name == name


def test_scroll_errors():
    with pytest.raises(ParameterError):
        CapitalParams(scroll=3)
    with pytest.raises(GrammarError) as exc:
        CapitalParams(scroll="R0.7 P0.5, R0.7 P0.2")
    assert exc.value.grammar == "scroll"
    with pytest.raises(ParameterError):
        build_capital(CapitalParams(), top_radius=0.0)


def test_custom_volute():
    v = VoluteParams(capital_spiral_radius=0.3, capital_circle_radius=0.035)
    p = CapitalParams(volute=v, capital_length=1.6)
    parts = build_capital(p, top_radius=C)
    assert all(inspect_mesh(m).watertight for m in parts.volutes)
    assert capital_layout(p).total_radius == pytest.approx(0.3)
    assert math.isclose(parts.merged().extent[1, 0], 0.8, abs_tol=1e-9)


# -- the angle capital ----------------------------------------------------------------------------
#: the smallest triangle angle every capital family keeps after the sliver clean-up (degrees;
#: before it the united capitals had 0.0003° and the engaged angle capitals 0.0000°)
MIN_ANGLE_BOUND = 0.02


def _first_hits(mesh, origins, direction):
    """Distance along ``direction`` to the first triangle each ray meets (inf for a miss)."""
    p = mesh.points[mesh.triangles]
    e1, e2 = p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]
    d = np.asarray(direction, dtype=float) / np.linalg.norm(direction)
    h = np.cross(d, e2)
    a = np.einsum("ij,ij->i", e1, h)
    ok = np.abs(a) > 1e-14
    f = np.where(ok, 1.0 / np.where(ok, a, 1.0), 0.0)
    out = []
    for o in np.asarray(origins, dtype=float):
        s = o - p[:, 0]
        u = f * np.einsum("ij,ij->i", s, h)
        q = np.cross(s, e1)
        v = f * (q @ d)
        t = f * np.einsum("ij,ij->i", e2, q)
        hit = ok & (u >= 0) & (v >= 0) & (u + v <= 1) & (t > 0)
        out.append(t[hit].min() if hit.any() else np.inf)
    return np.array(out)


def _volute_face_runs(mesh, origins, direction, plane, depth):
    """Along a row of rays, how often the first hit switches between the band's face
    (``plane``) and the channel floor (``plane − depth``): a volute face shows its turns."""
    d = np.asarray(direction, dtype=float) / np.linalg.norm(direction)
    t = _first_hits(mesh, origins, d)
    level = np.asarray(origins) @ d + t  # how far along d each hit lies
    band = np.isclose(level, -plane, atol=1e-6)
    floor = np.isclose(level, -(plane - depth), atol=1e-6)
    on = band | floor
    kinds = band[on].astype(int)
    return int(on.sum()), int(np.count_nonzero(np.diff(kinds)))


@pytest.mark.parametrize("scroll", ["S1", "S2", "R1.0 P0.05, R0.8 P0.5, R1.0 P0.95"])
def test_the_volute_face_covers_the_bolsters_end(scroll):
    """Rays from the front, inside the bolster's end circle about the eye, meet the band's
    face or the channel floor, never the bolster's end a slab further back: where the roll is
    wider than the spiral's outer turn (below and inside it, 0.7 of the volute's radius for
    S1), its end is the volute's face (it was a crescent 45 mm deep on the default capital)."""
    from ionic_usd.column.capital_body import rim_radius

    p = CapitalParams(scroll=scroll, spiral_samples=96, ring_segments=24, bolster_rows=16)
    m = capital_mesh(p, top_radius=C)
    lay = capital_layout(p)
    r = rim_radius(p, lay)
    assert r == pytest.approx(p.scroll_grammar.rings[0].radius * lay.total_radius)
    rng = np.random.default_rng(3)
    a, q = rng.uniform(0, 2 * np.pi, 300), 0.97 * r * np.sqrt(rng.uniform(0, 1, 300))
    x = lay.eye_x + q * np.cos(a)
    y = lay.eye_y + p.capital_position_y + q * np.sin(a)
    origins = np.stack([x, y, np.full_like(x, 2.0)], axis=1)
    z = 2.0 - _first_hits(m, origins, (0.0, 0.0, -1.0))
    floor = lay.face_z - p.relief_depth
    assert np.all(np.isfinite(z))
    assert z.min() >= floor - 1e-6, (z.min(), floor)
    # and both levels are met: the band's face and the floor between its turns
    assert np.isclose(z, lay.face_z, atol=1e-6).any() and np.isclose(z, floor, atol=1e-6).any()


@pytest.fixture(scope="module")
def angle_low():
    p = CapitalParams(spiral_samples=96, ring_segments=24, bolster_rows=16)
    return p, capital_mesh(p, top_radius=C, angle=True), capital_mesh(p, top_radius=C)


def test_angle_capital_is_one_clean_solid(angle_low):
    from ionic_usd.geometry.check import manifold_status, solid_report

    _, m, _ = angle_low
    r = solid_report(m)
    assert r.shells == 1 and r.open_edges == 0 and r.nonmanifold_edges == 0, r
    assert r.self_intersections == 0 and r.colocated_points == 0, r
    assert r.against_normals == 0 and r.volume > 0, r
    assert r.min_angle > MIN_ANGLE_BOUND, r
    assert manifold_status(m)[0] == "NoError"


def test_angle_capital_shows_a_volute_on_both_outer_faces(angle_low):
    """Rows of rays through the eye height hit the band's face and the channel floor in turn
    on +Z (front-left volute) and on +X (the side volute, at z = −eye_x); the normal capital
    shows a bolster there instead."""
    p, angle, normal = angle_low
    lay = capital_layout(p)
    y = lay.eye_y + 0.3 * lay.total_radius
    span = np.linspace(-0.95, 0.95, 161) * lay.total_radius
    front = np.stack([-lay.eye_x + span, np.full_like(span, y), np.full_like(span, 2.0)], 1)
    side = np.stack([np.full_like(span, 2.0), np.full_like(span, y), -lay.eye_x + span], 1)
    n, switches = _volute_face_runs(angle, front, (0, 0, -1), lay.face_z, p.relief_depth)
    assert n > 100 and switches >= 6, (n, switches)
    n, switches = _volute_face_runs(angle, side, (-1, 0, 0), lay.face_z, p.relief_depth)
    assert n > 100 and switches >= 6, (n, switches)
    # the normal capital's +X side is a bolster: no band or channel floor there
    n, _ = _volute_face_runs(normal, side, (-1, 0, 0), lay.face_z, p.relief_depth)
    assert n < 10


def test_angle_capital_corner_volute_lies_on_the_diagonal(angle_low):
    """The corner volute's eye is on the outer diagonal x = z, and rays along the diagonal
    meet its band face and channel floor in turn across its whole width."""
    from ionic_usd.column.angle_capital import corner_eye

    p, angle, normal = angle_low
    lay = capital_layout(p)
    eye = corner_eye(p)
    assert eye[0] == eye[2] > lay.face_z
    u = np.array([1.0, 0.0, 1.0]) / math.sqrt(2)
    v = np.array([1.0, 0.0, -1.0]) / math.sqrt(2)
    span = np.linspace(-0.95, 0.95, 161) * lay.total_radius
    y = eye[1] - 0.3 * lay.total_radius
    origins = eye + np.outer(span, v) + 2.0 * u
    origins[:, 1] = y
    plane = float(eye @ u)
    n, switches = _volute_face_runs(angle, origins, -u, plane, p.relief_depth)
    assert n > 100 and switches >= 6, (n, switches)
    n, _ = _volute_face_runs(normal, origins, -u, plane, p.relief_depth)
    assert n == 0
    # seen from the diagonal the corner volute stands in front of everything else: the
    # abacus corner (the farthest part of the normal capital there) lies behind its face
    assert plane > math.sqrt(2) * lay.face_z


def test_angle_capital_inner_faces_are_mitred_bolsters(angle_low):
    """Behind the outer faces' volutes the bolsters run along −Z (at x = −eye_x) and −X (at
    z = −eye_x) and meet on the inner diagonal: the capital is symmetric in the plane x = z
    but for the corner volute's spiral."""
    p, angle, _ = angle_low
    lay = capital_layout(p)
    y = lay.eye_y
    # a ray from −X at the bolster's height, halfway along it, meets its round side
    zs = np.linspace(-0.5, 0.3, 9) * lay.eye_x
    o = np.stack([np.full_like(zs, -2.0), np.full_like(zs, y), zs], 1)
    hit_x = -2.0 + _first_hits(angle, o, (1, 0, 0))
    o2 = np.stack([zs, np.full_like(zs, y), np.full_like(zs, -2.0)], 1)
    hit_z = -2.0 + _first_hits(angle, o2, (0, 0, 1))
    assert np.all(np.isfinite(hit_x)) and np.all(hit_x < -lay.eye_x - 0.5 * lay.total_radius)
    assert_allclose(hit_x, hit_z, atol=1e-6)  # the mirror image in x = z
