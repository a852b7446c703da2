"""Render the architectural detail pictures into docs/ (issue 17).

Run: ``python tools/render_detail.py`` (needs the preview extra). Writes

* ``docs/temple_carved.png`` — the Temple of Portunus in the ``carved`` detail variant;
* ``docs/temple_moulded.png`` — the same in ``moulded`` (profiles, no ornament);
* ``docs/capital_carved.png`` — the high-LOD capital with its egg-and-dart and bead-and-reel;
* ``docs/cornice_corner.png`` — the front-right corner of the entablature and roof: fasciae,
  dentils, corona and sima, raking cornice, tiles and antefixes, seen from slightly below.

The close-ups are small stages built from the same kernel values (clipped near the subject,
so that the project's renderer, which frames the whole scene, frames the detail).
"""

from __future__ import annotations

import math
import tempfile
from pathlib import Path

import numpy as np
from pxr import Sdf, Usd

from ionic_usd.blueprint.column_asset import column_ornament
from ionic_usd.column.column import build_column, portunus_column_params
from ionic_usd.column.ornament import Instances
from ionic_usd.geometry.clip import clip_mesh
from ionic_usd.geometry.mesh import Mesh, transform
from ionic_usd.pipeline.temple import compose_temple
from ionic_usd.preview import render_preview
from ionic_usd.temple.cuboid import cuboid_mesh
from ionic_usd.temple.layout import portunus_layout
from ionic_usd.temple.mouldings import REPLACED_CUBOIDS, cornice_levels
from ionic_usd.usd.column_asset import ColumnAssetOptions
from ionic_usd.usd.detail import detail_geometry
from ionic_usd.usd.instancer import author_point_instancer
from ionic_usd.usd.mesh import author_mesh
from ionic_usd.usd.stage import new_layer, save_layer

DOCS = Path(__file__).resolve().parent.parent / "docs"


def _tilt(elev_deg: float, az_deg: float = 35.0) -> np.ndarray:
    """A rotation about the three-quarter camera's right axis: the preview's 20° elevation
    becomes ``20 + elev_deg`` (a view from below for elev_deg < −20)."""
    az, el = math.radians(az_deg), math.radians(20.0)
    d = np.array([math.sin(az) * math.cos(el), math.sin(el), math.cos(az) * math.cos(el)])
    r = np.cross(-d, [0.0, 1.0, 0.0])
    r /= np.linalg.norm(r)
    a = math.radians(elev_deg)
    k = np.array([[0, -r[2], r[1]], [r[2], 0, -r[0]], [-r[1], r[0], 0]])
    m = np.eye(4)
    m[:3, :3] = np.eye(3) + math.sin(a) * k + (1 - math.cos(a)) * k @ k
    return m


def _stage(
    path: Path, meshes: dict[str, Mesh], inst: dict[str, Instances], xform: np.ndarray | None = None
) -> Path:
    lay = new_layer("Scene", kind="component")
    with Sdf.ChangeBlock():
        for name, m in meshes.items():
            author_mesh(lay, f"/Scene/{name}", m if xform is None else transform(m, xform))
        for name, i in inst.items():
            if xform is not None:
                from ionic_usd.column.ornament import frames_to_quaternions, quaternion_matrices

                r = xform[:3, :3] @ quaternion_matrices(i.orientations)
                i = Instances(
                    i.name,
                    i.prototypes,
                    i.proto_indices,
                    i.positions @ xform[:3, :3].T + xform[:3, 3],
                    frames_to_quaternions(r[:, :, 0], r[:, :, 1]),
                    i.scales,
                )
            author_point_instancer(lay, f"/Scene/{name}", i)
    return save_layer(lay, path, force=True)


def _keep(i: Instances, mask: np.ndarray) -> Instances:
    return Instances(
        i.name,
        i.prototypes,
        i.proto_indices[mask],
        i.positions[mask],
        i.orientations[mask],
        i.scales[mask],
    )


def capital(tmp: Path) -> Path:
    p = portunus_column_params()
    col = build_column(p)
    y_cap = col.base_height + col.shaft_length
    shaft = clip_mesh(col.shaft, (0, y_cap - 0.35, 0), (0, 1, 0))
    meshes = {"Shaft": shaft, "Capital": col.capital_body}
    orn = {a.name: a.instances for a in column_ornament(ColumnAssetOptions(params=p))}
    # turn the volute face (+Z) to the lit side and look up at the echinus a little
    turn = np.eye(4)
    c, s = math.cos(math.radians(70.0)), math.sin(math.radians(70.0))
    turn[:3, :3] = [[c, 0, s], [0, 1, 0], [-s, 0, c]]
    return _stage(tmp / "capital.usda", meshes, orn, xform=_tilt(-22.0) @ turn)


