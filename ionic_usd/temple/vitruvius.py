"""The Ionic temple as a type (Vitruvius III.2–5, IV.4): rules, a type value, its plan numbers.

A :class:`TempleType` names an **arrangement** (III.2), a number of **front columns** and an
**intercolumniation** (III.3); a lower diameter or a stylobate width fixes the scale. Every
other dimension follows from Vitruvius' rules (cited where they are used below) unless the
description gives a measured value, which overrides the rule. :func:`resolve` turns a type
into plain numbers (:class:`TypePlan`: column axes, stylobate, heights);
:mod:`ionic_usd.temple.typed_layout` turns those into the composer's cuboid layers and column
placements. No pxr here.

Rules (M. H. Morgan's translation, 1914; book.chapter.paragraph):

* **Arrangements** (III.2.2–7): *in antis* — antae at the front corners, columns between
  them; *prostyle* — a row of columns in front of the antae; *amphiprostyle* — the same at the
  rear; *peripteral* — "six columns in front and in the rear, eleven on the flanks including
  the corner columns", the walk round the cella one intercolumniation wide (III.2.5);
  *pseudodipteral* — "eight columns in front and rear, fifteen on the flanks including the
  corner columns", the walk two intercolumniations and a column wide (III.2.6); *dipteral* —
  octastyle with a double row round the cella (III.2.7; decastyle for the hypaethral temple,
  III.2.8). *Pseudoperipteral* (IV.8.6): the flank columns engaged in the cella walls.
  Flank count rule: ``2·front − 1`` counting the corners (III.2.5–6; applied by analogy to
  dipteral and pseudoperipteral temples — Portunus has 4 × 7).
* **Intercolumniations** (III.3.1–6): clear space between shafts of pycnostyle 1½ D,
  systyle 2 D, eustyle 2¼ D with the middle bay front and rear 3 D, diastyle 3 D,
  araeostyle "wider than it should be" (we take 4 D — an assumption, Vitruvius gives no
  figure). **Column heights** in lower diameters: eustyle 8½ (III.3.7), araeostyle 8,
  diastyle 8½, systyle 9½, pycnostyle 10 (III.3.10).
* **Module from the front** (III.3.7): the front, "not including the projections of the bases",
  is divided into 11½ parts (tetrastyle eustyle), 18 (hexastyle), 24½ (octastyle); one part is
  the lower diameter. In general ``parts = front + (front − 1)·clear + (middle − clear)``.
* **Upper diameter** (III.3.12): 5/6 of the lower for columns up to 15 ft, 5½/6½ for 15–20 ft,
  6/7 for 20–30, 6½/7½ for 30–40, 7/8 for 40–50 (Roman foot 0.2957 m).
* **Architrave** (III.5.8): columns of 12–15 ft: D/2; 15–20 ft: H/13; 20–25 ft: H/12½;
  25–30 ft: H/12; higher, in proportion (we keep H/12).
* **Cella** (IV.4.1): a non-peripteral temple is twice as long as wide; the cella (with its
  door wall) 1¼ of the width long, the remaining ¾ to the antae the pronaos; antae as thick as
  the columns (the walls, too, here).
* **Steps** (III.4.4): an odd number in front; risers 9–10 in., treads 1½–2 ft. A Greek
  crepidoma (three steps all round) or a Roman podium with a frontal stair (III.4.5).

``(!)`` marks our own assumptions; all of them are fields of :class:`TempleType`, so a
description overrides them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields, replace
from enum import StrEnum
from typing import Any

from ionic_usd.errors import ParameterError
from ionic_usd.params import FieldSpec, check_table

__all__ = [
    "Arrangement",
    "Intercolumniation",
    "Order",
    "Foundation",
    "CLEAR_BAY",
    "HEIGHT_IN_D",
    "EUSTYLE_MIDDLE",
    "FRONTS",
    "ROMAN_FOOT",
    "TempleType",
    "TypePlan",
    "resolve",
    "front_parts",
    "side_rule",
    "upper_ratio_rule",
    "architrave_divisor_rule",
    "type_from_table",
    "TYPE_SCHEMA",
]

ROMAN_FOOT = 0.2957  # m


class Arrangement(StrEnum):
    IN_ANTIS = "in_antis"
    PROSTYLE = "prostyle"
    AMPHIPROSTYLE = "amphiprostyle"
    PERIPTERAL = "peripteral"
    PSEUDOPERIPTERAL = "pseudoperipteral"
    PSEUDODIPTERAL = "pseudodipteral"
    DIPTERAL = "dipteral"


class Intercolumniation(StrEnum):
    PYCNOSTYLE = "pycnostyle"
    SYSTYLE = "systyle"
    EUSTYLE = "eustyle"
    DIASTYLE = "diastyle"
    ARAEOSTYLE = "araeostyle"


class Order(StrEnum):
    """``attic``: architrave, frieze, cornice with dentils; ``asiatic`` (Asia Minor): the
    dentil cornice straight on the architrave, no frieze."""

    ATTIC = "attic"
    ASIATIC = "asiatic"


class Foundation(StrEnum):
    CREPIDOMA = "crepidoma"
    PODIUM = "podium"


#: clear intercolumniation in lower diameters (III.3.1–6; araeostyle 4 is our assumption)
CLEAR_BAY = {
    Intercolumniation.PYCNOSTYLE: 1.5,
    Intercolumniation.SYSTYLE: 2.0,
    Intercolumniation.EUSTYLE: 2.25,
    Intercolumniation.DIASTYLE: 3.0,
    Intercolumniation.ARAEOSTYLE: 4.0,
}
#: the eustyle middle bay, front and rear (III.3.6–7)
EUSTYLE_MIDDLE = 3.0
#: column height in lower diameters (III.3.7 eustyle; III.3.10 the others)
HEIGHT_IN_D = {
    Intercolumniation.PYCNOSTYLE: 10.0,
    Intercolumniation.SYSTYLE: 9.5,
    Intercolumniation.EUSTYLE: 8.5,
    Intercolumniation.DIASTYLE: 8.5,
    Intercolumniation.ARAEOSTYLE: 8.0,
}
#: front column counts each arrangement takes (in antis: the antae count as the end axes)
FRONTS = {
    Arrangement.IN_ANTIS: (4, 6, 8),
    Arrangement.PROSTYLE: (4, 6, 8),
    Arrangement.AMPHIPROSTYLE: (4, 6, 8),
    Arrangement.PERIPTERAL: (4, 6, 8),
    Arrangement.PSEUDOPERIPTERAL: (4, 6, 8),
    Arrangement.PSEUDODIPTERAL: (6, 8),
    Arrangement.DIPTERAL: (8, 10),
}
PERIPTERAL_FAMILY = (
    Arrangement.PERIPTERAL,
    Arrangement.PSEUDOPERIPTERAL,
    Arrangement.PSEUDODIPTERAL,
    Arrangement.DIPTERAL,
)
#: bays from the outer colonnade in to the cella walls' axes (III.2.5–7)
CELLA_INSET = {
    Arrangement.PERIPTERAL: 1,
    Arrangement.PSEUDODIPTERAL: 2,
    Arrangement.DIPTERAL: 2,
}


def front_parts(front: int, clear: float, middle: float | None = None) -> float:
    """Vitruvius' division of the front into modules (III.3.7): the shafts' outer faces
    across, in lower diameters. ``middle``: the clear middle bay (an even front only)."""
    extra = 0.0 if middle is None or front % 2 else middle - clear
    return front + (front - 1) * clear + extra


def side_rule(arrangement: Arrangement, front: int) -> int:
    """Columns down each flank counting the corners: ``2·front − 1`` (III.2.5–6), 0 without
    a flank colonnade."""
    return 2 * front - 1 if arrangement in PERIPTERAL_FAMILY else 0


def upper_ratio_rule(height: float) -> float:
    """Upper / lower diameter for a column ``height`` metres high (III.3.12)."""
    ft = height / ROMAN_FOOT
    for limit, ratio in ((15, 5 / 6), (20, 5.5 / 6.5), (30, 6 / 7), (40, 6.5 / 7.5)):
        if ft <= limit:
            return ratio
    return 7 / 8


def architrave_divisor_rule(height: float, lower_diameter: float) -> float:
    """Column height / architrave height (III.5.8)."""
    ft = height / ROMAN_FOOT
    if ft <= 15:
        return height / (lower_diameter / 2)
    if ft <= 20:
        return 13.0
    if ft <= 25:
        return 12.5
    return 12.0


_M = FieldSpec("float", 1e-3, 1e3, "m")
_R = FieldSpec("float", 1e-3, 1e3)
TYPE_SCHEMA: dict[str, FieldSpec] = {
    "arrangement": FieldSpec("str", choices=tuple(a.value for a in Arrangement)),
    "front": FieldSpec("int", 2, 12, "count"),
    "intercolumniation": FieldSpec("str", choices=tuple(i.value for i in Intercolumniation)),
    "lower_diameter": _M,
    "stylobate_width": _M,
    "stylobate_length": _M,
    "side": FieldSpec("int", 0, 40, "count"),
    "rear": FieldSpec("int", 2, 13, "count"),
    "clear_bay": FieldSpec("float", 0.5, 10.0),
    "middle_bay": FieldSpec("float", 0.5, 10.0),
    "flank_bay": FieldSpec("float", 0.5, 10.0),
    "column_height": _M,
    "upper_diameter_ratio": FieldSpec("float", 0.5, 1.0),
    "margin": _M,
    "order": FieldSpec("str", choices=tuple(o.value for o in Order)),
    "base": FieldSpec("str", max_len=64),
    "foundation": FieldSpec("str", choices=tuple(f.value for f in Foundation)),
    "steps": FieldSpec("int", 1, 60, "count"),
    "step_height": _M,
    "step_tread": _M,
    "podium_height": _M,
    "wall_thickness": _M,
    "pronaos": _M,
    "opisthodomos": FieldSpec("float", 0.0, 1e3, "m"),
    "porch": FieldSpec("int", 1, 20, "count"),
    "architrave_divisor": FieldSpec("float", 4.0, 40.0),
    "frieze_ratio": FieldSpec("float", 0.0, 3.0),
    "cornice_ratio": _R,
    "tympanum_ratio": FieldSpec("float", 2.0, 40.0),
    "roof_slab": _M,
}


@dataclass(frozen=True)
class TempleType:
    """A temple by Vitruvius' rules; ``None`` fields take the rule (module docstring).

    Lengths in metres; ``clear_bay``, ``middle_bay``, ``flank_bay`` in lower diameters (clear
    space between shafts). Either ``lower_diameter`` or ``stylobate_width`` is required.
    """

    arrangement: str = "peripteral"
    front: int = 6
    intercolumniation: str = "eustyle"
    lower_diameter: float | None = None
    stylobate_width: float | None = None
    stylobate_length: float | None = None
    side: int | None = None
    rear: int | None = None
    clear_bay: float | None = None
    middle_bay: float | None = None
    flank_bay: float | None = None
    column_height: float | None = None
    upper_diameter_ratio: float | None = None
    margin: float | None = None
    order: str = "attic"
    base: str | None = None
    foundation: str | None = None
    steps: int | None = None
    step_height: float | None = None
    step_tread: float | None = None
    podium_height: float | None = None
    wall_thickness: float | None = None
    pronaos: float | None = None
    opisthodomos: float | None = None
    porch: int | None = None
    architrave_divisor: float | None = None
    frieze_ratio: float | None = None
    cornice_ratio: float = 1.0
    tympanum_ratio: float = 9.0
    roof_slab: float = 0.35

    def __post_init__(self) -> None:
        ctx = "[type]"
        check_table(
            {
                f.name: getattr(self, f.name)
                for f in fields(self)
                if getattr(self, f.name) is not None
            },
            TYPE_SCHEMA,
            context=ctx,
        )
        arr = Arrangement(self.arrangement)
        if self.base is not None:
            from ionic_usd.column.base import base_preset_names

            if self.base not in base_preset_names():
                raise ParameterError(
                    "base", self.base, "one of " + ", ".join(base_preset_names()), context=ctx
                )
        if self.front not in FRONTS[arr] and self.side is None:
            raise ParameterError(
                "front",
                self.front,
                f"one of {', '.join(map(str, FRONTS[arr]))} for a {arr.value} temple "
                "(or give side = … to leave the rule)",
                context=ctx,
            )
        if self.lower_diameter is None and self.stylobate_width is None:
            raise ParameterError(
                "lower_diameter", "(missing)", "lower_diameter or stylobate_width", context=ctx
            )
        if self.rear is not None and (
            self.rear < self.front
            or arr in (Arrangement.IN_ANTIS, Arrangement.PROSTYLE, Arrangement.PSEUDOPERIPTERAL)
        ):
            raise ParameterError(
                "rear",
                self.rear,
                f"≥ front = {self.front}, and a rear colonnade (not {arr.value})",
                context=ctx,
            )
        if arr in PERIPTERAL_FAMILY and self.side is not None and self.side < self.front:
            raise ParameterError("side", self.side, f"≥ front = {self.front}", context=ctx)

    def with_changes(self, changes: dict[str, Any]) -> TempleType:
        return replace(self, **changes)


@dataclass(frozen=True)
class TypePlan:
    """A type's resolved numbers (metres; the frame of :mod:`ionic_usd.temple.layout`)."""

    type: TempleType
    arrangement: Arrangement
    order: Order
    foundation: Foundation
    lower_diameter: float
    column_height: float
    upper_ratio: float
    clear_bay: float  # D
    middle_bay: float  # D
    flank_bay: float  # D
    xs: tuple[float, ...]  # front column axes, left to right
    xs_rear: tuple[float, ...]  # rear column axes (= xs unless ``rear`` differs)
    side: int  # flank columns counting the corners (0: none)
    flank_spacing: float  # axial, m
    x_outer: float  # |x| of the outer front axes
    z_front: float  # z of the front row's axes
    margin: float
    stylobate_width: float
    stylobate_length: float
    wall_thickness: float
    base_height: float  # stylobate top above the ground
    steps: int
    step_height: float
    step_tread: float
    architrave_divisor: float
    frieze_ratio: float

    @property
    def front_spacing(self) -> float:
        """The normal axial bay of the front, m."""
        return self.lower_diameter * (1 + self.clear_bay)

    def intercolumniations(self) -> tuple[float, ...]:
        """Clear spaces between the front shafts, m."""
        d = self.lower_diameter
        return tuple(b - a - d for a, b in zip(self.xs, self.xs[1:], strict=False))


