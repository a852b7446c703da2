"""Author :class:`~ionic_usd.column.ornament.Instances` as a ``UsdGeom.PointInstancer``.

Layout of one instancer (Sdf API, so it can be written into any layer, a variant included)::

    def PointInstancer "<Name>"     positions, orientations (quath), scales, protoIndices,
                                    extent, prototypes → <Name>/Prototypes/*
        def Scope "Prototypes"
            def Mesh "<Prototype>"  one small closed mesh each

Prototypes live under their instancer (UsdGeom's recommendation), so renderers draw them only
through it.
"""

from __future__ import annotations

import numpy as np
from pxr import Gf, Sdf, Usd, UsdGeom, Vt

from ionic_usd.column.ornament import Instances
from ionic_usd.usd.mesh import author_mesh, define_prim

__all__ = ["author_point_instancer", "instances_extent", "bind_spec", "drawn_triangles"]

_T = Sdf.ValueTypeNames


def instances_extent(inst: Instances) -> np.ndarray:
    """(2, 3) bounds of all copies (each prototype's box corners, transformed)."""
    if len(inst) == 0:
        return np.zeros((2, 3))
    boxes = []
    for k, proto in enumerate(inst.prototypes):
        sel = inst.proto_indices == k
        if not sel.any():
            continue
        lo, hi = proto.extent
        corners = np.array(
            [[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])]
        )
        m = inst.matrices()[sel]
        pts = np.einsum("nij,cj->nci", m[:, :3, :3], corners) + m[:, None, :3, 3]
        boxes.append(pts.reshape(-1, 3))
    allp = np.concatenate(boxes)
    return np.stack([allp.min(axis=0), allp.max(axis=0)])


def drawn_triangles(root: Usd.Prim, _memo: dict | None = None) -> int:
    """Triangles a renderer draws under ``root``: the one count every scene report uses.

    Meshes count once; every copy of a native instance and of a PointInstancer counts
    (prototypes under an instancer are drawn only through it, nested instancers multiply);
    default and render purpose only (proxy and guide subtrees skipped), invisible subtrees
    and inactive prims skipped.
    """
    memo: dict[str, int] = {} if _memo is None else _memo
    total = 0
    it = iter(Usd.PrimRange(root))
    for prim in it:
        img = UsdGeom.Imageable(prim)
        if img and (
            img.GetPurposeAttr().Get() in (UsdGeom.Tokens.proxy, UsdGeom.Tokens.guide)
            or img.GetVisibilityAttr().Get() == UsdGeom.Tokens.invisible
        ):
            it.PruneChildren()
            continue
        if prim != root and prim.IsInstance():
            it.PruneChildren()
            proto = prim.GetPrototype()
            key = str(proto.GetPath())
            if key not in memo:
                memo[key] = drawn_triangles(proto, memo)
            total += memo[key]
        elif prim.IsA(UsdGeom.PointInstancer):
            it.PruneChildren()
            pi = UsdGeom.PointInstancer(prim)
            idx = np.asarray(pi.GetProtoIndicesAttr().Get() or [], dtype=np.int64)
            per = [
                drawn_triangles(prim.GetStage().GetPrimAtPath(t), memo)
                for t in pi.GetPrototypesRel().GetForwardedTargets()
            ]
            if len(idx) and per:
                total += int(np.asarray(per)[idx[idx < len(per)]].sum())
        elif prim.IsA(UsdGeom.Mesh):
            counts = UsdGeom.Mesh(prim).GetFaceVertexCountsAttr().Get()
            total += int(np.sum(np.asarray(counts) - 2)) if counts is not None else 0
    return total


def bind_spec(spec: Sdf.PrimSpec, material_path: str) -> None:
    """Bind a material to a prim spec (MaterialBindingAPI applied), Sdf level."""
    spec.SetInfo("apiSchemas", Sdf.TokenListOp.Create(prependedItems=["MaterialBindingAPI"]))
    rel = spec.relationships.get("material:binding")
    if rel is None:
        rel = Sdf.RelationshipSpec(spec, "material:binding", custom=False)
    rel.targetPathList.explicitItems = [Sdf.Path(material_path)]


def author_point_instancer(
    layer: Sdf.Layer, path: str | Sdf.Path, inst: Instances, *, material: str | None = None
) -> Sdf.PrimSpec:
    """Write ``inst`` as a PointInstancer at ``path`` (see the module docstring).

    Parameters
    ----------
    layer : the layer to author into
    path : the instancer's prim path
    inst : the copies and their prototypes
    material : optional material path bound on the instancer
    """
    path = Sdf.Path(str(path))
    spec = define_prim(layer, path, "PointInstancer")
    define_prim(layer, path.AppendChild("Prototypes"), "Scope")
    targets = []
    for proto in inst.prototypes:
        p = path.AppendChild("Prototypes").AppendChild(proto.name)
        author_mesh(layer, p, proto)
        targets.append(p)
    rel = Sdf.RelationshipSpec(spec, "prototypes", custom=False)
    rel.targetPathList.explicitItems = targets
    q = inst.orientations[:, [1, 2, 3, 0]]  # (w, x, y, z) → GfQuath's memory order (x, y, z, w)

    def attr(name, tname, value):
        Sdf.AttributeSpec(spec, name, tname).default = value

    attr("protoIndices", _T.IntArray, Vt.IntArray.FromNumpy(inst.proto_indices))
    attr(
        "positions",
        _T.Point3fArray,
        Vt.Vec3fArray.FromNumpy(np.ascontiguousarray(inst.positions, dtype=np.float32)),
    )
    attr(
        "orientations",
        _T.QuathArray,
        Vt.QuathArray.FromNumpy(np.ascontiguousarray(q, dtype=np.float16)),
    )
    attr(
        "scales",
        _T.Float3Array,
        Vt.Vec3fArray.FromNumpy(np.ascontiguousarray(inst.scales, dtype=np.float32)),
    )
    ext = instances_extent(inst)
    attr("extent", _T.Float3Array, Vt.Vec3fArray([Gf.Vec3f(*ext[0]), Gf.Vec3f(*ext[1])]))
    if material is not None:
        bind_spec(spec, material)
    return spec
