"""Benchmark the command's process settings (:mod:`ionic_usd.cli.process`): one OpenBLAS
thread and glibc's malloc keeping freed memory, against the same command without them.

Usage: python tools/bench_process.py [--pairs N]

Both sides run this checkout's command line in a fresh process: ``python -m ionic_usd ARGS``
(``main()`` tunes the process) and ``python -c "...main(ARGS)"`` (``main`` given its
arguments leaves the process as it is, as for a library caller), the latter with
``OPENBLAS_NUM_THREADS`` removed from its environment. N turns (default 5), the two sides one
after the other in each, of two jobs: the default temple with an empty cache, and the fit of
the fragment scan of docs/fitting.md (5,000 points in mm). Prints the medians of wall time,
CPU time (user + sys of the process and its workers) and minor page faults per side, and the
median of the turn-by-turn ratios (pairing keeps a ratio meaningful when the load drifts).
The outputs of the two sides are compared file by file (SHA-256): the settings change how
fast, not what.
"""

from __future__ import annotations

import argparse
import hashlib
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

_UNTUNED = "import sys; from ionic_usd.cli import main; sys.exit(main(sys.argv[1:]))"


def _run(tuned: bool, args: list[str], cwd: str) -> tuple[float, float, int]:
    """(wall s, CPU s, minor page faults) of one command run in a fresh process."""
    env = dict(os.environ, IONIC_USD_CACHE=tempfile.mkdtemp(prefix="bench_process_cache_"))
    if not tuned:
        env.pop("OPENBLAS_NUM_THREADS", None)
    head = ["-m", "ionic_usd"] if tuned else ["-c", _UNTUNED]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    subprocess.run(
        [sys.executable, *head, *args],
        env=env,
        cwd=cwd,
        check=True,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return wall, cpu, after.ru_minflt - before.ru_minflt


def _digest(folder: Path) -> dict[str, str]:
    """SHA-256 of every file below ``folder`` but the manifests and reports that record times
    (the fit's JSON holds its seconds)."""
    out = {}
    for f in sorted(folder.rglob("*")):
        if f.is_file() and "manifest" not in f.name and f.suffix != ".json":
            out[str(f.relative_to(folder))] = hashlib.sha256(f.read_bytes()).hexdigest()
    return out


def _fragment(folder: Path) -> Path:
    """The fragment scan of docs/fitting.md, in mm."""
    import numpy as np

    from ionic_usd.column.column import build_column, portunus_column_params
    from ionic_usd.evaluate.scan_io import synthetic_scan

    p = portunus_column_params(lower_diameter=0.8)
    pts, _, _ = synthetic_scan(
        build_column(p).parts(),
        n=5000,
        noise=0.0008,
        y_range=(0.0, 2.0),
        holes=2,
        hole_radius=0.05,
        seed=1,
    )
    path = folder / "fragment_mm.xyz"
    np.savetxt(path, pts * 1000.0, fmt="%.3f")
    return path


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--pairs", type=int, default=5)
    args = ap.parse_args(argv)
    work = Path(tempfile.mkdtemp(prefix="bench_process_"))
    scan = _fragment(work)
    jobs = {
        "temple, empty cache": lambda out: ["temple", "-o", str(out / "T")],
        "fit column --scan": lambda out: ["fit", "column", "--scan", str(scan), "-o", str(out)],
    }
    print(
        f"{args.pairs} turns, untuned then tuned in each (load average "
        f"{os.getloadavg()[0]:.1f} at the start on {os.cpu_count()} cores)"
    )
    head = f"{'job':22s} {'side':8s} {'wall s':>7s} {'cpu s':>7s} {'faults':>8s}"
    print(head)
    differ = 0
    for job, make_args in jobs.items():
        runs: dict[bool, list[tuple[float, float, int]]] = {False: [], True: []}
        for turn in range(args.pairs):
            digests = {}
            for tuned in (False, True):
                out = work / f"{job[:5]}_{turn}_{int(tuned)}"
                runs[tuned].append(_run(tuned, make_args(out), str(work)))
                digests[tuned] = _digest(out)
            differ += digests[False] != digests[True]
        for tuned in (False, True):
            r = runs[tuned]
            print(
                f"{job:22s} {'tuned' if tuned else 'untuned':8s} "
                f"{statistics.median(x[0] for x in r):7.2f} "
                f"{statistics.median(x[1] for x in r):7.2f} "
                f"{statistics.median(x[2] for x in r):8.0f}"
            )
        ratio = [
            statistics.median(t[i] / u[i] for t, u in zip(runs[True], runs[False], strict=True))
            for i in range(3)
        ]
        print(
            f"{job:22s} {'tuned/untuned (paired medians)':>30s}: wall {ratio[0]:.3f}x  "
            f"cpu {ratio[1]:.3f}x  faults {ratio[2]:.3f}x"
        )
    print("outputs identical on every turn" if not differ else f"outputs differ on {differ} turns")
    return 0


if __name__ == "__main__":
    import bench_md

    raise SystemExit(bench_md.run(main))
