"""The `detail` variant set: plain / moulded / carved switch geometry; layers valid alone."""

from __future__ import annotations

import numpy as np
import pytest
from pxr import Sdf, Usd, UsdGeom, UsdShade

from ionic_usd.temple.layout import portunus_layout
from ionic_usd.usd import validate_stage
from ionic_usd.usd.detail import DETAIL_VARIANTS, detail_counts, detail_geometry


def _tris(prim) -> int:
    counts = UsdGeom.Mesh(prim).GetFaceVertexCountsAttr().Get()
    return int(np.sum(np.asarray(counts) - 2))


def shown(prim) -> bool:
    """Active and visible (a variant hides what it does not show; its paths stay)."""
    return prim.IsActive() and UsdGeom.Imageable(prim).ComputeVisibility() != "invisible"


def scene_counts(stage) -> dict[str, int]:
    """Triangles drawn (instanced copies included), meshes, PointInstancer prototypes and
    instances on the composed stage (native column instances left out)."""
    out = {"triangles": 0, "meshes": 0, "prototypes": 0, "instances": 0}
    it = iter(Usd.PrimRange(stage.GetPseudoRoot()))
    for prim in it:
        if prim.IsInstance() or not shown(prim):  # a variant hides what it does not show
            it.PruneChildren()
        elif prim.IsA(UsdGeom.PointInstancer):
            it.PruneChildren()
            pi = UsdGeom.PointInstancer(prim)
            idx = np.asarray(pi.GetProtoIndicesAttr().Get())
            targets = pi.GetPrototypesRel().GetTargets()
            per = np.array([_tris(stage.GetPrimAtPath(t)) for t in targets])
            out["prototypes"] += len(targets)
            out["instances"] += len(idx)
            out["triangles"] += int(per[idx].sum())
        elif prim.IsA(UsdGeom.Mesh):
            out["meshes"] += 1
            out["triangles"] += _tris(prim)
    return out


@pytest.fixture(scope="module")
def stage(carved_temple):
    return Usd.Stage.Open(str(carved_temple.root))


def test_variants_switch_geometry_and_counts(stage):
    root = stage.GetDefaultPrim()
    vs = root.GetVariantSets().GetVariantSet("detail")
    assert vs.GetVariantNames() == sorted(DETAIL_VARIANTS)
    assert vs.GetVariantSelection() == "carved"
    want = detail_counts(detail_geometry(portunus_layout()))
    got = {}
    for v in DETAIL_VARIANTS:
        vs.SetVariantSelection(v)
        got[v] = scene_counts(stage)
        cornice = stage.GetPrimAtPath("/Temple/Entablature/cornice")
        assert shown(cornice) == (v == "plain")
        assert shown(stage.GetPrimAtPath("/Temple/Roof/Tiles")) == (v == "carved")
        assert shown(stage.GetPrimAtPath("/Temple/Entablature/Mouldings")) == (v != "plain")
        assert validate_stage(stage) == [], v
    # what each variant adds to the plain cuboids is what the kernel built; the moulded
    # variant drops two 12-triangle cuboids (architrave, cornice)
    base = got["plain"]
    for v in ("moulded", "carved"):
        assert got[v]["triangles"] - base["triangles"] == want[v]["triangles"] - 24, v
        assert got[v]["meshes"] - base["meshes"] == want[v]["meshes"] - 2, v
        assert got[v]["instances"] == want[v]["instances"]
        assert got[v]["prototypes"] == want[v]["prototypes"]
    assert got["plain"]["instances"] == 0 and got["moulded"]["instances"] == 0
    assert got["carved"]["instances"] > 1000 and got["carved"]["prototypes"] == 4
    vs.SetVariantSelection("carved")


def test_materials_per_role(stage):
    def bound(path):
        return str(
            UsdShade.MaterialBindingAPI(stage.GetPrimAtPath(path))
            .ComputeBoundMaterial()[0]
            .GetPath()
            .name
        )

    assert bound("/Temple/Roof/Tiles") == "Terracotta"
    assert bound("/Temple/Podium/die") == "Travertine"
    assert bound("/Temple/Podium/Mouldings/podium_crown") == "Travertine"
    assert bound("/Temple/Cella/wall_left") == "PaintedStucco"
    assert bound("/Temple/Entablature/Mouldings/cornice") == "PaintedStucco"
    tex = stage.GetPrimAtPath("/Temple/Materials/Terracotta/BaseColor")
    assert UsdShade.Shader(tex).GetInput("file").Get().resolvedPath


def test_every_detail_layer_is_valid_alone(carved_temple):
    folder = carved_temple.root.parent
    files = [folder / "detail.usdc", *sorted((folder / "layers").glob("*.usdc"))]
    # the detail, the frieze relief, the detail re-placed for the two hypotheses that move the
    # entablature or the roof, and the garlands on the lower frieze
    assert {f.name for f in files} >= {
        "detail.usdc",
        "frieze-garlands.usdc",
        "roof-pitch-15.detail.usdc",
        "frieze-plain.detail.usdc",
    }
    for f in files:
        assert validate_stage(Usd.Stage.Open(str(f))) == [], f.name


