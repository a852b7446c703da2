"""Tests for the scroll-body ring grammar (paper Table 5)."""

from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from ionic_usd.errors import GrammarError, ParameterError
from ionic_usd.grammar.scroll import (
    ScrollRing,
    format_scroll,
    load_scroll_preset,
    parse_scroll,
    resolve_scroll,
    scroll_preset_names,
    scroll_preset_text,
)

S1 = "R0.7 P0.05, R0.7 P0.4, R0.8 P0.5, R0.7 P0.6, R0.7 P0.95"
S2 = (
    "R0.7 P0.05, R0.6 P0.1, R0.6 P0.3, R0.7 P0.35, R0.6 P0.4, R0.6 P0.45, R0.7 P0.5, "
    "R0.6 P0.55, R0.6 P0.6, R0.7 P0.65, R0.6 P0.7, R0.6 P0.9, R0.7 P0.95"
)
S1_RINGS = [(0.7, 0.05), (0.7, 0.4), (0.8, 0.5), (0.7, 0.6), (0.7, 0.95)]
S2_RINGS = [
    (0.7, 0.05),
    (0.6, 0.1),
    (0.6, 0.3),
    (0.7, 0.35),
    (0.6, 0.4),
    (0.6, 0.45),
    (0.7, 0.5),
    (0.6, 0.55),
    (0.6, 0.6),
    (0.7, 0.65),
    (0.6, 0.7),
    (0.6, 0.9),
    (0.7, 0.95),
]


@pytest.mark.parametrize("text, rings", [(S1, S1_RINGS), (S2, S2_RINGS)])
def test_paper_examples(text, rings):
    g = parse_scroll(text)
    assert [(r.radius, r.position) for r in g.rings] == rings
    assert g.radii == tuple(r for r, _ in rings)


@pytest.mark.parametrize("name, text, rings", [("S1", S1, S1_RINGS), ("S2", S2, S2_RINGS)])
def test_presets_are_the_spec_strings(name, text, rings):
    assert scroll_preset_text(name) == text
    assert [(r.radius, r.position) for r in load_scroll_preset(name).rings] == rings
    assert load_scroll_preset(name.lower()) == parse_scroll(text)
    assert resolve_scroll(name) == parse_scroll(text)


def test_unknown_preset_lists_names():
    assert scroll_preset_names() == ("S1", "S2")
    with pytest.raises(ParameterError, match="S1, S2"):
        load_scroll_preset("S9")


@pytest.mark.parametrize(
    "text",
    [
        "R0.7 P0.05,R0.8 P1",
        " R0.7\tP0.05 ,\nR0.8  P1 ",
        "r0.7 p0.05, R.8 P1.0",
        "R0.7P0.05,R8e-1P1",
        "R+0.7 P5e-2, R0.80 P1",
    ],
)
def test_whitespace_case_and_number_forms(text):
    assert parse_scroll(text).rings == (ScrollRing(0.7, 0.05), ScrollRing(0.8, 1.0))


def test_equal_positions_and_range_ends_are_allowed():
    g = parse_scroll("R0 P0, R2 P0, R2 P1, R0 P1")
    assert g.positions == (0.0, 0.0, 1.0, 1.0)


@pytest.mark.parametrize(
    "text, token, module, message",
    [
        ("R0.7 P0.05, X1 P0.2", "X1", 2, "unknown token"),
        ("R0.7 P0.05, R0.7 P0.2 Q", "Q", 2, "unknown token"),
        ("R0.7 P0.05, R P0.2", "R", 2, "missing radius"),
        ("R0.7 P", "P", 1, "missing position"),
        ("R0.7 P0.05, Rabc P0.2", "abc", 2, "not a number"),
        ("R0.7 P0.05, R0.7 P0.2.1", "0.2.1", 2, "not a number"),
        ("R0.7 P0.05, R2.5 P0.2", "2.5", 2, "outside [0, 2]"),
        ("R-0.1 P0", "-0.1", 1, "outside [0, 2]"),
        ("R0.7 P1.5", "1.5", 1, "outside [0, 1]"),
        ("R0.7 P0.5, R0.7 P0.4", "0.4", 2, "must not decrease"),
        ("R0.7 P0.5, R0.7 R0.8 P0.6", "R0.8", 2, "second R"),
        ("R0.7 P0.5, P0.6 R0.7", "P0.6", 2, "P before R"),
        ("R0.7 P1e999", "1e999", 1, "finite"),
        ("R0.7 P0.1, , R0.7 P0.2", ",", 2, "empty module"),
    ],
)
def test_pointed_errors(text, token, module, message):
    with pytest.raises(GrammarError) as exc:
        parse_scroll(text)
    e = exc.value
    assert message in e.message
    assert e.grammar == "scroll" and e.module == module
    # the caret sits under the offending token
    start = text.rindex(token) if token != "R" else text.rindex("R P")
    if token == ",":
        start = text.index(", ,") + 2
    assert e.offset == start
    assert e.length == len(token)
    src_line, caret_line = e.get_context().splitlines()
    assert caret_line.index("^") - 2 == start
    assert src_line[2 + start : 2 + start + len(token)] == token
    assert f"module {module}" in str(e)


@pytest.mark.parametrize("text", ["", "   ", "R0.7"])
def test_incomplete_strings(text):
    with pytest.raises(GrammarError):
        parse_scroll(text)


def test_missing_position_points_after_the_radius():
    with pytest.raises(GrammarError) as exc:
        parse_scroll("R0.7 P0.1, R0.7")
    assert exc.value.offset == len("R0.7 P0.1, R0.7")


@settings(max_examples=400, deadline=None)
@given(st.text(alphabet="RPrp0123456789.,-+eE xQ\t", max_size=40))
def test_fuzz_only_grammar_errors_escape(text):
    try:
        g = parse_scroll(text)
    except GrammarError as e:
        assert 0 <= e.offset <= len(text)
        return
    ps = g.positions
    assert all(b >= a for a, b in zip(ps, ps[1:], strict=False))
    assert all(0 <= r <= 2 for r in g.radii) and all(0 <= p <= 1 for p in ps)


@settings(max_examples=200, deadline=None)
@given(st.text(max_size=30))
def test_fuzz_any_text(text):
    try:
        parse_scroll(text)
    except GrammarError:
        pass


ring_lists = st.lists(
    st.tuples(st.floats(0, 2, allow_nan=False), st.floats(0, 1, allow_nan=False)),
    min_size=1,
    max_size=12,
).map(
    lambda xs: [
        ScrollRing(r, p) for r, p in zip([x[0] for x in xs], sorted(x[1] for x in xs), strict=True)
    ]
)


@settings(max_examples=200, deadline=None)
@given(ring_lists)
def test_format_round_trip(rings):
    text = format_scroll(rings)
    assert parse_scroll(text).rings == tuple(rings)
