"""City plans without USD: GeoJSON reading, fitting temples to lots, colonnades, LOD."""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import shapely

from ionic_usd.city.layout import (
    Footprint,
    drop_inside,
    extra_columns,
    fit_temple,
    lod_by_distance,
    porticus_columns,
    yaw_quaternions,
)
from ionic_usd.city.plan import Lot, Porticus, grid_plan, read_geojson
from ionic_usd.errors import ParameterError

FORUM = Path(__file__).resolve().parents[1] / "examples" / "forum.geojson"
FP = Footprint(-5.935, 5.935, -10.335, 15.265, 14.7)  # a Portunus-sized box (11.87 × 25.6)


def _front(fit) -> np.ndarray:
    """Plan direction (e, n) of the placed temple's front (local +Z)."""
    a = math.radians(fit.yaw_deg)
    x, z = math.sin(a), math.cos(a)
    return np.array([x, -z])


def test_forum_example_reads():
    plan = read_geojson(FORUM)
    assert len(plan.lots) == 21 and len(plan.porticoes) == 6
    east = next(lot for lot in plan.lots if lot.id == "aedes_east")
    assert east.orientation is None and east.column == {"lower_diameter": 0.9}
    assert east.temple is None and east.choice == {"preset": "portunus"}
    cap = next(lot for lot in plan.lots if lot.id == "capitolium")
    assert cap.choice == {"front": 6, "intercolumniation": "eustyle"}
    assert east.hypotheses == {"flutes-20": "alternative"}
    deck = next(p for p in plan.porticoes if p.id == "decumanus")
    assert deck.sides == 2 and deck.spacing == 3.5 and deck.offset == 5.0
    assert next(p for p in plan.porticoes if p.id == "precinct").closed


def _write(tmp_path, doc) -> Path:
    p = tmp_path / "plan.geojson"
    p.write_text(json.dumps(doc))
    return p


def _fc(*features, **extra):
    return {"type": "FeatureCollection", "features": list(features), **extra}


def _feature(props, gtype, coords):
    return {
        "type": "Feature",
        "properties": props,
        "geometry": {"type": gtype, "coordinates": coords},
    }


@pytest.mark.parametrize(
    "doc, match",
    [
        (
            _fc(
                _feature({"type": "temple"}, "Polygon", [[[0, 0], [1, 0], [1, 1]]]),
                crs={"type": "name", "properties": {"name": "urn:ogc:def:crs:OGC:1.3:CRS84"}},
            ),
            "geographic",
        ),
        (
            _fc(_feature({"type": "villa", "id": "v1"}, "Polygon", [[[0, 0], [1, 0], [1, 1]]])),
            r"features\[0\] \(v1\).*type = 'villa'",
        ),
        (
            _fc(_feature({"type": "porticus", "id": "p"}, "LineString", [[0, 0], [1, "x"]])),
            r"\(p\).*coordinates\[1\]\[1\]",
        ),
        (
            _fc(
                _feature(
                    {"type": "porticus", "id": "p", "sides": 3}, "LineString", [[0, 0], [9, 0]]
                )
            ),
            "sides = 3",
        ),
        (
            _fc(
                _feature(
                    {"type": "temple", "id": "t", "hypotheses": {"a": "maybe"}},
                    "Polygon",
                    [[[0, 0], [1, 0], [1, 1]]],
                )
            ),
            "hypotheses",
        ),
        (
            _fc(
                _feature(
                    {"type": "porticus", "spacing": float("nan")}, "LineString", [[0, 0], [9, 0]]
                )
            ),
            "spacing",
        ),
        ({"type": "Feature"}, "FeatureCollection"),
    ],
)
def test_bad_plans_name_the_feature(tmp_path, doc, match):
    with pytest.raises(ParameterError, match=match):
        read_geojson(_write(tmp_path, doc))


def test_bad_json_names_line(tmp_path):
    p = tmp_path / "bad.geojson"
    p.write_text('{"type": "FeatureCollection",\n "features": [}')
    with pytest.raises(ParameterError, match="line 2"):
        read_geojson(p)


