"""The column asset's coordinator: generate → clip → UV → texture → author.

:func:`build_column_asset` runs the pipeline for one ``IonicColumn`` folder:

1. **generate** every part per variant (:mod:`ionic_usd.column`): bases, shafts per flute
   count, capitals per scroll × capital × volute model;
2. **clip** each part to its ``form`` (engaged: the wall plane; corner: a quadrant), a plane
   clip or a notch between two wall planes, capped (:mod:`ionic_usd.pipeline.forms`);
3. **UV**: every part's own metric charts (analytic: the base and shaft unrolled, the
   capital's parts charted by their generators and kept through the union), packed per part
   and LOD at one texel density per LOD (:mod:`ionic_usd.texture.uv`; xatlas only for a part
   without charts);
4. **texture**: the tileable stone maps, made once per (style, size, seed) and kept in the
   cache folder (:mod:`ionic_usd.texture.stone`);
5. **author** the layers from those values (:func:`ionic_usd.usd.column_asset.author_column_asset`).

The variant vocabulary (sets, variants, ``UV_SPAN``) is the asset's, in
:mod:`ionic_usd.blueprint.column_asset`, the texel densities the levels' (:mod:`ionic_usd.lod`);
this module loads no ``pxr`` until it authors.
"""

from __future__ import annotations

import dataclasses
import math
import os
import shutil
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ionic_usd.blueprint.asset import AssetInstancer, AssetMesh
from ionic_usd.blueprint.column_asset import (
    ASSET_NAME,
    BASE_CHART_BOUNDARY,
    FINISHES,
    FLUTE_VARIANTS,
    UV_SPAN,
    ColumnAssetOptions,
    column_ornament,
    volute_variant_params,
)
from ionic_usd.column.column import (
    build_base_part,
    build_capital_part,
    build_shaft_part,
)
from ionic_usd.errors import OutputExistsError
from ionic_usd.geometry.mesh import Mesh
from ionic_usd.io import up_to_date
from ionic_usd.lod import level, lod_rank
from ionic_usd.pipeline.forms import form_cut, form_cuts, outside_walls
from ionic_usd.pipeline.keys import asset_key
from ionic_usd.pipeline.mesh_cache import cached_meshes, wait_for_writes
from ionic_usd.texture.uv import UVCache, attach_uvs, unwrap_parts

if TYPE_CHECKING:
    from concurrent.futures import Future

__all__ = [
    "AssetReport",
    "asset_key",
    "build_column_asset",
    "column_asset_meshes",
    "column_asset_ornament",
    "copy_stone_textures",
    "form_cut",
    "form_cuts",
]


@dataclass(frozen=True)
class AssetReport:
    """What :func:`build_column_asset` wrote: meshes, triangles of the default selection per
    LOD (form full), xatlas unwraps run, wall seconds and bytes on disk."""

    path: Path
    meshes: int
    triangles_per_lod: dict[str, int]
    uv_unwraps: int
    seconds: float
    bytes_on_disk: int
    current: bool = False  # the folder already held this build's intact output: none written


# -- generate -----------------------------------------------------------------------------
@dataclass(frozen=True)
class _Unit:
    """One independent piece of the asset's generation: the bases and shafts of a LOD, or one
    capital variant of a LOD (with its chart and its form cuts)."""

    lod: str
    kind: str  # "base_shaft" | "capital"
    volute: str = ""
    scroll: str = ""
    capital: str = ""


def _units(opts: ColumnAssetOptions) -> list[_Unit]:
    out = []
    for lod in opts.lods:
        out.append(_Unit(lod, "base_shaft"))
        for vm in opts.volutes:
            for s in opts.scrolls:
                for c in opts.capitals:
                    out.append(_Unit(lod, "capital", vm, s, c))
    return out


