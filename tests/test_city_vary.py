"""Cities that vary: each lot's temple type, stoas on the colonnades, the paved ground.

Fast tests work on the plan, the choices and the stoa/ground geometry (no temple build). The
built cities are tested in test_city.py (a grid with stoas and ground; slow: the varied forum,
21 builds, every layer validated alone) and test_city_dask.py (a real scheduler and workers).
"""

from __future__ import annotations

import hashlib
import json
import math
from pathlib import Path

import numpy as np
import pytest
import shapely

from ionic_usd.city.choose import (
    INTERCOLUMNIATIONS,
    TempleType,
    derive_description,
    lot_rng,
    temple_for_lot,
    type_footprint,
)
from ionic_usd.city.ground import ground_meshes
from ionic_usd.city.layout import lot_box
from ionic_usd.city.plan import STOA_BACK, Lot, Porticus, grid_plan, read_geojson
from ionic_usd.city.stoa import StoaDims, bay_parts, corner_parts, porticus_stoa
from ionic_usd.errors import ParameterError
from ionic_usd.geometry.check import solid_report
from ionic_usd.pipeline.city import CityOptions
from ionic_usd.pipeline.city_lots import lot_specs
from ionic_usd.pipeline.spec import TempleSpec, temple_spec

FORUM = Path(__file__).resolve().parents[1] / "examples" / "forum.geojson"


def _specs(plan, **kw):
    centre = np.mean([lot.outline.mean(axis=0) for lot in plan.lots], axis=0)
    return lot_specs(plan, CityOptions(texture_size=64, **kw), centre)


def _geometry(spec: TempleSpec) -> tuple:
    p = spec.layout().params
    return (
        p.columns_front,
        p.columns_side,
        p.columns_lower_diameter,
        p.stylobate_width,
        p.stylobate_length,
        p.columns_height,
    )


@pytest.mark.parametrize("which", ["grid", "forum"])
def test_default_grid_and_forum_hold_20_distinct_builds(which):
    plan = grid_plan() if which == "grid" else read_geojson(FORUM)
    r = _specs(plan, rows=5, cols=5)
    keys = {s.key for s in r.specs}
    assert len(keys) == len(r.specs) >= 20
    # distinct geometry, not renamed copies: every build has its own proportions
    assert len({_geometry(s) for s in r.specs}) == len(r.specs)
    fronts = {s.layout().params.columns_front for s in r.specs}
    assert len(fronts) >= 2
    # each lot's podium fits its lot at scale 1 (the chooser sized its module to the lot)
    for lot, b, rng in zip(plan.lots, r.build, r.scale_ranges, strict=True):
        p = r.specs[b].layout().params
        if r.specs[b].name == "portunus":
            continue
        w, d = lot_box(lot, np.mean([x.outline.mean(axis=0) for x in plan.lots], axis=0))
        assert p.podium_base_width <= w and p.podium_base_length <= d
        assert rng == (lot.scale or (0.5, 1.0))


def test_choices_are_seeded_per_lot():
    plan = grid_plan(3, 3)
    a, b = _specs(plan), _specs(plan)
    assert [c for c in a.choices] == [c for c in b.choices]
    c = _specs(plan, seed=5)
    assert [x["build"] for x in c.choices] != [x["build"] for x in a.choices]
    # a lot's choice depends on the seed and its id, not on the other lots
    one = lot_specs(
        type(plan)(plan.lots[4:5], ()),
        CityOptions(texture_size=64),
        np.mean([lot.outline.mean(axis=0) for lot in plan.lots], axis=0),
    )
    assert one.choices[0]["build"] == a.choices[4]["build"]


