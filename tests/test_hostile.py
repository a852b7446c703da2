"""Hostile input to the command line (issue 11): every case is refused with exit status 2, one
line on stderr (a grammar error may add its source and caret), no traceback, nothing written.
"""

from __future__ import annotations

import contextlib
import os
import subprocess
import sys
from pathlib import Path

import pytest

from ionic_usd.cli import main

LONG = "a" * 300

# (argv, files to create first {name: bytes or None for a folder}, text expected in the message)
CASES: list[tuple[list[str], dict[str, bytes | None], str]] = [
    # tracebacks of issue 11
    (["column", "--base", "R0.1 H0 R0.2 H0", "-o", "c.usda"], {}, "base"),
    (["column", "--scroll", "R0 P0, R0 P1", "-o", "c.usda"], {}, "scroll"),
    (["city", "c", "--seed", "-1"], {"c": None}, "--seed"),
    (["city", "c", "--block", "inf"], {"c": None}, "--block"),
    (["city", "c", "--block", "1e308"], {"c": None}, "--block"),
    (["city", "c", "--block", "nan"], {"c": None}, "--block"),
    (["city", "c", "--temple", "../../etc"], {"c": None}, "--temple"),
    (["asset", "-o", ".", "--force"], {}, "output"),
    (["temple", "-o", ".", "--force"], {}, "output"),
    (["temple", "-o", "..", "--force"], {}, "output"),
    (["shaft", "-o", LONG + ".usda"], {}, "255"),
    (["temple", "-o", LONG], {}, "255"),
    (["shaft", "-o", "afile/x.usda"], {"afile": b"x"}, "afile is a file"),
    (["temple", "-o", "afile/T"], {"afile": b"x"}, "afile is a file"),
    (["shaft", "-o", "d.usda", "--force"], {"d.usda": None}, "folder"),
    (
        ["preview", "scene.usda", "-o", "p.png", "--force"],
        {"p.png": None, "scene.usda": b"#usda 1.0\n"},
        "folder",
    ),
    (["temple", "-o", "T", "--force"], {"T": b"a file"}, "existing file"),
    # TOML: types, encoding, nesting, ranges
    (["column", "--config", "bin.toml"], {"bin.toml": bytes(range(256)) * 4}, "UTF-8"),
    (["column", "--config", "a.toml"], {"a.toml": b'[column]\nlod = ["high"]\n'}, "lod"),
    (["column", "--config", "a.toml"], {"a.toml": b"[column]\nbase = 5\n"}, "base"),
    (["column", "--config", "a.toml"], {"a.toml": b'[column]\nbase_height = "x"\n'}, "base_height"),
    (["column", "--config", "a.toml"], {"a.toml": b"column = 5\n"}, "column"),
    (["column", "--config", "a.toml"], {"a.toml": b"[shaft]\nflutes = true\n"}, "flutes"),
    (["column", "--config", "a.toml"], {"a.toml": b"[shaft]\nheight = 1e308\n"}, "height"),
    (["column", "--config", "a.toml"], {"a.toml": b"[shaft]\nheight = nan\n"}, "height"),
    (["column", "--config", "a.toml"], {"a.toml": b"[volute]\nthickness = inf\n"}, "thickness"),
    (
        ["column", "--config", "a.toml"],
        {"a.toml": b"[capital]\nring_segments = 1e7\n"},
        "ring_segments",
    ),
    (
        ["column", "--config", "a.toml"],
        {"a.toml": b"[capital]\nspiral_samples = 100000000\n"},
        "spiral_samples",
    ),
    (
        ["column", "--config", "a.toml"],
        {"a.toml": b"a = " + b"[" * 5000 + b"]" * 5000 + b"\n"},
        "nested",
    ),
    (["column", "--config", "missing.toml"], {}, "missing.toml"),
    (["column", "--config", "dir.toml"], {"dir.toml": None}, "folder"),
    (["temple", "--config", "a.toml", "-o", "T"], {"a.toml": b"temple = 5\n"}, "temple"),
    (["temple", "--config", "a.toml", "-o", "T"], {"a.toml": b"podium = 5\n"}, "podium"),
    (["temple", "--config", "a.toml", "-o", "T"], {"a.toml": b"[temple]\nname = 5\n"}, "name"),
    (
        ["temple", "--config", "a.toml", "-o", "T"],
        {"a.toml": b"[podium]\nheight = 1e300\n"},
        "podium.height",
    ),
    (
        ["temple", "--config", "a.toml", "-o", "T"],
        {
            "a.toml": b'extends = "portunus"\n'
            b'[[hypothesis]]\nid = "h"\ndescription = ""\nsources = []\n'
            b'certainty = "low"\n'
            b'changes = { "column.flute_count" = "abc" }\n'
        },
        "column.flute_count",
    ),
    (
        ["temple", "--config", "a.toml", "-o", "T"],
        {
            "a.toml": b'extends = "portunus"\n'
            b'[[hypothesis]]\nid = "../../ESCAPED"\ndescription = ""\nsources = []\n'
            b'certainty = "low"\nchanges = { "roof.tympanum_ratio" = 8.0 }\n'
        },
        "id",
    ),
    (
        ["temple", "--config", "a.toml", "-o", "T"],
        {
            "a.toml": b'extends = "portunus"\n'
            b'[[hypothesis]]\nid = "a/b"\ndescription = ""\nsources = []\n'
            b'certainty = "low"\nchanges = { "roof.tympanum_ratio" = 8.0 }\n'
        },
        "id",
    ),
    (
        ["temple", "--config", "a.toml", "-o", "T"],
        {
            "a.toml": b'extends = "portunus"\n'
            b'[[hypothesis]]\nid = "a-b"\ndescription = ""\nsources = []\n'
            b'certainty = "low"\nchanges = { "roof.tympanum_ratio" = 8.0 }\n'
            b'[[hypothesis]]\nid = "a_b"\ndescription = ""\nsources = []\n'
            b'certainty = "low"\nchanges = { "roof.tympanum_ratio" = 7.0 }\n'
        },
        "a-b",
    ),
    (
        ["temple", "--config", "a.toml", "-o", "T"],
        {
            "a.toml": b'extends = "portunus"\n'
            b'[[cuboid]]\nname = "a-b"\nmin = [0, 0, 0]\nmax = [1, 1, 1]\n'
            b'layer = "cella"\n'
            b'[[cuboid]]\nname = "a_b"\nmin = [2, 0, 0]\nmax = [3, 1, 1]\nlayer = "cella"\n'
        },
        "a-b",
    ),
    (
        ["temple", "--config", "a.toml", "-o", "T"],
        {
            "a.toml": b'extends = "portunus"\n'
            b'[[cuboid]]\nname = "big"\nmin = [-1e300, 0, 0]\nmax = [1e300, 1, 1]\n'
            b'layer = "cella"\n'
        },
        "min",
    ),
    # non-finite or absurd numbers on the command line
    (["shaft", "--height", "1e308"], {}, "height"),
    (["shaft", "--top-radius", "1e308"], {}, "top_radius"),
    (["shaft", "--bottom-radius", "1e308"], {}, "bottom_radius"),
    (["shaft", "--arc-ratio", "1e308"], {}, "arc_ratio"),
    (["shaft", "--ring-bottom", "1e308"], {}, "ring_bottom"),
    (["shaft", "--height", "nan"], {}, "height"),
    (["column", "--base", "R1e308 H1 R0 H2", "-o", "c.usda"], {}, "base"),
    (["column", "--base", "R0.074 H4 R0.074 H0.05", "-o", "c.usda"], {}, "inside out or flat"),
    # resources: refused with the estimate and the limit, before any allocation
    (["shaft", "--flute-slices", "100000"], {}, "triangles"),
    (
        ["column", "--config", "a.toml"],
        {"a.toml": b'[column]\nlod = "custom"\n[shaft]\nflute_slices = 100000\n'},
        "limit",
    ),
    (
        ["column", "--config", "a.toml"],
        {"a.toml": b'[column]\nlod = "custom"\n[capital]\nspiral_samples = 900000\n'},
        "limit",
    ),
    (["city", "c", "--rows", "1000", "--cols", "1000"], {"c": None}, "limit"),
    (["asset", "--texture-size", "8192", "-o", "A"], {}, "--max-memory"),
    (["asset", "--max-memory", "nan", "-o", "A"], {}, "--max-memory"),
    # collisions and bad user textures
    (
        ["asset", "--texture", "basecolor=a.png", "--texture", "basecolor=b.png", "-o", "A"],
        {},
        "basecolor",
    ),
    (["asset", "--texture", "albedo=a.png", "-o", "A"], {}, "--texture"),
    # argparse's own refusals stay one line too
    (["shaft", "--height", "tall"], {}, "height"),
    (["nonsense"], {}, "invalid choice"),
]


