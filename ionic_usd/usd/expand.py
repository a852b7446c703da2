"""Point instancers expanded into plain meshes, for the ARKit profile of usdz packages.

Apple's ARKit profile (usd-core's ``UsdUtils.ComplianceChecker(arkit=True)``) does not allow
``PointInstancer`` prims: AR Quick Look drops them, and with them a temple's dentils, roof tiles
and the capitals' egg-and-dart and bead-and-reel. :func:`expand_point_instancers` rewrites a
(flattened) stage so that each point instancer becomes an ``Xform`` at the same path holding,
for every mesh of every prototype, one ``Mesh`` with all its copies baked in (points moved,
normals by the inverse transpose, faces of mirrored copies reversed, primvars repeated per
copy). A prototype of more than :data:`BAKE_MAX_TRIANGLES` triangles (a city street's
columns) is not baked copy by copy: it is kept once under the class
:data:`PROTOTYPES_ROOT` and each copy becomes an instanceable ``Xform`` referencing it (native
instancing, which ARKit allows). The prototypes, no longer referenced, are removed (materials
inside them copied out first). What is drawn stays the same: the
instancer's own transform, visibility and purpose are kept on the Xform, each baked mesh keeps
the material its prototype was bound to.

Instancers are expanded deepest first, so an instancer inside another's prototype is a mesh by
the time the outer one is baked; prims inside native instances are read through instance
proxies (an instancer *inside* a native prototype is edited in that prototype, once).
"""

from __future__ import annotations

import numpy as np
from pxr import Gf, Sdf, Usd, UsdGeom, UsdShade, Vt

from ionic_usd.errors import UsdAuthoringError

__all__ = ["expand_point_instancers", "normals_as_attributes"]

_INSTANCER_PROPS = (
    "positions",
    "orientations",
    "orientationsf",
    "scales",
    "protoIndices",
    "prototypes",
    "ids",
    "invisibleIds",
    "velocities",
    "angularVelocities",
    "accelerations",
    "extent",
)
_PREDICATE = Usd.TraverseInstanceProxies(Usd.PrimAllPrimsPredicate)
#: a prototype of more triangles than this (a street's columns) is placed as native instances
#: of one copy of it, kept under :data:`PROTOTYPES_ROOT`, instead of baked copy by copy
BAKE_MAX_TRIANGLES = 2000
PROTOTYPES_ROOT = Sdf.Path("/_ExpandedPrototypes")


def _triangles(proto: Usd.Prim) -> int:
    n = 0
    for p in Usd.PrimRange(proto, _PREDICATE):
        if p.IsA(UsdGeom.Mesh):
            counts = p.GetAttribute("faceVertexCounts").Get()
            n += int(np.sum(np.asarray(counts) - 2)) if counts else 0
    return n


def _as_instances(
    stage: Usd.Stage, owner: Sdf.Path, target: Sdf.Path, mats: np.ndarray, names: set[str]
) -> None:
    """One instanceable ``Xform`` per matrix of ``mats`` under ``owner``, each referencing a
    copy of the prototype ``target`` kept under the class :data:`PROTOTYPES_ROOT`. ``mats``
    include the prototype root's own transform: the copies' ``xformOpOrder`` (a stronger
    opinion than the referenced root's) leaves the root's own ops unused."""
    layer = stage.GetEditTarget().GetLayer()
    if not layer.GetPrimAtPath(PROTOTYPES_ROOT):
        Sdf.CreatePrimInLayer(layer, PROTOTYPES_ROOT).specifier = Sdf.SpecifierClass
    base = f"{str(owner).strip('/').replace('/', '_')}_{target.name}"
    name, i = base, 1
    while layer.GetPrimAtPath(PROTOTYPES_ROOT.AppendChild(name)):
        name, i = f"{base}_{i}", i + 1
    dst = PROTOTYPES_ROOT.AppendChild(name)
    src = next((x for x in stage.GetPrimAtPath(target).GetPrimStack() if x.layer == layer), None)
    if src is None or not Sdf.CopySpec(layer, src.path, layer, dst):
        raise UsdAuthoringError(f"{target}: could not keep the prototype as {dst}")
    with Sdf.ChangeBlock():
        for k, m in enumerate(mats):
            child = f"{target.name}_{k}"
            while child in names:
                child += "_"
            names.add(child)
            spec = Sdf.CreatePrimInLayer(layer, owner.AppendChild(child))
            spec.specifier, spec.typeName, spec.instanceable = Sdf.SpecifierDef, "Xform", True
            spec.referenceList.Prepend(Sdf.Reference(primPath=dst))
            op = Sdf.AttributeSpec(spec, "xformOp:transform", Sdf.ValueTypeNames.Matrix4d)
            op.default = Gf.Matrix4d(*(float(x) for x in m.reshape(-1)))
            order = Sdf.AttributeSpec(
                spec, "xformOpOrder", Sdf.ValueTypeNames.TokenArray, Sdf.VariabilityUniform
            )
            order.default = Vt.TokenArray(["xformOp:transform"])


