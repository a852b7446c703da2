"""Parsers for the two column-base shape grammars (paper Tables 2–3; SPEC §2).

Version 1 (tori): modules separated by commas, each ``R<r> H<h> C<c> R<r> [H<h> C<c> R<r>]…``:
floors from a bottom radius to a top radius over a height with curvature c ∈ {1, −1}; the
floors of one module share (weld) their rings. Functional form ``M(r1, h1, c1, r2, …)``.

Version 2 (Bézier): each module is one floor ``R<r> H<h> R<r> H<h> … [C1]``: ≥ 2 control points
(r, h) and an optional trailing continuity flag. Functional form ``M(r1, h1, …, rn, hn[, c])``
(an odd argument count means a trailing c).

Radii r are added to the shaft's bottom radius $d; heights h are measured from the module's
bottom. Both are in scene units (metres): see :mod:`ionic_usd.column.base` for why.

Version detection (:func:`parse_base_grammar` with ``version=None``):

* functional form: v1 when every module has 3k + 1 arguments (k ≥ 1) and its every third
  argument is ±1; otherwise v2. (``M(1,0,1,1)`` reads as v1; pass ``version=2`` to force.)
* letter form: v1 when the string has an H and *every* H is immediately followed by a C;
  otherwise v2. A valid v2 module has ≥ 2 H and only its last may be followed by C, and in a
  valid v1 string every H is followed by C, so no valid string is ambiguous.

Every syntax or range error raises :class:`~ionic_usd.errors.GrammarError` naming the 1-based
module with a caret under the token; nothing else escapes the parsers. The parsed values keep
the offsets of their tokens (excluded from equality) so the generator can point at a radius
that reaches the column axis — a check only it can make, since it knows $d.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import ClassVar

from ionic_usd.checks import check_fields
from ionic_usd.errors import GrammarError, ParameterError
from ionic_usd.grammar.lexer import Token, split_top_level, token_number, tokenize

__all__ = [
    "TorusFloor",
    "TorusModule",
    "TorusBase",
    "ControlPoint",
    "BezierModule",
    "BezierBase",
    "BaseGrammar",
    "parse_base_v1",
    "parse_base_v2",
    "parse_base_grammar",
    "detect_base_version",
]

V1 = "base v1"
V2 = "base v2"

Span = tuple[int, int]  # (offset, length) of a token in the source
_NOWHERE: Span = (0, 0)


def _fmt(x: float) -> str:
    """Shortest text that reads back to the same float (``repr`` without a trailing .0)."""
    s = repr(float(x))
    return s[:-2] if s.endswith(".0") else s


@dataclass(frozen=True)
class TorusFloor:
    """A v1 floor: an elliptic arc from (r_bottom, 0) to (r_top, height), revolved.

    ``curvature`` 1 bulges outward (torus), −1 inward (scotia / cavetto). ``r_*_at`` are the
    (offset, length) of the radius tokens in the parsed source (not compared).
    """

    r_bottom: float
    r_top: float
    height: float
    curvature: int
    r_bottom_at: Span = field(default=_NOWHERE, compare=False, repr=False)
    r_top_at: Span = field(default=_NOWHERE, compare=False, repr=False)

    def __post_init__(self) -> None:
        check_fields(
            self,
            context="base floor",
            skip=("curvature", "r_bottom_at", "r_top_at"),
            non_negative=("height",),
        )
        if self.curvature not in (1, -1):
            raise ParameterError("curvature", self.curvature, "1 or -1", context="base floor")
        object.__setattr__(self, "curvature", int(self.curvature))


@dataclass(frozen=True)
class TorusModule:
    """A v1 module: ≥ 1 floors, each starting at the previous one's top radius."""

    floors: tuple[TorusFloor, ...]

    def __post_init__(self) -> None:
        object.__setattr__(self, "floors", tuple(self.floors))
        if not self.floors:
            raise ParameterError("floors", (), "at least one floor", context="base module")
        for a, b in zip(self.floors[:-1], self.floors[1:], strict=True):
            if a.r_top != b.r_bottom:
                raise ParameterError(
                    "r_bottom",
                    b.r_bottom,
                    f"the previous floor's r_top {a.r_top}",
                    context="base module",
                )

    @property
    def height(self) -> float:
        return float(sum(f.height for f in self.floors))

    def to_string(self) -> str:
        parts = [f"R{_fmt(self.floors[0].r_bottom)}"]
        for f in self.floors:
            parts.append(f"H{_fmt(f.height)} C{f.curvature} R{_fmt(f.r_top)}")
        return " ".join(parts)


