"""Base grammar parsers: expected floor lists, forms, detection, pointed errors, fuzzing."""

from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from ionic_usd.errors import GrammarError, ParameterError
from ionic_usd.grammar import (
    BezierBase,
    BezierModule,
    ControlPoint,
    TorusBase,
    TorusFloor,
    TorusModule,
    detect_base_version,
    parse_base_grammar,
    parse_base_v1,
    parse_base_v2,
    tokenize,
)

G1 = "R0 H0.1 C-1 R0.1, R0.1 H0.1 C1 R0.2 H0.1 C1 R0.1"
G2 = (
    "R0.12 H0.12 C1 R0.12, R0.12 H0 C1 R0.074,R0.074 H0.046 C1 R0.12 H0.046 C1 R0.074, "
    "R0.074 H0.015 C1 R0.074, R0.074 H0.027 C-1 R0.026 H0.018 C-1 R0.044, "
    "R0.044 H0.015 C1 R0.044, R0.044 H0.038 C1 R0.082 H0.038 C1 R0.044, "
    "R0.044 H0.030 C1 R0.044, R0.044 H0.053 C-1 R0"
)
B_LETTER = "R1 H0 R2 H0 R2 H1 R1 H1, R1 H0 R1 H1 C1"
B_PAPER = "M(1,0,2,0,2,1,1,1), M(1,0,1,1,1)"


def _v1(*modules):
    """Modules given as (r0, (h, c, r1), (h, c, r2), …)."""
    out = []
    for m in modules:
        rb, floors = m[0], []
        for h, c, rt in m[1:]:
            floors.append(TorusFloor(rb, rt, h, c))
            rb = rt
        out.append(TorusModule(tuple(floors)))
    return TorusBase(tuple(out))


G1_EXPECTED = _v1((0, (0.1, -1, 0.1)), (0.1, (0.1, 1, 0.2), (0.1, 1, 0.1)))
G2_EXPECTED = _v1(
    (0.12, (0.12, 1, 0.12)),
    (0.12, (0, 1, 0.074)),
    (0.074, (0.046, 1, 0.12), (0.046, 1, 0.074)),
    (0.074, (0.015, 1, 0.074)),
    (0.074, (0.027, -1, 0.026), (0.018, -1, 0.044)),
    (0.044, (0.015, 1, 0.044)),
    (0.044, (0.038, 1, 0.082), (0.038, 1, 0.044)),
    (0.044, (0.030, 1, 0.044)),
    (0.044, (0.053, -1, 0)),
)
B_EXPECTED = BezierBase(
    (
        BezierModule(
            (ControlPoint(1, 0), ControlPoint(2, 0), ControlPoint(2, 1), ControlPoint(1, 1))
        ),
        BezierModule((ControlPoint(1, 0), ControlPoint(1, 1)), continuous=True),
    )
)


# -- expected values ------------------------------------------------------------------------
@pytest.mark.parametrize(
    "text, expected",
    [
        (G1, G1_EXPECTED),
        (G2, G2_EXPECTED),
        (B_LETTER, B_EXPECTED),
        (B_PAPER, B_EXPECTED),
        ("M(0, 0.1, -1, 0.1), M(0.1, 0.1, 1, 0.2, 0.1, 1, 0.1)", G1_EXPECTED),
    ],
)
def test_presets_parse_to_hand_written_floors(text, expected):
    assert parse_base_grammar(text) == expected


def test_g2_module_heights_sum_by_hand():
    g = parse_base_grammar(G2)
    assert [len(m.floors) for m in g.modules] == [1, 1, 2, 1, 2, 1, 2, 1, 1]
    assert g.height == pytest.approx(
        0.12 + 0 + 0.092 + 0.015 + 0.045 + 0.015 + 0.076 + 0.030 + 0.053
    )


@pytest.mark.parametrize("text", [G1, G2, B_LETTER])
def test_whitespace_and_comma_spacing_are_free(text):
    squeezed = text.replace(", ", ",")
    spread = "  " + text.replace(" ", "\t \n").replace(",", " ,  ") + "\n"
    glued = text.replace(" ", "")  # R0H0.1C-1R0.1: letters delimit the items
    ref = parse_base_grammar(text)
    for variant in (squeezed, spread, glued):
        assert parse_base_grammar(variant) == ref


