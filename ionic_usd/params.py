"""Parameters from TOML and back: strict loading, one typed schema, and a TOML writer.

Every table a user can write (``[column]``, ``[shaft]``, ``[capital]``, ``[volute]``, the
temple's ``[temple]`` and dimension sections, ``[[cuboid]]``, ``[[hypothesis]]``) is checked
here, at the boundary, before any constructor sees it: unknown keys, wrong types (a string for
a number, a table for a string, a bool for a count), non-finite numbers and values outside a
physical range (a column is not 1e308 m tall) are :class:`ParameterError` naming the file, the
table and the key. The parameter dataclasses then check the relations between values.
"""

from __future__ import annotations

import dataclasses
import math
import os
import re
import tomllib
import typing
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ionic_usd.errors import ParameterError

__all__ = [
    "FieldSpec",
    "IDENTIFIER",
    "UNIT_LIMITS",
    "check_identifier",
    "check_table",
    "check_value",
    "prim_key",
    "dataclass_from_mapping",
    "dataclass_schema",
    "load_toml",
    "to_toml",
    "toml_key",
    "toml_string",
    "toml_value",
]

#: A name that becomes a file name or a USD prim name: a letter or ``_``, then letters,
#: digits, ``_`` or ``-`` (``-`` becomes ``_`` in prim names; see :func:`prim_key`).
IDENTIFIER = re.compile(r"[A-Za-z_][A-Za-z0-9_-]{0,63}")
#: |value| limits by unit: generous physical envelopes (no column is 1 km tall, no count of
#: samples reaches a million — the triangle/memory estimate refuses far smaller ones).
UNIT_LIMITS: dict[str, float] = {"m": 1000.0, "deg": 36000.0, "count": 1_000_000}
_DEFAULT_LIMIT = 10_000.0  # ratios, spiral units and other dimensionless numbers
_MAX_TOML_BYTES = 16 << 20
_TINY = 1e-9  # below any physical resolution here (a nanometre, a nano-degree)


def load_toml(path: str | os.PathLike) -> dict[str, Any]:
    """Read a TOML file; errors name the file (and TOML's line/column)."""
    p = Path(path)
    try:
        if p.is_dir():
            raise ParameterError("config", str(p), "a TOML file (this is a folder)")
        with p.open("rb") as fh:
            raw = fh.read(_MAX_TOML_BYTES + 1)
        if len(raw) > _MAX_TOML_BYTES:
            raise ParameterError("config", str(p), f"a TOML file under {_MAX_TOML_BYTES >> 20} MB")
        return tomllib.loads(raw.decode("utf-8"))
    except FileNotFoundError:
        raise ParameterError("config", str(p), "an existing TOML file") from None
    except UnicodeDecodeError as exc:
        raise ParameterError(
            "config", str(p), f"a UTF-8 text file (byte {exc.start} is not UTF-8)"
        ) from None
    except tomllib.TOMLDecodeError as exc:
        raise ParameterError("config", str(p), f"valid TOML ({exc})") from None
    except RecursionError:
        raise ParameterError("config", str(p), "TOML nested less deeply") from None
    except OSError as exc:
        raise ParameterError("config", str(p), f"a readable file ({exc.strerror})") from None


def dataclass_from_mapping(cls, mapping: dict[str, Any], *, context: str, base=None):
    """Build a frozen parameter dataclass from a mapping, refusing unknown keys.

    Parameters
    ----------
    cls : dataclass type
    mapping : key → value (from TOML or CLI flags)
    context : where the mapping came from, for messages (e.g. ``"column.toml [shaft]"``)
    base : an instance whose values fill keys absent from ``mapping`` (defaults otherwise)
    """
    if not isinstance(mapping, Mapping):
        raise ParameterError("table", mapping, "a table of key = value", context=context)
    names = {f.name for f in dataclasses.fields(cls) if not f.name.startswith("_")}
    unknown = sorted(set(mapping) - names)
    if unknown:
        raise ParameterError(
            unknown[0],
            mapping[unknown[0]],
            f"one of the known keys: {', '.join(sorted(names))}",
            context=context,
        )
    mapping = check_table(mapping, dataclass_schema(cls), context=context)
    if base is not None:
        return dataclasses.replace(base, **mapping)
    return cls(**mapping)


_BARE_KEY = re.compile(r"[A-Za-z0-9_-]+")
_TOML_ESCAPES = {
    "\b": "\\b",
    "\t": "\\t",
    "\n": "\\n",
    "\f": "\\f",
    "\r": "\\r",
    '"': '\\"',
    "\\": "\\\\",
}


