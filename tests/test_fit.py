"""Automatic fitting: recovers parameters of curves the project generated itself."""

from __future__ import annotations

import dataclasses
import math
import tomllib
from pathlib import Path

import numpy as np
import pytest
from numpy.testing import assert_allclose

from ionic_usd.column.column import column_params_from_mapping, portunus_column_params
from ionic_usd.column.volute import VoluteParams, volute_curve
from ionic_usd.errors import OutputExistsError, ParameterError
from ionic_usd.evaluate.fit import (
    BaseLayout,
    densify,
    fit_base,
    fit_shaft,
    fit_volute,
    suggest_base_layout,
)
from ionic_usd.evaluate.metrics import curve_length, resample
from ionic_usd.evaluate.reference import align
from ionic_usd.evaluate.sections import base_section, shaft_silhouette_section, volute_section

ROOT = Path(__file__).resolve().parents[1]
V0 = VoluteParams()
# a volute clearly unlike the Vitruvian start: 10 % larger, tighter, rotated start, fewer turns
TRUE_VOLUTE = V0.with_(
    capital_spiral_radius=0.26, c=V0.c * 1.1, d=V0.d * 0.97, start_angle=100.0, spiral_circuits=2.9
)


def _roundtrip(res, tmp_path):
    path = res.write_toml(tmp_path / "fitted.toml")
    with pytest.raises(OutputExistsError):
        res.write_toml(path)
    res.write_toml(path, force=True)
    return column_params_from_mapping(tomllib.loads(path.read_text("utf-8")))


# -- shaft (fast) ---------------------------------------------------------------------------------
def test_fit_shaft_recovers_parameters(tmp_path):
    p = portunus_column_params()
    true = dataclasses.replace(
        p.shaft, bottom_radius=0.5, top_radius=0.42, height=6.5, entasis=0.02
    )
    ref = shaft_silhouette_section(dataclasses.replace(p, shaft=true)) + [0.0, 0.3]
    res = fit_shaft(ref[::-1])  # either direction
    s = res.params
    assert s.bottom_radius == pytest.approx(0.5, abs=1e-5)
    assert s.top_radius == pytest.approx(0.42, abs=1e-5)
    assert s.height == pytest.approx(6.5, abs=1e-4)
    assert s.entasis == pytest.approx(0.02, abs=1e-4)
    assert res.before.hausdorff_pct > 1.0
    assert res.after.hausdorff_pct < 0.01
    col = _roundtrip(res, tmp_path)
    assert col.shaft == res.column.shaft


# -- volute ---------------------------------------------------------------------------------------
def _turned(curve, deg, shift):
    a = math.radians(deg)
    rot = np.array([[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]])
    return curve @ rot.T + np.asarray(shift)


def test_fit_volute_log_spiral_recovers_own_parameters(tmp_path):
    # posed: translated and turned 25°; a turn of the spiral is a change of start and circuits
    ref = _turned(volute_curve(TRUE_VOLUTE, 400), 25.0, [0.3, 1.2])
    res = fit_volute(ref, models="log_spiral")
    assert res.model == "log_spiral" and not res.alternatives
    assert res.after.hausdorff_pct < 0.02 and res.after.discrete_frechet_pct < 0.1
    assert res.after.hausdorff < res.before.hausdorff
    p = res.params
    # turning r = a e^{-cθ}/b − d by φ is the same family at ψ = θ + φ with
    # R' = R e^{cφ} and d' = d e^{-cφ} (a, b held): the fit must land there exactly
    k = math.exp(TRUE_VOLUTE.c * math.radians(25.0))
    assert p.capital_spiral_radius == pytest.approx(0.26 * k, rel=5e-3)
    assert p.c == pytest.approx(TRUE_VOLUTE.c, rel=5e-3)
    assert p.d == pytest.approx(TRUE_VOLUTE.d / k, rel=1e-2)
    assert p.start_angle == pytest.approx(125.0, abs=0.5)
    assert p.spiral_circuits == pytest.approx(2.9 + 25.0 / 360.0, abs=2e-3)
    assert (p.a, p.b) == (V0.a, V0.b)  # held: the curve depends on R·a/b and R·d only
    assert res.bounds_hit == ()
    col = _roundtrip(res, tmp_path)
    assert col.capital.volute == p
    # the written column's volute section has the reference's shape
    _, how = align(ref, volute_section(col, frame="volute", samples=400))
    assert how.hausdorff_after < 2e-3 * curve_length(ref)


