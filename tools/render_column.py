"""Render the default (Temple of Portunus) column, front and side, into docs/.

Run: ``python tools/render_column.py`` (needs the preview extra). Writes docs/column_front.png and
docs/column_side.png from a USD file written by ``ionic-usd column``.
"""

from __future__ import annotations

import tempfile
from pathlib import Path

from pxr import Sdf, Usd, UsdGeom

from ionic_usd.column.column import build_column, portunus_column_params
from ionic_usd.preview import render_preview
from ionic_usd.usd import write_meshes

DOCS = Path(__file__).resolve().parent.parent / "docs"


def main() -> None:
    tmp = Path(tempfile.mkdtemp())
    col = build_column(portunus_column_params())
    front = write_meshes(tmp / "front.usda", col.parts(), root="Column")
    # the side view: the same column turned 90 degrees about its axis
    side = tmp / "side.usda"
    layer = Sdf.Layer.CreateNew(str(side))
    stage = Usd.Stage.Open(layer)
    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.y)
    UsdGeom.SetStageMetersPerUnit(stage, 1.0)
    xf = UsdGeom.Xform.Define(stage, "/Side")
    xf.AddRotateYOp().Set(90.0)
    xf.GetPrim().GetReferences().AddReference(str(front))
    stage.SetDefaultPrim(xf.GetPrim())
    layer.Save()
    for src, name in ((front, "column_front.png"), (side, "column_side.png")):
        s = render_preview(src, DOCS / name, width=360, height=800, camera="front", force=True)
        print(f"{name}: {s.triangles:,} triangles, {s.seconds:.2f} s")


if __name__ == "__main__":
    main()
