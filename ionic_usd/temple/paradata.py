"""Paradata of a temple's parts: evidence class (Extended Matrix), certainty, sources.

Every part the composer writes (podium, stair, cella walls, each column position, the
entablature's members, roof, tiles, finishes, ornament) gets a :class:`Record`: its
**evidence class** in the units of the Extended Matrix formal language (EM; E. Demetrescu,
"Archaeological stratigraphy as a formal language for virtual reconstruction", 2015; the unit
codes and the colour chart are those of the EM palette, ``em_palette_template.graphml`` of the
EM tools' library ``s3dgraphy``), its certainty, its sources and a sentence saying why.

The temple TOML states them in ``[paradata]``::

    [paradata.sources]            # short names for citations used below
    adam1994 = "J.-P. Adam, Le temple de Portunus au Forum Boarium (1994)"
    [paradata.part.podium]        # one table per part key (PART_KEYS), or "column.<name>"
    evidence = "US"               # US, USD, USV/s, USV/n, SF, VSF
    certainty = "high"
    sources = ["adam1994"]
    description = "the podium stands in situ"

and a ``[[hypothesis]]`` may say ``evidence = "USV/n"`` (its certainty, sources and description
are the hypothesis' own). A part without a table takes its group's (``column.front_1`` →
``column``), else :data:`DEFAULT_EVIDENCE` with certainty low. Pure Python: no ``pxr``.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from enum import StrEnum
from types import MappingProxyType
from typing import Any

from ionic_usd.errors import ParameterError
from ionic_usd.temple.description import Certainty, Hypothesis, enum_value

__all__ = [
    "Evidence",
    "EM_CHART",
    "PART_KEYS",
    "Record",
    "Paradata",
    "part_key",
    "paradata_from_tables",
    "default_paradata",
    "hypothesis_record",
]


class Evidence(StrEnum):
    """Extended Matrix unit types used for a part's relation to the evidence."""

    US = "US"  # stratigraphic unit: existing, in situ
    USD = "USD"  # documentary unit: known from documents (drawings, photographs, texts)
    USV_S = "USV/s"  # structural virtual stratigraphic unit: structural reconstruction
    USV_N = "USV/n"  # non-structural virtual unit: finishes, ornament, completion
    SF = "SF"  # special find (a fragment not in situ)
    VSF = "VSF"  # virtual special find (a reconstructed find)


@dataclass(frozen=True)
class ChartEntry:
    """One EM unit type: meaning, yEd node shape, fill and border colour (sRGB hex)."""

    label: str
    shape: str
    fill: str
    border: str


#: the EM palette (yEd node styles); ``border`` is the type's colour in the EM colour chart
EM_CHART: Mapping[Evidence, ChartEntry] = MappingProxyType(
    {
        Evidence.US: ChartEntry("existing in situ", "rectangle", "#FFFFFF", "#9B3333"),
        Evidence.USD: ChartEntry("known from documents", "roundrectangle", "#FFFFFF", "#D86400"),
        Evidence.USV_S: ChartEntry(
            "structural virtual reconstruction", "parallelogram", "#000000", "#248FE7"
        ),
        Evidence.USV_N: ChartEntry(
            "non-structural virtual reconstruction", "hexagon", "#000000", "#31792D"
        ),
        Evidence.SF: ChartEntry("special find", "octagon", "#FFFFFF", "#D8BD30"),
        Evidence.VSF: ChartEntry("virtual special find", "octagon", "#000000", "#B19F61"),
    }
)

#: the part keys a temple's prims map to (see :func:`part_key`)
PART_KEYS = (
    "podium",
    "stair",
    "cella",
    "column",
    "architrave",
    "frieze",
    "frieze_relief",
    "cornice",
    "sima",
    "dentils",
    "pediment",
    "raking_cornice",
    "roof",
    "tiles",
    "finish.stucco",
    "finish.travertine",
    "finish.terracotta",
)
_NON_STRUCTURAL = {"frieze_relief", "dentils", "tiles", "sima"}
#: the class of a part a description does not state
DEFAULT_EVIDENCE = Evidence.USV_S


