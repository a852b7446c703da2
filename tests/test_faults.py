"""Faults (issue 11): full disk, read-only folder, corrupt cache, kill -9 during a rebuild.

Full and read-only disks are small tmpfs mounts, which needs root; elsewhere those tests are
skipped with the reason. Root ignores permission bits, so "read-only" is a tmpfs remounted
``ro`` (the kernel refuses writes even to root).
"""

from __future__ import annotations

import contextlib
import os
import random
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from ionic_usd.cli import main

REPO = Path(__file__).resolve().parents[1]


def _can_mount() -> str | None:
    if not hasattr(os, "geteuid") or os.geteuid() != 0:
        return "needs root to mount a small tmpfs"
    return None


@contextlib.contextmanager
def tmpfs(path: Path, size: str):
    path.mkdir(parents=True, exist_ok=True)
    r = subprocess.run(
        ["mount", "-t", "tmpfs", "-o", f"size={size}", "tmpfs", str(path)],
        capture_output=True,
        text=True,
    )
    if r.returncode != 0:
        pytest.skip(f"cannot mount a tmpfs here: {r.stderr.strip()}")
    try:
        yield path
    finally:
        subprocess.run(["umount", "-l", str(path)], capture_output=True)


def _listing(root: Path) -> list[str]:
    return sorted(str(p.relative_to(root)) for p in root.rglob("*"))


def _run(argv, capsys, cwd: Path | None = None):
    old = Path.cwd()
    if cwd is not None:
        os.chdir(cwd)
    try:
        code = main(argv)
    except SystemExit as exc:
        code = exc.code
    finally:
        os.chdir(old)
    cap = capsys.readouterr()
    return code, cap.out, cap.err


def _one_line_refusal(code, err) -> None:
    assert code == 2, err
    assert len(err.splitlines()) == 1 and "Traceback" not in err, err


def _fill(folder: Path, leave: int) -> None:
    """Fill a tmpfs until about ``leave`` bytes are free."""
    st = os.statvfs(folder)
    free = st.f_bavail * st.f_frsize
    with contextlib.suppress(OSError), open(folder / "filler", "wb") as fh:
        fh.write(b"\0" * max(0, free - leave))


@pytest.mark.skipif(_can_mount() is not None, reason=str(_can_mount()))
def test_full_disk_refused_cleanly(tmp_path, capsys):
    with tmpfs(tmp_path / "full", "256k") as full:
        code, out, err = _run(["column", "--lod", "low", "-o", str(full / "c.usda")], capsys)
        _one_line_refusal(code, err)
        assert "No space left" in err or "disk full" in err, err
        assert _listing(full) == []  # no temporaries, no truncated layer
    # a folder build: OpenUSD reports success for a truncated Geometry.usdc; the read-back
    # check catches it, and the staging folder goes
    with tmpfs(tmp_path / "full2", "3m") as full:
        code, out, err = _run(["asset", "-o", str(full / "A"), "--texture-size", "16"], capsys)
        _one_line_refusal(code, err)
        assert "No space left" in err, err
        assert _listing(full) == []


@pytest.mark.skipif(_can_mount() is not None, reason=str(_can_mount()))
def test_full_disk_preview_not_reported_written(tmp_path, capsys):
    pytest.importorskip("moderngl")
    scene = tmp_path / "s.usda"
    assert _run(["shaft", "--flute-slices", "2", "-o", str(scene)], capsys)[0] == 0
    with tmpfs(tmp_path / "full", "1m") as full:
        _fill(full, 4096)
        code, out, err = _run(
            ["preview", str(scene), "-o", str(full / "p.png"), "--width", "400", "--height", "300"],
            capsys,
        )
        if "EGL" in err or "context" in err:
            pytest.skip(f"no headless OpenGL here: {err.strip()}")
        _one_line_refusal(code, err)
        assert "wrote" not in out
        assert _listing(full) == ["filler"]


@pytest.mark.skipif(_can_mount() is not None, reason=str(_can_mount()))
def test_full_cache_disk_never_poisons_textures(tmp_path, monkeypatch):
    from ionic_usd.io import MANIFEST_NAME
    from ionic_usd.pipeline.asset import copy_stone_textures
    from ionic_usd.texture.stone import verify_image

    with tmpfs(tmp_path / "cache", "64k") as cache:
        monkeypatch.setenv("IONIC_USD_CACHE", str(cache))
        out = tmp_path / "asset"
        files = copy_stone_textures(out, "travertine", 128, 3)
        for f in files:  # the asset got whole images (written straight into it)
            verify_image(f)
        # nothing half-written stays in the cache
        for entry in (cache / "textures").glob("*") if (cache / "textures").exists() else []:
            assert (entry / MANIFEST_NAME).is_file(), _listing(cache)
        # space freed: the cache fills properly and is then used
        subprocess.run(["mount", "-o", "remount,size=16m", str(cache)], check=True)
        copy_stone_textures(tmp_path / "a2", "travertine", 128, 3)
        entries = list((cache / "textures").iterdir())
        assert len(entries) == 1 and (entries[0] / MANIFEST_NAME).is_file()
        for f in files:
            assert (tmp_path / "a2" / f.name).read_bytes() == f.read_bytes()


