"""Text grammars → frozen dataclasses, with errors that point at the offending token."""

from ionic_usd.grammar.base import (
    BaseGrammar,
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
)
from ionic_usd.grammar.lexer import Token, split_top_level, token_number, tokenize

__all__ = [
    "BaseGrammar",
    "BezierBase",
    "BezierModule",
    "ControlPoint",
    "Token",
    "TorusBase",
    "TorusFloor",
    "TorusModule",
    "detect_base_version",
    "parse_base_grammar",
    "parse_base_v1",
    "parse_base_v2",
    "split_top_level",
    "token_number",
    "tokenize",
]
