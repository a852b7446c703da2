"""usdz packages for AR (ARKit profile) made with usd-core's own ``UsdUtils`` packaging.

The scene is opened, the requested variant selections are made in the session layer (see
:func:`ionic_usd.usd.variants.select_variants`), and the composed stage is flattened — variant
sets resolved away, references and payloads merged, native instancing kept as flattened
prototypes — into one crate layer in a temporary folder beside the textures' real paths.
``UsdUtils.CreateNewARKitUsdzPackage`` then copies that layer and every texture it uses into a
zip-aligned ``.usdz``. The package is checked with ``pxr.UsdValidation`` before it replaces
the output.
"""

from __future__ import annotations

import os
import tempfile
import time
import zipfile
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

from pxr import Ar, Sdf, UsdUtils

from ionic_usd.errors import UsdAuthoringError
from ionic_usd.usd.stage import validate_stage
from ionic_usd.usd.variants import open_stage, select_variants

__all__ = ["UsdzReport", "write_usdz"]


@dataclass(frozen=True)
class UsdzReport:
    path: Path
    bytes: int
    files: int
    variant_sets_left: int
    validation_errors: int
    seconds: float


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
        if not flat.Export(str(root)):
            raise UsdAuthoringError(f"{scene}: could not write the flattened stage")
        pkg = Path(tmp) / "package.usdz"
        if not UsdUtils.CreateNewARKitUsdzPackage(Sdf.AssetPath(str(root)), str(pkg)):
            raise UsdAuthoringError(f"{scene}: UsdUtils could not package it as usdz")
        errors = validate_stage(str(pkg))
        if errors:
            raise UsdAuthoringError(
                f"{out}: the usdz package fails validation: {errors[0]} ({len(errors)} errors)"
            )
        with zipfile.ZipFile(pkg) as z:
            files = len(z.namelist())
        os.replace(pkg, out)
    return UsdzReport(out, out.stat().st_size, files, left, 0, time.perf_counter() - t0)
