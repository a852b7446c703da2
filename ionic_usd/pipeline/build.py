"""Build prototypes on Dask, through a content-addressed cache.

Who writes what
---------------
Workers **return bytes**; the client alone writes files. A build task composes the temple in a
private temporary folder on the worker, reads every file back and returns ``{relative path:
bytes}`` (a temple at 1024 px textures is ~30 MB). So a cluster needs no shared filesystem, a
worker can never leave a half-written folder in the output, and the output cannot depend on
which worker built what, or how many there were: the client writes each result into the cache
(temporary folder + rename, with a SHA-256 manifest) and copies verified cache entries into
the city. Workers must run the same ionic_usd version as the client (checked: the version is
part of every cache key, and a worker with another version is an error).

Scheduling
----------
``scheduler=None`` starts a ``distributed.LocalCluster`` with one single-threaded worker
process per core (xatlas and USD authoring hold the GIL, so processes, not threads), only
when two or more builds are missing (a single one is built in-process: a cluster of one
would only add its start-up); ``scheduler="tcp://HOST:PORT"`` uses an existing cluster
(``dask scheduler`` + ``dask worker``s that can import ionic_usd).
"""

from __future__ import annotations

import hashlib
import json
import logging
import os
import shutil
import tempfile
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

from ionic_usd.errors import IonicError, ParameterError, UsdAuthoringError
from ionic_usd.pipeline.spec import TempleSpec

__all__ = [
    "PrototypeCache",
    "BuildResult",
    "build_temple_files",
    "build_prototypes",
    "default_prototype_cache",
]

_MANIFEST = "manifest.json"
CONNECT_TIMEOUT = "10s"  # to reach an existing scheduler


def default_prototype_cache() -> Path:
    """``$IONIC_USD_CACHE/prototypes``, else ``$XDG_CACHE_HOME/ionic_usd/prototypes``."""
    root = os.environ.get("IONIC_USD_CACHE")
    if root:
        return Path(root).expanduser() / "prototypes"
    xdg = os.environ.get("XDG_CACHE_HOME")
    return (Path(xdg).expanduser() if xdg else Path.home() / ".cache") / "ionic_usd" / "prototypes"


def build_temple_files(spec: TempleSpec) -> tuple[dict[str, bytes], str, str, float]:
    """Build one temple folder in a private temporary folder and return its files.

    Runs on a Dask worker (or in-process). Returns ``(files, worker address, ionic_usd
    version, seconds)``; ``files`` maps ``/``-separated relative paths to bytes.
    """
    from ionic_usd import __version__
    from ionic_usd.column.column import column_params_from_mapping, portunus_column_params
    from ionic_usd.pipeline.temple import compose_temple

    t0 = time.perf_counter()
    data = spec.tables()
    col_tables = {k: data.pop(k) for k in ("column", "shaft", "capital", "volute") if k in data}
    layout = spec.layout()
    p = layout.params
    column = portunus_column_params(
        height=p.columns_height, lower_diameter=p.columns_lower_diameter
    )
    if col_tables:
        column = column_params_from_mapping(col_tables, context=f"temple {spec.name}", base=column)
    from ionic_usd.sync import scratch_writes

    # a scratch folder, read back and deleted: its writes need not reach the disk (the
    # client's install of these bytes does, atomically and synced)
    with tempfile.TemporaryDirectory(prefix="ionic_usd_build_") as tmp, scratch_writes():
        root = Path(tmp) / "Temple"
        compose_temple(root, layout, column, texture_size=spec.texture_size, seed=spec.seed)
        files = {
            f.relative_to(root).as_posix(): f.read_bytes()
            for f in sorted(root.rglob("*"))
            if f.is_file()
        }
    try:
        from distributed import get_worker

        address = get_worker().address
    except (ImportError, ValueError):
        address = "local"
    return files, address, __version__, time.perf_counter() - t0


