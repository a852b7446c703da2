"""Temple composition that holds in production: every layer alone, model hierarchy, one material
library, the user's layer strongest, hypotheses in every combination, classes, xform ops, lod."""

from __future__ import annotations

import itertools
from pathlib import Path

import numpy as np
import pytest
from pxr import Gf, Sdf, Usd, UsdGeom, UsdShade

from ionic_usd.cli import main
from ionic_usd.errors import ParameterError
from ionic_usd.params import load_toml
from ionic_usd.pipeline.temple import compose_temple
from ionic_usd.temple.layout import ROOF_BED, layout_from_mapping, portunus_layout
from ionic_usd.usd import validate_stage
from ionic_usd.usd.column_asset import UV_SPAN
from ionic_usd.usd.temple import hypothesis_layers, temple_triangles

EVERYTHING = Usd.TraverseInstanceProxies(Usd.PrimAllPrimsPredicate)


def folder_of(report) -> Path:
    return report.root.parent


def layer_files(folder: Path) -> list[Path]:
    return sorted(f for f in folder.rglob("*") if f.suffix in (".usda", ".usdc", ".usd"))


def select(stage: Usd.Stage, **selections: str) -> None:
    with Usd.EditContext(stage, stage.GetSessionLayer()):
        for vs, v in selections.items():
            stage.GetPrimAtPath("/Temple").GetVariantSet(vs).SetVariantSelection(v)


def assert_contiguous_models(stage: Usd.Stage, where: str) -> None:
    for prim in Usd.PrimRange(stage.GetPseudoRoot(), EVERYTHING):
        if prim.IsPseudoRoot() or not prim.IsModel():
            continue
        parent = prim.GetParent()
        assert parent.IsPseudoRoot() or parent.IsGroup(), (where, str(prim.GetPath()))


def test_every_layer_alone_is_a_valid_stage(portunus_temple):
    folder = folder_of(portunus_temple)
    files = layer_files(folder)
    names = {f.relative_to(folder).as_posix() for f in files}
    assert {
        "Temple.usda",
        "generated.usda",
        "overrides.usda",
        "materials.usda",
        "podium.usda",
        "cella.usda",
        "entablature.usda",
        "roof.usda",
        "colonnade.usda",
        "IonicColumn/IonicColumn.usda",
        "IonicColumn/Payload/Geometry.usdc",
        "layers/roof-pitch-15.usda",
    } <= names
    for f in files:
        layer = Sdf.Layer.FindOrOpen(str(f))
        where = f.relative_to(folder).as_posix()
        assert layer.pseudoRoot.GetInfo("upAxis") == "Y", where
        assert layer.pseudoRoot.GetInfo("metersPerUnit") == 1.0, where
        assert layer.defaultPrim, where
        spec = layer.GetPrimAtPath("/" + layer.defaultPrim)
        if spec is not None:  # Temple.usda holds sublayers only
            assert spec.specifier == Sdf.SpecifierDef and spec.typeName == "Xform", where
        stage = Usd.Stage.Open(layer)
        prim = stage.GetDefaultPrim()
        assert prim.IsDefined() and prim.GetTypeName() == "Xform", where
        assert validate_stage(stage) == [], where
        assert_contiguous_models(stage, where)
        # material bindings resolve in the layer alone
        for p in stage.Traverse():
            rel = UsdShade.MaterialBindingAPI(p).GetDirectBindingRel()
            for target in rel.GetTargets() if rel else []:
                assert UsdShade.Material(stage.GetPrimAtPath(target)), (where, target)
    # big arrays live in crate files: no text layer holds an array of over 1,000 values
    for f in files:
        if f.suffix != ".usda":
            continue
        layer = Sdf.Layer.FindOrOpen(str(f))
        sizes = []

        def visit(path, layer=layer, sizes=sizes):
            if path.IsPropertyPath():
                spec = layer.GetPropertyAtPath(path)
                value = getattr(spec, "default", None)
                if value is not None and hasattr(value, "__len__") and not isinstance(value, str):
                    sizes.append(len(value))

        layer.Traverse(layer.pseudoRoot.path, visit)
        assert max(sizes, default=0) <= 1000, f


