"""City scale: temples and street colonnades authored from numpy arrays into crate layers.

Files written into the city folder by :func:`compose_city` (the temple folders under
``Temples/`` come from :mod:`ionic_usd.pipeline`)::

    City.usda        the root (text, small): /City (Xform, kind = assembly) with the build summary
                     in customData and the city's extentsHint; sublayers ./Instances.usdc
    Instances.usdc   every instance, in crate: /City (assembly)
      /City/Temples            Xform, kind = group, holding either
        Temple_<lot>           instanceable references to ./Temples/<build>/Temple.usda with the
                               lot's variant selections (hypotheses, lod), translate/rotateXYZ/
                               scale (XformCommonAPI ops) — up to ``instancer_threshold`` temples;
                               a far temple (``TempleInstances.cards``) carries card draw mode
                               (GeomModelAPI, a box of ./Temples/Cards/<key>/<Face>.png)
        Field                  or a UsdGeom.PointInstancer (kind = group) whose prototypes
                               (Prototypes, Scope, kind = group) are the unique temple choices
      /City/Porticus           UsdGeom.PointInstancer (kind = group) of the column asset, one
                               prototype per LOD used (Prototypes/Column_<lod>, components),
                               and for the far columns (``ColumnInstances.cards``) Column_cards:
                               the asset at lod low carrying card draw mode (a box of
                               ./Temples/Cards/<column key>/<Face>.png)
    Temples/<name>-<key>/      one folder per unique temple build (content-addressed)

Every model's parent is a model (assembly › group › component/assembly). Instance arrays are
built with ``Vt.*Array.FromNumpy`` — no per-instance Python object — and nothing re-opens the
city to check it: prototype counts, bounds and drawn triangles come from the arrays and from
the prototypes' own (small) stages (:mod:`ionic_usd.usd.city_prototypes`).
"""

from __future__ import annotations

import os
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from pxr import Gf, Sdf, Usd, Vt

from ionic_usd.blueprint.city import ColumnInstances, TempleInstances
from ionic_usd.blueprint.layers import CITY_INSTANCES_LAYER, CITY_ROOT_LAYER
from ionic_usd.city.layout import DEFAULT_INSTANCER_THRESHOLD, yaw_quaternions
from ionic_usd.errors import OutputExistsError, ParameterError
from ionic_usd.lod import LOD_NAMES
from ionic_usd.usd.city_instances import (
    CARD_TRIANGLES,
    COLUMN_CARD_SELECTION,
    ColumnPrototypes,
    TemplePrototypes,
    city_triangles,
    column_prototypes,
    default_render,
    temple_prototypes,
)
from ionic_usd.usd.city_prototypes import (
    instance_bounds,
    prim_identifier,
    purpose_bounds,
    temple_selection,
    temple_variant_sets,
)
from ionic_usd.usd.draw_mode import CARD_FACES, author_cards
from ionic_usd.usd.stage import new_layer, save_layer, vt_dictionary

__all__ = [
    "CityReport",
    "TempleInstances",
    "ColumnInstances",
    "compose_city",
    "load_region",
    "ROOT_LAYER",
    "INSTANCES_LAYER",
    "DEFAULT_INSTANCER_THRESHOLD",
    "temple_variant_sets",
    "temple_selection",
    "CARD_TRIANGLES",
    "COLUMN_CARD_SELECTION",
]

ROOT_LAYER = CITY_ROOT_LAYER
INSTANCES_LAYER = CITY_INSTANCES_LAYER
_T = Sdf.ValueTypeNames


@dataclass(frozen=True)
class CityReport:
    path: Path
    temples: int
    temple_prototypes: int
    temple_builds: int
    street_columns: int
    column_prototypes: int
    temples_as: str  # "references" or "point-instancer"
    triangles: dict[str, int]  # LOD setting → triangles drawn
    extent: tuple[tuple[float, ...], tuple[float, ...]]
    seconds: dict[str, float] = field(default_factory=dict)


