"""The ``evaluate`` and ``fit`` subcommands (wired into :mod:`ionic_usd.cli` by the lead).

``ionic-usd evaluate`` compares one section of the model — from a USD file written by this
project (``--usd``) or built from parameters (``--config``, default the Portunus column) —
with a reference curve and prints a table like the paper's Table 6. ``ionic-usd fit`` fits a
part's parameters to a reference and writes TOML that ``ionic-usd column --config`` accepts.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from ionic_usd.errors import ParameterError

__all__ = ["add_parsers", "cmd_evaluate", "cmd_fit"]


def _column(config: Path | None):
    from ionic_usd.column.column import column_params_from_mapping, portunus_column_params
    from ionic_usd.params import load_toml

    if config is None:
        return portunus_column_params()
    return column_params_from_mapping(load_toml(config), context=str(config))


def _check_out(path: Path | None, force: bool, suffix: str, flag: str) -> None:
    if path is None:
        return
    from ionic_usd.io import check_output_file

    if path.suffix.lower() != suffix:
        raise ParameterError(flag, str(path), f"a file ending in {suffix}")
    if not path.parent.is_dir() and str(path.parent):
        raise ParameterError(flag, str(path), "a path in an existing folder")
    # before any work: a read-only folder or a bad name is found now, not after a long fit
    check_output_file(path, force=force, what=flag)


def _variants(items: list[str] | None) -> dict[str, str]:
    out = {}
    for item in items or []:
        name, sep, value = item.partition("=")
        if not sep or not name or not value:
            raise ParameterError("--variant", item, "SET=VALUE, e.g. lod=high")
        out[name] = value
    return out


#: reference files larger than this are refused before reading (a 2,000,000-row CSV is ~30 MB;
#: a measured profile has thousands of nodes, not millions)
MAX_REFERENCE_BYTES = {".svg": 4 << 20}
MAX_REFERENCE_BYTES_DEFAULT = 16 << 20
#: nodes after resampling at --spacing (both curves together)
MAX_RESAMPLED_NODES = 2_000_000


def _reference(args: argparse.Namespace) -> np.ndarray:
    from ionic_usd.evaluate.reference import read_reference

    if not (np.isfinite(args.scale) and args.scale > 0):
        raise ParameterError("--scale", args.scale, "a finite number > 0 (m per unit)")
    p = Path(args.reference)
    limit = MAX_REFERENCE_BYTES.get(p.suffix.lower(), MAX_REFERENCE_BYTES_DEFAULT)
    if p.is_file() and p.stat().st_size > limit:
        raise ParameterError("--reference", str(p), f"a curve file under {limit >> 20} MB "
                             f"(this one has {p.stat().st_size / 1e6:.0f} MB)")
    return read_reference(args.reference, scale=args.scale, flip_y=args.flip_y,
                          element_id=args.element_id)


def _generated(args: argparse.Namespace) -> tuple[np.ndarray, str]:
    from ionic_usd.evaluate import sections

    if args.usd is not None:
        curve = sections.section_from_usd(args.usd, args.part, variants=_variants(args.variant))
        return curve, f"section of {args.usd}"
    params = _column(args.config)
    src = f"parameters from {args.config}" if args.config else "the Portunus column parameters"
    if args.part == "base":
        return sections.base_section(params), src
    if args.part == "shaft":
        return sections.shaft_silhouette_section(params), src
    return sections.volute_section(params), src


def cmd_evaluate(args: argparse.Namespace) -> int:
    """Compare a section of the model with a reference; print the table, write JSON/PNG."""
    from ionic_usd.evaluate.fit import orient_like
    from ionic_usd.evaluate.metrics import compare
    from ionic_usd.evaluate.reference import align
    from ionic_usd.evaluate.report import format_table, plot_overlay, write_json

    if args.usd is not None and args.config is not None:
        raise ParameterError("--usd/--config", (str(args.usd), str(args.config)),
                             "one source of the generated curve, not both")
    if args.variant and args.usd is None:
        raise ParameterError("--variant", args.variant, "used only with --usd")
    _check_out(args.json, args.force, ".json", "--json")
    _check_out(args.plot, args.force, ".png", "--plot")
    if args.spacing is not None and not (np.isfinite(args.spacing) and args.spacing > 0):
        raise ParameterError("--spacing", args.spacing, "a finite length > 0 (m)")
    ref = _reference(args)
    gen, source = _generated(args)
    if args.spacing is not None:  # the resampled node count, before any allocation
        length = sum(float(np.linalg.norm(np.diff(c, axis=0), axis=1).sum()) for c in (ref, gen))
        nodes = length / args.spacing
        if nodes > MAX_RESAMPLED_NODES:
            raise ParameterError("--spacing", args.spacing, f"a spacing giving at most "
                                 f"{MAX_RESAMPLED_NODES:,} nodes (curves {length:.3g} m long "
                                 f"would give {nodes:,.0f})")
    moved, how = align(ref, gen, allow_mirror=args.mirror)
    moved = orient_like(ref, moved)
    result = compare(ref, moved, spacing=args.spacing)
    print(f"reference: {args.reference} ({len(ref)} nodes, scale {args.scale:g} m/unit"
          f"{', y flipped' if args.flip_y else ''})")
    print(f"generated: {args.part}, {source} ({len(gen)} nodes)")
    print(f"alignment: {how.describe()}")
    if args.spacing is not None:
        print(f"both curves resampled at {args.spacing:g} m spacing")
    print(format_table({args.part: result}))
    meta = {"reference": str(args.reference), "generated": source, "part": args.part,
            "scale": args.scale, "flip_y": args.flip_y, "spacing": args.spacing}
    if args.json is not None:
        write_json(args.json, {args.part: result}, alignments={args.part: how}, metadata=meta)
        print(f"wrote {args.json}")
    if args.plot is not None:
        from ionic_usd.evaluate.metrics import resample

        a = ref if args.spacing is None else resample(ref, spacing=args.spacing)
        b = moved if args.spacing is None else resample(moved, spacing=args.spacing)
        plot_overlay(a, b, args.plot, title=f"{args.part}: reference vs generated")
        print(f"wrote {args.plot}")
    return 0


def _floats(text: str | None, n: int, flag: str) -> list[float] | None:
    if text is None:
        return None
    try:
        vals = [float(v) for v in text.split(",")]
    except ValueError:
        vals = []
    if len(vals) != n or not all(np.isfinite(vals)):
        raise ParameterError(flag, text, f"{n} comma-separated numbers")
    return vals


def cmd_fit(args: argparse.Namespace) -> int:
    """Fit a part to a reference; print before/after tables; write (or print) TOML."""
    from ionic_usd.evaluate import fit as F
    from ionic_usd.evaluate.report import format_table, plot_overlay

    out = args.output
    if out is not None:
        from ionic_usd.io import check_output_file

        if out.suffix.lower() != ".toml":
            raise ParameterError("--output", str(out), "a file ending in .toml")
        check_output_file(out, force=args.force, what="--output")  # before the whole fit
    _check_out(args.plot, args.force, ".png", "--plot")
    if args.modules is not None and args.part != "base":
        raise ParameterError("--modules", args.modules, "used only with `fit base`")
    if args.eye is not None and args.part != "volute":
        raise ParameterError("--eye", args.eye, "used only with `fit volute`")
    column = _column(args.config)
    ref = _reference(args)
    if args.part == "volute":
        res = F.fit_volute(ref, column=column, measure=args.measure, seed=args.seed,
                           eye=_floats(args.eye, 2, "--eye"))
    elif args.part == "base":
        mods = None
        if args.modules is not None:
            try:
                mods = [int(m) for m in args.modules.split(",")]
            except ValueError:
                raise ParameterError("--modules", args.modules,
                                     "comma-separated control-point counts, e.g. 2,4,4") from None
        res = F.fit_base(ref, modules=mods, initial=column, measure=args.measure,
                         seed=args.seed)
    else:
        res = F.fit_shaft(ref, initial=column, measure=args.measure, seed=args.seed)
    print(f"reference: {args.reference} ({len(ref)} nodes)")
    print(f"fit {args.part}: minimised {args.measure}; {res.iterations} iterations, "
          f"{res.evaluations} curve evaluations, {res.seconds:.2f} s")
    for note in res.notes:
        print(f"  {note}")
    print(f"alignment after the fit: {res.alignment.describe()}")
    print(format_table({"before": res.before, "after": res.after}))
    if out is not None:
        res.write_toml(out, force=args.force)
        print(f"wrote {out} (use: ionic-usd column --config {out})")
    else:
        sys.stdout.write(res.to_toml())
    if args.plot is not None:
        plot_overlay(res.reference, res.fitted, args.plot, title=f"fitted {args.part}",
                     labels=("reference", "fitted"))
        print(f"wrote {args.plot}")
    return 0


def _reference_flags(p: argparse.ArgumentParser) -> None:
    p.add_argument("--reference", type=Path, required=True,
                   help="reference curve: .csv/.txt (x,y per line) or .svg (a <path>)")
    p.add_argument("--scale", type=float, default=1.0,
                   help="metres per reference unit [default 1]")
    p.add_argument("--flip-y", action="store_true",
                   help="negate the reference's y (SVG and image coordinates point down)")
    p.add_argument("--element-id", help="SVG: id of the element to read (default: first path)")


def add_parsers(subparsers, parser_class=argparse.ArgumentParser) -> None:
    """Add the ``evaluate`` and ``fit`` subcommands to ``subparsers``.

    Parameters
    ----------
    subparsers : the object returned by ``ArgumentParser.add_subparsers``
    parser_class : the CLI's parser class; unused, as ``add_subparsers(parser_class=…)``
        already makes every subparser of that class (kept for the lead's call signature)
    """
    del parser_class
    from ionic_usd.evaluate.fit import FIT_MEASURES
    from ionic_usd.evaluate.sections import PARTS

    p = subparsers.add_parser(
        "evaluate",
        help="compare a section of the model with a reference curve (paper Table 6)",
        description="Cut a section of the model — from a USD file written by ionic-usd "
        "(--usd; composed, active variants) or built from parameters (--config, default the "
        "Portunus column) — align it to the reference (translation, --mirror also tries a "
        "mirror image) and print the paper's measures in metres and % of the mean curve "
        "length. Sections: base half-profile (r, y), shaft silhouette (r, y), the front-right "
        "volute's outer spiral (x, y) on the front face.",
    )
    p.add_argument("--part", choices=PARTS, required=True, help="which section")
    src = p.add_mutually_exclusive_group()
    src.add_argument("--usd", type=Path, help="USD file from `ionic-usd column` or `asset`")
    src.add_argument("--config", type=Path, help="column TOML (see ionic-usd column "
                     "--print-config)")
    p.add_argument("--variant", action="append", metavar="SET=VALUE",
                   help="with --usd: select a variant (e.g. lod=high, base=G2); repeatable")
    _reference_flags(p)
    p.add_argument("--mirror", action="store_true",
                   help="also try the mirrored section (the drawing's handedness is arbitrary)")
    p.add_argument("--spacing", type=float,
                   help="resample both curves at this node spacing (m) first, as the paper")
    p.add_argument("--json", type=Path, help="write the measures as JSON")
    p.add_argument("--plot", type=Path, help="write an overlay plot (PNG)")
    p.add_argument("--force", action="store_true", help="overwrite existing --json/--plot files")
    p.set_defaults(func=cmd_evaluate)

    p = subparsers.add_parser(
        "fit",
        help="fit a part's parameters to a reference curve (writes column TOML)",
        description="Fit the volute (R, c, d, start angle, circuits, placement), the base "
        "(Bézier grammar control points; module layout suggested unless --modules) or the "
        "shaft (bottom/top radius, height, entasis) to a reference curve: differential "
        "evolution, then least squares, then Nelder-Mead on --measure. Prints the measures "
        "before and after and writes TOML for `ionic-usd column --config`.",
    )
    p.add_argument("part", choices=PARTS, help="what to fit")
    _reference_flags(p)
    p.add_argument("--measure", choices=FIT_MEASURES, default="hausdorff",
                   help="what to minimise [default hausdorff: the paper's 'weak Fréchet']")
    p.add_argument("-o", "--output", type=Path,
                   help="TOML file to write (default: print the TOML)")
    p.add_argument("--force", action="store_true", help="overwrite existing output files")
    p.add_argument("--seed", type=int, default=0, help="seed of the global stage [default 0]")
    p.add_argument("--config", type=Path,
                   help="column TOML to start from (default: the Portunus column)")
    p.add_argument("--modules", help="base: control points per module, e.g. 2,4,4,2")
    p.add_argument("--eye", help="volute: the eye centre X,Y in metres in the reference's "
                   "frame (after --scale/--flip-y); sets the offsets")
    p.add_argument("--plot", type=Path, help="write an overlay of the fitted curve (PNG)")
    p.set_defaults(func=cmd_fit)
