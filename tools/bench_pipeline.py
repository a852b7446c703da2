"""Benchmark: whole column per LOD, the column asset and the Portunus temple, cold and warm.

Run: ``python tools/bench_pipeline.py [--cli-only] [--baseline CHECKOUT [--pairs N]]``. "Cold"
uses an empty cache folder (every UV unwrap and texture is computed: what a first run on a new
machine costs);
"warm" rebuilds the same output with the cache filled: the same command again (the folder is
verified and left as it is), a temple option edited (the asset's verified files reused) and
``--rebuild`` (every file regenerated from the warm caches). ``--pairs N`` adds N turns of a
cold temple and its ``--rebuild`` with the baseline, then with this checkout: the medians of
each side and of the turn-by-turn ratios.
Targets: full column ≤ 50 ms at high LOD on one core (issue 4); default temple cold ≤ 2.5 s and
warm ≤ 0.6 s on the 2-core machine (issue 12), measured as the user runs it: ``ionic-usd temple
-o X --force`` in a fresh process, wall time and the CPU time of the process and its workers (on
a shared machine the CPU time is the steadier figure), beside ``ionic-usd --version`` (the
start-up floor).
"""

from __future__ import annotations

import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path


def main() -> None:
    os.environ["IONIC_USD_CACHE"] = tempfile.mkdtemp(prefix="ionic_bench_cache_")
    from ionic_usd.column.column import build_column, portunus_column_params
    from ionic_usd.lod import LOD_NAMES
    from ionic_usd.pipeline.asset import build_column_asset
    from ionic_usd.pipeline.temple import compose_temple
    from ionic_usd.temple.layout import portunus_layout
    from ionic_usd.usd.column_asset import ColumnAssetOptions

    print("whole column (base + shaft + capital body + scrolls), best of 5:")
    print(f"{'lod':>8} {'triangles':>10} {'ms':>8} {'Mtri/s':>8}")
    for lod in LOD_NAMES:
        p = portunus_column_params(lod=lod)
        build_column(p)
        best = min(_timed(lambda p=p: build_column(p)) for _ in range(5))
        n = build_column(p).n_triangles
        print(f"{lod:>8} {n:>10,} {1e3 * best:>8.1f} {n / best / 1e6:>8.2f}")
    print("target: high LOD <= 50 ms\n")

    out = Path(tempfile.mkdtemp())
    cold = build_column_asset(out / "a" / "IonicColumn", ColumnAssetOptions())
    warm = build_column_asset(
        out / "a" / "IonicColumn", ColumnAssetOptions(), force=True, rebuild=True
    )
    print(
        f"column asset: {cold.meshes} meshes, triangles per LOD {cold.triangles_per_lod}, "
        f"{cold.bytes_on_disk / 1e6:.1f} MB"
    )
    print(
        f"  cold {cold.seconds:.2f} s ({cold.uv_unwraps} unwraps), warm {warm.seconds:.2f} s "
        f"({warm.uv_unwraps} unwraps), ratio {cold.seconds / warm.seconds:.1f}x\n"
    )

    os.environ["IONIC_USD_CACHE"] = tempfile.mkdtemp(prefix="ionic_bench_cache_")
    t = compose_temple(out / "t", portunus_layout())
    w = compose_temple(out / "t", portunus_layout(), force=True, rebuild=True)
    print(
        f"Portunus temple: {t.files} files, {t.prims} prims, {t.instances} instances of "
        f"{t.prototypes} prototypes, {t.triangles:,} triangles"
    )
    print(
        f"  cold {t.seconds:.2f} s, warm {w.seconds:.2f} s, ratio {t.seconds / w.seconds:.1f}x"
        f"  (target: cold <= 5 s on 2 cores)"
    )


