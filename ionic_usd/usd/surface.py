"""UsdPreviewSurface materials read as plain values (the scene reader's shading half).

:func:`read_material` follows a material's surface output to its UsdPreviewSurface and each
input to a constant or a UsdUVTexture (resolved file, channel, colour space, wrap, scale/bias)
whose ``st`` may pass through a UsdTransform2d.
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass

from pxr import Sdf, UsdShade

from ionic_usd.errors import UsdAuthoringError

__all__ = ["TextureRef", "MaterialData", "read_material"]


@dataclass(frozen=True)
class TextureRef:
    """A UsdUVTexture as a glTF-like texture reference.

    ``path`` is the resolved file; ``channels`` the output read (``"rgb"``, ``"r"``, …);
    ``scale``/``bias`` (4,) UsdUVTexture's decode; ``st_scale``/``st_rotation`` (degrees,
    counter-clockwise)/``st_translation`` a UsdTransform2d on the ``st`` input, or None.
    """

    path: str
    channels: str
    colour_space: str
    wrap_s: str = "repeat"
    wrap_t: str = "repeat"
    scale: tuple[float, float, float, float] = (1.0, 1.0, 1.0, 1.0)
    bias: tuple[float, float, float, float] = (0.0, 0.0, 0.0, 0.0)
    st_scale: tuple[float, float] | None = None
    st_rotation: float = 0.0
    st_translation: tuple[float, float] = (0.0, 0.0)


@dataclass(frozen=True)
class MaterialData:
    """A UsdPreviewSurface: constant inputs and, where connected, their textures."""

    name: str
    path: str
    diffuse: tuple[float, float, float] = (0.18, 0.18, 0.18)
    diffuse_texture: TextureRef | None = None
    roughness: float = 0.5
    roughness_texture: TextureRef | None = None
    metallic: float = 0.0
    metallic_texture: TextureRef | None = None
    normal_texture: TextureRef | None = None
    emissive: tuple[float, float, float] = (0.0, 0.0, 0.0)
    opacity: float = 1.0

    @property
    def key(self) -> str:
        """A content key: equal materials found under different prototypes share it."""
        d = {k: v for k, v in self.__dict__.items() if k not in ("name", "path")}
        return hashlib.blake2b(repr(sorted(d.items())).encode(), digest_size=8).hexdigest()


def _input_value(shader: UsdShade.Shader, name: str):
    inp = shader.GetInput(name)
    return inp.Get() if inp else None


def _source(inp: UsdShade.Input) -> tuple[UsdShade.Shader, str] | None:
    if not inp or not inp.HasConnectedSource():
        return None
    src, out_name, _ = inp.GetConnectedSource()
    return UsdShade.Shader(src.GetPrim()), str(out_name)


def _texture(shader: UsdShade.Shader, channels: str) -> TextureRef | None:
    if _input_value(shader, "file") is None:
        return None
    asset = _input_value(shader, "file")
    path = asset.resolvedPath if isinstance(asset, Sdf.AssetPath) else ""
    if not path:
        raise UsdAuthoringError(f"{shader.GetPath()}: texture {asset} does not resolve")
    space = _input_value(shader, "sourceColorSpace") or "auto"
    kw: dict = {}
    for name in ("scale", "bias"):
        v = _input_value(shader, name)
        if v is not None:
            kw[name] = tuple(float(x) for x in v)
    for name, key in (("wrapS", "wrap_s"), ("wrapT", "wrap_t")):
        v = _input_value(shader, name)
        if v:
            kw[key] = str(v)
    st = _source(shader.GetInput("st"))
    if st is not None and st[0].GetIdAttr().Get() == "UsdTransform2d":
        xf = st[0]
        sc = _input_value(xf, "scale")
        kw["st_scale"] = (float(sc[0]), float(sc[1])) if sc is not None else (1.0, 1.0)
        kw["st_rotation"] = float(_input_value(xf, "rotation") or 0.0)
        tr = _input_value(xf, "translation")
        kw["st_translation"] = (float(tr[0]), float(tr[1])) if tr is not None else (0.0, 0.0)
    return TextureRef(path=path, channels=channels, colour_space=str(space), **kw)


def read_material(mat: UsdShade.Material) -> MaterialData | None:
    """A bound material's UsdPreviewSurface as :class:`MaterialData` (None: not a preview
    surface)."""
    src = mat.ComputeSurfaceSource()
    shader = src[0] if isinstance(src, tuple) else src
    if not shader or shader.GetIdAttr().Get() != "UsdPreviewSurface":
        return None
    kw: dict = {}
    for name, key, tex_key in (
        ("diffuseColor", "diffuse", "diffuse_texture"),
        ("roughness", "roughness", "roughness_texture"),
        ("metallic", "metallic", "metallic_texture"),
        ("normal", None, "normal_texture"),
        ("emissiveColor", "emissive", None),
        ("opacity", "opacity", None),
    ):
        inp = shader.GetInput(name)
        if not inp:
            continue
        conn = _source(inp)
        if conn is not None and conn[0].GetIdAttr().Get() == "UsdUVTexture" and tex_key:
            tex = _texture(conn[0], conn[1])
            if tex is not None:
                kw[tex_key] = tex
                continue
        v = inp.Get()
        if v is not None and key is not None:
            kw[key] = tuple(float(x) for x in v) if hasattr(v, "__len__") else float(v)
    return MaterialData(name=mat.GetPrim().GetName(), path=str(mat.GetPath()), **kw)
