"""The temple description's TOML tables: readers into values, and the document's schema.

:func:`check_temple_tables` checks types and ranges of a whole temple document at the boundary
(``[temple]``, the dimension sections, ``[[cuboid]]``, ``[[hypothesis]]``, column tables);
:func:`params_from_tables`, :func:`cuboids_from_tables` and :func:`hypotheses_from_tables`
then turn its tables into the value types of :mod:`ionic_usd.temple.description`;
:func:`cuboids_to_toml` writes cuboids back. :mod:`ionic_usd.temple.layout` calls them.
"""

from __future__ import annotations

import os
from collections.abc import Iterable, Mapping, Sequence
from typing import Any

from ionic_usd.column.column import check_column_tables
from ionic_usd.errors import ParameterError
from ionic_usd.grammar.cuboid import Cuboid, Incline
from ionic_usd.params import (
    UNIT_LIMITS,
    FieldSpec,
    check_identifier,
    check_table,
    check_value,
    dataclass_schema,
    load_toml,
    prim_key,
    toml_value,
)
from ionic_usd.temple.description import (
    COMPOSER_NAMESPACES,
    SECTIONS,
    Hypothesis,
    Layer,
    TempleParams,
    enum_value,
)

__all__ = [
    "HYPOTHESIS_EXTRA_CHANGES",
    "check_temple_tables",
    "cuboids_from_tables",
    "cuboids_to_toml",
    "hypotheses_from_tables",
    "load_cuboids_toml",
    "params_from_tables",
    "REQUIRED_TABLES",
    "resolve_extends",
]


# ---------------------------------------------------------------------------------------------
# the dimension sections


def params_from_tables(data: Mapping[str, Any], *, context: str) -> TempleParams:
    """A :class:`TempleParams` from TOML tables (``[temple] name`` and the dimension sections);
    unknown sections or keys raise :class:`ParameterError` naming them."""
    kw: dict[str, Any] = {}
    temple = data.get("temple", {})
    if not isinstance(temple, Mapping):
        raise ParameterError("[temple]", temple, "a table", context=context)
    for key, value in temple.items():
        if key != "name":
            raise ParameterError(
                f"temple.{key}", value, "name (the only key of [temple])", context=context
            )
    if "name" in temple:
        kw["name"] = temple["name"]
    for sec, table in data.items():
        if sec in ("temple", "hypothesis", "cuboid", "mouldings", "paradata"):  # temple.mouldings,
            # temple.paradata read these
            continue
        if sec not in SECTIONS:
            raise ParameterError(
                f"[{sec}]",
                "…",
                "a known section: " + ", ".join(["temple", *SECTIONS, "hypothesis", "cuboid"]),
                context=context,
            )
        for key, value in table.items():
            if key not in SECTIONS[sec]:
                raise ParameterError(
                    f"{sec}.{key}", value, f"one of {', '.join(SECTIONS[sec])}", context=context
                )
            kw[f"{sec}_{key}"] = value
    return TempleParams(**kw)


# ---------------------------------------------------------------------------------------------
# cuboids in TOML


def cuboids_from_tables(
    entries: Iterable[Mapping[str, Any]], *, context: str
) -> dict[Layer, tuple[Cuboid, ...]]:
    """Cuboids from ``[[cuboid]]`` tables grouped by layer.

    Each table: ``name`` (str), ``min`` / ``max`` ([x, y, z] metres), ``layer`` (one of
    :class:`Layer`), optional ``rise`` (metres, default 0) and ``incline`` (``"shear"`` or
    ``"wedge"``). Errors name ``context`` (the file), the entry and the key.
    """
    out: dict[Layer, list[Cuboid]] = {}
    allowed = {"name", "min", "max", "rise", "incline", "layer"}
    for i, e in enumerate(entries, 1):
        where = f"{context} [[cuboid]] #{i}"
        if not isinstance(e, Mapping):
            raise ParameterError("[[cuboid]]", e, "a table", context=where)
        if "name" in e:
            where += f" ({e['name']!r})"
        for key in e:
            if key not in allowed:
                raise ParameterError(
                    key, e[key], f"one of {', '.join(sorted(allowed))}", context=where
                )
        for key in ("name", "min", "max", "layer"):
            if key not in e:
                raise ParameterError(key, "(missing)", "a value (required key)", context=where)
        layer = enum_value(Layer, e["layer"], "layer", where)
        try:
            c = Cuboid(
                e["min"], e["max"], e.get("rise", 0.0), e.get("incline", "shear"), name=e["name"]
            )
        except ParameterError as exc:
            raise ParameterError(exc.name, exc.value, exc.valid, context=where) from None
        out.setdefault(layer, []).append(c)
    return {k: tuple(v) for k, v in out.items()}


