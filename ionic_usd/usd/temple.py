"""The temple composer: an assembly of layers that instances the column asset.

Folder written by :func:`compose_temple` (all asset paths ``./``-relative)::

    Temple.usda          root layer: /Temple (Xform, kind = assembly); sublayer ./overrides.usda;
                         references the part layers; one variant set per reconstruction hypothesis
    overrides.usda       the user's layer — created empty once, never written again
    materials.usda       /Temple/Materials: PaintedStucco, Travertine (UsdPreviewSurface)
    podium.usda cella.usda entablature.usda roof.usda
                         cuboid meshes (/Temple/Podium/…, kind = component)
    colonnade.usda       /Temple/Colonnade/{Free,Engaged,Corner}/<name>: instanceable references
                         to ./IonicColumn/IonicColumn.usda (form = full | engaged | corner)
    layers/<id>.usda     one layer per reconstruction hypothesis (overs only)
    IonicColumn/         the column component asset (see :mod:`ionic_usd.usd.column_asset`)
    Textures/            stone maps of the temple's materials

Strength, strongest first (USD's LIVRPS): the user's ``overrides.usda`` (a local sublayer), the
selected hypothesis layers (references inside variants of /Temple), then the part layers
(references of /Temple). So a hypothesis overrides the baseline and the user overrides both;
regenerating the temple rewrites every file but ``overrides.usda``, which is kept byte for byte.

Reconstruction hypotheses (London Charter, principles 4 and 6 — intellectual transparency): each
``[[hypothesis]]`` of the temple description becomes the variant set ``hyp_<id>`` on /Temple with
the variants ``baseline`` (no opinion) and ``alternative`` (references ``layers/<id>.usda``). Every
prim a hypothesis layer touches carries ``customData["ionic_usd"]["hypothesis"]`` with its id,
description, certainty and sources, and /Temple's customData lists all hypotheses — those the
generator cannot realise yet are listed with ``realised = false`` and get no layer. Hypotheses
are authored independently against the baseline: selecting two that override the same prim
gives the stronger variant set's opinion (variant sets are evaluated in the listed order).
"""

from __future__ import annotations

import dataclasses
import os
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from pxr import Gf, Sdf, Tf, Usd, Vt

from ionic_usd import __version__
from ionic_usd.column.column import ColumnParams, portunus_column_params
from ionic_usd.errors import OutputExistsError, UsdAuthoringError
from ionic_usd.geometry.mesh import Mesh
from ionic_usd.temple.cuboid import cuboid_mesh
from ionic_usd.temple.layout import ColumnKind, Hypothesis, Layer, TempleLayout, build_layout
from ionic_usd.usd.asset import replace_folder
from ionic_usd.usd.column_asset import (
    ASSET_NAME,
    FINISHES,
    TILE_METRES,
    ColumnAssetOptions,
    build_column_asset,
    copy_stone_textures,
)
from ionic_usd.usd.detail import add_detail
from ionic_usd.usd.materials import MaterialTextures, author_preview_material, bind_material
from ionic_usd.usd.mesh import author_mesh, define_prim
from ionic_usd.usd.stage import new_layer, save_layer

__all__ = ["TempleReport", "compose_temple", "hypothesis_layers", "ROOT_LAYER",
           "OVERRIDES_LAYER", "PART_LAYERS"]

ROOT_LAYER = "Temple.usda"
OVERRIDES_LAYER = "overrides.usda"
PART_LAYERS = {Layer.PODIUM: "podium.usda", Layer.CELLA: "cella.usda",
               Layer.ENTABLATURE: "entablature.usda", Layer.ROOF: "roof.usda"}
_PRIM = {Layer.PODIUM: "Podium", Layer.CELLA: "Cella", Layer.ENTABLATURE: "Entablature",
         Layer.ROOF: "Roof"}
# baseline finish: the ancient painted stucco (see portunus.toml); bare stone is a hypothesis
BASELINE_FINISH = "stucco"


@dataclass(frozen=True)
class TempleReport:
    root: Path
    files: int
    prims: int
    instances: int
    prototypes: int
    triangles: int
    hypotheses: tuple[str, ...]
    seconds: float


def _ident(name: str) -> str:
    return Tf.MakeValidIdentifier(name)


def _hyp_set(h: Hypothesis) -> str:
    return "hyp_" + _ident(h.id)


def _hyp_meta(h: Hypothesis) -> dict:
    return {"hypothesis": {"id": h.id, "description": " ".join(h.description.split()),
                           "certainty": str(h.certainty),
                           "sources": Vt.StringArray(list(h.sources))}}


