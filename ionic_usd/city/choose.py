"""Which temple stands on a lot: a named description, a preset, a type, or a seeded choice.

:func:`temple_for_lot` is the one place the city decides a lot's temple. A lot may name

* ``temple``: a description (a built-in name or a TOML path) — used as it is, scaled to fit;
* ``preset``: a built-in description by name (today: ``portunus``);
* a **type**: ``arrangement``, ``front`` (columns across the front), ``intercolumniation``
  and optionally ``lower_diameter`` (the module, m) — the description is derived below;
* nothing: the city draws a type (front and intercolumniation) from a generator seeded by
  the city's seed and the lot's id, and sizes its module to the lot.

Derived type (Vitruvius III.3; the rules cited in :data:`INTERCOLUMNIATIONS` and below)
----------------------------------------------------------------------------------------
Today's temple description (:mod:`ionic_usd.temple.layout`) is one arrangement,
pseudoperipteral on a podium with one axial spacing front and flanks; a type sets, for a
lower diameter ``D``:

* axial spacing ``s = D·(1 + g)`` with ``g`` the clear intercolumniation in diameters
  (III.3.1–6; the eustyle's wider middle bay is not representable by today's layout);
* column height ``h·D`` (III.3.7 and III.3.10);
* columns down each flank ``2·front − 1`` (twice the front's intervals, the peripteral rule
  of III.4/IV.4; Portunus: 4 → 7), fewer (not below ``front + 2``) when the lot is shallow;
* the margin, podium, stairs and walls in Portunus' proportions to ``D`` and the column
  height (``portunus.toml`` cites them), the architrave by III.5.8 from the column height in
  feet; the rest of the description (mouldings, hypotheses) is Portunus'.

``D`` is the largest module (within the city's module limits) whose podium fits the lot
box, times a seeded factor in [0.8, 1], rounded down to 5 mm: lots of one size still hold
different builds. Pure Python/numpy: no USD.
"""

from __future__ import annotations

import hashlib
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from importlib import resources

import numpy as np

from ionic_usd.errors import ParameterError
from ionic_usd.temple.presets import PRESETS as _TEMPLE_PRESETS

__all__ = [
    "ARRANGEMENTS",
    "FRONTS",
    "INTERCOLUMNIATIONS",
    "PRESETS",
    "TempleChoice",
    "TempleType",
    "derive_description",
    "lot_rng",
    "temple_for_lot",
    "type_footprint",
]

#: arrangements today's temple description can build
ARRANGEMENTS = ("pseudoperipteral",)
FRONTS = {4: "tetrastyle", 6: "hexastyle", 8: "octastyle"}
#: name → (clear intercolumniation in lower diameters, column height in lower diameters)
INTERCOLUMNIATIONS: dict[str, tuple[float, float]] = {
    "pycnostyle": (1.5, 10.0),  # III.3.2 (1½ D), III.3.10 (10 D)
    "systyle": (2.0, 9.5),  # III.3.2 (2 D), III.3.10 (9½ D)
    "eustyle": (2.25, 8.5),  # III.3.6 (2¼ D), III.3.7 (8½ D)
    "diastyle": (3.0, 8.5),  # III.3.4 (3 D), III.3.10 (8½ D)
    # III.3.5 gives no figure (wooden architraves); (!) 4 D assumed; III.3.10: 8 D
    "araeostyle": (4.0, 8.0),
}
#: preset name → built-in description (``ionic_usd/data``): every preset of
#: :mod:`ionic_usd.temple.presets` (``ionic-usd presets`` lists them)
PRESETS = dict(_TEMPLE_PRESETS)
_PORTUNUS_D = 0.95  # portunus.toml: the lower diameter the proportions below are taken from
_FOOT = 0.2957  # Roman foot, m (portunus.toml)