def toml_string(s: str) -> str:
    """``s`` as a TOML basic string: quotes, backslashes and control characters escaped."""
    try:
        s.encode("utf-8")
    except UnicodeEncodeError:  # a lone surrogate: no TOML file can hold it
        raise ParameterError("value", s, "a string of Unicode characters") from None
    out = []
    for ch in s:
        if ch in _TOML_ESCAPES:
            out.append(_TOML_ESCAPES[ch])
        elif ch < " " or ch == "\x7f":
            out.append(f"\\u{ord(ch):04X}")
        else:
            out.append(ch)
    return '"' + "".join(out) + '"'


def toml_key(key: str) -> str:
    """A TOML key: bare when it can be (letters, digits, ``_``, ``-``), else quoted."""
    return key if _BARE_KEY.fullmatch(key) else toml_string(key)


def toml_value(v: Any) -> str:
    """A Python scalar/list/dict as a TOML value."""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        if not math.isfinite(v):
            raise ParameterError("value", v, "a finite number (TOML files hold no inf/nan here)")
        return repr(v)
    if isinstance(v, str):
        return toml_string(v)
    if isinstance(v, list | tuple):
        return "[" + ", ".join(toml_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{ " + ", ".join(f"{toml_key(k)} = {toml_value(x)}" for k, x in v.items()) + " }"
    if v is None:
        raise ParameterError("value", v, "a value (TOML has no null)")
    raise ParameterError("value", v, "a TOML scalar, list or table")


def to_toml(
    sections: dict[str, dict[str, Any]],
    docs: dict[str, dict[str, tuple[str, str, str]]] | None = None,
    header: str = "",
) -> str:
    """Render tables as TOML with a comment (paper letter, unit, meaning) above each key.

    ``None`` values are written as commented-out keys (optional parameters).
    """
    out = [f"# {line}" for line in header.splitlines()]
    for name, values in sections.items():
        if out:
            out.append("")
        out.append(f"[{toml_key(name)}]")
        sec_docs = (docs or {}).get(name, {})
        for key, value in values.items():
            if key in sec_docs:
                letter, unit, text = sec_docs[key]
                tag = f"{letter}, " if letter else ""
                out.append(f"# {text} ({tag}{unit})")
            if value is None:
                out.append(f"# {toml_key(key)} =")
            else:
                out.append(f"{toml_key(key)} = {toml_value(value)}")
    return "\n".join(out) + "\n"


# -- one typed schema --------------------------------------------------------------------------
@dataclass(frozen=True)
class FieldSpec:
    """The type and range of one TOML value.

    ``kind``: ``float`` (int accepted), ``int``, ``bool``, ``str``, ``ident`` (see
    :data:`IDENTIFIER`), ``vec3`` (three floats), ``strings`` (a list of str), ``table``,
    ``scalar`` (a bool, bounded number or short string) or ``any`` (checked by the
    constructor). Numbers lie in ``[lo, hi]``.
    """

    kind: str
    lo: float = -_DEFAULT_LIMIT
    hi: float = _DEFAULT_LIMIT
    unit: str = ""
    choices: tuple[str, ...] = ()
    max_len: int = 4096


def _kind_name(spec: FieldSpec) -> str:
    return {
        "float": "a number",
        "int": "an integer",
        "bool": "true or false",
        "str": "a string",
        "ident": "an identifier (letters, digits, _, -; ≤ 64)",
        "vec3": "three numbers [x, y, z]",
        "strings": "a list of strings",
        "table": "a table",
    }.get(spec.kind, "a value")


def _number(key: str, v: Any, spec: FieldSpec, context: str, *, integer: bool) -> Any:
    if isinstance(v, bool) or not isinstance(v, int | float):
        raise ParameterError(key, v, "an integer" if integer else "a number", context=context)
    if integer and isinstance(v, float):
        if not (math.isfinite(v) and v == int(v)):
            raise ParameterError(key, v, "an integer", context=context)
        v = int(v)
    if not math.isfinite(v):
        raise ParameterError(key, v, "a finite number", context=context)
    if v != 0 and abs(v) < _TINY:  # subnormal-like values overflow the first division
        raise ParameterError(key, v, f"0 or a magnitude of at least {_TINY:g}", context=context)
    if not spec.lo <= v <= spec.hi:
        unit = f" {spec.unit}" if spec.unit and spec.unit not in ("count",) else ""
        raise ParameterError(
            key, v, f"a value in [{spec.lo:g}, {spec.hi:g}]{unit}", context=context
        )
    return v if integer else float(v)


def check_value(key: str, value: Any, spec: FieldSpec, *, context: str = "") -> Any:
    """``value`` checked against ``spec`` (ints widened to float for ``float``)."""
    k = spec.kind
    if k == "float":
        return _number(key, value, spec, context, integer=False)
    if k == "int":
        return _number(key, value, spec, context, integer=True)
    if k == "bool":
        if not isinstance(value, bool):
            raise ParameterError(key, value, "true or false", context=context)
        return value
    if k in ("str", "ident"):
        if not isinstance(value, str):
            raise ParameterError(key, value, _kind_name(spec), context=context)
        if len(value) > spec.max_len:
            raise ParameterError(
                key, value[:40] + "…", f"at most {spec.max_len} characters", context=context
            )
        if k == "ident":
            check_identifier(key, value, context=context)
        if spec.choices and value not in spec.choices:
            raise ParameterError(key, value, f"one of {', '.join(spec.choices)}", context=context)
        return value
    if k == "vec3":
        if not isinstance(value, list | tuple) or len(value) != 3:
            raise ParameterError(key, value, "three numbers [x, y, z]", context=context)
        return [
            _number(f"{key}[{i}]", x, spec, context, integer=False) for i, x in enumerate(value)
        ]
    if k == "strings":
        if not isinstance(value, list | tuple) or not all(isinstance(x, str) for x in value):
            raise ParameterError(key, value, "a list of strings", context=context)
        return list(value)
    if k == "scalar":
        if isinstance(value, bool):
            return value
        if isinstance(value, int | float):
            return _number(key, value, spec, context, integer=isinstance(value, int))
        return check_value(key, value, FieldSpec("str", max_len=256), context=context)
    if k == "table":
        if not isinstance(value, Mapping):
            raise ParameterError(key, value, "a table", context=context)
        return value
    return value


def check_identifier(key: str, value: Any, *, context: str = "") -> str:
    """``value`` if it is an identifier (it names files and prims: no ``/``, ``..``, spaces)."""
    if not isinstance(value, str) or not IDENTIFIER.fullmatch(value):
        raise ParameterError(
            key,
            value,
            "an identifier: a letter or _ then letters, digits, "
            "_ or - (at most 64; no '/', '.' or spaces)",
            context=context,
        )
    return value


def prim_key(name: str) -> str:
    """What two names must not share: their USD prim / file form, case-folded
    (``a-b`` and ``a_b`` are the same prim; ``A`` and ``a`` the same file on macOS)."""
    return re.sub(r"[^A-Za-z0-9_]", "_", name).lower()


def check_table(
    mapping: Mapping[str, Any], schema: Mapping[str, FieldSpec], *, context: str
) -> dict[str, Any]:
    """Check every key of ``mapping`` against ``schema`` (unknown keys are errors)."""
    if not isinstance(mapping, Mapping):
        raise ParameterError("table", mapping, "a table of key = value", context=context)
    out = {}
    for key, value in mapping.items():
        if key not in schema:
            raise ParameterError(
                key, value, f"one of the known keys: {', '.join(schema)}", context=context
            )
        out[key] = check_value(key, value, schema[key], context=context)
    return out


_DOC_SOURCES = {
    "ShaftParams": ("ionic_usd.column.shaft", "SHAFT_PARAMETER_DOCS"),
    "CapitalParams": ("ionic_usd.column.capital", "CAPITAL_PARAMETER_DOCS"),
    "VoluteParams": ("ionic_usd.column.volute", "VOLUTE_PARAMETER_DOCS"),
}


def _units(cls) -> dict[str, str]:
    src = _DOC_SOURCES.get(cls.__name__)
    if src is None:
        return {}
    import importlib

    docs = getattr(importlib.import_module(src[0]), src[1], {})
    return {k: v[1] for k, v in docs.items() if len(v) >= 2}


def _unit_of(cls, name: str, units: Mapping[str, str]) -> str:
    if name in units:
        return units[name]
    if cls.__name__ == "TempleParams":  # dimension sections: lengths unless ratio/divisor
        return "" if ("ratio" in name or "divisor" in name) else "m"
    return ""


def dataclass_schema(cls) -> dict[str, FieldSpec]:
    """The :class:`FieldSpec` of every public field of a parameter dataclass.

    The kind follows the type hint (``float``, ``int``, ``bool``, ``str``; a union with
    ``str`` is a string; other types are left to the constructor); the range follows the
    unit in the class's parameter docs (:data:`UNIT_LIMITS`, ±10⁴ for dimensionless values).
    """
    hints = typing.get_type_hints(cls)
    units = _units(cls)
    out = {}
    for f in dataclasses.fields(cls):
        if f.name.startswith("_") or not f.init:
            continue
        t = hints.get(f.name, Any)
        args = set(typing.get_args(t)) - {type(None)} or {t}
        unit = _unit_of(cls, f.name, units)
        lim = UNIT_LIMITS.get(unit, _DEFAULT_LIMIT)
        if args == {bool}:
            spec = FieldSpec("bool")
        elif args == {int}:
            spec = FieldSpec("int", 0 if unit == "count" else -lim, lim, unit)
        elif args <= {float, int}:
            spec = FieldSpec("float", -lim, lim, unit)
        elif str in args:
            spec = FieldSpec("str", max_len=4096)
        else:
            spec = FieldSpec("any")
        out[f.name] = spec
    return out
