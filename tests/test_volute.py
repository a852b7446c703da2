"""Tests for the Ionic volute: the paper's spiral (formula 3, Table 4) and the volute solid."""

from __future__ import annotations

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose

from ionic_usd.column.volute import (
    VoluteParams,
    spiral_limit,
    vitruvian_coefficients,
    vitruvian_volute,
    volute_curve,
    volute_extent,
    volute_eye,
    volute_inner_curve,
    volute_theta,
    volute_thickness,
    volute_total_radius,
)
from ionic_usd.column.volute_solid import (
    build_volute,
    build_volute_backing,
    build_volute_band,
    build_volute_eye,
)
from ionic_usd.errors import GeometryError, IonicError, ParameterError
from ionic_usd.geometry.analysis import inspect_mesh
from ionic_usd.geometry.mesh import face_normals, transform

D = 0.95
PART = D / 18


def closed_form(p: VoluteParams, th: np.ndarray) -> np.ndarray:
    """Paper formula 3 written out independently."""
    rr = p.a / (p.b * np.exp(p.c * th)) - p.d
    return np.stack(
        [p.capital_spiral_radius * rr * np.cos(th), p.capital_spiral_radius * rr * np.sin(th)],
        axis=1,
    )


# an inward-winding set (c > 0): the same spiral read backwards
INWARD = dict(
    start_angle=90.0,
    spiral_circuits=3,
    a=2.0,
    b=1.0,
    c=0.1,
    d=0.0,
    thickness=0.05,
    min_thickness=0.05,
    increasing_max=0.0,
)


@pytest.mark.parametrize(
    "params",
    [
        VoluteParams(),
        VoluteParams(**INWARD),
        VoluteParams(
            a=-3.0, b=-2.0, c=-0.05, d=0.5, thickness=0.1, min_thickness=0.1, offset_x=0.01
        ),
    ],
)
@pytest.mark.parametrize("samples", [2, 17, 192])
def test_curve_matches_closed_form(params, samples):
    th = volute_theta(params, samples)
    assert_allclose(volute_curve(params, samples), closed_form(params, th), rtol=0, atol=1e-12)
    assert th[0] == pytest.approx(math.radians(params.start_angle))


@pytest.mark.parametrize("n", [1, 2, 3, 4, 5.5])
def test_circuit_limit(n):
    p = VoluteParams(
        spiral_circuits=n,
        start_angle=90.0 if n >= 3 else 400.0 - 360 * (n < 2),
        min_thickness=0.01,
        thickness=0.02,
    )
    want = 2.5 * math.pi + 2 * math.pi * (n - 1)
    assert spiral_limit(n) == pytest.approx(want)
    assert volute_theta(p, 50)[-1] == pytest.approx(want)
    # the curve ends straight above the origin (θ ≡ π/2) for whole circuits
    if float(n).is_integer():
        end = volute_curve(p, 50)[-1]
        assert end[0] == pytest.approx(0.0, abs=1e-12) and end[1] > 0


def test_thickness_growth():
    p = VoluteParams(start_angle=90, min_thickness=0.02, thickness=0.1, increasing_max=540)
    t0, t_max = math.radians(90), math.radians(540)
    assert volute_thickness(p, t0) == pytest.approx(0.02)
    assert volute_thickness(p, t_max) == pytest.approx(0.1)
    assert volute_thickness(p, 0.5 * (t0 + t_max)) == pytest.approx(0.06)  # linear
    after = np.linspace(t_max, p.theta_end, 7)
    assert_allclose(volute_thickness(p, after), 0.1)
    # increasing_max at or before the start: constant thickness
    q = VoluteParams(min_thickness=0.02, thickness=0.1, increasing_max=0)
    assert_allclose(volute_thickness(q, volute_theta(q, 9)), 0.1)


@pytest.mark.parametrize("params", [VoluteParams(), VoluteParams(**INWARD)])
def test_inner_curve_is_radius_minus_thickness(params):
    th = volute_theta(params, 101)
    outer, inner = volute_curve(params, 101), volute_inner_curve(params, 101)
    R = params.capital_spiral_radius
    r_out = np.linalg.norm(outer, axis=1)
    r_in = np.linalg.norm(inner, axis=1)
    assert_allclose(r_out - r_in, R * volute_thickness(params, th), atol=1e-12)
    # same direction from the origin
    assert_allclose(
        np.arctan2(inner[:, 1], inner[:, 0]), np.arctan2(outer[:, 1], outer[:, 0]), atol=1e-9
    )


def test_eye_circle():
    p = VoluteParams(offset_x=0.01, offset_y=-0.02)
    eye = volute_eye(p, 40)
    assert_allclose(eye.mean(axis=0), [0.01, -0.02], atol=1e-12)
    assert_allclose(np.linalg.norm(eye - [0.01, -0.02], axis=1), p.capital_circle_radius)