@dataclass(frozen=True)
class TempleType:
    """A temple type: arrangement, columns across the front, intercolumniation, module (m),
    columns down each flank (None: the rule, ``2·front − 1``)."""

    arrangement: str
    front: int
    intercolumniation: str
    lower_diameter: float
    side: int | None = None

    @property
    def flank(self) -> int:
        return self.side if self.side is not None else 2 * self.front - 1

    @property
    def name(self) -> str:
        return f"{FRONTS.get(self.front, f'{self.front}-column')}_{self.intercolumniation}"


@dataclass(frozen=True)
class TempleChoice:
    """What stands on a lot: ``temple`` (a description name/path) or ``preset``, or a derived
    ``description`` (TOML text) named ``name``; ``type`` (for the summary) and the uniform
    ``scale_range`` it may take to fit the lot (None: the city's)."""

    name: str
    temple: str | None = None
    description: str | None = None
    type: Mapping[str, object] = field(default_factory=dict)
    scale_range: tuple[float, float] | None = None


def lot_rng(seed: int, lot_id: str) -> np.random.Generator:
    """A generator for one lot: seeded by the city's seed and the lot's id only, so adding or
    reordering lots does not change the others' choices."""
    h = int.from_bytes(hashlib.blake2b(lot_id.encode(), digest_size=8).digest(), "little")
    return np.random.default_rng([int(seed) & 0xFFFFFFFF, h])


def _dims(t: TempleType) -> dict[str, float | int]:
    """The description keys of a type (see the module docstring), lengths in metres."""
    g, h_d = INTERCOLUMNIATIONS[t.intercolumniation]
    d = t.lower_diameter
    s = d * (1.0 + g)
    m = 0.85 / _PORTUNUS_D * d
    width = (t.front - 1) * s + 2 * m
    length = width + (t.flank - t.front) * s
    height = h_d * d
    podium = 2.40 / 8.22 * height
    proj = (11.87 - 10.50) / 2 / _PORTUNUS_D * d
    steps = max(3, round(podium / 0.24))
    run = steps * 0.493 * max(1.0, d / _PORTUNUS_D)
    feet = height / _FOOT  # III.5.8: architrave by the column's height in feet
    if feet <= 15:
        divisor = height / (d / 2)
    else:
        divisor = 13.0 if feet <= 20 else 12.5 if feet <= 25 else 12.0
    return {
        "podium.height": podium,
        "podium.footing_height": 0.45 / 2.40 * podium,
        "podium.base_width": width + 2 * proj,
        "podium.base_length": length + 2 * proj + run,
        "podium.cheek_wall_width": m,
        "stylobate.width": width,
        "stylobate.length": length,
        "columns.height": height,
        "columns.lower_diameter": d,
        "columns.front": t.front,
        "columns.side": t.flank,
        "columns.porch_depth": 2 if t.front == 4 or t.flank - 2 < 3 else 3,
        "steps.count": steps,
        "cella.wall_thickness": 0.80 / _PORTUNUS_D * d,
        "entablature.architrave_divisor": divisor,
    }


def type_footprint(t: TempleType) -> tuple[float, float]:
    """(width, depth) in metres of the type's podium, stairs included."""
    k = _dims(t)
    return float(k["podium.base_width"]), float(k["podium.base_length"])


def derive_description(t: TempleType) -> str:
    """The temple TOML of a type: ``portunus.toml`` with the type's keys replaced."""
    check_type(t)
    text = (resources.files("ionic_usd") / "data" / PRESETS["portunus"]).read_text("utf-8")
    keys = _dims(t)
    title = (
        f"{FRONTS.get(t.front, t.front)} {t.intercolumniation} {t.arrangement} temple "
        f"(D = {t.lower_diameter:g} m)"
    )
    text = text.replace('name = "Temple of Portunus"', f'name = "{title.capitalize()}"', 1)
    header = (
        f"# Derived by ionic_usd.city.choose from the type {t.arrangement}, front {t.front}, "
        f"{t.intercolumniation}, lower diameter {t.lower_diameter:g} m; the keys below that "
        "differ from Portunus' are the type's (see that module), the comments are Portunus'.\n"
    )
    return header + set_keys(text, keys)


