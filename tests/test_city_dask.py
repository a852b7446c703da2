"""The distributed build against a real Dask scheduler and workers on loopback.

A ``dask scheduler`` and two ``dask worker`` processes are started here (random free ports)
and torn down afterwards; the city built on them must equal, byte for byte, the city built on
a local cluster.
"""

from __future__ import annotations

import json
import os
import socket
import subprocess
import sys
import time
from importlib import resources
from pathlib import Path

import pytest

from ionic_usd.pipeline.city import CityOptions, build_city

REPO = Path(__file__).resolve().parents[1]
DASK = Path(sys.executable).with_name("dask")
TEX = 64


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.fixture(scope="module")
def loopback_cluster(tmp_path_factory):
    from distributed import Client

    if not DASK.exists():
        pytest.skip("the dask command is not installed beside this Python")
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(REPO), env.get("PYTHONPATH", "")])
    log = tmp_path_factory.mktemp("dask")
    port = _free_port()
    address = f"tcp://127.0.0.1:{port}"
    procs = [
        subprocess.Popen(
            [str(DASK), "scheduler", "--host", "127.0.0.1", "--port", str(port), "--no-dashboard"],
            env=env,
            stdout=open(log / "scheduler.log", "w"),
            stderr=subprocess.STDOUT,
        )
    ]
    try:
        for k in range(2):
            procs.append(
                subprocess.Popen(
                    [
                        str(DASK),
                        "worker",
                        address,
                        "--host",
                        "127.0.0.1",
                        "--nthreads",
                        "1",
                        "--nworkers",
                        "1",
                        "--no-dashboard",
                        "--name",
                        f"w{k}",
                    ],
                    env=env,
                    stdout=open(log / f"worker{k}.log", "w"),
                    stderr=subprocess.STDOUT,
                )
            )
        deadline = time.monotonic() + 90
        while True:  # the scheduler needs a moment before it accepts connections
            try:
                with Client(address, timeout="5s") as client:
                    client.wait_for_workers(2, timeout=90)
                    workers = set(client.scheduler_info()["workers"])
                break
            except (OSError, TimeoutError):
                if time.monotonic() > deadline:
                    raise
                time.sleep(0.5)
        yield address, workers
    finally:
        for p in reversed(procs):
            p.terminate()
        for p in procs:
            try:
                p.wait(timeout=5)
            except subprocess.TimeoutExpired:
                p.kill()


def _files(folder: Path) -> dict[str, bytes]:
    return {
        f.relative_to(folder).as_posix(): f.read_bytes()
        for f in sorted(folder.rglob("*"))
        if f.is_file()
    }


def _plan(tmp_path: Path) -> Path:
    """Two temple lots needing two builds (a lower podium is a temple of its own) and a
    porticus between them."""
    text = (resources.files("ionic_usd") / "data" / "portunus.toml").read_text()
    (tmp_path / "low_podium.toml").write_text(
        text.replace("\nheight = 2.40\n", "\nheight = 2.10\n", 1)
    )
    doc = {
        "type": "FeatureCollection",
        "features": [
            {
                "type": "Feature",
                "properties": {"id": "a", "type": "temple", "orientation": 180},
                "geometry": {
                    "type": "Polygon",
                    "coordinates": [[[-20, 0], [0, 0], [0, 30], [-20, 30], [-20, 0]]],
                },
            },
            {
                "type": "Feature",
                "properties": {"id": "b", "type": "temple", "temple": "low_podium.toml"},
                "geometry": {
                    "type": "Polygon",
                    "coordinates": [[[10, 0], [40, 0], [40, 16], [10, 16], [10, 0]]],
                },
            },
            {
                "type": "Feature",
                "properties": {"id": "street", "type": "porticus", "sides": 2},
                "geometry": {"type": "LineString", "coordinates": [[-30, -10], [50, -10]]},
            },
        ],
    }
    p = tmp_path / "plan.geojson"
    p.write_text(json.dumps(doc))
    return p


@pytest.mark.slow
def test_cluster_build_equals_local_build(portunus_temple, loopback_cluster, tmp_path):
    # (the session's temple has warmed the UV cache the workers share through the environment)
    address, workers = loopback_cluster
    plan = str(_plan(tmp_path))
    local = build_city(
        tmp_path / "local",
        CityOptions(
            plan=plan, texture_size=TEX, workers=2, prototype_cache=str(tmp_path / "cache_local")
        ),
    )
    remote = build_city(
        tmp_path / "remote",
        CityOptions(
            plan=plan,
            texture_size=TEX,
            scheduler=address,
            prototype_cache=str(tmp_path / "cache_remote"),
        ),
    )
    assert local["prototypes_built"] == remote["prototypes_built"] == 2
    assert local["cluster_workers"] == 2 and remote["cluster_workers"] == 2
    assert remote["workers"] and set(remote["workers"]) <= workers
    a, b = _files(tmp_path / "local"), _files(tmp_path / "remote")
    assert len(a) > 40 and a == b  # every file, byte for byte
    assert local["temple_prototypes"] == 2 and local["columns"] > 20


def test_unreachable_scheduler_is_a_parameter_error(tmp_path, monkeypatch):
    from ionic_usd.errors import ParameterError
    from ionic_usd.pipeline import build

    monkeypatch.setattr(build, "CONNECT_TIMEOUT", "1s")
    port = _free_port()  # nothing listens there
    with pytest.raises(ParameterError, match="--scheduler"):
        build_city(
            tmp_path / "x",
            CityOptions(
                rows=1,
                cols=1,
                texture_size=TEX,
                scheduler=f"tcp://127.0.0.1:{port}",
                prototype_cache=str(tmp_path / "empty_cache"),
            ),
        )
    assert not (tmp_path / "x").exists()