def _with_forms(
    opts: ColumnAssetOptions, lod: str, groups: list[tuple[str, str, Mesh, dict[str, str]]]
) -> list[AssetMesh]:
    out = []
    for part, name, mesh, tags in groups:
        for form, m in zip(opts.forms, form_cuts(mesh, opts.forms, part), strict=True):
            if part == "CapitalBody":
                m = _weld_exact(m)
            suffix = "" if form == "full" else f"_{form}"
            t = {"lod": lod, **tags}
            if len(opts.forms) > 1:
                t["form"] = form
            out.append(AssetMesh(part, f"{name}_{lod}{suffix}", m.with_(name=name), t))
    return out


def _unit_meshes(
    opts: ColumnAssetOptions, unit: _Unit, uv_cache: UVCache | None, workers: int | None = None
) -> tuple[list[AssetMesh], tuple[int, int]]:
    """The unit's meshes (every form) and the UV cache's (misses, hits) it added: xatlas runs
    and charts read from the cache."""
    p = opts.params.with_lod(unit.lod)
    base_h = p.base_params().height
    groups: list[tuple[str, str, Mesh, dict[str, str]]] = []
    if unit.kind == "base_shaft":
        for b in opts.bases:
            groups.append(("Base", f"Base_{b}", build_base_part(p, b), {"base": b}))
        for fname in opts.flutes:
            fp = p.with_flutes(FLUTE_VARIANTS[fname])
            groups.append(
                ("Shaft", f"Shaft_{fname}", build_shaft_part(fp, base_h), {"flutes": fname})
            )
        return _with_forms(opts, unit.lod, groups), (0, 0)
    vp = volute_variant_params(p, unit.volute)
    body = build_capital_part(
        vp, base_h + p.shaft.length, scroll=unit.scroll, angle=unit.capital == "angle"
    )
    tag = {"scroll": unit.scroll, "capital": unit.capital}
    name = f"Capital_{unit.scroll}_{unit.capital}"
    if len(opts.volutes) > 1:
        tag["volute"] = unit.volute
        name = f"{name}_{unit.volute}"
    counts = (0, 0)
    if uv_cache is not None and body.st is None:
        # every part carries analytic st, the capital's through its union (parts without
        # it, e.g. from a user's generator, are charted by xatlas once, before the cuts)
        from ionic_usd.texture.uv import metric_charts

        m0, h0 = uv_cache.misses, uv_cache.hits
        (body,) = metric_charts(
            [body], level(unit.lod).asset_texels_per_metre, cache=uv_cache, workers=workers
        )
        counts = (uv_cache.misses - m0, uv_cache.hits - h0)
    return _with_forms(opts, unit.lod, [("CapitalBody", name, body, tag)]), counts


# the worker's copy of (opts, uv_cache), set by the pool's initializer (fork: no pickling)
_WORKER_STATE: dict[str, Any] = {}


def _worker_init(opts: ColumnAssetOptions, uv_cache: UVCache | None, parent: int) -> None:
    from ionic_usd.outputs import die_with_parent

    die_with_parent(parent)
    _WORKER_STATE["args"] = (opts, uv_cache)


def _worker_unit(unit: _Unit) -> tuple[list[AssetMesh], tuple[int, int]]:
    opts, uv_cache = _WORKER_STATE["args"]
    meshes, counts = _unit_meshes(opts, unit, uv_cache, workers=1)
    # the charts' packing at the asset's density, made here in parallel: it travels back with
    # each mesh's derived values and _with_uvs finds it there
    from ionic_usd.texture.atlas import analytic_atlas

    for m in meshes:
        if m.mesh.st is not None and np.all(m.mesh.face_vertex_counts == 3):
            analytic_atlas(m.mesh, texels_per_metre=level(m.tags["lod"]).asset_texels_per_metre)
    return meshes, counts


def _preload() -> None:
    """Import, before the pool forks, the libraries every unit imports on first use (the
    booleans' manifold3d and connected components, shapely's cuts, xatlas, the k-d tree):
    the forked workers share them instead of importing each its own copy (~0.5 s a worker)."""
    import importlib

    for name in (
        "manifold3d",
        "scipy.sparse.csgraph",
        "scipy.spatial",
        "shapely",
        "xatlas",
        "ionic_usd.geometry.boolean",
        "ionic_usd.geometry.clip",
        "ionic_usd.texture.uv",
    ):
        try:
            importlib.import_module(name)
        except ImportError:  # optional here: the unit that needs it reports it
            pass


