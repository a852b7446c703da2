"""A whole column with its capital, scanned (issue 36): per-part deviation against the noise,
on scans from tests/synth_column.py — the tests' own base, shaft and capital (an echinus,
Archimedean volutes on a cushion, a square abacus), not the project's model."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))

from synth_column import column_scan  # noqa: E402
from synth_scan import Truth  # noqa: E402

NOISE = 0.8  # mm
PARTS = ("base", "shaft", "capital")


def _fit(seed: int):
    from ionic_usd.evaluate.fit_scan import fit_column_scan

    pts, part, _, _ = column_scan(noise=NOISE, seed=seed)
    fit = fit_column_scan(pts * 1e-3)
    rms = {
        name: 1000.0 * float(np.sqrt(np.mean(fit.deviation[part == k] ** 2)))
        for k, name in enumerate(PARTS)
    }
    return fit, rms


#: the capital's rms (mm) on seeds 0-4: 38.8-41.9 with the volute's size, eyes and placement
#: free, 5.8-6.4 with its width, bolsters, echinus and abacus free too, 3.4-4.9 with the
#: volute started on the rolls' circle and its growth, turns, band width, the eye's offset,
#: the bolster's belt and the relief depth free, 2.6-3.1 with the bolsters put on the rolls
#: and the volute's shape swept, 2.2-2.5 with the volute's face covering the bolster's end
#: (issue 36; per surface: tools/capital_surfaces.py)
CAPITAL_BEFORE = 3.1
CAPITAL_BOUND = 2.9


def _check_capital(fit, rms: dict[str, float]) -> None:
    """The capital's rms below the previous model's (not yet the noise: the strict xfail
    below), and the parts the scan shows measured: the volute faces 680 mm apart (the
    description's D = 800), the abacus 960 mm square, the volutes' eyes (the rolls' axis)
    390 mm out and 120 mm above the shaft's top."""
    assert rms["capital"] <= CAPITAL_BOUND < CAPITAL_BEFORE, rms
    from synth_column import CapitalTruth

    c, v = CapitalTruth(), fit.summary()["parts"]["capital"]["values"]
    # the model's volutes are not these Archimedean ones: its width comes out 11-13 mm wide
    # of the faces on seeds 1 and 3 (691, 693 mm), within 3 %
    assert 1000.0 * v["capital_width"] == pytest.approx(2.0 * c.face, abs=20.0)
    assert 1000.0 * v["abacus_length"] == pytest.approx(2.0 * c.abacus_half, abs=25.0)
    assert 1000.0 * v["abacus_width"] == pytest.approx(2.0 * c.abacus_half, abs=25.0)
    # the model's eye is where its volute's spiral and its bolsters on the eye's axis best
    # agree with these faces and rolls: within 15 mm of the rolls' axis (measured 391-402
    # mm out, 109-122 up on seeds 0-4; 18-20 mm off before its offset and growth were free)
    assert 1000.0 * v["eye_x"] == pytest.approx(c.eye_x, abs=15.0)
    assert 1000.0 * v["scroll_position_y"] == pytest.approx(c.echinus_top, abs=15.0)
    fitted = fit.summary()["parts"]["capital"]
    assert {"capital_width", "abacus_side", "echinus_height"} <= set(fitted["fitted"])
    assert {"eye_offset_x", "volute_growth", "relief_depth", "volute_turns"} <= set(
        fitted["fitted"]
    )
    assert "slab_depth" in fitted["kept"]
    # the bolsters lie on the rolls (before: 9-12 mm out and 7 mm low of their axis, their
    # radius 10-11 mm short), and the abacus rests on them
    from ionic_usd.column.capital_body import capital_layout
    from ionic_usd.evaluate.scan_volute import bolster_circle

    cap = fit.column.capital
    got = 1000.0 * bolster_circle(cap, fit.column.shaft.top_radius)
    want = np.array([c.eye_x, c.echinus_top, c.volute_radius])
    assert np.abs(got - want).max() <= 5.0, (got, want)
    seat = 1000.0 * (capital_layout(cap).abacus_y + cap.capital_position_y)
    assert seat == pytest.approx(c.echinus_top + c.volute_radius, abs=5.0)


def _check_base_and_shaft(seed: int) -> None:
    fit, rms = _fit(seed)
    _check_capital(fit, rms)
    s = fit.summary()
    t = Truth()
    assert s["parts_found"] == ["base", "capital", "shaft"]
    assert s["flutes"] == t.flutes
    assert 2.0 * fit.column.shaft.bottom_radius == pytest.approx(2e-3 * t.radius, rel=0.002)
    # the points of each part (by the generator's labels) and the fit's own split
    for part in ("base", "shaft"):
        assert rms[part] <= 2.0 * NOISE, (part, rms)
        assert 1000.0 * s["parts"][part]["deviation"]["rms"] <= 2.0 * NOISE, (part, s["parts"])
    # the top ring, from the flutes' top tip (before: the Vitruvian 60 mm, shaft rms 1.45 mm)
    sh = fit.column.shaft
    # (4 mm: the capital's fitted height sets the shaft's top; seed 3's came out 38.5 mm
    # once the volute's turns and band were fitted, 2.7 mm higher than before)
    assert 1000.0 * sh.ring_top == pytest.approx(t.ring, abs=4.0)
    assert 1000.0 * sh.top_radius == pytest.approx(t.radius * t.top_ratio, abs=0.5)


def test_whole_column_base_and_shaft_fit_to_the_noise():
    """Measured (seed 0): base 0.89, shaft 0.88 mm rms (the shaft was 1.45 before its top
    ring and taper were fitted again at the length the capital sets); the capital 2.30 mm
    (2.80 before the volute's face covered the bolster's end, 3.34 before its shape was
    swept, 4.05 before the bolsters were put on the rolls, 6.3 before the volute was started
    on the rolls' circle)."""
    _check_base_and_shaft(0)


@pytest.mark.slow
@pytest.mark.parametrize("seed", [1, 2, 3, 4])
def test_whole_column_base_and_shaft_fit_to_the_noise_any_scan(seed):
    _check_base_and_shaft(seed)


@pytest.mark.slow
@pytest.mark.xfail(
    strict=True,
    reason="the capital model (the project's capital with its volute's size, growth, eye "
    "height, spacing and offset, turns, band width, width, bolster radius and belt, relief "
    "depth, echinus height and projection, abacus side and height, scale and height free) "
    "cannot take this "
    "capital's faces: a full disc carved with a sine channel between Archimedean turns, "
    "against a raised band with a flat channel floor between log-spiral turns (the faces' "
    "spirals 2.8-3.5 mm rms), a sine canalis against a flat one (2.4-2.7), a quarter-ellipse "
    "echinus against the model's ovolo (2.9-3.5); measured 2.2-2.5 mm rms on seeds 0-4 "
    "(issue 36)",
)
def test_whole_column_capital_fits_to_the_noise():
    _, rms = _fit(0)
    assert rms["capital"] <= 2.0 * NOISE, rms
