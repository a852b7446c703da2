"""Safe writing: one atomic file writer, one kill-safe folder update, one verified cache.

Every module that writes goes through here, so the guarantees hold everywhere:

* :func:`atomic_path` / :func:`atomic_write_bytes` — a file appears whole or not at all: it is
  written to a temporary sibling (same extension, so writers pick the format by it), flushed to
  disk (``fsync``), optionally verified, then renamed over the target and the folder synced.
* :func:`replace_folder` — (re)build a generated folder without losing anything: a build runs
  in a staging sibling; a journal written into the staging folder then lists what moves in
  (leaves first, the root layer last) and which previously generated files are obsolete. Only
  files this package generated (listed in the folder's manifest) are ever replaced or deleted;
  the user's own files (``notes.txt``, ``Textures/my_decal.png``, a symlinked
  ``overrides.usda``) are left alone and never read. A process killed at any instant leaves
  either the old folder, or a journal that the next run rolls forward; staging folders of dead
  runs are removed.
* :func:`verified_cache` — a cache entry is a folder with a SHA-256 manifest written last;
  reading verifies every file and rebuilds on any mismatch, writing is atomic (rename of a
  complete folder).
* :func:`check_output_file` / :func:`check_output_folder` — refuse unusable outputs before any
  work: an empty name (``.``), a name too long for the file system, a parent that is a file, a
  read-only or missing-permission folder.
"""

from __future__ import annotations

import contextlib
import errno
import hashlib
import json
import os
import re
import secrets
import shutil
from collections.abc import Callable, Iterable, Iterator, Sequence
from pathlib import Path
from typing import Any

from ionic_usd.errors import OutputExistsError, ParameterError
from ionic_usd.sync import _fsync_dir, _fsync_file

__all__ = [
    "MANIFEST_NAME",
    "atomic_path",
    "atomic_write_bytes",
    "check_output_file",
    "check_output_folder",
    "cache_intact",
    "clean_stale_temporaries",
    "generated_files",
    "manifest_record",
    "up_to_date",
    "recover_folder",
    "removed_if_failed",
    "replace_folder",
    "sha256_file",
    "verified_cache",
]

MANIFEST_NAME = ".ionic_usd-manifest.json"  # the files a folder's last build generated
_JOURNAL = ".ionic_usd-journal.json"  # in a staging folder: written when the build is complete
_TMP_TAG = "ionic-tmp"
_STAGE_TAG = "ionic-build"
# temporaries of this package: .<name>.ionic-tmp-<pid>-<hex><suffix> (files) and
# .<name>.ionic-build-<pid>-<hex> (staging folders)
_OURS = re.compile(rf"^\.(?P<name>.+)\.(?P<tag>{_TMP_TAG}|{_STAGE_TAG})-(?P<pid>\d+)-[0-9a-f]{{8}}")
# temporaries of ionic_usd < 0.2 (tempfile.mkdtemp(prefix=".X.") and ".X.old-PID")
_LEGACY = re.compile(r"^\.(?P<name>.+)\.(?:old-(?P<pid>\d+)|[a-z0-9_]{8})$")


# -- small helpers ---------------------------------------------------------------------------
def _pid_alive(pid: int) -> bool:
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def _tmp_sibling(path: Path, tag: str = _TMP_TAG) -> Path:
    # keep the extension: USD and OpenImageIO choose the format by it
    stem = path.name[:100]
    return path.with_name(f".{stem}.{tag}-{os.getpid()}-{secrets.token_hex(4)}{path.suffix}")


@contextlib.contextmanager
def removed_if_failed(*folders: str | os.PathLike) -> Iterator[None]:
    """Folders the block is about to create, taken away again if it raises.

    Of ``folders``, those that do not exist yet are noted; on an exception every empty folder
    inside them, and then each of them, is removed (``rmdir``, deepest first: a folder holding
    any file stays, so nothing but this block's empty folders can go). A refusal half-way (a
    full disk) then leaves the output as it was.
    """
    new = [Path(f) for f in folders if not os.path.lexists(f)]
    try:
        yield
    except BaseException:
        for top in sorted(new, key=lambda p: len(p.parts), reverse=True):
            if not top.is_dir() or top.is_symlink():
                continue
            for d, _, _ in sorted(os.walk(top), key=lambda w: len(w[0]), reverse=True):
                with contextlib.suppress(OSError):
                    os.rmdir(d)
        raise


