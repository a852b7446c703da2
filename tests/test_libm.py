"""The generated geometry is the same on every CPU: ionic_usd.geometry.libm against the C
library and plain products, and the column and the asset's meshes built with numpy's SIMD
loops and OpenBLAS's kernels switched to other code paths, array for array."""

from __future__ import annotations

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


def test_exp_is_the_c_librarys_value_by_value():
    rng = np.random.default_rng(3)
    x = np.concatenate([rng.uniform(-30.0, 30.0, 5000), SPECIAL, [math.nan]])
    want = np.array([math.inf if v > 709.782712893384 else math.exp(v) for v in x])
    got = libm.exp(x)
    assert got.dtype == np.float64 and got.shape == x.shape
    assert _same_bits(got[:-1], want[:-1]) and math.isnan(got[-1])
    # overflow gives inf as numpy's exp does, neither an exception nor a floating-point flag
    with np.errstate(all="raise"):
        assert libm.exp(709.78) < math.inf and libm.exp([709.79, 1000.0]).tolist() == [math.inf] * 2
    # shapes: a scalar gives a 0-d array, a (2, 3) array a (2, 3) array
    assert libm.exp(0.5).shape == () and libm.exp(0.5) == math.exp(0.5)
    assert libm.exp(np.ones((2, 3), np.float32)).shape == (2, 3)


def test_arctan2_is_the_c_librarys_value_by_value_and_broadcasts():
    rng = np.random.default_rng(4)
    y = np.concatenate([rng.normal(size=4000), SPECIAL])
    x = np.concatenate([rng.normal(size=4000), SPECIAL[::-1]])
    want = np.array([math.atan2(a, b) for a, b in zip(y, x, strict=True)])
    assert _same_bits(libm.arctan2(y, x), want)
    # signed zeros as numpy's: atan2(+0, -0) = pi, atan2(-0, -0) = -pi
    assert libm.arctan2(0.0, -0.0) == math.pi and libm.arctan2(-0.0, -0.0) == -math.pi
    assert np.array_equal(libm.arctan2(np.zeros(3), -1.0), np.full(3, math.pi))
    grid = libm.arctan2(np.arange(3.0)[:, None], np.arange(1.0, 5.0)[None, :])
    assert grid.shape == (3, 4)
    assert np.allclose(grid, np.arctan2(np.arange(3.0)[:, None], np.arange(1.0, 5.0)[None, :]))


# Every array but the normals (their angle weights stay on numpy's loops; see libm): the
# Portunus column at every LOD and every mesh of the default asset (3 LODs, every base and
# flute count, both volute models, both scrolls, normal and angle capitals, the engaged and
# corner cuts): 564 arrays.
_HASHES = """
import hashlib, json, sys
import numpy as np
from ionic_usd.column.column import build_column, portunus_column_params
from ionic_usd.pipeline.asset import ColumnAssetOptions, column_asset_meshes

FIELDS = ("points", "face_vertex_indices", "st", "st_indices", "normals_indices")
out = {}
def put(name, mesh):
    for f in FIELDS:
        a = getattr(mesh, f, None)
        if a is not None:
            out[f"{name}/{f}"] = hashlib.sha256(np.ascontiguousarray(a).tobytes()).hexdigest()
for lod in ("high", "medium", "low"):
    for part, mesh in build_column(portunus_column_params(lod=lod)).parts().items():
        put(f"column_{lod}/{part}", mesh)
for am in column_asset_meshes(ColumnAssetOptions(), workers=1):
    put(am.name, am.mesh)
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
