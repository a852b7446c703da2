"""The city's prototypes and what it draws: which unique temple and street column prototypes
the instances of :func:`ionic_usd.usd.city.compose_city` use, their bounds and triangles (read
from each prototype's own small stage, not from the city), and the city's drawn triangles per
LOD setting."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from pxr import Usd

from ionic_usd.errors import ParameterError, UsdAuthoringError
from ionic_usd.lod import LOD_NAMES
from ionic_usd.usd.city_prototypes import (
    prototype_purpose_stats,
    prototype_triangles,
    stage_variant_sets,
    temple_selection,
)

if TYPE_CHECKING:
    from ionic_usd.blueprint.city import ColumnInstances, TempleInstances

__all__ = [
    "CARD_TRIANGLES",
    "COLUMN_CARD_SELECTION",
    "ColumnPrototypes",
    "TemplePrototypes",
    "city_triangles",
    "column_prototypes",
    "default_render",
    "temple_prototypes",
]

#: triangles of a box of cards as a renderer draws it: six quads
CARD_TRIANGLES = 12
#: the variant selections of the street columns' card prototype (besides ``finish``): what a
#: consumer that ignores draw modes draws for a far column, and what its cards are baked from
COLUMN_CARD_SELECTION = {"lod": "low", "form": "full"}
#: the triangle counts a city reports: as its instances select, and at each LOD throughout
_SETTINGS = ("as authored", *LOD_NAMES)


@dataclass(frozen=True)
class TemplePrototypes:
    """The unique temple prototypes (build, sorted selections, drawn as cards) and, per
    prototype, the default/render bounds ``lo``/``hi`` (k, 3), the bounds per purpose
    ``lo4``/``hi4`` (k, 4, 3) and the triangles per LOD setting ``tri``; ``of`` (n,) is each
    temple's prototype."""

    keys: list[tuple[int, tuple[tuple[str, str], ...], bool]]
    of: np.ndarray
    lo: np.ndarray
    hi: np.ndarray
    lo4: np.ndarray
    hi4: np.ndarray
    tri: dict[str, np.ndarray]


@dataclass(frozen=True)
class ColumnPrototypes:
    """The street column's prototypes: the asset at each LOD index ``lods`` used by a near
    column, then (index ``len(lods)``) the card prototype if ``card`` (m,) has any far column;
    ``index`` (m,) is each column's prototype, ``lo``/``hi`` each prototype's default/render
    bounds, ``tri`` the asset's triangles per LOD name (empty without columns)."""

    card: np.ndarray
    lods: list[int]
    index: np.ndarray
    lo: np.ndarray
    hi: np.ndarray
    tri: dict[str, int]

    @property
    def count(self) -> int:
        """The number of prototypes the street columns' instancer holds."""
        return len(self.lods) + int(self.card.any())