@dataclass(frozen=True)
class ControlPoint:
    """A v2 Bézier control point: ``r`` outward from radius $d, ``h`` up from the module's
    bottom."""

    r: float
    h: float
    r_at: Span = field(default=_NOWHERE, compare=False, repr=False)
    h_at: Span = field(default=_NOWHERE, compare=False, repr=False)

    def __post_init__(self) -> None:
        check_fields(self, context="base control point", skip=("r_at", "h_at"), non_negative=("h",))


@dataclass(frozen=True)
class BezierModule:
    """A v2 module: one Bézier floor of ≥ 2 control points; ``continuous`` is the C1 flag."""

    points: tuple[ControlPoint, ...]
    continuous: bool = False

    def __post_init__(self) -> None:
        object.__setattr__(self, "points", tuple(self.points))
        if len(self.points) < 2:
            raise ParameterError(
                "points", len(self.points), "at least 2 control points", context="base module"
            )

    @property
    def height(self) -> float:
        """Height of the module: the last control point's h (the next module starts there)."""
        return float(self.points[-1].h)

    def to_string(self) -> str:
        s = " ".join(f"R{_fmt(p.r)} H{_fmt(p.h)}" for p in self.points)
        return s + (" C1" if self.continuous else "")


class _ParsedBase:
    """What both parsed base grammars share: a non-empty module tuple, height, text form."""

    modules: tuple
    source: str
    version: ClassVar[int]

    def __post_init__(self) -> None:
        object.__setattr__(self, "modules", tuple(self.modules))
        if not self.modules:
            raise ParameterError("modules", (), "at least one module", context="base grammar")

    @property
    def height(self) -> float:
        return float(sum(m.height for m in self.modules))

    def to_string(self) -> str:
        """Canonical letter form; parses back to an equal value."""
        return ", ".join(m.to_string() for m in self.modules)

    def located(self) -> TorusBase | BezierBase:
        """This grammar with token offsets: itself if parsed from text, else re-parsed."""
        if self.source:
            return self  # type: ignore[return-value]  # (only the two subclasses exist)
        return (parse_base_v1 if self.version == 1 else parse_base_v2)(self.to_string())


@dataclass(frozen=True)
class TorusBase(_ParsedBase):
    """A parsed v1 (tori) base grammar. ``source`` is the parsed text (not compared)."""

    modules: tuple[TorusModule, ...]
    source: str = field(default="", compare=False, repr=False)

    version: ClassVar[int] = 1
    grammar_name = V1


@dataclass(frozen=True)
class BezierBase(_ParsedBase):
    """A parsed v2 (Bézier) base grammar. ``source`` is the parsed text (not compared)."""

    modules: tuple[BezierModule, ...]
    source: str = field(default="", compare=False, repr=False)

    version: ClassVar[int] = 2
    grammar_name = V2


BaseGrammar = TorusBase | BezierBase


# -- shared scanning ------------------------------------------------------------------------
def _is_functional(toks: list[Token]) -> bool:
    """The ``M(…)`` form: any parenthesis, or a leading ``M``."""
    return any(t.kind == "(" for t in toks) or (
        bool(toks) and toks[0].kind == "item" and toks[0].letter == "M"
    )


