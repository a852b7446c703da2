"""docs/city_cards.png and the default city's drawn triangles at each LOD setting.

Builds the 4 x 4 Portunus city (``--rows 4 --cols 4 --temple portunus``, the default before
the lots chose their types) three ways — every temple high (no focus), LOD by distance
from the corner (0, 0) without cards, and the same with temples beyond ``--cards-beyond`` drawn
as card boxes — and prints what the project's renderer draws for each (``render_preview``'s
triangle count: a card box is 12). Then renders the picture: a larger grid seen from its focus
corner, near temples in full geometry and far ones as cards.

    python tools/render_city_cards.py [--cards-beyond 200] [--work /tmp/city_cards]
"""

from __future__ import annotations

import argparse
import shutil
from pathlib import Path

from ionic_usd.pipeline.city import CityOptions, build_city
from ionic_usd.preview import render_preview

DOCS = Path(__file__).resolve().parents[1] / "docs"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--cards-beyond", type=float, default=200.0)
    ap.add_argument("--work", type=Path, default=Path("/tmp/city_cards"))
    ap.add_argument("--texture-size", type=int, default=256)
    ap.add_argument("--skip-counts", action="store_true")
    args = ap.parse_args()
    if args.work.exists():
        shutil.rmtree(args.work)
    base = dict(texture_size=args.texture_size, workers=1, temple="portunus")
    settings = {
        "no focus (temples high, columns low)": CityOptions(**base, rows=4, cols=4),
        "LOD by distance": CityOptions(**base, rows=4, cols=4, focus=(0.0, 0.0), cards=False),
        f"LOD + cards beyond {args.cards_beyond:g} m": CityOptions(
            **base, rows=4, cols=4, focus=(0.0, 0.0), cards_beyond=args.cards_beyond
        ),
    }
    if not args.skip_counts:
        rows = []
        for i, (name, opts) in enumerate(settings.items()):
            out = args.work / f"city{i}"
            s = build_city(out, opts)
            st = render_preview(
                out / "City.usda", args.work / f"city{i}.png", width=400, height=300, samples=0
            )
            rows.append((name, st.triangles, s["triangles"]["as authored"], st.cards // 6))
            if i == 0:  # the composer's count with every temple and street column at high
                everything_high = s["triangles"]["high"]
        first = rows[0][1]
        print(f"{'setting':38} {'drawn (preview)':>16} {'composer':>12} {'cards':>6} ratio")
        for name, drawn, composed, cards in rows:
            print(f"{name:38} {drawn:16,} {composed:12,} {cards:6} {drawn / first:5.3f}")
        print(f"{'everything high (composer)':38} {'':16} {everything_high:12,}")
    # the picture: a 6 x 6 grid, LOD by distance from the corner nearest the camera (the
    # three-quarter view looks from +x, +z: plan (300, 0)), cards beyond --cards-beyond
    big = args.work / "big"
    build_city(
        big,
        CityOptions(
            rows=6,
            cols=6,
            focus=(300.0, 0.0),
            lod_distances=(100.0, 200.0),
            cards_beyond=args.cards_beyond,
            **base,
        ),
    )
    st = render_preview(
        big / "City.usda",
        DOCS / "city_cards.png",
        width=1400,
        height=800,
        camera="three-quarter",
        force=True,
    )
    print(f"docs/city_cards.png: {st.triangles:,} triangles, {st.cards // 6} temples as cards")


if __name__ == "__main__":
    main()
