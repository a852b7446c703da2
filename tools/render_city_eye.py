"""docs/city_eye.png: the example forum seen at eye level — varied temples, stoas, paving.

Builds ``examples/forum.geojson`` (21 temple lots, each its own build: a type chosen by the
city or named by the plan) and renders it with the project's preview renderer from a
standing eye (1.7 m) on the forum square, looking north at the capitolium between the west
and east stoas. Prints the builds and what was drawn.

    python tools/render_city_eye.py [--work /tmp/city_eye] [--texture-size 128]
"""

from __future__ import annotations

import argparse
from pathlib import Path

from ionic_usd.pipeline.city import CityOptions, build_city
from ionic_usd.preview import render_preview

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
#: (USD x, y, z): plan (e, n) = (x, −z). The eye stands on the square's south end
VIEWS = {
    "city_eye.png": ((-6.0, 1.7, 36.0), (4.0, 7.0, -60.0)),
}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--work", type=Path, default=Path("/tmp/city_eye"))
    ap.add_argument("--texture-size", type=int, default=128)
    ap.add_argument("--workers", type=int, default=None)
    args = ap.parse_args()
    out = args.work / "forum"
    s = build_city(
        out,
        CityOptions(
            plan=str(ROOT / "examples" / "forum.geojson"),
            texture_size=args.texture_size,
            workers=args.workers,
            force=True,
        ),
    )
    print(
        f"{s['temples']} temples, {s['builds']} builds, {s['stoa_bays']} stoa bays, "
        f"{s['stoa_corners']} corners, {s['columns']} street columns"
    )
    for c in s["lots"]:
        kind = c.get("preset") or (
            f"{c['arrangement']} {c['front']}x{c['side']} {c['intercolumniation']} "
            f"D={c['lower_diameter']:g} m"
        )
        print(f"  {c['lot']:14} {kind}")
    for name, (eye, target) in VIEWS.items():
        st = render_preview(
            out / "City.usda",
            DOCS / name,
            width=1600,
            height=900,
            ground=False,  # the city has its own paving
            eye=eye,
            target=target,
            force=True,
        )
        print(f"docs/{name}: {st.triangles:,} triangles, {st.instances:,} instances")


if __name__ == "__main__":
    main()