ARCS = V0.with_(
    volute_model="centred_arcs",
    capital_circle_radius=0.03,
    arc_square=0.035,
    arc_ratio=0.5,
    start_angle=80.0,
    spiral_circuits=2.75,
)


def test_fit_volute_centred_arcs_recovers_own_parameters():
    ref = _turned(volute_curve(ARCS, 600), -15.0, [1.0, 2.0])[::-1]
    res = fit_volute(ref, models="centred_arcs")
    assert res.model == "centred_arcs"
    assert res.after.hausdorff_pct < 0.02
    p = res.params
    assert p.volute_model == "centred_arcs"
    assert p.capital_circle_radius == pytest.approx(0.03, rel=5e-3)
    assert p.arc_square == pytest.approx(0.035, rel=5e-3)
    assert p.arc_ratio == pytest.approx(0.5, abs=5e-3)
    assert p.start_angle == pytest.approx(65.0, abs=0.5)
    assert p.spiral_circuits == pytest.approx(2.75 - 15.0 / 360.0, abs=2e-3)
    upright = _turned(volute_curve(ARCS, 2048), 90.0 - math.degrees(ARCS.theta_end), [0, 0])
    assert res.diameter == pytest.approx(18 / 8 * np.ptp(upright[:, 1]), rel=1e-2)


@pytest.mark.slow
@pytest.mark.parametrize("diameter", [0.6, 0.95, 1.2])
def test_fit_volute_scale_free_chooses_the_construction(diameter):
    from ionic_usd.column.volute import vitruvian_volute

    true = vitruvian_volute(diameter, volute_model="centred_arcs", arc_ratio=0.4)
    ref = volute_curve(true, 800) + [5.0, -3.0]
    res = fit_volute(ref)  # every model; bounds from the reference, not from Portunus
    assert res.model == "centred_arcs"  # exact: the freer arc models gain nothing (BIC)
    by = {a.model: a for a in res.alternatives}
    assert sorted(by) == ["free_arcs", "free_joints", "log_spiral"]
    assert res.after.hausdorff_pct < 0.2 and res.after.discrete_frechet_pct < 0.2
    assert by["log_spiral"].after.hausdorff > res.after.hausdorff
    assert res.params.arc_square == pytest.approx(true.arc_square, rel=1e-2)
    # the estimate reads 8/18 D off the fitted volute's height; this construction is not
    # exactly 8 parts high, so compare with the reference's own height
    assert res.diameter == pytest.approx(18 / 8 * np.ptp(ref[:, 1]), rel=1e-2)


def test_fit_reports_a_bound_hit():
    # a spiral of 6 turns: circuits may go 0.6 above the traced turns at most, so a start
    # forced far from it (through a fixed seed and no global stage) cannot explain it all;
    # instead check the box flags values on its edge directly
    from ionic_usd.evaluate.fit_core import Box

    box = Box([0.0, 0.0], [1.0, 2.0])
    assert box.hit(np.array([0.5, 1.0]), ("a", "b")) == ("b",)
    assert box.hit(np.array([0.0, 0.5]), ("a", "b")) == ("a",)
    assert box.hit(np.array([0.4, 0.5]), ("a", "b")) == ()


@pytest.mark.slow
def test_fit_volute_with_noise_reaches_noise_level():
    rng = np.random.default_rng(3)
    sigma = 5e-4
    clean = volute_curve(TRUE_VOLUTE, 400)
    ref = clean + rng.normal(0.0, sigma, clean.shape) + np.array([-0.2, 0.5])
    res = fit_volute(ref, initial=V0, eye=[-0.2, 0.5], models="log_spiral")
    # mean node-to-curve error ≈ E|N(0, σ)| = 0.8 σ; the worst node a few σ
    assert res.after.average_error < 1.2 * sigma
    assert res.after.hausdorff < 6 * sigma
    p = res.params
    # R, c, d and the start angle trade off against each other (R·a scales, d shifts and the
    # start angle turns the curve), so under noise each is recovered to a few per cent
    assert p.capital_spiral_radius == pytest.approx(0.26, rel=3e-2)
    assert p.c == pytest.approx(TRUE_VOLUTE.c, rel=2e-2)
    assert p.d == pytest.approx(TRUE_VOLUTE.d, rel=2e-2)
    assert p.start_angle == pytest.approx(100.0, abs=5.0)
    assert p.spiral_circuits == pytest.approx(2.9, abs=0.01)
    # the eye was placed at the spiral origin: the offsets are the origin's fitting error
    assert math.hypot(p.offset_x, p.offset_y) < 2e-3


