"""Issue 31 faults: one writer per output folder (a lock, two real processes), a fresh city
killed half-way leaves no partial folder, an immutable folder is refused before the build
(no staging folder left), and a repaired temple's manifest is byte for byte a fresh build's.
"""

from __future__ import annotations

import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def _env() -> dict[str, str]:
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    env.pop("IONIC_USD_DEBUG", None)
    env.pop("IONIC_USD_LOCK_WAIT", None)
    return env


def _ionic(args: list[str], cwd: Path, **kw) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "ionic_usd", *args],
        cwd=cwd,
        env=_env(),
        capture_output=True,
        text=True,
        timeout=300,
        **kw,
    )


_HOLD = (
    "import sys, time\n"
    "from ionic_usd.outputs import folder_lock\n"
    "with folder_lock(sys.argv[1]):\n"
    "    print('held', flush=True)\n"
    "    time.sleep(float(sys.argv[2]))\n"
)


def test_second_builder_into_one_folder_is_refused_naming_the_holder(tmp_path):
    """Process A holds T's lock (as `temple` does while it builds); `temple -o T` in process B
    is refused at once with status 2, naming A's pid; nothing is written; after A is done the
    lock file is gone and B builds."""
    holder = subprocess.Popen(
        [sys.executable, "-c", _HOLD, str(tmp_path / "T"), "30"],
        cwd=tmp_path,
        env=_env(),
        stdout=subprocess.PIPE,
        text=True,
    )
    try:
        assert holder.stdout is not None and holder.stdout.readline().strip() == "held"
        before = sorted(os.listdir(tmp_path))
        r = _ionic(["temple", "-o", "T", "--texture-size", "16"], tmp_path)
        assert r.returncode == 2, r.stderr
        assert len(r.stderr.splitlines()) == 1
        assert f"pid {holder.pid}" in r.stderr and "being built" in r.stderr
        assert sorted(os.listdir(tmp_path)) == before  # only the holder's lock file
        # the same for asset and city
        for argv in (["asset", "-o", "T", "--texture-size", "16"], ["city", "T"]):
            r = _ionic(argv, tmp_path)
            assert r.returncode == 2 and f"pid {holder.pid}" in r.stderr, r.stderr
    finally:
        holder.kill()
        holder.wait()
    # the kernel released the dead holder's lock: a new holder gets it at once
    from ionic_usd.outputs import folder_lock

    with folder_lock(tmp_path / "T"):
        pass
    assert not any(n.endswith(".ionic-lock") for n in os.listdir(tmp_path))


def test_waiting_builder_gets_the_lock_when_the_holder_is_done(tmp_path):
    from ionic_usd.outputs import folder_lock

    holder = subprocess.Popen(
        [sys.executable, "-c", _HOLD, str(tmp_path / "T"), "1.0"],
        env=_env(),
        stdout=subprocess.PIPE,
        text=True,
    )
    assert holder.stdout is not None and holder.stdout.readline().strip() == "held"
    t0 = time.monotonic()
    with folder_lock(tmp_path / "T", wait=30):
        waited = time.monotonic() - t0
    holder.wait()
    assert 0.2 < waited < 30
    assert os.listdir(tmp_path) == []


@pytest.mark.slow
def test_killed_fresh_city_leaves_no_partial_folder(tmp_path):
    """kill -9 while the city is written: no `c` folder (only a hidden staging sibling, which
    the next build removes)."""
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "ionic_usd",
            "city",
            "c",
            "--rows",
            "30",
            "--cols",
            "30",
            "--temple",
            "portunus",  # one build for every lot (900 chosen types are refused by memory)
            "--texture-size",
            "16",
            "-q",
        ],
        cwd=tmp_path,
        env=_env(),
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    deadline = time.monotonic() + 120
    staged = []
    while time.monotonic() < deadline and proc.poll() is None:
        staged = [n for n in os.listdir(tmp_path) if ".ionic-build-" in n]
        if staged and any((tmp_path / staged[0]).rglob("*.usd*")):
            break
        time.sleep(0.05)
    assert proc.poll() is None, "the build finished before it could be killed"
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait()
    assert not (tmp_path / "c").exists()
    assert staged and (tmp_path / staged[0]).exists()
    # the next build removes the dead build's staging folder
    r = _ionic(["city", "c", "--rows", "30", "--cols", "30", "--scheduler", "tcp://"], tmp_path)
    assert r.returncode == 2
    from ionic_usd.outputs import staged_new_folder

    with pytest.raises(RuntimeError), staged_new_folder(tmp_path / "c"):
        raise RuntimeError("refused")
    assert os.listdir(tmp_path) == []