def _arr(value, dtype=np.float64) -> np.ndarray:
    return np.array(value, dtype=dtype) if value is not None else np.zeros(0, dtype)


def _primvars(mesh: UsdGeom.Mesh) -> list[tuple[str, Sdf.ValueTypeName, str, np.ndarray]]:
    """(name, type, interpolation, flattened values) of every authored primvar; the
    ``normals`` attribute joins as a vertex or faceVarying ``normals`` entry."""
    out = []
    for pv in UsdGeom.PrimvarsAPI(mesh).GetPrimvars():
        if not pv.HasAuthoredValue():
            continue
        v = pv.ComputeFlattened()
        if v is None:
            continue
        out.append((pv.GetPrimvarName(), pv.GetTypeName(), pv.GetInterpolation(), np.array(v)))
    n_attr = mesh.GetNormalsAttr()
    if n_attr.HasAuthoredValue() and not any(o[0] == "normals" for o in out):
        interp = mesh.GetNormalsInterpolation()
        out.append(("@normals", n_attr.GetTypeName(), interp, _arr(n_attr.Get())))
    return out


def _bake(mesh: UsdGeom.Mesh, mats: np.ndarray) -> dict:
    """The arrays of ``mesh`` repeated at each row-vector matrix of ``mats`` (n, 4, 4)."""
    pts = _arr(mesh.GetPointsAttr().Get())
    counts = _arr(mesh.GetFaceVertexCountsAttr().Get(), np.int64)
    idx = _arr(mesh.GetFaceVertexIndicesAttr().Get(), np.int64)
    n, nv, nf, k = len(mats), len(pts), len(counts), len(idx)
    lin = mats[:, :3, :3]
    flip = np.linalg.det(lin) < 0
    # each face's corners reversed for mirrored copies (the first corner kept)
    starts = np.repeat(np.cumsum(counts) - counts, counts)
    pos_in = np.arange(k) - starts
    rev = starts + np.where(pos_in == 0, 0, np.repeat(counts, counts) - pos_in)
    corner = np.where(flip[:, None], rev[None], np.arange(k)[None])  # (n, k)
    out = {
        "points": (np.einsum("vj,njk->nvk", pts, lin) + mats[:, None, 3, :3]).reshape(-1, 3),
        "counts": np.tile(counts, n),
        "indices": (idx[corner] + (np.arange(n) * nv)[:, None]).reshape(-1),
        "primvars": [],
    }
    inv_t = np.transpose(np.linalg.inv(lin), (0, 2, 1))
    for name, type_name, interp, v in _primvars(mesh):
        is_normal = name in ("normals", "@normals")
        if interp == UsdGeom.Tokens.faceVarying and len(v) == k:
            rep = v[corner]
        elif interp in (UsdGeom.Tokens.vertex, UsdGeom.Tokens.varying) and len(v) == nv:
            rep = np.broadcast_to(v, (n, *v.shape))
        elif interp == UsdGeom.Tokens.uniform and len(v) == nf:
            rep = np.broadcast_to(v, (n, *v.shape))
        elif interp == UsdGeom.Tokens.constant:
            out["primvars"].append((name, type_name, interp, v))
            continue
        else:
            raise UsdAuthoringError(
                f"{mesh.GetPath()}: primvar {name} has {len(v)} values for {interp}"
            )
        if is_normal:
            rep = np.einsum("nvj,njk->nvk", rep.astype(np.float64), inv_t)
            rep = rep / np.maximum(np.linalg.norm(rep, axis=2, keepdims=True), 1e-30)
        rep = np.ascontiguousarray(rep).reshape(-1, *v.shape[1:])
        out["primvars"].append((name, type_name, interp, rep))
    return out


def _source_info(src: UsdGeom.Mesh) -> dict:
    """What the baked mesh keeps of its prototype mesh (read before the prototype goes)."""
    attrs = {}
    for attr in ("subdivisionScheme", "doubleSided", "orientation"):
        a = src.GetPrim().GetAttribute(attr)
        if a and a.HasAuthoredValue():
            attrs[attr] = a.Get()
    purpose = UsdGeom.Imageable(src).ComputePurpose()
    if purpose != UsdGeom.Tokens.default_:  # a proxy stays a proxy (not drawn for render)
        attrs["purpose"] = purpose
    mat, _ = UsdShade.MaterialBindingAPI(src.GetPrim()).ComputeBoundMaterial()
    return {"attrs": attrs, "material": mat.GetPrim() if mat else None}


