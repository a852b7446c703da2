"""Generated asset meshes cached by content: a rebuild of unchanged parameters generates nothing.

The column asset's meshes cost most of a build (the capital's manifold3d unions, the form cuts
and their sliver clean-up: ~15 s of a ~20 s temple on 2 cores), and they are a pure function of
the asset options and of the code that generates them. So they are kept in
``$IONIC_USD_CACHE/meshes/<key>/`` (beside the UV and texture caches) as one ``.npz`` of plain
arrays (no pickle) plus a JSON index, written and read through
:func:`ionic_usd.io.verified_cache` (SHA-256 manifest, atomic rename: a truncated or edited
entry is discarded and produced again).

The key (:func:`ionic_usd.pipeline.keys.build_key`) hashes ``repr(opts)``, the UV cache's
folder (a part without its own charts is unwrapped through it), the package version, the bytes
of every module of the package and the libraries' versions, so any change to the generators —
released or not — misses the cache instead of returning stale geometry.
"""

from __future__ import annotations

import json
import logging
import threading
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from ionic_usd.blueprint.asset import AssetMesh
from ionic_usd.geometry.mesh import CornerValues, Mesh
from ionic_usd.pipeline.keys import build_key

__all__ = ["cached_meshes", "mesh_cache_folder", "wait_for_writes"]

log = logging.getLogger(__name__)

_FIELDS = ("points", "face_vertex_counts", "face_vertex_indices")
_ATTRS = ("normals", "st")  # CornerValues: values, indices (unless per point or per corner)
#: the entry layout, in the key: 2 = the attributes as CornerValues (1: USD's encodings)
_FORMAT = 2
_INDEX = "meshes.json"
_ARRAYS = "meshes.npz"


def mesh_cache_folder() -> Path:
    """``meshes/`` beside the UV cache (``$IONIC_USD_CACHE/meshes`` or ``~/.cache/...``)."""
    from ionic_usd.texture.uv import default_cache_folder

    return default_cache_folder().parent / "meshes"


def _key(tag: str, opts: object, extra: str) -> str:
    return build_key(tag, opts, f"{extra}|mesh-format-{_FORMAT}")


def _write(folder: Path, meshes: list[AssetMesh]) -> None:
    index = []
    arrays: dict[str, Any] = {}  # (numpy types savez's keywords as its flags)
    for i, am in enumerate(meshes):
        m = am.mesh
        for f in _FIELDS:
            arrays[f"{i}.{f}"] = np.asarray(getattr(m, f))
        attrs = {}
        for a in _ATTRS:
            cv: CornerValues | None = getattr(m, a)
            if cv is None:
                continue
            arrays[f"{i}.{a}"] = cv.values
            layout = "point" if cv.by_point else "corner" if cv.one_per_corner else "indexed"
            if layout == "indexed":
                arrays[f"{i}.{a}.indices"] = cv.indices
            # distinct: authoring writes such st without sorting
            attrs[a] = {"layout": layout, "distinct": cv.distinct}
        index.append(
            {
                "part": am.part,
                "name": am.name,
                "tags": dict(am.tags),
                "mesh_name": m.name,
                "attrs": attrs,
            }
        )
    np.savez(folder / _ARRAYS, **arrays)
    (folder / _INDEX).write_text(json.dumps(index))


def _read(folder: Path) -> list[AssetMesh]:
    index = json.loads((folder / _INDEX).read_text())
    out = []
    with np.load(folder / _ARRAYS, allow_pickle=False) as z:
        for i, e in enumerate(index):
            kw: dict[str, Any] = {f: z[f"{i}.{f}"] for f in _FIELDS}
            for a, spec in e["attrs"].items():
                values, distinct = z[f"{i}.{a}"], bool(spec["distinct"])
                if spec["layout"] == "corner":
                    kw[a] = CornerValues.per_corner(values, distinct)
                elif spec["layout"] == "point":
                    kw[a] = CornerValues(values, None, distinct)
                else:
                    kw[a] = CornerValues(values, z[f"{i}.{a}.indices"], distinct)
            mesh = Mesh(name=e["mesh_name"], **kw)
            out.append(AssetMesh(e["part"], e["name"], mesh, e["tags"]))
    return out


def cached_meshes(
    tag: str, opts: object, produce: Callable[[], list[AssetMesh]], *, extra: str = ""
) -> tuple[list[AssetMesh], bool]:
    """``produce()``'s meshes, from the cache when ``(tag, opts, extra)`` and the code match.

    Returns the meshes and whether they came from the cache. Produced meshes are returned at
    once and written to the cache by a background thread (the arrays' writes, CRCs, SHA-256
    and fsync release the GIL: it overlaps the caller's authoring); :func:`wait_for_writes`
    joins it. A cache that cannot be written (read-only or full disk) is no error: the meshes
    are returned all the same.
    """
    from ionic_usd.io import cache_intact

    entry = mesh_cache_folder() / _key(tag, opts, extra)
    if cache_intact(entry):
        try:
            return _read(entry), True
        except (OSError, ValueError, KeyError) as exc:  # unreadable despite its manifest
            log.info("mesh cache entry %s unreadable (%s); rebuilding", entry, exc)
    meshes = produce()
    writer = threading.Thread(target=_store, args=(entry, meshes), name="ionic_usd mesh cache")
    _WRITERS.append(writer)
    writer.start()
    return meshes, False


# cache writes still running (each joined by wait_for_writes; non-daemon: the interpreter
# also waits for them at exit, so an entry is never cut short by a normal exit)
_WRITERS: list[threading.Thread] = []


def _store(entry: Path, meshes: list[AssetMesh]) -> None:
    from ionic_usd.io import verified_cache

    try:
        verified_cache(entry, lambda tmp: _write(tmp, meshes))
    except Exception as exc:  # noqa: BLE001 (an optional cache: the build goes on without it)
        log.info("mesh cache not written (%s: %s); building without it", type(exc).__name__, exc)


def wait_for_writes() -> None:
    """Wait until every mesh cache entry this process started writing is in place."""
    while _WRITERS:
        _WRITERS.pop().join()
