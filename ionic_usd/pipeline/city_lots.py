"""Each lot's temple build: its choice (:mod:`ionic_usd.city.choose`) made a :class:`TempleSpec`.

:func:`lot_specs` runs step 1 of the city build: for every lot the temple it holds — the
description it names, a preset, a type, or the city's seeded choice sized to the lot — as
a spec (content-keyed: equal choices share a build), the uniform scales it may take to fit,
and what was chosen (for the summary).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from ionic_usd.city.choose import TempleChoice, lot_rng, temple_for_lot
from ionic_usd.city.layout import lot_box
from ionic_usd.city.plan import CityPlan
from ionic_usd.errors import ParameterError
from ionic_usd.pipeline.spec import TempleSpec, temple_spec

__all__ = ["LotSpecs", "lot_specs", "PORTUNUS_LOWER_DIAMETER"]

#: the module the city's scale range is relative to (portunus.toml's lower diameter)
PORTUNUS_LOWER_DIAMETER = 0.95
# a chosen type fills at most this share of its lot's box (room for the fit's 1 mm slack and
# for a lot that is not a rectangle)
_FILL = 0.97


@dataclass(frozen=True)
class LotSpecs:
    """Step 1's result: the unique builds, each lot's build index, its fit scale range (None:
    the city's) and its choice (a JSON-able dict)."""

    specs: list[TempleSpec]
    build: np.ndarray
    scale_ranges: list[tuple[float, float] | None]
    choices: list[dict]


def lot_specs(plan: CityPlan, opts, centre: Sequence[float] | np.ndarray | None) -> LotSpecs:
    """The temple build of every lot of ``plan`` (``opts``: a :class:`CityOptions`)."""
    specs: list[TempleSpec] = []
    index: dict[str, int] = {}
    build = np.zeros(len(plan.lots), dtype=np.int32)
    ranges: list[tuple[float, float] | None] = []
    choices: list[dict] = []
    cache: dict[tuple, TempleSpec] = {}
    diameters: dict[str, float] = {}
    col_rng = np.random.default_rng(opts.seed)
    lo, hi = opts.scale_range
    module = (lo * PORTUNUS_LOWER_DIAMETER, hi * PORTUNUS_LOWER_DIAMETER)
    if opts.temple is not None and opts.temple != "auto":  # checked once, named as its flag
        try:
            temple_spec(opts.temple, base_dir=plan.base_dir, texture_size=opts.texture_size)
        except ParameterError:
            raise ParameterError(
                "--temple",
                opts.temple,
                "a built-in description (ionic-usd presets lists them), auto, or a temple TOML",
            ) from None
    for i, lot in enumerate(plan.lots):
        ctx = f"{plan.source} lot {lot.id}"
        props: dict[str, object] = dict(lot.choice)
        if lot.temple is not None:
            props["temple"] = lot.temple
        elif not props and opts.temple is not None:
            props["temple"] = opts.temple
        if ("temple" in props and props["temple"] != "auto") or "preset" in props:
            choice = temple_for_lot(
                props,
                lot_rng(opts.seed, lot.id),
                width=0,
                depth=0,
                module_range=module,
                context=ctx,
            )
        else:
            w, d = lot_box(lot, None if centre is None else [float(c) for c in centre])
            choice = temple_for_lot(
                props,
                lot_rng(opts.seed, lot.id),
                width=_FILL * w,
                depth=_FILL * d,
                module_range=module,
                context=ctx,
            )
        spec = _spec(choice, lot.column, plan, opts, ctx, cache, diameters, col_rng)
        build[i] = index.setdefault(spec.key, len(index))
        if build[i] == len(specs):
            specs.append(spec)
        ranges.append(lot.scale or choice.scale_range)
        choices.append({"lot": lot.id, "build": spec.folder, **dict(choice.type)})
    return LotSpecs(specs, build, ranges, choices)


def _spec(
    choice: TempleChoice,
    column: Mapping[str, float],
    plan: CityPlan,
    opts,
    ctx: str,
    cache: dict[tuple, TempleSpec],
    diameters: dict[str, float],
    col_rng: np.random.Generator,
) -> TempleSpec:
    """The spec of one choice: a derived description as it is; a named one with the lot's
    column overrides, or ``--column-variety``'s drawn lower diameter."""
    if choice.description is not None:
        key: tuple = ("derived", choice.description)
        if key not in cache:
            spec = TempleSpec(choice.name, choice.description, int(opts.texture_size))
            spec.layout()  # validates before any build
            cache[key] = spec
        return cache[key]
    name = str(choice.temple)
    base_key: tuple = (name, ())
    if base_key not in cache:
        cache[base_key] = temple_spec(
            name, base_dir=plan.base_dir, texture_size=opts.texture_size, context=ctx
        )
    col: dict[str, float] = dict(column)
    if not col and opts.column_variety > 1:
        if name not in diameters:
            diameters[name] = cache[base_key].layout().params.columns_lower_diameter
        d0 = diameters[name]
        levels = np.linspace(0.95 * d0, 1.05 * d0, opts.column_variety)
        col = {"lower_diameter": round(float(levels[col_rng.integers(opts.column_variety)]), 4)}
    if not col:
        return cache[base_key]
    vkey = (name, tuple(sorted(col.items())))
    if vkey not in cache:
        cache[vkey] = temple_spec(
            name, col, base_dir=plan.base_dir, texture_size=opts.texture_size, context=ctx
        )
    return cache[vkey]
