"""Carved volutes (issue 36): the free-arc model and the choice of model by BIC."""

from __future__ import annotations

import json
import math
import shlex
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from volute_jitter import carved_volute

from ionic_usd.column.volute import vitruvian_volute, volute_curve
from ionic_usd.evaluate.fit import fit_volute
from ionic_usd.evaluate.metrics import resample
from ionic_usd.evaluate.volute_chain import ArcChain, chain_residuals, criterion, fit_chain

FAST = {"samples": 128, "popsize": 4, "maxiter": 2, "polish_evals": 150}


def _chain(radii, sweeps=None, sense=1.0):
    radii = np.asarray(radii, dtype=float)
    sweeps = np.full(len(radii), 0.5 * math.pi) if sweeps is None else np.asarray(sweeps)
    return ArcChain((0.0, 0.0), 0.0, sense, radii, sweeps)


def test_chain_residuals_hand_computed():
    one = _chain([1.0])
    pts = np.array([[2.0, 0.0], [0.5 / math.sqrt(2), 0.5 / math.sqrt(2)], [0.0, -1.0]])
    # outside, inside the quarter; the third point lies outside the arc's span: the nearer end
    np.testing.assert_allclose(chain_residuals(one, pts), [1.0, -0.5, math.sqrt(2)], atol=1e-12)


def test_chain_is_tangent_continuous():
    chain = _chain([5.0, 4.1, 3.0, 2.2, 1.5], sweeps=[1.5, 1.7, 1.4, 1.6, 1.0], sense=-1.0)
    centres, phi = chain.frame()
    for j in range(len(chain.radii) - 1):
        u = np.array([math.cos(phi[j + 1]), math.sin(phi[j + 1])])
        end_j = centres[j] + chain.radii[j] * u  # the end of arc j …
        start = centres[j + 1] + chain.radii[j + 1] * u  # … is the start of arc j + 1
        np.testing.assert_allclose(end_j, start, atol=1e-12)  # same normal: same tangent
    assert np.abs(chain_residuals(chain, chain.points(32))).max() < 1e-12


def test_fit_chain_frees_the_radii_where_the_steps_are_not_linear():
    rng = np.random.default_rng(3)
    true = _chain([5.0, 4.3, 3.5, 2.9, 2.1, 1.6])  # steps 0.7, 0.8, 0.6, 0.8, 0.5
    pts = true.points(80) + rng.normal(0.0, 1e-3, (6 * 80 + 1, 2))
    start = _chain(5.0 - 0.68 * np.arange(6))  # linear steps
    centred, rss_c, k_c = fit_chain(start, pts, "centred_arcs")
    free, rss_f, k_f = fit_chain(centred, pts, "free_arcs")
    assert (k_c, k_f) == (7, 10)
    np.testing.assert_allclose(free.radii, true.radii, atol=5e-3)
    assert math.sqrt(rss_f / len(pts)) < 1.2e-3 < math.sqrt(rss_c / len(pts))
    size = 10.0
    assert (
        criterion(rss_f, len(pts), k_f, size)["bic"] < criterion(rss_c, len(pts), k_c, size)["bic"]
    )


def test_criterion_formulas():
    c = criterion(4.0, 100, 3, 1.0)
    assert c["aic"] == pytest.approx(100 * math.log(0.04) + 6)
    assert c["bic"] == pytest.approx(100 * math.log(0.04) + 3 * math.log(100))
    # an exact fit: the rms floor (1e-5 of the size) leaves the parameter count to decide
    assert criterion(0.0, 100, 3, 1.0)["bic"] < criterion(0.0, 100, 4, 1.0)["bic"]


def test_carved_volute_generator_is_a_treatise_volute():
    exact = carved_volute(0.6, jitter=0.0, noise=0.0)
    eye = 0.6 / 36
    # the outermost arc (radius 8½ eye radii about the corner (½, ½) eye radii) ends on top,
    # 4½ parts (a part is the eye's diameter) above the eye centre
    np.testing.assert_allclose(exact[-1], [0.5 * eye, 9.0 * eye], rtol=1e-9)
    assert np.ptp(exact[:, 1]) == pytest.approx(8.0 * 2 * eye, rel=0.02)
    carved = carved_volute(0.6, noise=0.0, seed=1)
    # a little off: the jitter accumulates along the re-joined arcs, a few % of the radius
    off = np.abs(resample(carved, count=500) - resample(exact, count=500)).max()
    assert 0.005 * 8.5 * eye < off < 0.1 * 8.5 * eye


