"""Curve measures against brute force, hand-computed cases and GEOS (shapely) as an oracle."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
import shapely  # noqa: E402
from numpy.testing import assert_allclose

from ionic_usd.errors import GeometryError, ParameterError
from ionic_usd.evaluate import metrics as M


# ------------------------------------------------------------------------------ brute force
def brute_point_to_polyline(points: np.ndarray, poly: np.ndarray) -> np.ndarray:
    if poly.shape[0] == 1:
        return np.linalg.norm(points - poly[0], axis=1)
    o = poly[:-1]
    v = poly[1:] - poly[:-1]
    len2 = (v * v).sum(axis=1)
    w = points[:, None, :] - o[None]
    t = np.clip((w * v).sum(-1) / np.where(len2 > 0, len2, 1.0), 0.0, 1.0)
    return np.linalg.norm(w - t[..., None] * v, axis=-1).min(axis=1)


def brute_discrete_frechet(a: np.ndarray, b: np.ndarray) -> float:
    d = np.linalg.norm(a[:, None] - b[None], axis=-1)
    n, m = d.shape
    big = np.full((n, m), np.inf)
    for i in range(n):
        for j in range(m):
            if i == 0 and j == 0:
                big[i, j] = d[0, 0]
                continue
            prev = min(
                big[i - 1, j] if i else np.inf,
                big[i, j - 1] if j else np.inf,
                big[i - 1, j - 1] if i and j else np.inf,
            )
            big[i, j] = max(prev, d[i, j])
    return float(big[-1, -1])


def random_walk(rng: np.random.Generator, n: int, d: int = 2) -> np.ndarray:
    return np.cumsum(rng.normal(size=(n, d)), axis=0)


def linestring(c: np.ndarray):
    return shapely.LineString(c)


# ------------------------------------------------------------------------------ resampling
def test_resample_constant_spacing_and_endpoints():
    t = np.linspace(0.0, 1.0, 7) ** 2
    curve = np.c_[np.cos(3 * t), np.sin(3 * t)]
    out = M.resample(curve, spacing=0.05)
    length = M.curve_length(curve)
    assert out.shape[0] == math.ceil(length / 0.05) + 1
    assert_allclose(out[0], curve[0])
    assert_allclose(out[-1], curve[-1])
    # Every output node lies on the input polyline, at constant arc-length steps.
    assert_allclose(brute_point_to_polyline(out, curve), 0.0, atol=1e-12)
    step = length / (out.shape[0] - 1)
    assert step <= 0.05
    straight = M.resample(np.array([[0.0, 0.0], [3.0, 0.0], [3.0, 4.0]]), count=15)
    assert_allclose(np.linalg.norm(np.diff(straight, axis=0), axis=1), 0.5)


def test_resample_exact_multiple_keeps_node_count():
    line = np.array([[0.0, 0.0], [96.0, 0.0]])
    assert M.resample(line, spacing=1.0).shape == (97, 2)  # the paper's base: 96 + 1 nodes


@pytest.mark.parametrize(
    "kwargs", [{}, {"spacing": 1.0, "count": 3}, {"spacing": 0.0}, {"count": 1}]
)
def test_resample_rejects_bad_arguments(kwargs):
    with pytest.raises(ParameterError):
        M.resample(np.array([[0.0, 0.0], [1.0, 0.0]]), **kwargs)


def test_resample_zero_length():
    with pytest.raises(GeometryError):
        M.resample(np.zeros((3, 2)), count=4)


@pytest.mark.parametrize(
    "bad", [np.zeros((3,)), np.zeros((3, 4)), np.array([[0.0, np.nan], [1.0, 1.0]])]
)
def test_invalid_curves_raise_parameter_error(bad):
    with pytest.raises(ParameterError):
        M.hausdorff_distance(bad, np.zeros((2, 2)))


def test_dimension_mismatch():
    with pytest.raises(ParameterError):
        M.hausdorff_distance(np.zeros((2, 2)), np.zeros((2, 3)))


# ------------------------------------------------------------------------------ node-to-curve
@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("d", [2, 3])
def test_point_to_polyline_matches_brute_force(seed, d):
    rng = np.random.default_rng(seed)
    poly = random_walk(rng, int(rng.integers(1, 300)), d)
    # Mixed near and far points, plus a near-identical copy of the polyline.
    pts = np.vstack(
        [
            rng.normal(scale=5.0, size=(200, d)) + poly.mean(axis=0),
            poly + rng.normal(scale=0.05, size=poly.shape),
        ]
    )
    assert_allclose(
        M.point_to_polyline_distances(pts, poly), brute_point_to_polyline(pts, poly), atol=1e-12
    )


def _closest_case(rng: np.random.Generator, kind: int) -> tuple[np.ndarray, np.ndarray]:
    """A 2-D polyline large enough for the grid kernel and points near, far and on it."""
    m, n = int(rng.integers(40, 1500)), int(rng.integers(700, 2000))
    if kind == 0:  # a random walk (crossings, long and short segments)
        poly = random_walk(rng, m)
    elif kind == 1:  # a circle far from the origin (georeferenced metres)
        th = np.linspace(0.0, 2.0 * np.pi, m)
        poly = np.stack([np.cos(th), np.sin(th)], axis=1) * 10.0 + 5e5
    elif kind == 2:  # a flat line: a grid one cell high
        poly = np.stack([np.linspace(0.0, 100.0, m), np.zeros(m)], axis=1)
    else:  # nodes on a lattice, each three times (zero-length segments, many exact ties)
        poly = np.repeat(np.round(rng.normal(size=(m // 3 + 1, 2)) * 3.0) / 3.0, 3, axis=0)
    size = float(np.ptp(poly, axis=0).max()) + 1.0
    scale = (0.0, 0.01, 0.5, 3.0, 1e3, 1e12)[int(rng.integers(6))]
    pts = poly.mean(axis=0) + rng.normal(size=(n, 2)) * size * scale
    if kind == 3:
        pts = np.round(pts * 3.0) / 3.0
    pts = np.concatenate([pts, poly[:50], 0.5 * (poly[:-1] + poly[1:])[:50]])
    return np.ascontiguousarray(pts), np.ascontiguousarray(poly)


@pytest.mark.parametrize("seed", range(12))
def test_closest_on_polyline_grid_is_the_brute_force(seed):
    """The grid kernel gives every value of trying every segment, bit for bit (distance,
    segment, parameter; of equally close segments the first), on curves that stress it:
    crossings, far-off coordinates, a flat grid, repeated nodes with exact ties, points from
    on the curve to 1e12 away."""
    from ionic_usd.evaluate.polyline import _closest_brute, closest_on_polyline

    rng = np.random.default_rng(seed)
    pts, poly = _closest_case(rng, seed % 4)
    got = closest_on_polyline(pts, poly)
    want = _closest_brute(pts, poly)
    for g, w in zip(got, want, strict=True):
        np.testing.assert_array_equal(g, w)
    # and the brute force itself against the numpy one
    assert_allclose(got[0], brute_point_to_polyline(pts, poly), rtol=1e-12, atol=1e-12)


def test_closest_on_polyline_small_and_degenerate():
    """One node, two nodes, non-finite values: the every-segment path, numpy's values."""
    from ionic_usd.evaluate.polyline import closest_on_polyline

    pts = np.array([[1.0, 1.0], [3.0, 4.0]])
    d, s, t = closest_on_polyline(pts, np.array([[0.0, 0.0]]))
    assert_allclose(d, [math.sqrt(2.0), 5.0])
    d, s, t = closest_on_polyline(pts, np.array([[0.0, 0.0], [4.0, 0.0]]))
    assert_allclose(d, [1.0, 4.0])
    assert_allclose(t, [0.25, 0.75])
    d, _, _ = closest_on_polyline(np.array([[np.nan, 0.0]]), np.array([[0.0, 0.0], [1.0, 0.0]]))
    assert not np.isfinite(d[0])


