"""Validation of numeric parameters: the one loop behind every ``*Params.__post_init__``.

>>> from dataclasses import dataclass
>>> @dataclass(frozen=True)
... class Box:
...     width: float = 1.0
...     cells: int = 4
...     def __post_init__(self):
...         check_fields(self, context="box", integers={"cells": 1}, positive=("width",))
>>> Box(2, 3.0).cells                      # an integer-valued float becomes an int
3
>>> Box(width=-1)
Traceback (most recent call last):
...
ionic_usd.errors.ParameterError: box: width = -1 is invalid; expected a finite number > 0
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Collection, Mapping
from typing import Any

from ionic_usd.errors import ParameterError

__all__ = [
    "SEED_RANGE",
    "TEXTURE_SIZES",
    "check_fields",
    "check_number",
    "check_stone_options",
]

#: the one schema of the stone flags every command shares (``--texture-size``, ``--seed``), and
#: of the same options in the Python API: (low, high)
TEXTURE_SIZES = (16, 8192)
SEED_RANGE = (0, 2**63 - 1)


def check_stone_options(texture_size: object, seed: object) -> None:
    """``texture_size`` a power of two in :data:`TEXTURE_SIZES`, ``seed`` an integer in
    :data:`SEED_RANGE` (ParameterError naming the flag otherwise)."""
    ts = (
        texture_size if isinstance(texture_size, int) and not isinstance(texture_size, bool) else -1
    )
    if not TEXTURE_SIZES[0] <= ts <= TEXTURE_SIZES[1] or ts & (ts - 1):
        raise ParameterError("--texture-size", texture_size, "a power of two in [16, 8192]")
    sd = seed if isinstance(seed, int) and not isinstance(seed, bool) else -1
    if not SEED_RANGE[0] <= sd <= SEED_RANGE[1]:
        raise ParameterError("--seed", seed, "an integer in [0, 2**63 - 1]")


def check_number(
    name: str,
    value: object,
    *,
    context: str = "",
    integer: bool = False,
    minimum: float | None = None,
    positive: bool = False,
) -> float | int:
    """A real, finite number (bools refused), optionally an integer, ``> 0`` or ``>= minimum``.

    Returns ``value`` as ``int`` when ``integer`` (an integer-valued float such as TOML's
    ``3.0`` is accepted), else as given. Raises :class:`~ionic_usd.errors.ParameterError`
    naming ``name``, the value and what was expected.
    """
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise ParameterError(name, value, "an integer" if integer else "a number", context=context)
    if not math.isfinite(value):
        raise ParameterError(name, value, "a finite number", context=context)
    out: float | int = value
    if integer:
        if value != int(value):
            raise ParameterError(name, value, "an integer", context=context)
        out = int(value)
    if positive and not value > 0:
        raise ParameterError(
            name, value, f"{'an integer' if integer else 'a finite number'} > 0", context=context
        )
    if minimum is not None and value < minimum:
        raise ParameterError(
            name,
            value,
            f"{'an integer' if integer else 'a number'} >= {minimum:g}",
            context=context,
        )
    return out


def check_fields(
    obj: Any,
    *,
    context: str,
    skip: Collection[str] = (),
    integers: Mapping[str, int | None] | Collection[str] = (),
    positive: Collection[str] = (),
    non_negative: Collection[str] = (),
) -> None:
    """Check every numeric field of the frozen dataclass ``obj`` with :func:`check_number`.

    Parameters
    ----------
    context : where the fields belong, for the messages (``"shaft"``)
    skip : fields that are not numbers (names, grammars, nested parameters) or are private
        (``_``-prefixed fields are always skipped)
    integers : fields that must be integers, normalised to ``int`` on ``obj``; a mapping
        gives each one's minimum (None: none)
    positive, non_negative : fields that must be ``> 0`` / ``>= 0``
    """
    minima = dict(integers) if isinstance(integers, Mapping) else dict.fromkeys(integers)
    for f in dataclasses.fields(obj):
        if f.name in skip or f.name.startswith("_"):
            continue
        integer = f.name in minima
        low = minima.get(f.name)
        if f.name in non_negative:
            low = 0.0 if low is None else max(low, 0)
        v = check_number(
            f.name,
            getattr(obj, f.name),
            context=context,
            integer=integer,
            minimum=low,
            positive=f.name in positive,
        )
        if integer:
            object.__setattr__(obj, f.name, v)
