"""The ``evaluate`` and ``fit`` subcommands (wired into :mod:`ionic_usd.cli` by the lead).

``ionic-usd evaluate`` compares one section of the model — from a USD file written by this
project (``--usd``) or built from parameters (``--config``, default the Portunus column) —
with a reference curve and prints a table like the paper's Table 6. ``ionic-usd fit`` fits a
part's parameters to a reference and writes TOML that ``ionic-usd column --config`` accepts.
"""

from __future__ import annotations

import argparse
import math
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ionic_usd.cli.flags import (
    add_command,
    add_config_flags,
    add_memory_flag,
    add_output_flags,
    add_report_flags,
    add_seed_flag,
    add_variant_flag,
)
from ionic_usd.errors import ParameterError

if TYPE_CHECKING:  # numpy is imported by the commands, not by building the parser
    import numpy as np

    from ionic_usd.column.column import ColumnParams
    from ionic_usd.evaluate.fit_core import FitResult

__all__ = ["add_evaluate_parser", "add_fit_parser", "add_parsers", "cmd_evaluate", "cmd_fit"]


def _column(config: Path | None) -> ColumnParams:
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


#: reference files larger than this are refused before reading (a 2,000,000-row CSV is ~30 MB;
#: a measured profile has thousands of nodes, not millions)
MAX_REFERENCE_BYTES = {".svg": 4 << 20}
MAX_REFERENCE_BYTES_DEFAULT = 16 << 20
#: nodes after resampling at --spacing (both curves together)
MAX_RESAMPLED_NODES = 2_000_000


def _read(path: Path, args: argparse.Namespace) -> np.ndarray:
    import numpy as np

    from ionic_usd.evaluate.reference import read_reference

    if not (math.isfinite(args.scale) and args.scale > 0):
        raise ParameterError("--scale", args.scale, "a finite number > 0 (m per unit)")
    p = Path(path)
    limit = MAX_REFERENCE_BYTES.get(p.suffix.lower(), MAX_REFERENCE_BYTES_DEFAULT)
    if p.is_file() and p.stat().st_size > limit:
        raise ParameterError(
            "--reference",
            str(p),
            f"a curve file under {limit >> 20} MB (this one has {p.stat().st_size / 1e6:.0f} MB)",
        )
    ref = read_reference(path, scale=args.scale, flip_y=args.flip_y, element_id=args.element_id)
    spacing = getattr(args, "spacing", None)
    if spacing is not None:  # the resampled node count, before any allocation
        nodes = 2.0 * float(np.linalg.norm(np.diff(ref, axis=0), axis=1).sum()) / spacing
        if nodes > MAX_RESAMPLED_NODES:
            raise ParameterError(
                "--spacing",
                spacing,
                f"a spacing giving at most {MAX_RESAMPLED_NODES:,} nodes (about {nodes:,.0f} here)",
            )
    return ref


def _check_memory(what: str, *files: Any, limit: float | None = None) -> None:
    """Refuse (``--max-memory``) work whose inputs would need more memory than allowed."""
    from ionic_usd.resources import check_estimate, estimate_inputs

    check_estimate(estimate_inputs(what, *files), limit)


def _reference(args: argparse.Namespace) -> np.ndarray:
    return _read(args.reference, args)


def _references(args: argparse.Namespace) -> list[tuple[str, Path]]:
    """``--reference`` items as (part, file): ``PART=FILE``, or a plain FILE with --part."""
    from ionic_usd.evaluate.sections import PARTS

    out = []
    for item in args.reference:
        name, sep, file = str(item).partition("=")
        if sep and name in PARTS:
            out.append((name, Path(file)))
        elif args.part is not None:
            out.append((args.part, Path(item)))
        else:
            raise ParameterError(
                "--reference", str(item), f"PART=FILE (PART one of {', '.join(PARTS)}) or --part"
            )
    parts = [p for p, _ in out]
    if len(set(parts)) != len(parts):
        raise ParameterError(
            "--reference", [str(i) for i in args.reference], "one reference per part"
        )
    return out


def _generated(
    args: argparse.Namespace, part: str, section_y: float | None
) -> tuple[np.ndarray, str]:
    from ionic_usd.evaluate import sections

    if args.usd is not None:
        from ionic_usd.usd.variants import parse_variant_args

        curve = sections.section_from_usd(
            args.usd, part, variants=parse_variant_args(args.variant), y=section_y
        )
        return curve, f"section of {args.usd}"
    params = _column(args.config)
    src = f"parameters from {args.config}" if args.config else "the Portunus column parameters"
    if part == "base":
        return sections.base_section(params), src
    if part == "shaft":
        if section_y is not None:
            return sections.shaft_cross_section_at(params, section_y), src
        return sections.shaft_silhouette_section(params), src
    return sections.volute_section(params), src


