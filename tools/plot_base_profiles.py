"""Draw the half-profiles of the base presets G1, G2 and attic_bezier into docs/base_profiles.png.

Usage: python tools/plot_base_profiles.py [output.png]
"""

from __future__ import annotations

import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from ionic_usd.column.base import base_profile, load_base_preset  # noqa: E402
from ionic_usd.column.column import portunus_column_params  # noqa: E402

PRESETS = ("G1", "G2", "attic_bezier", "attic_bezier_plinth")


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    out = Path(argv[0]) if argv else Path(__file__).resolve().parents[1] / "docs/base_profiles.png"
    fig, axes = plt.subplots(1, len(PRESETS), figsize=(4 * len(PRESETS), 4.6), sharey=True)
    for ax, name in zip(axes, PRESETS, strict=True):
        own = load_base_preset(name, profile_slices=16).height  # the grammar's own height
        p = portunus_column_params(base=name).base_params()  # as the column builds it
        outline = base_profile(p, closed=True)
        curve = base_profile(p)
        ax.fill(outline[:, 0], outline[:, 1], color="0.88", zorder=0)
        ax.plot(curve[:, 0], curve[:, 1], "-", color="tab:red", lw=1.6, label="outside curve")
        ax.plot(curve[:, 0], curve[:, 1], ".", color="k", ms=2.5, label="rows")
        d = p.shaft_radius
        ax.axvline(d, color="tab:blue", lw=0.8, ls="--", label="shaft radius d")
        ax.set_title(
            f"{name} (v{p.parsed.version}): {p.height:.3f} m in the column\n"
            f"(grammar's own height {own:.3f} m, scaled)",
            fontsize=9,
        )
        ax.set_aspect("equal")
        ax.set_xlim(min(d, curve[:, 0].min()) - 0.15, curve[:, 0].max() + 0.04)
        ax.set_xlabel("r (m)")
        ax.grid(lw=0.3)
    axes[0].set_ylabel("y (m)")
    axes[0].legend(fontsize=7, loc="upper left")
    fig.suptitle(
        "Column base half-profiles as built for the Portunus column (d = 0.475 m, "
        "every base scaled to half a diameter)",
        fontsize=11,
    )
    fig.tight_layout()
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=110)
    print(f"wrote {out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
