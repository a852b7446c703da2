"""The column component asset: layout on disk, variant sets (volute models too), the carved
capital, UVs, materials, textures, cache."""

from __future__ import annotations

import dataclasses
import itertools
import json
import os

import numpy as np
import pytest
from pxr import Sdf, Usd, UsdGeom, UsdShade

from ionic_usd.errors import OutputExistsError, ParameterError
from ionic_usd.geometry import CornerValues, Mesh, inspect_mesh
from ionic_usd.pipeline.asset import build_column_asset, column_asset_meshes
from ionic_usd.texture.stone import TextureError
from ionic_usd.usd import validate_stage
from ionic_usd.usd.column_asset import ColumnAssetOptions

LIB = "/_IonicColumnParts/"
VARIANTS = {
    "lod": ("high", "medium", "low"),
    "base": ("attic_bezier_plinth", "attic_bezier", "G1", "G2"),
    "scroll": ("S1", "S2"),
    "capital": ("normal", "angle"),
    "volute": ("log_spiral", "centred_arcs"),
    "flutes": ("f24", "f20"),
    "form": ("full", "engaged", "corner"),
    "finish": ("travertine", "stucco"),
}


def open_stage(report) -> Usd.Stage:
    return Usd.Stage.Open(str(report.path))


def source(prim: Usd.Prim) -> str:
    """The library item (``/_IonicColumnParts/<part>/<name>``) a slot references."""
    (name,) = {s.path.name for s in prim.GetPrimStack() if s.path.pathString.startswith(LIB)}
    return name


def active_meshes(stage, purpose: str = "render") -> dict[str, Usd.Prim]:
    """Drawn part meshes of one purpose (render: the selected lod under Geom; proxy: Proxy),
    not the ornament prototypes under PointInstancers, keyed by their stable path and the
    library item they reference (``/IonicColumn/Geom/Base/Base_G1_high``)."""
    return {
        f"{p.GetPath()}/{source(p)}": p
        for p in stage.Traverse()
        if p.IsA(UsdGeom.Mesh)
        and UsdGeom.Imageable(p).ComputePurpose() == purpose
        and UsdGeom.Imageable(p).ComputeVisibility() != UsdGeom.Tokens.invisible
        and not _prototype_of_instancer(p)
    }


def test_low_lod_is_the_proxy_of_every_selection(column_asset):
    stage = open_stage(column_asset)
    vsets = stage.GetDefaultPrim().GetVariantSets()
    assert not active_meshes(stage, "default")  # every mesh is render or proxy
    names = ["lod", "base", "scroll", "volute", "flutes", "form"]
    for combo in itertools.product(*(VARIANTS[n] for n in names)):
        for n, v in zip(names, combo, strict=True):
            vsets.GetVariantSet(n).SetVariantSelection(v)
        render = {p.rsplit("/", 1)[1] for p in active_meshes(stage)}
        proxy = {p.rsplit("/", 1)[1]: prim for p, prim in active_meshes(stage, "proxy").items()}
        # the proxy is the low lod of the same selection: the render meshes' names, lod low
        assert set(proxy) == {n.replace(f"_{combo[0]}", "_low") for n in render}, combo
        for prim in proxy.values():
            assert UsdShade.MaterialBindingAPI(prim).ComputeBoundMaterial()[0], prim.GetPath()
        # every render mesh names its proxy (UsdGeomImageable proxyPrim), the same part
        for prim in active_meshes(stage).values():
            (target,) = UsdGeom.Imageable(prim).GetProxyPrimRel().GetTargets()
            assert target == Sdf.Path(f"/IonicColumn/Proxy/{prim.GetName()}")
    # proxies are references to the low meshes, not second copies of their arrays
    layer = Sdf.Layer.FindOrOpen(str(column_asset.path.parent / "Payload/Geometry.usdc"))
    assert not layer.GetPrimAtPath("/IonicColumn/Proxy")
    for prim in stage.GetPrimAtPath("/IonicColumn/Proxy").GetChildren():
        assert [s.layer for s in prim.GetPrimStack() if s.attributes] == [layer]