CHAINS = ("centred_arcs", "free_arcs", "free_joints")  # the log spiral: in the slow tests


def test_fit_volute_on_a_carved_volute_chooses_free_arcs():
    ref = carved_volute(0.6, seed=1, noise=3e-4)
    res = fit_volute(ref, models=("centred_arcs", "free_arcs"), **FAST)
    assert res.model == "free_arcs"
    assert res.after.hausdorff_pct <= 0.2 and res.after.discrete_frechet_pct <= 0.2
    centred = next(a for a in res.alternatives if a.model == "centred_arcs")
    assert res.after.hausdorff < centred.after.hausdorff
    entry = json.loads(json.dumps(res.as_dict()))
    bic = {m: e["criterion"]["bic"] for m, e in entry["models"].items()}
    assert min(bic, key=bic.get) == "free_arcs"
    free = entry["models"]["free_arcs"]
    radii = [k for k in free["parameters"] if k.startswith("radius_")]
    assert len(radii) >= 12  # a quarter-turn arc each (three turns or more)
    # every radius, the first centre (2), the start direction and the last sweep
    assert free["criterion"]["parameters"] == len(radii) + 4


@pytest.mark.slow
def test_fit_volute_frees_the_joints_where_the_carver_moved_them():
    ref = carved_volute(1.2, seed=1, noise=3e-4)
    res = fit_volute(ref, models=CHAINS, **FAST)
    assert res.model == "free_joints"
    assert res.after.hausdorff_pct <= 0.2 and res.after.discrete_frechet_pct <= 0.2
    # down to the digitising noise: rms residual within 10 % of the 0.3 mm
    assert math.sqrt(res.criterion["rss"] / res.criterion["points"]) < 3.3e-4
    free = next(a for a in res.alternatives if a.model == "free_arcs")
    assert res.criterion["bic"] < free.criterion["bic"]


def test_exact_centred_construction_keeps_the_simpler_model():
    true = vitruvian_volute(0.6, volute_model="centred_arcs", arc_ratio=0.4)
    ref = resample(volute_curve(true, 2000), count=1200)
    ref = ref + np.random.default_rng(0).normal(0.0, 3e-4, ref.shape)
    res = fit_volute(ref, models=CHAINS, **FAST)
    assert res.model == "centred_arcs"
    assert {a.model for a in res.alternatives} == {"free_arcs", "free_joints"}
    for free in res.alternatives:
        # freeing lowers the residuals a little, not enough for nine or more parameters
        assert free.criterion["rss"] <= res.criterion["rss"]
        assert free.criterion["bic"] > res.criterion["bic"]


@pytest.mark.slow
@pytest.mark.parametrize("seed", [0, 1, 2, 4])
@pytest.mark.parametrize("diameter", [0.6, 1.2])
def test_carved_volutes_fit_within_a_fifth_of_a_percent(diameter, seed):
    ref = carved_volute(diameter, seed=seed, noise=3e-4) + [2.0, -1.0]
    res = fit_volute(ref)
    assert res.model == "free_joints"
    assert res.after.hausdorff_pct <= 0.2 and res.after.discrete_frechet_pct <= 0.2


