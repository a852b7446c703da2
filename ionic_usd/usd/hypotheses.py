"""Reconstruction hypotheses as layers that combine: relative opinions, paradata by id.

Each realised hypothesis of a temple becomes one layer of opinions *relative to what it
changes*, so that any set of hypotheses can be selected at once:

* a cuboid that only moves (the cornice and the roof under a lower frieze) gets a
  ``xformOp:translate`` — on its part (``/Temple/Roof``) when the whole part moves alike, else on
  the mesh; its points stay those of the baseline, so another hypothesis may reshape them;
* a cuboid that changes shape (the roof slabs under another pitch) gets new points, normals and
  ``st`` at the baseline position, so a translation from another hypothesis still applies;
* a column that moves or is rescaled gets its XformCommonAPI ops; ``column.flute_count`` and
  ``material.finish`` become variant selections and material bindings.

Where two or more hypotheses still interact (both reshape one mesh, or both move one prim), the
composer writes a *combination* layer (``layers/<a>+<b>.usda``) with the combined values and
references it from a nested variant set ``hyp_<b>`` inside ``hyp_<a>``'s ``alternative``, which
Pcp selects by name with the prim's own ``hyp_<b>`` selection; see
:func:`ionic_usd.pipeline.temple.compose_temple`, which checks every combination against
:func:`ionic_usd.temple.layout.build_layout` and writes only the combination layers needed.

Paradata (London Charter principles 4 and 6) is keyed by hypothesis id, so a prim that several
selected hypotheses touch lists them all (``customData`` dictionaries merge across layers):
``customData["ionic_usd"]["hypotheses"][<id>] = {id, description, certainty, sources}``, and
the same as ``userProperties:ionic_usd:<id>:…`` string attributes, which Blender's USD importer
turns into custom properties.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
from pxr import Sdf, Tf, Vt

from ionic_usd.blueprint.hypotheses import (
    FINISH_VALUES,
    FORMS,
    GROUPS,
    PART_PRIMS,
    HypothesisChanges,
    check_composer_changes,
    cuboid_meshes,
    hyp_choices,
    hyp_ident,
    hyp_set,
    hyp_sets,
    temple_keys,
)
from ionic_usd.geometry.mesh import Mesh
from ionic_usd.temple.layout import (
    ColumnPlacement,
    Hypothesis,
    TempleLayout,
    build_layout,
)
from ionic_usd.usd.materials import bind_material_spec
from ionic_usd.usd.mesh import author_attribute, author_mesh
from ionic_usd.usd.stage import new_layer

__all__ = [
    "FINISH_VALUES",
    "GROUPS",
    "FORMS",
    "PART_PRIMS",
    "HypothesisChanges",
    "column_path",
    "cuboid_meshes",
    "hyp_ident",
    "hyp_set",
    "hyp_choices",
    "hyp_sets",
    "hypothesis_paradata",
    "add_paradata",
    "check_composer_changes",
    "define_overs",
    "column_xform",
    "temple_keys",
    "hypothesis_layer",
]

_T = Sdf.ValueTypeNames
_TOL = 1e-9


def column_path(c: ColumnPlacement) -> str:
    return f"/Temple/Colonnade/{GROUPS[c.kind]}/{Tf.MakeValidIdentifier(c.name)}"


def hypothesis_paradata(h: Hypothesis) -> dict:
    """``{id, description, certainty, sources}`` of ``h`` (customData values)."""
    return {
        "id": h.id,
        "description": " ".join(h.description.split()),
        "certainty": str(h.certainty),
        "sources": Vt.StringArray(list(h.sources)),
    }


def add_paradata(spec: Sdf.PrimSpec, hyps: Sequence[Hypothesis]) -> None:
    """Record ``hyps`` on ``spec``: customData keyed by id, and ``userProperties:`` strings."""
    custom = dict(spec.customData)
    top = dict(custom.get("ionic_usd", {}))
    listed = dict(top.get("hypotheses", {}))
    for h in hyps:
        ident = hyp_ident(h.id)
        listed[ident] = hypothesis_paradata(h)
        values = {
            "id": h.id,
            "description": listed[ident]["description"],
            "certainty": str(h.certainty),
            "sources": "; ".join(h.sources),
        }
        for field, value in values.items():
            name = f"userProperties:ionic_usd:{ident}:{field}"
            attr = spec.attributes.get(name) or Sdf.AttributeSpec(
                spec, name, _T.String, Sdf.VariabilityUniform, declaresCustom=True
            )
            attr.default = value
    top["hypotheses"] = listed
    custom["ionic_usd"] = top
    spec.customData = custom


def column_xform(spec: Sdf.PrimSpec, pos: Sequence[float], rot_y_deg: float, scale: float) -> None:
    """Translate, rotateXYZ and scale ops in XformCommonAPI's order (no pivot)."""
    from pxr import Gf  # noqa: PLC0415 - local: keeps the module's import list short

    k = float(scale)
    author_attribute(spec, "xformOp:translate", _T.Double3, Gf.Vec3d(*map(float, pos)))
    author_attribute(spec, "xformOp:rotateXYZ", _T.Float3, Gf.Vec3f(0.0, float(rot_y_deg), 0.0))
    author_attribute(spec, "xformOp:scale", _T.Float3, Gf.Vec3f(k, k, k))
    ops = Vt.TokenArray(["xformOp:translate", "xformOp:rotateXYZ", "xformOp:scale"])
    author_attribute(spec, "xformOpOrder", _T.TokenArray, ops, uniform=True)


