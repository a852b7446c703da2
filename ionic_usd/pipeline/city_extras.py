"""The city's stoas and ground: laid out from the plan, written beside the instances.

:func:`lay_stoas` (step 2 of the city build) turns every porticus into columns, bays and
corners (:func:`ionic_usd.city.stoa.porticus_stoa`) and keeps what stands clear: bays and
corners overlapping no temple lot and no stoa part kept before them, and the columns that
carry a kept bay. :func:`write_stoas_and_ground` (step 5, once the temple builds are in the
city: their maps texture the stoas and the ground) writes ``Stoas/Stoa.usda`` and
``Ground.usda`` and returns what :func:`ionic_usd.usd.city.compose_city` places.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ionic_usd.city.ground import ground_meshes
from ionic_usd.city.layout import drop_inside
from ionic_usd.city.plan import CityPlan
from ionic_usd.city.stoa import StoaDims, StoaLayout, porticus_stoa
from ionic_usd.pipeline.spec import TempleSpec

__all__ = ["StoaPlan", "lay_stoas", "street_column_spec", "write_stoas_and_ground"]

STOA_ASSET = "Stoas/Stoa.usda"
GROUND_ASSET = "Ground.usda"
_TURN_DIGITS = 6  # corner prototypes: one per distinct back normal, rounded


@dataclass(frozen=True)
class StoaPlan:
    """Step 2's colonnades: the columns kept (USD x, z; yaw), the bays (start, yaw, length)
    and corners (position, yaw, second back normal in the corner's frame) kept."""

    column_xz: np.ndarray
    column_yaw: np.ndarray
    bay_xz: np.ndarray
    bay_yaw: np.ndarray
    bay_length: np.ndarray
    corner_xz: np.ndarray
    corner_yaw: np.ndarray
    corner_normal: np.ndarray
    dropped: int


def street_column_spec(specs: list[TempleSpec]) -> TempleSpec:
    """The build whose column lines the streets: the slenderest module (a stoa's columns are
    smaller than a temple's), ties by name, then description and options: never by the key,
    which holds the code's digest (a tie broken by it chose another temple's column, with
    other triangles, after any edit of the code)."""
    return min(
        specs,
        key=lambda s: (
            s.layout().params.columns_lower_diameter,
            s.name,
            s.description,
            s.texture_size,
            s.seed,
        ),
    )


def _bay_polygons(lay: StoaLayout, depth: float) -> list[np.ndarray]:
    """Each bay's plan footprint (column line to the stoa's back)."""
    out = []
    for (x, z), yaw, ln in zip(lay.bay_xz, lay.bay_yaw, lay.bay_length, strict=True):
        a = np.radians(yaw)
        u = np.array([np.cos(a), -np.sin(a)])  # local +X in USD x, z
        f = np.array([np.sin(a), np.cos(a)])  # local +Z
        o = np.array([x, z])
        quad = np.array([o, o + ln * u, o + ln * u - depth * f, o - depth * f])
        out.append(np.stack([quad[:, 0], -quad[:, 1]], axis=1))
    return out


def _corner_polygon(xz: np.ndarray, yaw: float, nb_local: np.ndarray, back: float) -> np.ndarray:
    """A corner piece's plan footprint: the rhombus between its two runs' backs, ``back`` m
    deep (the wedge it fills; a square at a right-angled corner)."""
    a = np.radians(yaw)
    ex = np.array([np.cos(a), -np.sin(a)])  # local +X in USD x, z
    street = np.array([np.sin(a), np.cos(a)])  # local +Z
    back_a = -street
    back_b = nb_local[0] * ex + nb_local[1] * street
    o = np.asarray(xz, dtype=float)
    quad = np.array([o, o + back * back_a, o + back * (back_a + back_b), o + back * back_b])
    return np.stack([quad[:, 0], -quad[:, 1]], axis=1)


_OVERLAP_M2 = 1e-3  # parts that share an edge touch (area ~0); more than this overlaps


def lay_stoas(
    plan: CityPlan, spacing: float, footprints: list[np.ndarray], dims_back: float
) -> StoaPlan:
    """Columns, bays and corners of every porticus, clear of the temples and of each other.

    A bay or corner is kept when its plan footprint (column line to the stoa's back) overlaps
    no temple lot or footprint and no bay or corner kept before it, in the plan's order (list
    the main streets first): where two stoas would interpenetrate (back to back, at a
    crossing, inside a bend) the later one leaves a gap instead. A column is kept when it
    carries a kept bay (and stands clear of the temples), so no column stands carrying
    nothing; ``dropped`` counts the columns left out.
    """
    import shapely

    lays = [porticus_stoa(p, spacing) for p in plan.porticoes]
    cols = [lay.column_xz for lay in lays]
    cxz = np.concatenate(cols) if cols else np.zeros((0, 2))
    cyaw = np.concatenate([lay.column_yaw for lay in lays]) if lays else np.zeros(0)
    clear = drop_inside(cxz, footprints)
    # every candidate part, in the order decided (each porticus' bays, then its corners),
    # then what no part may overlap (the temples' footprints and lots), in one index
    parts: list[tuple] = []  # (porticus, "bay" or "corner", item, first column index)
    geoms = []
    base = 0
    for n, lay in enumerate(lays):
        for i, quad in enumerate(_bay_polygons(lay, dims_back)):
            parts.append((n, "bay", i, base))
            geoms.append(shapely.Polygon(quad))
        for k in range(len(lay.corner_xz)):
            quad = _corner_polygon(
                lay.corner_xz[k], lay.corner_yaw[k], lay.corner_normal[k], dims_back
            )
            parts.append((n, "corner", k, base))
            geoms.append(shapely.Polygon(quad))
        base += len(lay.column_xz)
    geoms += [shapely.Polygon(f) for f in footprints]
    geoms += [shapely.Polygon(lot.outline) for lot in plan.lots]
    tree = shapely.STRtree(geoms)
    kept = np.zeros(len(parts), dtype=bool)
    carries = np.zeros(len(cxz), dtype=bool)
    bays: list[tuple] = []
    corners: list[tuple] = []
    for i, (n, kind, k, first) in enumerate(parts):
        lay = lays[n]
        if kind == "bay":
            a, b = lay.bay_columns[k] + first
            if not (clear[a] and clear[b]):
                continue
        hits = tree.query(geoms[i], predicate="intersects")
        if any(
            (j >= len(parts) or (j < i and kept[j]))
            and geoms[j].intersection(geoms[i]).area > _OVERLAP_M2
            for j in hits
        ):
            continue
        kept[i] = True
        if kind == "bay":
            bays.append((lay.bay_xz[k], lay.bay_yaw[k], lay.bay_length[k]))
            carries[[a, b]] = True
        else:
            corners.append((lay.corner_xz[k], lay.corner_yaw[k], lay.corner_normal[k]))
    keep = clear & carries
    return StoaPlan(
        cxz[keep],
        cyaw[keep],
        np.array([b[0] for b in bays]).reshape(-1, 2),
        np.array([b[1] for b in bays], dtype=float),
        np.array([b[2] for b in bays], dtype=float),
        np.array([c[0] for c in corners]).reshape(-1, 2),
        np.array([c[1] for c in corners], dtype=float),
        np.array([c[2] for c in corners]).reshape(-1, 2),
        int((~keep).sum()),
    )


def stoa_dims(spec: TempleSpec) -> StoaDims:
    """The stoa's section from its street column's build."""
    p = spec.layout().params
    d = p.columns_lower_diameter
    return StoaDims(p.columns_height, d, d * p.columns_upper_diameter_ratio)


def write_stoas_and_ground(
    out: Path,
    plan: CityPlan,
    stoas: StoaPlan,
    column_spec: TempleSpec,
    spacing: float,
    extent_points: np.ndarray,
):
    """Write the stoa asset and the ground (module docstring); returns ``(stoa, ground)``:
    ``stoa`` = (asset, prototype names, :class:`StoaInstances`, bounds, triangles per
    prototype) or None, ``ground`` = (asset, triangles, lo (3,), hi (3,))."""
    from ionic_usd.usd.stoa import StoaInstances, write_ground, write_stoa

    build = f"Temples/{column_spec.folder}"
    col_tex = f"{build}/IonicColumn/Payload/Textures"
    stoa = None
    if len(stoas.bay_xz) or len(stoas.corner_xz):
        normals = np.round(stoas.corner_normal, _TURN_DIGITS)
        uniq, corner_proto = (
            np.unique(normals, axis=0, return_inverse=True)
            if len(normals)
            else (np.zeros((0, 2)), np.zeros(0, dtype=int))
        )
        maps = {"Stucco": f"../{col_tex}/stucco_painted", "Roof": f"../{build}/Textures/terracotta"}
        stats = write_stoa(out / STOA_ASSET, stoa_dims(column_spec), list(uniq), maps, spacing)
        names = ["Bay"] + [f"Corner_{k}" for k in range(len(uniq))]
        inst = StoaInstances(
            np.concatenate([np.zeros(len(stoas.bay_xz), int), 1 + np.ravel(corner_proto)]),
            np.concatenate([stoas.bay_xz, stoas.corner_xz]).reshape(-1, 2),
            np.concatenate([stoas.bay_yaw, stoas.corner_yaw]),
            np.concatenate([stoas.bay_length, np.ones(len(stoas.corner_xz))]),
        )
        stoa = (
            f"./{STOA_ASSET}",
            names,
            inst,
            [(lo, hi) for lo, hi, _ in stats],
            [t for _, _, t in stats],
        )
    meshes = ground_meshes([lot.outline for lot in plan.lots], list(plan.plazas), extent_points)
    tex = f"./{col_tex}"
    maps = {
        "Paving": f"{tex}/travertine",
        "Plazas": f"{tex}/travertine",
        "Lots": f"{tex}/stucco_painted",
    }
    tris = write_ground(out / GROUND_ASSET, meshes, {m.name: maps[m.name] for m in meshes})
    pts = np.concatenate([m.points for m in meshes]) if meshes else np.zeros((1, 3))
    return stoa, (f"./{GROUND_ASSET}", tris, pts.min(axis=0), pts.max(axis=0))
