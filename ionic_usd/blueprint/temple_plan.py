"""A temple's plan, as values (no ``pxr``): what its layers will hold, validated before
anything is written.

:func:`plan_temple` checks the hypotheses (bounded combinations, changes the composer can
realise), chooses the column asset's options and computes the kernel values every layer needs
(the cuboids' meshes, the detail's mouldings and ornament);
:func:`ionic_usd.usd.temple.write_temple` authors them. The ``detail`` variant vocabulary is
here too: the detail's levels, what each shows (:meth:`DetailGeometry.prims`) and the prim
paths they use.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

from ionic_usd.blueprint.column_asset import FINISHES, FLUTE_VARIANTS, UV_SPAN, ColumnAssetOptions
from ionic_usd.blueprint.hypotheses import (
    FRIEZE_KEY,
    HypothesisChanges,
    check_composer_changes,
    check_hypothesis_budget,
    cuboid_meshes,
    prim_name,
    temple_keys,
)
from ionic_usd.blueprint.materials import TILE_METRES
from ionic_usd.blueprint.temple import temple_asset_options, temple_column_params
from ionic_usd.column.column import ColumnParams
from ionic_usd.column.ornament import Instances
from ionic_usd.errors import ParameterError
from ionic_usd.geometry.mesh import Mesh
from ionic_usd.lod import LOD_NAMES
from ionic_usd.temple.layout import Layer, TempleLayout
from ionic_usd.temple.mouldings import MouldingParams, moulding_meshes, portunus_mouldings
from ionic_usd.temple.ornament import dentils, frieze_garlands, roof_tiles

__all__ = [
    "BASELINE_FINISH",
    "CUBOID_UV_SCALE",
    "DEFAULT_DETAIL",
    "DETAIL_LAYER",
    "DETAIL_SET",
    "DETAIL_VARIANTS",
    "FRIEZE_KEY",
    "FRIEZE_PATH",
    "TERRACOTTA",
    "DetailGeometry",
    "TemplePlan",
    "check_detail",
    "check_hypotheses",
    "detail_counts",
    "detail_geometry",
    "plan_temple",
]

DETAIL_SET = "detail"
DETAIL_VARIANTS = ("plain", "moulded", "carved")
# the default selection: see the README (Detail) for the measured cost of each variant
DEFAULT_DETAIL = "carved"
DETAIL_LAYER = "detail.usdc"
FRIEZE_PATH = "/Temple/Entablature/Ornament/FriezeGarlands"
# material prim name, stone style of its maps (the temple's library, materials.usda)
TERRACOTTA = ("Terracotta", "terracotta")
_PART = {
    "podium": "Podium",
    "architrave": "Entablature",
    "cornice": "Entablature",
    "sima": "Entablature",
    "raking": "Roof",
}
# baseline finish: the ancient painted stucco (see portunus.toml); bare stone is a hypothesis
BASELINE_FINISH = "stucco"
# the cuboids' st share the column asset's convention: UV_SPAN metres per unit of st
CUBOID_UV_SCALE = 1.0 / UV_SPAN
# temple keys the composer cannot realise: the column asset is built once per temple
_COLUMN_SHAPE_KEYS = ("columns.lower_diameter", "columns.upper_diameter_ratio")


@dataclass(frozen=True, eq=False)
class DetailGeometry:
    """Kernel values of a temple's detail: members by part prim, ornament by prim path."""

    mouldings: dict[str, dict[str, Mesh]]  # part prim name → member name → mesh
    ornament: dict[str, Instances]  # path below /Temple → instances
    frieze: Instances | None
    podium_cuboids: tuple[str, ...] = field(default=())

    def prims(self, variant: str, *, garlands: bool = False) -> dict[str, Mesh | Instances]:
        """Absolute prim path → the mesh or instances shown by ``variant`` (cuboids aside)."""
        if variant == "plain":
            return {}
        out: dict[str, Mesh | Instances] = {
            f"/Temple/{part}/Mouldings/{name}": m
            for part, members in self.mouldings.items()
            for name, m in members.items()
        }
        if variant == "carved":
            out.update({f"/Temple/{rel}": inst for rel, inst in self.ornament.items()})
            if garlands and self.frieze is not None:
                out[FRIEZE_PATH] = self.frieze
        return out


def check_detail(value: str) -> str:
    """``value`` if it names a ``detail`` variant, else :class:`ParameterError`."""
    if value not in DETAIL_VARIANTS:
        raise ParameterError("detail", value, f"one of {', '.join(DETAIL_VARIANTS)}")
    return value