def _set_xform(spec: Sdf.PrimSpec, x: float, z: float, yaw: float, scale: float) -> None:
    Sdf.AttributeSpec(spec, "xformOp:translate", _T.Double3).default = Gf.Vec3d(x, 0.0, z)
    Sdf.AttributeSpec(spec, "xformOp:rotateXYZ", _T.Float3).default = Gf.Vec3f(0.0, yaw, 0.0)
    Sdf.AttributeSpec(spec, "xformOp:scale", _T.Float3).default = Gf.Vec3f(scale, scale, scale)
    Sdf.AttributeSpec(
        spec, "xformOpOrder", _T.TokenArray, Sdf.VariabilityUniform
    ).default = Vt.TokenArray(["xformOp:translate", "xformOp:rotateXYZ", "xformOp:scale"])


def _group(layer: Sdf.Layer, path: str, type_name: str = "Xform") -> Sdf.PrimSpec:
    """A group model of ``type_name``. A PointInstancer whose prototypes are models (temples,
    the column asset) is a group too, and so is its Prototypes scope: draw modes (the cards)
    apply to models only, and a prototype is a model only when the hierarchy above it is
    one (docs/usd.md)."""
    spec = Sdf.CreatePrimInLayer(layer, path)
    spec.specifier, spec.typeName, spec.kind = Sdf.SpecifierDef, type_name, "group"
    return spec


def _arc(spec: Sdf.PrimSpec, ref: str) -> None:
    """A temple by payload (an unloaded city composes none of it), anything else by reference
    (the column asset carries its own payload)."""
    if ref.endswith("/Temple.usda"):
        spec.payloadList.Prepend(Sdf.Payload(ref))
    else:
        spec.referenceList.Prepend(Sdf.Reference(ref))


def _as_default(ext: tuple[np.ndarray, np.ndarray], n: int) -> tuple[np.ndarray, np.ndarray]:
    lo4, hi4 = np.full((4, 3), np.inf), np.full((4, 3), -np.inf)
    if n:
        lo4[0], hi4[0] = ext
    return lo4, hi4


def _extents_hint(lo4: np.ndarray, hi4: np.ndarray) -> Vt.Vec3fArray:
    """``UsdGeomModelAPI`` extentsHint: a (min, max) pair per ordered purpose, trailing empty
    purposes dropped, an empty one in between as Gf's empty range."""
    ok = [k for k in range(4) if np.all(lo4[k] <= hi4[k])]
    out = []
    for k in range(max(ok) + 1 if ok else 1):
        if k in ok:
            out += [Gf.Vec3f(*map(float, lo4[k])), Gf.Vec3f(*map(float, hi4[k]))]
        else:
            empty = Gf.Range3f()
            out += [empty.GetMin(), empty.GetMax()]
    return Vt.Vec3fArray(out)


def _instancer(
    layer: Sdf.Layer,
    path: str,
    protos: list[tuple[str, str, dict[str, str], str | None]],
    index: np.ndarray,
    xz: np.ndarray,
    yaw: np.ndarray,
    scale: np.ndarray | None,
    extent: tuple[np.ndarray, np.ndarray],
) -> None:
    """A PointInstancer (kind = group) with prototypes (name, reference, selections, card
    image folder or None)."""
    pi = _group(layer, path, "PointInstancer")
    _group(layer, f"{path}/Prototypes", "Scope")
    targets = []
    for name, ref, sel, cards in protos:
        spec = Sdf.CreatePrimInLayer(layer, f"{path}/Prototypes/{name}")
        spec.specifier, spec.typeName = Sdf.SpecifierDef, "Xform"
        _arc(spec, ref)
        for k, v in sorted(sel.items()):
            spec.variantSelections[k] = v
        if cards is not None:
            _cards(spec, cards)
        targets.append(spec.path)
    Sdf.RelationshipSpec(pi, "prototypes", custom=False).targetPathList.explicitItems = targets
    n = len(index)
    pos = np.zeros((n, 3), dtype=np.float32)
    pos[:, 0], pos[:, 2] = xz[:, 0], xz[:, 1]
    Sdf.AttributeSpec(pi, "positions", _T.Point3fArray).default = Vt.Vec3fArray.FromNumpy(pos)
    del pos
    Sdf.AttributeSpec(pi, "protoIndices", _T.IntArray).default = Vt.IntArray.FromNumpy(
        np.ascontiguousarray(index, dtype=np.int32)
    )
    Sdf.AttributeSpec(pi, "orientations", _T.QuathArray).default = Vt.QuathArray.FromNumpy(
        yaw_quaternions(yaw)
    )
    if scale is not None:
        s = np.repeat(np.asarray(scale, dtype=np.float32)[:, None], 3, axis=1)
        Sdf.AttributeSpec(pi, "scales", _T.Float3Array).default = Vt.Vec3fArray.FromNumpy(s)
    Sdf.AttributeSpec(pi, "extent", _T.Float3Array).default = Vt.Vec3fArray(
        [Gf.Vec3f(*map(float, extent[0])), Gf.Vec3f(*map(float, extent[1]))]
    )