def _over(layer: Sdf.Layer, path: str) -> Sdf.PrimSpec:
    spec = layer.GetPrimAtPath(path)
    if spec is None:
        spec = Sdf.CreatePrimInLayer(layer, path)
        spec.specifier = Sdf.SpecifierOver
    return spec


def _translate(spec: Sdf.PrimSpec, offset: np.ndarray) -> None:
    from pxr import Gf  # noqa: PLC0415

    author_attribute(spec, "xformOp:translate", _T.Double3, Gf.Vec3d(*map(float, offset)))
    ops = Vt.TokenArray(["xformOp:translate"])
    author_attribute(spec, "xformOpOrder", _T.TokenArray, ops, uniform=True)


def _offset(old: Mesh, new: Mesh) -> np.ndarray | None:
    """The constant translation from ``old`` to ``new`` (None: the shape changed)."""
    if old.points.shape != new.points.shape:
        return None
    d = np.asarray(new.points, dtype=np.float64) - np.asarray(old.points, dtype=np.float64)
    return d[0] if np.allclose(d, d[0], atol=_TOL, rtol=0) else None


def _shape_opinions(
    lay: Sdf.Layer,
    base: TempleLayout,
    alt: TempleLayout,
    uv_scale: float,
    asset_ref: str,
    touched: list[Sdf.PrimSpec],
    *,
    column_height: float,
) -> None:
    """Relative opinions that turn ``base`` into ``alt`` (cuboids and column placements)."""
    old_m, new_m = cuboid_meshes(base, uv_scale), cuboid_meshes(alt, uv_scale)
    for layer in sorted(set(old_m) | set(new_m)):
        part = f"/Temple/{PART_PRIMS[layer]}"
        olds, news = old_m.get(layer, {}), new_m.get(layer, {})
        moves = {n: _offset(olds[n], news[n]) for n in olds if n in news}
        shifts = [v for v in moves.values() if v is not None]
        same_move = (
            set(olds) == set(news)
            and len(shifts) == len(moves) > 0
            and len({tuple(np.round(v, 12)) for v in shifts}) == 1
        )
        if same_move and np.any(np.abs(shifts[0]) > _TOL):
            spec = _over(lay, part)
            _translate(spec, shifts[0])
            touched.append(spec)
            continue
        for name in sorted(set(olds) | set(news)):
            path = f"{part}/{name}"
            if name not in news:
                spec = _over(lay, path)
                _hide(spec)  # hidden, not deactivated: the prim paths stay
            elif name not in olds:
                author_mesh(lay, path, news[name])
                spec = lay.GetPrimAtPath(path)
            else:
                off = moves[name]
                if off is not None and not np.any(np.abs(off) > _TOL):
                    continue
                # a moved mesh keeps its baseline data beside the translate, so that the layer
                # alone holds a whole mesh (NVIDIA's checks); the values equal the part layer's
                spec = author_mesh(lay, path, olds[name] if off is not None else news[name])
                if off is not None:
                    _translate(spec, off)
            touched.append(spec)
    ratio = alt.params.columns_height / column_height
    olds_c = {column_path(c): c for c in base.columns}
    for c in alt.columns:
        path = column_path(c)
        o = olds_c.pop(path, None)
        scale = c.scale * ratio
        if (
            o is not None
            and np.allclose(o.position, c.position, atol=_TOL, rtol=0)
            and abs(o.rotation_deg - c.rotation_deg) < _TOL
            and abs(o.scale - scale) < _TOL
        ):
            continue
        spec = _over(lay, path)
        if o is None:
            spec.specifier = Sdf.SpecifierDef
            spec.typeName = "Xform"
            spec.instanceable = True
            spec.referenceList.Prepend(Sdf.Reference(asset_ref))
            spec.variantSelections["form"] = FORMS[c.kind]
        column_xform(spec, c.position, c.rotation_deg, scale)
        touched.append(spec)
    for path in olds_c:
        spec = _over(lay, path)
        _hide(spec)
        touched.append(spec)