def check_type(t: TempleType, context: str = "") -> None:
    """Refuse a type today's description cannot build (one line naming the key)."""
    if t.arrangement not in ARRANGEMENTS:
        raise ParameterError(
            "arrangement", t.arrangement, f"one of {', '.join(ARRANGEMENTS)}", context=context
        )
    if t.front not in FRONTS:
        raise ParameterError("front", t.front, "4, 6 or 8 columns", context=context)
    if t.intercolumniation not in INTERCOLUMNIATIONS:
        raise ParameterError(
            "intercolumniation",
            t.intercolumniation,
            f"one of {', '.join(INTERCOLUMNIATIONS)}",
            context=context,
        )
    if not (math.isfinite(t.lower_diameter) and 0.2 <= t.lower_diameter <= 3.0):
        raise ParameterError("lower_diameter", t.lower_diameter, "0.2 … 3 m", context=context)


def set_keys(text: str, keys: Mapping[str, float | int]) -> str:
    """``text`` (TOML) with ``section.key = value`` assignments replaced (TOML forbids a
    repeated key: the old line goes, the new one is written where it stood)."""
    out: list[str] = []
    section = ""
    for line in text.splitlines():
        s = line.strip()
        if s.startswith("[") and not s.startswith("[["):
            section = s.strip("[]")
        elif s.startswith("[["):
            section = ""
        elif "=" in s and not s.startswith("#"):
            dotted = f"{section}.{s.split('=')[0].strip()}"
            if dotted in keys:
                v = keys[dotted]
                line = f"{dotted.split('.')[1]} = {v if isinstance(v, int) else repr(float(v))}"
        out.append(line)
    return "\n".join(out) + "\n"


def _fit_module(t: TempleType, width: float, depth: float, lo: float, hi: float) -> float:
    """The largest module in [lo, hi] whose podium fits ``width × depth`` (0 if none)."""

    def fits(d: float) -> bool:
        w, ln = type_footprint(TempleType(t.arrangement, t.front, t.intercolumniation, d, t.side))
        return w <= width and ln <= depth

    if not fits(lo):
        return 0.0
    if fits(hi):
        return hi
    a, b = lo, hi
    for _ in range(40):
        mid = (a + b) / 2
        a, b = (mid, b) if fits(mid) else (a, mid)
    return a


def temple_for_lot(
    props: Mapping[str, object],
    rng: np.random.Generator,
    *,
    width: float,
    depth: float,
    module_range: tuple[float, float],
    context: str = "",
) -> TempleChoice:
    """Choose a lot's temple (see the module docstring).

    Parameters
    ----------
    props : the lot's choices: ``temple``, ``preset``, ``arrangement``, ``front``,
        ``intercolumniation``, ``lower_diameter`` (absent keys: the city chooses)
    rng : the lot's generator (:func:`lot_rng`)
    width, depth : the lot's box in the temple's frame (m), across and along its axis
    module_range : (min, max) lower diameter (m) the city allows
    """
    if props.get("temple") == "auto":  # any arrangement after Vitruvius, fitted to the lot
        from ionic_usd.city.types import choose_type

        slug, text = choose_type(min(width, depth), max(width, depth), rng)
        return TempleChoice(slug, description=text, type={"auto": slug}, scale_range=(0.5, 1.0))
    if props.get("temple"):
        name = str(props["temple"])
        return TempleChoice(name, temple=name)
    preset = props.get("preset")
    if preset is not None:
        if preset not in PRESETS:
            raise ParameterError("preset", preset, f"one of {', '.join(PRESETS)}", context=context)
        return TempleChoice(str(preset), temple=str(preset), type={"preset": preset})
    arr = str(props.get("arrangement", ARRANGEMENTS[0]))
    if arr not in ARRANGEMENTS:  # another of Vitruvius' arrangements: a typed temple
        return _typed_choice(props, arr, rng, width, depth, context)
    fronts = [props["front"]] if "front" in props else list(FRONTS)
    ics = [props["intercolumniation"]] if "intercolumniation" in props else list(INTERCOLUMNIATIONS)
    lo, hi = module_range
    if "lower_diameter" in props:
        lo = hi = float(props["lower_diameter"])  # type: ignore[arg-type]
    cands = [(f, ic) for f in fronts for ic in ics]
    order = rng.permutation(len(cands))
    factor = float(rng.uniform(0.8, 1.0))
    # first a type whose module can be chosen (the largest that fits >= 1.2 the minimum),
    # then any that fits at all
    for need in (min(hi, 1.2 * lo), lo):
        for k in order:
            found = _sized(cands[int(k)], arr, width, depth, lo, hi, need, factor, context)
            if found is not None:
                return found
    raise ParameterError(
        "outline",
        f"{width:.1f} × {depth:.1f} m",
        f"a lot that holds a temple of the type asked for with a module >= {lo:g} m",
        context=context,
    )


