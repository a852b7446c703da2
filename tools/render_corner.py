"""Render the cella's rear-right corner from outside and an angle capital into docs/.

Run: ``python tools/render_corner.py`` (needs the preview extra). Writes docs/cella_corner.png
(the Temple of Portunus' rear-right corner: the three-quarter ``corner`` column rear_4 between
the engaged half columns rear_3 and right_6, on their walls, as the layout places them) and
docs/angle_capital.png (the angle capital seen from the corner's diagonal, both outer faces'
volutes in view, and from its front face).
"""

from __future__ import annotations

import argparse
import math
import tempfile
from pathlib import Path

import numpy as np

from ionic_usd.column.capital import capital_mesh
from ionic_usd.column.column import portunus_column_params
from ionic_usd.geometry.mesh import Mesh, merge, transform
from ionic_usd.pipeline.asset import column_asset_meshes
from ionic_usd.preview import render_preview
from ionic_usd.temple.cuboid import Cuboid, cuboid_mesh
from ionic_usd.temple.layout import Layer, portunus_layout
from ionic_usd.usd import write_meshes
from ionic_usd.usd.column_asset import ColumnAssetOptions

DOCS = Path(__file__).resolve().parent.parent / "docs"


def _placement_matrix(pos, rot_deg: float, turn_deg: float) -> np.ndarray:
    """Column frame → world, then the whole scene turned by ``turn_deg`` about +Y."""

    def rot_y(deg: float) -> np.ndarray:
        t = math.radians(deg)
        m = np.eye(4)
        m[0, 0], m[0, 2], m[2, 0], m[2, 2] = math.cos(t), math.sin(t), -math.sin(t), math.cos(t)
        return m

    tr = np.eye(4)
    tr[:3, 3] = pos
    return rot_y(turn_deg) @ tr @ rot_y(rot_deg)


def _crop(c: Cuboid, lo, hi) -> Cuboid:
    a = np.maximum(np.asarray(c.min), lo)
    b = np.minimum(np.asarray(c.max), hi)
    return Cuboid(tuple(a), tuple(b), name=c.name)


def cella_corner(lod: str, out: Path) -> None:
    layout = portunus_layout()
    cols = {c.name: c for c in layout.columns}
    names = ("rear_3", "rear_4", "right_6", "right_5")
    meshes = column_asset_meshes(
        ColumnAssetOptions(
            lods=(lod,),
            bases=("attic_bezier_plinth",),
            scrolls=("S1",),
            capitals=("normal",),
            flutes=("f24",),
            forms=("engaged", "corner"),
        )
    )
    by_form: dict[str, list[Mesh]] = {}
    for m in meshes:
        by_form.setdefault(m.tags["form"], []).append(m.mesh)
    turn = -90.0  # the rear-right corner turned towards the camera's front-right
    scene: dict[str, Mesh] = {}
    for n in names:
        c = cols[n]
        col = merge(by_form[c.kind.value], name=n)
        scene[n] = transform(col, _placement_matrix(c.position, c.rotation_deg, turn))
    xa, zr = layout.params.x_axis, -layout.params.z_front_axis
    lo = np.array([0.3, -1.0, zr - 1.2])
    hi = np.array([xa + 1.2, 50.0, zr + 7.5])
    for c in (*layout.cuboids[Layer.CELLA], layout.cuboid("die")):
        if np.all(np.asarray(c.min) < hi) and np.all(np.asarray(c.max) > lo):
            box = cuboid_mesh(_crop(c, lo, hi))
            scene[c.name] = transform(box, _placement_matrix((0, 0, 0), 0.0, turn))
    tmp = Path(tempfile.mkdtemp())
    src = write_meshes(tmp / "corner.usda", scene, root="Corner")
    s = render_preview(src, out, width=900, height=900, camera="three-quarter", force=True)
    print(f"{out.name}: {s.triangles:,} triangles, {s.seconds:.2f} s")


def _join(pngs: list[Path], out: Path) -> None:
    """Put pictures of one height side by side (OpenImageIO)."""
    import OpenImageIO as oiio

    tiles = [oiio.ImageBuf(str(p)).get_pixels(oiio.UINT8) for p in pngs]
    row = np.concatenate(tiles, axis=1)
    spec = oiio.ImageSpec(row.shape[1], row.shape[0], row.shape[2], oiio.UINT8)
    buf = oiio.ImageBuf(spec)
    buf.set_pixels(oiio.ROI(), row)
    if not buf.write(str(out)):
        raise OSError(f"cannot write {out}: {buf.geterror()}")


def angle_capital(lod: str, out: Path) -> None:
    """Two views: from the outer diagonal (the corner volute square on, the volutes of both
    outer faces on either side) and from the front (+Z) face a little to the right (its own
    volute on the left, the canalis running into the corner volute turned 45°)."""
    p = portunus_column_params(lod=lod)
    cap = capital_mesh(p.capital_params(), top_radius=p.shaft.top_radius, angle=True)
    tmp = Path(tempfile.mkdtemp())
    pngs = []
    # the three-quarter camera looks from 35° off +Z towards +X: turn the capital so that it
    # sees the diagonal (45°) and then the front face from 15°
    for k, turn in enumerate((-10.0, 20.0)):
        m = transform(cap, _placement_matrix((0, 0, 0), 0.0, turn))
        src = write_meshes(tmp / f"capital{k}.usda", {"AngleCapital": m}, root="Capital")
        pngs.append(tmp / f"capital{k}.png")
        s = render_preview(src, pngs[-1], width=700, height=560, camera="three-quarter", force=True)
    _join(pngs, out)
    print(f"{out.name}: {s.triangles:,} triangles, {s.seconds:.2f} s per view")


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--lod", default="high")
    ap.add_argument("--out", type=Path, default=DOCS)
    args = ap.parse_args()
    cella_corner(args.lod, args.out / "cella_corner.png")
    angle_capital(args.lod, args.out / "angle_capital.png")


if __name__ == "__main__":
    main()