@pytest.mark.parametrize("ic", list(INTERCOLUMNIATIONS))
@pytest.mark.parametrize("front", [4, 6, 8])
def test_a_type_follows_vitruvius(front, ic):
    g, h = INTERCOLUMNIATIONS[ic]
    t = TempleType("pseudoperipteral", front, ic, 0.8)
    p = TempleSpec(t.name, derive_description(t)).layout().params
    assert p.axial_spacing == pytest.approx(0.8 * (1 + g))  # III.3.1-6
    assert p.columns_height == pytest.approx(h * 0.8)  # III.3.7, III.3.10
    assert (p.columns_front, p.columns_side) == (front, 2 * front - 1)
    w, d = type_footprint(t)
    assert (w, d) == pytest.approx((p.podium_base_width, p.podium_base_length))


def test_plan_names_a_type_or_a_preset():
    plan = read_geojson(FORUM)
    r = _specs(plan)
    by_lot = {c["lot"]: c for c in r.choices}
    cap = by_lot["capitolium"]
    assert (cap["front"], cap["intercolumniation"]) == (6, "eustyle")
    east = by_lot["aedes_east"]
    want = temple_spec("portunus", {"lower_diameter": 0.9}, texture_size=64)
    assert east["build"] == want.folder  # the preset, with the lot's column override
    assert by_lot["capitolium_e"]["front"] == 8


@pytest.mark.parametrize(
    "props, match",
    [
        ({"arrangement": "tholos"}, "arrangement"),
        ({"arrangement": "peripteral", "front": 10}, "front"),  # decastyle: dipteral only
        ({"arrangement": "dipteral", "intercolumniation": "wide"}, "intercolumniation"),
        ({"intercolumniation": "wide"}, "intercolumniation"),
        ({"preset": "parthenon"}, "preset"),
        ({"front": 4, "lower_diameter": 3.0}, "outline"),  # too big for the lot
    ],
)
def test_bad_types_name_the_key(props, match):
    with pytest.raises(ParameterError, match=match):
        temple_for_lot(props, lot_rng(0, "x"), width=30, depth=50, module_range=(0.5, 1.3))


@pytest.mark.parametrize(
    "props",
    [
        {"arrangement": "dipteral", "front": 8, "intercolumniation": "eustyle"},
        {"arrangement": "in_antis"},
        {"arrangement": "peripteral", "front": 6, "lower_diameter": 0.5},
    ],
)
def test_a_lot_may_name_any_vitruvian_arrangement(props):
    """Another arrangement than the derived description's is a typed temple: the named keys
    kept, the others drawn, the module fitted to the lot (its plan within FILL of it)."""
    import tomllib

    from ionic_usd.city.types import FILL, _footprint
    from ionic_usd.temple.vitruvius import TempleType, type_from_table

    choice = temple_for_lot(props, lot_rng(0, "x"), width=30, depth=50, module_range=(0.5, 1.3))
    assert choice.description is not None
    typ = tomllib.loads(choice.description)["type"]
    for key, value in props.items():
        assert typ[key] == value
    t = type_from_table(typ, context="test")
    assert isinstance(t, TempleType)
    w, ln = _footprint(t)
    if "lower_diameter" not in props:  # sized to the lot
        assert w <= FILL * 30 * 1.001 and ln <= FILL * 50 * 1.001
        assert max(w / (FILL * 30), ln / (FILL * 50)) > 0.95  # and as large as it fits


def test_plan_refuses_bad_type_values(tmp_path):
    ring = [[0, 0], [30, 0], [30, 40], [0, 40], [0, 0]]
    for props, match in (({"front": 5}, "front"), ({"preset": "portunus", "front": 4}, "preset")):
        doc = {
            "type": "FeatureCollection",
            "features": [
                {
                    "type": "Feature",
                    "properties": {"type": "temple", **props},
                    "geometry": {"type": "Polygon", "coordinates": [ring]},
                }
            ],
        }
        p = tmp_path / "p.geojson"
        p.write_text(json.dumps(doc))
        with pytest.raises(ParameterError, match=match):
            read_geojson(p)


# -- stoas --------------------------------------------------------------------------------
D = StoaDims(height=6.0, lower_diameter=0.6, upper_diameter=0.51)


def _box(m):
    return m.points.min(axis=0), m.points.max(axis=0)


