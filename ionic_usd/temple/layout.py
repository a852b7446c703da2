"""Temple layouts: cuboids by layer, column placements, reconstruction hypotheses.

:func:`portunus_layout` builds the Temple of Portunus (Rome, Forum Boarium; Ionic, tetrastyle,
pseudoperipteral on a high podium; SPEC §4) from ``ionic_usd/data/portunus.toml``, whose
comments cite every number. The same builder reads any TOML of that schema
(:func:`layout_from_toml`), so a user can lay out a similar temple.

Frame: metres, Y up, right-handed; the long axis is Z and the front (steps, porch) faces +Z;
the origin is the centre of the stylobate footprint at ground level (``x = 0`` on the long
axis, ``y = 0`` the ground, ``z = 0`` halfway along the stylobate). The stylobate (the top of
the podium, where the columns stand) is at ``y = podium.height``.

Derived geometry (documented here, tested in ``tests/test_layout.py``):

* Column axes form a rectangle with ``columns.front`` columns across and ``columns.side``
  down each flank (corners counted on both). One axial spacing ``s`` on front and flanks and
  one margin ``m`` from the stylobate edge to the outer axes on all four sides give
  ``(front − 1)·s + 2m = width`` and ``(side − 1)·s + 2m = length``, hence
  ``s = (length − width) / (side − front)`` and ``m = (width − (front − 1)·s) / 2``.
  Portunus: s = 8.80 / 3 = 2.933 m (3.09 lower diameters; clear intercolumniation 1.98 m =
  2.09 D, between Vitruvius' systyle 2 D and eustyle 2¼ D), m = 0.85 m.
* Rows are numbered k = 0 (front) … side − 1 (rear). Rows k < ``columns.porch_depth`` are the
  porch: the whole front row and, in the further porch rows, the two flank columns stand free.
  The cella's front wall face lies on row ``porch_depth``; from there back every flank column,
  and the whole rear row, stands on a wall: on a wall corner (the cella's two rear corners and
  the two front ends of the flank walls, where the front wall meets them) a three-quarter
  ``corner`` column, elsewhere an ``engaged`` half column, so no cut face is in view. Counting
  for Portunus (front 4, side 7, porch 2): free = 4 + 2·(2 − 1) = 6; corner = 4; engaged =
  2·3 on the flanks + 2 on the rear wall = 8.
* Engaged columns sit with their axis on the outer wall-face line (a half column stands
  proud of the wall). ``rotation_deg`` turns the column's local +Z (its capital's volute face)
  to ``(sin θ, 0, cos θ)``: 0 faces the front, ±90 the right/left flank, 180 the rear. Front-row
  and rear-row columns face front/rear, all other flank columns face outward sideways.
* Podium: a moulded footing (``podium.base_width`` wide; it projects
  ``(base_width − stylobate.width)/2`` on the flanks and the rear, and in front of the cheek
  walls) under a die as wide and long as the stylobate. The stairs run forward from the die
  between two cheek walls; the footing length gives the stair run:
  ``run = base_length − stylobate.length − 2·projection``. Steps are stacked slabs, step i
  (from the ground) ``y ∈ [i·r, (i+1)·r]``, ``z ∈ [front, front + (n − i)·t]``.
* Cella walls stand on the stylobate up to the architrave soffit (column height); the door
  follows Vitruvius IV.6.1.
* Entablature: architrave ``H / architrave_divisor``, frieze ``frieze_ratio ×`` architrave,
  cornice ``cornice_ratio ×`` architrave. Architrave and frieze cover the outer column axes
  plus half the upper diameter; the cornice projects by its own height (Vitruvius III.5.11).
* Roof: pitch ``atan(2 / tympanum_ratio)`` (Vitruvius III.5.12: tympanum height = cornice
  width / 9, so tan φ = (W/9)/(W/2) = 2/9, φ = 12.53°). Two sheared slabs (the paper's two
  inclined cuboids) run from the cornice edges up to the ridge at x = 0; under them two wedge
  cuboids as wide as the cornice and as long as the frieze fill the gable exactly (their tops
  meet the slab soffits, their bottoms sit on the cornice), so the front face of the wedge pair
  is the pediment, set back behind the cornice, and no void runs under the slabs. A cuboid
  cannot taper to nothing, so the slabs rest on a bed ``ROOF_BED`` thick at the eaves (the
  wedges' outer faces): the ridge is ``width / tympanum_ratio + ROOF_BED`` above the cornice.
"""

from __future__ import annotations

import math
import os
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, fields, replace
from enum import StrEnum
from importlib import resources
from pathlib import Path
from types import MappingProxyType
from typing import Any

