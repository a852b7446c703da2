"""Headless thumbnails of USD scenes: OpenGL 3.3 on a standalone (EGL) context via moderngl.

A client of USD, not part of the kernel: it opens a composed stage, gathers every visible mesh
(prototype meshes of native instances and of point instancers are uploaded once and drawn with
one instanced call carrying a per-instance ``mat4``), shades them with a key light that casts
shadow-mapped shadows, a fill light and a hemispheric ambient term, and writes a PNG.

``moderngl`` is the optional ``preview`` extra; it is imported only when a picture is rendered,
so :func:`render_preview` raises :class:`PreviewUnavailableError` (naming what to install) on a
machine without it or without an EGL driver.
"""

from __future__ import annotations

import math
import os
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from pxr import Sdf, Usd, UsdGeom, UsdShade

from ionic_usd.errors import (
    GeometryError,
    IonicError,
    ParameterError,
    UsdAuthoringError,
)
from ionic_usd.geometry.mesh import face_normals, triangulate_fan

__all__ = [
    "CAMERAS",
    "PreviewStats",
    "PreviewUnavailableError",
    "create_context",
    "render_preview",
]

CAMERAS = ("auto", "front", "three-quarter")
STONE_GREY = (0.50, 0.48, 0.44)  # linear RGB: a warm light limestone once lit
_SKIP_PURPOSES = ("proxy", "guide")
_SHADOW_SIZE = 2048
_FOV_DEG = 40.0


class PreviewUnavailableError(IonicError, RuntimeError):
    """No OpenGL context can be made: moderngl is missing or there is no EGL driver."""


@dataclass(frozen=True)
class PreviewStats:
    """What one :func:`render_preview` call drew and how long it took.

    ``meshes`` counts distinct meshes uploaded to the GPU (a prototype mesh once however many
    instances use it); ``prototypes`` the instancing prototypes drawn (native and point
    instancer); ``instances`` the mesh copies drawn through instancing; ``draws`` the instanced
    draw calls of the colour pass; ``triangles`` every triangle drawn, copies included.
    """

    meshes: int
    prototypes: int
    instances: int
    draws: int
    triangles: int
    width: int
    height: int
    seconds: float
    load_seconds: float = 0.0
    render_seconds: float = 0.0

    def __post_init__(self) -> None:
        for name in ("meshes", "prototypes", "instances", "draws", "triangles"):
            if getattr(self, name) < 0:
                raise ParameterError(name, getattr(self, name), "a count >= 0")


# -- scene gathering ---------------------------------------------------------------------------
@dataclass
class _MeshData:
    """One mesh ready for upload: corners interleaved as ``(3 * t, 6) float32`` (pos, normal)."""

    vertices: np.ndarray
    colour: tuple[float, float, float]
    lo: np.ndarray  # (3,) local bounds
    hi: np.ndarray
    placements: list[np.ndarray] = field(default_factory=list)  # (4, 4) row-vector matrices
    instanced: bool = False

    @property
    def triangles(self) -> int:
        return len(self.vertices) // 3


@dataclass
class _Scene:
    meshes: dict[str, _MeshData] = field(default_factory=dict)  # by prim path
    prototypes: set[str] = field(default_factory=set)


def _np(value, dtype) -> np.ndarray:
    return np.asarray(value if value is not None else [], dtype=dtype)


def _srgb_to_linear(c: np.ndarray) -> np.ndarray:
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


class _Colours:
    """Material colours, cached per material path and per texture file."""

    def __init__(self) -> None:
        self._materials: dict[str, tuple[float, float, float] | None] = {}
        self._textures: dict[str, np.ndarray | None] = {}

    def of(self, prim: Usd.Prim) -> tuple[float, float, float]:
        mat, _ = UsdShade.MaterialBindingAPI(prim).ComputeBoundMaterial()
        if mat:
            key = str(mat.GetPath())
            if key not in self._materials:
                self._materials[key] = self._material_colour(mat)
            if self._materials[key] is not None:
                return self._materials[key]
        pv = UsdGeom.Mesh(prim).GetDisplayColorPrimvar()
        if pv and pv.HasValue():
            vals = _np(pv.ComputeFlattened(), np.float64).reshape(-1, 3)
            if len(vals):
                return tuple(float(x) for x in vals.mean(axis=0))
        return STONE_GREY

    def _material_colour(self, mat: UsdShade.Material) -> tuple[float, float, float] | None:
        shader = mat.ComputeSurfaceSource()
        shader = shader[0] if isinstance(shader, tuple) else shader
        if not shader or shader.GetIdAttr().Get() != "UsdPreviewSurface":
            return None
        inp = shader.GetInput("diffuseColor")
        if not inp:
            return None
        if inp.HasConnectedSource():
            source = inp.GetConnectedSource()[0]
            tex = UsdShade.Shader(source.GetPrim())
            if tex and tex.GetIdAttr().Get() == "UsdUVTexture":
                rgb = self._texture_colour(tex)
                if rgb is not None:
                    return rgb
                fallback = tex.GetInput("fallback")
                if fallback and fallback.Get() is not None:
                    return tuple(float(x) for x in list(fallback.Get())[:3])
        value = inp.Get()
        return None if value is None else tuple(float(x) for x in value)

    def _texture_colour(self, tex: UsdShade.Shader) -> tuple[float, float, float] | None:
        file_in = tex.GetInput("file")
        asset = file_in.Get() if file_in else None
        path = getattr(asset, "resolvedPath", "") if asset is not None else ""
        if not path:
            return None
        space = tex.GetInput("sourceColorSpace")
        space = str(space.Get()) if space and space.Get() else "auto"
        key = f"{path}|{space}"
        if key not in self._textures:
            self._textures[key] = _mean_texture_colour(path, space)
        mean = self._textures[key]
        if mean is None:
            return None
        scale = np.ones(3)
        bias = np.zeros(3)
        for name, arr in (("scale", scale), ("bias", bias)):
            i = tex.GetInput(name)
            if i and i.Get() is not None:
                arr[:] = list(i.Get())[:3]
        return tuple(float(x) for x in np.clip(mean * scale + bias, 0.0, None))