def test_prim_paths_are_the_same_under_every_selection(column_asset):
    """Switching a variant swaps what is under a path, never the path (all sets, sampled)."""
    import random

    stage = open_stage(column_asset)
    root = stage.GetDefaultPrim()
    vsets = root.GetVariantSets()

    def paths():
        return [str(p.GetPath()) for p in Usd.PrimRange(root, Usd.PrimAllPrimsPredicate)]

    first = paths()
    assert "/IonicColumn/Geom/Shaft" in first and "/IonicColumn/Proxy/Shaft" in first
    rnd = random.Random(32)
    sources = set()
    for _ in range(60):
        for n, vs in VARIANTS.items():
            vsets.GetVariantSet(n).SetVariantSelection(rnd.choice(vs))
        assert paths() == first, vsets.GetAllVariantSelections()
        sources.add(source(stage.GetPrimAtPath("/IonicColumn/Geom/Shaft")))
    assert len(sources) == 3 * 2 * 3  # lod x flutes x form: the content did change


def _prototype_of_instancer(p: Usd.Prim) -> bool:
    return any(a.IsA(UsdGeom.PointInstancer) for a in _ancestors(p))


def _ancestors(p: Usd.Prim):
    p = p.GetParent()
    while p and not p.IsPseudoRoot():
        yield p
        p = p.GetParent()


def mesh_value(prim) -> Mesh:
    g = UsdGeom.Mesh(prim)
    st = UsdGeom.PrimvarsAPI(prim).GetPrimvar("st")
    return Mesh(
        np.array(g.GetPointsAttr().Get()),
        np.array(g.GetFaceVertexCountsAttr().Get()),
        np.array(g.GetFaceVertexIndicesAttr().Get()),
        st=CornerValues(np.array(st.Get()), np.array(st.GetIndices())),
    )


def test_layout_on_disk_and_interface(column_asset):
    root = column_asset.path.parent
    assert column_asset.path.name == "IonicColumn.usda"
    for rel in ("Payload/Contents.usda", "Payload/Geometry.usdc", "Payload/Materials.usda"):
        assert (root / rel).is_file(), rel
    layer = Sdf.Layer.FindOrOpen(str(column_asset.path))
    prim = layer.GetPrimAtPath("/IonicColumn")
    assert layer.defaultPrim == "IonicColumn" and prim.typeName == "Xform"
    assert prim.kind == "component"
    assert prim.assetInfo["name"] == "IonicColumn" and "version" in prim.assetInfo
    assert [p.assetPath for p in prim.payloadList.prependedItems] == ["./Payload/Contents.usda"]
    contents = Sdf.Layer.FindOrOpen(str(root / "Payload/Contents.usda"))
    assert list(contents.subLayerPaths) == ["./Materials.usda", "./Geometry.usdc"]
    # only ./-relative asset paths anywhere
    for f in root.rglob("*.usd*"):
        lay = Sdf.Layer.FindOrOpen(str(f))
        for dep in lay.GetCompositionAssetDependencies():
            assert dep == "" or dep.startswith("./"), (f, dep)  # "": internal reference
    mats = (root / "Payload/Materials.usda").read_text()
    assert "@./Textures/" in mats and "@../" not in mats


def test_variant_sets_and_validation_per_selection(column_asset):
    stage = open_stage(column_asset)
    root = stage.GetDefaultPrim()
    vsets = root.GetVariantSets()
    assert set(vsets.GetNames()) == set(VARIANTS)
    for name, variants in VARIANTS.items():
        assert vsets.GetVariantSet(name).GetVariantNames() == sorted(variants)
    assert validate_stage(stage) == []
    for name, variants in VARIANTS.items():
        vs = vsets.GetVariantSet(name)
        default = vs.GetVariantSelection()
        for v in variants:
            vs.SetVariantSelection(v)
            assert validate_stage(stage) == [], (name, v)
        vs.SetVariantSelection(default)


def test_every_selection_has_one_mesh_per_part(column_asset):
    stage = open_stage(column_asset)
    vsets = stage.GetDefaultPrim().GetVariantSets()
    names = ["lod", "base", "scroll", "capital", "volute", "flutes", "form"]
    for combo in itertools.product(*(VARIANTS[n] for n in names)):
        for n, v in zip(names, combo, strict=True):
            vsets.GetVariantSet(n).SetVariantSelection(v)
        meshes = active_meshes(stage)
        parts = sorted(p.split("/")[3] for p in meshes)
        assert parts == ["Base", "CapitalBody", "Shaft"], combo
        lod, form = combo[0], combo[-1]
        suffix = lod if form == "full" else f"{lod}_{form}"
        assert all(p.endswith(suffix) for p in meshes), combo


