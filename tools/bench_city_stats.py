"""Benchmark a city's prototype stats (``compose_city``'s "usd prototype stats" step: each
temple prototype's bounds per purpose and its triangles per level of detail, the street
column's likewise) side by side with a baseline checkout's.

Usage: ``python tools/bench_city_stats.py --baseline DIR [--rows 5 --cols 5] [--repeat 5]``

``DIR`` is another checkout of this project (``git worktree add /tmp/base <commit>``). Builds
the city once with this checkout (``ionic-usd city``, the default 5 × 5 grid unless
``--rows``/``--cols``; a private cache, so the first build is cold: about 2 minutes on 2
cores), recording the arguments ``compose_city`` hands to ``temple_prototypes`` and
``column_prototypes``. Then runs both steps on those arguments with each checkout, each run
in a fresh process (the stages are opened cold; the files are in the OS cache), taking
turns, and prints the best and median seconds, the ratio, and whether both checkouts found
the same prototypes, bounds and triangle counts.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

CAPTURE = r"""
import pickle, sys
import ionic_usd.usd.city as city

def _recording(name):
    orig = getattr(city, name)
    def rec(*args):
        with open(sys.argv[1] + "." + name, "wb") as f:
            pickle.dump(args, f)
        return orig(*args)
    return rec

if __name__ == "__main__":  # Dask's workers import this script again: only the client runs
    for name in ("temple_prototypes", "column_prototypes"):
        setattr(city, name, _recording(name))
    from ionic_usd.cli import main
    sys.exit(main(sys.argv[2:]))
"""

TIME = r"""
import hashlib, json, pickle, sys, time
from pathlib import Path
import numpy as np
try:  # the instance arrays: ionic_usd.blueprint.city (older checkouts: ionic_usd.usd.city)
    import ionic_usd.blueprint.city
except ModuleNotFoundError:  # an older baseline: unpickle them as its usd.city's classes
    import ionic_usd.usd.city
    sys.modules["ionic_usd.blueprint.city"] = ionic_usd.usd.city
from ionic_usd.usd.city_instances import column_prototypes, temple_prototypes

args = {}
for name in ("temple_prototypes", "column_prototypes"):
    with open(sys.argv[1] + "." + name, "rb") as f:
        a = list(pickle.load(f))
    a[0] = Path(sys.argv[2])  # the city as built (it was built in a scratch folder)
    args[name] = a
t0 = time.perf_counter()
tp = temple_prototypes(*args["temple_prototypes"])
cp = column_prototypes(*args["column_prototypes"])
secs = time.perf_counter() - t0
h = hashlib.sha256(repr(tp.keys).encode())
for a in (tp.of, tp.lo, tp.hi, tp.lo4, tp.hi4, cp.index, cp.lo, cp.hi):
    h.update(np.ascontiguousarray(a).tobytes())
h.update(json.dumps({k: v.tolist() for k, v in tp.tri.items()}, sort_keys=True).encode())
h.update(json.dumps(cp.tri, sort_keys=True).encode())
print(json.dumps({"secs": secs, "digest": h.hexdigest(), "prototypes": len(tp.keys)}))
"""


def _run(code: str, pythonpath: Path, *args: str, env: dict | None = None) -> str:
    e = dict(os.environ if env is None else env, PYTHONPATH=str(pythonpath))
    r = subprocess.run(  # cwd: "-c" puts the working folder first on sys.path
        [sys.executable, "-c", code, *args],
        env=e,
        cwd=tempfile.gettempdir(),
        capture_output=True,
        text=True,
        check=False,
    )
    if r.returncode:
        sys.exit(f"bench_city_stats: a run failed ({pythonpath}):\n{r.stderr[-2000:]}")
    return r.stdout


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--baseline", type=Path, required=True, help="another checkout")
    ap.add_argument("--rows", type=int, default=None)
    ap.add_argument("--cols", type=int, default=None)
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args(argv)
    if not (args.baseline / "ionic_usd" / "usd" / "city_instances.py").is_file():
        sys.exit(f"bench_city_stats: {args.baseline} is not a checkout of this project")
    tmp = Path(tempfile.mkdtemp(prefix="bench_city_stats_"))
    env = dict(os.environ, IONIC_USD_CACHE=str(tmp / "cache"))
    grid = [f"--{k}={v}" for k, v in (("rows", args.rows), ("cols", args.cols)) if v]
    rec = str(tmp / "args")
    _run(CAPTURE, ROOT, rec, "city", str(tmp / "C"), "-q", *grid, env=env)
    for name in ("temple_prototypes", "column_prototypes"):
        if not Path(f"{rec}.{name}").is_file():
            sys.exit(f"bench_city_stats: the city build did not call {name}")
    check = "import ionic_usd, sys; sys.stdout.write(ionic_usd.__file__)"
    for path in (args.baseline.resolve(), ROOT):
        got = Path(_run(check, path)).resolve()
        if not got.is_relative_to(path):
            sys.exit(f"bench_city_stats: {path} imports ionic_usd from {got}")
    times: dict[str, list[float]] = {"baseline": [], "current": []}
    found: dict[str, set[str]] = {"baseline": set(), "current": set()}
    protos = 0
    for _ in range(args.repeat):  # taking turns: drifting load hits both alike
        for side, path in (("baseline", args.baseline.resolve()), ("current", ROOT)):
            out = json.loads(_run(TIME, path, rec, str(tmp / "C")).strip().splitlines()[-1])
            times[side].append(out["secs"])
            found[side].add(out["digest"])
            protos = out["prototypes"]
    city = f"{args.rows or 'default'} x {args.cols or 'default'} grid"
    print(f"city prototype stats, {city}: {protos} temple prototypes, {args.repeat} runs each")
    print(f"{'checkout':10s} {'best s':>7s} {'median s':>9s}")
    for side in ("baseline", "current"):
        print(f"{side:10s} {min(times[side]):7.3f} {statistics.median(times[side]):9.3f}")
    b, c = statistics.median(times["baseline"]), statistics.median(times["current"])
    print(f"ratio (baseline / current, medians): {b / c:.2f}x")
    same = found["baseline"] == found["current"] and len(found["current"]) == 1
    print(
        "same prototypes, bounds and triangle counts in both checkouts"
        if same
        else "RESULTS DIFFER between the checkouts"
    )
    return 0 if same else 1


if __name__ == "__main__":
    import bench_md

    raise SystemExit(bench_md.run(main))
