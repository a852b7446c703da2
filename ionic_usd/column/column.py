"""The whole column: base + shaft + capital stacked on one axis, levels of detail, presets.

Vertical placement (metres, +Y up, origin at the centre of the base's bottom face)::

    0 ............................ base bottom (on the stylobate)
    base height .................. shaft bottom ring (welded ring of the base's top)
    base height + shaft length ... shaft top = capital origin (the volutes hang below it)
    + capital height ............. abacus top = column top

Every base variant is scaled uniformly (``BaseParams.scale``) to the column's base height, so the
shaft and the capital do not move when the base grammar changes — a base variant changes only
the base. The Temple of Portunus column is 8.22 m from the base bottom to the abacus top with a
lower diameter of 0.95 m (issue #6 brief, after Piranesi's survey as used by Konečný et al.);
its shaft height $a is derived so that the total is exact.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, TypedDict

import numpy as np

from ionic_usd.column.base import BaseParams, base_preset_names, build_base, load_base_preset
from ionic_usd.column.capital import CapitalParams, build_capital, capital_height
from ionic_usd.column.portunus import PORTUNUS_HEIGHT, PORTUNUS_LOWER_DIAMETER
from ionic_usd.column.shaft import ShaftParams, build_shaft
from ionic_usd.errors import GrammarError, ParameterError
from ionic_usd.geometry.boolean import union
from ionic_usd.geometry.guard import guarded
from ionic_usd.geometry.mesh import Mesh
from ionic_usd.lod import LOD_NAMES
from ionic_usd.lod import lod_sampling as _lod
from ionic_usd.params import (
    UNIT_LIMITS,
    FieldSpec,
    check_table,
    check_value,
    dataclass_from_mapping,
    dataclass_schema,
)

__all__ = [
    "check_column_tables",
    "ColumnParams",
    "Column",
    "build_column",
    "portunus_column_params",
    "PORTUNUS_HEIGHT",
    "PORTUNUS_LOWER_DIAMETER",
    "COLUMN_DOCS",
    "column_params_from_mapping",
    "column_params_to_tables",
]


class _BaseSampling(TypedDict):
    """The BaseParams fields a column imposes on every base (its shaft's radius, its LOD)."""

    shaft_radius: float
    segments: int
    profile_slices: int


@dataclass(frozen=True)
class ColumnParams:
    """A column: its parts' parameters and a level of detail.

    A named LOD (high, medium, low) sets the sampling of every part — the shaft's $h and $i,
    the base's profile slices, the capital's spiral, ring and bolster counts; ``custom`` keeps
    those fields as given.

    ``base`` is a preset name (``G1``, ``G2``, ``attic_bezier``, ``attic_bezier_plinth``) or a
    grammar string; ``base_height`` (m) is what every base is scaled to (None: the preset's own
    height). The LOD overrides the sampling fields of ``shaft`` and ``capital``.
    """

    # defaults: the Temple of Portunus column, the same as portunus_column_params()
    shaft: ShaftParams = field(default_factory=lambda: portunus_shaft_params())
    capital: CapitalParams = field(default_factory=CapitalParams)
    base: str = "attic_bezier_plinth"
    base_height: float | None = PORTUNUS_LOWER_DIAMETER / 2.0
    lod: str = "high"
    base_plinth: int | None = None

    def __post_init__(self) -> None:
        _lod(self.lod)
        if self.base_plinth is not None and (
            isinstance(self.base_plinth, bool)
            or not isinstance(self.base_plinth, int)
            or self.base_plinth < 0
        ):
            raise ParameterError("base_plinth", self.base_plinth, "a count >= 0 or unset")
        if self.base_height is not None and not (
            math.isfinite(self.base_height) and self.base_height > 0
        ):
            raise ParameterError("base_height", self.base_height, "a length > 0 (m) or unset")
        self.base_params()  # validates the grammar / preset name now, not at build time

    def base_params(self, base: str | None = None) -> BaseParams:
        """BaseParams for ``base`` (default: this column's), at this LOD and base height."""
        lod = _lod(self.lod)
        shaft = self.shaft_params()
        common: _BaseSampling = {
            "shaft_radius": shaft.bottom_radius,
            "segments": shaft.ring_segments,
            "profile_slices": lod.base_slices if lod else 8,
        }
        name = self.base if base is None else base
        bp = _base_from_text(name, common)
        if self.base_plinth is not None:
            bp = dataclasses.replace(bp, plinth_modules=self.base_plinth)
        h = guarded(lambda: bp.height, "base", name)
        if not (math.isfinite(h) and h > 0):
            raise ParameterError("base", name, "a base grammar with a height > 0 (m)")
        if self.base_height is not None:
            bp = dataclasses.replace(bp, scale=bp.scale * self.base_height / h)
        return bp

    def shaft_params(self) -> ShaftParams:
        lod = _lod(self.lod)
        if lod is None:
            return self.shaft
        return dataclasses.replace(
            self.shaft,
            flute_slices=lod.flute_slices,
            flute_slices_per_fillet_slice=lod.fillet_ratio,
            body_rows=lod.shaft_rows,
        )

    def capital_params(self, scroll: str | None = None) -> CapitalParams:
        lod = _lod(self.lod)
        changes: dict[str, int | str] = (
            {}
            if lod is None
            else {
                "spiral_samples": lod.spiral_samples,
                "ring_segments": lod.ring_segments,
                "bolster_rows": lod.bolster_rows,
            }
        )
        if scroll is not None:
            changes["scroll"] = scroll
        return self.capital.with_(**changes)

    def with_lod(self, lod: str) -> ColumnParams:
        return dataclasses.replace(self, lod=lod)

    def with_flutes(self, flutes: int) -> ColumnParams:
        """The same column with another flute count.

        The flute/period ratio is kept; the fluted body $a is re-derived so the shaft keeps its
        length (wider flutes have taller rounded ends), and the bottom/top rings keep their
        vertex count, so every base variant fits every flute variant.
        """
        sh = self.shaft
        if flutes == sh.flutes:
            return self
        ratio = sh.flute_angle / (360.0 / sh.flutes)
        probe = dataclasses.replace(
            sh,
            flutes=flutes,
            flute_angle=ratio * 360.0 / flutes,
            ring_vertices=self.shaft_params().ring_segments,
        )
        height = sh.length - (probe.length - probe.height)
        if height <= 0:
            raise ParameterError("flutes", flutes, "a count whose flute ends fit the shaft")
        return dataclasses.replace(self, shaft=dataclasses.replace(probe, height=height))


@dataclass(frozen=True)
class Column:
    """A built column: part meshes in column coordinates and the stacking heights (m)."""

    params: ColumnParams
    base: Mesh
    shaft: Mesh
    capital_body: Mesh
    base_height: float
    shaft_length: float
    capital_height: float

    @property
    def height(self) -> float:
        return self.base_height + self.shaft_length + self.capital_height

    @property
    def capital(self) -> Mesh:
        """The capital: one solid (abacus, echinus, volutes, canales and bolsters united)."""
        return self.capital_body

    def parts(self) -> dict[str, Mesh]:
        """Prim name → mesh: ``Base``, ``Shaft``, ``CapitalBody`` (each one closed solid)."""
        return {"Base": self.base, "Shaft": self.shaft, "CapitalBody": self.capital_body}

    @property
    def n_triangles(self) -> int:
        return sum(m.n_triangles for m in self.parts().values())


def build_base_part(params: ColumnParams, base: str | None = None, **kwargs) -> Mesh:
    """The base as a closed, outward solid (or a ParameterError naming ``base``)."""
    name = params.base if base is None else base
    return guarded(
        lambda: build_base(params.base_params(base), name="base", **kwargs), "base", name
    )


def build_shaft_part(params: ColumnParams, base_height: float, **kwargs) -> Mesh:
    """The shaft lifted by ``base_height`` (a ParameterError naming ``shaft`` if it fails)."""
    return guarded(
        lambda: build_shaft(params.shaft_params(), y_offset=base_height, name="shaft", **kwargs),
        "shaft",
        "parameters",
    )


def build_capital_part(
    params: ColumnParams, y: float, scroll: str | None = None, *, angle: bool = False
) -> Mesh:
    """The capital lifted to ``y``: abacus, echinus, volutes, canales and the scroll's bolsters
    united into one closed solid (manifold3d); ``angle`` builds the angle capital.

    A failure is a ParameterError naming the scroll (a user's ring grammar is the likely
    culprit) or the capital (for the presets)."""
    from ionic_usd.grammar.scroll import scroll_preset_names

    cp = params.capital_params(scroll)
    text = _scroll_text(cp)
    lift = np.array([0.0, y, 0.0])

    def build() -> Mesh:
        parts = build_capital(cp, top_radius=params.shaft.top_radius, angle=angle)
        return union(
            [m.with_(points=m.points + lift) for m in parts.as_dict().values()], name="capital"
        )

    return guarded(build, "capital" if text in scroll_preset_names() else "scroll", text)


def build_column(params: ColumnParams | None = None) -> Column:
    """Build every part of a column at its LOD, stacked on the +Y axis."""
    params = params or portunus_column_params()
    bp = guarded(params.base_params, "base", params.base)
    if not (bp.height > 0 and math.isfinite(bp.height)):
        raise ParameterError("base", params.base, "a base grammar with a height > 0")
    base = build_base_part(params)
    shaft = build_shaft_part(params, bp.height)
    y_cap = bp.height + params.shaft.length
    body = build_capital_part(params, y_cap)
    return Column(
        params, base, shaft, body, bp.height, params.shaft.length, capital_height(params.capital)
    )


def _scroll_text(cp: CapitalParams) -> str:
    from ionic_usd.grammar.scroll import format_scroll

    s = cp.scroll
    return s if isinstance(s, str) else format_scroll(s)


def portunus_column_params(
    *,
    lod: str = "high",
    base: str = "attic_bezier_plinth",
    flutes: int = 24,
    height: float = PORTUNUS_HEIGHT,
    lower_diameter: float = PORTUNUS_LOWER_DIAMETER,
    scroll: str = "S1",
) -> ColumnParams:
    """The Temple of Portunus column (Rome, Forum Boarium, 1st c. BC).

    Sources: total height 8.22 m and lower diameter 0.95 m (issue #6 brief, after Piranesi's
    measured drawings used by the paper); top diameter 6/7 of the bottom (Vitruvius III.3.12:
    columns of 20–30 ft diminish by 1/7 — 8.22 m ≈ 28 Roman ft); Attic base half a diameter
    high (Vitruvius III.5.1–3); 24 flutes with fillets ¼ of a flute and semicircular flutes
    (Vitruvius III.5.14; ``flutes=20`` is the reconstruction hypothesis); capital proportions
    after Vitruvius III.5.5–8 (see :mod:`ionic_usd.column.capital`), scaled with the lower
    diameter (the capital of a 1.2 m column is 1.2 / 0.95 times the Portunus one).
    """
    cap = CapitalParams().scaled(lower_diameter / PORTUNUS_LOWER_DIAMETER)
    shaft = portunus_shaft_params(
        height=height, lower_diameter=lower_diameter, flutes=flutes, capital=cap
    )
    return ColumnParams(
        shaft=shaft,
        capital=cap.with_(scroll=scroll),
        base=base,
        base_height=lower_diameter / 2.0,
        lod=lod,
    )


def portunus_shaft_params(
    *,
    height: float = PORTUNUS_HEIGHT,
    lower_diameter: float = PORTUNUS_LOWER_DIAMETER,
    flutes: int = 24,
    capital: CapitalParams | None = None,
) -> ShaftParams:
    """The shaft of a column ``height`` m tall from base bottom to abacus top, with a base half
    a diameter high: top diameter 6/7 of the lower one, flutes of 4/5 of the period."""
    d = lower_diameter / 2.0
    cap = capital or CapitalParams()
    probe = ShaftParams(
        bottom_radius=d, top_radius=d * 6.0 / 7.0, flutes=flutes, flute_angle=0.8 * 360.0 / flutes
    )
    fixed = probe.length - probe.height  # rings + flute ends
    shaft_a = height - lower_diameter / 2.0 - capital_height(cap) - fixed
    if not shaft_a > 0:
        raise ParameterError("height", height, "tall enough for base, capital and flute ends")
    return dataclasses.replace(probe, height=shaft_a)


COLUMN_DOCS: dict[str, tuple[str, str, str]] = {
    "lod": (
        "",
        "name",
        f"level of detail: {', '.join(LOD_NAMES)}, or custom (use the sampling "
        "fields of [shaft] and [capital] as given)",
    ),
    "base": (
        "",
        "name|grammar",
        "base preset (G1, G2, attic_bezier, attic_bezier_plinth) or a "
        "base grammar string (tori v1 or Bézier v2, the paper's Tables 2–3)",
    ),
    "base_height": ("", "m", "height every base is scaled to (unset: the grammar's own)"),
    "base_plinth": (
        "",
        "count",
        "bottom base modules built as a square plinth (unset: the preset's; a grammar: 0)",
    ),
    "scroll": ("", "name|grammar", "scroll-body ring grammar: S1, S2 or 'R<r> P<p>, …'"),
}


_COLUMN_TABLE = {
    "lod": FieldSpec("str", max_len=16),
    "base": FieldSpec("str", max_len=4096),
    "base_height": FieldSpec("float", 0.0, UNIT_LIMITS["m"], "m"),
    "base_plinth": FieldSpec("int", 0, 64),
    "scroll": FieldSpec("str", max_len=4096),
}


def check_column_tables(data: Mapping[str, Any], *, context: str) -> None:
    """Check ``[column]``, ``[shaft]``, ``[capital]``, ``[volute]`` (types and ranges) against
    the parameter classes' schemas (:func:`ionic_usd.params.dataclass_schema`)."""
    from ionic_usd.column.volute import VoluteParams

    for table, schema in (
        ("column", _COLUMN_TABLE),
        ("shaft", dataclass_schema(ShaftParams)),
        ("capital", dataclass_schema(CapitalParams)),
        ("volute", dataclass_schema(VoluteParams)),
    ):
        if table in data:
            check_table(
                check_value(table, data[table], FieldSpec("table"), context=context),
                {k: v for k, v in schema.items() if k != "volute"},
                context=f"{context} [{table}]",
            )


def column_params_from_mapping(
    data: dict, *, context: str = "column config", base: ColumnParams | None = None
) -> ColumnParams:
    """ColumnParams from TOML-like tables ``[column]``, ``[shaft]``, ``[capital]``, ``[volute]``.

    Missing tables keep ``base``'s values (default: the Portunus column); unknown tables or keys
    are errors naming them.
    """
    from ionic_usd.column.volute import VoluteParams

    cur = base or portunus_column_params()
    unknown = sorted(set(data) - {"column", "shaft", "capital", "volute"})
    if unknown:
        raise ParameterError(
            "table",
            f"[{unknown[0]}]",
            "one of [column], [shaft], [capital], [volute]",
            context=context,
        )
    for table in ("column", "shaft", "capital", "volute"):
        if table in data and not isinstance(data[table], dict):
            raise ParameterError(table, data[table], "a table", context=context)
    check_column_tables(data, context=context)  # types and ranges, at the boundary
    col = dict(data.get("column", {}))
    bad = sorted(set(col) - set(COLUMN_DOCS))
    if bad:
        raise ParameterError(
            bad[0],
            col[bad[0]],
            f"one of the keys {', '.join(COLUMN_DOCS)}",
            context=f"{context} [column]",
        )
    shaft = dataclass_from_mapping(
        ShaftParams, data.get("shaft", {}), context=f"{context} [shaft]", base=cur.shaft
    )
    volute = dataclass_from_mapping(
        VoluteParams, data.get("volute", {}), context=f"{context} [volute]", base=cur.capital.volute
    )
    cap_map = dict(data.get("capital", {}))
    if "scroll" in col:
        cap_map["scroll"] = col.pop("scroll")
    cap_fields = {f.name for f in dataclasses.fields(CapitalParams) if not f.name.startswith("_")}
    bad = sorted(set(cap_map) - cap_fields - {"scroll"})
    if bad or "volute" in cap_map:
        key = bad[0] if bad else "volute"
        raise ParameterError(
            key,
            cap_map[key],
            "a [capital] key (volute parameters go in [volute])",
            context=f"{context} [capital]",
        )
    capital = cur.capital.with_(volute=volute, **cap_map)
    return dataclasses.replace(cur, shaft=shaft, capital=capital, **col)


def column_params_to_tables(p: ColumnParams) -> dict[str, dict]:
    """The inverse of :func:`column_params_from_mapping` (for ``--print-config`` and fitting)."""

    def plain(obj) -> dict:
        out = {}
        for f in dataclasses.fields(obj):
            if f.name.startswith("_"):
                continue
            v = getattr(obj, f.name)
            if dataclasses.is_dataclass(v) or (isinstance(v, tuple) and not v):  # () : unset
                continue
            out[f.name] = v if not hasattr(v, "to_string") else v.to_string()
        return out

    cap = plain(p.capital)
    cap.pop("scroll", None)  # a parsed grammar (a dataclass) is left out by plain(): as text
    scroll = p.capital.scroll
    if not isinstance(scroll, str):
        from ionic_usd.grammar.scroll import format_scroll

        scroll = format_scroll(scroll)
    column: dict[str, Any] = {"lod": p.lod, "base": p.base, "scroll": scroll}
    if p.base_height is not None:
        column["base_height"] = p.base_height
    if p.base_plinth is not None:
        column["base_plinth"] = p.base_plinth
    return {
        "column": column,
        "shaft": plain(p.shaft),
        "capital": cap,
        "volute": plain(p.capital.volute),
    }


def _base_from_text(name: str, common: _BaseSampling) -> BaseParams:
    """The base a column names: a shipped preset when ``name`` is one of
    :func:`~ionic_usd.column.base.base_preset_names`, otherwise a base grammar string.

    A text that is neither gets one error naming both readings; a grammar that goes wrong past
    its first token keeps the grammar's own error (with the caret under the mistake).
    """
    presets = base_preset_names()
    if name in presets:
        return load_base_preset(name, **common)
    try:
        return BaseParams(grammar=name, **common)
    except GrammarError as err:
        if err.offset > 0:
            raise
        raise ParameterError(
            "base",
            name,
            f"a base preset ({', '.join(presets)}) or a base grammar such as "
            "'R0.12 H0.05 C1 R0.12'",
        ) from None