def _split(source: str, grammar: str) -> tuple[bool, list[tuple[list[Token], int]]]:
    """Tokenize, split into modules, and tell whether the functional ``M(…)`` form is used."""
    toks = tokenize(source, grammar=grammar)
    if not toks:
        raise GrammarError(
            "empty grammar: expected at least one module", source, 0, grammar=grammar
        )
    functional = _is_functional(toks)
    parts = split_top_level(toks)
    for k, (part, start) in enumerate(parts, 1):
        if not part:
            # point at the comma that closes the empty module (the opening one if trailing)
            at = parts[k][1] if k < len(parts) else start
            raise GrammarError(
                "empty module (two commas or a trailing comma)",
                source,
                at,
                module=k,
                grammar=grammar,
            )
    return functional, parts


def _call_args(part: list[Token], source: str, k: int, grammar: str) -> list[Token]:
    """Argument tokens of one ``M(a, b, …)`` module (commas inside are separators)."""
    head = part[0]
    if head.kind != "item" or head.letter != "M" or head.text != "":
        raise GrammarError(
            f"expected 'M(' to start module {k}, found {head.raw!r}",
            source,
            head.offset,
            length=head.length,
            module=k,
            grammar=grammar,
        )
    if len(part) < 2 or part[1].kind != "(":
        at = part[1] if len(part) > 1 else head
        raise GrammarError(
            "expected '(' after M", source, at.offset, length=at.length, module=k, grammar=grammar
        )
    if part[-1].kind != ")":
        last = part[-1]
        raise GrammarError(
            "missing ')' at the end of the module",
            source,
            last.offset + last.length,
            module=k,
            grammar=grammar,
        )
    inner = part[2:-1]
    args: list[Token] = []
    expect_value = True
    for t in inner:
        if expect_value:
            if t.kind != "item":
                raise GrammarError(
                    f"missing value before {t.kind!r}", source, t.offset, module=k, grammar=grammar
                )
            if t.letter:
                raise GrammarError(
                    f"unknown token {source[t.offset : t.offset + t.length]!r} "
                    "(the M(...) form takes bare numbers)",
                    source,
                    t.offset,
                    length=t.length,
                    module=k,
                    grammar=grammar,
                )
            args.append(t)
        elif t.kind != ",":
            raise GrammarError(
                f"expected ',' between values, found {source[t.offset : t.offset + t.length]!r}",
                source,
                t.offset,
                length=t.length,
                module=k,
                grammar=grammar,
            )
        expect_value = not expect_value
    if expect_value:
        at = part[-1]
        raise GrammarError("missing value before ')'", source, at.offset, module=k, grammar=grammar)
    return args


def _expect(
    tok: Token | None, letter: str, source: str, k: int, grammar: str, end: int, what: str
) -> Token:
    if tok is None:
        raise GrammarError(
            f"module ends early: expected {letter}<{what}>", source, end, module=k, grammar=grammar
        )
    if tok.kind != "item":
        raise GrammarError(
            f"expected {letter}<{what}>, found {tok.kind!r}",
            source,
            tok.offset,
            module=k,
            grammar=grammar,
        )
    if tok.letter != letter:
        shown = source[tok.offset : tok.offset + tok.length]
        known = "R, H or C"
        kind = "unknown token" if tok.letter not in ("R", "H", "C") else "unexpected token"
        raise GrammarError(
            f"{kind} {shown!r}: expected {letter}<{what}> (tokens are {known})",
            source,
            tok.offset,
            length=tok.length,
            module=k,
            grammar=grammar,
        )
    return tok


def _span(t: Token) -> Span:
    return (t.offset, t.length)


def _height(t: Token, source: str, k: int, grammar: str) -> float:
    h = token_number(t, source, grammar=grammar, module=k, what="height")
    if h < 0:
        raise GrammarError(
            f"negative height {t.text}",
            source,
            t.text_offset,
            length=len(t.text),
            module=k,
            grammar=grammar,
        )
    return h


def _curvature(t: Token, source: str, k: int) -> int:
    c = token_number(t, source, grammar=V1, module=k, what="curvature")
    if c not in (1.0, -1.0):
        raise GrammarError(
            f"curvature must be 1 (convex) or -1 (concave), got {t.text}",
            source,
            t.text_offset,
            length=len(t.text),
            module=k,
            grammar=V1,
        )
    return int(c)


