"""glTF 2.0 (``.glb`` / ``.gltf``) from a :class:`ionic_usd.usd.reader.Scene`, with pygltflib.

What carries over, and how:

* meshes: one glTF mesh per distinct scene mesh, one primitive, fan-triangulated; vertices
  split where normals or ``st`` differ per face corner. ``NORMAL`` always (flat normals when the
  USD mesh has none); ``TEXCOORD_0`` = ``(s, 1 − t)`` — glTF's v runs down the image.
* materials: UsdPreviewSurface → ``pbrMetallicRoughness``. Textures are embedded (in the GLB
  binary chunk, or the ``.gltf``'s data-URI buffer), deduplicated by content. Roughness (and
  metallic) maps are repacked into one image, roughness in G and metallic in B as glTF wants.
  Normal maps are copied as they are (8-bit, OpenGL +Y; USD's ``scale 2, bias −1`` decode is
  glTF's), flipping green if the USD decode flips it. A ``UsdTransform2d`` on ``st`` becomes
  ``KHR_texture_transform`` (conjugated by the v flip).
* instancing: a mesh placed more than once (native instances at any depth, PointInstancers,
  equal prims) is one glTF mesh. Copies of a small mesh (ornament, tiles) are baked into one
  mesh per point instancer (:mod:`ionic_usd.export.gltf_merge`), shared by groups laid out
  alike; other copies are one node each referencing the shared mesh — core glTF, which every
  client draws the same. With ``gpu_instancing`` those copies become one node with
  ``EXT_mesh_gpu_instancing`` (TRANSLATION/ROTATION/SCALE accessors), and the extension is
  *required*: the extension has no fallback (a client without it would draw one copy at the
  origin), so such a client must refuse the file rather than draw a wrong temple.
* space: Y-up metres (the reader already applied the stage's upAxis and metersPerUnit).
* paradata: the scene's in ``scenes[0].extras``, a mesh's in ``meshes[i].extras``, an
  instance's in its node's ``extras`` (GPU instanced: ``extras.instances``, one entry each).

Vertex streams and the buffer/accessor/texture packing are :mod:`ionic_usd.export.gltf_buffers`;
this module assembles materials, meshes, nodes and the scene.
"""

from __future__ import annotations

import base64
import json
import os
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ionic_usd.errors import GeometryError, IonicError, ParameterError
from ionic_usd.export.common import atomic_write
from ionic_usd.export.gltf_buffers import (
    ARRAY_BUFFER,
    ELEMENT_ARRAY_BUFFER,
    GltfBuilder,
    texture_transform,
    vertex_streams,
)
from ionic_usd.export.gltf_merge import MergeGroup, merged_streams, plan_merges, trs_decompose
from ionic_usd.usd.reader import MaterialData, Scene, TextureRef

__all__ = ["GltfReport", "write_gltf", "trs_decompose", "texture_transform", "split_common"]

_GPU = "EXT_mesh_gpu_instancing"


class TextureExportError(IonicError, ValueError):
    """A texture could not be read or converted for glTF (names the file)."""


@dataclass(frozen=True)
class GltfReport:
    """What one :func:`write_gltf` wrote.

    ``draw_calls`` counts (node, primitive) pairs a renderer issues: a GPU-instanced node is one
    call however many copies it draws.
    """

    path: Path
    bytes: int
    meshes: int
    nodes: int
    materials: int
    images: int
    triangles: int
    triangles_drawn: int
    draw_calls: int
    gpu_instanced_meshes: int
    instances: int
    seconds: float
    merged: int = 0  # copies baked into merged meshes


def split_common(dicts: list[dict]) -> tuple[dict, list[dict]]:
    """``(common, residuals)``: what every dict holds (recursively, compared as JSON), and
    what is left of each. Paradata shared by all copies of a mesh is then stored once."""

    def j(v: object) -> str:
        return json.dumps(v, sort_keys=True, default=str)

    common: dict = {}
    rest = [dict(d) for d in dicts]
    for k, v in dicts[0].items():
        vals = [d.get(k, _MISSING) for d in dicts]
        if any(x is _MISSING for x in vals):
            continue
        if all(j(x) == j(v) for x in vals[1:]):
            common[k] = v
            for r in rest:
                del r[k]
        elif all(isinstance(x, dict) for x in vals):
            sub, subrest = split_common(vals)
            if sub:
                common[k] = sub
                for r, sr in zip(rest, subrest, strict=True):
                    if sr:
                        r[k] = sr
                    else:
                        del r[k]
    return common, rest


