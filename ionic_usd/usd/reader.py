"""The one scene reader: a composed USD stage as plain numpy data for exporters and viewers.

:func:`read_scene` opens a stage, applies variant selections (``--variant set=value``,
``--lod``), and walks it once. Each drawable mesh is read once and deduplicated by content
(geometry + material + paradata), so a mesh repeated by native instancing (instanceable prims,
nested at any depth), by a ``UsdGeom.PointInstancer`` or simply authored twice becomes one
:class:`SceneMesh` with several :class:`Placement` values — the instancing a glTF writer keeps.

All matrices are row-vector (USD's ``Gf.Matrix4d`` layout: ``p_world = p_local @ M``), already
converted to Y-up metres (``upAxis`` and ``metersPerUnit`` of the stage are applied).

Paradata: ``customData`` and ``userProperties:*`` attributes are gathered as JSON-ready values —
the default prim's on :attr:`Scene.paradata`, a mesh's own and its ancestors' inside its
prototype on :attr:`SceneMesh.paradata`, and an instance's chain outside the prototype on
:attr:`Placement.paradata`.

``pxr`` stays in this module: callers get numpy arrays, strings and dicts.
"""

from __future__ import annotations

import hashlib
import json
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from pxr import Sdf, Usd, UsdGeom, UsdShade

from ionic_usd.errors import GeometryError, ParameterError, UsdAuthoringError
from ionic_usd.usd.draw_mode import CardFace, card_colour, card_faces
from ionic_usd.usd.surface import MaterialData, TextureRef, read_material

__all__ = [
    "TextureRef",
    "MaterialData",
    "SceneMesh",
    "Placement",
    "Scene",
    "read_scene",
    "open_stage",
    "select_variants",
    "parse_variant_args",
    "to_json_value",
]

_SKIP_PURPOSES = ("proxy", "guide")


# -- values ------------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class SceneMesh:
    """One distinct mesh.

    Parameters
    ----------
    key : content key (unique in the scene)
    name : prim name of its first occurrence; ``source`` that prim's path
    points : (n, 3) float64, in the mesh's own space
    face_vertex_counts : (f,) int64
    face_vertex_indices : (k,) int64, counter-clockwise seen from outside
    normals : (n, 3) ('vertex') or (k, 3) ('faceVarying') float64, or None
    st : (k, 2) float64 texture coordinates per face corner (flattened), or None
    material : key into :attr:`Scene.materials`, or None
    display_color : the mean ``primvars:displayColor`` (linear RGB), or None
    card_face : for a face of a model drawn as cards (``read_scene(draw_modes=True)``), the
        face's name (``XPos`` … ``ZNeg``); its material's diffuse texture is the card image
    """

    key: str
    name: str
    source: str
    points: np.ndarray
    face_vertex_counts: np.ndarray
    face_vertex_indices: np.ndarray
    normals: np.ndarray | None
    normals_interpolation: str
    st: np.ndarray | None
    material: str | None
    double_sided: bool = False
    paradata: dict = field(default_factory=dict)
    display_color: tuple[float, float, float] | None = None
    card_face: str = ""

    @property
    def n_triangles(self) -> int:
        return int(np.sum(self.face_vertex_counts - 2))


@dataclass(frozen=True, eq=False)
class Placement:
    """A mesh placed in the world: ``matrix`` (4, 4) row-vector, Y-up metres.

    ``path`` names the prim it came from (an instance's path, or ``instancer[i]``);
    ``instanced`` is True when the mesh is reused (through native instancing, a PointInstancer,
    or a second prim of equal content); ``via_instancing`` only for the first two.
    """

    mesh: str
    matrix: np.ndarray
    path: str
    instanced: bool = False
    paradata: dict = field(default_factory=dict)
    via_instancing: bool = False


