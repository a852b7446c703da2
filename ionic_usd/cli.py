"""The ``ionic-usd`` command line: thin wrappers over the public API.

Every command validates all input before writing anything; errors print one line
(``ionic-usd: error: …``) and exit with status 2.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
import time
from pathlib import Path

from ionic_usd.errors import IonicError

__all__ = ["main", "build_parser"]


# -- parameter flags from dataclasses ----------------------------------------------------------
def add_dataclass_flags(
    parser: argparse.ArgumentParser,
    cls,
    docs: dict[str, tuple[str, str, str]],
    *,
    prefix: str = "",
    title: str = "parameters",
) -> None:
    """One ``--flag`` per dataclass field; help shows the paper letter, unit and default."""
    group = parser.add_argument_group(title)
    defaults = cls()
    for f in dataclasses.fields(cls):
        if f.name.startswith("_"):
            continue
        letter, unit, text = docs.get(f.name, ("", "", f.name.replace("_", " ")))
        default = getattr(defaults, f.name)
        typ = type(default) if default is not None else str
        if typ is bool:
            typ = _parse_bool
        tag = f"{letter}, " if letter else ""
        group.add_argument(
            f"--{prefix}{f.name.replace('_', '-')}",
            dest=f"{prefix.replace('-', '_')}{f.name}",
            type=typ,
            default=None,
            metavar=unit.upper() if unit else "VALUE",
            help=f"{text} [{tag}{unit}; default {default}]",
        )


def _parse_bool(text: str) -> bool:
    low = text.lower()
    if low in ("1", "true", "yes", "on"):
        return True
    if low in ("0", "false", "no", "off"):
        return False
    raise argparse.ArgumentTypeError(f"expected true/false, got {text!r}")


def collect_flags(args: argparse.Namespace, cls, *, prefix: str = "") -> dict:
    """The dataclass fields given on the command line (None = not given)."""
    out = {}
    for f in dataclasses.fields(cls):
        v = getattr(args, f"{prefix.replace('-', '_')}{f.name}", None)
        if v is not None:
            out[f.name] = v
    return out


# -- commands ----------------------------------------------------------------------------------
def _shaft_params(args: argparse.Namespace):
    from ionic_usd.column.shaft import ShaftParams
    from ionic_usd.params import dataclass_from_mapping, load_toml

    base = ShaftParams()
    if args.config:
        data = load_toml(args.config)
        section = data.get("shaft", data)
        if not isinstance(section, dict):
            from ionic_usd.errors import ParameterError

            raise ParameterError("shaft", section, "a TOML table", context=str(args.config))
        base = dataclass_from_mapping(ShaftParams, section, context=f"{args.config} [shaft]")
    flags = collect_flags(args, ShaftParams)
    return dataclass_from_mapping(ShaftParams, flags, context="command line", base=base)


def cmd_shaft(args: argparse.Namespace) -> int:
    from ionic_usd.column.shaft import (
        SHAFT_PARAMETER_DOCS,
        build_shaft,
        shaft_triangle_estimate,
    )
    from ionic_usd.params import to_toml

    params = _shaft_params(args)
    if args.print_config:
        sys.stdout.write(
            to_toml({"shaft": params.to_dict()}, {"shaft": SHAFT_PARAMETER_DOCS},
                    header="ionic_usd shaft parameters (edit and pass with --config)")
        )
        return 0
    from ionic_usd.usd import check_output_path, write_meshes

    out = check_output_path(args.output, force=args.force)
    _check_memory("the shaft", shaft_triangle_estimate(params), args)
    t0 = time.perf_counter()
    from ionic_usd.geometry.guard import guarded

    mesh = guarded(lambda: build_shaft(params, max_triangles=args.max_triangles), "shaft",
                   "parameters")
    t1 = time.perf_counter()
    write_meshes(out, {"Shaft": mesh}, root="Shaft", force=args.force)
    t2 = time.perf_counter()
    print(
        f"wrote {out}: {mesh.n_triangles:,} triangles, {mesh.n_points:,} points "
        f"(generate {1e3 * (t1 - t0):.1f} ms, write {1e3 * (t2 - t1):.1f} ms)"
    )
    return 0


def _column_params(args: argparse.Namespace):
    from ionic_usd.column.column import column_params_from_mapping, portunus_column_params
    from ionic_usd.params import load_toml

    params = portunus_column_params()
    if args.config:
        params = column_params_from_mapping(load_toml(args.config), context=str(args.config))
    flags = {k: getattr(args, k) for k in ("lod", "base", "scroll") if getattr(args, k, None)}
    if flags:
        params = column_params_from_mapping({"column": flags}, context="command line",
                                            base=params)
    return params


_PARTS = {
    "all": ("Base", "Shaft", "CapitalBody"),
    "base": ("Base",),
    "shaft": ("Shaft",),
    "capital": ("CapitalBody",),
    "base+shaft": ("Base", "Shaft"),
}


def cmd_column(args: argparse.Namespace) -> int:
    from ionic_usd.column.column import COLUMN_DOCS, build_column, column_params_to_tables
    from ionic_usd.column.shaft import SHAFT_PARAMETER_DOCS
    from ionic_usd.params import to_toml

    params = _column_params(args)
    if args.print_config:
        from ionic_usd.column.capital import CAPITAL_PARAMETER_DOCS
        from ionic_usd.column.volute import VOLUTE_PARAMETER_DOCS

        docs = {"column": COLUMN_DOCS, "shaft": SHAFT_PARAMETER_DOCS,
                "capital": CAPITAL_PARAMETER_DOCS, "volute": VOLUTE_PARAMETER_DOCS}
        sys.stdout.write(to_toml(column_params_to_tables(params), docs,
                                 header="ionic_usd column parameters (edit and pass with "
                                 "--config); lengths in metres, angles in degrees"))
        return 0
    from ionic_usd.usd import check_output_path, write_meshes

    out = check_output_path(args.output, force=args.force)
    from ionic_usd.resources import check_estimate, estimate_column

    check_estimate(estimate_column(params), args.max_memory)
    t0 = time.perf_counter()
    col = build_column(params)
    t1 = time.perf_counter()
    meshes = {k: v for k, v in col.parts().items() if k in _PARTS[args.part]}
    write_meshes(out, meshes, root="Column", force=args.force,
                 comment=f"ionic_usd column ({params.lod}, base {params.base})")
    t2 = time.perf_counter()
    tris = sum(m.n_triangles for m in meshes.values())
    print(f"wrote {out}: {', '.join(meshes)}; {tris:,} triangles, height {col.height:.3f} m "
          f"(generate {1e3 * (t1 - t0):.1f} ms, write {1e3 * (t2 - t1):.1f} ms)")
    return 0


def cmd_asset(args: argparse.Namespace) -> int:
    from ionic_usd.errors import ParameterError
    from ionic_usd.io import check_output_folder
    from ionic_usd.resources import check_estimate, estimate_asset
    from ionic_usd.usd.column_asset import ColumnAssetOptions, build_column_asset

    check_output_folder(args.output, force=args.force)
    params = _column_params(args)
    user = None
    if args.texture:
        user: dict[str, str] = {}
        roles = ("basecolor", "roughness", "normal")
        for item in args.texture:
            role, sep, path = item.partition("=")
            if not sep or role not in roles or not path:
                raise ParameterError("--texture", item, "ROLE=FILE with ROLE basecolor, "
                                     "roughness or normal")
            if role in user:  # the last one silently winning would hide a typo
                raise ParameterError("--texture", item, f"each role once ({role} is also "
                                     f"{user[role]!r})")
            user[role] = path
    check_estimate(estimate_asset(params, args.texture_size), args.max_memory)
    opts = ColumnAssetOptions(params=params, texture_size=args.texture_size, seed=args.seed,
                              make_tx=args.tx, user_textures=user)
    rep = build_column_asset(args.output, opts, force=args.force)
    lods = ", ".join(f"{k} {v:,}" for k, v in rep.triangles_per_lod.items())
    print(f"wrote {rep.path}: {rep.meshes} meshes, triangles per LOD: {lods}; "
          f"{rep.uv_unwraps} UV unwraps, {rep.bytes_on_disk / 1e6:.1f} MB, {rep.seconds:.2f} s")
    return 0


def cmd_temple(args: argparse.Namespace) -> int:
    from ionic_usd.column.column import column_params_from_mapping, portunus_column_params
    from ionic_usd.io import check_output_folder
    from ionic_usd.params import load_toml
    from ionic_usd.temple.layout import layout_from_mapping, portunus_layout
    from ionic_usd.usd.temple import compose_temple

    check_output_folder(args.output, force=args.force)
    column = mouldings = None
    if args.config:
        data = load_toml(args.config)
        from ionic_usd.temple.mouldings import mouldings_from_tables

        mouldings = mouldings_from_tables(data, context=str(args.config))
        col_tables = {k: data.pop(k) for k in ("column", "shaft", "capital", "volute")
                      if k in data}
        layout = layout_from_mapping(data, context=str(args.config))
    else:
        col_tables = {}
        layouts = {"portunus": portunus_layout}
        if args.layout not in layouts:
            from ionic_usd.errors import ParameterError

            raise ParameterError("--layout", args.layout,
                                 f"one of the built-in layouts: {', '.join(layouts)} "
                                 "(or describe a temple in a TOML file: --config)")
        layout = layouts[args.layout]()
    p = layout.params
    base = portunus_column_params(height=p.columns_height,
                                  lower_diameter=p.columns_lower_diameter)
    if col_tables:
        column = column_params_from_mapping(col_tables, context=str(args.config), base=base)
    from ionic_usd.resources import check_estimate, estimate_temple

    n_cuboids = sum(len(c) for c in layout.cuboids.values())
    check_estimate(estimate_temple(column or base, args.texture_size, n_cuboids),
                   args.max_memory)
    rep = compose_temple(args.output, layout, column, force=args.force,
                         texture_size=args.texture_size, seed=args.seed,
                         detail=args.detail, mouldings=mouldings)
    print(f"wrote {rep.root} ({layout.name}): {rep.files} files, {rep.prims} prims, "
          f"{rep.instances} column instances of {rep.prototypes} prototypes, "
          f"{rep.triangles:,} triangles, {len(rep.hypotheses)} hypotheses, {rep.seconds:.2f} s")
    print(f"  open {rep.root} in usdview, Blender, Houdini or Omniverse; put your own edits in "
          f"{Path(args.output) / 'overrides.usda'} (kept on rebuilds)")
    return 0


def cmd_preview(args: argparse.Namespace) -> int:
    from ionic_usd.errors import ParameterError
    from ionic_usd.preview import render_preview

    try:
        background = tuple(float(x) for x in args.background.split(","))
    except ValueError:
        raise ParameterError("--background", args.background, "three numbers R,G,B") from None
    s = render_preview(args.scene, args.output, width=args.width, height=args.height,
                       camera=args.camera, lod=args.lod, background=background,
                       samples=args.samples, ground=not args.no_ground, force=args.force)
    print(f"wrote {args.output}: {s.triangles:,} triangles, {s.meshes} meshes, "
          f"{s.instances} instances ({s.seconds:.2f} s)")
    return 0


def _check_memory(what: str, triangles: int, args: argparse.Namespace) -> None:
    from ionic_usd.resources import (
        BASELINE_BYTES,
        BYTES_PER_TRIANGLE,
        Estimate,
        check_estimate,
    )

    check_estimate(Estimate(what, triangles, 0, BASELINE_BYTES + BYTES_PER_TRIANGLE * triangles),
                   args.max_memory)


def _add_memory_flag(p: argparse.ArgumentParser) -> None:
    from ionic_usd.resources import DEFAULT_MAX_MEMORY_GB

    p.add_argument("--max-memory", type=float, metavar="GB", default=None,
                   help="refuse work whose estimated peak memory exceeds this "
                   f"[default {DEFAULT_MAX_MEMORY_GB:g} GB]")


# -- parser --------------------------------------------------------------------------------------
class _Parser(argparse.ArgumentParser):
    def error(self, message: str):  # one line, status 2 (argparse's own convention)
        self.exit(2, f"{self.prog}: error: {message}\n")


def build_parser() -> argparse.ArgumentParser:
    from ionic_usd import __version__
    from ionic_usd.column.shaft import DEFAULT_TRIANGLE_BUDGET, SHAFT_PARAMETER_DOCS, ShaftParams

    parser = _Parser(
        prog="ionic-usd",
        description="Procedural Ionic-order columns and temples authored as OpenUSD scenes.",
    )
    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    parser.add_argument("-v", "--verbose", action="count", default=0,
                        help="say what each step does (-vv: debugging detail) on stderr")
    parser.add_argument("-q", "--quiet", action="store_true",
                        help="no progress bars and no messages but errors")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)

    p = sub.add_parser(
        "shaft",
        help="write the fluted column shaft as USD",
        description="Build the fluted shaft (paper Table 1, parameters $a-$i) and write it as "
        "USD (.usda text, .usdc/.usd binary, by extension). Parameters come from defaults "
        "(the Temple of Portunus), then --config TOML ([shaft] table), then flags.",
    )
    p.add_argument("-o", "--output", default="shaft.usda", help="output USD file")
    p.add_argument("--config", type=Path, help="TOML file with a [shaft] table")
    p.add_argument("--print-config", action="store_true",
                   help="print the full parameter set as TOML and exit")
    p.add_argument("--force", action="store_true", help="overwrite an existing output file")
    p.add_argument("--max-triangles", type=int, default=DEFAULT_TRIANGLE_BUDGET,
                   help="refuse a level of detail above this triangle count "
                   f"[default {DEFAULT_TRIANGLE_BUDGET:,}]")
    add_dataclass_flags(p, ShaftParams, SHAFT_PARAMETER_DOCS, title="shaft parameters")
    _add_memory_flag(p)
    p.set_defaults(func=cmd_shaft)

    p = sub.add_parser(
        "column",
        help="write a whole column (base, shaft, capital) as USD",
        description="Build base + shaft + capital (default: the Temple of Portunus column) and "
        "write the parts as separate meshes under one Xform. Parameters: defaults, then "
        "--config TOML ([column], [shaft], [capital], [volute] tables; see --print-config), "
        "then flags.",
    )
    p.add_argument("-o", "--output", default="column.usda", help="output USD file")
    p.add_argument("--config", type=Path, help="TOML file (see --print-config)")
    p.add_argument("--print-config", action="store_true",
                   help="print the full parameter set as TOML and exit")
    p.add_argument("--force", action="store_true", help="overwrite an existing output file")
    p.add_argument("--part", choices=list(_PARTS), default="all", help="which parts to write")
    p.add_argument("--lod", help="level of detail: high, medium, low or custom")
    p.add_argument("--base", help="base preset (G1, G2, attic_bezier, attic_bezier_plinth) or "
                   "a base grammar string")
    p.add_argument("--scroll", help="scroll preset (S1, S2) or ring grammar 'R0.7 P0.05, …'")
    _add_memory_flag(p)
    p.set_defaults(func=cmd_column)

    p = sub.add_parser(
        "temple",
        help="compose a temple scene (default: the Temple of Portunus) — the main job",
        description="Write a temple as a USD assembly: Temple.usda (root) with podium, cella, "
        "entablature, roof and colonnade layers, the instanced column asset, textures, and one "
        "variant set per reconstruction hypothesis (layers/). Your overrides.usda is kept.",
    )
    p.add_argument("-o", "--output", default="PortunusTemple", help="output folder")
    p.add_argument("--config", type=Path,
                   help="temple TOML (schema of ionic_usd/data/portunus.toml; may add [column], "
                   "[shaft], [capital], [volute] tables for the column)")
    p.add_argument("--layout", default="portunus", help="built-in temple layout (portunus)")
    p.add_argument("--texture-size", type=int, default=1024,
                   help="texture resolution (px): a power of two, 16-4096 within the default "
                   "memory limit; 8192 needs about 10 GB (--max-memory 10)")
    p.add_argument("--seed", type=int, default=7, help="seed of the procedural stone")
    p.add_argument("--detail", choices=("plain", "moulded", "carved"), default=None,
                   help="the default selection of the temple's variant set `detail`: plain "
                   "(cuboids), moulded (swept mouldings) or carved (mouldings, dentils, roof "
                   "tiles, frieze relief hypothesis) [default: carved]")
    p.add_argument("--force", action="store_true",
                   help="rebuild an existing folder (atomically; overrides.usda is kept)")
    _add_memory_flag(p)
    p.set_defaults(func=cmd_temple)

    from ionic_usd.pipeline.commands import add_city_parser

    add_city_parser(sub, _Parser)

    p = sub.add_parser(
        "asset",
        help="write the column as a USD component asset with variant sets",
        description="Write IonicColumn/IonicColumn.usda (interface: kind=component, assetInfo, "
        "variant sets lod/base/scroll/flutes/form/finish, payload) with Payload/Contents.usda, "
        "Geometry.usdc, Materials.usda and Textures/ (xatlas UVs, OpenImageIO stone maps).",
    )
    p.add_argument("-o", "--output", default="IonicColumn", help="asset folder")
    p.add_argument("--config", type=Path, help="column TOML (see ionic-usd column --print-config)")
    p.add_argument("--base", help="default base (variants are always all four presets)")
    p.add_argument("--scroll", help=argparse.SUPPRESS)
    p.add_argument("--lod", help=argparse.SUPPRESS)
    p.add_argument("--texture-size", type=int, default=1024,
                   help="texture resolution in pixels: a power of two, 16-4096 within the "
                   "default memory limit; 8192 needs about 10 GB (--max-memory 10)")
    p.add_argument("--seed", type=int, default=7, help="seed of the procedural stone")
    p.add_argument("--tx", action="store_true", help="also write mipmapped .tx textures")
    p.add_argument("--texture", action="append", metavar="ROLE=FILE",
                   help="use your own travertine map (png/jpg) for ROLE basecolor, roughness "
                   "or normal; give all three")
    p.add_argument("--force", action="store_true",
                   help="replace an existing asset folder (atomically)")
    _add_memory_flag(p)
    p.set_defaults(func=cmd_asset)

    p = sub.add_parser(
        "preview",
        help="render a USD scene to a PNG thumbnail (headless OpenGL)",
        description="Render SCENE with moderngl on a software EGL context (needs the preview "
        "extra: pip install 'ionic_usd[preview]'). Instances are drawn from one upload each.",
    )
    p.add_argument("scene", type=Path, help="USD file to render")
    p.add_argument("-o", "--output", type=Path, default=Path("preview.png"), help="PNG file")
    p.add_argument("--width", type=int, default=800)
    p.add_argument("--height", type=int, default=600)
    p.add_argument("--camera", choices=["auto", "front", "three-quarter"], default="auto")
    p.add_argument("--lod", help="select this lod variant on every prim that has one")
    p.add_argument("--background", default="0.80,0.84,0.89", help="R,G,B in [0, 1]")
    p.add_argument("--samples", type=int, default=4, help="MSAA samples")
    p.add_argument("--no-ground", action="store_true", help="no ground plane")
    p.add_argument("--force", action="store_true", help="overwrite an existing PNG")
    p.set_defaults(func=cmd_preview)

    from ionic_usd.evaluate.commands import add_parsers

    add_parsers(sub, _Parser)
    from ionic_usd.export import add_export_parser

    add_export_parser(sub, _Parser)
    return parser


def _one_line(text: str) -> str:
    return " ".join(text.split())


def _os_message(exc: OSError) -> str:
    """An OS error as the user needs it: what failed, on which path."""
    import errno

    what = exc.strerror or _one_line(str(exc)) or type(exc).__name__
    hint = {errno.ENOSPC: " (free some space or write elsewhere)",
            errno.EROFS: " (write elsewhere)",
            errno.EACCES: " (check the folder's permissions)",
            errno.ENAMETOOLONG: " (use a shorter name)"}.get(exc.errno or 0, "")
    where = f": {exc.filename}" if exc.filename else ""
    if getattr(exc, "filename2", None):
        where += f" -> {exc.filename2}"
    return f"{what}{where}{hint}"


def _library_error(exc: Exception) -> str | None:
    """The message of an error raised inside OpenUSD (``pxr.Tf.ErrorException``), else None.

    Recognised by its type, without importing ``pxr`` here (only ``ionic_usd.usd`` does).
    """
    t = type(exc)
    if t.__module__.startswith("pxr") or (t.__name__ == "ArgumentError" \
            and "Boost" in t.__module__):
        lines = [ln.strip() for ln in str(exc).splitlines() if ln.strip()]
        return "OpenUSD: " + (lines[-1] if lines else t.__name__)
    return None


def _fail(message: str, status: int = 2) -> int:
    print(f"ionic-usd: error: {message}", file=sys.stderr)
    return status


def main(argv: list[str] | None = None) -> int:
    """Run the command line; returns the exit status (2 for any refused input or OS fault).

    Every failure prints one line on stderr (a grammar error adds its source with a caret):
    the package's own errors, OS errors (full disk, read-only folder, a name too long), and
    errors from OpenUSD. An unexpected exception is a bug: one line, status 70, and the
    traceback only with ``IONIC_USD_DEBUG=1``.
    """
    import os

    try:
        parser = build_parser()
        args = parser.parse_args(argv)
        from ionic_usd.progress import configure

        configure(-1 if args.quiet else args.verbose)
        return int(args.func(args) or 0)
    except IonicError as exc:
        # one line; a grammar error adds its source line with a caret under the token
        return _fail(str(exc))
    except RecursionError:
        return _fail("input nested too deeply to read")
    except MemoryError:
        return _fail("out of memory; lower the level of detail or texture size, or run on a "
                     "machine with more memory (see --max-memory)")
    except OSError as exc:
        return _fail(_os_message(exc))
    except KeyboardInterrupt:
        return _fail("interrupted", 130)
    except Exception as exc:
        msg = _library_error(exc)
        if msg is not None:
            return _fail(_one_line(msg))
        if os.environ.get("IONIC_USD_DEBUG"):
            raise
        return _fail(f"internal error, please report it: {type(exc).__name__}: "
                     f"{_one_line(str(exc))[:300]} (IONIC_USD_DEBUG=1 shows the traceback)", 70)


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
