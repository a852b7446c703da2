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

import json
import os
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ionic_usd.blueprint.layers import CITY_INSTANCES_LAYER, CITY_ROOT_LAYER
from ionic_usd.city.layout import (
    Footprint,
    TempleFit,
    extra_columns,
    fit_temple,
    lod_by_distance,
)
from ionic_usd.city.plan import STOA_BACK, CityPlan, grid_plan, read_geojson
from ionic_usd.errors import BudgetError, OutputExistsError, ParameterError
from ionic_usd.io import atomic_write_bytes
from ionic_usd.pipeline.build import PrototypeCache, build_prototypes
from ionic_usd.pipeline.city_cards import COLUMN_FINISH, far_cards, far_column_cards
from ionic_usd.pipeline.city_extras import (
    StoaPlan,
    lay_stoas,
    street_column_spec,
    write_stoas_and_ground,
)
from ionic_usd.pipeline.city_lots import LotSpecs, lot_specs
from ionic_usd.pipeline.city_options import CityOptions
from ionic_usd.pipeline.spec import TempleSpec, temple_spec

if TYPE_CHECKING:
    from ionic_usd.pipeline.build import BuildResult
    from ionic_usd.usd.city import CityReport

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
#: triangles a viewer draws interactively (usdview / Hydra Storm on a desktop GPU: a few
#: hundred million per frame at a usable frame rate); a city drawing more is warned about
VIEWER_TRIANGLES = 500_000_000


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


@dataclass(frozen=True)
class _Lots:
    """Step 1: the plan, its builds and each lot's choices (``centre``: the lots' mean)."""

    plan: CityPlan
    chosen: LotSpecs
    selections: list[dict[str, str]]
    centre: Sequence[float] | None


@dataclass(frozen=True)
class _Layout:
    """Step 2: the temples fitted to their lots, the street columns and stoas, LOD by distance."""

    fits: list[TempleFit]
    txz: np.ndarray
    stoas: StoaPlan
    cxz: np.ndarray
    cyaw: np.ndarray
    tlod: np.ndarray | None
    clod: np.ndarray | None


def _build_city(out: Path, opts: CityOptions, progress: Callable[[str], None] | None) -> dict:
    """Run steps 1-5 into ``out`` and return the summary."""
    from ionic_usd.usd.city import DEFAULT_INSTANCER_THRESHOLD

    t0 = time.perf_counter()
    timings: dict[str, float] = {}
    out = Path(out)
    threshold = (
        DEFAULT_INSTANCER_THRESHOLD
        if opts.instancer_threshold is None
        else opts.instancer_threshold
    )
    plan, notes = _read_plan(opts)
    lots = _choose(plan, opts)
    t1 = time.perf_counter()
    lay = _lay_out(lots, opts)
    timings["layout"] = time.perf_counter() - t1
    est = _check_budget(lots, lay, threshold, opts)
    t2 = time.perf_counter()
    needed = lots.chosen.specs or [temple_spec("portunus", texture_size=opts.texture_size)]
    cache = PrototypeCache(Path(opts.prototype_cache)) if opts.prototype_cache else PrototypeCache()
    res = build_prototypes(
        needed, cache=cache, scheduler=opts.scheduler, n_workers=opts.workers, progress=progress
    )
    for s in needed:
        cache.install(s, out / "Temples" / s.folder)
    timings["build"] = time.perf_counter() - t2
    t3 = time.perf_counter()
    street = street_column_spec(needed)
    cards = _cards(out, opts, lots, lay, street, progress)
    timings["cards"] = time.perf_counter() - t3
    t4 = time.perf_counter()
    extent_pts = [lot.outline for lot in plan.lots] + list(plan.plazas)
    extent_pts += [np.stack([lay.cxz[:, 0], -lay.cxz[:, 1]], axis=1)]
    extent_pts += [p.line for p in plan.porticoes]
    stoa, ground = write_stoas_and_ground(
        out, plan, lay.stoas, street, opts.column_spacing, np.concatenate(extent_pts)
    )
    timings["stoas and ground"] = time.perf_counter() - t4
    # what the file records depends on the inputs only (not on who built what, or when)
    summary = {
        "plan": Path(plan.source).name if opts.plan else "grid",
        "temples": len(plan.lots),
        "columns": int(len(lay.cxz)),
        "columns_dropped_inside_temples": lay.stoas.dropped,
        "stoa_bays": int(len(lay.stoas.bay_xz)),
        "stoa_corners": int(len(lay.stoas.corner_xz)),
        "builds": len(needed),
        "lots": lots.chosen.choices,
    }
    rep = _compose(out, lots, lay, cards, stoa, ground, threshold, summary)
    timings.update({f"usd {k}": v for k, v in rep.seconds.items()})
    timings["total"] = time.perf_counter() - t0
    summary.update(_built_summary(rep, res, opts, cards.note, est, len(plan.lots), len(lay.cxz)))
    summary["timings"] = {k: round(v, 3) for k, v in timings.items()}
    most = max(rep.triangles.values(), default=0)
    if most > VIEWER_TRIANGLES:
        notes.append(
            f"warning: the city draws up to {most:,} triangles, past what an interactive "
            f"viewer draws (about {VIEWER_TRIANGLES:,}): give --focus for LOD by distance "
            "and cards, or build fewer lots"
        )
    summary["notes"] = notes
    return summary


