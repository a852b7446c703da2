"""Paradata on every part of a temple build, and the reliability view.

:func:`annotate_temple` runs on a temple folder once its layers are written. It

* walks every layer of the build (the part layers, the colonnade, the detail, the generated
  layer's variants, the hypothesis layers) and writes on each *part* prim spec — a ``def``
  of a Mesh, a PointInstancer, a column instance or a finish Material; in a hypothesis' layer
  (or variant) every prim it touches — the part's :class:`~ionic_usd.temple.paradata.Record`
  as ``customData["paradata"]`` and as ``userProperties:em:<field>`` string
  attributes (Blender imports those as custom properties; the glTF exporter copies both into
  ``extras``). A hypothesis' alternative carries the hypothesis' own record, so the record
  composed on a prim is that of the strongest selection;
* defines the EM colour chart as materials ``/Temple/Materials/EM/<code>`` (in
  ``materials.usda``);
* adds the variant set ``view`` (``appearance``, ``reliability``) on ``/Temple`` in
  ``generated.usda``. ``reliability`` holds one collection per evidence class on ``/Temple``
  (``collection:em_<code>``, the part paths) bound ``strongerThanDescendants`` to the
  class's material, so it wins over every part's own binding whatever the ``detail`` and
  hypothesis selections; the columns are made non-instanceable there (a prototype's meshes
  cannot see a binding on their instance). A hypothesis whose class differs from a part's
  moves that part between the collections in its ``alternative`` (list edits on ``/Temple``,
  stronger than ``view``), so the view follows the hypotheses selected.

Returns the units found: ``{prim path: (part key, record)}`` for the baseline and per
hypothesis, which :mod:`ionic_usd.usd.em_graph` turns into the Extended Matrix graph.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path

from pxr import Gf, Sdf, Usd, UsdShade, Vt

from ionic_usd.temple.description import Hypothesis
from ionic_usd.temple.paradata import EM_CHART, Evidence, Paradata, Record, default_paradata
from ionic_usd.temple.paradata import part_key as _part_key
from ionic_usd.usd.hypotheses import hyp_choices

__all__ = [
    "Units",
    "annotate_temple",
    "annotate_hypothesis_layer",
    "write_record",
    "em_material_path",
    "VIEW_SET",
    "VIEWS",
]

VIEW_SET = "view"
VIEWS = ("appearance", "reliability")
EM_SCOPE = "/Temple/Materials/EM"
_PART_TYPES = {"Mesh", "PointInstancer", "Material"}
_SKIP_FILES = {"Temple.usda", "overrides.usda"}


def em_material_path(ev: Evidence) -> str:
    return f"{EM_SCOPE}/{ev.name}"


@dataclass
class Units:
    """What the annotation found: baseline units and each hypothesis' touched parts."""

    baseline: dict[str, tuple[str, Record]] = field(default_factory=dict)
    hypotheses: dict[str, dict[str, tuple[str, Record]]] = field(default_factory=dict)


def write_record(spec: Sdf.PrimSpec, unit: str, rec: Record) -> None:
    """``rec`` on ``spec``: customData ``ionic_usd.paradata`` and ``userProperties:em:*``."""
    values = rec.as_dict(unit)
    custom = dict(spec.customData)
    custom["paradata"] = {**values, "sources": Vt.StringArray(values["sources"])}
    spec.customData = custom
    for name, value in values.items():
        text = "; ".join(value) if isinstance(value, list) else str(value)
        prop = f"userProperties:em:{name}"
        attr = spec.attributes.get(prop) or Sdf.AttributeSpec(
            spec, prop, Sdf.ValueTypeNames.String, Sdf.VariabilityUniform, declaresCustom=True
        )
        attr.default = text


def _hyp_of_variants(path: Sdf.Path, by_set: dict[tuple[str, str], str]) -> str:
    """The hypothesis id whose variant (``alternative``, or its value of its question's set)
    encloses ``path`` ('' if none)."""
    p = path
    while p != Sdf.Path.absoluteRootPath and not p.isEmpty:
        if p.IsPrimVariantSelectionPath():
            vset, var = p.GetVariantSelection()
            if (vset, var) in by_set:
                return by_set[(vset, var)]
        p = p.GetParentPath()
    return ""