def _chattr(path: Path, flag: str) -> bool:
    if shutil.which("chattr") is None or os.geteuid() != 0:
        return False
    return subprocess.run(["chattr", flag, str(path)], capture_output=True).returncode == 0


def test_immutable_folder_refused_before_the_build_no_staging_left(tmp_path):
    from ionic_usd.errors import ParameterError
    from ionic_usd.io import replace_folder

    dest = tmp_path / "T"
    dest.mkdir()
    (dest / "a.usda").write_text("#usda 1.0\n")
    if not _chattr(dest, "+i"):
        pytest.skip("needs root and chattr")
    built = []
    try:
        with pytest.raises(ParameterError, match="can write"):
            replace_folder(lambda d: built.append(d), dest, force=True)
    finally:
        _chattr(dest, "-i")
    assert built == [] and sorted(os.listdir(tmp_path)) == ["T"]
    # an immutable generated file inside: the move fails before anything moved, the staging
    # folder goes and the error is the OS's
    (dest / "a.usda").unlink()
    replace_folder(lambda d: (d / "a.usda").write_text("#usda 1.0\n"), dest, force=True)
    assert _chattr(dest / "a.usda", "+i")
    try:
        with pytest.raises(OSError):
            replace_folder(lambda d: (d / "a.usda").write_text("#usda 1.0\n#x\n"), dest, force=True)
    finally:
        _chattr(dest / "a.usda", "-i")
    assert sorted(os.listdir(tmp_path)) == ["T"]


@pytest.fixture(scope="module")
def fresh_tiny(tmp_path_factory):
    from ionic_usd.pipeline.temple import compose_temple
    from ionic_usd.temple.layout import portunus_layout
    from ionic_usd.usd.column_asset import ColumnAssetOptions

    opts = ColumnAssetOptions(
        lods=("low",), bases=("attic_bezier_plinth",), scrolls=("S1",), texture_size=16
    )
    folder = tmp_path_factory.mktemp("fresh") / "T"
    kw = {"texture_size": 16, "asset_options": opts, "detail": "plain"}
    compose_temple(folder, portunus_layout(), **kw)
    return folder, kw