def _evidence(value: object, context: str) -> Evidence:
    spelled = {"USVs": "USV/s", "USVn": "USV/n"}  # the EM tools' codes
    if isinstance(value, str):
        value = spelled.get(value.strip(), value.strip())
    return enum_value(Evidence, value, "evidence", context)


@dataclass(frozen=True)
class Record:
    """A part's paradata. ``hypothesis`` is the id of the alternative it belongs to, or ''."""

    evidence: Evidence
    certainty: Certainty
    sources: tuple[str, ...]
    description: str
    hypothesis: str = ""

    def as_dict(self, unit: str) -> dict[str, Any]:
        """The values written on a prim (``customData`` and ``userProperties:``)."""
        return {
            "unit": unit,
            "evidence": str(self.evidence),
            "evidenceLabel": EM_CHART[self.evidence].label,
            "certainty": str(self.certainty),
            "sources": list(self.sources),
            "description": self.description,
            "hypothesis": self.hypothesis or "baseline",
        }


@dataclass(frozen=True)
class Paradata:
    """Records per part key (``column.<name>`` overrides ``column``) and per hypothesis id."""

    parts: Mapping[str, Record]
    hypotheses: Mapping[str, Record] = field(default_factory=dict)
    fallback: Record = Record(
        DEFAULT_EVIDENCE,
        Certainty.LOW,
        ("the temple description",),
        "Reconstructed from the temple description's dimensions; no evidence stated.",
    )

    def record(self, key: str) -> Record:
        """The record of a part key: its own, its group's, else the fallback."""
        if key in self.parts:
            return self.parts[key]
        group = key.split(".", 1)[0]
        if group in self.parts:
            return self.parts[group]
        if key in _NON_STRUCTURAL or group == "finish":
            return replace(self.fallback, evidence=Evidence.USV_N)
        return self.fallback

    def with_parts(self, parts: Mapping[str, Record]) -> Paradata:
        return replace(self, parts=MappingProxyType({**self.parts, **parts}))

    def __hash__(self) -> int:  # a build key hashes the layout's fields
        return hash(repr(sorted(self.parts.items())) + repr(sorted(self.hypotheses.items())))


def part_key(path: str) -> str | None:
    """The part key of a prim path of a temple (``/Temple/Podium/step_03`` → ``stair``), or
    None for a prim that is not a part (scopes, prototypes, shaders)."""
    segs = [s for s in path.split("/") if s]
    if len(segs) < 3 or "Prototypes" in segs or segs[-1] in ("Mouldings", "Ornament"):
        return None  # scopes that group parts
    comp, leaf = segs[1], segs[-1]
    if comp == "Materials":
        finishes = {"PaintedStucco": "stucco", "Travertine": "travertine"}
        name = finishes.get(leaf, leaf.lower())
        return f"finish.{name}" if len(segs) == 3 else None
    if comp == "Colonnade":
        return f"column.{leaf}" if len(segs) == 4 else None
    low = leaf.lower()
    for prefix, key in _LEAF_KEYS:
        if low.startswith(prefix):
            return key
    return {"Podium": "podium", "Cella": "cella", "Entablature": "frieze", "Roof": "roof"}.get(
        comp, comp.lower()
    )


_LEAF_KEYS = (
    ("step", "stair"),
    ("cheek", "stair"),
    ("architrave", "architrave"),
    ("frieze_relief", "frieze_relief"),
    ("relief", "frieze_relief"),
    ("garland", "frieze_relief"),
    ("candelabr", "frieze_relief"),
    ("frieze", "frieze"),
    ("raking", "raking_cornice"),
    ("cornice", "cornice"),
    ("sima", "sima"),
    ("dentil", "dentils"),
    ("pediment", "pediment"),
    ("tiles", "tiles"),
    ("tegula", "tiles"),
    ("imbrex", "tiles"),
    ("antefix", "tiles"),
    ("roof", "roof"),
    ("wall", "cella"),
    ("door", "cella"),
)


