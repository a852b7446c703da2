"""usdz packages for AR (ARKit profile), written with usd-core's own ``Sdf.ZipFileWriter``.

The scene is opened, the requested variant selections are made in the session layer (see
:func:`ionic_usd.usd.variants.select_variants`), and the composed stage is flattened — variant
sets resolved away, references and payloads merged, native instancing kept as flattened
prototypes — into one crate layer in a temporary folder, with every texture it uses copied
beside it (``textures/``). The package holds that layer first, then the textures by name
(uncompressed, 64-byte aligned, as usdz requires); it is checked with ``pxr.UsdValidation``
before it replaces the output.

The same scene gives the same package, byte for byte: ``Stage.Flatten`` names the prototypes
``/Flattened_Prototype_<n>`` in the order USD happened to number them, which changes from one
opening of the stage to the next (one thread or many), so :func:`stable_prototypes`
renumbers them by the path of their first instance; the flattened layer is written through
the text format and read back before the crate file is written, as the crate writer keeps
each spec's fields in the order they were authored, and ``Flatten`` authors them in an
order that changes from one process to another (``Sdf.CopySpec`` sorts them by the field
names' addresses in memory); the zip stamps each file with its
modification time, which is set to the zip epoch first (1980-01-01 00:00 local time, as the
zip stores it); the layer's documentation and the models' ``assetInfo`` identifiers are
made relative to the scene's folder; and ``UsdUtils.CreateNewARKitUsdzPackage``, which
listed the textures in an order that changed from run to run, is not used.
"""

from __future__ import annotations

import os
import tempfile
import time
import zipfile
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

from pxr import Ar, Sdf

from ionic_usd.errors import UsdAuthoringError
from ionic_usd.usd.expand import expand_point_instancers, normals_as_attributes
from ionic_usd.usd.stage import validate_stage
from ionic_usd.usd.variants import open_stage, select_variants

__all__ = ["UsdzReport", "stable_prototypes", "write_usdz"]

_FLAT = "Flattened_Prototype_"


@dataclass(frozen=True)
class UsdzReport:
    path: Path
    bytes: int
    files: int
    variant_sets_left: int
    validation_errors: int
    seconds: float
    expanded_copies: int = 0  # point-instancer copies baked into meshes


def _gather_textures(layer: Sdf.Layer, folder: Path) -> int:
    """Copy every asset the flattened layer uses into ``folder/textures/`` (one file per
    content) and point the layer at them with ``./textures/…`` paths, so the package holds
    them under one plain folder. Returns the number of files copied."""
    import hashlib  # noqa: PLC0415
    import shutil  # noqa: PLC0415

    by_hash: dict[str, str] = {}
    names: set[str] = set()

    def fix(path: Sdf.Path) -> None:
        if not path.IsPropertyPath():
            return
        attr = layer.GetAttributeAtPath(path)
        if attr is None or attr.typeName != Sdf.ValueTypeNames.Asset:
            return
        v = attr.default
        if not isinstance(v, Sdf.AssetPath) or not v.path:
            return
        # Flatten anchors asset paths to absolute ones; a stray relative one goes to Ar
        src = Path(v.resolvedPath or str(Ar.GetResolver().Resolve(v.path)) or v.path)
        if not src.is_absolute() or not src.is_file():
            raise UsdAuthoringError(f"{path}: asset {v.path} does not resolve")
        h = hashlib.blake2b(src.read_bytes(), digest_size=12).hexdigest()
        if h not in by_hash:
            name, i = src.name, 1
            while name.lower() in names:
                name, i = f"{src.stem}_{i}{src.suffix}", i + 1
            names.add(name.lower())
            (folder / "textures").mkdir(exist_ok=True)
            shutil.copyfile(src, folder / "textures" / name)
            by_hash[h] = f"./textures/{name}"
        attr.default = Sdf.AssetPath(by_hash[h])

    layer.Traverse(Sdf.Path.absoluteRootPath, fix)
    return len(by_hash)


