"""Stable prim paths for an asset's variants: every variant swaps what is under a path.

An asset's meshes and instancers (:class:`ionic_usd.blueprint.asset.AssetMesh`, ``AssetInstancer``)
are authored once each in a *library*, the class prim ``/_<Name>Parts`` of ``Geometry.usdc``
(outside the default prim, so a payload or reference of the asset never composes it). The
composed asset has one prim per *slot* — ``Geom/<Part>`` for a mesh part, ``Geom/<Part>/<Kind>``
for an instancer (``Geom/Ornament/EggAndDart``), ``Proxy/<Part>`` for the proxy of a mesh part
— and variants nested by name in ``Contents.usda`` point each slot at the library item its
selection asks for (an internal reference, Kitchen_set style). Switching a variant changes what
a slot references, never the slot's path: an override, a collection or a light link keyed by a
path keeps working under every selection.

A slot depends on the sets its items are tagged with (a shaft on ``flutes``, ``form`` and
``lod``); its variants nest in the asset's set order with ``lod`` innermost, so the render
slot and its proxy share their outer variants. A selection for which a slot has no item (the
carved ornament exists in the ``high`` lod only) references the item of the nearest selection
(the same tags but ``lod``) made invisible: the path and its children stay, nothing is drawn
and nothing is bounded.
"""

from __future__ import annotations

import itertools
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
from pxr import Gf, Sdf, Usd, UsdGeom

__all__ = ["Slot", "library_path", "slots", "author_slot_variants", "slot_extents_hints"]

Combo = tuple[str, ...]


@dataclass(frozen=True)
class Slot:
    """One stable prim (``rel``: its path relative to the asset root), the sets it depends on
    (innermost last) and, per combination of those sets, the library item it references and
    whether that item is drawn there."""

    rel: str
    purpose: str  # "render" | "proxy"
    sets: tuple[str, ...]
    items: Mapping[Combo, tuple[str, bool]]  # combination -> (library path, visible)
    type_name: str


def library_path(name: str) -> str:
    """The class prim holding every mesh and instancer of asset ``name`` once."""
    return f"/_{name}Parts"


def _slot_name(item) -> str:
    slot = getattr(item, "slot", "")
    if slot:
        return slot
    if type(item).__name__ == "AssetInstancer":
        return f"{item.part}/{item.name.split('_')[0]}"
    return item.part


def _ordered(sets: set[str], order: Sequence[str]) -> tuple[str, ...]:
    out = [s for s in order if s in sets and s != "lod"]
    return (*out, "lod") if "lod" in sets else tuple(out)


def _pick(items: Sequence, combo: dict[str, str]):
    """The item whose tags match ``combo`` (visible), else one matching all tags but ``lod``
    (invisible), else None."""
    for it in items:
        if all(combo.get(k, v) == v for k, v in it.tags.items()):
            return it, True
    for it in items:
        if all(combo.get(k, v) == v for k, v in it.tags.items() if k != "lod"):
            return it, False
    return None, False


def slots(
    name: str,
    tagged: Sequence,
    variant_sets: Mapping[str, Sequence[str]],
    proxy_lod: str | None,
) -> list[Slot]:
    """The stable slots of an asset's tagged items (meshes and instancers)."""
    lib = library_path(name)
    groups: dict[str, list] = {}
    for it in tagged:
        groups.setdefault(_slot_name(it), []).append(it)
    order = list(variant_sets)
    out: list[Slot] = []
    for slot, items in groups.items():
        sets = _ordered({k for it in items for k in it.tags}, order)
        is_mesh = type(items[0]).__name__ == "AssetMesh"
        kinds = [("Geom", "render", sets, items)]
        if proxy_lod is not None and is_mesh:
            low = [it for it in items if it.tags.get("lod") == proxy_lod]
            kinds.append(("Proxy", "proxy", tuple(s for s in sets if s != "lod"), low))
        for scope, purpose, ss, pool in kinds:
            table: dict[Combo, tuple[str, bool]] = {}
            for combo in itertools.product(*(variant_sets[s] for s in ss)):
                it, visible = _pick(pool, dict(zip(ss, combo, strict=True)))
                if it is None:
                    raise ValueError(f"asset {name}: no item for {scope}/{slot} at {combo}")
                table[combo] = (f"{lib}/{it.part}/{it.name}", visible)
            rel = f"{scope}/{slot}" if scope == "Geom" else f"Proxy/{slot.split('/')[-1]}"
            out.append(Slot(rel, purpose, ss, table, "Mesh" if is_mesh else "PointInstancer"))
    return out


def _variant_prim(spec: Sdf.PrimSpec, vset: str, variant: str) -> Sdf.PrimSpec:
    vs = spec.variantSets.get(vset)
    if vs is None:
        vs = Sdf.VariantSetSpec(spec, vset)
        spec.variantSetNameList.Append(vset)
    var = vs.variants.get(variant)
    if var is None:
        var = Sdf.VariantSpec(vs, variant)
    return var.primSpec