import numpy as np

from ionic_usd.errors import ParameterError
from ionic_usd.params import load_toml, toml_value
from ionic_usd.temple.cuboid import Cuboid, Incline

__all__ = [
    "Layer",
    "ColumnKind",
    "Certainty",
    "ColumnPlacement",
    "Hypothesis",
    "TempleParams",
    "TempleLayout",
    "colonnade_positions",
    "cuboids_from_tables",
    "load_cuboids_toml",
    "cuboids_to_toml",
    "params_from_tables",
    "layout_from_mapping",
    "build_layout",
    "layout_from_toml",
    "portunus_layout",
    "PORTUNUS_TOML",
    "ROOF_BED",
    "COMPOSER_NAMESPACES",
]

PORTUNUS_TOML = "portunus.toml"
# hypothesis ``changes`` namespaces realised by the composer, not by the layout
COMPOSER_NAMESPACES = ("column", "material", "detail")


class Layer(StrEnum):
    """The composer's cuboid layers."""

    PODIUM = "podium"
    CELLA = "cella"
    ENTABLATURE = "entablature"
    ROOF = "roof"


class ColumnKind(StrEnum):
    """How a column meets the walls: ``free``; ``engaged`` (a half column, its local −Z half
    in a wall); ``corner`` (a three-quarter column at a wall corner, its local quadrant
    x < 0, z < 0 in the walls, so its outer faces are local +Z and +X)."""

    FREE = "free"
    ENGAGED = "engaged"
    CORNER = "corner"


class Certainty(StrEnum):
    HIGH = "high"
    MEDIUM = "medium"
    LOW = "low"


def _enum(cls, value: object, name: str, context: str):
    try:
        return cls(value)
    except ValueError:
        valid = ", ".join(repr(m.value) for m in cls)
        raise ParameterError(name, value, f"one of {valid}", context=context) from None


def _finite(name: str, value: object, context: str, *, positive: bool = False) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise ParameterError(name, value, "a number", context=context)
    v = float(value)
    if not math.isfinite(v) or (positive and v <= 0):
        raise ParameterError(name, value, "a finite number > 0" if positive else "finite",
                             context=context)
    return v


@dataclass(frozen=True)
class ColumnPlacement:
    """Where the composer instances a column.

    Parameters
    ----------
    position : (3,) float
        Centre of the column's bottom (its axis on the stylobate), metres.
    rotation_deg : float
        Rotation about +Y; the column's local +Z ends up along ``(sin θ, 0, cos θ)``.
    kind : ColumnKind or str
        ``"free"``, ``"engaged"`` (a half column set against a wall: its axis is on the
        wall's outer face and its local −Z half is inside the wall) or ``"corner"`` (a
        three-quarter column on a wall corner, its local −X/−Z quadrant inside the walls).
    scale : float
        Uniform scale of the column asset (built at the layout's column height), > 0.
    name : str
    angle_rotation_deg : float or None
        For a corner of the colonnade: the rotation that turns an angle capital's two volute
        faces (local +Z and +X) to the building's two outer sides (None elsewhere).
    """

    position: tuple[float, float, float]
    rotation_deg: float = 0.0
    kind: ColumnKind = ColumnKind.FREE
    scale: float = 1.0
    name: str = "column"
    angle_rotation_deg: float | None = None

    def __post_init__(self) -> None:
        ctx = f"column {self.name!r}"
        pos = tuple(_finite("position", v, ctx) for v in np.asarray(self.position).tolist())
        if len(pos) != 3:
            raise ParameterError("position", self.position, "three numbers", context=ctx)
        object.__setattr__(self, "position", pos)
        object.__setattr__(self, "rotation_deg", _finite("rotation_deg", self.rotation_deg, ctx))
        object.__setattr__(self, "scale", _finite("scale", self.scale, ctx, positive=True))
        object.__setattr__(self, "kind", _enum(ColumnKind, self.kind, "kind", ctx))
        if self.angle_rotation_deg is not None:
            object.__setattr__(self, "angle_rotation_deg",
                               _finite("angle_rotation_deg", self.angle_rotation_deg, ctx))

    @property
    def facing(self) -> np.ndarray:
        """(3,) unit vector of the column's local +Z after the rotation."""
        t = math.radians(self.rotation_deg)
        return np.array([math.sin(t), 0.0, math.cos(t)])