def _flag(t: Token, source: str, k: int) -> bool:
    c = token_number(t, source, grammar=V2, module=k, what="continuity flag")
    if c != 1.0:
        raise GrammarError(
            f"the continuity flag can only be 1 (C1), got {t.text}",
            source,
            t.text_offset,
            length=len(t.text),
            module=k,
            grammar=V2,
        )
    return True


def _end_of(part: list[Token]) -> int:
    return part[-1].offset + part[-1].length


def _modules(
    source: str, grammar: str
) -> Iterator[tuple[int, list[Token], int, list[Token] | None]]:
    """Each module of ``source``: (1-based number, its tokens, the offset where it ends, its
    call arguments in the functional ``M(…)`` form or None in the letter form)."""
    functional, parts = _split(source, grammar)
    for k, (part, _start) in enumerate(parts, 1):
        args = _call_args(part, source, k, grammar) if functional else None
        yield k, part, _end_of(part), args


# -- version 1 --------------------------------------------------------------------------------
def _v1_floors(vals: list[tuple[str, Token]], source: str, k: int, end: int) -> TorusModule:
    """Floors from a flat sequence of (role, token), roles cycling r, h, c, r, h, c, r."""
    rb_tok = vals[0][1]
    rb = token_number(rb_tok, source, grammar=V1, module=k, what="radius")
    if len(vals) < 4:
        raise GrammarError(
            "a module needs at least one floor: R<r> H<h> C<c> R<r>",
            source,
            rb_tok.offset,
            length=end - rb_tok.offset,
            module=k,
            grammar=V1,
        )
    floors = []
    i = 1
    while i < len(vals):
        if i + 2 >= len(vals):
            role = ("height", "curvature", "radius")[len(vals) - i]
            raise GrammarError(
                f"module ends early: expected a {role}", source, end, module=k, grammar=V1
            )
        h = _height(vals[i][1], source, k, V1)
        c = _curvature(vals[i + 1][1], source, k)
        rt_tok = vals[i + 2][1]
        rt = token_number(rt_tok, source, grammar=V1, module=k, what="radius")
        floors.append(TorusFloor(rb, rt, h, c, _span(rb_tok), _span(rt_tok)))
        rb, rb_tok = rt, rt_tok
        i += 3
    return TorusModule(tuple(floors))


def parse_base_v1(source: str) -> TorusBase:
    """Parse a version-1 (tori) base grammar, letter or functional form.

    Raises
    ------
    GrammarError
        With the module number and a caret under the offending token.
    """
    modules = []
    for k, part, end, args in _modules(source, V1):
        if args is not None:
            roles = ["r", "h", "c"]
            vals = [(roles[i % 3], t) for i, t in enumerate(args)]
            if len(args) % 3 != 1 or len(args) < 4:
                if len(args) < 4:
                    raise GrammarError(
                        "a module needs at least one floor: M(r1, h1, c1, r2)",
                        source,
                        part[0].offset,
                        length=end - part[0].offset,
                        module=k,
                        grammar=V1,
                    )
                msg = (
                    f"{len(args)} values: a v1 module takes 3k + 1 values (r1, h1, c1, r2, …, rk+1)"
                )
                raise GrammarError(
                    msg, source, args[-1].offset, length=args[-1].length, module=k, grammar=V1
                )
        else:
            vals = []
            want = ("R", "H", "C")
            what = ("radius", "height", "curvature")
            for i, t in enumerate(part):
                j = i % 3
                _expect(t, want[j], source, k, V1, end, what[j])
                vals.append((want[j], t))
            if vals and vals[-1][0] != "R":
                nxt = len(vals) % 3
                raise GrammarError(
                    f"module ends early: expected {want[nxt]}<{what[nxt]}>",
                    source,
                    end,
                    module=k,
                    grammar=V1,
                )
        modules.append(_v1_floors(vals, source, k, end))
    return TorusBase(tuple(modules), source)


