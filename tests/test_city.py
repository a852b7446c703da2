"""City scale: the city build (plan and grid), prototype sharing, hierarchy, layers, LOD."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import shapely
from pxr import Sdf, Usd, UsdGeom

from ionic_usd.city.plan import read_geojson
from ionic_usd.cli import main
from ionic_usd.errors import BudgetError, OutputExistsError, ParameterError
from ionic_usd.pipeline.city import CityOptions, build_city
from ionic_usd.usd import validate_stage

FORUM = Path(__file__).resolve().parents[1] / "examples" / "forum.geojson"
TEX = 64


def _files(folder: Path) -> dict[str, bytes]:
    return {
        f.relative_to(folder).as_posix(): f.read_bytes()
        for f in sorted(folder.rglob("*"))
        if f.is_file()
    }


def _validate_each_layer(folder: Path) -> None:
    """Every layer the city writes is valid on its own, and the composed city too."""
    assert validate_stage(Usd.Stage.Open(str(folder / "Instances.usdc"))) == []
    for extra in ("Ground.usda", "Stoas/Stoa.usda"):  # the ground and the stoas' parts
        if not (folder / extra).exists():  # a city without porticoes has no stoas
            continue
        assert validate_stage(Usd.Stage.Open(str(folder / extra))) == [], extra
    # the root without its sublayer, saved beside it so relative paths anchor the same way
    alone = folder / "_root_alone.usda"
    layer = Sdf.Layer.OpenAsAnonymous(str(folder / "City.usda"))
    layer.subLayerPaths.clear()
    layer.Export(str(alone))
    try:
        assert validate_stage(Usd.Stage.Open(str(alone))) == []
    finally:
        alone.unlink()
    assert validate_stage(Usd.Stage.Open(str(folder / "City.usda"))) == []


def _model_hierarchy_ok(stage: Usd.Stage) -> list[str]:
    bad = []
    for prim in stage.Traverse():
        if Usd.ModelAPI(prim).GetKind():
            parent = prim.GetParent()
            if not (parent.IsPseudoRoot() or parent.IsModel()):
                bad.append(str(prim.GetPath()))
    return bad


@pytest.fixture(scope="module")
def grid_city(tmp_path_factory):
    out = tmp_path_factory.mktemp("grid") / "city"
    # one description for every lot (the uniform city: one build); the varied city's many
    # builds are tested (slow) in test_city_vary.py
    opts = CityOptions(rows=3, cols=3, texture_size=TEX, seed=1, temple="portunus")
    return out, build_city(out, opts), opts


def test_grid_city_instances_share_prototypes(grid_city):
    out, s, _ = grid_city
    stage = Usd.Stage.Open(str(out / "City.usda"))
    temples = stage.GetPrimAtPath("/City/Temples").GetChildren()
    assert len(temples) == 9 == s["temples"] and all(t.IsInstance() for t in temples)
    sels = {tuple(sorted(t.GetVariantSets().GetAllVariantSelections().items())) for t in temples}
    assert s["temple_prototypes"] == len(sels) == len({t.GetPrototype() for t in temples})
    assert 1 < len(sels) < 9  # seeded variety, and equal choices share a prototype
    pi = UsdGeom.PointInstancer(stage.GetPrimAtPath("/City/Porticus"))
    idx = np.asarray(pi.GetProtoIndicesAttr().Get())
    # 2 streets × 2 sides × columns every 3 m along 3 blocks of 60 m (the ends included)
    assert len(idx) == s["columns"] == 2 * 2 * (int(180 / 3) + 1)
    proto = stage.GetPrimAtPath(pi.GetPrototypesRel().GetTargets()[0])
    assert proto.GetVariantSets().GetVariantSet("lod").GetVariantSelection() == "low"
    assert proto.IsModel() and any(p.IsA(UsdGeom.Mesh) for p in Usd.PrimRange(proto))
    assert s["unique_prototypes"] == s["temple_prototypes"] + 1


def test_grid_city_layers_hierarchy_and_bounds(grid_city):
    out, s, _ = grid_city
    _validate_each_layer(out)
    assert (out / "Instances.usdc").read_bytes()[:8] == b"PXR-USDC"
    stage = Usd.Stage.Open(str(out / "City.usda"))
    assert _model_hierarchy_ok(stage) == []
    assert Usd.ModelAPI(stage.GetPrimAtPath("/City")).GetKind() == "assembly"
    # the hint (a range per purpose) read as BBoxCache reads it equals the computed bound
    hinted, box = (
        UsdGeom.BBoxCache(Usd.TimeCode.Default(), ["default", "render"], useExtentsHint=use)
        .ComputeWorldBound(stage.GetPrimAtPath("/City"))
        .ComputeAlignedRange()
        for use in (True, False)
    )
    np.testing.assert_allclose(np.array(hinted.GetMin()), np.array(box.GetMin()), atol=1e-3)
    np.testing.assert_allclose(np.array(hinted.GetMax()), np.array(box.GetMax()), atol=1e-3)
    # the stoas: one bay between every two neighbouring street columns, each bay starting on
    # a column; the ground under it all
    stoas = UsdGeom.PointInstancer(stage.GetPrimAtPath("/City/Stoas"))
    idx = np.asarray(stoas.GetProtoIndicesAttr().Get())
    assert len(idx) == s["stoa_bays"] + s["stoa_corners"] and s["stoa_bays"] > 0
    bays = np.asarray(stoas.GetPositionsAttr().Get(), dtype=float)[idx == 0]
    cols = np.asarray(
        UsdGeom.PointInstancer(stage.GetPrimAtPath("/City/Porticus")).GetPositionsAttr().Get()
    )
    near = np.min(np.linalg.norm(bays[:, None, [0, 2]] - cols[None, :, [0, 2]], axis=2), axis=1)
    assert (near < 1e-3).all()
    # 2 streets x 2 sides: 4 lines of 61 columns and 60 bays each
    assert s["columns"] == 244 and s["stoa_bays"] == 240 and s["stoa_corners"] == 0
    ground = stage.GetPrimAtPath("/City/Ground")
    assert ground.IsModel() and {c.GetName() for c in ground.GetChildren()} >= {"Paving", "Lots"}


def _meshes(stage: Usd.Stage) -> int:
    pred = Usd.TraverseInstanceProxies(Usd.PrimAllPrimsPredicate)
    return sum(1 for p in Usd.PrimRange(stage.GetPseudoRoot(), pred) if p.IsA(UsdGeom.Mesh))


def test_unloaded_city_composes_no_mesh_and_loads_by_region(grid_city):
    """Each temple is a payload (the street columns' asset has its own): a city opened with
    LoadNone composes no mesh at all; load_region loads the temples of one block only."""
    from ionic_usd.usd.city import load_region

    out, s, _ = grid_city
    stage = Usd.Stage.Open(str(out / "City.usda"), Usd.Stage.LoadNone)
    assert _meshes(stage) == 0
    temples = stage.GetPrimAtPath("/City/Temples").GetAllChildren()  # unloaded: not "Children"
    xz = {str(t.GetPath()): t.GetAttribute("xformOp:translate").Get() for t in temples}
    x0 = min(v[0] for v in xz.values())
    z0 = min(v[2] for v in xz.values())
    loaded = load_region(stage, (x0 - 1, z0 - 1), (x0 + 1, z0 + 1))
    assert len(loaded) == 1
    assert stage.GetPrimAtPath(loaded[0]).IsLoaded()
    assert not any(stage.GetPrimAtPath(p).IsLoaded() for p in xz if p not in loaded)
    one = _meshes(stage)
    assert one > 0
    full = Usd.Stage.Open(str(out / "City.usda"))
    assert _meshes(full) > one * (s["temples"] - 1)


def test_city_extents_hint_is_uniform_true_for_every_purpose(grid_city):
    out, _, _ = grid_city
    stage = Usd.Stage.Open(str(out / "City.usda"))
    city = stage.GetPrimAtPath("/City")
    attr = UsdGeom.ModelAPI(city).GetExtentsHintAttr()
    assert attr.GetVariability() == Sdf.VariabilityUniform
    for purposes in (["default"], ["render"], ["proxy"], ["default", "render"]):
        hinted, computed = (
            UsdGeom.BBoxCache(Usd.TimeCode.Default(), purposes, useExtentsHint=use)
            .ComputeUntransformedBound(city)
            .ComputeAlignedRange()
            for use in (True, False)
        )
        assert not computed.IsEmpty(), purposes
        np.testing.assert_allclose(hinted.GetMin(), computed.GetMin(), atol=1e-3)
        np.testing.assert_allclose(hinted.GetMax(), computed.GetMax(), atol=1e-3)


def test_rebuild_reuses_and_is_byte_identical(grid_city, tmp_path):
    out, s, opts = grid_city
    again = build_city(tmp_path / "again", opts)
    assert again["prototypes_built"] == 0 and again["prototypes_reused"] == s["builds"]
    assert _files(tmp_path / "again") == _files(out)
    with pytest.raises(OutputExistsError):
        build_city(out, opts)


def test_temples_as_point_instancer_draw_the_same(grid_city, tmp_path):
    out, s, opts = grid_city
    from dataclasses import replace

    pi_city = build_city(tmp_path / "pi", replace(opts, instancer_threshold=0))
    assert pi_city["temples_as"] == "point-instancer"
    assert pi_city["triangles"] == s["triangles"]
    assert pi_city["temple_prototypes"] == s["temple_prototypes"]
    stage = Usd.Stage.Open(str(tmp_path / "pi" / "City.usda"))
    field = UsdGeom.PointInstancer(stage.GetPrimAtPath("/City/Temples/Field"))
    assert len(field.GetProtoIndicesAttr().Get()) == 9
    assert len(field.GetPrototypesRel().GetTargets()) == s["temple_prototypes"]
    assert _model_hierarchy_ok(stage) == []
    _validate_each_layer(tmp_path / "pi")
    ref = Usd.Stage.Open(str(out / "City.usda"))
    cache = UsdGeom.BBoxCache(Usd.TimeCode.Default(), ["default", "render"])
    a = cache.ComputeWorldBound(ref.GetPrimAtPath("/City/Temples")).ComputeAlignedRange()
    cache.Clear()
    b = cache.ComputeWorldBound(stage.GetPrimAtPath("/City/Temples")).ComputeAlignedRange()
    np.testing.assert_allclose(np.array(a.GetMin()), np.array(b.GetMin()), atol=1e-3)
    np.testing.assert_allclose(np.array(a.GetMax()), np.array(b.GetMax()), atol=1e-3)


@pytest.mark.slow
def test_plan_city_buildings_on_lots_porticoes_on_lines(tmp_path):
    out = tmp_path / "forum"
    s = build_city(
        out,
        CityOptions(
            plan=str(FORUM), texture_size=TEX, focus=(0.0, 0.0), lod_distances=(60.0, 120.0)
        ),
    )
    plan = read_geojson(FORUM)
    stage = Usd.Stage.Open(str(out / "City.usda"))
    # every lot a build of its own: 21 lots, types chosen or named, the east one Portunus
    assert s["builds"] == len({c["build"] for c in s["lots"]}) >= 20
    for lot in plan.lots:
        prim = stage.GetPrimAtPath(f"/City/Temples/Temple_{lot.id}")
        assert prim.IsInstance()
        # the corners of the temple's composed bounds (its prototype: its own frame),
        # placed by the temple's transform, land inside the lot
        rng = (
            UsdGeom.BBoxCache(Usd.TimeCode.Default(), ["default", "render"])
            .ComputeWorldBound(prim.GetPrototype())
            .ComputeAlignedRange()
        )
        m = UsdGeom.Xformable(prim).ComputeLocalToWorldTransform(Usd.TimeCode.Default())
        lo, hi = rng.GetMin(), rng.GetMax()
        corners = [m.Transform((x, 0.0, z)) for x in (lo[0], hi[0]) for z in (lo[2], hi[2])]
        pts = shapely.points([(c[0], -c[2]) for c in corners])
        lot_poly = shapely.Polygon(lot.outline).buffer(0.05)
        assert shapely.contains(lot_poly, pts).all(), lot.id
    east = stage.GetPrimAtPath("/City/Temples/Temple_aedes_east")
    assert (
        east.GetVariantSets().GetVariantSet("hyp_flutes_20").GetVariantSelection() == "alternative"
    )
    pi = UsdGeom.PointInstancer(stage.GetPrimAtPath("/City/Porticus"))
    pos = np.asarray(pi.GetPositionsAttr().Get(), dtype=float)
    plan_pts = shapely.points(np.stack([pos[:, 0], -pos[:, 2]], axis=1))
    lines = []
    for p in plan.porticoes:
        g = shapely.LinearRing(p.line) if p.closed else shapely.LineString(p.line)
        lines.append((g, p.offset if p.sides == 2 else 0.0))
    d = np.min([np.abs(shapely.distance(g, plan_pts) - off) for g, off in lines], axis=0)
    assert (d < 1e-3).mean() > 0.97 and (d < 3.0).all()  # on their lines (mitred corners)
    assert len(pos) == s["columns"] > 300
    # LOD by distance from the focus: near columns high, far ones low
    idx = np.asarray(pi.GetProtoIndicesAttr().Get())
    names = [t.name for t in pi.GetPrototypesRel().GetTargets()]
    lods = np.array([names[i].split("_")[1] for i in idx])
    r = np.hypot(pos[:, 0], pos[:, 2])
    # (far columns: the low column, or its card prototype — lod low drawn as cards — past
    # the card distance)
    assert (lods[r < 59] == "high").all() and np.isin(lods[r > 121], ("low", "cards")).all()
    assert s["triangles"]["high"] > s["triangles"]["as authored"] > s["triangles"]["low"]
    _validate_each_layer(out)
    assert _model_hierarchy_ok(stage) == []


def test_memory_estimate_refuses_before_writing(tmp_path):
    with pytest.raises(BudgetError, match="GB"):
        build_city(
            tmp_path / "big", CityOptions(columns=10_000_000, memory_limit_gb=1.0, texture_size=TEX)
        )
    assert not (tmp_path / "big").exists()


def test_million_columns_arrays(grid_city, tmp_path):
    out, s, opts = grid_city
    from dataclasses import replace

    big = build_city(tmp_path / "m", replace(opts, columns=200_000))
    assert big["columns"] == 200_000
    stage = Usd.Stage.Open(str(tmp_path / "m" / "City.usda"))
    pi = UsdGeom.PointInstancer(stage.GetPrimAtPath("/City/Porticus"))
    pos = np.asarray(pi.GetPositionsAttr().Get())
    assert len(pos) == 200_000 and np.isfinite(pos).all()
    assert len(np.unique(pos.round(3), axis=0)) == 200_000
    q = np.asarray(pi.GetOrientationsAttr().Get(), dtype=float)
    np.testing.assert_allclose(np.linalg.norm(q, axis=1), 1.0, atol=2e-3)


def test_cli_city_json_and_errors(grid_city, tmp_path, capsys):
    out, s, _ = grid_city
    summary = tmp_path / "s.json"
    assert (
        main(
            [
                "city",
                str(tmp_path / "c"),
                "--rows",
                "3",
                "--cols",
                "3",
                "--seed",
                "1",
                "--temple",
                "portunus",
                "--texture-size",
                str(TEX),
                "--json",
                str(summary),
            ]
        )
        == 0
    )
    d = json.loads(summary.read_text())
    assert d["prototypes_reused"] == 1 and d["workers"] == []
    assert d["instances"] == 9 + d["columns"] and "timings" in d
    capsys.readouterr()
    assert main(["city", str(tmp_path / "x"), "--plan", str(tmp_path / "none.geojson")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "none.geojson" in err
    assert not (tmp_path / "x").exists()
    with pytest.raises(SystemExit):
        main(["city", str(tmp_path / "y"), "--focus", "1"])
    with pytest.raises(ParameterError):
        CityOptions(lod_distances=(100.0, 10.0))
    capsys.readouterr()
    assert main(["city", str(tmp_path / "z"), "--focus", "0,0", "--cards-beyond", "-5"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--cards-beyond" in err and not (tmp_path / "z").exists()
    with pytest.raises(ParameterError, match="--card-size"):
        CityOptions(card_size=8)


@pytest.mark.parametrize("n, scaled", [(500, False), (500, True), (20_000, False)])
def test_instance_bounds_match_brute_force(n, scaled):
    from ionic_usd.usd.city_prototypes import instance_bounds

    rng = np.random.default_rng(n + scaled)
    lo = np.array([[-1.0, 0.0, -2.0], [-3.0, 0.5, -1.0]])
    hi = np.array([[1.0, 5.0, 2.5], [2.0, 9.0, 1.0]])
    idx = rng.integers(0, 2, n)
    xz, yaw = rng.random((n, 2)) * 500, rng.random(n) * 360
    s = rng.random(n) + 0.5 if scaled else None
    got = instance_bounds(lo, hi, idx, xz, yaw, s)
    a = np.radians(yaw)
    S = np.ones(n) if s is None else s
    pts = []
    for ix in (0, 1):  # every corner of every placed box
        for iy in (0, 1):
            for iz in (0, 1):
                px = np.where(ix, hi[idx, 0], lo[idx, 0]) * S
                py = np.where(iy, hi[idx, 1], lo[idx, 1]) * S
                pz = np.where(iz, hi[idx, 2], lo[idx, 2]) * S
                pts.append(
                    np.stack(
                        [
                            px * np.cos(a) + pz * np.sin(a) + xz[:, 0],
                            py,
                            -px * np.sin(a) + pz * np.cos(a) + xz[:, 1],
                        ],
                        axis=1,
                    )
                )
    pts = np.concatenate(pts)
    np.testing.assert_allclose(got[0], pts.min(axis=0), atol=1e-9)
    np.testing.assert_allclose(got[1], pts.max(axis=0), atol=1e-9)


def test_lod_by_distance_selects_the_temple_lod_set(grid_city, tmp_path):
    """Each temple gets the LOD of its distance from the focus through the temple's own
    ``lod`` variant set (which passes it to every column); equal LODs share a prototype."""
    import shutil

    from ionic_usd.blueprint.city import ColumnInstances, TempleInstances
    from ionic_usd.usd.city import compose_city

    out, s, _ = grid_city
    src = next((out / "Temples").iterdir())
    shutil.copytree(src, tmp_path / "Temples" / src.name)
    xz = np.array([[0.0, 0.0], [200.0, 0.0], [600.0, 0.0], [610.0, 0.0]])
    temples = TempleInstances(
        [f"Temples/{src.name}"],
        np.zeros(4, dtype=np.int32),
        ["a", "b", "c", "d"],
        xz,
        np.zeros(4),
        np.ones(4),
        [{}, {}, {}, {}],
        lod=np.array([0, 1, 2, 2], dtype=np.int8),
    )
    columns = ColumnInstances(
        f"Temples/{src.name}/IonicColumn/IonicColumn.usda", np.zeros((0, 2)), np.zeros(0)
    )
    rep = compose_city(tmp_path, temples, columns)
    stage = Usd.Stage.Open(str(rep.path))
    got = [
        stage.GetPrimAtPath(f"/City/Temples/Temple_{n}")
        .GetVariantSets()
        .GetVariantSet("lod")
        .GetVariantSelection()
        for n in "abcd"
    ]
    assert got == ["high", "medium", "low", "low"] and rep.temple_prototypes == 3
    # the lod reaches the columns inside each (instanced) temple
    for n, lod in zip("abcd", got, strict=True):
        temple = stage.GetPrimAtPath(f"/City/Temples/Temple_{n}")
        cols = [
            p
            for p in Usd.PrimRange(temple, Usd.TraverseInstanceProxies())
            if p.IsInstance() and p.GetVariantSets().HasVariantSet("form")
        ]
        assert cols and {c.GetVariantSets().GetVariantSelection("lod") for c in cols} == {lod}


# -- cards for the far field (UsdGeomModelAPI draw mode) ----------------------------------------
CARD_PX = 64


@pytest.fixture(scope="module")
def card_city(tmp_path_factory):
    out = tmp_path_factory.mktemp("cards") / "city"
    opts = CityOptions(
        rows=1,
        cols=3,
        temple="portunus",
        texture_size=TEX,
        seed=1,
        focus=(0.0, 0.0),
        cards_beyond=100.0,
        card_size=CARD_PX,
        columns=0,
    )
    return out, build_city(out, opts), opts


def _temples_by_distance(stage: Usd.Stage) -> dict[str, float]:
    out = {}
    for t in stage.GetPrimAtPath("/City/Temples").GetChildren():
        x, _, z = t.GetAttribute("xformOp:translate").Get()
        out[str(t.GetPath())] = float(np.hypot(x, z))  # focus (0, 0)
    return out


def _read_rgba(path: Path) -> np.ndarray:
    import OpenImageIO as oiio

    inp = oiio.ImageInput.open(str(path))
    assert inp is not None, oiio.geterror()
    px = np.asarray(inp.read_image(oiio.UINT8))
    inp.close()
    return px


def test_far_temples_carry_card_draw_mode_with_baked_images(card_city):
    out, s, opts = card_city
    stage = Usd.Stage.Open(str(out / "City.usda"))
    dist = _temples_by_distance(stage)
    far = {p for p, d in dist.items() if d > opts.cards_beyond}
    assert 0 < len(far) < len(dist) and s["cards"]["temples"] == len(far)
    folders = {
        Path(stage.GetPrimAtPath(p).GetAttribute("model:cardTextureXPos").Get().resolvedPath).parent
        for p in far
    }
    # one set of images per temple prototype (build + hypotheses), shared by its lots
    assert len(folders) == s["cards"]["prototypes"] == s["cards"]["baked"]
    assert folders == set((out / "Temples" / "Cards").iterdir())
    for path in dist:
        prim = stage.GetPrimAtPath(path)
        api = UsdGeom.ModelAPI(prim)
        if path not in far:
            assert not prim.HasAPI(UsdGeom.ModelAPI) or not api.GetModelApplyDrawModeAttr().Get()
            continue
        # drawMode takes effect on a model whose applyDrawMode is true: the temple instance
        assert prim.IsModel() and prim.HasAPI(UsdGeom.ModelAPI)
        assert api.GetModelApplyDrawModeAttr().Get() is True
        assert api.ComputeModelDrawMode() == UsdGeom.Tokens.cards
        assert api.GetModelCardGeometryAttr().Get() == "box"
        for face in ("XPos", "XNeg", "YPos", "YNeg", "ZPos", "ZNeg"):
            asset = prim.GetAttribute(f"model:cardTexture{face}").Get()
            assert asset.path.startswith("./Temples/Cards/") and asset.path.endswith(f"/{face}.png")
            png = Path(asset.resolvedPath)
            assert png.is_file() and png.parent.parent == out / "Temples" / "Cards"
            px = _read_rgba(png)
            h, w, c = px.shape
            assert c == 4 and max(h, w) == CARD_PX and min(h, w) >= 16
            alpha = px[..., 3]
            assert (alpha == 0).any() and (alpha == 255).any()  # a silhouette, not a box
    assert _model_hierarchy_ok(stage) == []
    _validate_each_layer(out)


def test_baked_card_shows_the_temple(card_city):
    """The front card covers a plausible part of its frame, the side less (the colonnade's
    gaps, the pediment's corners), and the stone is lit, not black or flat."""
    out, _, _ = card_city
    folder = sorted((out / "Temples" / "Cards").iterdir())[0]
    front, side = _read_rgba(folder / "ZPos.png"), _read_rgba(folder / "XPos.png")
    cover_front = np.mean(front[..., 3] >= 128)
    cover_side = np.mean(side[..., 3] >= 128)
    assert 0.5 < cover_front < 0.95 and 0.4 < cover_side < 0.9
    assert cover_side < cover_front
    stone = front[front[..., 3] >= 128][:, :3].astype(float)
    assert 60 < stone.mean() < 245 and stone.std() > 4
    # the pediment narrows upwards: the top row is covered less than the middle
    rows = (front[..., 3] >= 128).mean(axis=1)
    assert rows[2] < rows[len(rows) // 2]


def test_reader_and_preview_draw_cards_far_and_meshes_near(card_city, tmp_path):
    from ionic_usd.preview import render_preview
    from ionic_usd.usd.reader import read_scene

    out, s, opts = card_city
    stage = Usd.Stage.Open(str(out / "City.usda"))
    dist = _temples_by_distance(stage)
    far = {p for p, d in dist.items() if d > opts.cards_beyond}
    drawn = read_scene(out / "City.usda", draw_modes=True)
    full = read_scene(out / "City.usda")

    def tris(scene, temple):
        return sum(
            scene.meshes[p.mesh].n_triangles
            for p in scene.placements
            if p.path == temple or p.path.startswith(temple + "/")
        )

    for temple in dist:
        cards = [p for p in drawn.placements if drawn.meshes[p.mesh].card_face and p.path == temple]
        if temple in far:
            assert len(cards) == 6 and tris(drawn, temple) == 12 < tris(full, temple)
        else:
            assert not cards and tris(drawn, temple) == tris(full, temple) > 10_000
    assert drawn.n_triangles == s["triangles"]["as authored"]
    assert s["triangles"]["without cards"] - drawn.n_triangles == sum(
        tris(full, t) - 12 for t in far
    )
    stats = render_preview(out / "City.usda", tmp_path / "c.png", width=96, height=64, samples=0)
    assert stats.triangles == drawn.n_triangles and stats.cards == 6 * len(far)


def test_cards_are_reused_and_work_in_a_temple_point_instancer(card_city, tmp_path):
    import shutil
    from dataclasses import replace

    from ionic_usd.usd.reader import read_scene

    out, s, opts = card_city
    # the images are content-addressed: a build that finds them in place bakes nothing
    shutil.copytree(out / "Temples" / "Cards", tmp_path / "pi" / "Temples" / "Cards")
    pi = build_city(tmp_path / "pi", replace(opts, instancer_threshold=0))
    assert pi["cards"]["temples"] == s["cards"]["temples"]
    assert pi["cards"]["baked"] == 0 and pi["cards"]["reused"] == s["cards"]["prototypes"]
    assert pi["triangles"] == s["triangles"]
    stage = Usd.Stage.Open(str(tmp_path / "pi" / "City.usda"))
    protos = stage.GetPrimAtPath("/City/Temples/Field/Prototypes").GetChildren()
    carded = [p for p in protos if UsdGeom.ModelAPI(p).ComputeModelDrawMode() == "cards"]
    assert carded and all(p.IsModel() for p in carded)
    assert _model_hierarchy_ok(stage) == []
    _validate_each_layer(tmp_path / "pi")
    assert (
        read_scene(tmp_path / "pi" / "City.usda", draw_modes=True).n_triangles
        == s["triangles"]["as authored"]
    )


def test_composer_counts_what_the_reader_draws(grid_city):
    """The summary's triangles (as authored: no focus, each temple at the file's own lod) are
    what a renderer draws, counted by the one reader on the composed city."""
    from ionic_usd.usd.reader import read_scene

    out, s, _ = grid_city
    assert read_scene(out / "City.usda").n_triangles == s["triangles"]["as authored"]


@pytest.fixture(scope="module")
def column_card_city(tmp_path_factory):
    """Two temples (at 0 m and 60 m from the focus, both near) and their street columns, the
    ones beyond 65 m drawn as cards."""
    out = tmp_path_factory.mktemp("colcards") / "city"
    opts = CityOptions(
        rows=1,
        cols=2,
        temple="portunus",
        texture_size=TEX,
        seed=1,
        focus=(0.0, 0.0),
        cards_beyond=65.0,
        card_size=CARD_PX,
    )
    return out, build_city(out, opts), opts


def test_far_street_columns_use_the_card_prototype(column_card_city, tmp_path):
    from ionic_usd.preview import render_preview
    from ionic_usd.usd.reader import read_scene

    out, s, opts = column_card_city
    stage = Usd.Stage.Open(str(out / "City.usda"))
    pi = UsdGeom.PointInstancer(stage.GetPrimAtPath("/City/Porticus"))
    pos = np.asarray(pi.GetPositionsAttr().Get())
    idx = np.asarray(pi.GetProtoIndicesAttr().Get())
    protos = [stage.GetPrimAtPath(t) for t in pi.GetPrototypesRel().GetTargets()]
    names = np.array([p.GetName() for p in protos])
    far = np.hypot(pos[:, 0], pos[:, 2]) > opts.cards_beyond  # focus (0, 0)
    assert 0 < far.sum() < len(far) and s["cards"]["columns"] == int(far.sum())
    assert s["cards"]["temples"] == 0  # the temples are near: only columns are cards
    # exactly the far columns are drawn by the card prototype
    assert np.array_equal(names[idx] == "Column_cards", far)
    card = protos[list(names).index("Column_cards")]
    api = UsdGeom.ModelAPI(card)
    assert card.IsModel() and Usd.ModelAPI(card).GetKind() == "component"
    assert card.HasAPI(UsdGeom.ModelAPI) and api.GetModelApplyDrawModeAttr().Get() is True
    assert api.ComputeModelDrawMode() == UsdGeom.Tokens.cards
    assert api.GetModelCardGeometryAttr().Get() == "box"
    # what ignores draw modes draws the low column
    assert card.GetVariantSets().GetVariantSelection("lod") == "low"
    for face in ("XPos", "XNeg", "YPos", "YNeg", "ZPos", "ZNeg"):
        png = Path(card.GetAttribute(f"model:cardTexture{face}").Get().resolvedPath)
        alpha = _read_rgba(png)[..., 3]
        assert png.parent.parent == out / "Temples" / "Cards"
        assert (alpha == 0).any() and (alpha == 255).any()  # the column's silhouette
    for p in protos:  # the near prototypes are full geometry
        if p != card:
            assert (
                not p.HasAPI(UsdGeom.ModelAPI)
                or UsdGeom.ModelAPI(p).ComputeModelDrawMode() != UsdGeom.Tokens.cards
            )
    assert _model_hierarchy_ok(stage) == []
    _validate_each_layer(out)
    # the reader and the preview draw what the composer counted
    drawn = read_scene(out / "City.usda", draw_modes=True)
    full = read_scene(out / "City.usda")
    assert drawn.n_triangles == s["triangles"]["as authored"]

    def column_tris(scene, instance: int) -> int:
        key = f"/City/Porticus[{instance}]"
        return sum(
            scene.meshes[p.mesh].n_triangles
            for p in scene.placements
            if p.path == key or p.path.startswith(key + "/")
        )

    i_far, i_near = int(np.flatnonzero(far)[0]), int(np.flatnonzero(~far)[0])
    assert column_tris(drawn, i_far) == 12 < column_tris(full, i_far)
    assert column_tris(drawn, i_near) == column_tris(full, i_near) > 12
    # "without cards" puts each far column at its lod by distance: high (all are within the
    # default near distance, 150 m), as the near column draws
    assert s["triangles"]["without cards"] - drawn.n_triangles == int(far.sum()) * (
        column_tris(full, i_near) - 12
    )
    stats = render_preview(out / "City.usda", tmp_path / "c.png", width=96, height=64, samples=0)
    assert stats.triangles == drawn.n_triangles and stats.cards == 6 * int(far.sum())


@pytest.mark.parametrize("layer", ["City.usda", "Instances.usdc"])
def test_an_existing_city_is_refused_before_any_work(tmp_path, capsys, layer):
    """One check (``check_city_output``) refuses a folder holding a city's layer: the command
    line before any work (one line, status 2, nothing touched), the API too."""
    from ionic_usd.pipeline.city import check_city_output

    folder = tmp_path / "city"
    folder.mkdir()
    (folder / layer).write_bytes(b"#usda 1.0\n")
    before = _files(folder)
    capsys.readouterr()
    assert main(["city", str(folder), "--rows", "1", "--cols", "1", "-q"]) == 2
    err = capsys.readouterr().err
    assert len(err.splitlines()) == 1 and layer in err and "--force" in err
    assert _files(folder) == before
    with pytest.raises(OutputExistsError, match=layer):
        build_city(folder, CityOptions(rows=1, cols=1))
    assert _files(folder) == before
    assert check_city_output(folder, force=True) == folder
    (tmp_path / "file").write_bytes(b"")
    with pytest.raises(ParameterError, match="existing file"):
        check_city_output(tmp_path / "file", force=True)
