"""Draw the default (Vitruvian) volute: outer edge, inner edge, band, eye → docs/volute.png.

Usage: ``python tools/plot_volute.py [output.png] [--samples N]``. Prints the volute's
proportions against Vitruvius' (height 8 parts of D/18, eye one part across).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from ionic_usd.column.volute import (  # noqa: E402
    VoluteParams,
    volute_band_outline,
    volute_extent,
    volute_eye,
)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument(
        "output", nargs="?", default=str(Path(__file__).parents[1] / "docs" / "volute.png")
    )
    ap.add_argument("--samples", type=int, default=600)
    ap.add_argument("--margin", type=float, default=0.12, help="canalis margin drawn (m)")
    args = ap.parse_args(argv)

    p = VoluteParams()
    outer, inner = volute_band_outline(p, args.samples, args.margin)
    eye = volute_eye(p, 96)
    ext = volute_extent(p)
    height = ext[1, 1] - ext[0, 1]
    d = 4 * p.capital_spiral_radius  # R = D/4 for the Vitruvian defaults
    print(
        f"volute height {height:.4f} m = {height / (d / 18):.3f} parts "
        f"(Vitruvius: 8); eye diameter / height = {2 * p.capital_circle_radius / height:.4f} "
        f"(Vitruvius: 1/8 = 0.125)"
    )

    fig, ax = plt.subplots(figsize=(6.4, 6.4), dpi=120)
    band = np.vstack([outer, inner[::-1]])
    ax.fill(band[:, 0], band[:, 1], color="#d9c8a0", label="band (listel)")
    ax.plot(outer[:, 0], outer[:, 1], color="#5a3d1a", lw=1.4, label="outer edge")
    ax.plot(inner[:, 0], inner[:, 1], color="#a0522d", lw=1.0, label="inner edge")
    ax.fill(eye[:, 0], eye[:, 1], color="#8b6b3d", label="eye")
    ax.plot(*np.vstack([eye, eye[:1]]).T, color="#5a3d1a", lw=1.0)
    ax.plot([0], [0], "k+", ms=8, label="spiral origin")
    ax.axhline(outer[:, 1].max(), color="0.6", lw=0.8, ls="--")
    ax.text(outer[:, 0].min(), outer[:, 1].max() + 0.004, "abacus", color="0.4", fontsize=8)
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_title(
        "Ionic volute, r(θ) = a/(b e^{cθ}) − d  (Vitruvian defaults, D = 0.95 m)", fontsize=9
    )
    ax.legend(loc="lower left", fontsize=7, frameon=False)
    out = Path(args.output)
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.tight_layout()
    fig.savefig(out)
    print(f"wrote {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