def _section_height(args: argparse.Namespace) -> float:
    """Column height of the shaft cross-section: --height, else 1/3 up the fluted body."""
    if args.height is not None:
        return float(args.height)
    params = _column(args.config)
    sp = params.shaft_params()
    return params.base_params().height + sp.length / 3.0


def _compare_one(args: argparse.Namespace, part: str, ref: np.ndarray) -> tuple[Any, ...]:
    """Align and compare one part; returns (comparison, alignment, a, b, source, spacing)."""
    from ionic_usd.evaluate.fit_core import orient_like
    from ionic_usd.evaluate.fit_shaft import closed_like, is_closed_curve
    from ionic_usd.evaluate.metrics import compare, curve_length, resample
    from ionic_usd.evaluate.reference import align

    section = part == "shaft" and args.section
    if is_closed_curve(ref) and not section:
        raise ParameterError(
            "--reference",
            f"{part}: a closed curve",
            "an open profile; a closed shaft cross-section needs --section",
        )
    if args.section and part != "shaft":
        raise ParameterError("--section", part, "used only with the shaft")
    gen, source = _generated(args, part, _section_height(args) if section else None)
    moved, how = align(
        ref, gen, allow_mirror=args.mirror, allow_rotation=args.rotate or bool(section)
    )
    moved = closed_like(ref, moved) if section else orient_like(ref, moved)
    spacing = args.spacing if args.spacing is not None else curve_length(ref) / 2000.0
    a, b = resample(ref, spacing=spacing), resample(moved, spacing=spacing)
    return compare(a, b), how, a, b, source, spacing, len(gen)


def cmd_evaluate(args: argparse.Namespace) -> int:
    """Compare sections of the model with references; print Table 6, write JSON/PNG/CSV."""
    from ionic_usd.evaluate.report import format_table, plot_overlay, write_json

    if args.usd is not None and args.config is not None:
        raise ParameterError(
            "--usd/--config",
            (str(args.usd), str(args.config)),
            "one source of the generated curve, not both",
        )
    if args.variant and args.usd is None:
        raise ParameterError("--variant", args.variant, "used only with --usd")
    _check_out(args.json, args.force, ".json", "--json")
    _check_out(args.plot, args.force, ".png", "--plot")
    _check_out(args.curves, args.force, ".csv", "--curves")
    if args.spacing is not None and not (math.isfinite(args.spacing) and args.spacing > 0):
        raise ParameterError("--spacing", args.spacing, "a finite length > 0 (m)")
    refs = _references(args)
    _check_memory("the comparison", args.usd, *(f for _, f in refs), limit=args.max_memory)
    if args.plot is not None and len(refs) > 1:
        raise ParameterError("--plot", str(args.plot), "one --reference (one part) per plot")
    rows, aligns, curves, meta = {}, {}, {}, {}
    for part, path in refs:
        ref = _read(path, args)
        result, how, a, b, source, spacing, n_gen = _compare_one(args, part, ref)
        rows[part], aligns[part], curves[part] = result, how, (a, b)
        print(
            f"{part}: reference {path} ({len(ref)} nodes, scale {args.scale:g} m/unit"
            f"{', y flipped' if args.flip_y else ''}); generated: {source} ({n_gen} nodes)"
        )
        print(f"  alignment: {how.describe()}")
        how_chosen = (
            " (the reference's length / 2000; --spacing to change)" if args.spacing is None else ""
        )
        print(f"  both curves resampled at {spacing:.6g} m spacing{how_chosen}")
        meta[part] = {"reference": str(path), "generated": source, "spacing": spacing}
    print(format_table(rows))
    meta_all = {"scale": args.scale, "flip_y": args.flip_y, "parts": meta}
    if args.json is not None:
        write_json(args.json, rows, alignments=aligns, metadata=meta_all)
        print(f"wrote {args.json}")
    if args.curves is not None:
        from ionic_usd.evaluate.report import write_curves_csv

        write_curves_csv(
            args.curves, {p: {"reference": c[0], "generated": c[1]} for p, c in curves.items()}
        )
        print(f"wrote {args.curves}")
    if args.plot is not None:
        ((part, (a, b)),) = curves.items()
        plot_overlay(a, b, args.plot, title=f"{part}: reference vs generated")
        print(f"wrote {args.plot}")
    return 0


