"""The ``evaluate`` and ``fit`` subcommands, through a parser built with ``add_parsers``."""

from __future__ import annotations

import argparse
import dataclasses
import json
import tomllib

import numpy as np
import pytest

from ionic_usd.cli.evaluate import add_parsers
from ionic_usd.column.column import (
    build_column,
    column_params_from_mapping,
    column_params_to_tables,
    portunus_column_params,
)
from ionic_usd.errors import IonicError, OutputExistsError, ParameterError, ReferenceCurveError
from ionic_usd.evaluate.sections import base_section, shaft_silhouette_section
from ionic_usd.params import to_toml


class _Parser(argparse.ArgumentParser):
    def error(self, message: str):
        self.exit(2, f"{self.prog}: error: {message}\n")


def _parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="ionic-usd")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)
    add_parsers(sub, _Parser)
    return parser


def run(argv: list[str]) -> int:
    args = _parser().parse_args(argv)
    return int(args.func(args))


def _csv(path, curve: np.ndarray, scale: float = 1.0):
    lines = ["x,y"] + [f"{float(x) / scale!r},{float(y) / scale!r}" for x, y in curve]
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


def test_evaluate_identical_curve_from_config(tmp_path, capsys):
    p = portunus_column_params(base="G2")
    cfg = tmp_path / "column.toml"
    cfg.write_text(to_toml(column_params_to_tables(p)), encoding="utf-8")
    # the reference in millimetres, shifted: --scale brings it back, the alignment undoes it
    ref = _csv(tmp_path / "base.csv", base_section(p) + [0.2, -0.1], scale=1e-3)
    out_json, out_png = tmp_path / "m.json", tmp_path / "m.png"
    assert (
        run(
            [
                "evaluate",
                "--part",
                "base",
                "--config",
                str(cfg),
                "--reference",
                str(ref),
                "--scale",
                "0.001",
                "--json",
                str(out_json),
                "--plot",
                str(out_png),
            ]
        )
        == 0
    )
    text = capsys.readouterr().out
    assert "weak Fréchet" in text and "translated by" in text
    doc = json.loads(out_json.read_text("utf-8"))
    part = doc["parts"]["base"]
    assert part["hausdorff"] < 1e-6
    assert part["alignment"]["translation"] == pytest.approx([0.2, -0.1], abs=1e-6)
    assert doc["metadata"]["scale"] == 0.001
    assert out_png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    # outputs are not overwritten without --force
    argv = [
        "evaluate",
        "--part",
        "base",
        "--config",
        str(cfg),
        "--reference",
        str(ref),
        "--scale",
        "0.001",
        "--json",
        str(out_json),
    ]
    with pytest.raises(OutputExistsError):
        run(argv)
    assert run([*argv, "--force"]) == 0


def test_evaluate_from_usd_and_spacing(tmp_path, capsys):
    from ionic_usd.usd import write_meshes

    p = portunus_column_params()
    usd = tmp_path / "column.usda"
    write_meshes(usd, build_column(p).parts(), root="Column")
    changed = dataclasses.replace(p, shaft=dataclasses.replace(p.shaft, top_radius=0.39))
    ref = _csv(tmp_path / "shaft.csv", shaft_silhouette_section(changed))
    out_json = tmp_path / "s.json"
    assert (
        run(
            [
                "evaluate",
                "--part",
                "shaft",
                "--usd",
                str(usd),
                "--reference",
                str(ref),
                "--spacing",
                "0.01",
                "--json",
                str(out_json),
            ]
        )
        == 0
    )
    part = json.loads(out_json.read_text("utf-8"))["parts"]["shaft"]
    # top radius 0.407 → 0.39: the curves differ by at most that much, and by something
    assert 1e-3 < part["hausdorff"] <= 0.0175
    assert part["nodes_a"] > 700  # resampled at 1 cm along ~8 m
    assert "resampled" in capsys.readouterr().out


def test_evaluate_errors(tmp_path):
    ref = _csv(tmp_path / "r.csv", np.array([[0.0, 0.0], [1.0, 1.0]]))
    with pytest.raises(SystemExit):  # --usd and --config exclude each other (argparse)
        run(
            [
                "evaluate",
                "--part",
                "base",
                "--usd",
                "a.usda",
                "--config",
                "b.toml",
                "--reference",
                str(ref),
            ]
        )
    with pytest.raises(ReferenceCurveError):
        run(["evaluate", "--part", "base", "--reference", str(tmp_path / "missing.csv")])
    with pytest.raises(ParameterError):
        run(["evaluate", "--part", "base", "--reference", str(ref), "--json", "x.txt"])
    with pytest.raises(ParameterError):
        run(["evaluate", "--part", "base", "--reference", str(ref), "--variant", "lod=high"])
    with pytest.raises(IonicError):
        run(
            [
                "evaluate",
                "--part",
                "volute",
                "--usd",
                str(tmp_path / "none.usda"),
                "--reference",
                str(ref),
            ]
        )


def test_fit_shaft_command_writes_accepted_toml(tmp_path, capsys):
    p = portunus_column_params()
    true = dataclasses.replace(
        p, shaft=dataclasses.replace(p.shaft, bottom_radius=0.45, top_radius=0.40, entasis=0.01)
    )
    ref = _csv(tmp_path / "shaft.csv", shaft_silhouette_section(true))
    out = tmp_path / "fitted.toml"
    argv = ["fit", "shaft", "--reference", str(ref), "-o", str(out), "--seed", "3"]
    assert run(argv) == 0
    text = capsys.readouterr().out
    assert "before" in text and "after" in text and f"wrote {out}" in text
    col = column_params_from_mapping(tomllib.loads(out.read_text("utf-8")))
    assert col.shaft.bottom_radius == pytest.approx(0.45, abs=1e-4)
    assert col.shaft.entasis == pytest.approx(0.01, abs=1e-3)
    with pytest.raises(OutputExistsError):
        run(argv)
    # without -o the TOML goes to stdout
    assert run(["fit", "shaft", "--reference", str(ref)]) == 0
    assert "[shaft]" in capsys.readouterr().out