@pytest.mark.parametrize("text", [G1, G2, B_LETTER, B_PAPER])
def test_round_trip_through_canonical_text(text):
    g = parse_base_grammar(text)
    assert parse_base_grammar(g.to_string(), g.version) == g


def test_token_offsets_point_into_the_source():
    g = parse_base_v1(G1)
    f = g.modules[1].floors[0]
    off, ln = f.r_top_at
    assert G1[off : off + ln] == "R0.2"
    b = parse_base_v2(B_LETTER)
    off, ln = b.modules[0].points[2].h_at
    assert B_LETTER[off : off + ln] == "H1"
    assert B_LETTER.index("R2 H1") + 3 == off


# -- detection --------------------------------------------------------------------------------
@pytest.mark.parametrize(
    "text, version",
    [
        (G1, 1),
        (G2, 1),
        (B_LETTER, 2),
        (B_PAPER, 2),
        ("R0 H1 C1 R1", 1),
        ("R0 H0 R1 H1", 2),
        ("R0 H0 R1 H1 C1", 2),
        ("M(0, 0.1, -1, 0.1)", 1),
        ("M(1,0,1,1)", 1),
        ("M(1,0,1,1,1)", 2),
        ("M(1,0,2,0,2,1,1,1)", 2),
        ("M(1,0,0.5,1)", 2),
    ],
)
def test_version_detection(text, version):
    assert detect_base_version(text) == version
    assert parse_base_grammar(text).version == version


def test_version_can_be_forced():
    g = parse_base_grammar("M(1,0,1,1)", version=2)
    assert g == BezierBase((BezierModule((ControlPoint(1, 0), ControlPoint(1, 1))),))
    with pytest.raises(ParameterError, match="version"):
        parse_base_grammar(G1, version=3)


# -- errors -----------------------------------------------------------------------------------
@pytest.mark.parametrize(
    "text, version, offset, module, fragment",
    [
        ("R0 H0.1 C2 R0.1", 1, 9, 1, "curvature"),
        ("R0 H0.1 C0.5 R0.1", 1, 9, 1, "curvature"),
        (
            G1.replace("H0.1 C1 R0.2", "H-0.1 C1 R0.2"),
            1,
            G1.index("H0.1 C1 R0.2") + 1,
            2,
            "negative height",
        ),
        ("R0 Hx C1 R1", 1, 4, 1, "not a number"),
        ("R0 H C1 R1", 1, 3, 1, "missing height"),
        ("R0 H0.1 C1", 1, 10, 1, "ends early"),
        ("R0 H0.1 C1 R1, R1", 1, 15, 2, "at least one floor"),
        ("R0 H0.1 C1 R1, X1 H1 C1 R2", 1, 15, 2, "unknown token"),
        ("R0 H0.1 C1 R1,, R1 H1 C1 R2", 1, 14, 2, "empty module"),
        ("R0 H0.1 C1 R1,", 1, 13, 2, "empty module"),
        ("R0 H1e999 C1 R1", 1, 4, 1, "not finite"),
        ("R0 Hnan C1 R1", 1, 4, 1, "not finite"),
        ("R0 H0.1 C1 R0.1.2", 1, 12, 1, "not a number"),
        ("", None, 0, None, "empty"),
        ("R1 H0 R1 H1 C2", 2, 13, 1, "continuity flag"),
        ("R1 H0 R1 H1, R1 H0", 2, 13, 2, "at least 2 control points"),
        ("R1 H0 R1", 2, 8, 1, "ends early"),
        ("R1 H0 C1 R1 H1", 2, 6, 1, "last item"),
        ("R1 H0 R1 H-1", 2, 10, 1, "negative height"),
        ("M(1,0,1,1,2)", 2, 10, 1, "continuity flag"),
        ("M(1,0,1", 2, 7, 1, "missing ')'"),
        ("M(1,,0,1)", 2, 4, 1, "missing value"),
        ("M(0, 0.1, 3, 0.1)", 1, 10, 1, "curvature"),
        ("M(0, 0.1, -1, 0.1, 1)", 1, 19, 1, "3k + 1"),
        ("M(0, 0.1, -1, 0.1), R0 H1 C1 R1", 1, 20, 2, "expected 'M('"),
        ("M(1 2)", 2, 4, 1, "expected ','"),
        ("M(R1, 0)", 2, 2, 1, "bare numbers"),
    ],
)
def test_errors_point_at_the_token(text, version, offset, module, fragment):
    with pytest.raises(GrammarError) as info:
        parse_base_grammar(text, version)
    e = info.value
    assert fragment in e.message
    assert e.offset == offset
    assert e.module == module
    if version is not None:
        assert e.grammar == f"base v{version}"
    # the caret sits under the offending column in the rendered message
    caret_line = str(e).splitlines()[-1]
    assert caret_line.index("^") - 2 == offset


