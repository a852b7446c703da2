"""The ``ionic-usd`` command line: thin wrappers over the public API.

The package is the whole command line (the parser here, the flag families in
:mod:`ionic_usd.cli.flags`, the commands in its other modules); no library module imports it
(``tests/test_layering.py``).

Every command validates all input before writing anything; errors print one line
(``ionic-usd: error: …``) and exit with status 2.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable, Collection, Sequence
from pathlib import Path
from typing import Any

from ionic_usd.cli.flags import (
    add_command,
    add_config_flags,
    add_dataclass_flags,
    add_memory_flag,
    add_output_flags,
    add_rebuild_flag,
    add_stone_flags,
)
from ionic_usd.cli.make import (
    PARTS,
    cmd_asset,
    cmd_column,
    cmd_presets,
    cmd_preview,
    cmd_shaft,
    cmd_temple,
)
from ionic_usd.errors import IonicError

__all__ = ["main", "build_parser"]


# -- parser --------------------------------------------------------------------------------------
class _Parser(argparse.ArgumentParser):
    def error(self, message: str):  # one line, status 2 (argparse's own convention)
        self.exit(2, f"{self.prog}: error: {message}\n")


_AddCommand = Callable[[Any, bool], None]


def _command(
    sub: Any, name: str, help: str, description: str, func: Callable[[argparse.Namespace], int]
) -> argparse.ArgumentParser:
    return add_command(sub, name, func, help=help, description=description)


def _add_shaft(sub: Any, full: bool) -> None:
    p = _command(
        sub,
        "shaft",
        "write the fluted column shaft as USD",
        "Build the fluted shaft (paper Table 1, parameters $a-$i) and write it as "
        "USD (.usda text, .usdc/.usd binary, by extension). Parameters come from "
        "defaults (the Temple of Portunus), then --config TOML ([shaft] table), then "
        "flags.",
        cmd_shaft,
    )
    if not full:
        return
    from ionic_usd.column.shaft import DEFAULT_TRIANGLE_BUDGET, SHAFT_PARAMETER_DOCS, ShaftParams

    add_output_flags(p, "output USD file", default="shaft.usda")
    add_config_flags(p, "TOML file with a [shaft] table", print_config=True)
    p.add_argument(
        "--max-triangles",
        type=int,
        default=DEFAULT_TRIANGLE_BUDGET,
        help="refuse a level of detail above this triangle count "
        f"[default {DEFAULT_TRIANGLE_BUDGET:,}]",
    )
    add_dataclass_flags(p, ShaftParams, SHAFT_PARAMETER_DOCS, title="shaft parameters")
    add_memory_flag(p)


def _add_column(sub: Any, full: bool) -> None:
    p = _command(
        sub,
        "column",
        "write a whole column (base, shaft, capital) as USD",
        "Build base + shaft + capital (default: the Temple of Portunus column) and "
        "write the parts as separate meshes under one Xform. Parameters: defaults, "
        "then --config TOML ([column], [shaft], [capital], [volute] tables; see "
        "--print-config), then flags.",
        cmd_column,
    )
    if not full:
        return
    add_output_flags(p, "output USD file", default="column.usda")
    add_config_flags(p, "TOML file (see --print-config)", print_config=True)
    p.add_argument("--part", choices=list(PARTS), default="all", help="which parts to write")
    p.add_argument("--lod", help="level of detail: high, medium, low or custom")
    p.add_argument(
        "--base",
        help="a shipped base preset by name (G1, G2, attic_bezier, attic_bezier_plinth, "
        "ephesian); any other text is read as a base grammar ('R0.12 H0.05 C1 R0.12, …')",
    )
    p.add_argument("--scroll", help="scroll preset (S1, S2) or ring grammar 'R0.7 P0.05, …'")
    add_memory_flag(p)


def _add_temple(sub: Any, full: bool) -> None:
    p = _command(
        sub,
        "temple",
        "compose a temple scene (default: the Temple of Portunus) — the main job",
        "Write a temple as a USD assembly: Temple.usda (root) with podium, cella, "
        "entablature, roof and colonnade layers, the instanced column asset, "
        "textures, and one variant set per reconstruction question (layers/): a switch per "
        "independent hypothesis, one value per alternative where hypotheses share a "
        "`question`. Your overrides.usda is kept.",
        cmd_temple,
    )
    if not full:
        return
    add_output_flags(
        p,
        "output folder",
        default="PortunusTemple",
        force_help="rebuild an existing folder (atomically; overrides.usda is kept)",
    )
    add_config_flags(
        p,
        "temple TOML (schema of ionic_usd/data/portunus.toml; may add "
        "[column], [shaft], [capital], [volute] tables for the column)",
    )
    p.add_argument("--layout", default="portunus", help="built-in temple layout (portunus)")
    p.add_argument(
        "--preset",
        default=None,
        help="a built-in temple (see `ionic-usd presets`: portunus, priene, nike, ilissos, "
        "magnesia, ephesus, saturn)",
    )
    add_stone_flags(p)
    p.add_argument(
        "--detail",
        choices=("plain", "moulded", "carved"),
        default=None,
        help="the default selection of the temple's variant set `detail`: plain "
        "(cuboids), moulded (swept mouldings) or carved (mouldings, dentils, roof "
        "tiles, frieze relief hypothesis) [default: carved]",
    )
    p.add_argument(
        "--paradata",
        type=Path,
        help="an Extended Matrix GraphML (from `ionic-usd paradata`, edited in yEd) whose "
        "units' classes, certainty and sources override the temple description's",
    )
    add_rebuild_flag(p)
    add_memory_flag(p)


def _add_presets(sub: Any, full: bool) -> None:
    _command(
        sub,
        "presets",
        "list the built-in temples (name, type, title, sources)",
        "Print the built-in temples one a line: the name for `ionic-usd temple --preset "
        "NAME`, its type after Vitruvius, its title and its sources (tab-separated).",
        cmd_presets,
    )


def _add_asset(sub: Any, full: bool) -> None:
    p = _command(
        sub,
        "asset",
        "write the column as a USD component asset with variant sets",
        "Write IonicColumn/IonicColumn.usda (interface: kind=component, assetInfo, "
        "variant sets lod/base/scroll/flutes/form/finish, payload) with "
        "Payload/Contents.usda, Geometry.usdc, Materials.usda and Textures/ (analytic "
        "UVs, OpenImageIO stone maps).",
        cmd_asset,
    )
    if not full:
        return
    add_output_flags(
        p,
        "asset folder",
        default="IonicColumn",
        force_help="replace an existing asset folder (atomically)",
    )
    add_config_flags(p, "column TOML (see ionic-usd column --print-config)")
    p.add_argument("--base", help="default base (variants are always all four presets)")
    p.add_argument("--scroll", help=argparse.SUPPRESS)
    p.add_argument("--lod", help=argparse.SUPPRESS)
    add_stone_flags(p)
    p.add_argument("--tx", action="store_true", help="also write mipmapped .tx textures")
    p.add_argument(
        "--texture",
        action="append",
        metavar="ROLE=FILE",
        help="use your own travertine map (png/jpg) for ROLE basecolor, roughness "
        "or normal; give all three",
    )
    add_rebuild_flag(p)
    add_memory_flag(p)


def _add_preview(sub: Any, full: bool) -> None:
    p = _command(
        sub,
        "preview",
        "render a USD scene to a PNG thumbnail (headless OpenGL)",
        "Render SCENE with moderngl on a software EGL context (needs the preview "
        "extra: pip install 'ionic_usd[preview]'). Instances are drawn from one "
        "upload each.",
        cmd_preview,
    )
    if not full:
        return
    p.add_argument("scene", type=Path, help="USD file to render")
    add_output_flags(
        p,
        "PNG file",
        default=Path("preview.png"),
        type=Path,
        force_help="overwrite an existing PNG",
    )
    p.add_argument("--width", type=int, default=800)
    p.add_argument("--height", type=int, default=600)
    p.add_argument("--camera", choices=["auto", "front", "three-quarter"], default="auto")
    p.add_argument("--lod", help="select this lod variant on every prim that has one")
    p.add_argument("--background", default="0.80,0.84,0.89", help="R,G,B in [0, 1]")
    p.add_argument("--samples", type=int, default=4, help="MSAA samples")
    p.add_argument("--no-ground", action="store_true", help="no ground plane")
    add_memory_flag(p, what="a picture")
    p.add_argument(
        "--view",
        choices=["appearance", "reliability"],
        help="select this `view` variant (reliability: the Extended Matrix colour chart)",
    )


def _add_city(sub: Any, full: bool) -> None:
    from ionic_usd.cli.city import add_city_parser

    add_city_parser(sub, _Parser, arguments=full)


def _add_evaluate(sub: Any, full: bool) -> None:
    from ionic_usd.cli.evaluate import add_evaluate_parser

    add_evaluate_parser(sub, arguments=full)


def _add_fit(sub: Any, full: bool) -> None:
    from ionic_usd.cli.evaluate import add_fit_parser

    add_fit_parser(sub, arguments=full)


def _add_export(sub: Any, full: bool) -> None:
    from ionic_usd.cli.export import add_parser

    add_parser(sub, _Parser, arguments=full)


def _add_paradata(sub: Any, full: bool) -> None:
    from ionic_usd.cli.paradata import add_paradata_parser

    add_paradata_parser(sub, full)


def _add_web(sub: Any, full: bool) -> None:
    from ionic_usd.cli.paradata import add_web_parser

    add_web_parser(sub, full)


#: subcommand → the function that adds it (in the order ``--help`` lists them)
_COMMANDS: dict[str, _AddCommand] = {
    "shaft": _add_shaft,
    "column": _add_column,
    "temple": _add_temple,
    "presets": _add_presets,
    "city": _add_city,
    "asset": _add_asset,
    "preview": _add_preview,
    "evaluate": _add_evaluate,
    "fit": _add_fit,
    "export": _add_export,
    "paradata": _add_paradata,
    "web": _add_web,
}


def build_parser(commands: Collection[str] | None = None) -> argparse.ArgumentParser:
    """The ``ionic-usd`` parser.

    Parameters
    ----------
    commands : the subcommands whose flags to add (default: all). The others get only their
        name and help line, enough for ``ionic-usd --help``: :func:`main` builds the flags of
        the one command it runs, so ``ionic-usd --version`` imports no numpy and
        ``ionic-usd temple`` none of the modules behind the other commands' flags.
    """
    from ionic_usd import __version__

    parser = _Parser(
        prog="ionic-usd",
        description="Procedural Ionic-order columns and temples authored as OpenUSD scenes.",
    )
    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    parser.add_argument(
        "-v",
        "--verbose",
        action="count",
        default=0,
        help="say what each step does (-vv: debugging detail) on stderr",
    )
    parser.add_argument(
        "-q", "--quiet", action="store_true", help="no progress bars and no messages but errors"
    )
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)
    for name, add in _COMMANDS.items():
        add(sub, commands is None or name in commands)
    return parser


def _command_name(argv: Sequence[str]) -> str | None:
    """The subcommand in ``argv``: the first word that is not an option (the top-level
    options take no values)."""
    return next((a for a in argv if not a.startswith("-")), None)


def _one_line(text: str) -> str:
    return " ".join(text.split())


def _os_message(exc: OSError) -> str:
    """An OS error as the user needs it: what failed, on which path."""
    import errno

    what = exc.strerror or _one_line(str(exc)) or type(exc).__name__
    hint = {
        errno.ENOSPC: " (free some space or write elsewhere)",
        errno.EROFS: " (write elsewhere)",
        errno.EACCES: " (check the folder's permissions)",
        errno.ENAMETOOLONG: " (use a shorter name)",
    }.get(exc.errno or 0, "")
    where = f": {exc.filename}" if exc.filename else ""
    if getattr(exc, "filename2", None):
        where += f" -> {exc.filename2}"
    return f"{what}{where}{hint}"


def _library_error(exc: Exception) -> str | None:
    """The message of an error raised inside OpenUSD (``pxr.Tf.ErrorException``), else None.

    Recognised by its type, without importing ``pxr`` here (only ``ionic_usd.usd`` does).
    """
    t = type(exc)
    if t.__module__.startswith("pxr") or (
        t.__name__ == "ArgumentError" and "Boost" in t.__module__
    ):
        lines = [ln.strip() for ln in str(exc).splitlines() if ln.strip()]
        text = "OpenUSD: " + (lines[-1] if lines else t.__name__)
        for cause in ("No space left on device", "File too large", "Disk quota exceeded"):
            if cause in str(exc):  # the cause first, not "crate file corrupt"
                return f"{cause}: {text}"
        return text
    return None


_STAGED = None


def _user_paths(message: str) -> str:
    """Staging and temporary names (``.T.ionic-build-<pid>-<hex>``) as the user's names."""
    global _STAGED
    if _STAGED is None:
        import re

        # the name, the tag, pid and hex, and the name's extension repeated (kept for USD)
        _STAGED = re.compile(r"\.([^/\s]+?)\.ionic-(?:build|tmp)-\d+-[0-9a-f]{8}(?:\.\w+)?")
    return _STAGED.sub(r"\1", message)


