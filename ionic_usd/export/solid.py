"""Printable solids: one closed shell per column (its parts unioned by manifold3d), STL and 3MF.

A scene's placements are grouped into bodies: each instance (a column of a temple, a column of a
city's PointInstancer) is one body; everything not instanced (the column of ``ionic-usd column``,
a temple's podium, cella and roof) is one more. The parts of a body — base, shaft, capital body,
bolsters, each a closed shell — are unioned with manifold3d into one watertight solid.

Files are in millimetres, Z up (what slicers expect): a point of the scene at ``(x, y, z)``
metres (Y up) is written at ``1000 · scale · (x, −z, y)``. Each solid is checked on the very
numbers written (float32): every edge shared by exactly two triangles with opposite directions
(closed and consistently oriented), and its volume (divergence theorem) positive.
"""

from __future__ import annotations

import math
import os
import time
import zipfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ionic_usd.errors import GeometryError, ParameterError
from ionic_usd.export.common import atomic_write, require
from ionic_usd.geometry.mesh import triangulate_fan, unique_rows
from ionic_usd.usd.reader import Scene

__all__ = [
    "Solid",
    "SolidReport",
    "SolidsReport",
    "scene_solids",
    "check_solid",
    "write_solids",
    "write_stl",
    "write_3mf",
    "read_stl",
]

_Y_TO_Z_UP = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])  # row vectors


@dataclass(frozen=True)
class Solid:
    """One body: ``vertices`` (n, 3) float64 mm, Z up; ``triangles`` (t, 3) int64, CCW out."""

    name: str
    vertices: np.ndarray
    triangles: np.ndarray
    parts: int


@dataclass(frozen=True)
class SolidReport:
    """Measured on the written numbers: volume in m³ and size (3,) in m, at print scale."""

    name: str
    volume: float
    size: tuple[float, float, float]
    closed: bool
    triangles: int
    parts: int
    non_manifold_edges: int = 0


@dataclass(frozen=True)
class SolidsReport:
    path: Path
    solids: tuple[SolidReport, ...]
    seconds: float

    @property
    def all_closed(self) -> bool:
        return all(s.closed for s in self.solids)


def _body_key(p, root: str) -> str:
    return p.path if p.instanced else root


def scene_solids(scene: Scene, *, scale: float = 1.0) -> list[Solid]:
    """Union each body's parts (see the module docstring) at ``scale``, in mm, Z up."""
    m3 = require("manifold3d", "STL/3MF export (the union of a column's parts)")
    if not (np.isfinite(scale) and scale > 0):
        raise ParameterError("scale", scale, "a finite number > 0")
    root = Path(scene.source).stem
    bodies: dict[str, list] = {}
    for p in scene.placements:
        bodies.setdefault(_body_key(p, root), []).append(p)
    conv = np.eye(4)
    conv[:3, :3] = _Y_TO_Z_UP * (1000.0 * scale)
    out: list[Solid] = []
    shells: dict[str, Any] = {}  # each mesh as a Manifold once, in its own space
    for name, placements in bodies.items():
        parts = []
        for p in placements:
            m = scene.meshes[p.mesh]
            if p.mesh not in shells:
                tris = triangulate_fan(m.face_vertex_counts, m.face_vertex_indices)
                mesh = m3.Mesh(
                    vert_properties=np.ascontiguousarray(m.points, np.float32),
                    tri_verts=np.ascontiguousarray(tris, np.uint32),
                )
                man = m3.Manifold(mesh)
                if man.status() != m3.Error.NoError:
                    mesh.merge()  # weld coincident vertices, then try again
                    man = m3.Manifold(mesh)
                if man.status() != m3.Error.NoError:
                    raise GeometryError(
                        f"{m.source}: not a closed manifold shell "
                        f"({man.status().name}); cannot make a printable solid"
                    )
                shells[p.mesh] = man
            mat = p.matrix @ conv  # row-vector; Manifold.transform takes a column-vector 3x4
            parts.append(shells[p.mesh].transform(np.ascontiguousarray(mat.T[:3, :4])))
        solid = m3.Manifold.batch_boolean(parts, m3.OpType.Add) if len(parts) > 1 else parts[0]
        res = solid.to_mesh()
        verts = np.asarray(res.vert_properties, dtype=np.float64)[:, :3]
        tris = np.asarray(res.tri_verts, dtype=np.int64)
        if len(tris) == 0:
            raise GeometryError(f"{name}: the union of its parts is empty")
        label = name.rsplit("/", 1)[-1].replace("[", "_").replace("]", "") or root
        out.append(Solid(label, verts, tris, len(parts)))
    return out


