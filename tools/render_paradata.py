"""Draw docs/temple_appearance.png and docs/temple_reliability.png: the default temple in its
two ``view`` variants (ionic-usd preview --view), the reliability view coloured by the Extended
Matrix chart. Run: ``python tools/render_paradata.py [TEMPLE_FOLDER]`` (builds one if absent)."""

from __future__ import annotations

import subprocess
import sys
import tempfile
from pathlib import Path

DOCS = Path(__file__).resolve().parent.parent / "docs"


def main() -> None:
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(sys.argv[1]) if len(sys.argv) > 1 else Path(tmp) / "PortunusTemple"
        cli = [sys.executable, "-m", "ionic_usd"]
        if not (folder / "Temple.usda").is_file():
            subprocess.run([*cli, "temple", "-o", str(folder), "-q"], check=True)
        for view in ("appearance", "reliability"):
            out = DOCS / f"temple_{view}.png"
            subprocess.run(
                [*cli, "preview", str(folder / "Temple.usda"), "-o", str(out), "--force",
                 "--view", view, "--camera", "three-quarter", "--width", "800", "--height", "600"],
                check=True,
            )  # fmt: skip


if __name__ == "__main__":
    main()