def _cards(spec: Sdf.PrimSpec, folder: str) -> None:
    """Card draw mode on a temple model: a box of the six baked views in ``folder``."""
    author_cards(spec, {f: f"./{folder}/{f}.png" for f in CARD_FACES}, geometry="box")


def compose_city(
    folder: str | os.PathLike,
    temples: TempleInstances,
    columns: ColumnInstances,
    *,
    instancer_threshold: int = DEFAULT_INSTANCER_THRESHOLD,
    finish: str = "stucco",
    summary: Mapping | None = None,
    card_dirs: Mapping[tuple[int, tuple], str] | None = None,
    column_card_dir: str | None = None,
    stoa: tuple | None = None,
    ground: tuple | None = None,
    force: bool = False,
) -> CityReport:
    """Write ``City.usda`` + ``Instances.usdc`` into ``folder`` (its ``Temples/`` must hold
    the builds named in ``temples.folders``).

    Parameters
    ----------
    instancer_threshold : temples above this count go into a PointInstancer
    finish : the street columns' finish variant
    summary : JSON-able build summary stored in /City's customData (``ionic_usd``)
    card_dirs : for the temples drawn as cards (``temples.cards``): ``(build, selections)`` →
        the city-relative folder of the baked card images (``XPos.png`` …), where
        ``selections`` is ``tuple(sorted(temple_selection(...).items()))`` without a lod
    column_card_dir : the city-relative folder of the street column's card images, needed
        when ``columns.cards`` has any far column (baked with :data:`COLUMN_CARD_SELECTION`)
    stoa : ``(asset, prototype names, StoaInstances, bounds per prototype, triangles per
        prototype)`` — the stoas' parts, placed by ``/City/Stoas`` (:mod:`ionic_usd.usd.stoa`)
    ground : ``(asset, triangles, lo, hi)`` — the ground layer, referenced by ``/City/Ground``
    """
    t0 = time.perf_counter()
    folder = Path(folder)
    root_path, body_path = folder / ROOT_LAYER, folder / INSTANCES_LAYER
    _check_outputs((root_path, body_path), force, instancer_threshold)
    secs: dict[str, float] = {}
    t1 = time.perf_counter()
    tp = temple_prototypes(folder, temples, card_dirs)
    cp = column_prototypes(folder, columns, finish, column_card_dir)
    secs["prototype stats"] = time.perf_counter() - t1
    t2 = time.perf_counter()
    placed = _placed(temples, columns, tp, cp, len(temples) > instancer_threshold)
    body = new_layer("City", kind="assembly")
    with Sdf.ChangeBlock():
        _group(body, "/City/Temples")
        _author_temples(body, placed, card_dirs)
        _author_columns(body, placed, finish, column_card_dir)
        extra_tris, extra_ext = _stoa_and_ground(body, stoa, ground)
    lo4, hi4 = _city_bounds(placed, extra_ext)
    root = _root_layer(lo4, hi4)
    triangles = city_triangles(temples, columns, tp, cp, extra_tris)
    if summary is not None:
        root.GetPrimAtPath("/City").customData = {"ionic_usd": vt_dictionary(summary)}
    secs["author"] = time.perf_counter() - t2
    t3 = time.perf_counter()
    folder.mkdir(parents=True, exist_ok=True)
    save_layer(body, body_path, force=True)
    save_layer(root, root_path, force=True)
    secs["save"] = time.perf_counter() - t3
    secs["total"] = time.perf_counter() - t0
    lo, hi = default_render(lo4, hi4)
    return CityReport(
        root_path,
        len(temples),
        len(tp.keys),
        len(temples.folders),
        len(columns),
        cp.count if len(columns) else 0,
        "point-instancer" if placed.as_instancer else "references",
        triangles,
        (tuple(map(float, lo)), tuple(map(float, hi))),
        secs,
    )


