"""Which numpy ufuncs give other bits when numpy's SIMD loops are switched off.

Run:  python tools/ufunc_bits.py

Evaluates each function (and the kernel's sums that are no ufunc call: einsum, add.reduce,
linalg.norm) on 200,000 seeded arguments in this process and in a child process
with every SIMD extension numpy found disabled (``NPY_DISABLE_CPU_FEATURES``), and prints, per
function, whether the two results are bit for bit equal. The functions that differ are the
ones ruff's banned-api rule (pyproject.toml, TID251) keeps out of the generators; use
``ionic_usd.geometry.libm`` instead. On a CPU without SIMD extensions beyond numpy's baseline
there is nothing to switch off and every row says "same".
"""

from __future__ import annotations

import hashlib
import json
import os
import subprocess
import sys

import numpy as np

FUNCS = (
    "sin cos tan arcsin arccos arctan arctan2 hypot sqrt exp exp2 expm1 log log2 log10 log1p "
    "sinh cosh tanh cbrt power"
).split()


def digests() -> dict[str, str]:
    rng = np.random.default_rng(0)
    x, y = rng.uniform(-3, 3, 200_000), rng.uniform(-3, 3, 200_000)
    u = rng.uniform(-1, 1, 200_000)
    out = {}
    for name in FUNCS:
        f = getattr(np, name)
        if name in ("hypot", "arctan2"):
            r = f(x, y)
        elif name == "power":
            r = f(np.abs(x), y)
        elif name in ("arcsin", "arccos"):
            r = f(u)
        elif name in ("log", "log2", "log10", "log1p", "sqrt"):
            r = f(np.abs(x))
        else:
            r = f(x)
        out[name] = hashlib.sha256(r.tobytes()).hexdigest()
    # the kernel's sums that are not ufunc calls: einsum's row dots and matrix products (its
    # kernels are compiled for numpy's baseline, the order of a sum set by the operands'
    # layout), the reductions behind norm and sum
    a, b = np.stack([x, y, u], 1), np.stack([y, u, x], 1)
    m = a[:3000].reshape(-1, 3, 3)
    for name, r in (
        ("einsum ij,ij->i", np.einsum("ij,ij->i", a, b)),
        ("einsum vj,njk->nvk", np.einsum("vj,njk->nvk", a[:500], m[:40])),
        ("einsum nij,cj->nci", np.einsum("nij,cj->nci", m, b[:8])),
        ("add.reduce axis 1", np.add.reduce(a * b, axis=1)),
        ("linalg.norm axis 1", np.linalg.norm(a, axis=1)),
    ):
        out[name] = hashlib.sha256(r.tobytes()).hexdigest()
    return out


def main() -> int:
    if len(sys.argv) > 1 and sys.argv[1] == "--child":
        print(json.dumps(digests()))
        return 0
    from numpy._core._multiarray_umath import (  # type: ignore[import-not-found]
        __cpu_dispatch__,
        __cpu_features__,
    )

    # the dispatch targets this CPU has (as tests/test_libm.py switches them off)
    found = [f for f in __cpu_dispatch__ if __cpu_features__.get(f)]
    env = dict(os.environ, NPY_DISABLE_CPU_FEATURES=" ".join(found))
    child = subprocess.run(
        [sys.executable, __file__, "--child"], env=env, capture_output=True, text=True, check=True
    )
    # numpy refuses to disable its baseline features and says so on stderr; the rest are off
    other = json.loads(child.stdout.strip().splitlines()[-1])
    here = digests()
    print(f"numpy {np.__version__}; SIMD switched off in the child: {' '.join(found)}")
    for name in here:
        print(f"{name:18s} {'same' if here[name] == other[name] else 'DIFFERS'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
