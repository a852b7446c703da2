"""The Ionic column as a USD component asset: variant sets, xatlas UVs, stone materials.

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
flutes      f24, f20                                    Shaft (f20: a reconstruction
                                                        hypothesis for the Portunus shafts)
form        full, engaged, corner                       every part (engaged: cut by the wall
                                                        plane z = −``ENGAGED_INSET``, capped;
                                                        corner: the quadrant x, z < −inset
                                                        removed, a three-quarter column)
finish      travertine, stucco                          the material bound to Geom
==========  ==========================================  ===================================

The ``high`` LOD also carries the carved capital: egg-and-dart on the echinus and bead-and-reel
on the astragal, two PointInstancers under ``Geom/Ornament`` (4 prototypes, 90 copies, 8.8k
triangles drawn; :func:`ionic_usd.usd.detail.column_ornament`), tagged ``lod = high``.

Every mesh is one closed solid: the capital's abacus, echinus, volutes, canales and bolsters are
united (manifold3d), so the capital mesh depends on the scroll and capital variants. Each mesh
is authored once: the shaft does not depend on the base. Triangle budgets of the default
column (three parts, form = full): high ≈ 40.7k, medium ≈ 15.9k, low ≈ 7.9k.

Texture coordinates come from xatlas, one chart set per part and LOD, at one texel density per
LOD (``ASSET_TEXELS_PER_METRE``); every LOD's pixel coordinates are divided by
``texels_per_metre × UV_SPAN`` so that ``st`` ∈ [0, 1] spans the same ``UV_SPAN`` metres on every
part and LOD. The material repeats its tileable stone maps ``UV_SPAN / TILE_METRES`` times per
unit of ``st`` (UsdTransform2d), i.e. once every ``TILE_METRES`` metres of stone.
"""

from __future__ import annotations

import dataclasses
import math
import os
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ionic_usd import __version__
from ionic_usd.column.column import (
    LODS,
    ColumnParams,
    build_base_part,
    build_capital_part,
    build_shaft_part,
    column_params_to_tables,
    portunus_column_params,
)
from ionic_usd.errors import GeometryError, ParameterError
from ionic_usd.geometry.mesh import Mesh
from ionic_usd.texture.uv import UVCache, attach_uvs, unwrap_parts
from ionic_usd.usd.asset import AssetMesh, AssetSpec, write_asset
from ionic_usd.usd.detail import column_ornament
from ionic_usd.usd.materials import MaterialTextures

__all__ = [
    "ColumnAssetOptions",
    "AssetReport",
    "build_column_asset",
    "column_asset_meshes",
    "ASSET_NAME",
    "BASE_VARIANTS",
    "SCROLL_VARIANTS",
    "FLUTE_VARIANTS",
    "FORM_VARIANTS",
    "CAPITAL_VARIANTS",
    "FINISHES",
    "ENGAGED_INSET",
    "UV_SPAN",
    "TILE_METRES",
]

ASSET_NAME = "IonicColumn"
BASE_VARIANTS = ("attic_bezier_plinth", "attic_bezier", "G1", "G2")
SCROLL_VARIANTS = ("S1", "S2")
FLUTE_VARIANTS = {"f24": 24, "f20": 20}
FORM_VARIANTS = ("full", "engaged", "corner")
CAPITAL_VARIANTS = ("normal", "angle")
# finish variant -> (material prim name, stone style of its textures)
FINISHES = {"travertine": ("Travertine", "travertine"),
            "stucco": ("PaintedStucco", "stucco_painted")}
ENGAGED_INSET = 0.05  # m: the cut lies this far behind the wall face (axis on the face)
# Atlas density of the asset's UVs. The materials tile 2 m stone maps, so the atlas density
# only sets the chart gutters (4 texels = 3 cm at 128 px/m) and the resolution available to a
# later bake; xatlas's packing time grows with the atlas area (measured: the four parts of
# the high-LOD column take 4.3 s at 256 px/m, 2.4 s at 64 px/m).
ASSET_TEXELS_PER_METRE = {"high": 128.0, "medium": 64.0, "low": 32.0}
BASE_CHART_BOUNDARY = 2.0  # m: see texture.uv.unwrap(max_chart_boundary=…)
UV_SPAN = 32.0  # m of surface across st ∈ [0, 1]
TILE_METRES = 2.0  # m of stone per repeat of the tileable maps


