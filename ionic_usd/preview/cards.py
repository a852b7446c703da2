"""Card textures for ``UsdGeomModelAPI`` draw mode ``cards``, baked by the preview renderer.

For each face of the card box (:data:`ionic_usd.usd.draw_mode.CARD_FACES`) the model is drawn
with an orthographic camera looking along the face's inward normal, framing exactly the face of
the given bound (image right and up as the table says — Hydra's mapping, so the four side
faces of a Y-up model are images turned a quarter turn: their up is the model's +Z), lit by the
same sun the preview uses for its default camera, on a transparent background: an RGBA PNG with
straight alpha per face.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ionic_usd.errors import ParameterError
from ionic_usd.preview.camera import camera_direction, look_at, ortho
from ionic_usd.preview.render import View, create_context, render, write_png

__all__ = ["CardBake", "bake_cards", "card_views"]


@dataclass(frozen=True)
class CardBake:
    """What :func:`bake_cards` wrote: face name → PNG path, face name → (width, height) pixels,
    face name → fraction of pixels the model covers (alpha >= 128)."""

    files: dict[str, Path]
    sizes: dict[str, tuple[int, int]]
    coverage: dict[str, float]


def card_views(lo: np.ndarray, hi: np.ndarray, size: int) -> dict[str, tuple[View, int, int]]:
    """Per face: the orthographic view of the bound ``lo``..``hi`` (each (3,)) and its image
    size (the longer side ``size`` pixels, the other in proportion, at least 16)."""
    from ionic_usd.usd.draw_mode import CARD_FACES  # noqa: PLC0415

    lo, hi = np.asarray(lo, dtype=np.float64), np.asarray(hi, dtype=np.float64)
    c, h = (lo + hi) / 2, np.maximum((hi - lo) / 2, 1e-6)
    sun = camera_direction("auto", lo, hi)  # one sun for every face, the preview's own
    out = {}
    for name, axes in CARD_FACES.items():
        n, r, u = (np.asarray(v, dtype=np.float64) for v in axes)
        hn, hr, hu = abs(n @ h), abs(r @ h), abs(u @ h)
        margin = 0.05 * float(np.linalg.norm(h)) + 0.1
        eye = c + n * (hn + margin)
        viewproj = ortho(hr, hu, 0.5 * margin, 2 * hn + 2 * margin) @ look_at(eye, c, u)
        scale = size / (2 * max(hr, hu))
        w, ht = max(16, round(2 * hr * scale)), max(16, round(2 * hu * scale))
        out[name] = (View(viewproj, c + n * 1e3 * (hn + margin), sun), w, ht)
    return out


def bake_cards(
    usd_path: str | os.PathLike,
    out_dir: str | os.PathLike,
    bound: tuple[np.ndarray, np.ndarray],
    *,
    variants: Mapping[str, str] | None = None,
    size: int = 256,
    samples: int = 8,
) -> CardBake:
    """Render the six card images of a model into ``out_dir`` (``XPos.png`` … ``ZNeg.png``).

    Parameters
    ----------
    usd_path : the model's stage (e.g. a temple's ``Temple.usda``), read by the one reader
    bound : ``(lo (3,), hi (3,))`` — the card box in the stage's Y-up metres, the box the
        viewer draws the cards on (:func:`ionic_usd.usd.draw_mode.card_bound`)
    variants : selections to make first (e.g. the hypotheses of a temple prototype)
    size : pixels of each image's longer side
    """
    from ionic_usd.preview.scene import draw_items  # noqa: PLC0415
    from ionic_usd.usd.reader import read_scene  # noqa: PLC0415

    if isinstance(size, bool) or not isinstance(size, int) or not 16 <= size <= 4096:
        raise ParameterError("card size", size, "an integer from 16 to 4096 pixels")
    lo, hi = (np.asarray(b, dtype=np.float64) for b in bound)
    if lo.shape != (3,) or hi.shape != (3,) or not np.all(np.isfinite([lo, hi])) or np.any(hi < lo):
        raise ParameterError("card bound", bound, "(lo, hi), finite 3-vectors with lo <= hi")
    scene = read_scene(usd_path, variants=variants, require_sets=False)
    items = draw_items(scene)
    box = np.array(
        [[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])]
    )
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    files, sizes, coverage = {}, {}, {}
    ctx = create_context()
    try:
        for name, (view, w, h) in card_views(lo, hi, size).items():
            px, _ = render(
                ctx, items, box, view, w, h, background=None, samples=samples, ground=False
            )
            files[name] = out / f"{name}.png"
            write_png(px, files[name])
            sizes[name] = (w, h)
            coverage[name] = float(np.mean(px[..., 3] >= 128))
    finally:
        ctx.release()
    return CardBake(files, sizes, coverage)
