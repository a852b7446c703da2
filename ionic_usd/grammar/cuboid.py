"""The compact text form of temple cuboids, in the functional style of the other grammars.

Grammar (whitespace is free everywhere; cuboids are separated by commas at the top level)::

    cuboids := cuboid ("," cuboid)*
    cuboid  := "C(" x0 "," y0 "," z0 "," x1 "," y1 "," z1 ["," rise] ")"   box / sheared piece
             | "W(" x0 "," y0 "," z0 "," x1 "," y1 "," z1 "," rise ")"    wedge piece

The two corners are the paper's two vertices (minimum and maximum x, y, z, metres, Y up);
``rise`` is the paper's "height difference". With ``C`` it shifts the four vertices at max x
along +y (the paper's rule, :attr:`Incline.SHEAR`: an inclined roof
slab); with ``W`` only the top edge at max x is raised (:attr:`Incline.
WEDGE`: a solid gable half). Examples::

    C(-5.25, 0, -9.65, 5.25, 2.4, 9.65)                      podium die
    C(-5.49, 12.85, -9.9, 0, 13.2, 9.9, 1.22),               left roof slab rising to the ridge
    C(0, 14.07, -9.9, 5.49, 14.42, 9.9, -1.22)               right roof slab falling to the eave

Names: the ``k``-th cuboid (1-based) is named ``cuboid{k}``. Every error is a
:class:`~ionic_usd.errors.GrammarError` with ``grammar='cuboid'``, ``module=k`` and a caret
under the offending token: a missing value, a non-number, an unknown letter, a stray token, a
wrong number of values, a max corner not above the min corner, a wedge turned inside out.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass
from enum import StrEnum

import numpy as np

from ionic_usd.errors import GrammarError, ParameterError
from ionic_usd.grammar.lexer import Token, split_top_level, token_number, tokenize

__all__ = ["Cuboid", "Incline", "parse_cuboids", "format_cuboids", "GRAMMAR"]

GRAMMAR = "cuboid"
_AXES = ("x", "y", "z")


class Incline(StrEnum):
    """How ``rise`` deforms a cuboid (see the module docstring)."""

    SHEAR = "shear"
    WEDGE = "wedge"

    @classmethod
    def parse(cls, value: object, *, context: str = "") -> Incline:
        try:
            return cls(value) if isinstance(value, str) else cls(str(value))
        except ValueError:
            valid = " or ".join(repr(m.value) for m in cls)
            raise ParameterError("incline", value, valid, context=context) from None


def _vec3(name: str, value: object, context: str) -> tuple[float, float, float]:
    try:
        arr = np.asarray(value, dtype=np.float64).reshape(-1)
    except (TypeError, ValueError):
        raise ParameterError(name, value, "three numbers (x, y, z)", context=context) from None
    if arr.size != 3:
        raise ParameterError(name, value, "three numbers (x, y, z)", context=context)
    if not np.all(np.isfinite(arr)):
        raise ParameterError(name, value, "finite numbers", context=context)
    return (float(arr[0]), float(arr[1]), float(arr[2]))


@dataclass(frozen=True)
class Cuboid:
    """An axis-aligned box, optionally inclined across X (a roof piece).

    Parameters
    ----------
    min, max : (3,) float
        Corners with the smallest and largest x, y, z, in metres; ``min < max`` on every axis.
    rise : float
        Height difference (metres, along +y) applied to the vertices at max x; 0 for a box.
    incline : Incline or str
        ``"shear"`` (the paper's rule: the whole max-x face moves) or ``"wedge"`` (only its
        top edge moves). A wedge must keep its max-x face upright: ``max.y + rise > min.y``.
    name : str
        Prim name for authoring.
    """

    min: tuple[float, float, float]
    max: tuple[float, float, float]
    rise: float = 0.0
    incline: Incline = Incline.SHEAR
    name: str = "cuboid"

    def __post_init__(self) -> None:
        ctx = f"cuboid {self.name!r}"
        lo = _vec3("min", self.min, ctx)
        hi = _vec3("max", self.max, ctx)
        for k, axis in enumerate(_AXES):
            if not lo[k] < hi[k]:
                raise ParameterError(f"max.{axis}", hi[k], f"> min.{axis} = {lo[k]!r}", context=ctx)
        try:
            rise = float(self.rise)
        except (TypeError, ValueError):
            raise ParameterError("rise", self.rise, "a number (metres)", context=ctx) from None
        if not math.isfinite(rise):
            raise ParameterError("rise", self.rise, "a finite number (metres)", context=ctx)
        incline = Incline.parse(self.incline, context=ctx)
        if incline is Incline.WEDGE and not hi[1] + rise > lo[1]:
            raise ParameterError(
                "rise",
                rise,
                f"> {lo[1] - hi[1]!r} (a wedge's top edge must stay above its "
                "bottom: max.y + rise > min.y)",
                context=ctx,
            )
        if not isinstance(self.name, str) or not self.name:
            raise ParameterError("name", self.name, "a non-empty string", context=ctx)
        object.__setattr__(self, "min", lo)
        object.__setattr__(self, "max", hi)
        object.__setattr__(self, "rise", rise)
        object.__setattr__(self, "incline", incline)

    @property
    def size(self) -> tuple[float, float, float]:
        """(Δx, Δy, Δz) of the undeformed box."""
        return tuple(b - a for a, b in zip(self.min, self.max, strict=True))  # type: ignore[return-value]

    @property
    def inclined(self) -> bool:
        return self.rise != 0.0

    @property
    def pitch_deg(self) -> float:
        """Slope of the inclined faces, ``atan(rise / Δx)`` in degrees (signed)."""
        return math.degrees(math.atan2(self.rise, self.size[0]))

    def top_at(self, x: float | np.ndarray) -> float | np.ndarray:
        """Height of the top face at ``x`` (linear across the slope)."""
        t = (np.asarray(x, dtype=np.float64) - self.min[0]) / self.size[0]
        return self.max[1] + self.rise * t

    def bottom_at(self, x: float | np.ndarray) -> float | np.ndarray:
        """Height of the bottom face at ``x``."""
        t = (np.asarray(x, dtype=np.float64) - self.min[0]) / self.size[0]
        return self.min[1] + (self.rise * t if self.incline is Incline.SHEAR else 0.0 * t)

    def contains(self, p, *, strict: bool = True, tol: float = 1e-9) -> bool:
        """Whether point ``p`` (3,) is inside the (deformed) solid; ``strict`` excludes the
        boundary within ``tol``."""
        x, y, z = (float(v) for v in p)
        e = tol if strict else -tol
        if not (self.min[0] + e < x < self.max[0] - e and self.min[2] + e < z < self.max[2] - e):
            return False
        return float(self.bottom_at(x)) + e < y < float(self.top_at(x)) - e

    def translated(self, offset) -> Cuboid:
        d = _vec3("offset", offset, f"cuboid {self.name!r}")
        (x0, y0, z0), (x1, y1, z1) = self.min, self.max
        return Cuboid(
            (x0 + d[0], y0 + d[1], z0 + d[2]),
            (x1 + d[0], y1 + d[1], z1 + d[2]),
            self.rise,
            self.incline,
            self.name,
        )


_KINDS = {"C": Incline.SHEAR, "W": Incline.WEDGE}
_NAMES = ("x0", "y0", "z0", "x1", "y1", "z1", "rise")


def _err(msg: str, source: str, tok_or_offset: Token | int, k: int, length: int = 1):
    if isinstance(tok_or_offset, Token):
        return GrammarError(
            msg,
            source,
            tok_or_offset.offset,
            length=tok_or_offset.length,
            module=k,
            grammar=GRAMMAR,
        )
    return GrammarError(msg, source, tok_or_offset, length=length, module=k, grammar=GRAMMAR)


def _typed(t: Token, source: str) -> str:
    return source[t.offset : t.offset + t.length] if t.kind == "item" else t.kind


def _args(part: list[Token], source: str, k: int) -> tuple[Token, list[Token], Token]:
    """Head, argument tokens and closing parenthesis of one ``C(…)`` / ``W(…)``."""
    head = part[0]
    if head.kind != "item" or head.letter not in _KINDS:
        raise _err(
            f"expected 'C(' or 'W(' to start cuboid {k}, found {_typed(head, source)!r}",
            source,
            head,
            k,
        )
    if head.text != "":
        raise _err(
            f"expected '(' right after {head.letter}, found {head.text!r}",
            source,
            head.text_offset,
            k,
            len(head.text),
        )
    if len(part) < 2 or part[1].kind != "(":
        at = part[1] if len(part) > 1 else None
        if at is None:
            raise _err(f"expected '(' after {head.letter}", source, head.offset + head.length, k)
        raise _err(f"expected '(' after {head.letter}, found {_typed(at, source)!r}", source, at, k)
    close = None
    for i, t in enumerate(part[2:], 2):
        if t.kind == "(":
            raise _err("unexpected '(' inside a cuboid", source, t, k)
        if t.kind == ")":
            close = i
            break
    if close is None:
        last = part[-1]
        raise _err("missing ')' at the end of the cuboid", source, last.offset + last.length, k)
    if close != len(part) - 1:
        extra = part[close + 1]
        raise _err(
            f"unexpected {_typed(extra, source)!r} after the cuboid's ')' (cuboids are "
            "separated by commas)",
            source,
            extra,
            k,
        )
    args: list[Token] = []
    expect_value = True
    for t in part[2:close]:
        if expect_value:
            if t.kind != "item":
                raise _err(f"missing {_NAMES[min(len(args), 6)]} before {t.kind!r}", source, t, k)
            if t.letter:
                raise _err(
                    f"{_NAMES[min(len(args), 6)]} {_typed(t, source)!r} is not a number",
                    source,
                    t,
                    k,
                )
            args.append(t)
        elif t.kind != ",":
            raise _err(f"expected ',' before {_typed(t, source)!r}", source, t, k)
        expect_value = not expect_value
    if args and expect_value:
        raise _err(f"missing {_NAMES[min(len(args), 6)]} after ','", source, part[close], k)
    return head, args, part[close]


def _cuboid(part: list[Token], source: str, k: int) -> Cuboid:
    head, args, close = _args(part, source, k)
    kind = _KINDS[head.letter]
    want = "6 or 7" if kind is Incline.SHEAR else "7"
    if len(args) < 6 or (kind is Incline.WEDGE and len(args) == 6):
        missing = _NAMES[len(args)]
        raise _err(
            f"missing {missing}: {head.letter}(…) takes {want} values "
            f"(x0, y0, z0, x1, y1, z1{', rise' if kind is Incline.WEDGE else '[, rise]'})"
            f", found {len(args)}",
            source,
            close,
            k,
        )
    if len(args) > 7:
        raise _err(
            f"too many values: {head.letter}(…) takes {want}, found {len(args)}", source, args[7], k
        )
    vals = [
        token_number(t, source, grammar=GRAMMAR, module=k, what=_NAMES[i])
        for i, t in enumerate(args)
    ]
    for a in range(3):
        if not vals[a] < vals[a + 3]:
            t = args[a + 3]
            raise _err(
                f"{_NAMES[a + 3]} = {t.text} must be greater than {_NAMES[a]} = {args[a].text}",
                source,
                t,
                k,
            )
    rise = vals[6] if len(vals) == 7 else 0.0
    try:
        return Cuboid(
            (vals[0], vals[1], vals[2]), (vals[3], vals[4], vals[5]), rise, kind, name=f"cuboid{k}"
        )
    except ParameterError as exc:  # the wedge turned inside out: point at its rise
        raise _err(str(exc), source, args[6], k) from None


def parse_cuboids(source: str) -> tuple[Cuboid, ...]:
    """Parse the compact text form.

    Parameters
    ----------
    source : str
        ``C(x0, y0, z0, x1, y1, z1[, rise])`` / ``W(…, rise)`` items separated by commas.

    Returns
    -------
    tuple of Cuboid, named ``cuboid1``, ``cuboid2``, …

    Raises
    ------
    GrammarError
        For every malformed input (and only that).
    """
    toks = tokenize(source, grammar=GRAMMAR)
    if not toks:
        raise GrammarError("no cuboids (empty text)", source, 0, grammar=GRAMMAR)
    out = []
    for k, (part, start) in enumerate(split_top_level(toks), 1):
        if not part:
            raise _err("empty cuboid (two commas or a trailing comma)", source, start, k)
        out.append(_cuboid(part, source, k))
    return tuple(out)


def format_cuboids(cuboids: Iterable[Cuboid], *, sep: str = ",\n") -> str:
    """The text form of cuboids (names are not kept); ``parse_cuboids`` reads it back exactly."""
    items = []
    for c in cuboids:
        vals = [*c.min, *c.max]
        letter = "W" if c.incline is Incline.WEDGE else "C"
        if c.rise != 0.0 or letter == "W":
            vals.append(c.rise)
        items.append(f"{letter}({', '.join(repr(float(v)) for v in vals)})")
    return sep.join(items)