_MISSING = object()


def _read_image(path: str) -> np.ndarray:
    """(h, w, c) float32 in [0, 1], rows top first (as stored)."""
    import OpenImageIO as oiio  # noqa: PLC0415

    buf = oiio.ImageBuf(path)
    if buf.has_error:
        raise TextureExportError(f"{path}: cannot read texture: {buf.geterror()}")
    px = buf.get_pixels(oiio.FLOAT)
    if px is None or buf.has_error:
        raise TextureExportError(f"{path}: cannot read texture: {buf.geterror()}")
    px = np.asarray(px, dtype=np.float32)
    return px[:, :, None] if px.ndim == 2 else px


def _png_bytes(px: np.ndarray) -> bytes:
    import OpenImageIO as oiio  # noqa: PLC0415

    u8 = np.clip(np.rint(px * 255.0), 0, 255).astype(np.uint8)
    with tempfile.TemporaryDirectory(prefix="ionic_usd_gltf_") as d:
        f = os.path.join(d, "t.png")
        buf = oiio.ImageBuf(np.ascontiguousarray(u8))
        if not buf.write(f, oiio.UINT8, "png"):
            raise TextureExportError(f"cannot encode a PNG: {oiio.geterror()}")
        return Path(f).read_bytes()


def _file_image(path: str) -> tuple[bytes, str]:
    """The file's bytes if glTF takes it as is (PNG, JPEG), else a PNG conversion."""
    data = Path(path).read_bytes()
    if data[:8] == b"\x89PNG\r\n\x1a\n":
        return data, "image/png"
    if data[:3] == b"\xff\xd8\xff":
        return data, "image/jpeg"
    return _png_bytes(_read_image(path)[:, :, :4]), "image/png"


def _channel(px: np.ndarray, ch: str) -> np.ndarray:
    i = {"r": 0, "g": 1, "b": 2, "a": 3}.get(ch, 0)
    return px[:, :, min(i, px.shape[2] - 1)]


def _material(b: GltfBuilder, mat: MaterialData, double_sided: bool) -> int:
    g = b.g
    pbr = g.PbrMetallicRoughness()
    out = g.Material(
        name=mat.name,
        pbrMetallicRoughness=pbr,
        doubleSided=double_sided,
        extras={"usdPath": mat.path},
    )
    alpha = float(np.clip(mat.opacity, 0.0, 1.0))
    if mat.diffuse_texture is not None:
        t = mat.diffuse_texture
        data, mime = _file_image(t.path)
        pbr.baseColorTexture = b.texture_info(t, b.image(data, mime, Path(t.path).stem))
        pbr.baseColorFactor = [float(np.clip(t.scale[i], 0, 1)) for i in range(3)] + [alpha]
    else:
        pbr.baseColorFactor = [float(np.clip(c, 0, 1)) for c in mat.diffuse] + [alpha]
    if alpha < 1.0:
        out.alphaMode = "BLEND"
    rt, mt = mat.roughness_texture, mat.metallic_texture
    if rt is not None or mt is not None:
        key = (rt, mt)
        if key not in b.packed:
            b.packed[key] = _pack_metallic_roughness(rt, mt)
        ref = rt if rt is not None else mt
        assert ref is not None  # one of the two, by the test above
        name = Path(ref.path).stem + "_metallicRoughness"
        pbr.metallicRoughnessTexture = b.texture_info(
            ref, b.image(b.packed[key], "image/png", name)
        )
        pbr.roughnessFactor = 1.0 if rt is not None else float(mat.roughness)
        pbr.metallicFactor = 1.0 if mt is not None else float(mat.metallic)
    else:
        pbr.roughnessFactor = float(np.clip(mat.roughness, 0, 1))
        pbr.metallicFactor = float(np.clip(mat.metallic, 0, 1))
    nt = mat.normal_texture
    if nt is not None:
        if nt.scale[1] < 0:  # a DirectX (−Y) map decoded by a negative scale: flip green
            px = _read_image(nt.path)[:, :, :3].copy()
            px[:, :, 1] = 1.0 - px[:, :, 1]
            data, mime = _png_bytes(px), "image/png"
        else:
            data, mime = _file_image(nt.path)
        out.normalTexture = b.texture_info(nt, b.image(data, mime, Path(nt.path).stem), normal=True)
    if any(c > 0 for c in mat.emissive):
        out.emissiveFactor = [float(np.clip(c, 0, 1)) for c in mat.emissive]
    b.doc.materials.append(out)
    return len(b.doc.materials) - 1


