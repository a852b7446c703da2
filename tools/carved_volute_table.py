"""Table: carved (jittered twelve-centre) volutes fitted by every model, chosen by BIC.

The drawings come from the tests' generator (tests/volute_jitter.py: radii and centres off by
up to 1.5 %, arcs re-joined tangentially, 0.3 mm digitising noise). Prints a Markdown table of
the centred-arc fit and the chosen fit (Hausdorff and discrete Fréchet, % of the curve's
length, as ``fit volute`` reports them) and each model's BIC.
Run: ``python tools/carved_volute_table.py [--diameters 0.6,1.2] [--seeds 0,1,2,4]``.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))

from volute_jitter import carved_volute  # noqa: E402

from ionic_usd.evaluate.fit import fit_volute  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--diameters", default="0.6,1.2")
    ap.add_argument("--seeds", default="0,1,2,4")
    ap.add_argument("--noise", type=float, default=3e-4, help="digitising noise, m")
    args = ap.parse_args()
    print(
        "| D (m) | carving | centred arcs H % / F % | chosen | chosen H % / F % "
        "| BIC log spiral | BIC centred | BIC free arcs | BIC free joints |"
    )
    print("|---|---|---|---|---|---|---|---|---|")
    for d in (float(x) for x in args.diameters.split(",")):
        for seed in (int(x) for x in args.seeds.split(",")):
            res = fit_volute(carved_volute(d, seed=seed, noise=args.noise))
            by = {r.model: r for r in (res, *res.alternatives)}
            c = by["centred_arcs"].after
            bic = {m: f"{r.criterion['bic']:.0f}" for m, r in by.items()}
            print(
                f"| {d:g} | {seed} | {c.hausdorff_pct:.3f} / {c.discrete_frechet_pct:.3f} "
                f"| {res.model} | {res.after.hausdorff_pct:.3f} / "
                f"{res.after.discrete_frechet_pct:.3f} | {bic['log_spiral']} "
                f"| {bic['centred_arcs']} | {bic['free_arcs']} | {bic['free_joints']} |",
                flush=True,
            )


if __name__ == "__main__":
    main()
