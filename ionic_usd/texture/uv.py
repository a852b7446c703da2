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

Consistent texel density between parts
--------------------------------------
A column is several meshes (base, shaft, capital, ...), each unwrapped on its own (one chart
set per part, so each can carry its own material and texture). :func:`apply_uvs` unwraps all
parts with the *same* density and then divides every part's pixel coordinates by one common
size ``S`` = the largest ``max(width, height)`` over all parts, rounded up to a power of two
(:func:`common_atlas_size`). Both axes are divided by the same ``S``, so texels stay square,
every ``st`` lies in [0, 1], and one texel of an ``S × S`` texture covers the same surface
area (``1 / texels_per_metre`` metres on a side) on every part: a tileable stone texture
looks equally fine on the 7 m shaft and on the small capital. If the resolution cap forced a
lower density on one part, all parts are unwrapped again at that lower density.
Alternative meshes that share a texture budget (variant sets: several bases for one LOD)
pass the same explicit ``atlas_size`` (compute it with :func:`common_atlas_size` over all
their atlases from :func:`unwrap_parts`).

Caching
-------
Unwrapping runs once per unique geometry. :class:`UVCache` keys an atlas by a SHA-256 of the
points, the face arrays, the density, the padding, the resolution cap, the xatlas version and
this module's option signature, and stores it as ``<key>.npz`` (written to a temporary file
and moved into place with :func:`os.replace`, so readers never see half a file) behind an
in-process dictionary. The default folder is ``$IONIC_USD_CACHE/uv`` or, without that
variable, ``$XDG_CACHE_HOME/ionic_usd/uv`` (``~/.cache/ionic_usd/uv``). A corrupt or foreign
cache file is ignored and rewritten; a cache folder that cannot be written only disables
persistence. ``cache.hits`` / ``cache.misses`` count look-ups (a miss means xatlas ran).
"""

from __future__ import annotations

import hashlib
import math
import os
import time
import zipfile
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Literal

import numpy as np
import xatlas

from ionic_usd.errors import GeometryError, ParameterError
from ionic_usd.geometry.mesh import Mesh, face_normals

__all__ = [
    "DEFAULT_PADDING",
    "DEFAULT_RESOLUTION_CAP",
    "LOD_TEXELS_PER_METRE",
    "XATLAS_VERSION",
    "UVAtlas",
    "UVCache",
    "apply_uvs",
    "attach_uvs",
    "common_atlas_size",
    "default_cache",
    "default_cache_folder",
    "uv_cache_key",
    "unwrap",
    "unwrap_parts",
]

#: Texel densities per level of detail (px per metre of surface). 256 px/m puts about
#: 4 px on a 16 mm fillet of the Portunus shaft and gives it a 4096² atlas.
LOD_TEXELS_PER_METRE: dict[str, float] = {"high": 256.0, "medium": 128.0, "low": 64.0}
DEFAULT_PADDING = 4
DEFAULT_RESOLUTION_CAP = 8192

XATLAS_VERSION: str = getattr(xatlas, "__version__", "unknown")
# Every xatlas option that changes the result; part of the cache key, so editing an option
# here (or bumping the format tag) invalidates old cache entries.
_CHART_OPTIONS = {"max_iterations": 1, "fix_winding": True}
_PACK_OPTIONS = {
    "blockAlign": False,
    "rotate_charts": False,
    "rotate_charts_to_axis": False,
    "bruteForce": False,
}
_FORMAT = "ionic_usd.uv/1"
_SIGNATURE = f"{_FORMAT};xatlas={XATLAS_VERSION};chart={_CHART_OPTIONS};pack={_PACK_OPTIONS}"
# first guess of the fraction of the atlas the charts fill, used only to pre-shrink the
# density of a mesh that would obviously not fit under the resolution cap
_EXPECTED_UTILISATION = 0.4
_MAX_REFITS = 8


def _frozen(a: np.ndarray) -> np.ndarray:
    a = np.ascontiguousarray(a)
    a.setflags(write=False)
    return a


@dataclass(frozen=True, eq=False)
class UVAtlas:
    """Texture coordinates of one mesh in atlas pixels.

    Parameters
    ----------
    st_px : (u, 2) float32
        Chart vertex positions in pixels, ``0 <= x <= width``, ``0 <= y <= height``.
    st_indices : (k,) int32
        One index into ``st_px`` per face corner, in the order of ``face_vertex_indices``.
    width, height : int
        Atlas size in pixels.
    chart_count : int
    utilisation : float
        Fraction of the ``width × height`` atlas covered by charts (xatlas's estimate).
    texels_per_metre : float
        Density actually used (lower than requested only if the resolution cap forced it).
    seconds : float
        Wall time of the xatlas run(s) that produced the atlas; a diagnostic, not stored in
        the cache (0 for an atlas read from disk).
    """

    st_px: np.ndarray
    st_indices: np.ndarray
    width: int
    height: int
    chart_count: int
    utilisation: float
    texels_per_metre: float
    seconds: float = field(default=0.0, compare=False)

    def __post_init__(self) -> None:
        st = np.asarray(self.st_px, dtype=np.float32).reshape(-1, 2)
        sti = np.asarray(self.st_indices, dtype=np.int32).reshape(-1)
        for name in ("width", "height"):
            v = getattr(self, name)
            if int(v) != v or v < 1:
                raise ParameterError(name, v, "an integer >= 1", context="UVAtlas")
            object.__setattr__(self, name, int(v))
        if int(self.chart_count) != self.chart_count or self.chart_count < 0:
            raise ParameterError(
                "chart_count", self.chart_count, "an integer >= 0", context="UVAtlas"
            )
        object.__setattr__(self, "chart_count", int(self.chart_count))
        if not 0.0 <= float(self.utilisation) <= 1.0 + 1e-6:
            raise ParameterError(
                "utilisation", self.utilisation, "0 <= utilisation <= 1", context="UVAtlas"
            )
        if not (math.isfinite(self.texels_per_metre) and self.texels_per_metre > 0):
            raise ParameterError(
                "texels_per_metre", self.texels_per_metre, "a number > 0", context="UVAtlas"
            )
        if sti.size and (sti.min() < 0 or sti.max() >= len(st)):
            raise GeometryError("UVAtlas: st_indices out of range")
        if st.size and (
            not np.all(np.isfinite(st))
            or st.min() < -1e-3
            or np.any(st.max(axis=0) > np.array([self.width, self.height]) + 1e-3)
        ):
            raise GeometryError("UVAtlas: st_px outside the atlas")
        object.__setattr__(self, "st_px", _frozen(st))
        object.__setattr__(self, "st_indices", _frozen(sti))
        object.__setattr__(self, "utilisation", float(self.utilisation))
        object.__setattr__(self, "texels_per_metre", float(self.texels_per_metre))

    @property
    def size(self) -> int:
        """Longer side of the atlas in pixels."""
        return max(self.width, self.height)

    def st(self, atlas_size: int | None = None) -> np.ndarray:
        """(u, 2) float32 coordinates normalised by ``atlas_size`` on both axes.

        ``atlas_size`` defaults to :attr:`size` rounded up to a power of two and must be at
        least :attr:`size` so that the result lies in [0, 1].
        """
        s = _next_pow2(self.size) if atlas_size is None else _check_atlas_size(atlas_size)
        if s < self.size:
            raise ParameterError(
                "atlas_size", atlas_size, f"an integer >= {self.size} (this atlas's longer side)"
            )
        return (self.st_px.astype(np.float64) / s).astype(np.float32)


# -- cache ---------------------------------------------------------------------------------


def default_cache_folder() -> Path:
    """``$IONIC_USD_CACHE/uv``, else ``$XDG_CACHE_HOME/ionic_usd/uv`` (``~/.cache/...``)."""
    root = os.environ.get("IONIC_USD_CACHE")
    if root:
        return Path(root).expanduser() / "uv"
    xdg = os.environ.get("XDG_CACHE_HOME")
    base = Path(xdg).expanduser() if xdg else Path.home() / ".cache"
    return base / "ionic_usd" / "uv"


class UVCache:
    """Atlases by content key: an in-memory dictionary in front of ``.npz`` files.

    Parameters
    ----------
    folder : path or None
        Where the ``.npz`` files live (created on first write); ``None`` gives
        :func:`default_cache_folder`.
    persist : bool
        ``False`` keeps the cache in memory only.

    Attributes
    ----------
    hits, misses : int
        Look-ups answered from memory or disk, and look-ups that found nothing.
    disk_hits : int
        The part of ``hits`` read from a file.
    corrupt : int
        Unreadable or mismatching files met (each is then treated as a miss and rewritten).
    """

    def __init__(self, folder: str | os.PathLike | None = None, *, persist: bool = True) -> None:
        self.folder = Path(folder) if folder is not None else default_cache_folder()
        self.persist = persist
        self.hits = 0
        self.misses = 0
        self.disk_hits = 0
        self.corrupt = 0
        self._memory: dict[str, UVAtlas] = {}

    def __repr__(self) -> str:
        return (
            f"UVCache({str(self.folder)!r}, persist={self.persist}, hits={self.hits}, "
            f"misses={self.misses})"
        )

    def path_for(self, key: str) -> Path:
        return self.folder / f"{key}.npz"

    def get(self, key: str) -> UVAtlas | None:
        """The atlas stored under ``key``, or ``None`` (counted as a miss)."""
        atlas = self._memory.get(key)
        if atlas is None and self.persist:
            atlas = self._read(key)
            if atlas is not None:
                self.disk_hits += 1
                self._memory[key] = atlas
        if atlas is None:
            self.misses += 1
        else:
            self.hits += 1
        return atlas

    def put(self, key: str, atlas: UVAtlas) -> None:
        """Store ``atlas``; a folder that cannot be written only skips the file."""
        self._memory[key] = atlas
        if self.persist:
            self._write(key, atlas)

    def clear_memory(self) -> None:
        """Forget the in-memory layer (the files stay)."""
        self._memory.clear()

    def _read(self, key: str) -> UVAtlas | None:
        path = self.path_for(key)
        if not path.is_file():
            return None
        try:
            with np.load(path, allow_pickle=False) as z:
                if str(z["key"]) != key:
                    raise ValueError("key mismatch")
                meta = z["meta"]
                return UVAtlas(
                    st_px=z["st_px"],
                    st_indices=z["st_indices"],
                    width=int(meta[0]),
                    height=int(meta[1]),
                    chart_count=int(meta[2]),
                    utilisation=float(z["utilisation"]),
                    texels_per_metre=float(z["texels_per_metre"]),
                )
        # a truncated, foreign or garbage file: ignore it, the caller recomputes and rewrites
        except (
            OSError,
            ValueError,
            KeyError,
            IndexError,
            EOFError,
            zipfile.BadZipFile,
            GeometryError,
        ):
            self.corrupt += 1
            return None

    def _write(self, key: str, atlas: UVAtlas) -> None:
        from ionic_usd.io import atomic_path

        try:
            self.folder.mkdir(parents=True, exist_ok=True)
            with atomic_path(self.path_for(key)) as tmp, open(tmp, "wb") as f:
                np.savez(
                    f,
                    key=np.array(key),
                    st_px=atlas.st_px,
                    st_indices=atlas.st_indices,
                    meta=np.array([atlas.width, atlas.height, atlas.chart_count], np.int64),
                    utilisation=np.array(atlas.utilisation),
                    texels_per_metre=np.array(atlas.texels_per_metre),
                )
        except OSError:
            pass  # a read-only or full disk must not stop geometry from being built


_DEFAULT_CACHES: dict[Path, UVCache] = {}


def default_cache() -> UVCache:
    """The process-wide cache in :func:`default_cache_folder` (re-read on every call)."""
    folder = default_cache_folder()
    if folder not in _DEFAULT_CACHES:
        _DEFAULT_CACHES[folder] = UVCache(folder)
    return _DEFAULT_CACHES[folder]


def _resolve_cache(cache: UVCache | None | Literal[False]) -> UVCache | None:
    if cache is False:
        return None
    if cache is None:
        return default_cache()
    if not isinstance(cache, UVCache):
        raise ParameterError("cache", cache, "a UVCache, None (default cache) or False (none)")
    return cache


def uv_cache_key(
    mesh: Mesh,
    *,
    texels_per_metre: float,
    padding: int,
    resolution_cap: int = DEFAULT_RESOLUTION_CAP,
    max_chart_boundary: float | None = None,
) -> str:
    """SHA-256 hex digest of everything that determines :func:`unwrap`'s result."""
    h = hashlib.sha256()
    h.update(_SIGNATURE.encode())
    if max_chart_boundary is not None:
        h.update(f";boundary={float(max_chart_boundary)!r}".encode())
    h.update(
        f";tpm={float(texels_per_metre)!r};pad={int(padding)};cap={int(resolution_cap)}".encode()
    )
    pts = np.ascontiguousarray(mesh.points, dtype="<f8")
    h.update(f";points={pts.shape}".encode())
    h.update(pts.tobytes())
    counts = np.ascontiguousarray(mesh.face_vertex_counts, dtype="<i4")
    h.update(f";counts={counts.shape}".encode())
    h.update(counts.tobytes())
    h.update(b";indices")
    h.update(np.ascontiguousarray(mesh.face_vertex_indices, dtype="<i4").tobytes())
    return h.hexdigest()


# -- unwrapping ----------------------------------------------------------------------------


def _next_pow2(n: int) -> int:
    return 1 << max(0, int(n) - 1).bit_length()


def _check_atlas_size(atlas_size: int) -> int:
    if isinstance(atlas_size, bool) or int(atlas_size) != atlas_size or atlas_size < 1:
        raise ParameterError("atlas_size", atlas_size, "an integer >= 1")
    return int(atlas_size)


def _check_options(texels_per_metre: float, padding: int, resolution_cap: int) -> None:
    if (
        isinstance(texels_per_metre, bool)
        or not isinstance(texels_per_metre, int | float)
        or not math.isfinite(texels_per_metre)
        or texels_per_metre <= 0
    ):
        raise ParameterError(
            "texels_per_metre", texels_per_metre, "a finite number > 0", context="uv"
        )
    if isinstance(padding, bool) or int(padding) != padding or not 0 <= padding <= 64:
        raise ParameterError("padding", padding, "an integer 0..64", context="uv")
    if (
        isinstance(resolution_cap, bool)
        or int(resolution_cap) != resolution_cap
        or not 16 <= resolution_cap <= 65536
    ):
        raise ParameterError("resolution_cap", resolution_cap, "an integer 16..65536", context="uv")


def _run_xatlas(
    points: np.ndarray, tri: np.ndarray, tpm: float, padding: int, boundary: float | None = None
) -> tuple[np.ndarray, np.ndarray, np.ndarray, xatlas.Atlas]:
    atlas = xatlas.Atlas()
    atlas.add_mesh(points, tri)
    co = xatlas.ChartOptions()
    for k, v in _CHART_OPTIONS.items():
        setattr(co, k, v)
    if boundary is not None:
        co.max_boundary_length = float(boundary)
    po = xatlas.PackOptions()
    for k, v in _PACK_OPTIONS.items():
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
    texels_per_metre: float = LOD_TEXELS_PER_METRE["high"],
    padding: int = DEFAULT_PADDING,
    resolution_cap: int = DEFAULT_RESOLUTION_CAP,
    cache: UVCache | None | Literal[False] = None,
    max_chart_boundary: float | None = None,
) -> UVAtlas:
    """Cut, flatten and pack a triangle mesh into one atlas with xatlas.

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
    _check_options(texels_per_metre, padding, resolution_cap)
    if mesh.n_faces == 0:
        raise GeometryError(f"unwrap: mesh {mesh.name!r} has no faces")
    if not np.all(mesh.face_vertex_counts == 3):
        raise GeometryError(
            f"unwrap: mesh {mesh.name!r} has non-triangle faces; xatlas UVs need a triangle "
            "mesh (fan-triangulate it first)"
        )
    store = _resolve_cache(cache)
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

    store = _resolve_cache(cache)
    if store is None:
        return 0
    todo: dict[str, tuple] = {}
    for item in meshes:
        mesh, tpm = item[0], item[1]
        boundary = item[2] if len(item) > 2 else None
        _check_options(tpm, padding, resolution_cap)
        key = uv_cache_key(
            mesh,
            texels_per_metre=tpm,
            padding=padding,
            resolution_cap=resolution_cap,
            max_chart_boundary=boundary,
        )
        if key in todo or key in store._memory:
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
            with ProcessPoolExecutor(max_workers=min(n, len(todo)), mp_context=ctx) as ex:
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
    texels_per_metre: float = LOD_TEXELS_PER_METRE["high"],
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
    kw = {"padding": padding, "resolution_cap": resolution_cap, "cache": cache}
    bnd = chart_boundaries or {}

    def run(tpm: float) -> dict[str, UVAtlas]:
        return {
            k: unwrap(m, texels_per_metre=tpm, max_chart_boundary=bnd.get(k), **kw)
            for k, m in meshes.items()
        }

    atlases = run(texels_per_metre)
    lowest = min(a.texels_per_metre for a in atlases.values())
    if lowest < float(texels_per_metre):
        atlases = run(lowest)
    return atlases


def common_atlas_size(atlases: Iterable[UVAtlas]) -> int:
    """The normalising size S: the longest atlas side over all parts, rounded up to 2^n."""
    sides = [a.size for a in atlases]
    if not sides:
        raise GeometryError("common_atlas_size needs at least one atlas")
    return _next_pow2(max(sides))


def attach_uvs(mesh: Mesh, atlas: UVAtlas, atlas_size: int | None = None) -> Mesh:
    """``mesh`` with ``st = atlas.st_px / atlas_size`` and ``st_indices`` attached.

    Points, faces and normals are untouched.
    """
    if atlas.st_indices.size != mesh.face_vertex_indices.size:
        raise GeometryError(
            f"attach_uvs: atlas has {atlas.st_indices.size} corners, mesh {mesh.name!r} has "
            f"{mesh.face_vertex_indices.size}"
        )
    return mesh.with_(st=atlas.st(atlas_size), st_indices=atlas.st_indices)


def apply_uvs(
    meshes: Mapping[str, Mesh],
    *,
    texels_per_metre: float = LOD_TEXELS_PER_METRE["high"],
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
    {name: Mesh} in the input order, each with faceVarying indexed ``st`` in [0, 1]; points,
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
        size = _check_atlas_size(atlas_size)
        longest = max(a.size for a in atlases.values())
        if size < longest:
            raise ParameterError(
                "atlas_size",
                atlas_size,
                f"an integer >= {longest} (the largest part atlas side at this density)",
                context="apply_uvs",
            )
    return {k: attach_uvs(m, atlases[k], size) for k, m in meshes.items()}