@dataclass(frozen=True)
class ColumnAssetOptions:
    """What to build: variants, texture resolution, extras."""

    params: ColumnParams = dataclasses.field(default_factory=portunus_column_params)
    lods: tuple[str, ...] = tuple(LODS)
    bases: tuple[str, ...] = BASE_VARIANTS
    scrolls: tuple[str, ...] = SCROLL_VARIANTS
    flutes: tuple[str, ...] = tuple(FLUTE_VARIANTS)
    forms: tuple[str, ...] = FORM_VARIANTS
    capitals: tuple[str, ...] = CAPITAL_VARIANTS
    texture_size: int = 1024
    seed: int = 7
    make_tx: bool = False
    user_textures: Mapping[str, str] | None = None  # role (basecolor/roughness/normal) -> file
    # the carved echinus and astragal (instanced ornament in the high LOD): written with the
    # temple's architectural detail (ionic-usd temple --detail …)
    carved: bool = False

    def __post_init__(self) -> None:
        def check(name: str, given: Sequence[str], valid: Sequence[str]) -> None:
            if not given:
                raise ParameterError(name, given, f"at least one of {', '.join(valid)}")
            for g in given:
                if g not in valid:
                    raise ParameterError(name, g, f"one of {', '.join(valid)}")

        check("lod", self.lods, tuple(LODS))
        check("base", self.bases, BASE_VARIANTS)
        check("scroll", self.scrolls, SCROLL_VARIANTS)
        check("flutes", self.flutes, tuple(FLUTE_VARIANTS))
        check("form", self.forms, FORM_VARIANTS)
        check("capital", self.capitals, CAPITAL_VARIANTS)
        if self.user_textures is not None:
            roles = {"basecolor", "roughness", "normal"}
            if set(self.user_textures) != roles:
                raise ParameterError("user textures", sorted(self.user_textures),
                                     "exactly the roles basecolor, roughness, normal")


@dataclass(frozen=True)
class AssetReport:
    path: Path
    meshes: int
    triangles_per_lod: dict[str, int]
    uv_unwraps: int
    seconds: float
    bytes_on_disk: int


def _wall_cut(mesh: Mesh, x_max: float | None, simplify: bool = False) -> Mesh:
    """``mesh`` minus the wall block z < −ENGAGED_INSET (and x < ``x_max`` if given), by a
    robust boolean difference (manifold3d): the cut faces are exact planar caps."""
    from ionic_usd.geometry.boolean import difference
    from ionic_usd.temple.cuboid import Cuboid, cuboid_mesh

    lo, hi = mesh.extent
    big = float(np.abs(np.concatenate([lo, hi])).max()) + 1.0
    x1 = big if x_max is None else x_max
    block = cuboid_mesh(Cuboid((-big, lo[1] - 1.0, -big), (x1, hi[1] + 1.0, -ENGAGED_INSET),
                               name="wall"))
    return difference(mesh, [block], name=mesh.name, simplify=simplify)


def _engage(mesh: Mesh, part: str = "") -> Mesh:
    """The half column: the part behind the wall plane z = −ENGAGED_INSET removed.

    A plane clip capped by a constrained Delaunay triangulation (base and shaft cut faces meet
    along the same vertices, so they still weld); for a capital whose united surface has
    slivers the triangulation chokes on, the boolean difference.
    """
    import shapely

    from ionic_usd.geometry.clip import clip_mesh

    try:
        return clip_mesh(mesh, (0.0, 0.0, -ENGAGED_INSET), (0.0, 0.0, 1.0), name=mesh.name)
    except (GeometryError, shapely.errors.GEOSException):
        if part != "CapitalBody":
            raise
        return _wall_cut(mesh, None, simplify=True)


def _corner(mesh: Mesh, part: str = "") -> Mesh:
    """The three-quarter column: the quadrant x, z < −ENGAGED_INSET (inside the walls of a
    corner whose outer faces hold the axis) removed."""
    return _wall_cut(mesh, -ENGAGED_INSET, simplify=part == "CapitalBody")


_FORM_CUT = {"full": None, "engaged": _engage, "corner": _corner}


def _flute_params(params: ColumnParams, flutes: int) -> ColumnParams:
    return params.with_flutes(flutes)