def _pack_metallic_roughness(rt: TextureRef | None, mt: TextureRef | None) -> bytes:
    """One RGB image: R = 1 (unused), G = roughness, B = metallic (glTF's packing)."""
    imgs = {}
    for name, t in (("r", rt), ("m", mt)):
        if t is not None:
            px = _read_image(t.path)
            ch = "r" if len(t.channels) != 1 else t.channels
            imgs[name] = np.clip(_channel(px, ch) * abs(t.scale[0]) + t.bias[0], 0.0, 1.0)
    shapes = {v.shape for v in imgs.values()}
    if len(shapes) > 1:
        raise TextureExportError(
            "the roughness and metallic maps differ in size "
            f"({' vs '.join(str(s) for s in shapes)}); glTF packs them "
            "into one image"
        )
    shape = next(iter(shapes))
    px = np.ones((*shape, 3), dtype=np.float32)
    px[:, :, 1] = imgs.get("r", 1.0)
    px[:, :, 2] = imgs.get("m", 1.0)
    return _png_bytes(px)


# -- scene -------------------------------------------------------------------------------------
def _primitive(b: GltfBuilder, streams, compress: str | None):
    """A glTF primitive (triangles) of ``(pos, nrm, uv, tan, tris)``."""
    g = b.g
    pos, nrm, uv, tan, tris = streams
    if compress == "draco":
        from ionic_usd.export.draco import DRACO, draco_primitive  # noqa: PLC0415

        attrs, indices, ext, _ = draco_primitive(b, pos, nrm, uv, tan, tris)
        b.used.add(DRACO)
        b.required.add(DRACO)
        return g.Primitive(attributes=attrs, mode=4, indices=indices, extensions={DRACO: ext})
    attrs = g.Attributes(
        POSITION=b.accessor(pos, "VEC3", ARRAY_BUFFER, bounds=True),
        NORMAL=b.accessor(nrm, "VEC3", ARRAY_BUFFER),
    )
    if uv is not None:
        attrs.TEXCOORD_0 = b.accessor(uv, "VEC2", ARRAY_BUFFER)
        attrs.TANGENT = b.accessor(tan, "VEC4", ARRAY_BUFFER)
    itype = np.uint16 if len(pos) < 65536 else np.uint32
    return g.Primitive(
        attributes=attrs,
        mode=4,
        indices=b.accessor(tris.reshape(-1).astype(itype), "SCALAR", ELEMENT_ARRAY_BUFFER),
    )


class _Meshes:
    """glTF meshes of a scene's meshes (each once) and of merged groups (each layout once)."""

    def __init__(self, b: GltfBuilder, scene: Scene, compress: str | None) -> None:
        self.b, self.scene, self.compress = b, scene, compress
        self.streams: dict[str, tuple] = {}
        self.index: dict[str, int | None] = {}
        self.materials: dict[tuple[str, bool], int] = {}
        self.stored = 0  # triangles stored

    def _streams(self, key: str) -> tuple:
        if key not in self.streams:
            self.streams[key] = vertex_streams(self.scene.meshes[key])
        return self.streams[key]

    def _add(self, key: str, streams, name: str, extras: dict) -> int | None:
        if len(streams[4]) == 0:
            return None
        m = self.scene.meshes[key]
        prim = _primitive(self.b, streams, self.compress)
        if m.material is not None and m.material in self.scene.materials:
            mk = (m.material, m.double_sided)
            if mk not in self.materials:
                self.materials[mk] = _material(
                    self.b, self.scene.materials[m.material], m.double_sided
                )
            prim.material = self.materials[mk]
        self.b.doc.meshes.append(self.b.g.Mesh(name=name, primitives=[prim], extras=extras))
        self.stored += len(streams[4])
        return len(self.b.doc.meshes) - 1

    def mesh(self, key: str) -> int | None:
        """The glTF mesh of one scene mesh."""
        if key not in self.index:
            m = self.scene.meshes[key]
            extras = {"usdPath": m.source, **m.paradata}
            self.index[key] = self._add(key, self._streams(key), m.name, extras)
        return self.index[key]

    def merged(self, grp: MergeGroup) -> int | None:
        """The glTF mesh of a merged group (shared by groups laid out alike)."""
        if grp.key not in self.index:
            m = self.scene.meshes[grp.mesh]
            streams = merged_streams(self._streams(grp.mesh), grp.relative)
            extras = {"usdPath": m.source, "copies": len(grp.placements), **m.paradata}
            name = f"{m.name} x{len(grp.placements)}"
            self.index[grp.key] = self._add(grp.mesh, streams, name, extras)
        return self.index[grp.key]