def test_error_message_names_module_and_renders_source():
    with pytest.raises(GrammarError) as info:
        parse_base_grammar(G2.replace("C-1 R0.026", "C-2 R0.026"))
    text = str(info.value)
    assert (
        "module 5" in text and "base v1" in text and G2.replace("C-1 R0.026", "C-2 R0.026") in text
    )


def test_direct_construction_is_validated():
    with pytest.raises(ParameterError):
        TorusFloor(0, 1, 0.1, 0)
    with pytest.raises(ParameterError):
        TorusFloor(0, 1, -0.1, 1)
    with pytest.raises(ParameterError):
        BezierModule((ControlPoint(0, 0),))
    with pytest.raises(ParameterError):
        ControlPoint(float("nan"), 0)


# -- lexer --------------------------------------------------------------------------------
def test_lexer_tokens_carry_letter_text_and_offset():
    toks = tokenize("R0.12 H-1e-3,R5 M(1, 2)")
    items = [(t.kind, t.letter, t.text, t.offset) for t in toks]
    assert items == [
        ("item", "R", "0.12", 0),
        ("item", "H", "-1e-3", 6),
        (",", "", "", 12),
        ("item", "R", "5", 13),
        ("item", "M", "", 16),
        ("(", "", "", 17),
        ("item", "", "1", 18),
        (",", "", "", 19),
        ("item", "", "2", 21),
        (")", "", "", 22),
    ]


# -- fuzzing: nothing but GrammarError escapes ----------------------------------------------
_ALPHABET = "RHCMrhc0123456789.-+eE ,()\t\nxinf#"


def _parse_all(text):
    for version in (None, 1, 2):
        try:
            g = parse_base_grammar(text, version)
        except GrammarError:
            continue
        assert isinstance(g, TorusBase | BezierBase)
        assert parse_base_grammar(g.to_string(), g.version) == g


@settings(max_examples=300, deadline=None)
@given(st.text(alphabet=_ALPHABET, max_size=60))
def test_random_strings_raise_only_grammar_errors(text):
    _parse_all(text)


@settings(max_examples=300, deadline=None)
@given(
    st.sampled_from([G1, G2, B_LETTER, B_PAPER]),
    st.lists(
        st.tuples(
            st.integers(0, 400),
            st.sampled_from(["del", "ins", "rep"]),
            st.sampled_from(list(_ALPHABET)),
        ),
        min_size=1,
        max_size=4,
    ),
)
def test_mutated_presets_raise_only_grammar_errors(base, edits):
    text = base
    for pos, op, ch in edits:
        pos %= len(text) + 1
        if op == "del":
            text = text[:pos] + text[pos + 1 :]
        elif op == "ins":
            text = text[:pos] + ch + text[pos:]
        else:
            text = text[:pos] + ch + text[pos + 1 :]
    _parse_all(text)


_num = st.floats(-2, 2, allow_nan=False).map(lambda x: round(x, 4))
_pos = st.floats(0, 2, allow_nan=False).map(lambda x: round(x, 4))


@settings(max_examples=100, deadline=None)
@given(
    st.lists(
        st.tuples(
            _num, st.lists(st.tuples(_pos, st.sampled_from([1, -1]), _num), min_size=1, max_size=3)
        ),
        min_size=1,
        max_size=4,
    )
)
def test_generated_v1_grammars_round_trip(mods):
    g = _v1(*[(r0, *floors) for r0, floors in mods])
    assert parse_base_grammar(g.to_string()) == g


@settings(max_examples=100, deadline=None)
@given(
    st.lists(
        st.tuples(st.lists(st.tuples(_num, _pos), min_size=2, max_size=5), st.booleans()),
        min_size=1,
        max_size=4,
    )
)
def test_generated_v2_grammars_round_trip(mods):
    g = BezierBase(
        tuple(BezierModule(tuple(ControlPoint(r, h) for r, h in pts), c) for pts, c in mods)
    )
    assert parse_base_grammar(g.to_string()) == g
