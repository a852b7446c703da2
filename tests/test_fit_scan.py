"""Whole columns from scans: synthetic scans of generated columns in random poses."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from ionic_usd.column.column import build_column, portunus_column_params
from ionic_usd.errors import ReferenceCurveError
from ionic_usd.evaluate.scan_io import read_scan, synthetic_scan


def _scan(diameter: float, n: int, seed: int, y_range=None, holes: int = 4):
    p = portunus_column_params(lower_diameter=diameter)
    bh, length = p.base_params().height, p.shaft_params().length
    hidden = ((0.0, 99.0), (bh, 9.0), (bh + length, 9.0))  # the ground and the joints
    pts, rot, t = synthetic_scan(
        build_column(p).parts(),
        n=n,
        noise=5e-4,
        holes=holes,
        missing_sector=(40.0, 100.0),
        hidden=hidden,
        seed=seed,
        y_range=y_range,
        hole_radius=0.05,
    )
    return p, pts, rot, t


def _fragment_base_with_a_drum(seed: int) -> None:
    from ionic_usd.evaluate.fit_scan import fit_column_scan

    p, pts, rot, t = _scan(1.2, 12_000, seed=seed, y_range=(0.0, 1.6), holes=2)
    fit = fit_column_scan(pts)
    s = fit.summary()
    assert s["parts_found"] == ["base", "shaft"]
    assert s["flutes"] == 24
    # a short drum (1.2 m) leaves the axis less certain than a whole column: measured
    # D +0.5 %, axis 0.8°, deviation rms 16 mm, p95 37 mm (whole columns: 2–4 mm, 0.0005°)
    assert s["diameter"] == pytest.approx(1.2, rel=0.02)
    assert math.degrees(math.acos(min(1.0, abs(fit.frame.direction @ rot[:, 1])))) < 1.5
    assert fit.frame.direction @ rot[:, 1] > 0  # the base at the bottom
    assert s["deviation"]["p95"] < 0.05 and np.all(np.isfinite(fit.deviation))
    # the joint from the flutes' start (the parts' bins alone gave −47 %); on seeds 1–8 the
    # base height came out −0.15 to +1.85 %, p95 of the deviation 5.3–8.1 mm
    b0, b1 = s["part_heights"]["base"]
    assert b1 - b0 == pytest.approx(p.base_params().height, rel=0.02)


# the narrow band of a short fragment often starts at the base's upper torus, and the first
# section (a quarter up the band) was unfluted there: 6 of 8 scans failed before the first
# section was sought higher up (passing seed 3 alone had hidden it)
@pytest.mark.parametrize("seed", [2, 3])
def test_fit_a_fragment_base_with_a_drum(seed):
    _fragment_base_with_a_drum(seed)


@pytest.mark.slow
@pytest.mark.parametrize("seed", [1, 4, 5, 6, 7, 8])
def test_fit_a_fragment_base_with_a_drum_any_scan(seed):
    _fragment_base_with_a_drum(seed)


def _write_ply(path, pts):
    from plyfile import PlyData, PlyElement

    v = np.zeros(len(pts), dtype=[("x", "f8"), ("y", "f8"), ("z", "f8")])
    v["x"], v["y"], v["z"] = pts.T
    PlyData([PlyElement.describe(v, "vertex")]).write(str(path))
    return path


@pytest.mark.slow
def test_fit_column_from_a_noisy_posed_scan_with_holes(tmp_path, capsys):
    from pxr import Usd, UsdGeom

    from ionic_usd.cli import main

    p, pts, rot, t = _scan(0.8, 20_000, seed=0)
    scan = _write_ply(tmp_path / "scan.ply", pts)
    out, rj = tmp_path / "out", tmp_path / "R.json"
    assert main(["fit", "column", "--scan", str(scan), "-o", str(out), "--json", str(rj)]) == 0
    doc = json.loads(rj.read_text("utf-8"))
    assert doc["schema"] == "ionic_usd.evaluate/1"
    assert doc["parts_found"] == ["base", "capital", "shaft"]
    assert doc["flutes"] == 24
    assert doc["diameter"] == pytest.approx(0.8, rel=0.02)
    axis = np.asarray(doc["axis"]["direction"])
    assert math.degrees(math.acos(min(1.0, abs(axis @ rot[:, 1])))) < 0.5
    dev = doc["deviation"]
    # 0.5 mm noise, 60° missing, holes, a fitted (not the true) model: measured 2.1 / 3.6 mm
    assert dev["rms"] < 0.006 and dev["p95"] < 0.012
    assert dev["rms"] <= dev["p95"] <= dev["max"]
    # USD: the scan as points with a deviation primvar and colours; the column in its frame
    stage = Usd.Stage.Open(str(out / "scan_deviation.usdc"))
    prim = UsdGeom.Points(stage.GetPrimAtPath("/Scan/Points"))
    n = len(prim.GetPointsAttr().Get())
    assert n == len(pts)
    pv = UsdGeom.PrimvarsAPI(prim)
    assert len(pv.GetPrimvar("deviation").Get()) == n
    assert len(pv.GetPrimvar("displayColor").Get()) == n
    col = Usd.Stage.Open(str(out / "fitted_column.usda"))
    xf = UsdGeom.Xformable(col.GetPrimAtPath("/Column")).ComputeLocalToWorldTransform(0)
    up = np.asarray(xf)[1, :3]
    assert abs(up @ rot[:, 1]) == pytest.approx(1.0, abs=1e-4)
    assert (out / "scan_fit.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    # refuses to overwrite
    assert main(["fit", "column", "--scan", str(scan), "-o", str(out)]) == 2


def test_read_scan_formats_and_errors(tmp_path):
    pts = np.random.default_rng(0).normal(size=(200, 3))
    xyz = tmp_path / "a.xyz"
    xyz.write_text("x y z\n" + "\n".join(" ".join(map(repr, r)) for r in pts.tolist()))
    np.testing.assert_allclose(read_scan(xyz), pts)
    np.testing.assert_allclose(
        read_scan(_write_ply(tmp_path / "a.ply", pts), scale=0.001), pts * 0.001
    )
    with pytest.raises(ReferenceCurveError):
        read_scan(tmp_path / "missing.ply")
    bad = tmp_path / "b.csv"
    bad.write_text("1,2,3\n4,5,nope\n")
    with pytest.raises(ReferenceCurveError, match="b.csv:2"):
        read_scan(bad)
    few = tmp_path / "c.csv"
    few.write_text("1,2,3\n")
    with pytest.raises(ReferenceCurveError, match="at least 100"):
        read_scan(few)


@pytest.mark.slow
def test_fit_scan_200k_points():
    """A 200,000-point scan fits (its time is the benchmarks' business, not a test's: a
    60 s bound here failed on a loaded machine)."""
    from ionic_usd.evaluate.fit_scan import fit_column_scan

    _, pts, _, _ = _scan(0.95, 200_000, seed=2)
    fit = fit_column_scan(pts)
    assert fit.flutes == 24 and fit.diameter == pytest.approx(0.95, rel=0.02)


def _column_points(meshes, n, seed, **kw):
    """Scan points of ``meshes`` taken back into column coordinates with the known pose."""
    pts, rot, t = synthetic_scan(meshes, n=n, seed=seed, **kw)
    return (pts - t) @ rot


@pytest.mark.parametrize(
    "diameter,base,square", [(0.8, "attic_bezier_plinth", True), (1.2, "attic_bezier", False)]
)
def test_base_meridian_follows_the_visible_profile(diameter, base, square):
    """The meridian at the plinth's face normals, from a noisy scan with holes and a missing
    sector, lies within 0.6 of a height bin (1/60 of the base's height) + 2 mm of the true
    base's outer profile: 0.5 mm noise, and the horizontal faces only seen as steps between
    bins (measured 2.1 mm at D = 0.8 m, 5.6 mm at 1.2 m)."""
    import dataclasses

    from ionic_usd.column.column import build_base_part
    from ionic_usd.evaluate.metrics import hausdorff_distance
    from ionic_usd.evaluate.scan_parts import base_meridian, has_square_plinth

    p = dataclasses.replace(portunus_column_params(lower_diameter=diameter), base=base)
    bh = p.base_params().height
    mesh = {"Base": build_base_part(p)}
    pts = _column_points(
        mesh, 20_000, 2, noise=5e-4, holes=3, missing_sector=(40.0, 100.0), hole_radius=0.05
    )
    mer = base_meridian(pts, 0.0, bh)
    truth = base_meridian(
        _column_points(mesh, 100_000, 5, noise=0.0, holes=0, missing_sector=None), 0.0, bh
    )
    assert hausdorff_distance(mer, truth) < 0.6 * bh / 60 + 0.002
    assert mer[0, 1] == 0.0 and mer[-1, 1] == pytest.approx(bh)
    assert has_square_plinth(pts, 0.0, bh) is square
    assert base_meridian(pts[:300], 0.0, bh) is None  # too sparse: no section


@pytest.mark.slow
@pytest.mark.parametrize("diameter,base", [(0.8, "attic_bezier_plinth"), (1.2, "attic_bezier")])
def test_scan_fits_the_base_and_names_the_rebuilt_parts(diameter, base):
    """A whole column in a random pose (noise, holes, a broken sector): the shaft, the base
    and the capital are fitted; a round base is taken into the column, a square plinth is
    reported only. The base's top is the joint found from the flutes' start: its height
    within 1.5 %, and over the height it covers, its outer profile within 10 mm + 3 % of the
    base's height of the truth's (the meridian's own 2–6 mm, plus the Bézier layout's).
    Measured on six scans of the 1.2 m column (seeds 1–6): 13.1–17.1 mm on five, 25.4 mm on
    seed 4 (the lower curve of the upper torus, where the radius changes fastest with height);
    the bound is 28 mm there."""
    import dataclasses

    from ionic_usd.column.column import build_base_part
    from ionic_usd.evaluate.fit_scan import fit_column_scan
    from ionic_usd.evaluate.metrics import hausdorff_distance
    from ionic_usd.evaluate.scan_parts import base_meridian

    p = dataclasses.replace(portunus_column_params(lower_diameter=diameter), base=base)
    bh, length = p.base_params().height, p.shaft_params().length
    hidden = ((0.0, 99.0), (bh, 9.0), (bh + length, 9.0))
    pts, rot, t = synthetic_scan(
        build_column(p).parts(),
        n=120_000,
        noise=5e-4,
        holes=4,
        missing_sector=(40.0, 100.0),
        hidden=hidden,
        seed=4,
        hole_radius=0.05,
    )
    fit = fit_column_scan(pts)
    s = fit.summary()
    parts = s["parts"]
    assert set(parts) == {"base", "shaft", "capital"}
    assert parts["shaft"]["status"] == "fitted" and parts["capital"]["status"] == "fitted"
    assert parts["capital"]["deviation"]["rms"] < 0.5 * parts["capital"]["rebuilt_rms"]
    assert parts["base"]["status"].startswith("fitted")
    assert parts["base"]["measures"]["hausdorff_pct"] < 1.0
    b = fit.base.column
    h_fit = b.base_params().height
    assert h_fit == pytest.approx(bh, rel=0.015)
    truth = base_meridian(
        _column_points(
            {"Base": build_base_part(p)}, 100_000, 5, noise=0.0, holes=0, missing_sector=None
        ),
        0.0,
        bh,
    )
    fm = build_base_part(b)
    fitted = base_meridian(
        _column_points({"Base": fm}, 100_000, 6, noise=0.0, holes=0, missing_sector=None),
        0.0,
        b.base_params().height,
    )
    # the fit is at the fitted diameter (±2 %): compare in units of the true one
    k = diameter / fit.diameter
    assert hausdorff_distance(fitted * k, truth[truth[:, 1] <= h_fit * k]) < 0.010 + 0.03 * bh
    taken = fit.column.base == b.base
    assert taken == (base == "attic_bezier")
    for rep in parts.values():
        assert rep["status"].startswith("fitted")
        assert rep["deviation"]["rms"] is not None and rep["deviation"]["rms"] < 0.01


@pytest.mark.parametrize("diameter", [0.8, 1.2])
def test_base_top_at_the_joint_from_the_flutes_start(diameter):
    """The base's last fillet and the shaft's ring are one cylinder: the joint is found from
    the flutes' start less the fitted shaft's own ring and spoon ends, within 1 % of the
    base's height (the parts' bins fell 5–47 % short)."""
    from ionic_usd.column.shaft import build_shaft
    from ionic_usd.evaluate.scan_parts import base_top

    p = portunus_column_params(lower_diameter=diameter)
    bh = p.base_params().height
    parts = build_column(p).parts()
    q = _column_points(
        parts,
        20_000,
        1,
        noise=5e-4,
        holes=3,
        missing_sector=(40.0, 100.0),
        hole_radius=0.05,
        y_range=(0.0, bh + 1.5),
    )
    r, h = np.hypot(q[:, 0], q[:, 2]), q[:, 1]
    found = base_top(r, h, 0.6 * bh, diameter, build_shaft(p.shaft))
    assert found is not None
    assert found[0] == pytest.approx(bh, rel=0.01)
    assert p.shaft.ring_bottom < found[1] < p.shaft.ring_bottom + 0.05
    plain = r < 0  # no flutes anywhere: no start
    assert base_top(np.where(plain, r, 0.5), h, 0.6 * bh, diameter, build_shaft(p.shaft)) is None


@pytest.mark.slow  # 30-37 s: a capital fit (the default suite fits one in the whole column)
def test_capital_fitted_to_its_points_beats_the_rebuilt_one():
    """The generator's capital of a column 2 % wider than the shaft's estimate, 2 cm higher:
    the fit recovers its volute (R, eye height and spacing within 1 %) and its deviation
    drops well below the Vitruvian capital rebuilt at the estimate's place."""
    from ionic_usd.evaluate.scan_capital import fit_scanned_capital
    from ionic_usd.evaluate.scan_deviation import shaft_deviation

    p = portunus_column_params(lower_diameter=0.6)
    b = build_column(p)
    y_top = b.base_height + b.shaft_length
    q = _column_points(
        b.parts(),
        6000,
        4,
        noise=5e-4,
        holes=3,
        missing_sector=(40.0, 100.0),
        hole_radius=0.03,
        y_range=(y_top - 0.35, 99.0),
    )
    # the shaft's top disc is the joint under the echinus: no scanner sees it (the fit
    # measures to the capital's outer surface, as the deviation map does)
    joint = (np.abs(q[:, 1] - y_top) < 0.002) & (
        np.hypot(q[:, 0], q[:, 2]) < p.shaft.top_radius - 0.002
    )
    q = q[~joint]
    other = shaft_deviation(q, p)
    start = portunus_column_params(lower_diameter=0.6 / 1.02).capital
    fit = fit_scanned_capital(q, start, p.shaft.top_radius, y_top - 0.02, other)
    v, c = fit.values, p.capital
    assert fit.model == "log_spiral"  # the generator's own
    assert v["capital_spiral_radius"] == pytest.approx(c.volute.capital_spiral_radius, rel=0.01)
    assert v["scroll_position_y"] == pytest.approx(c.scroll_position_y, abs=0.01 * 0.6 / 18)
    assert v["capital_length"] == pytest.approx(c.capital_length, rel=0.01)
    assert fit.ty == pytest.approx(0.02, abs=0.002)
    assert fit.rms < 0.3 * fit.rms_start
    assert set(fit.models) == {"log_spiral", "centred_arcs"}
    assert fit.models["centred_arcs"]["cost"] >= fit.models["log_spiral"]["cost"]