@pytest.mark.slow
def test_fit_volute_mirrored_reference_and_other_measure():
    ref = volute_curve(TRUE_VOLUTE, 300)
    ref[:, 0] *= -1.0
    res = fit_volute(ref[::-1], initial=V0, measure="average_error", models="log_spiral")
    assert res.alignment.mirrored
    assert res.after.average_error_pct < 0.05


def test_fit_volute_bad_input():
    with pytest.raises(ParameterError):
        fit_volute(np.zeros((5, 3)))
    with pytest.raises(ParameterError):
        fit_volute(volute_curve(V0, 50), measure="chamfer")


# -- base -----------------------------------------------------------------------------------------
def test_fit_base_noise_free(tmp_path):
    p = portunus_column_params()
    target = dataclasses.replace(p, base="attic_bezier")
    ref = resample(base_section(target), count=300) + [1.0, 2.0]
    res = fit_base(ref, initial=dataclasses.replace(p, base="G1"))
    assert res.before.hausdorff_pct > 5
    assert res.after.hausdorff_pct < 0.2
    col = _roundtrip(res, tmp_path)
    assert col.base == res.params
    assert col.base_height == pytest.approx(res.column.base_height)
    # the written column rebuilds the fitted base exactly, and it has the reference's shape
    assert_allclose(base_section(col), base_section(res.column), atol=1e-9)
    assert col.base_params().scale == pytest.approx(1.0)
    # the convention: the top end meets the shaft (radius d), up to the fit error
    assert base_section(col)[-1, 0] == pytest.approx(
        p.shaft.bottom_radius, abs=2 * res.after.hausdorff
    )


@pytest.mark.slow
@pytest.mark.parametrize("measure", ["average_error", "discrete_frechet"])
def test_fit_base_given_modules(measure):
    p = portunus_column_params()
    ref = base_section(dataclasses.replace(p, base="G2"))
    res = fit_base(
        ref,
        modules=[2, 2, 4, 4, 4, 2, 4, 4, 2, 4, 4, 4, 4],
        measure=measure,
        initial=dataclasses.replace(p, base="G1"),
    )
    assert res.params.count(",") == 12
    assert res.after.hausdorff_pct < 0.5
    assert res.after.percent(measure) < res.before.percent(measure)


def test_suggest_base_layout_cuts_at_corner_and_extremum():
    # a straight vertical run, then a half circle bulging outward (r max in its middle)
    line = np.column_stack([np.full(50, 1.0), np.linspace(0.0, 1.0, 50)])
    a = np.linspace(-np.pi / 2, np.pi / 2, 200)
    arc = np.column_stack([1.0 + 0.5 * np.cos(a), 1.5 + 0.5 * np.sin(a)])
    prof = np.vstack([line, arc[1:]])
    lay = suggest_base_layout(prof)
    assert isinstance(lay, BaseLayout)
    p = resample(prof, count=400)
    cuts = p[list(lay.breaks)]
    # a cut at the corner (1, 1) and one at the outermost point (1.5, 1.5)
    assert np.min(np.linalg.norm(cuts - [1.0, 1.0], axis=1)) < 0.02
    assert np.min(np.linalg.norm(cuts - [1.5, 1.5], axis=1)) < 0.02
    assert lay.points[0] == 2  # the straight run is a 2-point module
    assert all(n in (2, 4) for n in lay.points)


def test_base_layout_validation():
    with pytest.raises(ParameterError):
        BaseLayout((0, 5), (2, 4))
    with pytest.raises(ParameterError):
        BaseLayout((0, 5, 3), (2, 4))
    with pytest.raises(ParameterError):
        fit_base(base_section(portunus_column_params()), modules=[1, 4])