def check_solid(vertices: np.ndarray, triangles: np.ndarray) -> tuple[bool, int, float]:
    """``(closed, non_manifold_edges, volume)`` of a triangle shell.

    ``closed``: watertight and consistently oriented — every directed edge ``a→b`` is used as
    often as ``b→a`` (no boundary, no flipped triangle). ``non_manifold_edges``: edges with more
    than two triangles (a pinch where a shell touches itself; still closed). ``volume`` by the
    divergence theorem, positive when triangles wind counter-clockwise seen from outside.

    Parameters
    ----------
    vertices : (n, 3) float
    triangles : (t, 3) int
    """
    t = np.asarray(triangles, dtype=np.int64)
    v = np.asarray(vertices, dtype=np.float64)
    if len(t) == 0:
        return False, 0, 0.0
    n = len(v)
    a = np.concatenate([t[:, 0], t[:, 1], t[:, 2]])
    b = np.concatenate([t[:, 1], t[:, 2], t[:, 0]])
    fwd_u, fwd_c = np.unique(a * n + b, return_counts=True)
    rev_u, rev_c = np.unique(b * n + a, return_counts=True)
    closed = bool(np.all(a != b) and np.array_equal(fwd_u, rev_u) and np.array_equal(fwd_c, rev_c))
    und_u, und_c = np.unique(np.minimum(a, b) * n + np.maximum(a, b), return_counts=True)
    pinched = int(np.sum(und_c > 2))
    p0, p1, p2 = v[t[:, 0]], v[t[:, 1]], v[t[:, 2]]
    volume = float(np.einsum("ij,ij->i", p0, np.cross(p1, p2)).sum() / 6.0)
    return closed, pinched, volume


def _report(s: Solid) -> SolidReport:
    v32 = s.vertices.astype(np.float32)
    # the check runs on the written float32 numbers, welded by position as a slicer does
    uniq, inv = unique_rows(v32, return_inverse=True)
    tris = inv.reshape(-1)[s.triangles]
    closed, pinched, vol = check_solid(uniq, tris)
    ext = (uniq.max(axis=0) - uniq.min(axis=0)) * 1e-3
    size = (float(ext[0]), float(ext[1]), float(ext[2]))
    return SolidReport(
        s.name,
        vol * 1e-9,
        size,
        bool(closed and vol > 0),
        len(s.triangles),
        s.parts,
        pinched,
    )


#: the model scales ``--scale`` accepts: 1:10,000 (a site model) to 10:1 (a detail study)
SCALE_RANGE = (1e-4, 10.0)
#: the printed size of a solid's longest side (m): from 1 mm (a few nozzle or resin-voxel
#: widths: below it a column is a speck) to 100 m (construction printers print whole
#: buildings; a temple at 1:1 is 26 m)
PRINT_SIZE = (1e-3, 100.0)


def _check_printable(s: Solid, r: SolidReport, scale: float) -> None:
    """Refuse, before anything is written, a solid no printer can make: non-finite written
    numbers, a longest side outside :data:`PRINT_SIZE`, no volume."""
    v32 = s.vertices.astype(np.float32)
    longest = max(r.size)
    lo, hi = PRINT_SIZE
    if not (np.isfinite(v32).all() and math.isfinite(longest) and lo <= longest <= hi):
        raise ParameterError(
            "--scale",
            f"{scale:g}",
            f"a scale at which every solid's longest side is {lo * 1e3:g} mm to {hi:g} m "
            f"({s.name} would be {longest * 1e3:.3g} mm)",
        )
    if not (math.isfinite(r.volume) and r.volume > 0):
        raise GeometryError(f"{s.name}: no volume at scale {scale:g}; nothing written")


def write_stl(path: Path, solids: list[Solid]) -> None:
    """Binary STL (all solids, mm)."""
    tris = [s.vertices[s.triangles] for s in solids]
    allt = np.concatenate(tris).astype(np.float32)  # (t, 3, 3)
    nrm = np.cross(allt[:, 1] - allt[:, 0], allt[:, 2] - allt[:, 0]).astype(np.float64)
    ln = np.linalg.norm(nrm, axis=1, keepdims=True)
    nrm = np.where(ln > 0, nrm / np.where(ln > 0, ln, 1.0), 0.0)
    rec = np.zeros(len(allt), dtype=[("n", "<f4", (3,)), ("v", "<f4", (3, 3)), ("a", "<u2")])
    rec["n"], rec["v"] = nrm, allt
    header = f"ionic_usd: {len(solids)} solids, mm, Z up".encode()[:80].ljust(80, b" ")

    def write(tmp: Path) -> None:
        with open(tmp, "wb") as f:
            f.write(header)
            f.write(np.uint32(len(rec)).tobytes())
            f.write(rec.tobytes())

    atomic_write(path, write)