def _cost(unit: _Unit) -> tuple[int, int]:
    """Scheduling order: capitals before bases, high LOD first (the longest units first)."""
    return (unit.kind != "capital", lod_rank(unit.lod))


def column_asset_meshes(
    opts: ColumnAssetOptions,
    uv_cache: UVCache | None = None,
    *,
    workers: int | None = None,
    side_jobs: Sequence[tuple[Callable[..., object], tuple]] = (),
    pending: list[Future] | None = None,
) -> list[AssetMesh]:
    """Every mesh of the asset with its variant tags and metric charts (geometry only; every
    part is charted by its generator, the form cuts carry the charts; with ``uv_cache`` a
    capital without charts would be unwrapped by xatlas before its cuts).

    The units of work (the bases and shafts of a LOD; each capital variant of a LOD, with its
    chart and cuts) are independent: they run in ``workers`` processes (default: one per
    core; in-process on one core or inside a daemonic process such as a Dask worker), and the
    result does not depend on how many. ``side_jobs`` (picklable ``(function, args)``, their
    results dropped: cache warm-ups such as :func:`warm_stone_textures`) run in the same pool
    after the high LOD's units, so they overlap the geometry instead of following it; without
    a pool they are not run. With a ``pending`` list they are queued after every unit instead
    and this returns as soon as the geometry is done, leaving their futures in ``pending``:
    the pool's workers go on with them while the caller's serial work (caching, UVs, writing
    the layers) runs, and the caller waits for them before it reads what they make.

    Returns
    -------
    one :class:`~ionic_usd.blueprint.asset.AssetMesh` per (part variant, lod, form), named
    ``<Part>_<variant>_<lod>[_<form>]``; capitals are tagged with ``scroll``, ``capital`` and
    (when the asset has more than one model) ``volute``.
    """
    import multiprocessing as mp

    units = _units(opts)
    n = min(workers or os.cpu_count() or 1, len(units))
    results: dict[_Unit, tuple[list[AssetMesh], tuple[int, int]]] = {}
    if n <= 1 or mp.current_process().daemon or "fork" not in mp.get_all_start_methods():
        for u in units:
            results[u] = _unit_meshes(opts, u, uv_cache)
    else:
        from concurrent.futures import ProcessPoolExecutor

        _preload()
        order = sorted(units, key=_cost)
        ctx = mp.get_context("fork")
        first = sum(u.kind == "capital" and u.lod == order[0].lod for u in order)  # longest
        ex = ProcessPoolExecutor(
            max_workers=n,
            mp_context=ctx,
            initializer=_worker_init,
            initargs=(opts, uv_cache, os.getpid()),
        )
        try:
            if pending is None:  # the side jobs fill the gaps between the units
                futures = {u: ex.submit(_worker_unit, u) for u in order[:first]}
                side = [ex.submit(fn, *args) for fn, args in side_jobs]
                futures.update({u: ex.submit(_worker_unit, u) for u in order[first:]})
            else:  # ... or follow them, running on beside the caller's serial work
                futures = {u: ex.submit(_worker_unit, u) for u in order}
                side = [ex.submit(fn, *args) for fn, args in side_jobs]
            for u, f in futures.items():
                results[u] = f.result()
            if pending is None:
                for job in side:
                    job.result()
            else:
                pending.extend(side)
        except BaseException:
            ex.shutdown(wait=True, cancel_futures=True)
            raise
        # the workers exit once the queued side jobs are done; nothing here waits for them
        ex.shutdown(wait=pending is None)
        if uv_cache is not None:  # the workers' cache use, counted where the report reads it
            uv_cache.misses += sum(r[1][0] for r in results.values())
            uv_cache.hits += sum(r[1][1] for r in results.values())
    out: list[AssetMesh] = []
    for lod in opts.lods:  # the order of the serial loop: bases, shafts, then capitals
        for u in units:
            if u.lod == lod:
                out.extend(results[u][0])
    return out