@dataclass(frozen=True)
class Hypothesis:
    """An alternative reconstruction the composer can author as a layer or variant.

    ``changes`` maps dotted keys to the alternative values: ``section.key`` of the temple TOML
    (applied by :func:`build_layout`) or another namespace (``column.…``, ``material.…``)
    that the layout records for the composer. ``certainty`` rates the alternative.
    """

    id: str
    description: str
    sources: tuple[str, ...]
    certainty: Certainty
    changes: Mapping[str, Any]

    def __post_init__(self) -> None:
        ctx = f"hypothesis {self.id!r}"
        from ionic_usd.params import check_identifier

        check_identifier("id", self.id, context=ctx)  # it names a file: never a path
        object.__setattr__(self, "certainty", _enum(Certainty, self.certainty, "certainty", ctx))
        object.__setattr__(self, "sources", tuple(self.sources))
        if not self.changes:
            raise ParameterError("changes", self.changes, "at least one dotted key", context=ctx)
        for k in self.changes:
            if not isinstance(k, str) or k.count(".") != 1:
                raise ParameterError("changes", k, "keys like 'section.key'", context=ctx)
        object.__setattr__(self, "changes", MappingProxyType(dict(self.changes)))


# ---------------------------------------------------------------------------------------------
# parameters


_INT_FIELDS = {"columns_front", "columns_side", "columns_porch_depth", "steps_count"}
# ratios that may be any positive number; everything else is a length in metres (> 0)


@dataclass(frozen=True)
class TempleParams:
    """Dimensions of a tetrastyle-like pseudoperipteral temple (the TOML ``[section] key``
    maps to the field ``section_key``; see ``portunus.toml`` for meanings and sources)."""

    name: str = "temple"
    podium_height: float = 2.40
    podium_footing_height: float = 0.45
    podium_base_width: float = 11.87
    podium_base_length: float = 25.60
    podium_cheek_wall_width: float = 0.85
    stylobate_width: float = 10.50
    stylobate_length: float = 19.30
    columns_height: float = 8.22
    columns_lower_diameter: float = 0.95
    columns_upper_diameter_ratio: float = 6.0 / 7.0
    columns_front: int = 4
    columns_side: int = 7
    columns_porch_depth: int = 2
    steps_count: int = 10
    cella_wall_thickness: float = 0.80
    cella_door_height_ratio: float = 2.0 / 3.5
    cella_door_width_ratio: float = 5.5 / 12.0
    entablature_architrave_divisor: float = 12.0
    entablature_frieze_ratio: float = 1.25
    entablature_cornice_ratio: float = 1.0
    entablature_cornice_projection_ratio: float = 1.0
    roof_tympanum_ratio: float = 9.0
    roof_slab_thickness: float = 0.35

    def __post_init__(self) -> None:
        ctx = f"temple {self.name!r}"
        for f in fields(self):
            if f.name == "name":
                continue
            v = getattr(self, f.name)
            key = f.name.replace("_", ".", 1)
            if f.name in _INT_FIELDS:
                if isinstance(v, bool) or not isinstance(v, int):
                    raise ParameterError(key, v, "an integer", context=ctx)
            else:
                object.__setattr__(self, f.name, _finite(key, v, ctx, positive=True))
        if self.columns_front < 2 or self.columns_side < self.columns_front + 1:
            raise ParameterError("columns.side", self.columns_side,
                                 f"> columns.front = {self.columns_front} (≥ 2)", context=ctx)
        if not 1 <= self.columns_porch_depth <= self.columns_side - 2:
            raise ParameterError("columns.porch_depth", self.columns_porch_depth,
                                 f"1 … {self.columns_side - 2} (a cella needs ≥ 1 bay)",
                                 context=ctx)
        if self.steps_count < 1:
            raise ParameterError("steps.count", self.steps_count, "≥ 1", context=ctx)
        if self.stylobate_length <= self.stylobate_width:
            raise ParameterError("stylobate.length", self.stylobate_length,
                                 f"> stylobate.width = {self.stylobate_width}", context=ctx)
        if self.margin <= self.columns_lower_diameter / 2:
            raise ParameterError(
                "stylobate.width", self.stylobate_width,
                f"a value leaving the corner columns on the stylobate (margin {self.margin:.3f}"
                f" m ≤ lower radius {self.columns_lower_diameter / 2:.3f} m)", context=ctx)
        if self.podium_base_width <= self.stylobate_width:
            raise ParameterError("podium.base_width", self.podium_base_width,
                                 f"> stylobate.width = {self.stylobate_width}", context=ctx)
        if self.stair_run <= 0:
            raise ParameterError("podium.base_length", self.podium_base_length,
                                 "long enough for the stairs (stylobate + projections)",
                                 context=ctx)
        if self.podium_footing_height >= self.podium_height:
            raise ParameterError("podium.footing_height", self.podium_footing_height,
                                 f"< podium.height = {self.podium_height}", context=ctx)
        if self.podium_cheek_wall_width >= self.stylobate_width / 2:
            raise ParameterError("podium.cheek_wall_width", self.podium_cheek_wall_width,
                                 f"< half the stylobate width ({self.stylobate_width / 2})",
                                 context=ctx)
        inner = 2 * (self.x_axis - self.cella_wall_thickness)
        if self.door_width >= inner or self.door_height >= self.columns_height:
            raise ParameterError("cella.door_width_ratio", self.cella_door_width_ratio,
                                 "a door that fits inside the cella's front wall", context=ctx)
        if self.cella_wall_thickness >= self.axial_spacing:
            raise ParameterError("cella.wall_thickness", self.cella_wall_thickness,
                                 f"< the axial spacing {self.axial_spacing:.3f}", context=ctx)

    # -- derived dimensions (see the module docstring) -------------------------------------
    @property
    def axial_spacing(self) -> float:
        return (self.stylobate_length - self.stylobate_width) / (
            self.columns_side - self.columns_front)

    @property
    def margin(self) -> float:
        return (self.stylobate_width - (self.columns_front - 1) * self.axial_spacing) / 2

    @property
    def x_axis(self) -> float:
        """|x| of the flank column axes (= the cella side walls' outer faces)."""
        return self.stylobate_width / 2 - self.margin

    @property
    def z_front_axis(self) -> float:
        return self.stylobate_length / 2 - self.margin

    @property
    def footing_projection(self) -> float:
        return (self.podium_base_width - self.stylobate_width) / 2

    @property
    def stair_run(self) -> float:
        return self.podium_base_length - self.stylobate_length - 2 * self.footing_projection

    @property
    def door_height(self) -> float:
        return self.cella_door_height_ratio * self.columns_height

    @property
    def door_width(self) -> float:
        return self.cella_door_width_ratio * self.door_height

    @property
    def architrave_height(self) -> float:
        return self.columns_height / self.entablature_architrave_divisor

    @property
    def entablature_heights(self) -> tuple[float, float, float]:
        """(architrave, frieze, cornice) heights in metres."""
        a = self.architrave_height
        return a, a * self.entablature_frieze_ratio, a * self.entablature_cornice_ratio

    @property
    def pitch_deg(self) -> float:
        return math.degrees(math.atan(2.0 / self.roof_tympanum_ratio))