def test_every_mesh_closed_with_uvs_in_unit_square(column_asset):
    layer = Sdf.Layer.FindOrOpen(str(column_asset.path.parent / "Payload/Geometry.usdc"))
    stage = Usd.Stage.Open(layer)
    prims = [
        p
        for p in stage.TraverseAll()
        if p.IsA(UsdGeom.Mesh)
        and "Proxy" not in str(p.GetPath())
        and not _prototype_of_instancer(p)
    ]
    assert len(prims) == column_asset.meshes == 3 * (4 + 2 + 2 * 2 * 2) * 3
    for prim in prims:
        m = mesh_value(prim)
        r = inspect_mesh(m)
        assert r.closed and r.consistent and r.signed_volume > 0, prim.GetPath()
        assert m.st.values.min() >= 0.0 and m.st.values.max() <= 1.0, prim.GetPath()
        assert UsdGeom.PrimvarsAPI(prim).GetPrimvar("st").GetInterpolation() == "faceVarying"
        assert UsdGeom.PrimvarsAPI(prim).GetPrimvar("st").GetTypeName() == "texCoord2f[]"


@pytest.mark.slow
def test_charts_do_not_overlap_in_any_mesh(column_asset):
    from scipy.ndimage import maximum_filter, minimum_filter
    from test_uv import rasterise, uv_charts

    from ionic_usd.blueprint.column_asset import UV_SPAN
    from ionic_usd.lod import LOD_NAMES, level
    from ionic_usd.texture.uv import DEFAULT_PADDING

    layer = Sdf.Layer.FindOrOpen(str(column_asset.path.parent / "Payload/Geometry.usdc"))
    stage = Usd.Stage.Open(layer)
    checked = 0
    for prim in stage.TraverseAll():
        if (
            not prim.IsA(UsdGeom.Mesh)
            or prim.GetParent().GetName() == "Proxy"
            or _prototype_of_instancer(prim)
        ):
            continue
        m = mesh_value(prim)
        charts = uv_charts(m.st.indices, len(m.st.values))
        cover, _ = rasterise(m.st.values * 2048, m.st.indices, 2048, 2048, charts)
        assert cover.max() == 1, prim.GetPath()
        # finer: no overlap either, and no two charts within the padding the atlas keeps
        # around every chart (DEFAULT_PADDING texels of this LOD's S = density × UV_SPAN)
        res = 4096
        cover, label = rasterise(m.st.values * res, m.st.indices, res, res, charts)
        assert cover.max() == 1, prim.GetPath()
        lod = next(k for k in LOD_NAMES if f"_{k}" in prim.GetName())
        r = DEFAULT_PADDING * res // int(level(lod).asset_texels_per_metre * UV_SPAN)
        occupied = label >= 0
        hi = maximum_filter(label, size=2 * r - 1)
        lo = minimum_filter(np.where(occupied, label, label.max() + 1), size=2 * r - 1)
        assert not np.any(occupied & ((hi != label) | (lo != label))), prim.GetPath()
        checked += 1
    assert checked > 0


def test_switching_variants_changes_exactly_their_part(column_asset):
    stage = open_stage(column_asset)
    vsets = stage.GetDefaultPrim().GetVariantSets()
    expect = {
        "lod": {"Base", "Shaft", "CapitalBody"},
        "base": {"Base"},
        "scroll": {"CapitalBody"},
        "capital": {"CapitalBody"},
        "volute": {"CapitalBody"},
        "flutes": {"Shaft"},
        "form": {"Base", "Shaft", "CapitalBody"},
    }
    for name, parts in expect.items():
        vs = vsets.GetVariantSet(name)
        default = vs.GetVariantSelection()
        before = set(active_meshes(stage))
        vs.SetVariantSelection(VARIANTS[name][1])
        after = set(active_meshes(stage))
        changed = {p.split("/")[3] for p in before ^ after}
        assert changed == parts, name
        vs.SetVariantSelection(default)
    # finish switches the bound material of every mesh and no geometry
    vs = vsets.GetVariantSet("finish")
    before = set(active_meshes(stage))
    mats = set()
    for v in VARIANTS["finish"]:
        vs.SetVariantSelection(v)
        assert set(active_meshes(stage)) == before
        bound = {
            UsdShade.MaterialBindingAPI(p).ComputeBoundMaterial()[0].GetPath()
            for p in active_meshes(stage).values()
        }
        assert len(bound) == 1
        mats |= bound
    assert {p.name for p in mats} == {"Travertine", "PaintedStucco"}