def _referencing_specs(layer: Sdf.Layer) -> list[tuple[Sdf.Path, Sdf.PrimSpec]]:
    """Every prim spec of ``layer`` that has references, with its path (traversal order)."""
    found: list[tuple[Sdf.Path, Sdf.PrimSpec]] = []

    def visit(path: Sdf.Path) -> None:
        if path.IsPrimPath():
            spec = layer.GetPrimAtPath(path)
            if spec is not None and spec.hasReferences:
                found.append((path, spec))

    layer.Traverse(Sdf.Path.absoluteRootPath, visit)
    return found


def _internal_refs(layer: Sdf.Layer) -> dict[str, list[str]]:
    """Prototype root path → paths of the prim specs that reference it internally."""
    users: dict[str, list[str]] = {}
    for path, spec in _referencing_specs(layer):
        for ref in spec.referenceList.GetAddedOrExplicitItems():
            if not ref.assetPath and ref.primPath.name.startswith(_FLAT):
                users.setdefault(str(ref.primPath), []).append(str(path))
    return users


def _rename_references(layer: Sdf.Layer, mapping: dict[str, str]) -> None:
    """Internal references to ``mapping``'s keys point at its values instead."""

    def fix(ref: Sdf.Reference) -> Sdf.Reference:
        new = mapping.get(str(ref.primPath)) if not ref.assetPath else None
        if new is None:
            return ref
        return Sdf.Reference(ref.assetPath, Sdf.Path(new), ref.layerOffset, ref.customData)

    for _, spec in _referencing_specs(layer):
        refs = spec.referenceList
        for kind in ("explicitItems", "prependedItems", "appendedItems"):
            items = list(getattr(refs, kind))
            fixed = [fix(r) for r in items]
            if fixed != items:
                setattr(refs, kind, fixed)


def stable_prototypes(layer: Sdf.Layer) -> int:
    """Renumber a flattened layer's ``/Flattened_Prototype_<n>`` by their first instance.

    A prototype's key is the smallest path among the prims that reference it, a path inside
    another prototype taken under that prototype's own key (nested instancing), so the order
    depends on the scene alone. Each prototype is copied under its new name with
    ``Sdf.CopySpec`` (which moves the targets and connections inside it along) and the
    references to it are rewritten. Returns how many prototypes were renumbered.
    """
    protos = [str(p.path) for p in layer.rootPrims if p.name.startswith(_FLAT)]
    if not protos:
        return 0
    users = _internal_refs(layer)
    keys: dict[str, str] = {}

    def key(proto: str, depth: int = 0) -> str:
        if proto not in keys:
            stable = []
            for u in users.get(proto, []):
                owner = next((p for p in protos if u.startswith(p + "/")), None)
                if owner is None or depth > len(protos):
                    stable.append(u)
                else:
                    stable.append(key(owner, depth + 1) + u[len(owner) :])
            keys[proto] = min(stable, default="\uffff" + proto)
        return keys[proto]

    order = sorted(protos, key=key)
    final = {old: f"/{_FLAT}{i + 1}" for i, old in enumerate(order)}
    moved = sum(old != new for old, new in final.items())
    # every prototype is copied, moved or not, so the layer's order of root prims (copies
    # come last) does not depend on USD's numbering either; in two steps, through temporary
    # names, as a new name may be another prototype's old one
    temp = {old: f"/_ionic_usd_prototype_{i}" for i, old in enumerate(order)}
    for step in (temp, {temp[old]: new for old, new in final.items()}):
        for src, dst in step.items():
            if not Sdf.CopySpec(layer, Sdf.Path(src), layer, Sdf.Path(dst)):
                raise UsdAuthoringError(f"could not copy the flattened prototype {src}")
        _rename_references(layer, step)
        for src in step:
            del layer.rootPrims[Sdf.Path(src).name]
    return moved


def _relative_paths(layer: Sdf.Layer, scene: Path) -> None:
    """Flatten anchors the models' ``assetInfo`` identifiers to absolute paths and documents
    the root layer's: both relative to the scene's folder instead (the file's name for one
    outside it), so the package neither depends on nor tells where the scene lay on disk."""
    folder = scene.resolve().parent
    layer.documentation = f"Flattened by ionic_usd from {scene.name}"

    def relative(path: str) -> str:
        p = Path(path)
        if not p.is_absolute():
            return path
        try:
            return "./" + p.resolve().relative_to(folder).as_posix()
        except ValueError:
            return "./" + p.name

    def visit(path: Sdf.Path) -> None:
        if not path.IsPrimPath():
            return
        spec = layer.GetPrimAtPath(path)
        info = dict(spec.assetInfo) if spec is not None and spec.assetInfo else {}
        ident = info.get("identifier")
        if isinstance(ident, Sdf.AssetPath) and Path(ident.path).is_absolute():
            info["identifier"] = Sdf.AssetPath(relative(ident.path))
            spec.SetInfo("assetInfo", info)

    layer.Traverse(Sdf.Path.absoluteRootPath, visit)