def _strings(value: object, name: str, context: str) -> tuple[str, ...]:
    if not isinstance(value, list) or not all(isinstance(x, str) for x in value):
        raise ParameterError(name, value, "a list of strings", context=context)
    return tuple(value)


def _record(table: object, cites: Mapping[str, str], context: str, hyp: str = "") -> Record:
    if not isinstance(table, Mapping):
        raise ParameterError("paradata", table, "a table", context=context)
    allowed = {"evidence", "certainty", "sources", "description"}
    for k in table:
        if k not in allowed:
            raise ParameterError(
                k, table[k], f"one of {', '.join(sorted(allowed))}", context=context
            )
    missing = [k for k in sorted(allowed) if k not in table]
    if missing:
        raise ParameterError(missing[0], "(missing)", "a value (required key)", context=context)
    desc = table["description"]
    if not isinstance(desc, str) or not desc.strip():
        raise ParameterError("description", desc, "a non-empty string", context=context)
    sources = _strings(table["sources"], "sources", context)
    return Record(
        _evidence(table["evidence"], context),
        enum_value(Certainty, table["certainty"], "certainty", context),
        tuple(cites.get(s, s) for s in sources),
        " ".join(desc.split()),
        hyp,
    )


def hypothesis_record(h: Hypothesis, evidence: object = None) -> Record:
    """A hypothesis' own record: its certainty, sources and description; ``evidence`` given
    or USV/n for a change of material or detail only, else USV/s."""
    if evidence is None:
        soft = all(k.split(".")[0] in ("material", "detail") for k in h.changes)
        ev = Evidence.USV_N if soft else Evidence.USV_S
    else:
        ev = _evidence(evidence, f"hypothesis {h.id!r}")
    return Record(ev, h.certainty, h.sources, " ".join(h.description.split()), h.id)


def default_paradata(hypotheses: Sequence[Hypothesis] = ()) -> Paradata:
    """No stated paradata: every part reconstructed, certainty low."""
    return Paradata(MappingProxyType({}), {h.id: hypothesis_record(h) for h in hypotheses})


def paradata_from_tables(
    data: Mapping[str, Any], hypotheses: Sequence[Hypothesis], *, context: str
) -> Paradata:
    """The ``[paradata]`` table and the hypotheses' ``evidence`` keys of a temple document."""
    table = data.get("paradata", {})
    if not isinstance(table, Mapping):
        raise ParameterError("[paradata]", table, "a table", context=context)
    for k in table:
        if k not in ("sources", "part"):
            raise ParameterError(f"paradata.{k}", "…", "sources or part", context=context)
    cites = table.get("sources", {})
    if not isinstance(cites, Mapping) or not all(isinstance(v, str) for v in cites.values()):
        raise ParameterError("paradata.sources", cites, "a table of strings", context=context)
    parts_table = table.get("part", {})
    if not isinstance(parts_table, Mapping):
        raise ParameterError("paradata.part", parts_table, "a table", context=context)
    parts = {}
    for key, t in parts_table.items():
        if key.split(".")[0] not in PART_KEYS and key not in PART_KEYS:
            raise ParameterError(
                f"paradata.part.{key}", "…", "a part key: " + ", ".join(PART_KEYS), context=context
            )
        parts[key] = _record(t, cites, f"{context} [paradata.part.{key}]")
    evid = {
        e.get("id"): e.get("evidence") for e in data.get("hypothesis", []) if isinstance(e, Mapping)
    }
    hyps = {h.id: hypothesis_record(h, evid.get(h.id)) for h in hypotheses}
    return Paradata(MappingProxyType(parts), MappingProxyType(hyps))
