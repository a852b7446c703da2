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

from ionic_usd.blueprint.layers import CITY_INSTANCES_LAYER, CITY_ROOT_LAYER
from ionic_usd.city.layout import DEFAULT_INSTANCER_THRESHOLD, yaw_quaternions
from ionic_usd.errors import OutputExistsError, ParameterError, UsdAuthoringError
from ionic_usd.lod import LOD_NAMES
from ionic_usd.usd.city_prototypes import (
    instance_bounds,
    prim_identifier,
    prototype_purpose_stats,
    prototype_stats,
    purpose_bounds,
    temple_selection,
    temple_variant_sets,
)
from ionic_usd.usd.draw_mode import CARD_FACES, author_cards
from ionic_usd.usd.stage import new_layer, save_layer

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

#: triangles of a box of cards as a renderer draws it: six quads
CARD_TRIANGLES = 12

ROOT_LAYER = CITY_ROOT_LAYER
INSTANCES_LAYER = CITY_INSTANCES_LAYER
#: the variant selections of the street columns' card prototype (besides ``finish``): what a
#: consumer that ignores draw modes draws for a far column, and what its cards are baked from
COLUMN_CARD_SELECTION = {"lod": "low", "form": "full"}
_T = Sdf.ValueTypeNames


@dataclass(frozen=True)
class TempleInstances:
    """Temples of a city as arrays (n temples, b builds).

    Attributes
    ----------
    folders : (b,) build folders relative to the city (``Temples/<name>-<key>``)
    build : (n,) int — build of each temple
    names : (n,) lot ids
    xz : (n, 2) float — USD x, z translation; yaw : (n,) degrees about +Y; scale : (n,)
    selections : (n,) hypothesis id → "baseline" | "alternative" per temple (ids the build
        does not realise are ignored)
    lod : (n,) int8 index into LOD_NAMES, or None (no lod selection)
    cards : (n,) bool — drawn as cards (far field), or None (none); a card temple's prototype
        carries ``UsdGeomModelAPI`` draw mode cards with the images of ``card_dirs``
    """

    folders: Sequence[str]
    build: np.ndarray
    names: Sequence[str]
    xz: np.ndarray
    yaw: np.ndarray
    scale: np.ndarray
    selections: Sequence[Mapping[str, str]]
    lod: np.ndarray | None = None
    cards: np.ndarray | None = None

    def __len__(self) -> int:
        return len(self.build)


@dataclass(frozen=True)
class ColumnInstances:
    """Street columns as arrays: ``asset`` (city-relative path of the column asset folder's
    root layer), ``xz`` (m, 2), ``yaw`` (m,) degrees, ``lod`` (m,) int8 (None: all low),
    ``cards`` (m,) bool — drawn by the card prototype (far field), or None (none)."""

    asset: str
    xz: np.ndarray
    yaw: np.ndarray
    lod: np.ndarray | None = None
    cards: np.ndarray | None = None

    def __len__(self) -> int:
        return len(self.xz)


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


