"""Paradata on every part (customData, userProperties), the reliability view, the EM graph."""

from __future__ import annotations

import itertools
import xml.etree.ElementTree as ET

import pytest
from pxr import Sdf, Usd, UsdGeom, UsdShade

from ionic_usd.temple.em_graphml import HYP_PREFIX, graph_of, read_graphml, write_graphml
from ionic_usd.temple.layout import portunus_layout
from ionic_usd.temple.paradata import EM_CHART, Evidence, part_key
from ionic_usd.usd.hypotheses import hyp_choices
from ionic_usd.usd.paradata import em_material_path
from ionic_usd.usd.paradata_scene import read_scene_paradata

PARTS = {"Mesh", "PointInstancer"}


def part_prims(stage: Usd.Stage) -> list[Usd.Prim]:
    """Every part drawn: a mesh or instancer of the temple's own layers, or a column instance
    (a detail or hypothesis hides what it does not show, keeping its path: skipped)."""
    out = []
    for p in stage.Traverse():
        path = str(p.GetPath())
        if "Prototypes" in path or path.startswith("/Temple/Materials"):
            continue
        img = UsdGeom.Imageable(p)
        if img and img.ComputeVisibility() == UsdGeom.Tokens.invisible:
            continue
        if p.GetTypeName() in PARTS or (path.startswith("/Temple/Colonnade/") and p.IsInstance()):
            out.append(p)
    return out


def record_of(prim: Usd.Prim) -> dict:
    return dict(prim.GetCustomData()["paradata"])


def selections(stage):
    root = stage.GetDefaultPrim()
    sets = root.GetVariantSets()
    hyps = [n for n in sets.GetNames() if n.startswith("hyp_")]
    details = sets.GetVariantSet("detail").GetVariantNames()
    yield from ({"detail": d} for d in details)
    # every value of every hypothesis set (a question's set has one per alternative)
    values = {
        h: [v for v in sets.GetVariantSet(h).GetVariantNames() if v != "baseline"] for h in hyps
    }
    yield from ({h: v} for h in hyps for v in values[h])
    yield {h: values[h][-1] for h in hyps}


def select(stage, sel: dict) -> None:
    sets = stage.GetDefaultPrim().GetVariantSets()
    for k, v in sel.items():
        sets.GetVariantSet(k).SetVariantSelection(v)


@pytest.fixture(scope="module")
def stage(tiny_temple):
    return Usd.Stage.Open(str(tiny_temple.root))


def test_every_part_carries_its_record_as_custom_data_and_user_properties(tiny_temple):
    stage = Usd.Stage.Open(str(tiny_temple.root))
    for sel in selections(stage):
        select(stage, sel)
        prims = part_prims(stage)
        assert len(prims) > 40, sel
        for p in prims:
            rec = record_of(p)
            assert rec["unit"] == part_key(str(p.GetPath())) or rec["hypothesis"] != "baseline"
            assert Evidence(rec["evidence"]) in EM_CHART and rec["sources"] and rec["description"]
            props = {
                a.GetName().split(":", 2)[2]: a.Get()
                for a in p.GetAuthoredAttributes()
                if a.GetName().startswith("userProperties:em:")
            }
            assert props["evidence"] == rec["evidence"] and props["unit"] == rec["unit"]
            assert props["sources"] == "; ".join(rec["sources"]), p.GetPath()
            assert props["certainty"] == rec["certainty"]
        select(stage, {k: ("baseline" if k.startswith("hyp_") else "plain") for k in sel})


def test_portunus_in_situ_and_reconstructed_parts(stage):
    select(stage, {"detail": "carved"})
    by_unit = {record_of(p)["unit"]: record_of(p) for p in part_prims(stage)}
    for unit in ("podium", "cella", "architrave", "column.front_1", "column.rear_4"):
        assert by_unit[unit]["evidence"] == "US", unit
        assert any("Adam" in s for s in by_unit[unit]["sources"])
    assert by_unit["roof"]["evidence"] == "USV/s"
    assert by_unit["stair"]["evidence"] == "USV/s"
    assert by_unit["tiles"]["evidence"] == "USV/n"
    stucco = stage.GetPrimAtPath("/Temple/Materials/PaintedStucco")
    assert record_of(stucco)["evidence"] == "USV/n"
    select(stage, {"detail": "plain"})


def test_a_hypothesis_alternative_carries_its_own_record(tiny_temple):
    stage = Usd.Stage.Open(str(tiny_temple.root))
    select(stage, {"detail": "carved"})  # the frieze relief is carved detail
    layout = portunus_layout()
    choices = hyp_choices(layout.hypotheses)  # a question's alternatives share one set
    for h in layout.hypotheses:
        vset, value = choices[h.id]
        select(stage, {vset: value})
        mine = [p for p in part_prims(stage) if record_of(p)["hypothesis"] == h.id]
        assert mine, h.id
        for p in mine:
            rec = record_of(p)
            assert rec["certainty"] == str(h.certainty)
            assert list(rec["sources"]) == list(h.sources)
        select(stage, {vset: "baseline"})
        assert not [p for p in part_prims(stage) if record_of(p)["hypothesis"] == h.id]


