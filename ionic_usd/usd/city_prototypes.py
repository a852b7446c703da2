"""A city's prototypes measured in their own (small) stages, never in the city.

:func:`temple_variant_sets` and :func:`temple_selection` give a temple build's variant sets and
one lot's selections in them; :func:`model_card_bound` the box a viewer draws a model's cards
on; :func:`prototype_stats` a prototype's bounds and drawn triangles under some selections; and
:func:`instance_bounds` the exact bounds of every placed prototype box, from the instance
arrays. :func:`ionic_usd.usd.city.compose_city` writes the city from them.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np
from pxr import Sdf, Tf, Usd, UsdGeom

from ionic_usd.errors import ParameterError, UsdAuthoringError
from ionic_usd.usd.draw_mode import card_bbox_cache, card_bound
from ionic_usd.usd.instancer import drawn_triangles

__all__ = [
    "instance_bounds",
    "model_card_bound",
    "prim_identifier",
    "prototype_stats",
    "prototype_triangles",
    "temple_card_bound",
    "stage_variant_sets",
    "temple_selection",
    "temple_variant_sets",
]


def temple_variant_sets(temple_root: Path) -> dict[str, tuple[str, ...]]:
    """Variant set → its variants, on the default prim of a temple (composed, payloads unloaded:
    the root layer only sublayers the user's and the generated layer)."""
    stage = Usd.Stage.Open(str(temple_root), Usd.Stage.LoadNone)
    if stage is None:
        raise UsdAuthoringError(f"cannot open {temple_root}")
    return stage_variant_sets(stage, temple_root)


def stage_variant_sets(stage: Usd.Stage, where: object = "") -> dict[str, tuple[str, ...]]:
    """:func:`temple_variant_sets` of a stage already open (``where`` names it in errors)."""
    prim = stage.GetDefaultPrim()
    if not prim:
        raise UsdAuthoringError(f"{where or stage.GetRootLayer().identifier} has no default prim")
    vsets = prim.GetVariantSets()
    return {name: tuple(vsets.GetVariantSet(name).GetVariantNames()) for name in vsets.GetNames()}


def temple_selection(
    vsets: Mapping[str, Sequence[str]], selections: Mapping[str, str], lod: str | None = None
) -> dict[str, str]:
    """The variant selections of one temple: hypothesis id → its set where the build has it
    (others are ignored) — ``hyp_<id>`` = the choice for an independent hypothesis; for an
    alternative of a question, its set ``hyp_<question>`` (the one whose values name it) =
    its value if chosen, else ``baseline`` unless another alternative of it is chosen —
    plus ``lod`` where the build has a lod set."""
    sel: dict[str, str] = {}
    for h, v in selections.items():
        ident = prim_identifier(h)
        if f"hyp_{ident}" in vsets:
            sel[f"hyp_{ident}"] = v
            continue
        owner = next((n for n, vs in vsets.items() if n.startswith("hyp_") and ident in vs), None)
        if owner is None:
            continue
        if v == "alternative":
            if sel.get(owner, "baseline") not in ("baseline", ident):
                raise ParameterError(
                    "hypotheses",
                    dict(selections),
                    f"one alternative of {owner}: {sel[owner]} and {ident} exclude each other",
                )
            sel[owner] = ident
        else:
            sel.setdefault(owner, "baseline")
    if lod is not None and "lod" in vsets:
        sel["lod"] = lod
    return sel


def model_card_bound(
    root_layer: Path, selections: Mapping[str, str]
) -> tuple[np.ndarray, np.ndarray]:
    """The card box of the default prim of ``root_layer`` with ``selections`` (its own frame,
    metres): the box a viewer draws its cards on (:func:`ionic_usd.usd.draw_mode.card_bound`)."""
    stage = Usd.Stage.Open(str(root_layer))
    if stage is None:
        raise UsdAuthoringError(f"cannot open {root_layer}")
    prim = stage.GetDefaultPrim()
    with Usd.EditContext(stage, stage.GetSessionLayer()):
        for name, value in selections.items():
            prim.GetVariantSet(name).SetVariantSelection(value)
    bound = card_bound(prim, card_bbox_cache())
    if bound is None:
        raise UsdAuthoringError(f"{root_layer}: the model has no bound to put cards on")
    return bound


def temple_card_bound(
    temple_root: Path, selections: Mapping[str, str]
) -> tuple[np.ndarray, np.ndarray]:
    """The card box of a temple with ``selections`` (:func:`model_card_bound`)."""
    return model_card_bound(temple_root, selections)


PURPOSES = ("default", "render", "proxy", "guide")  # UsdGeom's ordered purpose tokens


def prototype_stats(
    stage: Usd.Stage, root: str, selections: Mapping[str, str]
) -> tuple[np.ndarray, np.ndarray, int]:
    """Bounds (lo (3,), hi (3,)) and drawn triangles of ``root`` with ``selections`` made in
    the stage's session layer (default + render purposes, visible prims only); earlier
    selections there are cleared first, so "as authored" means the file's own."""
    lo, hi, tris = prototype_purpose_stats(stage, root, selections)
    both = [k for k in (0, 1) if np.all(lo[k] <= hi[k])]
    if not both:
        return np.zeros(3), np.zeros(3), tris
    return lo[both].min(axis=0), hi[both].max(axis=0), tris


def prototype_triangles(stage: Usd.Stage, root: str, selections: Mapping[str, str]) -> int:
    """:func:`prototype_stats`' drawn triangles alone (no bounds: a fourth of the work)."""
    return drawn_triangles(_selected(stage, root, selections))


def _selected(stage: Usd.Stage, root: str, selections: Mapping[str, str]) -> Usd.Prim:
    """``root`` with ``selections`` made in the stage's (cleared) session layer.

    The clearing and every selection are one change (Sdf edits in one ``ChangeBlock``), so
    the stage recomposes once; a selection at a time recomposed the temple (and loaded its
    columns' payloads) once per set: 5.5x slower on a city's temples."""
    layer = stage.GetSessionLayer()
    with Sdf.ChangeBlock():
        layer.Clear()
        if selections:
            spec = Sdf.CreatePrimInLayer(layer, root)
            for name, value in selections.items():
                spec.variantSelections[name] = value
    return stage.GetPrimAtPath(root)


def prototype_purpose_stats(
    stage: Usd.Stage, root: str, selections: Mapping[str, str]
) -> tuple[np.ndarray, np.ndarray, int]:
    """:func:`prototype_stats` per purpose (:data:`PURPOSES`): lo, hi (4, 3), an empty
    purpose as lo = +inf, hi = -inf; and the drawn triangles."""
    prim = _selected(stage, root, selections)
    lo, hi = np.full((4, 3), np.inf), np.full((4, 3), -np.inf)
    for k, purpose in enumerate(PURPOSES):
        cache = UsdGeom.BBoxCache(Usd.TimeCode.Default(), [purpose])
        rng = cache.ComputeWorldBound(prim).ComputeAlignedRange()
        if not rng.IsEmpty():
            lo[k], hi[k] = rng.GetMin(), rng.GetMax()
    return lo, hi, drawn_triangles(prim)


def purpose_bounds(
    lo: np.ndarray,
    hi: np.ndarray,
    index: np.ndarray,
    xz: np.ndarray,
    yaw: np.ndarray,
    scale: np.ndarray | None,
) -> tuple[np.ndarray, np.ndarray]:
    """:func:`instance_bounds` per purpose from per-prototype (p, 4, 3) bounds; an instance
    whose prototype is empty for a purpose does not count there. Returns lo, hi (4, 3)."""
    out_lo, out_hi = np.full((4, 3), np.inf), np.full((4, 3), -np.inf)
    for k in range(4):
        ok = np.all(lo[:, k] <= hi[:, k], axis=1)
        use = ok[index] if len(index) else np.zeros(0, dtype=bool)
        if not use.any():
            continue
        sc = None if scale is None else np.asarray(scale)[use]
        out_lo[k], out_hi[k] = instance_bounds(
            np.where(ok[:, None], lo[:, k], 0.0),
            np.where(ok[:, None], hi[:, k], 0.0),
            index[use],
            xz[use],
            np.asarray(yaw)[use],
            sc,
        )
    return out_lo, out_hi


def prim_identifier(name: str) -> str:
    """``name`` made a valid prim name (``Tf.MakeValidIdentifier``)."""
    return Tf.MakeValidIdentifier(str(name))


def instance_bounds(
    lo: np.ndarray,
    hi: np.ndarray,
    index: np.ndarray,
    xz: np.ndarray,
    yaw: np.ndarray,
    scale: np.ndarray | None,
) -> tuple[np.ndarray, np.ndarray]:
    """Axis-aligned bounds of every placed prototype box (boxes (p, 3) lo/hi), exact for
    rotations about Y: the rotated box's half-widths are |cos|·hx + |sin|·hz and the like."""
    if len(index) == 0:
        return np.zeros(3), np.zeros(3)
    # only instances near the extremes of the positions can bound the whole: with r the
    # largest horizontal reach of any placed box from its pivot, an instance more than 2r
    # inside the positions' extremes cannot hold an extreme (its box starts beyond one that
    # does); so the exact computation runs on a thin rim (1M columns: a few thousand)
    smax = 1.0 if scale is None else float(np.max(scale))
    reach = (
        np.hypot(
            np.maximum(np.abs(lo[:, 0]), np.abs(hi[:, 0])),
            np.maximum(np.abs(lo[:, 2]), np.abs(hi[:, 2])),
        ).max()
        * smax
    )
    x, z = xz[:, 0], xz[:, 1]
    rim = (
        (x <= x.min() + 2 * reach)
        | (x >= x.max() - 2 * reach)
        | (z <= z.min() + 2 * reach)
        | (z >= z.max() - 2 * reach)
    )
    # heights do not depend on position: every instance counts (scale = 1 or per instance)
    if scale is None:
        used = np.bincount(index, minlength=len(lo)) > 0
        y_lo, y_hi = lo[used, 1].min(), hi[used, 1].max()
    else:
        sc = np.asarray(scale, dtype=float)
        y_lo = min((lo[index, 1] * sc).min(), (hi[index, 1] * sc).min())
        y_hi = max((lo[index, 1] * sc).max(), (hi[index, 1] * sc).max())
    index, xz, yaw = index[rim], xz[rim], np.asarray(yaw)[rim]
    scale = None if scale is None else np.asarray(scale)[rim]
    s = np.ones(len(index)) if scale is None else np.asarray(scale, dtype=float)
    c = (lo + hi) / 2
    h = (hi - lo) / 2
    ci, hi_ = c[index] * s[:, None], h[index] * s[:, None]
    a = np.radians(np.asarray(yaw, dtype=float))
    cs, sn = np.cos(a), np.sin(a)
    cx = ci[:, 0] * cs + ci[:, 2] * sn + xz[:, 0]
    cz = -ci[:, 0] * sn + ci[:, 2] * cs + xz[:, 1]
    hx = np.abs(cs) * hi_[:, 0] + np.abs(sn) * hi_[:, 2]
    hz = np.abs(sn) * hi_[:, 0] + np.abs(cs) * hi_[:, 2]
    out_lo = np.array([(cx - hx).min(), y_lo, (cz - hz).min()])
    out_hi = np.array([(cx + hx).max(), y_hi, (cz + hz).max()])
    return out_lo, out_hi
