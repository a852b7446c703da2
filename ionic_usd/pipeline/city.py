"""The city build: plan → temple builds (Dask, cached) → instance arrays → USD layers.

:func:`build_city` is what ``ionic-usd city`` runs. Steps, each timed in the summary:

1. the plan (GeoJSON, or the default grid) and per-lot choices — the temple description and
   column parameters (a build), hypothesis selections, LOD by distance from a focus point;
2. fitting each temple to its lot and laying the colonnades (numpy/shapely, no USD);
3. a memory estimate, refused above ``memory_limit`` before anything is written;
4. the unique builds, from the content-addressed prototype cache or built on Dask; with a
   focus, the card images of the temple prototypes beyond ``cards_beyond`` (baked once each by
   the preview renderer, content-addressed under ``Temples/Cards/``);
5. ``City.usda`` + ``Instances.usdc`` (:func:`ionic_usd.usd.city.compose_city`).

Output bytes depend only on the inputs: the same city is written whether the temples were
built locally, on a cluster, by any number of workers, or taken from the cache.
"""

from __future__ import annotations

import hashlib
import json
import os
import time
from collections.abc import Callable
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from ionic_usd.blueprint.layers import CITY_INSTANCES_LAYER, CITY_ROOT_LAYER
from ionic_usd.city.layout import (
    Footprint,
    TempleFit,
    distance_from,
    extra_columns,
    fit_temple,
    lod_by_distance,
)
from ionic_usd.city.plan import STOA_BACK, CityPlan, grid_plan, read_geojson
from ionic_usd.errors import BudgetError, OutputExistsError, ParameterError
from ionic_usd.io import atomic_write_bytes
from ionic_usd.pipeline.build import PrototypeCache, build_prototypes
from ionic_usd.pipeline.city_extras import lay_stoas, street_column_spec, write_stoas_and_ground
from ionic_usd.pipeline.city_lots import lot_specs
from ionic_usd.pipeline.spec import TempleSpec, temple_spec

__all__ = [
    "CityOptions",
    "build_city",
    "check_city_output",
    "estimate_memory",
    "footprint_of",
    "write_summary",
]

# measured (tools/bench_city.py, peak RSS of the build process; rounded up): the process with
# pxr/shapely/numpy loaded, each street column (arrays + their Vt copies + temporaries), each
# temple as an instanceable reference or as a PointInstancer entry, each temple build held
# by the client while it is written to the cache
_BASE_BYTES = 300e6
_PER_COLUMN = 200.0
_PER_REFERENCE = 10e3
_PER_POINT = 1e3
_PER_BUILD = 40e6
# the LOD cards are baked from: at card resolution (256 px for a 25 m temple, ~10 cm a pixel)
# low and high columns cover the same pixels (coverage per face equal to 1e-4, measured) and
# the bake takes 3.2 s instead of 7.6 s
_CARD_LOD = "low"
# what the card images depend on besides the temple and its selections: the baker's version
_CARD_BAKE = f"cards-v2-{_CARD_LOD}"  # v2: Hydra's face axes (side faces Z-up)
#: triangles a viewer draws interactively (usdview / Hydra Storm on a desktop GPU: a few
#: hundred million per frame at a usable frame rate); a city drawing more is warned about
VIEWER_TRIANGLES = 500_000_000
# the street columns' finish variant
_COLUMN_FINISH = "stucco"


