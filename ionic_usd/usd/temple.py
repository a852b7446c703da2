"""The temple composer: an assembly of layers that instances the column asset.

Folder written by :func:`ionic_usd.pipeline.temple.compose_temple` (layers authored here by
:func:`write_temple` from a :class:`~ionic_usd.blueprint.temple_plan.TemplePlan`; all asset
paths relative)::

    Temple.usda          the root: stage metadata and two sublayers, nothing else —
                           ./overrides.usda (yours, strongest) over ./generated.usda
    overrides.usda       the user's layer — created once, never written again
    generated.usda       /Temple (Xform, kind = assembly, inherits /_class_Temple): references
                         the part layers; variant sets ``lod`` (high/medium/low, passed to every
                         column) and ``hyp_<id>`` per reconstruction hypothesis; extentsHint
                         per combination that changes bounds (nested variants)
    materials.usda       /Temple/Materials: a reference to the column asset's material library
                         (./IonicColumn/Payload/Materials.usda) — one library, one copy of maps
    podium.usda cella.usda entablature.usda roof.usda
                         cuboid meshes (/Temple/Podium/…, kind = component); each sublayers
                         ./materials.usda, so its material binding resolves when opened alone
    colonnade.usda       /Temple/Colonnade (group)/{Free,Engaged,Corner} (group)/<name>:
                         instanceable references to ./IonicColumn/IonicColumn.usda
                         (form = full | engaged | corner)
    layers/<id>.usda     one layer per realised hypothesis (see :mod:`ionic_usd.usd.hypotheses`)
    layers/<a>+<b>.usda  combined values of hypotheses that interact (only when needed)
    IonicColumn/         the column component asset (see :mod:`ionic_usd.usd.column_asset`)

Every layer opened alone is a valid stage: ``defaultPrim`` /Temple (a typed Xform, kind =
assembly), ``upAxis`` Y, ``metersPerUnit`` 1.

Strength, strongest first: ``overrides.usda`` (a stronger sublayer of the root, so a variant
selection, a visibility or a new prim authored there wins over everything generated),
``generated.usda`` (its variant selections are the defaults), the selected hypothesis layers
(references inside variants of /Temple), the part layers (references of /Temple). Rebuilding
rewrites every file but ``overrides.usda``, which is kept byte for byte.

Reconstruction hypotheses (London Charter, principles 4 and 6 — intellectual transparency): each
``[[hypothesis]]`` of the temple description becomes the variant set ``hyp_<id>`` on /Temple with
the variants ``baseline`` and ``alternative``. Any combination may be selected: every
combination is composed at build time and compared with the layout built with those
hypotheses applied. /Temple's customData lists all hypotheses; those the generator cannot
realise yet are listed with ``realised = false`` and get no layer.

``class`` prims: /_class_Temple (inherited by /Temple) and /_class_IonicColumn (inherited by
every column through the asset): an opinion authored on a class in ``overrides.usda`` changes
every temple or column of the scene at once. The column class carries the binding of every
column into the temple's library, per ``finish`` (:func:`_bind_finishes`).
"""

from __future__ import annotations

import logging
import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from pxr import Sdf, Usd

from ionic_usd import __version__
from ionic_usd.blueprint.column_asset import FINISHES, ColumnAssetOptions
from ionic_usd.blueprint.hypotheses import HypothesisChanges
from ionic_usd.blueprint.layers import (
    ASSET_NAME,
    COLONNADE_LAYER,
    GENERATED_LAYER,
    MATERIALS_LAYER,
    OVERRIDES_LAYER,
    ROOT_LAYER,
    TEMPLE_CLASS,
)
from ionic_usd.blueprint.temple_plan import (
    BASELINE_FINISH,
    CUBOID_UV_SCALE,
    TemplePlan,
    check_hypotheses,
)
from ionic_usd.errors import UsdAuthoringError
from ionic_usd.temple.layout import Layer, TempleLayout
from ionic_usd.usd.asset import class_path
from ionic_usd.usd.bounds import (
    author_extents_hints,
    bound_changing_sets,
    variant_extents_hints,
)
from ionic_usd.usd.combinations import realise_combinations, select_variants
from ionic_usd.usd.detail import (
    DETAIL_LAYER,
    DETAIL_SET,
    TERRACOTTA,
    author_detail_variants,
    detail_layer,
    write_frieze_hypotheses,
)
from ionic_usd.usd.hypotheses import (
    FORMS,
    GROUPS,
    PART_PRIMS,
    column_path,
    column_xform,
    hyp_choices,
    hyp_ident,
    hypothesis_layer,
    hypothesis_paradata,
)
from ionic_usd.usd.instancer import drawn_triangles
from ionic_usd.usd.materials import bind_material_spec, stone_material
from ionic_usd.usd.mesh import author_mesh, define_prim
from ionic_usd.usd.paradata import annotate_hypothesis_layer, annotate_temple
from ionic_usd.usd.stage import new_layer, save_layer

