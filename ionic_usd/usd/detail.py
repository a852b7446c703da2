"""Architectural detail as levels of detail: the ``detail`` variant set on ``/Temple``.

Files added to a temple folder (by :func:`add_detail`, called from
:func:`ionic_usd.usd.temple.compose_temple`)::

    detail.usda          /Temple: variant set ``detail`` = plain | moulded | carved; the
                         Terracotta material; sublayers ./detail_geom.usdc
    detail_geom.usdc     the swept mouldings and the ornament PointInstancers, under the part
                         prims they belong to:
                           /Temple/Podium/Mouldings/{podium_base, podium_crown}
                           /Temple/Entablature/Mouldings/{architrave, cornice}
                           /Temple/Entablature/Ornament/Dentils          (PointInstancer)
                           /Temple/Entablature/Ornament/FriezeGarlands   (hypothesis, inactive)
                           /Temple/Roof/Mouldings/{raking_cornice_front, raking_cornice_rear}
                           /Temple/Roof/Tiles                            (PointInstancer)
    layers/<id>.detail.usda   for each hypothesis that moves the entablature or the roof: the
                         same members rebuilt for it, referenced by that hypothesis'
                         ``alternative`` variant next to its own layer
    layers/frieze-garlands.usda   the frieze relief hypothesis (``hyp_frieze_garlands``)

Variants: ``plain`` deactivates everything above (today's cuboids); ``moulded`` shows the
mouldings and deactivates the ``architrave`` and ``cornice`` cuboids they replace; ``carved``
adds the instanced dentils and roof tiles. Both detailed variants bind the podium (cuboids and
mouldings) to Travertine — the podium's facing [C] — and the tiles to Terracotta; walls,
entablature and mouldings keep the part's binding (painted stucco, or the finish hypothesis').
The column asset's ``high`` LOD carries the carved echinus and astragal
(:func:`column_ornament`, PointInstancers inside the asset).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from pxr import Sdf, Tf, Usd, Vt

from ionic_usd.column.ornament import Instances, capital_ornament
from ionic_usd.errors import ParameterError
from ionic_usd.geometry.mesh import Mesh
from ionic_usd.temple.layout import Hypothesis, Layer, TempleLayout, build_layout
from ionic_usd.temple.mouldings import (
    REPLACED_CUBOIDS,
    MouldingParams,
    moulding_meshes,
    portunus_mouldings,
)
from ionic_usd.temple.ornament import dentils, frieze_garlands, roof_tiles
from ionic_usd.usd.asset import AssetInstancer
from ionic_usd.usd.instancer import author_point_instancer, bind_spec
from ionic_usd.usd.mesh import author_mesh, define_prim
from ionic_usd.usd.stage import new_layer, save_layer

__all__ = [
    "DETAIL_SET",
    "DETAIL_VARIANTS",
    "DEFAULT_DETAIL",
    "DETAIL_LAYER",
    "DETAIL_GEOM",
    "FRIEZE_KEY",
    "DetailGeometry",
    "detail_geometry",
    "detail_counts",
    "add_detail",
    "column_ornament",
]

DETAIL_SET = "detail"
DETAIL_VARIANTS = ("plain", "moulded", "carved")
DEFAULT_DETAIL = "carved"
DETAIL_LAYER = "detail.usda"
DETAIL_GEOM = "detail_geom.usdc"
FRIEZE_KEY = "detail.frieze"  # a hypothesis change key realised here ("garlands")
TERRACOTTA = ("Terracotta", "terracotta")
_PART = {"podium": "Podium", "architrave": "Entablature", "cornice": "Entablature",
         "sima": "Entablature", "raking": "Roof"}


@dataclass(frozen=True, eq=False)
class DetailGeometry:
    """Kernel values of a temple's detail: members by part prim, ornament by prim path."""

    mouldings: dict[str, dict[str, Mesh]]  # part prim name → member name → mesh
    ornament: dict[str, Instances]  # path below /Temple → instances
    frieze: Instances
    podium_cuboids: tuple[str, ...] = field(default=())


def _ident(name: str) -> str:
    return Tf.MakeValidIdentifier(name)


