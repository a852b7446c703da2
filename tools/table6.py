"""Table-6-style figures for the fits: before/after measures and fit times.

References are curves the project generates itself with known parameters (noise-free, and
with Gaussian noise of sigma = 0.5 mm on the volute), started from the Portunus defaults or
another preset. Also checks USD-cut sections against the API ones.

    python tools/table6.py
"""

from __future__ import annotations

import dataclasses
import tempfile
import time
from pathlib import Path

import numpy as np

from ionic_usd.column.column import build_column, portunus_column_params
from ionic_usd.column.volute import VoluteParams, volute_curve
from ionic_usd.evaluate import (
    base_section,
    fit_base,
    fit_shaft,
    fit_volute,
    hausdorff_distance,
    resample,
    section_from_usd,
    shaft_silhouette_section,
    volute_section,
)


def main() -> None:
    p = portunus_column_params()
    with tempfile.TemporaryDirectory() as tmp:
        from ionic_usd.usd import write_meshes

        usd = Path(tmp) / "column.usda"
        write_meshes(usd, build_column(p).parts(), root="Column")
        print("USD-cut sections vs API sections (Portunus, high LOD):")
        for part, api in (
            ("base", base_section(p)),
            ("shaft", shaft_silhouette_section(p)),
            ("volute", volute_section(p)),
        ):
            t0 = time.perf_counter()
            cut = section_from_usd(usd, part)
            dt = time.perf_counter() - t0
            print(
                f"  {part:7s} Hausdorff {hausdorff_distance(api, cut):.2e} m, "
                f"{len(cut)} nodes, cut in {dt * 1e3:.0f} ms"
            )

    v0 = VoluteParams()
    true_v = v0.with_(
        capital_spiral_radius=0.26,
        c=v0.c * 1.1,
        d=v0.d * 0.97,
        start_angle=100.0,
        spiral_circuits=2.9,
    )
    rng = np.random.default_rng(3)
    clean = volute_curve(true_v, 400)
    shaft_true = dataclasses.replace(
        p,
        shaft=dataclasses.replace(
            p.shaft, bottom_radius=0.5, top_radius=0.42, height=6.5, entasis=0.02
        ),
    )
    cases = [
        ("volute", "perturbed, noise-free", lambda: fit_volute(clean, initial=v0)),
        (
            "volute",
            "perturbed, sigma 0.5 mm",
            lambda: fit_volute(clean + rng.normal(0, 5e-4, clean.shape), initial=v0),
        ),
        (
            "base",
            "attic_bezier from G1",
            lambda: fit_base(
                resample(base_section(dataclasses.replace(p, base="attic_bezier")), count=300),
                initial=dataclasses.replace(p, base="G1"),
            ),
        ),
        (
            "base",
            "G2 (tori) from G1",
            lambda: fit_base(
                resample(base_section(dataclasses.replace(p, base="G2")), count=300),
                initial=dataclasses.replace(p, base="G1"),
            ),
        ),
        (
            "shaft",
            "r 0.5/0.42, entasis 0.02",
            lambda: fit_shaft(shaft_silhouette_section(shaft_true)),
        ),
    ]
    print("\nfits (weak Fréchet* = node-to-curve Hausdorff; % of the mean curve length):")
    print(
        f"  {'part':7s} {'reference':26s} {'time':>7s} {'evals':>6s} "
        f"{'weak Fréchet before':>20s} {'after':>10s} {'avg err after':>14s}"
    )
    for part, name, run in cases:
        res = run()
        print(
            f"  {part:7s} {name:26s} {res.seconds:6.2f}s {res.evaluations:6d} "
            f"{res.before.hausdorff_pct:19.3f}% {res.after.hausdorff_pct:9.4f}% "
            f"{res.after.average_error_pct:13.4f}%"
        )


if __name__ == "__main__":
    main()