@dataclass
class Scene:
    """What :func:`read_scene` returns."""

    source: str
    meshes: dict[str, SceneMesh] = field(default_factory=dict)
    materials: dict[str, MaterialData] = field(default_factory=dict)
    placements: list[Placement] = field(default_factory=list)
    paradata: dict = field(default_factory=dict)
    variants: dict[str, str] = field(default_factory=dict)
    prototypes: set[str] = field(default_factory=set)  # instancing prototypes that drew meshes

    def placements_of(self, key: str) -> list[Placement]:
        return [p for p in self.placements if p.mesh == key]

    @property
    def n_triangles(self) -> int:
        """Triangles drawn, every placement counted."""
        return sum(self.meshes[p.mesh].n_triangles for p in self.placements)


# -- JSON paradata -----------------------------------------------------------------------------
def to_json_value(v: object) -> object:
    """A USD value (dictionary, Vt array, Gf vector, asset path…) as plain JSON data."""
    if isinstance(v, Mapping):
        return {str(k): to_json_value(x) for k, x in v.items()}
    if isinstance(v, (bool, int, str)) or v is None:
        return v
    if isinstance(v, float):
        return v if np.isfinite(v) else None
    if isinstance(v, Sdf.AssetPath):
        return v.path
    if isinstance(v, Sdf.Path):
        return str(v)
    if isinstance(v, (list, tuple)) or hasattr(v, "__len__") and not isinstance(v, bytes):
        try:
            return [to_json_value(x) for x in v]  # type: ignore[attr-defined]
        except TypeError:
            pass
    if isinstance(v, (np.integer, np.floating)):
        return to_json_value(v.item())
    return str(v)


def _prim_paradata(prim: Usd.Prim) -> dict:
    out: dict = {}
    cd = prim.GetAllAuthoredMetadata().get("customData")  # not the schemas' userDocBrief
    if cd:
        out.update(to_json_value(dict(cd)))  # type: ignore[call-overload]
    props = {}
    for attr in prim.GetAuthoredAttributes():
        name = attr.GetName()
        if name.startswith("userProperties:"):
            props[name.split(":", 1)[1]] = to_json_value(attr.Get())
    if props:
        out["userProperties"] = props
    return out


def _merge(outer: dict, inner: dict) -> dict:
    out = dict(outer)
    for k, v in inner.items():
        out[k] = _merge(out[k], v) if isinstance(v, dict) and isinstance(out.get(k), dict) else v
    return out


# -- stage and variants ------------------------------------------------------------------------
def open_stage(path: str | os.PathLike) -> Usd.Stage:
    """Open a USD file with every payload loaded; errors name the file."""
    p = Path(path)
    if not p.is_file():
        raise ParameterError("scene", str(p), "an existing USD file (.usd, .usda, .usdc, .usdz)")
    try:
        stage = Usd.Stage.Open(str(p), Usd.Stage.LoadAll)
    except Exception as exc:  # pxr raises Tf.ErrorException carrying the parser's message
        msg = " ".join(str(exc).split())[:300]
        raise UsdAuthoringError(f"{p}: cannot open as a USD stage: {msg}") from None
    if stage is None:
        raise UsdAuthoringError(f"{p}: cannot open as a USD stage")
    return stage


def parse_variant_args(items: Sequence[str] | None) -> dict[str, str]:
    """``["lod=low", "finish=stucco"]`` → ``{"lod": "low", "finish": "stucco"}``."""
    out: dict[str, str] = {}
    for item in items or ():
        name, sep, value = item.partition("=")
        if not sep or not name.strip() or not value.strip():
            raise ParameterError("--variant", item, "SET=VALUE, e.g. lod=low")
        out[name.strip()] = value.strip()
    return out


def _outermost_instance(prim: Usd.Prim) -> Usd.Prim:
    """The instance prim (not a proxy) that makes ``prim`` an instance proxy."""
    p = prim
    while p and (p.IsInstanceProxy() or not p.IsInstance()):
        p = p.GetParent()
    return p