def detail_geometry(layout: TempleLayout, mp: MouldingParams | None = None) -> DetailGeometry:
    """Mouldings and ornament of a layout (pure numpy; see the module docstring)."""
    from ionic_usd.usd.column_asset import TILE_METRES

    mp = mp or portunus_mouldings()
    by_part: dict[str, dict[str, Mesh]] = {}
    for m in moulding_meshes(layout, mp, uv_scale=1.0 / TILE_METRES):
        part = _PART[m.name.split("_")[0]]
        by_part.setdefault(part, {})[m.name] = m.mesh
    orn = {"Entablature/Ornament/Dentils": dentils(layout), "Roof/Tiles": roof_tiles(layout)}
    podium = tuple(_ident(c.name) for c in layout.cuboids.get(Layer.PODIUM, ()))
    return DetailGeometry(by_part, orn, frieze_garlands(layout), podium)


def detail_counts(geom: DetailGeometry) -> dict[str, dict[str, int]]:
    """Triangles, prototypes and instances each ``detail`` variant *adds* to the cuboids
    (``plain`` adds nothing; ``moulded`` adds the sweeps; ``carved`` also the ornament, its
    triangles counted over every copy)."""
    sweep_tris = sum(m.n_triangles for ms in geom.mouldings.values() for m in ms.values())
    orn = list(geom.ornament.values())
    return {
        "plain": {"triangles": 0, "prototypes": 0, "instances": 0, "meshes": 0},
        "moulded": {"triangles": sweep_tris, "prototypes": 0, "instances": 0,
                    "meshes": sum(len(ms) for ms in geom.mouldings.values())},
        "carved": {"triangles": sweep_tris + sum(i.triangles for i in orn),
                   "prototypes": sum(len(i.prototypes) for i in orn),
                   "instances": sum(len(i) for i in orn),
                   "meshes": sum(len(ms) for ms in geom.mouldings.values())},
    }


def _geom_layer(geom: DetailGeometry) -> Sdf.Layer:
    lay = new_layer("Temple", kind=None)
    with Sdf.ChangeBlock():
        for part, members in geom.mouldings.items():
            define_prim(lay, f"/Temple/{part}/Mouldings", "Xform")
            for name, m in members.items():
                author_mesh(lay, f"/Temple/{part}/Mouldings/{name}", m)
        for rel, inst in geom.ornament.items():
            author_point_instancer(lay, f"/Temple/{rel}", inst)
        spec = author_point_instancer(lay, "/Temple/Entablature/Ornament/FriezeGarlands",
                                      geom.frieze)
        spec.active = False  # the frieze-garlands hypothesis activates it
    return lay


def _over(lay: Sdf.Layer | Sdf.PrimSpec, path: str) -> Sdf.PrimSpec:
    """An ``over`` at ``path`` relative to a variant's prim spec (or a layer's root)."""
    spec = lay
    for name in path.split("/"):
        child = spec.nameChildren.get(name) if isinstance(spec, Sdf.PrimSpec) else \
            spec.GetPrimAtPath(f"/{name}")
        if child is None:
            child = Sdf.PrimSpec(spec, name, Sdf.SpecifierOver) if isinstance(
                spec, Sdf.PrimSpec) else Sdf.PrimSpec(spec, name, Sdf.SpecifierOver)
        spec = child
    return spec


