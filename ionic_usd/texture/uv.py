"""Texture coordinates from xatlas, with one texel density for every part and a cache.

Unwrapping
----------
:func:`unwrap` runs xatlas on a triangle mesh and returns a :class:`UVAtlas`: per-corner
texture coordinates in *atlas pixels* (``st_px``) indexed by ``st_indices`` (one index per face
corner, in the order of ``face_vertex_indices``), plus the atlas size. xatlas cuts the surface
into charts, flattens and packs them; it keeps the input faces and their corner order (checked
on every call), so the mesh's points and faces never change: the UVs are attached as the
indexed faceVarying primvar ``st`` and the mesh stays watertight.

Charts are scaled to ``texels_per_metre`` texels per metre of surface (xatlas's
``texels_per_unit``; points are in metres), with ``padding`` empty texels between charts.
Because the padding already keeps a bilinear footprint inside the gutter, xatlas's extra
``bilinear`` texel is only asked for when ``padding == 0`` (it halves packing time).
Every chart winds counter-clockwise in (s, t) like its faces seen from outside: xatlas's
``fix_winding`` is on and its packer's chart rotation is off, because in xatlas 0.0.11 that
"rotation" transposes a chart, i.e. mirrors it, which flips tangent-space normal maps
(checked in the tests). Charts are not turned to an axis either (``rotate_charts_to_axis``
is off): on the fluted shaft that packs tighter (utilisation 0.58 against 0.35).
An atlas larger than ``resolution_cap`` on a side is not produced: the density is lowered
until it fits, and the density actually used is recorded in :attr:`UVAtlas.texels_per_metre`.

Atlas values, the common size and analytic charts live in :mod:`ionic_usd.texture.atlas`, the
cache in :mod:`ionic_usd.texture.uv_cache`; their public names are importable from here too.
"""

from __future__ import annotations

import math
import os
import time
from collections.abc import Iterable, Mapping
from typing import Literal

import numpy as np
import xatlas

from ionic_usd.errors import GeometryError, ParameterError
from ionic_usd.geometry.mesh import CornerValues, Mesh, face_normals
from ionic_usd.texture.atlas import (
    DEFAULT_PADDING,
    DEFAULT_RESOLUTION_CAP,
    DEFAULT_TEXELS_PER_METRE,
    UVAtlas,
    analytic_atlas,
    attach_uvs,
    check_atlas_size,
    check_uv_options,
    common_atlas_size,
)
from ionic_usd.texture.charts import split_overlapping_charts
from ionic_usd.texture.uv_cache import (
    XATLAS_CHART_OPTIONS,
    XATLAS_PACK_OPTIONS,
    XATLAS_VERSION,
    UVCache,
    default_cache,
    default_cache_folder,
    resolve_cache,
    uv_cache_key,
)

__all__ = [
    "DEFAULT_PADDING",
    "DEFAULT_RESOLUTION_CAP",
    "DEFAULT_TEXELS_PER_METRE",
    "XATLAS_VERSION",
    "UVAtlas",
    "UVCache",
    "apply_uvs",
    "attach_uvs",
    "common_atlas_size",
    "default_cache",
    "analytic_atlas",
    "default_cache_folder",
    "metric_charts",
    "prefetch",
    "uv_cache_key",
    "unwrap",
    "unwrap_parts",
]

# first guess of the fraction of the atlas the charts fill, used only to pre-shrink the
# density of a mesh that would obviously not fit under the resolution cap
_EXPECTED_UTILISATION = 0.4
_MAX_REFITS = 8


def _run_xatlas(
    points: np.ndarray, tri: np.ndarray, tpm: float, padding: int, boundary: float | None = None
) -> tuple[np.ndarray, np.ndarray, np.ndarray, xatlas.Atlas]:
    atlas = xatlas.Atlas()
    atlas.add_mesh(points, tri)
    co = xatlas.ChartOptions()
    for k, v in XATLAS_CHART_OPTIONS.items():
        setattr(co, k, v)
    if boundary is not None:
        co.max_boundary_length = float(boundary)
    po = xatlas.PackOptions()
    for k, v in XATLAS_PACK_OPTIONS.items():
        setattr(po, k, v)
    po.padding = int(padding)
    po.texels_per_unit = float(tpm)
    po.resolution = 0  # size follows the density: one atlas, as large as needed
    po.bilinear = padding == 0
    atlas.generate(co, po)
    vmapping, indices, uvs = atlas[0]
    return vmapping, indices, uvs, atlas