@pytest.mark.slow  # 30-37 s: a capital fit (the default suite fits one in the whole column)
def test_fit_a_capital_scanned_alone():
    """A capital alone (random pose, noise, holes, a 60° missing sector): no fluted shaft is
    found, so the capital sets the axis and the size — measured axis 0.01–0.03°, D within
    0.01 %, deviation rms 1.1–2.0 mm at D = 0.6–1.2 (the shaft's path gave 88° and 58 mm)."""
    from ionic_usd.evaluate.fit_scan import fit_column_scan

    p = portunus_column_params(lower_diameter=0.8)
    caps = {k: m for k, m in build_column(p).parts().items() if k.startswith("Capital")}
    pts, rot, t = synthetic_scan(
        caps, n=6000, noise=5e-4, holes=3, missing_sector=(40.0, 100.0), seed=5, hole_radius=0.04
    )
    fit = fit_column_scan(pts)
    s = fit.summary()
    assert s["parts_found"] == ["capital"]
    assert math.degrees(math.acos(min(1.0, abs(fit.frame.direction @ rot[:, 1])))) < 2.0
    assert fit.frame.direction @ rot[:, 1] > 0  # the abacus up
    assert s["diameter"] == pytest.approx(0.8, rel=0.02)
    assert s["deviation"]["rms"] < 0.004 and np.all(np.isfinite(fit.deviation))
    assert s["parts"]["capital"]["status"] == "fitted"
    assert any("capital alone" in n for n in s["notes"])


def test_a_cut_drum_top_is_not_a_capital():
    """A base with a short drum at D = 0.6 (the first axis 4° off): the drum's cut top flares
    in the bins but reaches neither a capital's width nor its height — only the base and the
    shaft are found (before: a capital at the cut, or "cannot orient the column")."""
    from ionic_usd.evaluate.scan_axis import estimate_axis, find_parts

    p = portunus_column_params(lower_diameter=0.6)
    bh = p.base_params().height
    pts, rot, t = synthetic_scan(
        build_column(p).parts(),
        n=20_000,
        noise=5e-4,
        holes=4,
        missing_sector=(40.0, 100.0),
        hidden=((0.0, 99.0), (bh, 9.0)),
        seed=2,
        y_range=(0.0, bh + 0.8),
        hole_radius=0.05,
    )
    a, c, _ = estimate_axis(pts)
    frame = find_parts(pts, a, c)
    assert sorted(frame.parts) == ["base", "shaft"]
    assert frame.direction @ rot[:, 1] > 0