def _floats(text: str | None, n: int, flag: str) -> list[float] | None:
    if text is None:
        return None
    try:
        vals = [float(v) for v in text.split(",")]
    except ValueError:
        vals = []
    if len(vals) != n or not all(math.isfinite(v) for v in vals):
        raise ParameterError(flag, text, f"{n} comma-separated numbers")
    return vals


def _print_criterion(res: FitResult) -> None:
    from ionic_usd.evaluate.fit_volute_free import CRITERION

    if not res.criterion:
        return
    print(
        f"model chosen by the lowest {CRITERION.upper()} (AIC also shown; n nodes, k parameters):"
    )
    for r in (res, *res.alternatives):
        c = r.criterion
        rms = (c["rss"] / c["points"]) ** 0.5
        print(
            f"  {r.model:<13} k={int(c['parameters']):>2}  rms={rms:.4g} m"
            f"  AIC={c['aic']:.1f}  BIC={c['bic']:.1f}" + ("  <- chosen" if r is res else "")
        )


def _fit_part(args: argparse.Namespace, column: ColumnParams, ref: np.ndarray) -> FitResult:
    from ionic_usd.evaluate import fit as F
    from ionic_usd.evaluate.fit_shaft import fit_shaft_section, is_closed_curve

    if args.part == "volute":
        return F.fit_volute(
            ref,
            column=column,
            measure=args.measure,
            seed=args.seed,
            eye=_floats(args.eye, 2, "--eye"),
            models=args.model,
        )
    if args.part == "base":
        mods = None
        if args.modules is not None:
            try:
                mods = [int(m) for m in args.modules.split(",")]
            except ValueError:
                raise ParameterError(
                    "--modules", args.modules, "comma-separated control-point counts, e.g. 2,4,4"
                ) from None
        return F.fit_base(
            ref,
            modules=mods,
            initial=None if args.config is None else column,
            measure=args.measure,
            seed=args.seed,
        )
    if args.section:
        return fit_shaft_section(ref, initial=column, measure=args.measure, seed=args.seed)
    if is_closed_curve(ref):
        raise ParameterError(
            "--reference",
            f"{args.reference}: a closed curve",
            "a shaft silhouette; fit a closed cross-section with --section",
        )
    return F.fit_shaft(ref, initial=column, measure=args.measure, seed=args.seed)


def cmd_fit(args: argparse.Namespace) -> int:
    """Fit a part to a reference; print before/after tables; write (or print) TOML."""
    _check_memory("the fit", args.scan, args.reference, limit=args.max_memory)
    if args.part == "column":
        from ionic_usd.cli.fit_scan import cmd_fit_column

        return cmd_fit_column(args)
    _check_fit_args(args)  # every output checked before the whole fit
    column = _column(args.config)
    ref = _reference(args)
    res = _fit_part(args, column, ref)
    _print_fit(args, res, len(ref))
    _write_fit(args, res)
    return 0


def _check_fit_args(args: argparse.Namespace) -> None:
    """Refuse (ParameterError) a missing reference, an output that would be overwritten or
    has the wrong suffix, and the flags of other parts, before anything runs."""
    if args.reference is None:
        raise ParameterError("--reference", None, f"a reference curve for `fit {args.part}`")
    if args.output is not None:
        from ionic_usd.io import check_output_file

        if args.output.suffix.lower() != ".toml":
            raise ParameterError("--output", str(args.output), "a file ending in .toml")
        check_output_file(args.output, force=args.force, what="--output")
    _check_out(args.plot, args.force, ".png", "--plot")
    _check_out(args.json, args.force, ".json", "--json")
    _check_out(args.curves, args.force, ".csv", "--curves")
    if args.modules is not None and args.part != "base":
        raise ParameterError("--modules", args.modules, "used only with `fit base`")
    if args.eye is not None and args.part != "volute":
        raise ParameterError("--eye", args.eye, "used only with `fit volute`")
    if args.model is not None and args.part != "volute":
        raise ParameterError("--model", args.model, "used only with `fit volute`")
    if args.section and args.part != "shaft":
        raise ParameterError("--section", args.part, "used only with `fit shaft`")
    if args.scan is not None:
        raise ParameterError("--scan", str(args.scan), "used only with `fit column`")
    if args.units is not None:
        raise ParameterError("--units", args.units, "used only with `fit column --scan`")


