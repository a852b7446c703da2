"""One material library per temple, bound once: UsdShade resolves every mesh of a composed
temple (its columns' meshes, read through their instances) to ``/Temple/Materials``, and a
column's ``finish`` still switches its material."""

from __future__ import annotations

from collections import defaultdict

import pytest
from pxr import Sdf, Usd, UsdGeom, UsdShade

from ionic_usd.usd import validate_stage

PROXIES = Usd.TraverseInstanceProxies(Usd.PrimAllPrimsPredicate)


def _bound(root: Usd.Prim) -> dict[Sdf.Path, Sdf.Path]:
    """Every Mesh and PointInstancer under ``root`` (through instances) → its bound material."""
    out = {}
    for p in Usd.PrimRange(root, PROXIES):
        if p.IsActive() and (p.IsA(UsdGeom.Mesh) or p.IsA(UsdGeom.PointInstancer)):
            mat, _ = UsdShade.MaterialBindingAPI(p).ComputeBoundMaterial()
            assert mat, f"{p.GetPath()}: no bound material"
            out[p.GetPath()] = mat.GetPath()
    return out


def _check_one_library(root: Usd.Prim, library: Sdf.Path) -> dict[Sdf.Path, Sdf.Path]:
    bound = _bound(root)
    assert bound
    outside = {m: p for m, p in bound.items() if not p.HasPrefix(library)}
    assert not outside, f"bound outside {library}: {sorted(set(outside.values()))[:4]}"
    # one prim per material: no two bound materials share a name (a client that makes a
    # material per bound prim makes each once)
    used = set(bound.values())
    assert len(used) == len({p.name for p in used}), sorted(used)
    return bound


def test_every_mesh_of_the_temple_binds_into_its_one_library(portunus_temple):
    stage = Usd.Stage.Open(str(portunus_temple.root))
    bound = _check_one_library(stage.GetPseudoRoot(), Sdf.Path("/Temple/Materials"))
    columns = {m: p for m, p in bound.items() if m.HasPrefix("/Temple/Colonnade")}
    assert len({m.GetPrefixes()[3] for m in columns}) == 18  # every column's meshes
    assert set(columns.values()) == {Sdf.Path("/Temple/Materials/PaintedStucco")}
    assert {p.name for p in bound.values()} == {"PaintedStucco", "Travertine", "Terracotta"}
    # every Material of the composed stage is the temple library's, or one of the column
    # asset's own (inside an instance: what a reader of the prototype alone binds), which
    # UsdShade resolves nothing to
    for p in Usd.PrimRange(stage.GetPseudoRoot(), PROXIES):
        if p.IsA(UsdShade.Material) and not p.GetPath().HasPrefix("/Temple/Materials"):
            assert p.IsInstanceProxy() and p.GetPath().HasPrefix("/Temple/Colonnade"), p
            assert p.GetPath() not in bound.values()
    assert len(stage.GetPrototypes()) == 3  # the bindings left the columns' sharing alone
    assert validate_stage(stage) == []


def test_the_finish_switches_the_columns_material_in_the_library(portunus_temple):
    stage = Usd.Stage.Open(str(portunus_temple.root))
    stage.SetEditTarget(stage.GetSessionLayer())
    temple = stage.GetDefaultPrim()
    # the finish hypothesis: every column (and part) travertine
    temple.GetVariantSet("hyp_finish_bare_stone").SetVariantSelection("alternative")
    bound = _check_one_library(stage.GetPseudoRoot(), Sdf.Path("/Temple/Materials"))
    assert {p.name for m, p in bound.items() if m.HasPrefix("/Temple/Colonnade")} == {"Travertine"}
    stage.GetSessionLayer().Clear()
    # a user's selection on one column: that column only
    one = stage.GetPrimAtPath("/Temple/Colonnade/Free/front_1")
    one.GetVariantSet("finish").SetVariantSelection("travertine")
    per_column = defaultdict(set)
    for m, p in _check_one_library(stage.GetPseudoRoot(), Sdf.Path("/Temple/Materials")).items():
        if m.HasPrefix("/Temple/Colonnade"):
            per_column[m.GetPrefixes()[3].name].add(p.name)
    assert per_column.pop("front_1") == {"Travertine"}
    assert set().union(*per_column.values()) == {"PaintedStucco"}


def test_the_reliability_view_still_wins_over_the_columns_binding(portunus_temple):
    stage = Usd.Stage.Open(str(portunus_temple.root))
    stage.GetDefaultPrim().GetVariantSet("view").SetVariantSelection("reliability")
    bound = _bound(stage.GetPseudoRoot())
    cols = {p for m, p in bound.items() if m.HasPrefix("/Temple/Colonnade")}
    assert cols and all(p.HasPrefix("/Temple/Materials/EM") for p in cols), cols


def test_the_column_asset_alone_keeps_its_own_library(portunus_temple):
    asset = portunus_temple.root.parent / "IonicColumn" / "IonicColumn.usda"
    stage = Usd.Stage.Open(str(asset))
    root = stage.GetDefaultPrim()
    for finish, name in (("stucco", "PaintedStucco"), ("travertine", "Travertine")):
        root.GetVariantSet("finish").SetVariantSelection(finish)
        bound = _check_one_library(root, Sdf.Path("/IonicColumn/Materials"))
        assert {p.name for p in bound.values()} == {name}


@pytest.mark.parametrize("temple", ["Temple_a", "Temple_b", "Temple_c", "Temple_d"])
def test_every_temple_of_a_city_binds_into_its_own_library(tiny_city, temple):
    stage = Usd.Stage.Open(str(tiny_city))
    roots = [p for p in stage.Traverse() if p.GetName() == temple]
    assert len(roots) == 1
    bound = _check_one_library(roots[0], roots[0].GetPath().AppendChild("Materials"))
    colonnade = roots[0].GetPath().AppendChild("Colonnade")
    columns = {p for m, p in bound.items() if m.HasPrefix(colonnade)}
    assert columns == {roots[0].GetPath().AppendPath(Sdf.Path("Materials/PaintedStucco"))}
