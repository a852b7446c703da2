"""Repeated ornament of the temple, placed by rule (the ``carved`` level of detail; issue 17).

Pure numpy: each function returns :class:`~ionic_usd.column.ornament.Instances` (positions,
``(w, x, y, z)`` quaternions, scales, prototype indices) for a layout.

Rules and sources
-----------------
* **Dentils** under the corona, on the four sides of the horizontal cornice only (none under
  the raking cornice: Vitruvius IV.2.5). Height = the dentil course of the cornice section
  (:data:`ionic_usd.temple.mouldings._DENTIL_BAND`), projection = height (III.5.11), width =
  half the height and interval (*metoche*) = two thirds of the width (III.5.11): one dentil
  every ``5/6`` of the height. Each side carries as many as fit, centred; the corners are left
  open (their dentils would collide with the return).
* **Roof tiles**: Roman *tegulae* (flat, flanged) in rows up each slab and *imbrices* (half-
  round cover tiles) over their joints, with an *antefix* closing each imbrex row at the eaves
  (the flanks). Vitruvius gives no tile size; (!) we take the common Roman tegula of about
  0.50 × 0.62 m (Adam, *Roman Building*, 1994, ch. 9: 2 × 1½ Roman feet), laid with 0.10 m
  overlap.
* **Frieze garlands** (a hypothesis, ``frieze-garlands`` in ``portunus.toml``): candelabra on
  the column axes and mid-bays, a garland hanging between each pair — a modelled relief panel
  repeated round the frieze.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields

import numpy as np

from ionic_usd.checks import check_fields
from ionic_usd.column.ornament import (
    Instances,
    box_prototype,
    frames_to_quaternions,
    lathe_closed,
)
from ionic_usd.errors import ParameterError
from ionic_usd.geometry.mesh import Mesh
from ionic_usd.geometry.sweep import sweep
from ionic_usd.temple.layout import Layer, TempleLayout
from ionic_usd.temple.mouldings import cornice_levels

__all__ = [
    "TileParams",
    "dentils",
    "dentil_spacing",
    "roof_tiles",
    "frieze_garlands",
    "tegula_prototype",
    "imbrex_prototype",
    "antefix_prototype",
]

_UP = np.array([0.0, 1.0, 0.0])


@dataclass(frozen=True)
class TileParams:
    """Roof tile sizes (metres); see the module docstring for the source."""

    tegula_width: float = 0.50
    tegula_length: float = 0.62
    overlap: float = 0.10
    thickness: float = 0.03
    flange: float = 0.06
    imbrex_diameter: float = 0.16
    antefix_height: float = 0.30

    def __post_init__(self) -> None:
        check_fields(self, context="tiles", positive=[f.name for f in fields(self)])
        if self.overlap >= self.tegula_length:
            raise ParameterError("overlap", self.overlap, "< the tegula length", context="tiles")


def _side_frames(x: float, z: float):
    """(name, centre offset along the side's normal, normal, along, half length) of the four
    sides of the rectangle |x|, |z|, front first."""
    return (
        ("front", np.array([0.0, 0.0, 1.0]), np.array([1.0, 0.0, 0.0]), z, x),
        ("right", np.array([1.0, 0.0, 0.0]), np.array([0.0, 0.0, -1.0]), x, z),
        ("rear", np.array([0.0, 0.0, -1.0]), np.array([-1.0, 0.0, 0.0]), z, x),
        ("left", np.array([-1.0, 0.0, 0.0]), np.array([0.0, 0.0, 1.0]), x, z),
    )


def dentil_spacing(height: float) -> tuple[float, float]:
    """(width, centre-to-centre spacing) of dentils of a height: w = h/2, gap = 2w/3."""
    w = 0.5 * height
    return w, w + 2.0 * w / 3.0


def _centred(half: float, width: float, spacing: float) -> np.ndarray:
    """Centres of as many items as fit in [−half, half], centred."""
    n = int(math.floor((2 * half - width) / spacing + 1e-9)) + 1
    return (np.arange(n) - (n - 1) / 2) * spacing


def dentils(layout: TempleLayout) -> Instances:
    """Dentils round the horizontal cornice (module docstring for the rule)."""
    lv = cornice_levels(layout)
    h = lv["dentil_top"] - lv["dentil_bottom"]
    depth = lv["dentil_front"] - lv["dentil_face"]
    w, s = dentil_spacing(h)
    back = 0.02 * h  # into the band: no face coplanar with it
    proto = box_prototype((w, h, depth), back=back, name="Dentil")
    pos, xs, ys = [], [], []
    for _, nrm, along, off, half in _side_frames(
        lv["xe"] + lv["dentil_face"], lv["ze"] + lv["dentil_face"]
    ):
        t = _centred(half, w, s)
        p = t[:, None] * along + (off * nrm + lv["dentil_bottom"] * _UP)[None]
        pos.append(p)
        xs.append(np.tile(along, (len(t), 1)))
        ys.append(np.tile(_UP, (len(t), 1)))
    pos_a = np.concatenate(pos)
    n = len(pos_a)
    return Instances(
        "Dentils",
        (proto,),
        np.zeros(n, np.int32),
        pos_a,
        frames_to_quaternions(np.concatenate(xs), np.concatenate(ys)),
        np.ones((n, 3)),
    )


# -- roof tiles ----------------------------------------------------------------------------------
def _shear_tile(m: Mesh, rise: float, length: float) -> Mesh:
    """Raise the lower (z = 0) end by ``rise``, tapering to 0 at z = length: each tile rests
    on the one below."""
    pts = m.points.copy()
    pts[:, 1] += rise * (1.0 - np.clip(pts[:, 2] / length, 0.0, 1.0))
    # the shear y += rise·(1 − z/L) is linear on the tile (0 ≤ z ≤ L): normals go through the
    # inverse transpose of its matrix, n' ∝ (n_x, n_y, n_z + rise/L · n_y)
    assert m.normals is not None
    n = np.asarray(m.normals.values, dtype=np.float64).copy()
    n[:, 2] += rise / length * n[:, 1]
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    return m.with_(points=pts, normals=m.normals.with_values(n.astype(np.float32)))


def tegula_prototype(tp: TileParams) -> Mesh:
    """A flanged flat tile: x across, z up the slope from its lower edge, y up from its
    underside."""
    w, t, f = tp.tegula_width / 2, tp.thickness, tp.flange
    sec = np.array(
        [
            [-w, 0.0],
            [w, 0.0],
            [w, t + f],
            [w - t, t + f],
            [w - t, t],
            [-w + t, t],
            [-w + t, t + f],
            [-w, t + f],
        ]
    )
    m = sweep(
        sec, np.array([[0.0, 0.0, 0.0], [0.0, 0.0, tp.tegula_length]]), closed=False, name="Tegula"
    )
    return _shear_tile(m, t, tp.tegula_length)


def imbrex_prototype(tp: TileParams, *, segments: int = 8) -> Mesh:
    """A half-round cover tile over two flanges, same frame as the tegula."""
    r = tp.imbrex_diameter / 2
    a = np.linspace(0.0, np.pi, segments + 1)
    outer = np.stack([r * np.cos(a), r * np.sin(a)], 1)
    inner = np.stack(
        [(r - tp.thickness) * np.cos(a[::-1]), (r - tp.thickness) * np.sin(a[::-1])], 1
    )
    sec = np.vstack([outer, inner]) + [0.0, tp.thickness]
    m = sweep(
        sec,
        np.array([[0.0, 0.0, 0.0], [0.0, 0.0, tp.tegula_length]]),
        closed=False,
        crease_deg=50.0,
        name="Imbrex",
    )
    return _shear_tile(m, tp.thickness, tp.tegula_length)


def antefix_prototype(tp: TileParams) -> Mesh:
    """An antefix: a palmette plaque (fan top over a base) in the XY plane, facing +Z."""
    h, r = tp.antefix_height, tp.imbrex_diameter / 2
    a = np.linspace(np.pi, 0.0, 15)
    lobes = 1.0 + 0.12 * np.abs(np.sin(3.5 * (a - np.pi / 2)))  # scalloped palmette edge
    rad = 0.55 * h
    fan = np.stack([rad * np.cos(a) * lobes * 0.8, 0.45 * h + rad * 0.75 * np.sin(a) * lobes], 1)
    sec = np.vstack(
        [[[-r, 0.0], [r, 0.0], [0.6 * r, 0.45 * h]], fan[::-1][1:-1], [[-0.6 * r, 0.45 * h]]]
    )
    sec = sec[::-1]  # any winding: sweep orients the solid
    return sweep(
        sec[:, [0, 1]] * [-1, 1],
        np.array([[0.0, 0.0, 0.0], [0.0, 0.0, tp.thickness]]),
        closed=False,
        crease_deg=60.0,
        name="Antefix",
    )


def _slab_top_at_eaves(layout: TempleLayout) -> float:
    """Height of the roof slabs' top at the eaves, read from the layout's ``roof_left``
    cuboid (its max-x side is raised to the ridge): the tiles lie on the slab itself, bed
    included (:data:`ionic_usd.temple.layout.ROOF_BED`). Laid on the cornice top + slab
    thickness instead, they sank 5 cm into the slab, which showed through every pan."""
    slab = next(c for c in layout.cuboids[Layer.ROOF] if c.name == "roof_left")
    return float(slab.max[1])


def roof_tiles(layout: TempleLayout, tp: TileParams | None = None) -> Instances:
    """Tegulae, imbrices and antefixes on the two roof slabs (module docstring)."""
    tp = tp or TileParams()
    p = layout.params
    lv = cornice_levels(layout)
    tan = 2.0 / p.roof_tympanum_ratio
    phi = math.atan(tan)
    xc, zc = lv["xe"] + lv["projection"], lv["ze"] + lv["projection"]
    y_eave = _slab_top_at_eaves(layout)
    slope = xc / math.cos(phi)
    step = tp.tegula_length - tp.overlap
    rows = int(math.ceil((slope - tp.tegula_length) / step)) + 1
    cols = max(1, int(round(2 * zc / tp.tegula_width)))
    wcol = 2 * zc / cols
    zt = -zc + (np.arange(cols) + 0.5) * wcol  # tegula centres
    zi = -zc + np.arange(1, cols) * wcol  # imbrices over the joints
    d = np.minimum(np.arange(rows) * step, slope - tp.tegula_length)  # lower edges up the slope
    tegula, imbrex, antefix = tegula_prototype(tp), imbrex_prototype(tp), antefix_prototype(tp)
    sx = wcol / tp.tegula_width  # stretch across to close the course
    pos, xs, ys, idx, sc = [], [], [], [], []
    for sgn in (-1.0, 1.0):  # left slab (x < 0), right slab
        upd = np.array([-sgn * math.cos(phi), math.sin(phi), 0.0])  # up the slope
        nrm = np.array([sgn * math.sin(phi), math.cos(phi), 0.0])
        across = np.cross(nrm, upd)  # local +X so that local +Z = up the slope
        eave = np.array([sgn * xc, y_eave, 0.0])
        for proto_i, zs, lift in ((0, zt, 0.0), (1, zi, tp.flange)):  # imbrex on the flanges
            zz, dd = np.meshgrid(zs, d, indexing="ij")
            pts = eave + dd.reshape(-1, 1) * upd + lift * nrm
            pts[:, 2] = zz.reshape(-1)
            pos.append(pts)
            xs.append(np.tile(across, (len(pts), 1)))
            ys.append(np.tile(nrm, (len(pts), 1)))
            idx.append(np.full(len(pts), proto_i))
            s = np.ones((len(pts), 3))
            if proto_i == 0:
                s[:, 0] = sx
            sc.append(s)
        # antefixes: upright at the eaves, facing out, one per imbrex row
        out = np.array([sgn, 0.0, 0.0])
        pts = np.tile(eave + (tp.thickness + tp.flange) * nrm, (len(zi), 1))
        pts[:, 2] = zi
        pos.append(pts)
        xs.append(np.tile(np.cross(_UP, out), (len(zi), 1)))
        ys.append(np.tile(_UP, (len(zi), 1)))
        idx.append(np.full(len(zi), 2))
        sc.append(np.ones((len(zi), 3)))
    return Instances(
        "RoofTiles",
        (tegula, imbrex, antefix),
        np.concatenate(idx),
        np.concatenate(pos),
        frames_to_quaternions(np.concatenate(xs), np.concatenate(ys)),
        np.concatenate(sc),
    )


# -- frieze relief (hypothesis) --------------------------------------------------------------
def _garland_prototype(span: float, drop: float, thick: float) -> Mesh:
    """A garland: an octagonal tube swept along a hanging arc in the XY plane (relief, +Z)."""
    t = np.linspace(-1.0, 1.0, 13)
    path = np.stack([0.5 * span * t, -drop * (1 - t * t), np.zeros_like(t)], 1)
    a = np.linspace(0, 2 * np.pi, 9)[:-1]
    sec = np.stack([0.5 * thick * np.cos(a), 0.5 * thick * np.sin(a)], 1)
    return sweep(sec, path, axis=(0.0, 0.0, 1.0), closed=False, crease_deg=60.0, name="Garland")


def _candelabrum_prototype(height: float, width: float) -> Mesh:
    """A candelabrum: a baluster-like lathe (half of it sunk in the frieze)."""
    r = 0.5 * width
    prof = np.array(
        [
            [0.0, 0.0],
            [0.9 * r, 0.0],
            [0.9 * r, 0.06 * height],
            [0.3 * r, 0.12 * height],
            [0.25 * r, 0.45 * height],
            [0.6 * r, 0.55 * height],
            [0.2 * r, 0.62 * height],
            [0.2 * r, 0.85 * height],
            [r, 0.9 * height],
            [0.7 * r, height],
            [0.0, height],
        ]
    )
    return lathe_closed(prof, 10, name="Candelabrum")


def frieze_garlands(layout: TempleLayout) -> Instances:
    """Candelabra and garlands round the frieze (the ``frieze-garlands`` hypothesis)."""
    lv = cornice_levels(layout)
    fh = lv["y_cornice"] - lv["y_frieze"]
    s = layout.axial_spacing / 2  # a candelabrum on every column axis and mid-bay
    relief = min(0.08, 0.1 * fh)
    cand = _candelabrum_prototype(0.8 * fh, 2 * relief)
    garland = _garland_prototype(0.9 * s, 0.35 * fh, 1.6 * relief)  # a fat swag
    pos, xs, idx = [], [], []
    for _, nrm, along, off, half in _side_frames(lv["xe"], lv["ze"]):
        # candelabra at k·s from the centre of the side, garlands between them
        n = int(math.floor(half / s))
        tc = np.arange(-n, n + 1) * s if (half - n * s) > 0.25 * s else np.arange(-n + 1, n) * s
        tg = 0.5 * (tc[1:] + tc[:-1])
        for proto_i, ts, y in (
            (0, tc, lv["y_frieze"] + 0.1 * fh),
            (1, tg, lv["y_frieze"] + 0.8 * fh),
        ):
            p = ts[:, None] * along + (off * nrm + y * _UP)[None]
            pos.append(p)
            xs.append(np.tile(along, (len(ts), 1)))
            idx.append(np.full(len(ts), proto_i))
    pos_a = np.concatenate(pos)
    n = len(pos_a)
    return Instances(
        "FriezeGarlands",
        (cand, garland),
        np.concatenate(idx),
        pos_a,
        frames_to_quaternions(np.concatenate(xs), np.tile(_UP, (n, 1))),
        np.ones((n, 3)),
    )
