"""Issue 31: the last bad inputs refused at the boundary — exit 2, one line naming the
problem, nothing written (the folder listing unchanged)."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.test_hostile import _listing, assert_clean_refusal, run_cli

SCENE = (
    b'#usda 1.0\n(defaultPrim = "Base")\ndef Mesh "Base" {\n'
    b"  int[] faceVertexCounts = [3, 3, 3, 3]\n"
    b"  int[] faceVertexIndices = [0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3]\n"
    b"  point3f[] points = [(0,0,0), (1,0,0), (0,1,0), (0,0,1)]\n}\n"
)
CSV = b"0,0\n0.1,0.05\n0.2,0.1\n"


def _plan(*features: str) -> bytes:
    return ('{"type": "FeatureCollection", "features": [' + ", ".join(features) + "]}").encode()


def _lot(fid: str, x0: float, y0: float, x1: float, y1: float) -> str:
    ring = f"[[{x0}, {y0}], [{x1}, {y0}], [{x1}, {y1}], [{x0}, {y1}], [{x0}, {y0}]]"
    return (
        f'{{"type": "Feature", "properties": {{"type": "temple", "id": "{fid}"}}, '
        f'"geometry": {{"type": "Polygon", "coordinates": [{ring}]}}}}'
    )


PORTUNUS = (Path(__file__).resolve().parents[1] / "ionic_usd/data/portunus.toml").read_text()


def _without(table: str) -> bytes:
    """portunus.toml without one table (its header and keys, up to the next header)."""
    out, skip = [], False
    for line in PORTUNUS.splitlines():
        if line.startswith("["):
            skip = line.strip() == f"[{table}]"
        if not skip:
            out.append(line)
    text = "\n".join(out) + "\n"
    assert f"[{table}]" not in text
    return text.encode()


# (argv, files {name: bytes or None for a folder}, text the message must hold)
CASES: list[tuple[list[str], dict[str, bytes | None], str]] = [
    # one schema for --texture-size / --seed / --max-memory on every command that has them
    *[
        (["asset", "-o", "A", "--texture-size", v], {}, "--texture-size")
        for v in ("0", "-1", "3", "15", "100", "x")
    ],
    *[
        (["temple", "-o", "T", "--texture-size", v], {}, "--texture-size")
        for v in ("0", "3", "100")
    ],
    (["city", "c", "--texture-size", "100"], {}, "--texture-size"),
    (["asset", "-o", "A", "--seed", "-1"], {}, "--seed"),
    (["temple", "-o", "T", "--seed", "-1"], {}, "--seed"),
    (["city", "c", "--seed", "-1"], {}, "--seed"),
    (["fit", "shaft", "--reference", "r.csv", "--seed", "-1"], {"r.csv": CSV}, "--seed"),
    (["city", "c", "--memory-limit", "-1"], {}, "--memory-limit"),
    (["city", "c", "--max-memory", "nan"], {}, "--max-memory"),
    (["shaft", "--max-memory", "0"], {}, "--max-memory"),
    # the commands that had no memory flag: an estimate and a refusal past the limit
    (
        [
            "preview",
            "s.usda",
            "-o",
            "p.png",
            "--width",
            "8192",
            "--height",
            "8192",
            "--samples",
            "16",
        ],
        {"s.usda": SCENE},
        "8192x8192",
    ),
    (["export", "s.usda", "-o", "s.glb", "--max-memory", "0.1"], {"s.usda": SCENE}, "limit"),
    (
        ["evaluate", "--part", "base", "--reference", "r.csv", "--max-memory", "0.1"],
        {"r.csv": CSV},
        "limit",
    ),
    (["fit", "shaft", "--reference", "r.csv", "--max-memory", "0.1"], {"r.csv": CSV}, "limit"),
    # city: every output path and flag checked before any work
    (["city", "c", "--json", "/nonexistent/dir/x.json"], {}, "--json"),
    (["city", "c", "--json", "x.txt"], {}, "--json"),
    (["city", "c", "--instancer-threshold", "-1"], {}, "--instancer-threshold"),
    *[
        (["city", "c", "--scheduler", a], {}, "--scheduler")
        for a in (
            "http://example.invalid:80",
            "tcp://256.1.1.1:99999",
            "tcp://256.1.1.1:99",
            "tcp://",
            "inproc://x",
            "tcp://example.invalid:8786",
            "tcp://127.0.0.1:1",  # nothing listens on port 1
        )
    ],
    (
        ["city", "c", "--plan", "p.geojson"],
        {"p.geojson": _plan(_lot("a", 0, 0, 1e300, 40))},
        "1e+07",
    ),
    (
        ["city", "c", "--plan", "p.geojson"],
        {"p.geojson": _plan(_lot("a", 0, 0, 30, 40), _lot("b", 20, 10, 50, 50))},
        "a and b",
    ),
    # export --scale: the range a printer can make, nothing non-finite or degenerate written
    *[
        (["export", "s.usda", "-o", f"s{ext}", "--scale", v], {"s.usda": SCENE}, "--scale")
        for ext in (".stl", ".3mf")
        for v in ("1e300", "1e30", "1e-300", "1e-12", "inf", "0", "-1", "1:0")
    ],
    # a temple description missing tables names them (unless it says what it extends)
    *[
        (["temple", "--config", "t.toml", "-o", "T"], {"t.toml": _without(t)}, f"[{t}]")
        for t in ("columns", "podium", "roof", "temple")
    ],
    (["temple", "--config", "t.toml", "-o", "T"], {"t.toml": b'[temple]\nname = "x"\n'}, "[roof]"),
    (["temple", "--config", "t.toml", "-o", "T"], {"t.toml": b'extends = "nope"\n'}, "extends"),
    (["temple", "--config", "t.toml", "-o", "T"], {"t.toml": b"extends = 5\n"}, "extends"),
    # hypotheses: bounded work, refused before any (the limits of usd.combinations)
    (["temple", "--config", "t.toml", "-o", "T"], {"t.toml": b"@1000"}, "at most 64"),
    (["temple", "--config", "t.toml", "-o", "T"], {"t.toml": b"@6"}, "limit is 256"),
    # alternatives of one question (one variant set): the same change twice, or a question
    # named like an independent hypothesis' set
    (
        ["temple", "--config", "t.toml", "-o", "T"],
        {
            "t.toml": b'extends = "portunus"\n[[hypothesis]]\nid = "frieze-low"\n'
            b'question = "frieze"\ndescription = "d"\nsources = ["s"]\ncertainty = "low"\n'
            b'changes = { "entablature.frieze_ratio" = 0.75 }\n'
        },
        "same change",
    ),
    (
        ["temple", "--config", "t.toml", "-o", "T"],
        {
            "t.toml": b'extends = "portunus"\n[[hypothesis]]\nid = "pitch-a"\n'
            b'question = "roof-pitch-15"\ndescription = "d"\nsources = ["s"]\n'
            b'certainty = "low"\nchanges = { "roof.tympanum_ratio" = 8.0 }\n'
        },
        "question",
    ),
    # names and values that used to pass
    (["shaft", "-o", "a\nb.usda"], {}, "control characters"),
    (["temple", "-o", "a\tb"], {}, "control characters"),
    (["column", "--lod", "", "-o", "c.usda"], {}, "lod"),
    (["column", "--base", "", "-o", "c.usda"], {}, "base"),
    (["shaft", "--flute-slices-per-fillet-slice", "10000"], {}, "changes nothing"),
    (
        [
            "evaluate",
            "--usd",
            "s.usda",
            "--variant",
            "lod=bogus",
            "--part",
            "base",
            "--reference",
            "r.csv",
        ],
        {"s.usda": SCENE, "r.csv": CSV},
        "lod",
    ),
]


def _hypotheses(n: int) -> bytes:
    """extends portunus (3 hypotheses changing geometry) + n changing the roof."""
    out = ['extends = "portunus"']
    for i in range(n):
        out += [
            "[[hypothesis]]",
            f'id = "h{i}"',
            'description = "d"',
            'sources = ["s"]',
            'certainty = "low"',
            f'changes = {{ "roof.tympanum_ratio" = {5 + 0.001 * i} }}',
        ]
    return ("\n".join(out) + "\n").encode()


@pytest.mark.parametrize("argv,files,needle", CASES, ids=[" ".join(c[0])[:60] for c in CASES])
def test_refused_cleanly_and_nothing_written(tmp_path, capsys, argv, files, needle):
    for name, data in files.items():
        if data is None:
            (tmp_path / name).mkdir()
        else:
            if data.startswith(b"@"):  # portunus + n more hypotheses
                data = _hypotheses(int(data[1:]))
            (tmp_path / name).write_bytes(data)
    before = _listing(tmp_path)
    code, _out, err = run_cli(argv, tmp_path, capsys)
    assert_clean_refusal(code, err, needle)
    assert _listing(tmp_path) == before


def test_memory_limit_is_a_deprecated_alias(tmp_path, capsys):
    """city's old --memory-limit still sets the one limit (and says it is deprecated)."""
    from ionic_usd.cli import build_parser

    args = build_parser(("city",)).parse_args(["city", "c", "--memory-limit", "2"])
    assert args.max_memory == 2.0
    assert "deprecated" in capsys.readouterr().err
    args = build_parser(("city",)).parse_args(["city", "c"])
    assert args.max_memory is None