@pytest.mark.skipif(_can_mount() is not None, reason=str(_can_mount()))
def test_read_only_folder_refused_before_work(tmp_path, capsys):
    with tmpfs(tmp_path / "ro", "1m") as ro:
        (ro / "keep.txt").write_text("x")
        subprocess.run(["mount", "-o", "remount,ro", str(ro)], check=True)
        for argv in (
            ["shaft", "-o", str(ro / "x.usda")],
            ["temple", "-o", str(ro / "T")],
            ["asset", "-o", str(ro / "A")],
        ):
            t0 = time.perf_counter()
            code, _, err = _run(argv, capsys)
            _one_line_refusal(code, err)
            assert "read-only" in err, err
            assert time.perf_counter() - t0 < 5.0  # refused before building anything
        assert _listing(ro) == ["keep.txt"]


def test_corrupt_texture_cache_is_recomputed(tmp_path, monkeypatch):
    from ionic_usd.pipeline.asset import copy_stone_textures
    from ionic_usd.texture.stone import write_stone_textures

    monkeypatch.setenv("IONIC_USD_CACHE", str(tmp_path / "cache"))
    fresh = write_stone_textures(tmp_path / "fresh", "marble", 32, 5)
    copy_stone_textures(tmp_path / "a", "marble", 32, 5)
    entry = next((tmp_path / "cache" / "textures").iterdir())
    png = entry / "marble_basecolor.png"
    for damage in (
        lambda: png.write_bytes(png.read_bytes()[: png.stat().st_size // 2]),
        lambda: png.write_bytes(b"garbage under the right name"),
        lambda: (entry / "marble_normal.png").unlink(),
    ):
        damage()
        out = copy_stone_textures(tmp_path / "b", "marble", 32, 5)
        for f in out:  # the asset gets the true maps, never the damaged cache entry
            key = f.stem.split("_", 1)[1]
            assert f.read_bytes() == fresh[key].read_bytes(), (damage, f)


def _temple_ok(x: Path) -> None:
    from pxr import Sdf, Usd, UsdUtils

    root = x / "Temple.usda"
    assert root.is_file(), sorted(p.name for p in x.iterdir())
    _, _, unresolved = UsdUtils.ComputeAllDependencies(Sdf.AssetPath(str(root)))
    assert not unresolved, unresolved
    stage = Usd.Stage.Open(str(root))
    assert len(list(stage.GetPrimAtPath("/Temple/Colonnade").GetAllChildren())) > 0


def _kill_rebuilds(tmp_path: Path, kills: int, *, final_run: bool) -> None:
    x = tmp_path / "X"
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    # --rebuild: every run regenerates (an unchanged folder would be verified and left alone)
    cmd = [
        sys.executable, "-m", "ionic_usd.cli", "temple", "-o", str(x), "--texture-size", "16",
        "--rebuild",
    ]  # fmt: skip
    t0 = time.perf_counter()
    assert main(cmd[3:]) == 0  # the first build in-process (no interpreter start-up)
    full = time.perf_counter() - t0 + 4.0  # + a new interpreter's imports
    (x / "notes.txt").write_text("my notes")
    (x / "Textures").mkdir(exist_ok=True)  # the user's own folder (the temple shares the
    (x / "Textures" / "my_decal.png").write_bytes(b"decal")  # asset's maps, no Textures/)
    shared = tmp_path / "X" / "shared_overrides.usda"  # the user's layer, linked in
    shared.write_text('#usda 1.0\n(\n    doc = "my edits"\n)\n')
    (x / "overrides.usda").unlink()
    (x / "overrides.usda").symlink_to(shared.name)
    rng = random.Random(11)
    for _ in range(kills):
        p = subprocess.Popen(
            [*cmd, "--force"], env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL
        )
        time.sleep(rng.uniform(0.3, full))
        p.send_signal(signal.SIGKILL)
        p.wait()
        assert x.is_dir()
        _temple_ok(x)
        assert (x / "notes.txt").read_text() == "my notes"
        assert (x / "Textures" / "my_decal.png").read_bytes() == b"decal"
        assert (x / "overrides.usda").is_symlink()
        assert "my edits" in (x / "overrides.usda").read_text()
    if not final_run:  # what the next run does first, without its 10 s of building
        from ionic_usd.io import recover_folder

        recover_folder(x)
    else:  # the next run completes and removes every temporary of the killed ones
        subprocess.run([*cmd, "--force"], env=env, check=True, capture_output=True, timeout=300)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["X"]
    _temple_ok(x)
    assert (x / "notes.txt").read_text() == "my notes"
    assert (x / "overrides.usda").is_symlink() and (x / "Textures" / "my_decal.png").exists()


def test_kill_during_temple_rebuild(tmp_path):
    _kill_rebuilds(tmp_path, 1, final_run=False)


@pytest.mark.slow
def test_kill_during_temple_rebuild_many(tmp_path):
    _kill_rebuilds(tmp_path, 10, final_run=True)


def test_every_error_crosses_a_process_pool_intact():
    """A refusal raised in a mesh worker (a process pool, a Dask worker) comes back as the same
    error with the same one line, not as a broken pool (exit 70): every error pickles."""
    import pickle
    from concurrent.futures import ProcessPoolExecutor

    from ionic_usd import errors

    made = [
        errors.ParameterError("arc_radii", (0.1, -1.0), "lengths > 0 (m)", context="volute"),
        errors.GrammarError("unknown token 'Q'", "R0.1 Q", 5, length=1, module=1, grammar="base"),
        errors.GeometryError("g"),
        errors.BudgetError("b"),
        errors.ReferenceCurveError("r"),
        errors.OutputExistsError("o"),
        errors.UsdAuthoringError("u"),
    ]
    classes = {c for c in vars(errors).values() if isinstance(c, type) and issubclass(c, Exception)}
    assert classes - {errors.IonicError} <= {type(e) for e in made}  # a new error joins here
    made[2].note = "an attribute of its own"  # the instance's __dict__ travels too
    # plain pickle, and the exception pickling Dask's distributed installs (tblib: it rebuilds
    # an exception without a __reduce__ of its own through its built-in base's __new__)
    import copyreg

    from tblib import pickling_support

    for e in made:
        back = pickle.loads(pickle.dumps(e))
        assert type(back) is type(e) and str(back) == str(e) and vars(back) == vars(e)
    saved = dict(copyreg.dispatch_table)
    try:
        pickling_support.install()  # every exception class now pickles through tblib
        assert all(copyreg.dispatch_table.get(type(e)) for e in made)
        for e in made:
            back = pickle.loads(pickle.dumps(e))
            assert type(back) is type(e) and str(back) == str(e) and vars(back) == vars(e)
    finally:
        copyreg.dispatch_table.clear()
        copyreg.dispatch_table.update(saved)
    # and through a real pool: the worker's refusal, as the worker raised it
    with ProcessPoolExecutor(1) as ex:
        with pytest.raises(errors.ParameterError, match="arc_radii = .* lengths > 0"):
            ex.submit(_refuse_in_worker).result()


def _refuse_in_worker() -> None:
    from ionic_usd.column.volute import VoluteParams

    VoluteParams(volute_model="centred_arcs", arc_radii=(0.1, -1.0))


def test_a_killed_build_leaves_no_worker_holding_its_lock(tmp_path):
    """The mesh pool's workers are forked with the build's folder lock (flock belongs to the
    open file a fork shares): when the build is killed they die with it, so the lock is free
    at once (before, an orphan kept building and held it, and the next run found it busy)."""
    import psutil

    from ionic_usd.outputs import lock_path, remove_stale_lock

    x = tmp_path / "A"
    env = {**os.environ, "PYTHONPATH": str(REPO), "IONIC_USD_CACHE": str(tmp_path / "cache")}
    cmd = [sys.executable, "-m", "ionic_usd", "asset", "-o", str(x), "--texture-size", "16"]
    p = subprocess.Popen(cmd, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    proc = psutil.Process(p.pid)
    deadline = time.monotonic() + 120
    workers: list = []
    while time.monotonic() < deadline and len(workers) < 2 and p.poll() is None:
        workers = proc.children()
        time.sleep(0.05)
    assert len(workers) == 2, "the asset's mesh pool did not start"
    assert lock_path(x).exists()
    p.send_signal(signal.SIGKILL)
    p.wait()
    gone, alive = psutil.wait_procs(workers, timeout=5)
    assert not alive, f"orphaned workers: {[w.pid for w in alive]}"
    assert remove_stale_lock(x) and not lock_path(x).exists()