def _typed_choice(
    props: Mapping[str, object],
    arr: str,
    rng: np.random.Generator,
    width: float,
    depth: float,
    context: str,
) -> TempleChoice:
    """A lot naming an arrangement other than the derived description's: a typed temple
    (``ionic_usd.temple.vitruvius``) of that arrangement, its other keys kept or drawn and its
    module fitted to the lot (:func:`ionic_usd.city.types.choose_type`)."""
    from ionic_usd.city.types import choose_type
    from ionic_usd.temple.vitruvius import FRONTS as TYPE_FRONTS
    from ionic_usd.temple.vitruvius import Arrangement, Intercolumniation

    names = [a.value for a in Arrangement]
    if arr not in names:
        raise ParameterError("arrangement", arr, f"one of {', '.join(names)}", context=context)
    front = props.get("front")
    allowed = TYPE_FRONTS[Arrangement(arr)]
    if front is not None and front not in allowed:
        raise ParameterError(
            "front",
            front,
            f"{', '.join(map(str, allowed))} columns for a {arr} temple",
            context=context,
        )
    ic = props.get("intercolumniation")
    if ic is not None and ic not in [i.value for i in Intercolumniation]:
        raise ParameterError(
            "intercolumniation",
            ic,
            f"one of {', '.join(i.value for i in Intercolumniation)}",
            context=context,
        )
    d = props.get("lower_diameter")
    slug, text = choose_type(
        min(width, depth),
        max(width, depth),
        rng,
        arrangement=arr,
        front=None if front is None else int(front),
        intercolumniation=None if ic is None else str(ic),
        lower_diameter=None if d is None else float(d),  # type: ignore[arg-type]
    )
    import tomllib

    typ = tomllib.loads(text)["type"]
    return TempleChoice(slug, description=text, type=dict(typ), scale_range=(0.5, 1.0))


def _sized(
    cand: tuple,
    arr: str,
    width: float,
    depth: float,
    lo: float,
    hi: float,
    need: float,
    factor: float,
    context: str,
) -> TempleChoice | None:
    """The candidate (front, intercolumniation) sized to the lot, or None if its largest
    module that fits is below ``need``."""
    front, ic = cand
    t = TempleType(arr, int(front), str(ic), lo)
    check_type(t, context)
    for side in range(t.flank, t.front + 1, -1):  # the rule's flank, shorter if shallow
        ts = TempleType(arr, t.front, t.intercolumniation, lo, side)
        d = _fit_module(ts, width, depth, lo, hi)
        if d < need or d <= 0:
            continue
        d = max(lo, math.floor(max(lo, d * factor) * 200) / 200)
        ts = TempleType(arr, t.front, t.intercolumniation, round(d, 3), side)
        return TempleChoice(
            ts.name,
            description=derive_description(ts),
            type={
                "arrangement": arr,
                "front": ts.front,
                "side": ts.flank,
                "intercolumniation": ts.intercolumniation,
                "lower_diameter": ts.lower_diameter,
            },
            scale_range=(0.5, 1.0),
        )
    return None
