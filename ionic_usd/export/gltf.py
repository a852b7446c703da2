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
  equal prims) is one glTF mesh. With ``gpu_instancing`` its placements become one node with
  ``EXT_mesh_gpu_instancing`` (TRANSLATION/ROTATION/SCALE accessors; used, not required — a
  client without it draws one copy at the origin); without it (or when a placement has shear),
  one node per placement referencing the shared mesh.
* space: Y-up metres (the reader already applied the stage's upAxis and metersPerUnit).
* paradata: the scene's in ``scenes[0].extras``, a mesh's in ``meshes[i].extras``, an
  instance's in its node's ``extras`` (GPU instanced: ``extras.instances``, one entry each).
"""

from __future__ import annotations

import base64
import hashlib
import json
import math
import os
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ionic_usd import __version__
from ionic_usd.errors import GeometryError, IonicError, ParameterError
from ionic_usd.export.common import atomic_write, require
from ionic_usd.geometry.mesh import triangulate_fan, unique_rows
from ionic_usd.usd.reader import MaterialData, Scene, SceneMesh, TextureRef

__all__ = ["GltfReport", "write_gltf", "trs_decompose", "texture_transform", "split_common"]

_GPU = "EXT_mesh_gpu_instancing"
_XF = "KHR_texture_transform"
_WRAP = {"repeat": 10497, "clamp": 33071, "mirror": 33648, "black": 33071, "useMetadata": 10497}
_FLOAT, _U16, _U32 = 5126, 5123, 5125
_ARRAY, _ELEMENTS = 34962, 34963


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


# -- vertex data -------------------------------------------------------------------------------
def _streams(m: SceneMesh):
    """``positions (v, 3) f4, normals (v, 3) f4, uv (v, 2) f4 | None, tangents (v, 4) f4 |
    None, triangles (t, 3) u4``."""
    idx = m.face_vertex_indices
    k = len(idx)
    tri_c = triangulate_fan(m.face_vertex_counts, np.arange(k)).astype(np.int64)  # corners
    pts = m.points
    # flat normals per face (Newell-like sum of its fan triangles), for missing or null normals
    face_of_tri = np.repeat(np.arange(len(m.face_vertex_counts)), m.face_vertex_counts - 2)
    tp = pts[idx[tri_c]]
    cross = np.cross(tp[:, 1] - tp[:, 0], tp[:, 2] - tp[:, 0])
    fn = np.zeros((len(m.face_vertex_counts), 3))
    np.add.at(fn, face_of_tri, cross)
    fl = np.linalg.norm(fn, axis=1, keepdims=True)
    fn = np.where(fl > 0, fn / np.where(fl > 0, fl, 1.0), np.array([0.0, 1.0, 0.0]))
    flat = np.repeat(fn, m.face_vertex_counts, axis=0)
    if m.normals is None:
        nrm = flat
    else:
        nrm = m.normals[idx] if m.normals_interpolation == "vertex" else m.normals
        ln = np.linalg.norm(nrm, axis=1, keepdims=True)
        nrm = np.where(ln > 1e-12, nrm / np.where(ln > 1e-12, ln, 1.0), flat)
    cols = [idx[:, None].astype(np.float64), nrm]
    if m.st is not None:
        cols.append(m.st)
    key = np.concatenate(cols, axis=1)
    _, first, inverse = unique_rows(key, return_index=True, return_inverse=True)
    inverse = inverse.reshape(-1)
    tris = inverse[tri_c]
    good = (tris[:, 0] != tris[:, 1]) & (tris[:, 1] != tris[:, 2]) & (tris[:, 0] != tris[:, 2])
    tris = tris[good]
    # glTF requires unit normals: renormalise in float32
    n32 = nrm[first].astype(np.float32)
    n32 /= np.linalg.norm(n32, axis=1, keepdims=True)
    pos = pts[idx[first]]
    uv = tangents = None
    if m.st is not None:
        st = m.st[first]
        tangents = _tangents(pos, n32.astype(np.float64), st, tris)
        uv = st.astype(np.float32)
        uv[:, 1] = 1.0 - uv[:, 1]
    return pos.astype(np.float32), n32, uv, tangents, tris.astype(np.uint32)


def _tangents(pos: np.ndarray, nrm: np.ndarray, st: np.ndarray, tris: np.ndarray) -> np.ndarray:
    """Per-vertex tangents (v, 4) float32: xyz along +s, w the handedness that makes
    ``cross(normal, tangent) * w`` point along +t (up the image, the normal maps' +Y).

    Lengyel's accumulation over triangles, orthogonalised against the normal; the maps are
    tileable (not baked against these meshes), so any consistent frame shades them right.
    """
    p0, p1, p2 = (pos[tris[:, i]] for i in range(3))
    w0, w1, w2 = (st[tris[:, i]] for i in range(3))
    e1, e2 = p1 - p0, p2 - p0
    d1, d2 = w1 - w0, w2 - w0
    det = d1[:, 0] * d2[:, 1] - d2[:, 0] * d1[:, 1]
    r = np.where(np.abs(det) > 1e-20, 1.0 / np.where(det == 0, 1.0, det), 0.0)[:, None]
    sdir = (e1 * d2[:, 1:2] - e2 * d1[:, 1:2]) * r
    tdir = (e2 * d1[:, 0:1] - e1 * d2[:, 0:1]) * r
    acc_s = np.zeros_like(pos)
    acc_t = np.zeros_like(pos)
    for i in range(3):
        np.add.at(acc_s, tris[:, i], sdir)
        np.add.at(acc_t, tris[:, i], tdir)
    t = acc_s - nrm * np.sum(nrm * acc_s, axis=1, keepdims=True)
    ln = np.linalg.norm(t, axis=1)
    bad = ln < 1e-12
    if bad.any():  # no usable st gradient: any unit vector perpendicular to the normal
        helper = np.where(np.abs(nrm[bad, 0:1]) < 0.9, [[1.0, 0, 0]], [[0, 1.0, 0]])
        alt = np.cross(nrm[bad], helper)
        t[bad] = alt
        ln[bad] = np.linalg.norm(alt, axis=1)
    t /= ln[:, None]
    w = np.where(np.sum(np.cross(nrm, t) * acc_t, axis=1) < 0.0, -1.0, 1.0)
    out = np.empty((len(pos), 4), dtype=np.float32)
    out[:, :3] = t
    out[:, :3] /= np.linalg.norm(out[:, :3], axis=1, keepdims=True)
    out[:, 3] = w
    return out


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


def trs_decompose(matrix: np.ndarray, tol: float = 1e-5):
    """Row-vector affine (4, 4) → ``(translation (3,), quaternion xyzw (4,), scale (3,))``.

    Returns None when the matrix has shear or a projective part (not a TRS).
    """
    from scipy.spatial.transform import Rotation  # noqa: PLC0415

    m = np.asarray(matrix, dtype=np.float64)
    if not np.allclose(m[:, 3], [0, 0, 0, 1], atol=1e-9):
        return None
    lin = m[:3, :3].T  # column-vector linear part: columns are the scaled axes
    scale = np.linalg.norm(lin, axis=0)
    if np.any(scale < 1e-12):
        return None
    rot = lin / scale
    if np.linalg.det(rot) < 0:
        scale[0], rot[:, 0] = -scale[0], -rot[:, 0]
    if not np.allclose(rot.T @ rot, np.eye(3), atol=tol):
        return None
    q = Rotation.from_matrix(rot).as_quat()
    q /= np.linalg.norm(q)
    return m[3, :3].copy(), q, scale


# -- document builder --------------------------------------------------------------------------
class _Builder:
    def __init__(self) -> None:
        g = require("pygltflib", "glTF export")
        self.g = g
        self.doc = g.GLTF2(
            asset=g.Asset(version="2.0", generator=f"ionic_usd {__version__} (pygltflib)")
        )
        self.blob = bytearray()
        self.used: set[str] = set()
        self.required: set[str] = set()
        self._images: dict[str, int] = {}
        self._textures: dict[tuple, int] = {}
        self._samplers: dict[tuple, int] = {}
        self._packed: dict[tuple, bytes] = {}

    # buffers
    def view(self, data: bytes, target: int | None = None) -> int:
        while len(self.blob) % 4:
            self.blob.append(0)
        bv = self.g.BufferView(
            buffer=0, byteOffset=len(self.blob), byteLength=len(data), target=target
        )
        self.blob.extend(data)
        self.doc.bufferViews.append(bv)
        return len(self.doc.bufferViews) - 1

    def accessor(
        self, arr: np.ndarray, kind: str, target: int | None = None, *, bounds: bool = False
    ) -> int:
        ctype = {
            np.dtype(np.float32): _FLOAT,
            np.dtype(np.uint16): _U16,
            np.dtype(np.uint32): _U32,
        }[arr.dtype]
        arr = np.ascontiguousarray(arr)
        acc = self.g.Accessor(
            bufferView=self.view(arr.tobytes(), target),
            componentType=ctype,
            count=len(arr),
            type=kind,
        )
        if bounds:
            flat = arr.reshape(len(arr), -1)
            acc.min = [float(x) for x in flat.min(axis=0)]
            acc.max = [float(x) for x in flat.max(axis=0)]
        self.doc.accessors.append(acc)
        return len(self.doc.accessors) - 1

    # textures
    def image(self, data: bytes, mime: str, name: str) -> int:
        h = hashlib.blake2b(data, digest_size=16).hexdigest()
        if h not in self._images:
            self.doc.images.append(
                self.g.Image(bufferView=self.view(data), mimeType=mime, name=name)
            )
            self._images[h] = len(self.doc.images) - 1
        return self._images[h]

    def texture_info(self, tex: TextureRef, image: int, normal: bool = False):
        skey = (_WRAP.get(tex.wrap_s, 10497), _WRAP.get(tex.wrap_t, 10497))
        if skey not in self._samplers:
            self.doc.samplers.append(
                self.g.Sampler(magFilter=9729, minFilter=9987, wrapS=skey[0], wrapT=skey[1])
            )
            self._samplers[skey] = len(self.doc.samplers) - 1
        tkey = (image, skey)
        if tkey not in self._textures:
            self.doc.textures.append(self.g.Texture(source=image, sampler=self._samplers[skey]))
            self._textures[tkey] = len(self.doc.textures) - 1
        cls = self.g.NormalMaterialTexture if normal else self.g.TextureInfo
        info = cls(index=self._textures[tkey])
        xf = texture_transform(tex)
        if xf is not None:
            info.extensions = {_XF: xf}
            self.used.add(_XF)
        return info


def texture_transform(tex: TextureRef) -> dict | None:
    """USD's ``st' = T + R(θ)·S·st`` seen through glTF's flip ``v = 1 − t``.

    ``F∘M∘F`` with ``F(p) = D p + e``, ``D = diag(1, −1)``, ``e = (0, 1)``: the linear part is
    ``R(−θ)·S`` — KHR_texture_transform's ``rotation = θ`` (its matrix turns the other way) and
    ``scale = S`` — and the offset is ``D·R(θ)·S·e + D·T + e``.
    """
    if tex.st_scale is None:
        return None
    sx, sy = tex.st_scale
    th = math.radians(tex.st_rotation)
    c, s = math.cos(th), math.sin(th)
    rs_e = (c * 0.0 - s * sy, s * 0.0 + c * sy)  # R(θ)·S·(0, 1)
    tx, ty = tex.st_translation
    off = (rs_e[0] + tx, -rs_e[1] - ty + 1.0)
    out: dict = {"scale": [sx, sy]}
    if any(abs(v) > 1e-12 for v in off):
        out["offset"] = [off[0], off[1]]
    if abs(th) > 1e-12:
        out["rotation"] = th
    return out


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


def _material(b: _Builder, mat: MaterialData, double_sided: bool) -> int:
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
        if key not in b._packed:
            b._packed[key] = _pack_metallic_roughness(rt, mt)
        ref = rt if rt is not None else mt
        assert ref is not None  # one of the two, by the test above
        name = Path(ref.path).stem + "_metallicRoughness"
        pbr.metallicRoughnessTexture = b.texture_info(
            ref, b.image(b._packed[key], "image/png", name)
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
def write_gltf(
    scene: Scene,
    path: str | os.PathLike,
    *,
    gpu_instancing: bool = True,
    binary: bool | None = None,
    compress: str | None = None,
) -> GltfReport:
    """Write ``scene`` as glTF 2.0 (``.glb`` binary, ``.gltf`` JSON with embedded buffer).

    Parameters
    ----------
    scene : from :func:`ionic_usd.usd.reader.read_scene`
    path : output file (written atomically)
    gpu_instancing : keep repeated meshes as ``EXT_mesh_gpu_instancing`` nodes (else one plain
        node per copy, the mesh still shared)
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
    b = _Builder()
    g = b.g
    mat_index: dict[tuple[str, bool], int] = {}
    mesh_index: dict[str, int] = {}
    by_mesh: dict[str, list] = {}
    for p in scene.placements:
        by_mesh.setdefault(p.mesh, []).append(p)
    tris_total = 0
    for key in by_mesh:
        m = scene.meshes[key]
        pos, nrm, uv, tan, tris = _streams(m)
        if len(tris) == 0:
            continue
        if compress == "draco":
            from ionic_usd.export.draco import DRACO, draco_primitive  # noqa: PLC0415

            attrs, indices, ext, _ = draco_primitive(b, pos, nrm, uv, tan, tris)
            prim = g.Primitive(attributes=attrs, mode=4, indices=indices, extensions={DRACO: ext})
            b.used.add(DRACO)
            b.required.add(DRACO)
        else:
            attrs = g.Attributes(
                POSITION=b.accessor(pos, "VEC3", _ARRAY, bounds=True),
                NORMAL=b.accessor(nrm, "VEC3", _ARRAY),
            )
            if uv is not None:
                attrs.TEXCOORD_0 = b.accessor(uv, "VEC2", _ARRAY)
                attrs.TANGENT = b.accessor(tan, "VEC4", _ARRAY)
            itype = np.uint16 if len(pos) < 65536 else np.uint32
            prim = g.Primitive(
                attributes=attrs,
                mode=4,
                indices=b.accessor(tris.reshape(-1).astype(itype), "SCALAR", _ELEMENTS),
            )
        if m.material is not None and m.material in scene.materials:
            mk = (m.material, m.double_sided)
            if mk not in mat_index:
                mat_index[mk] = _material(b, scene.materials[m.material], m.double_sided)
            prim.material = mat_index[mk]
        extras = {"usdPath": m.source, **m.paradata}
        b.doc.meshes.append(g.Mesh(name=m.name, primitives=[prim], extras=extras))
        mesh_index[key] = len(b.doc.meshes) - 1
        tris_total += len(tris)

    roots: list[int] = []
    draws = gpu_meshes = instances = drawn = 0
    for key, placements in by_mesh.items():
        if key not in mesh_index:
            continue
        mi = mesh_index[key]
        n_tris = b.doc.meshes[mi].primitives[0].indices
        n_tris = b.doc.accessors[n_tris].count // 3
        drawn += n_tris * len(placements)
        trs = [trs_decompose(p.matrix) for p in placements] if gpu_instancing else []
        # paradata every copy shares goes on the node once; the rest per copy
        each = [{"path": p.path, **p.paradata} for p in placements]
        common, each = split_common(each) if len(each) > 1 else ({}, each)
        name = scene.meshes[key].name
        if gpu_instancing and len(placements) > 1 and all(t is not None for t in trs):
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
            node = g.Node(
                name=name, mesh=mi, extensions={_GPU: ext}, extras={**common, "instances": each}
            )
            b.used.add(_GPU)
            b.doc.nodes.append(node)
            roots.append(len(b.doc.nodes) - 1)
            draws += 1
            gpu_meshes += 1
            instances += len(placements)
            continue
        children = []
        for p, extras in zip(placements, each, strict=True):
            node = g.Node(name=p.path.rsplit("/", 1)[-1] or p.path, mesh=mi, extras=extras)
            if not np.allclose(p.matrix, np.eye(4), atol=1e-12):
                node.matrix = [float(x) for x in np.asarray(p.matrix).reshape(-1)]
            b.doc.nodes.append(node)
            children.append(len(b.doc.nodes) - 1)
            draws += 1
            instances += int(p.instanced)
        if len(children) > 1:  # one group node per shared mesh, holding the common paradata
            b.doc.nodes.append(
                g.Node(name=f"{name} x{len(children)}", children=children, extras=common)
            )
            roots.append(len(b.doc.nodes) - 1)
        else:
            roots.extend(children)
    if not roots:
        raise GeometryError(f"{scene.source}: nothing to export (no triangles)")
    root_name = Path(scene.source).stem
    b.doc.nodes.append(g.Node(name=root_name, children=roots))
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
        tris_total,
        drawn,
        draws,
        gpu_meshes,
        instances,
        time.perf_counter() - t0,
    )
