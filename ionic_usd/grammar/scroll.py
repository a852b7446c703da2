"""The scroll-body (bolster) ring grammar (paper Table 5; SPEC §3).

A string is a comma-separated list of modules ``R<r> P<p>``, one ring each: ``r ∈ [0, 2]`` is the
ring radius as a fraction of the volute's total radius, ``p ∈ [0, 1]`` its position from the
front (0) to the rear (1) volute; positions must not decrease (equal positions make a step).
Whitespace of any kind (or none) may separate tokens and commas; the symbols are
case-insensitive; numbers are decimal, optionally signed, with an optional exponent.

Every syntax or range error raises :class:`~ionic_usd.errors.GrammarError` (``grammar='scroll'``)
naming the 1-based module, with a caret under the offending token; nothing else escapes
:func:`parse_scroll`. Tokens come from the grammars' shared lexer (:mod:`ionic_usd.grammar.lexer`).

Presets S1 and S2 (the paper's examples) ship in ``ionic_usd/data/scroll_presets.toml``.
"""

from __future__ import annotations

import tomllib
from dataclasses import dataclass, field
from functools import lru_cache
from importlib import resources

from ionic_usd.errors import GrammarError, ParameterError
from ionic_usd.grammar.lexer import Token, split_top_level, token_number, tokenize

__all__ = [
    "ScrollRing",
    "ScrollGrammar",
    "parse_scroll",
    "format_scroll",
    "scroll_preset_names",
    "scroll_preset_text",
    "load_scroll_preset",
    "resolve_scroll",
    "RADIUS_RANGE",
    "POSITION_RANGE",
]

GRAMMAR = "scroll"
RADIUS_RANGE = (0.0, 2.0)
POSITION_RANGE = (0.0, 1.0)


@dataclass(frozen=True)
class ScrollRing:
    """One ring of the scroll body.

    ``radius``: fraction of the volute's total radius, [0, 2]; ``position``: 0 = front volute,
    1 = rear volute. ``span`` is the (offset, length) of the module in the source (not
    compared).
    """

    radius: float
    position: float
    span: tuple[int, int] = field(default=(0, 0), compare=False, repr=False)


@dataclass(frozen=True)
class ScrollGrammar:
    """A parsed scroll string: rings ordered front to rear."""

    rings: tuple[ScrollRing, ...]
    source: str = field(default="", compare=False)

    @property
    def radii(self) -> tuple[float, ...]:
        return tuple(r.radius for r in self.rings)

    @property
    def positions(self) -> tuple[float, ...]:
        return tuple(r.position for r in self.rings)

    def __str__(self) -> str:
        return format_scroll(self)


def _fmt(x: float) -> str:
    s = repr(float(x))
    return s[:-2] if s.endswith(".0") else s


def format_scroll(g: ScrollGrammar | list[ScrollRing] | tuple[ScrollRing, ...]) -> str:
    """The canonical string of a scroll grammar (parses back to equal rings)."""
    rings = g.rings if isinstance(g, ScrollGrammar) else tuple(g)
    return ", ".join(f"R{_fmt(r.radius)} P{_fmt(r.position)}" for r in rings)