def select_variants(
    stage: Usd.Stage, selections: Mapping[str, str], *, require_sets: bool = True
) -> dict[str, str]:
    """Select ``set=value`` on every prim that has the set, in the session layer.

    Prims reached only through instancing (instance proxies) cannot carry a selection, so the
    instance above them is made non-instanceable in the session layer first (its nested
    instances stay instanced). Repeats until stable, because a selection can compose in prims
    with variant sets of their own. Raises ParameterError for a set no prim has, or a value a
    prim's set does not offer (listing the valid ones); with ``require_sets=False`` a set no
    prim has is ignored. Returns the selections made.
    """
    found: set[str] = set()
    session = stage.GetSessionLayer()
    with Usd.EditContext(stage, session):
        for _ in range(64):
            deinstance: dict[str, Usd.Prim] = {}
            select: list[tuple[Usd.Prim, str, str]] = []
            for prim in Usd.PrimRange(stage.GetPseudoRoot(), Usd.TraverseInstanceProxies()):
                if not prim.HasVariantSets():
                    continue
                vsets = prim.GetVariantSets()
                names = vsets.GetNames()
                for vset_name, value in selections.items():
                    if vset_name not in names:
                        continue
                    found.add(vset_name)
                    vset = vsets.GetVariantSet(vset_name)
                    valid = vset.GetVariantNames()
                    if value not in valid:
                        raise ParameterError(
                            f"--variant {vset_name}",
                            value,
                            f"one of {', '.join(valid)}",
                            context=str(prim.GetPath()),
                        )
                    if vset.GetVariantSelection() == value:
                        continue
                    if prim.IsInstanceProxy():
                        inst = _outermost_instance(prim)
                        deinstance[str(inst.GetPath())] = inst
                    else:
                        select.append((prim, vset_name, value))
            if not deinstance and not select:
                break
            with Sdf.ChangeBlock():
                for inst in deinstance.values():
                    inst.SetInstanceable(False)
                for prim, vset_name, value in select:
                    prim.GetVariantSets().GetVariantSet(vset_name).SetVariantSelection(value)
        else:  # pragma: no cover - would need a pathological stage
            raise UsdAuthoringError("variant selections did not settle after 64 passes")
    missing = [s for s in selections if s not in found]
    if missing and require_sets:
        sets: set[str] = set()
        for prim in Usd.PrimRange(stage.GetPseudoRoot(), Usd.TraverseInstanceProxies()):
            if prim.HasVariantSets():
                sets.update(prim.GetVariantSets().GetNames())
        valid = ", ".join(sorted(sets)) or "none: the scene has no variant sets"
        raise ParameterError(
            "--variant",
            missing[0],
            f"a variant set of the scene ({valid}); the scene has no {missing[0]!r} variant set",
        )
    return {k: v for k, v in selections.items() if k in found}


def _root_matrix(stage: Usd.Stage) -> np.ndarray:
    """Row-vector matrix taking stage coordinates to Y-up metres."""
    s = float(UsdGeom.GetStageMetersPerUnit(stage)) or 1.0
    m = np.eye(4)
    m[:3, :3] *= s
    if UsdGeom.GetStageUpAxis(stage) == UsdGeom.Tokens.z:
        # (x, y, z) -> (x, z, -y): +Z becomes +Y, handedness kept
        m[:3, :3] = s * np.array([[1.0, 0, 0], [0, 0, -1.0], [0, 1.0, 0]])
    return m


# -- meshes ------------------------------------------------------------------------------------
def _np(value, dtype) -> np.ndarray:
    return np.asarray(value if value is not None else [], dtype=dtype)


