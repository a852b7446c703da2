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

Opening a stage and selecting variants are :mod:`ionic_usd.usd.variants`; one mesh prim's
arrays, its paradata and the content keys are :mod:`ionic_usd.usd.prim_values`. ``pxr`` stays
under :mod:`ionic_usd.usd`: callers get numpy arrays, strings and dicts.
"""

from __future__ import annotations

import dataclasses
import json
import os
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np
from pxr import Sdf, Usd, UsdGeom, UsdShade

from ionic_usd.errors import GeometryError
from ionic_usd.usd.draw_mode import CardFace, card_colour, card_faces
from ionic_usd.usd.prim_values import (
    as_array,
    content_key,
    display_colour,
    merge_paradata,
    prim_paradata,
    read_mesh_arrays,
    to_json_value,
)
from ionic_usd.usd.surface import MaterialData, TextureRef, read_material
from ionic_usd.usd.variants import open_stage, parse_variant_args, select_variants

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
    name : prim name of its first occurrence; ``source`` that prim's path, as the scene names
        it: inside a native instance, the instance proxy's path under the first instance in
        traversal order (USD's ``/__Prototype_N`` names are not stable from one opening of a
        stage to the next)
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


def _root_matrix(stage: Usd.Stage) -> np.ndarray:
    """Row-vector matrix taking stage coordinates to Y-up metres."""
    s = float(UsdGeom.GetStageMetersPerUnit(stage)) or 1.0
    m = np.eye(4)
    m[:3, :3] *= s
    if UsdGeom.GetStageUpAxis(stage) == UsdGeom.Tokens.z:
        # (x, y, z) -> (x, z, -y): +Z becomes +Y, handedness kept
        m[:3, :3] = s * np.array([[1.0, 0, 0], [0, 0, -1.0], [0, 1.0, 0]])
    return m


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
        self, root: Usd.Prim, relative: bool, chain: dict, alias: tuple[str, str] | None = None
    ) -> list[tuple[str, np.ndarray, str, dict, bool]]:
        """``(mesh key, matrix, path, paradata, instanced)`` per drawable under ``root``;
        matrices are relative to ``root`` when ``relative``, else local-to-world; ``path`` is
        the placing instance's path (an instance proxy path when nested) or the mesh's.
        ``alias``: (a prototype's path, the path of the instance it is walked for): the
        meshes' ``source`` paths are named under the instance."""
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
            own = prim_paradata(prim) if prim != self.stage.GetDefaultPrim() else {}
            para[path] = merge_paradata(para.get(parent, {}), own) if own else para.get(parent, {})
            if prim.IsA(UsdShade.Material):
                it.PruneChildren()
                continue
            cards = card_faces(prim, self.bbox) if self.bbox is not None else None
            if cards is not None:  # a model drawn as its card box stands in for its subtree
                it.PruneChildren()
                m = self._matrix(prim, root, relative)
                for key in self._cards(prim, cards, alias):
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
                for k, rel, ip, pd, via in self._prototype(proto, _aliased(path, alias)):
                    out.append(
                        (
                            k,
                            rel @ m,
                            str(path) + (ip[n:] if via else ""),
                            merge_paradata(para[path], pd),
                            True,
                        )
                    )
            elif prim.IsA(UsdGeom.PointInstancer):
                it.PruneChildren()
                pi = UsdGeom.PointInstancer(prim)
                out.extend(self._point_instancer(pi, m, para[path], alias))
            else:
                mkey = self._mesh(prim, para[path] if relative else {}, alias)
                if mkey is not None:
                    out.append((mkey, m, str(path), {} if relative else para[path], False))
        return out

    def _matrix(self, prim: Usd.Prim, root: Usd.Prim, relative: bool) -> np.ndarray:
        if relative:
            return np.array(self.xfc.ComputeRelativeTransform(prim, root)[0]).reshape(4, 4)
        return np.array(self.xfc.GetLocalToWorldTransform(prim)).reshape(4, 4)

    def _cards(
        self, prim: Usd.Prim, faces: list[CardFace], alias: tuple[str, str] | None
    ) -> list[str]:
        """One quad mesh per card face, textured by the face's image (keys of the meshes)."""
        source = _aliased(prim.GetPath(), alias)
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
            mat = MaterialData(f"card{face.name}", source, colour, tex)
            self.scene.materials.setdefault(mat.key, mat)
            counts, idx = np.array([4], np.int64), np.arange(4, dtype=np.int64)
            key = content_key([face.points, counts, idx, face.st], f"card|{mat.key}")
            self.scene.meshes.setdefault(
                key,
                SceneMesh(
                    key,
                    f"card{face.name}",
                    source,
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

    def _material(self, prim: Usd.Prim, alias: tuple[str, str] | None) -> str | None:
        """The key of the material bound to ``prim``; a material inside a prototype is named
        under the instance, as the meshes are."""
        mat, _ = UsdShade.MaterialBindingAPI(prim).ComputeBoundMaterial()
        if not mat:
            return None
        mpath = str(mat.GetPath())
        if mpath not in self._materials:
            data = read_material(mat)
            if data is not None:
                data = dataclasses.replace(data, path=_aliased(mat.GetPath(), alias))
                self.scene.materials.setdefault(data.key, data)
            self._materials[mpath] = data.key if data is not None else None
        return self._materials[mpath]

    def _mesh(self, prim: Usd.Prim, paradata: dict, alias: tuple[str, str] | None) -> str | None:
        read = read_mesh_arrays(prim, self.t)
        if read is None:
            return None
        pts, counts, idx, nrm, interp, st, double = read
        material = self._material(prim, alias)
        colour = display_colour(prim)
        meta = json.dumps(paradata, sort_keys=True, default=str)
        key = content_key(
            [pts, counts, idx, nrm, st], f"{interp}|{material}|{double}|{meta}|{colour}"
        )
        if key not in self.scene.meshes:
            self.scene.meshes[key] = SceneMesh(
                key=key,
                name=prim.GetName(),
                source=_aliased(prim.GetPath(), alias),
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

    def _prototype(
        self, root: Usd.Prim, instance: str | None = None
    ) -> list[tuple[str, np.ndarray, str, dict, bool]]:
        """The drawables of a prototype, walked once; ``instance``: the path of the (first)
        native instance it is walked for, under which its meshes are named."""
        key = str(root.GetPath())
        if key not in self._protos:
            alias = (key, instance) if instance is not None else None
            self._protos[key] = self.walk(root, relative=True, chain={}, alias=alias)  # type: ignore[assignment]
            if self._protos[key]:
                self.scene.prototypes.add(key)
        return self._protos[key]  # type: ignore[return-value]

    def _point_instancer(
        self,
        pi: UsdGeom.PointInstancer,
        world: np.ndarray,
        chain: dict,
        alias: tuple[str, str] | None = None,
    ):
        targets = pi.GetPrototypesRel().GetForwardedTargets()
        ids = as_array(pi.GetProtoIndicesAttr().Get(self.t), np.int64)
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
            named = _aliased(target, alias) if alias is not None else None
            for k, rel, ip, pd, via in self._prototype(proto, named):
                tail = ip[n:] if via else ""
                for i in sel:
                    out.append(
                        (
                            k,
                            rel @ full[i] @ world,
                            f"{base}[{i}]{tail}",
                            merge_paradata(chain, pd),
                            True,
                        )
                    )
        return out


def _aliased(path: Sdf.Path, alias: tuple[str, str] | None) -> str:
    """``path`` as the scene names it: under ``alias = (prototype, instance)`` the prototype's
    prefix is replaced by the instance's path."""
    s = str(path)
    if alias is None or not (s == alias[0] or s.startswith(alias[0] + "/")):
        return s  # not under it (a prefix of the name alone, /__Prototype_1 of _10, is not)
    return alias[1] + s[len(alias[0]) :]


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
        scene.paradata = prim_paradata(root)
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