def _cuboid_meshes(layout: TempleLayout) -> dict[Layer, dict[str, Mesh]]:
    return {layer: {_ident(c.name): cuboid_mesh(c, uv_scale=1.0 / TILE_METRES)
                    for c in cs} for layer, cs in layout.cuboids.items()}


def _part_layer(layer: Layer, meshes: dict[str, Mesh], material: str) -> Sdf.Layer:
    lay = new_layer("Temple", kind=None)
    root = f"/Temple/{_PRIM[layer]}"
    with Sdf.ChangeBlock():
        spec = define_prim(lay, root, "Xform")
        spec.kind = "component"
        for name, m in meshes.items():
            author_mesh(lay, f"{root}/{name}", m)
    stage = Usd.Stage.Open(lay)
    bind_material(stage.GetPrimAtPath(root), f"/Temple/Materials/{material}")
    return lay


def _materials_layer() -> Sdf.Layer:
    lay = new_layer("Temple", kind=None)
    stage = Usd.Stage.Open(lay)
    stage.DefinePrim("/Temple/Materials", "Scope")
    for mat, style in FINISHES.values():
        tex = MaterialTextures(*(f"./Textures/{style}_{r}.png"
                                 for r in ("basecolor", "roughness", "normal")))
        author_preview_material(stage, f"/Temple/Materials/{mat}", tex)
    return lay


def _set_xform(spec: Sdf.PrimSpec, pos, rot_deg: float, scale: float) -> None:
    T = Sdf.ValueTypeNames
    Sdf.AttributeSpec(spec, "xformOp:translate", T.Double3).default = Gf.Vec3d(*pos)
    Sdf.AttributeSpec(spec, "xformOp:rotateY", T.Float).default = float(rot_deg)
    Sdf.AttributeSpec(spec, "xformOp:scale", T.Float3).default = Gf.Vec3f(scale, scale, scale)
    Sdf.AttributeSpec(spec, "xformOpOrder", T.TokenArray, Sdf.VariabilityUniform).default = \
        Vt.TokenArray(["xformOp:translate", "xformOp:rotateY", "xformOp:scale"])


def _colonnade_layer(layout: TempleLayout) -> Sdf.Layer:
    lay = new_layer("Temple", kind=None)
    with Sdf.ChangeBlock():
        col = define_prim(lay, "/Temple/Colonnade", "Xform")
        col.kind = "group"
        for kind, group in _GROUPS:
            g = define_prim(lay, f"/Temple/Colonnade/{group}", "Xform")
            g.kind = "group"
            for c in layout.columns_of(kind):
                spec = define_prim(lay, f"/Temple/Colonnade/{group}/{_ident(c.name)}", "Xform")
                spec.instanceable = True
                spec.referenceList.Prepend(Sdf.Reference(f"./{ASSET_NAME}/{ASSET_NAME}.usda"))
                spec.variantSelections["form"] = _FORM[kind]
                spec.variantSelections["finish"] = BASELINE_FINISH
                _set_xform(spec, c.position, c.rotation_deg, c.scale)
    return lay


_GROUPS = ((ColumnKind.FREE, "Free"), (ColumnKind.ENGAGED, "Engaged"),
           (ColumnKind.CORNER, "Corner"))
_FORM = {ColumnKind.FREE: "full", ColumnKind.ENGAGED: "engaged", ColumnKind.CORNER: "corner"}


def _column_path(c) -> str:
    return f"/Temple/Colonnade/{dict(_GROUPS)[c.kind]}/{_ident(c.name)}"


def _column_prims(layout: TempleLayout) -> list[str]:
    out = []
    for kind, group in _GROUPS:
        out += [f"/Temple/Colonnade/{group}/{_ident(c.name)}" for c in layout.columns_of(kind)]
    return out


def _over_path(lay: Sdf.Layer, path: str) -> Sdf.PrimSpec:
    spec = lay.GetPrimAtPath(path)
    if spec is None:
        spec = Sdf.CreatePrimInLayer(lay, path)
        spec.specifier = Sdf.SpecifierOver
    return spec