def _corner_values(
    pv: UsdGeom.Primvar, n_points: int, counts: np.ndarray, idx: np.ndarray, width: int, what: str
) -> np.ndarray | None:
    """A primvar (indexed or not) expanded to one value per face corner: (k, width)."""
    if not pv or not pv.HasValue():
        return None
    vals = _np(pv.ComputeFlattened(), np.float64).reshape(-1, width)
    interp = pv.GetInterpolation()
    if interp == UsdGeom.Tokens.faceVarying and len(vals) == len(idx):
        return vals
    if interp in (UsdGeom.Tokens.vertex, UsdGeom.Tokens.varying) and len(vals) == n_points:
        return vals[idx]
    if interp == UsdGeom.Tokens.uniform and len(vals) == len(counts):
        return np.repeat(vals, counts, axis=0)
    if interp == UsdGeom.Tokens.constant and len(vals) >= 1:
        return np.repeat(vals[:1], len(idx), axis=0)
    raise GeometryError(
        f"{pv.GetAttr().GetPath()}: {len(vals)} {what} values do not fit interpolation {interp}"
    )


def _read_mesh(prim: Usd.Prim, t: Usd.TimeCode):
    mesh = UsdGeom.Mesh(prim)
    pts = _np(mesh.GetPointsAttr().Get(t), np.float64).reshape(-1, 3)
    counts = _np(mesh.GetFaceVertexCountsAttr().Get(t), np.int64)
    idx = _np(mesh.GetFaceVertexIndicesAttr().Get(t), np.int64)
    if len(pts) == 0 or len(counts) == 0:
        return None
    if counts.sum() != len(idx) or (len(idx) and (idx.min() < 0 or idx.max() >= len(pts))):
        raise GeometryError(
            f"{prim.GetPath()}: faceVertexCounts/faceVertexIndices do not match {len(pts)} points"
        )
    if not np.all(np.isfinite(pts)):
        raise GeometryError(f"{prim.GetPath()}: points contain non-finite values")
    keep = counts >= 3  # points and lines carry no area
    if not keep.all():
        corner_keep = np.repeat(keep, counts)
        counts, idx = counts[keep], idx[corner_keep]
    else:
        corner_keep = None
    if len(counts) == 0:
        return None
    pvapi = UsdGeom.PrimvarsAPI(prim)
    nrm, interp = None, "vertex"
    pv = pvapi.GetPrimvar("normals")
    if pv and pv.HasValue():
        nrm = _corner_values(pv, len(pts), counts, idx, 3, "normal")
        interp = "faceVarying"
    elif mesh.GetNormalsAttr().HasValue():
        raw = _np(mesh.GetNormalsAttr().Get(t), np.float64).reshape(-1, 3)
        ni = mesh.GetNormalsInterpolation()
        if ni in (UsdGeom.Tokens.vertex, UsdGeom.Tokens.varying) and len(raw) == len(pts):
            nrm = raw
        elif ni == UsdGeom.Tokens.faceVarying and corner_keep is not None:
            nrm, interp = raw[corner_keep], "faceVarying"
        elif ni == UsdGeom.Tokens.faceVarying and len(raw) == len(idx):
            nrm, interp = raw, "faceVarying"
        elif ni == UsdGeom.Tokens.uniform and len(raw) == len(keep):
            nrm, interp = np.repeat(raw[keep], counts, axis=0), "faceVarying"
        elif ni == UsdGeom.Tokens.constant and len(raw):
            nrm, interp = np.repeat(raw[:1], len(idx), axis=0), "faceVarying"
        else:
            raise GeometryError(
                f"{prim.GetPath()}: {len(raw)} normals do not fit interpolation {ni}"
            )
    st = None
    pv = pvapi.GetPrimvar("st")
    if pv and pv.HasValue() and corner_keep is None:
        st = _corner_values(pv, len(pts), counts, idx, 2, "st")
    for name, arr in (("normals", nrm), ("st", st)):
        if arr is not None and not np.all(np.isfinite(arr)):
            raise GeometryError(f"{prim.GetPath()}: {name} contain non-finite values")
    if mesh.GetOrientationAttr().Get() == UsdGeom.Tokens.leftHanded:
        # reverse each face's corners so the winding is counter-clockwise
        starts = np.concatenate([[0], np.cumsum(counts)[:-1]])
        order = np.concatenate(
            [s + np.arange(c)[::-1] for s, c in zip(starts, counts, strict=True)]
        )
        idx = idx[order]
        if st is not None:
            st = st[order]
        if nrm is not None and interp == "faceVarying":
            nrm = nrm[order]
    double = bool(mesh.GetDoubleSidedAttr().Get())
    return pts, counts, idx, nrm, interp, st, double