def load_cuboids_toml(path: str | os.PathLike) -> dict[Layer, tuple[Cuboid, ...]]:
    """Read the ``[[cuboid]]`` entries of a TOML file, grouped by layer."""
    data = load_toml(path)
    entries = data.get("cuboid", [])
    if not isinstance(entries, list):
        raise ParameterError(
            "cuboid", entries, "an array of tables ([[cuboid]])", context=str(path)
        )
    return cuboids_from_tables(entries, context=str(path))


def cuboids_to_toml(groups: Mapping[str, Iterable[Cuboid]]) -> str:
    """``[[cuboid]]`` tables for cuboids grouped by layer (read back by
    :func:`load_cuboids_toml`)."""
    out = []
    for layer, cs in groups.items():
        lay = enum_value(Layer, layer, "layer", "cuboids_to_toml")
        for c in cs:
            out += [
                "[[cuboid]]",
                f"name = {toml_value(c.name)}",
                f"layer = {toml_value(lay.value)}",
                f"min = {toml_value(list(c.min))}",
                f"max = {toml_value(list(c.max))}",
            ]
            if c.rise != 0.0 or c.incline is not Incline.SHEAR:
                out += [f"rise = {toml_value(c.rise)}", f"incline = {toml_value(c.incline.value)}"]
            out.append("")
    return "\n".join(out)


def hypotheses_from_tables(
    entries, context: str, *, sections: Mapping[str, tuple[str, ...]] | None = None
) -> tuple[Hypothesis, ...]:
    """``[[hypothesis]]`` tables as :class:`Hypothesis` values: required keys, distinct ids,
    and ``changes`` that name a temple ``section.key`` of ``sections`` (default: the
    dimension sections) or a composer namespace."""
    sections = SECTIONS if sections is None else sections
    out = []
    allowed = {"id", "description", "sources", "certainty", "changes"}
    optional = {"evidence", "question"}  # evidence: read by ionic_usd.temple.paradata
    for i, e in enumerate(entries, 1):
        where = f"{context} [[hypothesis]] #{i}"
        if not isinstance(e, Mapping):
            raise ParameterError("[[hypothesis]]", e, "a table", context=where)
        for key in e:
            if key not in allowed | optional:
                raise ParameterError(
                    key, e[key], f"one of {', '.join(sorted(allowed | optional))}", context=where
                )
        for key in sorted(allowed):
            if key not in e:
                raise ParameterError(key, "(missing)", "a value (required key)", context=where)
        src = e["sources"]
        if not isinstance(src, list) or not all(isinstance(x, str) for x in src):
            raise ParameterError("sources", src, "a list of strings", context=where)
        try:
            q = e.get("question", "")
            if not isinstance(q, str):
                raise ParameterError("question", q, "a name (string)", context=where)
            out.append(
                Hypothesis(e["id"], e["description"], tuple(src), e["certainty"], e["changes"], q)
            )
        except ParameterError as exc:
            raise ParameterError(exc.name, exc.value, exc.valid, context=where) from None
    seen: dict[str, str] = {}  # ids name files and variant sets: hyp_a_b for a-b and a_b
    for h in out:
        check_identifier("id", h.id, context=f"{context} [[hypothesis]]")
        if prim_key(h.id) in seen:
            other = seen[prim_key(h.id)]
            raise ParameterError(
                "id",
                h.id,
                f"an id distinct from {other!r} (both would name "
                "the same layer file and variant set)",
                context=f"{context} [[hypothesis]]",
            )
        seen[prim_key(h.id)] = h.id
    _check_questions(out, context)
    for i, h in enumerate(out, 1):
        for key, value in h.changes.items():
            sec, k = key.split(".")
            if sec in COMPOSER_NAMESPACES:
                continue  # the composer checks these (ionic_usd.usd.hypotheses)
            if sec not in sections or k not in sections[sec]:
                valid = (
                    f"one of {sec}.{', '.join(sections[sec])}"
                    if sec in sections
                    else "section.key of the temple TOML, or column.… / material.…"
                )
                raise ParameterError(
                    key, value, valid, context=f"{context} [[hypothesis]] #{i} ({h.id!r})"
                )
    return tuple(out)


