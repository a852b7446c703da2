"""Output folders: a fresh folder built in a staging sibling and renamed in whole, and one
writer at a time (a lock beside the folder).

* :func:`staged_new_folder` — a folder that does not exist yet is built as
  ``.<name>.ionic-build-<pid>-<hex>`` and renamed to ``<name>`` when complete: a kill leaves
  no partial ``<name>`` (the staging folder of a dead process is removed by the next run,
  :func:`ionic_usd.io.clean_stale_temporaries`).
* :func:`folder_lock` — an exclusive ``fcntl.flock`` on ``.<name>.ionic-lock`` beside the
  folder (beside, not inside: the folder may not exist yet, and a staged build replaces it).
  A second process building into the same folder waits up to ``wait`` seconds, then is
  refused with a message naming the holder (pid and command line, written into the lock
  file). The kernel releases the lock when its holder dies, however it dies; the holder
  removes the file when it is done (a waiter checks it locked the file still at the path).
  A forked process pool's workers inherit the lock (``flock`` belongs to the open file, which
  a fork shares): they start with :func:`die_with_parent`, so a killed build leaves no orphan
  holding its folder's lock.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import sys
import time
from collections.abc import Iterator
from pathlib import Path

from ionic_usd.errors import IonicError
from ionic_usd.lockfile import LOCK_SUFFIX, lock_path, remove_stale_lock

__all__ = [
    "LOCK_SUFFIX",
    "die_with_parent",
    "FolderBusyError",
    "folder_lock",
    "lock_path",
    "remove_stale_lock",
    "staged_new_folder",
]

DEFAULT_WAIT = 0.0  # s: refuse at once (IONIC_USD_LOCK_WAIT=SECONDS waits)


def die_with_parent(parent: int) -> None:
    """In a forked pool worker: be killed when ``parent`` (the process that forked the pool)
    dies (Linux ``PR_SET_PDEATHSIG``), and exit at once if it died already. The worker shares
    the parent's folder lock; an orphan would hold it after the parent was killed."""
    if sys.platform.startswith("linux"):
        import ctypes
        import signal

        with contextlib.suppress(OSError, AttributeError):
            ctypes.CDLL(None, use_errno=True).prctl(1, signal.SIGKILL)  # PR_SET_PDEATHSIG
    if os.getppid() != parent:  # the parent died before the line above
        os._exit(0)


class FolderBusyError(IonicError):
    """Another process is building into the same output folder."""


def _holder(path: Path) -> str:
    try:
        text = path.read_text("utf-8", errors="replace").strip()
    except OSError:
        return "another process"
    return " ".join(text.split())[:200] or "another process"


@contextlib.contextmanager
def folder_lock(dest: str | os.PathLike, *, wait: float | None = None) -> Iterator[None]:
    """Hold the exclusive build lock of output folder ``dest`` for the block."""
    import fcntl

    if wait is None:
        try:
            wait = float(os.environ.get("IONIC_USD_LOCK_WAIT", DEFAULT_WAIT))
        except ValueError:
            wait = DEFAULT_WAIT
    path = lock_path(dest)
    path.parent.mkdir(parents=True, exist_ok=True)
    deadline = time.monotonic() + max(wait, 0.0)
    while True:
        fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            os.close(fd)
            if time.monotonic() >= deadline:
                raise FolderBusyError(
                    f"{dest} is being built by {_holder(path)} (lock {path}); wait for it to "
                    "finish or write elsewhere"
                ) from None
            time.sleep(0.1)
            continue
        try:  # the file we locked must still be the one at the path (a holder unlinks it)
            same = os.stat(path).st_ino == os.fstat(fd).st_ino
        except FileNotFoundError:
            same = False
        if same:
            break
        os.close(fd)
    try:
        argv = " ".join(["ionic-usd", *sys.argv[1:]])[:150]
        os.pwrite(fd, f"pid {os.getpid()} ({argv})\n".encode(), 0)
        yield
    finally:
        # unlinked while still held, so a waiter that locked the old file sees it is gone
        # and opens a new one: no lock file is left behind
        with contextlib.suppress(OSError):
            os.unlink(path)
        os.close(fd)


@contextlib.contextmanager
def staged_new_folder(dest: str | os.PathLike) -> Iterator[Path]:
    """Yield where to build ``dest``: itself if it exists (its files are replaced one by one
    atomically), else a staging sibling renamed to ``dest`` when the block succeeds and
    removed when it fails."""
    from ionic_usd.io import _STAGE_TAG, _fsync_dir, _tmp_sibling, clean_stale_temporaries

    dest = Path(dest)
    parent = dest.parent if str(dest.parent) else Path(".")
    clean_stale_temporaries(parent, dest.name)
    remove_stale_lock(dest)
    if dest.exists():
        yield dest
        return
    stage = _tmp_sibling(dest, _STAGE_TAG)
    parent.mkdir(parents=True, exist_ok=True)
    stage.mkdir()
    try:
        yield stage
        _fsync_dir(stage)
        os.rename(stage, dest)  # fails if dest appeared meanwhile: nothing is overwritten
        _fsync_dir(parent)
    except BaseException:
        shutil.rmtree(stage, ignore_errors=True)
        raise
