"""The reconstruction's Extended Matrix graph as yEd GraphML: write it, read an edited one.

The graph follows the EM formal language as the EM tools read it (their parser is
``s3dgraphy.importer.import_graphml``; the node styles are those of the EM palette,
``em_palette_template.graphml``):

* one **unit** per part key (``podium``, ``stair``, ``column.front_1``, …) and one per
  hypothesis alternative (labelled ``hyp:<id>``): a ``y:ShapeNode`` whose shape and border colour
  give its EM type (US rectangle #9B3333, USV/s parallelogram #248FE7, USV/n hexagon #31792D,
  USD round rectangle #D86400, SF octagon #D8BD30, VSF octagon #B19F61); the part's sentence in
  the node's ``description``;
* one **property** node per unit (a BPMN annotation, ``ARTIFACT_TYPE_ANNOTATION``), labelled
  ``certainty`` with the certainty as its description;
* one **document** node per distinct source (a BPMN data object, ``DATA_OBJECT_TYPE_PLAIN``),
  labelled ``D.01``, ``D.02``, … with the citation as its description;
* dashed edges (``has_data_provenance``) unit → property → documents, and dash-dotted edges
  (``contrasts_with``) from a hypothesis' unit to the baseline units it changes, and between
  the alternatives of one question (``frieze-plain`` and ``frieze-garlands``: exclusive).

:func:`read_graphml` takes such a file back (as edited in yEd: a node's shape or border colour
changed, a document's text changed, an edge added or removed) and returns the records it states,
which a build applies over the temple description (``ionic-usd temple --paradata FILE``).
Pure Python (``xml.etree``).
"""

from __future__ import annotations

import os
import xml.etree.ElementTree as ET
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

from ionic_usd.errors import ParameterError
from ionic_usd.temple.description import Certainty
from ionic_usd.temple.paradata import EM_CHART, Evidence, Record

__all__ = ["EmGraph", "graph_of", "write_graphml", "read_graphml", "HYP_PREFIX"]

G = "http://graphml.graphdrawing.org/xmlns"
Y = "http://www.yworks.com/xml/graphml"
HYP_PREFIX = "hyp:"
_NS = {
    "xmlns": G,
    "xmlns:y": Y,
    "xmlns:yed": "http://www.yworks.com/xml/yed/3",
    "xmlns:xsi": "http://www.w3.org/2001/XMLSchema-instance",
    "xsi:schemaLocation": f"{G} http://www.yworks.com/xml/schema/graphml/1.1/ygraphml.xsd",
}
_BPMN = "com.yworks.bpmn.Artifact.withShadow"


@dataclass(frozen=True)
class EmGraph:
    """Units (label → record), documents (citation → label) and edges (label pairs + kind)."""

    units: Mapping[str, Record]
    documents: Mapping[str, str]
    edges: tuple[tuple[str, str, str], ...]


def graph_of(
    parts: Mapping[str, Record],
    hypotheses: Mapping[str, tuple[Record, tuple[str, ...]]],
    questions: Mapping[str, str] | None = None,
) -> EmGraph:
    """The graph of the baseline units ``parts`` and the hypotheses (record, parts touched).
    ``questions``: hypothesis id → the question it answers; the alternatives of one question
    (mutually exclusive) are linked to each other by ``contrasts_with`` edges."""
    units = dict(sorted(parts.items()))
    for hid, (rec, _) in sorted(hypotheses.items()):
        units[HYP_PREFIX + hid] = rec
    docs: dict[str, str] = {}
    for rec in units.values():
        for s in rec.sources:
            docs.setdefault(s, f"D.{len(docs) + 1:02d}")
    edges = []
    for label, rec in units.items():
        prop = f"{label}#certainty"
        edges.append((label, prop, "has_data_provenance"))
        edges.extend((prop, docs[s], "has_data_provenance") for s in dict.fromkeys(rec.sources))
    for hid, (_, touched) in sorted(hypotheses.items()):
        edges.extend((HYP_PREFIX + hid, t, "contrasts_with") for t in sorted(touched) if t in parts)
    groups: dict[str, list[str]] = {}
    for hid in sorted(hypotheses):
        groups.setdefault((questions or {}).get(hid) or hid, []).append(hid)
    for alts in groups.values():
        edges.extend(
            (HYP_PREFIX + a, HYP_PREFIX + b, "contrasts_with")
            for i, a in enumerate(alts)
            for b in alts[i + 1 :]
        )
    return EmGraph(units, docs, tuple(edges))