def _read_plan(opts: CityOptions) -> tuple[CityPlan, list[str]]:
    """The plan (GeoJSON, lots checked apart, or the grid) and the notes it gives rise to."""
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
    return plan, notes


def _choose(plan: CityPlan, opts: CityOptions) -> _Lots:
    """Step 1: each lot's build and hypothesis selections (seeded by ``opts.seed``)."""
    rng = np.random.default_rng(opts.seed)
    centre = np.mean([lot.outline.mean(axis=0) for lot in plan.lots], axis=0) if plan.lots else None
    chosen = lot_specs(plan, opts, centre)
    specs, build = chosen.specs, chosen.build
    hyps_of = {s.key: s.layout().hypotheses for s in specs}
    selections = []
    for i, lot in enumerate(plan.lots):
        hyps = hyps_of[specs[build[i]].key]
        selections.append(_lot_selection(lot, hyps, rng, opts.variety, plan.source))
    return _Lots(plan, chosen, selections, centre)


def _fit_lots(lots: _Lots, fps: list[Footprint], opts: CityOptions) -> list[TempleFit]:
    """Fit each lot's temple; a grid's lots differ by a translation only: fit one, move the rest."""
    build, fits = lots.chosen.build, []
    same_shape: dict[tuple, tuple[TempleFit, np.ndarray]] = {}
    for i, lot in enumerate(lots.plan.lots):
        key = None
        if lot.orientation is not None:
            key = (
                int(build[i]),
                lot.orientation,
                lots.chosen.scale_ranges[i],
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
            scale_range=lots.chosen.scale_ranges[i] or opts.scale_range,
            toward=lots.centre,
        )
        if key is not None:
            same_shape[key] = (fit, lot.outline[0])
        fits.append(fit)
    return fits


def _street_columns(
    stoas: StoaPlan, placed: list[np.ndarray], opts: CityOptions
) -> tuple[StoaPlan, np.ndarray, np.ndarray]:
    """The street columns (cut to, or extended south to, ``--columns``; then no stoa bays)."""
    cxz, cyaw = stoas.column_xz, stoas.column_yaw
    if opts.columns is None:
        return stoas, cxz, cyaw
    stoas = replace(stoas, bay_xz=np.zeros((0, 2)), corner_xz=np.zeros((0, 2)))
    stoas = replace(stoas, bay_yaw=np.zeros(0), bay_length=np.zeros(0))
    stoas = replace(stoas, corner_yaw=np.zeros(0), corner_normal=np.zeros((0, 2)))
    if opts.columns <= len(cxz):
        return stoas, cxz[: opts.columns], cyaw[: opts.columns]
    pts = np.concatenate([np.concatenate(placed) * [1, -1] if placed else np.zeros((0, 2)), cxz])
    bounds = (*pts.min(axis=0), *pts.max(axis=0)) if len(pts) else (0.0, 0.0, 0.0, 0.0)
    exz, eyaw = extra_columns(opts.columns - len(cxz), bounds, opts.column_spacing)
    return stoas, np.concatenate([cxz, exz]), np.concatenate([cyaw, eyaw])


def _lay_out(lots: _Lots, opts: CityOptions) -> _Layout:
    """Step 2: fit the temples, lay the stoas and street columns, choose LOD by distance."""
    build = lots.chosen.build
    fps = [footprint_of(s) for s in lots.chosen.specs]
    fits = _fit_lots(lots, fps, opts)
    placed = [f.footprint_plan(fps[build[i]]) for i, f in enumerate(fits)]
    stoas = lay_stoas(lots.plan, opts.column_spacing, placed, STOA_BACK)
    stoas, cxz, cyaw = _street_columns(stoas, placed, opts)
    txz = np.array([[f.x, f.z] for f in fits]).reshape(-1, 2)
    focus = opts.focus
    tlod = lod_by_distance(txz, focus, opts.lod_distances) if focus is not None else None
    clod = lod_by_distance(cxz, focus, opts.lod_distances) if focus is not None else None
    return _Layout(fits, txz, stoas, cxz, cyaw, tlod, clod)


