"""A :class:`~ionic_usd.temple.vitruvius.TempleType` as the composer's layout.

The result is the same :class:`~ionic_usd.temple.layout.TempleLayout` Portunus makes — cuboid
layers (podium, cella, entablature, roof) and column placements — so the USD composer, the
hypotheses, the LODs and the exports take it unchanged. Its ``params`` is a
:class:`TypeParams`: the :class:`~ionic_usd.temple.description.TempleParams` fields the
mouldings, ornament and roof tiles read, with the entablature's extent given by the type, and
a hook that rebuilds the layout when a hypothesis changes a ``type.…`` key.

Geometry (frame of :mod:`ionic_usd.temple.layout`; every rule cited in
:mod:`ionic_usd.temple.vitruvius`):

* **Colonnade.** The front row stands on the front axes ``xs`` at ``z = z_front``; a
  peripteral family temple repeats it at the rear and runs ``side`` columns down each flank at
  the flank spacing. Dipteral: an inner ring one flank bay inside the outer one, on the front
  axes ``xs[1] … xs[-2]``. Pseudoperipteral: the porch is ``porch`` rows deep (default 2, as at
  Portunus); behind it the flank and rear columns are engaged in the cella walls. Prostyle:
  the front row only; amphiprostyle: front and rear rows; in antis: ``xs[1:-1]`` between antae.
* **Cella.** Walls ``wall_thickness`` thick standing on the stylobate up to the architrave
  soffit. Peripteral family: the side walls on the front axes ``xs[±k]`` (k = 1 peripteral,
  2 pseudo-/dipteral), their antae ending k flank bays behind the front and rear rows, a
  pronaos of two flank bays and an opisthodomos of one (!), each with the front axes between
  the antae as columns in antis. Prostyle and amphiprostyle: side walls on the outer axes, the
  antae one bay behind the front (and rear) row, the pronaos 3/8 of the walls' length (IV.4.1:
  cella 1¼, pronaos ¾ of a width in a length of two). In antis: the walls reach the front
  row. Pseudoperipteral: the walls' outer faces on the column axes (Portunus).
* **Entablature** over the outer axes (+ the upper radius; + half a wall where walls carry it),
  **roof** as Portunus' (two sheared slabs, two gable wedges), **base**: a crepidoma of
  ``steps`` courses all round, or the Roman podium with a frontal stair.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field, replace
from typing import Any

from ionic_usd.errors import ParameterError
from ionic_usd.params import prim_key
from ionic_usd.temple.cuboid import Cuboid
from ionic_usd.temple.description import (
    SECTIONS,
    ColumnKind,
    ColumnPlacement,
    Hypothesis,
    Layer,
    TempleParams,
)
from ionic_usd.temple.massing import TempleLayout, outer_rotation, podium_cuboids, roof_cuboids
from ionic_usd.temple.vitruvius import (
    CELLA_INSET,
    PERIPTERAL_FAMILY,
    TYPE_SCHEMA,
    Arrangement,
    Foundation,
    Order,
    TempleType,
    TypePlan,
    resolve,
    type_from_table,
)

__all__ = [
    "TypeParams",
    "type_params",
    "type_layout",
    "layout_from_type_mapping",
    "ANGLE_HYPOTHESIS",
]


@dataclass(frozen=True)
class TypeParams(TempleParams):
    """TempleParams of a typed temple: ``x_axis``/``z_front_axis`` place the entablature
    (its faces less the upper radius); ``vitruvian`` is the type itself."""

    vitruvian: TempleType = field(default_factory=lambda: TempleType(lower_diameter=1.0))
    column_base: str = "attic_bezier_plinth"  # the column's base preset
    entablature_x: float = 1.0  # half extents of the architrave
    entablature_z: float = 1.0
    spacing: float = 1.0

    def __post_init__(self) -> None:  # the type validated itself
        pass

    @property
    def x_axis(self) -> float:
        return (
            self.entablature_x - self.columns_lower_diameter * self.columns_upper_diameter_ratio / 2
        )

    @property
    def z_front_axis(self) -> float:
        return (
            self.entablature_z - self.columns_lower_diameter * self.columns_upper_diameter_ratio / 2
        )

    @property
    def axial_spacing(self) -> float:
        return self.spacing

    @property
    def podium_mouldings(self) -> bool:
        """A Roman podium carries the moulded base and crown; a crepidoma does not."""
        return Foundation(resolve(self.vitruvian).foundation) is Foundation.PODIUM

    @property
    def margin(self) -> float:
        return (self.stylobate_width / 2) - self.x_axis

    def rebuild_layout(self, *, hypotheses, apply, extra_cuboids=None):
        return type_layout(
            self.vitruvian,
            name=self.name,
            hypotheses=hypotheses,
            apply=apply,
            extra_cuboids=extra_cuboids,
        )


def _entablature_extent(pl: TypePlan) -> tuple[float, float]:
    half_top = pl.lower_diameter * pl.upper_ratio / 2
    w2 = pl.wall_thickness / 2
    if pl.arrangement in PERIPTERAL_FAMILY:
        return pl.x_outer + half_top, pl.z_front + half_top
    ex = pl.x_outer + max(half_top, w2)
    if pl.arrangement is Arrangement.IN_ANTIS:
        return ex, pl.z_front + max(half_top, w2)
    return ex, pl.z_front + half_top


def type_params(t: TempleType, name: str = "temple") -> TypeParams:
    pl = resolve(t)
    ex, ez = _entablature_extent(pl)
    w, length = pl.stylobate_width, pl.stylobate_length
    pr = 0.065 * w  # (!) the podium footing's projection, Portunus' 0.685 m on 10.5 m
    run = pl.steps * pl.step_tread
    return TypeParams(
        name=name,
        podium_height=pl.base_height,
        podium_footing_height=0.19 * pl.base_height,  # (!) Portunus' 0.45 / 2.40
        podium_base_width=w + 2 * pr,
        podium_base_length=length + 2 * pr + run,
        podium_cheek_wall_width=pl.margin,
        stylobate_width=w,
        stylobate_length=length,
        columns_height=pl.column_height,
        columns_lower_diameter=pl.lower_diameter,
        columns_upper_diameter_ratio=pl.upper_ratio,
        columns_front=t.front,
        columns_side=max(pl.side, t.front + 1),
        columns_porch_depth=t.porch or 2,
        steps_count=pl.steps,
        cella_wall_thickness=pl.wall_thickness,
        entablature_architrave_divisor=pl.architrave_divisor,
        entablature_frieze_ratio=pl.frieze_ratio,
        entablature_cornice_ratio=t.cornice_ratio,
        roof_tympanum_ratio=t.tympanum_ratio,
        roof_slab_thickness=t.roof_slab,
        vitruvian=t,
        # the Asiatic order stands on the Ionic (Ephesian) base, the Attic on the Attic base
        column_base=t.base or ("ephesian" if pl.order is Order.ASIATIC else "attic_bezier_plinth"),
        entablature_x=ex,
        entablature_z=ez,
        spacing=pl.flank_spacing if pl.side else pl.front_spacing,
    )


def _box(name, x0, y0, z0, x1, y1, z1) -> Cuboid:
    return Cuboid((x0, y0, z0), (x1, y1, z1), name=name)


def _entablature(p: TypeParams) -> tuple[list[Cuboid], float, float, float, float]:
    """Architrave, frieze (none in the Asiatic order), cornice (layout._entablature's rule)."""
    a, f, c = p.entablature_heights
    xe, ze = p.entablature_x, p.entablature_z
    proj = c * p.entablature_cornice_projection_ratio
    y = p.podium_height + p.columns_height
    out = [_box("architrave", -xe, y, -ze, xe, y + a, ze)]
    if f > 0:
        out.append(_box("frieze", -xe, y + a, -ze, xe, y + a + f, ze))
    out.append(
        _box("cornice", -xe - proj, y + a + f, -ze - proj, xe + proj, y + a + f + c, ze + proj)
    )
    return out, y + a + f + c, xe, ze, proj


def _crepidoma(pl: TypePlan) -> list[Cuboid]:
    w2, l2, n = pl.stylobate_width / 2, pl.stylobate_length / 2, pl.steps
    out = []
    for i in range(n):
        o = (n - 1 - i) * pl.step_tread
        name = "stylobate" if i == n - 1 else f"step_{i + 1:02d}"
        y0, y1 = i * pl.step_height, (i + 1) * pl.step_height
        out.append(_box(name, -w2 - o, y0, -l2 - o, w2 + o, y1, l2 + o))
    return out


@dataclass
class _Walls:
    """The cella: side walls centred on ±x (outer faces at ±(x + t/2)), from z0 to z1 (outer
    faces of the antae's ends), the door wall centred on z_door, the back wall on z_back."""

    x: float
    z0: float
    z1: float
    z_door: float
    z_back: float


def _walls(pl: TypePlan, p: TypeParams) -> _Walls:
    t, a = pl.wall_thickness, pl.flank_spacing if pl.side else pl.front_spacing
    arr, zf = pl.arrangement, pl.z_front
    if arr is Arrangement.PSEUDOPERIPTERAL:
        porch = pl.type.porch or 2
        front = zf - porch * a
        return _Walls(pl.x_outer - t / 2, -zf, front, front - t / 2, -zf + t / 2)
    if arr in CELLA_INSET:
        k = CELLA_INSET[arr]
        x = -pl.xs[k]
        z1 = zf - k * a + t / 2
        pron = pl.type.pronaos if pl.type.pronaos is not None else 2 * a
        opis = pl.type.opisthodomos if pl.type.opisthodomos is not None else a
        return _Walls(x, -z1, z1, z1 - t / 2 - pron, -z1 + t / 2 + opis)
    x = pl.x_outer
    if arr is Arrangement.IN_ANTIS:
        z1 = zf + t / 2
    else:  # prostyle: the antae ``porch`` bays behind the front row (default 1)
        z1 = zf - (pl.type.porch or 1) * pl.front_spacing + t / 2
    z0 = -z1 if arr is Arrangement.AMPHIPROSTYLE else -(p.entablature_z)
    pron = pl.type.pronaos if pl.type.pronaos is not None else 0.375 * (z1 - z0)
    return _Walls(x, z0, z1, z1 - t / 2 - pron, z0 + t / 2)


def _cella(pl: TypePlan, p: TypeParams, w: _Walls) -> list[Cuboid]:
    t, y0 = pl.wall_thickness, pl.base_height
    y1 = y0 + pl.column_height
    xi = w.x - t / 2  # inner faces
    d2 = p.door_width / 2
    if d2 >= xi:
        d2 = 0.5 * xi
    dh = min(p.door_height, 0.9 * pl.column_height)
    zd = w.z_door
    out = [
        _box("wall_left", -w.x - t / 2, y0, w.z0, -xi, y1, w.z1),
        _box("wall_right", xi, y0, w.z0, w.x + t / 2, y1, w.z1),
        _box("wall_front_left", -xi, y0, zd - t / 2, -d2, y1, zd + t / 2),
        _box("wall_front_right", d2, y0, zd - t / 2, xi, y1, zd + t / 2),
        _box("door_lintel", -d2, y0 + dh, zd - t / 2, d2, y1, zd + t / 2),
        _box("wall_rear", -xi, y0, w.z_back - t / 2, xi, y1, w.z_back + t / 2),
    ]
    return out


def _row(xs, z, y, prefix, rot, corners=False, kind=ColumnKind.FREE) -> list[ColumnPlacement]:
    out = []
    n = len(xs)
    for j, x in enumerate(xs):
        angle = None
        if corners and j in (0, n - 1):
            angle = outer_rotation(1.0 if x > 0 else -1.0, 1.0 if z > 0 else -1.0)
        r = rot if angle is None else angle  # a corner turns its angle capital outward
        out.append(
            ColumnPlacement((x, y, z), r, kind, name=f"{prefix}_{j + 1}", angle_rotation_deg=angle)
        )
    return out


def _columns(pl: TypePlan, w: _Walls) -> list[ColumnPlacement]:
    y, zf, xs, arr = pl.base_height, pl.z_front, pl.xs, pl.arrangement
    out: list[ColumnPlacement] = []
    if arr is Arrangement.IN_ANTIS:
        return _row(xs[1:-1], zf, y, "front", 0.0)
    out += _row(xs, zf, y, "front", 0.0, corners=True)
    if arr in (Arrangement.PROSTYLE, Arrangement.AMPHIPROSTYLE):
        out += _returns(pl, 1.0)
        if arr is Arrangement.PROSTYLE:
            return out
        return out + _row(pl.xs_rear, -zf, y, "rear", 180.0, corners=True) + _returns(pl, -1.0)
    s, n = pl.flank_spacing, pl.side
    if arr is Arrangement.PSEUDOPERIPTERAL:
        return out + _pseudo(pl)
    out += _row(pl.xs_rear, -zf, y, "rear", 180.0, corners=True)
    for side, sgn in (("left", -1.0), ("right", 1.0)):
        for k in range(1, n - 1):
            out.append(
                ColumnPlacement(
                    (sgn * pl.x_outer, y, zf - k * s), sgn * 90.0, name=f"{side}_{k + 1}"
                )
            )
    if arr is Arrangement.DIPTERAL:
        zi = zf - s
        out += _row(xs[1:-1], zi, y, "inner_front", 0.0)
        out += _row(xs[1:-1], -zi, y, "inner_rear", 180.0)
        for side, sgn in (("inner_left", -1.0), ("inner_right", 1.0)):
            for k in range(2, n - 2):
                out.append(
                    ColumnPlacement(
                        (sgn * abs(xs[1]), y, zf - k * s), sgn * 90.0, name=f"{side}_{k + 1}"
                    )
                )
    k = CELLA_INSET[arr]
    inner = xs[k + 1 : len(xs) - k - 1]
    out += _row(inner, w.z1 - pl.wall_thickness / 2, y, "pronaos", 0.0)
    if w.z_back > w.z0 + pl.wall_thickness:  # an opisthodomos
        out += _row(inner, w.z0 + pl.wall_thickness / 2, y, "opisthodomos", 180.0)
    return out


def _returns(pl: TypePlan, sz: float) -> list[ColumnPlacement]:
    """A prostyle porch ``porch`` rows deep: the columns behind the corners (Saturn's)."""
    y, a = pl.base_height, pl.front_spacing
    out = []
    for side, sgn in (("left", -1.0), ("right", 1.0)):
        for k in range(1, pl.type.porch or 1):
            z = sz * (pl.z_front - k * a)
            name = f"{side}_{'front' if sz > 0 else 'rear'}_{k + 1}"
            out.append(ColumnPlacement((sgn * pl.x_outer, y, z), sgn * 90.0, name=name))
    return out


def _pseudo(pl: TypePlan) -> list[ColumnPlacement]:
    """Portunus' scheme: free porch, then engaged (corner where a wall turns)."""
    y, zf, s, n = pl.base_height, pl.z_front, pl.flank_spacing, pl.side
    porch = pl.type.porch or 2
    out = []
    for side, sgn in (("left", -1.0), ("right", 1.0)):
        for k in range(1, n - 1):
            kind, rot = ColumnKind.ENGAGED, sgn * 90.0
            if k < porch:
                kind = ColumnKind.FREE
            elif k == porch:
                kind, rot = ColumnKind.CORNER, outer_rotation(sgn, 1.0)
            out.append(
                ColumnPlacement(
                    (sgn * pl.x_outer, y, zf - k * s), rot, kind, name=f"{side}_{k + 1}"
                )
            )
    for j, x in enumerate(pl.xs):
        kind, rot, angle = ColumnKind.ENGAGED, 180.0, None
        if j in (0, len(pl.xs) - 1):
            kind = ColumnKind.CORNER
            rot = angle = outer_rotation(1.0 if x > 0 else -1.0, -1.0)
        out.append(
            ColumnPlacement((x, y, -zf), rot, kind, name=f"rear_{j + 1}", angle_rotation_deg=angle)
        )
    return out


ANGLE_HYPOTHESIS = "corner-capitals-normal"


def type_layout(
    t: TempleType,
    *,
    name: str = "temple",
    hypotheses: Iterable[Hypothesis] = (),
    apply: Iterable[str] = (),
    extra_cuboids: Mapping[Layer, Iterable[Cuboid]] | None = None,
):
    """The layout of a type (module docstring); ``apply``: ids of hypotheses whose
    ``type.…`` changes to apply."""
    hyps = tuple(hypotheses)
    by_id = {h.id: h for h in hyps}
    applied = tuple(apply)
    for hid in applied:
        if hid not in by_id:
            raise ParameterError(
                "hypothesis",
                hid,
                "one of: " + (", ".join(by_id) or "(none)"),
                context=f"temple {name!r}",
            )
        changes = {
            k.split(".")[1]: v for k, v in by_id[hid].changes.items() if k.startswith("type.")
        }
        t = replace(t, **changes)
    p = type_params(t, name)
    pl = resolve(t)
    ent, y_top, xe, ze, proj = _entablature(p)
    w = _walls(pl, p)
    crepidoma = pl.foundation is Foundation.CREPIDOMA
    groups: dict[Layer, list[Cuboid]] = {
        Layer.PODIUM: _crepidoma(pl) if crepidoma else podium_cuboids(p),
        Layer.CELLA: _cella(pl, p, w),
        Layer.ENTABLATURE: ent,
        Layer.ROOF: roof_cuboids(p, y_top, xe, ze, proj),
    }
    for layer, cs in (extra_cuboids or {}).items():
        groups[Layer(layer)].extend(cs)
    seen: dict[str, str] = {}  # two names that author the same prim would lose a cuboid
    for c in (c for cs in groups.values() for c in cs):
        other = seen.get(prim_key(c.name))
        if other is not None:
            raise ParameterError(
                "cuboid name",
                c.name,
                f"a name distinct from {other!r} (both would author the same prim)",
                context=f"temple {name!r}",
            )
        seen[prim_key(c.name)] = c.name
    layout = TempleLayout(
        name, {k: tuple(v) for k, v in groups.items()}, tuple(_columns(pl, w)), p, hyps, applied
    )
    return layout


TYPE_TABLES = ("temple", "type", "hypothesis", "cuboid", "mouldings")


def layout_from_type_mapping(data: Mapping[str, Any], *, context: str, apply: Iterable[str] = ()):
    """A layout from a type document: ``[temple] name``, ``[type]``, ``[[hypothesis]]`` whose
    changes name ``type.<key>`` or a composer namespace, ``[[cuboid]]``."""
    from ionic_usd.params import FieldSpec, check_table, check_value
    from ionic_usd.temple.tables import (
        HYPOTHESIS_EXTRA_CHANGES,
        cuboids_from_tables,
        hypotheses_from_tables,
    )

    for sec in data:
        if sec not in TYPE_TABLES and sec not in ("column", "shaft", "capital", "volute"):
            raise ParameterError(
                f"[{sec}]", "…", "a known table: " + ", ".join(TYPE_TABLES), context=context
            )
    name = check_table(
        check_value("temple", data.get("temple", {}), FieldSpec("table"), context=context),
        {"name": FieldSpec("str", max_len=256), "sources": FieldSpec("strings")},
        context=f"{context} [temple]",
    ).get("name", "temple")
    t = type_from_table(data["type"], context=context)
    entries = data.get("hypothesis", [])
    if not isinstance(entries, list):
        raise ParameterError(
            "hypothesis", entries, "an array of tables ([[hypothesis]])", context=context
        )
    schema = {f"type.{k}": v for k, v in TYPE_SCHEMA.items()}
    schema.update(HYPOTHESIS_EXTRA_CHANGES)
    plain = []
    for i, e in enumerate(entries, 1):
        where = f"{context} [[hypothesis]] #{i}"
        if not isinstance(e, Mapping) or not isinstance(e.get("changes"), Mapping):
            raise ParameterError("[[hypothesis]]", e, "a table with changes = {…}", context=where)
        for key, value in e["changes"].items():
            spec = schema.get(key)
            if spec is None and str(key).split(".")[0] in ("column", "material"):
                spec = FieldSpec("scalar")
            check_table({key: value}, {key: spec} if spec else schema, context=f"{where} changes")
        # the generic reader checks the rest; type.* keys are ours
        plain.append({**e, "changes": {k: v for k, v in e["changes"].items()}})
    sections = {**SECTIONS, "type": tuple(TYPE_SCHEMA)}
    hyps = hypotheses_from_tables(plain, context, sections=sections)
    extra = cuboids_from_tables(data.get("cuboid", []), context=context)
    layout = type_layout(t, name=name, hypotheses=hyps, apply=apply, extra_cuboids=extra)
    for h in hyps:  # every alternative must lay out
        if any(k.startswith("type.") for k in h.changes):
            type_layout(t, name=name, hypotheses=hyps, apply=[h.id])
    return layout
