"""A grid city whose lots each draw a temple type (``--temple auto``), rendered into docs/.

Run: ``python tools/render_city_types.py [--work DIR]`` (needs the preview extra; builds six
temples: minutes). Runs ``ionic-usd city DIR/city --temple auto --rows 2 --cols 3
--texture-size 64 --no-cards --seed 3`` and ``ionic-usd preview`` of it (three-quarter view,
LOD low) into docs/city_types.png.
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
from pathlib import Path

DOCS = Path(__file__).resolve().parent.parent / "docs"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--work", type=Path, default=None)
    args = ap.parse_args()
    work = args.work or Path(tempfile.mkdtemp(prefix="city_types_"))
    city = work / "city"
    cli = [sys.executable, "-m", "ionic_usd"]
    subprocess.run(
        [*cli, "city", str(city), "--temple", "auto", "--rows", "2", "--cols", "3"]
        + ["--texture-size", "64", "--no-cards", "--seed", "3", "--force"],
        check=True,
    )
    subprocess.run(
        [*cli, "preview", str(city / "City.usda"), "-o", str(DOCS / "city_types.png")]
        + ["--camera", "three-quarter", "--lod", "low", "--width", "1400", "--height", "700"]
        + ["--force"],
        check=True,
    )


if __name__ == "__main__":
    main()
