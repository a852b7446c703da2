"""Architectural detail as levels of detail: the ``detail`` variant set on ``/Temple``.

Files of a temple folder that hold the detail (written by :func:`write_detail`, called from
:func:`ionic_usd.pipeline.temple.compose_temple`)::

    detail.usdc          the swept mouldings and the ornament PointInstancers, as ``def`` prims
                         under the part prims they belong to (a crate file: ~8k points):
                           /Temple/Podium/Mouldings/{podium_base, podium_crown}
                           /Temple/Entablature/Mouldings/{architrave, cornice, sima_*}
                           /Temple/Entablature/Ornament/Dentils          (PointInstancer)
                           /Temple/Roof/Mouldings/{raking_cornice_front, raking_cornice_rear}
                           /Temple/Roof/Tiles                            (PointInstancer,
                                                                          bound to Terracotta)
                         it sublayers ./materials.usda, so the tiles' binding resolves alone
    layers/frieze-garlands.usdc   the frieze relief hypothesis (``hyp_frieze_garlands``): the
                         FriezeGarlands PointInstancer under /Temple/Entablature/Ornament
    layers/<id>.detail.usdc       the detail re-placed for a hypothesis that moves the
                         entablature or the roof (written by the combination check,
                         :mod:`ionic_usd.usd.combinations`, only where composing the
                         hypothesis' own layer over the detail is not already right)

The variant set itself lives in ``generated.usda`` (:func:`author_detail_variants`), where the
whole temple composes, so that none of its opinions dangles: ``plain`` hides
(``visibility = invisible``: every variant keeps every prim path) the mouldings and the
ornament (the cuboid temple); ``moulded`` shows the mouldings and hides the ``architrave`` and
``cornice`` cuboids they replace; ``carved`` adds the
instanced dentils, roof tiles and (with its hypothesis) the frieze relief. Both detailed
variants bind the podium (cuboids and mouldings) to Travertine — the podium's facing [C];
the tiles are Terracotta in every variant that shows them; walls, entablature and mouldings
keep the part's binding (painted stucco, or the finish hypothesis'). The materials come from the
temple's one library, ``materials.usda`` (:func:`ionic_usd.usd.materials.stone_material`).
The column asset's ``high`` LOD carries the carved echinus and astragal
(:func:`ionic_usd.blueprint.column_asset.column_ornament`, PointInstancers inside the asset).
"""

from __future__ import annotations

from pathlib import Path

from pxr import Sdf, Vt

from ionic_usd.blueprint.hypotheses import hyp_ident
from ionic_usd.blueprint.temple_plan import (
    DEFAULT_DETAIL,
    DETAIL_LAYER,
    DETAIL_SET,
    DETAIL_VARIANTS,
    FRIEZE_KEY,
    FRIEZE_PATH,
    TERRACOTTA,
    DetailGeometry,
    check_detail,
    detail_counts,
    detail_geometry,
)
from ionic_usd.errors import ParameterError
from ionic_usd.temple.layout import Hypothesis, TempleLayout
from ionic_usd.temple.mouldings import (
    REPLACED_CUBOIDS,
)
from ionic_usd.usd.hypotheses import add_paradata
from ionic_usd.usd.instancer import author_point_instancer
from ionic_usd.usd.materials import bind_material_spec
from ionic_usd.usd.mesh import author_mesh, define_prim
from ionic_usd.usd.stage import new_layer

__all__ = [
    "DETAIL_SET",
    "DETAIL_VARIANTS",
    "DEFAULT_DETAIL",
    "DETAIL_LAYER",
    "FRIEZE_KEY",
    "FRIEZE_PATH",
    "TERRACOTTA",
    "DetailGeometry",
    "detail_geometry",
    "detail_counts",
    "detail_layer",
    "frieze_layer",
    "author_detail_variants",
    "write_frieze_hypotheses",
    "check_detail",
]

TRAVERTINE = "/Temple/Materials/Travertine"


def detail_layer(geom: DetailGeometry, materials_ref: str = "./materials.usda") -> Sdf.Layer:
    """``detail.usdc``: every member and ornament as ``def`` prims (see the module docstring)."""
    lay = new_layer(
        "Temple",
        kind=None,
        comment="architectural detail (ionic_usd): shown by "
        "the detail variant set of generated.usda",
    )
    lay.subLayerPaths.append(materials_ref)
    with Sdf.ChangeBlock():
        # organising prims are Scopes (no transform of their own), the parts Xforms
        for part, members in geom.mouldings.items():
            define_prim(lay, f"/Temple/{part}/Mouldings", "Scope")
            for name, m in members.items():
                author_mesh(lay, f"/Temple/{part}/Mouldings/{name}", m)
        for rel in geom.ornament:
            if "/Ornament/" in rel:
                define_prim(lay, "/Temple/" + rel.split("/Ornament/")[0] + "/Ornament", "Scope")
        for rel, inst in geom.ornament.items():
            spec = author_point_instancer(lay, f"/Temple/{rel}", inst)
            if rel == "Roof/Tiles":
                bind_material_spec(spec, f"/Temple/Materials/{TERRACOTTA[0]}")
    return lay