@dataclass
class PrototypeCache:
    """Temple builds by content key: ``<folder>/<key>/`` + a SHA-256 manifest."""

    folder: Path = field(default_factory=default_prototype_cache)

    def path(self, spec: TempleSpec) -> Path:
        return Path(self.folder) / spec.key

    def has(self, spec: TempleSpec) -> bool:
        return (self.path(spec) / _MANIFEST).is_file()

    def put(self, spec: TempleSpec, files: dict[str, bytes]) -> Path:
        """Store a build atomically (temporary sibling + rename); returns its folder."""
        dest = self.path(spec)
        if self.has(spec):
            return dest
        dest.parent.mkdir(parents=True, exist_ok=True)
        tmp = Path(tempfile.mkdtemp(prefix=f".{spec.key[:12]}.", dir=dest.parent))
        try:
            manifest = {}
            for rel, data in files.items():
                f = tmp / rel
                f.parent.mkdir(parents=True, exist_ok=True)
                f.write_bytes(data)
                manifest[rel] = hashlib.sha256(data).hexdigest()
            (tmp / _MANIFEST).write_text(json.dumps(manifest, sort_keys=True, indent=0))
            if dest.exists():  # an incomplete entry (no manifest) from an interrupted run
                shutil.rmtree(dest)
            os.replace(tmp, dest)
        finally:
            if tmp.exists():
                shutil.rmtree(tmp, ignore_errors=True)
        return dest

    def install(self, spec: TempleSpec, dest: Path) -> None:
        """Copy a cached build to ``dest`` (verified against its manifest; atomically)."""
        src = self.path(spec)
        manifest = json.loads((src / _MANIFEST).read_text())
        if dest.exists() and _matches(dest, manifest):
            return
        dest.parent.mkdir(parents=True, exist_ok=True)
        tmp = Path(tempfile.mkdtemp(prefix=f".{dest.name}.", dir=dest.parent))
        try:
            for rel, digest in sorted(manifest.items()):
                data = (src / rel).read_bytes()
                if hashlib.sha256(data).hexdigest() != digest:
                    raise UsdAuthoringError(
                        f"prototype cache entry {src} is corrupt ({rel}); delete it and build again"
                    )
                f = tmp / rel
                f.parent.mkdir(parents=True, exist_ok=True)
                f.write_bytes(data)
            os.chmod(tmp, 0o755)
            if dest.exists():
                shutil.rmtree(dest)
            os.replace(tmp, dest)
        finally:
            if tmp.exists():
                shutil.rmtree(tmp, ignore_errors=True)


def _matches(folder: Path, manifest: dict[str, str]) -> bool:
    have = {f.relative_to(folder).as_posix() for f in folder.rglob("*") if f.is_file()}
    if have != set(manifest):
        return False
    return all(
        hashlib.sha256((folder / r).read_bytes()).hexdigest() == d for r, d in manifest.items()
    )


@dataclass(frozen=True)
class BuildResult:
    """What :func:`build_prototypes` did."""

    built: tuple[str, ...]  # keys built now
    reused: tuple[str, ...]  # keys found in the cache
    workers: tuple[str, ...]  # addresses of the workers that built prototypes
    n_workers: int  # workers of the cluster used (0: none started)
    seconds: float
    task_seconds: dict[str, float]  # key → build time on its worker


def _local_cluster(n_workers: int | None, n_builds: int):
    """A Dask LocalCluster on 127.0.0.1: one single-threaded worker process per build, at
    most ``n_workers`` (default: the machine's cores)."""
    from distributed import LocalCluster

    n = n_workers or os.cpu_count() or 1
    return LocalCluster(
        n_workers=min(n, n_builds),
        threads_per_worker=1,
        processes=True,
        host="127.0.0.1",
        dashboard_address=None,
        silence_logs=logging.ERROR,
    )


def _client(cluster, scheduler: str | None):
    """A client of the local ``cluster``, or of the scheduler at ``scheduler`` (refused with
    a ParameterError when it cannot be reached)."""
    from distributed import Client

    if scheduler is None:
        return Client(cluster)
    try:
        return Client(scheduler, timeout=CONNECT_TIMEOUT)
    except (OSError, TimeoutError, ValueError, TypeError) as exc:
        raise ParameterError(
            "--scheduler",
            scheduler,
            f"a reachable Dask scheduler tcp://HOST:PORT ({type(exc).__name__}: {exc})",
        ) from None