def unwrap(
    mesh: Mesh,
    *,
    texels_per_metre: float = DEFAULT_TEXELS_PER_METRE,
    padding: int = DEFAULT_PADDING,
    resolution_cap: int = DEFAULT_RESOLUTION_CAP,
    cache: UVCache | None | Literal[False] = None,
    max_chart_boundary: float | None = None,
    analytic: bool = True,
) -> UVAtlas:
    """Cut, flatten and pack a triangle mesh into one atlas with xatlas.

    A mesh that already carries ``st`` (an analytic parametrisation in metres from its
    generator: the base and shaft) is not unwrapped: with ``analytic`` its charts are packed
    as they are by :func:`~ionic_usd.texture.atlas.analytic_atlas` (no xatlas run, no cache
    entry, not counted in the cache's misses).

    Parameters
    ----------
    mesh : Mesh
        Triangles only (``face_vertex_counts == 3``), at least one face.
    texels_per_metre : float > 0
        Texel density on the surface.
    padding : int 0..64
        Empty texels between charts.
    resolution_cap : int
        Largest atlas side; a denser request is scaled down until it fits.
    cache : UVCache, None or False
        ``None`` uses :func:`default_cache`, ``False`` disables caching.
    max_chart_boundary : float or None
        Limit a chart's boundary length (m). xatlas's flattening cost grows faster than the
        chart size; lathed parts (column bases) otherwise form a few huge charts. Measured on
        the G2 base at 64 px/m: 1.39 s → 0.31 s with 2 m, at the price of more seams and
        ≈ 10 % more area stretch on small discs.
    analytic : bool
        Use the mesh's own ``st`` charts when it has them (``False``: always run xatlas).

    Returns
    -------
    UVAtlas with ``st_indices`` of shape ``(3 * n_faces,)`` in corner order.

    Raises
    ------
    GeometryError
        Non-triangle faces, an empty mesh, or xatlas reordering the faces.
    ParameterError
        Out-of-range options.
    """
    check_uv_options(texels_per_metre, padding, resolution_cap)
    if mesh.n_faces == 0:
        raise GeometryError(f"unwrap: mesh {mesh.name!r} has no faces")
    if not np.all(mesh.face_vertex_counts == 3):
        raise GeometryError(
            f"unwrap: mesh {mesh.name!r} has non-triangle faces; xatlas UVs need a triangle "
            "mesh (fan-triangulate it first)"
        )
    if analytic and mesh.st is not None:
        return analytic_atlas(
            mesh, texels_per_metre=texels_per_metre, padding=padding, resolution_cap=resolution_cap
        )
    store = resolve_cache(cache)
    key = uv_cache_key(
        mesh,
        texels_per_metre=texels_per_metre,
        padding=padding,
        resolution_cap=resolution_cap,
        max_chart_boundary=max_chart_boundary,
    )
    if store is not None:
        hit = store.get(key)
        if hit is not None:
            return hit
    atlas = _unwrap_uncached(
        mesh, float(texels_per_metre), int(padding), int(resolution_cap), max_chart_boundary
    )
    if store is not None:
        store.put(key, atlas)
    return atlas


def _unwrap_uncached(
    mesh: Mesh, tpm: float, padding: int, cap: int, boundary: float | None = None
) -> UVAtlas:
    tri = mesh.triangles
    points = np.ascontiguousarray(mesh.points, dtype=np.float32)
    tri_u = np.ascontiguousarray(tri, dtype=np.uint32)
    area = float(face_normals(mesh.points, tri)[1].sum())
    if area <= 0:
        raise GeometryError(f"unwrap: mesh {mesh.name!r} has zero surface area")
    # packing time grows with the atlas area: do not even try a size that cannot fit
    guess = math.sqrt(area / _EXPECTED_UTILISATION) * tpm
    if guess > cap:
        tpm *= cap / guess
    t0 = time.perf_counter()
    for _ in range(_MAX_REFITS):
        vmapping, indices, uvs, xa = _run_xatlas(points, tri_u, tpm, padding, boundary)
        side = max(xa.width, xa.height)
        if xa.atlas_count == 1 and side <= cap:
            break
        tpm *= 0.97 * cap / side if side > cap else 0.8
    else:
        raise GeometryError(
            f"unwrap: mesh {mesh.name!r} does not fit a {cap}² atlas (last try "
            f"{xa.width}×{xa.height} at {tpm:.3g} px/m)"
        )
    seconds = time.perf_counter() - t0
    indices = np.asarray(indices, dtype=np.int64).reshape(-1, 3)
    # USD's st_indices run parallel to face_vertex_indices: this only holds if xatlas kept
    # face i as face i with its corners in the same order
    if indices.shape != tri.shape or not np.array_equal(
        np.asarray(vmapping, dtype=np.int64)[indices], tri
    ):
        raise GeometryError(f"unwrap: xatlas reordered the faces of mesh {mesh.name!r}")
    st_px = np.asarray(uvs, dtype=np.float64).reshape(-1, 2) * np.array([xa.width, xa.height])
    return UVAtlas(
        st_px=st_px.astype(np.float32),
        st_indices=indices.reshape(-1).astype(np.int32),
        width=xa.width,
        height=xa.height,
        chart_count=xa.chart_count,
        utilisation=min(1.0, float(xa.get_utilization(0))),
        texels_per_metre=tpm,
        seconds=seconds,
    )


