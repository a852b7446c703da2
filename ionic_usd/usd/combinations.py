"""Every combination of hypotheses × ``detail`` variant, checked against the layout it stands for.

:func:`realise_combinations` composes ``generated.usda`` for every subset of the hypotheses
that change geometry (the temple's dimensions, or the frieze relief) and every ``detail``
variant, and compares each prim with what :func:`ionic_usd.temple.layout.build_layout` of that
subset gives (cuboid meshes, column placements, the mouldings' points and the ornament's
positions of :func:`ionic_usd.usd.detail.detail_geometry`). Where composing the layers is not
already right it writes a layer of absolute values and references it from the variants:

* one hypothesis alone: only the detail may need it (the hypothesis' own layer moves the
  cuboids and columns; a moulding swept along a changed outline, or tiles on another pitch,
  are rebuilt) — ``layers/<id>.detail.usdc`` in ``hyp_<id>``'s ``alternative``;
* two or more: the values where they interact — ``layers/<a>+<b>.usdc`` in a variant set
  ``hyp_<b>`` nested inside ``hyp_<a>``'s ``alternative`` (Pcp selects it by name);
* a single hypothesis whose own layer composes a cuboid or column wrongly is a bug: an error.

Values are written relative to the composed parent, so a part's translation from another
layer still applies; a prim that must not show is hidden (``visibility``, its path stays),
and one a hypothesis hid is shown again only where a combination needs it, so the ``detail``
variants keep switching what they show.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Sequence
from pathlib import Path

import numpy as np
from pxr import Gf, Sdf, Usd, UsdGeom, Vt

from ionic_usd.column.ornament import Instances
from ionic_usd.errors import UsdAuthoringError
from ionic_usd.geometry.mesh import Mesh
from ionic_usd.temple.description import questions
from ionic_usd.temple.layout import ColumnPlacement, Hypothesis, Layer, TempleLayout, build_layout
from ionic_usd.temple.mouldings import REPLACED_CUBOIDS
from ionic_usd.usd.detail import DETAIL_SET, DETAIL_VARIANTS, FRIEZE_KEY, DetailGeometry
from ionic_usd.usd.hypotheses import (
    GROUPS,
    PART_PRIMS,
    add_paradata,
    column_path,
    column_xform,
    cuboid_meshes,
    define_overs,
    hyp_choices,
    hyp_sets,
    temple_keys,
)
from ionic_usd.usd.instancer import author_point_instancer
from ionic_usd.usd.mesh import author_mesh
from ionic_usd.usd.stage import new_layer, save_layer

__all__ = [
    "Fix",
    "select_variants",
    "expected_column",
    "mismatches",
    "realise_combinations",
]

# what a prim should be: a mesh, ornament copies, a column's placement, or None (not there)
Fix = Mesh | Instances | ColumnPlacement | None
DetailOf = Callable[[TempleLayout], DetailGeometry]


def select_variants(stage: Usd.Stage, selections: dict[str, str]) -> None:
    """Variant selections on /Temple in the session layer (cleared first)."""
    session = stage.GetSessionLayer()
    with Usd.EditContext(stage, session), Sdf.ChangeBlock():  # one recomposition, not two
        session.Clear()
        prim = stage.GetPrimAtPath("/Temple")
        for vs, v in selections.items():
            prim.GetVariantSet(vs).SetVariantSelection(v)


def expected_column(c: ColumnPlacement, ratio: float) -> Gf.Matrix4d:
    s = c.scale * ratio
    return (
        Gf.Matrix4d().SetScale(Gf.Vec3d(s, s, s))
        * Gf.Matrix4d().SetRotate(Gf.Rotation(Gf.Vec3d(0, 1, 0), c.rotation_deg))
        * Gf.Matrix4d().SetTranslate(Gf.Vec3d(*c.position))
    )


def _world(cache: UsdGeom.XformCache, prim: Usd.Prim, pts) -> np.ndarray:
    xf = np.array(cache.GetLocalToWorldTransform(prim))
    return np.asarray(pts, dtype=np.float64).reshape(-1, 3) @ xf[:3, :3] + xf[3, :3]


def _shown(prim: Usd.Prim) -> bool:
    """Active and visible: a variant hides what it does not show (the path stays)."""
    return (
        prim.IsActive() and UsdGeom.Imageable(prim).ComputeVisibility() != UsdGeom.Tokens.invisible
    )


def _differs(
    stage: Usd.Stage, cache: UsdGeom.XformCache, path: str, want: Mesh | Instances, atol: float
) -> bool:
    prim = stage.GetPrimAtPath(path)
    if not prim or not _shown(prim):
        return True
    if isinstance(want, Instances):
        pi = UsdGeom.PointInstancer(prim)
        pos = pi.GetPositionsAttr().Get()
        if (
            pos is None
            or len(pos) != len(want)
            or len(pi.GetPrototypesRel().GetTargets()) != len(want.prototypes)
        ):
            return True
        # positions are float32 on disk: compare at their resolution (~1 µm at 20 m)
        return not np.allclose(_world(cache, prim, pos), want.positions, atol=max(atol, 1e-5))
    pts = UsdGeom.Mesh(prim).GetPointsAttr().Get()
    world = _world(cache, prim, pts)
    return world.shape != want.points.shape or not np.allclose(world, want.points, atol=atol)


def mismatches(
    stage: Usd.Stage,
    expected: TempleLayout,
    column_height: float,
    *,
    uv_scale: float,
    variant: str = "plain",
    detail: DetailGeometry | None = None,
    garlands: bool = False,
    atol: float = 1e-6,
    memo: dict | None = None,
) -> dict[str, Fix]:
    """Prims whose composed values differ from ``expected`` shown in the ``detail`` variant
    ``variant`` (``detail``: its detail geometry): path → the expected value, or None (the prim
    should not be there). ``memo``: :func:`~ionic_usd.usd.hypotheses.cuboid_meshes`'s, shared
    by the calls of one check."""
    cache = UsdGeom.XformCache()
    want: dict[str, Mesh | Instances] = {}
    for layer, ms in cuboid_meshes(expected, uv_scale, memo).items():
        for name, m in ms.items():
            if variant != "plain" and layer is Layer.ENTABLATURE and name in REPLACED_CUBOIDS:
                continue
            want[f"/Temple/{PART_PRIMS[layer]}/{name}"] = m
    if detail is not None:
        want.update(detail.prims(variant, garlands=garlands))
    out: dict[str, Fix] = {p: w for p, w in want.items() if _differs(stage, cache, p, w, atol)}
    for part in PART_PRIMS.values():
        for holder in (f"/Temple/{part}", f"/Temple/{part}/Mouldings"):
            prim = stage.GetPrimAtPath(holder)
            for child in prim.GetChildren() if prim else []:  # active children only
                if child.IsA(UsdGeom.Mesh) and _shown(child) and str(child.GetPath()) not in want:
                    out[str(child.GetPath())] = None
    ratio = expected.params.columns_height / column_height
    cols = {column_path(c): c for c in expected.columns}
    for path, c in cols.items():
        prim = stage.GetPrimAtPath(path)
        if (
            not prim
            or not _shown(prim)
            or not Gf.IsClose(cache.GetLocalToWorldTransform(prim), expected_column(c, ratio), atol)
        ):
            out[path] = c
    for group in GROUPS.values():
        prim = stage.GetPrimAtPath(f"/Temple/Colonnade/{group}")
        for child in prim.GetChildren() if prim else []:
            if _shown(child) and str(child.GetPath()) not in cols:
                out[str(child.GetPath())] = None
    return out


def _set_visibility(spec: Sdf.PrimSpec, value: str) -> None:
    attr = spec.attributes.get("visibility") or Sdf.AttributeSpec(
        spec, "visibility", Sdf.ValueTypeNames.Token
    )
    attr.default = value


def _show(spec: Sdf.PrimSpec) -> None:
    spec.active = True
    _set_visibility(spec, UsdGeom.Tokens.inherited)


def _correction_layer(
    stage: Usd.Stage,
    fixes: dict[str, Fix],
    hyps: Sequence[Hypothesis],
    ratio: float,
    inactive: set[str],
) -> Sdf.Layer:
    """Absolute values (relative to the composed parents) for the prims in ``fixes``;
    ``inactive``: those a hypothesis hid where they were checked."""
    lay = new_layer(
        "Temple",
        kind="assembly",
        comment="values of the hypotheses "
        + ", ".join(h.id for h in hyps)
        + " where composing their layers is not "
        "enough (ionic_usd)",
    )
    cache = UsdGeom.XformCache()
    types: dict[str, str] = {}
    with Sdf.ChangeBlock():
        for path, want in fixes.items():
            parent = stage.GetPrimAtPath(Sdf.Path(path).GetParentPath())
            for anc in Sdf.Path(path).GetAncestorsRange():
                p = stage.GetPrimAtPath(anc)
                if p and p.GetTypeName():
                    types[str(anc)] = str(p.GetTypeName())
            to_parent = np.array(cache.GetLocalToWorldTransform(parent).GetInverse())
            off = path in inactive
            if want is None:
                spec = Sdf.CreatePrimInLayer(lay, path)
                spec.specifier = Sdf.SpecifierOver
                _set_visibility(spec, UsdGeom.Tokens.invisible)
            elif isinstance(want, Mesh | Instances):
                if isinstance(want, Mesh):
                    local = want.points @ to_parent[:3, :3] + to_parent[3, :3]
                    spec = author_mesh(lay, path, want.with_(points=local))
                else:
                    pos = want.positions @ to_parent[:3, :3] + to_parent[3, :3]
                    spec = author_point_instancer(
                        lay,
                        path,
                        Instances(
                            want.name,
                            want.prototypes,
                            want.proto_indices,
                            pos,
                            want.orientations,
                            want.scales,
                        ),
                    )
                if off:  # hidden by a hypothesis, needed by the combination
                    _show(spec)
                Sdf.AttributeSpec(
                    spec, "xformOpOrder", Sdf.ValueTypeNames.TokenArray, Sdf.VariabilityUniform
                ).default = Vt.TokenArray([])
            else:
                m = expected_column(want, ratio) * Gf.Matrix4d(to_parent)
                spec = Sdf.CreatePrimInLayer(lay, path)
                spec.specifier = Sdf.SpecifierOver
                if off:
                    _show(spec)
                column_xform(
                    spec, Gf.Transform(m).GetTranslation(), want.rotation_deg, want.scale * ratio
                )
            add_paradata(spec, hyps)
        define_overs(lay, types)
        for path, type_name in types.items():  # the composed types, not the authoring default
            spec = lay.GetPrimAtPath(path)
            if spec is not None and path not in fixes:
                spec.typeName = type_name
    return lay


def _nest(
    gen: Sdf.Layer, hyps: Sequence[Hypothesis], ref: str, everyone: Sequence[Hypothesis]
) -> None:
    """Reference ``ref`` from the variant that selects each hypothesis of ``hyps`` (its
    ``alternative``, or its value of its question's set), nested in that order inside
    /Temple's variant sets (``everyone``: the temple's hypotheses, which group them)."""
    choices = hyp_choices(everyone)
    values = hyp_sets(everyone)
    spec = gen.GetPrimAtPath("/Temple")
    for i, h in enumerate(hyps):
        name, value = choices[h.id]
        vs = spec.variantSets.get(name)
        if vs is None:
            vs = Sdf.VariantSetSpec(spec, name)
            spec.variantSetNameList.Prepend(name)
        for v in values[name]:
            if v not in vs.variants:
                Sdf.VariantSpec(vs, v)
        spec = vs.variants[value].primSpec
        if i == len(hyps) - 1:
            spec.referenceList.Prepend(Sdf.Reference(ref))


def _subsets(shape: Sequence[Hypothesis]):
    """Every choice of at most one alternative per question among ``shape``, fewest first
    (the independent hypotheses: every subset)."""
    groups = list(questions(shape).values())
    picks = itertools.product(*(((None,) + tuple(g)) for g in groups))
    chosen = [tuple(h for h in p if h is not None) for p in picks]
    order = {h.id: i for i, h in enumerate(shape)}
    return sorted(chosen, key=lambda c: (len(c), [order[h.id] for h in c]))


def _is_detail(path: str) -> bool:
    return "/Mouldings/" in path or "/Ornament/" in path or path.endswith("/Tiles")


def realise_combinations(
    gen: Usd.Stage,
    folder: Path,
    layout: TempleLayout,
    realised: Sequence[Hypothesis],
    *,
    uv_scale: float,
    detail_of: DetailOf | None = None,
) -> list[str]:
    """Compose every subset of the realised hypotheses that change geometry in every
    ``detail`` variant (if /Temple has the set), compare it with :func:`build_layout` of that
    subset, and write the layers where composing is not enough (module docstring). Returns the
    layers written (names without suffix)."""
    shape = [h for h in realised if temple_keys(h) or FRIEZE_KEY in h.changes]
    choices = hyp_choices(layout.hypotheses)
    off = {choices[h.id][0]: "baseline" for h in realised}
    has_detail = gen.GetPrimAtPath("/Temple").GetVariantSets().HasVariantSet(DETAIL_SET)
    variants = DETAIL_VARIANTS if has_detail and detail_of is not None else ("plain",)
    height = layout.params.columns_height
    memo: dict = {}  # the cuboid meshes: the subsets' layouts share most cuboids

    def check(
        sel: dict[str, str], want: TempleLayout, geom: DetailGeometry | None, garlands: bool
    ) -> tuple[dict[str, Fix], set[str]]:
        bad: dict[str, Fix] = {}
        off: set[str] = set()
        for v in variants:  # the cuboids are checked in plain, the detail where it shows
            select_variants(gen, sel | ({DETAIL_SET: v} if has_detail else {}))
            found = mismatches(
                gen,
                want,
                height,
                uv_scale=uv_scale,
                variant=v,
                detail=geom,
                garlands=garlands,
                memo=memo,
            )
            off |= {p for p in found if (q := gen.GetPrimAtPath(p)) and not _shown(q)}
            bad.update(found)
        return bad, off

    written: list[str] = []
    try:
        for subset in _subsets(shape):
            size = len(subset)
            sel = dict(off) | dict(choices[h.id] for h in subset)
            ids = [h.id for h in subset]
            want = build_layout(layout.params, hypotheses=layout.hypotheses, apply=ids)
            geom = detail_of(want) if detail_of is not None and has_detail else None
            garlands = any(FRIEZE_KEY in h.changes for h in subset)
            bad, off_prims = check(sel, want, geom, garlands)
            if not bad:
                continue
            wrong = sorted(p for p in bad if not _is_detail(p))
            if size == 0 or (size == 1 and wrong):
                raise UsdAuthoringError(
                    f"hypotheses {ids or '(none)'} compose to other geometry than the "
                    f"layout at {', '.join(wrong or sorted(bad))}"
                )
            name = "+".join(ids) + (".detail" if size == 1 else "")
            ratio = want.params.columns_height / height
            select_variants(gen, sel | ({DETAIL_SET: "carved"} if has_detail else {}))
            save_layer(
                _correction_layer(gen, bad, subset, ratio, off_prims),
                folder / "layers" / f"{name}.usdc",
            )
            _nest(gen.GetRootLayer(), subset, f"./layers/{name}.usdc", layout.hypotheses)
            written.append(name)
            still, _ = check(sel, want, geom, garlands)
            if still:
                raise UsdAuthoringError(
                    f"hypotheses {ids} still compose wrongly at {', '.join(sorted(still))}"
                )
    finally:
        gen.GetSessionLayer().Clear()
    if written:
        gen.GetRootLayer().Save()
    return written