def parse_scroll(source: str) -> ScrollGrammar:
    """Parse ``R<r> P<p>, R<r> P<p>, …`` into rings.

    Raises
    ------
    GrammarError
        Unknown token, missing value, non-number, r ∉ [0, 2], p ∉ [0, 1], a module without R
        or P, an empty module or decreasing positions (the caret points at the token).
    """
    if not isinstance(source, str):
        raise GrammarError(
            f"expected a string, got {type(source).__name__}", "", 0, grammar=GRAMMAR
        )
    toks = tokenize(source, grammar=GRAMMAR)
    if not toks:
        raise GrammarError(
            "empty scroll grammar: expected rings like 'R0.7 P0.05, R0.7 P0.95'",
            source,
            0,
            length=max(1, len(source)),
            grammar=GRAMMAR,
        )
    modules = split_top_level(toks)  # runs of items between commas
    rings: list[ScrollRing] = []
    for k, (words, opening) in enumerate(modules):
        mod = k + 1
        if not words:
            # point at the comma that closes the empty module (the opening one if trailing)
            at = modules[k + 1][1] if k + 1 < len(modules) else opening
            raise GrammarError(
                f"empty module {mod}: expected 'R<r> P<p>'", source, at, module=mod, grammar=GRAMMAR
            )
        values = _module_values(words, source, mod)
        if "P" not in values:
            last = words[-1]
            raise GrammarError(
                "missing position P<p> after the radius",
                source,
                last.offset + last.length,
                module=mod,
                grammar=GRAMMAR,
            )
        r, p = values["R"][0], values["P"][0]
        if rings and p < rings[-1].position:
            pt = values["P"][1]
            raise GrammarError(
                f"position p = {_fmt(p)} is below the previous ring's "
                f"{_fmt(rings[-1].position)}: positions must not decrease",
                source,
                pt.text_offset,
                length=len(pt.text),
                module=mod,
                grammar=GRAMMAR,
            )
        start = words[0].offset
        end = words[-1].offset + words[-1].length
        rings.append(ScrollRing(r, p, (start, end - start)))
    return ScrollGrammar(tuple(rings), source)


def _module_values(words: list[Token], source: str, mod: int) -> dict[str, tuple[float, Token]]:
    """The R and P values of one module (each once, R first, in range), with their tokens."""
    values: dict[str, tuple[float, Token]] = {}
    for t in words:
        sym = t.letter if t.kind == "item" else t.kind

        def error(message: str, at: int, length: int, t=t) -> GrammarError:
            return GrammarError(message, source, at, length=length, module=mod, grammar=GRAMMAR)

        if sym not in ("R", "P"):
            text = source[t.offset : t.offset + t.length]
            raise error(
                f"unknown token {text!r}: expected R<radius> or P<position>", t.offset, t.length
            )
        if sym in values:
            raise error(
                f"second {sym} in one module (separate rings with commas)", t.offset, t.length
            )
        if sym == "P" and "R" not in values:
            raise error("P before R: a ring is written 'R<r> P<p>'", t.offset, t.length)
        what = "radius" if sym == "R" else "position"
        val = token_number(t, source, grammar=GRAMMAR, module=mod, what=what)
        lo, hi = RADIUS_RANGE if sym == "R" else POSITION_RANGE
        if not lo <= val <= hi:
            raise error(
                f"{what} {sym.lower()} = {_fmt(val)} is outside [{_fmt(lo)}, {_fmt(hi)}]",
                t.text_offset,
                len(t.text),
            )
        values[sym] = (val, t)
    return values


# -- presets -----------------------------------------------------------------------------
@lru_cache(maxsize=1)
def _presets() -> dict[str, dict]:
    path = resources.files("ionic_usd").joinpath("data", "scroll_presets.toml")
    with path.open("rb") as fh:
        data = tomllib.load(fh)
    return {k.upper(): v for k, v in data.items()}


def scroll_preset_names() -> tuple[str, ...]:
    """Names of the shipped scroll presets (e.g. ``('S1', 'S2')``)."""
    return tuple(sorted(_presets()))


def scroll_preset_text(name: str) -> str:
    """The grammar string of a preset (case-insensitive name)."""
    key = name.upper() if isinstance(name, str) else name
    if key not in _presets():
        raise ParameterError("scroll preset", name, f"one of {', '.join(scroll_preset_names())}")
    return _presets()[key]["grammar"]


def load_scroll_preset(name: str) -> ScrollGrammar:
    """Parse a shipped preset. Unknown names raise ParameterError listing the valid ones."""
    return parse_scroll(scroll_preset_text(name))


def resolve_scroll(spec: str | ScrollGrammar) -> ScrollGrammar:
    """A preset name (``'S1'``), a grammar string or an already parsed grammar → grammar."""
    if isinstance(spec, ScrollGrammar):
        return spec
    if isinstance(spec, str) and spec.strip().upper() in _presets():
        return load_scroll_preset(spec.strip())
    return parse_scroll(spec)