def _canonical(layer: Sdf.Layer) -> Sdf.Layer:
    """The layer read back from its text: every spec's fields in the text format's order."""
    canonical = Sdf.Layer.CreateAnonymous(".usda")
    if not canonical.ImportFromString(layer.ExportToString()):
        raise UsdAuthoringError("could not read back the flattened stage's text")
    return canonical


def _zip_package(root: Path, textures: list[Path], pkg: Path) -> None:
    """The usdz archive (``Sdf.ZipFileWriter``: uncompressed, 64-byte aligned): the root
    layer first, as the format requires, then the textures by name."""
    writer = Sdf.ZipFileWriter.CreateNew(str(pkg))
    if not writer.AddFile(str(root), root.name):
        raise UsdAuthoringError(f"{pkg}: could not add {root.name} to the package")
    for tex in textures:
        if not writer.AddFile(str(tex), f"textures/{tex.name}"):
            raise UsdAuthoringError(f"{pkg}: could not add textures/{tex.name} to the package")
    if not writer.Save():
        raise UsdAuthoringError(f"{pkg}: could not write the usdz package")


def write_usdz(
    scene: str | os.PathLike,
    output: str | os.PathLike,
    *,
    variants: Mapping[str, str] | None = None,
    lod: str | None = None,
) -> UsdzReport:
    """Write ``output`` (.usdz): ``scene`` flattened with the chosen variants, ARKit profile.

    Raises UsdAuthoringError if packaging fails or the package fails ``pxr.UsdValidation``
    (the output is then left as it was).
    """
    t0 = time.perf_counter()
    out = Path(output)
    sel = dict(variants or {})
    if lod is not None:
        sel["lod"] = lod
    stage = open_stage(scene)
    if sel:
        select_variants(stage, sel)
    flat = stage.Flatten()
    _relative_paths(flat, Path(scene))
    stable_prototypes(flat)
    expanded = expand_point_instancers(flat)  # the ARKit profile has no PointInstancer
    normals_as_attributes(flat)  # Blender reads primvars:normals twice
    # what Flatten keeps of variant sets: none should be left (the ARKit profile forbids them)
    left = 0

    def count(path: Sdf.Path) -> None:
        nonlocal left
        if path.IsPrimPath() and flat.GetPrimAtPath(path).variantSets:
            left += 1

    flat.Traverse(Sdf.Path.absoluteRootPath, count)
    # a hidden temporary folder beside the output: the final rename is atomic
    with tempfile.TemporaryDirectory(prefix=f".{out.stem}.usdz-", dir=out.parent) as tmp:
        _gather_textures(flat, Path(tmp))
        root = Path(tmp) / f"{out.stem or 'scene'}.usdc"
        if not _canonical(flat).Export(str(root)):
            raise UsdAuthoringError(f"{scene}: could not write the flattened stage")
        # the zip records local modification times: the epoch in local time, for every file
        epoch = time.mktime((1980, 1, 1, 0, 0, 0, 0, 1, -1))
        for f in Path(tmp).rglob("*"):
            os.utime(f, (epoch, epoch))
        pkg = Path(tmp) / "package.usdz"
        _zip_package(root, sorted((Path(tmp) / "textures").glob("*")), pkg)
        errors = validate_stage(str(pkg))
        if errors:
            raise UsdAuthoringError(
                f"{out}: the usdz package fails validation: {errors[0]} ({len(errors)} errors)"
            )
        with zipfile.ZipFile(pkg) as z:
            files = len(z.namelist())
        os.replace(pkg, out)
    return UsdzReport(out, out.stat().st_size, files, left, 0, time.perf_counter() - t0, expanded)
