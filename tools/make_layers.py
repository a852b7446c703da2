"""Regenerate the reconstruction-hypothesis layers shipped under ``layers/portunus/``.

Run: ``python tools/make_layers.py``. The same layers are written into every temple folder by
``ionic-usd temple`` (``<temple>/layers/``); the copies here let a user browse them, apply one to
a stage of their own, or review a hypothesis as a diff. ``tests/test_temple.py`` checks they are
up to date.

They sublayer ``../materials.usda``, the temple's material library. Outside a build folder that
is ``layers/materials.usda``, written here too: every material the layers bind, as a plain
one-colour surface (the textured library lives in a build folder), so that every layer the
repository ships opens alone and validates with no error (``tests/test_hostile_31.py``).
"""

from __future__ import annotations

from pathlib import Path

from ionic_usd.temple.layout import portunus_layout
from ionic_usd.usd.materials import stand_in_materials
from ionic_usd.usd.stage import save_layer
from ionic_usd.usd.temple import MATERIALS_LAYER, hypothesis_layers

OUT = Path(__file__).resolve().parent.parent / "layers" / "portunus"


def main() -> None:
    written = []
    for hid, layer in hypothesis_layers(portunus_layout()).items():
        if layer is None:
            print(f"{hid}: not realisable by the generator (listed in the temple's customData)")
            continue
        path = save_layer(layer, OUT / f"{hid}.usda", force=True)
        written.append(layer)
        print(f"wrote {path.relative_to(OUT.parent.parent)}")
    path = save_layer(stand_in_materials(written), OUT.parent / MATERIALS_LAYER, force=True)
    print(f"wrote {path.relative_to(OUT.parent.parent)}")


if __name__ == "__main__":
    main()