def _weld_exact(mesh: Mesh) -> Mesh:
    """``mesh`` with coincident points merged: the capital's union can leave one vertex twice
    at (nearly) the same place, with a sliver between (closed, but pinched: not a clean
    solid). Points within the solid check's tolerance (1e-7 of the diagonal) are welded,
    and the weld is kept only if it leaves the mesh closed and edge-manifold."""
    from ionic_usd.geometry.check import colocated_points, solid_report
    from ionic_usd.geometry.mesh import weld

    if colocated_points(mesh) == 0:
        return mesh
    tol = 1e-7 * float(np.linalg.norm(np.ptp(mesh.points, axis=0)))
    out = weld(mesh, tol)
    r = solid_report(out, intersections=False)
    return out if r.open_edges == 0 and r.nonmanifold_edges == 0 and r.shells == 1 else mesh


def column_asset_ornament(opts: ColumnAssetOptions) -> tuple[AssetInstancer, ...]:
    """The carved echinus (egg-and-dart) and astragal (bead-and-reel) of the ``high`` LOD,
    one PointInstancer pair per ``form``: the copies a form's wall would swallow (their
    centre behind the wall plane) are dropped, so an engaged column carries no eggs inside
    its wall. Nothing if the asset is not ``carved`` or has no high LOD.

    The instances are :func:`ionic_usd.blueprint.column_asset.column_ornament`'s (the one
    placement rule).
    """
    if not opts.carved or "high" not in opts.lods:
        return ()
    out = []
    for a in column_ornament(opts):
        inst: Any = a.instances  # ionic_usd.column.ornament.Instances
        for form in opts.forms:
            keep = outside_walls(np.asarray(inst.positions), form)
            sub = dataclasses.replace(
                inst,
                proto_indices=inst.proto_indices[keep],
                positions=inst.positions[keep],
                orientations=inst.orientations[keep],
                scales=inst.scales[keep],
            )
            tags = dict(a.tags)
            name = a.name
            if len(opts.forms) > 1:
                tags["form"] = form
                name = a.name if form == "full" else f"{a.name}_{form}"
            out.append(AssetInstancer(a.part, name, sub, tags))
    return tuple(out)


# -- UV -----------------------------------------------------------------------------------
def _with_uvs(meshes: list[AssetMesh], cache: UVCache | None) -> tuple[list[AssetMesh], int]:
    """The meshes with ``st`` packed (one atlas per part, one density per LOD) and the number
    of xatlas unwraps run (0 when every part has its own charts)."""
    from ionic_usd.texture.uv import prefetch

    misses0 = cache.misses if cache is not None else 0

    def boundary(m: AssetMesh) -> float | None:
        return BASE_CHART_BOUNDARY if m.part == "Base" else None

    prefetch(
        [(m.mesh, level(m.tags["lod"]).asset_texels_per_metre, boundary(m)) for m in meshes],
        cache=cache,
    )
    out = []
    for lod in {m.tags["lod"] for m in meshes}:
        these = [m for m in meshes if m.tags["lod"] == lod]
        tpm = level(lod).asset_texels_per_metre
        atlases = unwrap_parts(
            {f"{m.part}/{m.name}": m.mesh for m in these},
            texels_per_metre=tpm,
            cache=cache,
            chart_boundaries={f"{m.part}/{m.name}": boundary(m) for m in these},
        )
        used = min(a.texels_per_metre for a in atlases.values())
        size = max(math.ceil(used * UV_SPAN), max(a.size for a in atlases.values()))
        for m in these:
            a = atlases[f"{m.part}/{m.name}"]
            out.append(dataclasses.replace(m, mesh=attach_uvs(m.mesh, a, size)))
    order = {(m.part, m.name): i for i, m in enumerate(meshes)}
    out.sort(key=lambda m: order[(m.part, m.name)])
    unwraps = (cache.misses - misses0) if cache is not None else len(meshes)
    return out, unwraps