def _keep_materials(
    stage: Usd.Stage, owner: Sdf.Path, targets: list[Sdf.Path], made: list[tuple]
) -> None:
    """Materials that live inside a prototype about to be removed (or inside a native
    instance under it, read through an instance proxy) are copied under ``owner/Materials``
    from the layer's own spec, and the baked meshes bound to the copies; other materials are
    bound where they are."""
    layer = stage.GetEditTarget().GetLayer()
    copies: dict[Sdf.Path, Sdf.Path] = {}
    for _, info, _ in made:
        mat = info["material"]
        if mat is None:
            continue
        path = mat.GetPath()
        doomed = mat.IsInstanceProxy() or any(path.HasPrefix(t) for t in targets)
        if not doomed:
            info["material"] = path
            continue
        if path not in copies:
            spec = next((s for s in mat.GetPrimStack() if s.layer == layer), None)
            if spec is None:
                raise UsdAuthoringError(f"{path}: no spec of the material in the package layer")
            folder = owner.AppendChild("Materials")
            if not layer.GetPrimAtPath(folder):
                f = Sdf.CreatePrimInLayer(layer, folder)
                f.specifier, f.typeName = Sdf.SpecifierDef, "Scope"
            name, i = mat.GetName(), 1
            while layer.GetPrimAtPath(folder.AppendChild(name)):
                name, i = f"{mat.GetName()}_{i}", i + 1
            dst = folder.AppendChild(name)
            if not Sdf.CopySpec(layer, spec.path, layer, dst):
                raise UsdAuthoringError(f"{path}: could not copy the material to {dst}")
            copies[path] = dst
        info["material"] = copies[path]


def _author(stage: Usd.Stage, path: Sdf.Path, info: dict, baked: dict) -> None:
    # through Sdf: UsdGeom.Mesh.Define would turn the flattened prototypes' ``over`` roots
    # into ``def`` ones, drawn at the origin
    spec = Sdf.CreatePrimInLayer(stage.GetEditTarget().GetLayer(), path)
    spec.specifier = Sdf.SpecifierDef
    spec.typeName = "Mesh"
    m = UsdGeom.Mesh(stage.GetPrimAtPath(path))
    m.CreatePointsAttr(Vt.Vec3fArray.FromNumpy(baked["points"].astype(np.float32)))
    m.CreateFaceVertexCountsAttr(Vt.IntArray.FromNumpy(baked["counts"].astype(np.int32)))
    m.CreateFaceVertexIndicesAttr(Vt.IntArray.FromNumpy(baked["indices"].astype(np.int32)))
    for attr, value in info["attrs"].items():
        m.GetPrim().GetAttribute(attr).Set(value)
    for name, type_name, interp, v in baked["primvars"]:
        if name == "@normals":
            m.CreateNormalsAttr(_vt(type_name, v))
            m.SetNormalsInterpolation(interp)
            continue
        UsdGeom.PrimvarsAPI(m).CreatePrimvar(name, type_name, interp).Set(_vt(type_name, v))
    pts = baked["points"]
    m.CreateExtentAttr([tuple(map(float, pts.min(0))), tuple(map(float, pts.max(0)))])
    if info["material"] is not None:
        mat = UsdShade.Material(stage.GetPrimAtPath(info["material"]))
        UsdShade.MaterialBindingAPI.Apply(m.GetPrim()).Bind(mat)


def _vt(type_name: Sdf.ValueTypeName, v: np.ndarray):
    """A Vt array of ``type_name`` from numpy values."""
    cls = type(type_name.defaultValue)
    try:
        return cls.FromNumpy(np.ascontiguousarray(v))
    except (AttributeError, TypeError, ValueError):  # no buffer protocol for this type
        return cls(v.tolist())