def _print_fit(args: argparse.Namespace, res, nodes: int) -> None:
    """The fit's report on stdout: what was minimised, the notes, the alignment, the
    before/after table, the volute models side by side and the criterion."""
    from ionic_usd.evaluate.report import format_table

    print(f"reference: {args.reference} ({nodes} nodes)")
    print(
        f"fit {args.part} ({res.model}): minimised {args.measure}; {res.iterations} "
        f"iterations, {res.evaluations} curve evaluations, {res.seconds:.2f} s"
    )
    for note in res.notes:
        print(f"  {note}")
    print(f"alignment after the fit: {res.alignment.describe()}")
    print(f"measures on both curves densified to segments <= {res.spacing:.6g} m")
    print(format_table({"before": res.before, "after": res.after}))
    if res.alternatives:
        rows = {r.model: r.after for r in (res, *res.alternatives)}
        print(f"volute models side by side (best first; chosen: {res.model}):")
        print(format_table(rows))
    _print_criterion(res)


def _write_fit(args: argparse.Namespace, res) -> None:
    """The TOML (to ``--output`` or stdout), and the ``--json``, ``--curves`` and ``--plot``
    files asked for."""
    from ionic_usd.evaluate.report import plot_overlay, write_curves_csv, write_fit_json

    out = args.output
    if out is not None:
        res.write_toml(out, force=args.force)
        print(f"wrote {out} (use: ionic-usd column --config {out})")
    else:
        sys.stdout.write(res.to_toml())
    if args.json is not None:
        write_fit_json(
            args.json,
            {args.part: res},
            metadata={
                "reference": str(args.reference),
                "scale": args.scale,
                "flip_y": args.flip_y,
                "seed": args.seed,
            },
        )
        print(f"wrote {args.json}")
    if args.curves is not None:
        write_curves_csv(
            args.curves, {args.part: {"reference": res.reference, "fitted": res.fitted}}
        )
        print(f"wrote {args.curves}")
    if args.plot is not None:
        plot_overlay(
            res.reference,
            res.fitted,
            args.plot,
            title=f"fitted {args.part}",
            labels=("reference", "fitted"),
        )
        print(f"wrote {args.plot}")


def _reference_flags(
    p: argparse.ArgumentParser, *, multiple: bool = False, required: bool = True
) -> None:
    if multiple:
        p.add_argument(
            "--reference",
            required=True,
            action="append",
            metavar="[PART=]FILE",
            help="reference curve .csv/.txt (x,y per line) or .svg (a <path>); "
            "repeat as PART=FILE to evaluate several parts (Table 6)",
        )
    else:
        p.add_argument(
            "--reference",
            type=Path,
            required=required,
            help="reference curve: .csv/.txt (x,y per line) or .svg (a <path>)",
        )
    p.add_argument("--scale", type=float, default=1.0, help="metres per reference unit [default 1]")
    p.add_argument(
        "--flip-y",
        action="store_true",
        help="negate the reference's y (SVG and image coordinates point down)",
    )
    p.add_argument("--element-id", help="SVG: id of the element to read (default: first path)")


def add_evaluate_parser(subparsers: Any, *, arguments: bool = True) -> None:
    """Add the ``evaluate`` subcommand (``arguments=False``: its name and help only)."""
    p = add_command(
        subparsers,
        "evaluate",
        cmd_evaluate,
        help="compare a section of the model with a reference curve (paper Table 6)",
        description="Cut a section of the model — from a USD file written by ionic-usd "
        "(--usd; composed, active variants) or built from parameters (--config, default the "
        "Portunus column) — align it to the reference (translation, --mirror also tries a "
        "mirror image) and print the paper's measures in metres and % of the mean curve "
        "length. Sections: base half-profile (r, y), shaft silhouette (r, y), the front-right "
        "volute's outer spiral (x, y) on the front face.",
    )
    if not arguments:
        return
    from ionic_usd.evaluate.sections import PARTS

    p.add_argument(
        "--part",
        choices=PARTS,
        help="which section, for --reference FILE (else --reference PART=FILE)",
    )
    src = p.add_mutually_exclusive_group()
    src.add_argument("--usd", type=Path, help="USD file from `ionic-usd column` or `asset`")
    src.add_argument(
        "--config", type=Path, help="column TOML (see ionic-usd column --print-config)"
    )
    add_variant_flag(p, "with --usd: select a variant (e.g. lod=high, base=G2); repeatable")
    _reference_flags(p, multiple=True)
    p.add_argument(
        "--mirror",
        action="store_true",
        help="also try the mirrored section (the drawing's handedness is arbitrary)",
    )
    p.add_argument(
        "--rotate", action="store_true", help="also fit a rotation (always on with --section)"
    )
    p.add_argument(
        "--section",
        action="store_true",
        help="shaft: compare a closed cross-section (at --height) not the silhouette",
    )
    p.add_argument(
        "--height",
        type=float,
        help="--section: column height y (m) of the cut [default 1/3 up the shaft]",
    )
    p.add_argument(
        "--spacing",
        type=float,
        help="resample both curves at this node spacing (m) [default: the "
        "reference's length / 2000], as the paper",
    )
    add_report_flags(
        p,
        curves="write the compared curves as CSV",
        json="write the measures as JSON",
        plot="write an overlay plot (PNG)",
    )
    p.add_argument("--force", action="store_true", help="overwrite existing --json/--plot files")
    add_memory_flag(p, what="a comparison")