def test_point_to_polyline_uneven_segments():
    # One very long segment among tiny ones: the index must still find its interior.
    poly = np.array([[0.0, 0.0], [0.01, 0.0], [0.02, 0.0], [100.0, 0.0], [100.01, 0.0]])
    pts = np.array([[50.0, 3.0], [0.015, -1.0], [99.0, 0.5], [-4.0, 3.0]])
    assert_allclose(M.point_to_polyline_distances(pts, poly), [3.0, 1.0, 0.5, 5.0])


def test_point_on_edge_vs_node_only():
    # A point above the middle of a long edge: 1 to the curve, sqrt(26) to its nodes.
    assert_allclose(
        M.point_to_polyline_distances(np.array([[5.0, 1.0]]), np.array([[0.0, 0.0], [10.0, 0]])),
        [1.0],
    )
    a = np.array([[0.0, 0.0], [10.0, 0.0]])
    b = np.array([[0.0, 1.0], [5.0, 1.0], [10.0, 1.0]])
    assert M.hausdorff_distance(a, b) == pytest.approx(1.0)
    assert M.node_hausdorff_distance(a, b) == pytest.approx(math.sqrt(26.0))


def test_parallel_segments_separation():
    a = np.array([[0.0, 0.0], [4.0, 0.0]])
    b = np.array([[0.0, 0.75], [4.0, 0.75]])
    for f in (
        M.hausdorff_distance,
        M.node_hausdorff_distance,
        M.discrete_frechet_distance,
        M.frechet_distance,
        M.average_error,
    ):
        assert f(a, b) == pytest.approx(0.75)