def _triangles(b: GltfBuilder, mi: int) -> int:
    return b.doc.accessors[b.doc.meshes[mi].primitives[0].indices].count // 3


def _matrix_node(g, name: str, mi: int | None, matrix: np.ndarray, extras: dict):
    node = g.Node(name=name, mesh=mi, extras=extras)
    if not np.allclose(matrix, np.eye(4), atol=1e-12):
        node.matrix = [float(x) for x in np.asarray(matrix).reshape(-1)]
    return node


def write_gltf(
    scene: Scene,
    path: str | os.PathLike,
    *,
    gpu_instancing: bool = False,
    merge: bool = True,
    binary: bool | None = None,
    compress: str | None = None,
) -> GltfReport:
    """Write ``scene`` as glTF 2.0 (``.glb`` binary, ``.gltf`` JSON with embedded buffer).

    Parameters
    ----------
    scene : from :func:`ionic_usd.usd.reader.read_scene`
    path : output file (written atomically)
    gpu_instancing : draw a mesh's copies as one ``EXT_mesh_gpu_instancing`` node, the
        extension then listed in ``extensionsRequired`` (a client without it must refuse the
        file: it would draw one copy). Default: one plain node per copy, the mesh shared —
        core glTF, drawn alike by every client
    merge : bake the copies of small meshes (:mod:`ionic_usd.export.gltf_merge`) into one mesh
        per group: a few hundred draw calls for a temple instead of thousands
    binary : GLB or JSON (default: from the extension)
    compress : None, or ``"draco"`` (KHR_draco_mesh_compression, needs DracoPy; see
        :mod:`ionic_usd.export.draco`)
    """
    if compress not in (None, "none", "draco"):
        raise ParameterError("--compress", compress, "none or draco")
    compress = None if compress == "none" else compress
    t0 = time.perf_counter()
    path = Path(path)
    binary = path.suffix.lower() != ".gltf" if binary is None else binary
    b = GltfBuilder()
    by_mesh: dict[str, list] = {}
    for p in scene.placements:
        by_mesh.setdefault(p.mesh, []).append(p)
    keep, groups = plan_merges(scene, by_mesh) if merge else (by_mesh, [])
    meshes = _Meshes(b, scene, compress)
    tally = _Tally()
    for grp in groups:
        tally += _merged_node(b, scene, meshes, grp)
    for key, placements in keep.items():
        tally += _copy_nodes(b, scene, meshes, key, placements, gpu_instancing)
    if not tally.roots:
        raise GeometryError(f"{scene.source}: nothing to export (no triangles)")
    _scene_and_buffer(b, scene, tally.roots, binary)

    def write(tmp: Path) -> None:
        if binary:
            tmp.write_bytes(b"".join(b.doc.save_to_bytes()))
        else:
            tmp.write_text(b.doc.gltf_to_json())

    atomic_write(path, write)
    return GltfReport(
        path,
        path.stat().st_size,
        len(b.doc.meshes),
        len(b.doc.nodes),
        len(b.doc.materials),
        len(b.doc.images),
        meshes.stored,
        tally.drawn,
        tally.draws,
        tally.gpu_meshes,
        tally.instances,
        time.perf_counter() - t0,
        tally.merged,
    )


@dataclass(frozen=True)
class _Tally:
    """Root nodes added and what they draw: triangles, draw calls, GPU-instanced meshes,
    instances, and instances baked into merged meshes."""

    roots: tuple[int, ...] = ()
    drawn: int = 0
    draws: int = 0
    gpu_meshes: int = 0
    instances: int = 0
    merged: int = 0

    def __add__(self, other: _Tally) -> _Tally:
        return _Tally(
            self.roots + other.roots,
            self.drawn + other.drawn,
            self.draws + other.draws,
            self.gpu_meshes + other.gpu_meshes,
            self.instances + other.instances,
            self.merged + other.merged,
        )


