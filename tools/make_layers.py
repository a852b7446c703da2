"""Regenerate the reconstruction-hypothesis layers shipped under ``layers/portunus/``.

Run: ``python tools/make_layers.py``. The same layers are written into every temple folder by
``ionic-usd temple`` (``<temple>/layers/``); the copies here let a user browse them, apply one to
a stage of their own, or review a hypothesis as a diff. ``tests/test_temple.py`` checks they are
up to date.
"""

from __future__ import annotations

from pathlib import Path

from ionic_usd.temple.layout import portunus_layout
from ionic_usd.usd.stage import save_layer
from ionic_usd.usd.temple import hypothesis_layers

OUT = Path(__file__).resolve().parent.parent / "layers" / "portunus"


def main() -> None:
    for hid, layer in hypothesis_layers(portunus_layout()).items():
        if layer is None:
            print(f"{hid}: not realisable by the generator (listed in the temple's customData)")
            continue
        path = save_layer(layer, OUT / f"{hid}.usda", force=True)
        print(f"wrote {path.relative_to(OUT.parent.parent)}")


if __name__ == "__main__":
    main()
