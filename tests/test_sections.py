"""Sections of the model: from parameters (closed forms) and cut from USD files."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from numpy.testing import assert_allclose

from ionic_usd.column.column import build_column, portunus_column_params
from ionic_usd.column.shaft import shaft_radius_at
from ionic_usd.column.volute import volute_curve
from ionic_usd.errors import GeometryError, ParameterError
from ionic_usd.evaluate.metrics import hausdorff_distance, point_to_polyline_distances
from ionic_usd.evaluate.sections import (
    base_section,
    section_from_usd,
    shaft_cross_section_at,
    shaft_silhouette_section,
    slice_mesh,
    volute_section,
)
from ionic_usd.grammar.base import parse_base_grammar


def _shoelace(poly: np.ndarray) -> float:
    x, y = poly[:, 0], poly[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y))


# -- from parameters ------------------------------------------------------------------------------
@pytest.mark.parametrize("base", ["attic_bezier", "G2", "G1"])
def test_base_section_hits_module_ends(base):
    p = dataclasses.replace(portunus_column_params(base=base), base_height=None)
    prof = base_section(p)
    g = parse_base_grammar(p.base_params().grammar)
    d = p.shaft.bottom_radius
    y0 = 0.0
    ends = []
    for m in g.modules:
        last_r = m.points[-1].r if g.version == 2 else m.floors[-1].r_top
        y0 += m.height
        ends.append((d + last_r, y0))
    # every module ends on the profile (scale 1: the grammar is in metres)
    assert point_to_polyline_distances(np.array(ends), prof).max() < 1e-12
    assert prof[0, 1] == 0.0 and prof[-1, 1] == pytest.approx(g.height)
    assert np.all(np.diff(prof[:, 1]) >= -1e-12)  # bottom to top, never down
    assert prof[:, 0].min() > 0


def test_base_section_scaled_to_base_height():
    p = portunus_column_params(base="G2")
    prof = base_section(p)
    assert prof[-1, 1] == pytest.approx(p.base_height)
    assert prof[-1, 0] == pytest.approx(p.shaft.bottom_radius)  # G2 ends at r = 0 → d


@pytest.mark.parametrize("entasis", [0.0, 0.03])
def test_shaft_silhouette_ends(entasis):
    p = portunus_column_params()
    p = dataclasses.replace(p, shaft=dataclasses.replace(p.shaft, entasis=entasis))
    y0 = p.base_params().height
    sil = shaft_silhouette_section(p, ends=False)
    assert_allclose(sil[0], [p.shaft.bottom_radius, y0])
    assert_allclose(sil[-1], [p.shaft.top_radius, y0 + p.shaft.length])
    mid = shaft_silhouette_section(p, samples=3, ends=False)[1]
    expected = 0.5 * (p.shaft.bottom_radius + p.shaft.top_radius) + entasis * p.shaft.bottom_radius
    assert mid[0] == pytest.approx(expected)
    full = shaft_silhouette_section(p)
    assert_allclose(full[[0, -1], 0], 0.0)
    assert len(full) == len(sil) + 2


def test_shaft_cross_section_closed_and_on_circle():
    p = portunus_column_params()
    y0 = p.base_params().height
    y = y0 + 3.0
    poly = shaft_cross_section_at(p, y)
    assert_allclose(poly[0], poly[-1])
    r = np.hypot(poly[:, 0], poly[:, 1])
    assert r.max() == pytest.approx(float(shaft_radius_at(p.shaft_params(), np.array(3.0))))
    assert abs(_shoelace(poly)) < np.pi * r.max() ** 2
    with pytest.raises(ParameterError):
        shaft_cross_section_at(p, y0 - 0.1)


def test_volute_section_frames():
    p = portunus_column_params()
    own = volute_section(p, frame="volute")
    assert_allclose(own, volute_curve(p.capital.volute, p.capital_params().spiral_samples))
    col = volute_section(p)
    shift = col - own
    assert_allclose(shift, np.broadcast_to(shift[0], shift.shape), atol=1e-12)  # a translation
    # the capital length is measured between the volutes' outer edges: x max = length / 2
    assert col[:, 0].max() == pytest.approx(p.capital.capital_length / 2, abs=1e-9)
    with pytest.raises(ParameterError):
        volute_section(p, frame="world")


# -- slicing --------------------------------------------------------------------------------------
def _cube() -> tuple[np.ndarray, np.ndarray]:
    pts = np.array([[x, y, z] for z in (0.0, 1.0) for y in (0.0, 1.0) for x in (0.0, 1.0)])
    quads = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]
    tris = np.array([t for q in quads for t in ((q[0], q[1], q[2]), (q[0], q[2], q[3]))])
    return pts, tris


@pytest.mark.parametrize("z", [0.25, 0.5, 1.0])  # 1.0: through the top face's vertices
def test_slice_cube_gives_unit_square(z):
    pts, tris = _cube()
    loops = slice_mesh(pts, tris, np.array([0.0, 0.0, z]), np.array([0.0, 0.0, 1.0]))
    assert len(loops) == 1
    loop = loops[0]
    assert_allclose(loop[0], loop[-1])
    assert_allclose(loop[:, 2], z, atol=1e-12)
    assert abs(_shoelace(loop[:, :2])) == pytest.approx(1.0)


def test_slice_misses():
    pts, tris = _cube()
    assert slice_mesh(pts, tris, np.array([0.0, 0.0, 2.0]), np.array([0.0, 0.0, 1.0])) == []
    # on-plane vertices count as above it: the bottom face's plane misses the cube
    assert slice_mesh(pts, tris, np.zeros(3), np.array([0.0, 0.0, 1.0])) == []
    with pytest.raises(ParameterError):
        slice_mesh(pts, tris, np.zeros(3), np.zeros(3))


# -- from USD -------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def column_usd(tmp_path_factory):
    from ionic_usd.usd import write_meshes

    p = portunus_column_params(base="G2")
    path = tmp_path_factory.mktemp("sections") / "column.usda"
    write_meshes(path, build_column(p).parts(), root="Column")
    return path, p


@pytest.fixture(scope="module")
def small_asset(tmp_path_factory):
    from ionic_usd.pipeline.asset import build_column_asset
    from ionic_usd.usd.column_asset import ColumnAssetOptions

    folder = tmp_path_factory.mktemp("sections_asset") / "IonicColumn"
    opts = ColumnAssetOptions(
        lods=("high", "low"),
        bases=("attic_bezier_plinth", "G2"),
        scrolls=("S1",),
        flutes=("f24",),
        forms=("full",),
        texture_size=16,
    )
    return build_column_asset(folder, opts).path, opts.params


def test_usd_sections_match_api(column_usd):
    path, p = column_usd
    for part, api in (
        ("base", base_section(p)),
        ("shaft", shaft_silhouette_section(p)),
        ("volute", volute_section(p)),
    ):
        # the capital is one solid: its band joins the eye boss, which the parameters locate
        cut = section_from_usd(path, part, params=p if part == "volute" else None)
        assert hausdorff_distance(api, cut) < 1e-5, part  # float32 points: ~1e-7 m
        assert np.linalg.norm(cut[0] - api[0]) < 1e-5, part  # same start, same direction
        assert np.linalg.norm(cut[-1] - api[-1]) < 1e-5, part
    y = p.base_params().height + 2.5
    cut = section_from_usd(path, "shaft", y=y)
    assert hausdorff_distance(shaft_cross_section_at(p, y), cut) < 1e-5


@pytest.mark.parametrize("base", ["attic_bezier_plinth", "G2"])
def test_asset_sections_follow_variants(small_asset, base):
    path, p = small_asset
    cut = section_from_usd(path, "base", variants={"lod": "high", "base": base})
    assert hausdorff_distance(base_section(p, base=base), cut) < 1e-5
    other = "G2" if base != "G2" else "attic_bezier_plinth"
    assert hausdorff_distance(base_section(p, base=other), cut) > 1e-3
    vol = section_from_usd(path, "volute", variants={"lod": "high"})
    assert hausdorff_distance(volute_section(p), vol) < 1e-5
    low = section_from_usd(path, "volute", variants={"lod": "low"})
    assert hausdorff_distance(volute_section(p.with_lod("low")), low) < 1e-5


def test_usd_errors(tmp_path, column_usd):
    from ionic_usd.usd import write_meshes

    with pytest.raises(ParameterError):
        section_from_usd(tmp_path / "missing.usda", "base")
    with pytest.raises(ParameterError):
        section_from_usd(column_usd[0], "capital")
    p = portunus_column_params()
    only_shaft = tmp_path / "shaft.usda"
    write_meshes(only_shaft, {"Shaft": build_column(p).shaft}, root="Column")
    with pytest.raises(GeometryError):
        section_from_usd(only_shaft, "volute")


def test_usd_unknown_variant(small_asset):
    with pytest.raises(ParameterError, match="ultra"):
        section_from_usd(small_asset[0], "base", variants={"lod": "ultra"})


def test_band_picked_by_length_even_touching_x0():
    """Regression: a band whose minimum x is exactly 0.0 lost to the eye loop (issue 14)."""
    from ionic_usd.column.volute import volute_eye, volute_inner_curve
    from ionic_usd.evaluate.sections import pick_band

    v = portunus_column_params().capital.volute
    outer, inner = volute_curve(v, 200), volute_inner_curve(v, 200)
    band = np.vstack([outer, inner[::-1], outer[:1]])
    band[:, 0] -= band[:, 0].min()  # the band's min x exactly 0.0
    assert band[:, 0].min() == 0.0
    eye = volute_eye(v, 47) + [0.2, 0.0]
    eye = np.vstack([eye, eye[:1]])
    left = band * [-1.0, 1.0]  # the front-left volute: longer than the eye, but on -x
    assert pick_band([eye, left, band]) is band
    assert pick_band([eye[:5]]) is None
