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


def _check(truths: list[Truth], n: int, seed: int, stylobate: int = 0):
    from ionic_usd.evaluate.scan_colonnade import fit_colonnade

    pts, lab = colonnade_scan(truths, n, noise=NOISE, seed=seed, stylobate=stylobate)
    c = fit_colonnade(pts * 1e-3)
    assert len(c.fits) == len(truths)
    source = []
    for idx in c.indices:  # every cluster holds one column's points, all of them
        assert not (lab[idx] < 0).any()  # and none of the stylobate's
        counts = np.bincount(lab[idx], minlength=len(truths))
        assert np.count_nonzero(counts) == 1
        source.append(int(np.argmax(counts)))
        own = np.count_nonzero(lab == source[-1])
        # all of them; on a stylobate all but the plinth's bottom edge (its lowest ~6 mm,
        # within the noise and tilt of the stylobate's top: ~1.5 % of a column's points)
        assert counts.max() == own if not stylobate else counts.max() >= 0.97 * own
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
        # its pose as an instance: its own, moved along its axis by a few mm at most
        m, own = c.instance_matrix[i], c.fits[i].matrix
        np.testing.assert_array_equal(m[:3], own[:3])
        move = m[3, :3] - own[3, :3]
        assert np.linalg.norm(move - (move @ own[1, :3]) * own[1, :3]) < 1e-12
        assert abs(col["shift_from_own_pose"]) <= 0.03 * col["diameter"] + 1e-12
    # the columns stand on a line 2.8 m apart: their axes' feet, along the common up axis
    up = np.asarray(s["up"])
    pos = np.array([col["position"] for col in s["columns"]])
    flat = pos - np.outer(pos @ up, up)
    order = np.argsort(source)
    gaps = np.linalg.norm(np.diff(flat[order], axis=0), axis=1)
    assert gaps == pytest.approx(2.8, abs=0.05)
    return c


def test_colonnade_of_three(tmp_path):
    """Two equal columns and a wider one (radius 460 mm, not 400), 4,000 points each; written
    as instances of one column per group."""
    t = Truth()
    c = _check([t, t.scaled(460.0), t], 4000, 0)
    _check_instanced(c, tmp_path / "colonnade.usda")


# seed 2: the equal columns' own fits stand 2.8 mm apart along their axes (their zeros are
# their lowest points, a plinth's corner) and their plinths' heights absorb it: compared at
# their own zeros their descriptions differed by 1.64-1.72 mm rms against 1.5 x 0.86 allowed,
# and they were not grouped, with or without a stylobate; registered along the axis, 0.88 mm.
# Seeds 0-7 group right; the registered shift was -13.3 to +2.8 mm
@pytest.mark.parametrize("seed", [2] + [pytest.param(k, marks=pytest.mark.slow) for k in (1, 3, 4)])
def test_colonnade_groups_at_any_seed(seed):
    t = Truth()
    _check([t, t.scaled(460.0), t], 4000, seed)


@pytest.mark.parametrize("seed", [2, pytest.param(3, marks=pytest.mark.slow)])
def test_colonnade_on_a_stylobate_groups_at_any_seed(seed):
    t = Truth()
    _check([t, t.scaled(460.0), t], 4000, seed, stylobate=6000)


def _check_instanced(c, path: Path) -> None:
    """colonnade.usda: one prototype per part and group, every column's composed geometry
    equal to its group's description at its own pose and flute phase, its deviation on it."""
    from pxr import Usd, UsdGeom
    from scipy.spatial import cKDTree

    from ionic_usd.column.column import build_column
    from ionic_usd.evaluate.scan_colonnade import instance_column
    from ionic_usd.evaluate.scan_colonnade_report import colonnade_instances
    from ionic_usd.evaluate.scan_deviation import scan_deviation
    from ionic_usd.usd.scan import write_colonnade
    from ionic_usd.usd.stage import validate_stage

    prototypes, instances = colonnade_instances(c)
    write_colonnade(path, prototypes, instances)
    assert validate_stage(str(path)) == []
    stage = Usd.Stage.Open(str(path))
    assert len(stage.GetPrototypes()) == 3 * len(c.groups)  # Base, Shaft, CapitalBody each
    cache = UsdGeom.XformCache()
    s = c.summary()
    for k, f in enumerate(c.fits):
        g = c.group_of(k)
        col = stage.GetPrimAtPath(f"/Colonnade/Column_{k + 1}")
        assert col.GetCustomDataByKey("ionic_usd:fit")["group"] == "AB"[g]
        rms = col.GetAttribute("userProperties:fit:deviation_rms_m").Get()
        assert rms == pytest.approx(s["columns"][k]["deviation_from_group"]["rms"], rel=1e-9)
        inst = instance_column(c.fits[c.groups[g][0]], f)
        want = build_column(inst).parts()
        for name, mesh in want.items():
            prim = stage.GetPrimAtPath(f"/Colonnade/Column_{k + 1}/{name}/Mesh")
            assert prim.IsInstanceProxy()
            m = np.array(cache.GetLocalToWorldTransform(prim))
            pts = np.asarray(UsdGeom.Mesh(prim).GetPointsAttr().Get(), dtype=float)
            got = np.c_[pts, np.ones(len(pts))] @ m
            pose = c.instance_matrix[k]  # its own, moved along its axis (register_instance)
            ref = np.c_[mesh.points, np.ones(len(mesh.points))] @ pose
            assert len(got) == len(ref)
            src = prototypes["AB"[g]][name].points
            if name == "Shaft":  # the group's shaft turned about the axis (y) by shaft_turn
                a = np.radians(instances[k].shaft_turn)
                rot = np.array([[np.cos(a), 0, -np.sin(a)], [0, 1, 0], [np.sin(a), 0, np.cos(a)]])
                src = src @ rot
            placed = np.c_[src, np.ones(len(src))] @ pose
            assert np.abs(got - placed).max() < 2e-6, (k, name)
            if name == "Shaft":  # ... lies on the column's own surface (its flute phase):
                # every vertex as near it as the column's own build's (vertices sampled at
                # fixed angles move along the surface); the shaft's interior, as the two ends
                # are where the deviation model hands over to the base and capital
                y = src[:, 1]
                inner = (y > y.min() + 0.01) & (y < y.max() - 0.01)
                d = scan_deviation(got[inner, :3], inst, pose)
                d_own = scan_deviation(ref[:, :3], inst, pose)
                assert d.max() <= d_own.max() + 1e-6, (k, d.max(), d_own.max())
            else:  # base and capital: the column's own vertices
                d, _ = cKDTree(ref[:, :3]).query(got[:, :3])
                assert d.max() < 2e-6, (k, name, d.max())


def test_colonnade_on_a_stylobate():
    """Three columns standing on a stylobate scanned with them: one footprint, split by the
    shafts at mid-height, the stylobate's points dropped, every column fitted to the noise."""
    t = Truth()
    _check([t, t.scaled(460.0), t], 4000, 0, stylobate=6000)


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
    assert (out / "colonnade.usda").stat().st_size > 0
    for k in (1, 2, 3):
        assert (out / f"scan_fit_{k}.png").stat().st_size > 0
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
