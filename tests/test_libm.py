"""What ionic_usd writes is the same on every CPU: ionic_usd.geometry.libm against the C
library and plain products; the column's and the asset's meshes and the stone maps built with
numpy's SIMD loops and OpenBLAS's kernels switched to other code paths, array for array; and
(slow) the whole temple, file for file."""

from __future__ import annotations

import hashlib
import json
import math
import os
import subprocess
import sys

import numpy as np
import pytest

from ionic_usd.geometry import libm

SPECIAL = [0.0, -0.0, 1.0, -1.0, 1e-300, -1e-300, 709.0, 710.0, -746.0, math.inf, -math.inf]


def _same_bits(a: np.ndarray, b: np.ndarray) -> bool:
    return a.shape == b.shape and a.dtype == b.dtype and a.tobytes() == b.tobytes()


def _rel(got: np.ndarray, want: np.ndarray) -> float:
    return float(np.max(np.abs(got - want) / np.maximum(np.abs(want), np.finfo(float).tiny)))


def test_exp_within_an_ulp_or_two_of_the_c_library():
    rng = np.random.default_rng(3)
    x = np.concatenate([rng.uniform(-700.0, 700.0, 20000), rng.normal(size=5000) * 1e-9])
    want = np.array([math.exp(v) for v in x])
    got = libm.exp(x)
    assert got.dtype == np.float64 and got.shape == x.shape
    assert _rel(got, want) < 4e-16  # 1.4 units in the last place at most
    # the ends of the range: subnormal results, overflow to inf, NaN kept, no warning
    with np.errstate(all="raise"):
        edge = libm.exp(np.array([709.78, 709.79, 1000.0, -745.0, -746.0, -math.inf, math.inf]))
    assert edge[0] == pytest.approx(math.exp(709.78), rel=4e-16)
    assert edge[1:3].tolist() == [math.inf] * 2 and edge[3] == math.exp(-745.0)  # 5e-324
    assert edge[4:6].tolist() == [0.0, 0.0] and edge[6] == math.inf
    assert math.isnan(libm.exp(math.nan)) and libm.exp(0.0) == 1.0
    # shapes: a scalar gives a 0-d value, a (2, 3) array a (2, 3) array
    assert libm.exp(0.5).shape == () and libm.exp(0.5) == pytest.approx(math.exp(0.5), rel=3e-16)
    assert libm.exp(np.ones((2, 3))).shape == (2, 3)
    # float32 stays float32 (its own single-precision polynomial)
    x32 = rng.uniform(-80.0, 80.0, 20000).astype(np.float32)
    g32 = libm.exp(x32)
    assert g32.dtype == np.float32
    assert _rel(g32.astype(np.float64), np.exp(x32.astype(np.float64))) < 2e-7
    assert libm.exp(np.float32([89.0, -104.0])).tolist() == [math.inf, 0.0]


def test_log_and_power_within_an_ulp_or_two_of_the_c_library():
    rng = np.random.default_rng(6)
    x = np.concatenate([10.0 ** rng.uniform(-300, 300, 20000), rng.uniform(0.5, 2.0, 5000)])
    want = np.array([math.log(v) for v in x])
    assert _rel(libm.log(x), want) < 3e-16
    assert libm.log(1.0) == 0.0 and libm.log(5e-324) == pytest.approx(math.log(5e-324), rel=3e-16)
    special = libm.log(np.array([0.0, -1.0, math.inf, -math.inf, math.nan]))
    assert special[0] == -math.inf and special[2] == math.inf
    assert np.isnan(special[[1, 3, 4]]).all()
    x32 = (10.0 ** rng.uniform(-30, 30, 20000)).astype(np.float32)
    g32 = libm.log(x32)
    assert g32.dtype == np.float32
    assert np.max(np.abs(g32 - np.log(x32.astype(np.float64)))) < 5e-6  # |log x| up to 69
    u = rng.uniform(0.0, 1.0, 20000)
    for p in (1.0 / 2.4, 2.4, -1.6):
        want = np.array([math.pow(v, p) for v in u])
        assert _rel(libm.power(u, p), want) < 3e-15, p
    assert libm.power(np.array([0.0, 1.0]), 1.0 / 2.4).tolist() == [0.0, 1.0]
    assert _rel(libm.power(u.astype(np.float32), 1 / 2.4), u ** (1 / 2.4)) < 1e-6


