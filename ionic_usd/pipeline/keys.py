"""Content keys: what a generated file depends on, hashed, so that a build can tell it is current.

A generated output is a pure function of its inputs (frozen dataclasses of numbers, strings and
tuples, whose ``repr`` is stable across runs), of the code that generates it and of the
libraries that code calls. :func:`build_key` hashes all three: the inputs' ``repr``, the package
version, :func:`source_digest` (every module and data file of the installed package, names and
bytes) and :func:`library_versions` (the runtime dependencies' versions). So an edit of the
generators — released or not — or an upgraded usd-core changes every key, and nothing stale is
ever reused.

This module imports nothing heavy (no numpy, no ``pxr``): a command can decide that its output is
current before it loads the libraries that would rebuild it.
"""

from __future__ import annotations

import hashlib
from functools import lru_cache
from importlib import metadata
from pathlib import Path
from typing import TYPE_CHECKING

from ionic_usd import __version__

if TYPE_CHECKING:
    from ionic_usd.blueprint.column_asset import ColumnAssetOptions

__all__ = ["asset_key", "build_key", "file_digests", "library_versions", "source_digest"]

#: the distributions whose code makes the geometry, the charts, the maps and the files
LIBRARIES = (
    "usd-core",
    "numpy",
    "scipy",
    "numba",
    "shapely",
    "manifold3d",
    "xatlas",
    "OpenImageIO",
)


@lru_cache(maxsize=1)
def source_digest() -> str:
    """SHA-256 of every ``.py`` and data (``.toml``) file of the installed package, with their
    relative names, in sorted order."""
    root = Path(__file__).resolve().parents[1]
    h = hashlib.sha256()
    files = [*root.rglob("*.py"), *(root / "data").glob("*.toml")]
    for f in sorted(files):
        h.update(str(f.relative_to(root)).encode())
        h.update(b"\0")
        h.update(f.read_bytes())
    return h.hexdigest()


@lru_cache(maxsize=1)
def library_versions() -> str:
    """``name==version`` of each runtime library (``name==absent`` when not installed)."""
    out = []
    for name in LIBRARIES:
        try:
            out.append(f"{name}=={metadata.version(name)}")
        except metadata.PackageNotFoundError:
            out.append(f"{name}==absent")
    return ";".join(out)


def file_digests(paths: object) -> list[str]:
    """SHA-256 of each file a mapping names (e.g. the user's textures, whose bytes make the
    maps), in its order; ``unreadable:<path>`` for a file that cannot be read."""
    out = []
    for p in dict(paths or {}).values():  # type: ignore[call-overload]
        try:
            out.append(hashlib.sha256(Path(p).read_bytes()).hexdigest())
        except OSError:
            out.append(f"unreadable:{p}")
    return out


def build_key(tag: str, *inputs: object) -> str:
    """A 32-hex-digit key of ``tag``, the inputs' ``repr``, the version, the code and the
    libraries."""
    h = hashlib.sha256()
    for part in (tag, *map(repr, inputs), __version__, source_digest(), library_versions()):
        h.update(part.encode())
        h.update(b"\0")
    return h.hexdigest()[:32]


def asset_key(opts: ColumnAssetOptions) -> str:
    """The content key of a column asset build: its options, the bytes of the user's
    textures, the code and the libraries (:func:`build_key`)."""
    return build_key("column_asset", opts, file_digests(opts.user_textures))