def _hypothesis_layer(h: Hypothesis, layout: TempleLayout, base_meshes) -> Sdf.Layer | None:
    """The overs that realise ``h`` against the baseline, or None if nothing is realisable."""
    lay = Sdf.Layer.CreateAnonymous(".usda")
    lay.defaultPrim = "Temple"
    top = Sdf.CreatePrimInLayer(lay, "/Temple")
    top.specifier = Sdf.SpecifierOver
    touched: list[Sdf.PrimSpec] = []
    temple_keys = [k for k in h.changes if k.split(".")[0] not in ("column", "material")]
    with Sdf.ChangeBlock():
        if temple_keys:
            alt = build_layout(layout.params, hypotheses=layout.hypotheses, apply=[h.id])
            alt_meshes = _cuboid_meshes(alt)
            for layer, meshes in alt_meshes.items():
                for name, m in meshes.items():
                    old = base_meshes[layer].get(name)
                    if old is not None and np.allclose(old.points, m.points, atol=1e-9):
                        continue
                    path = f"/Temple/{_PRIM[layer]}/{name}"
                    spec = _over_path(lay, path)
                    if old is None:
                        spec.specifier = Sdf.SpecifierDef
                    author_mesh(lay, path, m)
                    spec.specifier = Sdf.SpecifierOver if old is not None else Sdf.SpecifierDef
                    touched.append(spec)
        for key, value in h.changes.items():
            if key == "column.flute_count":
                sel = f"f{int(value)}"
                for p in _column_prims(layout):
                    spec = _over_path(lay, p)
                    spec.variantSelections["flutes"] = sel
                    touched.append(spec)
            elif key == "column.corner_capital":
                # the colonnade's corner columns get the angle capital, turned so that its two
                # volute faces (local +Z, +X) face the building's two outer sides
                for c in layout.columns:
                    if c.angle_rotation_deg is None:
                        continue
                    spec = _over_path(lay, _column_path(c))
                    spec.variantSelections["capital"] = str(value)
                    if c.angle_rotation_deg != c.rotation_deg:
                        Sdf.AttributeSpec(spec, "xformOp:rotateY", Sdf.ValueTypeNames.Float
                                          ).default = float(c.angle_rotation_deg)
                    touched.append(spec)
            elif key == "material.finish":
                finish = "travertine" if value in ("bare_stone", "travertine") else "stucco"
                for p in _column_prims(layout):
                    spec = _over_path(lay, p)
                    spec.variantSelections["finish"] = finish
                    touched.append(spec)
                for layer in layout.cuboids:
                    spec = _over_path(lay, f"/Temple/{_PRIM[layer]}")
                    rel = Sdf.RelationshipSpec(spec, "material:binding", custom=False)
                    rel.targetPathList.explicitItems = [
                        Sdf.Path(f"/Temple/Materials/{FINISHES[finish][0]}")]
                    spec.SetInfo("apiSchemas", Sdf.TokenListOp.Create(
                        prependedItems=["MaterialBindingAPI"]))
                    touched.append(spec)
    if not touched:
        return None
    meta = _hyp_meta(h)
    for spec in {s.path: s for s in touched}.values():
        spec.customData = {"ionic_usd": meta}
    return lay


def hypothesis_layers(layout: TempleLayout) -> dict[str, Sdf.Layer | None]:
    """Hypothesis id → the anonymous layer of overs that realises it (None: not realisable)."""
    base_meshes = _cuboid_meshes(layout)
    return {h.id: _hypothesis_layer(h, layout, base_meshes) for h in layout.hypotheses}


def _user_overrides_layer() -> Sdf.Layer:
    lay = Sdf.Layer.CreateAnonymous(".usda")
    lay.comment = ("Your overrides: the strongest layer of the temple. ionic_usd creates this "
                   "file once and never writes it again.")
    return lay