def _listing(root: Path) -> list[tuple[str, int]]:
    out = []
    for dirpath, dirs, files in os.walk(root):
        for name in dirs + files:
            p = Path(dirpath) / name
            out.append((str(p.relative_to(root)), p.lstat().st_size if p.is_file() else -1))
    return sorted(out)


@contextlib.contextmanager
def _cwd(path: Path):
    old = Path.cwd()
    os.chdir(path)
    try:
        yield
    finally:
        os.chdir(old)


def run_cli(argv: list[str], cwd: Path, capsys) -> tuple[int, str, str]:
    with _cwd(cwd):
        try:
            code = main(argv)
        except SystemExit as exc:  # argparse
            code = exc.code if isinstance(exc.code, int) else 1
    cap = capsys.readouterr()
    return code, cap.out, cap.err


def assert_clean_refusal(code: int, err: str, needle: str) -> None:
    lines = err.splitlines()
    assert code == 2, err
    assert lines and "error:" in lines[0], err
    assert "Traceback" not in err
    # one line; a grammar error adds exactly its source line and the caret line
    assert len(lines) == 1 or (len(lines) == 3 and lines[2].strip().startswith("^")), err
    assert needle in err, err


@pytest.mark.parametrize("argv,files,needle", CASES, ids=[" ".join(c[0])[:60] for c in CASES])
def test_refused_cleanly_and_nothing_written(tmp_path, capsys, argv, files, needle):
    for name, data in files.items():
        if data is None:
            (tmp_path / name).mkdir()
        else:
            (tmp_path / name).write_bytes(data)
    before = _listing(tmp_path)
    code, _out, err = run_cli(argv, tmp_path, capsys)
    assert_clean_refusal(code, err, needle)
    assert _listing(tmp_path) == before
    assert _listing(tmp_path.parent / tmp_path.name) == before


