"""Scan fits down to the noise (issue 36), on scans from tests/synth_scan.py — an
independent generator (analytic surfaces, its own base profile and flute construction),
not the project's model."""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))

from synth_scan import Truth, attic_profile, fragment_scan, joint_height, section_radius  # noqa: E402

from ionic_usd.evaluate.scan_flutes import flute_factor, plinth_turn  # noqa: E402

NOISE = 0.8  # mm


def _fit(n: int, truth: Truth, unit: float, seed: int):
    from ionic_usd.evaluate.fit_scan import fit_column_scan

    pts, _, _ = fragment_scan(n, truth=truth, noise=NOISE, seed=seed, unit=unit)
    return fit_column_scan(pts * unit)


def _check(fit, truth: Truth) -> None:
    s = fit.summary()
    assert s["flutes"] == truth.flutes
    assert s["diameter"] == pytest.approx(2e-3 * truth.radius, rel=0.005)
    for part in ("base", "shaft"):
        rms_mm = 1000.0 * s["parts"][part]["deviation"]["rms"]
        assert rms_mm <= 2.0 * NOISE, (part, rms_mm)
    assert s["parts"]["base"]["status"] == "fitted"
    assert s["not_fitted"] == ["capital", "shaft length and top ring"]
    col = fit.column
    assert col.base_plinth == 1  # the plinth is a box, not a lathe
    sh = col.shaft
    period = 360.0 / truth.flutes
    # the generator turns its flutes +4° from +x towards +z; the model counts towards -z
    err = (sh.flute_phase + truth.rotation_deg + 0.5 * period) % period - 0.5 * period
    assert abs(err) < 0.5
    assert 360.0 / sh.flutes - sh.flute_angle == pytest.approx(truth.fillet_deg, abs=0.3)
    bp = col.base_params()
    assert bp.height == pytest.approx(1e-3 * joint_height(truth), abs=0.010)  # a 6 mm step, and the
    # frame's bottom (the lowest point, a noise width below the plinth's)


def test_fragment_fits_to_the_noise():
    """mm units, 2,500 points: every part's rms within twice the noise (was 38 mm)."""
    truth = Truth()
    _check(_fit(2500, truth, 1e-3, 0), truth)


@pytest.mark.slow
@pytest.mark.parametrize(
    ("radius", "unit", "seed"), [(250.0, 0.0254, 1), (700.0, 1e-3, 2), (400.0, 1e-3, 3)]
)
def test_fragment_fits_to_the_noise_at_other_scales(radius, unit, seed):
    truth = Truth().scaled(radius)
    _check(_fit(6000, truth, unit, seed), truth)


def test_flute_factor_matches_the_independent_section():
    """The fit's polar flute model against the test generator's own ray-ellipse section
    (written separately), full flutes and narrowed ends."""
    t = Truth()
    th = np.linspace(0.0, 2.0 * math.pi, 7201) + 1.2345e-4  # off the flutes' exact edges
    for k in (1.0, 0.5, 0.1):
        ref = section_radius(t, th, np.full(len(th), 400.0), np.full(len(th), k))
        period = 360.0 / t.flutes
        got = 400.0 * flute_factor(
            -th, np.full(len(th), k), t.flutes, period - t.fillet_deg, t.depth, -t.rotation_deg
        )
        assert np.max(np.abs(got - ref)) < 1e-6


def test_plinth_turn_finds_the_faces_and_not_a_round_plinth():
    rng = np.random.default_rng(0)
    a = 0.59
    u = rng.uniform(-a, a, 800)
    face = rng.integers(4, size=800)
    x = np.where(face < 2, np.where(face == 0, a, -a), u)
    z = np.where(face < 2, u, np.where(face == 2, a, -a))
    turn = math.radians(23.0)
    c, s = math.cos(turn), math.sin(turn)
    uv = np.column_stack([c * x - s * z, s * x + c * z]) + rng.normal(0, 8e-4, (800, 2))
    assert plinth_turn(uv) == pytest.approx(23.0, abs=0.1)
    ang = rng.uniform(0, 2 * math.pi, 800)
    assert plinth_turn(np.column_stack([a * np.cos(ang), a * np.sin(ang)])) is None


def test_principal_curve_follows_a_horizontal_step():
    """A fillet's step (r from 0.48 to 0.46 at one height) that y-bins cannot follow."""
    from ionic_usd.evaluate.scan_plinth import principal_curve

    rng = np.random.default_rng(1)
    prof = np.array([[0.48, 0.30], [0.48, 0.35], [0.46, 0.35], [0.46, 0.40]])
    seg = rng.integers(3, size=6000)
    f = rng.random(6000)[:, None]
    pts = prof[seg] + f * (prof[seg + 1] - prof[seg]) + rng.normal(0, 8e-4, (6000, 2))
    start = np.array([[0.48, 0.30], [0.48, 0.34], [0.47, 0.35], [0.46, 0.36], [0.46, 0.40]])
    curve = principal_curve(pts, start, 0.002)
    from ionic_usd.evaluate.polyline import point_to_polyline_distances

    mid = prof[1] + np.linspace(0, 1, 50)[:, None] * (prof[2] - prof[1])  # the step itself
    assert np.max(point_to_polyline_distances(mid, curve)) < 2.5e-3


def test_base_deviation_is_exact_on_the_plinth_and_the_lathe():
    from ionic_usd.column.column import portunus_column_params
    from ionic_usd.evaluate.scan_deviation import base_deviation

    col = portunus_column_params()
    bp = col.base_params()
    assert bp.plinth_modules >= 1
    from ionic_usd.column.base import _layout

    outer, _, half, top, _ = _layout(bp)
    p = np.array([[half + 0.01, 0.5 * top, 0.0], [0.0, 0.5 * top, -(half + 0.003)]])
    assert base_deviation(p, col) == pytest.approx([0.01, 0.003], abs=1e-9)
    # a point 2 mm off the lathe's meridian along its normal, at any turn
    i = len(outer) // 2
    t = outer[i + 1] - outer[i - 1]
    n = np.array([t[1], -t[0]]) / np.hypot(*t)
    q = outer[i] + 0.002 * n
    ang = 0.7
    pt = np.array([[q[0] * math.cos(ang), q[1], q[0] * math.sin(ang)]])
    assert base_deviation(pt, col)[0] == pytest.approx(0.002, abs=2e-4)


def test_units_detected_or_asked_for():
    from ionic_usd.errors import ReferenceCurveError
    from ionic_usd.evaluate.scan_io import detect_units

    pts, _, _ = fragment_scan(1500, unit=1e-3)
    assert detect_units(pts, "s")[1] == "mm"
    assert detect_units(pts * 1e-3, "s")[1] == "m"
    with pytest.raises(ReferenceCurveError, match="--units"):
        detect_units(pts / 25.4, "s")  # inches: a 31-unit column could be cm
    assert attic_profile(Truth())[-1, 0] == pytest.approx(400.0)
