"""Component assets with variant sets, laid out like Pixar's Kitchen_set and usd-exchange.

::

    <Name>/<Name>.usda            interface: Xform default prim, kind = component, assetInfo,
                                  variant sets, extentsHint, payload → ./Payload/Contents.usda
    <Name>/Payload/Contents.usda  sublayers ./Materials.usda and ./Geometry.usdc; the stable
                                  slots (Geom/<Part>, Proxy/<Part>) and the variants that point
                                  each at its library item
    <Name>/Payload/Geometry.usdc  every mesh once, in the library class /_<Name>Parts/<Part>/<name>
    <Name>/Payload/Materials.usda UsdPreviewSurface materials, default binding on Geom
    <Name>/Payload/Textures/      texture images (./Textures/… from Materials.usda)

Variant sets live on the interface's default prim, so they are visible before the payload is
loaded; the same sets, nested by name in ``Contents.usda``, hold the geometry. Each mesh
carries tags — the variant it belongs to in each variant set that concerns it (a shaft is
tagged only with ``lod``, ``flutes`` and ``form``). A slot (``Geom/Shaft``) references the
mesh whose tags match the selection (:mod:`ionic_usd.usd.asset_slots`): switching a set
changes what is under the paths of the parts it tags, never a path.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path

from pxr import Sdf, Usd

from ionic_usd.blueprint.asset import AssetInstancer, AssetMesh, AssetSpec
from ionic_usd.usd.asset_slots import (
    Slot,
    author_slot_variants,
    library_path,
    slot_extents_hints,
    slots,
)
from ionic_usd.usd.bounds import author_extents_hints
from ionic_usd.usd.materials import (
    author_preview_material,
    bind_material,
    bind_material_spec,
)
from ionic_usd.usd.mesh import author_mesh
from ionic_usd.usd.stage import new_layer, save_layer, vt_dictionary

__all__ = [
    "AssetMesh",
    "AssetInstancer",
    "AssetSpec",
    "class_path",
    "write_asset",
    "write_asset_layers",
    "replace_folder",
]


def _geometry_layer(spec: AssetSpec) -> Sdf.Layer:
    """Every mesh and instancer once, in the library class ``/_<Name>Parts/<part>/<name>``
    (:mod:`ionic_usd.usd.asset_slots`): the composed asset references them from stable slots."""
    layer = new_layer(spec.name, kind=None)
    lib = library_path(spec.name)
    with Sdf.ChangeBlock():
        for m in spec.meshes:
            author_mesh(layer, f"{lib}/{m.part}/{m.name}", m.mesh)
        if spec.instancers:
            from ionic_usd.usd.instancer import author_point_instancer

            for a in spec.instancers:
                author_point_instancer(layer, f"{lib}/{a.part}/{a.name}", a.instances)
        for child in layer.GetPrimAtPath(lib).nameChildren:
            child.typeName = "Scope"
        top = layer.GetPrimAtPath(lib)
        top.specifier, top.typeName = Sdf.SpecifierClass, "Scope"
    return layer


def _slots(spec: AssetSpec) -> list[Slot]:
    return slots(spec.name, spec.tagged(), spec.variant_sets, spec.proxy_lod)


def _materials_layer(spec: AssetSpec) -> Sdf.Layer:
    layer = new_layer(spec.name, kind=None)
    stage = Usd.Stage.Open(layer)
    stage.DefinePrim(f"/{spec.name}/Materials", "Scope")
    for mat_name, tex in spec.materials.items():
        author_preview_material(
            stage, f"/{spec.name}/Materials/{mat_name}", tex, st_scale=spec.st_scale
        )
    geom = stage.DefinePrim(f"/{spec.name}/Geom", "Scope")
    bind_material(geom, f"/{spec.name}/Materials/{spec.default_material}")
    if spec.proxy_lod is not None:
        proxy = stage.DefinePrim(f"/{spec.name}/Proxy", "Scope")
        bind_material(proxy, f"/{spec.name}/Materials/{spec.default_material}")
    return layer


def _contents_layer(spec: AssetSpec) -> Sdf.Layer:
    """The payload's root: the materials and the library as sublayers, the stable slots and
    the variants that point them at the library."""
    layer = new_layer(spec.name, kind=None)
    layer.subLayerPaths.append("./Materials.usda")
    layer.subLayerPaths.append("./Geometry.usdc")
    author_slot_variants(layer, f"/{spec.name}", _slots(spec), spec.defaults)
    return layer


def class_path(name: str) -> str:
    """The class every instance of the asset inherits (``/_class_<name>``): an opinion there
    changes every instance in a scene at once."""
    return f"/_class_{name}"


def _interface_layer(spec: AssetSpec) -> Sdf.Layer:
    name = spec.name
    layer = new_layer(name, kind="component", comment=spec.documentation)
    root = layer.GetPrimAtPath(f"/{name}")
    cls = Sdf.CreatePrimInLayer(layer, class_path(name))
    cls.specifier = Sdf.SpecifierClass
    root.inheritPathList.Prepend(Sdf.Path(class_path(name)))
    root.assetInfo = {
        "name": name,
        "version": spec.version,
        "identifier": Sdf.AssetPath(f"./{name}.usda"),
    }
    root.payloadList.Prepend(Sdf.Payload("./Payload/Contents.usda"))
    if spec.custom_data:
        root.customData = vt_dictionary(spec.custom_data)
    if spec.documentation:
        root.documentation = spec.documentation
    with Sdf.ChangeBlock():
        for vset, variants in spec.variant_sets.items():
            vs_spec = Sdf.VariantSetSpec(root, vset)
            root.variantSetNameList.Append(vset)
            for v in variants:
                var = Sdf.VariantSpec(vs_spec, v)
                vprim = var.primSpec
                if vset == "finish" and v in spec.finishes:
                    scopes = ["Geom"] + (["Proxy"] if spec.proxy_lod is not None else [])
                    for scope in scopes:
                        bind_material_spec(
                            _over(vprim, scope), f"/{name}/Materials/{spec.finishes[v]}"
                        )
            root.variantSelections[vset] = spec.defaults[vset]
    return layer


def _over(parent: Sdf.PrimSpec, child: str) -> Sdf.PrimSpec:
    spec = parent.nameChildren.get(child)
    if spec is None:
        spec = Sdf.PrimSpec(parent, child, Sdf.SpecifierOver)
    return spec


def write_asset_layers(spec: AssetSpec, folder: Path) -> dict[str, Path]:
    """Write the four layers of an asset into ``folder`` (which must hold ``Payload/Textures``)."""
    folder = Path(folder)
    payload = folder / "Payload"
    payload.mkdir(parents=True, exist_ok=True)
    written = {
        "geometry": save_layer(_geometry_layer(spec), payload / "Geometry.usdc", force=True),
        "materials": save_layer(_materials_layer(spec), payload / "Materials.usda", force=True),
        "contents": save_layer(_contents_layer(spec), payload / "Contents.usda", force=True),
    }
    interface = _interface_layer(spec)
    written["interface"] = save_layer(interface, folder / f"{spec.name}.usda", force=True)
    # extentsHint lets a renderer cull and a DCC frame the asset before its payload loads:
    # per combination of the sets that switch geometry, the union of what the slots reference
    tagging = {
        vs: spec.variant_sets[vs]
        for vs in spec.variant_sets
        if any(vs in m.tags for m in spec.tagged())
    }
    hints = slot_extents_hints(str(written["geometry"]), f"/{spec.name}", _slots(spec), tagging)
    author_extents_hints(interface, f"/{spec.name}", hints, list(tagging))
    save_layer(interface, written["interface"], force=True)
    return written


def replace_folder(
    build: Callable[[Path], object],
    dest: Path,
    *,
    force: bool = False,
    keep_existing: tuple[str, ...] = (),
    root_files: tuple[str, ...] = (),
    key: str | None = None,
    record: Callable[[object], dict] | None = None,
):
    """Build a folder in a staging sibling and move it into place kill-safely.

    See :func:`ionic_usd.io.replace_folder`: an existing ``dest`` is refused unless ``force``;
    only files the previous build generated are replaced or deleted (the user's own files
    stay), and a process killed at any instant is recovered by the next run. Returns what
    ``build`` returned.
    """
    from ionic_usd.io import replace_folder as _replace

    dest = Path(dest)
    result = _replace(
        build,
        dest,
        force=force,
        keep_existing=keep_existing,
        root_files=root_files,
        key=key,
        record=record,
    )
    # layers cached under the old content must be re-read
    for layer in Sdf.Layer.GetLoadedLayers():
        real = layer.realPath
        if real and Path(real).is_relative_to(dest.resolve()):
            layer.Reload(force=True)
    return result


def write_asset(
    spec: AssetSpec,
    folder: str | os.PathLike,
    *,
    populate: Callable[[Path], None] | None = None,
    force: bool = False,
    key: str | None = None,
    record: dict | None = None,
) -> Path:
    """Write an asset folder atomically; ``populate(tmp_folder)`` adds the textures after the
    layers (which only name them: maps still being generated elsewhere get the layers' time);
    ``key`` and ``record`` are kept in its manifest (:func:`ionic_usd.io.replace_folder`)."""
    dest = Path(folder)

    def build(tmp: Path):
        (tmp / "Payload" / "Textures").mkdir(parents=True, exist_ok=True)
        write_asset_layers(spec, tmp)
        if populate is not None:
            populate(tmp)

    replace_folder(
        build,
        dest,
        force=force,
        root_files=(f"{spec.name}.usda",),
        key=key,
        record=None if key is None else (lambda _: dict(record or {})),
    )
    return dest / f"{spec.name}.usda"