def test_stoa_bay_entablature_on_columns_roof_on_entablature_back_wall():
    parts = {m.name: m for m in bay_parts(D)}
    for m in parts.values():
        r = solid_report(m, intersections=False)
        assert r.open_edges == 0 and r.nonmanifold_edges == 0 and r.shells == 1, m.name
        assert r.volume > 0, m.name  # faces wound outwards
    lo, hi = _box(parts["Beam"])
    # on the column tops (y = column height), spanning the axes X = 0 … 1, within the
    # upper diameter of the axis line Z = 0
    assert lo[1] == pytest.approx(6.0) and (lo[0], hi[0]) == (0.0, 1.0)
    assert -lo[2] == hi[2] == pytest.approx(0.51 / 2)
    c_lo, c_hi = _box(parts["Cornice"])
    assert c_lo[1] == pytest.approx(hi[1]) and c_hi[1] == pytest.approx(D.top)
    bed_lo, _ = _box(parts["RoofBed"])
    roof = parts["Roof"]
    assert bed_lo[1] == pytest.approx(D.top)  # the roof's bed lies on the cornice
    # the roof's underside: at the cornice's front edge the bed's top, rising to the back
    under = roof.points[: len(roof.points) // 2]
    front = under[np.isclose(under[:, 2], D.front)]
    assert np.allclose(front[:, 1], D.top + D.bed)
    back = under[np.isclose(under[:, 2], -D.back)]
    assert (back[:, 1] > front[:, 1].max()).all()
    w_lo, w_hi = _box(parts["Wall"])
    assert w_lo[1] == 0.0 and w_hi[2] == pytest.approx(-D.depth)  # on the ground, behind
    # the wall's top meets the roof's underside over the wall
    wall_top = parts["Wall"].points[len(parts["Wall"].points) // 2 :]
    assert np.allclose(wall_top[:, 1], D.soffit(-wall_top[:, 2]))
    assert np.allclose(under[:, 1], D.soffit(-under[:, 2]))


def test_stoa_corner_is_closed_and_its_roof_halves_meet():
    for nb in (np.array([1.0, 0.0]), np.array([math.cos(0.5), -math.sin(0.5)])):
        parts = {m.name: m for m in corner_parts(D, nb)}
        for m in parts.values():
            r = solid_report(m, intersections=False)
            assert r.open_edges == 0 and r.shells == 1 and r.volume > 0, m.name
        a, b = parts["CornerRoofA"], parts["CornerRoofB"]
        # the two halves share the bisector edge at equal heights (a valley, no step)
        shared = [p for p in a.points if np.isclose(b.points, p).all(axis=1).any()]
        assert len(shared) == 4


def test_precinct_stoa_turns_its_corners_and_bays_tile_the_ring():
    ring = np.array([[0, 0], [0, 30], [30, 30], [30, 0]], dtype=float)  # clockwise: face in
    lay = porticus_stoa(Porticus("q", ring, 3.0, 1, closed=True), 3.0)
    assert len(lay.column_xz) == len(lay.bay_xz) == 40 and len(lay.corner_xz) == 4
    np.testing.assert_allclose(lay.corner_turn, 90.0)
    cols = {tuple(np.round(c, 6)) for c in lay.column_xz}
    for (x, z), yaw, ln in zip(lay.bay_xz, lay.bay_yaw, lay.bay_length, strict=True):
        a = math.radians(yaw)
        end = (x + ln * math.cos(a), z - ln * math.sin(a))
        assert (round(x, 6), round(z, 6)) in cols and tuple(np.round(end, 6)) in cols
        # the street (local +Z) is inside the ring, the stoa's back outside
        mid = np.array([x, -z]) + 0.5 * ln * np.array([math.cos(a), math.sin(a)])
        f = np.array([math.sin(a), -math.cos(a)])
        assert shapely.Polygon(ring).contains(shapely.Point(mid + 2 * f))
        assert not shapely.Polygon(ring).contains(shapely.Point(mid - 2 * f))
    corners = {tuple(np.round([x, -z], 6)) for x, z in lay.corner_xz}
    assert corners == {tuple(map(float, v)) for v in ring}


def test_ground_paves_the_streets_and_lies_under_every_lot():
    plan = read_geojson(FORUM)
    pts = np.concatenate([lot.outline for lot in plan.lots] + [p.line for p in plan.porticoes])
    meshes = {m.name: m for m in ground_meshes([x.outline for x in plan.lots], plan.plazas, pts)}
    assert set(meshes) == {"Paving", "Plazas", "Lots"}

    def area(m):
        t = m.points[m.face_vertex_indices.reshape(-1, 3)]
        cr = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])
        assert (cr[:, 1] > 0).all()  # every triangle faces up
        return 0.5 * cr[:, 1].sum()

    lo, hi = pts.min(axis=0) - 20, pts.max(axis=0) + 20
    site = np.prod(hi - lo)
    total = sum(area(m) for m in meshes.values())
    assert total == pytest.approx(site, rel=1e-9)  # the three tile the site: no overlap
    lots = shapely.union_all([shapely.Polygon(x.outline) for x in plan.lots])
    assert area(meshes["Lots"]) == pytest.approx(lots.area, rel=1e-9)
    assert all(np.allclose(m.points[:, 1], 0.0) for m in meshes.values())
    # under each lot's centre lies a lot triangle
    tri = meshes["Lots"].points[meshes["Lots"].face_vertex_indices.reshape(-1, 3)]
    polys = shapely.polygons([[(p[0], -p[2]) for p in t] for t in tri])
    for lot in plan.lots:
        c = shapely.Polygon(lot.outline).representative_point()
        assert shapely.contains(polys, c).any() or shapely.touches(polys, c).any(), lot.id