def _content_key(arrays: Sequence[np.ndarray | None], extra: str) -> str:
    h = hashlib.blake2b(digest_size=12)
    for a in arrays:
        h.update(b"-" if a is None else np.ascontiguousarray(a).tobytes())
        h.update(b"|")
    h.update(extra.encode())
    return h.hexdigest()


# -- walking -----------------------------------------------------------------------------------
class _Reader:
    """Walk a stage once; prototypes (native and point instancer) are read once and memoised."""

    def __init__(
        self, stage: Usd.Stage, t: Usd.TimeCode, scene: Scene, draw_modes: bool = False
    ) -> None:
        self.stage, self.t, self.scene = stage, t, scene
        self.xfc = UsdGeom.XformCache(t)
        self.bbox = (
            UsdGeom.BBoxCache(
                t, [UsdGeom.Tokens.default_, UsdGeom.Tokens.render], useExtentsHint=True
            )
            if draw_modes
            else None
        )
        self._protos: dict[str, list[tuple[str, np.ndarray, str]]] = {}
        self._by_prim: dict[str, str | None] = {}
        self._materials: dict[str, str | None] = {}

    def walk(
        self, root: Usd.Prim, relative: bool, chain: dict
    ) -> list[tuple[str, np.ndarray, str, dict, bool]]:
        """``(mesh key, matrix, path, paradata, instanced)`` per drawable under ``root``;
        matrices are relative to ``root`` when ``relative``, else local-to-world; ``path`` is
        the placing instance's path (an instance proxy path when nested) or the mesh's."""
        out: list[tuple[str, np.ndarray, str, dict, bool]] = []
        purposes: dict[Sdf.Path, str] = {}
        para: dict[Sdf.Path, dict] = {root.GetPath().GetParentPath(): chain}
        it = iter(Usd.PrimRange(root, Usd.PrimDefaultPredicate))
        for prim in it:
            path = prim.GetPath()
            parent = path.GetParentPath()
            inherited = purposes.get(parent, "default")
            img = UsdGeom.Imageable(prim)
            purpose = inherited
            if img:
                if img.GetVisibilityAttr().Get(self.t) == UsdGeom.Tokens.invisible:
                    it.PruneChildren()
                    continue
                attr = img.GetPurposeAttr()
                if attr.HasAuthoredValue():
                    purpose = str(attr.Get())
                if purpose in _SKIP_PURPOSES:
                    it.PruneChildren()
                    continue
            purposes[path] = purpose
            own = _prim_paradata(prim) if prim != self.stage.GetDefaultPrim() else {}
            para[path] = _merge(para.get(parent, {}), own) if own else para.get(parent, {})
            if prim.IsA(UsdShade.Material):
                it.PruneChildren()
                continue
            cards = card_faces(prim, self.bbox) if self.bbox is not None else None
            if cards is not None:  # a model drawn as its card box stands in for its subtree
                it.PruneChildren()
                m = self._matrix(prim, root, relative)
                for key in self._cards(prim, cards):
                    out.append((key, m, str(path), {} if relative else para[path], False))
                continue
            if not (
                prim.IsInstance() or prim.IsA(UsdGeom.PointInstancer) or prim.IsA(UsdGeom.Mesh)
            ):
                continue
            m = self._matrix(prim, root, relative)
            if prim.IsInstance():
                it.PruneChildren()
                proto = prim.GetPrototype()
                n = len(str(proto.GetPath()))
                for k, rel, ip, pd, via in self._prototype(proto):
                    out.append(
                        (
                            k,
                            rel @ m,
                            str(path) + (ip[n:] if via else ""),
                            _merge(para[path], pd),
                            True,
                        )
                    )
            elif prim.IsA(UsdGeom.PointInstancer):
                it.PruneChildren()
                out.extend(self._point_instancer(UsdGeom.PointInstancer(prim), m, para[path]))
            else:
                mkey = self._mesh(prim, para[path] if relative else {})
                if mkey is not None:
                    out.append((mkey, m, str(path), {} if relative else para[path], False))
        return out

    def _matrix(self, prim: Usd.Prim, root: Usd.Prim, relative: bool) -> np.ndarray:
        if relative:
            return np.array(self.xfc.ComputeRelativeTransform(prim, root)[0]).reshape(4, 4)
        return np.array(self.xfc.GetLocalToWorldTransform(prim)).reshape(4, 4)

    def _cards(self, prim: Usd.Prim, faces: list[CardFace]) -> list[str]:
        """One quad mesh per card face, textured by the face's image (keys of the meshes)."""
        keys = []
        colour = card_colour(prim)
        for face in faces:
            tex = (
                TextureRef(
                    path=face.texture,
                    channels="rgba",
                    colour_space="sRGB",
                    wrap_s="clamp",
                    wrap_t="clamp",
                )
                if face.texture
                else None
            )
            mat = MaterialData(f"card{face.name}", str(prim.GetPath()), colour, tex)
            self.scene.materials.setdefault(mat.key, mat)
            counts, idx = np.array([4], np.int64), np.arange(4, dtype=np.int64)
            key = _content_key([face.points, counts, idx, face.st], f"card|{mat.key}")
            self.scene.meshes.setdefault(
                key,
                SceneMesh(
                    key,
                    f"card{face.name}",
                    str(prim.GetPath()),
                    face.points,
                    counts,
                    idx,
                    None,
                    "vertex",
                    face.st,
                    mat.key,
                    card_face=face.name,
                ),
            )
            keys.append(key)
        return keys

    def _material(self, prim: Usd.Prim) -> str | None:
        mat, _ = UsdShade.MaterialBindingAPI(prim).ComputeBoundMaterial()
        if not mat:
            return None
        mpath = str(mat.GetPath())
        if mpath not in self._materials:
            data = read_material(mat)
            if data is not None:
                self.scene.materials.setdefault(data.key, data)
            self._materials[mpath] = data.key if data is not None else None
        return self._materials[mpath]

    def _mesh(self, prim: Usd.Prim, paradata: dict) -> str | None:
        read = _read_mesh(prim, self.t)
        if read is None:
            return None
        pts, counts, idx, nrm, interp, st, double = read
        material = self._material(prim)
        colour: tuple[float, float, float] | None = None
        pv = UsdGeom.Mesh(prim).GetDisplayColorPrimvar()
        if pv and pv.HasValue():
            vals = _np(pv.ComputeFlattened(), np.float64).reshape(-1, 3)
            if len(vals):
                r, g, b = (float(x) for x in vals.mean(axis=0))
                colour = (r, g, b)
        meta = json.dumps(paradata, sort_keys=True, default=str)
        key = _content_key(
            [pts, counts, idx, nrm, st], f"{interp}|{material}|{double}|{meta}|{colour}"
        )
        if key not in self.scene.meshes:
            self.scene.meshes[key] = SceneMesh(
                key=key,
                name=prim.GetName(),
                source=str(prim.GetPath()),
                points=pts,
                face_vertex_counts=counts,
                face_vertex_indices=idx,
                normals=nrm,
                normals_interpolation=interp,
                st=st,
                material=material,
                double_sided=double,
                paradata=paradata,
                display_color=colour,
            )
        return key

    def _prototype(self, root: Usd.Prim) -> list[tuple[str, np.ndarray, str, dict, bool]]:
        key = str(root.GetPath())
        if key not in self._protos:
            self._protos[key] = self.walk(root, relative=True, chain={})  # type: ignore[assignment]
            if self._protos[key]:
                self.scene.prototypes.add(key)
        return self._protos[key]  # type: ignore[return-value]

    def _point_instancer(self, pi: UsdGeom.PointInstancer, world: np.ndarray, chain: dict):
        targets = pi.GetPrototypesRel().GetForwardedTargets()
        ids = _np(pi.GetProtoIndicesAttr().Get(self.t), np.int64)
        if len(ids) == 0 or not targets:
            return []
        # the prototype root's own transform is part of each instance (IncludeProtoXform)
        xforms = pi.ComputeInstanceTransformsAtTime(
            self.t,
            self.t,
            UsdGeom.PointInstancer.IncludeProtoXform,
            UsdGeom.PointInstancer.ApplyMask,
        )
        mats = np.array(xforms, dtype=np.float64).reshape(-1, 4, 4)
        mask = pi.ComputeMaskAtTime(self.t)
        keep = np.ones(len(ids), bool) if not mask else np.asarray(mask, bool)
        if len(mats) != int(keep.sum()):
            raise GeometryError(f"{pi.GetPath()}: instance transforms do not match protoIndices")
        full = np.full((len(ids), 4, 4), np.nan)
        full[keep] = mats
        out = []
        base = str(pi.GetPath())
        for j, target in enumerate(targets):
            proto = self.stage.GetPrimAtPath(target)
            sel = np.flatnonzero((ids == j) & keep)
            if not proto or len(sel) == 0:
                continue
            # the prototype's transform is in ``mats``: walk it relative to itself
            n = len(str(proto.GetPath()))
            for k, rel, ip, pd, via in self._prototype(proto):
                tail = ip[n:] if via else ""
                for i in sel:
                    out.append(
                        (k, rel @ full[i] @ world, f"{base}[{i}]{tail}", _merge(chain, pd), True)
                    )
        return out


