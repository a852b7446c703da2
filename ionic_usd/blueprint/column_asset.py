"""The Ionic column asset as values (no ``pxr``): its variant vocabulary, build options and
description.

:func:`column_asset_spec` describes the asset (an :class:`~ionic_usd.blueprint.asset.AssetSpec`);
:func:`ionic_usd.usd.column_asset.author_column_asset` writes it; the pipeline that makes the
meshes (generate → clip → UV → texture) is :mod:`ionic_usd.pipeline.asset`, whose
:func:`~ionic_usd.pipeline.asset.build_column_asset` is the entry point.

Variant sets on ``/IonicColumn`` (defaults first):

==========  ==========================================  ===================================
set         variants                                    meshes it switches
==========  ==========================================  ===================================
lod         high, medium, low                           every part
base        attic_bezier_plinth, attic_bezier, G1, G2   Base
scroll      S1, S2                                      CapitalBody (its bolsters)
capital     normal, angle                               CapitalBody (angle: the corner volute
                                                        turned 45° onto the diagonal, volutes
                                                        on the +Z and +X faces)
volute      log_spiral, centred_arcs                    CapitalBody (the volute's curve: the
                                                        paper's formula 3, or the treatises'
                                                        quarter circles about twelve centres)
flutes      f24, f20                                    Shaft (f20: a reconstruction
                                                        hypothesis for the Portunus shafts)
form        full, engaged, corner                       every part (engaged: cut by the wall
                                                        plane z = −``ENGAGED_INSET``, capped;
                                                        corner: the quadrant x, z < −inset
                                                        removed, a three-quarter column)
finish      travertine, stucco                          the material bound to Geom
==========  ==========================================  ===================================

The ``high`` LOD also carries the carved capital (``carved``, on by default): egg-and-dart on
the echinus and bead-and-reel on the astragal, two PointInstancers under ``Geom/Ornament``
per form (4 prototypes, 90 copies on the full column, 8.8k triangles drawn;
:func:`column_ornament`), tagged ``lod = high`` and ``form`` (an engaged
or corner column drops the copies inside its wall).

The ``volute`` set's default is the model of the column's parameters (``log_spiral`` for the
Portunus column: the paper's generator, which every fitted and published figure refers to);
``centred_arcs`` derives its arcs from the same volute height (eye radius R/9, arc squares
4R/33 with ratio 1/3: the Vitruvian twelve-centre construction), scaled so that the capital
keeps its height.

Every mesh is one closed solid: the capital's abacus, echinus, volutes, canales and bolsters are
united (manifold3d), so the capital mesh depends on the scroll and capital variants. Each mesh
is authored once: the shaft does not depend on the base. Triangle budgets of the default
column (three parts, form = full): high 40,862, medium 16,054, low 7,996.

Texture coordinates come from each part's analytic charts (its generator's parametrisation, packed
by :func:`ionic_usd.texture.atlas.analytic_atlas`; xatlas only for a mesh without charts), one
chart set per part and LOD, at one texel density per LOD (its ``asset_texels_per_metre``,
:mod:`ionic_usd.lod`); every LOD's pixel coordinates are divided by
``texels_per_metre × UV_SPAN`` so that ``st`` ∈ [0, 1] spans the same ``UV_SPAN`` metres on
every part and LOD. The material repeats its tileable stone maps
``UV_SPAN / TILE_METRES`` times per unit of ``st`` (UsdTransform2d), i.e. once every
``TILE_METRES`` metres of stone.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

from ionic_usd import __version__
from ionic_usd.blueprint.asset import AssetInstancer, AssetMesh, AssetSpec
from ionic_usd.blueprint.layers import ASSET_NAME
from ionic_usd.blueprint.materials import TILE_METRES, MaterialTextures
from ionic_usd.checks import check_stone_options
from ionic_usd.column.base import base_preset_names
from ionic_usd.column.column import (
    ColumnParams,
    column_params_to_tables,
    portunus_column_params,
)
from ionic_usd.column.volute import VOLUTE_MODELS, volute_extent
from ionic_usd.errors import ParameterError
from ionic_usd.lod import LOD_NAMES

__all__ = [
    "ColumnAssetOptions",
    "column_asset_spec",
    "volute_variant_params",
    "column_ornament",
    "ASSET_NAME",
    "BASE_VARIANTS",
    "SCROLL_VARIANTS",
    "FLUTE_VARIANTS",
    "FORM_VARIANTS",
    "CAPITAL_VARIANTS",
    "VOLUTE_VARIANTS",
    "FINISHES",
    "ENGAGED_INSET",
    "BASE_CHART_BOUNDARY",
    "UV_SPAN",
    "TILE_METRES",
]

BASE_VARIANTS = ("attic_bezier_plinth", "attic_bezier", "G1", "G2")
SCROLL_VARIANTS = ("S1", "S2")
FLUTE_VARIANTS = {"f24": 24, "f20": 20}
FORM_VARIANTS = ("full", "engaged", "corner")
CAPITAL_VARIANTS = ("normal", "angle")
VOLUTE_VARIANTS = tuple(VOLUTE_MODELS)  # log_spiral, centred_arcs
# finish variant -> (material prim name, stone style of its textures)
FINISHES = {
    "travertine": ("Travertine", "travertine"),
    "stucco": ("PaintedStucco", "stucco_painted"),
}
ENGAGED_INSET = 0.05  # m: the cut lies this far behind the wall face (axis on the face)
BASE_CHART_BOUNDARY = 2.0  # m: see texture.uv.unwrap(max_chart_boundary=…)
UV_SPAN = 32.0  # m of surface across st ∈ [0, 1]


@dataclass(frozen=True)
class ColumnAssetOptions:
    """What to build: variants, texture resolution, extras."""

    params: ColumnParams = dataclasses.field(default_factory=portunus_column_params)
    lods: tuple[str, ...] = LOD_NAMES
    bases: tuple[str, ...] = BASE_VARIANTS
    scrolls: tuple[str, ...] = SCROLL_VARIANTS
    flutes: tuple[str, ...] = tuple(FLUTE_VARIANTS)
    forms: tuple[str, ...] = FORM_VARIANTS
    capitals: tuple[str, ...] = CAPITAL_VARIANTS
    # volute models, the first the default selection; (): both, the params' own model first
    volutes: tuple[str, ...] = ()
    texture_size: int = 1024
    seed: int = 7
    make_tx: bool = False
    user_textures: Mapping[str, str] | None = None  # role (basecolor/roughness/normal) -> file
    # the carved echinus and astragal (instanced ornament in the high LOD)
    carved: bool = True

    def __post_init__(self) -> None:
        def check(name: str, given: Sequence[str], valid: Sequence[str]) -> None:
            if not given:
                raise ParameterError(name, given, f"at least one of {', '.join(valid)}")
            for g in given:
                if g not in valid:
                    raise ParameterError(name, g, f"one of {', '.join(valid)}")

        check_stone_options(self.texture_size, self.seed)
        check("lod", self.lods, LOD_NAMES)
        check("base", self.bases, base_preset_names())  # any preset; default BASE_VARIANTS
        check("scroll", self.scrolls, SCROLL_VARIANTS)
        check("flutes", self.flutes, tuple(FLUTE_VARIANTS))
        check("form", self.forms, FORM_VARIANTS)
        check("capital", self.capitals, CAPITAL_VARIANTS)
        if not self.volutes:
            own = self.params.capital.volute.volute_model
            object.__setattr__(self, "volutes", (own, *(v for v in VOLUTE_VARIANTS if v != own)))
        check("volute", self.volutes, VOLUTE_VARIANTS)
        if self.user_textures is not None:
            roles = {"basecolor", "roughness", "normal"}
            if set(self.user_textures) != roles:
                raise ParameterError(
                    "user textures",
                    sorted(self.user_textures),
                    "exactly the roles basecolor, roughness, normal",
                )


def volute_variant_params(params: ColumnParams, model: str) -> ColumnParams:
    """``params`` with the volute drawn by ``model`` (a ``volute`` variant).

    The params' own model is kept as given. ``centred_arcs`` taken from a log-spiral column
    derives its arcs from the volute height R (``capital_spiral_radius``): eye radius R/9, arc
    squares from R/11 (innermost, ratio 1/3) to 4R/33 — the Portunus defaults at D = 0.95 m —
    then scaled together so that the band rises as far above the eye as the spiral's (the
    capital keeps its height: the abacus and the entablature do not move). ``log_spiral``
    keeps the spiral's own a, b, c, d and R (and drops a free chain of arcs).
    """
    v = params.capital.volute
    if v.volute_model == model:
        return params
    cp = params.capital_params()
    top = volute_extent(v, cp.spiral_samples, cp.ring_segments)[1, 1]
    if model == "centred_arcs":
        r = v.capital_spiral_radius
        v = v.with_(
            volute_model=model,
            capital_circle_radius=r / 9.0,
            arc_square=r * 4.0 / 33.0,
            arc_ratio=1.0 / 3.0,
        )
        # the same height above the eye as the column's own volute, so the abacus (and all
        # that stands on the column) stays where it was: the arcs scale linearly
        for _ in range(3):
            k = top / volute_extent(v, cp.spiral_samples, cp.ring_segments)[1, 1]
            v = v.with_(
                capital_circle_radius=v.capital_circle_radius * k, arc_square=v.arc_square * k
            )
    else:  # a free chain of arcs is the centred-arc model's own: the spiral has none
        v = v.with_(volute_model=model, arc_radii=(), arc_sweeps=())
    own_gap = _margin_gap(params)[0]
    out = dataclasses.replace(params, capital=params.capital.with_(volute=v))
    gap, top_end_x = _margin_gap(out)
    if own_gap > 0.0 and gap < own_gap:
        # the straight margins stop as far short of the centre plane as the column's own
        # model's do (0.026 mm for Portunus; the capital then carries both a seat across it,
        # see capital_body.seat_depth)
        margin = max(top_end_x - own_gap, 0.0)
        out = dataclasses.replace(out, capital=out.capital.with_(spiral_margin=margin))
    return out


def column_ornament(opts: ColumnAssetOptions) -> tuple[AssetInstancer, ...]:
    """The carved echinus and astragal of the column asset's ``high`` LOD (PointInstancers
    tagged ``lod = high``), or nothing if the asset has no high LOD.

    The one placement rule: the asset's instancers (:mod:`ionic_usd.pipeline.asset` drops,
    per ``form``, the copies a wall would swallow) and the pictures of the detail use it.
    """
    from ionic_usd.column.ornament import capital_ornament

    if "high" not in opts.lods:
        return ()
    p = opts.params.with_lod("high")
    y_cap = p.base_params().height + p.shaft.length
    cap = p.capital_params()
    egg, bead = capital_ornament(
        y_capital=y_cap,
        top_radius=p.shaft.top_radius,
        echinus_height=cap.echinus_height,
        echinus_projection=cap.echinus_projection,
        ring_top=p.shaft.ring_top,
        capital_lift=cap.capital_position_y,
    )
    return (
        AssetInstancer("Ornament", "EggAndDart_high", egg, {"lod": "high"}),
        AssetInstancer("Ornament", "BeadAndReel_high", bead, {"lod": "high"}),
    )


def _margin_gap(params: ColumnParams) -> tuple[float, float]:
    """How far short of the centre plane x = 0 a volute's straight margin stops, and the x of
    the band's top end where the margin starts (m)."""
    from ionic_usd.column.capital import capital_layout

    lay = capital_layout(params.capital_params())
    return lay.margin_gap, lay.margin + lay.margin_gap