# ---------------------------------------------------------------------------------------------
# the schema of a whole document (types and ranges, at the boundary)


_CUBOID = {
    "name": FieldSpec("ident"),
    "min": FieldSpec("vec3", -UNIT_LIMITS["m"], UNIT_LIMITS["m"], "m"),
    "max": FieldSpec("vec3", -UNIT_LIMITS["m"], UNIT_LIMITS["m"], "m"),
    "rise": FieldSpec("float", -UNIT_LIMITS["m"], UNIT_LIMITS["m"], "m"),
    "incline": FieldSpec("str", max_len=16),
    "layer": FieldSpec("str", max_len=32),
}
_HYPOTHESIS = {
    "id": FieldSpec("ident"),
    "description": FieldSpec("str", max_len=10_000),
    "sources": FieldSpec("strings"),
    "certainty": FieldSpec("str", max_len=32),
    "changes": FieldSpec("table"),
    "evidence": FieldSpec("str", max_len=16),
    "question": FieldSpec("ident"),  # alternatives of one question: one variant set
}
#: hypothesis changes outside the temple's dimension sections, realised by the composer
HYPOTHESIS_EXTRA_CHANGES = {
    "column.flute_count": FieldSpec("int", 3, 64, "count"),
    "material.finish": FieldSpec(
        "str", choices=("bare_stone", "travertine", "stucco", "painted_stucco")
    ),
    "detail.frieze": FieldSpec("str", choices=("garlands", "plain")),  # usd.detail
}


def check_temple_tables(data: Mapping[str, Any], *, context: str) -> None:
    """Check a temple document: ``[temple]``, the dimension sections, ``[[cuboid]]``,
    ``[[hypothesis]]`` (ids are identifiers; changes name known keys with valid values) and
    any column tables. Cuboid names must stay distinct as prim names."""
    if not isinstance(data, Mapping):
        raise ParameterError("document", data, "TOML tables", context=context)
    dims = dataclass_schema(TempleParams)
    sections: dict[str, dict[str, FieldSpec]] = {}
    for name, dim in dims.items():
        if name != "name":
            sec, key = name.split("_", 1)
            sections.setdefault(sec, {})[key] = dim
    column_tables = {"column", "shaft", "capital", "volute"}
    for sec, table in data.items():
        if sec == "temple":
            check_table(
                check_value("temple", table, FieldSpec("table"), context=context),
                {"name": FieldSpec("str", max_len=256)},
                context=f"{context} [temple]",
            )
        elif sec in sections:
            table = check_value(sec, table, FieldSpec("table"), context=context)
            check_table(
                {f"{sec}.{k}": v for k, v in table.items()},
                {f"{sec}.{k}": v for k, v in sections[sec].items()},
                context=context,
            )
        elif sec in ("mouldings", "paradata"):  # checked by temple.mouldings / .paradata
            check_value(sec, table, FieldSpec("table"), context=context)
        elif sec in ("cuboid", "hypothesis"):
            if not isinstance(table, list):
                raise ParameterError(sec, table, f"an array of tables ([[{sec}]])", context=context)
        elif sec not in column_tables:
            raise ParameterError(
                f"[{sec}]",
                "…",
                "a known table: "
                + ", ".join(
                    [
                        "temple",
                        *sections,
                        "mouldings",
                        "paradata",
                        "cuboid",
                        "hypothesis",
                        *sorted(column_tables),
                    ]
                ),
                context=context,
            )
    check_column_tables({k: v for k, v in data.items() if k in column_tables}, context=context)
    for i, e in enumerate(data.get("cuboid", []), 1):
        where = f"{context} [[cuboid]] #{i}"
        check_table(
            check_value("[[cuboid]]", e, FieldSpec("table"), context=where), _CUBOID, context=where
        )
    changes_schema = {
        f"{sec}.{k}": spec for sec, keys in sections.items() for k, spec in keys.items()
    }
    changes_schema.update(HYPOTHESIS_EXTRA_CHANGES)
    for i, e in enumerate(data.get("hypothesis", []), 1):
        where = f"{context} [[hypothesis]] #{i}"
        e = check_table(
            check_value("[[hypothesis]]", e, FieldSpec("table"), context=where),
            _HYPOTHESIS,
            context=where,
        )
        for key, value in e.get("changes", {}).items():
            # column.* / material.* record alternatives the generator may not realise yet
            change: FieldSpec | None = changes_schema.get(key)
            if change is None and str(key).split(".")[0] in ("column", "material"):
                change = FieldSpec("scalar")
            check_table(
                {key: value},
                {key: change} if change else changes_schema,
                context=f"{where} changes",
            )