def frieze_layer(h: Hypothesis, geom: DetailGeometry) -> Sdf.Layer:
    """The frieze relief hypothesis: its PointInstancer, with the hypothesis' paradata."""
    lay = new_layer(
        "Temple", kind="assembly", comment=f"reconstruction hypothesis {h.id!r} (ionic_usd)"
    )
    if geom.frieze is None:
        raise ParameterError(FRIEZE_KEY, "garlands", "a temple with a frieze", context=h.id)
    with Sdf.ChangeBlock():
        define_prim(lay, FRIEZE_PATH.rsplit("/", 1)[0], "Scope")
        spec = author_point_instancer(lay, FRIEZE_PATH, geom.frieze)
        add_paradata(spec, [h])
    return lay


def _hide(spec: Sdf.PrimSpec) -> None:
    Sdf.AttributeSpec(spec, "visibility", Sdf.ValueTypeNames.Token).default = "invisible"


def _over(parent: Sdf.PrimSpec, rel: str) -> Sdf.PrimSpec:
    """An ``over`` at ``rel`` below ``parent`` (a variant's prim spec)."""
    spec = parent
    for name in rel.split("/"):
        child = spec.nameChildren.get(name)
        spec = child if child is not None else Sdf.PrimSpec(spec, name, Sdf.SpecifierOver)
    return spec


def author_detail_variants(spec: Sdf.PrimSpec, geom: DetailGeometry, default: str) -> None:
    """The ``detail`` variant set on ``spec`` (/Temple of ``generated.usda``)."""
    check_detail(default)
    vs = Sdf.VariantSetSpec(spec, DETAIL_SET)
    spec.variantSetNameList.Append(DETAIL_SET)
    sweeps = [f"{part}/Mouldings" for part in geom.mouldings]
    ornament = sorted(
        {
            rel.split("/Ornament/")[0] + "/Ornament" if "/Ornament/" in rel else rel
            for rel in geom.ornament
        }
    )
    for v in DETAIL_VARIANTS:
        prim = Sdf.VariantSpec(vs, v).primSpec
        # hidden, not deactivated: every variant keeps every prim path (an override or a
        # collection keyed by a path holds under every selection); invisible draws nothing
        if v == "plain":
            for p in (*sweeps, *ornament):
                _hide(_over(prim, p))
            continue
        for c in REPLACED_CUBOIDS:
            _hide(_over(prim, f"Entablature/{c}"))
        if v == "moulded":
            for p in ornament:
                _hide(_over(prim, p))
        for name in geom.podium_cuboids:
            bind_material_spec(_over(prim, f"Podium/{name}"), TRAVERTINE)
        if "Podium" in geom.mouldings:
            bind_material_spec(_over(prim, "Podium/Mouldings"), TRAVERTINE)
    spec.variantSelections[DETAIL_SET] = check_detail(default)
    data = dict(spec.customData.get("ionic_usd", {}))
    data["detail"] = {"variants": Vt.StringArray(list(DETAIL_VARIANTS)), "default": default}
    spec.customData = {"ionic_usd": data}


def write_frieze_hypotheses(
    folder: Path, spec: Sdf.PrimSpec, layout: TempleLayout, geom: DetailGeometry
) -> list[Hypothesis]:
    """The hypotheses realised by the detail (``detail.frieze``): their layers, their variant
    sets on ``spec`` (/Temple of ``generated.usda``) and their listing. Returns them."""
    from ionic_usd.usd.hypotheses import hyp_choices
    from ionic_usd.usd.stage import save_layer

    done = []
    data = dict(spec.customData.get("ionic_usd", {}))
    listing = {k: dict(v) for k, v in data.get("hypotheses", {}).items()}
    choices = hyp_choices(layout.hypotheses)
    for h in layout.hypotheses:
        if FRIEZE_KEY not in h.changes:
            continue
        vset, value = choices[h.id]
        name = f"{h.id}.usdc"
        save_layer(frieze_layer(h, geom), folder / "layers" / name, force=True)
        if vset not in spec.variantSets:
            vs = Sdf.VariantSetSpec(spec, vset)
            spec.variantSetNameList.Append(vset)
            Sdf.VariantSpec(vs, "baseline")
        if value not in spec.variantSets[vset].variants:
            Sdf.VariantSpec(spec.variantSets[vset], value)
        # every variant of the set references the relief, all but its own hide it: the same
        # prim paths, and another alternative of the question never shows it
        for v, var in spec.variantSets[vset].variants.items():
            var.primSpec.referenceList.Append(Sdf.Reference(f"./layers/{name}"))
            if v != value:
                _hide(_over(var.primSpec, FRIEZE_PATH.removeprefix("/Temple/")))
        spec.variantSelections[vset] = "baseline"
        listing.setdefault(hyp_ident(h.id), {}).update(
            realised=True, variantSet=vset, variant=value, question=h.key
        )
        done.append(h)
    data["hypotheses"] = listing
    spec.customData = {"ionic_usd": data}
    return done
