"""City plans: lots and porticoes, from a GeoJSON survey plan or a regular grid.

Coordinates
-----------
A plan is in **metres in a local projected frame** (a site grid, or any projected CRS in metres
— a UTM zone, a national grid — translated near the site so that coordinates stay small):
GeoJSON ``[x, y]`` = (easting, northing). Geographic coordinates (degrees: ``EPSG:4326``,
``OGC:CRS84``) are refused — project the plan first. In USD (Y up) easting becomes ``+x`` and
northing ``-z``, so north is ``-Z`` and the plan reads the right way round from above.

Features (``properties``)
-------------------------
Polygon, ``type = "temple"``
    ``temple`` (a built-in description — ``ionic-usd presets`` lists them: ``"portunus"``,
    ``"priene"``, … —, ``"auto"`` (the city chooses, as for a lot that names nothing), or a
    temple TOML path relative to the plan) or ``preset`` (a built-in description by name) or a
    type: ``arrangement``, ``front`` (4, 6, 8), ``intercolumniation`` (pycnostyle …
    araeostyle), ``lower_diameter`` (m) — each optional; what the lot leaves open the city
    chooses, seeded, to fit the lot (:mod:`ionic_usd.city.choose`); ``orientation`` (azimuth
    of the front in degrees clockwise from north; default: along the lot's long axis, the
    front towards the plan's centre), ``hypotheses`` (``{id: "baseline" | "alternative"}``;
    unnamed ones are drawn per lot, seeded, unless the city is built with variety off),
    ``column`` (``{"height": m, "lower_diameter": m}``), ``scale`` (``[min, max]``: the
    uniform scales the temple may take to fit its lot), ``id``.
LineString / MultiLineString, ``type = "porticus"``
    a colonnade along the street: ``spacing`` (m between column axes), ``sides`` (1: on the line,
    the columns facing to its right as drawn; 2: on both sides of it, facing the street),
    ``offset`` (m from the line to each side's column axes).
Polygon, ``type = "porticus"``
    a colonnaded square: columns along its outline (``spacing``), facing in when the ring is
    drawn clockwise.
Polygon, ``type = "plaza"``
    open ground: paved in its own stone (:mod:`ionic_usd.city.ground`).

Only the standard library reads the file; shapely is used later, for geometry.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ionic_usd.errors import ParameterError

__all__ = [
    "Lot",
    "Porticus",
    "CityPlan",
    "read_geojson",
    "grid_plan",
    "FEATURE_TYPES",
    "GEOGRAPHIC_CRS",
]

FEATURE_TYPES = ("temple", "porticus", "plaza")
GEOGRAPHIC_CRS = ("EPSG:4326", "OGC:CRS84", "CRS84", "EPSG:4258", "EPSG:4269", "EPSG:4979")
_HYP_CHOICES = ("baseline", "alternative")
#: how far behind its column axes a stoa reaches (depth 6 m + wall 0.6 m + eave 0.4 m: the
#: defaults of :class:`ionic_usd.city.stoa.StoaDims`)
STOA_BACK = 7.0


@dataclass(frozen=True)
class Lot:
    """A building lot.

    Attributes
    ----------
    id : feature id (names the prim and error messages)
    outline : (n, 2) float — the exterior ring in plan metres (easting, northing), not closed
    temple : built-in description name or a TOML path, or None (``choice`` decides)
    choice : the lot's preset or type keys (``preset``, ``arrangement``, ``front``,
        ``intercolumniation``, ``lower_diameter``); what it leaves open the city chooses
    orientation : azimuth of the front (degrees clockwise from north) or None (automatic)
    hypotheses : id → "baseline" | "alternative" chosen in the plan (others drawn per lot)
    column : column overrides, e.g. ``{"height": 8.0, "lower_diameter": 0.9}``
    scale : (min, max) uniform scales allowed to fit the lot, or None (the city's default)
    """

    id: str
    outline: np.ndarray
    temple: str | None = None
    orientation: float | None = None
    hypotheses: Mapping[str, str] = field(default_factory=dict)
    column: Mapping[str, float] = field(default_factory=dict)
    scale: tuple[float, float] | None = None
    choice: Mapping[str, object] = field(default_factory=dict)


@dataclass(frozen=True)
class Porticus:
    """A colonnade: column axes along ``line`` (open) or around it (``closed``).

    Attributes
    ----------
    id : feature id
    line : (n, 2) float — plan metres
    spacing : axial spacing (m); None → the city's default
    sides : 1 (on the line) or 2 (both sides, ``offset`` away)
    offset : distance of each side from the line (m)
    closed : the line is a polygon's outline
    """

    id: str
    line: np.ndarray
    spacing: float | None = None
    sides: int = 1
    offset: float = 4.0
    closed: bool = False


@dataclass(frozen=True)
class CityPlan:
    """Lots and porticoes of a city, plus where the plan came from (for messages)."""

    lots: tuple[Lot, ...]
    porticoes: tuple[Porticus, ...]
    source: str = "grid"
    base_dir: Path | None = None
    plazas: tuple[np.ndarray, ...] = ()  # open areas' outlines (plan metres), paved apart


#: largest plan coordinate (m): a local frame near the site (a UTM northing is below 1e7);
#: beyond it float32 USD positions lose whole metres and GEOS's arithmetic overflows
MAX_COORDINATE = 1e7
#: largest length of a feature's property (spacing, offset, column size), m
MAX_LENGTH = 1e4


def _num(
    value: object, name: str, ctx: str, *, positive: bool = False, limit: float = MAX_LENGTH
) -> float:
    if (
        not isinstance(value, (int, float))
        or isinstance(value, bool)
        or not math.isfinite(value)
        or (positive and value <= 0)
        or abs(value) > limit
    ):
        raise ParameterError(
            name,
            value,
            "a finite number" + (" > 0" if positive else "") + f" of magnitude <= {limit:g}",
            context=ctx,
        )
    return float(value)


def _ring(coords: object, ctx: str, *, closed: bool) -> np.ndarray:
    if not isinstance(coords, list) or not coords:
        raise ParameterError("coordinates", coords, "a list of [x, y] positions", context=ctx)
    pts = []
    for i, c in enumerate(coords):
        if not isinstance(c, list) or len(c) < 2:
            raise ParameterError(f"coordinates[{i}]", c, "[x, y] in metres", context=ctx)
        pts.append(
            [
                _num(c[0], f"coordinates[{i}][0]", ctx, limit=MAX_COORDINATE),
                _num(c[1], f"coordinates[{i}][1]", ctx, limit=MAX_COORDINATE),
            ]
        )
    a = np.asarray(pts, dtype=float)
    if closed and len(a) > 1 and np.array_equal(a[0], a[-1]):
        a = a[:-1]
    need = 3 if closed else 2
    if len(a) < need:
        raise ParameterError(
            "coordinates", len(a), f"at least {need} distinct positions", context=ctx
        )
    return a


def _check_crs(doc: Mapping[str, Any], where: str) -> None:
    crs = doc.get("crs")
    if crs is None:
        return
    name = crs.get("properties", {}).get("name", "") if isinstance(crs, dict) else crs
    text = str(name).upper()
    if any(g.upper() in text for g in GEOGRAPHIC_CRS):
        raise ParameterError(
            "crs",
            str(name),
            "metres in a local projected frame (the plan is "
            "in geographic degrees: project it first)",
            context=where,
        )


def _lot(fid: str, geom: Mapping, props: Mapping, ctx: str) -> Lot:
    if geom.get("type") != "Polygon":
        raise ParameterError("geometry.type", geom.get("type"), "Polygon for a temple", context=ctx)
    outline = _ring((geom.get("coordinates") or [None])[0], ctx, closed=True)
    orient = props.get("orientation")
    if orient is not None:
        orient = _num(orient, "orientation", ctx, limit=1e6) % 360.0
    hyps = props.get("hypotheses", {})
    if not isinstance(hyps, dict) or any(v not in _HYP_CHOICES for v in hyps.values()):
        raise ParameterError(
            "hypotheses", hyps, 'an object {id: "baseline" | "alternative"}', context=ctx
        )
    column = props.get("column", {})
    if not isinstance(column, dict) or set(column) - {"height", "lower_diameter"}:
        raise ParameterError(
            "column", column, "an object with height and/or lower_diameter (m)", context=ctx
        )
    column = {k: _num(v, f"column.{k}", ctx, positive=True) for k, v in column.items()}
    scale = props.get("scale")
    if scale is not None:
        if not (isinstance(scale, list) and len(scale) == 2):
            raise ParameterError("scale", scale, "[min, max]", context=ctx)
        lo, hi = (_num(s, "scale", ctx, positive=True) for s in scale)
        if lo > hi:
            raise ParameterError("scale", scale, "[min, max] with min <= max", context=ctx)
        scale = (lo, hi)
    temple = props.get("temple")
    if temple is not None and (not isinstance(temple, str) or not temple):
        raise ParameterError("temple", temple, "a description name or TOML path", context=ctx)
    return Lot(fid, outline, temple, orient, dict(hyps), column, scale, _choice(props, ctx))


def _choice(props: Mapping, ctx: str) -> dict[str, object]:
    """The lot's preset or type keys, checked for their types (their values are checked by
    :mod:`ionic_usd.city.choose`)."""
    out: dict[str, object] = {}
    for key in ("preset", "arrangement", "intercolumniation"):
        if key in props:
            v = props[key]
            if not isinstance(v, str) or not v:
                raise ParameterError(key, v, "a name", context=ctx)
            out[key] = v
    if "front" in props:
        v = props["front"]
        if isinstance(v, bool) or v not in (4, 6, 8):
            raise ParameterError("front", v, "4, 6 or 8 columns", context=ctx)
        out["front"] = int(v)
    if "lower_diameter" in props:
        out["lower_diameter"] = _num(props["lower_diameter"], "lower_diameter", ctx, positive=True)
    if "preset" in out and (len(out) > 1 or props.get("temple") is not None):
        raise ParameterError(
            "preset", out["preset"], "alone (not with temple or type keys)", context=ctx
        )
    return out


def _porticoes(fid: str, geom: Mapping, props: Mapping, ctx: str) -> list[Porticus]:
    spacing = props.get("spacing")
    if spacing is not None:
        spacing = _num(spacing, "spacing", ctx, positive=True)
    sides = props.get("sides", 1)
    if sides not in (1, 2):
        raise ParameterError("sides", sides, "1 or 2", context=ctx)
    offset = _num(props.get("offset", 4.0), "offset", ctx, positive=True)
    kind = geom.get("type")
    coords = geom.get("coordinates")
    if kind == "LineString":
        lines, closed = [coords], False
    elif kind == "MultiLineString" and isinstance(coords, list):
        lines, closed = coords, False
    elif kind == "Polygon" and isinstance(coords, list) and coords:
        lines, closed = [coords[0]], True
    else:
        raise ParameterError(
            "geometry.type",
            kind,
            "LineString, MultiLineString or Polygon for a porticus",
            context=ctx,
        )
    out = []
    for k, line in enumerate(lines):
        name = fid if len(lines) == 1 else f"{fid}_{k}"
        out.append(
            Porticus(name, _ring(line, ctx, closed=closed), spacing, int(sides), offset, closed)
        )
    return out


def read_geojson(path: str | os.PathLike) -> CityPlan:
    """Read a plan (a GeoJSON FeatureCollection in metres; see the module docstring).

    Errors name the file and the feature (index and id).
    """
    p = Path(path)
    where = str(p)
    try:
        doc = json.loads(p.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise ParameterError("--plan", where, "an existing GeoJSON file") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise ParameterError("--plan", where, f"a readable UTF-8 file ({exc})") from None
    except json.JSONDecodeError as exc:
        raise ParameterError(
            "--plan", where, f"valid JSON (line {exc.lineno}, column {exc.colno}: {exc.msg})"
        ) from None
    if not isinstance(doc, dict) or doc.get("type") != "FeatureCollection":
        raise ParameterError(
            "type",
            doc.get("type") if isinstance(doc, dict) else doc,
            "a GeoJSON FeatureCollection",
            context=where,
        )
    _check_crs(doc, where)
    feats = doc.get("features")
    if not isinstance(feats, list):
        raise ParameterError("features", feats, "a list of features", context=where)
    lots: list[Lot] = []
    porticoes: list[Porticus] = []
    plazas: list[np.ndarray] = []
    seen: set[str] = set()
    for i, f in enumerate(feats):
        if not isinstance(f, dict) or not isinstance(f.get("geometry"), dict):
            raise ParameterError(f"features[{i}]", f, "a Feature with a geometry", context=where)
        props = f.get("properties") or {}
        if not isinstance(props, dict):
            raise ParameterError(f"features[{i}].properties", props, "an object", context=where)
        fid = str(props.get("id", f.get("id", f"feature{i}")))
        ctx = f"{where} features[{i}] ({fid})"
        if fid in seen:
            raise ParameterError("id", fid, "ids unique within the plan", context=ctx)
        seen.add(fid)
        kind = props.get("type")
        if kind not in FEATURE_TYPES:
            raise ParameterError("type", kind, f"one of {', '.join(FEATURE_TYPES)}", context=ctx)
        if kind == "temple":
            lots.append(_lot(fid, f["geometry"], props, ctx))
        elif kind == "porticus":
            porticoes += _porticoes(fid, f["geometry"], props, ctx)
        else:
            geom = f["geometry"]
            if geom.get("type") != "Polygon":
                raise ParameterError(
                    "geometry.type", geom.get("type"), "Polygon for a plaza", context=ctx
                )
            plazas.append(_ring((geom.get("coordinates") or [None])[0], ctx, closed=True))
    if not lots and not porticoes:
        raise ParameterError(
            "features", len(feats), "at least one temple or porticus", context=where
        )
    return CityPlan(
        tuple(lots), tuple(porticoes), source=where, base_dir=p.parent, plazas=tuple(plazas)
    )


def grid_plan(
    rows: int = 5, cols: int = 5, block: float = 60.0, *, street: float = 8.0, spacing: float = 3.0
) -> CityPlan:
    """The default city: ``rows × cols`` square lots, fronts facing south, temples at their
    own size (scale 1), with a colonnade on both sides of every street running east–west
    between the rows.

    Lot (i, j) is centred at easting ``j·block``, northing ``i·block``; each lot is the block
    minus the street and the stoas behind its colonnades (``block − street − 2·STOA_BACK``
    square; at most half of what the street leaves).
    """
    for name, n in (("--rows", rows), ("--cols", cols)):
        if isinstance(n, bool) or not isinstance(n, int) or n < 1:
            raise ParameterError(name, n, "an integer >= 1")
    for name, v in (("--block", block), ("street", street), ("--column-spacing", spacing)):
        _num(v, name, "grid", positive=True)
    if street >= block:
        raise ParameterError("block", block, f"more than the street width ({street} m)")
    h = (block - street) / 2
    h -= min(STOA_BACK, h / 2)  # room for the stoas behind the street's columns
    lots = []
    for i in range(rows):
        for j in range(cols):
            cx, cy = j * block, i * block
            ring = np.array(
                [[cx - h, cy - h], [cx + h, cy - h], [cx + h, cy + h], [cx - h, cy + h]]
            )
            lots.append(Lot(f"{i}_{j}", ring, orientation=180.0, scale=(1.0, 1.0)))
    x0, x1 = -block / 2, (cols - 0.5) * block
    ys = [(i + 0.5) * block for i in range(rows - 1)] or [-block / 2]
    porticoes = tuple(
        Porticus(f"Street_{k}", np.array([[x0, y], [x1, y]]), spacing, 2, street / 2)
        for k, y in enumerate(ys)
    )
    return CityPlan(tuple(lots), porticoes)