def compose_temple(
    folder: str | os.PathLike,
    layout: TempleLayout,
    column: ColumnParams | None = None,
    *,
    force: bool = False,
    texture_size: int = 1024,
    seed: int = 7,
    asset_options: ColumnAssetOptions | None = None,
    detail: str = "carved",
    mouldings=None,
) -> TempleReport:
    """Write the temple folder (see the module docstring) atomically.

    Parameters
    ----------
    folder : output folder; an existing one needs ``force`` and is replaced atomically, keeping
        its ``overrides.usda`` byte for byte
    layout : the temple (e.g. :func:`ionic_usd.temple.portunus_layout`)
    column : column parameters (default: Portunus proportions at the layout's column height and
        lower diameter)
    """
    t0 = time.perf_counter()
    dest = Path(folder)
    if dest.exists() and not force:
        raise OutputExistsError(f"{dest} exists; pass --force (force=True) to rebuild it "
                                f"(your {OVERRIDES_LAYER} is kept)")
    p = layout.params
    column = column or portunus_column_params(height=p.columns_height,
                                              lower_diameter=p.columns_lower_diameter)
    opts = asset_options or ColumnAssetOptions(params=column, texture_size=texture_size,
                                               seed=seed)
    if opts.params != column:
        opts = dataclasses.replace(opts, params=column)
    base_meshes = _cuboid_meshes(layout)
    hyp_layers = hypothesis_layers(layout)
    baseline_material = FINISHES[BASELINE_FINISH][0]
    stats: dict[str, object] = {}

    def build(tmp: Path) -> None:
        rep = build_column_asset(tmp / ASSET_NAME, opts)
        stats["asset"] = rep
        for _, style in FINISHES.values():
            copy_stone_textures(tmp / "Textures", style, opts.texture_size, opts.seed)
        save_layer(_materials_layer(), tmp / "materials.usda")
        for layer, meshes in base_meshes.items():
            save_layer(_part_layer(layer, meshes, baseline_material), tmp / PART_LAYERS[layer])
        save_layer(_colonnade_layer(layout), tmp / "colonnade.usda")
        for hid, lay in hyp_layers.items():
            if lay is not None:
                save_layer(lay, tmp / "layers" / f"{hid}.usda")
        root = new_layer("Temple", kind="assembly",
                         comment=f"{layout.name}, composed by ionic_usd {__version__}")
        root.subLayerPaths.append(f"./{OVERRIDES_LAYER}")
        spec = root.GetPrimAtPath("/Temple")
        spec.assetInfo = {"name": _ident(layout.name), "version": __version__,
                          "identifier": Sdf.AssetPath(f"./{ROOT_LAYER}")}
        for ref in ["./materials.usda", *(f"./{PART_LAYERS[la]}" for la in base_meshes),
                    "./colonnade.usda"]:
            spec.referenceList.Append(Sdf.Reference(ref))
        listing = {}
        for h in layout.hypotheses:
            realised = hyp_layers[h.id] is not None
            entry = dict(_hyp_meta(h)["hypothesis"])
            entry["realised"] = realised
            entry["variantSet"] = _hyp_set(h) if realised else ""
            listing[_ident(h.id)] = entry
            if not realised:
                continue
            vs = Sdf.VariantSetSpec(spec, _hyp_set(h))
            spec.variantSetNameList.Append(_hyp_set(h))
            Sdf.VariantSpec(vs, "baseline")
            alt = Sdf.VariantSpec(vs, "alternative")
            alt.primSpec.referenceList.Prepend(Sdf.Reference(f"./layers/{h.id}.usda"))
            spec.variantSelections[_hyp_set(h)] = "baseline"
        spec.customData = {"ionic_usd": {"hypotheses": listing, "temple": layout.name,
                                         "baseline_finish": BASELINE_FINISH}}
        add_detail(tmp, root, layout, texture_size=opts.texture_size, seed=opts.seed,
                   mouldings=mouldings, default=detail)  # ionic_usd.usd.detail
        save_layer(root, tmp / ROOT_LAYER)
        # created only where absent: an existing overrides.usda (or symlink) is never touched
        save_layer(_user_overrides_layer(), tmp / OVERRIDES_LAYER)
        _check_resolves(tmp / ROOT_LAYER)

    replace_folder(build, dest, force=force, keep_existing=(OVERRIDES_LAYER,),
                   root_files=(ROOT_LAYER,))
    root_path = dest / ROOT_LAYER
    stage = Usd.Stage.Open(str(root_path))
    if stage is None:
        raise UsdAuthoringError(f"cannot open the temple written at {root_path}")
    return _report(stage, dest, layout, time.perf_counter() - t0)


def _check_resolves(root: Path) -> None:
    """Every layer and asset the temple refers to must resolve (before it is moved in place):
    an unresolved column reference would otherwise compose to an empty colonnade."""
    from pxr import UsdUtils

    _, _, unresolved = UsdUtils.ComputeAllDependencies(Sdf.AssetPath(str(root)))
    if unresolved:
        raise UsdAuthoringError(f"the temple refers to files that do not resolve: "
                                f"{', '.join(sorted(unresolved))}")
    stage = Usd.Stage.Open(str(root))
    for prim in stage.GetPrimAtPath("/Temple/Colonnade").GetAllChildren():
        for inst in prim.GetChildren():
            if not inst.IsInstance() or not inst.GetPrototype().GetChildren():
                raise UsdAuthoringError(f"column instance {inst.GetPath()} composed to nothing")


def _report(stage: Usd.Stage, dest: Path, layout: TempleLayout, seconds: float) -> TempleReport:
    prims = instances = tris = 0
    proto_tris: dict[str, int] = {}
    from ionic_usd.usd.instancer import drawn_triangles  # PointInstancer copies counted

    for proto in stage.GetPrototypes():
        proto_tris[str(proto.GetPath())] = 0
    for prim in stage.Traverse():
        prims += 1
        if prim.IsInstance():
            instances += 1
    tris = drawn_triangles(stage.GetPseudoRoot())
    files = sum(1 for f in dest.rglob("*") if f.is_file())
    return TempleReport(dest / ROOT_LAYER, files, prims, instances, len(proto_tris), tris,
                        tuple(h.id for h in layout.hypotheses), seconds)
