"""Benchmark ionic_usd's curve measures against similaritymeasures, scipy and GEOS (shapely).

Run:  python tools/bench_metrics.py [--sizes 1000 5000 10000] [--budget 30]

For each size and pair kind (two independent 2D random walks; a random walk and a
near-identical noisy copy), times this project's measures beside the baselines that compute
the same quantity, checks that the values agree and prints times and ratios
(baseline time / ours). Everything runs on one core (thread pools pinned to 1). A baseline
whose predicted time (O(n m) scaling from the previous size) exceeds --budget seconds is
skipped, and one that runs longer than that is stopped; the table says so. The targets from
the issue are printed with the measurements.

Which quantities correspond:

* ``hausdorff_distance`` (node-to-curve, the paper's "weak Fréchet") = GEOS
  ``hausdorff_distance(LineString, LineString)`` (GEOS measures vertex-to-geometry).
* ``node_hausdorff_distance`` (node-to-node) = max of scipy ``directed_hausdorff`` both ways.
* ``discrete_frechet_distance`` = similaritymeasures ``frechet_dist`` = GEOS
  ``frechet_distance`` (GEOS 3.14 was seen to return larger values on some random walks).
* ``frechet_distance`` (continuous) and ``compare`` (the whole bundle) have no baseline.
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import multiprocessing as mp  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from collections.abc import Callable  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from ionic_usd.evaluate import metrics as M  # noqa: E402

TARGETS = {
    ("discrete_frechet", 10_000): 0.2,
    ("hausdorff", 10_000): 0.15,
    ("compare", 1_000): 0.020,
}
TARGET_TEXT = {
    "discrete_frechet": "discrete Fréchet 10k x 10k <= 0.2 s",
    "hausdorff": "node-to-curve (symmetric) at 10k <= 0.15 s",
    "compare": "full bundle at 1k < 20 ms",
}


def pairs(n: int, seed: int) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    rng = np.random.default_rng(seed)
    walk = np.cumsum(rng.normal(size=(n, 2)), axis=0)
    other = np.cumsum(rng.normal(size=(n, 2)), axis=0)
    near = walk + rng.normal(scale=0.05, size=walk.shape)
    return {"random walks": (walk, other), "near-identical": (walk, near)}


def timed(fn: Callable[[], float], repeat: int) -> tuple[float, float]:
    best = np.inf
    value = np.nan
    for _ in range(repeat):
        t0 = time.perf_counter()
        value = fn()
        best = min(best, time.perf_counter() - t0)
    return best, float(value)


def _child(fn: Callable[[], float], queue) -> None:
    t0 = time.perf_counter()
    value = fn()
    queue.put((time.perf_counter() - t0, float(value)))


def timed_with_limit(fn: Callable[[], float], limit: float) -> tuple[float, float] | None:
    """Time one call in a forked child process; None if it runs longer than ``limit`` s.

    The slow baselines cannot be interrupted from Python, so they run in a child that is
    terminated (by its own pid) when over budget.
    """
    ctx = mp.get_context("fork")
    queue = ctx.Queue()
    proc = ctx.Process(target=_child, args=(fn, queue), daemon=True)
    proc.start()
    proc.join(limit)
    if proc.is_alive():
        proc.terminate()
        proc.join()
        return None
    if queue.empty():
        return None
    return queue.get()


def baselines(a: np.ndarray, b: np.ndarray) -> dict[str, list[tuple[str, Callable[[], float]]]]:
    out: dict[str, list[tuple[str, Callable[[], float]]]] = {}
    try:
        import shapely

        la, lb = shapely.LineString(a), shapely.LineString(b)
        out.setdefault("hausdorff", []).append(
            ("GEOS hausdorff_distance", lambda: shapely.hausdorff_distance(la, lb))
        )
        out.setdefault("discrete_frechet", []).append(
            ("GEOS frechet_distance", lambda: shapely.frechet_distance(la, lb))
        )
    except ImportError:
        print("shapely not installed: GEOS baselines skipped")
    try:
        from scipy.spatial.distance import directed_hausdorff

        out.setdefault("node_hausdorff", []).append(
            (
                "scipy directed_hausdorff x2",
                lambda: max(directed_hausdorff(a, b)[0], directed_hausdorff(b, a)[0]),
            )
        )
    except ImportError:
        print("scipy not installed: scipy baseline skipped")
    try:
        import similaritymeasures

        out.setdefault("discrete_frechet", []).append(
            ("similaritymeasures frechet_dist", lambda: similaritymeasures.frechet_dist(a, b))
        )
    except ImportError:
        print("similaritymeasures not installed: its baseline skipped")
    return out


def ours(a: np.ndarray, b: np.ndarray) -> dict[str, Callable[[], float]]:
    return {
        "hausdorff": lambda: M.hausdorff_distance(a, b),
        "node_hausdorff": lambda: M.node_hausdorff_distance(a, b),
        "average_error": lambda: M.average_error(a, b),
        "discrete_frechet": lambda: M.discrete_frechet_distance(a, b),
        "frechet": lambda: M.frechet_distance(a, b),
        "compare": lambda: M.compare(a, b).frechet,
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[1000, 5000, 10000])
    parser.add_argument("--budget", type=float, default=30.0, help="seconds per baseline call")
    parser.add_argument("--seed", type=int, default=1)
    args = parser.parse_args(argv)

    # JIT warm-up (numba compiles on first call, or loads its on-disk cache).
    w = pairs(50, 0)["near-identical"]
    for fn in ours(*w).values():
        fn()

    header = (
        f"{'n':>6}  {'pair':<15} {'measure':<17} {'ours s':>9}  {'baseline':<32}"
        f" {'base s':>9} {'ratio':>8}  agree"
    )
    print(header)
    print("-" * len(header))
    last_time: dict[tuple[str, str], tuple[int, float]] = {}
    measured: dict[tuple[str, int, str], float] = {}
    for n in args.sizes:
        for kind, (a, b) in pairs(n, args.seed).items():
            base = baselines(a, b)
            for name, fn in ours(a, b).items():
                repeat = 5 if n <= 1000 else (3 if n <= 5000 or name != "frechet" else 1)
                t_ours, v_ours = timed(fn, repeat)
                measured[(name, n, kind)] = t_ours
                rows = base.get(name) or [("-", None)]
                for bname, bfn in rows:
                    if bfn is None:
                        print(f"{n:>6}  {kind:<15} {name:<17} {t_ours:>9.4f}")
                        continue
                    prev = last_time.get((kind, bname))
                    if prev is not None and not np.isfinite(prev[1]):
                        print(
                            f"{n:>6}  {kind:<15} {name:<17} {t_ours:>9.4f}  {bname:<32}"
                            f" {'skipped':>9} {'':>8}  (over budget at n = {prev[0]})"
                        )
                        continue
                    if prev is not None:
                        predicted = prev[1] * (n / prev[0]) ** 2
                        if predicted > args.budget:
                            print(
                                f"{n:>6}  {kind:<15} {name:<17} {t_ours:>9.4f}  {bname:<32}"
                                f" {'skipped':>9} {'':>8}  (predicted {predicted:.0f} s >"
                                f" {args.budget:.0f} s)"
                            )
                            continue
                    result = timed_with_limit(bfn, args.budget)
                    if result is None:
                        last_time[(kind, bname)] = (n, np.inf)
                        print(
                            f"{n:>6}  {kind:<15} {name:<17} {t_ours:>9.4f}  {bname:<32}"
                            f" {'skipped':>9} {'':>8}  (stopped after {args.budget:.0f} s)"
                        )
                        continue
                    t_base, v_base = result
                    last_time[(kind, bname)] = (n, t_base)
                    agree = abs(v_base - v_ours) <= 1e-9 * max(1.0, abs(v_ours))
                    note = "yes" if agree else f"NO ({v_ours:.6g} vs {v_base:.6g})"
                    print(
                        f"{n:>6}  {kind:<15} {name:<17} {t_ours:>9.4f}  {bname:<32}"
                        f" {t_base:>9.4f} {t_base / t_ours:>8.1f}x  {note}"
                    )
    print()
    print("targets (one core, after JIT warm-up; worst of the two pair kinds):")
    ok = True
    for (name, n), limit in TARGETS.items():
        times = [t for (m, size, _), t in measured.items() if m == name and size == n]
        if not times:
            print(f"  {TARGET_TEXT[name]:<45} not measured (size {n} not run)")
            continue
        worst = max(times)
        passed = worst <= limit
        ok &= passed
        print(f"  {TARGET_TEXT[name]:<45} measured {worst:.4f} s  {'PASS' if passed else 'FAIL'}")
    return 0 if ok else 1


if __name__ == "__main__":
    import bench_md

    raise SystemExit(bench_md.run(main))