@pytest.mark.slow
@pytest.mark.parametrize("damaged", ["Temple.usda", "layers", "IonicColumn"])
def test_manifest_after_repair_equals_a_fresh_builds(fresh_tiny, tmp_path, damaged):
    """Damage a generated file, repair with force: every file, the manifest included, holds a
    fresh build's bytes (the manifest used to record that the asset was reused)."""
    from ionic_usd.io import MANIFEST_NAME
    from ionic_usd.pipeline.temple import compose_temple
    from ionic_usd.temple.layout import portunus_layout

    fresh, kw = fresh_tiny
    copy = tmp_path / "T"
    shutil.copytree(fresh, copy)
    target = copy / damaged
    if target.is_dir():
        target = sorted(p for p in target.rglob("*.usd*") if p.is_file())[0]
    target.write_bytes(target.read_bytes()[: len(target.read_bytes()) // 2])
    rep = compose_temple(copy, portunus_layout(), force=True, **kw)
    assert not rep.current
    assert (copy / MANIFEST_NAME).read_bytes() == (fresh / MANIFEST_NAME).read_bytes()
    files = sorted(p.relative_to(copy) for p in copy.rglob("*") if p.is_file())
    assert files == sorted(p.relative_to(fresh) for p in fresh.rglob("*") if p.is_file())
    for rel in files:
        assert (copy / rel).read_bytes() == (fresh / rel).read_bytes(), rel


def test_file_size_limit_named_first(tmp_path):
    """Under `ulimit -f` the error names the cause (not OpenUSD's "Could not close")."""
    import resource

    def limit() -> None:
        resource.setrlimit(resource.RLIMIT_FSIZE, (100_000, resource.RLIM_INFINITY))

    for out in ("s.usda", "s.usdc"):
        r = _ionic(["shaft", "-o", out], tmp_path, preexec_fn=limit)
        assert r.returncode == 2, r.stderr
        assert len(r.stderr.splitlines()) == 1
        assert r.stderr.startswith("ionic-usd: error: File too large"), r.stderr
        assert os.listdir(tmp_path) == []


def test_usd_warnings_folded_into_the_one_error_line(tmp_path):
    """A sublayer that does not load: OpenUSD's Warning: line is folded into the error."""
    (tmp_path / "w.usda").write_text("#usda 1.0\n(\n    subLayers = [@./missing.usda@]\n)\n")
    r = _ionic(["preview", "w.usda", "-o", "w.png"], tmp_path)
    assert r.returncode == 2, r.stderr
    lines = r.stderr.splitlines()
    assert len(lines) == 1, r.stderr
    assert "OpenUSD warned: Could not load sublayer" in lines[0] and "missing.usda" in lines[0]
    assert "Warning: in" not in r.stderr
    assert sorted(os.listdir(tmp_path)) == ["w.usda"]


def test_staging_names_shown_as_the_users():
    from ionic_usd.cli import _user_paths

    assert (
        _user_paths("x: out/.T.ionic-build-15537-8ab514f7/.IonicColumn.ionic-build-1-a6ff2456/a")
        == "x: out/T/IonicColumn/a"
    )
    assert _user_paths("at /d/.x.json.ionic-tmp-15159-5978de3c.json") == "at /d/x.json"


def test_full_disk_named_first(tmp_path):
    """On a full file system (a 1 MB tmpfs, filled; root only) the error starts with the
    cause and names the user's path; nothing is left behind."""
    if os.geteuid() != 0 or shutil.which("mount") is None:
        pytest.skip("needs root to mount a tmpfs")
    full = tmp_path / "full"
    full.mkdir()
    if subprocess.run(["mount", "-t", "tmpfs", "-o", "size=1m", "tmpfs", str(full)]).returncode:
        pytest.skip("cannot mount a tmpfs")
    try:
        st = os.statvfs(full)
        with open(full / "filler", "wb") as fh:
            fh.write(b"\0" * (st.f_bavail * st.f_frsize - 200 * 1024))
        for argv in (["shaft", "-o", "full/s.usda"], ["column", "-o", "full/c.usdc"]):
            r = _ionic(argv, tmp_path)
            assert r.returncode == 2 and len(r.stderr.splitlines()) == 1, r.stderr
            assert r.stderr.startswith("ionic-usd: error: No space left on device"), r.stderr
            assert argv[-1] in r.stderr and "ionic-tmp" not in r.stderr
        assert os.listdir(full) == ["filler"]
    finally:
        subprocess.run(["umount", "-l", str(full)], capture_output=True)


@pytest.mark.slow
def test_two_temple_processes_into_one_folder(tmp_path):
    """Two real `ionic-usd temple` processes into T: the second (detail plain) is refused
    naming the first's pid while the first builds; the first finishes and T is its build."""
    from pxr import Usd

    first = subprocess.Popen(
        [sys.executable, "-m", "ionic_usd", "temple", "-o", "T", "--texture-size", "16", "-q"],
        cwd=tmp_path,
        env=_env(),
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    lock = tmp_path / ".T.ionic-lock"
    deadline = time.monotonic() + 120
    while not (lock.exists() and lock.stat().st_size) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert first.poll() is None, "the first build finished before the second started"
    second = _ionic(["temple", "-o", "T", "--texture-size", "16", "--detail", "plain"], tmp_path)
    assert second.returncode == 2 and len(second.stderr.splitlines()) == 1, second.stderr
    assert f"pid {first.pid}" in second.stderr
    out, err = first.communicate(timeout=600)
    assert first.returncode == 0, err
    stage = Usd.Stage.Open(str(tmp_path / "T" / "Temple.usda"))
    detail = stage.GetPrimAtPath("/Temple").GetVariantSets().GetVariantSet("detail")
    assert detail.GetVariantSelection() == "carved"  # the first's default, not plain
    assert sorted(os.listdir(tmp_path)) == ["T"]