def _hide(spec: Sdf.PrimSpec) -> None:
    Sdf.AttributeSpec(spec, "visibility", Sdf.ValueTypeNames.Token).default = "invisible"


def hypothesis_layer(
    hyps: Sequence[Hypothesis],
    layout: TempleLayout,
    *,
    changes: Mapping[str, HypothesisChanges],
    uv_scale: float,
    asset_ref: str,
    materials_ref: str,
    finish_materials: Mapping[str, str],
    column_height: float,
) -> Sdf.Layer | None:
    """The layer that realises one hypothesis (``len(hyps) == 1``) against the baseline.

    Returns None when the hypothesis changes nothing the generator can realise.
    """
    (h,) = hyps
    lay = new_layer(
        "Temple", kind="assembly", comment=f"reconstruction hypothesis {h.id!r} (ionic_usd)"
    )
    touched: list[Sdf.PrimSpec] = []
    ch = changes[h.id]
    with Sdf.ChangeBlock():
        if temple_keys(h):
            alt = build_layout(layout.params, hypotheses=layout.hypotheses, apply=[h.id])
            _shape_opinions(
                lay, layout, alt, uv_scale, asset_ref, touched, column_height=column_height
            )
        columns = [column_path(c) for c in layout.columns]
        if ch.flutes is not None:
            for p in columns:
                spec = _over(lay, p)
                spec.variantSelections["flutes"] = ch.flutes
                touched.append(spec)
        if ch.capital is not None:
            # the colonnade's corner columns get the angle capital, turned so that its two
            # volute faces show on the building's two outer sides
            ratio = layout.params.columns_height / column_height
            for c in layout.columns:
                if c.angle_rotation_deg is None:
                    continue
                spec = _over(lay, column_path(c))
                spec.variantSelections["capital"] = ch.capital
                if abs(c.angle_rotation_deg - c.rotation_deg) > _TOL:
                    column_xform(spec, c.position, c.angle_rotation_deg, c.scale * ratio)
                touched.append(spec)
        if ch.finish is not None:
            lay.subLayerPaths.append(materials_ref)  # the bindings resolve in this layer alone
            for p in columns:
                spec = _over(lay, p)
                spec.variantSelections["finish"] = ch.finish
                touched.append(spec)
            for layer in layout.cuboids:
                spec = _over(lay, f"/Temple/{PART_PRIMS[layer]}")
                bind_material_spec(spec, f"/Temple/Materials/{finish_materials[ch.finish]}")
                touched.append(spec)
        if not touched:
            return None
        for spec in {s.path: s for s in touched}.values():
            add_paradata(spec, [h])
        define_overs(lay)
    return lay


def define_overs(lay: Sdf.Layer, types: Mapping[str, str] | None = None) -> None:
    """Turn every ``over`` of a temple delta layer into a typed ``def`` (the type the prim has
    in the generated layers: ``types[path]`` if given, else Mesh for a cuboid of a part and
    Xform for the rest), so the layer opened alone has no dangling overs; in composition the
    opinions are the same."""
    parts = set(PART_PRIMS.values())
    types = types or {}

    def visit(path: Sdf.Path) -> None:
        if not path.IsPrimPath() or path.IsPrimVariantSelectionPath():
            return
        spec = lay.GetPrimAtPath(path)
        if spec is None or spec.specifier != Sdf.SpecifierOver:
            return
        spec.specifier = Sdf.SpecifierDef
        if not spec.typeName and path.pathString in types:
            spec.typeName = types[path.pathString]
        elif not spec.typeName:
            names = path.pathString.split("/")
            mesh = len(names) == 4 and names[1] == "Temple" and names[2] in parts
            spec.typeName = "Mesh" if mesh else "Xform"

    lay.Traverse(Sdf.Path.absoluteRootPath, visit)
