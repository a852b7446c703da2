"""The ``evaluate`` and ``fit`` subcommands, through a parser built with ``add_parsers``."""

from __future__ import annotations

import argparse
import dataclasses
import json
import tomllib

import numpy as np
import pytest

from ionic_usd.column.column import (
    build_column,
    column_params_from_mapping,
    column_params_to_tables,
    portunus_column_params,
)
from ionic_usd.errors import IonicError, OutputExistsError, ParameterError, ReferenceCurveError
from ionic_usd.evaluate.commands import add_parsers
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
    assert run(["evaluate", "--part", "base", "--config", str(cfg), "--reference", str(ref),
                "--scale", "0.001", "--json", str(out_json), "--plot", str(out_png)]) == 0
    text = capsys.readouterr().out
    assert "weak Fréchet" in text and "translated by" in text
    doc = json.loads(out_json.read_text("utf-8"))
    part = doc["parts"]["base"]
    assert part["hausdorff"] < 1e-6
    assert part["alignment"]["translation"] == pytest.approx([0.2, -0.1], abs=1e-6)
    assert doc["metadata"]["scale"] == 0.001
    assert out_png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    # outputs are not overwritten without --force
    argv = ["evaluate", "--part", "base", "--config", str(cfg), "--reference", str(ref),
            "--scale", "0.001", "--json", str(out_json)]
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
    assert run(["evaluate", "--part", "shaft", "--usd", str(usd), "--reference", str(ref),
                "--spacing", "0.01", "--json", str(out_json)]) == 0
    part = json.loads(out_json.read_text("utf-8"))["parts"]["shaft"]
    # top radius 0.407 → 0.39: the curves differ by at most that much, and by something
    assert 1e-3 < part["hausdorff"] <= 0.0175
    assert part["nodes_a"] > 700  # resampled at 1 cm along ~8 m
    assert "resampled" in capsys.readouterr().out


def test_evaluate_errors(tmp_path):
    ref = _csv(tmp_path / "r.csv", np.array([[0.0, 0.0], [1.0, 1.0]]))
    with pytest.raises(SystemExit):  # --usd and --config exclude each other (argparse)
        run(["evaluate", "--part", "base", "--usd", "a.usda", "--config", "b.toml",
             "--reference", str(ref)])
    with pytest.raises(ReferenceCurveError):
        run(["evaluate", "--part", "base", "--reference", str(tmp_path / "missing.csv")])
    with pytest.raises(ParameterError):
        run(["evaluate", "--part", "base", "--reference", str(ref), "--json", "x.txt"])
    with pytest.raises(ParameterError):
        run(["evaluate", "--part", "base", "--reference", str(ref), "--variant", "lod=high"])
    with pytest.raises(IonicError):
        run(["evaluate", "--part", "volute", "--usd", str(tmp_path / "none.usda"),
             "--reference", str(ref)])


def test_fit_shaft_command_writes_accepted_toml(tmp_path, capsys):
    p = portunus_column_params()
    true = dataclasses.replace(p, shaft=dataclasses.replace(p.shaft, bottom_radius=0.45,
                                                            top_radius=0.40, entasis=0.01))
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
