"""An output folder's lock file, ``.<name>.ionic-lock`` beside it: its path, and its removal
once no process holds it (:mod:`ionic_usd.outputs` takes the lock; :mod:`ionic_usd.io`
removes a killed build's). Standard library only."""

from __future__ import annotations

import os
from pathlib import Path

__all__ = ["LOCK_SUFFIX", "lock_path", "remove_stale_lock"]

LOCK_SUFFIX = ".ionic-lock"


def lock_path(dest: str | os.PathLike) -> Path:
    d = Path(dest)
    return d.with_name(f".{d.name[:100]}{LOCK_SUFFIX}")


def remove_stale_lock(dest: str | os.PathLike) -> bool:
    """Remove ``dest``'s lock file if no process holds it (its holder was killed); True if
    removed. Safe against a racing builder: it re-checks the file it locked is at the path."""
    import fcntl

    path = lock_path(dest)
    try:
        fd = os.open(path, os.O_RDWR)
    except OSError:
        return False
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:  # held (by another process, or by this one on another descriptor)
        os.close(fd)
        return False
    try:
        if os.stat(path).st_ino == os.fstat(fd).st_ino:
            os.unlink(path)
            return True
        return False
    except OSError:
        return False
    finally:
        os.close(fd)
