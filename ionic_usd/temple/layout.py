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

import os
from collections.abc import Iterable, Mapping
from dataclasses import replace
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np

from ionic_usd.errors import ParameterError
from ionic_usd.params import load_toml, prim_key
from ionic_usd.temple.cuboid import Cuboid

# the description's types, re-exported: a layout is read in their terms
from ionic_usd.temple.description import (
    COMPOSER_NAMESPACES,
    SECTIONS,
    Certainty,
    ColumnKind,
    ColumnPlacement,
    Hypothesis,
    Layer,
    TempleParams,
    exclusive_clash,
)
from ionic_usd.temple.massing import (
    ROOF_BED,
    TempleLayout,
    box,
    outer_rotation,
    podium_cuboids,
    roof_cuboids,
)

# the TOML readers, re-exported for callers of the layout
from ionic_usd.temple.paradata import paradata_from_tables
from ionic_usd.temple.tables import (
    check_temple_tables,
    cuboids_from_tables,
    cuboids_to_toml,
    hypotheses_from_tables,
    load_cuboids_toml,
    params_from_tables,
)
from ionic_usd.temple.typed_layout import layout_from_type_mapping

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


def _cella(p: TempleParams) -> list[Cuboid]:
    xa, t, y0 = p.x_axis, p.cella_wall_thickness, p.podium_height
    y1 = y0 + p.columns_height
    zr = -p.z_front_axis
    zf = p.z_front_axis - p.columns_porch_depth * p.axial_spacing
    d2 = p.door_width / 2
    return [
        box("wall_left", -xa, y0, zr, -xa + t, y1, zf),
        box("wall_right", xa - t, y0, zr, xa, y1, zf),
        box("wall_rear", -xa + t, y0, zr, xa - t, y1, zr + t),
        box("wall_front_left", -xa + t, y0, zf - t, -d2, y1, zf),
        box("wall_front_right", d2, y0, zf - t, xa - t, y1, zf),
        box("door_lintel", -d2, y0 + p.door_height, zf - t, d2, y1, zf),
    ]