def test_model_hierarchy_and_scopes(portunus_temple):
    stage = Usd.Stage.Open(str(portunus_temple.root))
    assert_contiguous_models(stage, "Temple.usda")
    root = stage.GetDefaultPrim()
    assert Usd.ModelAPI(root).GetKind() == "assembly"
    kinds = {p.GetName(): Usd.ModelAPI(p).GetKind() for p in root.GetChildren()}
    assert kinds["Colonnade"] == "group" and kinds["Podium"] == "component"
    assert root.GetChild("Materials").GetTypeName() == "Scope"
    columns = [p for p in stage.Traverse() if p.IsInstance()]
    assert len(columns) == 18
    for col in columns:
        assert col.IsModel() and Usd.ModelAPI(col).GetKind() == "component"
        proto = col.GetPrototype()
        assert proto.GetChild("Geom").GetTypeName() == "Scope"
        # stable slots: Geom/Base, Geom/Shaft, Geom/CapitalBody meshes, Geom/Ornament
        assert {c.GetName(): c.GetTypeName() for c in proto.GetChild("Geom").GetChildren()} == {
            "Base": "Mesh",
            "Shaft": "Mesh",
            "CapitalBody": "Mesh",
            "Ornament": "Scope",
        }
    # every Xform either is a model or carries transform ops: organising prims are Scopes
    for p in Usd.PrimRange(stage.GetPseudoRoot(), EVERYTHING):
        if p.GetTypeName() == "Xform" and not p.IsModel():
            assert UsdGeom.Xformable(p).GetOrderedXformOps(), p.GetPath()


def test_one_material_library_one_copy_of_the_maps(portunus_temple):
    folder = folder_of(portunus_temple)
    # the stone maps are the column asset's; the temple adds only the roof's terracotta
    assert sorted(p.name for p in (folder / "Textures").iterdir()) == [
        f"terracotta_{m}.png" for m in ("basecolor", "normal", "roughness")
    ]
    pngs = sorted(folder.rglob("*.png"))
    assert {p.parent for p in pngs} == {
        folder / "IonicColumn" / "Payload" / "Textures",
        folder / "Textures",
    }
    stage = Usd.Stage.Open(str(portunus_temple.root))
    used = set()
    for p in Usd.PrimRange(stage.GetPseudoRoot(), EVERYTHING):
        shader = UsdShade.Shader(p)
        if not shader or shader.GetIdAttr().Get() != "UsdUVTexture":
            continue
        file = shader.GetInput("file").Get()
        used.add(Path(file.resolvedPath))
        fallback = shader.GetInput("fallback")
        assert fallback and fallback.Get() is not None, p.GetPath()
        space = shader.GetInput("sourceColorSpace").Get()
        assert space == ("sRGB" if p.GetName() == "BaseColor" else "raw"), p.GetPath()
        # stone: st comes through the material's UsdTransform2d (the shared tiling); the
        # tiles' st are already in repeats (one per tile)
        src = shader.GetInput("st").GetConnectedSources()[0][0].source
        node = UsdShade.Shader(src.GetPrim()).GetIdAttr().Get()
        terracotta = p.GetParent().GetName() == "Terracotta"
        assert node == ("UsdPrimvarReader_float2" if terracotta else "UsdTransform2d")
    assert used == {p.resolve() for p in pngs} and len(used) == 9
    # the temple's parts bind the library's materials, and their st follow its convention
    part = stage.GetPrimAtPath("/Temple/Podium")
    mat, _ = UsdShade.MaterialBindingAPI(part).ComputeBoundMaterial()
    assert mat.GetPath() == Sdf.Path("/Temple/Materials/PaintedStucco")
    die = stage.GetPrimAtPath("/Temple/Podium/die")
    st = np.array(UsdGeom.PrimvarsAPI(die).GetPrimvar("st").ComputeFlattened())
    pts = np.array(UsdGeom.Mesh(die).GetPointsAttr().Get())
    assert np.ptp(st) * UV_SPAN == pytest.approx(np.ptp(pts, axis=0).max(), abs=1e-3)