# -- version 2 --------------------------------------------------------------------------------
def parse_base_v2(source: str) -> BezierBase:
    """Parse a version-2 (Bézier) base grammar, letter or functional form.

    Raises
    ------
    GrammarError
        With the module number and a caret under the offending token.
    """
    modules = []
    for k, part, end, args in _modules(source, V2):
        flag_tok: Token | None = None
        pairs: list[tuple[Token, Token]] = []
        if args is not None:
            if len(args) % 2 == 1:
                flag_tok = args[-1]
                args = args[:-1]
            pairs = [(args[i], args[i + 1]) for i in range(0, len(args), 2)]
        else:
            toks = list(part)
            if toks and toks[-1].kind == "item" and toks[-1].letter == "C":
                flag_tok = toks.pop()
            for i, t in enumerate(toks):
                if t.kind == "item" and t.letter == "C":
                    raise GrammarError(
                        "the continuity flag C must be the last item of a v2 "
                        "module (C after every H means v1: pass version=1?)",
                        source,
                        t.offset,
                        length=t.length,
                        module=k,
                        grammar=V2,
                    )
                want, what = ("R", "radius") if i % 2 == 0 else ("H", "height")
                _expect(t, want, source, k, V2, end, what)
            if len(toks) % 2 == 1:
                at = flag_tok.offset if flag_tok is not None else end
                raise GrammarError(
                    "module ends early: expected H<height>", source, at, module=k, grammar=V2
                )
            pairs = [(toks[i], toks[i + 1]) for i in range(0, len(toks), 2)]
        pts = []
        for rt, ht in pairs:
            r = token_number(rt, source, grammar=V2, module=k, what="radius")
            h = _height(ht, source, k, V2)
            pts.append(ControlPoint(r, h, _span(rt), _span(ht)))
        cont = _flag(flag_tok, source, k) if flag_tok is not None else False
        if len(pts) < 2:
            first = pairs[0][0] if pairs else part[0]
            raise GrammarError(
                f"a Bézier module needs at least 2 control points, got {len(pts)}",
                source,
                first.offset,
                length=max(1, end - first.offset),
                module=k,
                grammar=V2,
            )
        modules.append(BezierModule(tuple(pts), cont))
    return BezierBase(tuple(modules), source)


# -- detection --------------------------------------------------------------------------------
def detect_base_version(source: str) -> int:
    """1 or 2 by the rule in the module docstring (never raises on malformed text)."""
    try:
        toks = tokenize(source, grammar="base")
    except GrammarError:
        return 1
    if _is_functional(toks):
        for part, _ in split_top_level(toks):
            args = [t for t in part if t.kind == "item" and t.letter == ""]
            if len(args) < 4 or len(args) % 3 != 1:
                return 2
            for t in args[2::3]:
                if t.text not in ("1", "-1", "+1", "1.0", "-1.0"):
                    return 2
        return 1
    hs = [i for i, t in enumerate(toks) if t.kind == "item" and t.letter == "H"]
    if not hs:
        return 1
    for i in hs:
        nxt = toks[i + 1] if i + 1 < len(toks) else None
        if nxt is None or nxt.kind != "item" or nxt.letter != "C":
            return 2
    return 1


def parse_base_grammar(source: str, version: int | None = None) -> BaseGrammar:
    """Parse a base grammar of either version.

    Parameters
    ----------
    source : grammar text (letter form ``R.. H.. C..`` or functional form ``M(…)``)
    version : 1, 2 or None (detect: see the module docstring)

    Raises
    ------
    GrammarError
        For malformed text (``grammar`` is ``'base v1'`` or ``'base v2'``).
    ParameterError
        For a version other than 1, 2 or None.
    """
    if version is None:
        if not isinstance(source, str):
            raise GrammarError(
                f"expected a string, got {type(source).__name__}", "", 0, grammar="base"
            )
        version = detect_base_version(source)
    if version == 1:
        return parse_base_v1(source)
    if version == 2:
        return parse_base_v2(source)
    raise ParameterError("version", version, "1, 2 or None (detect)", context="base grammar")