def _sub(parent: ET.Element, tag: str, text: str | None = None, **attrs: str) -> ET.Element:
    el = ET.SubElement(parent, tag, {k.replace("_", "."): v for k, v in attrs.items()})
    if text is not None:
        el.text = text
    return el


def _label(parent: ET.Element, text: str) -> None:
    _sub(parent, "y:NodeLabel", text, alignment="center", autoSizePolicy="content",
         fontFamily="Dialog", fontSize="12", textColor="#000000", visible="true")  # fmt: skip


def _node(graph: ET.Element, nid: str, desc: str, xy: tuple[float, float]) -> ET.Element:
    node = _sub(graph, "node", id=nid)
    _sub(node, "data", desc, key="d_desc")
    gfx = _sub(node, "data", key="d_gfx")
    return gfx


def _geometry(el: ET.Element, xy: tuple[float, float], w: float = 150.0) -> None:
    _sub(el, "y:Geometry", height="30.0", width=f"{w}", x=f"{xy[0]:.1f}", y=f"{xy[1]:.1f}")


def _unit(graph: ET.Element, nid: str, label: str, rec: Record, xy) -> None:
    entry = EM_CHART[rec.evidence]
    shape = _sub(_node(graph, nid, rec.description, xy), "y:ShapeNode")
    _geometry(shape, xy)
    _sub(shape, "y:Fill", color=entry.fill, transparent="false")
    _sub(shape, "y:BorderStyle", color=entry.border, type="line", width="4.0")
    _label(shape, label)
    _sub(shape, "y:Shape", type=entry.shape)


def _bpmn(graph: ET.Element, nid: str, label: str, desc: str, kind: str, xy) -> None:
    gen = _sub(_node(graph, nid, desc, xy), "y:GenericNode", configuration=_BPMN)
    _geometry(gen, xy, 60.0)
    _sub(gen, "y:Fill", color="#FFFFFFE6", transparent="false")
    _sub(gen, "y:BorderStyle", color="#000000", type="line", width="1.0")
    _label(gen, label)
    props = _sub(gen, "y:StyleProperties")
    enum = "com.yworks.yfiles.bpmn.view."
    values = [("BPMNTypeEnum", "com.yworks.bpmn.type", "ARTIFACT_TYPE_ANNOTATION")]
    if kind == "document":
        values = [
            ("BPMNTypeEnum", "com.yworks.bpmn.type", "ARTIFACT_TYPE_DATA_OBJECT"),
            ("DataObjectTypeEnum", "com.yworks.bpmn.dataObjectType", "DATA_OBJECT_TYPE_PLAIN"),
        ]
    for cls, name, value in values:
        _sub(props, "y:Property", **{"class": enum + cls, "name": name, "value": value})


_LINE = {"has_data_provenance": "dashed", "contrasts_with": "dashed_dotted"}


def write_graphml(g: EmGraph, path: str | os.PathLike) -> None:
    """Write ``g`` as yEd GraphML (units in a column, their property and documents beside)."""
    root = ET.Element("graphml", _NS)
    keys = [
        ("d_url", "node", "url"),
        ("d_desc", "node", "description"),
        ("e_url", "edge", "url"),
        ("e_desc", "edge", "description"),
    ]
    for kid, kfor, name in keys:
        _sub(root, "key", id=kid, **{"for": kfor, "attr.name": name, "attr.type": "string"})
    _sub(root, "key", id="d_gfx", **{"for": "node", "yfiles.type": "nodegraphics"})
    _sub(root, "key", id="e_gfx", **{"for": "edge", "yfiles.type": "edgegraphics"})
    graph = _sub(root, "graph", id="G", edgedefault="directed")
    ids: dict[str, str] = {}
    for i, (label, rec) in enumerate(g.units.items()):
        ids[label] = f"u{i}"
        _unit(graph, ids[label], label, rec, (0.0, 60.0 * i))
        ids[f"{label}#certainty"] = f"p{i}"
        _bpmn(graph, f"p{i}", "certainty", str(rec.certainty), "property", (250.0, 60.0 * i))
    for j, (cite, label) in enumerate(g.documents.items()):
        ids[label] = f"d{j}"
        _bpmn(graph, f"d{j}", label, cite, "document", (450.0, 60.0 * j))
    for k, (a, b, kind) in enumerate(g.edges):
        edge = _sub(graph, "edge", id=f"e{k}", source=ids[a], target=ids[b])
        poly = _sub(_sub(edge, "data", key="e_gfx"), "y:PolyLineEdge")
        _sub(poly, "y:LineStyle", color="#000000", type=_LINE[kind], width="1.0")
        _sub(poly, "y:Arrows", source="none", target="standard")
    ET.indent(root)
    Path(path).write_bytes(
        b'<?xml version="1.0" encoding="UTF-8" standalone="no"?>\n'
        + ET.tostring(root, encoding="utf-8")
        + b"\n"
    )


