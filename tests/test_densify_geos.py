"""Densifying as GEOS does, at exact ties (issue 31).

GEOS (and JTS) split a segment for the Hausdorff/Fréchet ``densify`` fraction into
``round(1 / fraction)`` parts with a half rounded *up* (Python's ``round`` goes to even:
1 / 0.4 = 2.5 gave 2 parts, GEOS 3), and ``segmentize`` (the Densifier) into
``ceil(length / max_length)`` parts. Both are compared with shapely (GEOS) here.
"""

from __future__ import annotations

import numpy as np
import pytest

shapely = pytest.importorskip("shapely")

from ionic_usd.evaluate import metrics  # noqa: E402
from ionic_usd.evaluate.fit_core import densify  # noqa: E402
from ionic_usd.evaluate.polyline import densify_curve  # noqa: E402

# 1 / f is exactly k + 0.5 in floating point for these
TIES = (0.4, 2 / 9, 2 / 7, 2 / 11)


@pytest.mark.parametrize("fraction", TIES)
def test_fraction_at_a_tie_splits_like_geos(fraction):
    assert (1.0 / fraction) % 1.0 == 0.5
    k = int(1.0 / fraction) + 1  # GEOS: the half rounds up
    c = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 2.0]])
    assert len(densify_curve(c, fraction)) == 2 * k + 1


@pytest.mark.parametrize("fraction", (*TIES, 0.5, 0.3, 0.1))
def test_hausdorff_equals_shapely(fraction):
    rng = np.random.default_rng(7)
    for _ in range(60):
        a, b = rng.random((4, 2)), rng.random((5, 2))
        la, lb = shapely.LineString(a), shapely.LineString(b)
        assert metrics.hausdorff_distance(a, b, densify=fraction) == pytest.approx(
            shapely.hausdorff_distance(la, lb, densify=fraction), abs=1e-12
        )


@pytest.mark.parametrize(
    "length,max_length", [(3.0, 1.0), (0.3, 0.1), (1.0, 0.25), (0.7, 0.1), (2.5, 0.5), (1.0, 1.0)]
)
def test_max_length_densify_equals_segmentize_at_ties(length, max_length):
    """length / max_length a whole number (or its float neighbour): ceil, as GEOS."""
    c = np.array([[0.0, 0.0], [length, 0.0], [length, length], [0.0, 0.0]])
    ours = densify(c, max_length)
    geos = np.asarray(shapely.segmentize(shapely.LineString(c), max_length).coords)
    assert ours.shape == geos.shape
    np.testing.assert_allclose(ours, geos, atol=1e-12)
