"""Argparse flag families shared by the subcommands: one helper per family.

Every subcommand module (:mod:`ionic_usd.cli`, :mod:`ionic_usd.evaluate.commands`,
:mod:`ionic_usd.export.command`, :mod:`ionic_usd.pipeline.commands`) takes its common flags
from here, so ``--output``/``--force``, ``--config``, the stone texture flags, ``--max-memory``,
``--variant`` and the report files read and behave the same everywhere.

Nothing here imports more than the standard library at module level: building the parser must
stay cheap (``ionic-usd --version`` imports no numpy).
"""

from __future__ import annotations

import argparse
import dataclasses
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

__all__ = [
    "add_command",
    "add_config_flags",
    "add_dataclass_flags",
    "add_memory_flag",
    "add_output_flags",
    "add_report_flags",
    "add_stone_flags",
    "add_variant_flag",
    "collect_flags",
    "parse_bool",
]


def add_command(
    subparsers: Any,
    name: str,
    func: Callable[[argparse.Namespace], int],
    *,
    help: str,
    description: str,
) -> argparse.ArgumentParser:
    """Add subcommand ``name`` running ``func(args)``; its flags are the caller's to add.

    A caller building only the name and help (``ionic-usd --help`` lists every command, but
    parses with the flags of one) adds nothing more.
    """
    p: argparse.ArgumentParser = subparsers.add_parser(name, help=help, description=description)
    p.set_defaults(func=func)
    # -v / -q after the command name too (``ionic-usd temple --force -q``); SUPPRESS keeps
    # the value given before the command when none is given after it
    p.add_argument(
        "-v",
        "--verbose",
        action="count",
        default=argparse.SUPPRESS,
        help="say what each step does (-vv: debugging detail) on stderr",
    )
    p.add_argument(
        "-q",
        "--quiet",
        action="store_true",
        default=argparse.SUPPRESS,
        help="no progress bars and no messages but errors",
    )
    return p


def parse_bool(text: str) -> bool:
    """``true/yes/on/1`` or ``false/no/off/0`` (any case) → bool, for flags of bool fields."""
    low = text.lower()
    if low in ("1", "true", "yes", "on"):
        return True
    if low in ("0", "false", "no", "off"):
        return False
    raise argparse.ArgumentTypeError(f"expected true/false, got {text!r}")


def add_output_flags(
    p: argparse.ArgumentParser,
    help: str,
    *,
    default: str | Path | None = None,
    required: bool = False,
    type: Any = None,
    force_help: str = "overwrite an existing output file",
) -> None:
    """``-o/--output`` and ``--force`` (an existing output is refused without it)."""
    kwargs: dict[str, Any] = {"help": help, "required": required}
    if default is not None:
        kwargs["default"] = default
    if type is not None:
        kwargs["type"] = type
    p.add_argument("-o", "--output", **kwargs)
    p.add_argument("--force", action="store_true", help=force_help)


def add_config_flags(p: argparse.ArgumentParser, help: str, *, print_config: bool = False) -> None:
    """``--config TOML`` and, with ``print_config``, ``--print-config``."""
    p.add_argument("--config", type=Path, help=help)
    if print_config:
        p.add_argument(
            "--print-config",
            action="store_true",
            help="print the full parameter set as TOML and exit",
        )


def add_stone_flags(p: argparse.ArgumentParser) -> None:
    """``--texture-size`` and ``--seed`` of the procedural stone textures."""
    p.add_argument(
        "--texture-size",
        type=int,
        default=1024,
        help="texture resolution in pixels: a power of two, 16-4096 within the "
        "default memory limit; 8192 needs about 10 GB (--max-memory 10) "
        "[default 1024]",
    )
    p.add_argument("--seed", type=int, default=7, help="seed of the procedural stone [default 7]")


def add_memory_flag(p: argparse.ArgumentParser) -> None:
    """``--max-memory GB``: refuse work whose estimated peak exceeds it."""
    from ionic_usd.resources import DEFAULT_MAX_MEMORY_GB

    p.add_argument(
        "--max-memory",
        type=float,
        metavar="GB",
        default=None,
        help="refuse work whose estimated peak memory exceeds this "
        f"[default {DEFAULT_MAX_MEMORY_GB:g} GB]",
    )


def add_rebuild_flag(p: argparse.ArgumentParser) -> None:
    """``--rebuild``: regenerate a folder that already holds this build's intact output."""
    p.add_argument(
        "--rebuild",
        action="store_true",
        help="regenerate every file even when the folder already holds this build's intact "
        "output (by default such a folder is verified — SHA-256 of every generated file — "
        "and left as it is)",
    )


def add_variant_flag(p: argparse.ArgumentParser, help: str) -> None:
    """``--variant SET=VALUE`` (repeatable); read with
    :func:`ionic_usd.usd.variants.parse_variant_args`."""
    p.add_argument("--variant", action="append", metavar="SET=VALUE", help=help)


def add_report_flags(p: argparse.ArgumentParser, *, curves: str, json: str, plot: str) -> None:
    """``--curves`` (CSV), ``--json`` and ``--plot`` (PNG): the report files of a comparison."""
    p.add_argument("--curves", type=Path, help=curves)
    p.add_argument("--json", type=Path, help=json)
    p.add_argument("--plot", type=Path, help=plot)


def add_dataclass_flags(
    parser: argparse.ArgumentParser,
    cls: type,
    docs: Mapping[str, tuple[str, str, str]],
    *,
    prefix: str = "",
    title: str = "parameters",
) -> None:
    """One ``--flag`` per dataclass field; help shows the paper letter, unit and default.

    Every flag defaults to None (not given), so :func:`collect_flags` returns only what the
    user typed and the defaults stay those of the dataclass (or of a ``--config`` file).
    """
    group = parser.add_argument_group(title)
    defaults = cls()
    for f in dataclasses.fields(cls):
        if f.name.startswith("_"):
            continue
        letter, unit, text = docs.get(f.name, ("", "", f.name.replace("_", " ")))
        default = getattr(defaults, f.name)
        typ: Any = type(default) if default is not None else str
        if typ is bool:
            typ = parse_bool
        tag = f"{letter}, " if letter else ""
        group.add_argument(
            f"--{prefix}{f.name.replace('_', '-')}",
            dest=f"{prefix.replace('-', '_')}{f.name}",
            type=typ,
            default=None,
            metavar=unit.upper() if unit else "VALUE",
            help=f"{text} [{tag}{unit}; default {default}]",
        )


def collect_flags(args: argparse.Namespace, cls: type, *, prefix: str = "") -> dict[str, Any]:
    """The dataclass fields given on the command line (None = not given)."""
    out = {}
    for f in dataclasses.fields(cls):
        v = getattr(args, f"{prefix.replace('-', '_')}{f.name}", None)
        if v is not None:
            out[f.name] = v
    return out