def read_stl(path: str | os.PathLike) -> np.ndarray:
    """Triangles (t, 3, 3) float32 of a binary STL."""
    data = Path(path).read_bytes()
    n = int(np.frombuffer(data, "<u4", 1, 80)[0])
    rec = np.frombuffer(
        data, dtype=[("n", "<f4", (3,)), ("v", "<f4", (3, 3)), ("a", "<u2")], count=n, offset=84
    )
    return rec["v"].copy()


_CONTENT_TYPES = """<?xml version="1.0" encoding="UTF-8"?>
<Types xmlns="http://schemas.openxmlformats.org/package/2006/content-types">
 <Default Extension="rels" ContentType="application/vnd.openxmlformats-package.relationships+xml"/>
 <Default Extension="model" ContentType="application/vnd.ms-package.3dmanufacturing-3dmodel+xml"/>
</Types>
"""
_RELS = """<?xml version="1.0" encoding="UTF-8"?>
<Relationships xmlns="http://schemas.openxmlformats.org/package/2006/relationships">
 <Relationship Target="/3D/3dmodel.model" Id="rel0"
  Type="http://schemas.microsoft.com/3dmanufacturing/2013/01/3dmodel"/>
</Relationships>
"""


def _xml_attr(text: str) -> str:
    from xml.sax.saxutils import quoteattr  # noqa: PLC0415

    return quoteattr(text)


def write_3mf(path: Path, solids: list[Solid], *, title: str = "") -> None:
    """3MF core (a zip of XML): one mesh object per solid, each a build item; millimetres."""
    objects, items = [], []
    for i, s in enumerate(solids, start=1):
        # float32 values printed with 9 significant digits read back bit for bit
        v = s.vertices.astype(np.float32).astype(np.float64).tolist()
        vfmt = '<vertex x="{:.9g}" y="{:.9g}" z="{:.9g}"/>'.format
        tfmt = '<triangle v1="{}" v2="{}" v3="{}"/>'.format
        verts = "".join([vfmt(*r) for r in v])
        tris = "".join([tfmt(*r) for r in s.triangles.tolist()])
        objects.append(
            f'<object id="{i}" type="model" name={_xml_attr(s.name)}><mesh>'
            f"<vertices>{verts}</vertices><triangles>{tris}</triangles></mesh>"
            "</object>"
        )
        items.append(f'<item objectid="{i}"/>')
    meta = f'<metadata name="Title">{_xml_escape(title)}</metadata>' if title else ""
    model = (
        '<?xml version="1.0" encoding="UTF-8"?>\n'
        '<model unit="millimeter" xml:lang="en-US" '
        'xmlns="http://schemas.microsoft.com/3dmanufacturing/core/2015/02">'
        f'{meta}<metadata name="Application">ionic_usd</metadata>'
        f"<resources>{''.join(objects)}</resources><build>{''.join(items)}</build></model>"
    )

    def write(tmp: Path) -> None:
        with zipfile.ZipFile(tmp, "w", zipfile.ZIP_DEFLATED) as z:
            for name, text in (
                ("[Content_Types].xml", _CONTENT_TYPES),
                ("_rels/.rels", _RELS),
                ("3D/3dmodel.model", model),
            ):
                # a fixed time stamp (the zip epoch): the same solids give the same bytes
                info = zipfile.ZipInfo(name, date_time=(1980, 1, 1, 0, 0, 0))
                info.compress_type = zipfile.ZIP_DEFLATED
                z.writestr(info, text)

    atomic_write(path, write)


def _xml_escape(text: str) -> str:
    from xml.sax.saxutils import escape  # noqa: PLC0415

    return escape(text)


def write_solids(scene: Scene, path: str | os.PathLike, *, scale: float = 1.0) -> SolidsReport:
    """Write the scene's solids as ``.stl`` (binary) or ``.3mf`` by the extension."""
    t0 = time.perf_counter()
    path = Path(path)
    solids = scene_solids(scene, scale=scale)
    reports = tuple(_report(s) for s in solids)
    for s, r in zip(solids, reports, strict=True):
        _check_printable(s, r, scale)
    if path.suffix.lower() == ".3mf":
        write_3mf(path, solids, title=Path(scene.source).stem)
    else:
        write_stl(path, solids)
    return SolidsReport(path, reports, time.perf_counter() - t0)