def _cli(args: list[str], env: dict[str, str]) -> tuple[float, float]:
    """Wall and CPU (user + sys, process and children) seconds of one CLI run."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    # cwd: a neutral folder, so ``-m`` does not put a checkout in the working directory
    # ahead of PYTHONPATH
    subprocess.run(
        [sys.executable, "-m", "ionic_usd", *args],
        env=env,
        check=True,
        cwd=tempfile.gettempdir(),
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return wall, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def cli_temple(baseline: str | None = None) -> None:
    """The CLI temple cold (empty cache) and warm, in fresh processes.

    ``baseline``: a checkout of another revision (``git worktree add /tmp/base REV``) run the
    same way (its package first on ``PYTHONPATH``), for a side-by-side figure.
    """
    env = {**os.environ, "IONIC_USD_CACHE": tempfile.mkdtemp(prefix="ionic_bench_cli_")}
    if baseline:
        env["PYTHONPATH"] = baseline
    out = str(Path(tempfile.mkdtemp()) / "t")
    probe = subprocess.run(
        [sys.executable, "-c", "import ionic_usd; print(ionic_usd.__file__)"],
        env=env,
        cwd=tempfile.gettempdir(),
        capture_output=True,
        text=True,
    )
    print(f"package: {probe.stdout.strip()}")
    ver = min(_cli(["--version"], env) for _ in range(3))
    cold = _cli(["temple", "-o", out, "--force"], env)
    warm = min(_cli(["temple", "-o", out, "--force"], env) for _ in range(2))
    # the edit loop: a temple option changed (the asset's options are not), then back
    edit = min(
        _cli(["temple", "-o", out, "--force", "--detail", d], env) for d in ("plain", "carved")
    )
    regen = None
    if not baseline:  # --rebuild: every file regenerated with the caches warm
        regen = min(_cli(["temple", "-o", out, "--force", "--rebuild"], env) for _ in range(2))
    print(
        f"CLI {baseline or 'this checkout'} (load average {os.getloadavg()[0]:.1f} on "
        f"{os.cpu_count()} cores):"
    )
    print(f"  ionic-usd --version  wall {ver[0]:.2f} s  cpu {ver[1]:.2f} s")
    print(f"  temple cold          wall {cold[0]:.2f} s  cpu {cold[1]:.2f} s  (target 2.5 s)")
    print(f"  temple warm          wall {warm[0]:.2f} s  cpu {warm[1]:.2f} s  (target 0.6 s)")
    print(f"  temple --detail edit wall {edit[0]:.2f} s  cpu {edit[1]:.2f} s")
    if regen is not None:
        print(f"  temple --rebuild     wall {regen[0]:.2f} s  cpu {regen[1]:.2f} s")
    print(
        f"  cold/warm wall ratio {cold[0] / warm[0]:.1f}x, warm minus start-up "
        f"{warm[0] - ver[0]:.2f} s"
    )


def paired_cold(baseline: str, pairs: int) -> None:
    """``pairs`` turns of a cold temple (a new empty cache and output each run) with the
    baseline checkout, then with this one, and a ``--rebuild`` of each (caches warm): medians
    of each side and of the turn-by-turn ratios (pairing keeps the ratio meaningful when the
    machine's load drifts during the runs)."""
    import statistics

    sides = {"baseline": baseline, "this": None}
    runs: dict[tuple[str, str], list[tuple[float, float]]] = {}
    for _ in range(pairs):
        for side, path in sides.items():
            env = {**os.environ, "IONIC_USD_CACHE": tempfile.mkdtemp(prefix="ionic_bench_cold_")}
            if path:
                env["PYTHONPATH"] = path
            out = str(Path(tempfile.mkdtemp()) / "t")
            runs.setdefault((side, "cold"), []).append(_cli(["temple", "-o", out], env))
            rebuild = ["temple", "-o", out, "--force", "--rebuild"]
            runs.setdefault((side, "rebuild"), []).append(_cli(rebuild, env))
    print(
        f"paired: {pairs} turns of baseline {baseline} then this checkout "
        f"(load average {os.getloadavg()[0]:.1f} at the end on {os.cpu_count()} cores):"
    )
    for what in ("cold", "rebuild"):
        for side in sides:
            r = runs[(side, what)]
            walls, cpus = [w for w, _ in r], [c for _, c in r]
            print(
                f"  temple {what:<8} {side:<8} wall median {statistics.median(walls):.2f} s "
                f"({min(walls):.2f}-{max(walls):.2f})  cpu median {statistics.median(cpus):.2f} s "
                f"({min(cpus):.2f}-{max(cpus):.2f})"
            )
        a, b = runs[("this", what)], runs[("baseline", what)]
        wall = statistics.median(x[0] / y[0] for x, y in zip(a, b, strict=True))
        cpu = statistics.median(x[1] / y[1] for x, y in zip(a, b, strict=True))
        print(
            f"  temple {what:<8} this/baseline: wall {wall:.3f}x  cpu {cpu:.3f}x (paired medians)"
        )


def _timed(fn) -> float:
    t0 = time.perf_counter()
    fn()
    return time.perf_counter() - t0


def _run() -> None:
    if "--cli-only" not in sys.argv:
        main()
    if "--baseline" in sys.argv:
        base = sys.argv[sys.argv.index("--baseline") + 1]
        if "--pairs" in sys.argv:
            paired_cold(base, int(sys.argv[sys.argv.index("--pairs") + 1]))
        cli_temple(base)
    cli_temple()


if __name__ == "__main__":
    import bench_md

    raise SystemExit(bench_md.run(_run))