def column_asset_meshes(opts: ColumnAssetOptions,
                        uv_cache: UVCache | None = None) -> list[AssetMesh]:
    """Every mesh of the asset with its variant tags (geometry only; with ``uv_cache`` the
    capital is charted by xatlas before the form cuts, which carry the charts)."""
    out: list[AssetMesh] = []
    for lod in opts.lods:
        p = opts.params.with_lod(lod)
        base_h = p.base_params().height
        groups: list[tuple[str, str, Mesh, dict[str, str]]] = []
        for b in opts.bases:
            groups.append(("Base", f"Base_{b}", build_base_part(p, b), {"base": b}))
        for fname in opts.flutes:
            fp = _flute_params(p, FLUTE_VARIANTS[fname])
            groups.append(("Shaft", f"Shaft_{fname}", build_shaft_part(fp, base_h),
                           {"flutes": fname}))
        y_cap = base_h + p.shaft.length
        for s in opts.scrolls:
            for c in opts.capitals:
                body = build_capital_part(p, y_cap, scroll=s, angle=c == "angle")
                tag = {"scroll": s, "capital": c}
                groups.append(("CapitalBody", f"Capital_{s}_{c}", body, tag))
        if uv_cache is not None:  # base and shaft have analytic st; chart the capital once
            from ionic_usd.texture.uv import metric_charts

            caps = [i for i, g in enumerate(groups) if g[0] == "CapitalBody"]
            charted = metric_charts([groups[i][2] for i in caps], ASSET_TEXELS_PER_METRE[lod],
                                    cache=uv_cache)
            for i, m in zip(caps, charted, strict=True):
                groups[i] = (groups[i][0], groups[i][1], m, groups[i][3])
        for part, name, mesh, tags in groups:
            for form in opts.forms:
                cut = _FORM_CUT[form]
                m = mesh if cut is None else cut(mesh, part)
                suffix = "" if form == "full" else f"_{form}"
                t = {"lod": lod, **tags}
                if len(opts.forms) > 1:
                    t["form"] = form
                out.append(AssetMesh(part, f"{name}_{lod}{suffix}", m.with_(name=name), t))
    return out


def _with_uvs(meshes: list[AssetMesh], cache: UVCache | None) -> tuple[list[AssetMesh], int]:
    from ionic_usd.texture.uv import prefetch

    misses0 = cache.misses if cache is not None else 0
    def boundary(m: AssetMesh) -> float | None:
        return BASE_CHART_BOUNDARY if m.part == "Base" else None

    prefetch([(m.mesh, ASSET_TEXELS_PER_METRE[m.tags["lod"]], boundary(m)) for m in meshes],
             cache=cache)
    out = []
    for lod in {m.tags["lod"] for m in meshes}:
        these = [m for m in meshes if m.tags["lod"] == lod]
        tpm = ASSET_TEXELS_PER_METRE[lod]
        atlases = unwrap_parts({f"{m.part}/{m.name}": m.mesh for m in these},
                               texels_per_metre=tpm, cache=cache,
                               chart_boundaries={f"{m.part}/{m.name}": boundary(m)
                                                 for m in these})
        used = min(a.texels_per_metre for a in atlases.values())
        size = max(math.ceil(used * UV_SPAN), max(a.size for a in atlases.values()))
        for m in these:
            a = atlases[f"{m.part}/{m.name}"]
            out.append(dataclasses.replace(m, mesh=attach_uvs(m.mesh, a, size)))
    order = {(m.part, m.name): i for i, m in enumerate(meshes)}
    out.sort(key=lambda m: order[(m.part, m.name)])
    unwraps = (cache.misses - misses0) if cache is not None else len(meshes)
    return out, unwraps