@dataclass(frozen=True)
class CityOptions:
    """What ``ionic-usd city`` can set (defaults = the CLI's)."""

    plan: str | None = None
    rows: int = 5
    cols: int = 5
    block: float = 60.0
    columns: int | None = None
    column_spacing: float = 3.0
    variety: bool = True
    column_variety: int = 1
    temple: str | None = None  # lots that name no temple, preset or type: None = choose
    seed: int = 0
    focus: tuple[float, float] | None = None
    lod_distances: tuple[float, float] = (150.0, 400.0)
    cards_beyond: float | None = None  # None: the far LOD distance, when a focus is given
    cards: bool = True
    card_size: int = 256
    scale_range: tuple[float, float] = (0.6, 1.4)
    texture_size: int = 1024
    instancer_threshold: int | None = None
    scheduler: str | None = None
    workers: int | None = None
    memory_limit_gb: float = 4.0  # ionic_usd.resources.DEFAULT_MAX_MEMORY_GB
    force: bool = False
    prototype_cache: str | None = None  # default: $IONIC_USD_CACHE/prototypes

    def __post_init__(self) -> None:
        if self.columns is not None and (
            isinstance(self.columns, bool) or not isinstance(self.columns, int) or self.columns < 0
        ):
            raise ParameterError("--columns", self.columns, "an integer >= 0")
        if not (isinstance(self.column_variety, int) and 1 <= self.column_variety <= 16):
            raise ParameterError("--column-variety", self.column_variety, "an integer 1-16")
        near, far = self.lod_distances
        if not (np.isfinite([near, far]).all() and 0 < near <= far):
            raise ParameterError(
                "--lod-distances", self.lod_distances, "NEAR,FAR with 0 < NEAR <= FAR (m)"
            )
        if self.cards_beyond is not None and not (
            np.isfinite(self.cards_beyond) and self.cards_beyond >= 0
        ):
            raise ParameterError("--cards-beyond", self.cards_beyond, "a distance >= 0 (m)")
        cs = self.card_size
        if isinstance(cs, bool) or not isinstance(cs, int) or not 16 <= cs <= 4096:
            raise ParameterError("--card-size", cs, "an integer from 16 to 4096 pixels")
        lo, hi = self.scale_range
        if not (np.isfinite([lo, hi]).all() and 0 < lo <= hi):
            raise ParameterError("--scale-range", self.scale_range, "MIN,MAX with 0 < MIN <= MAX")
        if self.focus is not None and not np.isfinite(self.focus).all():
            raise ParameterError("--focus", self.focus, "finite X,Y (plan metres)")
        if not (np.isfinite(self.memory_limit_gb) and self.memory_limit_gb > 0):
            raise ParameterError("--max-memory", self.memory_limit_gb, "GB > 0")
        ts = self.texture_size
        if isinstance(ts, bool) or not isinstance(ts, int) or not 16 <= ts <= 8192 or ts & (ts - 1):
            raise ParameterError("--texture-size", ts, "a power of two in [16, 8192]")
        if self.scheduler is not None:
            from ionic_usd.city.address import check_scheduler_address

            check_scheduler_address(self.scheduler)
        it = self.instancer_threshold
        if it is not None and (isinstance(it, bool) or not isinstance(it, int) or it < 0):
            raise ParameterError("--instancer-threshold", it, "an integer >= 0")
        if self.temple is not None and (not isinstance(self.temple, str) or not self.temple):
            raise ParameterError("--temple", self.temple, "a description name or TOML path")
        if self.workers is not None and (not isinstance(self.workers, int) or self.workers < 1):
            raise ParameterError("--workers", self.workers, "an integer >= 1")


def _lot_selection(lot, hyps, rng, variety: bool, source: str) -> dict[str, str]:
    """One lot's hypothesis choices: the plan's, the rest drawn (one draw per id, so plan
    choices do not shift the others). At most one alternative per question: the plan naming
    two is refused; of the drawn ones, the smallest draw of a question wins."""
    from ionic_usd.temple.description import exclusive_clash, questions

    known = [h.id for h in hyps]
    ctx = f"{source} lot {lot.id}"
    unknown = sorted(set(lot.hypotheses) - set(known))
    if unknown:
        raise ParameterError(
            "hypotheses",
            unknown,
            f"ids of the temple's hypotheses: {', '.join(known) or 'none'}",
            context=ctx,
        )
    planned = [h for h, v in lot.hypotheses.items() if v == "alternative"]
    clash = exclusive_clash(planned, hyps)
    if clash is not None:
        raise ParameterError("hypotheses", dict(lot.hypotheses), clash, context=ctx)
    draws = {h: rng.random() for h in known}
    sel = {}
    for alts in questions(hyps).values():
        ids = [h.id for h in alts]
        if any(lot.hypotheses.get(h) == "alternative" for h in ids):
            for h in ids:
                sel[h] = "alternative" if lot.hypotheses.get(h) == "alternative" else "baseline"
            continue
        free = [h for h in ids if h not in lot.hypotheses and variety and draws[h] < 0.3]
        win = min(free, key=lambda h: draws[h], default=None)
        for h in ids:
            sel[h] = lot.hypotheses.get(h) or ("alternative" if h == win else "baseline")
    return {h: sel[h] for h in known}


