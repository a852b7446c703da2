"""Mutually exclusive hypotheses: the alternatives of one question are ONE variant set.

``frieze-plain`` and ``frieze-garlands`` (portunus.toml, ``question = "frieze"``) are the set
``hyp_frieze`` = baseline | frieze_plain | frieze_garlands: the composed stage cannot show a
plain frieze with garlands. Independent hypotheses stay switches (``hyp_<id>``).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from pxr import Usd, UsdGeom

from ionic_usd.blueprint.hypotheses import (
    check_hypothesis_budget,
    hyp_choices,
    hyp_sets,
    shape_combinations,
)
from ionic_usd.errors import BudgetError, ParameterError
from ionic_usd.params import load_toml
from ionic_usd.pipeline.city import _lot_selection
from ionic_usd.temple.description import exclusive_clash, questions
from ionic_usd.temple.layout import build_layout, layout_from_mapping, portunus_layout
from ionic_usd.usd.combinations import mismatches
from ionic_usd.usd.temple import CUBOID_UV_SCALE

PORTUNUS = Path(__file__).resolve().parent.parent / "ionic_usd/data/portunus.toml"


def shown(prim: Usd.Prim) -> bool:
    return (
        bool(prim)
        and prim.IsActive()
        and UsdGeom.Imageable(prim).ComputeVisibility() != UsdGeom.Tokens.invisible
    )


def test_portunus_frieze_is_one_question():
    layout = portunus_layout()
    qs = questions(layout.hypotheses)
    assert [h.id for h in qs["frieze"]] == ["frieze-plain", "frieze-garlands"]
    assert all(len(qs[h.id]) == 1 for h in layout.hypotheses if h.key != "frieze")
    choices = hyp_choices(layout.hypotheses)
    assert choices["frieze-plain"] == ("hyp_frieze", "frieze_plain")
    assert choices["frieze-garlands"] == ("hyp_frieze", "frieze_garlands")
    assert choices["roof-pitch-15"] == ("hyp_roof_pitch_15", "alternative")
    assert hyp_sets(layout.hypotheses)["hyp_frieze"] == (
        "baseline",
        "frieze_plain",
        "frieze_garlands",
    )
    # composed and checked: roof pitch (2) x frieze (baseline, plain, garlands: 3)
    assert shape_combinations(layout.hypotheses) == 6


def test_applying_two_alternatives_of_a_question_is_refused():
    layout = portunus_layout()
    assert exclusive_clash(["frieze-plain", "roof-pitch-15"], layout.hypotheses) is None
    with pytest.raises(ParameterError, match="alternatives of the question 'frieze'") as info:
        build_layout(
            layout.params, hypotheses=layout.hypotheses, apply=["frieze-plain", "frieze-garlands"]
        )
    assert "\n" not in str(info.value)


def _stage_values(stage: Usd.Stage) -> dict[str, set[str]]:
    """Shown prim → the hypotheses (idents) its composed paradata lists."""
    out = {}
    for p in stage.Traverse():
        if p.GetPath() == "/Temple" or not shown(p):
            continue
        listed = set(p.GetCustomData().get("ionic_usd", {}).get("hypotheses", {}))
        if listed:
            out[str(p.GetPath())] = listed
    return out


def test_each_value_of_a_question_shows_exactly_that_alternative(portunus_temple):
    """For every question set of /Temple and every value: the composed geometry is the layout
    with exactly that alternative applied (cuboids, columns), the prims of the other
    alternatives are hidden, the prim paths are the same under every value."""
    stage = Usd.Stage.Open(str(portunus_temple.root))
    root = stage.GetDefaultPrim()
    listing = root.GetCustomData()["ionic_usd"]["hypotheses"]
    by_choice = {(e["variantSet"], e["variant"]): e["id"] for e in listing.values()}
    vsets = root.GetVariantSets()
    layout = portunus_layout()
    question_sets = [
        n
        for n in vsets.GetNames()
        if n.startswith("hyp_") and len(vsets.GetVariantSet(n).GetVariantNames()) > 2
    ]
    assert question_sets == ["hyp_frieze"]
    paths = None
    for name in question_sets:
        values = vsets.GetVariantSet(name).GetVariantNames()
        others = {v: by_choice[(name, v)] for v in values if v != "baseline"}
        for value in values:
            with Usd.EditContext(stage, stage.GetSessionLayer()):
                vsets.GetVariantSet(name).SetVariantSelection(value)
                vsets.GetVariantSet("detail").SetVariantSelection("plain")
            mine = others.get(value)
            want = build_layout(
                layout.params, hypotheses=layout.hypotheses, apply=[mine] if mine else []
            )
            bad = mismatches(stage, want, layout.params.columns_height, uv_scale=CUBOID_UV_SCALE)
            assert bad == {}, (name, value, sorted(bad))
            with Usd.EditContext(stage, stage.GetSessionLayer()):
                vsets.GetVariantSet("detail").SetVariantSelection("carved")
            listed = set().union(*_stage_values(stage).values())
            for v, hid in others.items():
                ident = hid.replace("-", "_")
                if v == value:
                    assert ident in listed, (name, value)  # its prims show
                else:
                    assert ident not in listed, (name, value, hid)  # never two at once
            now = [str(p.GetPath()) for p in stage.Traverse()]
            assert paths is None or now == paths  # a variant swaps content, never paths
            paths = now
        stage.GetSessionLayer().Clear()
    relief = stage.GetPrimAtPath("/Temple/Entablature/Ornament/FriezeGarlands")
    with Usd.EditContext(stage, stage.GetSessionLayer()):
        vsets.GetVariantSet("hyp_frieze").SetVariantSelection("frieze_plain")
    assert relief and not shown(relief)  # a plain frieze has no garlands
    stage.GetSessionLayer().Clear()


def _portunus_with(extra: list[dict]) -> dict:
    data = load_toml(PORTUNUS)
    data["hypothesis"] = list(data["hypothesis"]) + extra
    return data


def _hyp(hid: str, question: str, changes: dict) -> dict:
    return {
        "id": hid,
        "question": question,
        "description": "d",
        "sources": ["s"],
        "certainty": "low",
        "changes": changes,
    }


def test_a_question_declaring_one_change_twice_is_refused():
    data = _portunus_with([_hyp("frieze-low", "frieze", {"entablature.frieze_ratio": 0.75})])
    with pytest.raises(ParameterError, match="same change") as info:
        layout_from_mapping(data, context="t.toml")
    assert "\n" not in str(info.value) and "frieze-low" in str(info.value)
    data = _portunus_with([_hyp("pitch-a", "roof-pitch-15", {"roof.tympanum_ratio": 8.0})])
    with pytest.raises(ParameterError, match="variant set hyp_roof_pitch_15"):
        layout_from_mapping(data, context="t.toml")


def test_the_budget_counts_combinations():
    """A third frieze alternative: 2 x 4 = 8 combinations; 4 questions of 4 alternatives and
    the roof: 2 x 3 x 5^4 combinations, refused before any work."""
    ok = _portunus_with([_hyp("frieze-high", "frieze", {"entablature.frieze_ratio": 1.5})])
    layout = layout_from_mapping(ok, context="t.toml")
    assert shape_combinations(layout.hypotheses) == 8
    check_hypothesis_budget(layout)
    many = [
        _hyp(f"q{q}-{a}", f"q{q}", {"roof.tympanum_ratio": 5 + q + 0.1 * a})
        for q in range(4)
        for a in range(4)
    ]
    layout = layout_from_mapping(_portunus_with(many), context="t.toml")
    assert shape_combinations(layout.hypotheses) == 2 * 3 * 5**4
    with pytest.raises(BudgetError, match="3,750 combinations"):
        check_hypothesis_budget(layout)


class _Lot:
    def __init__(self, hyps: dict[str, str]):
        self.id, self.hypotheses = "lot1", hyps


def test_city_lots_never_draw_two_alternatives_of_a_question():
    hyps = portunus_layout().hypotheses
    rng = np.random.default_rng(0)
    seen = set()
    for _ in range(400):
        sel = _lot_selection(_Lot({}), hyps, rng, True, "plan")
        assert set(sel) == {h.id for h in hyps}
        on = [h for h in ("frieze-plain", "frieze-garlands") if sel[h] == "alternative"]
        assert len(on) <= 1
        seen.add(tuple(on))
    assert seen == {(), ("frieze-plain",), ("frieze-garlands",)}  # each can be drawn
    # the plan's choice wins, and the other alternative of its question is off
    for _ in range(50):
        sel = _lot_selection(_Lot({"frieze-garlands": "alternative"}), hyps, rng, True, "plan")
        assert sel["frieze-garlands"] == "alternative" and sel["frieze-plain"] == "baseline"
    with pytest.raises(ParameterError, match="alternatives of the question 'frieze'") as info:
        _lot_selection(
            _Lot({"frieze-plain": "alternative", "frieze-garlands": "alternative"}),
            hyps,
            rng,
            True,
            "plan",
        )
    assert "\n" not in str(info.value) and "lot1" in str(info.value)


def test_web_data_groups_the_alternatives_of_a_question(tiny_temple):
    """The web panel's data: both frieze alternatives under the question 'frieze', each with
    its own value of hyp_frieze and the parts that value changes (the relief for garlands)."""
    from ionic_usd.usd.paradata_scene import read_scene_paradata
    from ionic_usd.usd.web_scene import hypothesis_changes
    from ionic_usd.web import _data

    changes, base = hypothesis_changes(tiny_temple.root, {"lod": "low", "detail": "carved"})
    assert "hyp_frieze=frieze_plain" in changes and "hyp_frieze=frieze_garlands" in changes
    data = _data(read_scene_paradata(tiny_temple.root), changes, base)
    frieze = {h["id"]: h for h in data["hypotheses"] if h["question"] == "frieze"}
    assert set(frieze) == {"frieze-plain", "frieze-garlands"}
    assert {(h["set"], h["variant"]) for h in frieze.values()} == {
        ("hyp_frieze", "frieze_plain"),
        ("hyp_frieze", "frieze_garlands"),
    }
    assert any("FriezeGarlands" in p for p in frieze["frieze-garlands"]["changes"])
    assert not any("FriezeGarlands" in p for p in frieze["frieze-plain"]["changes"])
    roof = next(h for h in data["hypotheses"] if h["id"] == "roof-pitch-15")
    assert (roof["question"], roof["variant"]) == ("roof-pitch-15", "alternative")


def test_graphml_links_the_alternatives_of_a_question(tiny_temple, tmp_path):
    from ionic_usd.cli import main
    from ionic_usd.temple.em_graphml import HYP_PREFIX, graph_of, read_graphml
    from ionic_usd.usd.paradata_scene import read_scene_paradata

    pd = read_scene_paradata(tiny_temple.root)
    asks = {hid: str(e.get("question") or hid) for hid, e in pd.listing.items()}
    assert asks["frieze-plain"] == asks["frieze-garlands"] == "frieze"
    g = graph_of(pd.parts, pd.hypotheses, asks)
    between = [
        (a, b) for a, b, _ in g.edges if a in g.units and b in g.units and a.startswith(HYP_PREFIX)
    ]
    between = [(a, b) for a, b in between if b.startswith(HYP_PREFIX)]
    assert between == [(HYP_PREFIX + "frieze-garlands", HYP_PREFIX + "frieze-plain")]
    out = tmp_path / "em.graphml"
    assert main(["paradata", str(tiny_temple.root), "-o", str(out)]) == 0
    parts, hyps = read_graphml(out)  # the extra edges read back without harm
    assert {"frieze-plain", "frieze-garlands"} <= set(hyps)


@pytest.mark.slow  # a temple build of its own (~14 s)
def test_a_question_interacting_with_a_switch_gets_nested_combination_layers(tmp_path):
    """Two answers for the cornice (one question) with the roof pitch (a switch): where the
    roof pitch and an answer interact the combination layer is nested inside that answer's
    value, and every choice composes to the layout built with it."""
    from ionic_usd.pipeline.temple import compose_temple
    from ionic_usd.usd.detail import detail_geometry

    data = load_toml(PORTUNUS)
    data["hypothesis"] = [h for h in data["hypothesis"] if h["id"] == "roof-pitch-15"] + [
        _hyp("deep-cornice", "cornice", {"entablature.cornice_projection_ratio": 1.6}),
        _hyp("shallow-cornice", "cornice", {"entablature.cornice_projection_ratio": 0.7}),
    ]
    layout = layout_from_mapping(data, context="test")
    rep = compose_temple(tmp_path / "T", layout, texture_size=16)
    assert "roof-pitch-15+deep-cornice" in rep.combination_layers
    stage = Usd.Stage.Open(str(tmp_path / "T" / "Temple.usda"))
    vsets = stage.GetDefaultPrim().GetVariantSets()
    assert vsets.GetVariantSet("hyp_cornice").GetVariantNames() == [
        "baseline",
        "deep_cornice",
        "shallow_cornice",
    ]
    ids_of = {
        "baseline": [],
        "deep_cornice": ["deep-cornice"],
        "shallow_cornice": ["shallow-cornice"],
    }
    for pitch in ("baseline", "alternative"):
        for cornice, ids in ids_of.items():
            with Usd.EditContext(stage, stage.GetSessionLayer()):
                vsets.GetVariantSet("hyp_roof_pitch_15").SetVariantSelection(pitch)
                vsets.GetVariantSet("hyp_cornice").SetVariantSelection(cornice)
                vsets.GetVariantSet("detail").SetVariantSelection("moulded")
            apply = ids + (["roof-pitch-15"] if pitch == "alternative" else [])
            want = build_layout(layout.params, hypotheses=layout.hypotheses, apply=apply)
            bad = mismatches(
                stage,
                want,
                layout.params.columns_height,
                uv_scale=CUBOID_UV_SCALE,
                variant="moulded",
                detail=detail_geometry(want),
            )
            assert bad == {}, (apply, sorted(bad))


def test_prim_name_is_tf_make_valid_identifier():
    """The blueprint names prims without pxr; its names are USD's own, byte for byte."""
    from pxr import Tf

    from ionic_usd.blueprint.hypotheses import prim_name

    names = ["abc", "1abc", "a-b", "", "é", "aé", "a b", "日本", "_x", "ab.c", "x²", "٣a", "9"]
    names += ["podium_front", "roof-pitch-15", "frieze_garlands", "Temple/A", "a\u0301"]
    for n in names:
        assert prim_name(n) == Tf.MakeValidIdentifier(n), n