@pytest.mark.parametrize("orientation", [0.0, 90.0, 180.0, 270.0, 35.0])
def test_fit_keeps_footprint_inside_and_faces_orientation(orientation):
    ring = np.array([[0, 0], [40, 0], [40, 40], [0, 40]], dtype=float)
    lot = Lot("l", ring, orientation=orientation)
    fit = fit_temple(lot, FP, scale_range=(0.5, 1.2))
    placed = shapely.Polygon(fit.footprint_plan(FP))
    assert shapely.Polygon(ring).buffer(1e-3).contains(placed)
    az = math.radians(orientation)
    np.testing.assert_allclose(_front(fit), [math.sin(az), math.cos(az)], atol=1e-9)
    assert 0.5 <= fit.scale <= 1.2
    # proportions kept: the placed box's sides are the footprint's, scaled
    sides = sorted(np.hypot(*np.diff(fit.footprint_plan(FP)[[0, 1, 2]], axis=0).T))
    np.testing.assert_allclose(sides, sorted([FP.width * fit.scale, FP.length * fit.scale]))


def test_fit_uses_the_lot_and_its_long_axis_towards_the_centre():
    # a 16 × 36 m lot, long axis turned 30° from north; the centre lies "ahead" of it
    a = math.radians(30.0)
    u, v = np.array([math.sin(a), math.cos(a)]), np.array([math.cos(a), -math.sin(a)])
    ring = np.array([s * 18 * u + t * 8 * v for s, t in ((-1, -1), (1, -1), (1, 1), (-1, 1))])
    lot = Lot("rot", ring + [100, 50])
    fit = fit_temple(lot, FP, scale_range=(0.6, 2.0), toward=(100 + 50 * u[0], 50 + 50 * u[1]))
    np.testing.assert_allclose(_front(fit), u, atol=1e-9)
    # as large as the lot allows: 16 m / 11.87 m or 36 m / 25.6 m, whichever binds
    assert fit.scale == pytest.approx(min(16 / FP.width, 36 / FP.length), rel=1e-6)
    assert (
        shapely.Polygon(ring + [100, 50])
        .buffer(1e-3)
        .contains(shapely.Polygon(fit.footprint_plan(FP)))
    )
    flipped = fit_temple(lot, FP, scale_range=(0.6, 2.0), toward=(100 - 50 * u[0], 50 - 50 * u[1]))
    np.testing.assert_allclose(_front(flipped), -u, atol=1e-9)


def test_fit_of_an_l_shaped_lot_shrinks_until_inside():
    ring = np.array([[0, 0], [30, 0], [30, 12], [14, 12], [14, 40], [0, 40]], dtype=float)
    fit = fit_temple(Lot("L", ring, orientation=180.0), FP, scale_range=(0.5, 1.5))
    assert shapely.Polygon(ring).buffer(1e-3).contains(shapely.Polygon(fit.footprint_plan(FP)))
    assert fit.scale < 14 / FP.width + 1e-9


def test_fit_refuses_a_lot_too_small():
    ring = np.array([[0, 0], [8, 0], [8, 8], [0, 8]], dtype=float)
    with pytest.raises(ParameterError, match="lot tiny.*scale >= 0.6"):
        fit_temple(Lot("tiny", ring), FP, scale_range=(0.6, 1.4))