def footprint_of(spec: TempleSpec) -> Footprint:
    """The temple's plan box (its own frame) and height, from its cuboids."""
    lay = spec.layout()
    lo = np.min([c.min for c in lay.all_cuboids()], axis=0)
    hi = np.max([np.asarray(c.max) + [0, max(c.rise, 0), 0] for c in lay.all_cuboids()], axis=0)
    return Footprint(float(lo[0]), float(hi[0]), float(lo[2]), float(hi[2]), float(hi[1]))


def estimate_memory(temples: int, columns: int, builds: int, threshold: int) -> float:
    """Peak bytes the city build is expected to need (linear model, measured constants)."""
    per_temple = _PER_POINT if temples > threshold else _PER_REFERENCE
    return _BASE_BYTES + columns * _PER_COLUMN + temples * per_temple + builds * _PER_BUILD


def check_city_output(out: str | os.PathLike, *, force: bool, what: str = "output") -> Path:
    """Refuse a city folder that cannot be written: an existing file, a folder this process
    cannot write, or (without ``force``) a folder that already holds a city's layers.

    The one check: the command line calls it before any work, :func:`build_city` again once
    it holds the folder's lock (a city finished in between is not overwritten)."""
    from ionic_usd.io import check_output_folder

    p = check_output_folder(out, force=True, what=what)
    for name in (CITY_ROOT_LAYER, CITY_INSTANCES_LAYER):
        if (p / name).exists() and not force:
            raise OutputExistsError(f"{p / name} exists; pass --force to rebuild the city")
    return p


def build_city(
    out: str | os.PathLike, opts: CityOptions, *, progress: Callable[[str], None] | None = None
) -> dict:
    """Build the city into ``out`` (see the module docstring); returns the summary (JSON).

    A fresh city is built in a staging folder beside ``out`` and renamed to ``out`` when
    complete, so a failed or killed build leaves no partial city; an existing city's files are
    replaced one by one, atomically. A second build into the same folder meanwhile is refused
    (:func:`ionic_usd.outputs.folder_lock`)."""
    from ionic_usd.outputs import folder_lock, staged_new_folder

    out = Path(out)
    if opts.scheduler is not None:  # before any work, even when nothing needs building
        from ionic_usd.city.address import resolve_scheduler_host

        resolve_scheduler_host(opts.scheduler)
    # one writer at a time; a fresh city is built in a staging sibling and renamed in whole
    from ionic_usd.io import removed_if_failed

    with folder_lock(out):
        check_city_output(out, force=opts.force)
        with staged_new_folder(out) as where, removed_if_failed(where / "Temples"):
            summary = _build_city(where, opts, progress)
    summary["city"] = str(out / Path(summary["city"]).name)
    return summary