def _hyp_of_file(rel: str, ids: dict[str, str]) -> str:
    if not rel.startswith("layers/"):
        return ""
    stem = rel.split("/", 1)[1].split(".", 1)[0]
    first = stem.split("+")[-1]  # a combination layer: the last hypothesis selected
    return ids.get(first, "")


def _is_part(spec: Sdf.PrimSpec, key: str, in_hyp: bool) -> bool:
    if spec.typeName in ("Scope", "Shader"):
        return False
    if in_hyp:
        return True
    if spec.specifier != Sdf.SpecifierDef:
        return False
    return spec.typeName in _PART_TYPES or key.startswith("column.")


def _layer_files(folder: Path) -> list[Path]:
    out = [p for p in sorted(folder.glob("*.usd*")) if p.name not in _SKIP_FILES]
    return out + sorted((folder / "layers").glob("*.usd*"))


def _annotate_layer(
    lay: Sdf.Layer,
    rel: str,
    pd: Paradata,
    hyps: dict[str, str],
    sets: dict[tuple[str, str], str],
) -> list[tuple[str, str, str, Record]]:
    found: list[Sdf.Path] = []
    lay.Traverse(
        Sdf.Path.absoluteRootPath,
        lambda p: found.append(p) if p.IsPrimPath() or p.IsPrimVariantSelectionPath() else None,
    )
    out = []
    file_hyp = _hyp_of_file(rel, hyps)
    for path in found:
        if not path.IsPrimPath():
            continue
        plain = path.StripAllVariantSelections()
        key = _part_key(str(plain))
        if key is None:
            continue
        hid = _hyp_of_variants(path, sets) or file_hyp
        spec = lay.GetPrimAtPath(path)
        if spec is None or not _is_part(spec, key, bool(hid)):
            continue
        rec = pd.hypotheses[hid] if hid else pd.record(key)
        write_record(spec, key, rec)
        out.append((str(plain), key, hid, rec))
    return out


def _finish_overs(lay: Sdf.Layer, pd: Paradata) -> list[tuple[str, str, str, Record]]:
    """The column asset's finishes (referenced into /Temple/Materials) get an over each."""
    out = []
    for name in ("PaintedStucco", "Travertine"):
        path = f"/Temple/Materials/{name}"
        spec = lay.GetPrimAtPath(path) or Sdf.CreatePrimInLayer(lay, path)
        key = _part_key(path) or ""
        write_record(spec, key, pd.record(key))
        out.append((path, key, "", pd.record(key)))
    return out


def _em_materials(lay: Sdf.Layer) -> None:
    stage = Usd.Stage.Open(lay)
    stage.DefinePrim(EM_SCOPE, "Scope")
    for ev, entry in EM_CHART.items():
        mat = UsdShade.Material.Define(stage, em_material_path(ev))
        surf = UsdShade.Shader.Define(stage, f"{em_material_path(ev)}/PreviewSurface")
        surf.CreateIdAttr("UsdPreviewSurface")
        rgb = [int(entry.border[i : i + 2], 16) / 255.0 for i in (1, 3, 5)]
        lin = [c / 12.92 if c <= 0.04045 else ((c + 0.055) / 1.055) ** 2.4 for c in rgb]
        surf.CreateInput("diffuseColor", Sdf.ValueTypeNames.Color3f).Set(Gf.Vec3f(*lin))
        surf.CreateInput("roughness", Sdf.ValueTypeNames.Float).Set(0.8)
        mat.CreateSurfaceOutput().ConnectToSource(surf.ConnectableAPI(), "surface")
        mat.GetPrim().SetCustomDataByKey("ionic_usd:em", f"{ev.value}: {entry.label}")
    del stage


def _collection(spec: Sdf.PrimSpec, name: str) -> Sdf.RelationshipSpec:
    rel = spec.relationships.get(f"collection:{name}:includes")
    if rel is None:
        rel = Sdf.RelationshipSpec(spec, f"collection:{name}:includes", custom=False)
    return rel