# -- texture ------------------------------------------------------------------------------
def copy_stone_textures(
    folder: Path, style: str, size: int, seed: int, *, make_tx: bool = False
) -> list[Path]:
    """Put a stone style's maps into ``folder``, generating them once per (style, size, seed).

    Generated maps are deterministic, so they are kept in the cache folder (beside the UV
    cache) and copied: a rebuild writes no PNG.
    """
    from ionic_usd.texture.stone import TextureError, write_stone_textures

    names = [
        f"{style}_{r}.{e}"
        for r in ("basecolor", "roughness", "normal")
        for e in (("png", "tx") if make_tx else ("png",))
    ]
    try:
        store = _stone_store(style, size, seed, make_tx)
    except (OSError, TextureError):  # an unwritable or full cache: write into the asset
        write_stone_textures(folder, style, size, seed, make_tx=make_tx)
        return [folder / n for n in names]
    folder.mkdir(parents=True, exist_ok=True)
    out = []
    for n in names:
        shutil.copyfile(store / n, folder / n)
        out.append(folder / n)
    return out


def _stone_store(style: str, size: int, seed: int, make_tx: bool) -> Path:
    """The cache folder holding a stone style's maps, generated there on first use (verified
    on read by its SHA-256 manifest, written atomically, rebuilt when bad). Keyed by the
    options, the package's code and the libraries (OpenImageIO writes the files): an edited
    generator never finds the old maps."""
    from ionic_usd.io import verified_cache
    from ionic_usd.pipeline.keys import build_key
    from ionic_usd.texture.stone import write_stone_textures
    from ionic_usd.texture.uv import default_cache_folder

    code = build_key("stone textures", style, size, seed, make_tx)[:16]
    key = f"{style}-{size}-{seed}-{code}{'-tx' if make_tx else ''}"
    return verified_cache(
        default_cache_folder().parent / "textures" / key,
        lambda tmp: write_stone_textures(tmp, style, size, seed, make_tx=make_tx),
    )


def warm_stone_textures(style: str, size: int, seed: int, make_tx: bool = False) -> None:
    """Generate a stone style's maps into the cache (what :func:`copy_stone_textures` then
    copies), quietly doing nothing when the cache cannot be written: the copy reports it."""
    from ionic_usd.texture.stone import TextureError

    try:
        _stone_store(style, size, seed, make_tx)
    except (OSError, TextureError):
        pass


def _texture_jobs(opts: ColumnAssetOptions) -> list[tuple[Callable[..., object], tuple]]:
    """The asset's generated maps as :func:`column_asset_meshes` side jobs."""
    styles = [s for _, s in FINISHES.values() if not (opts.user_textures and s == "travertine")]
    args = (opts.texture_size, opts.seed, opts.make_tx)
    return [(warm_stone_textures, (s, *args)) for s in dict.fromkeys(styles)]


def _textures_writer(opts: ColumnAssetOptions, pending: Sequence[Future] = ()):
    """``populate(tmp)``: the finishes' maps into ``tmp/Payload/Textures``, once the
    ``pending`` warm-ups that generate them are done."""
    from ionic_usd.texture.stone import copy_user_textures

    def populate(tmp: Path) -> None:
        from ionic_usd.progress import progress

        for job in pending:
            job.result()

        tex = tmp / "Payload" / "Textures"
        with progress(len(FINISHES), "stone textures (OpenImageIO)", unit="material") as bar:
            for _, style in FINISHES.values():
                if opts.user_textures and style == "travertine":
                    copy_user_textures(opts.user_textures, tex)
                else:
                    copy_stone_textures(
                        tex, style, opts.texture_size, opts.seed, make_tx=opts.make_tx
                    )
                bar.update(1)

    return populate


# -- the pipeline -------------------------------------------------------------------------
def _default_triangles(meshes: list[AssetMesh], opts: ColumnAssetOptions) -> dict[str, int]:
    """Triangles per LOD of the default selection (first variant of every set, form full)."""
    firsts = {
        "base": opts.bases[0],
        "scroll": opts.scrolls[0],
        "capital": opts.capitals[0],
        "flutes": opts.flutes[0],
        "volute": opts.volutes[0],
    }
    tris: dict[str, int] = {}
    for lod in opts.lods:
        sel = [
            m
            for m in meshes
            if m.tags["lod"] == lod
            and m.tags.get("form", "full") == "full"
            and all(m.tags.get(k, v) == v for k, v in firsts.items())
        ]
        tris[lod] = sum(m.mesh.n_triangles for m in sel)
    return tris