def test_identical_curves_are_at_zero():
    c = random_walk(np.random.default_rng(3), 50)
    result = M.compare(c, c)
    for name in CurveMeasures:
        assert getattr(result, name) == 0.0


CurveMeasures = ("hausdorff", "node_hausdorff", "average_error", "discrete_frechet", "frechet")


def test_reverse_curve_hausdorff_zero_frechet_positive():
    t = np.linspace(0.0, np.pi, 40)
    c = np.c_[np.cos(t), np.sin(t)]
    r = c[::-1]
    assert M.hausdorff_distance(c, r) == pytest.approx(0.0, abs=1e-12)
    assert M.node_hausdorff_distance(c, r) == pytest.approx(0.0, abs=1e-12)
    # Walking a half circle against its reverse: the endpoints are 2 apart at the start.
    assert M.frechet_distance(c, r) == pytest.approx(2.0)
    assert M.discrete_frechet_distance(c, r) == pytest.approx(2.0)


# ------------------------------------------------------------------------------ Hausdorff-type
@pytest.mark.parametrize("seed", range(5))
def test_hausdorff_and_average_vs_brute_force(seed):
    rng = np.random.default_rng(100 + seed)
    a = random_walk(rng, int(rng.integers(2, 200)))
    if seed % 2:
        b = random_walk(rng, int(rng.integers(2, 200)))
    else:
        b = a[::2] + rng.normal(scale=0.3, size=a[::2].shape)
        if b.shape[0] < 2:
            b = np.vstack([b, b + 1.0])
    da = brute_point_to_polyline(a, b)
    db = brute_point_to_polyline(b, a)
    assert M.directed_hausdorff_distance(a, b) == pytest.approx(da.max())
    assert M.hausdorff_distance(a, b) == pytest.approx(max(da.max(), db.max()))
    assert M.average_error(a, b) == pytest.approx(np.concatenate([da, db]).mean())
    nn = np.linalg.norm(a[:, None] - b[None], axis=-1)
    assert M.node_hausdorff_distance(a, b) == pytest.approx(
        max(nn.min(axis=1).max(), nn.min(axis=0).max())
    )
    assert M.paper_weak_frechet is M.hausdorff_distance