def test_fit_command_errors(tmp_path):
    ref = _csv(tmp_path / "r.csv", np.array([[0.5, 0.0], [0.45, 7.0]]))
    with pytest.raises(ParameterError):
        run(["fit", "shaft", "--reference", str(ref), "--modules", "2,4"])
    with pytest.raises(ParameterError):
        run(["fit", "base", "--reference", str(ref), "--modules", "2,x"])
    with pytest.raises(ParameterError):
        run(["fit", "shaft", "--reference", str(ref), "-o", str(tmp_path / "out.json")])
    with pytest.raises(SystemExit):
        run(["fit", "capital", "--reference", str(ref)])
    with pytest.raises(SystemExit):
        run(["fit", "volute", "--reference", str(ref), "--measure", "chamfer"])


# -- cross-sections, several references, machine-readable output ----------------------------------
def _closed_section(diameter: float, turn_deg: float, shift) -> np.ndarray:
    from ionic_usd.evaluate.sections import shaft_cross_section_at

    p = portunus_column_params(lower_diameter=diameter)
    sec = shaft_cross_section_at(p, p.base_params().height + 1.0)
    a = np.radians(turn_deg)
    rot = np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])
    return sec @ rot.T + np.asarray(shift)


def test_closed_curve_without_section_is_refused_by_the_cli(tmp_path, capsys):
    from ionic_usd.cli import main

    ref = _csv(tmp_path / "sec.csv", _closed_section(0.95, 7.0, [2.0, 1.0]))
    for argv in (
        ["fit", "shaft", "--reference", str(ref)],
        ["evaluate", "--part", "shaft", "--reference", str(ref)],
    ):
        capsys.readouterr()
        assert main(argv) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and "--section" in err[0] and "closed" in err[0]


def test_fit_shaft_section_command_json_and_curves(tmp_path, capsys):
    ref = _csv(tmp_path / "sec.csv", _closed_section(0.95, 7.0, [2.0, 1.0]))
    out, js, cv = tmp_path / "f.toml", tmp_path / "f.json", tmp_path / "f.csv"
    assert (
        run(
            [
                "fit",
                "shaft",
                "--section",
                "--reference",
                str(ref),
                "-o",
                str(out),
                "--json",
                str(js),
                "--curves",
                str(cv),
            ]
        )
        == 0
    )
    doc = json.loads(js.read_text("utf-8"))
    assert doc["schema"] == "ionic_usd.evaluate/1"
    part = doc["parts"]["shaft"]
    assert part["model"] == "section" and part["parameters"]["flutes"] == 24
    assert part["hausdorff_pct"] < 0.2 and part["discrete_frechet_pct"] < 0.2
    assert part["hausdorff"] == pytest.approx(part["hausdorff_pct"] / 100 * part["mean_length"])
    assert part["alignment"]["rotation_deg"] == pytest.approx(7.0 % 15.0, abs=0.05)
    assert part["bounds_hit"] == []
    rows = cv.read_text("utf-8").splitlines()
    assert rows[0] == "part,curve,index,x,y"
    assert {r.split(",")[1] for r in rows[1:]} == {"reference", "fitted"}
    col = column_params_from_mapping(tomllib.loads(out.read_text("utf-8")))
    assert col.shaft.flutes == 24
    assert col.shaft.bottom_radius == pytest.approx(part["parameters"]["radius"])


def test_evaluate_identical_curves_read_zero_and_several_references(tmp_path, capsys):
    p = portunus_column_params()
    from ionic_usd.evaluate.fit_core import densify

    base = _csv(tmp_path / "b.csv", densify(base_section(p), 0.003))  # more nodes, same curve
    shaft = _csv(tmp_path / "s.csv", shaft_silhouette_section(p, samples=57))
    js = tmp_path / "t6.json"
    assert (
        run(
            [
                "evaluate",
                "--reference",
                f"base={base}",
                "--reference",
                f"shaft={shaft}",
                "--json",
                str(js),
            ]
        )
        == 0
    )
    text = capsys.readouterr().out
    assert "resampled at" in text and "node-to-node" in text
    doc = json.loads(js.read_text("utf-8"))
    assert set(doc["parts"]) == {"base", "shaft"}
    for part in doc["parts"].values():
        # identical curves, differently sampled: resampled by default, no measure reads %
        assert part["node_hausdorff_pct"] < 1e-6 and part["hausdorff_pct"] < 1e-6


def test_evaluate_shaft_section(tmp_path, capsys):
    p = portunus_column_params()
    y = p.base_params().height + 2.0
    from ionic_usd.evaluate.sections import shaft_cross_section_at

    sec = shaft_cross_section_at(p, y)
    a = np.radians(40.0)
    rot = np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])
    ref = _csv(tmp_path / "s.csv", sec @ rot.T + [1.0, 1.0])
    js = tmp_path / "e.json"
    assert (
        run(
            [
                "evaluate",
                "--part",
                "shaft",
                "--section",
                "--height",
                str(y),
                "--reference",
                str(ref),
                "--json",
                str(js),
            ]
        )
        == 0
    )
    part = json.loads(js.read_text("utf-8"))["parts"]["shaft"]
    assert part["hausdorff"] < 1e-6 and part["discrete_frechet"] < 1e-3
