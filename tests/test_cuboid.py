"""Cuboids and inclined roof pieces: meshes, volumes, normals, UVs; the text grammar."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from numpy.testing import assert_allclose

from ionic_usd.errors import GrammarError, ParameterError
from ionic_usd.geometry import inspect_mesh
from ionic_usd.grammar.cuboid import format_cuboids, parse_cuboids
from ionic_usd.temple import Cuboid, Incline, cuboid_mesh, cuboid_points

BOXES = [
    ((0, 0, 0), (1, 1, 1), 0.0, "shear"),
    ((-2.5, 0.3, -1), (1.5, 0.7, 6), 0.0, "shear"),
    ((-5.5, 12.8, -9.9), (0, 13.2, 9.9), 1.22, "shear"),
    ((0, 14.0, -9.9), (5.5, 14.4, 9.9), -1.22, "shear"),
    ((-4.8, 12.8, -9.2), (0, 13.0, 9.2), 1.07, "wedge"),
    ((0, 12.8, -9.2), (4.8, 14.0, 9.2), -1.07, "wedge"),
    ((1e3, -3, 1e3), (1e3 + 2, -1, 1e3 + 5), 7.0, "wedge"),
]


def _analytic_volume(lo, hi, rise, incline) -> float:
    dx, dy, dz = (b - a for a, b in zip(lo, hi, strict=True))
    if incline == "shear":
        # a shear along y keeps every x-slice's height: Cavalieri gives the box volume
        return dx * dy * dz
    # right-trapezoid section of heights dy (at x0) and dy + rise (at x1), extruded along z
    return dz * dx * (dy + dy + rise) / 2


@pytest.mark.parametrize("lo,hi,rise,incline", BOXES)
def test_mesh_closed_outward_volume(lo, hi, rise, incline):
    m = cuboid_mesh(Cuboid(lo, hi, rise, incline))
    r = inspect_mesh(m)
    assert m.n_points == 8 and m.n_faces == 6 and np.all(m.face_vertex_counts == 4)
    assert r.closed and r.consistent and r.watertight
    assert r.degenerate_faces == 0 and r.unused_points == 0
    assert_allclose(r.signed_volume, _analytic_volume(lo, hi, rise, incline), rtol=1e-9)


def test_hand_computed_wedge_volume():
    # 2 x 1 x 3 box whose top edge at max x rises 0.5: section (1 + 1.5)/2 * 2 = 2.5, * 3
    m = cuboid_mesh(Cuboid((0, 0, 0), (2, 1, 3), 0.5, "wedge"))
    assert_allclose(inspect_mesh(m).signed_volume, 7.5, rtol=1e-12)


@pytest.mark.parametrize("incline", ["shear", "wedge"])
def test_inclined_vertex_heights(incline):
    c = Cuboid((-3, 2, 0), (1, 3, 5), 0.8, incline)
    p = cuboid_points(c)
    at_max_x = np.isclose(p[:, 0], 1)
    assert at_max_x.sum() == 4
    # the max-x top corners rise by 0.8; min-x corners are untouched
    assert_allclose(
        np.sort(p[at_max_x, 1]),
        [2.8, 2.8, 3.8, 3.8] if incline == "shear" else [2.0, 2.0, 3.8, 3.8],
    )
    assert_allclose(np.sort(p[~at_max_x, 1]), [2, 2, 3, 3])
    assert_allclose(c.pitch_deg, math.degrees(math.atan(0.8 / 4)))


@pytest.mark.parametrize("lo,hi,rise,incline", BOXES)
def test_normals_flat_unit_outward(lo, hi, rise, incline):
    m = cuboid_mesh(Cuboid(lo, hi, rise, incline))
    assert not m.normals.by_point
    n = m.corner_normals().reshape(6, 4, 3).astype(np.float64)
    assert_allclose(np.linalg.norm(n, axis=2), 1.0, rtol=1e-6)
    assert_allclose(n, np.repeat(n[:, :1], 4, axis=1))  # crisp: one normal per face
    q = m.points[m.face_vertex_indices].reshape(6, 4, 3)
    centre = m.points.mean(axis=0)
    for f in range(6):
        for a in range(4):  # perpendicular to every edge of the (planar) face
            e = q[f, (a + 1) % 4] - q[f, a]
            assert abs(e @ n[f, 0]) < 1e-5 * (1 + np.linalg.norm(e))
        assert (q[f].mean(axis=0) - centre) @ n[f, 0] > 0


def test_sloped_normal_follows_pitch():
    phi = math.atan(2 / 9)
    c = Cuboid((-4.5, 10, -1), (0, 10.3, 1), 4.5 * 2 / 9, "shear")
    m = cuboid_mesh(c)
    n = m.corner_normals().reshape(6, 4, 3)[:, 0]
    expect = np.array([-math.sin(phi), math.cos(phi), 0.0])
    assert np.any(np.all(np.abs(n - expect) < 1e-6, axis=1))  # top
    assert np.any(np.all(np.abs(n + expect) < 1e-6, axis=1))  # soffit (sheared bottom)


@pytest.mark.parametrize("uv_scale", [0.25, 1.0, 0.1])
@pytest.mark.parametrize("lo,hi,rise,incline", BOXES)
def test_uvs_are_metres_times_scale(lo, hi, rise, incline, uv_scale):
    m = cuboid_mesh(Cuboid(lo, hi, rise, incline), uv_scale=uv_scale)
    assert m.st.values.shape == (24, 2) and m.st.indices.shape == (24,)
    q = m.points[m.face_vertex_indices].reshape(6, 4, 3)
    uv = m.st.at_corners(m.face_vertex_indices).astype(np.float64).reshape(6, 4, 2)
    for f in range(6):  # every pair of a face's corners: UV distance = scale x metres
        d3 = np.linalg.norm(q[f][:, None] - q[f][None], axis=2)
        d2 = np.linalg.norm(uv[f][:, None] - uv[f][None], axis=2)
        # float32 st: allow a few ulps of the largest coordinate
        assert_allclose(d2, uv_scale * d3, atol=1e-6 * uv_scale * (1 + np.abs(q).max()))
        # not mirrored: UV winding has the same (counter-clockwise) sense as the face
        a = uv[f]
        area = 0.5 * np.sum(a[:, 0] * np.roll(a[:, 1], -1) - np.roll(a[:, 0], -1) * a[:, 1])
        assert area > 0


def test_box_projection_world_anchored():
    # two boxes sharing the plane z = 1: their front faces tile seamlessly (same st at the
    # same point), and the front face's st is (x, y) in metres x 0.25
    a = cuboid_mesh(Cuboid((0, 0, 0), (2, 1, 1)))
    b = cuboid_mesh(Cuboid((2, 0, -3), (5, 1, 1)))
    for m in (a, b):
        q = m.points[m.face_vertex_indices].reshape(6, 4, 3)
        uv = m.st.at_corners(m.face_vertex_indices).reshape(6, 4, 2)
        f = int(np.argmax(m.corner_normals().reshape(6, 4, 3)[:, 0, 2]))
        assert_allclose(uv[f], 0.25 * q[f][:, :2], atol=1e-6)


@pytest.mark.parametrize(
    "lo,hi,axis",
    [((0, 0, 0), (0, 1, 1), "x"), ((0, 2, 0), (1, 1, 1), "y"), ((0, 0, 5), (1, 1, 5), "z")],
)
def test_min_not_below_max_names_axis(lo, hi, axis):
    with pytest.raises(ParameterError, match=rf"max\.{axis}"):
        Cuboid(lo, hi)


@pytest.mark.parametrize(
    "kw",
    [
        dict(min=(0, float("nan"), 0), max=(1, 1, 1)),
        dict(min=(0, 0, 0), max=(1, 1, math.inf)),
        dict(min=(0, 0), max=(1, 1, 1)),
        dict(min=(0, 0, 0), max=(1, 1, 1), rise=math.nan),
        dict(min=(0, 0, 0), max=(1, 1, 1), incline="twist"),
        dict(min=(0, 0, 0), max=(1, 1, 1), rise=-1.0, incline="wedge"),
    ],
)
def test_invalid_cuboids(kw):
    with pytest.raises(ParameterError):
        Cuboid(**kw)


def test_uv_scale_validated():
    with pytest.raises(ParameterError, match="uv_scale"):
        cuboid_mesh(Cuboid((0, 0, 0), (1, 1, 1)), uv_scale=0)


# --- grammar ------------------------------------------------------------------------------


def test_parse_example():
    cs = parse_cuboids(
        "C(-5.25, 0, -9.65, 5.25, 2.4, 9.65),\n"
        "C(-5.5,12.8,-9.9,0,13.2,9.9,1.22) , W(0, 1, 0, 1, 1.2, 1, -0.1)"
    )
    assert [c.name for c in cs] == ["cuboid1", "cuboid2", "cuboid3"]
    assert cs[0] == Cuboid((-5.25, 0, -9.65), (5.25, 2.4, 9.65), name="cuboid1")
    assert cs[1].rise == 1.22 and cs[1].incline is Incline.SHEAR
    assert cs[2].rise == -0.1 and cs[2].incline is Incline.WEDGE


@pytest.mark.parametrize(
    "src,module,token,phrase",
    [
        ("C(0,0,0,1,1,1), C(0,0,0,1,0,1)", 2, "0", "y1 = 0 must be greater than y0 = 0"),
        ("C(0,0,0,-1,1,1)", 1, "-1", "x1"),
        ("C(0,0,0,1,1)", 1, ")", "missing z1"),
        ("W(0,0,0,1,1,1)", 1, ")", "missing rise"),
        ("C(0,0,0,1,1,1,,)", 1, ",", "missing rise"),
        ("C(0,0,0,1,1,1,2,3)", 1, "3", "too many"),
        ("C(0,zero,0,1,1,1)", 1, "zero", "not a number"),
        ("C(0,0,0,1,1,1.2.3)", 1, "1.2.3", "not a number"),
        ("C(0,0,0,1,1,1) X(1)", 1, "X", "unexpected"),
        ("Q(0,0,0,1,1,1)", 1, "Q", "expected 'C(' or 'W('"),
        ("C(0,0,0,1,1,1), , C(0,0,0,1,1,1)", 2, ",", "empty cuboid"),
        ("C(0 0,0,1,1,1)", 1, "0", "expected ','"),
        ("W(0,0,0,1,1,1,-3)", 1, "-3", "rise"),
        ("C(0,0,0,1,1,inf)", 1, "inf", "not finite"),
    ],
)
def test_grammar_errors_point_at_token(src, module, token, phrase):
    with pytest.raises(GrammarError) as ei:
        parse_cuboids(src)
    e = ei.value
    assert e.grammar == "cuboid" and e.module == module
    assert phrase in e.message
    if token == ")":
        assert src[e.offset] == ")"
    else:
        # the caret is under the token that is to blame (the last occurrence for the repeats)
        assert src[e.offset : e.offset + len(token)] == token
        assert e.offset in {i for i in range(len(src)) if src.startswith(token, i)}
    ctx = e.get_context().splitlines()
    assert ctx[1].index("^") - 2 == e.offset


def test_missing_close_paren_points_past_the_end():
    src = "C(0,0,0,1,1,1"
    with pytest.raises(GrammarError, match=r"missing '\)'") as ei:
        parse_cuboids(src)
    assert ei.value.offset == len(src)


@pytest.mark.parametrize("src", ["", "   ", ",", "C", "C(", "()", "C()"])
def test_degenerate_inputs(src):
    with pytest.raises(GrammarError):
        parse_cuboids(src)


finite = st.floats(-1e6, 1e6, allow_nan=False, allow_infinity=False)


@st.composite
def cuboids(draw):
    lo = [draw(finite) for _ in range(3)]
    size = [draw(st.floats(1e-3, 1e3)) for _ in range(3)]
    hi = [a + s for a, s in zip(lo, size, strict=True)]
    if any(not a < b for a, b in zip(lo, hi, strict=True)):
        hi = [a + max(abs(a), 1.0) for a in lo]
    incline = draw(st.sampled_from(["shear", "wedge"]))
    rise = draw(st.floats(-1e3, 1e3)) if draw(st.booleans()) else 0.0
    if incline == "wedge" and not hi[1] + rise > lo[1]:
        rise = 0.0
    return Cuboid(tuple(lo), tuple(hi), rise, incline)


@settings(max_examples=200, deadline=None)
@given(st.lists(cuboids(), min_size=1, max_size=5))
def test_format_parse_round_trip(cs):
    back = parse_cuboids(format_cuboids(cs))
    assert len(back) == len(cs)
    for a, b in zip(cs, back, strict=True):
        assert (a.min, a.max, a.rise, a.incline) == (b.min, b.max, b.rise, b.incline)


@settings(max_examples=400, deadline=None)
@given(st.text(max_size=60))
def test_fuzz_any_text_only_grammar_error(src):
    try:
        parse_cuboids(src)
    except GrammarError:
        pass


@settings(max_examples=400, deadline=None)
@given(st.text(alphabet="CWcw(),.-+e 0123456789\n", max_size=60))
def test_fuzz_near_miss_text_only_grammar_error(src):
    try:
        out = parse_cuboids(src)
    except GrammarError:
        return
    assert all(isinstance(c, Cuboid) for c in out)
