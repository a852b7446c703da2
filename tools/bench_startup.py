"""Startup cost of the command line, side by side with the interpreter and pxr baselines.

Each figure is the median wall time of ``--runs`` fresh processes:

* ``python -c pass`` — the interpreter alone (the floor);
* ``python -c "import pxr.Usd"`` — what any command that writes USD pays at least;
* ``ionic-usd --version`` and ``ionic-usd temple --help`` — parsing only;
* with ``--temple``: a warm ``ionic-usd temple -o X --force`` (cache filled by a first build).

``--compare DIR`` runs the same with DIR's ``ionic_usd`` first on ``PYTHONPATH`` (e.g. a
checkout of the previous commit: ``git worktree add /tmp/before HEAD~1``), and prints both
columns and their ratio. Run from the repository root::

    python tools/bench_startup.py --runs 7 --temple --compare /tmp/before
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def _env(src: Path, cache: Path) -> dict[str, str]:
    env = dict(os.environ, IONIC_USD_CACHE=str(cache))
    env["PYTHONPATH"] = os.pathsep.join([str(src), env.get("PYTHONPATH", "")]).rstrip(os.pathsep)
    return env


def _run(cmd: list[str], env: dict[str, str], cwd: Path) -> float:
    t0 = time.perf_counter()
    subprocess.run(
        cmd, env=env, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, cwd=cwd
    )  # not the repo: -m puts cwd first
    return time.perf_counter() - t0


def measure(trees: list[Path], runs: int, temple: bool, work: Path) -> list[dict[str, float]]:
    """Median seconds per case for each tree's ionic_usd; the trees' runs alternate, so a
    change of machine load during the bench affects every column alike."""
    py = sys.executable
    envs = [_env(src, work / f"cache-{i}") for i, src in enumerate(trees)]
    for src, env in zip(trees, envs, strict=True):
        where = subprocess.run(
            [py, "-c", "import ionic_usd; print(ionic_usd.__file__)"],
            env=env,
            cwd=work,
            capture_output=True,
            text=True,
            check=True,
        ).stdout
        assert where.startswith(str(src)), f"{src}: imported {where}"
    cli = [py, "-m", "ionic_usd"]
    cases: dict[str, list[list[str]]] = {
        "python -c pass": [[py, "-c", "pass"]] * len(trees),
        "python -c 'import pxr.Usd'": [[py, "-c", "import pxr.Usd"]] * len(trees),
        "ionic-usd --version": [[*cli, "--version"]] * len(trees),
        "ionic-usd temple --help": [[*cli, "temple", "--help"]] * len(trees),
    }
    n = {case: runs for case in cases}
    if temple:
        builds = [
            [
                *cli,
                "-q",
                "temple",
                "-o",
                str(work / f"temple-{i}"),
                "--force",
                "--texture-size",
                "256",
            ]
            for i in range(len(trees))
        ]
        for cmd, env in zip(builds, envs, strict=True):
            _run(cmd, env, work)  # fill the cache: what follows are warm rebuilds
        cases["warm temple rebuild (256 px)"] = builds
        n["warm temple rebuild (256 px)"] = max(3, runs // 2)
    out: list[dict[str, float]] = [{} for _ in trees]
    for case, cmds in cases.items():
        times: list[list[float]] = [[] for _ in trees]
        for _ in range(n[case]):
            for i, (cmd, env) in enumerate(zip(cmds, envs, strict=True)):
                times[i].append(_run(cmd, env, work))
        for i, t in enumerate(times):
            out[i][case] = statistics.median(t)
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--runs", type=int, default=7, help="processes per figure [default 7]")
    ap.add_argument("--temple", action="store_true", help="also time a warm temple rebuild")
    ap.add_argument("--compare", type=Path, help="a checkout to compare with (before)")
    args = ap.parse_args(argv)
    with tempfile.TemporaryDirectory(prefix="bench_startup") as tmp:
        work = Path(tmp)
        trees = [ROOT] + ([args.compare.resolve()] if args.compare else [])
        after, *rest = measure(trees, args.runs, args.temple, work)
        before = rest[0] if rest else None
    floor = after["python -c pass"]
    print(
        f"median of {args.runs} runs, {os.cpu_count()} cores, load "
        f"{os.getloadavg()[0]:.1f}; python {sys.version.split()[0]}"
    )
    head = f"{'case':34s} {'this tree':>10s}"
    if before:
        head += f" {'compare':>10s} {'ratio':>7s}"
    print(head + f" {'x python':>9s}")
    for case, t in after.items():
        row = f"{case:34s} {t:9.3f}s"
        if before:
            row += f" {before[case]:9.3f}s {before[case] / t:6.2f}x"
        print(row + f" {t / floor:8.1f}x")
    return 0


if __name__ == "__main__":
    import bench_md

    raise SystemExit(bench_md.run(main))