def test_overrides_are_strongest_and_survive_a_rebuild(tmp_path):
    folder = tmp_path / "T"
    layout = portunus_layout()
    compose_temple(folder, layout, texture_size=16)
    user = Sdf.Layer.FindOrOpen(str(folder / "overrides.usda"))
    temple = user.GetPrimAtPath("/Temple")
    temple.variantSelections["hyp_roof_pitch_15"] = "alternative"
    temple.variantSelections["lod"] = "low"
    podium = Sdf.CreatePrimInLayer(user, "/Temple/Podium")
    podium.specifier = Sdf.SpecifierOver
    Sdf.AttributeSpec(
        podium, "visibility", Sdf.ValueTypeNames.Token, Sdf.VariabilityUniform
    ).default = "invisible"
    altar = Sdf.CreatePrimInLayer(user, "/Temple/Altar")
    altar.specifier, altar.typeName = Sdf.SpecifierDef, "Cube"
    col = Sdf.CreatePrimInLayer(user, "/Temple/Colonnade/Free/front_2")
    col.specifier = Sdf.SpecifierOver
    col.variantSelections["lod"] = "medium"
    user.Save()
    before = (folder / "overrides.usda").read_bytes()

    def check() -> None:
        stage = Usd.Stage.Open(str(folder / "Temple.usda"))
        root = stage.GetDefaultPrim()
        assert root.GetVariantSet("hyp_roof_pitch_15").GetVariantSelection() == "alternative"
        pitch = stage.GetPrimAtPath("/Temple/Roof/roof_left").GetCustomData()["ionic_usd"]
        assert "roof_pitch_15" in pitch["hypotheses"]
        assert (
            UsdGeom.Imageable(stage.GetPrimAtPath("/Temple/Podium")).ComputeVisibility()
            == UsdGeom.Tokens.invisible
        )
        assert stage.GetPrimAtPath("/Temple/Altar").GetTypeName() == "Cube"
        lods = {
            p.GetName(): p.GetVariantSet("lod").GetVariantSelection()
            for p in stage.Traverse()
            if p.IsInstance()
        }
        assert lods.pop("front_2") == "medium" and set(lods.values()) == {"low"}
        assert validate_stage(stage) == []

    check()
    compose_temple(folder, layout, texture_size=16, force=True, rebuild=True)
    assert (folder / "overrides.usda").read_bytes() == before
    check()


def layer_paradata(folder: Path) -> dict[str, dict[str, set[str]]]:
    """Layer file stem → prim path → hypothesis idents recorded there."""
    out: dict[str, dict[str, set[str]]] = {}
    for f in [*(folder / "layers").glob("*.usda"), *(folder / "layers").glob("*.usdc")]:
        layer = Sdf.Layer.FindOrOpen(str(f))
        found: dict[str, set[str]] = {}

        def visit(path, layer=layer, found=found):
            if path.IsPrimPath():
                hyps = layer.GetPrimAtPath(path).customData.get("ionic_usd", {}).get("hypotheses")
                if hyps:
                    found[str(path)] = set(hyps)

        layer.Traverse(Sdf.Path("/Temple"), visit)
        out[f.stem] = found  # <id>, <id>.detail or <a>+<b>
    return out


def shown(prim: Usd.Prim) -> bool:
    """Active and visible: a variant hides what it does not show (its prim paths stay)."""
    return prim.IsActive() and UsdGeom.Imageable(prim).ComputeVisibility() != "invisible"


def test_temple_prim_paths_are_the_same_under_every_selection(portunus_temple):
    """Every prim path of the temple, the columns' instance proxies included, is the same
    under sampled selections of all its variant sets (lod, detail, every hypothesis)."""
    import random

    stage = Usd.Stage.Open(str(portunus_temple.root))
    root = stage.GetDefaultPrim()
    vsets = root.GetVariantSets()
    pred = Usd.TraverseInstanceProxies(Usd.PrimAllPrimsPredicate)

    def paths() -> list[str]:
        return [str(p.GetPath()) for p in Usd.PrimRange(root, pred)]

    first = paths()
    assert sum(p.endswith("/Geom/Shaft") for p in first) == 18  # one slot per column
    options = {n: vsets.GetVariantSet(n).GetVariantNames() for n in vsets.GetNames()}
    assert len(options) >= 8  # lod, detail and the hypotheses
    rnd = random.Random(32)
    drawn = set()
    for _ in range(12):
        for n, vs in options.items():
            vsets.GetVariantSet(n).SetVariantSelection(rnd.choice(vs))
        assert paths() == first, vsets.GetAllVariantSelections()
        drawn.add(temple_triangles(stage))
    assert len(drawn) > 6  # the selections did change what is drawn