@pytest.mark.parametrize("seed", range(5))
def test_hausdorff_vs_geos(seed):
    rng = np.random.default_rng(200 + seed)
    a = random_walk(rng, int(rng.integers(2, 100)))
    b = random_walk(rng, int(rng.integers(2, 100)))
    la, lb = linestring(a), linestring(b)
    # GEOS' plain hausdorff is vertex-to-geometry (edges of the target included), i.e. the
    # paper's "weak Fréchet" exactly, not the node-to-node measure.
    assert M.hausdorff_distance(a, b) == pytest.approx(shapely.hausdorff_distance(la, lb))
    # GEOS on MultiPoints is the node-to-node measure (the paper's "Hausdorff").
    assert M.node_hausdorff_distance(a, b) == pytest.approx(
        shapely.hausdorff_distance(shapely.MultiPoint(a), shapely.MultiPoint(b))
    )
    # Densified, both converge to the continuous Hausdorff distance of the curves.
    for frac in (0.5, 0.1, 0.02):
        assert M.hausdorff_distance(a, b, densify=frac) == pytest.approx(
            shapely.hausdorff_distance(la, lb, densify=frac)
        )
    assert M.hausdorff_distance(a, b, densify=0.02) >= M.hausdorff_distance(a, b) - 1e-12


def test_densify_matches_brute_force_on_densified_curves():
    rng = np.random.default_rng(11)
    a, b = random_walk(rng, 30), random_walk(rng, 25)
    da, db = M.densify_curve(a, 0.1), M.densify_curve(b, 0.1)
    assert da.shape == (29 * 10 + 1, 2)
    assert_allclose(brute_point_to_polyline(da, a), 0.0, atol=1e-12)
    expected = max(brute_point_to_polyline(da, b).max(), brute_point_to_polyline(db, a).max())
    assert M.hausdorff_distance(a, b, densify=0.1) == pytest.approx(expected)


def test_directed_is_not_symmetric():
    a = np.array([[0.0, 0.0], [1.0, 0.0]])
    b = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 5.0]])
    assert M.directed_hausdorff_distance(a, b) == 0.0
    assert M.directed_hausdorff_distance(b, a) == pytest.approx(5.0)


# ------------------------------------------------------------------------------ Fréchet
@pytest.mark.parametrize("seed", range(8))
def test_discrete_frechet_vs_brute_force_and_geos(seed):
    rng = np.random.default_rng(300 + seed)
    d = 3 if seed % 2 else 2
    a = random_walk(rng, int(rng.integers(1, 60)), d)
    b = random_walk(rng, int(rng.integers(1, 60)), d)
    expected = brute_discrete_frechet(a, b)
    assert M.discrete_frechet_distance(a, b) == pytest.approx(expected)
    assert M.discrete_frechet_distance(b, a) == pytest.approx(expected)
    if d == 2 and a.shape[0] > 1 and b.shape[0] > 1:
        import similaritymeasures

        assert expected == pytest.approx(similaritymeasures.frechet_dist(a, b))
        # GEOS 3.14's DiscreteFrechetDistance sometimes returns a larger value than
        # Eiter-Mannila (e.g. seed 306: 20.11 vs 20.93; similaritymeasures agrees with the
        # brute force), so it is only an upper bound here.
        geos = shapely.frechet_distance(linestring(a), linestring(b))
        assert geos >= expected * (1 - 1e-12)


@pytest.mark.parametrize("seed", range(10))
def test_frechet_ordering_and_symmetry(seed):
    rng = np.random.default_rng(400 + seed)
    a = random_walk(rng, int(rng.integers(2, 80)))
    if seed % 2:
        b = a + rng.normal(scale=0.2, size=a.shape)
    else:
        b = random_walk(rng, int(rng.integers(2, 80)))
    haus = M.hausdorff_distance(a, b, densify=0.05)
    fr = M.frechet_distance(a, b, tol=1e-9)
    dfd = M.discrete_frechet_distance(a, b)
    assert haus <= fr * (1 + 1e-8)
    assert fr <= dfd * (1 + 1e-12)
    assert M.frechet_distance(b, a, tol=1e-9) == pytest.approx(fr, rel=1e-7)
    # Densifying both curves drives the discrete value down to the continuous one: with
    # pieces of length <= h the discrete coupling is within h of the continuous one.
    dense = M.discrete_frechet_distance(a, b, densify=0.01)
    h = 0.01 * max(np.linalg.norm(np.diff(c, axis=0), axis=1).max() for c in (a, b))
    assert fr <= dense * (1 + 1e-8)
    assert dense <= fr + h