@pytest.mark.slow
def test_fit_volute_command_reports_the_criterion(tmp_path):
    curve = carved_volute(1.2, seed=1, noise=3e-4)
    np.savetxt(tmp_path / "carved.csv", curve, delimiter=",", header="x,y", comments="")
    cmd = "ionic-usd fit volute --reference carved.csv --json fit.json"
    args = [sys.executable, "-m", "ionic_usd", *shlex.split(cmd)[1:]]
    out = subprocess.run(args, cwd=tmp_path, capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr[-2000:]
    assert "model chosen by the lowest BIC" in out.stdout
    assert "free_arcs     k=16" in out.stdout and "<- chosen" in out.stdout
    volute = json.loads(Path(tmp_path / "fit.json").read_text("utf-8"))["parts"]["volute"]
    assert volute["model"] == "free_joints"
    assert set(volute["criterion"]) == {"aic", "bic", "rss", "points", "parameters"}


def test_too_few_nodes_for_the_free_models():
    """Twelve traced nodes cannot support 16 or more parameters: the centred arcs alone."""
    ref = carved_volute(0.6, noise=0.0)[::110]
    assert len(ref) == 12
    res = fit_volute(ref, models=CHAINS, **FAST)
    assert res.model == "centred_arcs" and res.alternatives == ()
    assert any("too few" in n for n in res.notes)
    assert math.isfinite(res.criterion["bic"])


def test_the_free_chain_rebuilds_the_column(tmp_path):
    """The chosen free chain is the column's volute (``arc_radii``/``arc_sweeps``): placed by
    the centred fit's pose its curve is the fitted chain, the TOML carries it to
    ``ionic-usd column --config``, and the capital is built on it."""
    import tomllib

    from ionic_usd.column.column import build_column, column_params_from_mapping
    from ionic_usd.evaluate.metrics import hausdorff_distance
    from ionic_usd.evaluate.volute_chain import chain_from_centred
    from ionic_usd.geometry.check import solid_report

    ref = carved_volute(0.6, seed=1, noise=3e-4)
    res = fit_volute(ref, models=("centred_arcs", "free_arcs"), **FAST)
    assert res.model == "free_arcs"
    assert any("rebuilt with this chain" in n for n in res.notes)
    v = res.column.capital.volute
    assert v is res.params and v.volute_model == "centred_arcs"
    radii = [res.values[f"radius_{j}"] for j in range(len(v.arc_radii))]
    assert v.arc_radii == pytest.approx(radii, abs=1e-12)
    assert f"radius_{len(radii)}" not in res.values
    assert len(v.arc_sweeps) == len(v.arc_radii) - 1
    centred = next(a for a in res.alternatives if a.model == "centred_arcs")
    pose = (centred.values["translation_x"], centred.values["translation_y"])
    placed = chain_from_centred(v, centred.alignment.mirrored, pose).points()
    # ... is the chain the fit reports, to the last bits
    sweeps = np.full(len(radii), 0.5 * math.pi)
    sweeps[-1] = math.radians(res.values["last_sweep_deg"])
    fitted = ArcChain(
        (res.values["first_centre_x"], res.values["first_centre_y"]),
        math.radians(res.values["start_direction_deg"]),
        -1.0 if res.values["mirrored"] else 1.0,
        np.asarray(radii),
        sweeps,
    )
    assert np.abs(placed - fitted.points()).max() < 1e-12
    # and as close to the drawing as the fit said (its measure re-aligns the curve)
    assert hausdorff_distance(ref, placed) == pytest.approx(res.after.hausdorff, rel=0.05)
    assert res.after.hausdorff_pct <= 0.2
    # the TOML round trip keeps every bit, and the column builds on it as one solid
    col = column_params_from_mapping(tomllib.loads(res.to_toml()))
    assert col.capital.volute == v
    (tmp_path / "v.toml").write_text(res.to_toml(), encoding="utf-8")
    cmd = [sys.executable, "-m", "ionic_usd", "column", "--config", "v.toml", "-o", "c.usda"]
    out = subprocess.run(cmd, cwd=tmp_path, capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    cap = build_column(col).capital
    report = solid_report(cap)
    assert np.isfinite(cap.points).all() and report.open_edges == 0 and report.shells == 1
    # the capital differs from the centred-arc one: the chain is what is built
    assert cap.n_triangles != build_column(centred.column).capital.n_triangles or not np.allclose(
        cap.points, build_column(centred.column).capital.points
    )


@pytest.mark.parametrize(
    ("changes", "what"),
    [
        ({"arc_radii": (0.01, -0.02)}, "arc_radii"),
        ({"arc_radii": (0.01, float("nan"))}, "arc_radii"),
        ({"arc_radii": "0.01"}, "arc_radii"),
        ({"arc_radii": (0.01,) * 5}, "arc_radii"),  # not one per quarter turn
        ({"arc_sweeps": (90.0,)}, "arc_sweeps"),  # sweeps without radii
        ({"arc_radii": (0.01, 0.02), "arc_sweeps": (90.0, 90.0)}, "arc_sweeps"),
        ({"arc_radii": (0.01, 0.02), "arc_sweeps": (0.0,)}, "arc_sweeps"),
        ({"arc_radii": (0.01, 0.02), "arc_sweeps": (2000.0,)}, "arc_sweeps"),
    ],
)
def test_a_bad_free_chain_is_refused_by_name(changes, what):
    from ionic_usd.column.volute import VoluteParams
    from ionic_usd.errors import ParameterError

    with pytest.raises(ParameterError, match=what):
        VoluteParams(volute_model="centred_arcs", **changes)
    with pytest.raises(ParameterError, match="arc_radii"):  # the spiral has no arcs
        VoluteParams(arc_radii=(0.01,))