def _front_axes(front: int, d: float, clear: float, middle: float) -> tuple[float, ...]:
    bays = [d * (1 + clear)] * (front - 1)
    if front % 2 == 0:
        bays[front // 2 - 1] = d * (1 + middle)
    xs = [0.0]
    for b in bays:
        xs.append(xs[-1] + b)
    half = xs[-1] / 2
    return tuple(x - half for x in xs)


def resolve(t: TempleType) -> TypePlan:
    """The numbers of a type (module docstring; each rule cited there)."""
    arr, ic = Arrangement(t.arrangement), Intercolumniation(t.intercolumniation)
    order = Order(t.order)
    found = Foundation(
        t.foundation or ("podium" if arr in (Arrangement.PSEUDOPERIPTERAL,) else "crepidoma")
    )
    d, margin, clear, middle, flank = _module(t, ic)
    ctx = "[type]"
    if d <= 0 or margin < 0.5 * d:
        raise ParameterError(
            "stylobate_width",
            t.stylobate_width,
            f"a width leaving the corner columns on the stylobate (margin {margin:.3f} m "
            f"< D/2 = {d / 2:.3f} m)",
            context=ctx,
        )
    h = t.column_height if t.column_height is not None else HEIGHT_IN_D[ic] * d
    xs = _front_axes(t.front, d, clear, middle)
    x_outer = xs[-1]
    # a rear row of another count spans the same corners evenly (the late Artemision: 9)
    xs_rear = xs
    if t.rear is not None and t.rear != t.front:
        xs_rear = tuple(-x_outer + 2 * x_outer * i / (t.rear - 1) for i in range(t.rear))
    width = 2 * (x_outer + margin)
    side = t.side if t.side is not None else side_rule(arr, t.front)
    flank_spacing = d * (1 + flank)
    if arr in PERIPTERAL_FAMILY:
        z_front = (side - 1) * flank_spacing / 2
        length = 2 * (z_front + margin)
        if t.stylobate_length is not None:
            length = t.stylobate_length
    else:
        side = 0
        # IV.4.1: twice as long as wide
        length = t.stylobate_length if t.stylobate_length is not None else 2 * width
        z_front = length / 2 - margin
    base_h, steps, rise, tread = _foundation(t, found, d, h)
    ratio = t.upper_diameter_ratio or upper_ratio_rule(h)
    div = t.architrave_divisor or architrave_divisor_rule(h, d)
    fr = _frieze_ratio(t, order)
    wall = t.wall_thickness if t.wall_thickness is not None else d  # IV.4.1 antae = D
    if margin < wall / 2 and arr not in PERIPTERAL_FAMILY:
        raise ParameterError(
            "margin", margin, f"≥ half the wall thickness {wall / 2:.3f} m", context=ctx
        )
    if length <= width and arr in PERIPTERAL_FAMILY:
        raise ParameterError(
            "side", side, f"a flank longer than the front ({t.front})", context=ctx
        )
    return TypePlan(
        t, arr, order, found, d, h, ratio, clear, middle, flank, xs, xs_rear, side, flank_spacing,
        x_outer, z_front, margin, width, length, wall, base_h, steps, rise, tread, div, fr,
    )  # fmt: skip


def _module(t: TempleType, ic: Intercolumniation) -> tuple[float, float, float, float, float]:
    """The module D, the margin from the outer axes to the stylobate's edge and the clear
    bays (ordinary, middle, flank) in D: from the rule, or from measured D, width, margin."""
    clear = t.clear_bay if t.clear_bay is not None else CLEAR_BAY[ic]
    middle = t.middle_bay
    if middle is None:
        middle = EUSTYLE_MIDDLE if ic is Intercolumniation.EUSTYLE else clear
    flank = t.flank_bay if t.flank_bay is not None else clear
    # (!) margin from the outer axes to the stylobate edge: 0.75 D (the Ionic base is
    # 1 3/8 D wide, III.5.1, so its plinth keeps 1/16 D of stylobate beyond it)
    mu = 0.75
    span = front_parts(t.front, clear, middle) - 1  # outer axes apart, in D
    if t.lower_diameter is not None:
        d = t.lower_diameter
        margin = t.margin if t.margin is not None else mu * d
        if t.stylobate_width is not None and t.margin is None:
            margin = (t.stylobate_width - span * d) / 2
        elif t.stylobate_width is not None and t.clear_bay is None:
            # measured D, width and margin: the bays follow (the middle keeps its excess)
            extra = middle - clear
            even = t.front % 2 == 0
            axes = (t.stylobate_width - 2 * margin) / d  # outer axes apart, in D
            clear = (axes - extra * even) / (t.front - 1) - 1
            middle = clear + extra
            flank = t.flank_bay if t.flank_bay is not None else clear
    else:
        assert t.stylobate_width is not None
        if t.margin is not None:
            d = (t.stylobate_width - 2 * t.margin) / span
            margin = t.margin
        else:
            d = t.stylobate_width / (span + 2 * mu)
            margin = mu * d
    return d, margin, clear, middle, flank


def _foundation(
    t: TempleType, found: Foundation, d: float, h: float
) -> tuple[float, int, float, float]:
    """Height, steps, riser and tread of the crepidoma or podium: (!) crepidoma risers D/3
    and treads D/2; podium 0.29 H (Portunus' ratio) with risers of at most 10 in. (III.4.4)."""
    if found is Foundation.CREPIDOMA:
        steps = t.steps if t.steps is not None else 3
        rise = t.step_height if t.step_height is not None else d / 3
        base_h = steps * rise
        tread = t.step_tread if t.step_tread is not None else d / 2
    else:
        base_h = t.podium_height if t.podium_height is not None else 0.29 * h
        steps = t.steps if t.steps is not None else max(3, math.ceil(base_h / (10 * 0.0246)))
        rise = base_h / steps
        tread = t.step_tread if t.step_tread is not None else 1.75 * ROMAN_FOOT
    return base_h, steps, rise, tread


def _frieze_ratio(t: TempleType, order: Order) -> float:
    """III.5.10: a frieze 1/4 higher than the architrave when it carries sculpture, 1/4 lower
    when plain; we take the sculptured one (Attic) and none for the Asiatic order."""
    fr = t.frieze_ratio
    if fr is None:
        fr = 1.25 if order is Order.ATTIC else 0.0
    if order is Order.ASIATIC:
        fr = 0.0
    return fr


def type_from_table(table: Any, *, context: str) -> TempleType:
    """A ``[type]`` table as a :class:`TempleType` (unknown keys and bad values: one-line
    :class:`ParameterError` naming them)."""
    checked = check_table(table, TYPE_SCHEMA, context=f"{context} [type]")
    for key in ("arrangement", "front"):
        if key not in checked:
            raise ParameterError(
                key, "(missing)", "a value (required key)", context=f"{context} [type]"
            )
    try:
        return TempleType(**checked)
    except ParameterError as exc:
        raise ParameterError(exc.name, exc.value, exc.valid, context=f"{context} [type]") from None
