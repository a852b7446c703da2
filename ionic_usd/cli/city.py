"""The ``ionic-usd city`` subcommand: flags and the thin wrapper over :func:`build_city`."""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

from ionic_usd.cli.flags import add_command, add_memory_flag, add_seed_flag, texture_size
from ionic_usd.errors import ParameterError

__all__ = ["add_city_parser", "cmd_city"]


def _pair(flag: str):
    def parse(text: str) -> tuple[float, float]:
        try:
            a, b = (float(x) for x in text.split(","))
        except ValueError:
            raise argparse.ArgumentTypeError(
                f"{flag} expects two numbers A,B, got {text!r}"
            ) from None
        return a, b

    return parse


def _check_grid_memory(args: argparse.Namespace, limit_gb: float) -> None:
    """A grid's size is known before any layout work: refuse a city that cannot fit in memory
    at once (the layout of a million lots alone takes minutes)."""
    from ionic_usd.city.layout import DEFAULT_INSTANCER_THRESHOLD
    from ionic_usd.errors import BudgetError
    from ionic_usd.pipeline.city import estimate_memory

    temples = args.rows * args.cols
    street = 2 * (args.rows + 1) * (args.cols + 1) * int(args.block / args.column_spacing)
    if args.columns is not None:
        street = args.columns
    threshold = (
        DEFAULT_INSTANCER_THRESHOLD
        if args.instancer_threshold is None
        else args.instancer_threshold
    )
    est = estimate_memory(temples, street, 1, threshold)
    if est > limit_gb * 1e9:
        raise BudgetError(
            f"this city needs about {est / 1e9:.1f} GB ({temples:,} temples, "
            f"about {street:,} columns), above --max-memory "
            f"{limit_gb:g} GB; raise the limit to build it anyway"
        )


def cmd_city(args: argparse.Namespace) -> int:
    from ionic_usd.pipeline.city import CityOptions, build_city, check_city_output, write_summary

    # every output path and flag is checked before any work (issue 31)
    if args.json is not None:
        from ionic_usd.io import check_output_file

        check_output_file(args.json, force=args.force, what="--json", suffixes=(".json",))
        parent = args.json.parent
        if not parent.is_dir() and parent.resolve() != Path(args.folder).resolve():
            raise ParameterError("--json", str(args.json), "a file in an existing folder")
    check_city_output(args.folder, force=args.force, what="folder")
    for flag, v, lo, hi in (
        ("--rows", args.rows, 1, 10_000),
        ("--cols", args.cols, 1, 10_000),
    ):
        if not lo <= v <= hi:
            raise ParameterError(flag, v, f"an integer in [{lo}, {hi:,}]")
    for flag, length, low, high in (
        ("--block", args.block, 1.0, 10_000.0),
        ("--column-spacing", args.column_spacing, 0.5, 1_000.0),
    ):
        if not (math.isfinite(length) and low <= length <= high):
            raise ParameterError(flag, length, f"a length in [{low:g}, {high:g}] m")
    from ionic_usd.resources import DEFAULT_MAX_MEMORY_GB

    limit_gb = DEFAULT_MAX_MEMORY_GB if args.max_memory is None else args.max_memory
    opts = CityOptions(
        plan=str(args.plan) if args.plan else None,
        rows=args.rows,
        cols=args.cols,
        block=args.block,
        columns=args.columns,
        column_spacing=args.column_spacing,
        variety=not args.baseline,
        column_variety=args.column_variety,
        temple=args.temple,
        seed=args.seed,
        focus=args.focus,
        lod_distances=args.lod_distances,
        scale_range=args.scale_range,
        cards_beyond=args.cards_beyond,
        cards=not args.no_cards,
        card_size=args.card_size,
        texture_size=args.texture_size,
        instancer_threshold=args.instancer_threshold,
        scheduler=args.scheduler,
        workers=args.workers,
        memory_limit_gb=limit_gb,
        force=args.force,
    )
    if args.plan is None:
        _check_grid_memory(args, limit_gb)
    import logging

    log = logging.getLogger("ionic_usd.city")  # shown with -v; bars show the builds anyway
    s = build_city(args.folder, opts, progress=log.info)
    for note in s.get("notes", []):
        print(f"ionic-usd: {note}", file=sys.stderr)
    if args.json is not None:
        write_summary(s, args.json)
    tri = s["triangles"]
    print(
        f"wrote {s['city']}: {s['temples']:,} temples ({s['temples_as']}, "
        f"{s['temple_prototypes']} prototypes of {s['builds']} builds), {s['columns']:,} "
        f"street columns ({s['column_prototypes']} prototypes), {s['stoa_bays']:,} stoa bays "
        f"and {s['stoa_corners']} corners on paved ground; builds: "
        f"{s['prototypes_built']} built, {s['prototypes_reused']} reused; "
        f"{s['timings']['total']:.2f} s"
    )
    print("  triangles drawn: " + ", ".join(f"{k} {v:,}" for k, v in tri.items()))
    return 0