log = logging.getLogger(__name__)

__all__ = [
    "write_temple",
    "temple_counts",
    "hypothesis_layers",
    "temple_triangles",
    "triangles_with",
    "ROOT_LAYER",
    "GENERATED_LAYER",
    "OVERRIDES_LAYER",
    "MATERIALS_LAYER",
    "PART_LAYERS",
    "COLONNADE_LAYER",
    "TEMPLE_CLASS",
]

PART_LAYERS = {
    Layer.PODIUM: "podium.usda",
    Layer.CELLA: "cella.usda",
    Layer.ENTABLATURE: "entablature.usda",
    Layer.ROOF: "roof.usda",
}
ASSET_REF = f"./{ASSET_NAME}/{ASSET_NAME}.usda"


def _finish_materials() -> dict[str, str]:
    return {fin: mat for fin, (mat, _) in FINISHES.items()}


def hypothesis_layers(
    layout: TempleLayout,
    opts: ColumnAssetOptions | None = None,
    changes: Mapping[str, HypothesisChanges] | None = None,
) -> dict[str, Sdf.Layer | None]:
    """Hypothesis id → the anonymous layer that realises it (None: not realisable).

    ``changes``: the hypotheses' checked changes (a plan's); without them they are checked
    here, and a change the generator cannot realise raises :class:`ParameterError`.
    """
    opts = opts or ColumnAssetOptions()
    changes = check_hypotheses(layout, opts) if changes is None else changes
    out = {
        h.id: hypothesis_layer(
            [h],
            layout,
            changes=changes,
            uv_scale=CUBOID_UV_SCALE,
            asset_ref=ASSET_REF.replace("./", "../", 1),
            materials_ref=f"../{MATERIALS_LAYER}",
            finish_materials=_finish_materials(),
            column_height=layout.params.columns_height,
        )
        for h in layout.hypotheses
    }
    for hid, lay in out.items():  # each carries its hypothesis' paradata as shipped
        if lay is not None:
            annotate_hypothesis_layer(lay, hid, layout.paradata, layout.hypotheses)
    return out


def _materials_layer() -> Sdf.Layer:
    """The temple's one material library: the column asset's (stucco, travertine: one copy of
    their maps) and the roof's Terracotta."""
    lay = new_layer(
        "Temple",
        kind="assembly",
        comment="the temple's materials: the column "
        "asset's material library (one copy of every texture map) and Terracotta",
    )
    stage = Usd.Stage.Open(lay)
    stage.DefinePrim("/Temple/Materials", "Scope")
    stone_material(stage, f"/Temple/Materials/{TERRACOTTA[0]}", TERRACOTTA[1])
    del stage
    # after the stage: the asset is not on disk yet
    spec = lay.GetPrimAtPath("/Temple/Materials")
    spec.referenceList.Prepend(
        Sdf.Reference(
            f"./{ASSET_NAME}/Payload/Materials.usda", Sdf.Path(f"/{ASSET_NAME}/Materials")
        )
    )
    return lay


def _part_layer(layer: Layer, meshes: dict, material: str) -> Sdf.Layer:
    lay = new_layer("Temple", kind="assembly")
    lay.subLayerPaths.append(f"./{MATERIALS_LAYER}")
    root = f"/Temple/{PART_PRIMS[layer]}"
    with Sdf.ChangeBlock():
        spec = define_prim(lay, root, "Xform")
        spec.kind = "component"
        for name, m in meshes.items():
            author_mesh(lay, f"{root}/{name}", m)
        bind_material_spec(spec, f"/Temple/Materials/{material}")
    return lay