def _over_path(spec: Sdf.PrimSpec, rel: str) -> Sdf.PrimSpec:
    for part in rel.split("/"):
        child = spec.nameChildren.get(part)
        if child is None:
            child = Sdf.PrimSpec(spec, part, Sdf.SpecifierOver)
        spec = child
    return spec


def author_slot_variants(
    layer: Sdf.Layer, root: str, all_slots: Sequence[Slot], defaults: Mapping[str, str]
) -> None:
    """Define every slot under ``root`` in ``layer`` (typed, with its purpose on its scope; a
    render mesh's ``proxyPrim`` names its proxy) and, nested in the variants of its sets, the
    internal reference to its item (``visibility = invisible`` where it has none)."""
    root_spec = layer.GetPrimAtPath(root)
    rels = {s.rel for s in all_slots}
    with Sdf.ChangeBlock():
        for scope, purpose in (("Geom", "render"), ("Proxy", "proxy")):
            if any(r.startswith(scope + "/") for r in rels):
                sc = Sdf.CreatePrimInLayer(layer, f"{root}/{scope}")
                sc.specifier, sc.typeName = Sdf.SpecifierDef, "Scope"
                Sdf.AttributeSpec(
                    sc, "purpose", Sdf.ValueTypeNames.Token, Sdf.VariabilityUniform
                ).default = purpose
        for s in all_slots:
            path = Sdf.Path(f"{root}/{s.rel}")
            for anc in path.GetParentPath().GetPrefixes():
                a = layer.GetPrimAtPath(anc) or Sdf.CreatePrimInLayer(layer, anc)
                if not a.typeName and a.path != Sdf.Path(root):
                    a.specifier, a.typeName = Sdf.SpecifierDef, "Scope"
            spec = Sdf.CreatePrimInLayer(layer, path)
            spec.specifier, spec.typeName = Sdf.SpecifierDef, s.type_name
            proxy = f"Proxy/{s.rel.split('/')[-1]}"
            if s.purpose == "render" and proxy in rels:
                rel = Sdf.RelationshipSpec(spec, "proxyPrim", custom=False)
                rel.targetPathList.explicitItems = [Sdf.Path(f"{root}/{proxy}")]
            for combo, (target, visible) in s.items.items():
                v = root_spec
                for n, val in zip(s.sets, combo, strict=True):
                    v = _variant_prim(v, n, val)
                leaf = _over_path(v, s.rel)
                leaf.referenceList.Prepend(Sdf.Reference(primPath=Sdf.Path(target)))
                if not visible:
                    Sdf.AttributeSpec(
                        leaf, "visibility", Sdf.ValueTypeNames.Token
                    ).default = UsdGeom.Tokens.invisible
        for n, v in defaults.items():
            if n in root_spec.variantSets:
                root_spec.variantSelections[n] = v


def _item_ranges(geometry: str, paths: set[str]) -> dict[str, Gf.Range3d]:
    """Each library item's untransformed bound (every purpose but guide), the library made
    concrete in a session layer of a stage on ``geometry`` (a class prim is not bounded)."""
    stage = Usd.Stage.Open(geometry, Usd.Stage.LoadAll)
    session = stage.GetSessionLayer()
    libs = {Sdf.Path(p).GetPrefixes()[0] for p in paths}
    for lib in libs:
        Sdf.CreatePrimInLayer(session, lib).specifier = Sdf.SpecifierDef
    cache = UsdGeom.BBoxCache(
        Usd.TimeCode.Default(), ["default", "render", "proxy"], useExtentsHint=False
    )
    return {
        p: cache.ComputeUntransformedBound(stage.GetPrimAtPath(p)).ComputeAlignedRange()
        for p in paths
    }


def slot_extents_hints(
    geometry: str, root: str, all_slots: Sequence[Slot], vsets: Mapping[str, Sequence[str]]
) -> dict[Combo, dict[str, np.ndarray]]:
    """``extentsHint`` of ``root`` for every combination of ``vsets``: per purpose, the union
    of the bounds of the items its slots reference (the slots carry no transform, so this is
    what ``UsdGeom.BBoxCache`` computes on the composed asset)."""
    from ionic_usd.usd.bounds import _hint

    ranges = _item_ranges(geometry, {t for s in all_slots for t, _ in s.items.values()})
    purposes = list(UsdGeom.Imageable.GetOrderedPurposeTokens())
    names = list(vsets)
    out: dict[Combo, dict[str, np.ndarray]] = {}
    for combo in itertools.product(*(vsets[n] for n in names)):
        sel = dict(zip(names, combo, strict=True))
        per = {p: Gf.Range3d() for p in purposes}
        for s in all_slots:
            target, visible = s.items[tuple(sel[n] for n in s.sets)]
            if visible:
                per[s.purpose].UnionWith(ranges[target])
        out[combo] = {root: _hint([per[p] for p in purposes])}
    return out