def add_city_parser(sub, parser_class, *, arguments: bool = True) -> None:
    """Add ``city`` to the CLI's subparsers (``parser_class``: the CLI's one-line-error
    parser; ``arguments=False``: its name and help only, for ``ionic-usd --help``)."""
    p = add_command(
        sub,
        "city",
        cmd_city,
        help="build a city of temples and colonnades (grid, or a GeoJSON plan)",
        description="Build FOLDER/City.usda (+ Instances.usdc, crate): temples fitted to their "
        "lots and colonnades along the streets, from a GeoJSON plan (--plan; metres in a local "
        "projected frame, easting/northing) or a grid. The temples it needs are built (on Dask: "
        "a local cluster, or --scheduler) into FOLDER/Temples through a content-addressed "
        "cache, so a rebuild builds only what changed.",
    )
    if not arguments:
        return
    _plan_arguments(p)
    _temple_arguments(p)
    _far_field_arguments(p)
    _build_arguments(p)


def _plan_arguments(p) -> None:
    """The output folder and where the lots and streets come from: a plan or a grid."""
    p.add_argument("folder", type=Path, help="output folder (created if missing)")
    p.add_argument(
        "--plan",
        type=Path,
        help="GeoJSON FeatureCollection (see examples/forum.geojson); default: a grid",
    )
    p.add_argument("--rows", type=int, default=5, help="grid rows [default 5]")
    p.add_argument("--cols", type=int, default=5, help="grid columns [default 5]")
    p.add_argument("--block", type=float, default=60.0, help="grid spacing (m) [default 60]")
    p.add_argument(
        "--columns",
        type=int,
        help="street columns in all (more than the streets "
        "hold: extra colonnades south of the city) [default: what the streets hold]",
    )
    p.add_argument(
        "--column-spacing",
        type=float,
        default=3.0,
        help="axial spacing of colonnades (m) [default 3]",
    )


def _temple_arguments(p) -> None:
    """What each lot's temple is: baseline or varied, one named temple, column variety, seed."""
    p.add_argument(
        "--baseline",
        action="store_true",
        help="no per-lot variety: every temple at the baseline hypotheses",
    )
    p.add_argument(
        "--temple",
        metavar="NAME",
        help="the temple of every lot that names none (a built-in description such as "
        "portunus, or a TOML path): one build for them all [default: each lot chooses a "
        "type that fits it, seeded: pseudoperipteral, 4/6/8 columns across, pycnostyle to "
        "araeostyle, the module sized to the lot; `auto` says so explicitly]",
    )
    p.add_argument(
        "--column-variety",
        type=int,
        default=1,
        metavar="K",
        help="draw each lot's column lower diameter from K levels within ±5%% of "
        "the description's (each level is a temple build) [default 1]",
    )
    add_seed_flag(p, "seed of the per-lot choices", default=0)


def _far_field_arguments(p) -> None:
    """LOD by distance from a focus point, and the far field drawn as cards."""
    p.add_argument(
        "--focus",
        type=_pair("--focus"),
        metavar="X,Y",
        help="plan point (m) for LOD by distance; default: no LOD selection",
    )
    p.add_argument(
        "--lod-distances",
        type=_pair("--lod-distances"),
        default=(150.0, 400.0),
        metavar="NEAR,FAR",
        help="high within NEAR, medium within FAR, low beyond (m) [default 150,400]",
    )
    p.add_argument(
        "--cards-beyond",
        type=float,
        default=None,
        metavar="METRES",
        help="with --focus: temples farther than this draw as cards (UsdGeomModelAPI "
        "draw mode, images baked by the preview renderer; needs the preview extra) "
        "[default: FAR of --lod-distances]",
    )
    p.add_argument("--no-cards", action="store_true", help="no card draw mode for far temples")
    p.add_argument(
        "--card-size",
        type=int,
        default=256,
        metavar="PX",
        help="card image size, longer side (px) [default 256]",
    )


def _build_arguments(p) -> None:
    """How the temples are fitted and built (textures, instancing, Dask, memory) and the output."""
    from ionic_usd.city.layout import DEFAULT_INSTANCER_THRESHOLD

    p.add_argument(
        "--scale-range",
        type=_pair("--scale-range"),
        default=(0.6, 1.4),
        metavar="MIN,MAX",
        help="uniform scales a temple may take to fit its lot [default 0.6,1.4]",
    )
    p.add_argument(
        "--texture-size",
        type=texture_size,
        default=1024,
        help="texture resolution (px), a power of two in [16, 8192] [default 1024]",
    )
    p.add_argument(
        "--instancer-threshold",
        type=int,
        default=None,
        metavar="N",
        help="above N temples use a PointInstancer of temple prototypes instead of "
        f"instanceable references [default {DEFAULT_INSTANCER_THRESHOLD}]",
    )
    p.add_argument(
        "--scheduler",
        metavar="tcp://HOST:PORT",
        help="build on this Dask scheduler's workers (they return bytes; this "
        "process writes) [default: a local cluster on this machine's cores]",
    )
    p.add_argument("--workers", type=int, help="local cluster size [default: cores]")
    add_memory_flag(p, what="a city", old_name="--memory-limit")
    p.add_argument(
        "--json",
        type=Path,
        metavar="SUMMARY",
        help="write the build summary (prototypes built/reused, instances, "
        "timings, workers) as JSON",
    )
    p.add_argument("--force", action="store_true", help="rebuild an existing city")
