"""Porticoes as stoas: column axes, bays and corners of a colonnade, and their solids.

A porticus line (or each side of a street, or a precinct's ring) is split into straight
runs at its vertices; each run of length ``L`` holds ``round(L / spacing)`` equal bays, so a
column stands on every vertex (a precinct's corners) and the bays tile the line. Every
column faces the street; the stoa lies behind it (away from the street): an entablature
on the column axes, a lean-to roof from the entablature up to a back wall ``depth`` behind.

Frames. A **bay** is authored once, in a frame with its run along local ``+X`` from 0 to 1
(the instancer scales ``X`` to the bay's length), the street towards ``+Z`` and ``Y`` up;
placed like the columns (``yaw`` about ``Y``: local ``+Z`` → ``(sin yaw, cos yaw)`` in USD
``x, z``). A **corner** (where the backs of two runs part: the outside of a precinct) has
its origin on the corner column, local ``+X`` along the run that ends there; it fills the
wedge between the two runs' ends: the entablature's missing quarter, a roof whose two
halves each slope like their run (they meet in a valley on the bisector) and the back walls
mitred. Corners whose backs meet (inside a bend) get no piece; there the two runs' bays
overlap, and the city keeps the first (:func:`ionic_usd.pipeline.city_extras.lay_stoas`).

Dimensions (Vitruvius; :class:`StoaDims`): the architrave is ``H / 12`` (III.5.8, columns
of 25–30 ft), the plain frieze ¾ of it and the cornice as high as the architrave, projecting
its height (III.5.10–11, as in ``portunus.toml``); the roof's pitch, slab, eave, bed and
the wall are assumptions (stated in :class:`StoaDims`).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ionic_usd.city.plan import Porticus
from ionic_usd.errors import ParameterError
from ionic_usd.geometry import libm
from ionic_usd.geometry.mesh import Mesh

__all__ = [
    "StoaDims",
    "StoaLayout",
    "bay_parts",
    "corner_parts",
    "porticus_stoa",
    "prism",
]


@dataclass(frozen=True)
class StoaDims:
    """A stoa's section (metres): the column's height and diameters, and the stoa's depth
    (column axis to the back wall's inner face)."""

    height: float
    lower_diameter: float
    upper_diameter: float
    depth: float = 6.0
    wall: float = 0.6  # (!) back wall thickness
    pitch_deg: float = 15.0  # (!) a lean-to of tiles: 15°, the roof-pitch-15 hypothesis
    slab: float = 0.3  # (!) roof slab (tiles on rafters)
    eave: float = 0.4  # (!) the roof's overhang beyond the back wall
    bed: float = 0.05  # the roof's bed on the cornice (layout.ROOF_BED)

    @property
    def architrave(self) -> float:
        return self.height / 12.0

    @property
    def frieze(self) -> float:
        return 0.75 * self.architrave

    @property
    def cornice(self) -> float:
        return self.architrave

    @property
    def beam(self) -> float:
        """Half-width of architrave and frieze: the column's upper radius."""
        return self.upper_diameter / 2

    @property
    def front(self) -> float:
        """Half-width of the cornice (it projects by its height)."""
        return self.beam + self.cornice

    @property
    def top(self) -> float:
        """Height of the entablature's top (the cornice's)."""
        return self.height + self.architrave + self.frieze + self.cornice

    @property
    def back(self) -> float:
        """Distance behind the column axis of the roof's back edge."""
        return self.depth + self.wall + self.eave

    def soffit(self, b: np.ndarray) -> np.ndarray:
        """Height of the roof's underside at distance ``b`` behind the column axis."""
        tan = math.tan(math.radians(self.pitch_deg))
        return self.top + self.bed + (np.asarray(b, dtype=float) + self.front) * tan


def prism(
    poly: np.ndarray,
    bottom: Callable[[np.ndarray], np.ndarray],
    top: Callable[[np.ndarray], np.ndarray],
    name: str,
) -> Mesh:
    """A closed solid over a convex plan polygon ``poly`` ((n, 2) local ``X, Z``,
    counter-clockwise seen from above, i.e. from ``+Y``) between two planes given as
    heights ``bottom(poly)`` and ``top(poly)`` ((n,) each; top above bottom everywhere)."""
    poly = np.asarray(poly, dtype=float)
    n = len(poly)
    yb, yt = bottom(poly), top(poly)
    if not np.all(yt > yb):
        raise ParameterError("stoa", name, "a solid with its top above its bottom")
    pts = np.concatenate(
        [
            np.column_stack([poly[:, 0], yb, poly[:, 1]]),
            np.column_stack([poly[:, 0], yt, poly[:, 1]]),
        ]
    )
    # USD's faces are counter-clockwise seen from outside (right-handed). A polygon
    # counter-clockwise in (X, Z) has its right-hand normal along -Y: the bottom as it is,
    # the top reversed, and each side (i, top i, top j, j)
    faces = [list(range(n)), list(range(2 * n - 1, n - 1, -1))]
    for i in range(n):
        j = (i + 1) % n
        faces.append([i, n + i, n + j, j])
    counts = np.array([len(f) for f in faces], dtype=np.int32)
    return Mesh(pts, counts, np.concatenate(faces).astype(np.int32), name=name)


def _ccw(poly: np.ndarray) -> np.ndarray:
    """The polygon ordered counter-clockwise in the (X, Z) plane's own orientation."""
    x, z = poly[:, 0], poly[:, 1]
    area = 0.5 * np.sum(x * np.roll(z, -1) - np.roll(x, -1) * z)
    return poly if area > 0 else poly[::-1]


def _flat(h: float) -> Callable[[np.ndarray], np.ndarray]:
    return lambda p: np.full(len(p), h)


def bay_parts(d: StoaDims) -> list[Mesh]:
    """The unit bay's solids (see the module docstring): architrave with frieze, cornice, the
    roof's bed over the cornice, the roof and the back wall."""

    def rect(z0: float, z1: float) -> np.ndarray:
        return _ccw(np.array([[0.0, z0], [1.0, z0], [1.0, z1], [0.0, z1]]))

    def soffit(p: np.ndarray) -> np.ndarray:
        return d.soffit(-p[:, 1])

    def roof_top(p: np.ndarray) -> np.ndarray:
        return soffit(p) + d.slab

    y0, y1, y2 = d.height, d.height + d.architrave + d.frieze, d.top
    return [
        prism(rect(-d.beam, d.beam), _flat(y0), _flat(y1), "Beam"),
        prism(rect(-d.front, d.front), _flat(y1), _flat(y2), "Cornice"),
        prism(rect(-d.front, d.front), _flat(y2), soffit, "RoofBed"),
        prism(rect(-d.back, d.front), soffit, roof_top, "Roof"),
        prism(rect(-(d.depth + d.wall), -d.depth), _flat(0.0), soffit, "Wall"),
    ]


def corner_parts(d: StoaDims, n_b: np.ndarray) -> list[Mesh]:
    """The solids of a corner whose second run's back normal is ``n_b`` (local ``X, Z``; the
    first run's is ``(0, −1)``; ``n_b`` has ``X > 0``: the backs part)."""
    n_a = np.array([0.0, -1.0])
    n_b = np.asarray(n_b, dtype=float)
    mitre = (n_a + n_b) / (1.0 + float(n_a @ n_b))  # on the bisector, 1 from each run's axis
    o = np.zeros(2)

    def height(n: np.ndarray, extra: float = 0.0) -> Callable[[np.ndarray], np.ndarray]:
        return lambda p: d.soffit(p @ n) + extra

    y0, y1, y2 = d.height, d.height + d.architrave + d.frieze, d.top
    out = [
        prism(
            _ccw(np.array([o, d.beam * n_b, d.beam * mitre, d.beam * n_a])),
            _flat(y0),
            _flat(y1),
            "CornerBeam",
        ),
        prism(
            _ccw(np.array([o, d.front * n_b, d.front * mitre, d.front * n_a])),
            _flat(y1),
            _flat(y2),
            "CornerCornice",
        ),
    ]
    for side, n in (("A", n_a), ("B", n_b)):
        out.append(
            prism(
                _ccw(np.array([o, d.front * n, d.front * mitre])),
                _flat(y2),
                height(n),
                f"CornerRoofBed{side}",
            )
        )
        out.append(
            prism(
                _ccw(np.array([o, d.back * n, d.back * mitre])),
                height(n),
                height(n, d.slab),
                f"CornerRoof{side}",
            )
        )
        w0, w1 = d.depth, d.depth + d.wall
        out.append(
            prism(
                _ccw(np.array([w0 * n, w1 * n, w1 * mitre, w0 * mitre])),
                _flat(0.0),
                height(n),
                f"CornerWall{side}",
            )
        )
    return out


@dataclass(frozen=True)
class StoaLayout:
    """A city's colonnades as arrays (USD ``x, z``; yaw in degrees about ``Y``).

    column_xz (m, 2), column_yaw (m,); bay_xz (b, 2) — each bay's start (local origin),
    bay_yaw (b,), bay_length (b,), bay_columns (b, 2) — the indices of its two columns;
    corner_xz (c, 2), corner_yaw (c,), corner_turn (c,) — the angle (degrees) between the
    two runs' back normals, corner_normal (c, 2) — the second run's back normal in the
    corner's frame (local X, Z: :func:`corner_parts`)."""

    column_xz: np.ndarray
    column_yaw: np.ndarray
    bay_xz: np.ndarray
    bay_yaw: np.ndarray
    bay_length: np.ndarray
    bay_columns: np.ndarray
    corner_xz: np.ndarray
    corner_yaw: np.ndarray
    corner_turn: np.ndarray
    corner_normal: np.ndarray


def _lines(p: Porticus) -> list[tuple[np.ndarray, float, bool]]:
    """The porticus' column lines: (plan points (n, 2), facing sign, closed)."""
    import shapely

    if p.sides == 1:
        return [(np.asarray(p.line, dtype=float), 0.0, p.closed)]
    geom = shapely.LinearRing(p.line) if p.closed else shapely.LineString(p.line)
    out = []
    for sign in (1.0, -1.0):
        off = shapely.offset_curve(geom, sign * p.offset, join_style="mitre")
        for part in shapely.get_parts(off):
            c = np.asarray(shapely.get_coordinates(part), dtype=float)
            closed = p.closed and len(c) > 2
            if closed and np.array_equal(c[0], c[-1]):
                c = c[:-1]
            out.append((c, sign, closed))
    return out


def _yaw(normal: np.ndarray) -> np.ndarray:
    """Yaw (degrees) turning local +Z to the plan direction ``normal`` (n, 2)."""
    return (180.0 - np.degrees(libm.arctan2(normal[:, 0], normal[:, 1]))) % 360.0


def porticus_stoa(p: Porticus, spacing: float) -> StoaLayout:
    """The columns, bays and corners of a porticus (see the module docstring)."""
    spacing = p.spacing or spacing
    if not (math.isfinite(spacing) and spacing > 0):
        raise ParameterError("spacing", spacing, "a length > 0 (m)", context=f"porticus {p.id}")
    cols: list[np.ndarray] = []
    cyaw: list[np.ndarray] = []
    bays: list[tuple] = []
    corners: list[tuple] = []
    base = 0
    for pts, sign, closed in _lines(p):
        seg_pts = np.vstack([pts, pts[:1]]) if closed else pts
        seg = np.diff(seg_pts, axis=0)
        length = np.hypot(seg[:, 0], seg[:, 1])
        keep = length > 1e-9
        starts, seg, length = seg_pts[:-1][keep], seg[keep], length[keep]
        if not len(seg):
            continue
        tangent = seg / length[:, None]
        # the street side: for the left side (sign > 0) that is the right normal
        normal = np.stack([tangent[:, 1], -tangent[:, 0]], axis=1) * (sign if sign else 1.0)
        nbay = np.maximum(1, np.rint(length / spacing).astype(int))
        line_cols: list[np.ndarray] = []
        line_yaw: list[np.ndarray] = []
        first: list[int] = []
        for k in range(len(seg)):
            t = np.arange(nbay[k]) / nbay[k]
            first.append(base + int(sum(len(c) for c in line_cols)))
            line_cols.append(starts[k] + t[:, None] * seg[k])
            line_yaw.append(np.full(nbay[k], _yaw(normal[k : k + 1])[0]))
        if not closed:  # the line's last column
            line_cols.append(seg_pts[-1:])
            line_yaw.append(line_yaw[-1][:1])
        pts_all = np.concatenate(line_cols)
        n_line = len(pts_all)
        for k in range(len(seg)):
            y = float(line_yaw[k][0])
            yaw_r = math.radians(y)
            u = np.array([math.cos(yaw_r), math.sin(yaw_r)])  # local +X in plan (e, n)
            forward = float(u @ tangent[k]) > 0
            for i in range(nbay[k]):
                a = first[k] + i
                b = a + 1 if a + 1 < base + n_line else base  # a ring's last bay closes it
                s = starts[k] + (i if forward else i + 1) / nbay[k] * seg[k]
                bays.append((s, y, length[k] / nbay[k], a, b))
        # corners: interior vertices (every vertex of a ring)
        for k in range(len(seg)) if closed else range(1, len(seg)):
            j = k - 1 if k else len(seg) - 1
            corners += _corner(starts[k], tangent[j], normal[j], tangent[k], normal[k])
        cols.append(pts_all)
        cyaw.append(np.concatenate(line_yaw))
        base += n_line
    return _as_arrays(cols, cyaw, bays, corners)


def _corner(v, t_in, n_in, t_out, n_out) -> list[tuple]:
    """A corner piece at vertex ``v`` (plan) if the backs of the two runs part there."""
    back_in, back_out = -n_in, -n_out
    if float(back_out @ t_in) <= 1e-6:  # straight on, or the backs meet: no gap
        return []
    # the frame of the run whose local +X runs into v: the incoming run if it runs along
    # +X (its street on +Z), else the outgoing run taken backwards
    ex, back_a, back_b = t_in, back_in, back_out
    street = -back_a
    if ex[0] * street[1] - ex[1] * street[0] > 0:  # +X × +Z must point down in plan terms
        ex, back_a, back_b = -t_out, back_out, back_in
        street = -back_a
    yaw = float(_yaw(street[None, :])[0])
    # back_b in local (X, Z): X along ex, Z along the street (-back_a)
    nb_local = np.array([float(back_b @ ex), float(back_b @ street)])
    turn = math.degrees(math.acos(max(-1.0, min(1.0, float(back_a @ back_b)))))
    return [(np.asarray(v, dtype=float), yaw, turn, nb_local)]


def _as_arrays(cols, cyaw, bays, corners) -> StoaLayout:
    def plan_to_usd(a: np.ndarray) -> np.ndarray:
        a = np.asarray(a, dtype=float).reshape(-1, 2)
        return np.stack([a[:, 0], -a[:, 1]], axis=1)

    return StoaLayout(
        plan_to_usd(np.concatenate(cols)) if cols else np.zeros((0, 2)),
        np.concatenate(cyaw) if cyaw else np.zeros(0),
        plan_to_usd(np.array([b[0] for b in bays])) if bays else np.zeros((0, 2)),
        np.array([b[1] for b in bays], dtype=float),
        np.array([b[2] for b in bays], dtype=float),
        np.array([[b[3], b[4]] for b in bays], dtype=np.int64).reshape(-1, 2),
        plan_to_usd(np.array([c[0] for c in corners])) if corners else np.zeros((0, 2)),
        np.array([c[1] for c in corners], dtype=float),
        np.array([c[2] for c in corners], dtype=float),
        np.array([c[3] for c in corners], dtype=float).reshape(-1, 2),
    )
