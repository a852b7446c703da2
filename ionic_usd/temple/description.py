"""The temple description's value types: dimensions, column placements, hypotheses, layers.

A temple TOML (``ionic_usd/data/portunus.toml`` is the reference; its comments cite every
number) holds ``[temple] name``, dimension sections (``[podium]``, ``[stylobate]``,
``[columns]``, ``[steps]``, ``[cella]``, ``[entablature]``, ``[roof]``; the key ``section.key``
is the field ``section_key`` of :class:`TempleParams`), ``[mouldings]``
(:mod:`ionic_usd.temple.mouldings`), extra ``[[cuboid]]`` tables and ``[[hypothesis]]``
tables. The readers that check those tables and turn them into these values are
:mod:`ionic_usd.temple.tables`; :mod:`ionic_usd.temple.layout` builds the geometry.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Iterator, Mapping
from dataclasses import dataclass, fields
from enum import StrEnum
from types import MappingProxyType
from typing import Any

import numpy as np

from ionic_usd.errors import ParameterError
from ionic_usd.params import check_identifier

__all__ = [
    "Layer",
    "ColumnKind",
    "Certainty",
    "ColumnPlacement",
    "Hypothesis",
    "questions",
    "exclusive_clash",
    "TempleParams",
    "SECTIONS",
    "COMPOSER_NAMESPACES",
    "enum_value",
]

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


def enum_value(cls, value: object, name: str, context: str):
    """``cls(value)``, or a :class:`ParameterError` listing the valid values."""
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
        raise ParameterError(
            name, value, "a finite number > 0" if positive else "finite", context=context
        )
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
        object.__setattr__(self, "kind", enum_value(ColumnKind, self.kind, "kind", ctx))
        if self.angle_rotation_deg is not None:
            object.__setattr__(
                self,
                "angle_rotation_deg",
                _finite("angle_rotation_deg", self.angle_rotation_deg, ctx),
            )

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
    ``question``: the question it answers, shared by mutually exclusive alternatives (e.g.
    ``frieze`` for ``frieze-plain`` and ``frieze-garlands``: one variant set, one value each);
    empty for an independent hypothesis (its own question, a switch).
    """

    id: str
    description: str
    sources: tuple[str, ...]
    certainty: Certainty
    changes: Mapping[str, Any]
    question: str = ""

    @property
    def key(self) -> str:
        """The question answered: ``question``, or the id of an independent hypothesis."""
        return self.question or self.id

    def __post_init__(self) -> None:
        ctx = f"hypothesis {self.id!r}"
        check_identifier("id", self.id, context=ctx)  # it names a file: never a path
        if self.question:
            check_identifier("question", self.question, context=ctx)
        object.__setattr__(
            self, "certainty", enum_value(Certainty, self.certainty, "certainty", ctx)
        )
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
        for key, value, expected in self._violations():
            raise ParameterError(key, value, expected, context=ctx)

    def _violations(self) -> Iterator[tuple[str, object, str]]:
        """The proportions that do not make a temple, as (key, value, expected), in order.

        Checked lazily, one at a time: a later check may rely on a derived dimension that only
        an earlier one guarantees (``margin`` needs ``columns.side > columns.front``).
        """
        if self.columns_front < 2 or self.columns_side < self.columns_front + 1:
            yield (
                "columns.side",
                self.columns_side,
                f"> columns.front = {self.columns_front} (≥ 2)",
            )
        if not 1 <= self.columns_porch_depth <= self.columns_side - 2:
            yield (
                "columns.porch_depth",
                self.columns_porch_depth,
                f"1 … {self.columns_side - 2} (a cella needs ≥ 1 bay)",
            )
        if self.steps_count < 1:
            yield ("steps.count", self.steps_count, "≥ 1")
        if self.stylobate_length <= self.stylobate_width:
            yield (
                "stylobate.length",
                self.stylobate_length,
                f"> stylobate.width = {self.stylobate_width}",
            )
        if self.margin <= self.columns_lower_diameter / 2:
            yield (
                "stylobate.width",
                self.stylobate_width,
                f"a value leaving the corner columns on the stylobate (margin {self.margin:.3f}"
                f" m ≤ lower radius {self.columns_lower_diameter / 2:.3f} m)",
            )
        if self.podium_base_width <= self.stylobate_width:
            yield (
                "podium.base_width",
                self.podium_base_width,
                f"> stylobate.width = {self.stylobate_width}",
            )
        if self.stair_run <= 0:
            yield (
                "podium.base_length",
                self.podium_base_length,
                "long enough for the stairs (stylobate + projections)",
            )
        if self.podium_footing_height >= self.podium_height:
            yield (
                "podium.footing_height",
                self.podium_footing_height,
                f"< podium.height = {self.podium_height}",
            )
        if self.podium_cheek_wall_width >= self.stylobate_width / 2:
            yield (
                "podium.cheek_wall_width",
                self.podium_cheek_wall_width,
                f"< half the stylobate width ({self.stylobate_width / 2})",
            )
        inner = 2 * (self.x_axis - self.cella_wall_thickness)
        if self.door_width >= inner or self.door_height >= self.columns_height:
            yield (
                "cella.door_width_ratio",
                self.cella_door_width_ratio,
                "a door that fits inside the cella's front wall",
            )
        if self.cella_wall_thickness >= self.axial_spacing:
            yield (
                "cella.wall_thickness",
                self.cella_wall_thickness,
                f"< the axial spacing {self.axial_spacing:.3f}",
            )

    # -- derived dimensions (see the module docstring) -------------------------------------
    @property
    def axial_spacing(self) -> float:
        return (self.stylobate_length - self.stylobate_width) / (
            self.columns_side - self.columns_front
        )

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


SECTIONS: dict[str, tuple[str, ...]] = {}
for _f in fields(TempleParams):
    if _f.name != "name":
        _sec, _key = _f.name.split("_", 1)
        SECTIONS.setdefault(_sec, ())
        SECTIONS[_sec] += (_key,)


def questions(hyps: Iterable[Hypothesis]) -> dict[str, tuple[Hypothesis, ...]]:
    """Question → its alternatives, in description order (an independent hypothesis is the
    one alternative of its own question)."""
    out: dict[str, list[Hypothesis]] = {}
    for h in hyps:
        out.setdefault(h.key, []).append(h)
    return {q: tuple(hs) for q, hs in out.items()}


def exclusive_clash(ids: Iterable[str], hyps: Iterable[Hypothesis]) -> str | None:
    """A one-line reason why ``ids`` cannot be applied together (two alternatives of one
    question), or None."""
    chosen = set(ids)
    for q, alts in questions(hyps).items():
        both = [h.id for h in alts if h.id in chosen]
        if len(both) > 1:
            return (
                f"{' and '.join(repr(b) for b in both)} are alternatives of the question "
                f"{q!r}: select one"
            )
    return None
