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


@pytest.mark.parametrize("name", ["abacus", "echinus", "volute_front_right", "volute_front_left",
                                  "volute_rear_right", "volute_rear_left", "canalis_front",
                                  "canalis_rear", "bolster_right", "bolster_left"])
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
    cn = m.normals.reshape(-1, 3, 3)
    assert_allclose(np.linalg.norm(cn, axis=2), 1.0, atol=1e-5)
    assert np.all(np.einsum("ij,ikj->ik", fn, cn) > 0.2)


def test_abacus_box_equals_its_parameters(parts):
    p = CapitalParams()
    ext = parts.abacus.extent
    top = capital_height(p)
    assert_allclose(ext, [[-p.abacus_length / 2, top - p.abacus_height, -p.abacus_width / 2],
                          [p.abacus_length / 2, top, p.abacus_width / 2]], atol=1e-12)
    assert inspect_mesh(parts.abacus).signed_volume == pytest.approx(
        p.abacus_length * p.abacus_width * p.abacus_height)


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
    # the volutes' top is the abacus bottom
    assert vol.extent[1, 1] == pytest.approx(lay.abacus_y)


def test_left_right_front_rear_are_mirrors(parts):
    fr, fl, rr, rl = parts.volutes
    assert_allclose(fl.points * [-1, 1, 1], fr.points)
    assert_allclose(rr.points * [1, 1, -1], fr.points)
    assert_allclose(rl.points * [-1, 1, -1], fr.points)
    for m in parts.volutes:
        assert inspect_mesh(m).signed_volume == pytest.approx(
            inspect_mesh(fr).signed_volume)


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
    side = (r > 1e-9)
    t = pts[side, 1] / p.echinus_height
    assert np.all(r[side] >= C + p.echinus_projection * t - 1e-12)


@pytest.mark.parametrize("scroll", ["S1", "S2", "R0.5 P0, R1 P0.5, R0.5 P1",
                                    "R0.7 P0.2, R0.9 P0.2, R0.7 P0.8"])
def test_bolster_rings_follow_the_grammar(scroll):
    p = CapitalParams(scroll=scroll)
    lay = capital_layout(p)
    parts = build_capital(p, top_radius=C)
    br = parts.bolsters[0]
    assert inspect_mesh(br).watertight
    pts = br.points
    # axis along Z through the eye; front (p = 0) at the back of the front volute disc
    assert pts[:, 2].max() == pytest.approx(lay.back_z)
    assert pts[:, 2].min() == pytest.approx(-lay.back_z)
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
    lo = capital_mesh(CapitalParams(spiral_samples=64, ring_segments=16, bolster_rows=8),
                      top_radius=C)
    hi = capital_mesh(CapitalParams(spiral_samples=384, ring_segments=96, bolster_rows=64),
                      top_radius=C)
    assert hi.n_triangles > 4 * lo.n_triangles
    assert inspect_mesh(hi).closed and inspect_mesh(hi).consistent


@pytest.mark.parametrize("dy", [-0.05, 0.0, 0.1])
def test_capital_position_lifts_everything(dy):
    base = build_capital(CapitalParams(), top_radius=C).merged()
    moved = build_capital(CapitalParams(capital_position_y=dy), top_radius=C).merged()
    assert_allclose(moved.points, base.points + [0, dy, 0], atol=1e-12)
    assert capital_height(CapitalParams(capital_position_y=dy)) == pytest.approx(
        moved.extent[1, 1])


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
    assert far.extent[0, 0] == pytest.approx(0.0, abs=1e-9)  # meets its mirror image at x = 0
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