def _bind_finishes(spec: Sdf.PrimSpec) -> None:
    """Bind every column to the temple's one library, per finish: on the column class
    ``spec`` (``/_class_IonicColumn``, inherited by every column), each value of the asset's
    ``finish`` set binds the column's root ``strongerThanDescendants`` to
    ``/Temple/Materials/<material>``. The set has the asset's name, so a column's one
    selection switches both; and on the class, not on each column, so the columns still
    share their prototypes (a variant on an instance's own root would make it unique).

    UsdShade resolves every mesh of every column to the temple's library. The asset keeps its
    own library and bindings (it opens alone, Kitchen_set style), which a client that reads
    an instance's prototype alone, such as Blender, still uses: such a client cannot see a
    binding on the instance."""
    vs = spec.variantSets.get("finish") or Sdf.VariantSetSpec(spec, "finish")
    if "finish" not in spec.variantSetNameList.prependedItems:
        spec.variantSetNameList.Prepend("finish")
    for finish, material in _finish_materials().items():
        var = vs.variants.get(finish) or Sdf.VariantSpec(vs, finish)
        bind_material_spec(var.primSpec, f"/Temple/Materials/{material}", stronger=True)


def _colonnade_layer(layout: TempleLayout) -> Sdf.Layer:
    lay = new_layer("Temple", kind="assembly")
    typed = getattr(layout.params, "vitruvian", None) is not None
    with Sdf.ChangeBlock():
        col = define_prim(lay, "/Temple/Colonnade", "Xform")
        col.kind = "group"
        for kind, group in GROUPS.items():
            g = define_prim(lay, f"/Temple/Colonnade/{group}", "Xform")
            g.kind = "group"
            for c in layout.columns_of(kind):
                spec = define_prim(lay, column_path(c), "Xform")
                spec.instanceable = True
                spec.referenceList.Prepend(Sdf.Reference(ASSET_REF))
                spec.variantSelections["form"] = FORMS[kind]
                spec.variantSelections["finish"] = BASELINE_FINISH
                if typed and c.angle_rotation_deg is not None:
                    # a typed temple's peristyle turns its corners on angle capitals (the
                    # layout already turned the column: rotation_deg = angle_rotation_deg)
                    spec.variantSelections["capital"] = "angle"
                column_xform(spec, c.position, c.rotation_deg, c.scale)
    return lay


def _root_layer(name: str) -> Sdf.Layer:
    """Temple.usda: stage metadata and the two sublayers, user's first (strongest)."""
    lay = Sdf.Layer.CreateAnonymous(".usda")
    lay.defaultPrim = "Temple"
    lay.pseudoRoot.SetInfo("upAxis", "Y")
    lay.pseudoRoot.SetInfo("metersPerUnit", 1.0)
    lay.comment = (
        f"{name}, composed by ionic_usd {__version__}. Put your edits in "
        f"{OVERRIDES_LAYER} (the strongest layer, never rewritten)."
    )
    lay.subLayerPaths.append(f"./{OVERRIDES_LAYER}")
    lay.subLayerPaths.append(f"./{GENERATED_LAYER}")
    return lay


def _user_overrides_layer() -> Sdf.Layer:
    lay = new_layer(
        "Temple",
        kind=None,
        comment=(
            "Your overrides: the strongest layer of the temple. ionic_usd creates this file once "
            "and never writes it again. Author `over` opinions below /Temple, or on "
            "/_class_IonicColumn to change every column at once."
        ),
    )
    return lay