def _view_variants(gen: Sdf.Layer, units: Units, ids: dict[tuple[str, str], str]) -> None:
    spec = gen.GetPrimAtPath("/Temple")
    vs = Sdf.VariantSetSpec(spec, VIEW_SET)
    spec.variantSetNameList.Append(VIEW_SET)
    for v in VIEWS:
        Sdf.VariantSpec(vs, v)
    spec.variantSelections[VIEW_SET] = VIEWS[0]
    rel_spec = vs.variants["reliability"].primSpec
    by_class: dict[Evidence, list[str]] = {ev: [] for ev in EM_CHART}
    for path, (key, rec) in sorted(units.baseline.items()):
        if not key.startswith("finish."):
            by_class[rec.evidence].append(path)
    schemas = ["MaterialBindingAPI", *(f"CollectionAPI:em_{ev.name}" for ev in EM_CHART)]
    rel_spec.SetInfo("apiSchemas", Sdf.TokenListOp.Create(prependedItems=schemas))
    for ev, paths in by_class.items():
        name = f"em_{ev.name}"
        _collection(rel_spec, name).targetPathList.prependedItems = [Sdf.Path(p) for p in paths]
        rule = Sdf.AttributeSpec(
            rel_spec,
            f"collection:{name}:expansionRule",
            Sdf.ValueTypeNames.Token,
            Sdf.VariabilityUniform,
        )
        rule.default = "expandPrims"
        bind = Sdf.RelationshipSpec(rel_spec, f"material:binding:collection:{name}", custom=False)
        bind.targetPathList.explicitItems = [
            Sdf.Path(f"/Temple.collection:{name}"),
            Sdf.Path(em_material_path(ev)),
        ]
        bind.SetInfo("bindMaterialAs", "strongerThanDescendants")
    for path, (key, _) in units.baseline.items():
        if key.startswith("column."):
            col = Sdf.CreatePrimInLayer(
                gen, rel_spec.path.AppendPath(Sdf.Path(path).MakeRelativePath(Sdf.Path("/Temple")))
            )
            col.specifier = Sdf.SpecifierOver
            col.instanceable = False
    _hypothesis_moves(spec, units, ids)


def _hypothesis_moves(spec: Sdf.PrimSpec, units: Units, ids: dict[tuple[str, str], str]) -> None:
    """In each hypothesis' variant: move the parts whose class it changes."""
    for hid, touched in units.hypotheses.items():
        choice = next((s for s, h in ids.items() if h == hid), None)
        if choice is None or choice[0] not in spec.variantSets:
            continue
        variants = spec.variantSets[choice[0]].variants
        if choice[1] not in variants:
            continue
        alt = variants[choice[1]].primSpec
        for path, (_, rec) in sorted(touched.items()):
            base = units.baseline.get(path)
            if base is not None and base[1].evidence == rec.evidence:
                continue
            if base is not None:
                rel = _collection(alt, f"em_{base[1].evidence.name}")
                rel.targetPathList.deletedItems = [*rel.targetPathList.deletedItems, Sdf.Path(path)]
            rel = _collection(alt, f"em_{rec.evidence.name}")
            rel.targetPathList.appendedItems = [*rel.targetPathList.appendedItems, Sdf.Path(path)]


def annotate_hypothesis_layer(
    lay: Sdf.Layer, hid: str, paradata: Paradata | None, hypotheses: Iterable[Hypothesis]
) -> None:
    """Write hypothesis ``hid``'s record on the prims its layer touches (the shipped
    ``layers/<id>.usda`` carry their paradata as built)."""
    hyps = tuple(hypotheses)
    pd = paradata or default_paradata(hyps)
    _annotate_layer(lay, f"layers/{hid}.usda", pd, {h.id: h.id for h in hyps}, {})


def annotate_temple(
    folder: Path, paradata: Paradata | None, hypotheses: Iterable[Hypothesis]
) -> Units:
    """Write the paradata and the ``view`` variant set into the temple folder's layers."""
    hyps = tuple(hypotheses)
    pd = paradata or default_paradata(hyps)
    ids = {h.id: h.id for h in hyps}
    sets = {choice: hid for hid, choice in hyp_choices(hyps).items()}
    units = Units()
    for path in _layer_files(folder):
        rel = path.relative_to(folder).as_posix()
        lay = Sdf.Layer.FindOrOpen(str(path))
        found = _annotate_layer(lay, rel, pd, ids, sets)
        if rel == "materials.usda":
            found += _finish_overs(lay, pd)
            _em_materials(lay)

        for p, key, hid, rec in found:
            if hid:
                units.hypotheses.setdefault(hid, {})[p] = (key, rec)
            else:
                units.baseline.setdefault(p, (key, rec))
        lay.Save()
    gen = Sdf.Layer.FindOrOpen(str(folder / "generated.usda"))
    _view_variants(gen, units, sets)
    gen.Save()
    return units