def default_render(lo4: np.ndarray, hi4: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The union of the default and render purposes' bounds (zeros when both are empty)."""
    ok = [k for k in (0, 1) if np.all(lo4[k] <= hi4[k])]
    if not ok:
        return np.zeros(3), np.zeros(3)
    return lo4[ok].min(axis=0), hi4[ok].max(axis=0)


def _temple_keys(
    temples: TempleInstances,
    card_dirs: Mapping[tuple[int, tuple], str] | None,
    vsets: list[dict],
) -> tuple[dict[tuple, int], np.ndarray]:
    """De-duplicate the temples into prototypes: (build, realised selections, lod, cards)."""
    keys: dict[tuple, int] = {}
    proto_of = np.zeros(len(temples), dtype=np.int32)
    for i in range(len(temples)):
        b = int(temples.build[i])
        card = temples.cards is not None and bool(temples.cards[i])
        lod = LOD_NAMES[int(temples.lod[i])] if temples.lod is not None and not card else None
        sel = temple_selection(vsets[b], temples.selections[i], lod)
        key = (b, tuple(sorted(sel.items())), card)
        if card and (card_dirs is None or key[:2] not in card_dirs):
            raise ParameterError(
                "card images",
                f"temple {temples.names[i]}",
                "a folder of baked cards for every temple drawn as cards (card_dirs)",
            )
        proto_of[i] = keys.setdefault(key, len(keys))
    return keys, proto_of


def temple_prototypes(
    folder: Path,
    temples: TempleInstances,
    card_dirs: Mapping[tuple[int, tuple], str] | None,
) -> TemplePrototypes:
    """The temples' unique prototypes with their bounds and triangles, from each build's stage
    (opened once; a selection's triangles are counted once: the as-authored selection of a
    near temple holds its lod)."""
    stages = [_open_temple(folder / f / "Temple.usda") for f in temples.folders]
    vsets = [stage_variant_sets(st, f) for st, f in zip(stages, temples.folders, strict=True)]
    keys, proto_of = _temple_keys(temples, card_dirs, vsets)
    authored_lod = [
        {"lod": st.GetPrimAtPath("/Temple").GetVariantSet("lod").GetVariantSelection()}
        if "lod" in vs
        else {}
        for st, vs in zip(stages, vsets, strict=True)
    ]
    protos = list(keys)
    tlo, thi = np.zeros((len(protos), 3)), np.zeros((len(protos), 3))
    tlo4, thi4 = np.zeros((len(protos), 4, 3)), np.zeros((len(protos), 4, 3))
    ttri = {s: np.zeros(len(protos), dtype=np.int64) for s in _SETTINGS}
    counted: dict[tuple, int] = {}  # (build, sorted selections) -> triangles
    for k, (b, sel, card) in enumerate(protos):
        tlo4[k], thi4[k], ttri["as authored"][k] = prototype_purpose_stats(
            stages[b], "/Temple", dict(sel)
        )
        # as authored is the authored lod: the lod loop below need not compose it again
        own = {**dict(sel), **authored_lod[b]}
        counted[(b, tuple(sorted(own.items())))] = int(ttri["as authored"][k])
        lo, hi = default_render(tlo4[k], thi4[k])
        if card:  # a box of cards stands in for the temple
            ttri["as authored"][k] = CARD_TRIANGLES
        tlo[k], thi[k] = lo, hi
        for lod in LOD_NAMES:
            # before the temple has a lod set its columns draw as authored
            at = {**dict(sel), "lod": lod} if "lod" in vsets[b] else dict(sel)
            key = (b, tuple(sorted(at.items())))
            if key not in counted:
                counted[key] = prototype_triangles(stages[b], "/Temple", at)
            ttri[lod][k] = counted[key]
    return TemplePrototypes(protos, proto_of, tlo, thi, tlo4, thi4, ttri)


def _open_temple(root: Path) -> Usd.Stage:
    """A temple build's stage, payloads loaded (its triangles are counted)."""
    stage = Usd.Stage.Open(str(root))
    if stage is None:
        raise UsdAuthoringError(f"cannot open {root}")
    return stage


def _column_index(
    columns: ColumnInstances, column_card_dir: str | None
) -> tuple[np.ndarray, list[int], np.ndarray]:
    """Which street columns draw as cards, the LODs the near ones use, each one's prototype."""
    ccard = (
        np.zeros(len(columns), dtype=bool)
        if columns.cards is None
        else np.asarray(columns.cards, dtype=bool)
    )
    if ccard.shape != (len(columns),):
        raise ParameterError("column cards", ccard.shape, f"({len(columns)},) bools")
    if ccard.any() and not column_card_dir:
        raise ParameterError(
            "column card images",
            "none",
            "a folder of baked cards for the far street columns (column_card_dir)",
        )
    near_lod = (
        np.asarray(columns.lod)[~ccard]
        if columns.lod is not None
        else np.full(int((~ccard).sum()), 2)
    )
    col_lods = sorted(set(np.unique(near_lod).tolist()))
    cidx = np.full(len(columns), len(col_lods), dtype=np.int32)
    cidx[~ccard] = np.searchsorted(col_lods, near_lod).astype(np.int32)
    return ccard, col_lods, cidx


def column_prototypes(
    folder: Path, columns: ColumnInstances, finish: str, column_card_dir: str | None
) -> ColumnPrototypes:
    """The street column's prototypes (one per LOD used, then the cards) and their stats."""
    ccard, col_lods, cidx = _column_index(columns, column_card_dir)
    card_li = LOD_NAMES.index(COLUMN_CARD_SELECTION["lod"])
    box_lods = col_lods + ([card_li] if ccard.any() else [])
    clo, chi = np.zeros((len(box_lods), 3)), np.zeros((len(box_lods), 3))
    col_tri = {}
    if len(columns):
        cstage = Usd.Stage.Open(str(folder / columns.asset))
        if cstage is None:
            raise UsdAuthoringError(f"cannot open the column asset {folder / columns.asset}")
        root = str(cstage.GetDefaultPrim().GetPath())
        for k, li in enumerate(box_lods):
            lo4, hi4, _ = prototype_purpose_stats(
                cstage, root, {"lod": LOD_NAMES[li], "form": "full", "finish": finish}
            )
            clo[k], chi[k] = default_render(lo4, hi4)
        for lod in LOD_NAMES:
            col_tri[lod] = prototype_triangles(
                cstage, root, {"lod": lod, "form": "full", "finish": finish}
            )
    return ColumnPrototypes(ccard, col_lods, cidx, clo, chi, col_tri)


def _column_triangles(columns: ColumnInstances, cp: ColumnPrototypes, setting: str) -> int:
    """The street columns' triangles at one LOD setting (cards count as a box)."""
    if not len(columns):
        return 0
    if setting != "as authored":
        return cp.tri[setting] * len(columns)
    ccounts = np.bincount(cp.index[~cp.card], minlength=len(cp.lods))
    col = int(sum(cp.tri[LOD_NAMES[li]] * int(c) for li, c in zip(cp.lods, ccounts, strict=True)))
    return col + CARD_TRIANGLES * int(cp.card.sum())


def _cards_replaced(cards: np.ndarray, lod: np.ndarray | None, tp: TemplePrototypes) -> int:
    """What drawing each card temple at its LOD by distance adds: its triangles, less a box's."""
    far = np.flatnonzero(cards)
    lods = np.asarray(lod)[far] if lod is not None else np.zeros(len(far), np.int8)
    instead = sum(
        int(tp.tri[LOD_NAMES[int(li)]][tp.of[i]]) for i, li in zip(far, lods, strict=True)
    )
    return instead - CARD_TRIANGLES * len(far)


def _column_cards_replaced(columns: ColumnInstances, cp: ColumnPrototypes) -> int:
    """What drawing each card column at its LOD by distance adds: its triangles, less a box's."""
    instead = 0
    if cp.card.any():
        clods = (
            np.asarray(columns.lod)[cp.card]
            if columns.lod is not None
            else np.full(int(cp.card.sum()), 2)
        )
        per_lod = np.bincount(clods.astype(np.int64), minlength=len(LOD_NAMES))
        instead += int(
            sum(cp.tri[name] * int(c) for name, c in zip(LOD_NAMES, per_lod, strict=True))
        )
    return instead - CARD_TRIANGLES * int(cp.card.sum())


def city_triangles(
    temples: TempleInstances,
    columns: ColumnInstances,
    tp: TemplePrototypes,
    cp: ColumnPrototypes,
    extra: int,
) -> dict[str, int]:
    """The city's drawn triangles per LOD setting (and without cards, when any is drawn)."""
    counts = np.bincount(tp.of, minlength=len(tp.keys))
    triangles = {
        s: int(np.dot(counts, tp.tri[s])) + _column_triangles(columns, cp, s) + extra
        for s in _SETTINGS
    }
    far_t = temples.cards is not None and bool(np.any(temples.cards))
    if far_t or cp.card.any():
        # the same city with each card temple and column at its LOD by distance instead
        triangles["without cards"] = triangles["as authored"] + _column_cards_replaced(columns, cp)
    if far_t and temples.cards is not None:
        triangles["without cards"] += _cards_replaced(temples.cards, temples.lod, tp)
    return triangles