def test_material_network(column_asset):
    stage = open_stage(column_asset)
    mat = UsdShade.Material(stage.GetPrimAtPath("/IonicColumn/Materials/Travertine"))
    surf = mat.ComputeSurfaceSource()[0]
    assert surf.GetIdAttr().Get() == "UsdPreviewSurface"
    spaces = {}
    for inp in ("diffuseColor", "roughness", "normal"):
        src = surf.GetInput(inp).GetConnectedSources()[0][0].source
        tex = UsdShade.Shader(src.GetPrim())
        assert tex.GetIdAttr().Get() == "UsdUVTexture"
        spaces[inp] = tex.GetInput("sourceColorSpace").Get()
        path = tex.GetInput("file").Get().resolvedPath
        assert path, inp
    assert spaces == {"diffuseColor": "sRGB", "roughness": "raw", "normal": "raw"}
    reader = stage.GetPrimAtPath("/IonicColumn/Materials/Travertine/StReader")
    assert UsdShade.Shader(reader).GetInput("varname").Get() == "st"
    geom = stage.GetPrimAtPath("/IonicColumn/Geom")
    assert geom.HasAPI(UsdShade.MaterialBindingAPI)


def test_textures_readable_with_declared_size(column_asset):
    import OpenImageIO as oiio

    tex = sorted((column_asset.path.parent / "Payload/Textures").glob("*.png"))
    assert len(tex) == 6
    for f in tex:
        inp = oiio.ImageInput.open(str(f))
        assert inp is not None, f
        spec = inp.spec()
        assert (spec.width, spec.height) == (64, 64)
        assert spec.nchannels == (1 if "roughness" in f.name else 3)
        inp.close()


def test_no_part_is_unwrapped_by_xatlas(tmp_path, monkeypatch):
    # every part carries its generator's charts (the capital's through its union and form
    # cuts): a cold build runs no xatlas at all, and packs the charts at the LOD's density
    from ionic_usd.texture import uv
    from ionic_usd.texture.uv import UVCache

    monkeypatch.setenv("IONIC_USD_CACHE", str(tmp_path / "cache"))  # its own mesh cache

    def no_xatlas(*_a, **_k):
        raise AssertionError("xatlas ran")

    monkeypatch.setattr(uv, "_run_xatlas", no_xatlas)
    cache = UVCache(tmp_path / "uv")
    opts = ColumnAssetOptions(
        lods=("low",), bases=("G1",), scrolls=("S1",), flutes=("f24",), texture_size=16
    )
    meshes = column_asset_meshes(opts, cache, workers=1)
    assert all(m.mesh.st is not None for m in meshes)
    assert sum(m.part == "CapitalBody" for m in meshes) == 2 * 2 * 3  # capitals × volutes × forms
    cold = build_column_asset(tmp_path / "a" / "IonicColumn", opts, cache=cache)
    assert cold.uv_unwraps == cache.misses == 0


def test_force_replaces_atomically(tmp_path):
    opts = ColumnAssetOptions(
        lods=("low",),
        bases=("G1",),
        scrolls=("S1",),
        flutes=("f24",),
        forms=("full",),
        texture_size=16,
    )
    dest = tmp_path / "IonicColumn"
    build_column_asset(dest, opts)
    (dest / "stray.txt").write_text("from the old asset")
    with pytest.raises(OutputExistsError):
        build_column_asset(dest, opts)
    assert (dest / "stray.txt").exists()
    # a generated file the next build no longer makes goes; the user's own file stays
    (dest / "Payload" / "Textures" / "old_generated.png").write_bytes(b"x")
    from ionic_usd.io import MANIFEST_NAME, generated_files

    listed = generated_files(dest)
    assert "Payload/Geometry.usdc" in listed and "stray.txt" not in listed
    (dest / MANIFEST_NAME).write_text(
        json.dumps({"files": [*listed, "Payload/Textures/old_generated.png"]})
    )
    build_column_asset(dest, opts, force=True)
    assert (dest / "stray.txt").read_text() == "from the old asset"
    assert not (dest / "Payload" / "Textures" / "old_generated.png").exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["IonicColumn"]


@pytest.mark.parametrize(
    "kw,needle",
    [
        ({"bases": ("G9",)}, "G1"),
        ({"lods": ("ultra",)}, "high"),
        ({"scrolls": ()}, "S1"),
        ({"forms": ("quarter",)}, "engaged"),
    ],
)
def test_unknown_variants_list_valid_ones(kw, needle):
    with pytest.raises(ParameterError, match=needle):
        ColumnAssetOptions(**kw)