def test_frechet_two_segments_known_value():
    # a: (0,0)->(2,0); b: (0,1)->(1,3)->(2,1). Continuous: the leash must reach b's apex
    # (1,3) from a at best (1,0): 3. Discrete (nodes only): apex vs nearest node: sqrt(10).
    a = np.array([[0.0, 0.0], [2.0, 0.0]])
    b = np.array([[0.0, 1.0], [1.0, 3.0], [2.0, 1.0]])
    assert M.frechet_distance(a, b, tol=1e-10) == pytest.approx(3.0, rel=1e-9)
    assert M.discrete_frechet_distance(a, b) == pytest.approx(math.sqrt(10.0))


def test_frechet_detects_backtracking():
    # b runs to x=3, back to x=1, then on to x=4: a monotone a must wait -> half the detour.
    a = np.array([[0.0, 0.0], [4.0, 0.0]])
    b = np.array([[0.0, 0.0], [3.0, 0.0], [1.0, 0.0], [4.0, 0.0]])
    assert M.hausdorff_distance(a, b) == 0.0
    assert M.frechet_distance(a, b, tol=1e-10) == pytest.approx(1.0, rel=1e-9)


def test_frechet_point_against_curve():
    p = np.array([[0.0, 0.0]])
    c = np.array([[1.0, 0.0], [0.0, 2.0], [-1.0, 0.0]])
    assert M.frechet_distance(p, c) == pytest.approx(2.0)
    assert M.discrete_frechet_distance(c, p) == pytest.approx(2.0)


def test_frechet_rejects_bad_tol():
    with pytest.raises(ParameterError):
        M.frechet_distance(np.zeros((2, 2)), np.ones((2, 2)), tol=0.0)


# ------------------------------------------------------------------------------ bundle
def test_compare_bundle_consistent_with_functions():
    rng = np.random.default_rng(7)
    t = np.linspace(0.0, 4.0, 120)
    a = np.c_[t, np.sin(t)]
    b = np.c_[t * 1.01, np.sin(t) * 0.97 + 0.01] + rng.normal(scale=1e-3, size=a.shape)
    r = M.compare(a, b)
    assert (r.nodes_a, r.nodes_b) == (120, 120)
    assert r.length_a == pytest.approx(M.curve_length(a))
    assert r.mean_length == pytest.approx(0.5 * (r.length_a + r.length_b))
    assert r.hausdorff == pytest.approx(M.hausdorff_distance(a, b))
    assert r.node_hausdorff == pytest.approx(M.node_hausdorff_distance(a, b))
    assert r.average_error == pytest.approx(M.average_error(a, b))
    assert r.discrete_frechet == pytest.approx(M.discrete_frechet_distance(a, b))
    assert r.frechet == pytest.approx(M.frechet_distance(a, b), rel=1e-6)
    assert r.hausdorff_pct == pytest.approx(100 * r.hausdorff / r.mean_length)
    d = json.loads(json.dumps(r.as_dict()))
    assert d["frechet_pct"] == pytest.approx(r.frechet_pct)
    assert r.node_hausdorff >= r.hausdorff >= r.average_error


def test_compare_with_spacing_resamples():
    a = np.array([[0.0, 0.0], [10.0, 0.0]])
    b = np.array([[0.0, 0.5], [10.0, 0.5]])
    r = M.compare(a, b, spacing=1.0)
    assert (r.nodes_a, r.nodes_b) == (11, 11)
    assert r.average_error == pytest.approx(0.5)


def test_comparison_validates():
    with pytest.raises(ParameterError):
        M.CurveComparison(2, 2, 1.0, 1.0, 1.0, -1.0, 0.0, 0.0, 0.0, 0.0)
    with pytest.raises(ParameterError):
        M.CurveComparison(2, 2, 1.0, 1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0).percent("bogus")
