"""Prototype build specifications: what a temple build depends on, and its content hash.

A :class:`TempleSpec` carries everything that decides the bytes of a temple folder written by
:func:`ionic_usd.pipeline.temple.compose_temple`: the description (TOML text), the column
overrides, texture size and seed, and the package version. Its :attr:`key` (SHA-256 of a
canonical JSON of those) names the folder in the prototype cache and in the city, so two lots
that choose the same temple share one build, and a rebuild builds only what changed.
"""

from __future__ import annotations

import hashlib
import json
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass
from functools import cached_property
from importlib import resources
from pathlib import Path
from typing import Any

from ionic_usd.errors import ParameterError
from ionic_usd.temple.presets import PRESETS

__all__ = ["TempleSpec", "temple_spec", "BUILTIN_TEMPLES"]

#: the built-in temples (ionic_usd.temple.presets: Portunus and the typed presets)
BUILTIN_TEMPLES = dict(PRESETS)
# what the column overrides of a lot may set, and the [columns] key each sets
_COLUMN_KEYS = {"height": "height", "lower_diameter": "lower_diameter"}
# the same in a typed description's [type] table (ionic_usd.temple.vitruvius)
_TYPE_KEYS = {"height": "column_height", "lower_diameter": "lower_diameter"}


@dataclass(frozen=True)
class TempleSpec:
    """One temple build.

    Attributes
    ----------
    name : a readable slug (folder names: ``<name>-<key[:12]>``)
    description : the temple TOML text, column overrides already applied
    texture_size, seed : as for ``compose_temple``
    """

    name: str
    description: str
    texture_size: int = 1024
    seed: int = 7

    @cached_property
    def key(self) -> str:
        """SHA-256 (hex) of everything the build's bytes depend on: the description and
        options, the version, the package's code and data (so an edited generator never
        reuses a cached build) and the runtime libraries' versions."""
        from ionic_usd import __version__
        from ionic_usd.pipeline.keys import library_versions, source_digest

        doc = {
            "name": self.name,
            "description": self.description,
            "texture_size": self.texture_size,
            "seed": self.seed,
            "version": __version__,
            "code": source_digest(),
            "libraries": library_versions(),
        }
        return hashlib.sha256(json.dumps(doc, sort_keys=True).encode()).hexdigest()

    @property
    def folder(self) -> str:
        """The build's folder name inside the city (``Temples/<folder>``)."""
        return f"{self.name}-{self.key[:12]}"

    def tables(self) -> dict[str, Any]:
        return tomllib.loads(self.description)

    def layout(self):
        """The :class:`ionic_usd.temple.layout.TempleLayout` this spec builds."""
        from ionic_usd.temple.layout import layout_from_mapping

        data = self.tables()
        for k in ("column", "shaft", "capital", "volute"):
            data.pop(k, None)
        layout = layout_from_mapping(data, context=f"temple {self.name}")
        from ionic_usd.blueprint.hypotheses import check_hypothesis_budget

        check_hypothesis_budget(layout)  # refused here, before any build of the city
        return layout


def _toml_value(v: float) -> str:
    return repr(float(v))


def temple_spec(
    temple: str,
    column: Mapping[str, float] | None = None,
    *,
    base_dir: Path | None = None,
    texture_size: int = 1024,
    seed: int = 7,
    context: str = "",
) -> TempleSpec:
    """The spec of a lot's temple: a built-in name (``portunus``) or a TOML path (relative to
    ``base_dir``), with column overrides (``height``, ``lower_diameter`` in metres) written into
    its ``[columns]`` table — so the description's own validation checks them."""
    if temple in BUILTIN_TEMPLES:
        ref = resources.files("ionic_usd") / "data" / BUILTIN_TEMPLES[temple]
        text = ref.read_text(encoding="utf-8")
        name = temple
    else:
        path = Path(temple)
        if not path.is_absolute() and base_dir is not None:
            path = base_dir / path
        try:
            text = path.read_text(encoding="utf-8")
        except (OSError, UnicodeDecodeError):
            raise ParameterError(
                "temple",
                temple,
                f"a built-in description ({', '.join(BUILTIN_TEMPLES)}) or a readable TOML file",
                context=context,
            ) from None
        name = "".join(c if c.isalnum() else "_" for c in path.stem) or "temple"
    try:
        tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ParameterError("temple", temple, f"valid TOML ({exc})", context=context) from None
    if column:
        typed = "type" in tomllib.loads(text)
        keys = _TYPE_KEYS if typed else _COLUMN_KEYS
        extra = [f"{keys[k]} = {_toml_value(v)}" for k, v in sorted(column.items())]
        # a typed temple with another lower diameter takes its stylobate from the module
        drop = {"stylobate_width"} if typed and "lower_diameter" in column else set()
        text = _set_columns(text, extra, table="type" if typed else "columns", drop=drop)
    spec = TempleSpec(name, text, int(texture_size), int(seed))
    try:
        spec.layout()  # validates the description (and the overrides) before any build
    except ParameterError as exc:
        raise ParameterError("temple", temple, str(exc), context=context) from None
    return spec


def _set_columns(
    text: str, assignments: list[str], *, table: str = "columns", drop: set[str] | None = None
) -> str:
    """Override keys of the ``[columns]`` (or another) table: TOML forbids a repeated key, so
    the old assignments (and the keys in ``drop``) are dropped and the new ones appended at
    the table's start."""
    keys = {a.split("=")[0].strip() for a in assignments} | set(drop or ())
    out: list[str] = []
    in_columns = False
    seen = False
    for line in text.splitlines():
        s = line.strip()
        if s.startswith("["):
            in_columns = s == f"[{table}]"
            out.append(line)
            if in_columns:
                seen = True
                out.extend(assignments)
            continue
        if in_columns and "=" in s and s.split("=")[0].strip() in keys:
            continue
        out.append(line)
    if not seen:
        out += ["", f"[{table}]", *assignments]
    return "\n".join(out) + "\n"