# ---------------------------------------------------------------------------------------------
# what a description inherits: ``extends = "portunus"``

#: the tables every temple description holds, itself or through ``extends``
REQUIRED_TABLES = ("temple", *SECTIONS)
_MAX_EXTENDS = 8  # a chain of descriptions deeper than this is a cycle or a mistake


def _builtin_tables(name: object, context: str) -> dict[str, Any]:
    from importlib import resources

    names = sorted(
        p.name[: -len(".toml")]
        for p in resources.files("ionic_usd").joinpath("data").iterdir()
        if p.name.endswith(".toml") and "[temple]" in p.read_text(encoding="utf-8")
    )
    if not isinstance(name, str) or name not in names:
        raise ParameterError(
            "extends", name, f"a built-in temple description ({', '.join(names)})", context=context
        )
    ref = resources.files("ionic_usd") / "data" / f"{name}.toml"
    with resources.as_file(ref) as p:
        return load_toml(p)


def resolve_extends(data: Mapping[str, Any], *, context: str) -> dict[str, Any]:
    """The description with what it inherits filled in, checked for missing tables.

    ``extends = "NAME"`` (a built-in description, e.g. ``portunus``) takes NAME's tables: each
    table the description gives is merged key by key over NAME's (``[temple]``, the dimension
    sections, ``[mouldings]``, the column tables), and its ``[[cuboid]]`` and ``[[hypothesis]]``
    entries are added to NAME's. Without ``extends`` every table of :data:`REQUIRED_TABLES`
    must be there: a missing one is an error naming it (it used to take Portunus's values in
    silence).
    """
    out = dict(data)
    chain: list[str] = []
    while "extends" in out:
        name = out.pop("extends")
        if name in chain or len(chain) >= _MAX_EXTENDS:
            raise ParameterError(
                "extends", name, f"a chain without cycles ({' -> '.join(chain)})", context=context
            )
        chain.append(str(name))
        base = _builtin_tables(name, context)
        merged: dict[str, Any] = dict(base)
        for key, value in out.items():
            old = base.get(key)
            if (
                key in ("cuboid", "hypothesis")
                and isinstance(old, list)
                and isinstance(value, list)
            ):
                merged[key] = [*old, *value]
            elif isinstance(old, Mapping) and isinstance(value, Mapping):
                merged[key] = {**old, **value}
            else:
                merged[key] = value
        out = merged
    missing = [t for t in REQUIRED_TABLES if t not in out]
    if missing:
        raise ParameterError(
            "tables",
            ", ".join(f"[{t}]" for t in missing),
            "every table of a temple description ("
            + ", ".join(f"[{t}]" for t in REQUIRED_TABLES)
            + '), or extends = "portunus" to take the missing ones from a built-in description',
            context=context,
        )
    return out


def _check_questions(hyps: Sequence[Hypothesis], context: str) -> None:
    """Alternatives of one question are one variant set ``hyp_<question>`` with a value per
    alternative: its name must not be another hypothesis' set, and no two alternatives may
    declare the same change (the same part twice: which would the variant show?)."""
    from ionic_usd.temple.description import questions

    where = f"{context} [[hypothesis]]"
    singles = {prim_key(h.id): h.id for h in hyps if not h.question}
    for h in hyps:
        if h.question and prim_key(h.question) in singles:
            raise ParameterError(
                "question",
                h.question,
                f"a name distinct from the hypothesis {singles[prim_key(h.question)]!r} "
                "(both would name the variant set hyp_" + prim_key(h.question) + ")",
                context=f"{where} {h.id!r}",
            )
    for q, alts in questions(hyps).items():
        if not alts[0].question:
            continue
        seen: dict[tuple, str] = {}
        for h in alts:
            decl = tuple(sorted((k, repr(v)) for k, v in h.changes.items()))
            if decl in seen:
                raise ParameterError(
                    "changes",
                    dict(h.changes),
                    f"changes other than those of {seen[decl]!r}: both alternatives of the "
                    f"question {q!r} declare the same change (one variant value each)",
                    context=f"{where} {h.id!r}",
                )
            seen[decl] = h.id
