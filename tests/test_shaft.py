"""The fluted shaft: closedness, winding, analytic volume and extents, flutes, LOD, errors."""

from __future__ import annotations

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose
from scipy.integrate import quad

from ionic_usd.column.shaft import (
    ShaftParams,
    build_shaft,
    shaft_cross_section,
    shaft_radius_at,
    shaft_triangle_estimate,
)
from ionic_usd.errors import BudgetError, ParameterError
from ionic_usd.geometry import inspect_mesh, merge, weld
from ionic_usd.geometry.mesh import face_normals


def analytic_area(p: ShaftParams, y: float) -> float:
    """Cross-section area of the ideal fluted solid at height y (independent derivation)."""
    r = float(shaft_radius_at(p, np.array([y]))[0])
    y0 = p.ring_bottom
    ab, at = p.arc_height(p.bottom_radius), p.arc_height(p.top_radius)
    y1, y2, y3 = y0 + ab, y0 + ab + p.height, y0 + ab + p.height + at
    if y < y0 or y > y3:
        k = 0.0
    elif y < y1:
        k = math.sqrt(max(0.0, 1 - ((y1 - y) / ab) ** 2))
    elif y <= y2:
        k = 1.0
    else:
        k = math.sqrt(max(0.0, 1 - ((y - y2) / at) ** 2))
    alpha = math.radians(p.flute_angle) / 2 * k
    rho = r * math.sin(alpha)
    segment = r * r / 2 * (2 * alpha - math.sin(2 * alpha))
    half_ellipse = math.pi * p.flute_depth * rho * rho / 2
    return math.pi * r * r - p.flutes * (segment + half_ellipse)


@pytest.mark.parametrize(
    "params",
    [
        ShaftParams(),
        ShaftParams(flute_slices=1, flute_slices_per_fillet_slice=1),
        ShaftParams(flute_slices=3, flutes=20, flute_angle=14, flute_depth=0.5),
        ShaftParams(entasis=0.03, flute_slices=5),
        ShaftParams(arc_ratio=0.0, ring_bottom=0.0, ring_top=0.0),
        ShaftParams(flutes=3, flute_angle=60, flute_slices=6),
    ],
)
def test_shaft_is_watertight(params):
    m = build_shaft(params)
    r = inspect_mesh(m)
    assert r.closed and r.consistent, r
    assert r.degenerate_faces == 0 and r.duplicate_faces == 0 and r.unused_points == 0
    assert r.signed_volume > 0
    assert m.n_triangles == shaft_triangle_estimate(params)


def test_normals_point_outward_and_agree_with_faces():
    m = build_shaft(ShaftParams(flute_slices=6))
    fn, _ = face_normals(m.points, m.triangles)
    corner = m.corner_normals().reshape(-1, 3, 3)
    # each corner normal lies on the outer side of its face
    assert np.all(np.einsum("ijk,ik->ij", corner, fn) > 0.2)


def test_crisp_fillet_edges_smooth_flutes():
    p = ShaftParams(flute_slices=8)
    m = build_shaft(p)
    tri = m.triangles.reshape(-1)
    normals = m.corner_normals()
    # group corner normals by vertex: a flute corner vertex carries two distinct normals,
    # an interior flute vertex only one
    order = np.argsort(tri, kind="stable")
    v_sorted = tri[order]
    starts = np.flatnonzero(np.r_[True, np.diff(v_sorted) != 0])
    spread = np.maximum.reduceat(
        np.linalg.norm(
            normals[order]
            - normals[order][starts].repeat(np.diff(np.r_[starts, len(order)]), axis=0),
            axis=1,
        ),
        starts,
    )
    pts = m.points[v_sorted[starts]]
    body = (pts[:, 1] > 1.0) & (pts[:, 1] < 6.0)
    crisp = spread[body] > 0.3
    # two crisp columns (the flute corners) per flute in every body row
    rows = np.unique(np.round(pts[body, 1], 6)).size
    assert crisp.sum() == 2 * p.flutes * rows
    assert np.all(spread[body][~crisp] < 1e-5)


