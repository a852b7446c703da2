"""The command line: outputs validate, errors are one line with status 2 and write nothing."""

from __future__ import annotations

import tomllib

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from ionic_usd.cli import main
from ionic_usd.column.shaft import ShaftParams
from ionic_usd.usd import validate_stage


def test_shaft_command_writes_valid_usd(tmp_path, capsys):
    out = tmp_path / "s.usdc"
    assert main(["shaft", "-o", str(out), "--flute-slices", "3"]) == 0
    assert out.exists()
    assert validate_stage(out) == []
    assert "triangles" in capsys.readouterr().out


def test_print_config_roundtrips_through_config(tmp_path, capsys):
    assert main(["shaft", "--print-config", "--flutes", "20", "--flute-angle", "14"]) == 0
    text = capsys.readouterr().out
    data = tomllib.loads(text)
    assert ShaftParams(**data["shaft"]) == ShaftParams(flutes=20, flute_angle=14.0)
    cfg = tmp_path / "c.toml"
    cfg.write_text(text)
    assert main(["shaft", "--config", str(cfg), "-o", str(tmp_path / "x.usda")]) == 0


@pytest.mark.parametrize(
    "args,needle",
    [
        (["--flutes", "2"], "flutes ($e) = 2"),
        (["--bottom-radius", "0"], "bottom_radius ($d)"),
        (["--flute-angle", "15"], "flute_angle ($f)"),
        (["--flute-slices", "0"], "flute_slices ($h)"),
        (["--height", "nan"], "height"),
        (["--flute-slices", "5000", "--max-triangles", "100000"], "triangles"),
    ],
)
def test_bad_input_one_line_status_2_nothing_written(tmp_path, capsys, args, needle):
    out = tmp_path / "bad.usda"
    assert main(["shaft", "-o", str(out), *args]) == 2
    err = capsys.readouterr().err.strip()
    assert needle in err and len(err.splitlines()) == 1
    assert not out.exists()


def test_unknown_toml_key(tmp_path, capsys):
    cfg = tmp_path / "c.toml"
    cfg.write_text("[shaft]\nflute_cnt = 24\n")
    assert main(["shaft", "--config", str(cfg), "-o", str(tmp_path / "x.usda")]) == 2
    assert "flute_cnt" in capsys.readouterr().err
    cfg.write_text("[shaft\n")
    assert main(["shaft", "--config", str(cfg)]) == 2


def test_existing_output_needs_force(tmp_path, capsys):
    out = tmp_path / "s.usda"
    out.write_text("user data")
    assert main(["shaft", "-o", str(out)]) == 2
    assert out.read_text() == "user data"
    assert main(["shaft", "-o", str(out), "--force"]) == 0
    assert validate_stage(out) == []


# -- the TOML writer behind --print-config ------------------------------------------------------
@settings(max_examples=300, deadline=None)
@given(
    st.text(alphabet=st.characters(exclude_categories=("Cs",)), max_size=40),
    st.text(alphabet=st.characters(exclude_categories=("Cs",)), min_size=1, max_size=12),
)
def test_toml_writer_round_trips_any_string(value, key):
    """Newlines, quotes, backslashes, control characters, odd keys: tomllib reads back what
    was written."""
    from ionic_usd.params import to_toml

    tables = {"t": {key: value, "plain": 'a "quoted" \\ line\nand\ta\r\nnext'}}
    if key == "plain":
        tables["t"] = {key: value}
    assert tomllib.loads(to_toml(tables, header="a header\nof two lines")) == tables


def test_print_config_with_a_newline_in_a_grammar_is_valid_toml(capsys):
    grammar = "R0.02 H0.05\nR0.03 H0.1"  # whitespace (a newline) is free in the grammar
    assert main(["column", "--print-config", "--base", grammar]) == 0
    data = tomllib.loads(capsys.readouterr().out)
    assert data["column"]["base"] == grammar


@pytest.mark.parametrize("where", ["before", "after"])
def test_verbosity_flags_before_or_after_the_command(tmp_path, caplog, where):
    import logging

    from ionic_usd.cli import build_parser

    flags = ["-q"]
    argv = (
        [*flags, "shaft", "-o", "x.usda"]
        if where == "before"
        else ["shaft", "-o", "x.usda", *flags]
    )
    args = build_parser().parse_args(argv)
    assert args.quiet is True and args.verbose == 0
    argv = ["-vv", "shaft"] if where == "before" else ["shaft", "-vv"]
    args = build_parser().parse_args(argv)
    assert args.verbose == 2 and args.quiet is False
    out = tmp_path / "s.usda"
    with caplog.at_level(logging.DEBUG):
        assert (
            main(
                ["shaft", "-o", str(out), "-q"]
                if where == "after"
                else ["-q", "shaft", "-o", str(out)]
            )
            == 0
        )
    assert out.exists()


def test_progress_messages_name_their_units_in_english(caplog):
    # -v prints "unwrapping UVs (xatlas) (1 mesh)", never "1 meshs" or "2 meshs"
    import logging

    from ionic_usd.progress import progress

    with caplog.at_level(logging.INFO, logger="ionic_usd"):
        for n, unit in ((1, "mesh"), (2, "mesh"), (3, "material"), (1, "material")):
            with progress(n, "step", unit=unit):
                pass
    assert [r.getMessage() for r in caplog.records] == [
        "step (1 mesh)",
        "step (2 meshes)",
        "step (3 materials)",
        "step (1 material)",
    ]