def _merged_node(b: GltfBuilder, scene: Scene, meshes: _Meshes, grp: MergeGroup) -> _Tally:
    """One node drawing a merged group's mesh, its copies' paradata in its extras."""
    mi = meshes.merged(grp)
    if mi is None:
        return _Tally()
    each = [{"path": p.path, **p.paradata} for p in grp.placements]
    common, each = split_common(each)
    name = f"{scene.meshes[grp.mesh].name} x{len(each)}"
    b.doc.nodes.append(_matrix_node(b.g, name, mi, grp.frame, {**common, "instances": each}))
    return _Tally((len(b.doc.nodes) - 1,), _triangles(b, mi), 1, 0, len(each), len(each))


def _copy_nodes(
    b: GltfBuilder,
    scene: Scene,
    meshes: _Meshes,
    key: str,
    placements: list,
    gpu_instancing: bool,
) -> _Tally:
    """The nodes drawing one scene mesh's copies: one GPU-instanced node, or a node per copy
    (grouped under one node holding the paradata they share)."""
    mi = meshes.mesh(key)
    if mi is None:
        return _Tally()
    drawn = _triangles(b, mi) * len(placements)
    trs = [trs_decompose(p.matrix) for p in placements] if gpu_instancing else []
    # paradata every copy shares goes on the node once; the rest per copy
    each = [{"path": p.path, **p.paradata} for p in placements]
    common, each = split_common(each) if len(each) > 1 else ({}, each)
    name = scene.meshes[key].name
    if gpu_instancing and len(placements) > 1 and all(t is not None for t in trs):
        _gpu_node(b, name, mi, trs, {**common, "instances": each})
        return _Tally((len(b.doc.nodes) - 1,), drawn, 1, 1, len(placements))
    children = []
    for p, extras in zip(placements, each, strict=True):
        b.doc.nodes.append(
            _matrix_node(b.g, p.path.rsplit("/", 1)[-1] or p.path, mi, p.matrix, extras)
        )
        children.append(len(b.doc.nodes) - 1)
    instances = sum(int(p.instanced) for p in placements)
    if len(children) > 1:  # one group node per shared mesh, holding the common paradata
        b.doc.nodes.append(
            b.g.Node(name=f"{name} x{len(children)}", children=children, extras=common)
        )
        return _Tally((len(b.doc.nodes) - 1,), drawn, len(children), 0, instances)
    return _Tally(tuple(children), drawn, len(children), 0, instances)


def _gpu_node(b: GltfBuilder, name: str, mi: int, trs: list, extras: dict) -> None:
    """One ``EXT_mesh_gpu_instancing`` node drawing mesh ``mi`` at each (t, r, s) of ``trs``."""
    t_arr = np.array([t[0] for t in trs], dtype=np.float32)
    r_arr = np.array([t[1] for t in trs], dtype=np.float32)
    s_arr = np.array([t[2] for t in trs], dtype=np.float32)
    r_arr /= np.linalg.norm(r_arr, axis=1, keepdims=True)
    ext = {
        "attributes": {
            "TRANSLATION": b.accessor(t_arr, "VEC3"),
            "ROTATION": b.accessor(r_arr, "VEC4"),
            "SCALE": b.accessor(s_arr, "VEC3"),
        }
    }
    node = b.g.Node(name=name, mesh=mi, extensions={_GPU: ext}, extras=extras)
    b.used.add(_GPU)
    b.required.add(_GPU)
    b.doc.nodes.append(node)


def _scene_and_buffer(b: GltfBuilder, scene: Scene, roots: tuple[int, ...], binary: bool) -> None:
    """The scene (a root node over ``roots``), the extension lists and the one buffer."""
    g = b.g
    root_name = Path(scene.source).stem
    b.doc.nodes.append(g.Node(name=root_name, children=list(roots)))
    b.doc.scenes.append(
        g.Scene(
            name=root_name,
            nodes=[len(b.doc.nodes) - 1],
            extras={
                "source": Path(scene.source).name,
                **scene.paradata,
                "requestedVariants": dict(scene.variants),
            },
        )
    )
    b.doc.scene = 0
    b.doc.extensionsUsed = sorted(b.used)
    if b.required:
        b.doc.extensionsRequired = sorted(b.required)
    while len(b.blob) % 4:
        b.blob.append(0)
    if binary:
        b.doc.buffers.append(g.Buffer(byteLength=len(b.blob)))
        b.doc.set_binary_blob(bytes(b.blob))
    else:
        uri = "data:application/octet-stream;base64," + base64.b64encode(b.blob).decode()
        b.doc.buffers.append(g.Buffer(byteLength=len(b.blob), uri=uri))