@pytest.mark.parametrize("h", [8, 24])
def test_volume_close_to_analytic(h):
    p = ShaftParams(flute_slices=h, entasis=0.02, entasis_rows=64)
    m = build_shaft(p)
    # the analytic solid has round circles: compare with the polygon's inscribed factor
    exact, _ = quad(
        lambda y: analytic_area(p, y),
        0,
        p.length,
        limit=400,
        points=[p.ring_bottom, p.length - p.ring_top],
    )
    got = inspect_mesh(m).signed_volume
    rel = abs(got - exact) / exact
    # the flute polygon is inscribed in the ellipse: O(1/h^2) more material than the ideal
    assert rel < (5e-3 if h == 8 else 1e-3), (got, exact, rel)


def test_volume_converges_with_lod():
    errs = []
    for h in (2, 4, 8, 16):
        p = ShaftParams(flute_slices=h)
        exact, _ = quad(lambda y, p=p: analytic_area(p, y), 0, p.length, limit=400)
        errs.append(abs(inspect_mesh(build_shaft(p)).signed_volume - exact) / exact)
    assert errs == sorted(errs, reverse=True)


def test_extents_equal_analytic():
    p = ShaftParams()
    m = build_shaft(p)
    lo, hi = m.extent
    assert_allclose([lo[1], hi[1]], [0.0, p.length], atol=1e-12)
    # the bottom plain ring has vertex 0 at +X on the radius d
    assert hi[0] == pytest.approx(p.bottom_radius, abs=1e-12)
    assert np.hypot(m.points[:, 0], m.points[:, 2]).max() == pytest.approx(p.bottom_radius)
    with_entasis = ShaftParams(entasis=0.05)
    r = np.hypot(*build_shaft(with_entasis).points[:, [0, 2]].T).max()
    ys = np.linspace(0, with_entasis.length, 10001)
    assert r == pytest.approx(shaft_radius_at(with_entasis, ys).max(), rel=1e-3)


@pytest.mark.parametrize("flutes", [20, 24, 28])
def test_flute_count_visible_in_cross_section(flutes):
    p = ShaftParams(flutes=flutes, flute_angle=0.8 * 360 / flutes)
    m = build_shaft(p)
    y = p.length / 2
    section = m.points[
        np.abs(m.points[:, 1] - m.points[:, 1][np.argmin(np.abs(m.points[:, 1] - y))]) < 1e-9
    ]
    ang = np.arctan2(-section[:, 2], section[:, 0])
    rad = np.hypot(section[:, 0], section[:, 2])
    order = np.argsort(ang)
    inside = rad[order] < rad.max() * (1 - 1e-6)
    # count runs of vertices inside the circle (flute hollows), cyclically
    starts = inside & ~np.roll(inside, 1)
    assert starts.sum() == flutes
    cs = shaft_cross_section(p, y)
    assert len(cs) == p.fluted_segments


def test_lod_monotonic():
    counts = [build_shaft(ShaftParams(flute_slices=h)).n_triangles for h in (1, 2, 4, 8, 16)]
    assert counts == sorted(counts) and len(set(counts)) == len(counts)


def test_open_ends_weld_to_rings():
    p = ShaftParams()
    open_m = build_shaft(p, cap_bottom=False, cap_top=False)
    r = inspect_mesh(open_m)
    # open exactly at the two plain rings
    assert r.boundary_edges == 2 * p.ring_segments
    # stacking two shafts open at the shared ring welds into one closed solid
    lower = build_shaft(p, cap_top=False)
    upper = build_shaft(p, cap_bottom=False, y_offset=p.length)
    # the rings must coincide: same radius at both ends for the test
    q = ShaftParams(top_radius=p.bottom_radius)
    lower, upper = (
        build_shaft(q, cap_top=False),
        build_shaft(q, cap_bottom=False, y_offset=q.length),
    )
    w = weld(merge([lower, upper]), tol=1e-9)
    assert inspect_mesh(w).watertight


@pytest.mark.parametrize(
    "kwargs,name",
    [
        ({"top_radius": 0.0}, "top_radius"),
        ({"bottom_radius": -1.0}, "bottom_radius"),
        ({"flutes": 2}, "flutes"),
        ({"flute_angle": 15.0}, "flute_angle"),
        ({"flute_slices": 0}, "flute_slices"),
        ({"height": float("nan")}, "height"),
        ({"flutes": 24.5}, "flutes"),
        ({"flute_depth": 5.0}, "flute_depth"),
        ({"entasis": 1.0}, "entasis"),
    ],
)
def test_bad_parameters_name_themselves(kwargs, name):
    with pytest.raises(ParameterError, match=name) as exc:
        ShaftParams(**kwargs)
    assert "expected" in str(exc.value)