@pytest.mark.parametrize("sides", [1, 2])
def test_porticus_columns_line_the_street(sides):
    line = np.array([[0, 0], [60, 0], [60, 30]], dtype=float)
    xz, yaw = porticus_columns(Porticus("p", line, 3.0, sides, 4.0), 9.0)
    plan = np.stack([xz[:, 0], -xz[:, 1]], axis=1)
    d = shapely.distance(shapely.LineString(line), shapely.points(plan))
    want = 0.0 if sides == 1 else 4.0
    # on the line or `offset` from it; at a mitred outer corner a little further
    assert (d >= want - 1e-6).all() and (np.abs(d - want) < 1e-6).mean() > 0.9
    # consecutive columns along a straight run are equally spaced, the run divided into
    # round(length / spacing) bays (a column on each vertex): 60 m -> 20 bays of 3 m; a side
    # offset by 4 m runs 56 m -> 19 bays of 2.947 m
    step = np.hypot(*np.diff(plan[:10], axis=0).T)
    want_step = 3.0 if sides == 1 else 56.0 / 19
    np.testing.assert_allclose(step, want_step, atol=1e-9)
    if sides == 2:
        # every column faces the line: its front points at the nearest point of the line
        a = np.radians(yaw)
        front = np.stack([np.sin(a), -np.cos(a)], axis=1)
        near = shapely.get_coordinates(
            shapely.shortest_line(shapely.points(plan), shapely.LineString(line))
        )[1::2]
        to_line = (near - plan) / 4.0
        ok = np.einsum("ij,ij->i", front, to_line) > 0.99
        assert ok.mean() > 0.95  # all but the columns at the corner's mitre


def test_closed_porticus_goes_round_evenly():
    ring = np.array([[0, 0], [30, 0], [30, 30], [0, 30]], dtype=float)
    xz, _ = porticus_columns(Porticus("q", ring, 3.0, 1, closed=True), 3.0)
    assert len(xz) == 40
    steps = np.hypot(*np.diff(np.vstack([xz, xz[:1]]), axis=0).T)
    np.testing.assert_allclose(steps[steps > 2.9], 3.0, atol=1e-9)


def test_grid_plan_and_extras():
    plan = grid_plan(2, 3, 60.0, spacing=3.0)
    assert len(plan.lots) == 6 and len(plan.porticoes) == 1
    assert all(lot.scale == (1.0, 1.0) for lot in plan.lots)
    xz, yaw = extra_columns(1000, (0.0, 0.0, 90.0, 10.0), 3.0)
    assert xz.shape == (1000, 2) and (xz[:, 1] > 10.0).all()
    assert len({tuple(p) for p in xz}) == 1000  # no two columns on one spot


def test_drop_inside_and_lod():
    xz = np.array([[0.0, 0.0], [50.0, 0.0], [0.0, -200.0]])
    fp = [np.array([[-5, -5], [5, -5], [5, 5], [-5, 5]], dtype=float)]
    assert drop_inside(xz, fp).tolist() == [False, True, True]
    lod = lod_by_distance(xz, (0.0, 0.0), (40.0, 100.0))
    assert lod.tolist() == [0, 1, 2]
    q = yaw_quaternions(np.array([0.0, 90.0, 180.0])).astype(float)
    np.testing.assert_allclose(np.linalg.norm(q, axis=1), 1.0, atol=1e-3)
    np.testing.assert_allclose(q[1], [0, math.sqrt(0.5), 0, math.sqrt(0.5)], atol=1e-3)


def test_city_packages_import_without_pxr():
    code = (
        "import sys; sys.modules['pxr'] = None\n"
        "import ionic_usd.city, ionic_usd.city.plan, ionic_usd.city.layout\n"
        "import ionic_usd.pipeline.spec, ionic_usd.pipeline.build\n"
    )
    subprocess.run([sys.executable, "-c", code], check=True)


def test_unknown_hypothesis_in_a_plan_is_an_error(tmp_path):
    from ionic_usd.pipeline.city import CityOptions, build_city

    doc = _fc(
        _feature(
            {"type": "temple", "id": "t", "hypotheses": {"roof-flat": "alternative"}},
            "Polygon",
            [[[0, 0], [30, 0], [30, 40], [0, 40]]],
        )
    )
    with pytest.raises(ParameterError, match=r"lot t: hypotheses = \['roof-flat'\].*flutes-20"):
        build_city(tmp_path / "c", CityOptions(plan=str(_write(tmp_path, doc))))
    assert not (tmp_path / "c").exists()