# -- reading --------------------------------------------------------------------------------


def _evidence_of(shape: str, border: str) -> Evidence | None:
    for ev, entry in EM_CHART.items():
        if entry.shape == shape and (
            entry.border.upper() == border.upper() or shape not in ("octagon",)
        ):
            return ev
    return None


def _parse(path: Path) -> ET.Element:
    try:
        head = path.read_bytes()
        if b"<!DOCTYPE" in head or b"<!ENTITY" in head:  # no entity expansion (a GraphML has none)
            raise ParameterError("--paradata", str(path), "a GraphML file without a DTD")
        return ET.fromstring(head)
    except (ET.ParseError, OSError) as exc:
        raise ParameterError("--paradata", str(path), f"a readable GraphML file ({exc})") from None


def _keys(root: ET.Element) -> dict[str, str]:
    out = {}
    for k in root.iter(f"{{{G}}}key"):
        name = k.get("attr.name") or k.get("yfiles.type") or ""
        out[f"{k.get('for')}:{name}"] = k.get("id", "")
    return out


def read_graphml(path: str | os.PathLike) -> tuple[dict[str, Record], dict[str, Record]]:
    """The part records and hypothesis records an EM GraphML states: ``(parts, hypotheses)``.

    A unit's class comes from its node style; its certainty from its ``certainty`` property;
    its sources from the documents its property (or the unit itself) points to."""
    p = Path(path)
    root = _parse(p)
    keys = _keys(root)
    desc_key, gfx_key = keys.get("node:description"), keys.get("node:nodegraphics")
    nodes: dict[str, dict] = {}
    for n in root.iter(f"{{{G}}}node"):
        info = {"desc": "", "label": "", "shape": "", "border": "", "bpmn": ""}
        for d in n.findall(f"{{{G}}}data"):
            if d.get("key") == desc_key:
                info["desc"] = (d.text or "").strip()
            elif d.get("key") == gfx_key:
                lab = d.find(f".//{{{Y}}}NodeLabel")
                info["label"] = (lab.text or "").strip() if lab is not None else ""
                sh, bo = d.find(f".//{{{Y}}}Shape"), d.find(f".//{{{Y}}}BorderStyle")
                info["shape"] = sh.get("type", "") if sh is not None else ""
                info["border"] = bo.get("color", "") if bo is not None else ""
                for prop in d.iter(f"{{{Y}}}Property"):
                    if prop.get("value") == "DATA_OBJECT_TYPE_PLAIN":
                        info["bpmn"] = "document"
                    elif prop.get("value") == "ARTIFACT_TYPE_ANNOTATION":
                        info["bpmn"] = "property"
        nodes[n.get("id", "")] = info
    out: dict[str, list[str]] = {}
    for e in root.iter(f"{{{G}}}edge"):
        out.setdefault(e.get("source", ""), []).append(e.get("target", ""))
    parts: dict[str, Record] = {}
    hyps: dict[str, Record] = {}
    for nid, info in nodes.items():
        if info["bpmn"] or not info["shape"]:
            continue
        ev = _evidence_of(info["shape"], info["border"])
        if ev is None:
            where = f"{p} node {nid} ({info['label']!r})"
            raise ParameterError("shape", info["shape"], "an EM unit shape", context=where)
        certainty, sources = Certainty.LOW, []
        for t in out.get(nid, []):
            tgt = nodes.get(t, {})
            if tgt.get("bpmn") == "property" and tgt.get("label") == "certainty":
                try:
                    certainty = Certainty(tgt["desc"])
                except ValueError:
                    where = f"{p} node {t}"
                    raise ParameterError(
                        "certainty", tgt["desc"], "high, medium or low", context=where
                    ) from None
                sources += [
                    nodes[d]["desc"]
                    for d in out.get(t, [])
                    if nodes.get(d, {}).get("bpmn") == "document"
                ]
            elif tgt.get("bpmn") == "document":
                sources.append(tgt["desc"])
        label = info["label"]
        hid = label[len(HYP_PREFIX) :] if label.startswith(HYP_PREFIX) else ""
        rec = Record(ev, certainty, tuple(dict.fromkeys(sources)), info["desc"], hid)
        (hyps if hid else parts)[hid or label] = rec
    if not parts and not hyps:
        raise ParameterError("--paradata", str(p), "a GraphML holding Extended Matrix units")
    return parts, hyps