def _placed(temples: TempleInstances, columns: ColumnInstances, tp, cp, as_instancer: bool):
    """The city's placements with each instance's world bounds (temples and columns)."""
    return _Placed(
        temples,
        columns,
        tp,
        cp,
        as_instancer=as_instancer,
        t_ext=instance_bounds(tp.lo, tp.hi, tp.of, temples.xz, temples.yaw, temples.scale),
        c_ext=instance_bounds(cp.lo, cp.hi, cp.index, columns.xz, columns.yaw, None),
    )


@dataclass(frozen=True)
class _Placed:
    """The instances with their prototypes and placed bounds, as the authoring steps read them."""

    temples: TempleInstances
    columns: ColumnInstances
    tp: TemplePrototypes
    cp: ColumnPrototypes
    as_instancer: bool
    t_ext: tuple[np.ndarray, np.ndarray]
    c_ext: tuple[np.ndarray, np.ndarray]


def _check_outputs(paths: Sequence[Path], force: bool, instancer_threshold: object) -> None:
    """Refuse existing output layers (without ``force``) and a bad instancer threshold."""
    if not force:
        for p in paths:
            if p.exists():
                raise OutputExistsError(f"{p} exists; pass --force to overwrite it")
    if not isinstance(instancer_threshold, int) or instancer_threshold < 0:
        raise ParameterError("instancer threshold", instancer_threshold, "an integer >= 0")


def _author_temples(
    body: Sdf.Layer, placed: _Placed, card_dirs: Mapping[tuple[int, tuple], str] | None
) -> None:
    """Author the temples under ``/City/Temples``: one PointInstancer, or a payload each."""
    temples, protos = placed.temples, placed.tp.keys
    refs = [f"./{temples.folders[b]}/Temple.usda" for b, _, _ in protos]
    dirs = [card_dirs[(b, sel)] if card and card_dirs else None for b, sel, card in protos]
    if placed.as_instancer:
        _instancer(
            body,
            "/City/Temples/Field",
            [(f"Temple_{k}", refs[k], dict(sel), dirs[k]) for k, (_, sel, _) in enumerate(protos)],
            placed.tp.of,
            temples.xz,
            temples.yaw,
            temples.scale,
            placed.t_ext,
        )
        return
    used: set[str] = set()
    for i in range(len(temples)):
        name = prim_identifier(f"Temple_{temples.names[i]}")
        while name in used:
            name += "_"
        used.add(name)
        spec = Sdf.CreatePrimInLayer(body, f"/City/Temples/{name}")
        spec.specifier, spec.typeName = Sdf.SpecifierDef, "Xform"
        spec.instanceable = True
        k = int(placed.tp.of[i])
        spec.payloadList.Prepend(Sdf.Payload(refs[k]))  # a temple loads on demand
        for vs, v in protos[k][1]:
            spec.variantSelections[vs] = v
        if dirs[k] is not None:
            _cards(spec, dirs[k])  # type: ignore[arg-type]
        _set_xform(
            spec,
            float(temples.xz[i, 0]),
            float(temples.xz[i, 1]),
            float(temples.yaw[i]),
            float(temples.scale[i]),
        )


