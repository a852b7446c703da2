"""The command's process settings (:mod:`ionic_usd.cli.process`): one OpenBLAS thread unless
the user chose, glibc's malloc keeping freed memory; a library caller's process untouched."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

_THREADS = """
import os, sys
{pre}
import numpy as np
a = np.random.default_rng(0).random((600, 600))
a @ a  # OpenBLAS starts its threads on the first large product
print(len(os.listdir("/proc/self/task")), os.environ.get("OPENBLAS_NUM_THREADS"))
"""


def _threads(pre: str, **env: str) -> tuple[int, str]:
    base = {k: v for k, v in os.environ.items() if k != "OPENBLAS_NUM_THREADS"}
    out = subprocess.run(
        [sys.executable, "-c", _THREADS.format(pre=pre)],
        env={**base, **env},
        capture_output=True,
        text=True,
        check=True,
        cwd=Path(__file__).parent,
    ).stdout.split()
    return int(out[0]), out[1]


@pytest.mark.skipif(
    not Path("/proc/self/task").is_dir() or (os.cpu_count() or 1) < 2,
    reason="counts threads in /proc on a machine with 2 cores or more",
)
def test_the_command_runs_numpy_on_one_blas_thread():
    tuned = "from ionic_usd.cli.process import tune; tune()"
    assert _threads("")[0] >= 2  # numpy's own default: a thread per core
    assert _threads(tuned) == (1, "1")
    assert _threads(tuned, OPENBLAS_NUM_THREADS="2") == (2, "2")  # the user's choice stays
    # numpy already loaded (a caller's process): nothing to set, nothing claimed
    late = "import numpy; from ionic_usd.cli.process import tune; tune()"
    assert _threads(late)[1] == "None"


def test_main_tunes_only_its_own_process(monkeypatch):
    """``main()`` (the ``ionic-usd`` process) tunes; ``main(argv)`` (a caller) does not."""
    from ionic_usd import cli
    from ionic_usd.cli import process

    calls = []
    monkeypatch.setattr(process, "tune", lambda: calls.append(1))
    with pytest.raises(SystemExit):  # argparse's --version exits
        cli.main(["--version"])
    assert calls == []
    monkeypatch.setattr(sys, "argv", ["ionic-usd", "--version"])
    with pytest.raises(SystemExit):
        cli.main()
    assert calls == [1]


def test_tune_keeps_malloc_working_where_it_applies():
    """On glibc the settings are accepted (mallopt returns 1 for each) and large arrays are
    allocated and freed as before; elsewhere tune() does nothing and fails nothing."""
    code = (
        "from ionic_usd.cli import process; process.tune()\n"
        "import ctypes, os, numpy as np\n"
        "ok = []\n"
        "if os.confstr('CS_GNU_LIBC_VERSION'):\n"
        "    libc = ctypes.CDLL(None)\n"
        "    ok = [libc.mallopt(ctypes.c_int(p), ctypes.c_int(v)) for p, v in process._MALLOC]\n"
        "s = sum(float(np.ones(1 << k).sum()) for k in range(10, 25))\n"
        "print(ok, s)\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True
    ).stdout.split("]")
    assert out[0].strip("[ ") in ("", "1, 1, 1")
    assert float(out[1]) == sum(1 << k for k in range(10, 25))
