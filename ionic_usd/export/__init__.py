"""Export for games, the web, AR and 3D printing: glTF/GLB, usdz, STL and 3MF.

Every writer is fed by the one scene reader (:func:`ionic_usd.usd.reader.read_scene`), so the
variant selections, instancing and paradata a user sees in USD are what the export carries.

>>> from ionic_usd.export import export_scene            # doctest: +SKIP
>>> export_scene("PortunusTemple/Temple.usda", "temple.glb", lod="medium")
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

from ionic_usd.export.common import EXPORT_FORMATS, check_export_path

__all__ = ["EXPORT_FORMATS", "ExportResult", "export_scene"]


@dataclass(frozen=True)
class ExportResult:
    """The written file, its format, and the writer's report (GltfReport, UsdzReport, …)."""

    path: Path
    format: str
    report: object


def export_scene(
    scene: str | os.PathLike,
    output: str | os.PathLike,
    *,
    variants: Mapping[str, str] | None = None,
    lod: str | None = None,
    gpu_instancing: bool = False,
    merge: bool = True,
    compress: str | None = None,
    scale: float = 1.0,
    force: bool = False,
) -> ExportResult:
    """Export a USD scene by the output's extension (.glb, .gltf, .usdz, .stl, .3mf).

    Parameters
    ----------
    scene : a USD file any ionic_usd command wrote (shaft, column, asset, temple, city)
    output : the file to write (atomically; an existing one needs ``force``)
    variants : ``{set: value}`` selected on every prim that has the set (default: authored)
    lod : shorthand for ``variants["lod"]``
    gpu_instancing : glTF only: ``EXT_mesh_gpu_instancing`` (required) for repeated meshes
        (default: one node per copy, the mesh shared; core glTF)
    merge : glTF only: bake the copies of small meshes into one mesh per point instancer
    compress : glTF only: None or ``"draco"`` (KHR_draco_mesh_compression, needs DracoPy)
    scale : STL/3MF only: model scale (1:20 → 0.05)
    """
    out = check_export_path(output, force=force)
    fmt = out.suffix.lower().lstrip(".")
    if fmt in ("glb", "gltf"):
        from ionic_usd.export.gltf import write_gltf
        from ionic_usd.usd.reader import read_scene

        s = read_scene(scene, variants=variants, lod=lod)
        return ExportResult(
            out,
            fmt,
            write_gltf(s, out, gpu_instancing=gpu_instancing, merge=merge, compress=compress),
        )
    if fmt == "usdz":
        from ionic_usd.usd.package import write_usdz

        return ExportResult(out, fmt, write_usdz(scene, out, variants=variants, lod=lod))
    from ionic_usd.export.solid import write_solids
    from ionic_usd.usd.reader import read_scene

    s = read_scene(scene, variants=variants, lod=lod)
    return ExportResult(out, fmt, write_solids(s, out, scale=scale))