def detail_geometry(layout: TempleLayout, mp: MouldingParams | None = None) -> DetailGeometry:
    """Mouldings and ornament of a layout (pure numpy; see the module docstring)."""
    mp = mp or portunus_mouldings()
    by_part: dict[str, dict[str, Mesh]] = {}
    for m in moulding_meshes(layout, mp, uv_scale=1.0 / TILE_METRES):
        part = _PART[m.name.split("_")[0]]
        by_part.setdefault(part, {})[m.name] = m.mesh
    orn = {"Entablature/Ornament/Dentils": dentils(layout), "Roof/Tiles": roof_tiles(layout)}
    podium = tuple(prim_name(c.name) for c in layout.cuboids.get(Layer.PODIUM, ()))
    # an entablature without a frieze (the Asiatic order) has no relief to carry
    has_frieze = any(c.name == "frieze" for c in layout.cuboids.get(Layer.ENTABLATURE, ()))
    return DetailGeometry(by_part, orn, frieze_garlands(layout) if has_frieze else None, podium)


def detail_counts(geom: DetailGeometry) -> dict[str, dict[str, int]]:
    """Triangles, prototypes and instances each ``detail`` variant *adds* to the cuboids
    (``plain`` adds nothing; ``moulded`` adds the sweeps; ``carved`` also the ornament, its
    triangles counted over every copy)."""
    sweep_tris = sum(m.n_triangles for ms in geom.mouldings.values() for m in ms.values())
    orn = list(geom.ornament.values())
    meshes = sum(len(ms) for ms in geom.mouldings.values())
    return {
        "plain": {"triangles": 0, "prototypes": 0, "instances": 0, "meshes": 0},
        "moulded": {"triangles": sweep_tris, "prototypes": 0, "instances": 0, "meshes": meshes},
        "carved": {
            "triangles": sweep_tris + sum(i.triangles for i in orn),
            "prototypes": sum(len(i.prototypes) for i in orn),
            "instances": sum(len(i) for i in orn),
            "meshes": meshes,
        },
    }


def check_hypotheses(
    layout: TempleLayout, opts: ColumnAssetOptions
) -> dict[str, HypothesisChanges]:
    """Every hypothesis' composer changes, validated against the asset's variants (a change
    the generator cannot realise raises :class:`ParameterError` naming it)."""
    flutes = {k: v for k, v in FLUTE_VARIANTS.items() if k in opts.flutes}
    out = {}
    for h in layout.hypotheses:
        for key in temple_keys(h):
            if key in _COLUMN_SHAPE_KEYS:
                raise ParameterError(
                    key,
                    h.changes[key],
                    "a key the composer can realise "
                    "(the column asset is built once; change [columns] "
                    "instead)",
                    context=f"hypothesis {h.id!r}",
                )
        out[h.id] = check_composer_changes(h, flutes, FINISHES, opts.capitals)
    return out


@dataclass
class TemplePlan:
    """Everything the temple's layers need, validated (:func:`plan_temple`):
    :func:`ionic_usd.usd.temple.write_temple` authors them into a folder that already holds
    the column asset."""

    layout: TempleLayout
    opts: ColumnAssetOptions
    detail: str
    changes: dict[str, HypothesisChanges]
    geometry: DetailGeometry
    base_meshes: dict
    lods: tuple[str, ...]
    detail_of: Callable[[TempleLayout], DetailGeometry]


def plan_temple(
    layout: TempleLayout,
    column: ColumnParams | None = None,
    *,
    texture_size: int = 1024,
    seed: int = 7,
    asset_options: ColumnAssetOptions | None = None,
    detail: str | None = None,
    mouldings: MouldingParams | None = None,
) -> TemplePlan:
    """The temple's column asset options and layers, validated before anything is written.

    Parameters are :func:`ionic_usd.pipeline.temple.compose_temple`'s. Hypothesis changes the
    generator cannot realise raise :class:`ParameterError`.
    """
    check_hypothesis_budget(layout)  # bounded work: before anything else
    column = column or temple_column_params(layout)
    opts = temple_asset_options(
        column, texture_size=texture_size, seed=seed, asset_options=asset_options
    )
    detail = check_detail(detail or DEFAULT_DETAIL)
    changes = check_hypotheses(layout, opts)  # every hypothesis, before any geometry
    mp = mouldings or portunus_mouldings()
    detail_cache: dict[object, DetailGeometry] = {}

    def detail_of(want: TempleLayout) -> DetailGeometry:
        # the detail follows the dimensions (hypotheses without temple keys share one)
        key = (want.params, tuple(want.all_cuboids()))
        if key not in detail_cache:
            detail_cache[key] = detail_geometry(want, mp)
        return detail_cache[key]

    return TemplePlan(
        layout=layout,
        opts=opts,
        detail=detail,
        changes=changes,
        geometry=detail_of(layout),
        base_meshes=cuboid_meshes(layout, CUBOID_UV_SCALE),
        lods=tuple(lod for lod in LOD_NAMES if lod in opts.lods),
        detail_of=detail_of,
    )