def _unwrap_job(args: tuple) -> UVAtlas:
    mesh, tpm, padding, cap, boundary = args
    return _unwrap_uncached(mesh, tpm, padding, cap, boundary)


def prefetch(
    meshes: Iterable[tuple[Mesh, float] | tuple[Mesh, float, float | None]],
    *,
    padding: int = DEFAULT_PADDING,
    resolution_cap: int = DEFAULT_RESOLUTION_CAP,
    cache: UVCache | None = None,
    workers: int | None = None,
) -> int:
    """Unwrap, in parallel processes, every (mesh, texels_per_metre) the cache lacks.

    xatlas holds the GIL, so threads do not help; a process pool over the cores does. The
    results go into the cache (each counted as a miss, i.e. one xatlas run), so the
    :func:`unwrap` calls that follow are hits. Returns the number of meshes unwrapped.
    """
    import multiprocessing as mp
    from concurrent.futures import ProcessPoolExecutor

    store = resolve_cache(cache)
    if store is None:
        return 0
    todo: dict[str, tuple] = {}
    for item in meshes:
        mesh, tpm = item[0], item[1]
        boundary = item[2] if len(item) > 2 else None
        check_uv_options(tpm, padding, resolution_cap)
        if mesh.st is not None:
            continue  # analytic charts: unwrap() packs them without xatlas
        key = uv_cache_key(
            mesh,
            texels_per_metre=tpm,
            padding=padding,
            resolution_cap=resolution_cap,
            max_chart_boundary=boundary,
        )
        if key in todo or store.in_memory(key):
            continue
        if store.persist and store.path_for(key).is_file():
            continue  # get() will read (and verify) it
        todo[key] = (mesh, float(tpm), int(padding), int(resolution_cap), boundary)
    if not todo:
        return 0
    n = workers or os.cpu_count() or 1
    # a daemonic process (a Dask worker) may not fork a pool: there the cluster is the
    # parallelism (one prototype per worker, see ionic_usd.pipeline), so unwrap in-process
    from ionic_usd.progress import progress

    with progress(len(todo), "unwrapping UVs (xatlas)", unit="mesh") as bar:
        if n <= 1 or len(todo) < 4 or mp.current_process().daemon:
            results = []
            for job in todo.values():
                results.append(_unwrap_job(job))
                bar.update(1)
        else:
            ctx = mp.get_context("fork" if "fork" in mp.get_all_start_methods() else "spawn")
            from ionic_usd.outputs import die_with_parent

            with ProcessPoolExecutor(
                max_workers=min(n, len(todo)),
                mp_context=ctx,
                initializer=die_with_parent,
                initargs=(os.getpid(),),
            ) as ex:
                results = []
                for r in ex.map(_unwrap_job, todo.values(), chunksize=1):
                    results.append(r)
                    bar.update(1)
    for key, atlas in zip(todo, results, strict=True):
        store.misses += 1
        store.put(key, atlas)
    return len(todo)


def unwrap_parts(
    meshes: Mapping[str, Mesh],
    *,
    texels_per_metre: float = DEFAULT_TEXELS_PER_METRE,
    padding: int = DEFAULT_PADDING,
    resolution_cap: int = DEFAULT_RESOLUTION_CAP,
    cache: UVCache | None | Literal[False] = None,
    chart_boundaries: Mapping[str, float | None] | None = None,
) -> dict[str, UVAtlas]:
    """Unwrap every part separately at one common texel density.

    If the resolution cap lowered the density of some part, every part is unwrapped again
    at the lowest density used, so the density stays equal across parts.
    ``chart_boundaries`` gives some parts a ``max_chart_boundary`` (see :func:`unwrap`).
    """
    if not meshes:
        raise GeometryError("unwrap_parts needs at least one mesh")
    bnd = chart_boundaries or {}

    def run(tpm: float) -> dict[str, UVAtlas]:
        return {
            k: unwrap(
                m,
                texels_per_metre=tpm,
                max_chart_boundary=bnd.get(k),
                padding=padding,
                resolution_cap=resolution_cap,
                cache=cache,
            )
            for k, m in meshes.items()
        }

    atlases = run(texels_per_metre)
    lowest = min(a.texels_per_metre for a in atlases.values())
    if lowest < float(texels_per_metre):
        atlases = run(lowest)
    return atlases