# -- stoas clear of the temples and of each other ----------------------------------------------


def _parts(sp, back):
    """Plan polygons of every kept bay and corner of a StoaPlan."""
    from ionic_usd.pipeline.city_extras import _bay_polygons, _corner_polygon

    class _L:
        bay_xz, bay_yaw, bay_length = sp.bay_xz, sp.bay_yaw, sp.bay_length

    polys = [shapely.Polygon(q) for q in _bay_polygons(_L, back)]
    polys += [
        shapely.Polygon(_corner_polygon(xz, yaw, nb, back))
        for xz, yaw, nb in zip(sp.corner_xz, sp.corner_yaw, sp.corner_normal, strict=True)
    ]
    return polys


def _overlaps(polys, others=()):
    """Pairs that overlap by more than 1e-3 m², brute force over every pair."""
    n = [(i, j) for i in range(len(polys)) for j in range(i + 1, len(polys))]
    bad = [(i, j) for i, j in n if polys[i].intersection(polys[j]).area > 1e-3]
    bad += [(i, -1) for i, p in enumerate(polys) for o in others if p.intersection(o).area > 1e-3]
    return bad


def test_stoas_back_to_back_crossing_and_bent_inward_leave_gaps_not_overlaps():
    from ionic_usd.city.plan import CityPlan
    from ionic_usd.pipeline.city_extras import _bay_polygons, lay_stoas

    back = 7.0
    porticoes = (
        # a street colonnaded both sides, then a second one crossing it
        Porticus("main", np.array([[-60.0, 0.0], [60.0, 0.0]]), 3.0, 2, offset=4.0),
        Porticus("cross", np.array([[0.0, -60.0], [0.0, 60.0]]), 3.0, 2, offset=4.0),
        # a single colonnade back to back with main's north side (4 m apart, 7 m deep each)
        Porticus("behind", np.array([[-30.0, 12.0], [30.0, 12.0]]), 3.0, 1),
        # an L bent so that the backs meet inside the bend
        Porticus("bent", np.array([[-100.0, 40.0], [-70.0, 40.0], [-70.0, 70.0]]), 3.0, 1),
    )
    lot = np.array([[20.0, 20.0], [40.0, 20.0], [40.0, 40.0], [20.0, 40.0]])
    plan = CityPlan((Lot("t", lot),), porticoes)
    whole = [porticus_stoa(p, 3.0) for p in porticoes]
    sp = lay_stoas(plan, 3.0, [], back)
    polys = _parts(sp, back)
    assert not _overlaps(polys, [shapely.Polygon(lot)])
    # the first porticus (listed first) is kept whole; the others give way
    assert len(sp.bay_xz) < sum(len(w.bay_xz) for w in whole)
    kept = {tuple(np.round(b, 6)) for b in sp.bay_xz}
    assert all(tuple(np.round(b, 6)) in kept for b in whole[0].bay_xz)
    # without the checks these inputs do overlap (the test is not vacuous)
    allp = [shapely.Polygon(q) for w in whole for q in _bay_polygons(w, back)]
    assert _overlaps(allp)
    # every kept column carries a kept bay: it is the start or the end of one
    ends = set()
    for (x, z), yaw, ln in zip(sp.bay_xz, sp.bay_yaw, sp.bay_length, strict=True):
        a = math.radians(yaw)
        ends |= {
            (round(x, 6), round(z, 6)),
            (round(x + ln * math.cos(a), 6), round(z - ln * math.sin(a), 6)),
        }
    assert {tuple(np.round(c, 6)) for c in sp.column_xz} <= ends
    assert sp.dropped == sum(len(w.column_xz) for w in whole) - len(sp.column_xz) > 0