def _expand(stage: Usd.Stage, pi: UsdGeom.PointInstancer) -> int:
    """Expand one instancer in place; returns the number of copies baked."""
    t = Usd.TimeCode.Default()
    prim = pi.GetPrim()
    xfs = pi.ComputeInstanceTransformsAtTime(
        t, t, UsdGeom.PointInstancer.IncludeProtoXform, UsdGeom.PointInstancer.ApplyMask
    )
    mats = np.array(xfs, dtype=np.float64).reshape(-1, 4, 4)
    ids = _arr(pi.GetProtoIndicesAttr().Get(t), np.int64)
    mask = pi.ComputeMaskAtTime(t)
    keep = np.ones(len(ids), bool) if not mask else np.asarray(mask, bool)
    ids = ids[keep]
    if len(mats) != len(ids):
        raise UsdAuthoringError(f"{prim.GetPath()}: instance transforms do not match protoIndices")
    targets = pi.GetPrototypesRel().GetForwardedTargets()
    xfc = UsdGeom.XformCache(t)
    made: list[tuple[Sdf.Path, dict, dict]] = []
    names: set[str] = set()
    for j, target in enumerate(targets):
        proto = stage.GetPrimAtPath(target)
        sel = np.flatnonzero(ids == j)
        if not proto or len(sel) == 0:
            continue
        if _triangles(proto) > BAKE_MAX_TRIANGLES:
            _as_instances(stage, prim.GetPath(), target, mats[sel], names)
            continue
        for p in Usd.PrimRange(proto, _PREDICATE):
            img = UsdGeom.Imageable(p)
            if img and img.ComputeVisibility(t) == UsdGeom.Tokens.invisible:
                continue
            if not p.IsA(UsdGeom.Mesh):
                continue
            rel = np.array(xfc.ComputeRelativeTransform(p, proto)[0]).reshape(4, 4)
            if p == proto:
                rel = np.eye(4)  # the prototype root's own transform is in mats
            name, i = p.GetName(), 1
            while name in names:
                name, i = f"{p.GetName()}_{i}", i + 1
            names.add(name)
            baked = _bake(UsdGeom.Mesh(p), rel[None] @ mats[sel])
            info = _source_info(UsdGeom.Mesh(p))
            made.append((prim.GetPath().AppendChild(name), info, baked))
    # read everything first, then rewrite: the prototypes go, the instancer becomes an Xform
    _keep_materials(stage, prim.GetPath(), list(targets), made)
    for tgt in targets:
        if tgt.HasPrefix(prim.GetPath()):
            stage.RemovePrim(tgt)
    for folder in {t.GetParentPath() for t in targets}:  # the prototypes' container
        f = stage.GetPrimAtPath(folder)
        if folder.HasPrefix(prim.GetPath()) and folder != prim.GetPath() and f:
            if not f.GetAllChildren() and f.GetTypeName() in ("", "Scope", "Xform"):
                stage.RemovePrim(folder)
    for name in _INSTANCER_PROPS:
        if prim.HasProperty(name):
            prim.RemoveProperty(name)
    prim.SetTypeName("Xform")
    for path, info, baked in made:
        _author(stage, path, info, baked)
    return len(ids)


def expand_point_instancers(layer: Sdf.Layer) -> int:
    """Expand every point instancer of ``layer`` (a flattened stage) into meshes, in place.
    Returns the number of copies baked."""
    stage = Usd.Stage.Open(layer)
    found = [
        p
        for p in Usd.PrimRange.Stage(stage, Usd.PrimAllPrimsPredicate)
        if p.IsA(UsdGeom.PointInstancer)
    ]
    found.sort(key=lambda p: -p.GetPath().pathElementCount)  # deepest first
    total = 0
    for p in found:
        total += _expand(stage, UsdGeom.PointInstancer(p))
    return total


def normals_as_attributes(layer: Sdf.Layer) -> int:
    """Every mesh's ``primvars:normals`` of ``layer`` moved to its ``normals`` attribute
    (flattened, same interpolation), in place; returns how many meshes changed.

    Blender (5.0) reads every array primvar as a generic attribute as well, so a
    ``primvars:normals`` arrives twice: as the custom normals and as a ``normals`` attribute.
    The attribute cannot be indexed, which is why the asset's files keep the indexed primvar
    (one normal per corner would more than double the column's geometry file, every level of
    detail in it); a usdz holds one selection of it, flattened, and pays far less.
    """
    stage = Usd.Stage.Open(layer)
    changed = 0
    for p in Usd.PrimRange.Stage(stage, Usd.PrimAllPrimsPredicate):
        if not p.IsA(UsdGeom.Mesh):
            continue
        pv = UsdGeom.PrimvarsAPI(p).GetPrimvar("normals")
        if not pv or not pv.HasAuthoredValue():
            continue
        flat, interp = pv.ComputeFlattened(), pv.GetInterpolation()
        names = [pv.GetAttr().GetName(), pv.GetIndicesAttr().GetName()]
        mesh = UsdGeom.Mesh(p)
        for name in names:
            if p.HasProperty(name):
                p.RemoveProperty(name)
        mesh.CreateNormalsAttr(flat)
        mesh.SetNormalsInterpolation(interp)
        changed += 1
    return changed