def _materials(opts: ColumnAssetOptions) -> dict[str, MaterialTextures]:
    materials: dict[str, MaterialTextures] = {}
    for _, (mat, style) in FINISHES.items():
        if opts.user_textures and style == "travertine":
            names = {r: Path(p).name for r, p in opts.user_textures.items()}
        else:
            names = {r: f"{style}_{r}.png" for r in ("basecolor", "roughness", "normal")}
        materials[mat] = MaterialTextures(
            *(f"./Textures/{names[r]}" for r in ("basecolor", "roughness", "normal"))
        )
    return materials


def column_asset_spec(
    opts: ColumnAssetOptions, meshes: Sequence[AssetMesh], instancers: Sequence[AssetInstancer] = ()
) -> AssetSpec:
    """The asset's description: ``meshes`` (with ``st``) and ``instancers`` under the variant
    sets of ``opts``, the finishes' materials, the parameters as customData."""
    variant_sets = {
        "lod": opts.lods,
        "base": opts.bases,
        "scroll": opts.scrolls,
        "capital": opts.capitals,
        "volute": opts.volutes,
        "flutes": opts.flutes,
        "form": opts.forms,
        "finish": tuple(FINISHES),
    }
    if len(opts.volutes) == 1:
        del variant_sets["volute"]
    custom = {
        "ionic_usd": {
            "version": __version__,
            "parameters": _flatten(column_params_to_tables(opts.params)),
        }
    }
    return AssetSpec(
        name=ASSET_NAME,
        version=__version__,
        meshes=tuple(meshes),
        variant_sets=variant_sets,
        defaults={k: v[0] for k, v in variant_sets.items()},
        materials=_materials(opts),
        default_material=FINISHES["travertine"][0],
        finishes={k: v[0] for k, v in FINISHES.items()},
        custom_data=custom,
        documentation="Ionic column (Temple of Portunus proportions) generated by ionic_usd "
        "after Konečný, Syllaiou & Liarokapis 2016; variant sets: "
        f"{', '.join(variant_sets)}.",
        st_scale=UV_SPAN / TILE_METRES,
        proxy_lod="low" if "low" in opts.lods and len(opts.lods) > 1 else None,
        instancers=tuple(instancers),
    )


def _flatten(tables: dict[str, dict]) -> dict[str, object]:
    """TOML-like tables as USD customData (a dictionary of dictionaries of scalars)."""
    return {name: {k: v for k, v in t.items() if v is not None} for name, t in tables.items()}