def add_fit_parser(subparsers: Any, *, arguments: bool = True) -> None:
    """Add the ``fit`` subcommand (``arguments=False``: its name and help only)."""
    p = add_command(
        subparsers,
        "fit",
        cmd_fit,
        help="fit a part's parameters to a reference curve (writes column TOML)",
        description="Fit the volute (R, c, d, start angle, circuits, placement), the base "
        "(Bézier grammar control points; module layout suggested unless --modules) or the "
        "shaft (bottom/top radius, height, entasis) to a reference curve: differential "
        "evolution, then least squares, then Nelder-Mead on --measure. Prints the measures "
        "before and after and writes TOML for `ionic-usd column --config`.",
    )
    if not arguments:
        return
    from ionic_usd.column.volute import VOLUTE_MODELS
    from ionic_usd.evaluate import FIT_MEASURES
    from ionic_usd.evaluate.sections import PARTS

    p.add_argument(
        "part", choices=(*PARTS, "column"), help="what to fit (column: a whole column from --scan)"
    )
    _reference_flags(p, required=False)
    p.add_argument(
        "--measure",
        choices=FIT_MEASURES,
        default="hausdorff",
        help="what to minimise [default hausdorff: the paper's 'weak Fréchet']",
    )
    add_output_flags(
        p,
        "TOML file to write (default: print the TOML); `fit column`: the "
        "output folder (fitted column USD, scan points USD, PNG)",
        type=Path,
        force_help="overwrite existing output files",
    )
    add_seed_flag(p, "seed of the global stage", default=0)
    add_memory_flag(p, what="a fit")
    add_config_flags(p, "column TOML to start from (default: the Portunus column)")
    p.add_argument("--modules", help="base: control points per module, e.g. 2,4,4,2")
    p.add_argument(
        "--eye",
        help="volute: the eye centre X,Y in metres in the reference's "
        "frame (after --scale/--flip-y); sets the offsets",
    )
    add_report_flags(
        p,
        curves="write the aligned reference and fitted curves as CSV (part, curve, index, x, y)",
        json="write the fit (schema ionic_usd.evaluate/1)",
        plot="write an overlay of the fitted curve (PNG)",
    )
    p.add_argument(
        "--model",
        choices=(*VOLUTE_MODELS, "free_arcs", "free_joints"),
        help="volute: fit only this model [default: every model, best chosen]",
    )
    p.add_argument(
        "--section",
        action="store_true",
        help="shaft: the reference is a closed fluted cross-section",
    )
    p.add_argument("--scan", type=Path, help="column: point cloud or mesh (.ply, .obj, .xyz, .csv)")
    p.add_argument(
        "--units",
        choices=("auto", "m", "cm", "mm", "in", "ft"),
        default=None,
        help="column: the scan's units [default auto: metres or millimetres from its extent, "
        "unless --scale is given]",
    )


def add_parsers(
    subparsers: Any,
    parser_class: Any = argparse.ArgumentParser,
    *,
    only: Sequence[str] | None = None,
) -> None:
    """Add the ``evaluate`` and ``fit`` subcommands to ``subparsers``.

    Parameters
    ----------
    subparsers : the object returned by ``ArgumentParser.add_subparsers``
    parser_class : unused, as ``add_subparsers(parser_class=…)`` already makes every
        subparser of that class (kept for the call signature)
    only : the subcommands whose flags to add (default: both)
    """
    del parser_class
    add_evaluate_parser(subparsers, arguments=only is None or "evaluate" in only)
    add_fit_parser(subparsers, arguments=only is None or "fit" in only)