def _mean_texture_colour(path: str, colour_space: str) -> np.ndarray | None:
    """The mean linear RGB of an image (subsampled to about 512 rows), or None if unreadable."""
    import OpenImageIO as oiio  # noqa: PLC0415

    inp = oiio.ImageInput.open(path)
    if inp is None:
        return None
    try:
        spec = inp.spec()
        eight_bit = spec.format == oiio.TypeDesc(oiio.UINT8)
        px = inp.read_image(0, 0, 0, min(spec.nchannels, 3), oiio.FLOAT)
    finally:
        inp.close()
    if px is None:
        return None
    px = np.asarray(px, dtype=np.float32)
    if px.ndim == 2:
        px = px[:, :, None]
    step = max(1, px.shape[0] // 512)
    px = px[::step, ::step]
    if px.shape[2] == 1:
        px = np.repeat(px, 3, axis=2)
    if colour_space == "sRGB" or (colour_space == "auto" and eight_bit):
        px = _srgb_to_linear(np.clip(px, 0.0, 1.0))
    return px.reshape(-1, px.shape[2])[:, :3].mean(axis=0).astype(np.float64)


def _read_mesh(prim: Usd.Prim, colours: _Colours, t: Usd.TimeCode) -> _MeshData | None:
    """Fan-triangulate a UsdGeom.Mesh into per-corner positions and normals (None if empty)."""
    mesh = UsdGeom.Mesh(prim)
    pts = _np(mesh.GetPointsAttr().Get(t), np.float64).reshape(-1, 3)
    counts = _np(mesh.GetFaceVertexCountsAttr().Get(t), np.int64)
    idx = _np(mesh.GetFaceVertexIndicesAttr().Get(t), np.int64)
    if len(pts) == 0 or len(counts) == 0:
        return None
    if counts.sum() != len(idx) or (len(idx) and (idx.min() < 0 or idx.max() >= len(pts))):
        raise GeometryError(f"{prim.GetPath()}: faceVertexCounts/faceVertexIndices do not match "
                            f"{len(pts)} points")
    keep = counts >= 3  # points and lines carry no area
    face_ids = np.arange(len(counts))
    corners = triangulate_fan(counts[keep], np.flatnonzero(np.repeat(keep, counts)))
    face_of_tri = np.repeat(face_ids[keep], counts[keep] - 2)
    if len(corners) == 0:
        return None
    corners = corners.astype(np.int64)
    if mesh.GetOrientationAttr().Get() == UsdGeom.Tokens.leftHanded:
        corners = corners[:, [0, 2, 1]]
    tri_pts = pts[idx[corners]]  # (t, 3, 3)

    nrm, interp = None, None
    pv = UsdGeom.PrimvarsAPI(prim).GetPrimvar("normals")
    if pv and pv.HasValue():
        nrm, interp = pv.ComputeFlattened(t), pv.GetInterpolation()
    elif mesh.GetNormalsAttr().HasValue():
        nrm, interp = mesh.GetNormalsAttr().Get(t), mesh.GetNormalsInterpolation()
    tri_nrm = None
    if nrm is not None:
        nrm = _np(nrm, np.float64).reshape(-1, 3)
        if interp == UsdGeom.Tokens.faceVarying and len(nrm) == len(idx):
            tri_nrm = nrm[corners]
        elif interp in (UsdGeom.Tokens.vertex, UsdGeom.Tokens.varying) and len(nrm) == len(pts):
            tri_nrm = nrm[idx[corners]]
        elif interp == UsdGeom.Tokens.uniform and len(nrm) == len(counts):
            tri_nrm = np.repeat(nrm[face_of_tri][:, None, :], 3, axis=1)
        elif interp == UsdGeom.Tokens.constant and len(nrm) >= 1:
            tri_nrm = np.broadcast_to(nrm[0], tri_pts.shape)
    if tri_nrm is None:  # flat shading from the winding
        fn, _ = face_normals(tri_pts.reshape(-1, 3), np.arange(3 * len(corners)).reshape(-1, 3))
        tri_nrm = np.repeat(fn[:, None, :], 3, axis=1)
    verts = np.empty((3 * len(corners), 6), dtype=np.float32)
    verts[:, :3] = tri_pts.reshape(-1, 3)
    verts[:, 3:] = np.asarray(tri_nrm).reshape(-1, 3)
    used = pts[np.unique(idx)] if len(idx) < len(pts) else pts  # unused points do not frame
    return _MeshData(verts, colours.of(prim), used.min(axis=0), used.max(axis=0))


def _gf(m) -> np.ndarray:
    return np.array(m, dtype=np.float64).reshape(4, 4)


class _Gatherer:
    """Walk a stage once; prototypes (native and point-instancer) are read once and memoised."""

    def __init__(self, stage: Usd.Stage, t: Usd.TimeCode) -> None:
        self.stage = stage
        self.t = t
        self.xfc = UsdGeom.XformCache(t)
        self.colours = _Colours()
        self.scene = _Scene()
        self._proto_entries: dict[str, list[tuple[str, np.ndarray]]] = {}

    def walk(self, root: Usd.Prim, relative: bool) -> list[tuple[str, np.ndarray]]:
        """``(mesh key, matrix)`` for every drawable under ``root`` (row-vector matrices,
        relative to ``root`` when ``relative``, else local-to-world)."""
        out: list[tuple[str, np.ndarray]] = []
        purposes: dict[Sdf.Path, str] = {}
        it = iter(Usd.PrimRange(root, Usd.PrimDefaultPredicate))
        for prim in it:
            path = prim.GetPath()
            inherited = purposes.get(path.GetParentPath(), "default")
            img = UsdGeom.Imageable(prim)
            if img:
                if img.GetVisibilityAttr().Get(self.t) == UsdGeom.Tokens.invisible:
                    it.PruneChildren()
                    continue
                attr = img.GetPurposeAttr()
                purpose = str(attr.Get()) if attr.HasAuthoredValue() else inherited
                if purpose in _SKIP_PURPOSES:
                    it.PruneChildren()
                    continue
                purposes[path] = purpose
            else:
                purposes[path] = inherited
            if not (prim.IsInstance() or prim.IsA(UsdGeom.PointInstancer)
                    or prim.IsA(UsdGeom.Mesh)):
                continue
            if relative:
                m = _gf(self.xfc.ComputeRelativeTransform(prim, root)[0])
            else:
                m = _gf(self.xfc.GetLocalToWorldTransform(prim))
            if prim.IsInstance():
                it.PruneChildren()
                proto = prim.GetPrototype()
                out.extend((k, rel @ m) for k, rel in self._prototype(proto))
            elif prim.IsA(UsdGeom.PointInstancer):
                it.PruneChildren()
                out.extend(self._point_instancer(UsdGeom.PointInstancer(prim), m))
            else:
                key = str(path)
                if key not in self.scene.meshes:
                    data = _read_mesh(prim, self.colours, self.t)
                    if data is None:
                        continue
                    self.scene.meshes[key] = data
                out.append((key, m))
        return out

    def _prototype(self, root: Usd.Prim) -> list[tuple[str, np.ndarray]]:
        key = str(root.GetPath())
        if key not in self._proto_entries:
            # relative to the root: a native prototype's root carries no transform, and a point
            # instancer's prototype transform is inside its instance transforms
            self._proto_entries[key] = self.walk(root, relative=True)
            for k, _ in self._proto_entries[key]:
                self.scene.meshes[k].instanced = True
        if self._proto_entries[key]:
            self.scene.prototypes.add(key)
        return self._proto_entries[key]

    def _point_instancer(self, pi: UsdGeom.PointInstancer, world: np.ndarray):
        targets = pi.GetPrototypesRel().GetForwardedTargets()
        ids = _np(pi.GetProtoIndicesAttr().Get(self.t), np.int64)
        if len(ids) == 0 or not targets:
            return []
        xforms = pi.ComputeInstanceTransformsAtTime(
            self.t, self.t, UsdGeom.PointInstancer.IncludeProtoXform,
            UsdGeom.PointInstancer.IgnoreMask)
        mats = np.array(xforms, dtype=np.float64).reshape(-1, 4, 4)
        mask = pi.ComputeMaskAtTime(self.t)
        keep = np.ones(len(ids), bool) if not mask else np.asarray(mask, bool)
        out = []
        for j, target in enumerate(targets):
            proto = self.stage.GetPrimAtPath(target)
            sel = np.flatnonzero((ids == j) & keep[: len(ids)])
            if not proto or len(sel) == 0:
                continue
            for k, rel in self._prototype(proto):
                out.extend((k, rel @ mats[i] @ world) for i in sel)
        return out


# -- stage -------------------------------------------------------------------------------------
def _open_stage(usd_path: str | os.PathLike) -> Usd.Stage:
    p = Path(usd_path)
    if not p.is_file():
        raise ParameterError("usd_path", str(p), "an existing USD file (.usd, .usda, .usdc, .usdz)")
    try:
        stage = Usd.Stage.Open(str(p), Usd.Stage.LoadAll)
    except Exception as exc:  # pxr raises Tf.ErrorException with the parser's message
        raise UsdAuthoringError(f"{p}: cannot open as a USD stage: {exc}") from exc
    if stage is None:
        raise UsdAuthoringError(f"{p}: cannot open as a USD stage")
    return stage


def _select_lod(stage: Usd.Stage, lod: str) -> int:
    """Select ``lod`` on every prim with a ``lod`` variant set (in the session layer)."""
    found = 0
    changed = True
    seen: set[Sdf.Path] = set()
    with Usd.EditContext(stage, stage.GetSessionLayer()):
        while changed:  # a selection may compose in prims with their own lod sets
            changed = False
            for prim in stage.Traverse():
                if prim.GetPath() in seen or not prim.HasVariantSets():
                    continue
                vsets = prim.GetVariantSets()
                if "lod" not in vsets.GetNames():
                    continue
                seen.add(prim.GetPath())
                vset = vsets.GetVariantSet("lod")
                names = vset.GetVariantNames()
                if lod not in names:
                    raise ParameterError("lod", lod, f"one of {', '.join(names)}",
                                         context=str(prim.GetPath()))
                found += 1
                if vset.GetVariantSelection() != lod:
                    vset.SetVariantSelection(lod)
                    changed = True
                    break
    if not found:
        raise ParameterError("lod", lod, "no lod (the stage has no 'lod' variant set)")
    return found


def _root_matrix(stage: Usd.Stage) -> np.ndarray:
    """Row-vector matrix taking stage coordinates to Y-up metres."""
    s = float(UsdGeom.GetStageMetersPerUnit(stage)) or 1.0
    m = np.eye(4) * s
    m[3, 3] = 1.0
    if UsdGeom.GetStageUpAxis(stage) == UsdGeom.Tokens.z:
        # (x, y, z) -> (x, z, -y): +Z becomes +Y, right-handed kept
        m[:3, :3] = s * np.array([[1.0, 0, 0], [0, 0, -1.0], [0, 1.0, 0]])
    return m


# -- camera ------------------------------------------------------------------------------------
def _look_at(eye: np.ndarray, target: np.ndarray, up: np.ndarray) -> np.ndarray:
    f = target - eye
    f /= np.linalg.norm(f)
    r = np.cross(f, up)
    r /= np.linalg.norm(r)
    u = np.cross(r, f)
    v = np.eye(4)
    v[0, :3], v[1, :3], v[2, :3] = r, u, -f
    v[:3, 3] = -v[:3, :3] @ eye
    return v


def _perspective(fovy: float, aspect: float, near: float, far: float) -> np.ndarray:
    f = 1.0 / math.tan(fovy / 2)
    p = np.zeros((4, 4))
    p[0, 0], p[1, 1] = f / aspect, f
    p[2, 2], p[2, 3] = (far + near) / (near - far), 2 * far * near / (near - far)
    p[3, 2] = -1.0
    return p


def _ortho(half: float, near: float, far: float) -> np.ndarray:
    p = np.eye(4)
    p[0, 0] = p[1, 1] = 1.0 / half
    p[2, 2], p[2, 3] = -2.0 / (far - near), -(far + near) / (far - near)
    return p


def _camera_direction(camera: str, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """Unit vector from the target towards the eye (front = +Z side)."""
    size = hi - lo
    if camera == "front":
        az, el = 0.0, 6.0
    elif camera == "three-quarter":
        az, el = 35.0, 20.0
    else:  # auto: look down more on wide, flat scenes (a temple plan), less on tall ones
        az, el = 35.0, (12.0 if size[1] > max(size[0], size[2]) else 28.0)
    az, el = math.radians(az), math.radians(el)
    return np.array([math.sin(az) * math.cos(el), math.sin(el), math.cos(az) * math.cos(el)])


def _frame(corners: np.ndarray, direction: np.ndarray, aspect: float):
    """Eye, target and distance such that every corner fits the 40° view with a margin."""
    target = 0.5 * (corners.min(axis=0) + corners.max(axis=0))
    f = -direction
    r = np.cross(f, [0.0, 1.0, 0.0])
    r /= np.linalg.norm(r)
    u = np.cross(r, f)
    tan_v = math.tan(math.radians(_FOV_DEG) / 2) / 1.1
    tan_h = tan_v * aspect
    d = 0.0
    for _ in range(2):  # second pass re-centres the projected box
        rel = corners - target
        x, y, z = rel @ r, rel @ u, rel @ f
        d = max(float(np.max(np.abs(x) / tan_h - z)), float(np.max(np.abs(y) / tan_v - z)))
        depth = d + z
        sx, sy = x / depth, y / depth
        target = target + r * 0.5 * (sx.max() + sx.min()) * d + u * 0.5 * (sy.max() + sy.min()) * d
    radius = 0.5 * float(np.linalg.norm(corners.max(axis=0) - corners.min(axis=0)))
    d = max(d, 1e-6 + radius * 0.05)
    return target + direction * d, target, d, radius


# -- shaders -----------------------------------------------------------------------------------
_LIGHTING = """
uniform vec3 u_key, u_fill, u_eye;
uniform mat4 u_light;
uniform sampler2DShadow u_shadow;
uniform float u_texel, u_texel_uv;

float shadow(vec3 p, vec3 n) {
    vec4 q = u_light * vec4(p + n * u_texel * 1.5, 1.0);
    vec3 s = q.xyz * 0.5 + 0.5;
    if (s.x <= 0.0 || s.x >= 1.0 || s.y <= 0.0 || s.y >= 1.0 || s.z >= 1.0) return 1.0;
    float sum = 0.0;
    for (int i = -1; i <= 1; ++i)
        for (int j = -1; j <= 1; ++j)
            sum += texture(u_shadow, vec3(s.xy + vec2(i, j) * u_texel_uv, s.z - 0.0005));
    return sum / 9.0;
}

vec3 shade(vec3 albedo, vec3 p, vec3 n, float gloss) {
    vec3 v = normalize(u_eye - p);
    float lit = shadow(p, n);
    float k = max(dot(n, u_key), 0.0) * lit;
    float f = max(dot(n, u_fill), 0.0);
    vec3 ambient = mix(vec3(0.36, 0.32, 0.27), vec3(0.62, 0.70, 0.80), 0.5 + 0.5 * n.y);
    vec3 h = normalize(u_key + v);
    float spec = gloss * pow(max(dot(n, h), 0.0), 48.0) * k;
    return albedo * (0.36 * ambient + 1.10 * k * vec3(1.0, 0.95, 0.86)
                     + 0.22 * f * vec3(0.70, 0.80, 1.0)) + spec * vec3(1.0, 0.97, 0.9);
}

vec3 to_srgb(vec3 c) {
    c = c / (1.0 + 0.15 * c);  // soft shoulder keeps highlights from clipping flat
    c = clamp(c, 0.0, 1.0);
    return mix(12.92 * c, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, step(0.0031308, c));
}
"""

_MESH_VS = """
#version 330
uniform mat4 u_viewproj;
in vec3 in_pos, in_nrm;
in mat4 in_model;
in mat3 in_nmat;
out vec3 v_pos, v_nrm;
void main() {
    vec4 w = in_model * vec4(in_pos, 1.0);
    v_pos = w.xyz;
    v_nrm = in_nmat * in_nrm;
    gl_Position = u_viewproj * w;
}
"""

_MESH_FS = "#version 330\n" + _LIGHTING + """
uniform vec3 u_colour;
in vec3 v_pos, v_nrm;
out vec4 f_colour;
void main() {
    vec3 n = dot(v_nrm, v_nrm) > 1e-20 ? normalize(v_nrm) : vec3(0.0, 1.0, 0.0);
    if (!gl_FrontFacing) n = -n;
    f_colour = vec4(to_srgb(shade(u_colour, v_pos, n, 0.10)), 1.0);
}
"""

_DEPTH_VS = """
#version 330
uniform mat4 u_viewproj;
in vec3 in_pos;
in mat4 in_model;
void main() { gl_Position = u_viewproj * (in_model * vec4(in_pos, 1.0)); }
"""

_DEPTH_FS = "#version 330\nvoid main() {}\n"

_BACKGROUND_VS = """
#version 330
in vec2 in_xy;
out float v_t;
void main() { v_t = in_xy.y * 0.5 + 0.5; gl_Position = vec4(in_xy, 0.999999, 1.0); }
"""

_BACKGROUND_FS = """
#version 330
uniform vec3 u_top, u_bottom;
in float v_t;
out vec4 f_colour;
void main() { f_colour = vec4(mix(u_bottom, u_top, smoothstep(0.0, 1.0, v_t)), 1.0); }
"""

_GROUND_VS = """
#version 330
uniform mat4 u_viewproj;
in vec3 in_pos;
out vec3 v_pos;
void main() { v_pos = in_pos; gl_Position = u_viewproj * vec4(in_pos, 1.0); }
"""

_GROUND_FS = "#version 330\n" + _LIGHTING + """
uniform vec3 u_colour;
uniform vec2 u_centre, u_fade;
in vec3 v_pos;
out vec4 f_colour;
void main() {
    float d = length(v_pos.xz - u_centre);
    float a = 1.0 - smoothstep(u_fade.x, u_fade.y, d);
    f_colour = vec4(to_srgb(shade(u_colour, v_pos, vec3(0.0, 1.0, 0.0), 0.0)), a);
}
"""


# -- GL ----------------------------------------------------------------------------------------
def create_context():
    """A standalone OpenGL 3.3 core context on EGL (headless), or :class:`PreviewUnavailableError`.

    Returns a ``moderngl.Context``; the caller releases it.
    """
    try:
        import moderngl  # noqa: PLC0415
    except ImportError as exc:
        raise PreviewUnavailableError(
            f"moderngl is not importable ({exc}); install the preview extra: "
            "pip install 'ionic_usd[preview]'") from exc
    try:
        return moderngl.create_standalone_context(backend="egl", require=330)
    except Exception as exc:  # glcontext raises plain Exception for a missing libEGL/driver
        raise PreviewUnavailableError(
            f"cannot create a headless OpenGL 3.3 context through EGL ({exc}); no OpenGL/EGL "
            "driver: apt-get install libegl1 libgl1-mesa-dri") from exc


def _instance_block(mats: np.ndarray) -> np.ndarray:
    """``(n, 25) float32``: the model matrix and the normal matrix, column-major for GLSL.

    ``mats`` are row-vector matrices, so their row-major bytes are the column-vector matrix in
    column-major order. The normal matrix is the cofactor of the linear part (the inverse
    transpose up to a positive scale, which the shader's normalize removes) and needs no
    inverse, so singular scales cannot fail.
    """
    a = mats[:, :3, :3]
    cof = np.stack([np.cross(a[:, 1], a[:, 2]), np.cross(a[:, 2], a[:, 0]),
                    np.cross(a[:, 0], a[:, 1])], axis=1)
    det = np.einsum("ij,ij->i", a[:, 0], cof[:, 0])
    cof *= np.where(det < 0, -1.0, 1.0)[:, None, None]
    out = np.empty((len(mats), 25), dtype=np.float32)
    out[:, :16] = mats.reshape(-1, 16)
    out[:, 16:] = cof.reshape(-1, 9)
    return out


def _gl_mat(m: np.ndarray) -> bytes:
    return np.ascontiguousarray(m.T, dtype=np.float32).tobytes()


def _write_png(pixels: np.ndarray, out: Path) -> None:
    import OpenImageIO as oiio  # noqa: PLC0415

    from ionic_usd.io import atomic_path  # noqa: PLC0415
    from ionic_usd.texture.stone import TextureError, verify_image  # noqa: PLC0415

    def check(tmp: Path) -> None:  # a full disk can leave a truncated PNG after "success"
        try:
            verify_image(tmp)
        except TextureError:
            raise UsdAuthoringError(f"cannot write {out}: the written PNG is incomplete "
                                    "(is the disk full?)") from None

    with atomic_path(out, verify=check) as tmp:
        h, w, c = pixels.shape
        img = oiio.ImageOutput.create(str(tmp))
        if img is None or not img.open(str(tmp), oiio.ImageSpec(w, h, c, oiio.UINT8)):
            raise UsdAuthoringError(f"cannot write {out}: {oiio.geterror()}")
        ok = img.write_image(np.ascontiguousarray(pixels))
        closed = img.close()  # the encoder flushes here: its result counts too
        if not (ok and closed):
            raise UsdAuthoringError(f"cannot write {out}: {img.geterror() or oiio.geterror()}")


def _validate(width, height, camera, samples, background, out: Path, force: bool) -> None:
    for name, v in (("width", width), ("height", height)):
        if not isinstance(v, int) or isinstance(v, bool) or not 16 <= v <= 8192:
            raise ParameterError(name, v, "an integer from 16 to 8192 pixels")
    if camera not in CAMERAS:
        raise ParameterError("camera", camera, f"one of {', '.join(CAMERAS)}")
    if not isinstance(samples, int) or isinstance(samples, bool) or not 0 <= samples <= 16:
        raise ParameterError("samples", samples, "an integer from 0 (no MSAA) to 16")
    bg = np.asarray(background, dtype=np.float64)
    if bg.shape != (3,) or not np.all((bg >= 0) & (bg <= 1)):
        raise ParameterError("background", background, "three sRGB components in [0, 1]")
    if out.suffix.lower() != ".png":
        raise ParameterError("out_png", str(out), "a file ending in .png")
    from ionic_usd.io import check_output_file  # noqa: PLC0415

    check_output_file(out, force=force)  # a name, a writable folder, not a folder itself


def render_preview(
    usd_path: str | os.PathLike,
    out_png: str | os.PathLike,
    *,
    width: int = 800,
    height: int = 600,
    camera: str = "auto",
    lod: str | None = None,
    background: tuple[float, float, float] = (0.80, 0.84, 0.89),
    samples: int = 4,
    ground: bool = True,
    force: bool = False,
) -> PreviewStats:
    """Render a USD scene to a PNG thumbnail with OpenGL on a headless EGL context.

    Parameters
    ----------
    usd_path : the stage to open (every payload is loaded)
    out_png : the picture to write (atomically); refused if it exists unless ``force``
    width, height : picture size in pixels
    camera : ``auto`` (three-quarter view, steeper for wide flat scenes), ``front`` (from +Z)
        or ``three-quarter``; all frame the drawn geometry's world bounds with a 40° vertical fov
    lod : select this variant on every prim that has a ``lod`` variant set (session layer)
    background : sRGB colour of the top of the gradient; the horizon is a lighter tint of it
    samples : MSAA samples (clamped to what the driver offers; 0 or 1 turns MSAA off)
    ground : draw a ground plane at the lowest point, with the key light's shadow

    Returns
    -------
    PreviewStats

    Raises
    ------
    ParameterError : bad argument, missing file, unknown ``lod``
    UsdAuthoringError : the file does not open as a stage
    GeometryError : nothing visible to draw, or a malformed mesh
    PreviewUnavailableError : no moderngl or no EGL driver
    """
    t0 = time.perf_counter()
    out = Path(out_png)
    _validate(width, height, camera, samples, background, out, force)
    stage = _open_stage(usd_path)
    if lod is not None:
        _select_lod(stage, lod)
    tc = Usd.TimeCode.EarliestTime()  # the first sample of animated attributes, else default
    gatherer = _Gatherer(stage, tc)
    entries = gatherer.walk(stage.GetPseudoRoot(), relative=False)
    scene = gatherer.scene
    root = _root_matrix(stage)
    for key, m in entries:
        scene.meshes[key].placements.append(m @ root)
    drawn = {k: d for k, d in scene.meshes.items() if d.placements}
    if not drawn:
        raise GeometryError(f"{usd_path}: no visible, active mesh to draw")
    corners = []
    for d in drawn.values():
        box = np.array([[x, y, z, 1.0] for x in (d.lo[0], d.hi[0]) for y in (d.lo[1], d.hi[1])
                        for z in (d.lo[2], d.hi[2])])
        mats = np.stack(d.placements)
        corners.append(np.einsum("ci,nij->ncj", box, mats)[..., :3].reshape(-1, 3))
    corners = np.concatenate(corners)
    t_load = time.perf_counter()

    ctx = create_context()
    try:
        pixels, draws = _render(ctx, drawn, corners, width, height, camera, background,
                                samples, ground)
    finally:
        ctx.release()
    t_render = time.perf_counter()
    out.parent.mkdir(parents=True, exist_ok=True)
    _write_png(pixels, out)
    t1 = time.perf_counter()
    protos = {k for k in scene.prototypes
              if any(drawn.get(key) is not None for key, _ in gatherer._proto_entries[k])}
    return PreviewStats(
        meshes=len(drawn), prototypes=len(protos),
        instances=sum(len(d.placements) for d in drawn.values() if d.instanced), draws=draws,
        triangles=sum(d.triangles * len(d.placements) for d in drawn.values()),
        width=width, height=height, seconds=t1 - t0, load_seconds=t_load - t0,
        render_seconds=t_render - t_load)


def _render(ctx, drawn: dict[str, _MeshData], corners: np.ndarray, width: int, height: int,
            camera: str, background, samples: int, ground: bool) -> tuple[np.ndarray, int]:
    """Draw into a multisampled framebuffer, resolve, and return ``(h, w, 3) uint8`` pixels."""
    lo, hi = corners.min(axis=0), corners.max(axis=0)
    aspect = width / height
    direction = _camera_direction(camera, lo, hi)
    eye, target, dist, radius = _frame(corners, direction, aspect)
    radius = max(radius, 1e-6)
    near = max(dist - 1.5 * radius, dist * 1e-3)
    far = dist + 12.0 * radius
    viewproj = _perspective(math.radians(_FOV_DEG), aspect, near, far) @ _look_at(
        eye, target, np.array([0.0, 1.0, 0.0]))

    # key light high on the camera's right, fill low from its left
    az = math.atan2(direction[0], direction[2])
    key = np.array([math.sin(az + 1.1) * 0.75, 0.66, math.cos(az + 1.1) * 0.75])
    key /= np.linalg.norm(key)
    fill = np.array([math.sin(az - 1.4) * 0.8, 0.25, math.cos(az - 1.4) * 0.8])
    fill /= np.linalg.norm(fill)
    centre = 0.5 * (lo + hi)
    ground_y = lo[1] - 1e-4 * radius
    shadow_half = radius * (1.6 if ground else 1.05)
    light_eye = centre + key * 3.0 * shadow_half
    light = _ortho(shadow_half, 0.0, 6.0 * shadow_half) @ _look_at(
        light_eye, centre, np.array([0.0, 0.0, 1.0]) if abs(key[1]) > 0.99 else np.eye(3)[1])

    mesh_prog = ctx.program(vertex_shader=_MESH_VS, fragment_shader=_MESH_FS)
    depth_prog = ctx.program(vertex_shader=_DEPTH_VS, fragment_shader=_DEPTH_FS)
    bg_prog = ctx.program(vertex_shader=_BACKGROUND_VS, fragment_shader=_BACKGROUND_FS)
    ground_prog = ctx.program(vertex_shader=_GROUND_VS, fragment_shader=_GROUND_FS)

    draws = []
    for d in drawn.values():
        vbo = ctx.buffer(d.vertices.tobytes())
        ibo = ctx.buffer(_instance_block(np.stack(d.placements)).tobytes())
        vao = ctx.vertex_array(mesh_prog, [(vbo, "3f 3f", "in_pos", "in_nrm"),
                                           (ibo, "16f 9f/i", "in_model", "in_nmat")])
        dvao = ctx.vertex_array(depth_prog, [(vbo, "3f 12x", "in_pos"),
                                             (ibo, "16f 36x/i", "in_model")])
        draws.append((vao, dvao, len(d.placements), d.colour))

    # shadow map from the key light
    shadow_tex = ctx.depth_texture((_SHADOW_SIZE, _SHADOW_SIZE))
    shadow_tex.compare_func = "<="
    shadow_tex.repeat_x = shadow_tex.repeat_y = False
    shadow_fbo = ctx.framebuffer(depth_attachment=shadow_tex)
    shadow_fbo.use()
    shadow_fbo.clear(depth=1.0)
    ctx.enable(ctx.DEPTH_TEST)
    ctx.polygon_offset = (2.0, 4.0)
    depth_prog["u_viewproj"].write(_gl_mat(light))
    for _, dvao, n, _ in draws:
        dvao.render(instances=n)
    ctx.polygon_offset = (0.0, 0.0)

    samples = min(samples, ctx.max_samples) if samples > 1 else 0
    size = (width, height)
    colour_rb = ctx.renderbuffer(size, components=4, samples=samples)
    depth_rb = ctx.depth_renderbuffer(size, samples=samples)
    fbo = ctx.framebuffer(color_attachments=[colour_rb], depth_attachment=depth_rb)
    fbo.use()
    fbo.clear(0.0, 0.0, 0.0, 1.0, depth=1.0)

    top = np.asarray(background, dtype=np.float64)
    bottom = 1.0 - 0.45 * (1.0 - top)
    bg_prog["u_top"].value = tuple(top)
    bg_prog["u_bottom"].value = tuple(bottom)
    quad = ctx.buffer(np.array([-1, -1, 3, -1, -1, 3], dtype=np.float32).tobytes())
    bg_vao = ctx.vertex_array(bg_prog, [(quad, "2f", "in_xy")])
    ctx.disable(ctx.DEPTH_TEST)
    bg_vao.render()
    ctx.enable(ctx.DEPTH_TEST)

    shadow_tex.use(location=0)
    texel = 2.0 * shadow_half / _SHADOW_SIZE
    uniforms = {"u_key": tuple(key), "u_fill": tuple(fill), "u_eye": tuple(eye),
                "u_shadow": 0, "u_texel": texel, "u_texel_uv": 1.0 / _SHADOW_SIZE}
    for prog in (mesh_prog, ground_prog):
        prog["u_viewproj"].write(_gl_mat(viewproj))
        prog["u_light"].write(_gl_mat(light))
        for name, value in uniforms.items():
            if name in prog:  # the compiler drops uniforms a program does not use
                prog[name].value = value
    draw_calls = 0
    for vao, _, n, colour in draws:
        mesh_prog["u_colour"].value = tuple(float(c) for c in colour)
        vao.render(instances=n)
        draw_calls += 1

    if ground:
        h = 8.0 * radius
        cx, cz = centre[0], centre[2]
        plane = np.array([[cx - h, ground_y, cz - h], [cx + h, ground_y, cz - h],
                          [cx + h, ground_y, cz + h], [cx - h, ground_y, cz - h],
                          [cx + h, ground_y, cz + h], [cx - h, ground_y, cz + h]], np.float32)
        gbuf = ctx.buffer(plane.tobytes())
        gvao = ctx.vertex_array(ground_prog, [(gbuf, "3f", "in_pos")])
        ground_prog["u_colour"].value = (0.42, 0.40, 0.36)
        ground_prog["u_centre"].value = (float(cx), float(cz))
        ground_prog["u_fade"].value = (1.0 * radius, 3.5 * radius)
        ctx.enable(ctx.BLEND)
        ctx.blend_func = ctx.SRC_ALPHA, ctx.ONE_MINUS_SRC_ALPHA
        gvao.render()  # after the meshes: depth test keeps it behind them, it blends over sky
        ctx.disable(ctx.BLEND)

    resolved = ctx.framebuffer(color_attachments=[ctx.renderbuffer(size, components=3)])
    ctx.copy_framebuffer(resolved, fbo)
    data = resolved.read(components=3, alignment=1)
    pixels = np.frombuffer(data, dtype=np.uint8).reshape(height, width, 3)[::-1]
    return np.ascontiguousarray(pixels), draw_calls