_SECTIONS: dict[str, tuple[str, ...]] = {}
for _f in fields(TempleParams):
    if _f.name != "name":
        _sec, _key = _f.name.split("_", 1)
        _SECTIONS.setdefault(_sec, ())
        _SECTIONS[_sec] += (_key,)


def params_from_tables(data: Mapping[str, Any], *, context: str) -> TempleParams:
    """A :class:`TempleParams` from TOML tables (``[temple] name`` and the dimension sections);
    unknown sections or keys raise :class:`ParameterError` naming them."""
    kw: dict[str, Any] = {}
    temple = data.get("temple", {})
    if not isinstance(temple, Mapping):
        raise ParameterError("[temple]", temple, "a table", context=context)
    for key, value in temple.items():
        if key != "name":
            raise ParameterError(f"temple.{key}", value, "name (the only key of [temple])",
                                 context=context)
    if "name" in temple:
        kw["name"] = temple["name"]
    for sec, table in data.items():
        if sec in ("temple", "hypothesis", "cuboid", "mouldings"):  # mouldings: temple.mouldings
            continue
        if sec not in _SECTIONS:
            raise ParameterError(f"[{sec}]", "…", "a known section: "
                                 + ", ".join(["temple", *_SECTIONS, "hypothesis", "cuboid"]),
                                 context=context)
        for key, value in table.items():
            if key not in _SECTIONS[sec]:
                raise ParameterError(f"{sec}.{key}", value,
                                     f"one of {', '.join(_SECTIONS[sec])}", context=context)
            kw[f"{sec}_{key}"] = value
    return TempleParams(**kw)


# ---------------------------------------------------------------------------------------------
# cuboids in TOML