def _build_city(out: Path, opts: CityOptions, progress: Callable[[str], None] | None) -> dict:
    from ionic_usd.blueprint.layers import ASSET_NAME
    from ionic_usd.usd.city import (
        DEFAULT_INSTANCER_THRESHOLD,
        ColumnInstances,
        TempleInstances,
        compose_city,
    )

    t0 = time.perf_counter()
    timings: dict[str, float] = {}
    out = Path(out)
    threshold = (
        DEFAULT_INSTANCER_THRESHOLD
        if opts.instancer_threshold is None
        else opts.instancer_threshold
    )
    plan: CityPlan = (
        read_geojson(opts.plan)
        if opts.plan
        else grid_plan(opts.rows, opts.cols, opts.block, spacing=opts.column_spacing)
    )
    notes: list[str] = []
    if opts.plan:
        from ionic_usd.city.layout import check_lots_apart

        check_lots_apart(plan.lots, plan.source)
        for p in plan.porticoes:
            if p.closed:  # resolved as documented, and said
                notes.append(
                    f"note: porticus {p.id} is a Polygon: its columns stand along its outline "
                    "(a colonnaded square); give a LineString for a colonnade along a street"
                )
    rng = np.random.default_rng(opts.seed)

    # -- 1. builds and per-lot choices -------------------------------------------------------
    centre = np.mean([lot.outline.mean(axis=0) for lot in plan.lots], axis=0) if plan.lots else None
    chosen = lot_specs(plan, opts, centre)
    specs, build = chosen.specs, chosen.build
    hyps_of = {s.key: s.layout().hypotheses for s in specs}
    selections = []
    for i, lot in enumerate(plan.lots):
        hyps = hyps_of[specs[build[i]].key]
        selections.append(_lot_selection(lot, hyps, rng, opts.variety, plan.source))

    # -- 2. fitting and colonnades ----------------------------------------------------------
    t1 = time.perf_counter()
    fps = [footprint_of(s) for s in specs]
    fits: list[TempleFit] = []
    # a grid's lots differ by a translation only: fit one, move the others
    same_shape: dict[tuple, tuple[TempleFit, np.ndarray]] = {}
    for i, lot in enumerate(plan.lots):
        key = None
        if lot.orientation is not None:
            key = (
                int(build[i]),
                lot.orientation,
                chosen.scale_ranges[i],
                (lot.outline - lot.outline[0]).round(9).tobytes(),
            )
        if key is not None and key in same_shape:
            f0, o0 = same_shape[key]
            d = lot.outline[0] - o0
            fits.append(replace(f0, x=f0.x + float(d[0]), z=f0.z - float(d[1])))
            continue
        fit = fit_temple(
            lot,
            fps[build[i]],
            scale_range=chosen.scale_ranges[i] or opts.scale_range,
            toward=centre,
        )
        if key is not None:
            same_shape[key] = (fit, lot.outline[0])
        fits.append(fit)
    placed = [f.footprint_plan(fps[build[i]]) for i, f in enumerate(fits)]
    stoas = lay_stoas(plan, opts.column_spacing, placed, STOA_BACK)
    cxz, cyaw, dropped = stoas.column_xz, stoas.column_yaw, stoas.dropped
    if opts.columns is not None:
        stoas = replace(stoas, bay_xz=np.zeros((0, 2)), corner_xz=np.zeros((0, 2)))
        stoas = replace(stoas, bay_yaw=np.zeros(0), bay_length=np.zeros(0))
        stoas = replace(stoas, corner_yaw=np.zeros(0), corner_normal=np.zeros((0, 2)))
        if opts.columns <= len(cxz):
            cxz, cyaw = cxz[: opts.columns], cyaw[: opts.columns]
        else:
            pts = np.concatenate(
                [np.concatenate(placed) * [1, -1] if placed else np.zeros((0, 2)), cxz]
            )
            bounds = (*pts.min(axis=0), *pts.max(axis=0)) if len(pts) else (0.0, 0.0, 0.0, 0.0)
            exz, eyaw = extra_columns(opts.columns - len(cxz), bounds, opts.column_spacing)
            cxz, cyaw = np.concatenate([cxz, exz]), np.concatenate([cyaw, eyaw])
    txz = np.array([[f.x, f.z] for f in fits]).reshape(-1, 2)
    focus = opts.focus
    tlod = lod_by_distance(txz, focus, opts.lod_distances) if focus is not None else None
    clod = lod_by_distance(cxz, focus, opts.lod_distances) if focus is not None else None
    timings["layout"] = time.perf_counter() - t1

    # -- 3. memory estimate ------------------------------------------------------------------
    est = estimate_memory(len(plan.lots), len(cxz), len(specs), threshold)
    if est > opts.memory_limit_gb * 1e9:
        raise BudgetError(
            f"this city needs about {est / 1e9:.1f} GB ({len(plan.lots):,} "
            f"temples, {len(cxz):,} columns), above --max-memory "
            f"{opts.memory_limit_gb:g} GB; raise the limit to build it anyway"
        )
    if not plan.lots and not len(cxz):
        raise ParameterError("city", "empty", "at least one temple or column")

    # -- 4. builds ------------------------------------------------------------------------
    t2 = time.perf_counter()
    needed = specs or [temple_spec("portunus", texture_size=opts.texture_size)]
    cache = PrototypeCache(Path(opts.prototype_cache)) if opts.prototype_cache else PrototypeCache()
    res = build_prototypes(
        needed, cache=cache, scheduler=opts.scheduler, n_workers=opts.workers, progress=progress
    )
    for s in needed:
        cache.install(s, out / "Temples" / s.folder)
    timings["build"] = time.perf_counter() - t2

    # -- 4b. cards for the far field -------------------------------------------------------
    t3 = time.perf_counter()
    tcards, card_dirs, card_note = _far_cards(out, opts, specs, build, selections, txz, progress)
    street = street_column_spec(needed)
    column_asset = f"Temples/{street.folder}/{ASSET_NAME}/{ASSET_NAME}.usda"
    ccards, column_card_dir = _far_column_cards(
        out, opts, street, column_asset, cxz, card_note, progress
    )
    timings["cards"] = time.perf_counter() - t3

    # -- 5. USD ---------------------------------------------------------------------------
    temples = TempleInstances(
        folders=[f"Temples/{s.folder}" for s in specs],
        build=build,
        names=[lot.id for lot in plan.lots],
        xz=txz,
        yaw=np.array([f.yaw_deg for f in fits]),
        scale=np.array([f.scale for f in fits]),
        selections=selections,
        lod=tlod,
        cards=tcards,
    )
    columns = ColumnInstances(column_asset, cxz, cyaw, clod, ccards)
    t4 = time.perf_counter()
    extent_pts = [lot.outline for lot in plan.lots] + list(plan.plazas)
    extent_pts += [np.stack([cxz[:, 0], -cxz[:, 1]], axis=1)]
    extent_pts += [p.line for p in plan.porticoes]
    stoa, ground = write_stoas_and_ground(
        out, plan, stoas, street, opts.column_spacing, np.concatenate(extent_pts)
    )
    timings["stoas and ground"] = time.perf_counter() - t4
    # what the file records depends on the inputs only (not on who built what, or when)
    summary = {
        "plan": Path(plan.source).name if opts.plan else "grid",
        "temples": len(plan.lots),
        "columns": int(len(cxz)),
        "columns_dropped_inside_temples": dropped,
        "stoa_bays": int(len(stoas.bay_xz)),
        "stoa_corners": int(len(stoas.corner_xz)),
        "builds": len(needed),
        "lots": chosen.choices,
    }
    rep = compose_city(
        out,
        temples,
        columns,
        stoa=stoa,
        ground=ground,
        instancer_threshold=threshold,
        summary=summary,
        card_dirs=card_dirs,
        finish=_COLUMN_FINISH,
        column_card_dir=column_card_dir,
        force=True,
    )
    timings.update({f"usd {k}": v for k, v in rep.seconds.items()})
    timings["total"] = time.perf_counter() - t0
    summary.update(
        {
            "city": str(rep.path),
            "prototypes_built": len(res.built),
            "prototypes_reused": len(res.reused),
            "workers": list(res.workers),
            "temples_as": rep.temples_as,
            "temple_prototypes": rep.temple_prototypes,
            "column_prototypes": rep.column_prototypes,
            "unique_prototypes": rep.temple_prototypes + rep.column_prototypes,
            "instances": len(plan.lots) + int(len(cxz)),
            "triangles": rep.triangles,
            "cards": card_note,
            "extent": [list(rep.extent[0]), list(rep.extent[1])],
            "memory_estimate_gb": round(est / 1e9, 3),
            "cluster_workers": res.n_workers,
            "scheduler": opts.scheduler or ("local" if res.n_workers else "none (all cached)"),
            "build_task_seconds": res.task_seconds,
            "timings": {k: round(v, 3) for k, v in timings.items()},
        }
    )
    most = max(rep.triangles.values(), default=0)
    if most > VIEWER_TRIANGLES:
        notes.append(
            f"warning: the city draws up to {most:,} triangles, past what an interactive "
            f"viewer draws (about {VIEWER_TRIANGLES:,}): give --focus for LOD by distance "
            "and cards, or build fewer lots"
        )
    summary["notes"] = notes
    return summary


def _far_cards(
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


def _far_column_cards(
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

    sel = {**COLUMN_CARD_SELECTION, "finish": _COLUMN_FINISH}
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


def write_summary(summary: dict, path: str | os.PathLike) -> None:
    """Write the summary as JSON atomically (:func:`ionic_usd.io.atomic_write_bytes`)."""
    text = json.dumps(summary, indent=2, sort_keys=True) + "\n"
    atomic_write_bytes(path, text.encode("utf-8"))