def build_column_asset(
    folder: str | os.PathLike,
    opts: ColumnAssetOptions | None = None,
    *,
    force: bool = False,
    cache: UVCache | None = None,
) -> AssetReport:
    """Write the column asset ``<folder>/IonicColumn.usda`` (+ Payload/) atomically.

    Parameters
    ----------
    folder : the asset folder (its name is usually ``IonicColumn``)
    opts : variants and textures to build (default: everything, Portunus column)
    force : replace an existing folder (atomically)
    cache : UV cache (default: the process-wide one); a rebuild of unchanged geometry runs
        no xatlas work

    User textures (``opts.user_textures``) are validated before anything is written.
    """
    from ionic_usd.texture.stone import copy_user_textures, validate_user_texture
    from ionic_usd.texture.uv import default_cache

    t0 = time.perf_counter()
    opts = opts or ColumnAssetOptions()
    dest = Path(folder)
    if dest.exists() and not force:
        from ionic_usd.errors import OutputExistsError

        raise OutputExistsError(f"{dest} exists; pass --force to replace it")
    if opts.user_textures:
        for src in opts.user_textures.values():
            validate_user_texture(src)
    cache = cache if cache is not None else default_cache()
    misses0 = cache.misses
    meshes, _ = _with_uvs(column_asset_meshes(opts, uv_cache=cache), cache)
    unwraps = cache.misses - misses0

    materials: dict[str, MaterialTextures] = {}
    for _, (mat, style) in FINISHES.items():
        if opts.user_textures and style == "travertine":
            names = {r: Path(p).name for r, p in opts.user_textures.items()}
        else:
            names = {r: f"{style}_{r}.png" for r in ("basecolor", "roughness", "normal")}
        materials[mat] = MaterialTextures(*(f"./Textures/{names[r]}"
                                            for r in ("basecolor", "roughness", "normal")))

    def populate(tmp: Path) -> None:
        from ionic_usd.progress import progress

        tex = tmp / "Payload" / "Textures"
        with progress(len(FINISHES), "stone textures (OpenImageIO)", unit="material") as bar:
            for _, style in FINISHES.values():
                if opts.user_textures and style == "travertine":
                    copy_user_textures(opts.user_textures, tex)
                else:
                    copy_stone_textures(tex, style, opts.texture_size, opts.seed,
                                        make_tx=opts.make_tx)
                bar.update(1)

    variant_sets = {"lod": opts.lods, "base": opts.bases, "scroll": opts.scrolls,
                    "capital": opts.capitals, "flutes": opts.flutes, "form": opts.forms,
                    "finish": tuple(FINISHES)}
    custom = {"ionic_usd": {"version": __version__,
                            "parameters": _flatten(column_params_to_tables(opts.params))}}
    spec = AssetSpec(
        name=ASSET_NAME,
        version=__version__,
        meshes=tuple(meshes),
        variant_sets=variant_sets,
        defaults={k: v[0] for k, v in variant_sets.items()},
        materials=materials,
        default_material=FINISHES["travertine"][0],
        finishes={k: v[0] for k, v in FINISHES.items()},
        custom_data=custom,
        documentation="Ionic column (Temple of Portunus proportions) generated by ionic_usd "
        "after Konečný, Syllaiou & Liarokapis 2016; variant sets: lod, base, scroll, capital, "
        "flutes, form, finish.",
        st_scale=UV_SPAN / TILE_METRES,
        proxy_lod="low" if "low" in opts.lods and len(opts.lods) > 1 else None,
        instancers=column_ornament(opts) if opts.carved else (),
    )
    path = write_asset(spec, dest, populate=populate, force=force)
    tris: dict[str, int] = {}
    for lod in opts.lods:
        sel = [m for m in meshes if m.tags["lod"] == lod and m.tags.get("form", "full") == "full"
               and m.tags.get("base", opts.bases[0]) == opts.bases[0]
               and m.tags.get("scroll", opts.scrolls[0]) == opts.scrolls[0]
               and m.tags.get("capital", opts.capitals[0]) == opts.capitals[0]
               and m.tags.get("flutes", opts.flutes[0]) == opts.flutes[0]]
        tris[lod] = sum(m.mesh.n_triangles for m in sel)
    size = sum(f.stat().st_size for f in dest.rglob("*") if f.is_file())
    return AssetReport(path, len(meshes), tris, unwraps, time.perf_counter() - t0, size)


def copy_stone_textures(folder: Path, style: str, size: int, seed: int, *,
                        make_tx: bool = False) -> list[Path]:
    """Put a stone style's maps into ``folder``, generating them once per (style, size, seed).

    Generated maps are deterministic, so they are kept in the cache folder (beside the UV
    cache) and copied: a rebuild writes no PNG.
    """
    import shutil

    from ionic_usd.io import verified_cache
    from ionic_usd.texture.stone import TextureError, write_stone_textures
    from ionic_usd.texture.uv import default_cache_folder

    key = f"{style}-{size}-{seed}-{__version__}{'-tx' if make_tx else ''}"
    store = default_cache_folder().parent / "textures" / key
    names = [f"{style}_{r}.{e}" for r in ("basecolor", "roughness", "normal")
             for e in (("png", "tx") if make_tx else ("png",))]
    try:  # verified on read (SHA-256 manifest), written atomically, rebuilt when bad
        store = verified_cache(store, lambda tmp: write_stone_textures(
            tmp, style, size, seed, make_tx=make_tx))
    except (OSError, TextureError):  # an unwritable or full cache: write into the asset
        write_stone_textures(folder, style, size, seed, make_tx=make_tx)
        return [folder / n for n in names]
    folder.mkdir(parents=True, exist_ok=True)
    out = []
    for n in names:
        shutil.copyfile(store / n, folder / n)
        out.append(folder / n)
    return out


def _flatten(tables: dict[str, dict]) -> dict[str, object]:
    """TOML-like tables as USD customData (a dictionary of dictionaries of scalars)."""
    return {name: {k: v for k, v in t.items() if v is not None} for name, t in tables.items()}