def test_bad_user_textures_refused_before_writing(tmp_path):
    bad = tmp_path / "fake.png"
    bad.write_bytes(b"not an image")
    for textures in (
        {"basecolor": tmp_path / "missing.png", "roughness": bad, "normal": bad},
        {"basecolor": bad, "roughness": bad, "normal": bad},
    ):
        with pytest.raises(TextureError):
            build_column_asset(
                tmp_path / "IonicColumn",
                ColumnAssetOptions(user_textures={k: str(v) for k, v in textures.items()}),
            )
        assert not (tmp_path / "IonicColumn").exists()


def _capital(stage) -> Usd.Prim:
    (prim,) = [p for path, p in active_meshes(stage).items() if "/CapitalBody/" in path]
    return prim


def _capital_name(stage) -> str:
    (name,) = [path.rsplit("/", 1)[1] for path in active_meshes(stage) if "/CapitalBody/" in path]
    return name


def test_volute_variant_switches_the_capital_to_the_centred_arcs(column_asset):
    """The ``volute`` set swaps the capital mesh at every lod; centred_arcs holds the
    generator's centred-arc capital (same points), and the two curves differ by centimetres."""
    from scipy.spatial import cKDTree

    from ionic_usd.column.column import build_capital_part
    from ionic_usd.usd.column_asset import volute_variant_params

    stage = open_stage(column_asset)
    vsets = stage.GetDefaultPrim().GetVariantSets()
    vs = vsets.GetVariantSet("volute")
    assert vs.GetVariantSelection() == "log_spiral"  # the paper's formula is the default
    params = ColumnAssetOptions().params
    for lod in VARIANTS["lod"]:
        vsets.GetVariantSet("lod").SetVariantSelection(lod)
        pts = {}
        for v in VARIANTS["volute"]:
            vs.SetVariantSelection(v)
            prim = _capital(stage)
            assert _capital_name(stage).endswith(f"_{v}_{lod}"), prim.GetPath()
            pts[v] = np.array(UsdGeom.Mesh(prim).GetPointsAttr().Get(), dtype=np.float64)
        d, _ = cKDTree(pts["log_spiral"]).query(pts["centred_arcs"])
        assert d.max() > 0.005, lod  # the volute's face is another curve
        if lod == "low":
            p = volute_variant_params(params.with_lod("low"), "centred_arcs")
            y = p.base_params().height + p.shaft.length
            ref = build_capital_part(p, y, scroll="S1", angle=False)
            # the same surface (the asset welds the union's coincident copies of a point)
            for a, b in ((pts["centred_arcs"], ref.points), (ref.points, pts["centred_arcs"])):
                assert cKDTree(b).query(a)[0].max() < 1e-5
    vs.SetVariantSelection("log_spiral")


@pytest.mark.parametrize(
    "lod",
    [
        "high",
        pytest.param("medium", marks=pytest.mark.slow),
        pytest.param("low", marks=pytest.mark.slow),
    ],
)
def test_every_volute_selection_validates_and_is_one_solid(column_asset, lod):
    """Each capital selection (volute × scroll × capital × form, per lod) has 0 UsdValidation
    errors and its capital is one closed, outward shell."""
    from ionic_usd.geometry.check import shell_count

    stage = open_stage(column_asset)
    vsets = stage.GetDefaultPrim().GetVariantSets()
    vsets.GetVariantSet("lod").SetVariantSelection(lod)
    names = ["volute", "scroll", "capital", "form"]
    seen = set()
    for combo in itertools.product(*(VARIANTS[n] for n in names)):
        for n, v in zip(names, combo, strict=True):
            vsets.GetVariantSet(n).SetVariantSelection(v)
        assert validate_stage(stage) == [], combo
        seen.add(_capital_name(stage))
        prim = _capital(stage)
        assert prim.GetPath() == Sdf.Path("/IonicColumn/Geom/CapitalBody")
        g = UsdGeom.Mesh(prim)
        m = Mesh(
            np.array(g.GetPointsAttr().Get()),
            np.array(g.GetFaceVertexCountsAttr().Get()),
            np.array(g.GetFaceVertexIndicesAttr().Get()),
        )
        assert shell_count(m) == 1, combo
    assert len(seen) == 2 * 2 * 2 * 3  # every combination its own mesh
    # closed and outward: test_every_mesh_closed_with_uvs_in_unit_square; here one shell