def check_combination(stage, selection, detail, recorded, layout) -> None:
    """Compose one selection of hypotheses x ``detail`` variant and check that the parts meet
    (columns between stylobate and architrave, roof on the cornice, ornament on its member),
    that the geometry is finite, that every prim lists the selected hypotheses touching it,
    and that the stage validates. ``selection``: hypothesis variant set → value."""
    select(stage, detail=detail, **selection)
    # the hypotheses chosen, as hyp_<ident> (a question's value names its alternative)
    chosen = [
        n if v == "alternative" else "hyp_" + v for n, v in selection.items() if v != "baseline"
    ]
    bbox = UsdGeom.BBoxCache(
        Usd.TimeCode.Default(), [UsdGeom.Tokens.default_, UsdGeom.Tokens.render]
    )
    where = (chosen, detail)

    def world(path: str) -> Gf.Range3d:
        prim = stage.GetPrimAtPath(path)
        assert prim and shown(prim), (where, path)
        return bbox.ComputeWorldBound(prim).ComputeAlignedRange()

    # plain shows the cuboids; the detailed variants the mouldings that replace two of them
    member = "/Temple/Entablature/" + ("" if detail == "plain" else "Mouldings/")
    for name in ("cornice", "architrave"):
        gone = shown(stage.GetPrimAtPath(f"/Temple/Entablature/{name}"))
        assert gone == (detail == "plain"), (where, name)
    cornice = world(member + "cornice")
    cornice_top = cornice.GetMax()[1]
    # the gable wedges sit on the cornice; the slabs rest on their bed at the eaves
    for slab, bed in (
        ("roof_left", ROOF_BED),
        ("roof_right", ROOF_BED),
        ("pediment_left", 0.0),
        ("pediment_right", 0.0),
    ):
        assert world(f"/Temple/Roof/{slab}").GetMin()[1] == pytest.approx(
            cornice_top + bed, abs=1e-3
        ), (where, slab)
    stylobate = world("/Temple/Podium/die").GetMax()[1]
    architrave = world(member + "architrave").GetMin()[1]
    assert stylobate == pytest.approx(layout.stylobate_height, abs=1e-6)
    columns = [p for p in stage.Traverse() if p.IsInstance()]
    assert len(columns) == 18
    for c in columns:
        r = bbox.ComputeWorldBound(c).ComputeAlignedRange()
        assert r.GetMin()[1] == pytest.approx(stylobate, abs=1e-3), (where, c.GetPath())
        assert r.GetMax()[1] == pytest.approx(architrave, abs=1e-3), (where, c.GetPath())
    if detail != "plain":
        crown = world("/Temple/Podium/Mouldings/podium_crown")
        assert crown.GetMax()[1] == pytest.approx(stylobate, abs=1e-3), where
    if detail == "carved":
        dentils = world("/Temple/Entablature/Ornament/Dentils")
        assert cornice.GetMin()[1] < dentils.GetMin()[1] < dentils.GetMax()[1] < cornice_top
        slab = world("/Temple/Roof/roof_left")
        tiles = world("/Temple/Roof/Tiles")
        # on the slabs: from the eaves (antefixes hang 5 cm) to just over the ridge
        assert tiles.GetMin()[1] > slab.GetMin()[1], where
        assert slab.GetMax()[1] < tiles.GetMax()[1] < slab.GetMax()[1] + 0.3, where
    expected: dict[str, set[str]] = {}
    for stem, found in recorded.items():
        ids = {("hyp_" + i) for i in stem.removesuffix(".detail").replace("-", "_").split("+")}
        if ids <= set(chosen):
            for path, idents in found.items():
                expected.setdefault(path, set()).update(idents)
    for p in stage.Traverse():
        if p.IsA(UsdGeom.Mesh):
            assert np.isfinite(np.array(p.GetAttribute("points").Get())).all()
        if not shown(p):
            continue  # a hidden prim (a variant not selected) shows nothing: no paradata
        listed = set(p.GetCustomData().get("ionic_usd", {}).get("hypotheses", {}))
        if str(p.GetPath()) == "/Temple":
            continue  # the listing of all hypotheses
        assert listed == expected.get(str(p.GetPath()), set()), (where, p.GetPath())
        for ident in listed:
            assert p.GetAttribute(f"userProperties:ionic_usd:{ident}:id").Get()
    assert validate_stage(stage) == []