def _entablature(p: TempleParams) -> tuple[list[Cuboid], float, float, float, float]:
    a, f, c = p.entablature_heights
    half_top = p.columns_lower_diameter * p.columns_upper_diameter_ratio / 2
    xe, ze = p.x_axis + half_top, p.z_front_axis + half_top
    proj = c * p.entablature_cornice_projection_ratio
    y = p.podium_height + p.columns_height
    out = [
        box("architrave", -xe, y, -ze, xe, y + a, ze),
        box("frieze", -xe, y + a, -ze, xe, y + a + f, ze),
        box("cornice", -xe - proj, y + a + f, -ze - proj, xe + proj, y + a + f + c, ze + proj),
    ]
    return out, y + a + f + c, xe, ze, proj


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
        corner = outer_rotation(np.sign(pos[0]), 1.0) if j in (0, nf - 1) else None
        out.append(
            ColumnPlacement(
                tuple(pos), 0.0, ColumnKind.FREE, name=f"front_{j + 1}", angle_rotation_deg=corner
            )
        )
    for side, sgn in (("left", -1.0), ("right", 1.0)):
        flank = colonnade_positions((sgn * xa, y, zf), (sgn * xa, y, zf - (ns - 1) * s), ns)
        for k in range(1, ns - 1):
            kind, rot = ColumnKind.ENGAGED, sgn * 90.0
            if k < porch:
                kind = ColumnKind.FREE
            elif k == porch:  # the flank wall starts here, at the cella's front wall
                kind, rot = ColumnKind.CORNER, outer_rotation(sgn, 1.0)
            out.append(ColumnPlacement(tuple(flank[k]), rot, kind, name=f"{side}_{k + 1}"))
    for j, pos in enumerate(rear):
        kind, rot, corner = ColumnKind.ENGAGED, 180.0, None
        if j in (0, nf - 1):
            kind = ColumnKind.CORNER
            rot = corner = outer_rotation(np.sign(pos[0]), -1.0)
        out.append(
            ColumnPlacement(tuple(pos), rot, kind, name=f"rear_{j + 1}", angle_rotation_deg=corner)
        )
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
    hypotheses, apply = tuple(hypotheses), tuple(apply)
    clash = exclusive_clash(apply, hypotheses)
    if clash is not None:
        raise ParameterError("hypothesis", list(apply), clash, context=f"temple {params.name!r}")
    rebuild = getattr(params, "rebuild_layout", None)
    if rebuild is not None:  # a typed temple (ionic_usd.temple.typed_layout) lays itself out
        return rebuild(hypotheses=hypotheses, apply=apply, extra_cuboids=extra_cuboids)
    hyps = tuple(hypotheses)
    by_id = {h.id: h for h in hyps}
    applied = tuple(apply)
    for hid in applied:
        if hid not in by_id:
            raise ParameterError(
                "hypothesis",
                hid,
                "one of: " + (", ".join(by_id) or "(none)"),
                context=f"temple {params.name!r}",
            )
        changes = {}
        for key, value in by_id[hid].changes.items():
            sec, k = key.split(".")
            if sec in SECTIONS:
                if k not in SECTIONS[sec]:
                    raise ParameterError(
                        key,
                        value,
                        f"one of {sec}.{', '.join(SECTIONS[sec])}",
                        context=f"hypothesis {hid!r}",
                    )
                changes[f"{sec}_{k}"] = value
        params = replace(params, **changes)
    ent, y_top, xe, ze, proj = _entablature(params)
    groups: dict[Layer, list[Cuboid]] = {
        Layer.PODIUM: podium_cuboids(params),
        Layer.CELLA: _cella(params),
        Layer.ENTABLATURE: ent,
        Layer.ROOF: roof_cuboids(params, y_top, xe, ze, proj),
    }
    for layer, cs in (extra_cuboids or {}).items():
        groups[Layer(layer)].extend(cs)
    seen: dict[str, str] = {}  # two names that author the same prim would lose a cuboid
    for c in (c for cs in groups.values() for c in cs):
        if prim_key(c.name) in seen:
            other = seen[prim_key(c.name)]
            raise ParameterError(
                "cuboid name",
                c.name,
                f"a name distinct from {other!r} (both would author the same prim)",
                context=f"temple {params.name!r}",
            )
        seen[prim_key(c.name)] = c.name
    return TempleLayout(
        params.name,
        {k: tuple(v) for k, v in groups.items()},
        tuple(_columns(params)),
        params,
        hyps,
        applied,
    )


def layout_from_toml(path: str | os.PathLike, *, apply: Iterable[str] = ()) -> TempleLayout:
    """Build a layout from a temple TOML (schema of ``portunus.toml``)."""
    return layout_from_mapping(load_toml(path), context=str(path), apply=apply)


def layout_from_mapping(
    data: Mapping[str, Any], *, context: str = "temple", apply: Iterable[str] = ()
) -> TempleLayout:
    """Build a layout from already-parsed TOML tables (see :func:`layout_from_toml`)."""
    ctx = context
    from ionic_usd.temple.tables import resolve_extends

    if isinstance(data, Mapping) and "extends" in data:
        data = resolve_extends(data, context=ctx)
    if isinstance(data, Mapping) and "type" in data:  # a temple type (temple.vitruvius)
        return layout_from_type_mapping(data, context=ctx, apply=apply)
    check_temple_tables(data, context=ctx)  # types and ranges of every table, at the boundary
    params = params_from_tables(data, context=ctx)
    hyps = hypotheses_from_tables(data.get("hypothesis", []), ctx)
    extra = cuboids_from_tables(data.get("cuboid", []), context=ctx)
    resolve_extends(data, context=ctx)  # missing tables: after what is there is checked
    layout = build_layout(params, hypotheses=hyps, apply=apply, extra_cuboids=extra)
    return replace(layout, paradata=paradata_from_tables(data, hyps, context=ctx))


def portunus_layout(*, apply: Iterable[str] = ()) -> TempleLayout:
    """The Temple of Portunus from the packaged ``portunus.toml``.

    Parameters
    ----------
    apply : ids of ``[[hypothesis]]`` entries to apply (e.g. ``("roof-pitch-15",)``).
    """
    ref = resources.files("ionic_usd") / "data" / PORTUNUS_TOML
    with resources.as_file(ref) as p:
        return layout_from_toml(Path(p), apply=apply)
