"""``--markdown PATH`` for every ``tools/bench_*.py``: its printed figures as a Markdown page.

Each benchmark script ends with ``raise SystemExit(bench_md.run(main))``. Given
``--markdown docs/bench/NAME.md`` (taken off the command line before the script parses it), the
script's output goes to the terminal as usual and, if the script succeeds, into that file too:
the exact command, the date, the revision, the machine (cores, load, Python) and the output
verbatim. The benchmarks page (``docs/benchmarks.md``) includes these files, so its tables are
what a script printed, never typed by hand.
"""

from __future__ import annotations

import atexit
import io
import os
import platform
import shlex
import shutil
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import TextIO

ROOT = Path(__file__).resolve().parent.parent


class _Tee(io.TextIOBase):
    def __init__(self, *streams: TextIO) -> None:
        self.streams = streams

    def write(self, s: str) -> int:
        for st in self.streams:
            st.write(s)
        return len(s)

    def flush(self) -> None:
        for st in self.streams:
            st.flush()


def split_markdown_flag(argv: list[str]) -> tuple[list[str], Path | None]:
    """argv without ``--markdown PATH`` (or ``--markdown=PATH``), and that path."""
    rest: list[str] = []
    path: Path | None = None
    it = iter(argv)
    for a in it:
        if a == "--markdown":
            value = next(it, None)
            if value is None:
                raise SystemExit("--markdown needs a file name")
            path = Path(value)
        elif a.startswith("--markdown="):
            path = Path(a.split("=", 1)[1])
        else:
            rest.append(a)
    return rest, path


def _revision() -> str:
    try:
        out = subprocess.run(
            ["git", "-C", str(ROOT), "describe", "--always", "--dirty"],
            capture_output=True,
            text=True,
            check=True,
        )
        return out.stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def page(command: str, output: str, seconds: float) -> str:
    """The Markdown page of one benchmark run."""
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    return (
        f"<!-- written by tools/bench_md.py: rerun the command below; do not edit by hand -->\n"
        f"`{command}` — {time.strftime('%Y-%m-%d')}, revision `{_revision()}`, "
        f"{os.cpu_count()} cores, load {load:.1f} at the end, Python "
        f"{platform.python_version()}, {seconds:.0f} s:\n\n"
        f"```text\n{output.rstrip()}\n```\n"
    )


def scratch_root(prefix: str) -> str:
    """Route this process's ``tempfile`` folders into one new folder that is removed at exit.

    Benchmarks write caches and whole temples or cities (2.4 GB for the default city) through
    ``tempfile``; without this every run would leave them behind until the disk fills.
    """
    root = tempfile.mkdtemp(prefix=prefix)
    atexit.register(shutil.rmtree, root, ignore_errors=True)
    tempfile.tempdir = root
    return root


def run(main: Callable[[], int | None]) -> int | None:
    """Run a benchmark's ``main`` with its scratch folders under one root removed at exit;
    with ``--markdown PATH`` also write its output there."""
    scratch_root(f"{Path(sys.argv[0]).stem}_")
    rest, path = split_markdown_flag(sys.argv[1:])
    if path is None:
        return main()
    script = Path(sys.argv[0])
    rel = script.resolve().relative_to(ROOT) if script.resolve().is_relative_to(ROOT) else script
    command = shlex.join(["python", str(rel), *rest])
    sys.argv = [sys.argv[0], *rest]
    buf = io.StringIO()
    stdout = sys.stdout
    sys.stdout = _Tee(stdout, buf)
    t0 = time.perf_counter()
    try:
        rc = main()
    finally:
        sys.stdout = stdout
    if rc not in (0, None):
        return rc
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.tmp")
    tmp.write_text(page(command, buf.getvalue(), time.perf_counter() - t0), "utf-8")
    tmp.replace(path)
    print(f"wrote {path}")
    return rc