def test_fillet_ratio_saturation_is_where_it_stops_changing():
    """Below the saturation $i the shaft differs from the next $i; from it on it is the same."""
    import dataclasses

    from ionic_usd.column.shaft import ShaftParams

    for p in (ShaftParams(), ShaftParams(flute_slices=16), ShaftParams(flutes=20, flute_angle=9)):
        top = p.fillet_ratio_saturation()
        slices = [
            dataclasses.replace(p, flute_slices_per_fillet_slice=i).fillet_slices
            for i in range(1, top + 5)
        ]
        assert slices[top - 1] == 1 and set(slices[top - 1 :]) == {1}
        assert top == 1 or slices[top - 2] > 1


def test_api_refuses_texture_size_and_seed():
    from ionic_usd.errors import ParameterError
    from ionic_usd.usd.column_asset import ColumnAssetOptions

    for kw in ({"texture_size": 100}, {"texture_size": 0}, {"seed": -1}, {"texture_size": True}):
        with pytest.raises(ParameterError):
            ColumnAssetOptions(**kw)


@pytest.mark.parametrize("scale", ["1e-4", "1:5000"])
def test_export_refuses_a_solid_below_a_millimetre(tmp_path, capsys, scale):
    """The 1 cm tetrahedron (a layer without metersPerUnit is in cm) at 1:5,000 would print
    2 µm long: refused, nothing written; at 1:1 it prints 10 mm long."""
    pytest.importorskip("manifold3d")
    (tmp_path / "s.usda").write_bytes(SCENE)
    before = _listing(tmp_path)
    code, _out, err = run_cli(
        ["export", "s.usda", "-o", "s.stl", "--scale", scale], tmp_path, capsys
    )
    assert_clean_refusal(code, err, "mm")
    assert _listing(tmp_path) == before
    code, _out, err = run_cli(["export", "s.usda", "-o", "s.stl", "--scale", "1"], tmp_path, capsys)
    assert code == 0, err  # 10 mm: printable
    assert (tmp_path / "s.stl").stat().st_size > 84


