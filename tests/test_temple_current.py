"""A rebuild of an unchanged temple writes nothing; one of changed inputs reuses only what it
verifies, and writes the bytes a fresh build writes."""

from __future__ import annotations

import dataclasses
import hashlib
import json
import shutil
from pathlib import Path

import pytest

from ionic_usd.cli import main
from ionic_usd.io import MANIFEST_NAME
from ionic_usd.pipeline import keys
from ionic_usd.pipeline.temple import compose_temple, temple_key
from ionic_usd.temple.layout import portunus_layout
from ionic_usd.usd.column_asset import ColumnAssetOptions

OPTS = ColumnAssetOptions(
    lods=("low",), bases=("attic_bezier_plinth",), scrolls=("S1",), texture_size=16
)


def _files(folder: Path) -> dict[str, tuple[str, int, int]]:
    """Relative path → (SHA-256, inode, mtime_ns) of every file (the manifest aside)."""
    out = {}
    for f in sorted(folder.rglob("*")):
        if f.is_file() and f != folder / MANIFEST_NAME:
            st = f.stat()
            out[f.relative_to(folder).as_posix()] = (
                hashlib.sha256(f.read_bytes()).hexdigest(),
                st.st_ino,
                st.st_mtime_ns,
            )
    return out


def _digests(folder: Path) -> dict[str, str]:
    return {k: v[0] for k, v in _files(folder).items()}


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    folder = tmp_path_factory.mktemp("current") / "T"
    rep = compose_temple(folder, portunus_layout(), asset_options=OPTS, detail="plain")
    return folder, rep


def _again(folder: Path, **kw):
    opts = {"asset_options": OPTS, "detail": "plain", **kw}
    return compose_temple(folder, portunus_layout(), force=True, **opts)


def test_an_unchanged_rebuild_writes_nothing_and_reports_the_same(built, tmp_path):
    src, first = built
    folder = tmp_path / "T"
    shutil.copytree(src, folder)
    before = _files(folder)
    rep = _again(folder)
    assert rep.current and not first.current
    assert _files(folder) == before  # not one file rewritten: same bytes, inode and mtime
    same = ("files", "prims", "instances", "prototypes", "triangles", "hypotheses")
    assert all(getattr(rep, f) == getattr(first, f) for f in same)
    assert rep.triangles_per_lod == first.triangles_per_lod
    assert rep.combination_layers == first.combination_layers


@pytest.mark.parametrize("damage", ["edit", "delete", "symlink"])
def test_a_damaged_generated_file_is_rebuilt(built, tmp_path, damage):
    src, _ = built
    folder = tmp_path / "T"
    shutil.copytree(src, folder)
    want = _digests(folder)
    target = folder / "podium.usda"
    if damage == "edit":
        target.write_bytes(target.read_bytes() + b"\n")
    elif damage == "delete":
        target.unlink()
    else:  # the same bytes behind a symlink are not the file the build wrote
        (tmp_path / "elsewhere.usda").write_bytes(target.read_bytes())
        target.unlink()
        target.symlink_to(tmp_path / "elsewhere.usda")
    rep = _again(folder)
    assert not rep.current
    assert _digests(folder) == want
    assert not target.is_symlink()


def test_the_users_files_do_not_make_a_folder_stale(built, tmp_path):
    src, _ = built
    folder = tmp_path / "T"
    shutil.copytree(src, folder)
    (folder / "notes.txt").write_text("mine")
    (folder / "overrides.usda").write_text("#usda 1.0\n")  # an edited user's layer
    assert _again(folder).current
    assert (folder / "notes.txt").read_text() == "mine"


def test_changed_options_reuse_only_the_verified_asset_and_write_a_fresh_builds_bytes(
    built, tmp_path
):
    src, _ = built
    folder = tmp_path / "T"
    shutil.copytree(src, folder)
    rep = _again(folder, detail="moulded")  # a temple option: the asset's options are the same
    assert not rep.current and rep.asset_reused
    fresh = tmp_path / "F"
    compose_temple(fresh, portunus_layout(), asset_options=OPTS, detail="moulded", rebuild=True)
    assert _digests(folder) == _digests(fresh)
    # an asset file edited by hand is not reused: the asset is built again
    geo = folder / "IonicColumn" / "Payload" / "Geometry.usdc"
    geo.write_bytes(geo.read_bytes()[:-8])
    rep = _again(folder, detail="carved")
    assert not rep.asset_reused
    fresh2 = tmp_path / "F2"
    compose_temple(fresh2, portunus_layout(), asset_options=OPTS, detail="carved", rebuild=True)
    assert _digests(folder) == _digests(fresh2)