def read_scene(
    path: str | os.PathLike,
    *,
    variants: Mapping[str, str] | None = None,
    lod: str | None = None,
    time: float | None = None,
    draw_modes: bool = False,
    require_sets: bool = True,
) -> Scene:
    """Read a USD scene into a :class:`Scene` of distinct meshes and their placements.

    Parameters
    ----------
    path : a USD file (.usda/.usdc/.usd/.usdz) any ionic_usd command wrote, or any stage of
        meshes, instanceable prims and point instancers
    variants : ``{set: value}`` selected on every prim that has the set (default: authored)
    lod : shorthand for ``variants["lod"]``
    time : time code to read (default: the default time)
    draw_modes : honour ``UsdGeomModelAPI`` card draw modes as a viewer does — a model with
        ``model:applyDrawMode = true`` whose resolved ``model:drawMode`` is ``cards`` is read as
        its card quads (:func:`ionic_usd.usd.draw_mode.card_faces`), not its subtree. Off for
        exporters, which want the geometry.
    require_sets : a selected variant set that no prim has is an error (else it is ignored)
    """
    sel = dict(variants or {})
    if lod is not None:
        sel["lod"] = lod
    stage = open_stage(path)
    if sel:
        sel = select_variants(stage, sel, require_sets=require_sets)
    t = Usd.TimeCode(time) if time is not None else Usd.TimeCode.Default()
    scene = Scene(source=str(path), variants=sel)
    root = stage.GetDefaultPrim()
    if root:
        scene.paradata = _prim_paradata(root)
        vs = root.GetVariantSets()
        scene.paradata["variantSelections"] = {n: vs.GetVariantSelection(n) for n in vs.GetNames()}
    conv = _root_matrix(stage)
    reader = _Reader(stage, t, scene, draw_modes)
    for key, m, ppath, pd, via in reader.walk(stage.GetPseudoRoot(), relative=False, chain={}):
        # through an instance, an instancer, or a second prim of equal content
        instanced = via or ppath != scene.meshes[key].source
        if not np.all(np.isfinite(m)):
            raise GeometryError(f"{ppath}: its transform is not finite")
        scene.placements.append(Placement(key, m @ conv, ppath, instanced, pd, via))
    if not scene.placements:
        raise GeometryError(f"{path}: the scene has no visible mesh")
    return scene