def bound(prim: Usd.Prim) -> str:
    mat, _ = UsdShade.MaterialBindingAPI(prim).ComputeBoundMaterial()
    return str(mat.GetPath()) if mat else ""


def meshes_with_part(stage):
    """Every drawn mesh (instance proxies included) and the record of its part."""
    pred = Usd.TraverseInstanceProxies(Usd.PrimDefaultPredicate)
    for p in stage.Traverse(pred):
        if p.GetTypeName() != "Mesh" or "/Materials" in str(p.GetPath()):
            continue
        if UsdGeom.Imageable(p).ComputeVisibility() == UsdGeom.Tokens.invisible:
            continue  # hidden by a detail or hypothesis (its path kept): not drawn
        anc = p
        while anc and "paradata" not in anc.GetCustomData():
            anc = anc.GetParent()
        assert anc, p.GetPath()
        yield p, record_of(anc)


def test_reliability_view_binds_the_em_chart_for_every_selection(tiny_temple):
    stage = Usd.Stage.Open(str(tiny_temple.root))
    for sel in itertools.chain(selections(stage), [{}]):
        select(stage, {**sel, "view": "reliability"})
        n = 0
        for mesh, rec in meshes_with_part(stage):
            assert bound(mesh) == em_material_path(Evidence(rec["evidence"])), (sel, mesh)
            n += 1
        assert n > 40
        select(stage, {"view": "appearance"})
        assert not any(
            bound(m).startswith("/Temple/Materials/EM") for m, _ in meshes_with_part(stage)
        )
        select(stage, {k: ("baseline" if k.startswith("hyp_") else "plain") for k in sel})


def test_em_material_colours_are_the_chart(stage):
    for ev, entry in EM_CHART.items():
        shader = UsdShade.Shader.Get(stage, em_material_path(ev) + "/PreviewSurface")
        lin = shader.GetInput("diffuseColor").Get()
        srgb = [int(entry.border[i : i + 2], 16) / 255 for i in (1, 3, 5)]
        back = [12.92 * c if c <= 0.0031308 else 1.055 * c ** (1 / 2.4) - 0.055 for c in lin]
        assert max(abs(a - b) for a, b in zip(back, srgb, strict=True)) < 1e-4


# -- the Extended Matrix graph ------------------------------------------------------------------


@pytest.fixture(scope="module")
def graph_file(tiny_temple, tmp_path_factory):
    pd = read_scene_paradata(tiny_temple.root)
    path = tmp_path_factory.mktemp("em") / "temple.graphml"
    g = graph_of(pd.parts, pd.hypotheses)
    write_graphml(g, path)
    return path, g, pd


def test_graph_has_a_unit_per_part_and_hypothesis(graph_file, stage):
    _, g, pd = graph_file
    units = {record_of(p)["unit"] for p in part_prims(stage)}
    assert set(pd.parts) >= units
    assert {HYP_PREFIX + h.id for h in portunus_layout().hypotheses} <= set(g.units)
    cites = {s for r in g.units.values() for s in r.sources}
    assert set(g.documents) == cites


def test_networkx_reads_the_same_units_and_edges(graph_file):
    nx = pytest.importorskip("networkx")
    path, g, _ = graph_file
    G = nx.read_graphml(path)
    # node labels as networkx reads them (yfiles NodeLabel → "label")
    label = {n: d.get("label") for n, d in G.nodes(data=True)}
    kind = {n: ("unit" if n[0] == "u" else "property" if n[0] == "p" else "document") for n in G}
    assert sorted(label[n] for n in G if kind[n] == "unit") == sorted(g.units)
    assert sorted(label[n] for n in G if kind[n] == "document") == sorted(g.documents.values())
    unit_of = {n: label[n] for n in G if kind[n] == "unit"}
    prop_of = {b: unit_of[a] + "#certainty" for a, b in G.edges() if kind[b] == "property"}
    name = {**unit_of, **prop_of, **{n: label[n] for n in G if kind[n] == "document"}}
    assert sorted((name[a], name[b]) for a, b in G.edges()) == sorted((a, b) for a, b, _ in g.edges)