def _combinations(portunus_temple, sample: int | None):
    stage = Usd.Stage.Open(str(portunus_temple.root))
    root = stage.GetDefaultPrim()
    vsets = root.GetVariantSets()
    hyps = sorted(n for n in vsets.GetNames() if n.startswith("hyp_"))
    # every hypothesis of portunus.toml is realised: four switches and the frieze's question
    # (plain or garlands: one set, so never both)
    assert len(hyps) == 5
    values = {n: vsets.GetVariantSet(n).GetVariantNames() for n in hyps}
    assert sorted(values["hyp_frieze"]) == ["baseline", "frieze_garlands", "frieze_plain"]
    details = vsets.GetVariantSet("detail").GetVariantNames()
    assert details == ["carved", "moulded", "plain"]
    combos = list(itertools.product(itertools.product(*values.values()), details))
    if sample is not None:  # none, all, and a seeded sample of the rest
        rng = np.random.default_rng(17)
        ends = [c for c in combos if all(v == "baseline" for v in c[0])]
        ends += [c for c in combos if all(v != "baseline" for v in c[0]) and c not in ends][:3]
        rest = [c for c in combos if c not in ends]
        combos = ends + [rest[k] for k in rng.choice(len(rest), sample, replace=False)]
    recorded = layer_paradata(folder_of(portunus_temple))
    layout = portunus_layout()
    for chosen, detail in combos:
        check_combination(stage, dict(zip(hyps, chosen, strict=True)), detail, recorded, layout)
    return len(combos)


def test_sampled_combinations_of_hypotheses_and_detail_compose(portunus_temple):
    assert _combinations(portunus_temple, sample=10) == 16  # 3 + 3 ends, 10 drawn


@pytest.mark.slow
def test_every_combination_of_hypotheses_and_detail_composes(portunus_temple):
    # 2^4 switches x 3 frieze values (baseline, plain, garlands) x 3 details
    assert _combinations(portunus_temple, sample=None) == 2**4 * 3 * 3


def test_interacting_hypotheses_get_a_combination_layer(tmp_path):
    """Two hypotheses that both reshape the roof: the composer writes their combined values
    and every combination composes to the layout built with those hypotheses."""
    from ionic_usd.temple.layout import build_layout
    from ionic_usd.usd.combinations import mismatches
    from ionic_usd.usd.detail import detail_geometry
    from ionic_usd.usd.temple import CUBOID_UV_SCALE

    data = load_toml(Path(__file__).resolve().parent.parent / "ionic_usd/data/portunus.toml")
    data["hypothesis"] = [h for h in data["hypothesis"] if h["id"] == "roof-pitch-15"] + [
        {
            "id": "deep-cornice",
            "description": "a cornice projecting 1.6 times its height",
            "sources": ["test"],
            "certainty": "low",
            "changes": {"entablature.cornice_projection_ratio": 1.6},
        }
    ]
    layout = layout_from_mapping(data, context="test")
    rep = compose_temple(tmp_path / "T", layout, texture_size=16)
    # each hypothesis re-places the detail it moves; together they reshape the roof
    assert rep.combination_layers == (
        "roof-pitch-15.detail",
        "deep-cornice.detail",
        "roof-pitch-15+deep-cornice",
    )
    folder = tmp_path / "T"
    assert (folder / "layers" / "roof-pitch-15+deep-cornice.usdc").is_file()
    stage = Usd.Stage.Open(str(folder / "Temple.usda"))
    for a, b, d in itertools.product(
        ("baseline", "alternative"), ("baseline", "alternative"), ("plain", "moulded", "carved")
    ):
        select(stage, hyp_roof_pitch_15=a, hyp_deep_cornice=b, detail=d)
        ids = [i for i, s in (("roof-pitch-15", a), ("deep-cornice", b)) if s == "alternative"]
        want = build_layout(layout.params, hypotheses=layout.hypotheses, apply=ids)
        assert (
            mismatches(
                stage,
                want,
                layout.params.columns_height,
                uv_scale=CUBOID_UV_SCALE,
                variant=d,
                detail=detail_geometry(want),
            )
            == {}
        ), (ids, d)
        assert validate_stage(stage) == []
    listed = stage.GetPrimAtPath("/Temple/Roof/roof_left").GetCustomData()["ionic_usd"]
    assert set(listed["hypotheses"]) == {"roof_pitch_15", "deep_cornice"}
    for f in layer_files(folder):
        assert validate_stage(Usd.Stage.Open(str(f))) == [], f