def test_extends_takes_the_missing_tables_and_adds_hypotheses(tmp_path):
    """extends = "portunus": the given keys win, every other value is Portunus's, and the
    description's hypotheses come after Portunus's."""
    from ionic_usd.api import Temple

    cfg = tmp_path / "t.toml"
    cfg.write_text(
        'extends = "portunus"\n[temple]\nname = "Mine"\n[podium]\nheight = 1.75\n'
        '[[hypothesis]]\nid = "mine"\ndescription = "d"\nsources = ["s"]\n'
        'certainty = "low"\nchanges = { "roof.tympanum_ratio" = 8.0 }\n'
    )
    mine, ref = Temple.from_toml(cfg).layout, Temple.portunus().layout
    assert mine.name == "Mine" and mine.params.podium_height == 1.75
    assert ref.params.podium_height != 1.75
    for f in (
        "columns_lower_diameter",
        "roof_tympanum_ratio",
        "steps_count",
        "cella_wall_thickness",
    ):
        assert getattr(mine.params, f) == getattr(ref.params, f), f
    assert [h.id for h in mine.hypotheses] == [h.id for h in ref.hypotheses] + ["mine"]
    # the full description needs no extends (the reference file itself)
    full = tmp_path / "full.toml"
    full.write_text(PORTUNUS)
    assert Temple.from_toml(full).layout.params == ref.params