def test_example_forum_stoas_are_whole_and_clear_of_every_lot():
    from ionic_usd.pipeline.city_extras import lay_stoas

    plan = read_geojson(FORUM)
    back = STOA_BACK
    sp = lay_stoas(plan, 3.0, [lot.outline for lot in plan.lots], back)
    whole = [porticus_stoa(p, 3.0) for p in plan.porticoes]
    # the example is laid out so that nothing gives way: every bay and corner is kept
    assert len(sp.bay_xz) == sum(len(w.bay_xz) for w in whole)
    assert len(sp.corner_xz) == sum(len(w.corner_xz) for w in whole) == 4
    assert sp.dropped == 0
    assert not _overlaps(_parts(sp, back), [shapely.Polygon(lot.outline) for lot in plan.lots])


def test_a_temple_build_key_follows_the_code(monkeypatch):
    """A city's temple builds are cached by key: an edit of the package's code (or a new
    library) must change it, or a city reuses temples the old code built."""
    from ionic_usd.pipeline import keys
    from ionic_usd.pipeline.spec import TempleSpec

    text = "[temple]\nname = 'x'\n"
    before = TempleSpec("x", text).key
    assert TempleSpec("x", text).key == before  # deterministic
    monkeypatch.setattr(keys, "source_digest", lambda: "an edited generator")
    edited = TempleSpec("x", text).key
    monkeypatch.setattr(keys, "library_versions", lambda: "numpy 9")
    assert len({before, edited, TempleSpec("x", text).key}) == 3


def test_street_column_build_does_not_depend_on_the_code_digest():
    """The default grid has builds tied at the slenderest module; the street column's build
    must be the same whatever the keys (they hold the code's digest): a tie broken by key
    gave the streets another temple's column after any edit of the code."""
    from ionic_usd.pipeline.city_extras import street_column_spec

    specs = _specs(grid_plan(), rows=5, cols=5).specs
    slender = min(s.layout().params.columns_lower_diameter for s in specs)
    tied = [s for s in specs if s.layout().params.columns_lower_diameter == slender]
    assert len(tied) >= 2  # else this test shows nothing
    chosen = []
    for salt in "abcdefgh":
        for s in specs:  # a new code digest: new keys, in another order
            s.__dict__["key"] = hashlib.sha256((salt + s.description).encode()).hexdigest()
        chosen.append(street_column_spec(specs).description)
        assert street_column_spec(list(reversed(specs))).description == chosen[-1]
    assert len(set(chosen)) == 1