@pytest.mark.parametrize(
    ("changes", "key"),
    [
        ({"column.flute_count": 7}, "column.flute_count"),
        ({"material.finish": "gold"}, "material.finish"),
        ({"column.volute_turns": 4}, "column.volute_turns"),
        ({"roof.colour": 1}, "roof.colour"),
        ({"columns.lower_diameter": 1.2}, "columns.lower_diameter"),
    ],
)
def test_unrealisable_hypothesis_changes_are_errors(tmp_path, changes, key):
    data = load_toml(Path(__file__).resolve().parent.parent / "ionic_usd/data/portunus.toml")
    data["hypothesis"] = [
        {"id": "bad", "description": "x", "sources": ["y"], "certainty": "low", "changes": changes}
    ]
    with pytest.raises(ParameterError, match=key.replace(".", r"\.")):
        hypothesis_layers(layout_from_mapping(data, context="t.toml"))
    with pytest.raises(ParameterError):
        compose_temple(tmp_path / "T", layout_from_mapping(data, context="t.toml"))
    assert not (tmp_path / "T").exists()


def test_cli_rejects_unknown_temple_key_and_bad_change(tmp_path, capsys):
    cfg = tmp_path / "t.toml"
    cfg.write_text('[temple]\nname = "x"\ncolour = "red"\n')
    assert main(["temple", "--config", str(cfg), "-o", str(tmp_path / "a")]) == 2
    err = capsys.readouterr().err
    assert "[temple]" in err and "colour" in err and "Traceback" not in err
    assert len(err.strip().splitlines()) == 1
    cfg.write_text(
        'extends = "portunus"\n'
        '[[hypothesis]]\nid = "h"\ndescription = "d"\nsources = ["s"]\n'
        'certainty = "low"\nchanges = { "column.flute_count" = 7 }\n'
    )
    assert main(["temple", "--config", str(cfg), "-o", str(tmp_path / "b")]) == 2
    err = capsys.readouterr().err
    assert "column.flute_count" in err and "7" in err and "Traceback" not in err
    assert not (tmp_path / "a").exists() and not (tmp_path / "b").exists()


def test_one_edit_in_a_class_changes_every_instance(portunus_temple):
    stage = Usd.Stage.Open(str(portunus_temple.root))
    columns = [p for p in stage.Traverse() if p.IsInstance()]
    assert len(columns) == 18
    assert all(UsdGeom.Imageable(c).ComputeVisibility() == "inherited" for c in columns)
    cls = stage.GetPrimAtPath("/_class_IonicColumn")
    assert cls and cls.IsAbstract()
    with Usd.EditContext(stage, stage.GetSessionLayer()):
        UsdGeom.Imageable(stage.OverridePrim("/_class_IonicColumn")).CreateVisibilityAttr(
            "invisible"
        )
        stage.OverridePrim("/_class_Temple").CreateAttribute(
            "userProperties:note", Sdf.ValueTypeNames.String
        ).Set("checked")
    assert all(UsdGeom.Imageable(c).ComputeVisibility() == "invisible" for c in columns)
    assert stage.GetPrimAtPath("/Temple").GetAttribute("userProperties:note").Get() == "checked"
    assert (
        UsdGeom.Imageable(stage.GetPrimAtPath("/Temple/Podium")).ComputeVisibility() == "inherited"
    )


def test_column_xform_ops_are_xform_common_api_compatible(portunus_temple):
    stage = Usd.Stage.Open(str(portunus_temple.root))
    placements = {c.name: c for c in portunus_layout().columns}
    for prim in (p for p in stage.Traverse() if p.IsInstance()):
        api = UsdGeom.XformCommonAPI(prim)
        assert api, prim.GetPath()
        t, r, s, pivot, order = api.GetXformVectors(Usd.TimeCode.Default())
        c = placements[prim.GetName()]
        assert np.allclose(t, c.position) and np.allclose(r, (0, c.rotation_deg, 0))
        assert np.allclose(s, (c.scale,) * 3) and np.allclose(pivot, 0)


