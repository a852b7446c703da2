"""The ``ionic-usd export`` subcommand."""

from __future__ import annotations

import argparse
import math
from pathlib import Path
from typing import Any

from ionic_usd.cli.flags import add_command, add_memory_flag, add_output_flags, add_variant_flag
from ionic_usd.errors import ParameterError

__all__ = ["add_parser", "cmd_export", "parse_scale"]


def parse_scale(text: str) -> float:
    """``"0.05"`` or ``"1:20"`` → 0.05 (a finite number > 0)."""
    t = str(text).strip()
    try:
        if ":" in t:
            a, b = t.split(":", 1)
            value = float(a) / float(b)
        else:
            value = float(t)
    except (ValueError, ZeroDivisionError):
        raise ParameterError("--scale", text, "a number > 0 or a ratio like 1:20") from None
    if not math.isfinite(value) or value <= 0:
        raise ParameterError("--scale", text, "a number > 0 or a ratio like 1:20")
    lo, hi = 1e-4, 10.0  # ionic_usd.export.solid.SCALE_RANGE (not imported: numpy)
    if not lo <= value <= hi:
        raise ParameterError(
            "--scale", text, "1:10000 (1e-4, a site model) to 10 (a detail study, 10:1)"
        )
    return value


def cmd_export(args: argparse.Namespace) -> int:
    from ionic_usd.export import export_scene
    from ionic_usd.export.common import check_export_path
    from ionic_usd.usd.variants import parse_variant_args

    variants = parse_variant_args(args.variant)
    scale = parse_scale(args.scale)
    fmt = Path(args.output).suffix.lower()
    if scale != 1.0 and fmt not in (".stl", ".3mf"):
        raise ParameterError(
            "--scale",
            args.scale,
            "1 unless the output is .stl or .3mf (glTF and usdz stay in metres)",
        )
    for flag, on in (("--gpu-instancing", args.gpu_instancing), ("--no-merge", args.no_merge)):
        if on and fmt not in (".glb", ".gltf"):
            raise ParameterError(flag, "given", "only with a .glb or .gltf output")
    if args.compress != "none" and fmt not in (".glb", ".gltf"):
        raise ParameterError("--compress", args.compress, "none unless the output is glTF")
    if args.compress == "draco":
        from ionic_usd.export.common import require

        require("DracoPy", "--compress draco")  # before any work
    check_export_path(args.output, force=args.force)
    if not Path(args.scene).is_file():
        raise ParameterError("scene", str(args.scene), "an existing USD file")
    if Path(args.output).resolve() == Path(args.scene).resolve():
        raise ParameterError("--output", args.output, "a file other than the scene read")
    from ionic_usd.resources import check_estimate, estimate_inputs

    check_estimate(estimate_inputs(f"exporting {args.scene}", args.scene), args.max_memory)
    res = export_scene(
        args.scene,
        args.output,
        variants=variants,
        lod=args.lod,
        gpu_instancing=args.gpu_instancing,
        merge=not args.no_merge,
        compress=None if args.compress == "none" else args.compress,
        scale=scale,
        force=args.force,
    )
    r: Any = res.report  # GltfReport, UsdzReport or SolidsReport, by res.format
    if res.format in ("glb", "gltf"):
        print(
            f"wrote {res.path}: {r.bytes / 1e6:.2f} MB, {r.meshes} meshes, "
            f"{r.materials} materials, {r.images} images, {r.triangles_drawn:,} triangles "
            f"drawn ({r.triangles:,} stored), {r.draw_calls} draw calls, "
            f"{r.gpu_instanced_meshes} GPU-instanced meshes, {r.merged} copies merged "
            f"({r.seconds:.2f} s)"
        )
    elif res.format == "usdz":
        print(
            f"wrote {res.path}: {r.bytes / 1e6:.2f} MB, {r.files} files packaged, "
            f"{r.expanded_copies} point-instanced copies expanded into meshes, "
            f"{r.validation_errors} validation errors ({r.seconds:.2f} s)"
        )
    else:
        for s in r.solids:
            ext = " x ".join(f"{1e3 * v:.1f}" for v in s.size)
            print(
                f"  {s.name}: volume {1e9 * s.volume:,.0f} mm^3, size {ext} mm, "
                f"{'closed' if s.closed else 'NOT closed'}, {s.triangles:,} triangles"
                + (
                    f", {s.non_manifold_edges} pinched edges (a part touches itself)"
                    if s.non_manifold_edges
                    else ""
                )
            )
        print(
            f"wrote {res.path}: {len(r.solids)} solids at scale {scale:g}, "
            f"{'all closed' if r.all_closed else 'SOME NOT CLOSED'} ({r.seconds:.2f} s)"
        )
        if not r.all_closed:
            return 1
    return 0


def add_parser(sub: Any, parser_class: Any = None, *, arguments: bool = True) -> None:
    """Add the ``export`` subcommand (``arguments=False``: its name and help only).

    ``parser_class`` is unused: ``add_subparsers(parser_class=…)`` already sets it.
    """
    del parser_class
    p = add_command(
        sub,
        "export",
        cmd_export,
        help="export a USD scene as glTF/GLB, usdz, STL or 3MF",
        description="Export SCENE (any scene ionic_usd writes: shaft, column, asset, temple, "
        "city) by the output's extension: .glb/.gltf (glTF 2.0 for game engines and the web: "
        "PBR materials with embedded textures, instancing kept, paradata in extras), .usdz "
        "(ARKit: one flattened package, textures inside), .stl/.3mf (3D printing: one closed "
        "solid per column, parts unioned, at --scale).",
    )
    if not arguments:
        return
    p.add_argument("scene", type=Path, help="USD file to export")
    add_output_flags(p, "output file: .glb, .gltf, .usdz, .stl or .3mf", required=True)
    add_variant_flag(
        p,
        "select VALUE in variant set SET on every prim that has it "
        "(repeatable; default: the authored selections)",
    )
    p.add_argument("--lod", help="level of detail (same as --variant lod=LOD)")
    p.add_argument(
        "--gpu-instancing",
        action=argparse.BooleanOptionalAction,
        default=False,
        help="glTF: draw a mesh's copies as one EXT_mesh_gpu_instancing node, the extension "
        "then required (clients without it refuse the file) [default: one node per copy, "
        "the mesh shared, drawn alike by every client]",
    )
    p.add_argument(
        "--no-merge",
        action="store_true",
        help="glTF: keep every copy of small meshes (tiles, dentils, egg-and-dart) as its own "
        "node instead of one merged mesh per instancer",
    )
    p.add_argument(
        "--compress",
        choices=["none", "draco"],
        default="none",
        help="glTF: compress meshes with Draco (KHR_draco_mesh_compression, a "
        "required extension; needs DracoPy) [default none]",
    )
    p.add_argument(
        "--scale",
        default="1",
        help="STL/3MF: model scale, a number or ratio (1:20 = 0.05) [default 1]",
    )
    add_memory_flag(p, what="an export")