def _fail(message: str, status: int = 2) -> int:
    print(f"ionic-usd: error: {_user_paths(message)}", file=sys.stderr)
    return status


def main(argv: list[str] | None = None) -> int:
    """Run the command line; returns the exit status (2 for any refused input or OS fault).

    Every failure prints one line on stderr (a grammar error adds its source with a caret):
    the package's own errors, OS errors (full disk, read-only folder, a name too long), and
    errors from OpenUSD. An unexpected exception is a bug: one line, status 70, and the
    traceback only with ``IONIC_USD_DEBUG=1``.
    """
    import os

    if argv is None:  # the process is this command: its own settings (not a caller's)
        from ionic_usd.cli.process import tune

        tune()
    from ionic_usd.usd_warnings import UsdWarnings

    usd = UsdWarnings()

    def fail(message: str, status: int = 2) -> int:
        # OpenUSD's Warning: lines (printed ahead of the error) folded into the one line
        head, sep, rest = message.partition("\n")  # a grammar error's source and caret stay
        return _fail(usd.fold(head) + sep + rest, status)

    try:
        words = sys.argv[1:] if argv is None else argv
        name = _command_name(words)
        parser = build_parser(() if name is None else (name,))
        args = parser.parse_args(words)
        from ionic_usd.progress import configure

        configure(-1 if args.quiet else args.verbose)
        usd.start()
        status = int(args.func(args) or 0)
        usd.stop()
        return status
    except IonicError as exc:
        # one line; a grammar error adds its source line with a caret under the token
        return fail(str(exc))
    except RecursionError:
        return fail("input nested too deeply to read")
    except MemoryError:
        return fail(
            "out of memory; lower the level of detail or texture size, or run on a "
            "machine with more memory (see --max-memory)"
        )
    except OSError as exc:
        return fail(_os_message(exc))
    except KeyboardInterrupt:
        return fail("interrupted", 130)
    except Exception as exc:
        msg = _library_error(exc)
        if msg is not None:
            return fail(_one_line(msg))
        if os.environ.get("IONIC_USD_DEBUG"):
            usd.stop()
            raise
        return fail(
            f"internal error, please report it: {type(exc).__name__}: "
            f"{_one_line(str(exc))[:300]} (IONIC_USD_DEBUG=1 shows the traceback)",
            70,
        )
    finally:
        usd.stop()  # (nothing left to print after fail(); restores stderr on SystemExit)
