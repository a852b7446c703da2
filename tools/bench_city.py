"""City cost story: instances vs author/save/open time and memory, with a raw usd-core anchor.

Every case runs in a fresh subprocess (so peak memory is that case's alone):

* ``ionic-usd city`` with 1k / 100k / 1M street columns (4 × 4 temples), and 100 × 100
  temples as a PointInstancer and as instanceable references — author+save, whole build,
  peak RSS, file size, then ``Usd.Stage.Open`` + counting instances in another process;
* the anchor: a raw usd-core PointInstancer of N instances of one cube, arrays from numpy,
  saved as .usdc, opened and counted the same way;
* the prototype build on Dask (``--distributed``, or alone with ``--only-distributed``):
  the example forum (21 temple lots) and the default grid (5 × 5), each a city of 20+
  distinct temple builds, built from an empty cache (prototypes, meshes, UVs, textures: every
  run does the same work) by a real ``dask scheduler`` with 1 and then 2 ``dask worker``
  processes on 127.0.0.1 (single-threaded, started and stopped here), and locally (no
  ``--scheduler``); the SHA-256 of every file of the three cities must agree. Besides the
  wall times the table gives Σ task s / build s: the workers' build seconds over the build
  step's wall time, i.e. how many builds ran at once (on a machine shared with other jobs
  the tasks slow down, this ratio shows whether both workers were kept busy).

Usage: ``python tools/bench_city.py [--quick] [--json out.json]`` (run from the repository
with PYTHONPATH set to it). Prints a Markdown table. Uses a private cache in a temporary
folder (its first build is cold).
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

TEX = "64"


def _child(argv: list[str]) -> dict:
    out = subprocess.run(
        [sys.executable, __file__, *argv],
        capture_output=True,
        text=True,
        env=os.environ,
        check=False,
    )
    if out.returncode != 0:
        raise SystemExit(f"bench case {argv} failed:\n{out.stderr[-3000:]}")
    return json.loads(out.stdout.strip().splitlines()[-1])


def _peak_mib() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def case_city(folder: str, *args: str) -> dict:
    from ionic_usd.cli import main

    summary = Path(folder + ".json")
    t0 = time.perf_counter()
    rc = main(["city", folder, "--texture-size", TEX, "--json", str(summary), "--force", *args])
    wall = time.perf_counter() - t0
    s = json.loads(summary.read_text())
    t = s["timings"]
    size = sum(f.stat().st_size for f in Path(folder).glob("*.usd*"))
    digest = hashlib.sha256()
    for f in sorted(Path(folder).rglob("*")):
        if f.is_file():
            digest.update(f.relative_to(folder).as_posix().encode() + b"\0" + f.read_bytes())
    return {
        "rc": rc,
        "wall": wall,
        "author_save": t["usd author"] + t["usd save"],
        "build": t["build"],
        "peak_mib": _peak_mib(),
        "bytes": size,
        "columns": s["columns"],
        "temples": s["temples"],
        "temples_as": s["temples_as"],
        "built": s["prototypes_built"],
        "workers": s["workers"],
        "cluster_workers": s["cluster_workers"],
        "digest": digest.hexdigest()[:16],
        "task_s": sum(s["build_task_seconds"].values()),
    }


def case_open(path: str) -> dict:
    t0 = time.perf_counter()
    from pxr import Usd, UsdGeom

    t1 = time.perf_counter()
    stage = Usd.Stage.Open(path)
    n = 0
    it = iter(stage.Traverse())
    for prim in it:
        if prim.IsA(UsdGeom.PointInstancer):
            n += len(UsdGeom.PointInstancer(prim).GetProtoIndicesAttr().Get())
            it.PruneChildren()  # its prototypes are not instances of the scene
        elif prim.IsInstance():
            n += 1
    t2 = time.perf_counter()
    return {"open_count": t2 - t1, "import": t1 - t0, "instances": n, "peak_mib": _peak_mib()}


def case_raw(n: int, path: str) -> dict:
    import numpy as np
    from pxr import Gf, Sdf, Usd, UsdGeom, Vt

    t0 = time.perf_counter()
    stage = Usd.Stage.CreateNew(path)
    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.y)
    pi = UsdGeom.PointInstancer.Define(stage, "/World/Instancer")
    UsdGeom.Cube.Define(stage, "/World/Instancer/Prototypes/Cube")
    pi.CreatePrototypesRel().SetTargets([Sdf.Path("/World/Instancer/Prototypes/Cube")])
    rng = np.random.default_rng(0)
    pos = (rng.random((n, 3)) * 1000).astype(np.float32)
    yaw = rng.random(n) * np.pi
    q = np.zeros((n, 4), dtype=np.float16)
    q[:, 1], q[:, 3] = np.sin(yaw / 2), np.cos(yaw / 2)
    pi.CreatePositionsAttr().Set(Vt.Vec3fArray.FromNumpy(pos))
    pi.CreateOrientationsAttr().Set(Vt.QuathArray.FromNumpy(q))
    pi.CreateProtoIndicesAttr().Set(Vt.IntArray.FromNumpy(np.zeros(n, dtype=np.int32)))
    pi.CreateExtentAttr().Set(Vt.Vec3fArray([Gf.Vec3f(-1, -1, -1), Gf.Vec3f(1001, 1001, 1001)]))
    stage.GetRootLayer().Save()
    t1 = time.perf_counter()
    return {"author_save": t1 - t0, "peak_mib": _peak_mib(), "bytes": Path(path).stat().st_size}


def _free_port() -> int:
    import socket

    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


class _Cluster:
    """A real ``dask scheduler`` and ``n`` ``dask worker`` processes (one thread each) on
    127.0.0.1, with this environment (the private cache, PYTHONPATH); stopped on exit."""

    def __init__(self, n: int, logs: Path):
        self.n, self.logs = n, logs
        self.procs: list[subprocess.Popen] = []

    def __enter__(self) -> str:
        dask = str(Path(sys.executable).with_name("dask"))
        port = _free_port()
        self.address = f"tcp://127.0.0.1:{port}"
        self.logs.mkdir(parents=True, exist_ok=True)
        start = [dask, "scheduler", "--host", "127.0.0.1", "--port", str(port), "--no-dashboard"]
        self._spawn(start, "scheduler")
        for k in range(self.n):
            w = [dask, "worker", self.address, "--host", "127.0.0.1", "--nthreads", "1"]
            self._spawn([*w, "--nworkers", "1", "--no-dashboard", "--name", f"w{k}"], f"w{k}")
        from distributed import Client

        deadline = time.monotonic() + 120
        while True:
            try:
                with Client(self.address, timeout="5s") as client:
                    client.wait_for_workers(self.n, timeout=120)
                return self.address
            except (OSError, TimeoutError):
                if time.monotonic() > deadline:
                    raise
                time.sleep(0.5)

    def _spawn(self, argv: list[str], name: str) -> None:
        log = open(self.logs / f"{name}.log", "w")  # noqa: SIM115 - closed with the process
        self.procs.append(subprocess.Popen(argv, stdout=log, stderr=subprocess.STDOUT))

    def __exit__(self, *exc) -> None:
        for p in reversed(self.procs):
            p.terminate()
        for p in self.procs:
            try:
                p.wait(timeout=10)
            except subprocess.TimeoutExpired:
                p.kill()


def _digests(folder: Path) -> dict[str, str]:
    return {
        f.relative_to(folder).as_posix(): hashlib.sha256(f.read_bytes()).hexdigest()
        for f in sorted(folder.rglob("*"))
        if f.is_file()
    }


def distributed(tmp: Path, which: list[str], local: bool) -> tuple[list[str], dict]:
    """The 1-vs-2-worker comparison (see the module docstring); returns (table rows, raw)."""
    cache = Path(os.environ["IONIC_USD_CACHE"])
    repo = str(Path(__file__).resolve().parents[1])
    os.environ["PYTHONPATH"] = os.pathsep.join([repo, os.environ.get("PYTHONPATH", "")])
    plans = {"forum": ["--plan", str(Path(repo) / "examples" / "forum.geojson")], "grid": []}
    rows = [
        "| city | temples | builds | run | workers | build s | whole s | speed-up | "
        "Σ task s / build s | files = local |",
        "|---|---:|---:|---|---:|---:|---:|---:|---:|---|",
    ]
    raw: dict = {}
    for name in which:
        runs: dict[str, dict] = {}
        digests: dict[str, dict] = {}
        for run, n in (("1 worker", 1), ("2 workers", 2), ("local", 0)):
            if run == "local" and not local:
                continue
            shutil.rmtree(cache, ignore_errors=True)  # every run from the same (empty) cache
            folder = tmp / f"{name}_{n}"
            if n:
                with _Cluster(n, tmp / "logs" / f"{name}_{n}") as address:
                    c = _child(["_city", str(folder), *plans[name], "--scheduler", address])
            else:
                c = _child(["_city", str(folder), *plans[name]])
            runs[run], digests[run] = c, _digests(folder)
            shutil.rmtree(folder, ignore_errors=True)
        base = runs["1 worker"]["wall"]
        for run, c in runs.items():
            ref = digests.get("local", digests["1 worker"])
            same = digests[run] == ref
            if not same:  # name what differs (the folders are gone by now)
                diff = sorted(
                    k for k in set(ref) | set(digests[run]) if ref.get(k) != digests[run].get(k)
                )
                print(f"{name} {run}: {len(diff)} files differ: {diff[:20]}", file=sys.stderr)
            rows.append(
                f"| {name} | {c['temples']} | {c['built']} | {run} | {c['cluster_workers']} | "
                f"{c['build']:.1f} | {c['wall']:.1f} | {base / c['wall']:.2f} | "
                f"{c['task_s'] / max(c['build'], 1e-9):.2f} | "
                f"{'yes' if same else 'NO'} ({len(digests[run])} files) |"
            )
            print(rows[-1], file=sys.stderr)
        raw[name] = {"runs": runs, "identical": len({json.dumps(d) for d in digests.values()}) == 1}
    return rows, raw


def _row(name: str, c: dict, o: dict) -> str:
    return (
        f"| {name} | {c.get('instances', o['instances']):,} | {c['author_save']:.2f} | "
        f"{c.get('wall', float('nan')):.2f} | {c['peak_mib']:.0f} | {o['open_count']:.3f} | "
        f"{c['bytes'] / 1e6:.1f} |"
    )


def main() -> None:
    if len(sys.argv) > 1 and sys.argv[1].startswith("_"):
        fn = {"_city": case_city, "_open": case_open, "_raw": lambda n, p: case_raw(int(n), p)}[
            sys.argv[1]
        ]
        print(json.dumps(fn(*sys.argv[2:])))
        return
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="skip the 1M and 100×100 cases")
    ap.add_argument("--json", type=Path, help="also write the raw numbers here")
    ap.add_argument("--skip-workers", action="store_true", help="skip the Dask comparison")
    ap.add_argument(
        "--only-distributed",
        nargs="*",
        choices=("forum", "grid"),
        help="only the 1-vs-2-worker comparison, of these cities [default both]",
    )
    ap.add_argument("--no-local", action="store_true", help="no local build to compare with")
    args = ap.parse_args()
    tmp = Path(tempfile.mkdtemp(prefix="bench_city_"))
    # a private cache: the runs below delete its prototypes, never the user's
    os.environ["IONIC_USD_CACHE"] = str(tmp / "cache")
    results: dict[str, dict] = {}
    rows = [
        "| case | instances | author+save s | whole build s | peak MiB | open+count s | "
        "MB on disk |",
        "|---|---:|---:|---:|---:|---:|---:|",
    ]
    if args.only_distributed is not None:
        try:
            rows, raw = distributed(
                tmp, args.only_distributed or ["forum", "grid"], not args.no_local
            )
        finally:
            shutil.rmtree(tmp, ignore_errors=True)
        print("\n".join(rows))
        if args.json:
            args.json.write_text(json.dumps(raw, indent=1))
        return
    try:
        _child(["_city", str(tmp / "warm"), "--temple", "portunus"])  # the one temple build
        counts = [1000, 100_000] + ([] if args.quick else [1_000_000])
        cases = [("default city (4×4 temples)", [])]
        cases += [(f"4×4 temples + {n:,} columns", ["--columns", str(n)]) for n in counts]
        if not args.quick:
            cases += [
                ("100×100 temples, PointInstancer", ["--rows", "100", "--cols", "100"]),
                (
                    "100×100 temples, references",
                    ["--rows", "100", "--cols", "100", "--instancer-threshold", "100000"],
                ),
                (
                    "50×50 temples, PointInstancer",
                    ["--rows", "50", "--cols", "50", "--instancer-threshold", "0"],
                ),
                (
                    "50×50 temples, references",
                    ["--rows", "50", "--cols", "50", "--instancer-threshold", "100000"],
                ),
            ]
        for name, extra in cases:
            folder = tmp / f"c{len(results)}"
            # one build for every lot (the uniform city): this table is about instances
            uniform = ["--temple", "portunus"] + ([] if "--rows" in extra else ["--rows", "4"])
            uniform += [] if "--cols" in extra else ["--cols", "4"]
            c = _child(["_city", str(folder), *uniform, *extra])
            o = _child(["_open", str(folder / "City.usda")])
            results[name] = {"city": c, "open": o}
            rows.append(_row(name, {**c, "instances": o["instances"]}, o))
            print(rows[-1], file=sys.stderr)
            shutil.rmtree(folder, ignore_errors=True)
        for n in counts:
            path = tmp / f"raw{n}.usdc"
            r = _child(["_raw", str(n), str(path)])
            o = _child(["_open", str(path)])
            results[f"raw {n}"] = {"raw": r, "open": o}
            rows.append(_row(f"raw usd-core PointInstancer, {n:,}", r, o))
            print(rows[-1], file=sys.stderr)
        if not args.skip_workers:
            drows, raw = distributed(tmp, ["forum", "grid"], not args.no_local)
            rows += ["", *drows]
            results["distributed"] = raw
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    print("\n".join(rows))
    if args.json:
        args.json.write_text(json.dumps(results, indent=1))


if __name__ == "__main__":
    import bench_md

    raise SystemExit(bench_md.run(main))
