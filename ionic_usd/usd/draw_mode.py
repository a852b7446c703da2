"""Card draw mode (``UsdGeomModelAPI``): authoring it on a model, and reading it as a viewer does.

A model (a prim with a model ``kind``) with ``model:applyDrawMode = true`` whose resolved
``model:drawMode`` (inherited down the namespace) is ``cards`` is imaged as textured quads in
place of its subtree. ``model:cardGeometry`` chooses the quads: ``box`` — the six faces of the
model's bound, ``cross`` — three quads through its centre, one per axis, each seen from both
sides. ``model:cardTexture{X,Y,Z}{Pos,Neg}`` are the images: the face ``XPos`` shows the model
seen from +X (an orthographic view along −X), and so on.

Our image convention for the view along each face normal ``n`` (kept by the baker,
:func:`ionic_usd.preview.bake_cards`, and by the reader): image right is the vector ``right``,
image up ``up`` of :data:`CARD_FACES` (``right × up = n``), so a face shows its view unmirrored
from outside; ``st`` (0, 0) is the image's bottom-left corner (UsdUVTexture's convention).

The card bound is what a viewer uses: the model's ``extentsHint`` where authored, else the
bound of its default/render geometry (``UsdGeom.BBoxCache`` with extents hints).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
from pxr import Sdf, Usd, UsdGeom

__all__ = ["CARD_FACES", "CARD_GEOMETRIES", "CardFace", "card_faces", "card_bound",
           "card_bbox_cache", "card_colour", "author_cards", "face_quad"]

#: face name → (outward normal, image right, image up), all unit axis vectors
CARD_FACES: dict[str, tuple[tuple[int, int, int], tuple[int, int, int], tuple[int, int, int]]] = {
    "XPos": ((1, 0, 0), (0, 0, -1), (0, 1, 0)),
    "XNeg": ((-1, 0, 0), (0, 0, 1), (0, 1, 0)),
    "YPos": ((0, 1, 0), (1, 0, 0), (0, 0, -1)),
    "YNeg": ((0, -1, 0), (1, 0, 0), (0, 0, 1)),
    "ZPos": ((0, 0, 1), (1, 0, 0), (0, 1, 0)),
    "ZNeg": ((0, 0, -1), (-1, 0, 0), (0, 1, 0)),
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
    st : (4, 2) float64 texture coordinates of the corners
    texture : the resolved image file, or "" (drawn in ``model:drawModeColor``)
    """

    name: str
    points: np.ndarray
    st: np.ndarray
    texture: str


def face_quad(name: str, lo: np.ndarray, hi: np.ndarray, geometry: str = "box"
              ) -> np.ndarray:
    """(4, 3) corners of face ``name`` of the bound ``lo``, ``hi`` (each (3,)): on the bound's
    side (``box``) or through its centre (``cross``), ordered as ``st`` (0,0) (1,0) (1,1) (0,1)."""
    n, r, u = (np.asarray(v, dtype=np.float64) for v in CARD_FACES[name])
    lo, hi = np.asarray(lo, dtype=np.float64), np.asarray(hi, dtype=np.float64)
    c, h = (lo + hi) / 2, (hi - lo) / 2
    centre = c + (n * h if geometry == "box" else 0.0)
    hr, hu = np.abs(r) @ h, np.abs(u) @ h
    return np.array([centre + sr * hr * r + su * hu * u
                     for sr, su in ((-1, -1), (1, -1), (1, 1), (-1, 1))])


_ST = np.array([(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)])


def card_faces(prim: Usd.Prim, bbox: UsdGeom.BBoxCache) -> list[CardFace] | None:
    """The card quads a viewer draws for ``prim``, or None when its draw mode is not cards.

    Cards apply on a model (``prim.IsModel()``) with ``model:applyDrawMode = true`` and a
    resolved ``model:drawMode`` of ``cards``. A face with no texture is drawn in the draw mode
    colour; a ``box`` face whose texture is missing takes the opposite face's (as Hydra does).
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
    out = []
    for name in CARD_FACES:
        tex = textures[name]
        if not tex and geometry == "box":
            tex = textures[name[0] + ("Neg" if name.endswith("Pos") else "Pos")]
        out.append(CardFace(name, face_quad(name, lo, hi, geometry), _ST.copy(), tex))
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
    return UsdGeom.BBoxCache(Usd.TimeCode.Default(), [UsdGeom.Tokens.default_,
                                                      UsdGeom.Tokens.render],
                             useExtentsHint=True)


def card_colour(prim: Usd.Prim) -> tuple[float, float, float]:
    """``model:drawModeColor`` (linear RGB; schema fallback 0.18 grey)."""
    attr = UsdGeom.ModelAPI(prim).GetModelDrawModeColorAttr()
    v = attr.Get() if attr else None
    return tuple(float(x) for x in v) if v is not None else (0.18, 0.18, 0.18)  # type: ignore


def author_cards(spec: Sdf.PrimSpec, textures: Mapping[str, str], *,
                 geometry: str = "box", colour: tuple[float, float, float] | None = None
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
            float(c) for c in colour)
    for name, asset in textures.items():
        if name not in CARD_FACES:
            raise ValueError(f"card face {name!r}: expected one of {', '.join(CARD_FACES)}")
        Sdf.AttributeSpec(spec, f"model:cardTexture{name}", _T.Asset).default = Sdf.AssetPath(
            asset)
