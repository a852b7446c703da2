"""Report table, JSON and overlay plot."""

from __future__ import annotations

import json
import os

import numpy as np
import pytest

from ionic_usd.errors import ParameterError
from ionic_usd.evaluate.metrics import CurveComparison, compare
from ionic_usd.evaluate.reference import align
from ionic_usd.evaluate.report import SCHEMA, format_table, plot_overlay, write_json


def paper_base_row() -> CurveComparison:
    # The paper's Table 6 base row (drawing units): 97 + 97 nodes, lengths 96 + 96.
    return CurveComparison(
        nodes_a=97,
        nodes_b=97,
        length_a=96.0,
        length_b=96.0,
        mean_length=96.0,
        hausdorff=1.7664,
        node_hausdorff=1.8257,
        average_error=0.2797,
        discrete_frechet=2.0,
        frechet=1.9,
    )


def parallel_pair() -> tuple[np.ndarray, np.ndarray]:
    x = np.linspace(0.0, 2.0, 21)
    return np.c_[x, np.zeros_like(x)], np.c_[x, np.full_like(x, 0.1)]


def test_table_reproduces_paper_percentages():
    table = format_table({"base": paper_base_row()}, unit="du")
    lines = table.splitlines()
    assert lines[0].split()[:3] == ["part", "nodes", "length"]
    base = next(line for line in lines if line.startswith("base"))
    assert "97 + 97" in base
    # Paper: 1.7664 (1.84%), 1.8257 (1.90%), 0.2797 (0.29%).
    for text in ("1.7664 du (1.84%)", "1.8257 du (1.90%)", "0.2797 du (0.29%)"):
        assert text in base
    assert "weak Fréchet" in lines[-1]


def test_table_rows_in_order_and_validation():
    a, b = parallel_pair()
    table = format_table({"shaft": compare(a, b), "spiral": compare(b, a)})
    order = [line.split()[0] for line in table.splitlines()[2:4]]
    assert order == ["shaft", "spiral"]
    assert "0.1000 m (5.00%)" in table  # separation 0.1 over length 2
    with pytest.raises(ParameterError):
        format_table({})
    with pytest.raises(ParameterError):
        format_table({"x": 1.0})  # type: ignore[dict-item]


def test_write_json_keys_and_values(tmp_path):
    a, b = parallel_pair()
    ref = a
    aligned, info = align(ref, b + [0.5, 0.0])
    row = compare(ref, aligned)
    out = write_json(
        tmp_path / "report.json",
        {"base": row},
        alignments={"base": info},
        metadata={"preset": "portunus"},
    )
    doc = json.loads(out.read_text(encoding="utf-8"))
    assert doc["schema"] == SCHEMA and doc["unit"] == "m"
    assert doc["metadata"] == {"preset": "portunus"}
    part = doc["parts"]["base"]
    for key in (
        "nodes_a",
        "nodes_b",
        "length_a",
        "length_b",
        "mean_length",
        "hausdorff",
        "node_hausdorff",
        "average_error",
        "discrete_frechet",
        "frechet",
    ):
        assert part[key] == pytest.approx(getattr(row, key))
        if key not in ("nodes_a", "nodes_b", "length_a", "length_b", "mean_length"):
            assert part[f"{key}_pct"] == pytest.approx(100 * part[key] / part["mean_length"])
    assert part["alignment"]["mirrored"] is False
    assert part["alignment"]["hausdorff_after"] <= part["alignment"]["hausdorff_before"]
    # Only the target remains in the folder: the temporary file was renamed over it.
    assert os.listdir(tmp_path) == ["report.json"]


def test_write_json_rejects_bad_input_and_leaves_no_temp(tmp_path):
    a, b = parallel_pair()
    row = compare(a, b)
    target = tmp_path / "r.json"
    target.write_text("old", encoding="utf-8")
    with pytest.raises(ParameterError):
        write_json(target, {"base": row}, metadata={"bad": object()})
    with pytest.raises(ParameterError):
        write_json(target, {"base": row}, alignments={"other": align(a, b)[1]})
    assert target.read_text(encoding="utf-8") == "old"
    assert os.listdir(tmp_path) == ["r.json"]


def test_plot_overlay_writes_png(tmp_path):
    a, b = parallel_pair()
    out = plot_overlay(a, b, tmp_path / "fig.png", title="base")
    data = out.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    assert os.listdir(tmp_path) == ["fig.png"]
    with pytest.raises(ParameterError):
        plot_overlay(np.zeros((3, 3)), np.ones((3, 3)), tmp_path / "x.png")
