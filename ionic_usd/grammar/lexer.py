"""A small tokenizer shared by the text grammars (base `R H C`, scroll `R P`, cuboids).

The grammars are lists of *items* — a letter followed by a number, ``R0.12`` — or of
function calls with bare numbers, ``M(1, 0, 2)``; items are grouped into modules by commas.
Whitespace is free everywhere (``R0.074,R0.074`` and ``R0.1H0.2`` both tokenize).

Every token keeps its character offset and length in the source so that a parser can raise a
:class:`~ionic_usd.errors.GrammarError` with a caret under it.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

from ionic_usd.errors import GrammarError

__all__ = ["Token", "tokenize", "split_top_level", "token_number", "NUMBER_RE"]

# a decimal number as written in the grammars; inf/nan are recognised so that they can be
# rejected with a pointed "non-finite" error instead of a confusing "unknown token"
NUMBER_RE = re.compile(r"[+-]?(?:(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][+-]?\d+)?|(?i:infinity|inf|nan))")
_PUNCT = ",()"
_STOP = re.compile(r"[\s,()]")


@dataclass(frozen=True)
class Token:
    """One lexical token.

    ``kind`` is ``"item"`` (an optional letter and a number text), ``","``, ``"("`` or ``")"``.
    For items, ``letter`` is the upper-cased prefix letter (``""`` for a bare number) and
    ``text`` the number as written (``""`` when the letter has no value). ``offset`` and
    ``length`` locate the whole token in the source; ``text_offset`` locates ``text``.
    """

    kind: str
    letter: str
    text: str
    offset: int
    length: int
    text_offset: int

    @property
    def raw(self) -> str:
        """The token as written (letter as typed is not kept; upper-case is shown)."""
        return f"{self.letter}{self.text}" if self.kind == "item" else self.kind


def tokenize(source: str, *, grammar: str = "grammar") -> list[Token]:
    """Split ``source`` into tokens.

    A letter is one ASCII letter; the number after it runs as far as :data:`NUMBER_RE`
    matches (so ``H0.1C1`` is two items); a letter followed by anything else that is not
    whitespace or punctuation takes that run as its (bad) number text. Characters that are
    neither whitespace, punctuation, letters nor a number start an item with an empty
    letter whose ``text`` is the run up to the next whitespace or punctuation (the parser
    then reports it as "not a number"). Every character is accepted here and judged by the
    parser, which knows which letters and forms are valid.

    Raises
    ------
    GrammarError
        Only when ``source`` is not a string.
    """
    if not isinstance(source, str):
        raise GrammarError(
            f"expected a string, got {type(source).__name__}", "", 0, grammar=grammar
        )
    out: list[Token] = []
    i, n = 0, len(source)
    while i < n:
        ch = source[i]
        if ch.isspace():
            i += 1
            continue
        if ch in _PUNCT:
            out.append(Token(ch, "", "", i, 1, i))
            i += 1
            continue
        start = i
        letter = ""
        if ch.isascii() and ch.isalpha():
            m = NUMBER_RE.match(source, i)
            # "inf"/"nan" as a bare word is a number; otherwise the letter is a prefix
            if m is None or not m.group(0)[:1].isalpha():
                letter = ch.upper()
                i += 1
        m = NUMBER_RE.match(source, i)
        if m is not None:
            j = m.end()
            # a number glued to garbage ("0.1.2", "0.1#") is one bad number, not two tokens
            if (
                j < n
                and not _STOP.match(source, j)
                and not (source[j].isascii() and source[j].isalpha())
            ):
                j = _run_end(source, j)
            text_start, i = i, j
        elif letter:
            text_start = i
            # the value is missing only when a separator follows; "Hx" is a bad number "x"
            if i < n and not _STOP.match(source, i):
                i = _run_end(source, i)
        else:
            text_start, i = i, _run_end(source, i)
        out.append(Token("item", letter, source[text_start:i], start, i - start, text_start))
    return out


def _run_end(source: str, i: int) -> int:
    m = _STOP.search(source, i)
    end = m.start() if m else len(source)
    return max(end, i + 1)


def split_top_level(tokens: list[Token]) -> list[tuple[list[Token], int]]:
    """Split tokens at commas outside parentheses.

    Returns
    -------
    list of (tokens of one part, offset where the part starts), one per comma-separated part
    (an empty part — ``",,"`` or a trailing comma — comes back as an empty list).
    """
    parts: list[tuple[list[Token], int]] = []
    cur: list[Token] = []
    start = 0
    depth = 0
    for t in tokens:
        if t.kind == "(":
            depth += 1
        elif t.kind == ")":
            depth = max(0, depth - 1)
        if t.kind == "," and depth == 0:
            parts.append((cur, start))
            cur, start = [], t.offset
            continue
        cur.append(t)
    parts.append((cur, start))
    return parts


def token_number(
    tok: Token, source: str, *, grammar: str, module: int | None, what: str = "value"
) -> float:
    """The finite float value of an item token, or a pointed GrammarError.

    Parameters
    ----------
    what : what the value means, for the message (``"radius"``, ``"height"`` …)
    """
    if tok.kind != "item":
        raise GrammarError(
            f"expected a {what}, found {tok.kind!r}",
            source,
            tok.offset,
            module=module,
            grammar=grammar,
        )
    if tok.text == "":
        raise GrammarError(
            f"missing {what} after {tok.letter!r}",
            source,
            tok.offset,
            length=tok.length,
            module=module,
            grammar=grammar,
        )
    if NUMBER_RE.fullmatch(tok.text) is None:
        raise GrammarError(
            f"{what} {tok.text!r} is not a number",
            source,
            tok.text_offset,
            length=len(tok.text),
            module=module,
            grammar=grammar,
        )
    value = float(tok.text)
    if not math.isfinite(value):
        raise GrammarError(
            f"{what} {tok.text!r} is not finite",
            source,
            tok.text_offset,
            length=len(tok.text),
            module=module,
            grammar=grammar,
        )
    return value