def test_densify_keeps_nodes_and_bounds_segments():
    c = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 0.25]])
    d = densify(c, 0.3)
    assert len(d) == 4 + 1 + 1  # 1 → 4 parts of 0.25, 0.25 → 1 part, plus the end node
    for node in c:
        assert np.min(np.linalg.norm(d - node, axis=1)) == 0.0
    assert np.linalg.norm(np.diff(d, axis=0), axis=1).max() <= 0.3
    with pytest.raises(ParameterError):
        densify(c, 0.0)


# -- shaft cross-section ---------------------------------------------------------------------------
@pytest.mark.parametrize("diameter", [0.6, 0.95, 1.2])
def test_fit_shaft_section_any_scale_with_rotation(diameter):
    from ionic_usd.evaluate.fit_shaft import fit_shaft_section
    from ionic_usd.evaluate.sections import shaft_cross_section_at

    p = portunus_column_params(lower_diameter=diameter)
    true = dataclasses.replace(p.shaft, flutes=20, flute_angle=14.0, flute_depth=0.8)
    p = dataclasses.replace(p, shaft=true)
    y = p.base_params().height + 1.0
    sec = shaft_cross_section_at(p, y)
    r_true = float(np.hypot(*sec[:-1].T).max())
    ref = _turned(sec, 31.0, [3.0, -1.0])[::-1]
    res = fit_shaft_section(ref)
    assert res.model == "section" and res.values["flutes"] == 20
    assert res.values["radius"] == pytest.approx(r_true, rel=1e-3)
    assert res.values["flute_angle"] == pytest.approx(14.0, abs=0.1)
    assert res.values["flute_depth"] == pytest.approx(0.8, abs=0.02)
    assert res.values["rotation_deg"] % 18.0 == pytest.approx(31.0 % 18.0, abs=0.05)
    assert res.after.hausdorff_pct < 0.2 and res.after.discrete_frechet_pct < 0.2
    assert res.diameter == pytest.approx(2 * r_true, rel=1e-3)


def test_fit_shaft_refuses_a_closed_curve():
    from ionic_usd.evaluate.sections import shaft_cross_section_at

    with pytest.raises(ParameterError, match="cross-section"):
        fit_shaft(shaft_cross_section_at(portunus_column_params(), 1.0))


def test_fit_volute_report_lists_every_model_once(tmp_path):
    """as_dict of a fit with alternatives: a ``models`` table, no table nested in itself."""
    import json

    from ionic_usd.evaluate.reference import read_csv_curve

    ref = read_csv_curve(ROOT / "examples" / "volute_twelve_centres.csv")
    res = fit_volute(ref, samples=64, popsize=4, maxiter=1, polish_evals=0)
    entry = json.loads(json.dumps(res.as_dict()))  # plain JSON: no cycle, no nesting
    models = entry["models"]
    assert sorted(models) == sorted([res.model, *(a.model for a in res.alternatives)])
    assert len(models) == 4  # log spiral, centred arcs and the free arcs / joints from them
    for name, fitted in models.items():
        assert "models" not in fitted
        same = res if name == res.model else next(a for a in res.alternatives if a.model == name)
        assert fitted["hausdorff"] == pytest.approx(same.after.hausdorff)
    assert entry["hausdorff"] == models[res.model]["hausdorff"]


@pytest.mark.slow
def test_documented_fit_volute_command_writes_its_json(tmp_path):
    """The docs' example, as written, in a folder holding a copy of examples/ (issue 31)."""
    import json
    import shlex
    import shutil
    import subprocess
    import sys

    shutil.copytree(ROOT / "examples", tmp_path / "examples")
    cmd = "ionic-usd fit volute --reference examples/volute_twelve_centres.csv --json fit.json"
    args = [sys.executable, "-m", "ionic_usd", *shlex.split(cmd)[1:]]
    out = subprocess.run(args, cwd=tmp_path, capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr[-2000:]
    report = json.loads((tmp_path / "fit.json").read_text("utf-8"))
    volute = report["parts"]["volute"]
    assert sorted(volute["models"]) == ["centred_arcs", "free_arcs", "free_joints", "log_spiral"]
    # the twelve centres' radius steps are not linear (a side, then the step between squares)
    # and the joints between squares are off the quarter turns: the free joints follow them
    # and the criterion says the data support the extra parameters
    assert volute["model"] == "free_joints"
    crit = {m: e["criterion"]["bic"] for m, e in volute["models"].items()}
    assert crit["free_joints"] == min(crit.values())