def apply_uvs(
    meshes: Mapping[str, Mesh],
    *,
    texels_per_metre: float = DEFAULT_TEXELS_PER_METRE,
    padding: int = DEFAULT_PADDING,
    cache: UVCache | None | Literal[False] = None,
    atlas_size: int | None = None,
    resolution_cap: int = DEFAULT_RESOLUTION_CAP,
) -> dict[str, Mesh]:
    """Attach xatlas UVs to every part with one texel density and one normalising size.

    Parameters
    ----------
    meshes : {name: Mesh}
        Triangle meshes (parts of one asset).
    texels_per_metre, padding, resolution_cap, cache : see :func:`unwrap`
    atlas_size : int or None
        The common size S that pixel coordinates are divided by. ``None`` computes it with
        :func:`common_atlas_size`; pass one value to several calls (variant alternatives)
        to give them the same scale. Must be at least every part's longer atlas side.

    Returns
    -------
    {name: Mesh} in the input order, each with indexed per-corner ``st`` in [0, 1]; points,
    faces and normals unchanged. A texture of ``S × S`` texels then has the requested
    density on every part.
    """
    atlases = unwrap_parts(
        meshes,
        texels_per_metre=texels_per_metre,
        padding=padding,
        resolution_cap=resolution_cap,
        cache=cache,
    )
    need = common_atlas_size(atlases.values())
    if atlas_size is None:
        size = need
    else:
        size = check_atlas_size(atlas_size)
        longest = max(a.size for a in atlases.values())
        if size < longest:
            raise ParameterError(
                "atlas_size",
                atlas_size,
                f"an integer >= {longest} (the largest part atlas side at this density)",
                context="apply_uvs",
            )
    return {k: attach_uvs(m, atlases[k], size) for k, m in meshes.items()}


def metric_charts(
    meshes: Iterable[Mesh],
    texels_per_metre: float,
    *,
    padding: int = DEFAULT_PADDING,
    resolution_cap: int = DEFAULT_RESOLUTION_CAP,
    cache: UVCache | None = None,
    workers: int | None = None,
) -> list[Mesh]:
    """The meshes with xatlas charts attached as metric ``st`` (metres of surface).

    For a mesh that is cut afterwards (the engaged and corner forms of a capital): the cuts
    carry ``st`` (:func:`ionic_usd.geometry.clip.clip_mesh`,
    :func:`ionic_usd.geometry.boolean.difference`), so xatlas runs once for the uncut mesh
    instead of once per form, and :func:`unwrap` then packs the cut pieces' charts as analytic
    ones. Meshes that already have ``st`` are returned as they are; the others are unwrapped
    in parallel (:func:`prefetch` over ``workers`` processes, through ``cache``) at
    ``texels_per_metre``. A chart xatlas folded onto itself is split into pieces that do not
    overlap (:func:`~ionic_usd.texture.charts.split_overlapping_charts`).
    """
    meshes = list(meshes)
    todo = [m for m in meshes if m.st is None]
    prefetch(
        [(m, texels_per_metre) for m in todo],
        padding=padding,
        resolution_cap=resolution_cap,
        cache=cache,
        workers=workers,
    )
    out = []
    for m in meshes:
        if m.st is not None:
            out.append(m)
            continue
        a = unwrap(
            m,
            texels_per_metre=texels_per_metre,
            padding=padding,
            resolution_cap=resolution_cap,
            cache=cache,
            analytic=False,
        )
        # xatlas can fold a chart onto itself near its boundary; once repacked the fold
        # covers whole texels twice, so such charts are split here (overlaps thinner than a
        # thousandth of a texel, i.e. touching neighbours, do not count)
        st, sti, _ = split_overlapping_charts(a.st_px, a.st_indices, 1e-3)
        out.append(m.with_(st=CornerValues(st / np.float32(a.texels_per_metre), sti)))
    return out