def _current_report(dest: Path, key: str, t0: float) -> AssetReport | None:
    """The report of ``dest`` when it already holds this build's intact output (its record
    and every file's SHA-256 in its manifest), else None (also for a record of another
    shape: then the asset is built)."""
    record = up_to_date(dest, key)
    if record is None:
        return None
    try:
        return AssetReport(
            dest / f"{ASSET_NAME}.usda",
            int(record["meshes"]),
            {str(k): int(v) for k, v in record["triangles_per_lod"].items()},
            0,
            time.perf_counter() - t0,
            sum(f.stat().st_size for f in dest.rglob("*") if f.is_file()),
            current=True,
        )
    except (KeyError, TypeError, ValueError, AttributeError):
        return None


def build_column_asset(
    folder: str | os.PathLike,
    opts: ColumnAssetOptions | None = None,
    *,
    force: bool = False,
    cache: UVCache | None = None,
    rebuild: bool = False,
    side_jobs: Sequence[tuple[Callable[..., object], tuple]] = (),
) -> AssetReport:
    """Write the column asset ``<folder>/IonicColumn.usda`` (+ Payload/) atomically.

    Parameters
    ----------
    folder : the asset folder (its name is usually ``IonicColumn``)
    opts : variants and textures to build (default: everything, Portunus column)
    force : replace an existing folder (atomically)
    cache : UV cache (default: the process-wide one) for parts without their own charts (none
        of the column's: every part is charted analytically, so no xatlas runs)
    rebuild : regenerate even when ``folder`` already holds this build's intact output
        (:func:`asset_key` and every file's SHA-256 in its manifest), which is otherwise left
        as it is
    side_jobs : more cache warm-ups for the geometry's process pool, after the asset's own
        maps (see :func:`column_asset_meshes`; the temple's terracotta maps)

    User textures (``opts.user_textures``) are validated before anything is written.
    """
    from ionic_usd.texture.stone import validate_user_texture
    from ionic_usd.texture.uv import default_cache

    t0 = time.perf_counter()
    opts = opts or ColumnAssetOptions()
    dest = Path(folder)
    if dest.exists() and not force:
        raise OutputExistsError(f"{dest} exists; pass --force to replace it")
    if opts.user_textures:
        for src in opts.user_textures.values():
            validate_user_texture(src)
    key = asset_key(opts)
    current = None if rebuild else _current_report(dest, key, t0)
    if current is not None:
        return current
    cache = cache if cache is not None else default_cache()
    misses0 = cache.misses
    # the generated meshes (unions, cuts, the capital's charts) with their packed UVs are a
    # pure function of the options and the code: a rebuild of unchanged parameters reads them
    # back. The charts are packed in the pool beside the geometry; the stone maps are made
    # there after it, while this process caches the meshes and writes the layers.
    pending: list[Future] = []
    meshes, _ = cached_meshes(
        "column_asset_uv",
        opts,
        lambda: _with_uvs(
            column_asset_meshes(
                opts, uv_cache=cache, side_jobs=[*_texture_jobs(opts), *side_jobs], pending=pending
            ),
            cache,
        )[0],
        extra=str(cache.folder),
    )
    unwraps = cache.misses - misses0
    triangles = _default_triangles(meshes, opts)
    from ionic_usd.usd.column_asset import author_column_asset  # pxr: only to author

    try:
        path = author_column_asset(
            dest,
            opts,
            meshes,
            column_asset_ornament(opts),
            populate=_textures_writer(opts, pending),
            force=force,
            key=key,
            record={"meshes": len(meshes), "triangles_per_lod": triangles},
        )
    finally:
        wait_for_writes()  # the mesh cache entry, written while the layers were
    size = sum(f.stat().st_size for f in dest.rglob("*") if f.is_file())
    return AssetReport(path, len(meshes), triangles, unwraps, time.perf_counter() - t0, size)