def _generated_layer(
    layout: TempleLayout, hyp_layers: dict[str, Sdf.Layer | None], lods: Sequence[str]
) -> Sdf.Layer:
    lay = new_layer(
        "Temple",
        kind="assembly",
        comment=f"{layout.name}, generated by ionic_usd {__version__}; "
        f"do not edit (rewritten on every build): edit {OVERRIDES_LAYER}",
    )
    spec = lay.GetPrimAtPath("/Temple")
    spec.assetInfo = {
        "name": hyp_ident(layout.name),
        "version": __version__,
        "identifier": Sdf.AssetPath(f"./{ROOT_LAYER}"),
    }
    cls = Sdf.CreatePrimInLayer(lay, TEMPLE_CLASS)
    cls.specifier = Sdf.SpecifierClass
    spec.inheritPathList.Prepend(Sdf.Path(TEMPLE_CLASS))
    col_cls = Sdf.CreatePrimInLayer(lay, class_path(ASSET_NAME))
    col_cls.specifier = Sdf.SpecifierClass
    _bind_finishes(col_cls)
    for ref in [
        f"./{MATERIALS_LAYER}",
        *(f"./{PART_LAYERS[la]}" for la in layout.cuboids),
        f"./{COLONNADE_LAYER}",
        f"./{DETAIL_LAYER}",
    ]:
        spec.referenceList.Append(Sdf.Reference(ref))
    # lod: one selection on /Temple passes to every column (a far temple is light)
    vs = Sdf.VariantSetSpec(spec, "lod")
    spec.variantSetNameList.Append("lod")
    for lod in lods:
        var = Sdf.VariantSpec(vs, lod)
        for c in layout.columns:
            over = Sdf.CreatePrimInLayer(
                lay,
                var.path.AppendPath(Sdf.Path(column_path(c)).MakeRelativePath(Sdf.Path("/Temple"))),
            )
            over.specifier = Sdf.SpecifierOver
            over.variantSelections["lod"] = lod
    spec.variantSelections["lod"] = lods[0]
    listing = {}
    choices = hyp_choices(layout.hypotheses)  # the alternatives of a question share one set
    for h in layout.hypotheses:
        realised = hyp_layers[h.id] is not None
        vset, value = choices[h.id]
        entry = dict(hypothesis_paradata(h))
        entry["realised"] = realised
        entry["variantSet"] = vset if realised else ""
        entry["variant"] = value if realised else ""
        entry["question"] = h.key
        listing[hyp_ident(h.id)] = entry
        if not realised:
            continue
        vs = spec.variantSets.get(vset)
        if vs is None:
            vs = Sdf.VariantSetSpec(spec, vset)
            spec.variantSetNameList.Append(vset)
            Sdf.VariantSpec(vs, "baseline")
        alt = Sdf.VariantSpec(vs, value)
        alt.primSpec.referenceList.Prepend(Sdf.Reference(f"./layers/{h.id}.usda"))
        spec.variantSelections[vset] = "baseline"
    spec.customData = {
        "ionic_usd": {
            "hypotheses": listing,
            "temple": layout.name,
            "baseline_finish": BASELINE_FINISH,
        }
    }
    return lay


def write_temple(plan: TemplePlan, tmp: Path) -> dict[str, Any]:
    """Author every temple layer into ``tmp`` (beside ``tmp/IonicColumn``), check every
    hypothesis combination, author the extentsHints; returns the triangles per LOD and the
    combination layers written."""
    layout, geom = plan.layout, plan.geometry
    hyp_layers = hypothesis_layers(layout, plan.opts, plan.changes)
    baseline_material = FINISHES[BASELINE_FINISH][0]
    log.info("writing the part, colonnade, detail and hypothesis layers")
    save_layer(_materials_layer(), tmp / MATERIALS_LAYER)
    save_layer(detail_layer(geom), tmp / DETAIL_LAYER)
    for layer, meshes in plan.base_meshes.items():
        save_layer(_part_layer(layer, meshes, baseline_material), tmp / PART_LAYERS[layer])
    save_layer(_colonnade_layer(layout), tmp / COLONNADE_LAYER)
    for hid, lay in hyp_layers.items():
        if lay is not None:
            save_layer(lay, tmp / "layers" / f"{hid}.usda")
    gen_layer = _generated_layer(layout, hyp_layers, plan.lods)
    spec = gen_layer.GetPrimAtPath("/Temple")
    author_detail_variants(spec, geom, plan.detail)
    frieze = write_frieze_hypotheses(tmp, spec, layout, geom)
    save_layer(gen_layer, tmp / GENERATED_LAYER)
    save_layer(_root_layer(layout.name), tmp / ROOT_LAYER)
    # created only where absent: an existing overrides.usda (or symlink) is never touched
    save_layer(_user_overrides_layer(), tmp / OVERRIDES_LAYER)
    # paradata on every part and the view variant set (ionic_usd.usd.paradata)
    annotate_temple(tmp, layout.paradata, layout.hypotheses)
    # checks and hints on the generated layer alone: the user's opinions are theirs
    # opened without payloads: the columns are bounded by the asset's extentsHints and
    # the checks compare transforms, not column geometry (composition ~30 % cheaper)
    gen = Usd.Stage.Open(str(tmp / GENERATED_LAYER), Usd.Stage.LoadNone)
    realised = [h for h in layout.hypotheses if hyp_layers[h.id] is not None or h in frieze]
    log.info("checking the combinations of %d hypotheses x detail", len(realised))
    combos = realise_combinations(
        gen, tmp, layout, realised, uv_scale=CUBOID_UV_SCALE, detail_of=plan.detail_of
    )
    temple_sets = gen.GetPrimAtPath("/Temple").GetVariantSets()
    candidates = {
        "lod": plan.lods,
        **{
            n: tuple(temple_sets.GetVariantSet(n).GetVariantNames())
            for n in temple_sets.GetNames()
            if n.startswith("hyp_") or n == DETAIL_SET
        },
    }
    parts = [
        "/Temple",
        *(f"/Temple/{PART_PRIMS[la]}" for la in layout.cuboids),
        "/Temple/Colonnade",
    ]
    log.info("extentsHint per variant combination")
    # loaded: the hints bound the columns' geometry, not the asset's own hints (which are
    # unions over the asset's sets: a temple hint over them would not be tight)
    gen.Load()
    memo: dict[Any, Any] = {}  # the passes and the product share combinations
    vsets = bound_changing_sets(gen, "/Temple", parts, candidates, base="lod", memo=memo)
    hints = variant_extents_hints(gen, "/Temple", parts, vsets, memo=memo)
    gen_layer = gen.GetRootLayer()
    author_extents_hints(gen_layer, "/Temple", hints, list(vsets))
    gen_layer.Save()
    lod_triangles = {lod: triangles_with(gen, {"lod": lod}) for lod in plan.lods}
    del gen
    _check_resolves(tmp / ROOT_LAYER, tmp / GENERATED_LAYER)
    return {"triangles_per_lod": lod_triangles, "combination_layers": list(combos)}


