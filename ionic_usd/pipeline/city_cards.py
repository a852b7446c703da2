"""The city's far field as cards: which temples and street columns beyond ``cards_beyond`` of
the focus draw as a box of six images, and those images, baked once per prototype by the
preview renderer under ``Temples/Cards/`` (content-addressed, so a rebuild reuses them)."""

from __future__ import annotations

import hashlib
import json
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ionic_usd.city.layout import distance_from
from ionic_usd.pipeline.spec import TempleSpec

if TYPE_CHECKING:
    from ionic_usd.pipeline.city_options import CityOptions

__all__ = ["COLUMN_FINISH", "far_cards", "far_column_cards"]

# the LOD cards are baked from: at card resolution (256 px for a 25 m temple, ~10 cm a pixel)
# low and high columns cover the same pixels (coverage per face equal to 1e-4, measured) and
# the bake takes 3.2 s instead of 7.6 s
_CARD_LOD = "low"
_CARD_BAKE = f"cards-v2-{_CARD_LOD}"  # v2: Hydra's face axes (side faces Z-up)
#: the street columns' finish variant
COLUMN_FINISH = "stucco"


def far_cards(
    out: Path,
    opts: CityOptions,
    specs: list[TempleSpec],
    build: np.ndarray,
    selections: list[dict],
    txz: np.ndarray,
    progress: Callable[[str], None] | None,
) -> tuple[np.ndarray | None, dict, dict]:
    """Which temples draw as cards (beyond ``cards_beyond`` of the focus) and their images.

    One set of six images per temple prototype (build + hypothesis selections), baked by the
    preview renderer into ``Temples/Cards/<build folder>-<key>/`` where ``key`` hashes what the
    images depend on, so a rebuild (or another lot of the same prototype) reuses them. Returns
    ``(cards (n,) bool or None, {(build, selections): folder}, summary note)``.
    """
    if opts.focus is None or not opts.cards:
        return None, {}, {"temples": 0, "why": "no --focus" if opts.cards else "--no-cards"}
    beyond = opts.cards_beyond if opts.cards_beyond is not None else opts.lod_distances[1]
    cards = distance_from(txz, opts.focus) > beyond
    note: dict = {
        "beyond_m": beyond,
        "temples": int(cards.sum()),
        "prototypes": 0,
        "baked": 0,
        "reused": 0,
        "size_px": opts.card_size,
    }
    if not cards.any():
        return None, {}, note
    from ionic_usd.preview import PreviewUnavailableError, bake_cards
    from ionic_usd.usd.city_prototypes import (
        temple_card_bound,
        temple_selection,
        temple_variant_sets,
    )
    from ionic_usd.usd.draw_mode import CARD_FACES

    dirs: dict[tuple, str] = {}
    vsets: dict[int, dict] = {}
    for i in np.flatnonzero(cards):
        b = int(build[i])
        root = out / "Temples" / specs[b].folder / "Temple.usda"
        if b not in vsets:
            vsets[b] = temple_variant_sets(root)
        sel = temple_selection(vsets[b], selections[i])
        key = (b, tuple(sorted(sel.items())))
        if key in dirs:
            continue
        digest = hashlib.blake2b(
            json.dumps([specs[b].key, key[1], opts.card_size, _CARD_BAKE]).encode(), digest_size=8
        ).hexdigest()
        rel = f"Temples/Cards/{specs[b].folder}-{digest}"
        if all((out / rel / f"{f}.png").is_file() for f in CARD_FACES):
            note["reused"] += 1
        else:
            try:
                bake_sel = temple_selection(vsets[b], selections[i], _CARD_LOD)
                bake_cards(
                    root,
                    out / rel,
                    temple_card_bound(root, sel),
                    variants=bake_sel,
                    size=opts.card_size,
                )
            except PreviewUnavailableError as exc:
                if opts.cards_beyond is not None:
                    raise  # asked for by name: say why it cannot be done
                if progress:
                    progress(f"far temples drawn in full: cannot bake cards ({exc})")
                return None, {}, {"temples": 0, "why": f"no renderer: {exc}"}
            note["baked"] += 1
            if progress:
                progress(f"baked cards {rel}")
        dirs[key] = rel
    note["prototypes"] = len(dirs)
    return cards, dirs, note


def far_column_cards(
    out: Path,
    opts: CityOptions,
    spec: TempleSpec,
    asset: str,
    cxz: np.ndarray,
    note: dict,
    progress: Callable[[str], None] | None,
) -> tuple[np.ndarray | None, str | None]:
    """Which street columns draw as cards (beyond the temples' card distance from the focus)
    and the folder of the column's six images, baked once by the preview renderer from the
    column asset at :data:`ionic_usd.usd.city.COLUMN_CARD_SELECTION` into
    ``Temples/Cards/<asset>-<key>/`` (content-addressed like the temples'). Records
    ``columns`` (far columns), ``column_baked`` / ``column_reused`` in ``note``. Returns
    ``(cards (m,) bool or None, folder or None)``."""
    if opts.focus is None or not opts.cards or not len(cxz) or note.get("why"):
        return None, None
    beyond = opts.cards_beyond if opts.cards_beyond is not None else opts.lod_distances[1]
    cards = distance_from(cxz, opts.focus) > beyond
    note.update(
        {"beyond_m": beyond, "columns": int(cards.sum()), "column_baked": 0, "column_reused": 0}
    )
    if not cards.any():
        return None, None
    from ionic_usd.preview import PreviewUnavailableError, bake_cards
    from ionic_usd.usd.city import COLUMN_CARD_SELECTION
    from ionic_usd.usd.city_prototypes import model_card_bound
    from ionic_usd.usd.draw_mode import CARD_FACES

    sel = {**COLUMN_CARD_SELECTION, "finish": COLUMN_FINISH}
    digest = hashlib.blake2b(
        json.dumps([spec.key, "column", sorted(sel.items()), opts.card_size, _CARD_BAKE]).encode(),
        digest_size=8,
    ).hexdigest()
    rel = f"Temples/Cards/{Path(asset).stem}-{digest}"
    if all((out / rel / f"{f}.png").is_file() for f in CARD_FACES):
        note["column_reused"] = 1
        return cards, rel
    root = out / asset
    try:
        bake_cards(root, out / rel, model_card_bound(root, sel), variants=sel, size=opts.card_size)
    except PreviewUnavailableError as exc:
        if opts.cards_beyond is not None:
            raise
        if progress:
            progress(f"far columns drawn in full: cannot bake cards ({exc})")
        note["columns"] = 0
        return None, None
    note["column_baked"] = 1
    if progress:
        progress(f"baked cards {rel}")
    return cards, rel