def cornice_corner(tmp: Path) -> Path:
    lay = portunus_layout()
    lv = cornice_levels(lay)
    geom = detail_geometry(lay)
    x0, z0 = lv["xe"] - 2.2, lv["ze"] - 2.2
    y0 = lv["y_architrave"] - 1.4
    planes = [((x0, 0, 0), (1, 0, 0)), ((0, 0, z0), (0, 0, 1)), ((0, y0, 0), (0, 1, 0))]

    def clip(m: Mesh) -> Mesh | None:
        for pt, n in planes:
            if m.extent[1] @ np.abs(n) <= np.dot(pt, n):
                return None
            m = clip_mesh(m, pt, n)
            if m.n_faces == 0:
                return None
        return m

    meshes = {}
    for c in lay.all_cuboids():
        if c.name in REPLACED_CUBOIDS or c.name.startswith("pediment_left"):
            continue
        m = clip(cuboid_mesh(c))
        if m is not None:
            meshes[c.name] = m
    for members in geom.mouldings.values():
        for name, m in members.items():
            cm = clip(m)
            if cm is not None:
                meshes[name] = cm
    # the corner column's capital and the top of its shaft
    p = portunus_column_params(
        height=lay.params.columns_height, lower_diameter=lay.params.columns_lower_diameter
    )
    col = build_column(p)
    front = next(c for c in lay.columns if c.name == "front_4")
    place = np.eye(4)
    place[:3, 3] = front.position
    for name, m in (("Shaft", col.shaft), ("Capital", col.capital_body)):
        cm = clip(transform(m, place))
        if cm is not None:
            meshes[name] = cm
    inst = {}
    for rel, i in geom.ornament.items():
        pos = i.positions
        keep = (pos[:, 0] > x0 + 0.3) & (pos[:, 2] > z0 + 0.3)
        inst[rel.split("/")[-1]] = _keep(i, keep)
    for a in column_ornament(ColumnAssetOptions(params=p)):
        i = a.instances
        inst[a.name] = Instances(
            i.name,
            i.prototypes,
            i.proto_indices,
            i.positions + np.asarray(front.position),
            i.orientations,
            i.scales,
        )
    return _stage(tmp / "corner.usda", meshes, inst, xform=_tilt(-30.0))


def main() -> None:
    tmp = Path(tempfile.mkdtemp())
    rep = compose_temple(tmp / "Temple", portunus_layout(), texture_size=256)
    root = Usd.Stage.Open(str(rep.root))
    for v in ("carved", "moulded"):
        sel = tmp / f"temple_{v}.usda"
        lay = Sdf.Layer.CreateNew(str(sel))
        lay.subLayerPaths.append(str(rep.root))
        over = Sdf.CreatePrimInLayer(lay, "/Temple")
        over.specifier = Sdf.SpecifierOver
        over.variantSelections["detail"] = v
        lay.defaultPrim = "Temple"
        lay.pseudoRoot.SetInfo("upAxis", "Y")
        lay.pseudoRoot.SetInfo("metersPerUnit", 1.0)
        lay.Save()
        s = render_preview(
            sel,
            DOCS / f"temple_{v}.png",
            width=1200,
            height=800,
            camera="three-quarter",
            force=True,
        )
        print(f"temple_{v}.png: {s.triangles:,} triangles, {s.instances} instances")
    del root
    s = render_preview(
        capital(tmp),
        DOCS / "capital_carved.png",
        width=900,
        height=700,
        camera="three-quarter",
        ground=False,
        force=True,
    )
    print(f"capital_carved.png: {s.triangles:,} triangles, {s.instances} instances")
    s = render_preview(
        cornice_corner(tmp),
        DOCS / "cornice_corner.png",
        width=1000,
        height=800,
        camera="three-quarter",
        ground=False,
        force=True,
    )
    print(f"cornice_corner.png: {s.triangles:,} triangles, {s.instances} instances")


if __name__ == "__main__":
    main()
