"""What each hypothesis changes in a temple scene, prim by prim, and scene subsets to export.

:func:`hypothesis_changes` compares every part prim (a mesh, a point instancer, a column
instance) of the scene with a hypothesis' ``alternative`` selected against the baseline: world
transform, points, instanced positions, composed variant selections, bound material. The parts
that differ (or exist on one side only) are that hypothesis' geometry. :func:`subset_layer`
writes a layer over the scene that selects variants and deactivates every other part, so the
exporter writes just those parts (``ionic-usd web``'s toggles)."""

from __future__ import annotations

import hashlib
import os
from collections.abc import Iterable, Mapping
from pathlib import Path

import numpy as np
from pxr import Kind, Sdf, Usd, UsdGeom, UsdShade

__all__ = ["part_centres", "part_signatures", "hypothesis_changes", "lod_groups", "subset_layer"]


def _is_part(p: Usd.Prim) -> bool:
    path = str(p.GetPath())
    if "Prototypes" in path or path.startswith("/Temple/Materials"):
        return False
    return p.GetTypeName() in ("Mesh", "PointInstancer") or (
        path.startswith("/Temple/Colonnade/") and p.IsInstance()
    )


def _digest(*values: object) -> str:
    h = hashlib.sha256()
    for v in values:
        h.update(np.asarray(v if v is not None else [], dtype=np.float64).tobytes())
    return h.hexdigest()[:16]


def _signature(p: Usd.Prim, cache: UsdGeom.XformCache) -> tuple:
    m = np.array(cache.GetLocalToWorldTransform(p)).round(6)
    mat, _ = UsdShade.MaterialBindingAPI(p).ComputeBoundMaterial()
    # the visibility too: a question's alternative may show a part the others hide (the relief)
    vis = str(UsdGeom.Imageable(p).ComputeVisibility())
    sig: list = [m.tobytes(), str(mat.GetPath()) if mat else "", vis]
    if p.GetTypeName() == "Mesh":
        sig.append(_digest(UsdGeom.Mesh(p).GetPointsAttr().Get()))
    elif p.GetTypeName() == "PointInstancer":
        pi = UsdGeom.PointInstancer(p)
        sig.append(_digest(pi.GetPositionsAttr().Get(), pi.GetProtoIndicesAttr().Get()))
        for child in Usd.PrimRange(p):
            if child.GetTypeName() == "Mesh":
                sig.append(_digest(UsdGeom.Mesh(child).GetPointsAttr().Get()))
    else:
        vs = p.GetVariantSets()
        sig.append(tuple(sorted((n, vs.GetVariantSelection(n)) for n in vs.GetNames())))
    return tuple(sig)


def part_signatures(stage: Usd.Stage) -> dict[str, tuple]:
    cache = UsdGeom.XformCache()
    return {str(p.GetPath()): _signature(p, cache) for p in stage.Traverse() if _is_part(p)}


def part_centres(scene: str | os.PathLike, variants: Mapping[str, str]) -> dict[str, list[float]]:
    """World bounding-box centre of every part (render purpose), ``variants`` selected."""
    stage = Usd.Stage.Open(str(scene))
    sets = stage.GetDefaultPrim().GetVariantSets()
    for k, v in variants.items():
        if sets.HasVariantSet(k):
            sets.GetVariantSet(k).SetVariantSelection(v)
    cache = UsdGeom.BBoxCache(Usd.TimeCode.Default(), ["default", "render"])
    out = {}
    for p in stage.Traverse():
        if _is_part(p):
            c = cache.ComputeWorldBound(p).ComputeAlignedRange().GetMidpoint()
            out[str(p.GetPath())] = [round(float(x), 4) for x in c]
    return out


def lod_groups(scene: str | os.PathLike) -> list[str]:
    """The units the web view switches level of detail by: the outermost ``assembly`` models
    below the default prim (a city's temples), or the default prim itself (one temple).
    Instances of a point instancer (``/City/Porticus[3]``) are units of their own."""
    stage = Usd.Stage.Open(str(scene))
    root = stage.GetDefaultPrim()
    out = []
    it = iter(Usd.PrimRange(root))
    next(it)  # the root itself
    for p in it:
        if Usd.ModelAPI(p).GetKind() == Kind.Tokens.assembly:
            out.append(str(p.GetPath()))
            it.PruneChildren()
    return out or [str(root.GetPath())]


def hypothesis_changes(
    scene: str | os.PathLike, variants: Mapping[str, str]
) -> tuple[dict[str, list[str]], list[str]]:
    """``({"<hypothesis variant set>=<value>": [part paths it changes]}, [baseline part
    paths])`` (every value but ``baseline`` of every ``hyp_`` set) with
    ``variants`` (e.g. ``detail``, ``lod``) selected throughout."""
    stage = Usd.Stage.Open(str(scene))
    root = stage.GetDefaultPrim()
    sets = root.GetVariantSets()
    for k, v in variants.items():
        if sets.HasVariantSet(k):
            sets.GetVariantSet(k).SetVariantSelection(v)
    base = part_signatures(stage)
    out = {}
    for name in sets.GetNames():
        if not name.startswith("hyp_"):
            continue
        vset = sets.GetVariantSet(name)
        for value in vset.GetVariantNames():
            if value == "baseline":
                continue
            vset.SetVariantSelection(value)
            alt = part_signatures(stage)
            vset.SetVariantSelection("baseline")
            out[f"{name}={value}"] = sorted(
                p
                for p in {*base, *alt}
                if base.get(p) != alt.get(p) and p in alt and alt[p][2] != "invisible"
            )
    return out, sorted(base)


def subset_layer(
    scene: str | os.PathLike, out: Path, variants: Mapping[str, str], keep: Iterable[str]
) -> Path:
    """A layer over ``scene`` selecting ``variants`` on its default prim and deactivating
    every part but ``keep``."""
    stage = Usd.Stage.Open(str(scene))
    root = stage.GetDefaultPrim()
    sets = root.GetVariantSets()
    for k, v in variants.items():
        sets.GetVariantSet(k).SetVariantSelection(v)
    keep = set(keep)
    drop = [
        str(p.GetPath()) for p in stage.Traverse() if _is_part(p) and str(p.GetPath()) not in keep
    ]
    lay = Sdf.Layer.CreateAnonymous(".usda")
    lay.subLayerPaths.append(str(Path(scene).resolve()))
    lay.defaultPrim = root.GetName()
    lay.pseudoRoot.SetInfo("upAxis", UsdGeom.GetStageUpAxis(stage))
    lay.pseudoRoot.SetInfo("metersPerUnit", UsdGeom.GetStageMetersPerUnit(stage))
    spec = Sdf.CreatePrimInLayer(lay, root.GetPath())
    spec.specifier = Sdf.SpecifierOver
    for k, v in variants.items():
        spec.variantSelections[k] = v
    for path in drop:
        over = Sdf.CreatePrimInLayer(lay, path)
        over.specifier = Sdf.SpecifierOver
        over.active = False
    lay.Export(str(out))
    return out
