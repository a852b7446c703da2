"""Card draw mode (``UsdGeomModelAPI``): authoring it on a model, and reading it as a viewer does.

A model (a prim with a model ``kind``) with ``model:applyDrawMode = true`` whose resolved
``model:drawMode`` (inherited down the namespace) is ``cards`` is imaged as textured quads in
place of its subtree. ``model:cardGeometry`` chooses the quads: ``box`` — the six faces of the
model's bound, ``cross`` — three quads through its centre, one per axis, each seen from both
sides. ``model:cardTexture{X,Y,Z}{Pos,Neg}`` are the images: the face ``XPos`` shows the model
seen from +X (an orthographic view along −X), and so on.

The image convention is Hydra's (UsdImaging ``drawModeAdapter.cpp``
``_GenerateCardsGeometry`` + ``_GenerateTextureCoordinates``, and ``drawModeStandin.cpp``
``_CardsDataCache::_CardsData::_ComputePoints`` / ``_ComputeUVs``, which agree): for the face with
outward normal ``n`` the image's ``s`` (right) runs along ``right`` and its ``t`` (up) along
``up`` of :data:`CARD_FACES`. The four side faces have ``t`` along the model's +Z whatever the
stage's ``upAxis`` — Hydra's cards are Z-up — and ``ZPos``/``ZNeg`` have ``s`` along +X, ``t``
along +Y/−Y. Every face shows its view from outside unmirrored (``right × up = n``). ``st``
(0, 0) is the image's bottom-left corner (UsdUVTexture's convention). A face whose texture is
not authored shows the opposite face's image with the opposite face's mapping (the model seen
through), and an axis with no texture on either side has no faces, unless no face has a
texture, when all six are drawn in ``model:drawModeColor``.

The card bound is what a viewer uses: the model's ``extentsHint`` where authored, else the
bound of its default/render geometry (``UsdGeom.BBoxCache`` with extents hints).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
from pxr import Sdf, Usd, UsdGeom

__all__ = [
    "CARD_FACES",
    "CARD_GEOMETRIES",
    "CardFace",
    "card_faces",
    "card_bound",
    "card_bbox_cache",
    "card_colour",
    "author_cards",
    "face_quad",
    "face_st",
]

#: face name → (outward normal, image right, image up), all unit axis vectors
CARD_FACES: dict[str, tuple[tuple[int, int, int], tuple[int, int, int], tuple[int, int, int]]] = {
    "XPos": ((1, 0, 0), (0, 1, 0), (0, 0, 1)),
    "XNeg": ((-1, 0, 0), (0, -1, 0), (0, 0, 1)),
    "YPos": ((0, 1, 0), (-1, 0, 0), (0, 0, 1)),
    "YNeg": ((0, -1, 0), (1, 0, 0), (0, 0, 1)),
    "ZPos": ((0, 0, 1), (1, 0, 0), (0, 1, 0)),
    "ZNeg": ((0, 0, -1), (1, 0, 0), (0, -1, 0)),
}
CARD_GEOMETRIES = ("box", "cross")
_T = Sdf.ValueTypeNames


@dataclass(frozen=True)
class CardFace:
    """One card quad in the model's own space.

    Attributes
    ----------
    name : ``XPos`` … ``ZNeg``
    points : (4, 3) float64, counter-clockwise seen from the side the face shows
    st : (4, 2) float64 texture coordinates of the corners (in the mapping of the face whose
        image it shows: its own, or the opposite face's when it borrows that image)
    texture : the resolved image file, or "" (drawn in ``model:drawModeColor``)
    """

    name: str
    points: np.ndarray
    st: np.ndarray
    texture: str


def face_quad(name: str, lo: np.ndarray, hi: np.ndarray, geometry: str = "box") -> np.ndarray:
    """(4, 3) corners of face ``name`` of the bound ``lo``, ``hi`` (each (3,)): on the bound's
    side (``box``) or through its centre (``cross``), ordered as ``st`` (0,0) (1,0) (1,1) (0,1)."""
    n, r, u = (np.asarray(v, dtype=np.float64) for v in CARD_FACES[name])
    lo, hi = np.asarray(lo, dtype=np.float64), np.asarray(hi, dtype=np.float64)
    c, h = (lo + hi) / 2, (hi - lo) / 2
    centre = c + (n * h if geometry == "box" else 0.0)
    hr, hu = np.abs(r) @ h, np.abs(u) @ h
    return np.array(
        [centre + sr * hr * r + su * hu * u for sr, su in ((-1, -1), (1, -1), (1, 1), (-1, 1))]
    )


def face_st(name: str, points: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """(n, 2) texture coordinates of ``points`` (n, 3) in face ``name``'s image of the bound
    ``lo``, ``hi``: ``s`` along the face's ``right``, ``t`` along its ``up``, 0..1 on the bound."""
    _, r, u = (np.asarray(v, dtype=np.float64) for v in CARD_FACES[name])
    lo, hi = np.asarray(lo, dtype=np.float64), np.asarray(hi, dtype=np.float64)
    c, h = (lo + hi) / 2, np.maximum((hi - lo) / 2, 1e-300)
    d = np.asarray(points, dtype=np.float64) - c
    return np.stack(
        [0.5 + 0.5 * (d @ r) / (np.abs(r) @ h), 0.5 + 0.5 * (d @ u) / (np.abs(u) @ h)], axis=-1
    )


def _opposite(name: str) -> str:
    return name[0] + ("Neg" if name.endswith("Pos") else "Pos")


def card_faces(prim: Usd.Prim, bbox: UsdGeom.BBoxCache) -> list[CardFace] | None:
    """The card quads a viewer draws for ``prim``, or None when its draw mode is not cards.

    Cards apply on a model (``prim.IsModel()``) with ``model:applyDrawMode = true`` and a
    resolved ``model:drawMode`` of ``cards``. As Hydra does (``drawModeStandin.cpp``,
    ``_CardsDataCache::_SchemaValues``): an axis is drawn (both its faces) when either of its
    faces has a texture; a face without one borrows the opposite face's image and mapping; with
    no texture at all, all six faces are drawn in the draw mode colour.
    """
    if not prim.IsModel():
        return None
    apply = prim.GetAttribute("model:applyDrawMode")
    if not (apply and apply.Get()):
        return None
    api = UsdGeom.ModelAPI(prim)
    if api.ComputeModelDrawMode() != UsdGeom.Tokens.cards:
        return None
    geometry = str(api.GetModelCardGeometryAttr().Get() or "cross")
    geometry = geometry if geometry in CARD_GEOMETRIES else "cross"  # fromTexture: not read
    bound = card_bound(prim, bbox)
    if bound is None:
        return None
    lo, hi = bound
    textures = {}
    for name in CARD_FACES:
        attr = prim.GetAttribute(f"model:cardTexture{name}")
        asset = attr.Get() if attr else None
        textures[name] = getattr(asset, "resolvedPath", "") or ""
    authored = {name for name in CARD_FACES if textures[name]}
    out = []
    for name in CARD_FACES:
        if authored and not authored & {name, _opposite(name)}:
            continue  # Hydra draws no face on an axis without any texture
        owner = name if name in authored or not authored else _opposite(name)
        points = face_quad(name, lo, hi, geometry)
        out.append(CardFace(name, points, face_st(owner, points, lo, hi), textures[owner]))
    return out


def card_bound(prim: Usd.Prim, bbox: UsdGeom.BBoxCache) -> tuple[np.ndarray, np.ndarray] | None:
    """The box a viewer puts cards on: ``prim``'s bound in its own space (its transform
    excluded; ``extentsHint`` used where authored), as ``(lo (3,), hi (3,))``; None if empty."""
    rng = bbox.ComputeUntransformedBound(prim).ComputeAlignedRange()
    if rng.IsEmpty():
        return None
    return np.array(rng.GetMin()), np.array(rng.GetMax())


def card_bbox_cache() -> UsdGeom.BBoxCache:
    """The bound cache :func:`card_bound` expects: default time, default + render purposes,
    extents hints used (as Hydra's draw modes read them)."""
    return UsdGeom.BBoxCache(
        Usd.TimeCode.Default(),
        [UsdGeom.Tokens.default_, UsdGeom.Tokens.render],
        useExtentsHint=True,
    )


def card_colour(prim: Usd.Prim) -> tuple[float, float, float]:
    """``model:drawModeColor`` (linear RGB; schema fallback 0.18 grey)."""
    attr = UsdGeom.ModelAPI(prim).GetModelDrawModeColorAttr()
    v = attr.Get() if attr else None
    return tuple(float(x) for x in v) if v is not None else (0.18, 0.18, 0.18)  # type: ignore


def author_cards(
    spec: Sdf.PrimSpec,
    textures: Mapping[str, str],
    *,
    geometry: str = "box",
    colour: tuple[float, float, float] | None = None,
) -> None:
    """Author card draw mode on a model's prim spec: ``GeomModelAPI`` applied,
    ``model:drawMode = cards``, ``model:applyDrawMode = true``, ``model:cardGeometry`` and one
    ``model:cardTexture<Face>`` asset path per entry of ``textures`` (face name → asset path,
    relative to the spec's layer)."""
    if geometry not in CARD_GEOMETRIES:
        raise ValueError(f"card geometry {geometry!r}: expected one of {CARD_GEOMETRIES}")
    api = spec.GetInfo("apiSchemas") if spec.HasInfo("apiSchemas") else Sdf.TokenListOp()
    items = list(api.prependedItems)
    if "GeomModelAPI" not in items:
        api.prependedItems = [*items, "GeomModelAPI"]
    spec.SetInfo("apiSchemas", api)
    uniform = Sdf.VariabilityUniform
    Sdf.AttributeSpec(spec, "model:drawMode", _T.Token, uniform).default = "cards"
    Sdf.AttributeSpec(spec, "model:applyDrawMode", _T.Bool, uniform).default = True
    Sdf.AttributeSpec(spec, "model:cardGeometry", _T.Token, uniform).default = geometry
    if colour is not None:
        Sdf.AttributeSpec(spec, "model:drawModeColor", _T.Float3, uniform).default = tuple(
            float(c) for c in colour
        )
    for name, asset in textures.items():
        if name not in CARD_FACES:
            raise ValueError(f"card face {name!r}: expected one of {', '.join(CARD_FACES)}")
        Sdf.AttributeSpec(spec, f"model:cardTexture{name}", _T.Asset).default = Sdf.AssetPath(asset)
