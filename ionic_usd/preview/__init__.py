"""Headless thumbnails of USD scenes: OpenGL 3.3 on a standalone (EGL) context via moderngl.

A client of USD, not part of the kernel, and no USD code of its own: the scene comes from the
one scene reader (:func:`ionic_usd.usd.reader.read_scene`, with card draw modes honoured, as a
viewer does), so preview, export and sections read the same meshes. Layout:

- :mod:`.scene` — the reader's scene as draw lists (vertex arrays, colours, placements);
- :mod:`.camera` — projections, view directions, framing;
- :mod:`.render` — the moderngl passes (shadow map, sky, lit meshes, card faces, ground);
- :mod:`.shaders` — the GLSL programs;
- :mod:`.cards` — baking card textures (orthographic views with alpha) for draw mode cards.

``moderngl`` is the optional ``preview`` extra; it is imported only when a picture is rendered,
so :func:`render_preview` raises :class:`PreviewUnavailableError` (naming what to install) on a
machine without it or without an EGL driver.
"""

from __future__ import annotations

import math
import os
import time
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ionic_usd.errors import GeometryError, ParameterError
from ionic_usd.preview.cards import CardBake, bake_cards
from ionic_usd.preview.render import (
    PreviewUnavailableError,
    View,
    create_context,
    render,
    write_png,
)

__all__ = [
    "CAMERAS",
    "CardBake",
    "PreviewStats",
    "PreviewUnavailableError",
    "bake_cards",
    "create_context",
    "render_preview",
]

CAMERAS = ("auto", "front", "three-quarter")


@dataclass(frozen=True)
class PreviewStats:
    """What one :func:`render_preview` call drew and how long it took.

    ``meshes`` counts distinct meshes uploaded to the GPU (a mesh once however many placements
    use it: instances, point-instancer entries or equal prims); ``prototypes`` the instancing
    prototypes drawn (native and point instancer); ``instances`` the mesh copies drawn through
    instancing; ``draws`` the instanced draw calls of the colour pass; ``triangles`` every
    triangle drawn, copies included (a box of cards is 12); ``cards`` the card faces drawn.
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
    cards: int = 0

    def __post_init__(self) -> None:
        for name in ("meshes", "prototypes", "instances", "draws", "triangles", "cards"):
            if getattr(self, name) < 0:
                raise ParameterError(name, getattr(self, name), "a count >= 0")


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


def perspective_view(
    corners: np.ndarray,
    camera: str,
    aspect: float,
    *,
    eye: tuple[float, float, float] | None = None,
    target: tuple[float, float, float] | None = None,
) -> View:
    """The named camera framing ``corners`` (m, 3) with a 40° vertical field of view, or the
    camera at ``eye`` looking at ``target`` (near plane 0.2 m, far beyond every corner)."""
    from ionic_usd.preview.camera import FOV_DEG, camera_direction, frame, look_at, perspective

    if (eye is None) != (target is None):
        raise ParameterError("eye", eye, "given with target (both or neither)")
    if eye is not None and target is not None:
        e, t = np.asarray(eye, dtype=float), np.asarray(target, dtype=float)
        if not (np.isfinite(e).all() and np.isfinite(t).all() and np.linalg.norm(t - e) > 0):
            raise ParameterError("target", target, "a finite point other than the eye")
        far = float(np.max(np.linalg.norm(corners - e, axis=1))) + 1.0
        up = np.array([0.0, 1.0, 0.0])
        vp = perspective(math.radians(FOV_DEG), aspect, 0.2, far) @ look_at(e, t, up)
        return View(vp, e, (e - t) / np.linalg.norm(e - t))
    lo, hi = corners.min(axis=0), corners.max(axis=0)
    direction = camera_direction(camera, lo, hi)
    at, aim, dist, radius = frame(corners, direction, aspect)
    radius = max(radius, 1e-6)
    near = max(dist - 1.5 * radius, dist * 1e-3)
    far = dist + 12.0 * radius
    viewproj = perspective(math.radians(FOV_DEG), aspect, near, far) @ look_at(
        at, aim, np.array([0.0, 1.0, 0.0])
    )
    return View(viewproj, at, direction)


def _load(usd_path, variants: Mapping[str, str] | None, lod: str | None):
    """(the scene read with these selections and its cards, what to draw, the world corners
    that frame it); refuses a scene with nothing visible to draw."""
    from ionic_usd.preview.scene import draw_items, world_corners
    from ionic_usd.usd.reader import read_scene

    try:
        scene = read_scene(usd_path, variants=variants, lod=lod, draw_modes=True)
    except GeometryError as exc:
        if "has no visible mesh" in str(exc):
            raise GeometryError(f"{usd_path}: no visible, active mesh to draw") from None
        raise
    items = draw_items(scene)
    return scene, items, world_corners(items)


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
    variants: Mapping[str, str] | None = None,
    eye: tuple[float, float, float] | None = None,
    target: tuple[float, float, float] | None = None,
) -> PreviewStats:
    """Render a USD scene to a PNG thumbnail with OpenGL on a headless EGL context.

    Parameters
    ----------
    usd_path : the stage to open (every payload is loaded)
    out_png : the picture to write (atomically); refused if it exists unless ``force``
    width, height : picture size in pixels
    camera : ``auto`` (three-quarter view, steeper for wide flat scenes), ``front`` (from +Z)
        or ``three-quarter``; all frame the drawn geometry's world bounds with a 40° vertical fov
    lod : select this variant on every prim that has a ``lod`` variant set (session layer;
        instances are made editable where needed, as ``ionic-usd export --lod`` does)
    background : sRGB colour of the top of the gradient; the horizon is a lighter tint of it
    samples : MSAA samples (clamped to what the driver offers; 0 or 1 turns MSAA off)
    ground : draw a ground plane at the lowest point, with the key light's shadow
    variants : ``{set: value}`` selected on every prim that has the set, as for export
    eye, target : world points (m, Y up) of a camera placed by hand (e.g. at eye level in a
        city) instead of ``camera``'s framing; both or neither

    Models with ``model:applyDrawMode`` and draw mode ``cards`` are drawn as their textured
    cards (see :mod:`ionic_usd.usd.draw_mode`).

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
    scene, items, corners = _load(usd_path, variants, lod)
    t_load = time.perf_counter()
    ctx = create_context()
    try:
        view = perspective_view(corners, camera, width / height, eye=eye, target=target)
        pixels, draws = render(
            ctx,
            items,
            corners,
            view,
            width,
            height,
            background=background,
            samples=samples,
            ground=ground,
        )
    finally:
        ctx.release()
    t_render = time.perf_counter()
    out.parent.mkdir(parents=True, exist_ok=True)
    write_png(pixels, out)
    t1 = time.perf_counter()
    return _stats(scene, items, draws, (width, height), (t0, t_load, t_render, t1))


def _stats(scene, items, draws: int, size: tuple[int, int], times) -> PreviewStats:
    """What was drawn and how long it took (``times``: start, loaded, rendered, written)."""
    t0, t_load, t_render, t1 = times
    return PreviewStats(
        meshes=len(items),
        prototypes=len(scene.prototypes),
        instances=sum(d.instanced for d in items),
        draws=draws,
        triangles=sum(d.triangles * len(d.placements) for d in items),
        width=size[0],
        height=size[1],
        seconds=t1 - t0,
        load_seconds=t_load - t0,
        render_seconds=t_render - t_load,
        cards=sum(len(d.placements) for d in items if d.uv is not None),
    )
