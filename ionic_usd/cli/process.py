"""Process settings of the ``ionic-usd`` command: made once, before the work, by :func:`tune`.

The command's jobs are parallel across processes (the asset's geometry pool, the texture
threads), so threads that numerical libraries start on their own only compete with them:

* **OpenBLAS** (numpy's and scipy's) starts a thread per core, which spin-wait after each
  call: on the 2-core machine ~3 % of the default temple's CPU time and ~10 % of a scan fit's,
  for no shorter wall time (``tools/bench_process.py``). One thread unless the user set
  ``OPENBLAS_NUM_THREADS``; only before numpy is loaded (the library reads it then). With
  one thread every product is also computed in one order on every machine.
* **glibc's malloc** returns freed blocks over 128 KiB (most mesh arrays) to the system and
  raises that threshold only as it sees them freed, so the same arrays are mapped and their
  pages zeroed again and again (~180 k page faults in the default temple). The command keeps
  up to 32 MiB blocks in its heap and returns its top only above 1 GiB free: ~30 % fewer page
  faults, ~3 % less CPU, ~16 MiB more peak memory. glibc only (``mallopt``); elsewhere,
  nothing.

A library user's process is left as it is: only the command line calls :func:`tune`.
"""

from __future__ import annotations

import os
import sys

__all__ = ["tune"]

#: glibc's mallopt parameters (malloc.h) and the values the command sets
_M_TRIM_THRESHOLD, _M_TOP_PAD, _M_MMAP_THRESHOLD = -1, -2, -3
_MALLOC = ((_M_MMAP_THRESHOLD, 32 << 20), (_M_TRIM_THRESHOLD, 1 << 30), (_M_TOP_PAD, 64 << 20))


def tune() -> None:
    """One OpenBLAS thread (if numpy is not loaded yet and the user chose none) and glibc's
    malloc keeping freed memory for reuse (see the module)."""
    if "numpy" not in sys.modules:
        os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    try:
        glibc = os.confstr("CS_GNU_LIBC_VERSION")
    except (ValueError, OSError):  # not a glibc system (macOS, musl, Windows)
        glibc = None
    if not glibc:
        return
    import ctypes

    try:
        libc = ctypes.CDLL(None)
        for param, value in _MALLOC:
            libc.mallopt(ctypes.c_int(param), ctypes.c_int(value))
    except (OSError, AttributeError):  # no mallopt to call: the defaults stay
        pass
