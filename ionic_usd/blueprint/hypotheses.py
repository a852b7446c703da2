"""A temple's hypotheses as values (no ``pxr``): the variant vocabulary they become on
``/Temple``, the part and column-group prim names, and the checks that say, before anything is
written, whether the composer can realise each one and whether their combinations can be
checked in bounded time.

:mod:`ionic_usd.usd.hypotheses` authors the layers from these;
:func:`ionic_usd.blueprint.temple_plan.plan_temple` runs the checks.
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass

from ionic_usd.errors import BudgetError, ParameterError
from ionic_usd.geometry.mesh import Mesh
from ionic_usd.temple.cuboid import Cuboid, cuboid_mesh
from ionic_usd.temple.description import questions
from ionic_usd.temple.layout import (
    COMPOSER_NAMESPACES,
    ColumnKind,
    Hypothesis,
    Layer,
    TempleLayout,
)

__all__ = [
    "FINISH_VALUES",
    "FORMS",
    "FRIEZE_KEY",
    "GROUPS",
    "MAX_HYPOTHESES",
    "MAX_SHAPE_COMBINATIONS",
    "MAX_SHAPE_HYPOTHESES",
    "PART_PRIMS",
    "RECORDED_ONLY",
    "HypothesisChanges",
    "check_composer_changes",
    "check_hypothesis_budget",
    "cuboid_meshes",
    "hyp_choices",
    "hyp_ident",
    "hyp_set",
    "hyp_sets",
    "prim_name",
    "shape_combinations",
    "temple_keys",
]

FRIEZE_KEY = "detail.frieze"  # a hypothesis change key realised by the detail ("garlands")

PART_PRIMS = {
    Layer.PODIUM: "Podium",
    Layer.CELLA: "Cella",
    Layer.ENTABLATURE: "Entablature",
    Layer.ROOF: "Roof",
}
GROUPS = {ColumnKind.FREE: "Free", ColumnKind.ENGAGED: "Engaged", ColumnKind.CORNER: "Corner"}
# the column asset's form variant of each kind of column
FORMS = {ColumnKind.FREE: "full", ColumnKind.ENGAGED: "engaged", ColumnKind.CORNER: "corner"}
# material.finish value -> the column asset's finish variant
FINISH_VALUES = {
    "bare_stone": "travertine",
    "travertine": "travertine",
    "stucco": "stucco",
    "painted_stucco": "stucco",
}
# composer keys recorded for the future (listed with realised = false, never an error)
RECORDED_ONLY: dict[str, tuple[str, ...]] = {}


def prim_name(name: str) -> str:
    """``name`` as a prim name, as ``Tf.MakeValidIdentifier`` makes it: every byte of its UTF-8
    form that is not an ASCII letter, digit or ``_`` becomes ``_``, and so does a leading digit
    (``"1a-é"`` → ``"_a___"``; empty → ``"_"``)."""
    out = re.sub(r"[^A-Za-z0-9_]", "_", name.encode("utf-8").decode("latin-1"))
    if not out:
        return "_"
    return "_" + out[1:] if out[0].isdigit() else out


def hyp_ident(hid: str) -> str:
    return prim_name(hid)


def hyp_set(hid: str) -> str:
    """The variant set of a hypothesis on /Temple."""
    return "hyp_" + hyp_ident(hid)


def hyp_choices(hyps: Iterable[Hypothesis]) -> dict[str, tuple[str, str]]:
    """Hypothesis id → (variant set on /Temple, the variant that selects it).

    An independent hypothesis is a switch: ``hyp_<id>`` = ``baseline`` | ``alternative``.
    The alternatives of one question (``question = "frieze"``) are ONE set ``hyp_<question>``
    = ``baseline`` | ``<id>`` per alternative, so two of them cannot be selected at once.
    """
    out: dict[str, tuple[str, str]] = {}
    for q, alts in questions(hyps).items():
        if len(alts) == 1 and not alts[0].question:
            out[alts[0].id] = (hyp_set(alts[0].id), "alternative")
        else:
            for h in alts:
                out[h.id] = ("hyp_" + hyp_ident(q), hyp_ident(h.id))
    return out


def hyp_sets(hyps: Iterable[Hypothesis]) -> dict[str, tuple[str, ...]]:
    """Variant set on /Temple → its variants (``baseline`` first), for ``hyps``."""
    out: dict[str, list[str]] = {}
    for vset, value in hyp_choices(hyps).values():
        out.setdefault(vset, ["baseline"]).append(value)
    return {k: tuple(v) for k, v in out.items()}


def temple_keys(h: Hypothesis) -> list[str]:
    """The ``section.key`` changes of ``h`` that reshape the temple layout."""
    return [k for k in h.changes if k.split(".")[0] not in COMPOSER_NAMESPACES]


def cuboid_meshes(
    layout: TempleLayout, uv_scale: float, memo: dict[tuple[Cuboid, float], Mesh] | None = None
) -> dict[Layer, dict[str, Mesh]]:
    """Meshes of every cuboid, by layer and prim name (``st`` at ``uv_scale`` per metre).

    ``memo``: meshes already made, by (cuboid, uv_scale), read and filled (the layouts of a
    hypothesis combination share most of their cuboids). Its meshes are shared, not copied.
    """
    memo = {} if memo is None else memo

    def mesh_of(c: Cuboid) -> Mesh:
        got = memo.get((c, uv_scale))
        if got is None:
            got = memo[(c, uv_scale)] = cuboid_mesh(c, uv_scale=uv_scale)
        return got

    return {
        layer: {prim_name(c.name): mesh_of(c) for c in cs} for layer, cs in layout.cuboids.items()
    }


@dataclass(frozen=True)
class HypothesisChanges:
    """What the composer will author for one hypothesis (``None`` members: nothing)."""

    flutes: str | None = None  # the column asset's flutes variant
    finish: str | None = None  # the column asset's finish variant
    capital: str | None = None  # the column asset's capital variant on the corner columns
    realised: bool = True


def check_composer_changes(
    h: Hypothesis,
    flute_variants: Mapping[str, int],
    finishes: Iterable[str],
    capitals: Iterable[str] = ("normal", "angle"),
) -> HypothesisChanges:
    """Validate the ``column.…``/``material.…`` changes of ``h`` against what the generator can
    realise; unknown keys or values raise :class:`ParameterError` naming them."""
    ctx = f"hypothesis {h.id!r}"
    flutes = finish = capital = None
    realised = bool(temple_keys(h))
    for key, value in h.changes.items():
        if key.split(".")[0] not in ("column", "material"):
            continue
        if key == "column.flute_count":
            by_count = {n: name for name, n in flute_variants.items()}
            if isinstance(value, bool) or value not in by_count:
                raise ParameterError(
                    key, value, "one of " + ", ".join(str(n) for n in sorted(by_count)), context=ctx
                )
            flutes, realised = by_count[value], True
        elif key == "material.finish":
            valid = [k for k, v in FINISH_VALUES.items() if v in set(finishes)]
            if value not in valid:
                raise ParameterError(key, value, "one of " + ", ".join(valid), context=ctx)
            finish, realised = FINISH_VALUES[value], True
        elif key == "column.corner_capital":
            valid_caps = [c for c in capitals if c != "normal"]
            if value not in valid_caps:
                raise ParameterError(key, value, "one of " + ", ".join(valid_caps), context=ctx)
            capital, realised = value, True
        elif key in RECORDED_ONLY:
            if value not in RECORDED_ONLY[key]:
                raise ParameterError(
                    key, value, "one of " + ", ".join(RECORDED_ONLY[key]), context=ctx
                )
        else:
            known = [
                "column.flute_count",
                "material.finish",
                "column.corner_capital",
                *RECORDED_ONLY,
            ]
            raise ParameterError(
                key, value, "a temple key (section.key) or one of " + ", ".join(known), context=ctx
            )
    return HypothesisChanges(flutes, finish, capital, realised)


def shape_combinations(hyps: Sequence[Hypothesis]) -> int:
    """How many combinations of the geometry hypotheses are composed and checked: the
    product over their questions of (1 + alternatives)."""
    out = 1
    for g in questions([h for h in hyps if temple_keys(h) or FRIEZE_KEY in h.changes]).values():
        out *= 1 + len(g)
    return out


#: at most this many hypotheses in a temple: each is a variant (a layer of its own)
MAX_HYPOTHESES = 64
#: at most this many combinations of the hypotheses that change geometry: only they can
#: interact (a material, a flute count or a capital model is a variant of its own part and
#: composes alone), and every combination of them is composed and checked in each detail
#: variant. Counted as combinations: the product over their questions of (1 + alternatives)
#: — 8 independent ones (2^8 = 256), or e.g. 4 questions of 3 alternatives (4^4 = 256)
MAX_SHAPE_COMBINATIONS = 256
MAX_SHAPE_HYPOTHESES = 8  # independent switches: log2 of MAX_SHAPE_COMBINATIONS


def check_hypothesis_budget(layout: TempleLayout) -> None:
    """Refuse, before any work, a description whose combinations cannot be checked in bounded
    time: more than :data:`MAX_HYPOTHESES` hypotheses, or more than
    :data:`MAX_SHAPE_COMBINATIONS` combinations of those that change geometry."""
    hyps = layout.hypotheses
    if len(hyps) > MAX_HYPOTHESES:
        raise BudgetError(
            f"{len(hyps):,} hypotheses: a temple holds at most {MAX_HYPOTHESES} (each is a "
            "variant and a layer); split the description"
        )
    shape = [h.id for h in hyps if temple_keys(h) or FRIEZE_KEY in h.changes]
    n = shape_combinations(hyps)
    if n > MAX_SHAPE_COMBINATIONS:
        raise BudgetError(
            f"{len(shape)} hypotheses change the temple's geometry ({', '.join(shape[:4])}, …): "
            f"every one of their {n:,} combinations (the product over their questions of "
            f"1 + alternatives) would be composed and checked; the limit is "
            f"{MAX_SHAPE_COMBINATIONS} combinations (e.g. {MAX_SHAPE_HYPOTHESES} independent "
            "hypotheses)"
        )