def _default_render(lo4: np.ndarray, hi4: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    ok = [k for k in (0, 1) if np.all(lo4[k] <= hi4[k])]
    if not ok:
        return np.zeros(3), np.zeros(3)
    return lo4[ok].min(axis=0), hi4[ok].max(axis=0)


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
    if not force:
        for p in (root_path, body_path):
            if p.exists():
                raise OutputExistsError(f"{p} exists; pass --force to overwrite it")
    if not isinstance(instancer_threshold, int) or instancer_threshold < 0:
        raise ParameterError("instancer threshold", instancer_threshold, "an integer >= 0")
    secs: dict[str, float] = {}

    # -- temple prototypes: unique (build, realised selections, lod) ---------------------------
    vsets = [temple_variant_sets(folder / f / "Temple.usda") for f in temples.folders]
    keys: dict[tuple, int] = {}
    proto_of = np.zeros(len(temples), dtype=np.int32)
    for i in range(len(temples)):
        b = int(temples.build[i])
        card = temples.cards is not None and bool(temples.cards[i])
        lod = LOD_NAMES[int(temples.lod[i])] if temples.lod is not None and not card else None
        sel = temple_selection(vsets[b], temples.selections[i], lod)
        key = (b, tuple(sorted(sel.items())), card)
        if card and (card_dirs is None or key[:2] not in card_dirs):
            raise ParameterError(
                "card images",
                f"temple {temples.names[i]}",
                "a folder of baked cards for every temple drawn as cards (card_dirs)",
            )
        proto_of[i] = keys.setdefault(key, len(keys))
    protos = list(keys)

    # per-prototype bounds and triangles, from each build's own stage (not the city)
    t1 = time.perf_counter()
    tlo, thi = np.zeros((len(protos), 3)), np.zeros((len(protos), 3))
    tlo4, thi4 = np.zeros((len(protos), 4, 3)), np.zeros((len(protos), 4, 3))
    ttri: dict[str, np.ndarray] = {
        s: np.zeros(len(protos), dtype=np.int64) for s in ("as authored", *LOD_NAMES)
    }
    stages: dict[int, Usd.Stage] = {}
    for k, (b, sel, card) in enumerate(protos):
        stage = stages.get(b) or Usd.Stage.Open(str(folder / temples.folders[b] / "Temple.usda"))
        stages[b] = stage
        tlo4[k], thi4[k], ttri["as authored"][k] = prototype_purpose_stats(
            stage, "/Temple", dict(sel)
        )
        lo, hi = _default_render(tlo4[k], thi4[k])
        if card:  # a box of cards stands in for the temple
            ttri["as authored"][k] = CARD_TRIANGLES
        tlo[k], thi[k] = lo, hi
        for lod in LOD_NAMES:
            if "lod" in vsets[b]:
                ttri[lod][k] = prototype_stats(stage, "/Temple", {**dict(sel), "lod": lod})[2]
            else:  # before the temple has a lod set its columns draw as authored
                ttri[lod][k] = prototype_stats(stage, "/Temple", dict(sel))[2]
    # the street columns' prototypes: the column asset at each LOD used by a near column,
    # then (index len(col_lods)) the card prototype for the far ones
    ccard = (
        np.zeros(len(columns), dtype=bool)
        if columns.cards is None
        else np.asarray(columns.cards, dtype=bool)
    )
    if ccard.shape != (len(columns),):
        raise ParameterError("column cards", ccard.shape, f"({len(columns)},) bools")
    if ccard.any() and not column_card_dir:
        raise ParameterError(
            "column card images",
            "none",
            "a folder of baked cards for the far street columns (column_card_dir)",
        )
    near_lod = (
        np.asarray(columns.lod)[~ccard]
        if columns.lod is not None
        else np.full(int((~ccard).sum()), 2)
    )
    col_lods = sorted(set(np.unique(near_lod).tolist()))
    cidx = np.full(len(columns), len(col_lods), dtype=np.int32)
    cidx[~ccard] = np.searchsorted(col_lods, near_lod).astype(np.int32)
    card_li = LOD_NAMES.index(COLUMN_CARD_SELECTION["lod"])
    box_lods = col_lods + ([card_li] if ccard.any() else [])
    clo, chi = np.zeros((len(box_lods), 3)), np.zeros((len(box_lods), 3))
    clo4, chi4 = np.zeros((len(box_lods), 4, 3)), np.zeros((len(box_lods), 4, 3))
    col_tri = {}
    if len(columns):
        cstage = Usd.Stage.Open(str(folder / columns.asset))
        if cstage is None:
            raise UsdAuthoringError(f"cannot open the column asset {folder / columns.asset}")
        root = str(cstage.GetDefaultPrim().GetPath())
        for k, li in enumerate(box_lods):
            clo4[k], chi4[k], _ = prototype_purpose_stats(
                cstage, root, {"lod": LOD_NAMES[li], "form": "full", "finish": finish}
            )
            clo[k], chi[k] = _default_render(clo4[k], chi4[k])
        for lod in LOD_NAMES:
            col_tri[lod] = prototype_stats(
                cstage, root, {"lod": lod, "form": "full", "finish": finish}
            )[2]
    secs["prototype stats"] = time.perf_counter() - t1

    # -- author ----------------------------------------------------------------------------------
    t2 = time.perf_counter()
    as_instancer = len(temples) > instancer_threshold
    t_ext = instance_bounds(tlo, thi, proto_of, temples.xz, temples.yaw, temples.scale)
    c_ext = instance_bounds(clo, chi, cidx, columns.xz, columns.yaw, None)
    body = new_layer("City", kind="assembly")
    with Sdf.ChangeBlock():
        _group(body, "/City/Temples")
        refs = [f"./{temples.folders[b]}/Temple.usda" for b, _, _ in protos]
        dirs = [card_dirs[(b, sel)] if card and card_dirs else None for b, sel, card in protos]
        if as_instancer:
            _instancer(
                body,
                "/City/Temples/Field",
                [
                    (f"Temple_{k}", refs[k], dict(sel), dirs[k])
                    for k, (_, sel, _) in enumerate(protos)
                ],
                proto_of,
                temples.xz,
                temples.yaw,
                temples.scale,
                t_ext,
            )
        else:
            used: set[str] = set()
            for i in range(len(temples)):
                name = prim_identifier(f"Temple_{temples.names[i]}")
                while name in used:
                    name += "_"
                used.add(name)
                spec = Sdf.CreatePrimInLayer(body, f"/City/Temples/{name}")
                spec.specifier, spec.typeName = Sdf.SpecifierDef, "Xform"
                spec.instanceable = True
                k = int(proto_of[i])
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
        if len(columns):
            cprotos: list[tuple[str, str, dict[str, str], str | None]] = [
                (
                    f"Column_{LOD_NAMES[li]}",
                    f"./{columns.asset}",
                    {"lod": LOD_NAMES[li], "form": "full", "finish": finish},
                    None,
                )
                for li in col_lods
            ]
            if ccard.any():
                cprotos.append(
                    (
                        "Column_cards",
                        f"./{columns.asset}",
                        {**COLUMN_CARD_SELECTION, "finish": finish},
                        column_card_dir,
                    )
                )
            _instancer(body, "/City/Porticus", cprotos, cidx, columns.xz, columns.yaw, None, c_ext)
        extra_tris = _stoa_and_ground(body, stoa, ground)
    # the city's extentsHint per purpose (default, render, proxy, guide), as BBoxCache with
    # useExtentsHint reads it: the union of the placed prototypes' bounds of that purpose
    # (a PointInstancer is bounded by its authored extent, which counts for its own purpose,
    # default: the street columns and a field of temples enter the default range)
    c4 = _as_default(c_ext, len(columns))
    if as_instancer:
        t4 = _as_default(t_ext, len(temples))
    else:
        t4 = purpose_bounds(tlo4, thi4, proto_of, temples.xz, temples.yaw, temples.scale)
    lo4, hi4 = np.minimum(t4[0], c4[0]), np.maximum(t4[1], c4[1])
    for elo, ehi in extra_tris[1]:  # the stoas' instancer and the ground: default purpose
        lo4[0], hi4[0] = np.minimum(lo4[0], elo), np.maximum(hi4[0], ehi)
    lo, hi = _default_render(lo4, hi4)
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
    counts = np.bincount(proto_of, minlength=len(protos))
    ccounts = np.bincount(cidx[~ccard], minlength=len(col_lods))
    triangles = {}
    for s in ("as authored", *LOD_NAMES):
        if not len(columns):
            col = 0
        elif s == "as authored":
            col = int(
                sum(
                    col_tri[LOD_NAMES[li]] * int(c) for li, c in zip(col_lods, ccounts, strict=True)
                )
            )
            col += CARD_TRIANGLES * int(ccard.sum())
        else:
            col = col_tri[s] * len(columns)
        triangles[s] = int(np.dot(counts, ttri[s])) + col + extra_tris[0]
    far_t = temples.cards is not None and bool(np.any(temples.cards))
    if far_t or ccard.any():
        # the same city with each card temple and column at its LOD by distance instead
        instead = 0
        if ccard.any():
            clods = (
                np.asarray(columns.lod)[ccard]
                if columns.lod is not None
                else np.full(int(ccard.sum()), 2)
            )
            per_lod = np.bincount(clods.astype(np.int64), minlength=len(LOD_NAMES))
            instead += int(
                sum(col_tri[name] * int(c) for name, c in zip(LOD_NAMES, per_lod, strict=True))
            )
        triangles["without cards"] = (
            triangles["as authored"] + instead - CARD_TRIANGLES * int(ccard.sum())
        )
    if far_t and temples.cards is not None:
        # the same city with each card temple at its LOD by distance instead of its cards
        far = np.flatnonzero(temples.cards)
        lods = (
            np.asarray(temples.lod)[far]
            if temples.lod is not None
            else np.zeros(len(far), dtype=np.int8)
        )
        instead = sum(
            int(ttri[LOD_NAMES[int(li)]][proto_of[i]]) for i, li in zip(far, lods, strict=True)
        )
        triangles["without cards"] += instead - CARD_TRIANGLES * len(far)
    if summary is not None:
        city.customData = {"ionic_usd": _vt_dict(summary)}
    secs["author"] = time.perf_counter() - t2
    t3 = time.perf_counter()
    folder.mkdir(parents=True, exist_ok=True)
    save_layer(body, body_path, force=True)
    save_layer(root, root_path, force=True)
    secs["save"] = time.perf_counter() - t3
    secs["total"] = time.perf_counter() - t0
    return CityReport(
        root_path,
        len(temples),
        len(protos),
        len(temples.folders),
        len(columns),
        len(col_lods) + int(ccard.any()) if len(columns) else 0,
        "point-instancer" if as_instancer else "references",
        triangles,
        (tuple(map(float, lo)), tuple(map(float, hi))),
        secs,
    )


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


def _vt_dict(d: Mapping) -> dict:
    """A JSON-like mapping as USD customData (lists of strings/numbers as arrays)."""
    out: dict = {}
    for k, v in d.items():
        if isinstance(v, Mapping):
            out[str(k)] = _vt_dict(v)
        elif isinstance(v, (list, tuple)):
            if any(isinstance(x, Mapping) for x in v):
                continue  # per-lot records stay in the JSON summary
            if all(isinstance(x, str) for x in v):
                out[str(k)] = Vt.StringArray([str(x) for x in v])
            else:
                out[str(k)] = Vt.DoubleArray([float(x) for x in v])
        elif isinstance(v, bool) or isinstance(v, (int, float, str)):
            out[str(k)] = v
    return out


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