def test_high_lod_carries_the_carved_capital_cut_by_each_form(column_asset):
    """Egg-and-dart and bead-and-reel PointInstancers in the high lod only; the engaged and
    corner forms drop the copies inside their walls."""
    stage = open_stage(column_asset)
    vsets = stage.GetDefaultPrim().GetVariantSets()
    counts = {}
    for lod in VARIANTS["lod"]:
        vsets.GetVariantSet("lod").SetVariantSelection(lod)
        for form in VARIANTS["form"]:
            vsets.GetVariantSet("form").SetVariantSelection(form)
            every = [p for p in stage.Traverse() if p.IsA(UsdGeom.PointInstancer)]
            assert [str(p.GetPath()) for p in every] == [
                "/IonicColumn/Geom/Ornament/EggAndDart",
                "/IonicColumn/Geom/Ornament/BeadAndReel",
            ]
            inst = [
                UsdGeom.PointInstancer(p)
                for p in every
                if UsdGeom.Imageable(p).ComputeVisibility() != UsdGeom.Tokens.invisible
            ]
            if lod != "high":
                assert inst == [], (lod, form)
                continue
            assert sorted(source(i.GetPrim()).split("_high")[0] for i in inst) == [
                "BeadAndReel",
                "EggAndDart",
            ], form
            pos = np.concatenate([np.array(i.GetPositionsAttr().Get()) for i in inst])
            counts[form] = len(pos)
            if form != "full":
                behind = pos[:, 2] < -0.05
                if form == "corner":
                    behind &= pos[:, 0] < -0.05
                assert not behind.any(), form
    vsets.GetVariantSet("lod").SetVariantSelection("high")
    vsets.GetVariantSet("form").SetVariantSelection("full")
    # 24 eggs + 24 darts; beads: 2π·0.407 m / (0.0768 + 0.0336 + 0.0096) m → 21 pairs
    assert counts["full"] == 2 * 24 + 2 * 21
    # about half (engaged) and a quarter (corner) of the ring lie inside the walls
    assert 0.4 * counts["full"] < counts["engaged"] < 0.6 * counts["full"]
    assert 0.65 * counts["full"] < counts["corner"] < 0.85 * counts["full"]


def test_volute_option_builds_one_model_without_the_set(tmp_path):
    opts = ColumnAssetOptions(
        lods=("low",),
        bases=("G1",),
        scrolls=("S1",),
        flutes=("f24",),
        forms=("full",),
        capitals=("normal",),
        volutes=("centred_arcs",),
        texture_size=16,
    )
    rep = build_column_asset(tmp_path / "IonicColumn", opts)
    stage = open_stage(rep)
    assert "volute" not in stage.GetDefaultPrim().GetVariantSets().GetNames()
    assert validate_stage(stage) == []
    with pytest.raises(ParameterError, match="log_spiral"):
        ColumnAssetOptions(volutes=("ionic_scroll",))


def test_generated_meshes_are_cached_by_content(tmp_path, monkeypatch):
    """A rebuild of unchanged options reads the generated meshes back (no generation) and
    writes byte-identical files; a damaged cache entry is produced again."""
    import hashlib

    from ionic_usd.pipeline import asset as pipeline_asset
    from ionic_usd.pipeline.mesh_cache import mesh_cache_folder
    from ionic_usd.texture.uv import UVCache

    monkeypatch.setenv("IONIC_USD_CACHE", str(tmp_path / "cache"))
    opts = ColumnAssetOptions(
        lods=("low",), bases=("G1",), scrolls=("S1",), flutes=("f24",), texture_size=16
    )
    calls = []
    real = pipeline_asset.column_asset_meshes
    monkeypatch.setattr(
        pipeline_asset, "column_asset_meshes", lambda *a, **k: calls.append(1) or real(*a, **k)
    )

    def build(name):
        build_column_asset(
            tmp_path / name / "IonicColumn", opts, cache=UVCache(tmp_path / "cache" / "uv")
        )
        return {
            p.relative_to(tmp_path / name): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted((tmp_path / name).rglob("*"))
            if p.is_file()
        }

    first = build("a")
    assert len(calls) == 1
    second = build("b")
    assert len(calls) == 1 and second == first  # read back, same bytes
    entries = list(mesh_cache_folder().iterdir())
    assert len(entries) == 1
    npz = entries[0] / "meshes.npz"
    npz.write_bytes(npz.read_bytes()[:100])  # truncated: its manifest no longer matches
    third = build("c")
    assert len(calls) == 2 and third == first
    # other options are another entry
    build_column_asset(
        tmp_path / "d" / "IonicColumn",
        dataclasses.replace(opts, bases=("G2",)),
        cache=UVCache(tmp_path / "cache" / "uv"),
    )
    assert len(calls) == 3 and len(list(mesh_cache_folder().iterdir())) == 2