def test_vitruvian_defaults():
    """Vitruvius III.5: volute 8 parts of D/18 high, the eye 4½ parts below its top, eye
    diameter one part (1/8 of the height), three circuits, thinning toward the eye."""
    p = VoluteParams()
    ext = volute_extent(p, 4096)
    assert ext[1, 1] == pytest.approx(4.5 * PART, rel=1e-9)
    # the lowest point lies half a turn before the top (θ = 5.5π: r = 7/9 exactly)
    assert closed_form(p, np.array([5.5 * math.pi]))[0, 1] == pytest.approx(-3.5 * PART)
    assert ext[0, 1] == pytest.approx(-3.5 * PART, rel=5e-3)
    height = ext[1, 1] - ext[0, 1]
    assert 2 * p.capital_circle_radius / height == pytest.approx(1 / 8, rel=3e-3)
    assert height / D == pytest.approx(4 / 9, rel=3e-3)  # ≈ half the lower diameter
    assert p.spiral_circuits == 3
    a, b, c, d = vitruvian_coefficients()
    assert c < 0  # r grows with θ: from the eye outward
    th = volute_theta(p, 500)
    r = np.linalg.norm(volute_curve(p, 500), axis=1)
    assert np.all(np.diff(r) > 0)
    assert r[0] == pytest.approx(p.capital_circle_radius)  # the band leaves the eye's rim
    assert volute_total_radius(p) == pytest.approx(p.capital_spiral_radius)
    assert vitruvian_volute(D) == p
    assert vitruvian_volute(2 * D).capital_spiral_radius == pytest.approx(2 * D / 4)
    assert th[-1] == pytest.approx(6.5 * math.pi)


def _brute_force_band_overlap(p: VoluteParams, samples=1500) -> bool:
    """Independent check: does any band polygon point fall inside another turn's band?"""
    from shapely.geometry import Polygon

    outer, inner = volute_curve(p, samples), volute_inner_curve(p, samples)
    # split the band into quarter-turn pieces; non-adjacent pieces must not overlap
    th = volute_theta(p, samples)
    step = int(np.ceil(samples * (math.pi / 2) / (th[-1] - th[0])))
    pieces = []
    for s in range(0, samples - 1, step):
        e = min(s + step + 1, samples)
        pieces.append(Polygon(np.vstack([outer[s:e], inner[s:e][::-1]])))
    for i in range(len(pieces)):
        for j in range(i + 2, len(pieces)):
            if pieces[i].intersection(pieces[j]).area > 1e-12:
                return True
    return False


def test_self_intersection_refused():
    # a band growing faster than the gap between turns: its inner edge at 4.5π
    # (0.592 − 0.333) dips below the previous turn's outer edge (0.309)
    bad = dict(min_thickness=0.1, thickness=0.45, increasing_max=1170.0)
    with pytest.raises(GeometryError, match="crosses itself") as exc:
        VoluteParams(**bad)
    assert "thickness" in str(exc.value)
    # a brute-force polygon-overlap check agrees with the validator on both sets
    assert not _brute_force_band_overlap(VoluteParams())
    unchecked = object.__new__(VoluteParams)  # bypass __post_init__ to draw the bad band
    for k, v in dict(VoluteParams().__dict__, **bad).items():
        object.__setattr__(unchecked, k, v)
    assert _brute_force_band_overlap(unchecked)


@pytest.mark.parametrize(
    "kwargs, name",
    [
        (dict(b=0.0), "b"),
        (dict(a=float("nan")), "a"),
        (dict(spiral_circuits=0.5), "spiral_circuits"),
        (dict(capital_spiral_radius=0.0), "capital_spiral_radius"),
        (dict(capital_circle_radius=-1.0), "capital_circle_radius"),
        (dict(thickness=0.0), "thickness"),
        (dict(min_thickness=0.2, thickness=0.1), "min_thickness"),
        (dict(start_angle=1170.0), "start_angle"),
        (dict(d=0.5), "a, b, c, d"),  # radius goes negative near the eye
        (dict(min_thickness=0.12, increasing_max=0), "thickness/min_thickness"),
        (dict(thickness="1"), "thickness"),
    ],
)
def test_parameter_errors_name_the_parameter(kwargs, name):
    with pytest.raises(ParameterError) as exc:
        VoluteParams(**kwargs)
    assert exc.value.name == name


def test_constant_radius_refused():
    with pytest.raises(GeometryError, match="monoton"):
        VoluteParams(c=0.0, a=1.0, d=0.0, min_thickness=0.05, thickness=0.05)


def _shell_ok(m, expected_volume=None, rel=None):
    r = inspect_mesh(m)
    assert r.closed and r.consistent, r
    assert r.signed_volume > 0 and r.degenerate_faces == 0 and r.duplicate_faces == 0, r
    if expected_volume is not None:
        assert r.signed_volume == pytest.approx(expected_volume, rel=rel)
    # corner normals agree with the faces they belong to
    fn, _ = face_normals(m.points, m.triangles)
    cn = m.corner_normals().reshape(-1, 3, 3)
    assert np.all(np.einsum("ij,ikj->ik", fn, cn) > 0.2)
    return r