def sha256_file(path: str | os.PathLike) -> str:
    """Hex SHA-256 of a file's bytes."""
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for chunk in iter(lambda: fh.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


# -- output checks -----------------------------------------------------------------------------
def _name_max(folder: Path) -> int:
    try:
        return int(os.pathconf(folder, "PC_NAME_MAX"))
    except (OSError, ValueError):
        return 255


def _existing_ancestor(p: Path) -> Path:
    q = p
    while not q.exists() and q != q.parent:
        q = q.parent
    return q


def _check_target(p: Path, what: str) -> Path:
    name = p.name
    if name in ("", ".", "..") or p.parts[-1:] in ((".",), ("..",)):
        raise ParameterError(
            what, str(p), "a path ending in a file or folder name (not '.', '..' or '/')"
        )
    if any(ord(c) < 32 or ord(c) == 127 for c in str(p)):
        # USD asset paths cannot hold control characters: such a file does not reopen
        raise ParameterError(what, str(p), "a path without control characters (newline, tab…)")
    parent = p.parent
    anc = _existing_ancestor(parent)
    if not anc.is_dir():
        raise ParameterError(what, str(p), f"a path inside a folder ({anc} is a file)")
    limit = _name_max(anc)
    for part in p.parts:
        if len(os.fsencode(part)) > limit:
            raise ParameterError(
                what,
                str(p)[:60] + "…",
                f"names of at most {limit} bytes (one has {len(os.fsencode(part))})",
            )
    if not os.access(anc, os.W_OK | os.X_OK):
        reason = "read-only file system" if _read_only_fs(anc) else "permission denied"
        raise ParameterError(what, str(p), f"a writable location ({anc}: {reason})")
    return p


def _read_only_fs(folder: Path) -> bool:
    try:
        return bool(os.statvfs(folder).f_flag & os.ST_RDONLY)
    except OSError:
        return False


def check_output_file(
    path: str | os.PathLike,
    *,
    force: bool = False,
    what: str = "output",
    suffixes: Sequence[str] | None = None,
) -> Path:
    """Refuse an output file that cannot be written, before any work is done.

    Refused: an extension not in ``suffixes`` (lower-case, with the dot; None: any); a name
    that is empty, ``.`` or ``..``; a name longer than the file system allows; a parent that
    is a file; a location that is read-only; an existing folder; an existing file unless
    ``force``.
    """
    if suffixes is not None and Path(path).suffix.lower() not in suffixes:
        raise ParameterError(what, str(path), f"a file ending in one of {', '.join(suffixes)}")
    p = _check_target(Path(path), what)
    if p.is_dir():
        raise ParameterError(what, str(p), "a file path (this is an existing folder)")
    if p.exists() and not force:
        raise OutputExistsError(f"{p} exists; pass --force to overwrite it")
    return p


def check_output_folder(
    path: str | os.PathLike, *, force: bool = False, what: str = "output"
) -> Path:
    """Refuse an output folder that cannot be written (as :func:`check_output_file`).

    An existing folder needs ``force``; an existing file of that name is always refused.
    """
    p = _check_target(Path(path), what)
    if p.exists() and not p.is_dir():
        raise ParameterError(what, str(p), "a folder path (this is an existing file)")
    if p.exists() and not force:
        raise OutputExistsError(f"{p} exists; pass --force to rebuild it")
    if p.is_dir() and not os.access(p, os.W_OK | os.X_OK):
        # an immutable or read-only folder: refused before the build, not after it
        raise ParameterError(what, str(p), "a folder this process can write (permission denied)")
    return p


# -- one atomic file writer ------------------------------------------------------------------
@contextlib.contextmanager
def atomic_path(
    path: str | os.PathLike, *, verify: Callable[[Path], None] | None = None
) -> Iterator[Path]:
    """Yield a temporary sibling of ``path`` to write; on success it replaces ``path``.

    The temporary file keeps ``path``'s extension. After the block: the file is synced to
    disk, ``verify(tmp)`` runs (it raises to reject what was written — e.g. a PNG truncated by
    a full disk), then the file is renamed over ``path`` and the folder synced. On any error
    the temporary file is removed and ``path`` is untouched.
    """
    p = Path(path)
    clean_stale_temporaries(p.parent, p.name)  # left by a killed earlier write of this file
    tmp = _tmp_sibling(p)
    try:
        yield tmp
        if not tmp.is_file():
            raise OSError(errno.EIO, "nothing was written", str(p))
        _fsync_file(tmp)
        if verify is not None:
            verify(tmp)
        os.replace(tmp, p)
        _fsync_dir(p.parent)
    finally:
        with contextlib.suppress(OSError):
            tmp.unlink()


def atomic_write_bytes(path: str | os.PathLike, data: bytes) -> Path:
    """Write ``data`` to ``path`` atomically (see :func:`atomic_path`)."""
    p = Path(path)
    with atomic_path(p) as tmp, open(tmp, "wb") as fh:
        fh.write(data)
    return p


def clean_stale_temporaries(folder: str | os.PathLike, name: str | None = None) -> list[Path]:
    """Remove this package's temporary files/folders in ``folder`` left by dead processes.

    ``name`` restricts to temporaries of that entry. Staging folders holding a complete
    journal are not removed here (:func:`replace_folder` rolls them forward). Returns what was
    removed.
    """
    removed: list[Path] = []
    try:
        entries = list(os.scandir(os.fspath(folder)))
    except OSError:
        return removed
    for e in entries:
        m = _OURS.match(e.name)
        if not m or (name is not None and m["name"] != name[:100]):
            continue
        if _pid_alive(int(m["pid"])):
            continue
        p = Path(e.path)
        if e.is_dir(follow_symlinks=False):
            if (p / _JOURNAL).is_file():
                continue
            shutil.rmtree(p, ignore_errors=True)
        else:
            with contextlib.suppress(OSError):
                p.unlink()
        removed.append(p)
    return removed


# -- one kill-safe folder update -------------------------------------------------------------
def generated_files(folder: str | os.PathLike) -> list[str]:
    """The relative paths the last build generated in ``folder`` (from its manifest)."""
    try:
        data = json.loads((Path(folder) / MANIFEST_NAME).read_text("utf-8"))
        files = data["files"]
        if isinstance(files, list) and all(isinstance(f, str) for f in files):
            return [f for f in files if _safe_rel(f)]
    except (OSError, ValueError, KeyError, TypeError):
        pass
    return []


def _safe_rel(rel: str) -> bool:
    parts = Path(rel).parts
    return bool(parts) and not Path(rel).is_absolute() and ".." not in parts


def _list_files(root: Path) -> list[str]:
    out = []
    for dirpath, _dirs, files in os.walk(root):
        for f in files:
            rel = os.path.relpath(os.path.join(dirpath, f), root)
            if rel not in (_JOURNAL, MANIFEST_NAME):
                out.append(rel)
    return out


def _move_order(rels: Iterable[str], root_files: Iterable[str]) -> list[str]:
    """Deepest files first, the root layers last: a reader sees the new root only when every
    file it refers to is in place."""
    last = set(root_files)
    return sorted(rels, key=lambda r: (r in last, -r.count(os.sep), r))


def _roll_forward(stage: Path, dest: Path) -> None:
    """Finish a committed update: idempotent, so a kill during it is finished next time."""
    journal = json.loads((stage / _JOURNAL).read_text("utf-8"))
    dest.mkdir(parents=True, exist_ok=True)
    for rel in journal["move"]:
        src, dst = stage / rel, dest / rel
        if not os.path.lexists(src):
            continue  # moved before a kill
        dst.parent.mkdir(parents=True, exist_ok=True)
        if rel in journal["keep_existing"]:
            # never replace the user's file (or symlink); link() fails if it exists
            with contextlib.suppress(FileExistsError):
                os.link(src, dst)
            os.unlink(src)
            continue
        if os.path.isdir(dst) and not os.path.islink(dst):
            raise OSError(errno.EISDIR, "a folder is in the way of a generated file", str(dst))
        os.replace(src, dst)
    for rel in journal["obsolete"]:
        p = dest / rel
        if os.path.lexists(p) and not os.path.isdir(p):
            with contextlib.suppress(OSError):
                p.unlink()
            if p.parent != dest:  # a folder it emptied goes too (rmdir refuses a full one)
                with contextlib.suppress(OSError):
                    p.parent.rmdir()
    manifest = journal.get("manifest", {"files": journal["files"]})
    atomic_write_bytes(dest / MANIFEST_NAME, json.dumps(manifest, indent=1).encode())
    _fsync_dir(dest)
    shutil.rmtree(stage, ignore_errors=True)


def up_to_date(dest: str | os.PathLike, key: str) -> dict | None:
    """The record of the build that made ``dest`` if it was a build of ``key`` and every file
    it generated is there with the bytes it wrote (SHA-256 against its manifest); else None.

    An interrupted update is finished (or discarded) first. The user's files (those the build
    did not generate, ``overrides.usda``) do not enter: they are theirs to edit.
    """
    dest = Path(dest)
    if not dest.is_dir():
        return None
    recover_folder(dest)
    try:
        manifest = json.loads((dest / MANIFEST_NAME).read_text("utf-8"))
        if manifest.get("key") != key:
            return None
        sums = manifest["sha256"]
        if set(sums) != set(manifest["files"]) or not _files_intact(dest, sums):
            return None
        record = manifest.get("record", {})
        return record if isinstance(record, dict) else None
    except (OSError, ValueError, KeyError, TypeError, AttributeError):
        return None


def manifest_record(dest: str | os.PathLike) -> tuple[str | None, dict, dict[str, str]]:
    """The key, record and SHA-256 per generated file of ``dest``'s last build (None, {}, {}
    when it kept none): what a build may reuse from it after checking the files itself."""
    try:
        m = json.loads((Path(dest) / MANIFEST_NAME).read_text("utf-8"))
        sums = {r: h for r, h in m.get("sha256", {}).items() if _safe_rel(r)}
        return m.get("key"), dict(m.get("record", {})), sums
    except (OSError, ValueError, KeyError, TypeError, AttributeError):
        return None, {}, {}


def recover_folder(dest: str | os.PathLike) -> None:
    """Finish or discard interrupted updates of ``dest`` and remove stale temporaries."""
    dest = Path(dest)
    parent = dest.parent if str(dest.parent) else Path(".")
    try:
        entries = list(os.scandir(parent))
    except OSError:
        return
    for e in entries:
        m = _OURS.match(e.name)
        if (
            m
            and m["name"] == dest.name[:100]
            and m["tag"] == _STAGE_TAG
            and not _pid_alive(int(m["pid"]))
            and (Path(e.path) / _JOURNAL).is_file()
        ):
            _roll_forward(Path(e.path), dest)
        legacy = _LEGACY.match(e.name)
        if legacy and legacy["name"] == dest.name and e.is_dir(follow_symlinks=False):
            pid = legacy["pid"]
            if pid is not None and _pid_alive(int(pid)):
                continue
            p = Path(e.path)
            if pid is not None and not dest.exists():
                os.replace(p, dest)  # killed between the two renames of ionic_usd < 0.2
            elif pid is not None or _looks_generated(p):
                shutil.rmtree(p, ignore_errors=True)
    clean_stale_temporaries(parent, dest.name)
    from ionic_usd.lockfile import remove_stale_lock

    remove_stale_lock(dest)  # a killed build's lock file (the kernel released its lock)


def _looks_generated(p: Path) -> bool:
    try:
        names = {c.name for c in p.iterdir()}
    except OSError:
        return False
    return (
        not names
        or bool(names & {"Temple.usda", "Payload", "IonicColumn"})
        or any(n.endswith(".usda") for n in names)
    )


def replace_folder(
    build: Callable[[Path], object],
    dest: str | os.PathLike,
    *,
    force: bool = False,
    keep_existing: Iterable[str] = (),
    root_files: Iterable[str] = (),
    key: str | None = None,
    record: Callable[[Any], dict] | None = None,
):
    """Build a generated folder in a staging sibling and move it into ``dest`` kill-safely.

    Parameters
    ----------
    build : ``build(stage_folder)`` writes every generated file; its result is returned
    dest : the output folder; an existing one needs ``force``
    keep_existing : relative paths created only when absent (the user's layer): an existing
        file or symlink there is never read, replaced or deleted
    root_files : relative paths moved last (the layers a user opens)
    key : the build's content key (:func:`ionic_usd.pipeline.keys.build_key`), kept in the
        manifest with every generated file's SHA-256, so that :func:`up_to_date` can tell a
        later build of the same key that this folder is its output, intact
    record : ``record(result)``: a JSON-able summary of the build kept beside the key (what
        :func:`up_to_date` returns)

    Files in ``dest`` that the previous build did not generate are never touched; files the
    previous build generated and this one does not are deleted.
    """
    dest = Path(dest)
    check_output_folder(dest, force=True)
    parent = dest.parent
    parent.mkdir(parents=True, exist_ok=True)
    recover_folder(dest)
    if dest.exists() and not force:
        raise OutputExistsError(f"{dest} exists; pass --force to replace it")
    if dest.exists() and not dest.is_dir():
        raise ParameterError("output", str(dest), "a folder path (this is an existing file)")
    stage = _tmp_sibling(dest, _STAGE_TAG)
    stage.mkdir()
    try:
        result = build(stage)
        files = _list_files(stage)
        keep = [k for k in keep_existing if k in files]
        new = sorted(set(files) - set(keep))
        manifest: dict[str, Any] = {"files": new}
        if key is not None:
            manifest["key"] = key
            manifest["sha256"] = {rel: sha256_file(stage / rel) for rel in new}
            manifest["record"] = record(result) if record is not None else {}
        for rel in files:
            _fsync_file(stage / rel)
        if not dest.exists():
            # a new folder appears whole with one rename
            atomic_write_bytes(stage / MANIFEST_NAME, json.dumps(manifest, indent=1).encode())
            _fsync_dir(stage)
            os.replace(stage, dest)
            _fsync_dir(parent)
            return result
        old = generated_files(dest)
        journal = {
            "move": _move_order(files, root_files),
            "keep_existing": keep,
            "obsolete": sorted(set(old) - set(new) - set(keep)),
            "files": new,
            "manifest": manifest,
        }
        atomic_write_bytes(stage / _JOURNAL, json.dumps(journal, indent=1).encode())
        _fsync_dir(stage)
    except BaseException:
        shutil.rmtree(stage, ignore_errors=True)
        raise
    # committed: from here on a kill is finished by the next run (recover_folder)
    try:
        _roll_forward(stage, dest)
    except OSError:
        if all(os.path.lexists(stage / r) for r in journal["move"]):
            shutil.rmtree(stage, ignore_errors=True)  # nothing moved yet: nothing to finish
        raise
    return result


def verified_cache(
    entry: str | os.PathLike,
    produce: Callable[[Path], object],
    verify: Callable[[Path], None] | None = None,
) -> Path:
    """A cache entry folder that is complete and intact, producing it when it is not.

    ``produce(folder)`` writes the entry's files. They are checked with ``verify(file)`` (which
    raises on a bad file), hashed into a manifest written last, and the folder is renamed into
    place. Reading re-hashes every file against the manifest: a truncated, edited or garbage
    entry is discarded and produced again. Raises ``OSError`` when the cache cannot be written.
    """
    entry = Path(entry)
    if _cache_ok(entry):
        return entry
    entry.parent.mkdir(parents=True, exist_ok=True)
    clean_stale_temporaries(entry.parent, entry.name)
    stage = _tmp_sibling(entry, _STAGE_TAG)
    stage.mkdir()
    try:
        produce(stage)
        sums = {}
        for rel in sorted(_list_files(stage)):
            _fsync_file(stage / rel)
            if verify is not None:
                verify(stage / rel)
            sums[rel] = sha256_file(stage / rel)
        atomic_write_bytes(stage / MANIFEST_NAME, json.dumps({"sha256": sums}).encode())
        _fsync_dir(stage)
        if os.path.lexists(entry):
            # another process may have finished the entry while this one produced it, and
            # may be reading it now: a good entry is kept (replacing it deleted the files
            # under that reader: a city's parallel builds, copying the stone maps)
            if _cache_ok(entry):
                return entry
            aside = _tmp_sibling(entry, _STAGE_TAG)  # a bad entry: move it aside, delete it
            os.replace(entry, aside)
            shutil.rmtree(aside, ignore_errors=True)
        try:
            os.replace(stage, entry)
        except OSError:
            if _cache_ok(entry):  # another process renamed its entry into place first
                return entry
            raise
        _fsync_dir(entry.parent)
    finally:
        shutil.rmtree(stage, ignore_errors=True)
    return entry


def _files_intact(root: Path, sums: dict[str, str]) -> bool:
    """Whether every file of ``sums`` (relative path → SHA-256) is a regular file below
    ``root`` with those bytes (a symlink is not the file a build wrote)."""
    for rel, digest in sums.items():
        p = root / rel
        if not _safe_rel(rel) or p.is_symlink() or not p.is_file() or sha256_file(p) != digest:
            return False
    return True


def cache_intact(entry: str | os.PathLike) -> bool:
    """Whether a :func:`verified_cache` entry is complete and every file matches its manifest
    (what :func:`verified_cache` checks before it returns an entry without producing it)."""
    return _cache_ok(Path(entry))


def _cache_ok(entry: Path) -> bool:
    try:
        sums = json.loads((entry / MANIFEST_NAME).read_text("utf-8"))["sha256"]
        if not sums:
            return False
        on_disk = set(_list_files(entry))
        if on_disk != set(sums):
            return False
        return _files_intact(entry, sums)
    except (OSError, ValueError, KeyError, TypeError, AttributeError):
        return False