def cuboids_from_tables(
    entries: Iterable[Mapping[str, Any]], *, context: str
) -> dict[Layer, tuple[Cuboid, ...]]:
    """Cuboids from ``[[cuboid]]`` tables grouped by layer.

    Each table: ``name`` (str), ``min`` / ``max`` ([x, y, z] metres), ``layer`` (one of
    :class:`Layer`), optional ``rise`` (metres, default 0) and ``incline`` (``"shear"`` or
    ``"wedge"``). Errors name ``context`` (the file), the entry and the key.
    """
    out: dict[Layer, list[Cuboid]] = {}
    allowed = {"name", "min", "max", "rise", "incline", "layer"}
    for i, e in enumerate(entries, 1):
        where = f"{context} [[cuboid]] #{i}"
        if not isinstance(e, Mapping):
            raise ParameterError("[[cuboid]]", e, "a table", context=where)
        if "name" in e:
            where += f" ({e['name']!r})"
        for key in e:
            if key not in allowed:
                raise ParameterError(key, e[key], f"one of {', '.join(sorted(allowed))}",
                                     context=where)
        for key in ("name", "min", "max", "layer"):
            if key not in e:
                raise ParameterError(key, "(missing)", "a value (required key)", context=where)
        layer = _enum(Layer, e["layer"], "layer", where)
        try:
            c = Cuboid(e["min"], e["max"], e.get("rise", 0.0), e.get("incline", "shear"),
                       name=e["name"])
        except ParameterError as exc:
            raise ParameterError(exc.name, exc.value, exc.valid, context=where) from None
        out.setdefault(layer, []).append(c)
    return {k: tuple(v) for k, v in out.items()}


def load_cuboids_toml(path: str | os.PathLike) -> dict[Layer, tuple[Cuboid, ...]]:
    """Read the ``[[cuboid]]`` entries of a TOML file, grouped by layer."""
    data = load_toml(path)
    entries = data.get("cuboid", [])
    if not isinstance(entries, list):
        raise ParameterError("cuboid", entries, "an array of tables ([[cuboid]])",
                             context=str(path))
    return cuboids_from_tables(entries, context=str(path))


def cuboids_to_toml(groups: Mapping[str, Iterable[Cuboid]]) -> str:
    """``[[cuboid]]`` tables for cuboids grouped by layer (read back by
    :func:`load_cuboids_toml`)."""
    out = []
    for layer, cs in groups.items():
        lay = _enum(Layer, layer, "layer", "cuboids_to_toml")
        for c in cs:
            out += ["[[cuboid]]", f"name = {toml_value(c.name)}",
                    f"layer = {toml_value(lay.value)}",
                    f"min = {toml_value(list(c.min))}", f"max = {toml_value(list(c.max))}"]
            if c.rise != 0.0 or c.incline is not Incline.SHEAR:
                out += [f"rise = {toml_value(c.rise)}",
                        f"incline = {toml_value(c.incline.value)}"]
            out.append("")
    return "\n".join(out)


# ---------------------------------------------------------------------------------------------
# the layout


def colonnade_positions(start, end, count: int) -> np.ndarray:
    """Evenly spaced column positions from ``start`` to ``end`` inclusive.

    Parameters
    ----------
    start, end : (3,) float
    count : int, ≥ 1 (a single column stands at ``start``)

    Returns
    -------
    (count, 3) float64, axial spacing ``|end − start| / (count − 1)``
    """
    if isinstance(count, bool) or not isinstance(count, int | np.integer) or count < 1:
        raise ParameterError("count", count, "an integer ≥ 1")
    a = np.asarray(start, dtype=np.float64).reshape(3)
    b = np.asarray(end, dtype=np.float64).reshape(3)
    if count == 1:
        return a[None, :].copy()
    t = np.linspace(0.0, 1.0, count)[:, None]
    return a + t * (b - a)


@dataclass(frozen=True, eq=False)
class TempleLayout:
    """A temple as values for the composer.

    Parameters
    ----------
    name : str
    cuboids : Mapping[Layer, tuple[Cuboid, ...]]
        Closed solids per layer (build meshes with :func:`~ionic_usd.temple.cuboid_mesh`).
    columns : tuple[ColumnPlacement, ...]
    params : TempleParams
        The dimensions used (after ``applied`` hypotheses).
    hypotheses : tuple[Hypothesis, ...]
        All alternatives recorded in the source TOML.
    applied : tuple[str, ...]
        Ids of the hypotheses whose temple keys were applied.
    """

    name: str
    cuboids: Mapping[Layer, tuple[Cuboid, ...]]
    columns: tuple[ColumnPlacement, ...]
    params: TempleParams
    hypotheses: tuple[Hypothesis, ...] = ()
    applied: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        groups = {_enum(Layer, k, "layer", self.name): tuple(v) for k, v in self.cuboids.items()}
        object.__setattr__(self, "cuboids", MappingProxyType(groups))
        object.__setattr__(self, "columns", tuple(self.columns))
        object.__setattr__(self, "hypotheses", tuple(self.hypotheses))
        object.__setattr__(self, "applied", tuple(self.applied))

    def all_cuboids(self) -> tuple[Cuboid, ...]:
        return tuple(c for cs in self.cuboids.values() for c in cs)

    def columns_of(self, kind: ColumnKind | str) -> tuple[ColumnPlacement, ...]:
        k = ColumnKind(kind)
        return tuple(c for c in self.columns if c.kind is k)

    def cuboid(self, name: str) -> Cuboid:
        for c in self.all_cuboids():
            if c.name == name:
                return c
        raise ParameterError("name", name, "the name of one of the layout's cuboids")

    @property
    def stylobate_height(self) -> float:
        return self.params.podium_height

    @property
    def pitch_deg(self) -> float:
        return self.params.pitch_deg

    @property
    def axial_spacing(self) -> float:
        return self.params.axial_spacing


