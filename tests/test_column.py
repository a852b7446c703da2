"""The whole column: stacking, closedness, LODs, base variants, TOML config, CLI."""

from __future__ import annotations

import tomllib

import numpy as np
import pytest

from ionic_usd.cli import main
from ionic_usd.column.base import build_base
from ionic_usd.column.column import (
    PORTUNUS_HEIGHT,
    ColumnParams,
    build_column,
    column_params_from_mapping,
    column_params_to_tables,
    portunus_column_params,
)
from ionic_usd.column.shaft import build_shaft
from ionic_usd.errors import GrammarError, ParameterError
from ionic_usd.geometry import inspect_mesh, merge, weld
from ionic_usd.lod import LOD_NAMES
from ionic_usd.usd import validate_stage


@pytest.mark.parametrize("lod", LOD_NAMES)
def test_portunus_column_parts_closed_and_stacked(lod):
    col = build_column(portunus_column_params(lod=lod))
    for name, mesh in col.parts().items():
        r = inspect_mesh(mesh)
        assert r.closed and r.consistent and r.signed_volume > 0, (name, r)
        assert r.degenerate_faces == 0, name
    assert col.height == pytest.approx(PORTUNUS_HEIGHT)
    # extents as designed: base from the ground, shaft on the base, abacus top = column top
    assert col.base.extent[0, 1] == pytest.approx(0.0)
    assert col.shaft.extent[0, 1] == pytest.approx(col.base_height)
    assert col.shaft.extent[1, 1] == pytest.approx(col.base_height + col.shaft_length)
    assert col.capital_body.extent[1, 1] == pytest.approx(PORTUNUS_HEIGHT)
    # lower diameter 0.95 m, top diameter 6/7 of it
    r_shaft = np.hypot(col.shaft.points[:, 0], col.shaft.points[:, 2])
    assert r_shaft.max() == pytest.approx(0.475)
    top = col.shaft.points[:, 1] > col.shaft.extent[1, 1] - 1e-9
    assert r_shaft[top].max() == pytest.approx(0.475 * 6 / 7)


def test_whole_column_mesh_is_closed():
    col = build_column(portunus_column_params(lod="medium"))
    r = inspect_mesh(merge(list(col.parts().values())))
    assert r.closed and r.consistent


@pytest.mark.parametrize("base", ["G1", "G2", "attic_bezier", "attic_bezier_plinth"])
def test_base_variants_weld_to_shaft_and_keep_height(base):
    p = portunus_column_params(lod="low", base=base)
    bp = p.base_params()
    assert bp.height == pytest.approx(p.base_height)
    solid = weld(
        merge(
            [
                build_base(bp, cap_top=False),
                build_shaft(p.shaft_params(), cap_bottom=False, y_offset=bp.height),
            ]
        )
    )
    assert inspect_mesh(solid).watertight


def test_lod_monotonic_in_triangles():
    counts = [
        build_column(portunus_column_params(lod=lod)).n_triangles
        for lod in ("low", "medium", "high")
    ]
    assert counts == sorted(counts) and len(set(counts)) == 3


def test_config_roundtrip_and_errors():
    p = portunus_column_params(base="G2", scroll="S2")
    tables = column_params_to_tables(p)
    assert column_params_from_mapping(tables) == p
    with pytest.raises(ParameterError, match="flute_cnt"):
        column_params_from_mapping({"shaft": {"flute_cnt": 3}})
    with pytest.raises(ParameterError, match=r"\[roof\]"):
        column_params_from_mapping({"roof": {}})
    with pytest.raises(ParameterError, match="lod"):
        ColumnParams(lod="ultra")
    with pytest.raises(GrammarError):
        column_params_from_mapping({"column": {"base": "R0 H0.1 C2 R0.1"}})


