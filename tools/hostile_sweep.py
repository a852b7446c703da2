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
    # 2b. the volute's free chain (arc_radii, arc_sweeps): lengths, signs, sizes, models
    centred = 'volute_model = "centred_arcs"\n'
    for chain in (
        "arc_radii = [0.03, -0.04]",
        "arc_radii = [0.03, nan]",
        "arc_radii = [0.03, inf]",
        "arc_radii = [0.03, 0.04]",
        'arc_radii = ["a", "b"]',
        "arc_radii = [[0.03]]",
        "arc_radii = [" + ", ".join(["0.03"] * 100_000) + "]",
        "arc_radii = [0.03, 0.04]\narc_sweeps = [90, 90, 90]",
        "arc_radii = [0.03, 0.04]\narc_sweeps = [0]",
        "arc_radii = [0.03, 0.04]\narc_sweeps = [1e300]",
        "arc_sweeps = [90.0]",
    ):
        for model in (centred, ""):
            out.append(
                (
                    ["column", "--config", "c.toml", "-o", "c.usda"],
                    {"c.toml": f"[volute]\n{model}{chain}\n".encode()},
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
                    {"t.toml": f'extends = "portunus"\n[{sec}]\n{key} = {v}\n'.encode()},
                )
            )
    for hid in ("../../ESCAPED", "a/b", "", " ", ".", "..", "x" * 100, "a b", "ü", "1abc"):
        out.append(
            (
                ["temple", "--config", "t.toml", "-o", "T"],
                {
                    "t.toml": (
                        'extends = "portunus"\n'
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
                    "t.toml": 'extends = "portunus"\n'
                    f'[[cuboid]]\nname = "c"\nmin = {lo}\nmax = {hi}\n'
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
    out += cases_31()
    return out + fit_scan_cases()


def cases_31() -> list[tuple[list[str], dict[str, bytes | None]]]:
    """Issue 31: the flag schema on every command, city's checks before work, export scales,
    temple descriptions' tables and hypotheses, names and values that used to pass (the case
    list of tests/test_hostile_31.py), and more values of the same flags."""
    from tests.test_hostile_31 import CASES, SCENE, _hypotheses

    out: list[tuple[list[str], dict[str, bytes | None]]] = []
    for argv, files, _needle in CASES:
        files = {
            k: (_hypotheses(int(v[1:])) if v is not None and v.startswith(b"@") else v)
            for k, v in files.items()
        }
        out.append((list(argv), files))
    sizes = ["0", "-1", "3", "15", "100", "1000", "16384", "1e3", "x", ""]
    for cmd in (["asset", "-o", "A"], ["temple", "-o", "T"], ["city", "c"]):
        for v in sizes:
            out.append(([*cmd, "--texture-size", v], {}))
        for v in ("-1", "2**63", "9223372036854775808", "1.5", "x"):
            out.append(([*cmd, "--seed", v], {}))
    mem = ["0", "-1", "nan", "inf", "0.01", "1e300", "x"]
    for cmd in (
        ["shaft"],
        ["column"],
        ["asset", "-o", "A"],
        ["temple", "-o", "T"],
        ["city", "c"],
        ["preview", "s.usda", "-o", "p.png"],
        ["export", "s.usda", "-o", "s.glb"],
        ["evaluate", "--part", "base", "--reference", "r.csv"],
        ["fit", "shaft", "--reference", "r.csv"],
    ):
        for v in mem:
            out.append(([*cmd, "--max-memory", v], {"s.usda": SCENE, "r.csv": _CSV}))
    for v in ("-1", "0"):
        out.append((["city", "c", "--memory-limit", v], {}))
    for name in ("a\nb.usda", "a\tb.usda", "a\x7fb.usda", "a\rb.usda"):
        out.append((["shaft", "-o", name], {}))
    for v in ("", " ", "HIGH"):
        out.append((["column", "--lod", v, "-o", "c.usda"], {}))
    for v in ("3", "8", "100", "10000"):
        out.append((["shaft", "--flute-slices-per-fillet-slice", v], {}))
    for a in ("tcp://1.2.3.4", "tcp://:80", "tls://[::1]", "ws://a_b:80", "tcp://x:-1", "x"):
        out.append((["city", "c", "--scheduler", a], {}))
    for v in ("-5", "x", "1.5"):
        out.append((["city", "c", "--instancer-threshold", v], {}))
    for j in ("d/x.json", "x.JSON.txt", "c"):
        out.append((["city", "c", "--json", j], {"d": b"a file"}))
    for v in ("1e-5", "100", "1:1e9", "nan", "1:-2"):
        out.append((["export", "s.usda", "-o", "s.stl", "--scale", v], {"s.usda": SCENE}))
    for v in ("lod=bogus", "base=G9", "x=y"):
        out.append(
            (
                [
                    "evaluate",
                    "--usd",
                    "s.usda",
                    "--variant",
                    v,
                    "--part",
                    "base",
                    "--reference",
                    "r.csv",
                ],
                {"s.usda": SCENE, "r.csv": _CSV},
            )
        )
    return out


_CSV = b"0,0\n0.1,0.05\n0.2,0.1\n"


# --- temple types and presets (issue 34): a separate block --------------------------------
def temple_type_cases() -> list[tuple[list[str], dict[str, bytes | None]]]:
    """``temple --preset`` and ``[type]`` documents with bad values (every key x TOML_BAD)."""
    from ionic_usd.temple.vitruvius import TYPE_SCHEMA

    out: list[tuple[list[str], dict[str, bytes | None]]] = []
    for v in ("nosuch", "", "../portunus", "PRIENE", "portunus.toml"):
        out.append((["temple", "--preset", v, "-o", "T"], {}))
    out.append((["temple", "--preset", "nike", "--config", "t.toml", "-o", "T"], {"t.toml": b""}))
    out.append((["presets", "extra"], {}))
    for v in ("nosuch", "", "missing.toml", "t.toml"):
        out.append((["city", "C", "--rows", "1", "--cols", "1", "--temple", v], {"t.toml": b"x"}))
    head = '[type]\narrangement = "peripteral"\nfront = 6\nlower_diameter = 1.2\n'
    for key in TYPE_SCHEMA:
        for v in TOML_BAD:
            body = "\n".join(line for line in head.splitlines() if not line.startswith(key + " "))
            doc = f"{body}\n{key} = {v}\n".encode()
            out.append((["temple", "--config", "t.toml", "-o", "T"], {"t.toml": doc}))
    for doc in (
        b'[type]\narrangement = "dipteral"\nfront = 4\nlower_diameter = 1\n',
        b'[type]\narrangement = "peripteral"\nfront = 6\n',
        b"[type]\nfront = 6\nlower_diameter = 1\n",
        b'[type]\narrangement = "peripteral"\nfront = 6\nstylobate_width = 3\nclear_bay = 3\n'
        b"lower_diameter = 1\n",
        b'[type]\narrangement = "peripteral"\nfront = 6\nlower_diameter = 1\n'
        b"[podium]\nheight = 2\n",
        b'[type]\narrangement = "peripteral"\nfront = 6\nlower_diameter = 1\n[[hypothesis]]\n'
        b'id = "a"\ndescription = "d"\nsources = []\ncertainty = "low"\n'
        b'changes = { "type.front" = 3 }\n',
    ):
        out.append((["temple", "--config", "t.toml", "-o", "T"], {"t.toml": doc}))
    return out


def paradata_cases() -> list[tuple[list[str], dict[str, bytes | None]]]:
    """``ionic-usd paradata``, ``ionic-usd web``, ``temple --paradata``, ``preview --view``."""
    not_temple = {"s.usda": b'#usda 1.0\n(defaultPrim = "T")\ndef Xform "T" {}\n'}
    junk = {"s.usda": os.urandom(512)}
    out: list[tuple[list[str], dict[str, bytes | None]]] = []
    for cmd in (["paradata"], ["web"]):
        out.append(([*cmd, "missing.usda"], {}))
        out.append(([*cmd, "s.usda"], not_temple))
        out.append(([*cmd, "s.usda"], junk))
        out.append(([*cmd, "d.usda"], {"d.usda": None}))
    out.append((["paradata", "s.usda", "-o", "g.txt"], not_temple))
    out.append((["web", "s.usda", "-o", "site"], {**not_temple, "site": None}))
    unit = (
        '<graphml xmlns="http://graphml.graphdrawing.org/xmlns" '
        'xmlns:y="http://www.yworks.com/xml/graphml"><key id="g" for="node" '
        'yfiles.type="nodegraphics"/><graph><node id="n0"><data key="g"><y:ShapeNode>'
        '<y:BorderStyle color="{c}"/><y:NodeLabel>{label}</y:NodeLabel><y:Shape type="{s}"/>'
        "</y:ShapeNode></data></node></graph></graphml>"
    )
    graphs = [
        os.urandom(256),
        b"",
        b"<graphml>",
        unit.format(c="#9B3333", label="roof", s="star").encode(),
        unit.format(c="#123456", label="roof", s="octagon").encode(),
        unit.format(c="#9B3333", label="nave", s="rectangle").encode(),
        unit.format(c="#9B3333", label="hyp:no-such", s="rectangle").encode(),
        b"<!DOCTYPE x [<!ENTITY a 'aaaa'><!ENTITY b '&a;&a;&a;&a;'>]><graphml>&b;</graphml>",
    ]
    for g in graphs:
        out.append((["temple", "-o", "T", "--paradata", "e.graphml"], {"e.graphml": g}))
    out.append((["temple", "-o", "T", "--paradata", "missing.graphml"], {}))
    out.append((["preview", "s.usda", "-o", "p.png", "--view", "xray"], not_temple))
    return out


# --- fit helper's block: scans and sections that are not what `fit` expects (issue 31) ---
def fit_scan_cases() -> list[tuple[list[str], dict[str, bytes | None]]]:
    """Scans no column gives and closed sections no shaft gives: each must be refused."""
    import numpy as np

    rng = np.random.default_rng(31)
    head = b"ply\nformat %s 1.0\nelement vertex 200\n" + b"".join(
        b"property float %s\n" % c for c in (b"x", b"y", b"z")
    )
    xyz = rng.random((200, 3)).astype("<f4").tobytes()
    sphere = rng.normal(size=(3000, 3))
    sphere /= np.linalg.norm(sphere, axis=1)[:, None]
    scans = {
        "garbage.ply": head % b"ascii" + b"end_header\n" + b"foo bar baz\n" * 200,
        "truncated.ply": head % b"binary_little_endian" + b"end_header\n" + xyz[:1000],
        "same.xyz": b"1 1 1\n" * 5000,
        "huge.xyz": _rows(1e300 * (1 + rng.random((2000, 3)))),
        "plane.xyz": _rows(np.c_[rng.random((3000, 2)) * 2, np.zeros(3000)]),
        "line.xyz": _rows(np.outer(rng.random(3000), [1.0, 2.0, 3.0])),
        "sphere.xyz": _rows(sphere),
        # a "colonnade" of three spheres: split into three clusters, none a column
        "spheres.xyz": _rows(np.vstack([sphere + [5.0 * k, 0.0, 0.0] for k in range(3)])),
    }
    out: list[tuple[list[str], dict[str, bytes | None]]] = [
        (["fit", "column", "--scan", name, "-o", "out"], {name: data})
        for name, data in scans.items()
    ]
    t = np.linspace(0.0, 2.0 * np.pi, 400)
    eight = np.c_[0.3 * np.sin(t), 0.2 * np.sin(2.0 * t)]
    corners = np.array([[0.0, 0.0], [0.6, 0.0], [0.3, 0.5], [0.0, 0.0]])
    tri = np.concatenate(
        [
            np.linspace(a, b, 60, endpoint=False)
            for a, b in zip(corners[:-1], corners[1:], strict=True)
        ]
    )
    for name, sec in (("eight.csv", eight), ("triangle.csv", np.vstack([tri, tri[:1]]))):
        data = "\n".join(f"{x:.9g},{y:.9g}" for x, y in sec).encode()
        out.append(
            (["fit", "shaft", "--section", "--reference", name, "-o", "f.toml"], {name: data})
        )
    return out


def _rows(a) -> bytes:
    return "\n".join(" ".join(f"{v:.17g}" for v in r) for r in a).encode()


# --- end of the fit helper's block ---


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
    todo = cases(args.quick) + temple_type_cases() + paradata_cases()
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
    by_command: dict[str, Counter[str]] = {}
    for i, (cmd, files) in enumerate(todo, 1):
        kind, detail = run_case(cmd, files)
        counts[kind] += 1
        by_command.setdefault(cmd[0] if cmd else "-", Counter())[kind] += 1
        if kind != "refused":
            print(f"{kind.upper()} {cmd}: {detail}", flush=True)
        if i % 50 == 0:
            print(f"... {i}/{len(todo)} {dict(counts)}", file=sys.stderr, flush=True)
    for name, c in sorted(by_command.items()):
        print(
            f"  {name}: {sum(c.values())} cases, refused cleanly {c['refused']}, accepted "
            f"{c['accepted']}, anything else {c['other']}"
        )
    total = len(todo) + counts["fault cases"]
    print(
        f"cases {total} ({counts['fault cases']} on read-only/full file systems): refused "
        f"cleanly {counts['refused']}, accepted (valid, finite) {counts['accepted']}, "
        f"anything else {counts['other']}"
    )
    return 1 if counts["other"] else 0


if __name__ == "__main__":
    sys.exit(main())