def test_the_em_tools_parser_reads_the_units_and_edges(graph_file, capsys):
    pytest.importorskip("s3dgraphy")
    from s3dgraphy.importer.import_graphml import GraphMLImporter

    path, g, _ = graph_file
    parsed = GraphMLImporter(str(path)).parse()
    capsys.readouterr()  # the parser prints progress
    codes = {Evidence.USV_S: "USVs", Evidence.USV_N: "USVn"}
    units = {n.name: n.node_type for n in parsed.nodes if n.node_type not in
             ("property", "document", "geo_position", "link")}  # fmt: skip
    assert units == {k: codes.get(r.evidence, r.evidence.value) for k, r in g.units.items()}
    docs = {n.description for n in parsed.nodes if n.node_type == "document"}
    assert docs == set(g.documents)
    assert len([n for n in parsed.nodes if n.node_type == "property"]) == len(g.units)
    assert len(parsed.edges) == len(g.edges)


def test_read_graphml_returns_what_was_written(graph_file):
    path, g, _ = graph_file
    parts, hyps = read_graphml(path)
    for label, rec in g.units.items():
        got = hyps[label[len(HYP_PREFIX) :]] if label.startswith(HYP_PREFIX) else parts[label]
        assert (got.evidence, got.certainty, got.sources) == (
            rec.evidence,
            rec.certainty,
            rec.sources,
        )
        assert got.description == rec.description


def yed_edit(src, dst, unit: str, shape: str, border: str, new_source: str) -> None:
    """What a yEd user does: restyle one unit (its EM class) and retype one document."""
    ET.register_namespace("", "http://graphml.graphdrawing.org/xmlns")
    ET.register_namespace("y", "http://www.yworks.com/xml/graphml")
    tree = ET.parse(src)
    Y = "{http://www.yworks.com/xml/graphml}"
    G = "{http://graphml.graphdrawing.org/xmlns}"
    ids = {}
    for n in tree.getroot().iter(G + "node"):
        lab = n.find(f".//{Y}NodeLabel")
        ids[n.get("id")] = (lab.text, n)
        if lab.text == unit:
            n.find(f".//{Y}Shape").set("type", shape)
            n.find(f".//{Y}BorderStyle").set("color", border)
    uid = next(i for i, (t, _) in ids.items() if t == unit)
    prop = next(e.get("target") for e in tree.getroot().iter(G + "edge") if e.get("source") == uid)
    doc = next(e.get("target") for e in tree.getroot().iter(G + "edge") if e.get("source") == prop)
    desc = next(d for d in ids[doc][1].findall(G + "data") if d.get("key") == "d_desc")
    desc.text = new_source
    tree.write(dst, xml_declaration=True, encoding="UTF-8")


def test_a_yed_edit_sets_class_and_source(graph_file, tmp_path):
    from ionic_usd.api import Temple
    from ionic_usd.cli.make import _with_graphml_paradata

    path, _, _ = graph_file
    edited = tmp_path / "edited.graphml"
    yed_edit(path, edited, "roof", "rectangle", "#9B3333", "A new survey of the roof")
    temple = _with_graphml_paradata(Temple.portunus(), edited)
    rec = temple.layout.paradata.record("roof")
    assert rec.evidence is Evidence.US and "A new survey of the roof" in rec.sources
    # every other unit as before
    base = Temple.portunus().layout.paradata
    assert temple.layout.paradata.record("podium") == base.record("podium")


def test_reliability_collections_exist_only_in_the_variant(tiny_temple):
    gen = Sdf.Layer.FindOrOpen(str(tiny_temple.root.parent / "generated.usda"))
    spec = gen.GetPrimAtPath("/Temple")
    assert list(spec.variantSets["view"].variants.keys()) == ["appearance", "reliability"]
    assert not [p for p in spec.properties if p.name.startswith("material:binding:collection")]


def test_gltf_extras_carry_every_parts_paradata(tiny_temple, tmp_path):
    pygltflib = pytest.importorskip("pygltflib")
    from ionic_usd.export import export_scene

    out = tmp_path / "t.glb"
    export_scene(tiny_temple.root, out, variants={"view": "reliability"})
    g = pygltflib.GLTF2().load(str(out))
    parent = {c: i for i, n in enumerate(g.nodes) for c in (n.children or [])}
    seen = set()
    for i, n in enumerate(g.nodes):
        if n.mesh is None:
            continue
        # a group node holds what its copies share: the record is the chain's, nearer first
        chain, j = [n], i
        while j in parent:
            j = parent[j]
            chain.append(g.nodes[j])
        ex: dict = {}
        for node in reversed(chain):
            mine = dict(node.extras or {})
            ex = {**ex, **mine, "paradata": {**ex.get("paradata", {}), **mine.get("paradata", {})}}
        entries = ex.get("instances") or [ex]
        for e in entries:
            rec = {**ex.get("paradata", {}), **e.get("paradata", {})}
            assert Evidence(rec["evidence"]) in EM_CHART and rec["sources"], (n.name, e)
            seen.add(rec["unit"])
    assert {"podium", "stair", "cella", "roof", "column.front_1"} <= seen
    # the reliability view exports the chart's materials, nothing else
    names = {m.name for m in g.materials}
    assert names <= {ev.name for ev in EM_CHART} and names