def test_rebuild_regenerates_an_unchanged_folder(built, tmp_path):
    src, _ = built
    folder = tmp_path / "T"
    shutil.copytree(src, folder)
    before = _files(folder)
    rep = _again(folder, rebuild=True)
    assert not rep.current and not rep.asset_reused
    after = _files(folder)
    assert {k: v[0] for k, v in after.items()} == {k: v[0] for k, v in before.items()}
    assert all(after[k][1:] != before[k][1:] for k in before if k != "overrides.usda")


def test_the_manifest_keeps_the_key_and_every_generated_files_digest(built):
    folder, _ = built
    m = json.loads((folder / MANIFEST_NAME).read_text())
    assert m["key"] == temple_key(portunus_layout(), asset_options=OPTS, detail="plain")
    assert set(m["sha256"]) == set(m["files"]) == set(_digests(folder)) - {"overrides.usda"}
    assert all(m["sha256"][k] == v for k, v in _digests(folder).items() if k in m["sha256"])


def test_the_key_follows_every_input_the_code_and_the_libraries(monkeypatch):
    layout = portunus_layout()
    base = temple_key(layout, asset_options=OPTS)
    other_layout = dataclasses.replace(
        layout,
        params=dataclasses.replace(
            layout.params, columns_height=layout.params.columns_height + 1e-9
        ),
    )
    variants = [
        temple_key(layout, asset_options=OPTS, seed=8),
        temple_key(layout, asset_options=OPTS, texture_size=512),
        temple_key(layout, asset_options=OPTS, detail="plain"),
        temple_key(layout, asset_options=dataclasses.replace(OPTS, texture_size=32)),
        temple_key(other_layout, asset_options=OPTS),
    ]
    assert len({base, *variants}) == 6
    assert temple_key(portunus_layout(), asset_options=OPTS) == base  # stable
    monkeypatch.setattr(keys, "source_digest", lambda: "0" * 64)
    assert temple_key(layout, asset_options=OPTS) != base
    monkeypatch.undo()
    monkeypatch.setattr(keys, "library_versions", lambda: "usd-core==0.0")
    assert temple_key(layout, asset_options=OPTS) != base


def test_cli_says_up_to_date_and_rebuild_regenerates(tmp_path, capsys):
    out = tmp_path / "T"
    argv = ["temple", "-o", str(out), "--texture-size", "16", "--detail", "plain"]
    assert main(argv) == 0
    assert "wrote" in capsys.readouterr().out
    assert main([*argv, "--force"]) == 0
    assert capsys.readouterr().out.startswith("up to date ")
    assert main([*argv, "--force", "--rebuild"]) == 0
    assert capsys.readouterr().out.startswith("wrote ")
    assert main(argv) == 2  # an existing folder still needs --force


def test_a_current_folder_is_verified_without_loading_usd_or_the_generators(
    portunus_temple, tmp_path
):
    """The up-to-date path hashes files: it must not import pxr, manifold3d, xatlas or scipy
    (their imports alone are most of a second)."""
    import subprocess
    import sys

    folder = tmp_path / "T"
    shutil.copytree(portunus_temple.root.parent, folder)
    code = (
        "import sys\n"
        "from ionic_usd.pipeline.temple import compose_temple\n"
        "from ionic_usd.temple.layout import portunus_layout\n"
        f"rep = compose_temple({str(folder)!r}, portunus_layout(), force=True, texture_size=64)\n"
        "assert rep.current, rep\n"
        "heavy = {'pxr', 'manifold3d', 'xatlas', 'scipy', 'OpenImageIO', 'numba'}\n"
        "print(sorted(heavy & {m.split('.')[0] for m in sys.modules}))\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, timeout=120
    )
    assert out.stdout.strip() == "[]", out.stdout


def test_the_asset_command_verifies_an_unchanged_folder_too(tmp_path, capsys):
    out = tmp_path / "A"
    argv = ["asset", "-o", str(out), "--texture-size", "16"]
    assert main(argv) == 0 and capsys.readouterr().out.startswith("wrote ")
    before = _files(out)
    assert main([*argv, "--force"]) == 0
    assert capsys.readouterr().out.startswith("up to date ")
    assert _files(out) == before
    (out / "Payload" / "Materials.usda").write_text("#usda 1.0\n")  # damaged: rebuilt
    assert main([*argv, "--force"]) == 0 and capsys.readouterr().out.startswith("wrote ")
    assert _digests(out) == {k: v[0] for k, v in before.items()}
    assert main([*argv, "--force", "--rebuild"]) == 0
    assert capsys.readouterr().out.startswith("wrote ")