def _box(name, x0, y0, z0, x1, y1, z1, rise=0.0, incline=Incline.SHEAR) -> Cuboid:
    return Cuboid((x0, y0, z0), (x1, y1, z1), rise, incline, name=name)


def _podium(p: TempleParams) -> list[Cuboid]:
    w2, l2, pr = p.stylobate_width / 2, p.stylobate_length / 2, p.footing_projection
    fh, h, cw, run = p.podium_footing_height, p.podium_height, p.podium_cheek_wall_width, \
        p.stair_run
    front = l2 + run
    out = [
        _box("footing", -w2 - pr, 0.0, -l2 - pr, w2 + pr, fh, l2),
        _box("die", -w2, fh, -l2, w2, h, l2),
    ]
    for side, sgn in (("left", -1.0), ("right", 1.0)):
        xs = sorted((sgn * (w2 - cw), sgn * (w2 + pr)))
        out.append(_box(f"cheek_footing_{side}", xs[0], 0.0, l2, xs[1], fh, front + pr))
        xs = sorted((sgn * (w2 - cw), sgn * w2))
        out.append(_box(f"cheek_wall_{side}", xs[0], fh, l2, xs[1], h, front))
    n = p.steps_count
    riser, tread = h / n, run / n
    for i in range(n):
        out.append(_box(f"step_{i + 1:02d}", -(w2 - cw), i * riser, l2, w2 - cw,
                        (i + 1) * riser, l2 + (n - i) * tread))
    return out


def _cella(p: TempleParams) -> list[Cuboid]:
    xa, t, y0 = p.x_axis, p.cella_wall_thickness, p.podium_height
    y1 = y0 + p.columns_height
    zr = -p.z_front_axis
    zf = p.z_front_axis - p.columns_porch_depth * p.axial_spacing
    d2 = p.door_width / 2
    return [
        _box("wall_left", -xa, y0, zr, -xa + t, y1, zf),
        _box("wall_right", xa - t, y0, zr, xa, y1, zf),
        _box("wall_rear", -xa + t, y0, zr, xa - t, y1, zr + t),
        _box("wall_front_left", -xa + t, y0, zf - t, -d2, y1, zf),
        _box("wall_front_right", d2, y0, zf - t, xa - t, y1, zf),
        _box("door_lintel", -d2, y0 + p.door_height, zf - t, d2, y1, zf),
    ]


def _entablature(p: TempleParams) -> tuple[list[Cuboid], float, float, float, float]:
    a, f, c = p.entablature_heights
    half_top = p.columns_lower_diameter * p.columns_upper_diameter_ratio / 2
    xe, ze = p.x_axis + half_top, p.z_front_axis + half_top
    proj = c * p.entablature_cornice_projection_ratio
    y = p.podium_height + p.columns_height
    out = [
        _box("architrave", -xe, y, -ze, xe, y + a, ze),
        _box("frieze", -xe, y + a, -ze, xe, y + a + f, ze),
        _box("cornice", -xe - proj, y + a + f, -ze - proj, xe + proj, y + a + f + c, ze + proj),
    ]
    return out, y + a + f + c, xe, ze, proj


# (!) assumption: the roof's bed on the cornice at the eaves (mortar and tile bedding), so the
# gable wedges have an outer face there; 5 cm.
ROOF_BED = 0.05


def _roof(p: TempleParams, y: float, xe: float, ze: float, proj: float) -> list[Cuboid]:
    tan = 2.0 / p.roof_tympanum_ratio
    xc, zc = xe + proj, ze + proj
    h = xc * tan  # the slab soffit's rise from the eaves to the ridge = width / tympanum_ratio
    s = p.roof_slab_thickness
    yb = y + ROOF_BED
    return [
        _box("roof_left", -xc, yb, -zc, 0.0, yb + s, zc, h),
        _box("roof_right", 0.0, yb + h, -zc, xc, yb + h + s, zc, -h),
        _box("pediment_left", -xc, y, -ze, 0.0, yb, ze, h, Incline.WEDGE),
        _box("pediment_right", 0.0, y, -ze, xc, yb + h, ze, -h, Incline.WEDGE),
    ]