def _author_columns(
    body: Sdf.Layer, placed: _Placed, finish: str, column_card_dir: str | None
) -> None:
    """Author the street columns' PointInstancer ``/City/Porticus`` (nothing without columns)."""
    columns, cp = placed.columns, placed.cp
    if not len(columns):
        return
    cprotos: list[tuple[str, str, dict[str, str], str | None]] = [
        (
            f"Column_{LOD_NAMES[li]}",
            f"./{columns.asset}",
            {"lod": LOD_NAMES[li], "form": "full", "finish": finish},
            None,
        )
        for li in cp.lods
    ]
    if cp.card.any():
        cprotos.append(
            (
                "Column_cards",
                f"./{columns.asset}",
                {**COLUMN_CARD_SELECTION, "finish": finish},
                column_card_dir,
            )
        )
    _instancer(
        body, "/City/Porticus", cprotos, cp.index, columns.xz, columns.yaw, None, placed.c_ext
    )


def _city_bounds(
    placed: _Placed, extra: list[tuple[np.ndarray, np.ndarray]]
) -> tuple[np.ndarray, np.ndarray]:
    """The city's bounds per purpose (default, render, proxy, guide), as BBoxCache with
    useExtentsHint reads them: the union of the placed prototypes' bounds of that purpose."""
    # a PointInstancer is bounded by its authored extent, which counts for its own purpose,
    # default: the street columns and a field of temples enter the default range
    temples, tp = placed.temples, placed.tp
    c4 = _as_default(placed.c_ext, len(placed.columns))
    if placed.as_instancer:
        t4 = _as_default(placed.t_ext, len(temples))
    else:
        t4 = purpose_bounds(tp.lo4, tp.hi4, tp.of, temples.xz, temples.yaw, temples.scale)
    lo4, hi4 = np.minimum(t4[0], c4[0]), np.maximum(t4[1], c4[1])
    for elo, ehi in extra:  # the stoas' instancer and the ground: default purpose
        lo4[0], hi4[0] = np.minimum(lo4[0], elo), np.maximum(hi4[0], ehi)
    return lo4, hi4


def _root_layer(lo4: np.ndarray, hi4: np.ndarray) -> Sdf.Layer:
    """The root layer ``City.usda``: /City sublayering the instances, with its extentsHint."""
    root = new_layer(
        "City",
        kind="assembly",
        comment="A city of Ionic temples, composed by "
        "ionic_usd; the instances live in ./Instances.usdc",
    )
    root.subLayerPaths.append(f"./{INSTANCES_LAYER}")
    city = root.GetPrimAtPath("/City")
    Sdf.AttributeSpec(
        city, "extentsHint", _T.Float3Array, Sdf.VariabilityUniform
    ).default = _extents_hint(lo4, hi4)
    return root


def _stoa_and_ground(body: Sdf.Layer, stoa: tuple | None, ground: tuple | None) -> tuple:
    """Author ``/City/Stoas`` and ``/City/Ground``; returns (their triangles, their extents)."""
    from ionic_usd.usd.stoa import author_ground, author_stoa_instancer

    tris, extents = 0, []
    if stoa is not None and len(stoa[2]):
        asset, names, inst, bounds, ptris = stoa
        extents.append(author_stoa_instancer(body, "/City/Stoas", asset, names, inst, bounds))
        tris += int(np.bincount(inst.proto, minlength=len(names)) @ np.asarray(ptris))
    if ground is not None:
        author_ground(body, "/City/Ground", ground[0])
        tris += int(ground[1])
        extents.append((np.asarray(ground[2]), np.asarray(ground[3])))
    return tris, extents


def load_region(stage: Usd.Stage, lo: Sequence[float], hi: Sequence[float]) -> list[str]:
    """Load the temples whose position (x, z) lies in the rectangle ``lo``–``hi`` of a city
    opened with ``Usd.Stage.LoadNone`` (each temple is a payload); returns their paths."""
    loaded = []
    holder = stage.GetPrimAtPath("/City/Temples")
    for prim in holder.GetAllChildren() if holder else []:
        t = prim.GetAttribute("xformOp:translate").Get()
        if t is not None and lo[0] <= t[0] <= hi[0] and lo[1] <= t[2] <= hi[1]:
            loaded.append(str(prim.GetPath()))
    stage.LoadAndUnload({Sdf.Path(p) for p in loaded}, set())
    return loaded