def test_every_usd_layer_the_repository_ships_opens_alone_and_validates():
    """layers/portunus/*.usda sublayer ../materials.usda: the repository ships it (stand-in
    materials), so each layer opens alone with 0 validation errors; and it is up to date."""
    from pxr import Sdf, Usd

    from ionic_usd.usd.materials import stand_in_materials
    from ionic_usd.usd.stage import validate_stage

    repo = Path(__file__).resolve().parents[1]
    shipped = sorted(
        p
        for p in repo.rglob("*.usd*")
        if p.suffix in (".usd", ".usda", ".usdc") and not {"tests", ".git"} & set(p.parts)
    )
    assert len(shipped) >= 6
    for p in shipped:
        stage = Usd.Stage.Open(str(p))
        assert stage is not None, p
        for sub in Sdf.Layer.FindOrOpen(str(p)).subLayerPaths:  # every sublayer is there
            assert (p.parent / sub).is_file(), (p, sub)
        assert validate_stage(stage) == [], p
    layers = [Sdf.Layer.FindOrOpen(str(p)) for p in sorted(repo.glob("layers/portunus/*.usda"))]
    fresh = stand_in_materials(layers).ExportToString()
    assert Sdf.Layer.FindOrOpen(str(repo / "layers/materials.usda")).ExportToString() == fresh


@pytest.mark.slow
def test_city_says_what_it_resolved_and_warns_past_a_viewer(tmp_path, capsys, monkeypatch):
    """A porticus Polygon stays a colonnaded square and the build says so; a city drawing more
    triangles than a viewer can is built with a warning (the threshold lowered here, so a
    small city crosses it)."""
    import json

    import ionic_usd.pipeline.city as city

    ring = "[[0, 100], [30, 100], [30, 130], [0, 130], [0, 100]]"
    porticus = (
        '{"type": "Feature", "properties": {"type": "porticus", "id": "square"}, '
        f'"geometry": {{"type": "Polygon", "coordinates": [{ring}]}}}}'
    )
    (tmp_path / "p.geojson").write_bytes(_plan(_lot("a", 0, 0, 30, 40), porticus))
    monkeypatch.setattr(city, "VIEWER_TRIANGLES", 1000)
    argv = ["city", "c", "--plan", "p.geojson", "--texture-size", "16", "--json", "s.json"]
    code, _out, err = run_cli(argv, tmp_path, capsys)
    assert code == 0, err
    assert "porticus square is a Polygon" in err and "colonnaded square" in err
    assert "warning: the city draws up to" in err
    summary = json.loads((tmp_path / "s.json").read_text())
    assert summary["columns"] > 0 and len(summary["notes"]) == 2
    assert summary["city"] == str(Path("c") / "City.usda")
