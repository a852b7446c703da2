"""``KHR_draco_mesh_compression`` for the glTF writer, with DracoPy (Google's Draco encoder).

Optional (``pip install DracoPy``, the ``export`` extra), imported only when asked for. The
extension has no uncompressed fallback in our files, so it goes into ``extensionsRequired``;
loaders need a Draco decoder (three.js: ``DRACOLoader``; Blender, Babylon.js, Unity's glTFast
and Godot ship one).

Quantization: positions 16 bits per axis of each mesh's own box (0.4 mm over the 26 m temple,
under 0.15 mm on a column part), normals 10 bits, texture coordinates 12 bits; tangents are a
float generic attribute. The accessors describe the decoded data (Draco may split or reorder
vertices), so the encoded buffer is decoded once here to count it and bound its positions.
"""

from __future__ import annotations

import numpy as np

from ionic_usd.export.common import require

__all__ = ["DRACO", "draco_primitive"]

DRACO = "KHR_draco_mesh_compression"
POSITION_BITS, NORMAL_BITS, TEXCOORD_BITS = 16, 10, 12
_FLOAT, _U16, _U32 = 5126, 5123, 5125


def draco_primitive(
    b,
    pos: np.ndarray,
    nrm: np.ndarray,
    uv: np.ndarray | None,
    tan: np.ndarray | None,
    tris: np.ndarray,
):
    """Encode one primitive; return ``(attributes, indices accessor, extension dict)``.

    Parameters
    ----------
    b : the glTF builder (:class:`ionic_usd.export.gltf_buffers.GltfBuilder`)
    pos, nrm : (v, 3) float32; uv : (v, 2) float32 or None; tan : (v, 4) float32 or None
    tris : (t, 3) uint32
    """
    DracoPy = require("DracoPy", "--compress draco")  # noqa: N806
    kw: dict = {"normals": nrm.astype(np.float64), "normal_quantization_bits": NORMAL_BITS}
    if uv is not None:
        kw["tex_coord"] = uv.astype(np.float64)
        kw["tex_coord_quantization_bits"] = TEXCOORD_BITS
        kw["generic_attributes"] = {"TANGENT": tan.astype(np.float64)}  # type: ignore[union-attr]
    data = DracoPy.encode(
        pos.astype(np.float64),
        tris.astype(np.uint32),
        quantization_bits=POSITION_BITS,
        compression_level=7,
        **kw,
    )
    dec = DracoPy.decode(data)
    ids: dict[str, int] = {}
    kinds = {0: "POSITION", 1: "NORMAL", 3: "TEXCOORD_0"}
    for a in dec.attributes:
        name = "TANGENT" if a["name"] == "TANGENT" else kinds.get(a["attribute_type"])
        if name is not None:
            ids[name] = int(a["unique_id"])
    n = len(dec.points)
    g = b.g

    def acc(kind: str, ctype: int = _FLOAT, count: int = n, lo=None, hi=None) -> int:
        a = g.Accessor(componentType=ctype, count=count, type=kind, byteOffset=None)
        if lo is not None:
            a.min, a.max = [float(x) for x in lo], [float(x) for x in hi]
        b.doc.accessors.append(a)
        return len(b.doc.accessors) - 1

    pts = np.asarray(dec.points, dtype=np.float32)
    attrs = g.Attributes(
        POSITION=acc("VEC3", lo=pts.min(axis=0), hi=pts.max(axis=0)), NORMAL=acc("VEC3")
    )
    if uv is not None:
        attrs.TEXCOORD_0 = acc("VEC2")
        attrs.TANGENT = acc("VEC4")
    faces = np.asarray(dec.faces).reshape(-1, 3)
    indices = acc("SCALAR", _U16 if n < 65536 else _U32, 3 * len(faces))
    ext = {"bufferView": b.view(bytes(data)), "attributes": ids}
    return attrs, indices, ext, len(faces)