def test_a_mesh_cache_that_cannot_be_written_costs_nothing_but_the_cache(tmp_path, monkeypatch):
    """The cache entry is written by a background thread: a full disk there (or any failure)
    leaves no entry, no staging folder and no error, and the asset is the same."""
    import errno
    import hashlib

    from ionic_usd.pipeline import mesh_cache
    from ionic_usd.texture.uv import UVCache

    monkeypatch.setenv("IONIC_USD_CACHE", str(tmp_path / "cache"))
    opts = ColumnAssetOptions(
        lods=("low",), bases=("G1",), scrolls=("S1",), flutes=("f24",), texture_size=16
    )

    def full(folder, meshes):
        (folder / "meshes.npz").write_bytes(b"partial")
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(mesh_cache, "_write", full)
    build_column_asset(tmp_path / "a" / "IonicColumn", opts, cache=UVCache(tmp_path / "uv"))
    assert not mesh_cache._WRITERS
    assert list(mesh_cache.mesh_cache_folder().iterdir()) == []
    monkeypatch.undo()
    monkeypatch.setenv("IONIC_USD_CACHE", str(tmp_path / "cache"))
    build_column_asset(tmp_path / "b" / "IonicColumn", opts, cache=UVCache(tmp_path / "uv"))
    assert len(list(mesh_cache.mesh_cache_folder().iterdir())) == 1

    def digest(root):
        return {
            p.relative_to(root): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(root.rglob("*"))
            if p.is_file() and "manifest" not in p.name
        }

    assert digest(tmp_path / "a") == digest(tmp_path / "b")


def test_generation_in_parallel_processes_gives_the_serial_meshes(tmp_path, monkeypatch):
    """The asset's units of work run in a process pool: the meshes (geometry, charts, tags,
    order) must not depend on how many processes ran them. The stone maps made in the same
    pool (side jobs) are in the cache afterwards: copying them generates nothing."""
    import ionic_usd.texture.stone as stone
    from ionic_usd.pipeline.asset import _texture_jobs, copy_stone_textures
    from ionic_usd.texture.uv import UVCache

    monkeypatch.setenv("IONIC_USD_CACHE", str(tmp_path / "cache"))
    opts = ColumnAssetOptions(
        lods=("low", "medium"), bases=("G1",), scrolls=("S1",), flutes=("f24",), texture_size=16
    )
    serial = column_asset_meshes(opts, UVCache(tmp_path / "a"), workers=1)
    cache = UVCache(tmp_path / "b")
    jobs = _texture_jobs(opts)
    assert sorted(args[0] for _, args in jobs) == ["stucco_painted", "travertine"]
    parallel = column_asset_meshes(opts, cache, workers=2, side_jobs=jobs)

    def no_generation(*_a, **_k):
        raise AssertionError("the maps should have been in the cache")

    monkeypatch.setattr(stone, "write_stone_textures", no_generation)
    for _, (style, size, seed, _tx) in jobs:
        got = copy_stone_textures(tmp_path / "tex", style, size, seed)
        assert [p.name for p in got] == [
            f"{style}_{r}.png" for r in ("basecolor", "roughness", "normal")
        ]
    assert cache.misses == 0  # every part brings its own charts: no xatlas run in the pool
    assert [(m.part, m.name, m.tags) for m in parallel] == [
        (m.part, m.name, m.tags) for m in serial
    ]
    for a, b in zip(serial, parallel, strict=True):
        for f in ("points", "face_vertex_indices", "normals", "st"):
            x, y = getattr(a.mesh, f), getattr(b.mesh, f)
            assert (x is None) == (y is None), (a.name, f)
            if isinstance(x, CornerValues):
                assert x.distinct == y.distinct and x.by_point == y.by_point, (a.name, f)
                np.testing.assert_array_equal(x.values, y.values, err_msg=f"{a.name}.{f}")
                x, y = x.indices, y.indices
                assert (x is None) == (y is None), (a.name, f)
            if x is not None:
                np.testing.assert_array_equal(x, y, err_msg=f"{a.name}.{f}")


