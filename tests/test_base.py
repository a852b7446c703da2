"""Column base generator: floor curves, profile, normals, closed solids, plinth, presets."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from numpy.testing import assert_allclose

from ionic_usd.column.base import (
    BaseParams,
    base_height,
    base_preset_names,
    base_profile,
    base_triangle_estimate,
    build_base,
    load_base_preset,
    torus_arc,
)
from ionic_usd.errors import GrammarError, ParameterError
from ionic_usd.geometry import (
    bezier,
    boundary_edges,
    inspect_mesh,
    merge,
    revolve,
    ring,
    smooth_normals,
    weld,
)
from ionic_usd.grammar import TorusFloor, parse_base_grammar

D = 0.475
PRESETS = ("G1", "G2", "attic_bezier", "attic_bezier_plinth")


def _chord_side(arc: np.ndarray) -> np.ndarray:
    """Signed horizontal distance of arc nodes from the chord: > 0 away from the axis."""
    (rb, _), (rt, h) = arc[0], arc[-1]
    return arc[:, 0] - (rb + (rt - rb) * arc[:, 1] / h)


def _frustum_volume(profile: np.ndarray, segments: int) -> float:
    """Exact volume of the revolved polygon: each segment sweeps a frustum of regular n-gons
    (the side quads are planar), area factor (n/2)·sin(2π/n)·r²."""
    r, y = profile[:, 0], profile[:, 1]
    k = 0.5 * segments * np.sin(2 * np.pi / segments)
    dy = np.diff(y)
    return float(k * np.sum(dy / 3 * (r[:-1] ** 2 + r[:-1] * r[1:] + r[1:] ** 2)))


# -- floor curves -----------------------------------------------------------------------------
@pytest.mark.parametrize("rb, rt", [(0.0, 0.1), (0.2, 0.05)])
@pytest.mark.parametrize("c", [1, -1])
def test_convex_floors_lie_outside_the_chord_and_concave_inside(rb, rt, c):
    arc = torus_arc(TorusFloor(rb, rt, 0.08, c), 12)
    assert len(arc) == 13
    assert_allclose(arc[0], [rb, 0.0], atol=0)
    assert_allclose(arc[-1], [rt, 0.08], atol=0)
    side = _chord_side(arc)[1:-1]
    assert np.all(c * side > 0)
    # a quarter ellipse: ((r - cr)/a)² + ((y - cy)/b)² = 1 about one of the two corners
    a, b = abs(rt - rb), 0.08
    ok = []
    for cr, cy in ((rb, 0.08), (rt, 0.0)):
        ok.append(np.allclose(((arc[:, 0] - cr) / a) ** 2 + ((arc[:, 1] - cy) / b) ** 2, 1))
    assert any(ok)


def test_convex_tangent_is_vertical_at_the_outermost_end():
    lower = torus_arc(TorusFloor(0.0, 0.1, 0.1, 1), 40)
    upper = torus_arc(TorusFloor(0.1, 0.0, 0.1, 1), 40)
    # both meet at r = 0.1 with a vertical tangent: a smooth half-ellipse torus
    assert abs(lower[-1, 0] - lower[-2, 0]) < 0.1 * abs(lower[-1, 1] - lower[-2, 1])
    assert abs(upper[1, 0] - upper[0, 0]) < 0.1 * abs(upper[1, 1] - upper[0, 1])


@pytest.mark.parametrize("floor", [TorusFloor(0.1, 0.1, 0.2, 1), TorusFloor(0.1, 0.3, 0.0, -1)])
def test_straight_and_flat_floors_have_two_rows(floor):
    assert_allclose(torus_arc(floor, 16), [[floor.r_bottom, 0], [floor.r_top, floor.height]])


# -- profile ----------------------------------------------------------------------------------
@pytest.mark.parametrize("slices", [1, 3, 8])
def test_g2_profile_hits_every_floor_end_exactly(slices):
    p = load_base_preset("G2", profile_slices=slices)
    prof = base_profile(p)
    y = 0.0
    ends = [(D + p.parsed.modules[0].floors[0].r_bottom, 0.0)]
    for m in p.parsed.modules:
        for f in m.floors:
            ends.append((D + f.r_bottom, y))
            y += f.height
            ends.append((D + f.r_top, y))
    for r, yy in ends:
        dist = np.hypot(prof[:, 0] - r, prof[:, 1] - yy).min()
        assert dist < 1e-12, (r, yy)
    assert_allclose(prof[-1], [D, 0.446], atol=1e-15)
    assert base_height(p) == pytest.approx(0.446)


def test_v2_profile_lies_on_the_bezier_curves():
    p = load_base_preset("attic_bezier", profile_slices=16)
    prof = base_profile(p)
    y0 = 0.0
    dense = []
    for m in p.parsed.modules:
        ctrl = np.array([[D + q.r, y0 + q.h] for q in m.points])
        dense.append(bezier(ctrl, np.linspace(0, 1, 2001)))
        # the module's end control points are hit exactly
        for end in (ctrl[0], ctrl[-1]):
            assert np.hypot(*(prof - end).T).min() < 1e-12
        y0 += m.height
    dense = np.concatenate(dense)
    far = [np.hypot(*(dense - q).T).min() for q in prof]
    assert max(far) < 1e-4


def test_grammar_units_are_metres_and_g2_is_vitruvian():
    # Vitruvius III.5: the Attic base is half the lower diameter high
    h = load_base_preset("G2").height
    assert 0.4 < h / (2 * D) < 0.6
    assert load_base_preset("G2", scale=2.0).height == pytest.approx(2 * h)


def test_two_point_module_emits_two_rows_whatever_the_slices():
    for slices in (1, 5, 30):
        p = BaseParams("R0.1 H0 R0.05 H0.2", shaft_radius=0.5, profile_slices=slices, segments=16)
        m = build_base(p)
        assert len(np.unique(m.points[:, 1])) == 2
        assert len(base_profile(p)) == 2


# -- continuity flag ----------------------------------------------------------------------------
def _without_c1(p: BaseParams) -> BaseParams:
    g = p.parsed
    text = ", ".join(m.to_string().removesuffix(" C1") for m in g.modules)
    return BaseParams(
        text,
        version=2,
        shaft_radius=p.shaft_radius,
        segments=p.segments,
        profile_slices=p.profile_slices,
    )


def test_continuity_flag_changes_only_the_normals_at_the_joint():
    smooth = load_base_preset("attic_bezier", segments=24, profile_slices=6)
    crisp = _without_c1(smooth)
    a, b = build_base(smooth), build_base(crisp)
    assert_allclose(a.points, b.points, atol=0)
    np.testing.assert_array_equal(a.face_vertex_indices, b.face_vertex_indices)
    an, bn = a.corner_normals(), b.corner_normals()
    differ = np.abs(an - bn).max(axis=1) > 1e-6
    corner_y = a.points[a.face_vertex_indices, 1]
    joints = [0.12 + 0.046, 0.12 + 0.092 + 0.015 + 0.045 + 0.015 + 0.038]  # the torus equators
    at_joint = np.any([np.abs(corner_y - j) < 1e-9 for j in joints], axis=0)
    assert differ.any()
    assert not differ[~at_joint].any()
    # with C1 the equator normals of the torus are horizontal (shared by both halves)
    eq = np.abs(corner_y - joints[0]) < 1e-9
    assert np.abs(an[eq, 1]).max() < 1e-3
    assert np.abs(bn[eq, 1]).max() > 0.05


def test_continuity_flag_drops_the_first_row_of_a_module():
    # the second module starts away from where the first ends: without C1 its first row is a
    # row of the mesh (joined by a joint band); with C1 that row is dropped
    crisp = BaseParams("R0.1 H0 R0.1 H0.1, R0.2 H0 R0.2 H0.1", segments=12)
    smooth = BaseParams("R0.1 H0 R0.1 H0.1, R0.2 H0 R0.2 H0.1 C1", segments=12)
    assert len(base_profile(crisp)) == 4
    assert len(base_profile(smooth)) == 3
    assert build_base(crisp).n_points == build_base(smooth).n_points + 12
    assert inspect_mesh(build_base(smooth)).watertight


def test_modules_meet_at_crisp_edges_and_floors_within_a_module_are_smooth():
    m = build_base(load_base_preset("G2", segments=32, profile_slices=8))
    n = m.corner_normals()
    corner = m.face_vertex_indices
    r = np.hypot(m.points[:, 0], m.points[:, 2])

    def ring_at(rr, y):
        return np.flatnonzero((np.abs(m.points[:, 1] - y) < 1e-12) & (np.abs(r - rr) < 1e-9))

    # module 3 (lower torus) ends on module 4 (fillet) at r = d + 0.074, y = 0.212
    joint = ring_at(D + 0.074, 0.12 + 0.092)
    # the lower torus's two floors meet at its equator r = d + 0.12, y = 0.166
    equator = ring_at(D + 0.12, 0.12 + 0.046)
    assert len(joint) == 32 and len(equator) == 32
    spread_joint = [np.ptp(n[corner == v], axis=0).max() for v in joint]
    spread_eq = [np.ptp(n[corner == v], axis=0).max() for v in equator]
    assert min(spread_joint) > 0.5  # two different normals: crisp
    assert max(spread_eq) < 1e-6  # one normal: the torus's floors are welded smooth
    # that normal is horizontal: both quarter ellipses have a vertical tangent there
    assert np.abs(n[np.isin(corner, equator), 1]).max() < 1e-6


# -- closed solids ----------------------------------------------------------------------------
@pytest.mark.parametrize("name", PRESETS)
@pytest.mark.parametrize("segments, slices", [(3, 1), (24, 4), (120, 8)])
def test_presets_are_watertight_with_the_frustum_volume(name, segments, slices):
    p = load_base_preset(name, segments=segments, profile_slices=slices)
    m = build_base(p)
    rep = inspect_mesh(m)
    assert rep.watertight and rep.unused_points == 0
    assert rep.n_triangles == base_triangle_estimate(p)
    want = _frustum_volume(base_profile(p, closed=True), segments)
    if p.plinth_modules:
        prof = base_profile(p, closed=True)
        half, top = prof[1, 0], prof[2, 1]
        # box + the revolved rest from its first outside row (its bottom disc is flat)
        want = 4 * half * half * top + _frustum_volume(prof[3:], segments)
    assert rep.signed_volume == pytest.approx(want, rel=1e-9)


def test_volume_converges_to_the_solid_of_revolution():
    # G1 cylinder part check: a base with one straight floor is a cylinder of radius d + r
    p = BaseParams("R0.1 H0.3 C1 R0.1", segments=2000, shaft_radius=0.5)
    assert inspect_mesh(build_base(p)).signed_volume == pytest.approx(
        np.pi * 0.6**2 * 0.3, rel=1e-5
    )


@pytest.mark.parametrize("name", ["G1", "G2", "attic_bezier"])
def test_open_top_is_exactly_the_shaft_ring(name):
    p = load_base_preset(name, segments=40, profile_slices=5)
    m = build_base(p, cap_top=False)
    edges = boundary_edges(m)
    loop = np.unique(edges)
    assert len(loop) == 40 and len(edges) == 40
    want = ring(D, p.height, 40)
    got = m.points[loop]
    # every ring vertex is present exactly (bit for bit)
    for q in want:
        assert np.any(np.all(got == q, axis=1))


def _stand_in_shaft(segments: int, y0: float, length: float = 1.0):
    prof = np.array([[D, y0], [D * 0.9, y0 + length], [0.0, y0 + length]])
    mesh, _ = revolve(prof, segments)
    return smooth_normals(mesh, np.arange(mesh.n_triangles) // segments)


@pytest.mark.parametrize("name", ["G1", "G2", "attic_bezier"])
def test_base_plus_stand_in_shaft_weld_into_one_watertight_solid(name):
    p = load_base_preset(name, segments=48, profile_slices=6)
    base = build_base(p, cap_top=False)
    shaft = _stand_in_shaft(48, p.height)
    joined = weld(merge([base, shaft]))
    assert joined.n_points == base.n_points + shaft.n_points - 48
    rep = inspect_mesh(joined)
    assert rep.watertight
    sep = (
        inspect_mesh(build_base(p)).signed_volume
        + inspect_mesh(_capped_stand_in(48, p.height)).signed_volume
    )
    assert rep.signed_volume == pytest.approx(sep, rel=1e-9)


def _capped_stand_in(segments, y0):
    prof = np.array([[0.0, y0], [D, y0], [D * 0.9, y0 + 1.0], [0.0, y0 + 1.0]])
    return revolve(prof, segments)[0]


@pytest.mark.parametrize("name", ["G2", "attic_bezier"])
def test_base_plus_real_shaft_is_watertight(name):
    import ionic_usd.column.shaft as shaft_mod

    sp = shaft_mod.ShaftParams(flute_slices=3, flute_slices_per_fillet_slice=1)
    p = load_base_preset(
        name, segments=sp.ring_segments, shaft_radius=sp.bottom_radius, profile_slices=4
    )
    base = build_base(p, cap_top=False)
    shaft = shaft_mod.build_shaft(sp, cap_bottom=False, y_offset=p.height)
    joined = weld(merge([base, shaft]))
    assert joined.n_points == base.n_points + shaft.n_points - sp.ring_segments
    assert inspect_mesh(joined).watertight


def test_open_bottom_leaves_the_first_ring():
    p = load_base_preset("G2", segments=20)
    m = build_base(p, cap_bottom=False)
    edges = boundary_edges(m)
    assert len(edges) == 20
    assert_allclose(m.points[np.unique(edges), 1], 0.0, atol=0)


# -- plinth -----------------------------------------------------------------------------------
def test_square_plinth_slab():
    p = load_base_preset("attic_bezier_plinth", segments=32)
    m = build_base(p)
    rep = inspect_mesh(m)
    assert rep.watertight
    low = m.points[m.points[:, 1] < 1e-12]
    assert_allclose(np.abs(low[:, [0, 2]]), D + 0.12, atol=1e-15)  # a square of half-side d+r
    assert len(low) == 4
    # the slab's height is the first module's
    slab = m.points[-8:]
    assert_allclose(np.unique(slab[:, 1]), [0.0, 0.12])
    # nothing of the revolved part lies below the slab top
    assert m.points[:-8, 1].min() == pytest.approx(0.12)
    # one shell: the revolved part stands in a hole of the slab's top face
    from ionic_usd.geometry.check import solid_report

    assert solid_report(m).solid
    # open bottom: only the box's bottom square is open
    assert len(boundary_edges(build_base(p, cap_bottom=False))) == 4


def test_plinth_of_two_modules_takes_the_larger_radius():
    p = BaseParams(
        "R0.1 H0 R0.1 H0.1, R0.2 H0 R0.15 H0.05, R0 H0 R0 H0.2",
        version=2,
        plinth_modules=2,
        segments=12,
    )
    prof = base_profile(p, closed=True)
    assert_allclose(prof[1:3], [[D + 0.2, 0.0], [D + 0.2, 0.15]], atol=1e-15)
    assert inspect_mesh(build_base(p)).watertight


# -- validation -------------------------------------------------------------------------------
@pytest.mark.parametrize(
    "text, d, module, token",
    [
        ("R0 H0.1 C-1 R-0.5, R0 H0.1 C1 R0", 0.475, 1, "R-0.5"),
        ("R0 H0 R0.2 H0.1, R-0.3 H0 R0 H0.2", 0.3, 2, "R-0.3"),
    ],
)
def test_radius_reaching_the_axis_is_a_pointed_grammar_error(text, d, module, token):
    with pytest.raises(GrammarError) as info:
        BaseParams(text, shaft_radius=d)
    e = info.value
    assert e.module == module
    assert text[e.offset : e.offset + e.length] == token
    assert "axis" in e.message


def test_parsed_grammar_objects_are_accepted_and_located():
    g = parse_base_grammar("R0 H0.1 C1 R-0.2")
    bare = type(g)(g.modules)  # no source: the generator re-derives token positions
    with pytest.raises(GrammarError) as info:
        BaseParams(bare, shaft_radius=0.1)
    assert info.value.source and info.value.source[info.value.offset] == "R"
    assert build_base(BaseParams(bare, segments=8)).n_points > 0


@pytest.mark.parametrize(
    "kw",
    [
        {"shaft_radius": 0},
        {"shaft_radius": float("nan")},
        {"segments": 2},
        {"segments": 7.5},
        {"segments": float("inf")},  # was an OverflowError before the shared check
        {"profile_slices": 0},
        {"plinth_modules": 9},
        {"plinth_modules": -1},
        {"version": 3},
        {"scale": -1},
        {"grammar": 5},
    ],
)
def test_bad_parameters_raise_parameter_error(kw):
    with pytest.raises(ParameterError):
        BaseParams(**kw)


def test_unknown_preset_lists_the_valid_names():
    with pytest.raises(ParameterError) as info:
        load_base_preset("G3")
    for name in ("G1", "G2", "attic_bezier", "attic_bezier_plinth"):
        assert name in str(info.value)
    assert set(PRESETS) <= set(base_preset_names())


def test_presets_hold_the_spec_strings():
    assert load_base_preset("G1").grammar == "R0 H0.1 C-1 R0.1, R0.1 H0.1 C1 R0.2 H0.1 C1 R0.1"
    assert load_base_preset("G2").grammar.startswith(
        "R0.12 H0.12 C1 R0.12, R0.12 H0 C1 R0.074,R0.074 H0.046"
    )
    assert load_base_preset("attic_bezier").parsed.version == 2


# -- fuzz: the generator adds nothing but GrammarError -----------------------------------------
@settings(max_examples=150, deadline=None)
@given(
    st.lists(st.tuples(st.floats(-0.6, 0.5), st.floats(0, 0.3)), min_size=2, max_size=6),
    st.booleans(),
    st.integers(1, 4),
)
def test_random_bezier_bases_build_or_raise_grammar_error(pts, c1, slices):
    text = " ".join(f"R{r:.3f} H{h:.3f}" for r, h in pts)
    text = f"R0.1 H0 R0.1 H0.1, {text}{' C1' if c1 else ''}"
    try:
        p = BaseParams(text, shaft_radius=0.5, segments=6, profile_slices=slices)
    except GrammarError:
        return
    m = build_base(p)
    assert inspect_mesh(m).degenerate_faces == 0


# -- analytic st ------------------------------------------------------------------------------


@pytest.mark.parametrize("name", ["G1", "G2", "attic_bezier", "attic_bezier_plinth"])
def test_analytic_st_is_finite_wound_and_bounded(name):
    from ionic_usd.column.charts import FLAT_SLOPE_DEG, SIDE_RADIUS_SPREAD
    from ionic_usd.geometry.mesh import face_normals
    from ionic_usd.texture.atlas import chart_labels

    m = build_base(load_base_preset(name))
    assert m.st is not None and np.all(np.isfinite(m.st.values))
    st = m.st.at_corners(m.face_vertex_indices).reshape(-1, 3, 2).astype(np.float64)
    e1, e2 = st[:, 1] - st[:, 0], st[:, 2] - st[:, 0]
    a_st = 0.5 * (e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])
    _, a3 = face_normals(m.points, m.triangles)
    ok = a3 > 1e-12 * a3.max()
    ratio = a_st[ok] / a3[ok]
    assert np.all(ratio > 0), "a triangle is folded or mirrored in st"
    # the tolerance the chart rules give: planar charts scale areas by cos(slope) ≥
    # cos(FLAT_SLOPE_DEG); side charts by r / R within sqrt(SIDE_RADIUS_SPREAD) either way;
    # chords of the profile and the ring make a few per cent more
    lo = min(np.cos(np.radians(FLAT_SLOPE_DEG)), 1 / np.sqrt(SIDE_RADIUS_SPREAD)) * 0.97
    hi = np.sqrt(SIDE_RADIUS_SPREAD) * 1.03
    assert lo < ratio.min() and ratio.max() < hi
    charts = chart_labels(m.st.indices, len(m.st.values))
    assert 3 <= charts.max() + 1 < 40


def test_wall_cuts_carry_the_analytic_st():
    from ionic_usd.geometry.boolean import difference
    from ionic_usd.geometry.clip import clip_mesh
    from ionic_usd.temple.cuboid import Cuboid, cuboid_mesh

    m = build_base(load_base_preset("G2", segments=48))
    half = clip_mesh(m, (0.0, 0.0, -0.05), (0.0, 0.0, 1.0))
    block = cuboid_mesh(Cuboid((-2.0, -1.0, -2.0), (-0.05, 2.0, -0.05), name="wall"))
    corner = difference(m, [block])
    for cut in (half, corner):
        assert cut.st is not None and inspect_mesh(cut).watertight
        st = cut.st.at_corners(cut.face_vertex_indices).reshape(-1, 3, 2).astype(np.float64)
        e1, e2 = st[:, 1] - st[:, 0], st[:, 2] - st[:, 0]
        a_st = 0.5 * (e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])
        big = a_st > 1e-10
        assert big.mean() > 0.99  # nothing folded but a few slivers at the cut
        # the cap on the wall plane is box-mapped: its st are its (x, y) up to sign
        on_cap = np.all(np.abs(cut.points[cut.triangles][:, :, 2] + 0.05) < 1e-9, axis=1)
        assert on_cap.any()
        cap_st = st[on_cap].reshape(-1, 2)
        cap_xy = cut.points[cut.triangles[on_cap].reshape(-1)][:, :2]
        assert_allclose(np.abs(cap_st), np.abs(cap_xy), atol=1e-6)


@pytest.mark.parametrize("with_st", [True, False])
def test_differences_share_the_operand_and_match_one_difference_each(with_st):
    """``differences`` hands the mesh to manifold3d once for several cutter sets: each result
    is the same mesh as its own ``difference`` (points, triangles, st), and a set that
    removes everything still raises."""
    from ionic_usd.errors import GeometryError
    from ionic_usd.geometry.boolean import difference, differences
    from ionic_usd.temple.cuboid import Cuboid, cuboid_mesh

    m = build_base(load_base_preset("G2", segments=48))
    if not with_st:
        m = m.with_(st=None)
    half = cuboid_mesh(Cuboid((-2.0, -1.0, -2.0), (2.0, 2.0, -0.05), name="wall"))
    quad = cuboid_mesh(Cuboid((-2.0, -1.0, -2.0), (-0.05, 2.0, -0.05), name="wall"))
    got = differences(m, [[half], [quad]], simplify=True)
    for cut, block in zip(got, (half, quad), strict=True):
        one = difference(m, [block], simplify=True)
        assert np.array_equal(cut.points, one.points)
        assert np.array_equal(cut.face_vertex_indices, one.face_vertex_indices)
        if with_st:
            assert np.array_equal(cut.st.values, one.st.values)
            assert np.array_equal(cut.st.indices, one.st.indices)
        assert inspect_mesh(cut).watertight
    assert len(got[0].points) != len(got[1].points)  # two different cuts, not one twice
    everything = cuboid_mesh(Cuboid((-5.0, -5.0, -5.0), (5.0, 5.0, 5.0), name="all"))
    with pytest.raises(GeometryError, match="nothing"):
        differences(m, [[half], [everything]])
