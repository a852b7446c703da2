"""glTF buffer packing: a scene mesh as vertex streams, and the document builder.

:func:`vertex_streams` splits a :class:`~ionic_usd.usd.reader.SceneMesh` into glTF vertices
(one per distinct point + normal + ``st`` corner), with unit normals, ``TEXCOORD_0`` flipped to
glTF's downward v and tangents. :class:`GltfBuilder` holds the pygltflib document and its one
binary buffer: buffer views (4-byte aligned), accessors, images and textures deduplicated by
content, samplers, with :func:`texture_transform` for ``KHR_texture_transform``.
:func:`ionic_usd.export.gltf.write_gltf` assembles the scene and materials over it.
"""

from __future__ import annotations

import hashlib
import math

import numpy as np

from ionic_usd import __version__
from ionic_usd.export.common import require
from ionic_usd.geometry.mesh import triangulate_fan, unique_rows
from ionic_usd.usd.reader import SceneMesh, TextureRef

__all__ = [
    "ARRAY_BUFFER",
    "ELEMENT_ARRAY_BUFFER",
    "GltfBuilder",
    "texture_transform",
    "vertex_streams",
]

_XF = "KHR_texture_transform"
_WRAP = {"repeat": 10497, "clamp": 33071, "mirror": 33648, "black": 33071, "useMetadata": 10497}
_FLOAT, _U16, _U32 = 5126, 5123, 5125
#: buffer view targets: vertex attributes, triangle indices
ARRAY_BUFFER, ELEMENT_ARRAY_BUFFER = 34962, 34963


# -- vertex data -------------------------------------------------------------------------------
def vertex_streams(m: SceneMesh):
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


# -- document builder --------------------------------------------------------------------------
class GltfBuilder:
    """A pygltflib document (``doc``) being built, its binary buffer (``blob``) and the
    extensions it uses (``used``) and requires (``required``)."""

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
        self.packed: dict[tuple, bytes] = {}  # metallic-roughness images by their maps

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