def test_arctan2_within_an_ulp_of_the_c_library_and_broadcasts():
    rng = np.random.default_rng(4)
    y = np.concatenate([rng.normal(size=20000), rng.normal(size=500) * 1e-30])
    x = np.concatenate([rng.normal(size=20000), rng.normal(size=500)])
    want = np.array([math.atan2(a, b) for a, b in zip(y, x, strict=True)])
    got = libm.arctan2(y, x)
    assert np.max(np.abs(got - want) / np.maximum(np.abs(want), 1.0)) < 4.5e-16
    # every pair of special values: the C library's angle, its sign included; exactly where
    # a zero or an infinity makes it a multiple of π/4 (each octant turns once: no double
    # rounding, so atan2(1, −0) is fl(π/2) as in C)
    for a in SPECIAL:
        for b in SPECIAL:
            g, w = float(libm.arctan2(a, b)), math.atan2(a, b)
            assert g == pytest.approx(w, rel=4.5e-16, abs=1e-300), (a, b)
            assert math.copysign(1.0, g) == math.copysign(1.0, w), (a, b)
            if a in (0.0, math.inf, -math.inf) or b in (0.0, math.inf, -math.inf):
                assert g == w, (a, b)
    # the left steep octant (|y| > |x|, x < 0) as often exact as the others
    left = (np.abs(y) > np.abs(x)) & (x < 0)
    assert np.mean(got[left] == want[left]) > 0.85
    assert libm.arctan2(0.0, -0.0) == math.pi and libm.arctan2(-0.0, -0.0) == -math.pi
    assert math.isnan(libm.arctan2(math.nan, 1.0)) and math.isnan(libm.arctan2(1.0, math.nan))
    grid = libm.arctan2(np.arange(3.0)[:, None], np.arange(1.0, 5.0)[None, :])
    assert grid.shape == (3, 4)
    assert np.allclose(grid, np.arctan2(np.arange(3.0)[:, None], np.arange(1.0, 5.0)[None, :]))


def test_the_functions_call_none_of_numpys_transcendental_loops():
    """What makes them CPU-independent: numpy's exp, log, power and arctan2 (the loops that
    differ between CPUs) raise here, and the functions still run. (It does not see ``**``
    or ``math``; the code-path test below compares the results themselves.)"""
    import unittest.mock as mock

    boom = mock.Mock(side_effect=AssertionError("a numpy transcendental was called"))
    with (
        mock.patch.object(libm.np, "exp", boom),
        mock.patch.object(libm.np, "log", boom),
        mock.patch.object(libm.np, "power", boom),
        mock.patch.object(libm.np, "arctan2", boom),
    ):
        libm.exp(np.linspace(-800.0, 800.0, 101))
        libm.log(np.linspace(0.0, 10.0, 101))
        libm.power(np.linspace(0.0, 1.0, 11), 0.4)
        libm.arctan2(np.linspace(-1.0, 1.0, 11), np.linspace(1.0, -1.0, 11))
        libm.exp(np.linspace(-90.0, 90.0, 11, dtype=np.float32))


# Every array: the Portunus column at every LOD and every mesh of the default asset (3 LODs,
# every base and flute count, both volute models, both scrolls, normal and angle capitals,
# the engaged and corner cuts) with its normals, and the stone maps.
_HASHES = """
import hashlib, json, sys
import numpy as np
from ionic_usd.column.column import build_column, portunus_column_params
from ionic_usd.pipeline.asset import ColumnAssetOptions, column_asset_meshes

FIELDS = ("points", "face_vertex_indices", "normals", "st")
out = {}
def put(name, mesh):
    for f in FIELDS:
        a = getattr(mesh, f, None)
        arrays = {f: a} if a is None or isinstance(a, np.ndarray) else {
            f: a.values, f"{f}_indices": a.indices}
        for k, v in arrays.items():
            if v is not None:
                out[f"{name}/{k}"] = hashlib.sha256(np.ascontiguousarray(v).tobytes()).hexdigest()
for lod in ("high", "medium", "low"):
    for part, mesh in build_column(portunus_column_params(lod=lod)).parts().items():
        put(f"column_{lod}/{part}", mesh)
for am in column_asset_meshes(ColumnAssetOptions(), workers=1):
    put(am.name, am.mesh)
from ionic_usd.texture.stone import generate_stone_maps
for style in ("travertine", "stucco_painted"):
    maps = generate_stone_maps(style, 256, 7)
    for f in ("base_color", "roughness", "normal", "height"):
        out[f"{style}/{f}"] = hashlib.sha256(getattr(maps, f).tobytes()).hexdigest()
json.dump(out, sys.stdout)
"""


def _other_code_paths() -> dict[str, str]:
    """Environment that sends numpy and OpenBLAS down other code paths on this CPU: every
    SIMD extension numpy dispatches to and this CPU has switched off (its transcendental
    loops and its sort, whose ties come out in another order), and on x86-64 OpenBLAS's
    Nehalem kernels (SSE only, no fused multiply-add; numpy's own baseline needs no more)."""
    import platform

    from numpy._core._multiarray_umath import __cpu_dispatch__, __cpu_features__

    env: dict[str, str] = {}
    found = [f for f in __cpu_dispatch__ if __cpu_features__.get(f)]
    if found:
        env["NPY_DISABLE_CPU_FEATURES"] = " ".join(found)
    if platform.machine().lower() in ("x86_64", "amd64") and __cpu_features__.get("AVX2"):
        env["OPENBLAS_CORETYPE"] = "Nehalem"
    return env