def test_frieze_hypothesis_is_realised_and_cited(stage):
    listing = stage.GetDefaultPrim().GetCustomData()["ionic_usd"]["hypotheses"]
    entry = listing["frieze_garlands"]
    assert entry["realised"] is True and entry["variantSet"] == "hyp_frieze"  # its question
    assert entry["variant"] == "frieze_garlands" and entry["question"] == "frieze"
    assert entry["certainty"] == "medium" and len(entry["sources"]) >= 2
    path = "/Temple/Entablature/Ornament/FriezeGarlands"
    assert not shown(stage.GetPrimAtPath(path))  # a plain band by default (the path stays)
    sets = stage.GetDefaultPrim().GetVariantSets()
    try:
        sets.GetVariantSet("hyp_frieze").SetVariantSelection("frieze_plain")  # the other one
        assert not shown(stage.GetPrimAtPath(path))
        sets.GetVariantSet("hyp_frieze").SetVariantSelection("frieze_garlands")
        garlands = UsdGeom.PointInstancer(stage.GetPrimAtPath(path))
        assert garlands and len(garlands.GetProtoIndicesAttr().Get()) > 10
        assert garlands.GetPrim().GetCustomData()["ionic_usd"]["hypotheses"]["frieze_garlands"]
        sets.GetVariantSet("detail").SetVariantSelection("moulded")  # relief is ornament
        assert not shown(stage.GetPrimAtPath("/Temple/Entablature/Ornament"))
    finally:
        sets.GetVariantSet("hyp_frieze").SetVariantSelection("baseline")
        sets.GetVariantSet("detail").SetVariantSelection("carved")


def test_roof_hypothesis_moves_the_tiles_with_the_roof(carved_temple):
    stage = Usd.Stage.Open(str(carved_temple.root))
    tiles = UsdGeom.PointInstancer(stage.GetPrimAtPath("/Temple/Roof/Tiles"))
    before = np.array(tiles.GetPositionsAttr().Get())
    stage.GetDefaultPrim().GetVariantSets().GetVariantSet("hyp_roof_pitch_15").SetVariantSelection(
        "alternative"
    )
    after = np.array(tiles.GetPositionsAttr().Get())
    ridge_before, ridge_after = before[:, 1].max(), after[:, 1].max()
    assert ridge_after > ridge_before + 0.2  # a steeper roof raises the ridge tiles


def test_column_high_lod_carries_the_carved_capital(carved_temple):
    path = carved_temple.root.parent / "IonicColumn" / "IonicColumn.usda"
    stage = Usd.Stage.Open(str(path))
    vs = stage.GetDefaultPrim().GetVariantSets().GetVariantSet("lod")
    for lod in ("high", "medium", "low"):
        vs.SetVariantSelection(lod)
        every = [p for p in stage.Traverse() if p.IsA(UsdGeom.PointInstancer)]
        # the same two paths at every lod (stable prim paths), drawn in the high lod only
        assert sorted(p.GetName() for p in every) == ["BeadAndReel", "EggAndDart"]
        inst = [
            p for p in every if UsdGeom.Imageable(p).ComputeVisibility() != UsdGeom.Tokens.invisible
        ]
        if lod == "high":
            n = sum(len(UsdGeom.PointInstancer(p).GetProtoIndicesAttr().Get()) for p in inst)
            # 24 eggs + 24 darts; beads: 2π·0.407 m / (0.0768 + 0.0336 + 0.0096) m → 21 pairs
            assert n == 2 * 24 + 2 * 21
        else:
            assert inst == [], lod
    layer = Sdf.Layer.FindOrOpen(str(path.parent / "Payload" / "Geometry.usdc"))
    assert layer.GetPrimAtPath("/_IonicColumnParts/Ornament/EggAndDart_high/Prototypes/Egg")


def test_selected_variant_is_a_choice(tmp_path):
    from ionic_usd.errors import ParameterError
    from ionic_usd.pipeline.temple import compose_temple
    from ionic_usd.usd.detail import author_detail_variants
    from ionic_usd.usd.stage import new_layer

    root = new_layer("Temple", kind="assembly")
    geom = detail_geometry(portunus_layout())
    author_detail_variants(root.GetPrimAtPath("/Temple"), geom, "plain")
    assert root.GetPrimAtPath("/Temple").variantSelections["detail"] == "plain"
    with pytest.raises(ParameterError, match="detail"):
        author_detail_variants(new_layer("Temple").GetPrimAtPath("/Temple"), geom, "fancy")
    with pytest.raises(ParameterError, match="detail"):  # before anything is written
        compose_temple(tmp_path / "t", portunus_layout(), detail="fancy")
    assert not (tmp_path / "t").exists()


def test_cli_bad_moulding_section_names_file_and_key(tmp_path, capsys):
    from ionic_usd.cli import main

    cfg = tmp_path / "t.toml"
    cfg.write_text('[mouldings]\ncornice = "R0 H0 Rx H1"\n')
    out = tmp_path / "out"
    assert main(["temple", "--config", str(cfg), "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert "t.toml" in err and "mouldings.cornice" in err and "Traceback" not in err
    assert not out.exists()


def test_docs_detail_table_matches_the_default_temple(stage):
    """The triangle table of docs/specification/temple.md, row by row, from the default build."""
    import re
    from pathlib import Path

    from ionic_usd.usd.temple import triangles_with

    page = Path(__file__).resolve().parents[1] / "docs" / "specification" / "temple.md"
    readme = page.read_text("utf-8")
    rows = re.findall(
        r"^\| (plain|moulded|carved)(?: \(default\))? \| .* \| ([\d,]+) \| ([\d,]+) \|$",
        readme,
        flags=re.M,
    )
    assert [r[0] for r in rows] == ["plain", "moulded", "carved"]
    for detail, high, low in rows:
        for lod, want in (("high", high), ("low", low)):
            got = triangles_with(stage, {"detail": detail, "lod": lod})
            assert got == int(want.replace(",", "")), (detail, lod)
