"""Argparse flag families shared by the subcommands: one helper per family.

Every subcommand module (:mod:`ionic_usd.cli`, :mod:`ionic_usd.cli.evaluate`,
:mod:`ionic_usd.cli.export`, :mod:`ionic_usd.cli.city`) takes its common flags
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

from ionic_usd.checks import SEED_RANGE, TEXTURE_SIZES

__all__ = [
    "add_command",
    "add_config_flags",
    "add_dataclass_flags",
    "add_memory_flag",
    "add_output_flags",
    "add_report_flags",
    "add_seed_flag",
    "add_stone_flags",
    "add_variant_flag",
    "collect_flags",
    "memory_gb",
    "parse_bool",
    "seed",
    "texture_size",
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


#: the one schema of the flags several commands share: (low, high) of each (the stone flags'
#: in ionic_usd.checks, which the Python API checks too)
MEMORY_GB_RANGE = (0.1, float(1 << 20))


def texture_size(text: str) -> int:
    """``--texture-size``: a power of two in [16, 8192] (argparse type: refused at parsing)."""
    lo, hi = TEXTURE_SIZES
    try:
        v = int(text)
    except ValueError:
        v = -1
    if not lo <= v <= hi or v & (v - 1):
        raise argparse.ArgumentTypeError(f"expected a power of two in [{lo}, {hi}], got {text!r}")
    return v


def seed(text: str) -> int:
    """``--seed``: an integer in [0, 2**63 - 1]."""
    lo, hi = SEED_RANGE
    try:
        v = int(text)
    except ValueError:
        v = -1
    if not lo <= v <= hi:
        raise argparse.ArgumentTypeError(f"expected an integer in [{lo}, 2**63 - 1], got {text!r}")
    return v


def memory_gb(text: str) -> float:
    """``--max-memory``: a number of GB in [0.1, 1048576]."""
    import math

    lo, hi = MEMORY_GB_RANGE
    try:
        v = float(text)
    except ValueError:
        v = math.nan
    if not (math.isfinite(v) and lo <= v <= hi):
        raise argparse.ArgumentTypeError(
            f"expected a number of GB in [{lo:g}, {hi:.0f}], got {text!r}"
        )
    return v


def add_stone_flags(p: argparse.ArgumentParser, *, seed_default: int = 7) -> None:
    """``--texture-size`` and ``--seed`` of the procedural stone textures."""
    p.add_argument(
        "--texture-size",
        type=texture_size,
        default=1024,
        help="texture resolution in pixels: a power of two, 16-4096 within the "
        "default memory limit; 8192 needs about 10 GB (--max-memory 10) "
        "[default 1024]",
    )
    add_seed_flag(p, "seed of the procedural stone", default=seed_default)


def add_seed_flag(p: argparse.ArgumentParser, help: str, *, default: int) -> None:
    """``--seed N`` (an integer in [0, 2**63 - 1])."""
    p.add_argument("--seed", type=seed, default=default, help=f"{help} [default {default}]")


class _DeprecatedAlias(argparse.Action):
    """An old flag name kept working: stores like the new one and says it is deprecated."""

    def __call__(self, parser: Any, namespace: Any, values: Any, option_string: Any = None):
        import sys

        print(
            f"ionic-usd: warning: {option_string} is deprecated; use --max-memory",
            file=sys.stderr,
        )
        setattr(namespace, self.dest, values)


def add_memory_flag(
    p: argparse.ArgumentParser, *, what: str = "work", old_name: str | None = None
) -> None:
    """``--max-memory GB``: refuse work whose estimated peak exceeds it. Every command that
    allocates has it, with one range and one default; ``old_name`` (``--memory-limit`` on
    ``city``) is still accepted, with a warning."""
    from ionic_usd.resources import DEFAULT_MAX_MEMORY_GB

    p.add_argument(
        "--max-memory",
        type=memory_gb,
        metavar="GB",
        default=None,
        help=f"refuse {what} whose estimated peak memory exceeds this "
        f"[default {DEFAULT_MAX_MEMORY_GB:g} GB]",
    )
    if old_name is None:
        return
    p.add_argument(
        old_name,
        type=memory_gb,
        dest="max_memory",
        action=_DeprecatedAlias,
        help=argparse.SUPPRESS,
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
