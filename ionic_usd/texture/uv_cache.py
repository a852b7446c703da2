"""The UV cache: atlases by content key, in memory and as ``.npz`` files.

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
import os
import zipfile
from pathlib import Path
from typing import Literal

import numpy as np
import xatlas

from ionic_usd.errors import GeometryError, ParameterError
from ionic_usd.geometry.mesh import Mesh
from ionic_usd.texture.atlas import DEFAULT_RESOLUTION_CAP, UVAtlas

__all__ = [
    "XATLAS_CHART_OPTIONS",
    "XATLAS_PACK_OPTIONS",
    "XATLAS_VERSION",
    "UVCache",
    "default_cache",
    "default_cache_folder",
    "resolve_cache",
    "uv_cache_key",
]

XATLAS_VERSION: str = getattr(xatlas, "__version__", "unknown")
# Every xatlas option that changes the result; part of the cache key, so editing an option
# here (or bumping the format tag) invalidates old cache entries.
XATLAS_CHART_OPTIONS = {"max_iterations": 1, "fix_winding": True}
XATLAS_PACK_OPTIONS = {
    "blockAlign": False,
    "rotate_charts": False,
    "rotate_charts_to_axis": False,
    "bruteForce": False,
}
_FORMAT = "ionic_usd.uv/1"
_SIGNATURE = (
    f"{_FORMAT};xatlas={XATLAS_VERSION};chart={XATLAS_CHART_OPTIONS};pack={XATLAS_PACK_OPTIONS}"
)


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

    def in_memory(self, key: str) -> bool:
        """Whether ``key`` is in the in-memory layer (no file access, not counted)."""
        return key in self._memory

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


def resolve_cache(cache: UVCache | None | Literal[False]) -> UVCache | None:
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