def _outer_rotation(sx: float, sz: float) -> float:
    """The quarter-turn rotation taking local +Z and +X to the outer sides ``(sx, 0, 0)`` and
    ``(0, 0, sz)`` (signs ±1) of a corner, in one order or the other."""
    for deg in (0.0, 90.0, 180.0, -90.0):
        t = math.radians(deg)
        facing = (round(math.sin(t)), round(math.cos(t)))  # local +Z as (x, z)
        xaxis = (round(math.cos(t)), round(-math.sin(t)))  # local +X as (x, z)
        if {facing, xaxis} == {(int(sx), 0), (0, int(sz))}:
            return deg
    raise AssertionError("unreachable: two perpendicular sides have a quarter turn")


def _columns(p: TempleParams) -> list[ColumnPlacement]:
    """Column placements. Forms: free in the porch; on the cella walls engaged (a half column)
    except on a wall corner — the cella's rear corners and the ends of the flank walls at the
    cella's front wall — where a three-quarter ``corner`` column shows no cut face."""
    y, xa, zf, s = p.podium_height, p.x_axis, p.z_front_axis, p.axial_spacing
    nf, ns, porch = p.columns_front, p.columns_side, p.columns_porch_depth
    out: list[ColumnPlacement] = []
    front = colonnade_positions((-xa, y, zf), (xa, y, zf), nf)
    rear = colonnade_positions((-xa, y, -zf), (xa, y, -zf), nf)
    for j, pos in enumerate(front):
        corner = _outer_rotation(np.sign(pos[0]), 1.0) if j in (0, nf - 1) else None
        out.append(ColumnPlacement(tuple(pos), 0.0, ColumnKind.FREE, name=f"front_{j + 1}",
                                   angle_rotation_deg=corner))
    for side, sgn in (("left", -1.0), ("right", 1.0)):
        flank = colonnade_positions((sgn * xa, y, zf), (sgn * xa, y, zf - (ns - 1) * s), ns)
        for k in range(1, ns - 1):
            kind, rot = ColumnKind.ENGAGED, sgn * 90.0
            if k < porch:
                kind = ColumnKind.FREE
            elif k == porch:  # the flank wall starts here, at the cella's front wall
                kind, rot = ColumnKind.CORNER, _outer_rotation(sgn, 1.0)
            out.append(ColumnPlacement(tuple(flank[k]), rot, kind, name=f"{side}_{k + 1}"))
    for j, pos in enumerate(rear):
        kind, rot, corner = ColumnKind.ENGAGED, 180.0, None
        if j in (0, nf - 1):
            kind = ColumnKind.CORNER
            rot = corner = _outer_rotation(np.sign(pos[0]), -1.0)
        out.append(ColumnPlacement(tuple(pos), rot, kind, name=f"rear_{j + 1}",
                                   angle_rotation_deg=corner))
    return out


def build_layout(
    params: TempleParams,
    *,
    hypotheses: Iterable[Hypothesis] = (),
    apply: Iterable[str] = (),
    extra_cuboids: Mapping[Layer, Iterable[Cuboid]] | None = None,
) -> TempleLayout:
    """Lay out a pseudoperipteral temple (see the module docstring for every rule).

    Parameters
    ----------
    params : TempleParams
    hypotheses : the alternatives to record
    apply : ids of hypotheses whose ``section.key`` temple changes to apply (other namespaces
        are left to the composer)
    extra_cuboids : more cuboids per layer, appended as given (e.g. an altar)
    """
    hyps = tuple(hypotheses)
    by_id = {h.id: h for h in hyps}
    applied = tuple(apply)
    for hid in applied:
        if hid not in by_id:
            raise ParameterError("hypothesis", hid, "one of: " + (", ".join(by_id) or "(none)"),
                                 context=f"temple {params.name!r}")
        changes = {}
        for key, value in by_id[hid].changes.items():
            sec, k = key.split(".")
            if sec in _SECTIONS:
                if k not in _SECTIONS[sec]:
                    raise ParameterError(key, value, f"one of {sec}.{', '.join(_SECTIONS[sec])}",
                                         context=f"hypothesis {hid!r}")
                changes[f"{sec}_{k}"] = value
        params = replace(params, **changes)
    ent, y_top, xe, ze, proj = _entablature(params)
    groups: dict[Layer, list[Cuboid]] = {
        Layer.PODIUM: _podium(params),
        Layer.CELLA: _cella(params),
        Layer.ENTABLATURE: ent,
        Layer.ROOF: _roof(params, y_top, xe, ze, proj),
    }
    for layer, cs in (extra_cuboids or {}).items():
        groups[Layer(layer)].extend(cs)
    from ionic_usd.params import prim_key

    seen: dict[str, str] = {}  # two names that author the same prim would lose a cuboid
    for c in (c for cs in groups.values() for c in cs):
        if prim_key(c.name) in seen:
            other = seen[prim_key(c.name)]
            raise ParameterError("cuboid name", c.name, f"a name distinct from {other!r} "
                                 "(both would author the same prim)",
                                 context=f"temple {params.name!r}")
        seen[prim_key(c.name)] = c.name
    return TempleLayout(params.name, {k: tuple(v) for k, v in groups.items()},
                        tuple(_columns(params)), params, hyps, applied)