def test_cli_column_validates_and_parts(tmp_path, capsys):
    out = tmp_path / "c.usdc"
    assert main(["column", "-o", str(out), "--lod", "low", "--base", "G1"]) == 0
    assert validate_stage(out) == []
    from pxr import Usd

    stage = Usd.Stage.Open(str(out))
    names = sorted(p.GetName() for p in stage.GetPrimAtPath("/Column/Geom").GetChildren())
    assert names == ["Base", "CapitalBody", "Shaft"]  # the capital is one solid
    out2 = tmp_path / "s.usda"
    assert main(["column", "-o", str(out2), "--part", "shaft", "--lod", "low"]) == 0
    stage = Usd.Stage.Open(str(out2))
    assert [p.GetName() for p in stage.GetPrimAtPath("/Column/Geom").GetChildren()] == ["Shaft"]


def test_cli_print_config_is_accepted_back(tmp_path, capsys):
    assert main(["column", "--print-config", "--scroll", "S2"]) == 0
    text = capsys.readouterr().out
    assert tomllib.loads(text)["column"]["scroll"] == "S2"
    cfg = tmp_path / "c.toml"
    cfg.write_text(text)
    assert (
        main(["column", "--config", str(cfg), "--lod", "low", "-o", str(tmp_path / "c.usda")]) == 0
    )


def test_cli_bad_grammar_points_at_token(tmp_path, capsys):
    assert main(["column", "--base", "R0 H0.1 Cx R0.1", "-o", str(tmp_path / "x.usda")]) == 2
    err = capsys.readouterr().err
    assert "module 1" in err and "^" in err
    assert not (tmp_path / "x.usda").exists()


@pytest.mark.parametrize("diameter", [0.6, 1.2])
def test_portunus_capital_scales_with_the_lower_diameter(diameter):
    """The capital of a column ``k`` times the Portunus diameter is the Portunus capital
    ``k`` times as large: every vertex of its meshes, and its height."""
    from ionic_usd.column.capital import build_capital, capital_height

    k = diameter / 0.95
    ref, p = portunus_column_params(), portunus_column_params(lower_diameter=diameter)
    assert p.capital.volute.capital_spiral_radius == pytest.approx(k * 0.95 / 4)
    assert p.capital.volute.a == ref.capital.volute.a  # spiral units kept
    assert p.capital.spiral_samples == ref.capital.spiral_samples
    assert capital_height(p.capital) == pytest.approx(k * capital_height(ref.capital), rel=1e-12)
    big = build_capital(p.capital, top_radius=p.shaft.top_radius).as_dict()
    small = build_capital(ref.capital, top_radius=ref.shaft.top_radius).as_dict()
    assert big.keys() == small.keys()
    for name, mesh in big.items():
        np.testing.assert_allclose(mesh.points, k * small[name].points, atol=1e-9, err_msg=name)
    # the column keeps its total height: the shaft gives what the capital takes
    built = build_column(p)
    top = max(m.points[:, 1].max() for m in built.parts().values())
    assert top == pytest.approx(8.22, abs=1e-6)
    assert portunus_column_params(lower_diameter=0.95) == ref


def test_a_base_is_a_preset_by_name_else_a_grammar():
    from ionic_usd.column.base import base_preset_names, load_base_preset

    # every shipped name reads as that preset (G1 has a digit, attic_bezier none)
    for name in base_preset_names():
        bp = ColumnParams(base=name).base_params()
        assert bp.grammar == load_base_preset(name, shaft_radius=bp.shaft_radius).grammar
    # anything else is a grammar, digits or not in the text
    grammar = "R0.12 H0.05 C1 R0.12"
    assert ColumnParams(base=grammar).base_params().grammar == grammar
    # neither: one error naming both readings (a preset typo with a digit, a bare word)
    for text in ("G3", "atticc", "T(1"):
        with pytest.raises(ParameterError) as err:
            ColumnParams(base=text)
        assert "a base preset (G1, G2" in str(err.value) and "base grammar" in str(err.value)
    # a grammar wrong past its first token keeps its own error and caret
    with pytest.raises(GrammarError) as gerr:
        ColumnParams(base="R0.1 H0.1 C1 Q")
    assert gerr.value.offset == 13


def test_the_base_flag_names_every_shipped_preset(capsys):
    from ionic_usd.column.base import base_preset_names

    with pytest.raises(SystemExit):
        main(["column", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert all(name in text for name in base_preset_names()), text
