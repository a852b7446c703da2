"""OpenGL 3.3 rendering of draw lists on a headless (EGL) moderngl context, and the PNG writer.

A mesh is uploaded once and drawn with one instanced call carrying a per-instance ``mat4`` and
normal matrix. Passes: a shadow map from the key light, the sky gradient (or a transparent
clear for card bakes), the lit meshes, the alpha-tested card faces, the ground plane.

``moderngl`` is the optional ``preview`` extra, imported only in :func:`create_context`.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ionic_usd.errors import IonicError, UsdAuthoringError
from ionic_usd.preview import shaders
from ionic_usd.preview.camera import key_and_fill, look_at, ortho
from ionic_usd.preview.scene import DrawItem

__all__ = ["PreviewUnavailableError", "View", "create_context", "render", "write_png"]

SHADOW_SIZE = 2048


class PreviewUnavailableError(IonicError, RuntimeError):
    """No OpenGL context can be made: moderngl is missing or there is no EGL driver."""


@dataclass(frozen=True)
class View:
    """A camera: ``viewproj`` (4, 4) column-vector matrix, ``eye`` (3,) for highlights,
    ``direction`` (3,) unit vector from the target towards the eye (sets the lights)."""

    viewproj: np.ndarray
    eye: np.ndarray
    direction: np.ndarray


def create_context():
    """A standalone OpenGL 3.3 core context on EGL (headless), or :class:`PreviewUnavailableError`.

    Returns a ``moderngl.Context``; the caller releases it.
    """
    try:
        import moderngl  # noqa: PLC0415
    except ImportError as exc:
        raise PreviewUnavailableError(
            f"moderngl is not importable ({exc}); install the preview extra: "
            "pip install 'ionic_usd[preview]'"
        ) from exc
    try:
        return moderngl.create_standalone_context(backend="egl", require=330)
    except Exception as exc:  # glcontext raises plain Exception for a missing libEGL/driver
        raise PreviewUnavailableError(
            f"cannot create a headless OpenGL 3.3 context through EGL ({exc}); no OpenGL/EGL "
            "driver: apt-get install libegl1 libgl1-mesa-dri"
        ) from exc


def instance_block(mats: np.ndarray) -> np.ndarray:
    """``(n, 25) float32``: the model matrix and the normal matrix, column-major for GLSL.

    ``mats`` (n, 4, 4) are row-vector matrices, so their row-major bytes are the column-vector
    matrix in column-major order. The normal matrix is the cofactor of the linear part (the
    inverse transpose up to a positive scale, which the shader's normalize removes) and needs
    no inverse, so singular scales cannot fail.
    """
    a = mats[:, :3, :3]
    cof = np.stack(
        [np.cross(a[:, 1], a[:, 2]), np.cross(a[:, 2], a[:, 0]), np.cross(a[:, 0], a[:, 1])], axis=1
    )
    det = np.einsum("ij,ij->i", a[:, 0], cof[:, 0])
    cof *= np.where(det < 0, -1.0, 1.0)[:, None, None]
    out = np.empty((len(mats), 25), dtype=np.float32)
    out[:, :16] = mats.reshape(-1, 16)
    out[:, 16:] = cof.reshape(-1, 9)
    return out


def _gl_mat(m: np.ndarray) -> bytes:
    return np.ascontiguousarray(m.T, dtype=np.float32).tobytes()


def write_png(pixels: np.ndarray, out: Path) -> None:
    """Write ``(h, w, c) uint8`` pixels (top row first) as a PNG, atomically and verified."""
    import OpenImageIO as oiio  # noqa: PLC0415

    from ionic_usd.io import atomic_path  # noqa: PLC0415
    from ionic_usd.texture.stone import TextureError, verify_image  # noqa: PLC0415

    def check(tmp: Path) -> None:  # a full disk can leave a truncated PNG after "success"
        try:
            verify_image(tmp)
        except TextureError:
            raise UsdAuthoringError(
                f"cannot write {out}: the written PNG is incomplete (is the disk full?)"
            ) from None

    with atomic_path(out, verify=check) as tmp:
        h, w, c = pixels.shape
        img = oiio.ImageOutput.create(str(tmp))
        if img is None or not img.open(str(tmp), oiio.ImageSpec(w, h, c, oiio.UINT8)):
            raise UsdAuthoringError(f"cannot write {out}: {oiio.geterror()}")
        ok = img.write_image(np.ascontiguousarray(pixels))
        closed = img.close()  # the encoder flushes here: its result counts too
        if not (ok and closed):
            raise UsdAuthoringError(f"cannot write {out}: {img.geterror() or oiio.geterror()}")


class _Uploaded:
    """The GPU side of a draw list: vertex arrays per item, card images as textures."""

    def __init__(self, ctx, items: list[DrawItem]) -> None:
        self.mesh_prog = ctx.program(vertex_shader=shaders.MESH_VS, fragment_shader=shaders.MESH_FS)
        self.depth_prog = ctx.program(
            vertex_shader=shaders.DEPTH_VS, fragment_shader=shaders.DEPTH_FS
        )
        self.card_prog = ctx.program(vertex_shader=shaders.CARD_VS, fragment_shader=shaders.CARD_FS)
        self.card_depth_prog = ctx.program(
            vertex_shader=shaders.CARD_DEPTH_VS, fragment_shader=shaders.CARD_DEPTH_FS
        )
        self.meshes: list[tuple[Any, Any, int, tuple[float, float, float]]] = []
        self.cards: list[tuple[Any, Any, int, Any]] = []
        textures: dict[int, Any] = {}
        for d in items:
            vbo = ctx.buffer(d.vertices.tobytes())
            ibo = ctx.buffer(instance_block(d.placements).tobytes())
            n = len(d.placements)
            if d.image is not None and d.uv is not None:
                tid = id(d.image)
                if tid not in textures:
                    h, w = d.image.shape[:2]
                    tex = ctx.texture((w, h), 4, d.image.tobytes())
                    tex.build_mipmaps()
                    tex.repeat_x = tex.repeat_y = False
                    textures[tid] = tex
                uvb = ctx.buffer(d.uv.tobytes())
                layout = [
                    (vbo, "3f 12x", "in_pos"),
                    (uvb, "2f", "in_uv"),
                    (ibo, "16f 36x/i", "in_model"),
                ]
                self.cards.append(
                    (
                        ctx.vertex_array(self.card_prog, layout),
                        ctx.vertex_array(self.card_depth_prog, layout),
                        n,
                        textures[tid],
                    )
                )
                continue
            vao = ctx.vertex_array(
                self.mesh_prog,
                [(vbo, "3f 3f", "in_pos", "in_nrm"), (ibo, "16f 9f/i", "in_model", "in_nmat")],
            )
            dvao = ctx.vertex_array(
                self.depth_prog, [(vbo, "3f 12x", "in_pos"), (ibo, "16f 36x/i", "in_model")]
            )
            self.meshes.append((vao, dvao, n, d.colour))

    def depth(self, viewproj: np.ndarray) -> None:
        self.depth_prog["u_viewproj"].write(_gl_mat(viewproj))
        for _, dvao, n, _ in self.meshes:
            dvao.render(instances=n)
        self.card_depth_prog["u_viewproj"].write(_gl_mat(viewproj))
        for _, dvao, n, tex in self.cards:
            tex.use(location=1)
            self.card_depth_prog["u_image"].value = 1
            dvao.render(instances=n)


def render(
    ctx,
    items: list[DrawItem],
    corners: np.ndarray,
    view: View,
    width: int,
    height: int,
    *,
    background: tuple[float, float, float] | None,
    samples: int,
    ground: bool,
) -> tuple[np.ndarray, int]:
    """Draw into a multisampled framebuffer, resolve, and return the pixels and draw calls.

    Parameters
    ----------
    corners : (m, 3) world points bounding what is drawn (frames the shadow map and ground)
    background : sRGB top colour of the sky gradient, or None for a transparent background
        (the pixels are then RGBA with straight alpha)

    Returns
    -------
    pixels : (height, width, 3 or 4) uint8, top row first
    draws : instanced draw calls of the colour pass
    """
    lo, hi = corners.min(axis=0), corners.max(axis=0)
    centre = 0.5 * (lo + hi)
    radius = max(0.5 * float(np.linalg.norm(hi - lo)), 1e-6)
    key, fill = key_and_fill(view.direction)
    ground_y = lo[1] - 1e-4 * radius
    shadow_half = radius * (1.6 if ground else 1.05)
    light = ortho(shadow_half, shadow_half, 0.0, 6.0 * shadow_half) @ look_at(
        centre + key * 3.0 * shadow_half,
        centre,
        np.array([0.0, 0.0, 1.0]) if abs(key[1]) > 0.99 else np.eye(3)[1],
    )
    gpu = _Uploaded(ctx, items)
    bg_prog = ctx.program(
        vertex_shader=shaders.BACKGROUND_VS, fragment_shader=shaders.BACKGROUND_FS
    )
    ground_prog = ctx.program(vertex_shader=shaders.GROUND_VS, fragment_shader=shaders.GROUND_FS)
    shadow_tex = _shadow_map(ctx, gpu, light)
    size = (width, height)
    fbo = _colour_target(ctx, size, samples, background, bg_prog)
    shadow_tex.use(location=0)
    uniforms = {
        "u_key": tuple(key),
        "u_fill": tuple(fill),
        "u_eye": tuple(view.eye),
        "u_shadow": 0,
        "u_texel": 2.0 * shadow_half / SHADOW_SIZE,
        "u_texel_uv": 1.0 / SHADOW_SIZE,
    }
    for prog in (gpu.mesh_prog, ground_prog):
        prog["u_viewproj"].write(_gl_mat(view.viewproj))
        prog["u_light"].write(_gl_mat(light))
        for name, value in uniforms.items():
            if name in prog:  # the compiler drops uniforms a program does not use
                prog[name].value = value
    draw_calls = _draw_items(ctx, gpu, view)
    if ground:
        _draw_ground(ctx, ground_prog, centre, radius, ground_y)
    pixels = _read_pixels(ctx, fbo, size, 3 if background is not None else 4)
    return pixels, draw_calls


def _shadow_map(ctx, gpu: _Uploaded, light: np.ndarray):
    """The depth texture of the scene seen from the key light (``light``: its view-projection)."""
    import moderngl  # noqa: PLC0415

    shadow_tex = ctx.depth_texture((SHADOW_SIZE, SHADOW_SIZE))
    shadow_tex.compare_func = "<="
    shadow_tex.repeat_x = shadow_tex.repeat_y = False
    shadow_fbo = ctx.framebuffer(depth_attachment=shadow_tex)
    shadow_fbo.use()
    shadow_fbo.clear(depth=1.0)
    ctx.enable(moderngl.DEPTH_TEST)
    ctx.polygon_offset = (2.0, 4.0)
    gpu.depth(light)
    ctx.polygon_offset = (0.0, 0.0)
    return shadow_tex


def _colour_target(ctx, size: tuple[int, int], samples: int, background, bg_prog):
    """The multisampled framebuffer, in use and cleared, with the sky gradient drawn when
    there is a ``background`` (sRGB top colour; None: transparent)."""
    import moderngl  # noqa: PLC0415

    samples = min(samples, ctx.max_samples) if samples > 1 else 0
    colour_rb = ctx.renderbuffer(size, components=4, samples=samples)
    depth_rb = ctx.depth_renderbuffer(size, samples=samples)
    fbo = ctx.framebuffer(color_attachments=[colour_rb], depth_attachment=depth_rb)
    fbo.use()
    fbo.clear(0.0, 0.0, 0.0, 0.0 if background is None else 1.0, depth=1.0)
    if background is not None:
        top = np.asarray(background, dtype=np.float64)
        bg_prog["u_top"].value = tuple(top)
        bg_prog["u_bottom"].value = tuple(1.0 - 0.45 * (1.0 - top))
        quad = ctx.buffer(np.array([-1, -1, 3, -1, -1, 3], dtype=np.float32).tobytes())
        ctx.disable(moderngl.DEPTH_TEST)
        ctx.vertex_array(bg_prog, [(quad, "2f", "in_xy")]).render()
        ctx.enable(moderngl.DEPTH_TEST)
    return fbo


def _draw_items(ctx, gpu: _Uploaded, view: View) -> int:
    """The colour pass of the meshes, then the cards; returns its instanced draw calls."""
    import moderngl  # noqa: PLC0415

    draw_calls = 0
    for vao, _, n, colour in gpu.meshes:
        gpu.mesh_prog["u_colour"].value = tuple(float(c) for c in colour)
        vao.render(instances=n)
        draw_calls += 1
    if gpu.cards:
        gpu.card_prog["u_viewproj"].write(_gl_mat(view.viewproj))
        ctx.enable(moderngl.CULL_FACE)  # a box card shows the faces turned towards the eye
        for vao, _, n, tex in gpu.cards:
            tex.use(location=1)
            gpu.card_prog["u_image"].value = 1
            vao.render(instances=n)
            draw_calls += 1
        ctx.disable(moderngl.CULL_FACE)
    return draw_calls


def _draw_ground(ctx, ground_prog, centre: np.ndarray, radius: float, ground_y: float) -> None:
    """A ground plane under the scene that fades out with the distance from its centre."""
    import moderngl  # noqa: PLC0415

    h = 8.0 * radius
    cx, cz = centre[0], centre[2]
    plane = np.array(
        [
            [cx - h, ground_y, cz - h],
            [cx + h, ground_y, cz - h],
            [cx + h, ground_y, cz + h],
            [cx - h, ground_y, cz - h],
            [cx + h, ground_y, cz + h],
            [cx - h, ground_y, cz + h],
        ],
        np.float32,
    )
    gvao = ctx.vertex_array(ground_prog, [(ctx.buffer(plane.tobytes()), "3f", "in_pos")])
    ground_prog["u_colour"].value = (0.42, 0.40, 0.36)
    ground_prog["u_centre"].value = (float(cx), float(cz))
    ground_prog["u_fade"].value = (1.0 * radius, 3.5 * radius)
    ctx.enable(moderngl.BLEND)
    ctx.blend_func = moderngl.SRC_ALPHA, moderngl.ONE_MINUS_SRC_ALPHA
    # after the meshes: depth test keeps it behind them, it blends over sky; pushed back
    # in depth so that a scene's own ground at its lowest point (a city's paving) wins
    # instead of z-fighting with it far from the camera
    ctx.polygon_offset = 2.0, 4.0
    gvao.render()
    ctx.polygon_offset = 0.0, 0.0
    ctx.disable(moderngl.BLEND)


def _read_pixels(ctx, fbo, size: tuple[int, int], comps: int) -> np.ndarray:
    """The resolved framebuffer as (height, width, comps) uint8, top row first; RGBA with
    straight alpha."""
    width, height = size
    resolved = ctx.framebuffer(color_attachments=[ctx.renderbuffer(size, components=comps)])
    ctx.copy_framebuffer(resolved, fbo)
    data = resolved.read(components=comps, alignment=1)
    pixels = np.frombuffer(data, dtype=np.uint8).reshape(height, width, comps)[::-1].copy()
    if comps == 4:  # the resolve averaged colour over a zero background: un-premultiply
        a = pixels[..., 3:].astype(np.float32)
        rgb = pixels[..., :3] * np.where(a > 0, 255.0 / np.maximum(a, 1), 0.0)
        pixels[..., :3] = np.clip(np.rint(rgb), 0, 255).astype(np.uint8)
    return np.ascontiguousarray(pixels)