def _hashes(extra: dict[str, str], tmp_path) -> dict[str, str]:
    env = {**os.environ, **extra, "IONIC_USD_CACHE": str(tmp_path / "cache")}
    r = subprocess.run(
        [sys.executable, "-c", _HASHES], env=env, capture_output=True, text=True, timeout=600
    )
    assert r.returncode == 0, r.stderr[-3000:]
    return json.loads(r.stdout)


def test_the_geometry_is_the_same_on_other_cpu_code_paths(tmp_path):
    other = _other_code_paths()
    if not other:
        pytest.skip("this CPU has no SIMD extension numpy dispatches to: one code path only")
    here = _hashes({}, tmp_path)
    there = _hashes(other, tmp_path)
    assert len(here) > 500 and here.keys() == there.keys()
    differ = sorted(k for k in here if here[k] != there[k])
    assert not differ, f"{len(differ)} arrays differ with {other}: {differ[:8]}"


@pytest.mark.slow
def test_the_temple_is_the_same_bytes_on_other_cpu_code_paths(tmp_path):
    """The default temple, every one of its files (layers, crate geometry, PNG maps,
    manifests), built twice in fresh processes with empty caches: here, and with numpy's SIMD
    loops off and OpenBLAS on its Nehalem kernels."""
    other = _other_code_paths()
    if not other:
        pytest.skip("this CPU has no SIMD extension numpy dispatches to: one code path only")
    digests = []
    for k, extra in enumerate(({}, other)):
        out, cache = tmp_path / f"T{k}", tmp_path / f"cache{k}"
        env = {**os.environ, **extra, "IONIC_USD_CACHE": str(cache)}
        r = subprocess.run(
            [sys.executable, "-m", "ionic_usd", "temple", "-o", str(out), "-q"],
            env=env,
            capture_output=True,
            text=True,
            timeout=900,
            cwd=tmp_path,
        )
        assert r.returncode == 0, r.stderr[-3000:]
        digests.append(
            {
                str(f.relative_to(out)): hashlib.sha256(f.read_bytes()).hexdigest()
                for f in sorted(out.rglob("*"))
                if f.is_file()
            }
        )
    here, there = digests
    assert len(here) >= 30 and here.keys() == there.keys()
    differ = sorted(k for k in here if here[k] != there[k])
    assert not differ, f"{len(differ)} files differ with {other}: {differ}"


def test_linear_and_dot_are_numpys_products_summed_in_order():
    rng = np.random.default_rng(5)
    p = rng.normal(size=(1000, 3))
    m = rng.normal(size=(3, 3))
    got = libm.linear(p, m)
    want = p[:, :1] * m[:, 0] + p[:, 1:2] * m[:, 1] + p[:, 2:3] * m[:, 2]  # the stated order
    assert _same_bits(got, want)
    assert np.allclose(got, p @ m.T, rtol=0, atol=1e-14)
    assert _same_bits(libm.dot(p, m[0]), want[:, 0])
    # dtypes follow numpy's product: float32 with float32, float64 otherwise
    assert libm.linear(p.astype(np.float32), m.astype(np.float32)).dtype == np.float32
    assert libm.linear(p.astype(np.float32), m).dtype == np.float64
    assert libm.linear(p[:, :2], m[:2, :2]).shape == (1000, 2)


def test_flat_slope_literal_is_tan_of_its_angle():
    # charts.py keeps tan(FLAT_SLOPE_DEG) as a literal (numpy's tan is CPU-dependent)
    from ionic_usd.column import charts

    exact = math.tan(math.radians(charts.FLAT_SLOPE_DEG))
    assert abs(charts._FLAT_SLOPE - exact) <= math.ulp(exact)


def test_sliver_order_by_cosine_matches_angles():
    # the clean-up picks and orders its slivers by the largest corner cosine: the same triangles
    # as the smallest angle under the threshold, in the same order
    from ionic_usd.geometry.slivers import _tri_angles, _tri_cosines

    rng = np.random.default_rng(5)
    p = rng.normal(size=(4000, 3, 3))
    p[:2000, 2] = p[:2000, 0] + 1e-3 * rng.normal(size=(2000, 3))  # needles
    worst_angle = _tri_angles(p).min(axis=1)
    worst_cos = _tri_cosines(p).max(axis=1)
    low = worst_angle < 1.0
    assert low.sum() > 100
    cand = worst_cos > math.cos(math.radians(1.0)) - 1e-12
    assert np.all(cand[low])  # every triangle under the angle is a candidate
    order_a = np.argsort(worst_angle[low], kind="stable")
    order_c = np.argsort(-worst_cos[low], kind="stable")
    assert np.array_equal(order_a, order_c)
