"""A scan of several columns (issue 36): split by footprint, one fit per column, instances of
one description grouped within the noise. Scans from tests/synth_scan.py (independent of the
project's model): fragments stood on a line with small random poses, one of another size."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))

from synth_scan import Truth, colonnade_scan  # noqa: E402

NOISE = 0.8  # mm


def _check(truths: list[Truth], n: int, seed: int) -> None:
    from ionic_usd.evaluate.scan_colonnade import fit_colonnade

    pts, lab = colonnade_scan(truths, n, noise=NOISE, seed=seed)
    c = fit_colonnade(pts * 1e-3)
    assert len(c.fits) == len(truths)
    source = []
    for idx in c.indices:  # every cluster holds one column's points, all of them
        counts = np.bincount(lab[idx], minlength=len(truths))
        assert np.count_nonzero(counts) == 1
        source.append(int(np.argmax(counts)))
        assert counts.max() == np.count_nonzero(lab == source[-1])
    # the grouping: columns of equal truth together, the other one alone
    want = {frozenset(i for i, s in enumerate(source) if truths[s] == t) for t in truths}
    assert {frozenset(g) for g in c.groups} == want
    s = c.summary()
    for i, col in enumerate(s["columns"]):
        t = truths[source[i]]
        assert col["diameter"] == pytest.approx(2e-3 * t.radius, rel=0.005)
        assert col["flutes"] == t.flutes
        assert 1000.0 * col["deviation"]["rms"] <= 2.0 * NOISE, (i, col["deviation"])
        assert 1000.0 * col["deviation_from_group"]["rms"] <= 2.0 * NOISE
    # the columns stand on a line 2.8 m apart: their axes' feet, along the common up axis
    up = np.asarray(s["up"])
    pos = np.array([col["position"] for col in s["columns"]])
    flat = pos - np.outer(pos @ up, up)
    order = np.argsort(source)
    gaps = np.linalg.norm(np.diff(flat[order], axis=0), axis=1)
    assert gaps == pytest.approx(2.8, abs=0.05)


def test_colonnade_of_three():
    """Two equal columns and a wider one (radius 460 mm, not 400), 4,000 points each."""
    t = Truth()
    _check([t, t.scaled(460.0), t], 4000, 0)


@pytest.mark.slow
def test_colonnade_of_four():
    t = Truth()
    _check([t, t, t.scaled(460.0), t], 6000, 1)


def test_split_drops_debris():
    from ionic_usd.evaluate.scan_colonnade import split_columns

    t = Truth()
    pts, lab = colonnade_scan([t, t], 3000, seed=2)
    rng = np.random.default_rng(0)
    far = pts[:40] + 6000.0 * np.cross(pts[1] - pts[0], [0.0, 0.0, 1.0]) / np.linalg.norm(
        np.cross(pts[1] - pts[0], [0.0, 0.0, 1.0])
    )
    debris = far + rng.normal(0.0, 5.0, far.shape)
    up, clusters, notes = split_columns(np.vstack([pts, debris]) * 1e-3)
    assert len(clusters) == 2
    assert sorted(len(c) for c in clusters) == [3000, 3000]
    assert notes and "dropped" in notes[0]


@pytest.mark.slow
def test_cli_writes_a_column_per_column_and_a_toml_per_description(tmp_path):
    import json

    from ionic_usd.cli import main

    t = Truth()
    pts, _ = colonnade_scan([t, t.scaled(460.0), t], 4000, noise=NOISE, seed=0)
    scan = tmp_path / "colonnade.xyz"
    np.savetxt(scan, pts, fmt="%.3f")
    out, rj = tmp_path / "out", tmp_path / "R.json"
    assert main(["fit", "column", "--scan", str(scan), "-o", str(out), "--json", str(rj)]) == 0
    doc = json.loads(rj.read_text())
    assert len(doc["columns"]) == 3
    assert sorted(len(g["instances"]) for g in doc["distinct_columns"]) == [1, 2]
    for k in (1, 2, 3):
        assert (out / f"fitted_column_{k}.usda").stat().st_size > 0
    assert sorted(p.name for p in out.glob("*.toml")) == [
        "fitted_column_A.toml",
        "fitted_column_B.toml",
    ]
    for c in doc["columns"]:
        assert 1000.0 * c["deviation"]["rms"] <= 2.0 * NOISE
    # a second run refuses to overwrite, before writing anything
    before = {p: p.stat().st_mtime_ns for p in out.iterdir()}
    assert main(["fit", "column", "--scan", str(scan), "-o", str(out)]) == 2
    assert {p: p.stat().st_mtime_ns for p in out.iterdir()} == before