def test_temple_lod_passes_to_every_column(portunus_temple):
    stage = Usd.Stage.Open(str(portunus_temple.root))
    root = stage.GetDefaultPrim()
    assert root.GetVariantSet("lod").GetVariantNames() == ["high", "low", "medium"]
    tris = portunus_temple.triangles_per_lod
    assert tris["high"] == portunus_temple.triangles == temple_triangles(stage)
    for lod in ("high", "medium", "low"):
        select(stage, lod=lod)
        assert {
            p.GetVariantSet("lod").GetVariantSelection() for p in stage.Traverse() if p.IsInstance()
        } == {lod}
        assert temple_triangles(stage) == tris[lod]
    assert tris["high"] > 2 * tris["medium"] > 2 * tris["low"] > 0
    # the count is by hand: instances × their prototype's rendered triangles + the cuboids
    # (12 each); the proxy meshes are not drawn with the render purpose
    select(stage, lod="low")
    per_proto, proxies = {}, 0
    for proto in stage.GetPrototypes():
        meshes = [p for p in Usd.PrimRange(proto) if p.IsA(UsdGeom.Mesh)]
        # the carved ornament keeps its paths at every lod, invisible but in lod high
        visible = [
            p
            for p in meshes
            if UsdGeom.Imageable(p).ComputeVisibility() != UsdGeom.Tokens.invisible
        ]
        drawn = [p for p in visible if UsdGeom.Imageable(p).ComputePurpose() == "render"]
        proxies += len(visible) - len(drawn)
        per_proto[proto.GetPath()] = sum(
            int(np.sum(np.array(UsdGeom.Mesh(p).GetFaceVertexCountsAttr().Get()) - 2))
            for p in drawn
        )
    # each prototype (form full, engaged, corner): its three low-lod parts as proxy
    assert len(stage.GetPrototypes()) == 3 and proxies == 3 * 3
    inst = sum(per_proto[p.GetPrototype().GetPath()] for p in stage.Traverse() if p.IsInstance())

    # the temple's own meshes (cuboids, mouldings) and every copy of the PointInstancers'
    # prototypes (dentils, tiles)
    def tris(p) -> int:
        return int(np.sum(np.array(UsdGeom.Mesh(p).GetFaceVertexCountsAttr().Get()) - 2))

    own, copies = 0, 0
    it = iter(stage.Traverse())
    for p in it:
        if not shown(p):  # what a variant hides (its paths stay) is not drawn
            it.PruneChildren()
        elif p.IsA(UsdGeom.PointInstancer):
            it.PruneChildren()
            pi = UsdGeom.PointInstancer(p)
            per = [tris(stage.GetPrimAtPath(t)) for t in pi.GetPrototypesRel().GetTargets()]
            copies += sum(per[i] for i in pi.GetProtoIndicesAttr().Get())
        elif p.IsA(UsdGeom.Mesh):
            own += tris(p)
    assert copies > 0
    assert temple_triangles(stage) == inst + own + copies


@pytest.mark.parametrize("rebuild", [True, False])
def test_a_rebuild_is_not_blocked_by_the_users_edits(tmp_path, rebuild):
    """The user's layer may de-instance a column or reference a file of their own that is not
    there yet: the build checks what it generates, and keeps the user's layer as it is; the
    report counts the scene as it composes with the user's layer, regenerated or found
    current."""
    folder = tmp_path / "T"
    compose_temple(folder, portunus_layout(), texture_size=16)
    user = Sdf.Layer.FindOrOpen(str(folder / "overrides.usda"))
    col = Sdf.CreatePrimInLayer(user, "/Temple/Colonnade/Free/front_1")
    col.specifier = Sdf.SpecifierOver
    col.instanceable = False
    extra = Sdf.CreatePrimInLayer(user, "/Temple/Statue")
    extra.specifier, extra.typeName = Sdf.SpecifierDef, "Xform"
    extra.referenceList.Prepend(Sdf.Reference("./statue.usda"))
    user.Save()
    before = (folder / "overrides.usda").read_bytes()
    rep = compose_temple(folder, portunus_layout(), texture_size=16, force=True, rebuild=rebuild)
    assert rep.current is not rebuild
    assert (folder / "overrides.usda").read_bytes() == before
    assert rep.instances == 17  # front_1 is the user's own, de-instanced, column