def test_budget_refused_with_estimate():
    p = ShaftParams(flute_slices=400)
    with pytest.raises(BudgetError, match=f"{shaft_triangle_estimate(p):,}"):
        build_shaft(p, max_triangles=1_000_000)


# -- indexed normals and analytic st -----------------------------------------------------------


def _st_ratio(m):
    """Per triangle: signed st area / 3D area, and the 3D areas."""
    st = m.st.at_corners(m.face_vertex_indices).reshape(-1, 3, 2).astype(np.float64)
    e1, e2 = st[:, 1] - st[:, 0], st[:, 2] - st[:, 0]
    a_st = 0.5 * (e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])
    _, a3 = face_normals(m.points, m.triangles)
    return a_st / a3, a3


@pytest.mark.parametrize(
    "params",
    [
        ShaftParams(),
        ShaftParams(flute_slices=3, entasis=0.01),
        ShaftParams(ring_bottom=0.0, ring_top=0.0),
    ],
)
def test_indexed_normals_compact_and_consistent(params):
    from ionic_usd.geometry.check import normals_against_winding

    m = build_shaft(params)
    assert m.normals.indices is not None and not m.normals.one_per_corner
    corner = m.corner_normals()
    assert corner.shape == (m.face_vertex_indices.size, 3)
    assert_allclose(np.linalg.norm(corner, axis=1), 1.0, atol=1e-5)
    # about one value per point (two on a flute edge): a third of the per-corner storage
    assert len(m.normals.values) < 0.5 * len(corner)
    if params.ring_bottom > 0:
        assert normals_against_winding(m) == 0
    # equal indices mean equal normals, and no two values are equal at one point across a
    # smooth region: indexing lost no crease
    again = weld(m)
    assert_allclose(again.corner_normals(), corner, atol=0)


@pytest.mark.parametrize(
    "params",
    [
        ShaftParams(),
        ShaftParams(flute_slices=3, entasis=0.01),
        ShaftParams(flute_slices=16, entasis=-0.01),
    ],
)
def test_analytic_st_is_finite_wound_and_nearly_isometric(params):
    from ionic_usd.texture.atlas import chart_labels

    m = build_shaft(params)
    assert m.st is not None and np.all(np.isfinite(m.st.values))
    ratio, area = _st_ratio(m)
    assert np.all(ratio > 0), "a triangle is folded or mirrored in st"
    # tolerance: the side is unrolled at the arc length of the mid-height full-flute row, so
    # rows elsewhere scale by (that perimeter)/(their own), the plain rings most; flute ends
    # (the spoons, tilted against v = y) are the only region beyond it
    r_mid = 0.5 * (params.bottom_radius + params.top_radius)
    ring_stretch = r_mid / params.top_radius * 1.3  # fluted/plain perimeter ≤ 1.3
    assert ratio.max() < 1.2 * ring_stretch
    body = (ratio > 1 / 1.25) & (ratio < 1.25)
    assert area[body].sum() > 0.97 * area.sum()
    charts = chart_labels(m.st.indices, len(m.st.values))
    assert charts.max() + 1 == 3  # the side (one seam) and two caps
    for c in range(3):
        sel = charts == c
        mean = (ratio[sel] * area[sel]).sum() / area[sel].sum()
        assert abs(mean - 1.0) < 0.03


def test_docs_lod_table_matches_the_generator():
    """The LOD table of docs/specification/column.md, row by row, from the generator."""
    import re
    from pathlib import Path

    from ionic_usd.column.column import build_column, portunus_column_params

    page = Path(__file__).resolve().parents[1] / "docs" / "specification" / "column.md"
    readme = page.read_text("utf-8")
    rows = re.findall(
        r"^\| (high|medium|low) \| (\d+) / (\d+) \| (\d+) \| ([\d,]+) \|$", readme, flags=re.M
    )
    assert [r[0] for r in rows] == ["high", "medium", "low"]
    for lod, h, i, body_rows, tris in rows:
        p = portunus_column_params(lod=lod)
        sp = p.shaft_params()  # the shaft as the column builds it at this LOD
        assert (sp.flute_slices, sp.flute_slices_per_fillet_slice, sp.body_rows) == (
            int(h),
            int(i),
            int(body_rows),
        )
        col = build_column(p)
        assert col.n_triangles == int(tris.replace(",", ""))
        assert col.parts()["Shaft"].n_triangles == shaft_triangle_estimate(sp, caps=2)
