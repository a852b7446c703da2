"""Getting written files to the disk (``fsync``), and the scratch writes that need not.

:mod:`ionic_usd.io` syncs every atomic write (the file, then its folder) before the rename;
:func:`scratch_writes` lifts that for builds into a temporary folder that is read back and
deleted.
"""

from __future__ import annotations

import contextlib
import os
from pathlib import Path

__all__ = ["scratch_writes"]

#: writes into a scratch folder that is read back and deleted need no trip to the disk
#: (:func:`scratch_writes`); a finished output always gets one
_SCRATCH = {"depth": 0}


@contextlib.contextmanager
def scratch_writes():
    """Within this block (this process, its thread pools too), atomic writes skip ``fsync``:
    for builds into a temporary folder whose files are read back and deleted (a Dask task's
    temple), where durability buys nothing and two builds side by side would queue on the
    disk. The rename stays atomic."""
    _SCRATCH["depth"] += 1
    try:
        yield
    finally:
        _SCRATCH["depth"] -= 1


def _fsync_dir(folder: Path) -> None:
    if _SCRATCH["depth"]:
        return
    try:
        fd = os.open(folder, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass  # some file systems cannot sync a directory; the rename is still atomic
    finally:
        os.close(fd)


def _fsync_file(path: Path) -> None:
    if _SCRATCH["depth"]:
        return
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)