def _hypotheses(entries, context: str) -> tuple[Hypothesis, ...]:
    out = []
    allowed = {"id", "description", "sources", "certainty", "changes"}
    for i, e in enumerate(entries, 1):
        where = f"{context} [[hypothesis]] #{i}"
        if not isinstance(e, Mapping):
            raise ParameterError("[[hypothesis]]", e, "a table", context=where)
        for key in e:
            if key not in allowed:
                raise ParameterError(key, e[key], f"one of {', '.join(sorted(allowed))}",
                                     context=where)
        for key in sorted(allowed):
            if key not in e:
                raise ParameterError(key, "(missing)", "a value (required key)", context=where)
        src = e["sources"]
        if not isinstance(src, list) or not all(isinstance(x, str) for x in src):
            raise ParameterError("sources", src, "a list of strings", context=where)
        try:
            out.append(Hypothesis(e["id"], e["description"], tuple(src),
                                  e["certainty"], e["changes"]))
        except ParameterError as exc:
            raise ParameterError(exc.name, exc.value, exc.valid, context=where) from None
    from ionic_usd.params import check_identifier, prim_key

    seen: dict[str, str] = {}  # ids name files and variant sets: hyp_a_b for a-b and a_b
    for h in out:
        check_identifier("id", h.id, context=f"{context} [[hypothesis]]")
        if prim_key(h.id) in seen:
            other = seen[prim_key(h.id)]
            raise ParameterError("id", h.id, f"an id distinct from {other!r} (both would name "
                                 "the same layer file and variant set)",
                                 context=f"{context} [[hypothesis]]")
        seen[prim_key(h.id)] = h.id
    for i, h in enumerate(out, 1):
        for key, value in h.changes.items():
            sec, k = key.split(".")
            if sec in COMPOSER_NAMESPACES:
                continue  # the composer checks these (ionic_usd.usd.hypotheses)
            if sec not in _SECTIONS or k not in _SECTIONS[sec]:
                valid = (f"one of {sec}.{', '.join(_SECTIONS[sec])}" if sec in _SECTIONS else
                         "section.key of the temple TOML, or column.… / material.…")
                raise ParameterError(key, value, valid,
                                     context=f"{context} [[hypothesis]] #{i} ({h.id!r})")
    return tuple(out)


def layout_from_toml(
    path: str | os.PathLike, *, apply: Iterable[str] = ()
) -> TempleLayout:
    """Build a layout from a temple TOML (schema of ``portunus.toml``)."""
    return layout_from_mapping(load_toml(path), context=str(path), apply=apply)


def layout_from_mapping(
    data: Mapping[str, Any], *, context: str = "temple", apply: Iterable[str] = ()
) -> TempleLayout:
    """Build a layout from already-parsed TOML tables (see :func:`layout_from_toml`)."""
    from ionic_usd.params import check_temple_tables

    ctx = context
    check_temple_tables(data, context=ctx)  # types and ranges of every table, at the boundary
    params = params_from_tables(data, context=ctx)
    hyps = _hypotheses(data.get("hypothesis", []), ctx)
    extra = cuboids_from_tables(data.get("cuboid", []), context=ctx)
    return build_layout(params, hypotheses=hyps, apply=apply, extra_cuboids=extra)


def portunus_layout(*, apply: Iterable[str] = ()) -> TempleLayout:
    """The Temple of Portunus from the packaged ``portunus.toml``.

    Parameters
    ----------
    apply : ids of ``[[hypothesis]]`` entries to apply (e.g. ``("roof-pitch-15",)``).
    """
    ref = resources.files("ionic_usd") / "data" / PORTUNUS_TOML
    with resources.as_file(ref) as p:
        return layout_from_toml(Path(p), apply=apply)