def _detail_layer(geom: DetailGeometry, default: str) -> Sdf.Layer:
    from ionic_usd.usd.materials import MaterialTextures, author_preview_material

    lay = new_layer("Temple", kind=None)
    stage = Usd.Stage.Open(lay)
    stage.DefinePrim("/Temple/Materials", "Scope")
    # Terracotta is the detail's own; Travertine comes from the temple's material library
    # (materials.usda, the column asset's: one copy of its maps), so this layer is valid alone
    mat, style = TERRACOTTA
    author_preview_material(stage, f"/Temple/Materials/{mat}", MaterialTextures(
        *(f"./Textures/{style}_{r}.png" for r in ("basecolor", "roughness", "normal"))))
    del stage
    # after the stage: these are not on disk yet
    lay.subLayerPaths.append("./materials.usda")
    lay.subLayerPaths.append(f"./{DETAIL_GEOM}")
    temple = lay.GetPrimAtPath("/Temple")
    bind_spec(_over(temple, "Roof/Tiles"), f"/Temple/Materials/{TERRACOTTA[0]}")
    vs = Sdf.VariantSetSpec(temple, DETAIL_SET)
    temple.variantSetNameList.Append(DETAIL_SET)
    sweeps = [f"{part}/Mouldings" for part in geom.mouldings]
    for v in DETAIL_VARIANTS:
        prim = Sdf.VariantSpec(vs, v).primSpec
        if v == "plain":
            for p in (*sweeps, *geom.ornament):
                _over(prim, p).active = False
            continue
        for c in REPLACED_CUBOIDS:
            _over(prim, f"Entablature/{c}").active = False
        if v == "moulded":
            for p in geom.ornament:
                _over(prim, p).active = False
        travertine = "/Temple/Materials/Travertine"
        for name in geom.podium_cuboids:
            bind_spec(_over(prim, f"Podium/{name}"), travertine)
        if "Podium" in geom.mouldings:
            bind_spec(_over(prim, "Podium/Mouldings"), travertine)
    temple.variantSelections[DETAIL_SET] = default
    return lay


def _meta(h: Hypothesis) -> dict:
    return {"ionic_usd": {"hypothesis": {
        "id": h.id, "description": " ".join(h.description.split()),
        "certainty": str(h.certainty), "sources": Vt.StringArray(list(h.sources))}}}


def _hypothesis_detail_layer(h: Hypothesis, layout: TempleLayout, base: DetailGeometry,
                             mp: MouldingParams) -> Sdf.Layer | None:
    """Overs re-placing the detail for a hypothesis that moves the building (or None)."""
    import numpy as np

    alt = detail_geometry(build_layout(layout.params, hypotheses=layout.hypotheses,
                                       apply=[h.id]), mp)
    lay = Sdf.Layer.CreateAnonymous(".usda")
    lay.defaultPrim = "Temple"
    lay.pseudoRoot.SetInfo("upAxis", "Y")
    lay.pseudoRoot.SetInfo("metersPerUnit", 1.0)
    touched = []
    with Sdf.ChangeBlock():
        for part, members in alt.mouldings.items():
            for name, m in members.items():
                old = base.mouldings[part][name]
                if old.points.shape == m.points.shape and np.allclose(old.points, m.points):
                    continue
                path = f"/Temple/{part}/Mouldings/{name}"
                author_mesh(lay, path, m)
                touched.append(path)
        for rel, inst in alt.ornament.items():
            old = base.ornament[rel]
            if len(old) == len(inst) and np.allclose(old.positions, inst.positions) and \
                    np.allclose(old.orientations, inst.orientations):
                continue
            author_point_instancer(lay, f"/Temple/{rel}", inst)
            touched.append(f"/Temple/{rel}")
        if not touched:
            return None
        for p in touched:
            for anc in Sdf.Path(p).GetAncestorsRange():
                s = lay.GetPrimAtPath(anc)
                if s is not None and anc != Sdf.Path(p):
                    s.specifier = Sdf.SpecifierOver
                    s.typeName = ""
            spec = lay.GetPrimAtPath(p)
            spec.specifier = Sdf.SpecifierOver
            spec.customData = _meta(h)
    return lay


def _frieze_layer(h: Hypothesis) -> Sdf.Layer:
    lay = Sdf.Layer.CreateAnonymous(".usda")
    lay.defaultPrim = "Temple"
    lay.pseudoRoot.SetInfo("upAxis", "Y")
    lay.pseudoRoot.SetInfo("metersPerUnit", 1.0)
    spec = _over(lay, "Temple/Entablature/Ornament/FriezeGarlands")
    spec.active = True
    spec.customData = _meta(h)
    return lay