def _build_on(client, todo, cache, progress) -> tuple[int, set[str], dict]:
    """Every build of ``todo`` submitted to ``client`` and put into ``cache`` as it
    completes: (the workers the scheduler had, the workers that built, seconds per build)."""
    from distributed import as_completed

    nw = len(client.scheduler_info().get("workers", {}))
    if nw == 0:
        client.wait_for_workers(1, timeout=60)
        nw = len(client.scheduler_info().get("workers", {}))
    futures = [
        client.submit(build_temple_files, s, key=f"temple-{s.key}", pure=False) for s in todo
    ]
    by_key = {f.key: s for f, s in zip(futures, todo, strict=True)}
    workers: set[str] = set()
    task_seconds: dict[str, float] = {}
    from ionic_usd.progress import progress as bar_over

    with bar_over(len(futures), "building temple prototypes (Dask)", unit="temple") as bar:
        for fut in as_completed(futures):
            _take(fut, by_key, cache, workers, task_seconds, progress)
            bar.update(1)
    return nw, workers, task_seconds


def build_prototypes(
    specs: Sequence[TempleSpec],
    *,
    cache: PrototypeCache | None = None,
    scheduler: str | None = None,
    n_workers: int | None = None,
    progress: Callable[[str], None] | None = None,
) -> BuildResult:
    """Make sure every spec is in the cache, building the missing ones on Dask.

    Parameters
    ----------
    specs : temple builds (duplicates are built once)
    cache : the prototype cache (default: :func:`default_prototype_cache`)
    scheduler : ``tcp://HOST:PORT`` of an existing Dask scheduler, or None for a LocalCluster
    n_workers : LocalCluster size (default: the machine's cores)
    """

    t0 = time.perf_counter()
    cache = cache or PrototypeCache()
    unique = {s.key: s for s in specs}
    todo = [s for k, s in sorted(unique.items()) if not cache.has(s)]
    reused = tuple(k for k, s in sorted(unique.items()) if cache.has(s))
    if not todo:
        return BuildResult((), reused, (), 0, time.perf_counter() - t0, {})
    if scheduler is None and len(todo) == 1 and not n_workers:
        # one build and no cluster asked for: a local cluster would add its start-up (~8 s on
        # two busy cores) and no parallelism; the bytes are the same either way
        files, address, _, secs = build_temple_files(todo[0])
        cache.put(todo[0], files)
        return BuildResult(
            (todo[0].key,),
            reused,
            ("in-process",),
            0,
            time.perf_counter() - t0,
            {todo[0].key: round(secs, 3)},
        )
    try:
        import distributed  # noqa: F401  (the city extra; the helpers below import from it)
    except ImportError:
        raise IonicError(
            "building prototypes on Dask needs distributed: pip install 'ionic_usd[city]'"
        ) from None

    cluster = None
    try:
        if scheduler is None:
            cluster = _local_cluster(n_workers, len(todo))
        client = _client(cluster, scheduler)
        with client:
            nw, workers, task_seconds = _build_on(client, todo, cache, progress)
    finally:
        if cluster is not None:
            cluster.close()
    return BuildResult(
        tuple(s.key for s in todo),
        reused,
        tuple(sorted(workers)),
        nw,
        time.perf_counter() - t0,
        task_seconds,
    )


def _take(
    fut,
    by_key: dict,
    cache: PrototypeCache,
    workers: set[str],
    task_seconds: dict[str, float],
    progress: Callable[[str], None] | None,
) -> None:
    """Store one finished prototype build in the cache (the client writes every byte)."""
    from ionic_usd import __version__

    files, address, version, secs = fut.result()
    spec = by_key[fut.key]
    if version != __version__:
        raise UsdAuthoringError(
            f"worker {address} runs ionic_usd {version}, the "
            f"client {__version__}: install the same version"
        )
    cache.put(spec, files)
    workers.add(address)
    task_seconds[spec.key] = round(secs, 3)
    fut.release()
    if progress:
        progress(f"built {spec.folder} on {address} ({secs:.1f} s)")
