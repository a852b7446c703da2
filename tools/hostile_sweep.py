"""Hostile sweep of the command line: many bad inputs, each classified.

Every case runs ``ionic_usd.cli.main`` in a fresh empty folder (in-process, so hundreds of
cases take minutes, not hours) and is counted as

* ``refused``  — exit status 2, one stderr line (a grammar error may add its source + caret),
  no traceback, the folder exactly as before;
* ``accepted`` — exit 0 and every USD file written holds only finite numbers (the value was
  valid after all, e.g. ``--entasis 0``);
* ``other``    — anything else (a traceback, status 70, several lines, a refusal that wrote a
  file, a non-finite value in a file): each is printed.

Usage: ``python tools/hostile_sweep.py [--quick]``; prints the counts and exits 1 if any case
is ``other``.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import os
import random
import sys
import tempfile
from collections import Counter
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

BAD_NUMBERS = ["nan", "inf", "-inf", "1e308", "-1e308", "1e-320", "abc", "", "0x10", "1e400"]
TOML_BAD = [
    "nan",
    "inf",
    "-inf",
    "1e308",
    "-1e308",
    '"x"',
    "[1, 2]",
    "{ a = 1 }",
    "true",
    "1979-05-27",
    '"' + "x" * 5000 + '"',
]
GRAMMAR_ALPHABET = "RHCPM0123456789.-+e, ()"


def _listing(root: Path) -> list[tuple[str, int]]:
    out = []
    for dirpath, dirs, files in os.walk(root):
        for n in dirs + files:
            p = Path(dirpath) / n
            out.append((str(p.relative_to(root)), p.lstat().st_size if p.is_file() else -1))
    return sorted(out)


def _usd_files_finite(root: Path) -> str | None:
    import numpy as np
    from pxr import Usd, UsdGeom

    for p in root.rglob("*.usd*"):
        stage = Usd.Stage.Open(str(p))
        if stage is None:
            return f"{p.name} does not open"
        for prim in stage.Traverse():
            if prim.IsA(UsdGeom.Mesh):
                for attr in ("points", "normals", "extent"):
                    v = prim.GetAttribute(attr).Get()
                    if v is not None and not np.isfinite(np.asarray(v)).all():
                        return f"{p.name} {prim.GetPath()}.{attr} is not finite"
    return None


def run_case(argv: list[str], files: dict[str, bytes | None]) -> tuple[str, str]:
    from ionic_usd.cli import main

    with tempfile.TemporaryDirectory(prefix="sweep-") as d:
        root = Path(d)
        for name, data in files.items():
            if data is None:
                (root / name).mkdir(parents=True)
            else:
                (root / name).parent.mkdir(parents=True, exist_ok=True)
                (root / name).write_bytes(data)
        before = _listing(root)
        err, out = io.StringIO(), io.StringIO()
        old = Path.cwd()
        os.chdir(root)
        try:
            with contextlib.redirect_stderr(err), contextlib.redirect_stdout(out):
                try:
                    code = main(argv)
                except SystemExit as exc:
                    code = exc.code if isinstance(exc.code, int) else 1
                except BaseException as exc:  # noqa: BLE001 - the sweep records anything
                    return "other", f"raised {type(exc).__name__}: {exc}"
        finally:
            os.chdir(old)
        text = err.getvalue()
        lines = text.splitlines()
        if code == 2:
            one = len(lines) == 1 or (len(lines) == 3 and lines[2].strip().startswith("^"))
            if one and "Traceback" not in text and _listing(root) == before:
                return "refused", lines[0] if lines else ""
            return "other", f"status 2 but {len(lines)} lines / files changed: {text[:300]}"
        if code == 0:
            bad = _usd_files_finite(root)
            return ("accepted", "") if bad is None else ("other", bad)
        return "other", f"status {code}: {text[:300]}"


def cases(quick: bool) -> list[tuple[list[str], dict[str, bytes | None]]]:
    from ionic_usd.column.capital import CapitalParams
    from ionic_usd.column.shaft import ShaftParams
    from ionic_usd.column.volute import VoluteParams
    from ionic_usd.params import dataclass_schema
    from ionic_usd.temple.layout import TempleParams

    rng = random.Random(2026)
    out: list[tuple[list[str], dict[str, bytes | None]]] = []
    # 1. every shaft flag x bad numbers
    for name in dataclass_schema(ShaftParams):
        flag = "--" + name.replace("_", "-")
        for v in BAD_NUMBERS:
            out.append((["shaft", flag, v, "-o", "s.usda"], {}))
    # 2. every TOML key of the column tables x bad values
    for table, cls in (
        ("shaft", ShaftParams),
        ("capital", CapitalParams),
        ("volute", VoluteParams),
    ):
        for key in dataclass_schema(cls):
            if key == "volute":
                continue
            for v in TOML_BAD[:: 2 if quick else 1]:
                out.append(
                    (
                        ["column", "--config", "c.toml", "-o", "c.usda"],
                        {"c.toml": f"[{table}]\n{key} = {v}\n".encode()},
                    )
                )
    for key in ("lod", "base", "base_height", "scroll"):
        for v in TOML_BAD:
            out.append(
                (["column", "--config", "c.toml"], {"c.toml": f"[column]\n{key} = {v}\n".encode()})
            )
    # 3. the temple's dimension sections, ids, cuboids, hypotheses
    for f in list(dataclass_schema(TempleParams))[:: 3 if quick else 1]:
        if f == "name":
            continue
        sec, key = f.split("_", 1)
        for v in ("nan", "1e308", '"x"', "-1", "0"):
            out.append(
                (
                    ["temple", "--config", "t.toml", "-o", "T"],
                    {"t.toml": f"[{sec}]\n{key} = {v}\n".encode()},
                )
            )
    for hid in ("../../ESCAPED", "a/b", "", " ", ".", "..", "x" * 100, "a b", "ü", "1abc"):
        out.append(
            (
                ["temple", "--config", "t.toml", "-o", "T"],
                {
                    "t.toml": (
                        f'[[hypothesis]]\nid = "{hid}"\ndescription = ""\nsources = []\n'
                        'certainty = "low"\nchanges = { "roof.tympanum_ratio" = 8.0 }\n'
                    ).encode()
                },
            )
        )
    for lo, hi in (
        ("[0,0,0]", "[1,1,1e300]"),
        ("[0,0,0]", "[nan,1,1]"),
        ("[0,0]", "[1,1,1]"),
        ('"a"', "[1,1,1]"),
        ("[0,0,0]", "[0,0,0]"),
        ("[1,1,1]", "[0,0,0]"),
    ):
        out.append(
            (
                ["temple", "--config", "t.toml", "-o", "T"],
                {
                    "t.toml": f'[[cuboid]]\nname = "c"\nmin = {lo}\nmax = {hi}\n'
                    f'layer = "cella"\n'.encode()
                },
            )
        )
    for doc in (
        "temple = 5",
        "podium = 5",
        "[temple]\nname = 5",
        "hypothesis = 5",
        "cuboid = 5",
        "[[cuboid]]\nname = 5",
        "[nonsense]\na = 1",
        "x = 1",
    ):
        out.append((["temple", "--config", "t.toml", "-o", "T"], {"t.toml": doc.encode()}))
    # 4. grammar garbage for --base and --scroll
    for _ in range(40 if quick else 150):
        text = "".join(rng.choice(GRAMMAR_ALPHABET) for _ in range(rng.randint(1, 30)))
        out.append((["column", "--lod", "low", "--base", text, "-o", "c.usda"], {}))
        out.append((["column", "--lod", "low", "--scroll", text, "-o", "c.usda"], {}))
    for text in (
        "R0.1 H0 R0.2 H0",
        "R0.074 H4 R0.074 H0.05",
        "R1e308 H1 R0 H2",
        "R0 H0",
        "R-5 H1 R0 H1",
    ):
        out.append((["column", "--lod", "low", "--base", text, "-o", "c.usda"], {}))
    for text in ("R0 P0, R0 P1", "R3 P0", "R1 P0.5, R1 P0.2", "R1e308 P0"):
        out.append((["column", "--lod", "low", "--scroll", text, "-o", "c.usda"], {}))
    # 5. outputs that cannot be written
    long = "a" * 300
    for argv, files in (
        (["shaft", "-o", "."], {}),
        (["shaft", "-o", ".."], {}),
        (["shaft", "-o", "/"], {}),
        (["shaft", "-o", long + ".usda"], {}),
        (["shaft", "-o", "f/x.usda"], {"f": b""}),
        (["shaft", "-o", "d.usda", "--force"], {"d.usda": None}),
        (["shaft", "-o", "x.txt"], {}),
        (["shaft", "-o", "e.usda"], {"e.usda": b"mine"}),
        (["temple", "-o", "."], {}),
        (["temple", "-o", ".", "--force"], {}),
        (["temple", "-o", long], {}),
        (["temple", "-o", "f/T"], {"f": b""}),
        (["temple", "-o", "T"], {"T": None}),
        (["temple", "-o", "T", "--force"], {"T": b"x"}),
        (["asset", "-o", ".", "--force"], {}),
        (["asset", "-o", "f/A"], {"f": b""}),
        (["preview", "s.usda", "-o", "p.png"], {}),
        (["preview", "s.usda", "-o", "p.jpg"], {"s.usda": b"#usda 1.0\n"}),
        (["city", "c", "--rows", "1", "--cols", "1"], {}),
        (["city", "c", "--rows", "1", "--cols", "1"], {"c": None}),
    ):
        out.append((argv, files))
    # 6. flags of city, asset, preview, evaluate
    for flag, vals in (
        ("--rows", ["0", "-1", "100000", "x"]),
        ("--cols", ["0", "1e3"]),
        ("--block", ["0", "-5", "nan", "inf", "1e308"]),
        ("--seed", ["-1", "1e30", "x"]),
        ("--temple", ["../x", "a/b", ""]),
        ("--max-memory", ["nan", "-1", "0", "inf"]),
    ):
        for v in vals:
            out.append((["city", "c", flag, v], {"c/PortunusTemple/Temple.usda": b"#usda 1.0\n"}))
    # 6b. a plan's temple lots naming bad presets and types
    ring = [[0, 0], [30, 0], [30, 40], [0, 40], [0, 0]]
    for props in (
        {"front": 5},
        {"front": "6"},
        {"intercolumniation": "wide"},
        {"arrangement": "dipteral"},
        {"preset": "nope"},
        {"preset": "portunus", "front": 4},
        {"lower_diameter": -1},
        {"lower_diameter": 40.0},
        {"front": 8, "lower_diameter": 2.5},
    ):
        feature = {
            "type": "Feature",
            "properties": {"type": "temple", **props},
            "geometry": {"type": "Polygon", "coordinates": [ring]},
        }
        doc = json.dumps({"type": "FeatureCollection", "features": [feature]}).encode()
        out.append((["city", "c", "--plan", "p.geojson"], {"p.geojson": doc}))
    for argv in (
        ["--texture-size", "8192"],
        ["--texture-size", "1000"],
        ["--texture-size", "-1"],
        ["--texture-size", "0"],
        ["--seed", "-1"],
        ["--texture", "basecolor"],
        ["--texture", "basecolor=a.png", "--texture", "basecolor=b.png"],
        ["--texture", "albedo=a.png"],
        [
            "--texture",
            "basecolor=missing.png",
            "--texture",
            "roughness=missing.png",
            "--texture",
            "normal=missing.png",
        ],
        ["--max-memory", "0.001"],
        ["--base", "G9"],
        ["--lod", "ultra"],
    ):
        out.append((["asset", "-o", "A", *argv], {}))
    for argv in (
        ["--width", "0"],
        ["--width", "100000"],
        ["--height", "-5"],
        ["--samples", "1000"],
        ["--background", "1,2"],
        ["--background", "nan,0,0"],
        ["--camera", "top"],
    ):
        out.append((["preview", "s.usda", "-o", "p.png", *argv], {"s.usda": b"#usda 1.0\n"}))
    csv = b"0,0\n0.1,0.05\n0.2,0.1\n"
    for argv in (
        ["--spacing", "1e-12"],
        ["--spacing", "0"],
        ["--spacing", "-1"],
        ["--spacing", "nan"],
        ["--spacing", "inf"],
        ["--scale", "nan"],
        ["--usd", "r.csv"],
        ["--usd", "missing.usda"],
    ):
        out.append((["evaluate", "--part", "base", "--reference", "r.csv", *argv], {"r.csv": csv}))
    for ref in (b"", b"x,y\n", b"nan,1\n1,2\n", b"\xff\xfe\x00", b"1,2\n" * 3):
        out.append((["evaluate", "--part", "base", "--reference", "r.csv"], {"r.csv": ref}))
    # 7. config files that are not TOML
    for data in (
        os.urandom(2048),
        b"\x00" * 10,
        b"a = " + b"[" * 5000 + b"]" * 5000,
        b"[column",
        "ü = 1".encode("latin-1"),
    ):
        out.append((["column", "--config", "c.toml"], {"c.toml": data}))
    out.append((["column", "--config", "d.toml"], {"d.toml": None}))
    out.append((["column", "--config", "missing.toml"], {}))
    return out


def fault_cases() -> list[tuple[list[str], dict[str, bytes | None]]]:
    """Outputs onto a read-only and onto a full file system ({RO}, {FULL}; root only)."""
    outs = [
        ["shaft", "-o", "{D}/s.usda"],
        ["column", "--lod", "low", "-o", "{D}/c.usda"],
        ["column", "--lod", "low", "-o", "{D}/c.usdc"],
        ["temple", "-o", "{D}/T", "--texture-size", "16"],
        ["asset", "-o", "{D}/A", "--texture-size", "16"],
        ["preview", "s.usda", "-o", "{D}/p.png", "--width", "64", "--height", "64"],
        ["city", "{D}"],
        ["evaluate", "--part", "base", "--reference", "r.csv", "--json", "{D}/e.json"],
        ["fit", "shaft", "--reference", "r.csv", "-o", "{D}/f.toml"],
    ]
    files: dict[str, bytes | None] = {"s.usda": _SCENE, "r.csv": b"0,0\n0.1,0.05\n0.2,0.1\n"}
    return [
        ([a.replace("{D}", d) for a in argv], files) for d in ("{RO}", "{FULL}") for argv in outs
    ]


_SCENE = (
    b'#usda 1.0\n(defaultPrim = "C")\ndef Mesh "C" {\n  int[] faceVertexCounts = [3, 3, 3, 3]'
    b"\n  int[] faceVertexIndices = [0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3]\n"
    b"  point3f[] points = [(0,0,0), (1,0,0), (0,1,0), (0,0,1)]\n}\n"
)


@contextlib.contextmanager
def fault_mounts():
    """(ro, full) tmpfs folders, or None when not root."""
    import subprocess

    if not hasattr(os, "geteuid") or os.geteuid() != 0:
        yield None
        return
    base = Path(tempfile.mkdtemp(prefix="sweep-mounts-"))
    ro, full = base / "ro", base / "full"
    ro.mkdir()
    full.mkdir()
    try:
        subprocess.run(["mount", "-t", "tmpfs", "-o", "size=1m", "tmpfs", str(ro)], check=True)
        subprocess.run(["mount", "-o", "remount,ro", str(ro)], check=True)
        subprocess.run(["mount", "-t", "tmpfs", "-o", "size=64k", "tmpfs", str(full)], check=True)
        st = os.statvfs(full)  # leave 2 kB: even a small JSON or TOML does not fit
        with contextlib.suppress(OSError), open(full / "filler", "wb") as fh:
            fh.write(b"\0" * max(0, st.f_bavail * st.f_frsize - 2048))
        yield ro, full
    finally:
        for m in (ro, full):
            subprocess.run(["umount", "-l", str(m)], capture_output=True)
        with contextlib.suppress(OSError):
            ro.rmdir()
            full.rmdir()
            base.rmdir()


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="fewer cases (about a third)")
    args = ap.parse_args(argv)
    os.environ.pop("IONIC_USD_DEBUG", None)
    todo = cases(args.quick)
    counts: Counter[str] = Counter()
    with fault_mounts() as mounts:
        if mounts is None:
            print("not root: the read-only / full-disk cases are skipped", file=sys.stderr)
        else:
            for cmd, files in fault_cases():
                folder = mounts[0] if "{RO}" in cmd[-1] + " ".join(cmd) else mounts[1]
                cmd = [
                    a.replace("{RO}", str(mounts[0])).replace("{FULL}", str(mounts[1])) for a in cmd
                ]
                before = _listing(folder)
                kind, detail = run_case(cmd, files)
                if kind == "refused" and _listing(folder) != before:
                    kind, detail = "other", f"wrote into {folder}: {_listing(folder)}"
                counts[kind] += 1
                counts["fault cases"] += 1
                if kind != "refused":
                    print(f"{kind.upper()} {cmd}: {detail}", flush=True)
    for i, (cmd, files) in enumerate(todo, 1):
        kind, detail = run_case(cmd, files)
        counts[kind] += 1
        if kind != "refused":
            print(f"{kind.upper()} {cmd}: {detail}", flush=True)
        if i % 50 == 0:
            print(f"... {i}/{len(todo)} {dict(counts)}", file=sys.stderr, flush=True)
    total = len(todo) + counts["fault cases"]
    print(
        f"cases {total} ({counts['fault cases']} on read-only/full file systems): refused "
        f"cleanly {counts['refused']}, accepted (valid, finite) {counts['accepted']}, "
        f"anything else {counts['other']}"
    )
    return 1 if counts["other"] else 0


if __name__ == "__main__":
    sys.exit(main())