# ---------------------------------------------------------------------------------------------
# checks and report


def _check_resolves(root: Path, generated: Path) -> None:
    """Every layer and asset the temple refers to must resolve (before it is moved in place):
    an unresolved column reference would otherwise compose to an empty colonnade. The columns
    are checked in the generated layer (what the user's layer does to them is theirs)."""
    from pxr import UsdUtils

    _, _, unresolved = UsdUtils.ComputeAllDependencies(Sdf.AssetPath(str(generated)))
    unresolved += [p for p in (OVERRIDES_LAYER, GENERATED_LAYER) if not (root.parent / p).is_file()]
    if unresolved:
        raise UsdAuthoringError(
            f"the temple refers to files that do not resolve: {', '.join(sorted(unresolved))}"
        )
    stage = Usd.Stage.Open(str(generated))
    for prim in stage.GetPrimAtPath("/Temple/Colonnade").GetAllChildren():
        for inst in prim.GetChildren():
            if not inst.IsInstance() or not inst.GetPrototype().GetChildren():
                raise UsdAuthoringError(f"column instance {inst.GetPath()} composed to nothing")


def temple_triangles(stage: Usd.Stage) -> int:
    """Triangles drawn by the composed stage (:func:`ionic_usd.usd.instancer.drawn_triangles`:
    every native instance and PointInstancer copy, nested ones included; default and render
    purpose, visible, active)."""
    return drawn_triangles(stage.GetPseudoRoot())


def triangles_with(stage: Usd.Stage, selections: dict[str, str]) -> int:
    """:func:`temple_triangles` with ``selections`` (variant set → variant) made on the
    default prim in the session layer, which is cleared again afterwards."""
    try:
        select_variants(stage, selections)
        return temple_triangles(stage)
    finally:
        stage.GetSessionLayer().Clear()


def temple_counts(root: str | os.PathLike) -> dict[str, int]:
    """Prims, native instances, prototypes and drawn triangles of the temple whose root layer
    is ``root``, as composed (defaults selected)."""
    stage = Usd.Stage.Open(str(root))
    if stage is None:
        raise UsdAuthoringError(f"cannot open the temple written at {root}")
    return {
        "prims": sum(1 for _ in stage.Traverse()),
        "instances": sum(1 for p in stage.Traverse() if p.IsInstance()),
        "prototypes": len(stage.GetPrototypes()),
        "triangles": temple_triangles(stage),
    }