@pytest.mark.skipif((os.cpu_count() or 1) < 2, reason="side jobs need the process pool")
def test_build_side_jobs_warm_the_cache_in_the_pool(tmp_path, monkeypatch):
    """``build_column_asset(side_jobs=)`` (the temple's terracotta maps) runs them in the
    geometry's pool: afterwards the maps are in the cache and copying them generates none."""
    import ionic_usd.texture.stone as stone
    from ionic_usd.pipeline.asset import copy_stone_textures, warm_stone_textures
    from ionic_usd.texture.uv import UVCache

    monkeypatch.setenv("IONIC_USD_CACHE", str(tmp_path / "cache"))
    opts = ColumnAssetOptions(
        lods=("low",), bases=("G1",), scrolls=("S1",), flutes=("f24",), texture_size=16
    )
    tiles = ("terracotta", 16, 3)
    build_column_asset(
        tmp_path / "a" / "IonicColumn",
        opts,
        cache=UVCache(tmp_path / "uv"),
        side_jobs=[(warm_stone_textures, tiles)],
    )

    def no_generation(*_a, **_k):
        raise AssertionError("the maps should have been in the cache")

    monkeypatch.setattr(stone, "write_stone_textures", no_generation)
    got = copy_stone_textures(tmp_path / "tex", *tiles)
    assert [p.name for p in got] == [
        f"terracotta_{r}.png" for r in ("basecolor", "roughness", "normal")
    ]


@pytest.mark.parametrize("form", ["engaged", "corner"])
def test_form_cuts_keep_the_charts_of_a_base_apart(form):
    # the plinth's top and the torus's underside are box-mapped with mirrored frames whose
    # values meet on the axis plane z = 0; the cuts re-indexed st by value and joined them
    # into one chart, repacked overlapping (106 sub-texels engaged, 1106 corner, of a 4x raster)
    from test_uv import overlap_texels

    from ionic_usd.column.column import build_base_part
    from ionic_usd.pipeline.asset import form_cut
    from ionic_usd.texture.uv import unwrap

    p = ColumnAssetOptions().params.with_lod("low")
    full = build_base_part(p, "attic_bezier_plinth")
    a = unwrap(form_cut(full, form, "Base"), texels_per_metre=32.0, cache=False)
    assert overlap_texels(a.st_px, a.st_indices) == 0


def test_an_asset_keeps_a_free_chain_of_arcs(tmp_path):
    """A column whose volute is a free chain (a carved volute's fit) builds as an asset: the
    log-spiral variant drops the chain, the centred-arc one keeps it, and the parameters in the
    asset's customData read back to the same volute, bit for bit."""
    from ionic_usd.column.column import column_params_from_mapping
    from ionic_usd.column.volute_arcs import arc_centres
    from ionic_usd.usd.sections_reader import stored_tables

    base = ColumnAssetOptions().params
    centred = base.capital.volute.with_(
        volute_model="centred_arcs", capital_circle_radius=0.024, arc_square=0.026
    )
    _, radii, _ = arc_centres(centred)
    bumped = tuple(float(r) * (1.0 + 0.01 * ((-1) ** j)) for j, r in enumerate(radii))
    chain = centred.with_(arc_radii=bumped)
    params = dataclasses.replace(base, capital=base.capital.with_(volute=chain))
    opts = ColumnAssetOptions(
        params=params,
        lods=("low",),
        bases=("G1",),
        scrolls=("S1",),
        flutes=("f24",),
        forms=("full",),
        capitals=("normal",),
        texture_size=16,
    )
    build_column_asset(tmp_path / "IonicColumn", opts)
    stage = Usd.Stage.Open(str(tmp_path / "IonicColumn" / "IonicColumn.usda"))
    assert not validate_stage(stage)
    tables = stored_tables(tmp_path / "IonicColumn" / "IonicColumn.usda", ("volute",))
    assert column_params_from_mapping(tables).capital.volute == chain
    # both volute variants were built: the chain's and the spiral's (which has no chain)
    vset = stage.GetDefaultPrim().GetVariantSet("volute")
    assert vset.GetVariantSelection() == "centred_arcs"
    body = UsdGeom.Mesh(stage.GetPrimAtPath("/IonicColumn/Geom/CapitalBody"))
    arcs = np.asarray(body.GetPointsAttr().Get())
    vset.SetVariantSelection("log_spiral")
    spiral = np.asarray(body.GetPointsAttr().Get())
    assert arcs.shape != spiral.shape or not np.allclose(arcs, spiral)