def test_process_level_no_traceback(tmp_path):
    """The same guarantees for a real process (deep nesting and binary input)."""
    (tmp_path / "deep.toml").write_text("a = " + "[" * 5000 + "]" * 5000 + "\n")
    (tmp_path / "bin.toml").write_bytes(os.urandom(4096))
    env = {**os.environ, "PYTHONPATH": str(Path(__file__).resolve().parents[1])}
    env.pop("IONIC_USD_DEBUG", None)
    for cfg in ("deep.toml",):  # bin.toml and the rest: in-process above
        before = _listing(tmp_path)
        r = subprocess.run(
            [sys.executable, "-m", "ionic_usd.cli", "column", "--config", cfg],
            cwd=tmp_path,
            env=env,
            capture_output=True,
            text=True,
            timeout=120,
        )
        assert r.returncode == 2 and len(r.stderr.splitlines()) == 1, r.stderr
        assert "Traceback" not in r.stderr and cfg in r.stderr
        assert _listing(tmp_path) == before


def test_big_png_refused_before_decoding(tmp_path):
    """A 20000² PNG is small on disk; its header is read, its pixels never are."""
    import struct
    import zlib

    from ionic_usd.texture.stone import TextureError, validate_user_texture

    def chunk(tag: bytes, data: bytes) -> bytes:
        return (
            struct.pack(">I", len(data))
            + tag
            + data
            + struct.pack(">I", zlib.crc32(tag + data) & 0xFFFFFFFF)
        )

    n = 20000
    z = zlib.compressobj(1)
    row = bytes(n + 1)  # filter byte + grey pixels
    idat = b"".join(z.compress(row) for _ in range(n)) + z.flush()
    p = tmp_path / "huge.png"
    ihdr = chunk(b"IHDR", struct.pack(">IIBBBBB", n, n, 8, 0, 0, 0, 0))
    p.write_bytes(b"\x89PNG\r\n\x1a\n" + ihdr + chunk(b"IDAT", idat) + chunk(b"IEND", b""))
    assert p.stat().st_size < 2_000_000
    import resource

    rss0 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    with pytest.raises(TextureError, match="20000x20000"):
        validate_user_texture(p)
    assert resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - rss0 < 100_000  # KB


def test_internal_error_is_one_line_status_70(tmp_path, capsys, monkeypatch):
    """A bug (an unexpected exception) still prints one line, with a distinct status."""
    import ionic_usd.cli as cli

    def boom(_args):
        raise KeyError("bug")

    monkeypatch.delenv("IONIC_USD_DEBUG", raising=False)
    parser = cli.build_parser()
    parser.parse_args(["shaft"])  # the sub-parser exists
    sub = parser._subparsers._group_actions[0]
    sub.choices["shaft"].set_defaults(func=boom)
    monkeypatch.setattr(cli, "build_parser", lambda *_a, **_k: parser)
    code, _, err = run_cli(["shaft"], tmp_path, capsys)
    assert code == 70 and len(err.splitlines()) == 1 and "KeyError" in err
    assert _listing(tmp_path) == []
