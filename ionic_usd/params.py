"""Parameters from TOML and back: strict loading (unknown keys are errors) and a TOML writer."""

from __future__ import annotations

import dataclasses
import math
import os
import tomllib
from pathlib import Path
from typing import Any

from ionic_usd.errors import ParameterError

__all__ = ["load_toml", "dataclass_from_mapping", "to_toml", "toml_value"]


def load_toml(path: str | os.PathLike) -> dict[str, Any]:
    """Read a TOML file; errors name the file (and TOML's line/column)."""
    p = Path(path)
    try:
        with p.open("rb") as fh:
            return tomllib.load(fh)
    except FileNotFoundError:
        raise ParameterError("config", str(p), "an existing TOML file") from None
    except tomllib.TOMLDecodeError as exc:
        raise ParameterError("config", str(p), f"valid TOML ({exc})") from None
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
    names = {f.name for f in dataclasses.fields(cls) if not f.name.startswith("_")}
    unknown = sorted(set(mapping) - names)
    if unknown:
        raise ParameterError(
            unknown[0], mapping[unknown[0]],
            f"one of the known keys: {', '.join(sorted(names))}", context=context,
        )
    if base is not None:
        return dataclasses.replace(base, **mapping)
    return cls(**mapping)


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
        return '"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(v, list | tuple):
        return "[" + ", ".join(toml_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{ " + ", ".join(f"{k} = {toml_value(x)}" for k, x in v.items()) + " }"
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
        out.append(f"[{name}]")
        sec_docs = (docs or {}).get(name, {})
        for key, value in values.items():
            if key in sec_docs:
                letter, unit, text = sec_docs[key]
                tag = f"{letter}, " if letter else ""
                out.append(f"# {text} ({tag}{unit})")
            if value is None:
                out.append(f"# {key} =")
            else:
                out.append(f"{key} = {toml_value(value)}")
    return "\n".join(out) + "\n"