def add_detail(folder: Path, root: Sdf.Layer, layout: TempleLayout, *,
               texture_size: int = 1024, seed: int = 7,
               mouldings: MouldingParams | None = None,
               default: str = DEFAULT_DETAIL) -> DetailGeometry:
    """Write the detail layers into a temple folder being built and wire them into its root.

    Parameters
    ----------
    folder : the temple folder (its ``Textures/`` and ``layers/`` are filled too)
    root : the temple's root layer (not yet saved): gets the reference to ``detail.usda``, the
        ``detail`` selection, and the variants of the hypotheses realised here
    layout : the temple
    mouldings : the sections (default: those of ``portunus.toml``)
    default : the selected ``detail`` variant (plain, moulded, carved)
    """
    from ionic_usd.usd.column_asset import copy_stone_textures

    if default not in DETAIL_VARIANTS:
        raise ParameterError("detail", default, f"one of {', '.join(DETAIL_VARIANTS)}")
    mp = mouldings or portunus_mouldings()
    geom = detail_geometry(layout, mp)
    # tiles repeat their map every metre (stone: every TILE_METRES = 2 m): half the size keeps
    # the texel density and saves ~3 s of a cold build
    copy_stone_textures(folder / "Textures", TERRACOTTA[1], max(16, texture_size // 2), seed)
    save_layer(_geom_layer(geom), folder / DETAIL_GEOM, force=True)
    save_layer(_detail_layer(geom, default), folder / DETAIL_LAYER, force=True)
    spec = root.GetPrimAtPath("/Temple")
    spec.referenceList.Append(Sdf.Reference(f"./{DETAIL_LAYER}"))
    spec.variantSelections[DETAIL_SET] = default
    data = dict(spec.customData.get("ionic_usd", {}))
    listing = {k: dict(v) for k, v in data.get("hypotheses", {}).items()}
    for h in layout.hypotheses:
        vset = "hyp_" + _ident(h.id)
        if FRIEZE_KEY in h.changes:
            save_layer(_frieze_layer(h), folder / "layers" / f"{h.id}.usda", force=True)
            if vset not in spec.variantSets:
                vs = Sdf.VariantSetSpec(spec, vset)
                spec.variantSetNameList.Append(vset)
                Sdf.VariantSpec(vs, "baseline")
                Sdf.VariantSpec(vs, "alternative")
            alt = spec.variantSets[vset].variants["alternative"].primSpec
            alt.referenceList.Append(Sdf.Reference(f"./layers/{h.id}.usda"))
            spec.variantSelections[vset] = "baseline"
            entry = listing.setdefault(_ident(h.id), {})
            entry.update(realised=True, variantSet=vset)
            continue
        if vset not in spec.variantSets:
            continue
        lay = _hypothesis_detail_layer(h, layout, geom, mp)
        if lay is None:
            continue
        name = f"{h.id}.detail.usda"
        save_layer(lay, folder / "layers" / name, force=True)
        spec.variantSets[vset].variants["alternative"].primSpec.referenceList.Append(
            Sdf.Reference(f"./layers/{name}"))
    data["hypotheses"] = listing
    data["detail"] = {"variants": Vt.StringArray(list(DETAIL_VARIANTS)), "default": default}
    spec.customData = {"ionic_usd": data}
    return geom


def column_ornament(opts) -> tuple[AssetInstancer, ...]:
    """The carved echinus and astragal of the column asset's ``high`` LOD (PointInstancers
    tagged ``lod = high``), or nothing if the asset has no high LOD.

    Parameters
    ----------
    opts : :class:`ionic_usd.usd.column_asset.ColumnAssetOptions`
    """
    if "high" not in opts.lods:
        return ()
    p = opts.params.with_lod("high")
    y_cap = p.base_params().height + p.shaft.length
    cap = p.capital_params()
    egg, bead = capital_ornament(
        y_capital=y_cap, top_radius=p.shaft.top_radius, echinus_height=cap.echinus_height,
        echinus_projection=cap.echinus_projection, ring_top=p.shaft.ring_top,
        capital_lift=cap.capital_position_y)
    return (AssetInstancer("Ornament", "EggAndDart_high", egg, {"lod": "high"}),
            AssetInstancer("Ornament", "BeadAndReel_high", bead, {"lod": "high"}))