def _check_budget(lots: _Lots, lay: _Layout, threshold: int, opts: CityOptions) -> float:
    """Step 3: refuse a city above ``--max-memory`` or an empty one; returns the estimate."""
    n = len(lots.plan.lots)
    est = estimate_memory(n, len(lay.cxz), len(lots.chosen.specs), threshold)
    if est > opts.memory_limit_gb * 1e9:
        raise BudgetError(
            f"this city needs about {est / 1e9:.1f} GB ({n:,} "
            f"temples, {len(lay.cxz):,} columns), above --max-memory "
            f"{opts.memory_limit_gb:g} GB; raise the limit to build it anyway"
        )
    if not lots.plan.lots and not len(lay.cxz):
        raise ParameterError("city", "empty", "at least one temple or column")
    return est


@dataclass(frozen=True)
class _Cards:
    """Step 4b: which temples and street columns draw as cards, their image folders, the note."""

    temples: np.ndarray | None
    dirs: dict
    column_asset: str
    columns: np.ndarray | None
    column_dir: str | None
    note: dict


def _cards(
    out: Path,
    opts: CityOptions,
    lots: _Lots,
    lay: _Layout,
    street: TempleSpec,
    progress: Callable[[str], None] | None,
) -> _Cards:
    """Step 4b: the far temples' and street columns' cards (baked or reused)."""
    from ionic_usd.blueprint.layers import ASSET_NAME

    specs, build = lots.chosen.specs, lots.chosen.build
    tcards, card_dirs, note = far_cards(out, opts, specs, build, lots.selections, lay.txz, progress)
    column_asset = f"Temples/{street.folder}/{ASSET_NAME}/{ASSET_NAME}.usda"
    ccards, column_card_dir = far_column_cards(
        out, opts, street, column_asset, lay.cxz, note, progress
    )
    return _Cards(tcards, card_dirs, column_asset, ccards, column_card_dir, note)


def _compose(
    out: Path,
    lots: _Lots,
    lay: _Layout,
    cards: _Cards,
    stoa: tuple | None,
    ground: tuple | None,
    threshold: int,
    summary: dict,
) -> CityReport:
    """Step 5: write the city's layers from the instance arrays (``compose_city``)."""
    from ionic_usd.blueprint.city import ColumnInstances, TempleInstances
    from ionic_usd.usd.city import compose_city

    temples = TempleInstances(
        folders=[f"Temples/{s.folder}" for s in lots.chosen.specs],
        build=lots.chosen.build,
        names=[lot.id for lot in lots.plan.lots],
        xz=lay.txz,
        yaw=np.array([f.yaw_deg for f in lay.fits]),
        scale=np.array([f.scale for f in lay.fits]),
        selections=lots.selections,
        lod=lay.tlod,
        cards=cards.temples,
    )
    columns = ColumnInstances(cards.column_asset, lay.cxz, lay.cyaw, lay.clod, cards.columns)
    return compose_city(
        out,
        temples,
        columns,
        stoa=stoa,
        ground=ground,
        instancer_threshold=threshold,
        summary=summary,
        card_dirs=cards.dirs,
        finish=COLUMN_FINISH,
        column_card_dir=cards.column_dir,
        force=True,
    )


def _built_summary(
    rep: CityReport,
    res: BuildResult,
    opts: CityOptions,
    card_note: dict,
    est: float,
    n: int,
    m: int,
) -> dict:
    """The summary's record of what was built and written (not part of the city's bytes)."""
    return {
        "city": str(rep.path),
        "prototypes_built": len(res.built),
        "prototypes_reused": len(res.reused),
        "workers": list(res.workers),
        "temples_as": rep.temples_as,
        "temple_prototypes": rep.temple_prototypes,
        "column_prototypes": rep.column_prototypes,
        "unique_prototypes": rep.temple_prototypes + rep.column_prototypes,
        "instances": n + int(m),
        "triangles": rep.triangles,
        "cards": card_note,
        "extent": [list(rep.extent[0]), list(rep.extent[1])],
        "memory_estimate_gb": round(est / 1e9, 3),
        "cluster_workers": res.n_workers,
        "scheduler": opts.scheduler or ("local" if res.n_workers else "none (all cached)"),
        "build_task_seconds": res.task_seconds,
    }


def write_summary(summary: dict, path: str | os.PathLike) -> None:
    """Write the summary as JSON atomically (:func:`ionic_usd.io.atomic_write_bytes`)."""
    text = json.dumps(summary, indent=2, sort_keys=True) + "\n"
    atomic_write_bytes(path, text.encode("utf-8"))