@pytest.mark.parametrize(
    "params",
    [
        VoluteParams(),
        VoluteParams(**INWARD),
        VoluteParams(spiral_circuits=1, start_angle=200, min_thickness=0.05),
    ],
)
def test_volute_shells_are_watertight(params):
    relief, slab = 0.015, 0.03
    R = params.capital_spiral_radius
    band = build_volute_band(params, samples=400, z0=-relief, z1=0.0)
    # band area in polar form: ∫ ½ R² (r² − (r − t)²) dθ (exact), × depth
    th = np.linspace(params.theta_start, params.theta_end, 20001)
    r = params.a / (params.b * np.exp(params.c * th)) - params.d
    t = volute_thickness(params, th)
    area = np.trapezoid(0.5 * R * R * (r**2 - (r - t) ** 2), th)
    _shell_ok(band, area * relief, rel=2e-3)
    _shell_ok(build_volute_backing(params, samples=400, z0=-relief - slab, z1=-relief))
    eye = build_volute_eye(params, segments=64, z0=-relief, z1=0.0)
    rr = params.capital_circle_radius
    _shell_ok(eye, 0.5 * 64 * math.sin(2 * math.pi / 64) * rr * rr * relief, rel=1e-9)


def test_volute_solid_and_mirror():
    p = VoluteParams()
    v = build_volute(p, margin=0.2)
    r = _shell_ok(v)
    assert r.n_triangles == v.n_triangles
    ext = v.extent
    assert_allclose(ext[1, 2], 0.0, atol=1e-12)
    assert_allclose(ext[0, 2], -0.045, atol=1e-12)
    assert ext[0, 0] == pytest.approx(-0.2, abs=1e-9)  # the margin runs 0.2 m towards −X
    mirrored = transform(v, np.diag([-1.0, 1, 1, 1]))
    rm = _shell_ok(mirrored)
    assert rm.signed_volume == pytest.approx(r.signed_volume)


def test_errors_are_package_errors():
    with pytest.raises(IonicError):
        build_volute(VoluteParams(), relief_depth=0.0)
    with pytest.raises(ParameterError):
        volute_theta(VoluteParams(), 1)


# -- centred arcs ----------------------------------------------------------------------------------
ARCS = VoluteParams(volute_model="centred_arcs")


def test_centred_arcs_are_quarter_circles_joined_tangentially():
    from ionic_usd.column.volute_arcs import arc_centres

    centres, radii, th0 = arc_centres(ARCS)
    assert len(radii) == 12 and np.all(np.diff(radii) > 0)  # 3 turns, growing outward
    assert radii[0] == pytest.approx(ARCS.capital_circle_radius)
    assert_allclose(centres.mean(axis=0), ARCS.eye_center, atol=1e-12)
    # every node of arc j lies on its circle; consecutive arcs share their junction point and
    # its tangent (the junction is on the line through both centres)
    for j in range(11):
        t = th0[j + 1]
        u = np.array([math.cos(t), math.sin(t)])
        assert_allclose(centres[j] + radii[j] * u, centres[j + 1] + radii[j + 1] * u, atol=1e-12)
    curve = volute_curve(ARCS, 12 * 64 + 1)
    th = np.linspace(ARCS.theta_start, ARCS.theta_end, len(curve))
    j = np.minimum(((th - ARCS.theta_start) // (math.pi / 2)).astype(int), 11)
    assert_allclose(np.linalg.norm(curve - centres[j], axis=1), radii[j], atol=1e-12)


def test_centred_arcs_shells_watertight_and_in_a_column(tmp_path):
    import dataclasses
    import tomllib

    from ionic_usd.column.column import (
        build_column,
        column_params_from_mapping,
        column_params_to_tables,
        portunus_column_params,
    )
    from ionic_usd.params import to_toml

    _shell_ok(build_volute(ARCS))
    p = portunus_column_params()
    col = dataclasses.replace(p, capital=p.capital.with_(volute=ARCS))
    built = build_column(col)
    assert np.all(np.isfinite(built.capital_body.points))
    text = to_toml(column_params_to_tables(col))
    back = column_params_from_mapping(tomllib.loads(text))
    assert back.capital.volute == ARCS


def test_centred_arcs_errors():
    with pytest.raises(ParameterError, match="volute_model"):
        VoluteParams(volute_model="spiral")
    with pytest.raises(ParameterError, match="arc_square"):
        VoluteParams(volute_model="centred_arcs", arc_square=0.0)
    with pytest.raises(GeometryError, match="crosses itself"):
        VoluteParams(volute_model="centred_arcs", thickness=0.5, min_thickness=0.5)
